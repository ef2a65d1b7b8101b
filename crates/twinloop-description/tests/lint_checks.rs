//! Each lint check on small robots made with the builder.

use twinloop_description::lint::{Finding, LintReport, Severity, Subject, codes, lint};
use twinloop_description::{DescriptionBuilder, Inertia, JointKind};

fn good_inertia() -> Inertia {
    Inertia::solid_box(1.0, [0.1, 0.2, 0.3])
}

/// A torso with one limited revolute joint to an arm: nothing to report but the total mass.
fn base() -> DescriptionBuilder {
    DescriptionBuilder::new("test")
        .link("torso")
        .mass(2.0, [0.0; 3], good_inertia())
        .done()
        .link("arm")
        .mass(
            0.5,
            [0.0, 0.0, -0.1],
            Inertia::solid_cylinder(0.5, 0.02, 0.2),
        )
        .done()
        .revolute("shoulder", "torso", "arm", [0.0, 1.0, 0.0])
        .limits(-1.0, 1.0, 5.0, 6.0)
        .done()
}

/// Findings other than the total-mass info, as (severity, code, subject, name).
fn problems(report: &LintReport) -> Vec<(Severity, &'static str, Subject, String)> {
    report
        .findings
        .iter()
        .filter(|f| f.code != codes::TOTAL_MASS)
        .map(|f| (f.severity, f.code, f.subject, f.name.clone()))
        .collect()
}

fn only(report: &LintReport) -> &Finding {
    let v: Vec<&Finding> = report
        .findings
        .iter()
        .filter(|f| f.code != codes::TOTAL_MASS)
        .collect();
    assert_eq!(v.len(), 1, "{:#?}", report.findings);
    v[0]
}

#[test]
fn clean_robot_has_only_the_total_mass() {
    let r = lint(&base().build().unwrap());
    assert!(problems(&r).is_empty(), "{:#?}", r.findings);
    assert!(!r.has_errors());
    assert_eq!(r.findings.len(), 1);
    let f = &r.findings[0];
    assert_eq!(
        (f.severity, f.code, f.subject),
        (Severity::Info, codes::TOTAL_MASS, Subject::Robot)
    );
    assert_eq!(f.name, "test");
    assert!(f.message.contains("2.5 kg"), "{}", f.message);
    assert!(
        f.message.contains("heaviest \"torso\" 2 kg"),
        "{}",
        f.message
    );
    assert_eq!(r.total_mass, 2.5);
    assert_eq!(
        (r.links, r.joints, r.moving_joints, r.dof, r.mimic_joints),
        (2, 1, 1, 1, 0)
    );
    assert_eq!((r.errors, r.warnings, r.infos), (0, 0, 1));
    assert_eq!(r.worst(), Some(Severity::Info));
}

#[test]
fn semi_definite_placeholder_is_an_error() {
    let robot = base()
        .link("hand")
        .mass(0.1, [0.0; 3], Inertia::diagonal(1.0, 1.0, 0.0))
        .done()
        .fixed("wrist", "arm", "hand")
        .done()
        .build()
        .unwrap();
    let r = lint(&robot);
    let f = only(&r);
    assert_eq!(
        (f.severity, f.code, f.subject),
        (
            Severity::Error,
            codes::INERTIA_NOT_POSITIVE_DEFINITE,
            Subject::Link
        )
    );
    assert_eq!(f.name, "hand");
    assert!(f.message.contains("semi-definite"), "{}", f.message);
    assert!(
        f.message.contains("principal moments 0, 1, 1"),
        "{}",
        f.message
    );
    assert!(r.has_errors());
    assert_eq!(r.findings[0].severity, Severity::Error, "errors come first");
}

