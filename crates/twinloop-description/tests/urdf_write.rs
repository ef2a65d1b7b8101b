//! The URDF writer: layout, exact numbers, escaping, frames and capsules.

use twinloop_description::*;

fn pendulum() -> Description {
    DescriptionBuilder::new("pendulum")
        .link("base")
        .box_shape([0.1, 0.1, 0.1])
        .done()
        .link("arm")
        .mass(
            1.0,
            [0.0, 0.0, -0.25],
            Inertia::solid_cylinder(1.0, 0.02, 0.5),
        )
        .done()
        .revolute("hinge", "base", "arm", [0.0, 1.0, 0.0])
        .origin(Pose::from_xyz([0.0, 0.0, -0.05]))
        .limits(-1.5, 1.5, 3.0, 5.0)
        .damping(0.1, 0.01)
        .done()
        .build()
        .unwrap()
}

#[test]
fn layout() {
    let text = urdf::to_string(&pendulum());
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines[0], "<?xml version=\"1.0\"?>");
    assert_eq!(lines[1], "<robot name=\"pendulum\">");
    assert_eq!(lines[2], "  <link name=\"base\">");
    assert_eq!(lines[3], "    <visual>");
    assert_eq!(lines[4], "      <geometry>");
    assert_eq!(lines[5], "        <box size=\"0.1 0.1 0.1\"/>");
    assert_eq!(*lines.last().unwrap(), "</robot>");
    assert!(text.contains(
        "  <joint name=\"hinge\" type=\"revolute\">\n    <origin xyz=\"0 0 -0.05\" rpy=\"0 0 0\"/>\n    <parent link=\"base\"/>\n    <child link=\"arm\"/>\n    <axis xyz=\"0 1 0\"/>\n    <limit lower=\"-1.5\" upper=\"1.5\" effort=\"3\" velocity=\"5\"/>\n    <dynamics damping=\"0.1\" friction=\"0.01\"/>\n  </joint>\n"
    ), "{text}");
    assert_eq!(urdf::from_str(&text).unwrap(), pendulum());
}

#[test]
fn numbers_are_bit_exact() {
    let values = [
        0.1,
        1.0 / 3.0,
        -2.0 / 7.0,
        1e-300,
        5e-324,
        f64::MIN_POSITIVE,
        f64::MAX,
        -f64::MAX,
        1e16,
        123_456_789.123_456_79,
        1.23e-7,
        -0.0,
        std::f64::consts::PI,
        9.999999999999999e-6,
    ];
    let mut robot = pendulum();
    for (k, v) in values.iter().enumerate() {
        let arm = robot.link_mut("arm").unwrap();
        let mut i = arm.inertial.unwrap();
        i.mass = *v;
        i.inertia.ixy = -*v;
        i.origin = Pose::new(i.origin.xyz, [*v, 0.5 * v, 0.0]);
        arm.inertial = Some(i);
        let back = urdf::from_str(&urdf::to_string(&robot)).unwrap();
        let got = back.link("arm").unwrap().inertial.unwrap();
        assert_eq!(got.mass.to_bits(), v.to_bits(), "value #{k} {v:e}");
        assert_eq!(got.inertia.ixy.to_bits(), (-*v).to_bits(), "value #{k}");
        assert_eq!(
            got.origin.rpy()[1].to_bits(),
            (0.5 * v).to_bits(),
            "value #{k}"
        );
    }
    // Small and huge numbers use exponent notation, ordinary ones do not.
    robot
        .link_mut("arm")
        .unwrap()
        .inertial
        .as_mut()
        .unwrap()
        .mass = 1.5e-300;
    let text = urdf::to_string(&robot);
    assert!(text.contains("<mass value=\"1.5e-300\"/>"), "{text}");
    assert!(text.contains("ixx=\"0.02093333333333333\""), "{text}");
}

#[test]
fn names_and_values_are_escaped() {
    let odd = "a&b<c>\"d\"'e'\tf\ng/h é";
    let mut robot = pendulum();
    robot.name = odd.to_string();
    robot.links[1].name = odd.to_string();
    robot.joints[0].child = odd.to_string();
    robot.links[0].visuals[0].geometry = Geometry::Mesh {
        filename: "file:///tmp/a b&c.stl".to_string(),
        scale: Some([0.001, 0.001, 0.001]),
    };
    robot.links[0].visuals[0].material = Some(Material {
        name: "<m>".into(),
        rgba: Some([1.0, 0.5, 0.25, 1.0]),
        texture: Some("t&x.png".into()),
    });
    robot
        .robot_attributes
        .push(("version".into(), "1.0 \"beta\"".into()));
    let text = urdf::to_string(&robot);
    assert!(
        text.contains("name=\"a&amp;b&lt;c&gt;&quot;d&quot;'e'&#9;f&#10;g/h é\""),
        "{text}"
    );
    assert_eq!(urdf::from_str(&text).unwrap(), robot);
}

