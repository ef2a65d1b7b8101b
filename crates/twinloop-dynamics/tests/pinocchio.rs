//! Agreement with Pinocchio 4.1 at seeded random states, floating base, on real
//! robots. Reference numbers come from tools/oracle/pinocchio_reference.py and are
//! committed under tests/data/pinocchio, so this test needs no Python.
//!
//! Differences in convention handled here: Pinocchio orders sibling URDF joints by
//! name (twinloop: file order), so everything is matched by joint and frame name;
//! Pinocchio stores a continuous joint as (cos, sin), twinloop as the angle.

use nalgebra::{DMatrix, DVector};
use serde_json::Value;
use std::path::PathBuf;
use twinloop_dynamics::*;

const TOL: f64 = 1e-9;

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn f(v: &Value) -> f64 {
    v.as_f64().expect("number")
}

fn vecf(v: &Value) -> Vec<f64> {
    v.as_array().expect("array").iter().map(f).collect()
}

fn mat(v: &Value) -> DMatrix<f64> {
    let rows: Vec<Vec<f64>> = v.as_array().unwrap().iter().map(vecf).collect();
    let (r, c) = (rows.len(), rows.first().map_or(0, |x| x.len()));
    DMatrix::from_fn(r, c, |i, j| rows[i][j])
}

thread_local! {
    /// The largest error of this test's model relative to max(1, |Pinocchio|), and
    /// where (each test runs on a thread of its own): how far inside TOL it is.
    static LARGEST: std::cell::RefCell<(f64, String)> = const { std::cell::RefCell::new((0.0, String::new())) };
}

fn close(what: &str, ours: f64, theirs: f64) {
    let err = (ours - theirs).abs();
    LARGEST.with(|l| {
        let rel = err / theirs.abs().max(1.0);
        if rel > l.borrow().0 {
            *l.borrow_mut() = (rel, what.to_string());
        }
    });
    assert!(
        err <= TOL * theirs.abs().max(1.0),
        "{what}: twinloop {ours:e} vs Pinocchio {theirs:e} (error {err:e})"
    );
}

/// Index maps between Pinocchio's and twinloop's coordinates.
struct Maps {
    /// For each twinloop v index, Pinocchio's v index.
    v_pin: Vec<usize>,
    /// For each Pinocchio joint (0-based, excluding universe), twinloop's parameter block.
    block_of_pin_joint: Vec<usize>,
}

fn maps(model: &Model, refd: &Value) -> Maps {
    let joints = refd["joints"].as_array().unwrap();
    let mut v_pin = vec![usize::MAX; model.nv];
    let mut block_of_pin_joint = Vec::new();
    for (k, j) in joints.iter().enumerate() {
        let idx_v = j["idx_v"].as_u64().unwrap() as usize;
        if j["type"] == "JointModelFreeFlyer" {
            assert_eq!(k, 0, "the free flyer is Pinocchio's first joint");
            for (d, slot) in v_pin.iter_mut().take(6).enumerate() {
                *slot = idx_v + d;
            }
            block_of_pin_joint.push(0);
            continue;
        }
        let name = j["name"].as_str().unwrap();
        let b = model
            .joint_index(name)
            .unwrap_or_else(|| panic!("Pinocchio joint {name} not in twinloop's model"));
        v_pin[model.v_offset + b] = idx_v;
        block_of_pin_joint.push(b + usize::from(model.is_floating()));
    }
    assert!(
        v_pin.iter().all(|&x| x != usize::MAX),
        "every twinloop coordinate maps"
    );
    Maps {
        v_pin,
        block_of_pin_joint,
    }
}

fn our_q(model: &Model, refd: &Value, q_pin: &[f64]) -> Vec<f64> {
    let mut q = vec![0.0; model.nq];
    for j in refd["joints"].as_array().unwrap() {
        let idx_q = j["idx_q"].as_u64().unwrap() as usize;
        if j["type"] == "JointModelFreeFlyer" {
            q[..7].copy_from_slice(&q_pin[idx_q..idx_q + 7]);
            continue;
        }
        let b = model.joint_index(j["name"].as_str().unwrap()).unwrap();
        let nq = j["nq"].as_u64().unwrap();
        q[model.q_offset + b] = if nq == 2 {
            q_pin[idx_q + 1].atan2(q_pin[idx_q])
        } else {
            q_pin[idx_q]
        };
    }
    q
}