#[test]
fn negative_principal_moment_is_an_error() {
    // Diagonal positive, but the product of inertia makes an eigenvalue negative.
    let bad = Inertia {
        ixx: 1.0,
        iyy: 1.0,
        izz: 1.0,
        ixy: 1.5,
        ..Default::default()
    };
    let mut robot = base().build().unwrap();
    robot
        .link_mut("arm")
        .unwrap()
        .inertial
        .as_mut()
        .unwrap()
        .inertia = bad;
    let r = lint(&robot);
    let f = only(&r);
    assert_eq!(
        (f.code, f.name.as_str()),
        (codes::INERTIA_NOT_POSITIVE_DEFINITE, "arm")
    );
    assert!(
        f.message.contains("negative principal moment"),
        "{}",
        f.message
    );
    assert!(f.message.contains("-0.5"), "{}", f.message);
}

#[test]
fn rotated_semi_definite_tensor_is_caught_despite_round_off() {
    // The placeholder diag(1, 1, 0) seen in a rotated frame: off-diagonal terms, an
    // eigenvalue that is 0 only up to round-off.
    let r = twinloop_description::rpy_to_matrix([0.4, 0.9, -1.3]);
    let d = [1.0, 1.0, 0.0];
    let mut m = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            m[i][j] = (0..3).map(|k| r[i][k] * d[k] * r[j][k]).sum();
        }
    }
    let mut robot = base().build().unwrap();
    robot
        .link_mut("arm")
        .unwrap()
        .inertial
        .as_mut()
        .unwrap()
        .inertia = Inertia::from_matrix(m);
    let f = only(&lint(&robot)).clone();
    assert_eq!(f.code, codes::INERTIA_NOT_POSITIVE_DEFINITE);
}

#[test]
fn triangle_inequality_violation_is_an_error_with_the_numbers() {
    // The COMAN Xtion_body case: 0.00050255 + 0.009 < 0.01000745.
    let mut robot = base().build().unwrap();
    robot
        .link_mut("arm")
        .unwrap()
        .inertial
        .as_mut()
        .unwrap()
        .inertia = Inertia::diagonal(0.009, 0.00050255, 0.01000745);
    let r = lint(&robot);
    let f = only(&r);
    assert_eq!(
        (f.severity, f.code, f.name.as_str()),
        (Severity::Error, codes::TRIANGLE_INEQUALITY, "arm")
    );
    assert!(
        f.message.contains("I1+I2=0.00950255 < I3=0.01000745"),
        "{}",
        f.message
    );
}

#[test]
fn thin_plate_on_the_triangle_boundary_passes() {
    // I1 + I2 = I3 exactly for a flat plate; a 1e-12 relative shortfall is rounding.
    let mut robot = base().build().unwrap();
    let i3 = 2.0 * 8.53333333e-7;
    robot
        .link_mut("arm")
        .unwrap()
        .inertial
        .as_mut()
        .unwrap()
        .inertia = Inertia::diagonal(8.53333333e-7, 8.53333333e-7, i3 * (1.0 + 1e-12));
    assert!(problems(&lint(&robot)).is_empty());
    // A real violation just beyond the slack is still caught.
    robot
        .link_mut("arm")
        .unwrap()
        .inertial
        .as_mut()
        .unwrap()
        .inertia = Inertia::diagonal(8.53333333e-7, 8.53333333e-7, i3 * (1.0 + 1e-8));
    assert_eq!(only(&lint(&robot)).code, codes::TRIANGLE_INEQUALITY);
}

#[test]
fn tiny_dummy_mass_with_zero_inertia_is_a_warning() {
    let robot = base()
        .link("camera")
        .mass(1e-9, [0.0; 3], Inertia::default())
        .done()
        .fixed("camera_frame", "torso", "camera")
        .axis([0.0, 0.0, 0.0])
        .done()
        .build()
        .unwrap();
    let r = lint(&robot);
    let f = only(&r);
    assert_eq!(
        (f.severity, f.code, f.subject, f.name.as_str()),
        (
            Severity::Warning,
            codes::ZERO_INERTIA_WITH_MASS,
            Subject::Link,
            "camera"
        )
    );
    assert!(f.message.contains("1e-9 kg"), "{}", f.message);
    assert!(!r.has_errors());
}

