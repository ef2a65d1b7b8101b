//! Malformed URDFs give errors that name the line, column and element.

use twinloop_description::{DescriptionError, urdf};

/// A small valid URDF; the tests below break one line of it.
const GOOD: &str = r#"<?xml version="1.0"?>
<robot name="t">
  <link name="base"/>
  <link name="thigh">
    <inertial>
      <origin xyz="0 0 -0.1" rpy="0 0 0"/>
      <mass value="1.5"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.001"/>
    </inertial>
    <visual>
      <geometry><box size="0.1 0.1 0.2"/></geometry>
      <material name="red"><color rgba="1 0 0 1"/></material>
    </visual>
  </link>
  <joint name="hip" type="revolute">
    <origin xyz="0 0 0" rpy="0 0 0"/>
    <parent link="base"/>
    <child link="thigh"/>
    <axis xyz="0 1 0"/>
    <limit lower="-1" upper="1" effort="10" velocity="2"/>
  </joint>
</robot>
"#;

/// `GOOD` with one piece of text replaced (it must occur exactly once).
fn with(from: &str, to: &str) -> String {
    assert_eq!(GOOD.matches(from).count(), 1, "{from}");
    GOOD.replacen(from, to, 1)
}

fn err(text: &str) -> DescriptionError {
    match urdf::from_str(text) {
        Ok(_) => panic!("expected an error for:\n{text}"),
        Err(e) => e,
    }
}

/// The error is on `line`, names `element`, and says `says`.
fn check(e: &DescriptionError, line: u32, element: &str, says: &str) {
    let shown = e.to_string();
    assert_eq!(e.location.line, Some(line), "line of: {shown}");
    assert!(e.location.column.is_some(), "column of: {shown}");
    assert!(shown.starts_with(&format!("line {line}:")), "{shown}");
    let el = e.location.element.as_deref().unwrap_or("");
    assert!(el.contains(element), "element {element:?} in: {shown}");
    assert!(e.message.contains(says), "{says:?} in: {shown}");
}

#[test]
fn the_template_is_valid() {
    let r = urdf::from_str(GOOD).unwrap();
    assert_eq!((r.links.len(), r.joints.len()), (2, 1));
}

