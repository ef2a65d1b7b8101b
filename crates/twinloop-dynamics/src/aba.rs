//! Articulated-body algorithm: forward dynamics in O(n) (Featherstone, RBDA table
//! 7.1), in base coordinates: articulated inertias then add up without transforms.

use crate::data::Data;
use crate::joint::{compose, joint_placement, subspace_column, subspace_in};
use crate::kinematics::{base_placement, check_q, check_v};
use crate::model::JointType;
use crate::model::{BASE, Model};
use nalgebra::{DVector, Matrix3, Vector3};
use twinloop_spatial::{Force, Motion, Symmetric6};

/// Accelerations `ddq = M^-1 (tau - C v - g)` (`data.ddq`). For a floating base,
/// `tau[0..6]` is an external wrench on the base (base frame); zero for a free robot.
pub fn aba<'a>(
    model: &Model,
    data: &'a mut Data,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
) -> &'a DVector<f64> {
    aba_impl(model, data, q, v, tau, None)
}

/// ABA with external spatial forces on the bodies: `fext[i]` acts on body `i`, given in
/// the world frame at the world origin (a force `f` at world point `p` is `(f, p x f)`).
/// `fext_base` acts on the floating base (ignored for a fixed base).
pub fn aba_with_forces<'a>(
    model: &Model,
    data: &'a mut Data,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
    fext: &[Force],
    fext_base: Force,
) -> &'a DVector<f64> {
    assert_eq!(fext.len(), model.nbodies, "fext needs one force per body");
    aba_impl(model, data, q, v, tau, Some((fext, fext_base)))
}

fn aba_impl<'a>(
    model: &Model,
    data: &'a mut Data,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
    fext: Option<(&[Force], Force)>,
) -> &'a DVector<f64> {
    check_q(model, q);
    check_v(model, v, "v");
    check_v(model, tau, "tau");
    let base = base_placement(model, q);
    data.base_placement = base;
    // Pass 1: placements, velocities, bias terms, body inertias (all in base coordinates).
    let (mut ia0, mut pa0) = velocity_pass(model, data, q, v, fext);
    // Pass 2: articulated inertias and bias forces, leaves to root.
    articulated_pass(model, data, tau, &mut ia0, &mut pa0);
    // Pass 3: accelerations, root to leaves. Gravity is an upward base acceleration.
    acceleration_pass(model, data, tau, &ia0, &pa0);
    &data.ddq
}

/// ABA's first pass, root to leaves, at `data.base_placement`: body placements,
/// subspaces, velocities, velocity-product accelerations, rigid inertias and bias
/// forces (external forces subtracted). Returns the floating base's own inertia and
/// bias force (zero for a fixed base).
#[inline(always)]
fn velocity_pass(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    v: &[f64],
    fext: Option<(&[Force], Force)>,
) -> (Symmetric6, Force) {
    let floating = model.is_floating();
    let base = data.base_placement;
    let v0 = if floating {
        Motion::from_slice(&v[0..6])
    } else {
        Motion::ZERO
    };
    let (ia0, pa0) = if floating {
        let i0 = &model.base_inertia;
        let mut pa0 = v0.cross_force(&i0.mul_motion(&v0));
        if let Some((_, fb)) = fext {
            pa0 -= base.act_inv_force(&fb);
        }
        let mut ia0 = i0.to_symmetric6();
        // The base armature's `a (qdd0 + w x v)` with `qdd0 = a0 - up` (the third pass
        // solves for `a0`, gravity in it as an upward acceleration, which the armature
        // does not feel): `a` on the diagonal, `a (w x v - up)` in the bias.
        let k = model.base_armature;
        if k != 0.0 {
            ia0.a += Matrix3::identity() * k;
            ia0.c += Matrix3::identity() * k;
            let up = base.rotation.tr_mul(&(-model.gravity));
            pa0.f += (v0.w.cross(&v0.v) - up) * k;
        }
        (ia0, pa0)
    } else {
        (Symmetric6::ZERO, Force::ZERO)
    };
    let one_dof = !model.has_spherical_joints();
    for i in 0..model.nbodies {
        let li = joint_placement(model, i, q);
        let p = model.parents[i];
        let (b, vp) = if p == BASE {
            (li, v0)
        } else {
            (compose(model, i, &data.b_m_i[p], &li), data.v[p])
        };
        data.b_m_i[i] = b;
        let sv = if one_dof {
            // Body i owns coordinate i alone: no index lookups, no loop.
            let s = subspace_column(model, i, 0, &b);
            data.s[i] = s;
            s * v[model.v_offset + i]
        } else {
            let (iv, n) = (model.idx_v[i], model.joint_types[i].nv());
            let d = iv - model.v_offset;
            subspace_in(model, i, &b, &mut data.s[d..]);
            let mut sv = Motion::ZERO;
            for k in 0..n {
                sv += data.s[d + k] * v[iv + k];
            }
            sv
        };
        let vi = vp + sv;
        data.v[i] = vi;
        data.c[i] = vi.cross(&sv);
        let yb = model.inertias[i].transformed(&b);
        data.ia[i] = yb.to_symmetric6();
        data.pa[i] = vi.cross_force(&yb.mul_motion(&vi));
        if let Some((f, _)) = fext {
            // World forces into base coordinates, where this ABA works.
            data.pa[i] -= base.act_inv_force(&f[i]);
        }
    }
    (ia0, pa0)
}