#[test]
fn massless_frame_without_or_with_empty_inertial_is_fine() {
    let robot = base()
        .link("sole")
        .done()
        .fixed("sole_joint", "arm", "sole")
        .done()
        .link("imu")
        .mass(0.0, [0.0; 3], Inertia::default())
        .done()
        .fixed("imu_joint", "torso", "imu")
        .done()
        .build()
        .unwrap();
    let r = lint(&robot);
    assert!(problems(&r).is_empty(), "{:#?}", r.findings);
    assert_eq!(r.links_without_inertial, 1);
}

#[test]
fn negative_mass_and_inertia_without_mass() {
    let mut robot = base().build().unwrap();
    robot
        .link_mut("arm")
        .unwrap()
        .inertial
        .as_mut()
        .unwrap()
        .mass = -0.5;
    let r = lint(&robot);
    assert!(
        problems(&r).contains(&(
            Severity::Error,
            codes::NEGATIVE_MASS,
            Subject::Link,
            "arm".into()
        )),
        "{:#?}",
        r.findings
    );

    let mut robot = base().build().unwrap();
    robot
        .link_mut("torso")
        .unwrap()
        .inertial
        .as_mut()
        .unwrap()
        .mass = 0.0;
    let f = only(&lint(&robot)).clone();
    assert_eq!(
        (f.severity, f.code, f.name.as_str()),
        (Severity::Warning, codes::INERTIA_WITHOUT_MASS, "torso")
    );
}

#[test]
fn massless_moving_leaf_is_an_error() {
    let robot = base()
        .link("finger")
        .done()
        .revolute("finger_joint", "arm", "finger", [1.0, 0.0, 0.0])
        .limits(0.0, 1.0, 1.0, 1.0)
        .done()
        .build()
        .unwrap();
    let r = lint(&robot);
    let f = only(&r);
    assert_eq!(
        (f.severity, f.code, f.subject, f.name.as_str()),
        (
            Severity::Error,
            codes::ZERO_MASS_MOVING_LINK,
            Subject::Link,
            "finger"
        )
    );
    assert!(f.message.contains("finger_joint"), "{}", f.message);
}

#[test]
fn massless_moving_link_with_a_massive_fixed_child_is_fine() {
    // The moving body is finger + pad: the pad's mass counts.
    let robot = base()
        .link("finger")
        .done()
        .revolute("finger_joint", "arm", "finger", [1.0, 0.0, 0.0])
        .limits(0.0, 1.0, 1.0, 1.0)
        .done()
        .link("pad")
        .mass(0.01, [0.0; 3], Inertia::solid_sphere(0.01, 0.01))
        .done()
        .fixed("pad_joint", "finger", "pad")
        .done()
        .build()
        .unwrap();
    let r = lint(&robot);
    assert!(problems(&r).is_empty(), "{:#?}", r.findings);
}

#[test]
fn massless_link_fixed_to_a_massless_moving_link_is_still_an_error() {
    let robot = base()
        .link("finger")
        .done()
        .revolute("finger_joint", "arm", "finger", [1.0, 0.0, 0.0])
        .limits(0.0, 1.0, 1.0, 1.0)
        .done()
        .link("tip")
        .done()
        .fixed("tip_joint", "finger", "tip")
        .done()
        .build()
        .unwrap();
    let r = lint(&robot);
    assert_eq!(
        problems(&r),
        vec![(
            Severity::Error,
            codes::ZERO_MASS_MOVING_LINK,
            Subject::Link,
            "finger".to_string()
        )]
    );
}

