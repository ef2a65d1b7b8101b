//! Visual-only details that Pinocchio's URDF parser reads past are read past
//! here too, each with an `ignored-detail` lint warning, instead of refusing the
//! whole file.

use twinloop_description::lint::{Severity, codes, lint};
use twinloop_description::{Geometry, urdf};

const ROBOT: &str = r#"<robot name="r">
  <material name="skin"><color rgba="1 1 1 1"/><texture/></material>
  <link name="base">
    <inertial><mass value="1"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial>
    <visual><geometry><mesh filename="m.stl" scale="0.001 0.001 0.001 1"/></geometry></visual>
  </link>
</robot>
"#;

#[test]
fn texture_without_file_and_four_number_scale_are_warnings() {
    let robot = urdf::from_str(ROBOT).unwrap();
    assert_eq!(robot.materials[0].texture, None);
    assert_eq!(
        robot.links[0].visuals[0].geometry,
        Geometry::Mesh {
            filename: "m.stl".into(),
            scale: Some([0.001; 3])
        }
    );
    let report = lint(&robot);
    let found: Vec<_> = report.with_code(codes::IGNORED_DETAIL).collect();
    assert_eq!(found.len(), 2, "{found:#?}");
    assert!(found.iter().all(|f| f.severity == Severity::Warning));
    assert!(
        found[0]
            .message
            .starts_with("line 2: a <texture> without a filename")
    );
    assert!(
        found[1]
            .message
            .starts_with("line 5: scale=\"0.001 0.001 0.001 1\" has 4 numbers")
    );
    // Five numbers are still an error.
    let e = urdf::from_str(&ROBOT.replace("0.001 1\"", "0.001 1 1\"")).unwrap_err();
    assert!(e.message.contains("expected 3 numbers"), "{e}");
}

#[test]
fn a_blank_line_before_the_xml_declaration_is_read_past_with_lines_kept() {
    let dir = std::env::temp_dir().join(format!("twinloop-urdf-decl-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("late.urdf");
    let text = format!(
        "\n<?xml version=\"1.0\"?>\n{}",
        ROBOT.replace("<mass value=\"1\"/>", "<mass value=\"x\"/>")
    );
    std::fs::write(&path, &text).unwrap();
    // The declaration no longer stops the reader: the error is the bad mass, on
    // its own line (6: two lines were added in front).
    let e = twinloop_description::load(&path).unwrap_err();
    assert_eq!(e.location.line, Some(6), "{e}");
    assert!(
        e.message.contains("mass") || e.to_string().contains("mass"),
        "{e}"
    );
    std::fs::write(&path, format!("\n<?xml version=\"1.0\"?>\n{ROBOT}")).unwrap();
    assert_eq!(twinloop_description::load(&path).unwrap().links.len(), 1);
    std::fs::remove_dir_all(&dir).unwrap();
}
