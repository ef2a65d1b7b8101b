//! Spherical (ball) joints against Pinocchio 4 and MuJoCo 4: random MJCF trees that
//! mix ball, hinge and slide joints (several per body, anchors, rotated bodies,
//! armature; two with a free root), loaded by twinloop's MJCF reader. Reference
//! numbers from tools/oracle/ball_joint_reference.py, committed under
//! tests/data/ball, so this test needs no Python.
//!
//! Compared at three seeded states per model: RNEA, the mass matrix, nonlinear
//! effects, ABA, CoM and its Jacobian, each body's world-frame Jacobian,
//! `integrate` and `difference` (Pinocchio), and with a fixed root the mass matrix
//! and bias forces (MuJoCo's `mj_fullM`, `qfrc_bias`). q is Pinocchio's order (a
//! ball's quaternion x, y, z, w), which is twinloop's.

use nalgebra::DMatrix;
use serde_json::Value;
use std::path::PathBuf;
use twinloop_description::load;
use twinloop_dynamics::configuration::{difference, integrate};
use twinloop_dynamics::*;

const TOL: f64 = 1e-9;

fn dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/ball")
}

fn vecf(v: &Value) -> Vec<f64> {
    v.as_array()
        .expect("array")
        .iter()
        .map(|x| x.as_f64().expect("number"))
        .collect()
}

fn mat(v: &Value) -> DMatrix<f64> {
    let rows: Vec<Vec<f64>> = v.as_array().unwrap().iter().map(vecf).collect();
    let (r, c) = (rows.len(), rows.first().map_or(0, |x| x.len()));
    DMatrix::from_fn(r, c, |i, j| rows[i][j])
}

thread_local! {
    static WORST: std::cell::Cell<f64> = const { std::cell::Cell::new(0.0) };
}

fn close(what: &str, ours: &[f64], theirs: &[f64]) {
    assert_eq!(ours.len(), theirs.len(), "{what}: sizes");
    let scale = theirs.iter().fold(1.0f64, |m, x| m.max(x.abs()));
    for (k, (a, b)) in ours.iter().zip(theirs).enumerate() {
        let rel = (a - b).abs() / scale;
        WORST.with(|w| w.set(w.get().max(rel)));
        assert!(rel <= TOL, "{what}[{k}]: twinloop {a:e} vs reference {b:e}");
    }
}

fn close_mat(what: &str, ours: &DMatrix<f64>, theirs: &DMatrix<f64>) {
    assert_eq!(ours.shape(), theirs.shape(), "{what}: shape");
    close(what, ours.as_slice(), theirs.as_slice());
}

/// The reference models, in name order.
fn models() -> Vec<(String, Value)> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    files.sort();
    files
        .into_iter()
        .map(|p| {
            let name = p.file_stem().unwrap().to_string_lossy().to_string();
            let refd = serde_json::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap();
            (name, refd)
        })
        .collect()
}

fn model_of(name: &str, refd: &Value) -> Model {
    let robot = load(dir().join(format!("{name}.xml"))).unwrap_or_else(|e| panic!("{name}: {e}"));
    let base = if refd["free_root"].as_bool().unwrap() {
        BaseKind::Floating
    } else {
        BaseKind::Fixed
    };
    let model =
        Model::from_description_with_base(&robot, base).unwrap_or_else(|e| panic!("{name}: {e}"));
    assert!(model.has_spherical_joints(), "{name}");
    assert_eq!(
        model.nq,
        refd["nq"].as_u64().unwrap() as usize,
        "{name}: nq"
    );
    assert_eq!(
        model.nv,
        refd["nv"].as_u64().unwrap() as usize,
        "{name}: nv"
    );
    // Same coordinate order as MuJoCo and Pinocchio (depth-first, file order).
    let names: Vec<String> = refd["v_names"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap().to_string())
        .collect();
    assert_eq!(model.v_names(), names, "{name}: velocity coordinates");
    model
}