#[test]
fn frames_become_links_with_fixed_joints() {
    let robot = DescriptionBuilder::new("r")
        .link("base")
        .done()
        .link("tool")
        .done()
        .fixed("mount", "base", "tool")
        .done()
        .frame("imu", "base", Pose::new([0.1, 0.0, 0.2], [0.0, 0.0, 1.0]))
        .build()
        .unwrap();
    let text = urdf::to_string(&robot);
    assert!(text.contains(
        "  <link name=\"imu\"/>\n  <joint name=\"imu_frame_joint\" type=\"fixed\">\n    <origin xyz=\"0.1 0 0.2\" rpy=\"0 0 1\"/>\n    <parent link=\"base\"/>\n    <child link=\"imu\"/>\n  </joint>\n"
    ), "{text}");
    let back = urdf::from_str(&text).unwrap();
    assert!(back.frames.is_empty());
    assert_eq!(back.links.len(), 3);
    let j = back.joint("imu_frame_joint").unwrap();
    assert_eq!(
        (j.kind, j.parent.as_str(), j.child.as_str()),
        (JointKind::Fixed, "base", "imu")
    );
    assert_eq!(j.origin, Pose::new([0.1, 0.0, 0.2], [0.0, 0.0, 1.0]));
    assert!(back.link("imu").unwrap().inertial.is_none());
}

/// MJCF names bodies and sites apart, URDF names every link in one namespace: a frame
/// named like a link (Open Duck Mini v2's `left_foot` body and site), like another
/// frame, or like a joint's `<frame>_frame_joint`, is written under a name of its own,
/// and the file reads back (twinloop's reader, like urdfdom, refuses a repeated name).
#[test]
fn frames_named_like_links_are_written_under_names_of_their_own() {
    let robot = DescriptionBuilder::new("r")
        .link("base")
        .done()
        .link("foot")
        .done()
        .link("foot_frame")
        .done()
        .fixed("ankle", "base", "foot")
        .done()
        .fixed("foot_frame_joint", "foot", "foot_frame")
        .done()
        .frame("foot", "foot", Pose::from_xyz([0.0, 0.0, -0.1]))
        .frame("foot", "base", Pose::from_xyz([0.0, 0.0, -0.2]))
        .build()
        .unwrap();
    let text = urdf::to_string(&robot);
    assert!(text.contains(
        "  <!-- frame \"foot\" written as link \"foot_frame2\": a link has its name -->\n  <link name=\"foot_frame2\"/>\n  <joint name=\"foot_frame_joint2\" type=\"fixed\">\n"
    ), "{text}");
    assert!(
        text.contains("<link name=\"foot_frame3\"/>\n  <joint name=\"foot_frame_joint3\""),
        "{text}"
    );
    let back = urdf::from_str(&text).unwrap();
    assert_eq!(back.links.len(), 5);
    let j = back.joint("foot_frame_joint3").unwrap();
    assert_eq!(
        (j.parent.as_str(), j.child.as_str()),
        ("base", "foot_frame3")
    );
    assert_eq!(j.origin, Pose::from_xyz([0.0, 0.0, -0.2]));
}

#[test]
fn capsules_are_written_as_cylinders_with_a_note() {
    let mut robot = pendulum();
    robot.links[1].collisions.push(Shape {
        name: Some("c".into()),
        origin: Pose::from_xyz([0.0, 0.0, -0.25]),
        geometry: Geometry::Capsule {
            radius: 0.02,
            length: 0.5,
        },
        material: None,
    });
    let text = urdf::to_string(&robot);
    assert!(text.contains("<!-- capsule (radius 0.02, length 0.5): URDF has no capsule, written as a cylinder -->\n        <cylinder radius=\"0.02\" length=\"0.5\"/>"), "{text}");
    let back = urdf::from_str(&text).unwrap();
    assert_eq!(
        back.links[1].collisions[0].geometry,
        Geometry::Cylinder {
            radius: 0.02,
            length: 0.5
        }
    );
}

