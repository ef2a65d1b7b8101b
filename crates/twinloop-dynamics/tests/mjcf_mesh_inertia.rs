//! Mesh `inertia="shell"` (mass on the surface) and `inertia="convex"` (the convex
//! hull's volume) against MuJoCo 4's compiled bodies:
//! twinloop-description/tests/data/mjcf/mesh_inertia,
//! made by tools/oracle/mesh_inertia_reference.py (committed numbers, no Python at
//! test time).

use serde_json::Value;
use std::path::PathBuf;
use twinloop_description::load;

type M3 = [[f64; 3]; 3];

fn mul(a: &M3, b: &M3) -> M3 {
    std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
}

fn transpose(a: &M3) -> M3 {
    std::array::from_fn(|i| std::array::from_fn(|j| a[j][i]))
}

/// Rotation of a unit quaternion (w, x, y, z), MuJoCo's order.
fn rot_wxyz(q: &[f64]) -> M3 {
    let (w, x, y, z) = (q[0], q[1], q[2], q[3]);
    [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - w * z),
            2.0 * (x * z + w * y),
        ],
        [
            2.0 * (x * y + w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - w * x),
        ],
        [
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ]
}

fn nums(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

#[test]
fn shell_and_convex_meshes_weigh_what_mujoco_says() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../twinloop-description/tests/data/mjcf/mesh_inertia");
    let refd: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("reference.json")).unwrap())
            .unwrap();
    let robot = load(dir.join("mesh_inertia.xml")).unwrap();
    let bodies = refd["bodies"].as_array().unwrap();
    assert_eq!(bodies.len(), 5);
    let mut worst: f64 = 0.0;
    for b in bodies {
        let name = b["name"].as_str().unwrap();
        let link = robot.links.iter().find(|l| l.name == name).unwrap();
        let i = link
            .inertial
            .unwrap_or_else(|| panic!("{name}: no inertial"));
        let mass = b["mass"].as_f64().unwrap();
        let rel = (i.mass - mass).abs() / mass;
        assert!(rel < 1e-9, "{name}: mass {} vs MuJoCo {mass}", i.mass);
        worst = worst.max(rel);
        let ipos = nums(&b["ipos"]);
        for k in 0..3 {
            let e = (i.origin.xyz[k] - ipos[k]).abs();
            assert!(
                e < 1e-9,
                "{name}: CoM {:?} vs MuJoCo {ipos:?}",
                i.origin.xyz
            );
            worst = worst.max(e);
        }
        // Both tensors in the body frame: twinloop's through its inertial origin,
        // MuJoCo's principal moments through body_iquat.
        let r = i.origin.rotation();
        let ours = mul(&mul(&r, &i.inertia.matrix()), &transpose(&r));
        let d = nums(&b["inertia"]);
        let q = rot_wxyz(&nums(&b["iquat"]));
        let diag = [[d[0], 0.0, 0.0], [0.0, d[1], 0.0], [0.0, 0.0, d[2]]];
        let theirs = mul(&mul(&q, &diag), &transpose(&q));
        let scale = d.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        for r in 0..3 {
            for c in 0..3 {
                let e = (ours[r][c] - theirs[r][c]).abs() / scale;
                // MuJoCo's mju_eig3 gives the axes to about 1e-8 (docs/mjcf.md).
                assert!(
                    e < 1e-7,
                    "{name}: inertia[{r}][{c}] {ours:?} vs MuJoCo {theirs:?}"
                );
                worst = worst.max(e);
            }
        }
    }
    eprintln!("shell and convex meshes: largest relative error {worst:.1e}");
}
