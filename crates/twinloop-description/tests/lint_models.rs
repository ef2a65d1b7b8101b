//! Lint on every bundled model: exactly the expected findings.
//!
//! Two sources of truth: the `inertia_problems`, `total_mass_kg` and `mimic_joints`
//! lines of each folder's SOURCE.md (computed independently with numpy when the
//! models were collected), and the full expected list of findings written out below.

mod models_support;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use twinloop_description::lint::{LintReport, Severity, codes, lint};

fn models_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models")
}

fn lint_file(rel: &str) -> LintReport {
    let path = models_dir().join(rel);
    let robot = twinloop_description::load(&path).unwrap_or_else(|e| panic!("{rel}: {e}"));
    lint(&robot)
}

/// Findings as (severity, code, name), sorted, the total-mass info left out.
fn findings(report: &LintReport) -> Vec<(Severity, &'static str, String)> {
    let mut v: Vec<_> = report
        .findings
        .iter()
        .filter(|f| f.code != codes::TOTAL_MASS)
        .map(|f| (f.severity, f.code, f.name.clone()))
        .collect();
    v.sort();
    v
}

fn expect(items: &[(Severity, &'static str, &[&str])]) -> Vec<(Severity, &'static str, String)> {
    let mut v: Vec<_> = items
        .iter()
        .flat_map(|(s, c, names)| names.iter().map(move |n| (*s, *c, n.to_string())))
        .collect();
    v.sort();
    v
}

/// The SOURCE.md summary of one file: `- key: value` lines under "### `file`".
/// A `*.nomesh.urdf` or `*.decimated.urdf` shares the summary of its `*.urdf`.
fn source_summary(rel: &str) -> BTreeMap<String, String> {
    let (folder, file) = rel.split_once('/').unwrap();
    let file = file
        .replace(".nomesh.urdf", ".urdf")
        .replace(".feet.urdf", ".urdf")
        .replace(".decimated.urdf", ".urdf");
    let text = std::fs::read_to_string(models_dir().join(folder).join("SOURCE.md")).unwrap();
    let header = format!("### `{file}`");
    let mut out = BTreeMap::new();
    let mut inside = false;
    for line in text.lines() {
        if line.starts_with("##") {
            inside = line.trim() == header;
            continue;
        }
        if inside && let Some((k, v)) = line.strip_prefix("- ").and_then(|l| l.split_once(": ")) {
            out.insert(k.to_string(), v.to_string());
        }
    }
    assert!(!out.is_empty(), "no section {header} in {folder}/SOURCE.md");
    out
}

/// `N — a; b; c` or `none` -> the items.
fn listed(value: &str) -> Vec<String> {
    match value.split_once(" — ") {
        None => {
            assert_eq!(value.trim(), "none", "unexpected summary value {value:?}");
            Vec::new()
        }
        Some((n, rest)) => {
            let items: Vec<String> = rest.split("; ").map(str::to_string).collect();
            assert_eq!(n.parse::<usize>().unwrap(), items.len(), "{value}");
            items
        }
    }
}

/// Lint's inertia findings must be exactly SOURCE.md's `inertia_problems`, and the
/// total mass and mimic joints must agree with it.
fn agrees_with_source(rel: &str, report: &LintReport) {
    let summary = source_summary(rel);
    let mut want: Vec<(Severity, &'static str, String)> = listed(&summary["inertia_problems"])
        .iter()
        .map(|item| {
            let (name, what) = item.split_once(": ").unwrap();
            let code = if what.starts_with("positive semi-definite only")
                || what.starts_with("not positive definite")
            {
                codes::INERTIA_NOT_POSITIVE_DEFINITE
            } else if what.starts_with("violates triangle inequality") {
                codes::TRIANGLE_INEQUALITY
            } else if what.starts_with("zero inertia with mass>0") {
                codes::ZERO_INERTIA_WITH_MASS
            } else {
                panic!("{rel}: unknown inertia problem {what:?}")
            };
            let severity = if code == codes::ZERO_INERTIA_WITH_MASS {
                Severity::Warning
            } else {
                Severity::Error
            };
            (severity, code, name.to_string())
        })
        .collect();
    want.sort();
    let inertia_codes = [
        codes::INERTIA_NOT_POSITIVE_DEFINITE,
        codes::TRIANGLE_INEQUALITY,
        codes::ZERO_INERTIA_WITH_MASS,
    ];
    let got: Vec<_> = findings(report)
        .into_iter()
        .filter(|f| inertia_codes.contains(&f.1))
        .collect();
    assert_eq!(got, want, "{rel}: inertia findings vs SOURCE.md");

    let mass_key = if rel.ends_with(".xml") {
        "total_mass_kg_from_inertial"
    } else {
        "total_mass_kg"
    };
    let mass: f64 = summary[mass_key].parse().unwrap();
    // SOURCE.md prints 6 significant digits.
    assert!(
        (report.total_mass - mass).abs() <= 5e-6 * mass,
        "{rel}: total mass {} vs SOURCE.md {mass}",
        report.total_mass
    );

    if let Some(mimic) = summary.get("mimic_joints") {
        let mut want = listed(mimic);
        want.sort();
        let mut got: Vec<String> = report
            .with_code(codes::MIMIC_JOINT)
            .map(|f| f.name.clone())
            .collect();
        got.sort();
        assert_eq!(got, want, "{rel}: mimic joints vs SOURCE.md");
    }
}

/// Every URDF in models/, with and without meshes.
const URDFS: &[&str] = &[
    "coman/coman.urdf",
    "coman/coman.nomesh.urdf",
    "darwin_op/robotis_op.urdf",
    "darwin_op/robotis_op.nomesh.urdf",
    // The nomesh file with sole boxes (SOURCE.md): the same inertials.
    "darwin_op/robotis_op.feet.urdf",
    "icub/iCubGazeboV2_5.urdf",
    "icub/iCubGazeboV2_5.nomesh.urdf",
    "icub/variants/iCubErzelli02.urdf",
    "icub/variants/iCubErzelli02.nomesh.urdf",
    "nao/nao_V50.urdf",
    "nao/nao_V50.nomesh.urdf",
    "nao/variants/nao_V50_committed.urdf",
    "op2/robotis_op2.urdf",
    "op2/robotis_op2.nomesh.urdf",
    "op3/robotis_op3.urdf",
    "op3/robotis_op3.nomesh.urdf",
    "sigmaban/sigmaban.urdf",
    "sigmaban/sigmaban.nomesh.urdf",
    "unitree_g1/g1_29dof_rev_1_0.urdf",
    "unitree_g1/g1_29dof_rev_1_0.nomesh.urdf",
    "unitree_g1/g1_29dof_rev_1_0.decimated.urdf",
    "unitree_g1/variants/g1_23dof_rev_1_0.urdf",
    "unitree_g1/variants/g1_23dof_rev_1_0.nomesh.urdf",
    "unitree_h1/h1.urdf",
    "unitree_h1/h1.nomesh.urdf",
    "unitree_h1/variants/h1_2025-06_a3b70ca.urdf",
    "unitree_h1/variants/h1_2025-12_c4519eb.urdf",
];

/// Every MJCF robot in models/ (`op3/mjcf/scene.xml` is a scene that includes op3.xml).
const MJCFS: &[&str] = &[
    "op3/mjcf/op3.xml",
    "talos/mjcf/talos.xml",
    "unitree_g1/mjcf/g1_29dof_rev_1_0_unitree.xml",
    "unitree_g1/mjcf/g1_menagerie.xml",
    "unitree_h1/mjcf/h1_menagerie.xml",
    "unitree_h1/mjcf/h1_unitree.xml",
];

/// The other humanoids of MuJoCo Menagerie in models/ (issue 30), each with the
/// warnings it must give, by name: what twinloop leaves out of its dynamics
/// (Cassie's four `<connect>` closures, sensors at sites) and Apollo's empty
/// static `world_link`. Everything else (Cassie's springs, every motor's force
/// range) is modelled and gives no warning.
const MENAGERIE: &[(&str, &[&str])] = &[
    (
        "agility_cassie/mjcf/cassie.xml",
        &[
            "<connect> in <equality>",
            "<connect> in <equality>",
            "<connect> in <equality>",
            "<connect> in <equality>",
            "<gyro name=\"pelvis-angular-velocity\">",
            "<accelerometer name=\"pelvis-linear-acceleration\">",
            "<magnetometer name=\"pelvis-magnetometer\">",
        ],
    ),
    (
        "apptronik_apollo/mjcf/apptronik_apollo.xml",
        &[
            "<gyro name=\"IMU-angular-velocity\">",
            "<accelerometer name=\"IMU-linear-acceleration\">",
            "<magnetometer name=\"IMU-magnetometer\">",
            "<body name=\"world_link\">",
        ],
    ),
    (
        "berkeley_humanoid/mjcf/berkeley_humanoid.xml",
        &[
            "<gyro name=\"local_rpyrate\">",
            "<velocimeter name=\"local_linvel\">",
            "<accelerometer name=\"accelerometer\">",
            "<force name=\"left_foot_force\">",
            "<force name=\"right_foot_force\">",
        ],
    ),
    (
        "booster_t1/mjcf/t1.xml",
        &[
            "<gyro name=\"angular-velocity\">",
            "<accelerometer name=\"linear-acceleration\">",
        ],
    ),
    (
        "fourier_n1/mjcf/n1.xml",
        &[
            "<gyro name=\"angular-velocity\">",
            "<accelerometer name=\"linear-acceleration\">",
        ],
    ),
    ("pndbotics_adam_lite/mjcf/adam_lite.xml", &[]),
    // Atlas (Drake's model): no sensors, equalities or tendons; unclamped motors.
    ("atlas/mjcf/atlas.xml", &[]),
    // BXI Elf2: its default class gives the free joint a frictionloss (a dry friction
    // on the six base velocities, not modelled; its armature and damping are), and
    // sensors at its `imu` and foot sites.
    (
        "bxi_elf2/mjcf/elf2_dof25.xml",
        &[
            "<joint name=\"world_joint\">",
            "<gyro name=\"Body_Gyro\">",
            "<accelerometer name=\"Body_Acc\">",
            "<touch name=\"lf_touch\">",
            "<touch name=\"rf_touch\">",
        ],
    ),
    // LimX Oli and Luna: the six `<connect>` closures of the ankle and waist linkages
    // (open-tree dynamics, as MuJoCo's M and bias), the free joint's 1e-9 spring, and
    // sensors at the IMU site.
    (
        "limx_oli/mjcf/oli.xml",
        &[
            "<joint name=\"floating_base_joint\">",
            "<connect name=\"A_achilles_connect_L\">",
            "<connect name=\"B_achilles_connect_L\">",
            "<connect name=\"A_achilles_connect_R\">",
            "<connect name=\"B_achilles_connect_R\">",
            "<connect name=\"waist_connect_A\">",
            "<connect name=\"waist_connect_B\">",
            "<gyro name=\"Body_Gyro\">",
            "<accelerometer name=\"Body_Acc\">",
        ],
    ),
    (
        "limx_luna/mjcf/luna.xml",
        &[
            "<joint> in <body name=\"base_link\">",
            "<connect name=\"left_A_connect_joint\">",
            "<connect name=\"left_B_connect_joint\">",
            "<connect name=\"right_A_connect_joint\">",
            "<connect name=\"right_B_connect_joint\">",
            "<connect name=\"waist_A_connect_joint\">",
            "<connect name=\"waist_B_connect_joint\">",
            "<gyro name=\"base_imu_gyro\">",
            "<accelerometer name=\"base_imu_acc\">",
        ],
    ),
    // Open Duck Mini v2: four 1e-9 kg dummy bodies with a zero inertia, and sensors
    // at its IMU site.
    (
        "open_duck_mini_v2/mjcf/open_duck_mini_v2.xml",
        &[
            "trunk",
            "left_foot",
            "head",
            "right_foot",
            "<gyro name=\"gyro\">",
            "<velocimeter name=\"local_linvel\">",
            "<accelerometer name=\"accelerometer\">",
        ],
    ),
    ("toddlerbot_2xc/mjcf/toddlerbot_2xc.xml", TODDLERBOT),
    ("toddlerbot_2xm/mjcf/toddlerbot_2xm.xml", TODDLERBOT),
];

/// ToddlerBot 2xc and 2xm: the four `<connect>` closures of the neck's four-bar, the
/// nine gear pairs tied by `<joint>` equalities (drive and driven joint each a
/// hinge of its own in the tree) and the two fixed tendons coupling the waist's
/// differential. The `<motor ctrlrange>` sits in the `toddlerbot` default class,
/// which the `<actuator>` section (outside every body) does not use, so MuJoCo
/// compiles the motors unclamped: every hinge also warns that it has no effort
/// limit, counted in [`UNCLAMPED`].
const TODDLERBOT: &[&str] = &[
    "<connect> in <equality>",
    "<connect> in <equality>",
    "<connect> in <equality>",
    "<connect> in <equality>",
    "<joint> in <equality>",
    "<joint> in <equality>",
    "<joint> in <equality>",
    "<joint> in <equality>",
    "<joint> in <equality>",
    "<joint> in <equality>",
    "<joint> in <equality>",
    "<joint> in <equality>",
    "<joint> in <equality>",
    "<fixed name=\"waist_roll_coupling\">",
    "<fixed name=\"waist_yaw_coupling\">",
];

/// Menagerie files whose motors MuJoCo leaves unclamped (no `ctrlrange` or
/// `forcerange` reaches them): each of their hinges (as many as summary.json's
/// MuJoCo count) warns `missing-effort-velocity`, and no other joint does.
const UNCLAMPED: &[&str] = &[
    "atlas/mjcf/atlas.xml",
    "toddlerbot_2xc/mjcf/toddlerbot_2xc.xml",
    "toddlerbot_2xm/mjcf/toddlerbot_2xm.xml",
];

/// The `missing-effort-velocity` warnings of an [`UNCLAMPED`] file: one per hinge.
fn check_unclamped(rel: &str, r: &LintReport) {
    let hinges = models_support::summary_for(&models_dir().join(rel))
        .and_then(|s| s.get("joints_by_type")?.get("hinge").map(|h| h.num()))
        .unwrap_or_else(|| panic!("{rel}: no hinge count in summary.json"));
    let unclamped = r
        .findings
        .iter()
        .filter(|f| f.code == codes::MISSING_EFFORT_VELOCITY)
        .count();
    assert_eq!(unclamped as f64, hinges, "{rel}: {:#?}", r.findings);
}

#[test]
fn menagerie_humanoids_warn_by_name_for_what_is_left_out() {
    for (rel, expected) in MENAGERIE {
        let r = lint_file(rel);
        if UNCLAMPED.contains(rel) {
            check_unclamped(rel, &r);
        }
        let mut warned: Vec<&str> = r
            .findings
            .iter()
            .filter(|f| f.severity == Severity::Warning)
            .filter(|f| !(UNCLAMPED.contains(rel) && f.code == codes::MISSING_EFFORT_VELOCITY))
            .map(|f| f.name.trim_start_matches("element "))
            .collect();
        warned.sort();
        let mut want = expected.to_vec();
        want.sort();
        assert_eq!(warned, want, "{rel}: {:#?}", r.findings);
        assert_eq!(r.errors, 0, "{rel}: {:#?}", r.findings);
    }
}

#[test]
fn the_mjcf_lists_cover_every_bundled_mjcf() {
    let mut found = Vec::new();
    for robot in std::fs::read_dir(models_dir()).unwrap() {
        let dir = robot.unwrap().path().join("mjcf");
        for e in std::fs::read_dir(&dir).into_iter().flatten() {
            let p = e.unwrap().path();
            let name = p.file_name().unwrap().to_str().unwrap();
            if name.ends_with(".xml") && name != "scene.xml" {
                let rel = p.strip_prefix(models_dir()).unwrap().to_str().unwrap();
                found.push(rel.replace('\\', "/"));
            }
        }
    }
    found.sort();
    let mut listed: Vec<String> = MJCFS
        .iter()
        .copied()
        .chain(MENAGERIE.iter().map(|(rel, _)| *rel))
        .map(String::from)
        .collect();
    listed.sort();
    assert_eq!(found, listed);
}

#[test]
fn the_lists_cover_every_bundled_model() {
    let mut found = Vec::new();
    let mut stack = vec![models_dir()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "urdf") {
                let rel = p
                    .strip_prefix(models_dir())
                    .unwrap()
                    .to_str()
                    .unwrap()
                    .replace('\\', "/");
                found.push(rel);
            }
        }
    }
    found.sort();
    let mut listed: Vec<String> = URDFS.iter().map(|s| s.to_string()).collect();
    listed.sort();
    assert_eq!(found, listed);
}

#[test]
fn every_urdf_agrees_with_its_source_summary() {
    for rel in URDFS {
        agrees_with_source(rel, &lint_file(rel));
    }
}

#[test]
fn clean_urdfs_have_nothing_at_error_level() {
    for rel in URDFS {
        if rel.starts_with("op2/") || rel.starts_with("coman/") {
            continue;
        }
        let r = lint_file(rel);
        assert!(!r.has_errors(), "{rel}: {:#?}", r.findings);
    }
}

#[test]
fn op2_placeholders_are_errors_on_every_inertia() {
    for rel in ["op2/robotis_op2.urdf", "op2/robotis_op2.nomesh.urdf"] {
        let r = lint_file(rel);
        let with_inertial = r.links - r.links_without_inertial;
        assert_eq!(with_inertial, 21);
        assert_eq!(r.errors, 21, "{rel}");
        assert_eq!(
            r.with_code(codes::INERTIA_NOT_POSITIVE_DEFINITE).count(),
            21
        );
        for f in r.with_code(codes::INERTIA_NOT_POSITIVE_DEFINITE) {
            assert_eq!(f.severity, Severity::Error);
            assert!(f.message.contains("semi-definite"), "{}", f.message);
        }
        assert_eq!(findings(&r).len(), 21, "{rel}: {:#?}", r.findings);
    }
}

#[test]
fn coman_has_exactly_one_invalid_inertia() {
    for rel in ["coman/coman.urdf", "coman/coman.nomesh.urdf"] {
        let r = lint_file(rel);
        assert_eq!(
            findings(&r),
            expect(&[(Severity::Error, codes::TRIANGLE_INEQUALITY, &["Xtion_body"])]),
            "{rel}"
        );
        let f = r.with_code(codes::TRIANGLE_INEQUALITY).next().unwrap();
        // SOURCE.md: I1+I2=0.009503 < I3=0.01001
        assert!(
            f.message.contains("I1+I2=0.00950255 < I3=0.01000745"),
            "{}",
            f.message
        );
        assert_eq!(
            (r.dof, r.moving_joints),
            (35, 30),
            "29 revolute + one floating joint"
        );
    }
}

#[test]
fn models_without_findings() {
    for rel in [
        "op3/robotis_op3.urdf",
        "op3/robotis_op3.nomesh.urdf",
        "darwin_op/robotis_op.urdf",
        "darwin_op/robotis_op.nomesh.urdf",
        "darwin_op/robotis_op.feet.urdf",
        "icub/iCubGazeboV2_5.urdf",
        "icub/iCubGazeboV2_5.nomesh.urdf",
        "icub/variants/iCubErzelli02.urdf",
        "icub/variants/iCubErzelli02.nomesh.urdf",
        "unitree_g1/g1_29dof_rev_1_0.urdf",
        "unitree_g1/g1_29dof_rev_1_0.nomesh.urdf",
        "unitree_g1/variants/g1_23dof_rev_1_0.urdf",
        "unitree_g1/variants/g1_23dof_rev_1_0.nomesh.urdf",
        "unitree_h1/h1.urdf",
        "unitree_h1/h1.nomesh.urdf",
        "unitree_h1/variants/h1_2025-06_a3b70ca.urdf",
        "unitree_h1/variants/h1_2025-12_c4519eb.urdf",
    ] {
        let r = lint_file(rel);
        assert_eq!(findings(&r), vec![], "{rel}");
        assert_eq!(r.with_code(codes::TOTAL_MASS).count(), 1);
    }
}

#[test]
fn op3_totals() {
    let r = lint_file("op3/robotis_op3.urdf");
    assert!((r.total_mass - 3.14747).abs() < 1e-9, "{}", r.total_mass);
    assert_eq!(
        (
            r.links,
            r.links_without_inertial,
            r.joints,
            r.moving_joints,
            r.dof
        ),
        (23, 2, 22, 20, 20)
    );
    assert_eq!((r.errors, r.warnings, r.infos), (0, 0, 1));
    let f = r.with_code(codes::TOTAL_MASS).next().unwrap();
    assert!(
        f.message.starts_with("total mass 3.14747 kg over 23 links"),
        "{}",
        f.message
    );
}

const NAO_MIMICS: &[&str] = &[
    "RHipYawPitch",
    "RFinger13",
    "RFinger12",
    "LFinger21",
    "LFinger13",
    "LFinger11",
    "RFinger22",
    "LFinger22",
    "RFinger21",
    "LFinger12",
    "RFinger23",
    "RFinger11",
    "LFinger23",
    "LThumb1",
    "RThumb1",
    "RThumb2",
    "LThumb2",
];

#[test]
fn nao_mimics_and_truncated_hip_axes_are_warnings() {
    for rel in [
        "nao/nao_V50.urdf",
        "nao/nao_V50.nomesh.urdf",
        "nao/variants/nao_V50_committed.urdf",
    ] {
        let r = lint_file(rel);
        assert_eq!(
            findings(&r),
            expect(&[
                (Severity::Warning, codes::MIMIC_JOINT, NAO_MIMICS),
                (
                    Severity::Warning,
                    codes::NON_UNIT_AXIS,
                    &["LHipYawPitch", "RHipYawPitch"]
                ),
            ]),
            "{rel}"
        );
        assert_eq!(r.mimic_joints, 17);
    }
}

const SIGMABAN_JOINTS: &[&str] = &[
    "right_elbow",
    "right_shoulder_roll",
    "right_shoulder_pitch",
    "left_elbow",
    "left_shoulder_roll",
    "left_shoulder_pitch",
    "left_ankle_roll",
    "left_ankle_pitch",
    "left_knee",
    "left_hip_pitch",
    "left_hip_roll",
    "left_hip_yaw",
    "right_ankle_roll",
    "right_ankle_pitch",
    "right_knee",
    "right_hip_pitch",
    "right_hip_roll",
    "right_hip_yaw",
    "head_pitch",
    "head_yaw",
];

#[test]
fn sigmaban_dummy_frames_and_missing_ranges_are_warnings() {
    for rel in ["sigmaban/sigmaban.urdf", "sigmaban/sigmaban.nomesh.urdf"] {
        let r = lint_file(rel);
        assert_eq!(
            findings(&r),
            expect(&[
                (
                    Severity::Warning,
                    codes::ZERO_INERTIA_WITH_MASS,
                    &[
                        "head_base",
                        "trunk",
                        "left_foot_tip",
                        "right_foot_tip",
                        "vive_head",
                        "camera"
                    ]
                ),
                (Severity::Warning, codes::MISSING_LIMITS, SIGMABAN_JOINTS),
            ]),
            "{rel}"
        );
        for f in r.with_code(codes::ZERO_INERTIA_WITH_MASS) {
            assert!(f.message.contains("1e-9 kg"), "{}", f.message);
        }
    }
}

#[test]
fn every_mjcf_agrees_with_its_source_summary() {
    for rel in MJCFS {
        agrees_with_source(rel, &lint_file(rel));
    }
}

#[test]
fn mjcf_models_have_no_errors_or_warnings() {
    for rel in MJCFS {
        let r = lint_file(rel);
        // TALOS ties its gripper joints with <equality><joint .../>; the Unitree
        // files put IMU sensors (gyro, accelerometer) at sites: those, and
        // nothing else, are warned about as unmodeled.
        let (expected, element) = match *rel {
            r if r.starts_with("talos/") => (6, "<joint> in <equality>"),
            r if r.starts_with("unitree_g1/") => (4, "imu-"),
            "unitree_h1/mjcf/h1_unitree.xml" => (2, "imu-"),
            _ => (0, ""),
        };
        let unmodeled: Vec<_> = r.with_code(codes::UNMODELED_ELEMENT).collect();
        assert_eq!(unmodeled.len(), expected, "{rel}: {unmodeled:#?}");
        assert!(unmodeled.iter().all(|f| f.name.contains(element)));
        assert_eq!(
            (r.errors, r.warnings),
            (0, expected),
            "{rel}: {:#?}",
            r.findings
        );
        // MJCF joints carry no effort or velocity limit (actuators do): one info
        // per ranged joint. OP3's hinges have no range, so they are continuous.
        let ranged = r.moving_joints;
        let want = if rel.starts_with("op3/") { 0 } else { ranged };
        assert_eq!(
            r.with_code(codes::MISSING_EFFORT_VELOCITY).count(),
            want,
            "{rel}"
        );
        assert_eq!(r.infos, want + 1, "{rel}");
    }
}

#[test]
fn op3_mjcf_and_urdf_weigh_the_same() {
    let urdf = lint_file("op3/robotis_op3.urdf");
    let mjcf = lint_file("op3/mjcf/op3.xml");
    assert!((urdf.total_mass - mjcf.total_mass).abs() < 1e-12);
    assert_eq!(urdf.dof, mjcf.dof);
}

/// Every bundled robot, 0.3 kg to 100 kg, is in metres and kilograms by the
/// `unit-scale` bounds (at most 20 m, less dense than water over its size cubed), and
/// the same file with its masses in grams or its lengths in millimetres is not.
#[test]
fn bundled_robots_pass_the_unit_scale_bounds_and_their_1000x_copies_do_not() {
    use twinloop_description::lint::unit_scale::{MAX_BULK_DENSITY, MAX_EXTENT_M, extent};
    let menagerie = MENAGERIE.iter().map(|(rel, _)| rel);
    for rel in URDFS.iter().chain(MJCFS).chain(menagerie) {
        let robot = twinloop_description::load(models_dir().join(rel)).unwrap();
        let size = extent(&robot);
        let density = robot.total_mass() / size.powi(3);
        eprintln!(
            "{rel}: {:.3} kg, {size:.3} m, {density:.1} kg/m^3",
            robot.total_mass()
        );
        let report = lint(&robot);
        assert!(
            report.with_code(codes::UNIT_SCALE).next().is_none(),
            "{rel}"
        );
        // Every element of the bundled files is one MuJoCo's schema has.
        assert!(
            report
                .findings
                .iter()
                .all(|f| !f.message.contains("not an MJCF element")),
            "{rel}: {:#?}",
            report.findings
        );
        // The margins: each model at least 10x below the density bound, its gram-scale
        // copy at least 5x above it, its millimetre-scale copy 10x beyond the size bound.
        assert!(density * 10.0 < MAX_BULK_DENSITY, "{rel}: {density}");
        assert!(
            density * 1000.0 > 5.0 * MAX_BULK_DENSITY,
            "{rel}: {density}"
        );
        assert!(size * 1000.0 > 10.0 * MAX_EXTENT_M, "{rel}: {size}");
        let mut grams = robot.clone();
        for l in &mut grams.links {
            if let Some(i) = &mut l.inertial {
                i.mass *= 1000.0;
            }
        }
        let g = lint(&grams);
        let f: Vec<_> = g.with_code(codes::UNIT_SCALE).collect();
        assert_eq!(f.len(), 1, "{rel}");
        assert_eq!(f[0].severity, Severity::Error);
        assert!(f[0].message.contains("grams"), "{rel}: {}", f[0]);
        let mut mm = robot.clone();
        for j in &mut mm.joints {
            j.origin.xyz = j.origin.xyz.map(|v| v * 1000.0);
        }
        let m = lint(&mm);
        let f: Vec<_> = m.with_code(codes::UNIT_SCALE).collect();
        assert_eq!(f.len(), 1, "{rel}");
        assert!(f[0].message.contains("millimetres"), "{rel}: {}", f[0]);
    }
}
