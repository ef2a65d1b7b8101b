//! The batch commands against Pinocchio's numbers (tests/data/pinocchio of the
//! dynamics crate): a trajectory built from the reference states goes in, and the
//! CSV that comes out must match Pinocchio's RNEA, ABA and CoM.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("twinloop-cli-dyn-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

fn nums(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

fn read_csv(p: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(p).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    (header, rows)
}

/// OP3's reference states as a trajectory CSV with twinloop's column names.
fn write_trajectory(refd: &Value, path: &Path) {
    let mut header = vec!["t".to_string()];
    let mut rows: Vec<Vec<f64>> = vec![];
    let joints = refd["joints"].as_array().unwrap();
    for (si, st) in refd["states"].as_array().unwrap().iter().enumerate() {
        let (q, v, a, tau) = (
            nums(&st["q"]),
            nums(&st["v"]),
            nums(&st["a"]),
            nums(&st["tau"]),
        );
        let mut row = vec![si as f64 * 0.01];
        for j in joints {
            let (iq, iv) = (
                j["idx_q"].as_u64().unwrap() as usize,
                j["idx_v"].as_u64().unwrap() as usize,
            );
            if j["type"] == "JointModelFreeFlyer" {
                if si == 0 {
                    for s in ["x", "y", "z", "qx", "qy", "qz", "qw"] {
                        header.push(format!("q:base.{s}"));
                    }
                    for p in ["v", "a"] {
                        for s in ["vx", "vy", "vz", "wx", "wy", "wz"] {
                            header.push(format!("{p}:base.{s}"));
                        }
                    }
                    for s in ["fx", "fy", "fz", "tx", "ty", "tz"] {
                        header.push(format!("tau:base.{s}"));
                    }
                }
                row.extend(&q[iq..iq + 7]);
                row.extend(&v[iv..iv + 6]);
                row.extend(&a[iv..iv + 6]);
                row.extend(&tau[iv..iv + 6]);
            } else {
                let n = j["name"].as_str().unwrap();
                if si == 0 {
                    for p in ["q", "v", "a", "tau"] {
                        header.push(format!("{p}:{n}"));
                    }
                }
                row.extend([q[iq], v[iv], a[iv], tau[iv]]);
            }
        }
        rows.push(row);
    }
    let mut s = header.join(",") + "\n";
    for r in rows {
        s += &r
            .iter()
            .map(|x| format!("{x:?}"))
            .collect::<Vec<_>>()
            .join(",");
        s += "\n";
    }
    std::fs::write(path, s).unwrap();
}

fn col(header: &[String], name: &str) -> usize {
    header
        .iter()
        .position(|h| h == name)
        .unwrap_or_else(|| panic!("no column {name}"))
}

#[test]
fn batch_commands_match_pinocchio() {
    let refd: Value = serde_json::from_str(
        &std::fs::read_to_string(
            repo().join("crates/twinloop-dynamics/tests/data/pinocchio/op3.json"),
        )
        .unwrap(),
    )
    .unwrap();
    let urdf = repo().join("models/op3/robotis_op3.nomesh.urdf");
    let traj = tmp("op3_traj.csv");
    write_trajectory(&refd, &traj);
    let bin = env!("CARGO_BIN_EXE_twinloop");
    let run = |cmd: &str, out: &Path| {
        let o = Command::new(bin)
            .args(["dynamics", cmd, "--robot"])
            .arg(&urdf)
            .arg("--trajectory")
            .arg(&traj)
            .arg("--out")
            .arg(out)
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "{cmd}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        read_csv(out)
    };
    let close = |a: f64, b: f64, what: &str| {
        assert!(
            (a - b).abs() <= 1e-9 * b.abs().max(1.0),
            "{what}: {a} vs {b}"
        )
    };
    let joints = refd["joints"].as_array().unwrap();
    let states = refd["states"].as_array().unwrap();

    let (h, rows) = run("inverse", &tmp("tau.csv"));
    let (ha, rows_a) = run("forward", &tmp("acc.csv"));
    let (hk, rows_k) = run("kinematics", &tmp("kin.csv"));
    assert_eq!(rows.len(), states.len());
    for (si, st) in states.iter().enumerate() {
        assert_eq!(rows[si][col(&h, "t")], si as f64 * 0.01);
        let (rnea, aba) = (nums(&st["rnea"]), nums(&st["aba"]));
        for j in joints {
            let iv = j["idx_v"].as_u64().unwrap() as usize;
            if j["type"] == "JointModelFreeFlyer" {
                for (k, s) in ["fx", "fy", "fz", "tx", "ty", "tz"].iter().enumerate() {
                    close(rows[si][col(&h, &format!("tau:base.{s}"))], rnea[iv + k], s);
                }
                for (k, s) in ["vx", "vy", "vz", "wx", "wy", "wz"].iter().enumerate() {
                    close(rows_a[si][col(&ha, &format!("a:base.{s}"))], aba[iv + k], s);
                }
            } else {
                let n = j["name"].as_str().unwrap();
                close(rows[si][col(&h, &format!("tau:{n}"))], rnea[iv], n);
                close(rows_a[si][col(&ha, &format!("a:{n}"))], aba[iv], n);
            }
        }
        let com = nums(&st["com"]);
        for (k, s) in ["com.x", "com.y", "com.z"].iter().enumerate() {
            close(rows_k[si][col(&hk, s)], com[k], s);
        }
        let foot = &st["body_placements"]["r_ank_roll_link"]["translation"];
        let t = nums(foot);
        close(
            rows_k[si][col(&hk, "pose:r_ank_roll_link.x")],
            t[0],
            "foot x",
        );
        close(
            rows_k[si][col(&hk, "pose:r_ank_roll_link.z")],
            t[2],
            "foot z",
        );
    }
}

#[test]
fn missing_columns_and_bad_cells_are_named() {
    let urdf = repo().join("models/op3/robotis_op3.nomesh.urdf");
    let bad = tmp("bad.csv");
    std::fs::write(&bad, "t,q:base.x\n0,1\n").unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_twinloop"))
        .args(["dynamics", "inverse", "--robot"])
        .arg(&urdf)
        .arg("--trajectory")
        .arg(&bad)
        .arg("--out")
        .arg(tmp("never.csv"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("bad.csv") && err.contains("missing") && err.contains("q:base.y"),
        "{err}"
    );
    std::fs::write(&bad, "t,q:base.x\n0,1\nx,2\n").unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_twinloop"))
        .args(["dynamics", "kinematics", "--robot"])
        .arg(&urdf)
        .arg("--trajectory")
        .arg(&bad)
        .arg("--out")
        .arg(tmp("never.csv"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("bad.csv:3") && err.contains("\"t\""), "{err}");
}

/// A ball-joint model's CSV columns (`q:<joint>.qx .. .qw`, `v:<joint>.wx .. .wz`,
/// `tau:<joint>.tx .. .tz`, `a:<joint>.wx ..`): forward dynamics of the dynamics
/// crate's ball_0 reference states equals Pinocchio's ABA.
#[test]
fn forward_dynamics_of_ball_joints_matches_pinocchio() {
    let dir = repo().join("crates/twinloop-dynamics/tests/data/ball");
    let refd: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("ball_0.json")).unwrap()).unwrap();
    assert_eq!(refd["free_root"], false);
    let v_names: Vec<String> = refd["v_names"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap().to_string())
        .collect();
    let mut q_names = Vec::new();
    for n in &v_names {
        match n.strip_suffix(".wx") {
            Some(j) => q_names.extend(["qx", "qy", "qz", "qw"].map(|s| format!("{j}.{s}"))),
            None if n.ends_with(".wy") || n.ends_with(".wz") => {}
            None => q_names.push(n.clone()),
        }
    }
    let tau_names: Vec<String> = v_names
        .iter()
        .map(|n| {
            n.replace(".wx", ".tx")
                .replace(".wy", ".ty")
                .replace(".wz", ".tz")
        })
        .collect();
    let mut header = vec!["t".to_string()];
    header.extend(q_names.iter().map(|n| format!("q:{n}")));
    header.extend(v_names.iter().map(|n| format!("v:{n}")));
    header.extend(tau_names.iter().map(|n| format!("tau:{n}")));
    let mut text = header.join(",") + "\n";
    let states = refd["states"].as_array().unwrap();
    for (k, s) in states.iter().enumerate() {
        let mut row = vec![k as f64];
        row.extend(nums(&s["q"]));
        row.extend(nums(&s["v"]));
        row.extend(nums(&s["tau"]));
        let cells: Vec<String> = row.iter().map(|x| format!("{x:e}")).collect();
        text += &(cells.join(",") + "\n");
    }
    let input = tmp("ball.csv");
    std::fs::write(&input, text).unwrap();
    let out = tmp("ball_acc.csv");
    let o = Command::new(env!("CARGO_BIN_EXE_twinloop"))
        .args(["dynamics", "forward", "--fixed-base", "--robot"])
        .arg(dir.join("ball_0.xml"))
        .arg("--trajectory")
        .arg(&input)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (h, rows) = read_csv(&out);
    for (s, row) in states.iter().zip(&rows) {
        for (n, want) in v_names.iter().zip(nums(&s["aba"])) {
            let got = row[col(&h, &format!("a:{n}"))];
            assert!(
                (got - want).abs() <= 1e-9 * want.abs().max(1.0),
                "a:{n}: {got} vs Pinocchio {want}"
            );
        }
    }
}

/// A model whose mass matrix is singular (a massless leaf on the wrist joint):
/// forward dynamics refuses it naming the joint and the row (exit 2), where it
/// used to write NaN rows and exit 0.
#[test]
fn forward_dynamics_refuses_a_singular_mass_matrix_naming_the_joint() {
    let urdf = tmp("massless_leaf.urdf");
    std::fs::write(
        &urdf,
        r#"<robot name="arm">
  <link name="base"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="upper"><inertial><origin xyz="0 0 -0.2"/><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="leaf"/>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="upper"/><axis xyz="1 0 0"/><limit lower="-2" upper="2" effort="10" velocity="5"/></joint>
  <joint name="wrist" type="revolute"><parent link="upper"/><child link="leaf"/><origin xyz="0 0 -0.4"/><axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="10" velocity="5"/></joint>
</robot>
"#,
    )
    .unwrap();
    let input = tmp("massless_leaf.csv");
    std::fs::write(
        &input,
        "t,q:shoulder,q:wrist,v:shoulder,v:wrist,tau:shoulder,tau:wrist\n\
         0,0.1,0.2,0,0,0,0\n0.01,0.2,0.3,0.1,0.1,0.5,0.1\n",
    )
    .unwrap();
    let out = tmp("massless_leaf_acc.csv");
    let o = Command::new(env!("CARGO_BIN_EXE_twinloop"))
        .args(["dynamics", "forward", "--fixed-base", "--robot"])
        .arg(&urdf)
        .arg("--trajectory")
        .arg(&input)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.starts_with("error: ")
            && err.contains("massless_leaf.csv")
            && err.contains("\"wrist\""),
        "{err}"
    );
    assert!(err.contains("singular"), "{err}");
    if let Ok(text) = std::fs::read_to_string(&out) {
        assert!(!text.to_lowercase().contains("nan"), "{text}");
    }
}

