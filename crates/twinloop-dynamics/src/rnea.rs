//! Recursive Newton-Euler: inverse dynamics (Featherstone, RBDA table 5.1), in body
//! frames as Pinocchio does.

use crate::data::Data;
use crate::joint::{joint_placement, subspace_dot, subspace_times};
use crate::kinematics::{base_placement, check_q, check_v};
use crate::model::{BASE, Model};
use nalgebra::DVector;
use twinloop_spatial::{Force, Motion};

/// Generalised forces `tau = M(q) a + C(q, v) v + g(q)` (`data.tau`). For a floating
/// base, `tau[0..6]` is the wrench on the base in the base frame (force, then torque):
/// zero exactly when the motion needs no external force on the base.
pub fn rnea<'a>(
    model: &Model,
    data: &'a mut Data,
    q: &[f64],
    v: &[f64],
    a: &[f64],
) -> &'a DVector<f64> {
    check_q(model, q);
    check_v(model, v, "v");
    check_v(model, a, "a");
    rnea_impl::<false>(model, data, q, v, Some(a), true);
    &data.tau
}

/// `C(q, v) v + g(q)`: RNEA with zero acceleration.
pub fn nonlinear_effects<'a>(
    model: &Model,
    data: &'a mut Data,
    q: &[f64],
    v: &[f64],
) -> &'a DVector<f64> {
    check_q(model, q);
    check_v(model, v, "v");
    rnea_impl::<false>(model, data, q, v, None, true);
    &data.tau
}

/// [`nonlinear_effects`] at the configuration of the last [`kinematics_pass`]: its
/// joint placements (`data.li_m_i`) and base placement are taken as computed, so a
/// simulator step that needs the kinematics, the mass matrix and the bias forces
/// computes each joint's placement once. The same operations as
/// [`nonlinear_effects`] on the same placements: the same bits.
///
/// [`kinematics_pass`]: crate::kinematics::kinematics_pass
pub fn nonlinear_effects_from_kinematics<'a>(
    model: &Model,
    data: &'a mut Data,
    v: &[f64],
) -> &'a DVector<f64> {
    check_v(model, v, "v");
    rnea_impl::<true>(model, data, &[], v, None, true);
    &data.tau
}

/// `g(q)`: the generalised gravity forces.
pub fn generalized_gravity<'a>(model: &Model, data: &'a mut Data, q: &[f64]) -> &'a DVector<f64> {
    check_q(model, q);
    rnea_impl::<false>(model, data, q, &[], None, false);
    &data.tau
}

/// The passes; `v` is ignored when `with_velocity` is false, `a` when it is `None`.
/// `GIVEN`: the base and joint placements are `data`'s (a kinematics pass's), and `q`
/// is not read.
#[inline(always)]
pub(crate) fn rnea_impl<const GIVEN: bool>(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    v: &[f64],
    a: Option<&[f64]>,
    with_velocity: bool,
) {
    let floating = model.is_floating();
    let base = if GIVEN {
        data.base_placement
    } else {
        let base = base_placement(model, q);
        data.base_placement = base;
        base
    };
    // Gravity enters as an upward acceleration of the base (the usual trick).
    let up = base.rotation.tr_mul(&(-model.gravity));
    let (v0, a0) = if floating {
        let v0 = if with_velocity {
            Motion::from_slice(&v[0..6])
        } else {
            Motion::ZERO
        };
        let mut a0 = a.map_or(Motion::ZERO, |a| Motion::from_slice(&a[0..6]));
        a0.v += up;
        (v0, a0)
    } else {
        (Motion::ZERO, Motion::new(up, nalgebra::Vector3::zeros()))
    };
    let mut f0 = if floating {
        let i0 = &model.base_inertia;
        i0.mul_motion(&a0) + v0.cross_force(&i0.mul_motion(&v0))
    } else {
        Force::ZERO
    };
    if floating {
        f0 += base_armature_force(model, &v0, a.map_or(&[0.0; 6][..], |a| &a[0..6]));
    }
    for i in 0..model.nbodies {
        let li = if GIVEN {
            data.li_m_i[i]
        } else {
            let li = joint_placement(model, i, q);
            data.li_m_i[i] = li;
            li
        };
        let p = model.parents[i];
        let (vp, ap) = if p == BASE {
            (v0, a0)
        } else {
            (data.v[p], data.a[p])
        };
        let iv = model.idx_v[i];
        let aj = a.map_or(Motion::ZERO, |a| subspace_times(model, i, &a[iv..]));
        let mut ai = li.act_inv_motion(&ap) + aj;
        let vi = if with_velocity {
            let vj = subspace_times(model, i, &v[iv..]);
            let vi = li.act_inv_motion(&vp) + vj;
            ai += vi.cross(&vj);
            vi
        } else {
            Motion::ZERO
        };
        data.v[i] = vi;
        data.a[i] = ai;
        let inertia = &model.inertias[i];
        let mut fi = inertia.mul_motion(&ai);
        if with_velocity {
            fi += vi.cross_force(&inertia.mul_motion(&vi));
        }
        data.f[i] = fi;
    }
    for i in (0..model.nbodies).rev() {
        let fi = data.f[i];
        let iv = model.idx_v[i];
        let n = model.joint_types[i].nv();
        let tau = &mut data.tau.as_mut_slice()[iv..iv + n];
        subspace_dot(model, i, &fi, tau);
        if let Some(a) = a {
            tau[0] += model.armature[i] * a[iv];
            if n == 3 {
                tau[1] += model.armature[i] * a[iv + 1];
                tau[2] += model.armature[i] * a[iv + 2];
            }
        }
        let fp = data.li_m_i[i].act_force(&fi);
        let p = model.parents[i];
        if p == BASE {
            f0 += fp;
        } else {
            data.f[p] += fp;
        }
    }
    if floating {
        f0.write_to(&mut data.tau.as_mut_slice()[0..6]);
    }
}

/// The force the floating base's armature (`Model::base_armature`, MuJoCo's free-joint
/// armature) takes at base velocity `v0` and acceleration `a0` (base frame, without
/// gravity): MuJoCo's `armature * qacc` on its free joint, whose linear coordinates are
/// world-frame, is `a (a0.v + w x v)` in the base frame (the derivative of a base-frame
/// velocity misses the frame's turn), and `a a0.w` on the angular ones.
#[inline(always)]
pub(crate) fn base_armature_force(model: &Model, v0: &Motion, a0: &[f64]) -> Force {
    let k = model.base_armature;
    if k == 0.0 {
        return Force::ZERO;
    }
    let a0 = Motion::from_slice(a0);
    Force::new((a0.v + v0.w.cross(&v0.v)) * k, a0.w * k)
}