/// ABA's second pass, leaves to root: each body's articulated inertia and bias force
/// folded into its parent's (the base's into `ia0`, `pa0`), keeping `U`, `D^-1` and
/// `u` for the third pass.
#[inline(always)]
fn articulated_pass(
    model: &Model,
    data: &mut Data,
    tau: &[f64],
    ia0: &mut Symmetric6,
    pa0: &mut Force,
) {
    for i in (0..model.nbodies).rev() {
        let (ia_a, pa_a) = if model.joint_types[i] == JointType::Spherical {
            articulate_spherical(model, data, i, tau)
        } else {
            let d = model.idx_v[i] - model.v_offset;
            let s = data.s[d];
            let ia = data.ia[i];
            let ucol = ia.mul_motion(&s);
            let d_inv = 1.0 / (s.dot(&ucol) + model.armature[i]);
            let u = tau[model.idx_v[i]] - s.dot(&data.pa[i]);
            data.u_col[d] = ucol;
            data.d_inv[d] = d_inv;
            data.u[d] = u;
            let mut ia_a = ia;
            ia_a.sub_rank1(&ucol, d_inv);
            let pa_a = data.pa[i] + ia_a.mul_motion(&data.c[i]) + ucol * (d_inv * u);
            (ia_a, pa_a)
        };
        let p = model.parents[i];
        if p == BASE {
            *ia0 += ia_a;
            *pa0 += pa_a;
        } else {
            data.ia[p] += ia_a;
            data.pa[p] += pa_a;
        }
    }
}

/// A spherical joint's step of the second pass (RBDA table 7.1 with a 6 x 3 `S`):
/// `U = IA S`, `D = S^T U` (+ armature), `u = tau - S^T pA`; returns the articulated
/// inertia `IA - U D^-1 U^T` and bias `pA + IA^a c + U D^-1 u` its parent receives.
/// `U D^-1 U^T` is subtracted as three rank-1 terms through the Cholesky factor of D.
#[inline(always)]
fn articulate_spherical(
    model: &Model,
    data: &mut Data,
    i: usize,
    tau: &[f64],
) -> (Symmetric6, Force) {
    let iv = model.idx_v[i];
    let d = iv - model.v_offset;
    let ia = data.ia[i];
    let mut dm = Matrix3::identity() * model.armature[i];
    for k in 0..3 {
        data.u_col[d + k] = ia.mul_motion(&data.s[d + k]);
        data.u[d + k] = tau[iv + k] - data.s[d + k].dot(&data.pa[i]);
    }
    for r in 0..3 {
        for c in 0..3 {
            dm[(r, c)] += data.s[d + r].dot(&data.u_col[d + c]);
        }
    }
    let mut ia_a = ia;
    let (l_inv, d_inv) = match dm.cholesky() {
        Some(ch) => {
            let l_inv = ch
                .l()
                .try_inverse()
                .unwrap_or_else(|| Matrix3::repeat(f64::NAN));
            (l_inv, l_inv.tr_mul(&l_inv))
        }
        // A massless subtree: report NaN like a 1-DoF joint's 1/0 would.
        None => (Matrix3::repeat(f64::NAN), Matrix3::repeat(f64::NAN)),
    };
    for j in 0..3 {
        let mut w = Force::ZERO;
        for a in 0..3 {
            w += data.u_col[d + a] * l_inv[(j, a)];
        }
        ia_a.sub_rank1(&w, 1.0);
    }
    data.d_inv_ball[i] = d_inv;
    let mut pa_a = data.pa[i] + ia_a.mul_motion(&data.c[i]);
    for a in 0..3 {
        let coef: f64 = (0..3).map(|b| d_inv[(a, b)] * data.u[d + b]).sum();
        pa_a += data.u_col[d + a] * coef;
    }
    (ia_a, pa_a)
}

/// ABA's third pass, root to leaves: the base acceleration (solving the locked
/// system for a floating base), then each joint's, into `data.ddq`.
#[inline(always)]
fn acceleration_pass(model: &Model, data: &mut Data, tau: &[f64], ia0: &Symmetric6, pa0: &Force) {
    let floating = model.is_floating();
    let base = data.base_placement;
    let off = model.v_offset;
    let up = Motion::new(base.rotation.tr_mul(&(-model.gravity)), Vector3::zeros());
    let a0 = if floating {
        // The base: ia0 a0 + pa0 = applied base wrench.
        let rhs = Force::from_slice(&tau[0..6]) - *pa0;
        let a0 = match ia0.to_matrix6().cholesky() {
            Some(ch) => Motion::from_vector6(&ch.solve(&rhs.to_vector6())),
            // Singular only for a massless robot; report NaN rather than panic.
            None => Motion::new(Vector3::repeat(f64::NAN), Vector3::repeat(f64::NAN)),
        };
        let qdd0 = a0 - up;
        let d = data.ddq.as_mut_slice();
        d[0..3].copy_from_slice(qdd0.v.as_slice());
        d[3..6].copy_from_slice(qdd0.w.as_slice());
        a0
    } else {
        up
    };
    for i in 0..model.nbodies {
        let p = model.parents[i];
        let ap = if p == BASE { a0 } else { data.a[p] };
        let ai = ap + data.c[i];
        let (iv, d) = (model.idx_v[i], model.idx_v[i] - off);
        if model.joint_types[i] == JointType::Spherical {
            let r = Vector3::from_fn(|k, _| data.u[d + k] - ai.dot(&data.u_col[d + k]));
            let qdd = data.d_inv_ball[i] * r;
            data.ddq.as_mut_slice()[iv..iv + 3].copy_from_slice(qdd.as_slice());
            data.a[i] = ai + data.s[d] * qdd.x + data.s[d + 1] * qdd.y + data.s[d + 2] * qdd.z;
        } else {
            let qdd = data.d_inv[d] * (data.u[d] - ai.dot(&data.u_col[d]));
            data.ddq[iv] = qdd;
            data.a[i] = ai + data.s[d] * qdd;
        }
    }
}