/// Two point masses 0.4 m apart on a fixed joint: every link has mass, but the
/// whole robot has no rotational inertia about the line through them, so as a
/// floating base (no --fixed-base) its mass matrix is singular. Forward dynamics
/// refuses it naming the floating base, the file and the row (exit 2, no NaN
/// rows), and `model lint` reports it as the `singular-floating-base` warning
/// (a warning: with a fixed base the same description may be fine).
#[test]
fn forward_dynamics_refuses_a_singular_floating_base() {
    let urdf = tmp("dumbbell.urdf");
    std::fs::write(
        &urdf,
        r#"<robot name="dumbbell">
  <link name="a"><inertial><mass value="1"/><inertia ixx="0" iyy="0" izz="0" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="b"><inertial><mass value="1"/><inertia ixx="0" iyy="0" izz="0" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="bar" type="fixed"><parent link="a"/><child link="b"/><origin xyz="0.4 0 0"/></joint>
</robot>
"#,
    )
    .unwrap();
    let input = tmp("dumbbell.csv");
    std::fs::write(
        &input,
        "t,q:base.x,q:base.y,q:base.z,q:base.qx,q:base.qy,q:base.qz,q:base.qw,\
         v:base.vx,v:base.vy,v:base.vz,v:base.wx,v:base.wy,v:base.wz,\
         tau:base.fx,tau:base.fy,tau:base.fz,tau:base.tx,tau:base.ty,tau:base.tz\n\
         0,0,0,1,0,0,0,1,0,0,0,0,0,0,0,0,0,0,0,0\n",
    )
    .unwrap();
    let out = tmp("dumbbell_acc.csv");
    let run = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_twinloop"))
            .args(args)
            .output()
            .unwrap()
    };
    let o = run(&[
        "dynamics",
        "forward",
        "--robot",
        urdf.to_str().unwrap(),
        "--trajectory",
        input.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.starts_with("error: ")
            && err.contains("dumbbell.csv")
            && err.contains("row 1")
            && err.contains("singular at the floating base")
            && err.contains("all mass on one line"),
        "{err}"
    );
    if let Ok(text) = std::fs::read_to_string(&out) {
        assert!(!text.to_lowercase().contains("nan"), "{text}");
    }
    let lint = run(&["model", "lint", urdf.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&lint.stdout);
    let line = text
        .lines()
        .find(|l| l.contains("singular-floating-base"))
        .unwrap_or_else(|| panic!("{text}"));
    assert!(
        line.starts_with("warning") && line.contains("principal moments about its CoM are 0"),
        "{line}"
    );
    assert_eq!(lint.status.code(), Some(0), "warnings only: {text}");
}
