//! Articulated-body algorithm: forward dynamics in O(n) (Featherstone, RBDA table
//! 7.1), in base coordinates: articulated inertias then add up without transforms.

use crate::data::Data;
use crate::joint::{joint_placement, subspace_in};
use crate::kinematics::{base_placement, check_q, check_v};
use crate::model::{BASE, Model};
use nalgebra::{DVector, Vector3};
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
    let qj = &q[model.q_offset..];
    let vj = &v[model.v_offset..];
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
        (i0.to_symmetric6(), pa0)
    } else {
        (Symmetric6::ZERO, Force::ZERO)
    };
    for i in 0..model.nbodies {
        let li = joint_placement(model, i, qj[i]);
        let p = model.parents[i];
        let (b, vp) = if p == BASE {
            (li, v0)
        } else {
            (data.b_m_i[p] * li, data.v[p])
        };
        data.b_m_i[i] = b;
        let s = subspace_in(model, i, &b);
        data.s[i] = s;
        let sv = s * vj[i];
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
    let tj = &tau[model.v_offset..];
    for i in (0..model.nbodies).rev() {
        let s = data.s[i];
        let ia = data.ia[i];
        let ucol = ia.mul_motion(&s);
        let d_inv = 1.0 / (s.dot(&ucol) + model.armature[i]);
        let u = tj[i] - s.dot(&data.pa[i]);
        data.u_col[i] = ucol;
        data.d_inv[i] = d_inv;
        data.u[i] = u;
        let mut ia_a = ia;
        ia_a.sub_rank1(&ucol, d_inv);
        let pa_a = data.pa[i] + ia_a.mul_motion(&data.c[i]) + ucol * (d_inv * u);
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
        let qdd = data.d_inv[i] * (data.u[i] - ai.dot(&data.u_col[i]));
        data.ddq[off + i] = qdd;
        data.a[i] = ai + data.s[i] * qdd;
    }
}