fn check_state(name: &str, model: &Model, data: &mut Data, s: &Value) {
    let (q, v, a, tau) = (vecf(&s["q"]), vecf(&s["v"]), vecf(&s["a"]), vecf(&s["tau"]));
    close(
        &format!("{name} rnea"),
        rnea(model, data, &q, &v, &a).as_slice(),
        &vecf(&s["rnea"]),
    );
    crba(model, data, &q);
    data.symmetrize_mass_matrix();
    let m_ref = mat(&s["mass_matrix"]);
    close_mat(&format!("{name} crba"), &data.mass_matrix, &m_ref);
    close(
        &format!("{name} nle"),
        nonlinear_effects(model, data, &q, &v).as_slice(),
        &vecf(&s["nle"]),
    );
    close(
        &format!("{name} aba"),
        aba(model, data, &q, &v, &tau).as_slice(),
        &vecf(&s["aba"]),
    );
    close(
        &format!("{name} com"),
        center_of_mass(model, data, &q).as_slice(),
        &vecf(&s["com"]),
    );
    let jc = jacobian_center_of_mass(model, data, &q).clone();
    close_mat(
        &format!("{name} com jacobian"),
        &jc,
        &mat(&s["com_jacobian"]),
    );
    compute_joint_jacobians(model, data, &q);
    let mut j = DMatrix::zeros(6, model.nv);
    for (body, jref) in s["body_jacobians"].as_object().unwrap() {
        let f = model.frame_index(body).unwrap_or_else(|| panic!("{body}"));
        frame_jacobian(model, data, f, ReferenceFrame::World, &mut j);
        close_mat(&format!("{name} {body} jacobian"), &j, &mat(jref));
    }
    let mut out = vec![0.0; model.nq];
    integrate(model, &q, &v, s["integrate_dt"].as_f64().unwrap(), &mut out);
    let pin_q = vecf(&s["integrate"]);
    if model.is_floating()
        && out[3..7]
            .iter()
            .zip(&pin_q[3..7])
            .map(|(a, b)| a * b)
            .sum::<f64>()
            < 0.0
    {
        // The base quaternion is twinloop's own (Shepperd, from the matrix); Pinocchio
        // keeps q's hemisphere. Same rotation; ball joints follow Pinocchio exactly.
        out[3..7].iter_mut().for_each(|x| *x = -*x);
    }
    close(&format!("{name} integrate"), &out, &pin_q);
    let mut dv = vec![0.0; model.nv];
    difference(model, &q, &vecf(&s["q2"]), &mut dv);
    close(&format!("{name} difference"), &dv, &vecf(&s["difference"]));
    if let Some(full) = s.get("mujoco_mass_matrix") {
        close_mat(
            &format!("{name} mj_fullM"),
            &data_m(model, data, &q),
            &mat(full),
        );
        close(
            &format!("{name} qfrc_bias"),
            nonlinear_effects(model, data, &q, &v).as_slice(),
            &vecf(&s["mujoco_bias"]),
        );
    }
}

fn data_m(model: &Model, data: &mut Data, q: &[f64]) -> DMatrix<f64> {
    crba(model, data, q);
    data.symmetrize_mass_matrix();
    data.mass_matrix.clone()
}

#[test]
fn ball_joint_models_match_pinocchio_and_mujoco() {
    let models = models();
    assert_eq!(models.len(), 8, "reference models");
    for (name, refd) in &models {
        let model = model_of(name, refd);
        let mut data = Data::new(&model);
        for s in refd["states"].as_array().unwrap() {
            check_state(name, &model, &mut data, s);
        }
    }
    eprintln!(
        "ball joints: {} models, largest relative error {:.1e}",
        models.len(),
        WORST.with(|w| w.get())
    );
}

#[test]
fn integrating_a_spinning_ball_keeps_a_unit_quaternion() {
    let (name, refd) = &models()[0];
    let model = model_of(name, refd);
    let mut q = model.neutral_configuration();
    let v: Vec<f64> = (0..model.nv).map(|k| 3.0 + k as f64).collect();
    let mut next = q.clone();
    for _ in 0..100_000 {
        integrate(&model, &q, &v, 1e-3, &mut next);
        std::mem::swap(&mut q, &mut next);
    }
    for i in 0..model.nbodies {
        if model.joint_types[i] == JointType::Spherical {
            let n: f64 = q[model.idx_q[i]..model.idx_q[i] + 4]
                .iter()
                .map(|x| x * x)
                .sum();
            assert!((n.sqrt() - 1.0).abs() < 1e-14, "{name}: |q| = {}", n.sqrt());
        }
    }
}
