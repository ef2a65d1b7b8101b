//! The floating base's armature (an MJCF `<joint type="free" armature>`, which a
//! `<default>` class gives BXI Elf2's free joint; issue 30): against analytic truth on
//! a free box, and against MuJoCo 4 with the base turned and moving
//! (tests/data/base_armature, from tools/oracle/base_armature_reference.py).
//!
//! MuJoCo's free-joint coordinates are the world-frame linear velocity of the body
//! origin and the body-frame angular velocity; twinloop's (Pinocchio's) base velocity
//! has both in the base frame. With `R` the base rotation and `w` its angular
//! velocity: `v = R^T pdot`, `a = R^T pddot - w x v`, a base force `R^T F`. The test
//! converts MuJoCo's numbers so, then compares M, RNEA and ABA entry by entry.

use nalgebra::{DMatrix, Matrix3, Quaternion, UnitQuaternion, Vector3};
use serde_json::Value;
use std::path::PathBuf;
use twinloop_dynamics::*;

const TOL: f64 = 1e-12;

fn vecf(v: &Value) -> Vec<f64> {
    v.as_array()
        .expect("array")
        .iter()
        .map(|x| x.as_f64().expect("number"))
        .collect()
}

fn mat(v: &Value) -> DMatrix<f64> {
    let rows: Vec<Vec<f64>> = v.as_array().unwrap().iter().map(vecf).collect();
    DMatrix::from_fn(rows.len(), rows[0].len(), |i, j| rows[i][j])
}

fn close(what: &str, ours: &[f64], theirs: &[f64]) -> f64 {
    assert_eq!(ours.len(), theirs.len(), "{what}: sizes");
    let scale = theirs.iter().fold(1.0f64, |m, x| m.max(x.abs()));
    let mut worst = 0.0f64;
    for (k, (a, b)) in ours.iter().zip(theirs).enumerate() {
        let rel = (a - b).abs() / scale;
        worst = worst.max(rel);
        assert!(rel <= TOL, "{what}[{k}]: twinloop {a:e} vs reference {b:e}");
    }
    worst
}

/// A free box of mass 2 and principal moments (0.2, 0.3, 0.4) at its origin, with a
/// free-joint armature of 0.05 from the default class.
const BOX: &str = r#"<mujoco model="box">
  <default><joint armature="0.05"/></default>
  <worldbody>
    <body name="box" pos="0 0 1">
      <joint name="root" type="free"/>
      <inertial pos="0 0 0" mass="2" diaginertia="0.2 0.3 0.4"/>
    </body>
  </worldbody>
</mujoco>"#;

fn free_box() -> Model {
    let robot = twinloop_description::mjcf::from_str(BOX).unwrap();
    assert_eq!(robot.base_armature, 0.05);
    Model::from_description(&robot).unwrap()
}

/// `M = diag(m + a, m + a, m + a, Ixx + a, Iyy + a, Izz + a)` at any base pose; a
/// fixed base has no base and no armature there.
#[test]
fn free_box_mass_matrix_has_the_armature_on_its_diagonal() {
    let model = free_box();
    let mut data = Data::new(&model);
    let q = [0.3, -0.2, 1.0, 0.1, -0.4, 0.2, (1.0f64 - 0.21).sqrt()];
    let m = crba(&model, &mut data, &q).clone();
    let want = [2.05, 2.05, 2.05, 0.25, 0.35, 0.45];
    let diag: Vec<f64> = (0..6).map(|k| m[(k, k)]).collect();
    close("box M diagonal", &diag, &want);
    for r in 0..6 {
        for c in r + 1..6 {
            assert_eq!(m[(r, c)], 0.0, "M[{r}][{c}]");
        }
    }
    let robot = twinloop_description::mjcf::from_str(BOX).unwrap();
    let fixed = Model::from_description_with_base(&robot, BaseKind::Fixed).unwrap();
    assert_eq!((fixed.nv, fixed.base_armature), (0, 0.0));
}

