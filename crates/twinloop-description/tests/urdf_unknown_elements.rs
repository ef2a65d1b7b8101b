//! Elements the URDF reader passes over are reported, never dropped in silence: a
//! misspelt `<colision>` (with the element meant), an unknown `<frobnicate/>` in a
//! link and at the top level, a second `<inertial>`, an `<orgin>` inside `<inertial>`
//! (the inertial then sits at the link origin), a second shape in `<geometry>`.
//! `model lint` warns (`unmodeled-element`), `--strict` makes them errors; the ROS and
//! simulator extensions (`<gazebo>`, `<transmission>`, `<ros2_control>`, a collision's
//! `<material>`, prefixed elements) stay quiet.

use twinloop_description::lint::{Severity, codes, lint};
use twinloop_description::urdf;

const TEXT: &str = r#"<robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro">
  <link name="a">
    <inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>
    <colision><geometry><box size="1 1 1"/></geometry></colision>
    <frobnicate/>
    <inertial><mass value="2"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>
    <collision><geometry><box size="1 1 1"/><sphere radius="1"/></geometry><material name="m"/></collision>
    <self_collision_checking/>
  </link>
  <link name="b">
    <inertial><orgin xyz="0 0 1"/><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>
    <visual><geometry><box size="1 1 1"/></geometry><xacro:grey/></visual>
  </link>
  <jiont name="x"/>
  <joint name="j" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/><joint_properties friction="0"/></joint>
  <gazebo reference="a"/>
  <transmission name="t"/>
  <ros2_control name="c"/>
  <frobnicate/>
</robot>"#;

#[test]
fn unknown_and_repeated_elements_are_reported_with_their_lines() {
    let robot = urdf::from_str(TEXT).unwrap();
    let notes: Vec<(u32, &str, &str)> = robot
        .unmodeled
        .iter()
        .map(|n| (n.line, n.element.as_str(), n.what.as_str()))
        .collect();
    let lines: Vec<u32> = notes.iter().map(|n| n.0).collect();
    assert_eq!(lines, [4, 5, 6, 7, 11, 14, 20], "{notes:#?}");
    assert_eq!(notes[0].1, "<colision> in <link name=\"a\">");
    assert!(
        notes[0].2.ends_with("did you mean <collision>?"),
        "{}",
        notes[0].2
    );
    assert!(!notes[1].2.contains("did you mean"), "{}", notes[1].2);
    assert!(notes[2].2.contains("a second <inertial>"), "{}", notes[2].2);
    assert!(notes[3].2.contains("a second shape"), "{}", notes[3].2);
    assert!(
        notes[4].2.contains("did you mean <origin>?"),
        "{}",
        notes[4].2
    );
    assert!(
        notes[5].2.contains("did you mean <joint>?"),
        "{}",
        notes[5].2
    );
    assert!(
        notes[6]
            .2
            .contains("<frobnicate> is not a URDF element of <robot>")
    );
    // The first inertial is the one read, and the second link's at the link origin.
    assert_eq!(robot.link("a").unwrap().mass(), 1.0);
    assert_eq!(
        robot
            .link("b")
            .unwrap()
            .inertial
            .as_ref()
            .unwrap()
            .origin
            .xyz,
        [0.0; 3]
    );

    let report = lint(&robot);
    let warned: Vec<u32> = report
        .with_code(codes::UNMODELED_ELEMENT)
        .map(|f| {
            assert_eq!(f.severity, Severity::Warning);
            f.message
                .strip_prefix("line ")
                .and_then(|m| m.split(':').next())
                .unwrap()
                .parse()
                .unwrap()
        })
        .collect();
    assert_eq!(warned, lines);
    assert!(!report.has_errors());
    let strict = report.strict();
    assert_eq!(strict.errors, 7, "{:#?}", strict.findings);
}