#[test]
fn massless_intermediate_body_with_mass_further_down_is_a_warning() {
    // A massless hip-yaw body carrying a massive leg through another joint:
    // not singular in general, but worth a look.
    let robot = base()
        .link("hip_yaw")
        .done()
        .revolute("hip_yaw_joint", "torso", "hip_yaw", [0.0, 0.0, 1.0])
        .limits(-1.0, 1.0, 1.0, 1.0)
        .done()
        .link("leg")
        .mass(1.0, [0.0, 0.0, -0.2], good_inertia())
        .done()
        .revolute("hip_roll_joint", "hip_yaw", "leg", [1.0, 0.0, 0.0])
        .limits(-1.0, 1.0, 1.0, 1.0)
        .done()
        .build()
        .unwrap();
    let r = lint(&robot);
    let f = only(&r);
    assert_eq!(
        (f.severity, f.code, f.name.as_str()),
        (Severity::Warning, codes::ZERO_MASS_MOVING_LINK, "hip_yaw")
    );
    assert!(f.message.contains("1 kg further down"), "{}", f.message);
}

#[test]
fn massless_root_fixed_to_the_world_is_not_a_moving_link() {
    // COMAN style: massless `world` root, floating joint to a massless base_link
    // that is fixed to the massive pelvis.
    let robot = DescriptionBuilder::new("floating")
        .link("world")
        .done()
        .link("base_link")
        .done()
        .link("pelvis")
        .mass(3.0, [0.0; 3], good_inertia())
        .done()
        .joint("reference", JointKind::Floating, "world", "base_link")
        .done()
        .fixed("base_joint", "base_link", "pelvis")
        .done()
        .build()
        .unwrap();
    let r = lint(&robot);
    assert!(problems(&r).is_empty(), "{:#?}", r.findings);
    assert_eq!(r.dof, 6);
    assert_eq!(r.moving_joints, 1);
}

#[test]
fn revolute_without_lower_upper_is_a_warning() {
    let mut robot = base().build().unwrap();
    let limit = robot.joints[0].limit.as_mut().unwrap();
    limit.lower = None;
    limit.upper = None;
    let r = lint(&robot);
    let f = only(&r);
    assert_eq!(
        (f.severity, f.code, f.subject, f.name.as_str()),
        (
            Severity::Warning,
            codes::MISSING_LIMITS,
            Subject::Joint,
            "shoulder"
        )
    );
    assert!(f.message.contains("lower/upper"), "{}", f.message);

    // No <limit> at all: range missing (warning) and effort/velocity missing (info).
    robot.joints[0].limit = None;
    let r = lint(&robot);
    assert_eq!(
        problems(&r),
        vec![
            (
                Severity::Warning,
                codes::MISSING_LIMITS,
                Subject::Joint,
                "shoulder".to_string()
            ),
            (
                Severity::Info,
                codes::MISSING_EFFORT_VELOCITY,
                Subject::Joint,
                "shoulder".to_string()
            ),
        ]
    );
}

#[test]
fn continuous_joint_needs_no_range() {
    let mut robot = base().build().unwrap();
    robot.joints[0].kind = JointKind::Continuous;
    robot.joints[0].limit = None;
    assert!(problems(&lint(&robot)).is_empty());
}

#[test]
fn inverted_empty_and_zero_limits() {
    let mut robot = base().build().unwrap();
    let limit = robot.joints[0].limit.as_mut().unwrap();
    limit.lower = Some(1.0);
    limit.upper = Some(-1.0);
    let f = only(&lint(&robot)).clone();
    assert_eq!(
        (f.severity, f.code),
        (Severity::Error, codes::LIMITS_INVERTED)
    );

    let limit = robot.joints[0].limit.as_mut().unwrap();
    limit.lower = Some(0.5);
    limit.upper = Some(0.5);
    let f = only(&lint(&robot)).clone();
    assert_eq!(
        (f.severity, f.code),
        (Severity::Warning, codes::LIMITS_EMPTY_RANGE)
    );

    let limit = robot.joints[0].limit.as_mut().unwrap();
    limit.lower = Some(-1.0);
    limit.effort = Some(0.0);
    let f = only(&lint(&robot)).clone();
    assert_eq!(
        (f.severity, f.code),
        (Severity::Warning, codes::ZERO_EFFORT_OR_VELOCITY)
    );
    assert!(f.message.starts_with("effort limit is 0"), "{}", f.message);
}