fn check_model(name: &str, file: &str) {
    let path = repo()
        .join("crates/twinloop-dynamics/tests/data/pinocchio")
        .join(format!("{name}.json"));
    let refd: Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let robot = twinloop_description::load(repo().join(file)).unwrap_or_else(|e| panic!("{e}"));
    let mut model = Model::from_description(&robot).unwrap();
    // The reference zeroes armature (tools/oracle/README.md); twinloop now reads
    // MJCF's (op3_mjcf: 0.045 on every joint), so compare without it.
    model.armature.fill(0.0);
    assert_eq!(
        model.nv,
        refd["nv"].as_u64().unwrap() as usize,
        "{name}: nv"
    );
    close(
        &format!("{name} total mass"),
        model.total_mass,
        f(&refd["total_mass"]),
    );
    let mp = maps(&model, &refd);
    let nv = model.nv;
    let to_ours = |x_pin: &[f64]| -> Vec<f64> { (0..nv).map(|i| x_pin[mp.v_pin[i]]).collect() };

    // Per-body dynamic parameters: checks the merging of fixed links.
    let ours_params = body_parameters(&model);
    for (k, j) in refd["joints"].as_array().unwrap().iter().enumerate() {
        let b = mp.block_of_pin_joint[k];
        for (p, x) in vecf(&j["dynamic_parameters"]).iter().enumerate() {
            close(
                &format!("{name} params of {} [{p}]", j["name"]),
                ours_params[10 * b + p],
                *x,
            );
        }
    }

    let mut data = Data::new(&model);
    for (si, st) in refd["states"].as_array().unwrap().iter().enumerate() {
        let tag = format!("{name} state {si}");
        let q = our_q(&model, &refd, &vecf(&st["q"]));
        let v = to_ours(&vecf(&st["v"]));
        let a = to_ours(&vecf(&st["a"]));
        let tau = to_ours(&vecf(&st["tau"]));
        let cmp_vec = |what: &str, ours: &DVector<f64>, pin: &Value| {
            let pin = vecf(pin);
            for i in 0..nv {
                close(&format!("{tag} {what}[{i}]"), ours[i], pin[mp.v_pin[i]]);
            }
        };

        // Frame placements.
        frames_forward_kinematics(&model, &mut data, &q);
        let bf = refd["body_frames"].as_array().unwrap();
        for fr in bf {
            if fr["parent_joint_index"].as_u64() == Some(0) {
                continue; // COMAN's world link: on Pinocchio's universe, not on the robot
            }
            let fname = fr["name"].as_str().unwrap();
            let k = model
                .frame_index(fname)
                .unwrap_or_else(|| panic!("{tag}: no frame {fname}"));
            let pl = &st["body_placements"][fname];
            let t = vecf(&pl["translation"]);
            let r = mat(&pl["rotation"]);
            let x = data.o_m_f[k];
            for d in 0..3 {
                close(
                    &format!("{tag} {fname} translation"),
                    x.translation[d],
                    t[d],
                );
                for e in 0..3 {
                    close(
                        &format!("{tag} {fname} rotation"),
                        x.rotation[(d, e)],
                        r[(d, e)],
                    );
                }
            }
        }

        // CoM and its Jacobian.
        let com = center_of_mass(&model, &mut data, &q);
        let pc = vecf(&st["com"]);
        for d in 0..3 {
            close(&format!("{tag} com"), com[d], pc[d]);
        }
        let jc = jacobian_center_of_mass(&model, &mut data, &q).clone();
        let pjc = mat(&st["com_jacobian"]);
        for d in 0..3 {
            for i in 0..nv {
                close(
                    &format!("{tag} com jacobian"),
                    jc[(d, i)],
                    pjc[(d, mp.v_pin[i])],
                );
            }
        }

        // Frame Jacobians in the three reference frames.
        compute_joint_jacobians(&model, &mut data, &q);
        let mut j = DMatrix::zeros(6, nv);
        for fname in refd["jacobian_frames"].as_array().unwrap() {
            let fname = fname.as_str().unwrap();
            let k = model.frame_index(fname).unwrap();
            for (key, rf) in [
                ("LOCAL", ReferenceFrame::Local),
                ("WORLD", ReferenceFrame::World),
                ("LOCAL_WORLD_ALIGNED", ReferenceFrame::LocalWorldAligned),
            ] {
                frame_jacobian(&model, &data, k, rf, &mut j);
                let pj = mat(&st["frame_jacobians"][fname][key]);
                for d in 0..6 {
                    for i in 0..nv {
                        close(
                            &format!("{tag} J {fname} {key}"),
                            j[(d, i)],
                            pj[(d, mp.v_pin[i])],
                        );
                    }
                }
            }
        }

        let r = rnea(&model, &mut data, &q, &v, &a).clone();
        cmp_vec("rnea", &r, &st["rnea"]);
        let r = nonlinear_effects(&model, &mut data, &q, &v).clone();
        cmp_vec("nle", &r, &st["nle"]);
        let r = generalized_gravity(&model, &mut data, &q).clone();
        cmp_vec("gravity", &r, &st["gravity_torque"]);
        let r = aba(&model, &mut data, &q, &v, &tau).clone();
        cmp_vec("aba", &r, &st["aba"]);

        crba(&model, &mut data, &q);
        data.symmetrize_mass_matrix();
        let pm = mat(&st["mass_matrix"]);
        for i in 0..nv {
            for k in 0..nv {
                close(
                    &format!("{tag} M[{i},{k}]"),
                    data.mass_matrix[(i, k)],
                    pm[(mp.v_pin[i], mp.v_pin[k])],
                );
            }
        }

        let y = joint_torque_regressor(&model, &mut data, &q, &v, &a).clone();
        let py = mat(&st["joint_torque_regressor"]);
        for (k, &b) in mp.block_of_pin_joint.iter().enumerate() {
            for p in 0..10 {
                for i in 0..nv {
                    close(
                        &format!("{tag} regressor[{i}, block {b}.{p}]"),
                        y[(i, 10 * b + p)],
                        py[(mp.v_pin[i], 10 * k + p)],
                    );
                }
            }
        }

        // Static regressor: Pinocchio's per-joint block (divided by the total mass) is
        // twinloop's block of the link that starts that body.
        let g = static_com_regressor(&model, &mut data, &q).clone();
        let pg = mat(&st["static_regressor"]);
        for (k, jn) in refd["joints"].as_array().unwrap().iter().enumerate() {
            let link = if jn["type"] == "JointModelFreeFlyer" {
                model.base_link.clone()
            } else {
                model.body_names[model.joint_index(jn["name"].as_str().unwrap()).unwrap()].clone()
            };
            let l = model.links.iter().position(|x| x.name == link).unwrap();
            for d in 0..3 {
                for c in 0..4 {
                    close(
                        &format!("{tag} static regressor {link}"),
                        g[(d, 4 * l + c)] / model.total_mass,
                        pg[(d, 4 * k + c)],
                    );
                }
            }
        }
    }
    check_batched(name, &model, &refd, &mp);
    LARGEST.with(|l| {
        let (rel, what) = &*l.borrow();
        eprintln!("{name}: largest error {rel:.2e} of max(1, |Pinocchio|), at {what}");
    });
}