#[test]
fn all_optional_joint_parts_round_trip() {
    let text = r#"<robot name="r" version="1.0">
  <material name="blue"><color rgba="0 0 1 1"/></material>
  <link name="a"><visual name="v"><geometry><sphere radius="0.1"/></geometry><material name="blue"/></visual>
    <collision><origin xyz="1 2 3"/><geometry><cylinder radius="0.1" length="0.2"/></geometry></collision>
    <self_collision_checking/></link>
  <link name="b"/>
  <link name="c"/>
  <joint name="j" type="prismatic">
    <parent link="a"/><child link="b"/>
    <limit lower="0" upper="0.5" effort="100" velocity="0.5"/>
    <safety_controller soft_lower_limit="0.01" soft_upper_limit="0.49" k_position="10" k_velocity="20"/>
    <calibration rising="0.1"/>
    <dynamics friction="0.3"/>
  </joint>
  <joint name="k" type="continuous"><parent link="b"/><child link="c"/>
    <mimic joint="j"/><vendor:thing xmlns:vendor="urn:v" a="1">text &amp; more</vendor:thing></joint>
  <gazebo reference="a"><material>Gazebo/Blue</material></gazebo>
</robot>"#;
    let r = urdf::from_str(text).unwrap();
    let j = r.joint("j").unwrap();
    assert_eq!(j.safety_controller.unwrap().k_velocity, Some(20.0));
    assert_eq!(j.calibration.unwrap().rising, Some(0.1));
    assert_eq!(j.calibration.unwrap().falling, None);
    assert_eq!(j.dynamics.unwrap().damping, None);
    assert_eq!(j.axis, None);
    let k = r.joint("k").unwrap();
    assert_eq!(k.mimic.as_ref().unwrap().multiplier, 1.0);
    assert_eq!(
        k.extra[0].0,
        "<vendor:thing xmlns:vendor=\"urn:v\" a=\"1\">text &amp; more</vendor:thing>"
    );
    assert_eq!(r.links[0].extra[0].0, "<self_collision_checking/>");
    assert_eq!(
        r.robot_attributes,
        vec![("version".to_string(), "1.0".to_string())]
    );
    assert_eq!(
        r.order,
        vec![
            Item::Material(0),
            Item::Link(0),
            Item::Link(1),
            Item::Link(2),
            Item::Joint(0),
            Item::Joint(1),
            Item::Extension(0)
        ]
    );
    let back = urdf::from_str(&urdf::to_string(&r)).unwrap();
    assert_eq!(back, r);
}

/// An MJCF slide without `range` (MS-Human-700's pelvis translations) is written
/// with `lower` and `upper` (URDF's default for both is 0, a pinned joint, and
/// yourdfpy's strict check refuses them missing) spanning a finite width, and
/// reads back as unlimited.
#[test]
fn unlimited_slides_are_written_with_a_wide_finite_range() {
    let robot = mjcf::from_str(
        r#"<mujoco><worldbody><body name="pelvis">
  <joint name="tx" type="slide" axis="1 0 0" limited="false" range="-5 5"/>
  <joint name="ty" type="slide" axis="0 1 0"/>
  <geom type="sphere" size="0.1" mass="2"/>
  <body name="leg"><joint name="knee" type="slide" range="-0.1 0.2"/><geom size="0.05"/></body>
</body></worldbody></mujoco>"#,
    )
    .unwrap();
    let text = urdf::to_string(&robot);
    let limits: Vec<&str> = text.lines().filter(|l| l.contains("<limit")).collect();
    assert_eq!(limits.len(), 3, "{text}");
    let attr = |line: &str, name: &str| -> f64 {
        let at = line.find(&format!(" {name}=\"")).unwrap() + name.len() + 3;
        line[at..].split('"').next().unwrap().parse().unwrap()
    };
    for line in &limits {
        let (lo, hi) = (attr(line, "lower"), attr(line, "upper"));
        assert!(lo < hi && (hi - lo).is_finite(), "{line}");
        assert_eq!(attr(line, "effort"), urdf::UNKNOWN_LIMIT, "{line}");
    }
    let unlimited: Vec<_> = limits.iter().filter(|l| attr(l, "upper") > 1e300).collect();
    assert_eq!(unlimited.len(), 2, "{text}");
    assert!(
        unlimited
            .iter()
            .all(|l| attr(l, "lower") == -urdf::UNLIMITED_SLIDE)
    );
    let back = urdf::from_str(&text).unwrap();
    for name in ["tx", "ty"] {
        let j = back.joint(name).unwrap();
        assert_eq!(j.kind, JointKind::Prismatic);
        assert_eq!(j.limit, None, "{name}");
    }
    let knee = back.joint("knee").unwrap().limit.unwrap();
    assert_eq!((knee.lower, knee.upper), (Some(-0.1), Some(0.2)));
}