#[test]
#[allow(
    clippy::approx_constant,
    reason = "NAO's axis is a truncated 1/sqrt(2), on purpose"
)]
fn non_unit_axis_is_a_warning_on_moving_joints_only() {
    // NAO's hip yaw-pitch axis as written: |a| = 0.99999887...
    let mut robot = base().build().unwrap();
    robot.joints[0].axis = Some([0.0, 0.707106, -0.707106]);
    let r = lint(&robot);
    let f = only(&r);
    assert_eq!(
        (f.severity, f.code, f.subject, f.name.as_str()),
        (
            Severity::Warning,
            codes::NON_UNIT_AXIS,
            Subject::Joint,
            "shoulder"
        )
    );
    assert!(f.message.contains("0.9999988"), "{}", f.message);

    // A zero axis on a fixed joint is ignored (URDF ignores it).
    let robot = base()
        .link("imu")
        .done()
        .fixed("imu_joint", "torso", "imu")
        .axis([0.0, 0.0, 0.0])
        .done()
        .build()
        .unwrap();
    assert!(problems(&lint(&robot)).is_empty());
}

#[test]
fn mimic_joint_is_a_warning_and_a_fixed_mimic_is_info() {
    let robot = base()
        .link("forearm")
        .mass(0.3, [0.0; 3], good_inertia())
        .done()
        .revolute("elbow", "arm", "forearm", [0.0, 1.0, 0.0])
        .limits(-1.0, 1.0, 5.0, 6.0)
        .mimic("shoulder", 2.0, 0.1)
        .done()
        .link("clip")
        .mass(0.01, [0.0; 3], good_inertia())
        .done()
        .fixed("clip_joint", "forearm", "clip")
        .mimic("shoulder", 1.0, 0.0)
        .done()
        .build()
        .unwrap();
    let r = lint(&robot);
    assert_eq!(
        problems(&r),
        vec![
            (
                Severity::Warning,
                codes::MIMIC_JOINT,
                Subject::Joint,
                "elbow".to_string()
            ),
            (
                Severity::Info,
                codes::MIMIC_JOINT,
                Subject::Joint,
                "clip_joint".to_string()
            ),
        ]
    );
    assert!(
        r.findings[0].message.contains("q = 2 * q_shoulder + 0.1"),
        "{}",
        r.findings[0].message
    );
    assert_eq!(r.mimic_joints, 2);
}

/// A mimic of a joint the file does not have (example-robot-data's Alex hands):
/// the file loads, lint warns.
#[test]
fn a_mimic_of_an_unknown_joint_is_a_warning() {
    let robot = base()
        .link("forearm")
        .mass(0.3, [0.0; 3], good_inertia())
        .done()
        .revolute("elbow", "arm", "forearm", [0.0, 1.0, 0.0])
        .limits(-1.0, 1.0, 5.0, 6.0)
        .mimic("index_q1", 1.0, 0.0)
        .done()
        .build()
        .unwrap();
    robot.validate().unwrap();
    let r = lint(&robot);
    let unknown: Vec<_> = r
        .with_code(codes::MIMIC_JOINT)
        .filter(|f| f.message.contains("which the file does not have"))
        .collect();
    assert_eq!(unknown.len(), 1, "{:#?}", r.findings);
    assert_eq!(unknown[0].severity, Severity::Warning);
    assert_eq!(unknown[0].name, "elbow");
    assert!(!r.has_errors());
}

#[test]
fn every_code_is_listed_once() {
    let mut all = codes::ALL.to_vec();
    all.sort();
    all.dedup();
    assert_eq!(all.len(), codes::ALL.len());
}