/// Free fall: the armature has inertia but no weight, so the box falls at
/// `g m / (m + a)`; spinning about z at rest in translation, a push along x gives
/// `F / (m + a)` and the armature's `a (w x v)` shows in RNEA once the box moves.
#[test]
fn free_box_falls_slower_by_its_armature() {
    let model = free_box();
    let mut data = Data::new(&model);
    let q = model.neutral_configuration();
    let zero = [0.0; 6];
    let qdd = aba(&model, &mut data, &q, &zero, &zero).clone();
    let g = 9.81 * 2.0 / 2.05;
    close(
        "box free fall",
        qdd.as_slice(),
        &[0.0, 0.0, -g, 0.0, 0.0, 0.0],
    );
    let tau = rnea(&model, &mut data, &q, &zero, qdd.as_slice()).clone();
    close("box free fall rnea", tau.as_slice(), &zero);
    // Moving along x while spinning about z: the base frame turns under v, and a
    // body-frame velocity held constant needs the force (m + a) w x v.
    let v = [1.5, 0.0, 0.0, 0.0, 0.0, 2.0];
    let nle = nonlinear_effects(&model, &mut data, &q, &v).clone();
    let wxv = 2.0 * 1.5; // (0, 0, 2) x (1.5, 0, 0) = (0, 3, 0)
    close(
        "box spinning bias",
        nle.as_slice(),
        &[0.0, 2.05 * wxv, 2.0 * 9.81, 0.0, 0.0, 0.0],
    );
}

fn rotation(qpos: &[f64]) -> Matrix3<f64> {
    UnitQuaternion::from_quaternion(Quaternion::new(qpos[3], qpos[4], qpos[5], qpos[6]))
        .to_rotation_matrix()
        .into_inner()
}

/// MuJoCo's free-joint vector (world linear, body angular, then the hinges) in
/// twinloop's base-frame coordinates: the linear part turned by `R^T`.
fn to_base_frame(r: &Matrix3<f64>, x: &[f64]) -> Vec<f64> {
    let lin = r.transpose() * Vector3::new(x[0], x[1], x[2]);
    let mut out = lin.as_slice().to_vec();
    out.extend_from_slice(&x[3..]);
    out
}

#[test]
fn base_armature_agrees_with_mujoco_with_the_base_turned_and_moving() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/base_armature");
    let robot = twinloop_description::load(dir.join("free_armature.xml")).unwrap();
    let refd: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("free_armature.json")).unwrap())
            .unwrap();
    assert_eq!(robot.base_armature, refd["base_armature"].as_f64().unwrap());
    let model = Model::from_description(&robot).unwrap();
    let mut data = Data::new(&model);
    let mut worst = 0.0f64;
    for (s, state) in refd["states"].as_array().unwrap().iter().enumerate() {
        let qpos = vecf(&state["qpos"]);
        let r = rotation(&qpos);
        let mut q = qpos[0..3].to_vec();
        q.extend_from_slice(&[qpos[4], qpos[5], qpos[6], qpos[3]]);
        q.extend_from_slice(&qpos[7..]);
        let v = to_base_frame(&r, &vecf(&state["qvel"]));
        let mut a = to_base_frame(&r, &vecf(&state["qacc"]));
        let wxv = Vector3::new(v[3], v[4], v[5]).cross(&Vector3::new(v[0], v[1], v[2]));
        for k in 0..3 {
            a[k] -= wxv[k];
        }
        let tau = to_base_frame(&r, &vecf(&state["qfrc_applied"]));
        // M in base coordinates: T^T M T, T = diag(R, I).
        let mut t = DMatrix::identity(model.nv, model.nv);
        t.view_mut((0, 0), (3, 3)).copy_from(&r);
        let m_ref = t.transpose() * mat(&state["mass_matrix"]) * &t;
        let mut m = crba(&model, &mut data, &q).clone();
        m.fill_lower_triangle_with_upper_triangle();
        worst = worst.max(close(
            &format!("state {s} M"),
            m.as_slice(),
            m_ref.as_slice(),
        ));
        let ours = rnea(&model, &mut data, &q, &v, &a).clone();
        worst = worst.max(close(&format!("state {s} rnea"), ours.as_slice(), &tau));
        let qdd = aba(&model, &mut data, &q, &v, &tau).clone();
        worst = worst.max(close(&format!("state {s} aba"), qdd.as_slice(), &a));
    }
    println!("base armature: largest relative error against MuJoCo {worst:.1e}");
}