#[test]
fn unknown_joint_type() {
    let e = err(&with(r#"type="revolute""#, r#"type="hinge""#));
    check(
        &e,
        15,
        r#"<joint name="hip">"#,
        r#"unknown joint type "hinge""#,
    );
    assert!(
        e.to_string()
            .starts_with(r#"line 15:21: <joint name="hip">: unknown joint type "hinge""#),
        "{e}"
    );
}

#[test]
fn malformed_xml() {
    // An unclosed element: the parser's position becomes the error's.
    let e = err(&with("<parent link=\"base\"/>", "<parent link=\"base\">"));
    assert_eq!(e.location.line, Some(21), "{e}");
    assert!(e.message.starts_with("malformed XML"), "{e}");
    // An attribute without quotes.
    let e = err(&with(r#"<mass value="1.5"/>"#, r#"<mass value=1.5/>"#));
    assert_eq!(e.location.line, Some(7), "{e}");
    // Not XML at all, and empty text.
    assert!(err("robot").message.starts_with("malformed XML"));
    assert!(err("").message.starts_with("malformed XML"));
}

#[test]
fn truncated_xml_points_at_the_end() {
    let cut = &GOOD[..GOOD.find("<axis").unwrap()];
    let e = err(cut);
    assert!(e.message.starts_with("malformed XML"), "{e}");
    assert_eq!(e.location.line, Some(19), "{e}");
    let cut = &GOOD[..GOOD.find("1.5").unwrap() + 2];
    let e = err(cut);
    assert_eq!(e.location.line, Some(7), "{e}");
}

#[test]
fn root_element_must_be_robot() {
    let e = err("<?xml version=\"1.0\"?>\n<mujoco model=\"x\"/>");
    check(&e, 2, "<mujoco>", "root element is <mujoco>");
}

#[test]
fn missing_required_attributes() {
    check(
        &err(&with(r#" type="revolute""#, "")),
        15,
        r#"<joint name="hip">"#,
        r#"missing attribute "type""#,
    );
    check(
        &err(&with(r#"<joint name="hip""#, "<joint")),
        15,
        "<joint>",
        r#"missing attribute "name""#,
    );
    check(
        &err(&with(r#"<parent link="base"/>"#, "<parent/>")),
        17,
        r#"<parent> in <joint name="hip">"#,
        r#"missing attribute "link""#,
    );
    check(
        &err(&with(r#"<child link="thigh"/>"#, "<child/>")),
        18,
        r#"<child> in <joint name="hip">"#,
        r#"missing attribute "link""#,
    );
    check(
        &err(&with(r#"<link name="thigh">"#, "<link>")),
        4,
        "<link>",
        r#"missing attribute "name""#,
    );
    check(
        &err(&with(r#"<parent link="base"/>"#, "")),
        15,
        r#"<joint name="hip">"#,
        "missing <parent>",
    );
    check(
        &err(&with(r#"<mass value="1.5"/>"#, "")),
        5,
        r#"<inertial> in <link name="thigh">"#,
        "missing <mass>",
    );
    check(
        &err(&with(r#" izz="0.001""#, "")),
        8,
        r#"<inertia> in <inertial> in <link name="thigh">"#,
        r#"missing attribute "izz""#,
    );
    check(
        &err(&with(r#"<box size="0.1 0.1 0.2"/>"#, "")),
        11,
        r#"<geometry> in <visual> in <link name="thigh">"#,
        "no shape",
    );
}

#[test]
fn bad_numbers() {
    let cases = [
        (
            r#"<mass value="1.5"/>"#,
            r#"<mass value="1.5kg"/>"#,
            7,
            "<mass>",
            "not a number",
        ),
        (
            r#"<mass value="1.5"/>"#,
            r#"<mass value="NaN"/>"#,
            7,
            "<mass>",
            "not finite",
        ),
        (
            r#"<mass value="1.5"/>"#,
            r#"<mass value="inf"/>"#,
            7,
            "<mass>",
            "not finite",
        ),
        (
            r#"<mass value="1.5"/>"#,
            r#"<mass value="1e999"/>"#,
            7,
            "<mass>",
            "not finite",
        ),
        (
            r#"lower="-1""#,
            r#"lower="-1,0""#,
            20,
            "<limit>",
            "not a number",
        ),
        (
            r#"<axis xyz="0 1 0"/>"#,
            r#"<axis xyz="0 nan 0"/>"#,
            19,
            "<axis>",
            "not finite",
        ),
        (
            r#"xyz="0 0 -0.1""#,
            r#"xyz="0 0 -O.1""#,
            6,
            "<origin>",
            "not a number",
        ),
        (
            r#"ixy="0""#,
            r#"ixy="-infinity""#,
            8,
            "<inertia>",
            "not finite",
        ),
    ];
    for (from, to, line, element, says) in cases {
        check(&err(&with(from, to)), line, element, says);
    }
}

#[test]
fn wrong_count_of_numbers() {
    let cases = [
        (
            r#"xyz="0 0 -0.1""#,
            r#"xyz="0 -0.1""#,
            6,
            "<origin> in <inertial>",
            "expected 3 numbers, found 2",
        ),
        (
            r#"<origin xyz="0 0 0" rpy="0 0 0"/>"#,
            r#"<origin xyz="0 0 0" rpy="0 0 0 0"/>"#,
            16,
            r#"<origin> in <joint name="hip">"#,
            "expected 3 numbers, found 4",
        ),
        (
            r#"size="0.1 0.1 0.2""#,
            r#"size="0.1 0.2""#,
            11,
            "<box>",
            "expected 3 numbers, found 2",
        ),
        (
            r#"rgba="1 0 0 1""#,
            r#"rgba="1 0 0""#,
            12,
            "<color>",
            "expected 4 numbers, found 3",
        ),
        (
            r#"<axis xyz="0 1 0"/>"#,
            r#"<axis xyz=""/>"#,
            19,
            "<axis>",
            "expected 3 numbers, found 0",
        ),
    ];
    for (from, to, line, element, says) in cases {
        check(&err(&with(from, to)), line, element, says);
    }
}

#[test]
fn missing_links_are_placed_at_the_joint() {
    check(
        &err(&with(
            r#"<parent link="base"/>"#,
            r#"<parent link="pelvis"/>"#,
        )),
        15,
        r#"<joint name="hip">"#,
        r#"parent link "pelvis" does not exist"#,
    );
    check(
        &err(&with(r#"<child link="thigh"/>"#, r#"<child link="shin"/>"#)),
        15,
        r#"<joint name="hip">"#,
        r#"child link "shin" does not exist"#,
    );
}

#[test]
fn duplicate_names_point_at_the_second() {
    let text = with(
        "  <link name=\"base\"/>\n",
        "  <link name=\"base\"/>\n  <link name=\"base\"/>\n",
    );
    check(
        &err(&text),
        4,
        r#"<link name="base">"#,
        "duplicate link name",
    );
    let joint2 = "  <joint name=\"hip\" type=\"fixed\"><parent link=\"thigh\"/><child link=\"foot\"/></joint>\n  <link name=\"foot\"/>\n</robot>";
    let text = with("</robot>", joint2);
    check(
        &err(&text),
        22,
        r#"<joint name="hip">"#,
        "duplicate joint name",
    );
}

#[test]
fn cycles_and_forests() {
    // thigh -> foot -> thigh: both have a parent, base stays the one root.
    let extra = "  <link name=\"foot\"/>\n  <joint name=\"ankle\" type=\"fixed\"><parent link=\"thigh\"/><child link=\"foot\"/></joint>\n  <joint name=\"loop\" type=\"fixed\"><parent link=\"foot\"/><child link=\"thigh\"/></joint>\n</robot>";
    let e = err(&with("</robot>", extra));
    assert!(
        e.message.contains("more than one joint") || e.message.contains("cycle"),
        "{e}"
    );
    assert_eq!(e.location.line, Some(24), "{e}");
    // A pure cycle: no root at all.
    let text = "<robot name=\"c\">\n  <link name=\"a\"/>\n  <link name=\"b\"/>\n  <joint name=\"ab\" type=\"fixed\"><parent link=\"a\"/><child link=\"b\"/></joint>\n  <joint name=\"ba\" type=\"fixed\"><parent link=\"b\"/><child link=\"a\"/></joint>\n</robot>";
    let e = err(text);
    assert!(e.message.contains("cycle"), "{e}");
    assert!(e.location.line.is_some(), "{e}");
    // Two roots: placed at <robot>.
    let e = err(&with("</robot>", "  <link name=\"loose\"/>\n</robot>"));
    assert!(e.message.contains("2 root links"), "{e}");
    assert_eq!(e.location.line, Some(2), "{e}");
    // A joint from a link to itself.
    let e = err(&with(r#"<child link="thigh"/>"#, r#"<child link="base"/>"#));
    check(&e, 15, r#"<joint name="hip">"#, "itself");
}

#[test]
fn zero_axis_only_on_fixed_joints() {
    let e = err(&with(r#"<axis xyz="0 1 0"/>"#, r#"<axis xyz="0 0 0"/>"#));
    check(&e, 15, r#"<joint name="hip">"#, "zero axis");
    let ok = with(r#"<axis xyz="0 1 0"/>"#, r#"<axis xyz="0 0 0"/>"#)
        .replace(r#"type="revolute""#, r#"type="fixed""#);
    assert_eq!(urdf::from_str(&ok).unwrap().joints[0].axis, Some([0.0; 3]));
}

#[test]
fn unknown_geometry() {
    let e = err(&with(
        r#"<box size="0.1 0.1 0.2"/>"#,
        r#"<capsule radius="0.1" length="0.2"/>"#,
    ));
    check(&e, 11, "<capsule>", "unknown geometry <capsule>");
}

#[test]
fn defaults_when_optional_parts_are_missing() {
    let text = with(r#"<origin xyz="0 0 0" rpy="0 0 0"/>"#, "")
        .replace(
            r#"<limit lower="-1" upper="1" effort="10" velocity="2"/>"#,
            r#"<limit effort="10"/>"#,
        )
        .replace(
            r#"<origin xyz="0 0 -0.1" rpy="0 0 0"/>"#,
            r#"<origin xyz="0 0 -0.1"/>"#,
        );
    let r = urdf::from_str(&text).unwrap();
    let j = &r.joints[0];
    assert_eq!(j.origin, twinloop_description::Pose::IDENTITY);
    let l = j.limit.unwrap();
    assert_eq!(
        (l.lower, l.upper, l.effort, l.velocity),
        (None, None, Some(10.0), None)
    );
    assert_eq!(r.links[1].inertial.unwrap().origin.rpy(), [0.0; 3]);
}
