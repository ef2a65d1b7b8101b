//! MJCF features on small inline models, errors with their places, and
//! mutation fuzzing of a real MJCF.

use std::f64::consts::PI;
use std::panic::{AssertUnwindSafe, catch_unwind};
use twinloop_description::{
    Description, DescriptionError, Geometry, JointKind, Pose, mjcf, rpy_to_matrix,
};

fn ok(text: &str) -> Description {
    mjcf::from_str(text).unwrap_or_else(|e| panic!("{e}"))
}

fn err(text: &str) -> DescriptionError {
    match mjcf::from_str(text) {
        Ok(_) => panic!("expected an error for:\n{text}"),
        Err(e) => e,
    }
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() < 1e-12
}

fn close3(a: [f64; 3], b: [f64; 3]) -> bool {
    (0..3).all(|i| close(a[i], b[i]))
}

fn apply(p: &Pose, v: [f64; 3]) -> [f64; 3] {
    let r = p.rotation();
    [
        r[0][0] * v[0] + r[0][1] * v[1] + r[0][2] * v[2] + p.xyz[0],
        r[1][0] * v[0] + r[1][1] * v[1] + r[1][2] * v[2] + p.xyz[1],
        r[2][0] * v[0] + r[2][1] * v[1] + r[2][2] * v[2] + p.xyz[2],
    ]
}

#[test]
fn angles_are_degrees_unless_said_otherwise() {
    let text = r#"<mujoco model="m">
  <worldbody>
    <body name="a">
      <body name="b" pos="1 0 0" euler="0 0 90">
        <joint name="j" range="-90 45"/>
      </body>
      <body name="c" axisangle="0 0 1 180"/>
    </body>
  </worldbody>
</mujoco>"#;
    let r = ok(text);
    let j = r.joint("j").unwrap();
    assert_eq!(j.kind, JointKind::Revolute);
    let l = j.limit.unwrap();
    assert!(close(l.lower.unwrap(), -PI / 2.0) && close(l.upper.unwrap(), PI / 4.0));
    assert!(close(j.origin.rpy()[2], PI / 2.0), "{:?}", j.origin);
    assert_eq!(j.axis, Some([0.0, 0.0, 1.0]));
    assert!(close(r.joint("c_fixed").unwrap().origin.rpy()[2].abs(), PI));
    let radian = text.replace(
        "<mujoco model=\"m\">",
        "<mujoco model=\"m\">\n  <compiler angle=\"radian\"/>",
    );
    let r = ok(&radian);
    let l = r.joint("j").unwrap().limit.unwrap();
    assert_eq!((l.lower, l.upper), (Some(-90.0), Some(45.0)));
}

#[test]
fn euler_sequences() {
    // Intrinsic xyz (MuJoCo's default): R = Rx(a) Ry(b) Rz(c).
    let r = ok(
        r#"<mujoco><compiler angle="radian"/><worldbody><body name="a">
      <body name="b" euler="0.3 0.2 0.1"/></body></worldbody></mujoco>"#,
    );
    let got = r.joints[0].origin.rotation();
    let rx = rpy_to_matrix([0.3, 0.0, 0.0]);
    let ry = rpy_to_matrix([0.0, 0.2, 0.0]);
    let rz = rpy_to_matrix([0.0, 0.0, 0.1]);
    let mul = |a: [[f64; 3]; 3], b: [[f64; 3]; 3]| {
        let mut m = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                m[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
            }
        }
        m
    };
    let want = mul(mul(rx, ry), rz);
    for i in 0..3 {
        assert!(close3(got[i], want[i]), "{got:?} vs {want:?}");
    }
    // Extrinsic XYZ is URDF's rpy.
    let r = ok(
        r#"<mujoco><compiler angle="radian" eulerseq="XYZ"/><worldbody><body name="a">
      <body name="b" euler="0.3 0.2 0.1"/></body></worldbody></mujoco>"#,
    );
    assert!(
        close3(r.joints[0].origin.rpy(), [0.3, 0.2, 0.1]),
        "{:?}",
        r.joints[0].origin
    );
}