/// MJCF elements the dynamics leave out are warnings (errors when strict), each
/// naming the element and its line.
/// An element MuJoCo's schema does not have, as a section of `<mujoco>`, in the
/// world body or in a body, is an unmodeled-element warning naming it and its line;
/// every bundled MJCF has none.
#[test]
fn unknown_mjcf_elements_are_named_not_dropped() {
    let robot = twinloop_description::mjcf::from_str(
        r#"<mujoco>
  <worldbody>
    <lamp/>
    <body name="a"><joint name="j1"/><geon size="0.1"/><geom size="0.1"/></body>
  </worldbody>
  <frobnicate/>
</mujoco>"#,
    )
    .unwrap();
    let report = lint(&robot);
    let found: Vec<(&str, &str)> = report
        .with_code(codes::UNMODELED_ELEMENT)
        .map(|f| (f.name.as_str(), f.message.split(':').next().unwrap()))
        .collect();
    assert_eq!(
        found,
        [
            ("<lamp> in <worldbody>", "line 3"),
            (r#"<geon> in <body name="a">"#, "line 4"),
            ("<frobnicate>", "line 6"),
        ],
        "{:#?}",
        report.findings
    );
    assert!(
        report
            .with_code(codes::UNMODELED_ELEMENT)
            .all(|f| f.message.contains("not an MJCF element"))
    );
}

#[test]
fn unmodeled_mjcf_elements_are_warnings_and_strict_makes_them_errors() {
    let robot = twinloop_description::mjcf::from_str(
        r#"<mujoco>
  <worldbody>
    <body name="a"><joint name="j1"/><geom size="0.1"/><site name="s" size="0.01"/>
      <body name="b"><joint name="j2"/><geom size="0.1"/></body>
    </body>
  </worldbody>
  <tendon><fixed name="t"><joint joint="j1" coef="1"/><joint joint="j2" coef="-1"/></fixed></tendon>
  <equality><joint joint1="j1" joint2="j2"/></equality>
  <actuator><motor joint="j1"/><motor tendon="t"/><general site="s"/></actuator>
  <sensor><jointpos joint="j1"/><accelerometer site="s"/></sensor>
  <deformable><flex name="cloth" dim="2" body="a a a" vertex="0 0 0 1 0 0 0 1 0" element="0 1 2"/></deformable>
</mujoco>"#,
    )
    .unwrap();
    let report = lint(&robot);
    let found: Vec<(&str, &str)> = report
        .with_code(codes::UNMODELED_ELEMENT)
        .map(|f| (f.name.as_str(), f.message.split(':').next().unwrap()))
        .collect();
    assert_eq!(
        found,
        [
            (r#"<fixed name="t">"#, "line 7"),
            ("<joint> in <equality>", "line 8"),
            ("<motor> in <actuator>", "line 9"),
            ("<general> in <actuator>", "line 9"),
            ("<accelerometer> in <sensor>", "line 10"),
            (r#"<flex name="cloth">"#, "line 11"),
        ]
    );
    assert!(
        report
            .with_code(codes::UNMODELED_ELEMENT)
            .all(|f| f.severity == Severity::Warning)
    );
    assert!(!report.has_errors());
    let strict = report.strict();
    assert_eq!(strict.errors, 6);
    assert_eq!(strict.findings[0].code, codes::UNMODELED_ELEMENT);
    assert!(strict.findings[0].message.contains("tendon"));
}

/// Two point masses on a line: every joint moves mass, but the whole robot has
/// no rotational inertia about that line, so as a floating base its mass matrix
/// is singular.
#[test]
fn point_masses_on_a_line_make_a_singular_floating_base() {
    let point = Inertia::default();
    let robot = DescriptionBuilder::new("dumbbell")
        .link("a")
        .mass(1.0, [0.0; 3], point)
        .done()
        .link("b")
        .mass(1.0, [0.0, 0.0, -0.5], point)
        .done()
        .revolute("j", "a", "b", [0.0, 0.0, 1.0])
        .limits(-1.0, 1.0, 5.0, 6.0)
        .done()
        .build()
        .unwrap();
    let r = lint(&robot);
    let f: Vec<_> = r.with_code(codes::SINGULAR_FLOATING_BASE).collect();
    assert_eq!(f.len(), 1, "{:#?}", r.findings);
    assert_eq!(
        (f[0].severity, f[0].subject),
        (Severity::Warning, Subject::Robot)
    );
    assert!(
        f[0].message
            .contains("principal moments about its CoM are 0"),
        "{}",
        f[0].message
    );
    // A body of real extent instead of one of the points: a full inertia.
    let mut solid = robot.clone();
    solid
        .link_mut("a")
        .unwrap()
        .inertial
        .as_mut()
        .unwrap()
        .inertia = Inertia::solid_sphere(1.0, 0.1);
    assert_eq!(
        lint(&solid)
            .with_code(codes::SINGULAR_FLOATING_BASE)
            .count(),
        0
    );
}

/// An MJCF body with several joints becomes a chain with massless links between
/// its joints: they are not the file's, so no zero-mass warning names them.
#[test]
fn links_between_the_joints_of_one_mjcf_body_are_not_massless_links() {
    let robot = twinloop_description::mjcf::from_str(
        r#"<mujoco><worldbody><body name="hip">
  <joint name="x" axis="1 0 0"/><joint name="y" axis="0 1 0"/><joint name="z" axis="0 0 1"/>
  <geom type="capsule" size="0.05" fromto="0 0 0 0 0 -0.4"/>
</body></worldbody></mujoco>"#,
    )
    .unwrap();
    let between: Vec<&str> = robot
        .links
        .iter()
        .filter(|l| l.between_joints)
        .map(|l| l.name.as_str())
        .collect();
    assert_eq!(between, ["hip_x", "hip_y"]);
    let r = lint(&robot);
    assert_eq!(
        r.with_code(codes::ZERO_MASS_MOVING_LINK).count(),
        0,
        "{:#?}",
        r.findings
    );
}

/// `<composite>` and `<flexcomp>` expand into soft bodies twinloop does not hold:
/// the rigid bodies around them load as written, and each is a lint warning
/// naming its line and what the dynamics leave out.
#[test]
fn composite_and_flexcomp_load_as_unmodeled_warnings() {
    let robot = twinloop_description::mjcf::from_str(
        r#"<mujoco>
  <worldbody>
    <body name="a"><joint name="j1"/><geom size="0.1" mass="2"/>
      <composite type="cable" count="10 1 1" curve="s" size="0.5"><geom type="capsule" size=".01"/></composite>
      <body name="b" pos="0 0 -0.5"><joint name="j2"/><geom size="0.1" mass="3"/></body>
    </body>
    <flexcomp name="cloth" type="grid" count="4 4 1" spacing=".1 .1 .1" mass="1"/>
  </worldbody>
</mujoco>"#,
    )
    .unwrap();
    let masses: Vec<(&str, f64)> = robot
        .links
        .iter()
        .map(|l| (l.name.as_str(), l.inertial.as_ref().map_or(0.0, |i| i.mass)))
        .collect();
    assert_eq!(masses.len(), 3, "world, a, b: {masses:?}");
    assert_eq!(masses[1], ("a", 2.0));
    assert_eq!(masses[2], ("b", 3.0));
    let report = lint(&robot);
    let mut found: Vec<(&str, &str)> = report
        .with_code(codes::UNMODELED_ELEMENT)
        .map(|f| (f.name.as_str(), f.message.split(':').next().unwrap()))
        .collect();
    found.sort_by_key(|f| f.1);
    assert_eq!(
        found,
        [
            ("<composite> in <body name=\"a\">", "line 4"),
            (r#"<flexcomp name="cloth">"#, "line 7"),
        ]
    );
    let says = |name: &str, words: [&str; 2]| {
        report
            .with_code(codes::UNMODELED_ELEMENT)
            .any(|f| f.name.contains(name) && words.iter().all(|w| f.message.contains(w)))
    };
    assert!(says("<composite>", ["\"cable\"", "mass"]));
    assert!(says("flexcomp", ["\"grid\"", "deformable"]));
    assert_eq!(report.strict().errors, 2);
}
