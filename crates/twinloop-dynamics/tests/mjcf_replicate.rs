//! `<replicate>` expanded as MuJoCo 4 does: nested replicas (offsets, rotations,
//! `sep`, two-digit suffixes) at the top level and inside a body, with hinge and
//! ball joints, geoms and sites. Reference from tools/oracle/replicate_reference.py
//! (tests/data/replicate, committed): body names and masses, site names, the
//! velocity coordinates, and with the root fixed the mass matrix (`mj_fullM`) and
//! bias forces (`qfrc_bias`) at two seeded states.

use serde_json::Value;
use std::path::PathBuf;
use twinloop_description::load;
use twinloop_dynamics::*;

fn strings(v: &Value) -> Vec<String> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_str().unwrap().to_string())
        .collect()
}

fn nums(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

#[test]
fn replicate_expands_as_mujoco_does() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/replicate");
    let refd: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("replicate.json")).unwrap())
            .unwrap();
    let robot = load(dir.join("replicate.xml")).unwrap();
    for (b, mass) in strings(&refd["bodies"])
        .iter()
        .zip(nums(&refd["body_mass"]))
    {
        let link = robot
            .links
            .iter()
            .find(|l| &l.name == b)
            .unwrap_or_else(|| panic!("no link {b}"));
        assert!(
            (link.mass() - mass).abs() <= 1e-12 * mass,
            "{b}: {} vs {mass}",
            link.mass()
        );
    }
    for s in strings(&refd["sites"]) {
        assert!(robot.frames.iter().any(|f| f.name == s), "no site {s}");
    }
    let model = Model::from_description_with_base(&robot, BaseKind::Fixed).unwrap();
    assert_eq!(model.v_names(), strings(&refd["v_names"]));
    let mut data = Data::new(&model);
    let mut worst: f64 = 0.0;
    for s in refd["states"].as_array().unwrap() {
        let (q, v) = (nums(&s["q"]), nums(&s["v"]));
        crba(&model, &mut data, &q);
        data.symmetrize_mass_matrix();
        let rows: Vec<Vec<f64>> = s["mass_matrix"]
            .as_array()
            .unwrap()
            .iter()
            .map(nums)
            .collect();
        for (r, row) in rows.iter().enumerate() {
            for (c, want) in row.iter().enumerate() {
                let e = (data.mass_matrix[(r, c)] - want).abs();
                assert!(e <= 1e-9 * want.abs().max(1.0), "M[{r}][{c}]: {e:e}");
                worst = worst.max(e);
            }
        }
        let bias = nonlinear_effects(&model, &mut data, &q, &v).clone();
        for (k, want) in nums(&s["bias"]).iter().enumerate() {
            let e = (bias[k] - want).abs();
            assert!(
                e <= 1e-9 * want.abs().max(1.0),
                "bias[{k}]: {} vs {want}",
                bias[k]
            );
            worst = worst.max(e);
        }
    }
    eprintln!("replicate: largest error {worst:.1e}");
}