#[test]
fn quaternions_are_normalised_and_other_orientations_work() {
    let r = ok(r#"<mujoco><worldbody><body name="a">
      <body name="q" quat="1 1 0 0"/>
      <body name="z" zaxis="0 0 -1"/>
      <body name="xy" xyaxes="0 1 0 -1 0 0"/>
    </body></worldbody></mujoco>"#);
    assert!(close3(
        r.joint("q_fixed").unwrap().origin.rpy(),
        [PI / 2.0, 0.0, 0.0]
    ));
    let z = r.joint("z_fixed").unwrap().origin.rotation();
    assert!(close(z[2][2], -1.0));
    assert!(close3(
        r.joint("xy_fixed").unwrap().origin.rpy(),
        [0.0, 0.0, PI / 2.0]
    ));
}

#[test]
fn default_classes_nest_and_childclass_applies() {
    // The meshes are not there: no inertia from geoms (MuJoCo would need them).
    let r = ok(r#"<mujoco>
  <compiler angle="radian" meshdir="meshes/" inertiafromgeom="false"/>
  <default>
    <joint axis="0 1 0" damping="0.5"/>
    <mesh scale="0.001 0.001 0.001"/>
    <geom type="box" size="0.1 0.2 0.3"/>
    <default class="arm">
      <joint range="-1 1" frictionloss="0.2"/>
      <default class="hand">
        <joint axis="1 0 0"/>
        <geom type="sphere" size="0.05" group="3"/>
      </default>
    </default>
  </default>
  <asset>
    <mesh file="parts/upper arm.stl"/>
    <mesh name="m2" file="/abs/hand.stl" scale="1 1 2"/>
  </asset>
  <worldbody>
    <body name="base">
      <geom/>
      <body name="upper" childclass="arm">
        <joint name="shoulder"/>
        <geom type="mesh" mesh="upper arm"/>
        <body name="hand">
          <joint name="wrist" class="hand" range="-2 2"/>
          <geom class="hand"/>
          <geom type="mesh" mesh="m2"/>
        </body>
      </body>
      <body name="free_spin">
        <joint name="spin" limited="false" range="-1 1"/>
      </body>
    </body>
  </worldbody>
</mujoco>"#);
    let s = r.joint("shoulder").unwrap();
    assert_eq!(s.axis, Some([0.0, 1.0, 0.0]));
    assert_eq!(s.kind, JointKind::Revolute);
    let d = s.dynamics.unwrap();
    assert_eq!((d.damping, d.friction), (Some(0.5), Some(0.2)));
    let w = r.joint("wrist").unwrap();
    assert_eq!(w.axis, Some([1.0, 0.0, 0.0]));
    assert_eq!(w.limit.unwrap().upper, Some(2.0));
    assert_eq!(r.joint("spin").unwrap().kind, JointKind::Continuous);
    assert_eq!(r.joint("spin").unwrap().limit, None);
    let base = r.link("base").unwrap();
    assert_eq!(
        base.visuals[0].geometry,
        Geometry::Box {
            size: [0.2, 0.4, 0.6]
        }
    );
    assert_eq!(base.collisions.len(), 1);
    let upper = r.link("upper").unwrap();
    assert_eq!(
        upper.visuals[0].geometry,
        Geometry::Mesh {
            filename: "meshes/parts/upper arm.stl".into(),
            scale: Some([0.001; 3])
        }
    );
    let hand = r.link("hand").unwrap();
    // The group-3 sphere is collision only; the mesh geom is both.
    assert_eq!(hand.visuals.len(), 1);
    assert_eq!(hand.collisions.len(), 2);
    assert_eq!(
        hand.collisions[0].geometry,
        Geometry::Sphere { radius: 0.05 }
    );
    assert_eq!(
        hand.visuals[0].geometry,
        Geometry::Mesh {
            filename: "/abs/hand.stl".into(),
            scale: Some([1.0, 1.0, 2.0])
        }
    );
}

#[test]
fn geoms_sites_materials() {
    let r = ok(r#"<mujoco>
  <asset><material name="red" rgba="1 0 0 1"/></asset>
  <worldbody>
    <geom type="plane" size="1 1 0.1"/>
    <body name="b">
      <inertial pos="0 0 0.1" mass="2" diaginertia="0.1 0.2 0.3"/>
      <geom name="cap" type="capsule" fromto="0 0 0 0 0 0.4" size="0.05" material="red"/>
      <geom type="cylinder" size="0.1 0.2" pos="1 0 0" rgba="0 1 0 1" contype="0" conaffinity="0"/>
      <geom type="box" fromto="0 0 0 0.2 0 0" size="0.01 0.02"/>
      <geom type="ellipsoid" size="0.1 0.2 0.3"/>
      <site name="tip" pos="0 0 0.4"/>
      <site pos="0 0 0.2"/>
    </body>
  </worldbody>
</mujoco>"#);
    let b = r.link("b").unwrap();
    assert_eq!(r.links.len(), 1);
    assert!(r.joints.is_empty());
    assert_eq!(b.visuals.len(), 3);
    assert_eq!(b.collisions.len(), 2);
    let cap = &b.visuals[0];
    assert_eq!(cap.name.as_deref(), Some("cap"));
    assert_eq!(
        cap.geometry,
        Geometry::Capsule {
            radius: 0.05,
            length: 0.4
        }
    );
    assert!(close3(cap.origin.xyz, [0.0, 0.0, 0.2]) && close3(cap.origin.rpy(), [0.0; 3]));
    let m = cap.material.as_ref().unwrap();
    assert_eq!(
        (m.name.as_str(), m.rgba),
        ("red", Some([1.0, 0.0, 0.0, 1.0]))
    );
    let cyl = &b.visuals[1];
    assert_eq!(
        cyl.geometry,
        Geometry::Cylinder {
            radius: 0.1,
            length: 0.4
        }
    );
    assert_eq!(
        cyl.material.as_ref().unwrap().rgba,
        Some([0.0, 1.0, 0.0, 1.0])
    );
    assert_eq!(cyl.material.as_ref().unwrap().name, "b_geom2_material");
    // A box along x from fromto: its z axis turned onto x; MuJoCo makes its
    // cross-section square from size[0] (compiled geom_size 0.01 0.01 0.1).
    let bx = &b.visuals[2];
    assert_eq!(
        bx.geometry,
        Geometry::Box {
            size: [0.02, 0.02, 0.2]
        }
    );
    let z = bx.origin.rotation();
    assert!(close3([z[0][2], z[1][2], z[2][2]], [1.0, 0.0, 0.0]));
    assert!(close3(bx.origin.xyz, [0.1, 0.0, 0.0]));
    assert_eq!(r.frames.len(), 2);
    assert_eq!(r.frames[0].name, "tip");
    assert_eq!(r.frames[1].name, "b_site2");
    assert_eq!(r.frames[1].origin.xyz, [0.0, 0.0, 0.2]);
    let i = b.inertial.unwrap();
    assert_eq!(
        (i.mass, i.inertia.iyy, i.origin.xyz),
        (2.0, 0.2, [0.0, 0.0, 0.1])
    );
}

/// A hinge with `pos`: the axis passes through that point of the body. The
/// link frame is put there, so everything in the body moves by -pos.
#[test]
fn hinge_pos_moves_the_link_frame_to_the_axis() {
    let r = ok(r#"<mujoco><compiler angle="radian"/><worldbody>
  <body name="a">
    <body name="b" pos="1 0 0">
      <joint name="j" pos="0 1 0" axis="0 0 1"/>
      <inertial pos="0.5 0 0" mass="1" diaginertia="1 1 1"/>
      <site name="origin_of_b"/>
      <body name="c" pos="2 0 0"/>
    </body>
  </body>
</worldbody></mujoco>"#);
    let j = r.joint("j").unwrap();
    assert_eq!(j.kind, JointKind::Continuous);
    assert!(close3(j.origin.xyz, [1.0, 1.0, 0.0]));
    let site = &r.frames[0];
    assert!(close3(site.origin.xyz, [0.0, -1.0, 0.0]));
    assert!(close3(
        r.link("b").unwrap().inertial.unwrap().origin.xyz,
        [0.5, -1.0, 0.0]
    ));
    assert!(close3(
        r.joint("c_fixed").unwrap().origin.xyz,
        [2.0, -1.0, 0.0]
    ));
    // Where body b's origin goes when the hinge turns by t, MuJoCo's way: about
    // the vertical line through (1, 1, 0): (1 + sin t, 1 - cos t, 0).
    for t in [0.0, 0.3, -1.2, 2.5] {
        let joint_frame = Pose::new(j.origin.xyz, [0.0, 0.0, t]);
        let p = apply(&joint_frame, site.origin.xyz);
        assert!(
            close3(p, [1.0 + t.sin(), 1.0 - t.cos(), 0.0]),
            "t={t}: {p:?}"
        );
    }
}

#[test]
fn root_body_cases() {
    // Free joint: the body is the root, no world link, no joint.
    let r = ok(
        r#"<mujoco><worldbody><body name="pelvis" pos="0 0 1"><freejoint/>
      <body name="leg"><joint type="slide" axis="0 0 2" range="-0.1 0.2"/></body></body></worldbody></mujoco>"#,
    );
    assert_eq!(r.root_link(), Some("pelvis"));
    assert_eq!(r.joints.len(), 1);
    let s = &r.joints[0];
    assert_eq!(
        (s.name.as_str(), s.kind),
        ("leg_joint", JointKind::Prismatic)
    );
    assert_eq!(s.axis, Some([0.0, 0.0, 1.0]));
    assert_eq!(s.limit.unwrap().upper, Some(0.2)); // no degree conversion for slides
    let r2 = ok(
        r#"<mujoco><worldbody><body name="pelvis"><joint type="free"/></body></worldbody></mujoco>"#,
    );
    assert_eq!((r2.links.len(), r2.joints.len()), (1, 0));
    // A hinge on the top body: a world link is added.
    let r = ok(
        r#"<mujoco><worldbody><body name="arm" pos="0 0 1"><joint name="j"/></body></worldbody></mujoco>"#,
    );
    assert_eq!(r.root_link(), Some("world"));
    assert_eq!(r.joint("j").unwrap().origin.xyz, [0.0, 0.0, 1.0]);
    // Unnamed bodies get names.
    let r = ok(r#"<mujoco><worldbody><body><body><joint/></body></body></worldbody></mujoco>"#);
    assert_eq!(r.links[0].name, "body1");
    assert_eq!(r.joints[0].name, "body2_joint");
}

#[test]
fn autolimits_off() {
    let r = ok(
        r#"<mujoco><compiler autolimits="false"/><worldbody><body name="a">
      <body name="b"><joint name="j" range="-10 10"/></body>
      <body name="c"><joint name="k" limited="true" range="-10 10"/></body></body></worldbody></mujoco>"#,
    );
    assert_eq!(r.joint("j").unwrap().kind, JointKind::Continuous);
    assert_eq!(r.joint("k").unwrap().kind, JointKind::Revolute);
}

/// The error is on `line`, names `element`, and says `says`.
fn check(e: &DescriptionError, line: u32, element: &str, says: &str) {
    let shown = e.to_string();
    assert_eq!(e.location.line, Some(line), "line of: {shown}");
    assert!(shown.starts_with(&format!("line {line}:")), "{shown}");
    let el = e.location.element.as_deref().unwrap_or("");
    assert!(el.contains(element), "element {element:?} in: {shown}");
    assert!(e.message.contains(says), "{says:?} in: {shown}");
}

const GOOD: &str = r#"<mujoco model="t">
  <compiler angle="radian"/>
  <default>
    <default class="c"><joint damping="1"/></default>
  </default>
  <worldbody>
    <body name="base">
      <freejoint/>
      <inertial pos="0 0 0" mass="1" diaginertia="0.1 0.1 0.1"/>
      <body name="thigh" pos="0 0 -0.1">
        <joint name="hip" axis="0 1 0" range="-1 1"/>
        <geom type="box" size="0.1 0.1 0.1"/>
      </body>
    </body>
  </worldbody>
</mujoco>
"#;

#[test]
fn ball_joint_is_spherical_without_axis_ref_or_cone_limit() {
    let d = ok(&with(
        r#"<joint name="hip" axis="0 1 0" range="-1 1"/>"#,
        r#"<joint name="hip" type="ball" pos="0 0 0.05" ref="0.3" range="0 1"/>"#,
    ));
    let hip = d.joints.iter().find(|j| j.name == "hip").unwrap();
    assert_eq!(hip.kind, twinloop_description::JointKind::Spherical);
    assert_eq!(hip.axis, None);
    assert!(
        hip.limit
            .is_none_or(|l| l.lower.is_none() && l.upper.is_none())
    );
    // The anchor moves the joint frame (pos 0 0 -0.1 plus the anchor 0 0 0.05), and
    // `ref` does not turn it.
    assert!(
        (hip.origin.xyz[2] - -0.05).abs() < 1e-15,
        "{:?}",
        hip.origin
    );
    assert!(hip.origin.rpy().iter().all(|a| a.abs() < 1e-15));
}

fn with(from: &str, to: &str) -> String {
    assert_eq!(GOOD.matches(from).count(), 1, "{from}");
    GOOD.replacen(from, to, 1)
}

#[test]
fn errors_name_line_and_element() {
    assert_eq!(ok(GOOD).links.len(), 2);
    check(
        &err(&with(
            r#"<joint name="hip""#,
            r#"<joint name="hip" type="hinged""#,
        )),
        11,
        r#"<joint name="hip">"#,
        r#"unknown joint type "hinged""#,
    );
    check(
        &err(&with("<freejoint/>", "<freejoint/><joint name=\"x\"/>")),
        7,
        r#"<body name="base">"#,
        "free joint must be the body's only joint",
    );
    check(
        &err(&with(r#"axis="0 1 0""#, r#"axis="0 NaN 0""#)),
        11,
        r#"<joint name="hip">"#,
        "not finite",
    );
    check(
        &err(&with(r#"axis="0 1 0""#, r#"axis="0 0 0""#)),
        11,
        r#"<joint name="hip">"#,
        "zero axis",
    );
    check(
        &err(&with(r#"range="-1 1""#, r#"range="-1""#)),
        11,
        r#"<joint name="hip">"#,
        "expected 2 numbers, found 1",
    );
    check(
        &err(&with(
            r#"<joint name="hip""#,
            r#"<joint name="hip" class="nope""#,
        )),
        11,
        r#"<joint name="hip">"#,
        r#"unknown default class "nope""#,
    );
    check(
        &err(&with(r#"size="0.1 0.1 0.1""#, r#"size="0.1 0.1""#)),
        12,
        r#"<geom> in <body name="thigh">"#,
        "box geom needs 3 size",
    );
    check(
        &err(&with(r#" mass="1""#, "")),
        9,
        r#"<inertial> in <body name="base">"#,
        r#"missing attribute "mass""#,
    );
    check(
        &err(&with(
            r#"<compiler angle="radian"/>"#,
            r#"<compiler angle="rad"/>"#,
        )),
        2,
        "<compiler>",
        "expected \"degree\" or \"radian\"",
    );
    check(
        &err(&with(
            r#"<joint name="hip" axis="0 1 0" range="-1 1"/>"#,
            "<freejoint/>",
        )),
        11,
        "<freejoint>",
        "only supported on the top-level body",
    );
    check(
        &err(&with(
            "  </worldbody>",
            "    <body name=\"other\"><geom size=\"0.1\"/></body>\n  </worldbody>",
        )),
        15,
        r#"<body name="other">"#,
        "second top-level body",
    );
    check(
        &err(&with(r#"<body name="thigh""#, r#"<body name="base""#)),
        10,
        r#"<link name="base">"#,
        "duplicate link name",
    );
    check(
        &err(&with("<worldbody>", "<worldbody><attach/>")),
        6,
        "<attach>",
        "not supported",
    );
    check(
        &err(&with("<worldbody>", "<worldbody><replicate/>")),
        6,
        "<replicate>",
        "count",
    );
    check(
        &err(&with("<worldbody>", "<worldbody><replicate count=\"0\"/>")),
        6,
        "<replicate",
        "not a replica count",
    );
    // Truncated and not XML.
    let e = err(&GOOD[..GOOD.find("<geom").unwrap()]);
    assert!(
        e.message.starts_with("malformed XML") && e.location.line == Some(12),
        "{e}"
    );
    check(
        &err("<robot name=\"x\"/>"),
        1,
        "<robot",
        "an MJCF model has <mujoco>",
    );
    check(&err("<mujoco/>"), 1, "<mujoco>", "no <body>");
}

#[test]
fn mutated_mjcf_never_panics() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/op3/mjcf/op3.xml");
    let original = std::fs::read(path).unwrap();
    let mut seed: u64 = 0x6d6a_6366_0000_0001;
    let mut next = move || {
        seed ^= seed >> 12;
        seed ^= seed << 25;
        seed ^= seed >> 27;
        seed.wrapping_mul(0x2545_F491_4F6C_DD1D)
    };
    let (mut accepted, mut rejected) = (0, 0);
    for _ in 0..600 {
        let mut t = original.clone();
        for _ in 0..1 + next() % 3 {
            let n = t.len().max(1) as u64;
            let a = (next() % n) as usize;
            match next() % 6 {
                0 => t.truncate(a),
                1 => {
                    let b = (a + 1 + (next() % 120) as usize).min(t.len());
                    t.drain(a.min(b)..b);
                }
                2 => {
                    let b = (a + 1 + (next() % 200) as usize).min(t.len());
                    let piece = t[a.min(b)..b].to_vec();
                    let at = (next() % (t.len() as u64 + 1)) as usize;
                    t.splice(at..at, piece);
                }
                3 => {
                    if let Some(i) = (a..t.len()).find(|&i| t[i].is_ascii_digit()) {
                        let to: &[u8] =
                            [&b"nan"[..], b"x", b"-", b"1e400", b""][(next() % 5) as usize];
                        t.splice(i..i + 1, to.iter().copied());
                    }
                }
                4 => {
                    let words: [&[u8]; 6] = [
                        b"hinge",
                        b"ball",
                        b"slide",
                        b"free",
                        b"class",
                        b"childclass",
                    ];
                    let w = words[(next() % 6) as usize];
                    if a < t.len() {
                        t.splice(a..a, w.iter().copied());
                    }
                }
                _ => {
                    let tags: [(&[u8], &[u8]); 4] = [
                        (b"<body", b"<geom"),
                        (b"<joint", b"<freejoint"),
                        (b"</body>", b""),
                        (b"<inertial", b"<site"),
                    ];
                    let (from, to) = tags[(next() % 4) as usize];
                    if let Some(i) = (a..t.len().saturating_sub(from.len()))
                        .find(|&i| &t[i..i + from.len()] == from)
                    {
                        t.splice(i..i + from.len(), to.iter().copied());
                    }
                }
            }
        }
        let text = String::from_utf8_lossy(&t).into_owned();
        match catch_unwind(AssertUnwindSafe(|| mjcf::from_str(&text).is_ok())) {
            Ok(true) => accepted += 1,
            Ok(false) => rejected += 1,
            Err(_) => {
                let p = std::env::temp_dir().join("twinloop-mjcf-fuzz-panic.xml");
                let _ = std::fs::write(&p, &text);
                panic!("panic on a mutated op3.xml; saved to {}", p.display());
            }
        }
    }
    assert!(
        accepted > 30 && rejected > 30,
        "accepted {accepted}, rejected {rejected}"
    );
}

/// Deep nesting is read without deep recursion.
#[test]
fn deeply_nested_bodies_and_classes() {
    let (n, classes) = (3000, 300);
    let mut s = String::from("<mujoco><default>");
    for i in 0..classes {
        s.push_str(&format!("<default class=\"c{i}\">"));
    }
    s.push_str("<joint axis=\"1 0 0\"/>");
    for _ in 0..classes {
        s.push_str("</default>");
    }
    s.push_str("</default><worldbody>");
    for i in 0..n {
        s.push_str(&format!(
            "<body name=\"b{i}\" pos=\"0 0 -0.01\"><joint class=\"c{}\"/>",
            classes - 1
        ));
    }
    for _ in 0..n {
        s.push_str("</body>");
    }
    s.push_str("</worldbody></mujoco>");
    let r = mjcf::from_str(&s).unwrap();
    assert_eq!(r.links.len(), n + 1);
    assert_eq!(r.root_link(), Some("world"));
    assert!(r.joints.iter().all(|j| j.axis == Some([1.0, 0.0, 0.0])));
    // An error deep inside unnamed bodies names a short path.
    let deep = format!(
        "<mujoco><worldbody>{}<geom type=\"what\"/>{}</worldbody></mujoco>",
        "<body>".repeat(n),
        "</body>".repeat(n)
    );
    let e = mjcf::from_str(&deep).unwrap_err();
    assert!(e.to_string().len() < 200, "{e}");
    assert!(e.message.contains("unknown geom type \"what\""), "{e}");
}

/// `<include>`: the included file's sections count as if written in place (here
/// its defaults); an error in it names that file and its own line.
#[test]
fn include_splices_files_and_errors_name_the_included_file() {
    let dir = std::env::temp_dir().join(format!("twinloop-mjcf-include-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("parts")).unwrap();
    let main = dir.join("robot.xml");
    std::fs::write(
        &main,
        r#"<mujoco>
  <include file="parts/defaults.xml"/>
  <worldbody><body name="b"><joint name="j"/><geom size="0.1"/></body></worldbody>
</mujoco>"#,
    )
    .unwrap();
    let defaults = dir.join("parts/defaults.xml");
    std::fs::write(
        &defaults,
        "<mujoco>\n  <default><joint armature=\"0.25\"/><geom density=\"500\"/></default>\n</mujoco>\n",
    )
    .unwrap();
    let r = twinloop_description::load(&main).unwrap();
    assert_eq!(r.joint("j").unwrap().armature, 0.25);
    let mass = r.link("b").unwrap().mass();
    assert!((mass - 500.0 * 4.0 / 3.0 * std::f64::consts::PI * 1e-3).abs() < 1e-12);
    std::fs::write(
        &defaults,
        "<mujoco>\n  <default><joint armature=\"x\"/></default>\n</mujoco>\n",
    )
    .unwrap();
    let e = twinloop_description::load(&main).unwrap_err();
    assert_eq!(e.location.file.as_deref(), Some(defaults.as_path()), "{e}");
    assert_eq!(e.location.line, Some(2), "{e}");
    std::fs::remove_file(&defaults).unwrap();
    let e = twinloop_description::load(&main).unwrap_err();
    assert_eq!(e.location.file.as_deref(), Some(main.as_path()), "{e}");
    assert!(e.message.contains("cannot read the included file"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `inertiafromgeom="true"` replaces a body's `<inertial>` only when it has geoms
/// to sum (MuJoCo 4.0 compiles this file to body masses 2 and 0.5236).
#[test]
fn inertia_from_geoms_keeps_the_inertial_of_a_body_without_geoms() {
    let r = ok(r#"<mujoco><compiler inertiafromgeom="true"/><worldbody>
  <body name="a"><joint axis="0 1 0"/><inertial pos="0 0 -0.1" mass="2" diaginertia="0.1 0.2 0.3"/>
    <body name="b" pos="0 0 -0.3"><joint/><geom size="0.05"/>
      <inertial pos="0 0 0" mass="7" diaginertia="1 1 1"/></body>
  </body></worldbody></mujoco>"#);
    assert_eq!(r.link("a").unwrap().mass(), 2.0);
    let sphere = 1000.0 * 4.0 / 3.0 * std::f64::consts::PI * 0.05_f64.powi(3);
    assert!((r.link("b").unwrap().mass() - sphere).abs() < 1e-12);
}

/// `boundmass` gives a body with nothing to weigh a mass; MuJoCo 4.0 puts its
/// CoM at the body's own `pos` in the body frame (compiled body_ipos 0.3 0.2
/// 0.1 here) and its inertia at `boundinertia`.
#[test]
fn boundmass_weighs_an_empty_body_where_mujoco_does() {
    let r = ok(
        r#"<mujoco><compiler boundmass="0.1" boundinertia="0.01"/><worldbody>
  <body name="a" pos="0.3 0.2 0.1"><joint axis="0 1 0"/>
    <body name="b" pos="0 0 -0.3"><joint/><geom size="0.05"/></body>
  </body></worldbody></mujoco>"#,
    );
    let a = r.link("a").unwrap().inertial.unwrap();
    assert_eq!(a.mass, 0.1);
    assert_eq!(a.origin.xyz, [0.3, 0.2, 0.1]);
    assert!((a.inertia.ixx - 0.01).abs() < 1e-15 && (a.inertia.izz - 0.01).abs() < 1e-15);
}

/// Free-floating props beside a free-floating robot (dm_control's quadruped
/// and dog with their ball): the robot is the top-level tree with the most
/// bodies, the others are left out (and so are free trees beside a larger
/// robot held by the world), each named by an `unmodeled-element` lint
/// warning (an error with `--strict`). `settotalmass` counts them, as MuJoCo
/// does (MuJoCo 4.0 on this file: 7 kg scaled to 10, so the torso's 2 kg
/// becomes 20/7); unnamed bodies are numbered in file order across all trees.
#[test]
fn free_props_beside_a_free_robot_are_left_out() {
    let text = r#"<mujoco><compiler settotalmass="10"/><worldbody>
<body name="ball"><freejoint/><geom type="sphere" size="0.1" mass="1"/></body>
<body name="torso" pos="0 0 1"><freejoint/><geom type="box" size="0.1 0.2 0.3" mass="2"/>
  <body name="arm" pos="0 0 0.3"><joint axis="0 1 0"/><geom type="capsule" fromto="0 0 0 0 0 0.4" size="0.05" mass="1"/></body>
  <body><joint axis="1 0 0"/><geom type="sphere" size="0.05" mass="1"/></body>
</body>
<body><freejoint/><geom type="sphere" size="0.1" mass="1"/><body><joint/><geom size="0.1" mass="1"/></body></body>
</worldbody></mujoco>"#;
    let r = ok(text);
    assert_eq!(r.root_link(), Some("torso"));
    let links: Vec<&str> = r.links.iter().map(|l| l.name.as_str()).collect();
    assert_eq!(links, ["torso", "arm", "body1"]);
    let mass = |l: &str| r.links.iter().find(|k| k.name == l).unwrap().mass();
    assert!(close(mass("torso"), 20.0 / 7.0), "{}", mass("torso"));
    assert!(close(mass("arm"), 10.0 / 7.0));
    let notes: Vec<(&str, u32)> = r
        .unmodeled
        .iter()
        .map(|n| (n.element.as_str(), n.line))
        .collect();
    assert_eq!(
        notes,
        [(r#"<body name="ball">"#, 2), ("<body> in <worldbody>", 7)]
    );
    assert!(r.unmodeled[0].what.contains(
        "free-floating body \"ball\" (1 body, 1.428571 kg, 6 DoFs) is a separate body tree \
         beside the robot \"torso\""
    ));
    assert!(
        r.unmodeled[1]
            .what
            .contains("(2 bodies, 2.857143 kg, 7 DoFs)")
    );
    let report = twinloop_description::lint::lint(&r);
    let code = twinloop_description::lint::codes::UNMODELED_ELEMENT;
    assert_eq!(report.with_code(code).count(), 2);
    assert!(!report.has_errors());
    assert_eq!(report.strict().errors, 2);

    // An arm held by the world with more bodies than the free tree beside it
    // (pybullet's striker and thrower): the arm is the robot, the free tree a prop.
    let r = ok(r#"<mujoco><worldbody>
<body name="base"><geom size="0.1"/><body name="link"><joint/><geom size="0.1"/></body></body>
<body name="puck" pos="1 0 0"><freejoint/><geom size="0.05" mass="0.2"/></body>
</worldbody></mujoco>"#);
    assert_eq!(r.root_link(), Some("base"));
    assert_eq!(r.links.len(), 2);
    assert_eq!(r.unmodeled.len(), 1);
    assert!(r.unmodeled[0].what.contains(
        "\"puck\" (1 body, 0.200000 kg, 6 DoFs) is a separate body tree beside the robot \
         (the bodies held by the world)"
    ));

    // A jointless (welded) body with mass or a hinged top-level body beside a larger
    // free one is not a prop: still refused, naming it. An empty one (no mass, no
    // joint: Apollo's world_link) is left out with a note (issue 30).
    let robot = ok(&text.replace(
        "<body name=\"ball\"><freejoint/><geom type=\"sphere\" size=\"0.1\" mass=\"1\"/></body>",
        "<body name=\"table\"/>",
    ));
    assert!(robot.link("table").is_none());
    assert!(
        robot
            .ignored
            .iter()
            .any(|n| n.element == "<body name=\"table\">" && n.what.contains("empty static body"))
    );
    for other in [
        "<body name=\"table\"><geom size=\"0.1\"/></body>",
        "<body name=\"table\"><joint/></body>",
    ] {
        let e = err(&text.replace(
            "<body name=\"ball\"><freejoint/><geom type=\"sphere\" size=\"0.1\" mass=\"1\"/></body>",
            other,
        ));
        assert!(e.to_string().contains("second top-level body"), "{e}");
    }
}

/// The free joint's own terms (issue 30, BXI Elf2): a `<joint type="free">` takes its
/// default class, as MuJoCo compiles it (armature, damping, frictionloss on all six
/// base DoFs), a `<freejoint>` takes none; armature and damping are kept, the dry
/// friction and a spring are named as not modelled. URDF cannot say the base's terms:
/// the written file says so in a comment, and reads back without them.
#[test]
fn free_joint_armature_and_damping_from_defaults_and_said_unwritable_in_urdf() {
    let file = |joint: &str| {
        format!(
            r#"<mujoco>
  <default><joint armature="0.01" damping="0.1" frictionloss="0.02" stiffness="3"/></default>
  <worldbody><body name="base">{joint}<geom size="0.1"/>
    <body name="arm"><joint name="j"/><geom size="0.05"/></body>
  </body></worldbody>
</mujoco>"#
        )
    };
    let r =
        twinloop_description::mjcf::from_str(&file(r#"<joint name="root" type="free"/>"#)).unwrap();
    assert_eq!((r.base_armature, r.base_damping), (0.01, 0.1));
    assert_eq!(r.joint("j").unwrap().armature, 0.01);
    let notes: Vec<&str> = r
        .unmodeled
        .iter()
        .filter(|n| n.element.contains("root"))
        .map(|n| n.what.as_str())
        .collect();
    assert_eq!(notes.len(), 2, "{notes:?}");
    assert!(
        notes[0].starts_with("free joint frictionloss 0.02"),
        "{notes:?}"
    );
    assert!(notes[1].starts_with("free joint stiffness 3"), "{notes:?}");
    let text = twinloop_description::urdf::to_string(&r);
    assert!(text.contains(
        "<!-- the floating base's armature 0.01 (the MJCF free joint's) is not written: URDF \
         has no joint for the floating base to carry it -->"
    ));
    assert!(
        text.contains("<!-- the floating base's damping 0.1 "),
        "{text}"
    );
    let back = twinloop_description::urdf::from_str(&text).unwrap();
    assert_eq!((back.base_armature, back.base_damping), (0.0, 0.0));
    assert!(twinloop_description::urdf::unwritable(&back).is_empty());
    let r = twinloop_description::mjcf::from_str(&file("<freejoint/>")).unwrap();
    assert_eq!((r.base_armature, r.base_damping), (0.0, 0.0));
    assert!(r.unmodeled.is_empty(), "{:?}", r.unmodeled);
    assert!(!twinloop_description::urdf::to_string(&r).contains("<!--"));
}

/// A directory of its own under the temporary directory, with `files` written.
fn write_model(tag: &str, files: &[(&str, &str)]) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("twinloop-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("parts")).unwrap();
    for (name, text) in files {
        std::fs::write(dir.join(name), text).unwrap();
    }
    dir
}

/// The inside of `<body name="thigh">`, once spliced (MS-Human-700 writes its
/// legs so, in `Body_Leg_Foot_r.xml` included from inside `pelvis`).
const THIGH: &str = r#"<joint name="hip" axis="0 1 0"/>
    <geom type="capsule" fromto="0 0 0 0 0 -0.4" size="0.05" mass="2"/>"#;
const SHIN: &str = r#"<body name="shin" pos="0 0 -0.4" euler="0 0 30">
      <joint name="knee" class="leg" range="-90 0"/>
      <inertial pos="0 0 -0.2" mass="1" diaginertia="0.01 0.01 0.002"/>
    </body>"#;

/// `<include>` inside a body, a default and an included file's body: the model
/// reads exactly as the same model written in one file (MuJoCo splices an
/// include wherever it stands: XML reference, "include").
#[test]
fn includes_inside_bodies_read_as_one_file() {
    let whole = format!(
        r#"<mujoco><default><default class="leg"><joint axis="1 0 0" damping="2"/></default></default>
  <worldbody><body name="torso" pos="0 0 1"><joint name="z" type="slide" axis="0 0 1" range="-1 1"/>
    <geom type="box" size="0.1 0.1 0.2" mass="3"/>
    <joint name="pitch" axis="0 1 0"/>
    <body name="thigh" pos="0.1 0 -0.2">{THIGH}
    {SHIN}</body>
  </body></worldbody></mujoco>"#
    );
    let dir = write_model(
        "mjcf-nested-include",
        &[
            ("whole.xml", whole.as_str()),
            (
                "robot.xml",
                r#"<mujoco><default><include file="parts/classes.xml"/></default>
  <worldbody><body name="torso" pos="0 0 1"><joint name="z" type="slide" axis="0 0 1" range="-1 1"/>
    <geom type="box" size="0.1 0.1 0.2" mass="3"/>
    <include file="parts/leg.xml"/>
  </body></worldbody></mujoco>"#,
            ),
            (
                "parts/classes.xml",
                r#"<mujoco><default class="leg"><joint axis="1 0 0" damping="2"/></default></mujoco>"#,
            ),
            (
                "parts/leg.xml",
                &format!(
                    "<mujoco>\n<joint name=\"pitch\" axis=\"0 1 0\"/>\n\
                     <body name=\"thigh\" pos=\"0.1 0 -0.2\">{THIGH}\n\
                     <include file=\"parts/shin.xml\"/></body>\n</mujoco>\n"
                ),
            ),
            (
                "parts/shin.xml",
                &format!("<mujoco>\n    {SHIN}\n</mujoco>\n"),
            ),
        ],
    );
    let one = twinloop_description::load(dir.join("whole.xml")).unwrap();
    let spliced = twinloop_description::load(dir.join("robot.xml")).unwrap();
    assert_eq!(spliced.links, one.links);
    assert_eq!(spliced.joints, one.joints);
    let names: Vec<&str> = spliced.joints.iter().map(|j| j.name.as_str()).collect();
    assert!(
        ["z", "pitch", "hip", "knee"]
            .iter()
            .all(|n| names.contains(n)),
        "{names:?}"
    );
    assert!((spliced.total_mass() - 6.0).abs() < 1e-12);
    let knee = spliced.joint("knee").unwrap();
    assert_eq!(knee.axis, Some([1.0, 0.0, 0.0]));
    assert_eq!(knee.dynamics.as_ref().and_then(|d| d.damping), Some(2.0));
    assert_eq!(knee.origin.xyz, [0.0, 0.0, -0.4]);
    assert!((knee.origin.rpy()[2] - PI / 6.0).abs() < 1e-12);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A file that includes itself through another, from inside a body: the cycle
/// is named, file by file; an error in a nested included file names that file
/// and its line, also one found after reading (a duplicate name).
#[test]
fn nested_include_cycles_and_errors_name_the_files() {
    let robot = r#"<mujoco><worldbody><body name="torso"><geom size="0.1"/>
  <include file="parts/leg.xml"/></body></worldbody></mujoco>"#;
    let leg = "<mujoco><body name=\"thigh\"><joint/><geom size=\"0.1\"/>\n\
               <include file=\"parts/shin.xml\"/></body></mujoco>\n";
    let dir = write_model(
        "mjcf-include-cycle",
        &[
            ("robot.xml", robot),
            ("parts/leg.xml", leg),
            (
                "parts/shin.xml",
                "<mujoco><body name=\"shin\"><joint/><geom size=\"0.1\"/>\n\
                 <include file=\"parts/leg.xml\"/></body></mujoco>\n",
            ),
        ],
    );
    let e = twinloop_description::load(dir.join("robot.xml")).unwrap_err();
    let (leg_path, shin_path) = (dir.join("parts/leg.xml"), dir.join("parts/shin.xml"));
    let cycle = format!(
        "include cycle: {} -> {} -> {}",
        leg_path.display(),
        shin_path.display(),
        leg_path.display()
    );
    assert!(e.message.contains(&cycle), "{e}");
    assert_eq!(e.location.file.as_deref(), Some(shin_path.as_path()), "{e}");
    assert_eq!(e.location.line, Some(2), "{e}");
    std::fs::write(
        &shin_path,
        "<mujoco><body name=\"shin\"><geom size=\"0.1\"/>\n\n  <joint damping=\"x\"/></body></mujoco>\n",
    )
    .unwrap();
    let e = twinloop_description::load(dir.join("robot.xml")).unwrap_err();
    assert_eq!(e.location.file.as_deref(), Some(shin_path.as_path()), "{e}");
    assert_eq!(e.location.line, Some(3), "{e}");
    assert!(e.to_string().contains("damping"), "{e}");
    // Found after reading (a name given twice): placed in the included file too.
    std::fs::write(
        &shin_path,
        "<mujoco>\n\n  <body name=\"thigh\"><joint/><geom size=\"0.1\"/></body></mujoco>\n",
    )
    .unwrap();
    let e = twinloop_description::load(dir.join("robot.xml")).unwrap_err();
    assert!(e.message.contains("duplicate link name"), "{e}");
    assert_eq!(e.location.file.as_deref(), Some(shin_path.as_path()), "{e}");
    assert_eq!(e.location.line, Some(3), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}