#[test]
fn op3_urdf() {
    check_model("op3", "models/op3/robotis_op3.nomesh.urdf");
}

#[test]
fn g1_urdf() {
    check_model("g1", "models/unitree_g1/g1_29dof_rev_1_0.nomesh.urdf");
}

#[test]
fn h1_urdf() {
    check_model("h1", "models/unitree_h1/h1.nomesh.urdf");
}

#[test]
fn coman_urdf() {
    check_model("coman", "models/coman/coman.nomesh.urdf");
}

#[test]
fn nao_urdf() {
    check_model("nao", "models/nao/nao_V50.nomesh.urdf");
}

#[test]
fn icub_urdf() {
    check_model("icub", "models/icub/iCubGazeboV2_5.nomesh.urdf");
}

#[test]
fn op3_mjcf() {
    check_model("op3_mjcf", "models/op3/mjcf/op3.xml");
}

#[test]
fn talos_mjcf() {
    check_model("talos_mjcf", "models/talos/mjcf/talos.xml");
}

/// The batched algorithms (`twinloop_dynamics::batch`) on all of the model's states at
/// once, against Pinocchio's numbers (tests/batch.rs: bit for bit the single calls).
fn check_batched(name: &str, model: &Model, refd: &Value, mp: &Maps) {
    let states = refd["states"].as_array().unwrap();
    let (n, nv) = (states.len(), model.nv);
    let to_ours = |x_pin: &[f64]| -> Vec<f64> { (0..nv).map(|i| x_pin[mp.v_pin[i]]).collect() };
    let (mut q, mut v, mut a, mut tau) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for st in states {
        q.extend(our_q(model, refd, &vecf(&st["q"])));
        v.extend(to_ours(&vecf(&st["v"])));
        a.extend(to_ours(&vecf(&st["a"])));
        tau.extend(to_ours(&vecf(&st["tau"])));
    }
    let mut bd = BatchData::new(model);
    let mut out = vec![0.0; n * nv];
    let mut m = vec![0.0; n * nv * nv];
    let mut com = vec![0.0; n * 3];
    rnea_batch(model, &mut bd, &q, &v, &a, &mut out);
    let rnea_out = out.clone();
    try_aba_batch(model, &mut bd, &q, &v, &tau, &mut out).unwrap();
    crba_batch(model, &mut bd, &q, &mut m);
    center_of_mass_batch(model, &mut bd, &q, &mut com);
    for (si, st) in states.iter().enumerate() {
        let tag = format!("{name} batched state {si}");
        let (prnea, paba) = (vecf(&st["rnea"]), vecf(&st["aba"]));
        let pm = mat(&st["mass_matrix"]);
        for i in 0..nv {
            close(
                &format!("{tag} rnea[{i}]"),
                rnea_out[si * nv + i],
                prnea[mp.v_pin[i]],
            );
            close(
                &format!("{tag} aba[{i}]"),
                out[si * nv + i],
                paba[mp.v_pin[i]],
            );
            for k in 0..nv {
                close(
                    &format!("{tag} M[{i},{k}]"),
                    m[(si * nv + i) * nv + k],
                    pm[(mp.v_pin[i], mp.v_pin[k])],
                );
            }
        }
        for (d, c) in vecf(&st["com"]).iter().enumerate() {
            close(&format!("{tag} com"), com[si * 3 + d], *c);
        }
    }
}
