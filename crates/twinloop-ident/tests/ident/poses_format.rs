//! The static-pose reader: a round trip, and errors that name the file, row and field.

use std::path::{Path, PathBuf};
use twinloop_dynamics::Model;
use twinloop_ident::poses::pose_columns;
use twinloop_ident::{PoseCategory, StaticPose, read_static_poses, write_static_poses};

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn h1() -> Model {
    let robot = twinloop_description::load(repo().join("models/unitree_h1/h1.urdf")).unwrap();
    Model::from_description(&robot).unwrap()
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("twinloop-ident-poses-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

fn sample(model: &Model) -> Vec<StaticPose> {
    let mut q = model.neutral_configuration();
    q[2] = 1.05;
    q[model.q_offset + 3] = 0.25;
    vec![
        StaticPose {
            q: q.clone(),
            cop: [0.001, -0.002],
            category: Some(PoseCategory::Crouch),
        },
        StaticPose {
            q,
            cop: [1.0 / 3.0, 0.0],
            category: None,
        },
    ]
}

fn write_text(name: &str, text: &str) -> PathBuf {
    let p = tmp(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// The sample poses as CSV text, with `edit` applied to the data row `row` (0-based)
/// and column `col`.
fn edited(model: &Model, row: usize, col: &str, value: &str) -> String {
    // A file per edit: tests run at once, and each output is written beside its
    // target and renamed.
    let p = tmp(&format!("base-{row}-{}.csv", col.replace(':', "_")));
    write_static_poses(&p, model, &sample(model)).unwrap();
    let text = std::fs::read_to_string(&p).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let k = lines[0].split(',').position(|c| c == col).unwrap();
    let mut cells: Vec<String> = lines[row + 1].split(',').map(String::from).collect();
    cells[k] = value.to_string();
    lines[row + 1] = cells.join(",");
    lines.join("\n") + "\n"
}

fn err(model: &Model, path: &Path) -> String {
    read_static_poses(path, model).unwrap_err().to_string()
}

#[test]
fn round_trip_is_exact() {
    let m = h1();
    let p = tmp("rt.csv");
    let poses = sample(&m);
    write_static_poses(&p, &m, &poses).unwrap();
    let back = read_static_poses(&p, &m).unwrap();
    assert_eq!(back, poses);
    assert_eq!(pose_columns(&m).len(), 1 + m.nq + 2);
}

#[test]
fn nan_cell_names_row_and_column() {
    let m = h1();
    let p = write_text("nan.csv", &edited(&m, 1, "q:left_knee_joint", "NaN"));
    let e = err(&m, &p);
    assert!(e.contains("nan.csv"), "{e}");
    assert!(e.contains("data row 2"), "{e}");
    assert!(e.contains("q:left_knee_joint"), "{e}");
}

#[test]
fn unknown_joint_column_is_named() {
    let m = h1();
    let text = std::fs::read_to_string({
        let p = tmp("u0.csv");
        write_static_poses(&p, &m, &sample(&m)).unwrap();
        p
    })
    .unwrap()
    .replacen("q:torso_joint", "q:waist_joint", 1);
    let p = write_text("unknown.csv", &text);
    let e = err(&m, &p);
    assert!(e.contains("q:waist_joint"), "{e}");
    assert!(e.contains("not a joint"), "{e}");
}

#[test]
fn missing_cop_and_bad_quaternion_and_category() {
    let m = h1();
    let text = std::fs::read_to_string({
        let p = tmp("c0.csv");
        write_static_poses(&p, &m, &sample(&m)).unwrap();
        p
    })
    .unwrap()
    .replacen("cop.y", "cop.z", 1);
    let e = err(&m, &write_text("nocop.csv", &text));
    assert!(e.contains("cop.y"), "{e}");

    let e = err(
        &m,
        &write_text("quat.csv", &edited(&m, 0, "q:base.qw", "0.5")),
    );
    assert!(e.contains("data row 1") && e.contains("norm"), "{e}");

    let e = err(&m, &write_text("cat.csv", &edited(&m, 1, "category", "9")));
    assert!(e.contains("data row 2") && e.contains("category"), "{e}");

    let e = err(&m, &write_text("empty.csv", &pose_columns(&m).join(",")));
    // The table layer refuses a header without rows (issue 29), naming the file.
    assert!(e.contains("empty.csv") && e.contains("no data rows"), "{e}");
}
