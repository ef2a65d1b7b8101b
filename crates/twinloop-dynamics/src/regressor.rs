//! Regressors linear in the inertial parameters: the joint-torque regressor
//! `tau = Y(q, v, a) phi` and the static CoM regressor.

use crate::data::Data;
use crate::joint::{compose, joint_placement, subspace_in, subspace_times};
use crate::kinematics::{base_placement, check_q, check_v, forward_kinematics};
use crate::model::{BASE, Model};
use nalgebra::{DMatrix, SMatrix, Vector3};
use twinloop_spatial::{Force, Inertia, Motion, Se3, skew};

/// 6 x 10 body regressor: the spatial force `I a + v x* I v` of a body as a linear map
/// of its 10 parameters (m, m c, I about the frame origin as Ixx Ixy Iyy Ixz Iyz Izz).
#[inline(always)]
fn body_regressor(v: &Motion, a: &Motion) -> SMatrix<f64, 6, 10> {
    let mut y = SMatrix::<f64, 6, 10>::zeros();
    let w = v.w;
    // Mass: f = m (a_v + w x v).
    let fm = a.v + w.cross(&v.v);
    y.fixed_view_mut::<3, 1>(0, 0).copy_from(&fm);
    // First moment h: f = ([a_w]x + [w]x[w]x) h, n = [v x w - a_v]x h.
    let sw = skew(&w);
    y.fixed_view_mut::<3, 3>(0, 1)
        .copy_from(&(skew(&a.w) + sw * sw));
    y.fixed_view_mut::<3, 3>(3, 1)
        .copy_from(&skew(&(v.v.cross(&w) - a.v)));
    // Rotational inertia: n = L(a_w) + [w]x L(w), with I x = L(x) (Ixx Ixy Iyy Ixz Iyz Izz).
    let l = |x: &Vector3<f64>| {
        SMatrix::<f64, 3, 6>::new(
            x.x, x.y, 0.0, x.z, 0.0, 0.0, //
            0.0, x.x, x.y, 0.0, x.z, 0.0, //
            0.0, 0.0, 0.0, x.x, x.y, x.z,
        )
    };
    y.fixed_view_mut::<3, 6>(3, 4)
        .copy_from(&(l(&a.w) + sw * l(&w)));
    y
}

/// The base's velocity and acceleration (gravity included as an upward acceleration,
/// RNEA's trick) in the base frame; sets `data.base_placement`.
#[inline(always)]
fn base_motion(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    v: &[f64],
    a: &[f64],
) -> (Motion, Motion) {
    let base = base_placement(model, q);
    data.base_placement = base;
    let up = base.rotation.tr_mul(&(-model.gravity));
    if model.is_floating() {
        let mut a0 = Motion::from_slice(&a[0..6]);
        a0.v += up;
        (Motion::from_slice(&v[0..6]), a0)
    } else {
        (Motion::ZERO, Motion::new(up, Vector3::zeros()))
    }
}

/// RNEA's forward pass (body-frame velocities and accelerations, the same sums as
/// `rnea_impl`, so the same bits) and the base-frame pass (`b_m_i`, `s`) in one sweep:
/// each joint's placement and sin/cos computed once, and no forces.
fn forward_pass(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    v: &[f64],
    a: &[f64],
    v0: &Motion,
    a0: &Motion,
) {
    let off = model.v_offset;
    for i in 0..model.nbodies {
        let li = joint_placement(model, i, q);
        data.li_m_i[i] = li;
        let p = model.parents[i];
        let (vp, ap, b) = if p == BASE {
            (*v0, *a0, li)
        } else {
            (data.v[p], data.a[p], compose(model, i, &data.b_m_i[p], &li))
        };
        let iv = model.idx_v[i];
        let vj = subspace_times(model, i, &v[iv..]);
        let aj = subspace_times(model, i, &a[iv..]);
        let mut ai = li.act_inv_motion(&ap) + aj;
        let vi = li.act_inv_motion(&vp) + vj;
        ai += vi.cross(&vj);
        data.v[i] = vi;
        data.a[i] = ai;
        data.b_m_i[i] = b;
        subspace_in(model, i, &b, &mut data.s[iv - off..]);
    }
}

/// The ten columns of a body regressor `y` (body frame) as forces in base coordinates
/// (`b` the body's placement there). The mass's column has no moment and the
/// rotational inertia's six have no force part: their transforms skip those products.
#[inline(always)]
fn base_frame_columns(b: &Se3, y: &SMatrix<f64, 6, 10>) -> [Force; 10] {
    let rot =
        |k: usize, r0: usize| b.rotation * Vector3::new(y[(r0, k)], y[(r0 + 1, k)], y[(r0 + 2, k)]);
    let mut out = [Force::ZERO; 10];
    let f = rot(0, 0);
    out[0] = Force::new(f, b.translation.cross(&f));
    for (k, o) in out.iter_mut().enumerate().take(4).skip(1) {
        let f = rot(k, 0);
        *o = Force::new(f, rot(k, 3) + b.translation.cross(&f));
    }
    for (k, o) in out.iter_mut().enumerate().skip(4) {
        *o = Force::new(Vector3::zeros(), rot(k, 3));
    }
    out
}

/// The joint-torque regressor (`data.regressor`, nv x 10 nb): `rnea(q, v, a) = Y phi`
/// with `phi` stacking [`Inertia::dynamic_parameters`] of each body in its own frame:
/// the floating base first (if any), then the bodies in model order (see
/// [`body_parameters`]). Pinocchio's `computeJointTorqueRegressor` layout.
pub fn joint_torque_regressor<'a>(
    model: &Model,
    data: &'a mut Data,
    q: &[f64],
    v: &[f64],
    a: &[f64],
) -> &'a DMatrix<f64> {
    check_q(model, q);
    check_v(model, v, "v");
    check_v(model, a, "a");
    let floating = model.is_floating();
    let (v0, a0) = base_motion(model, data, q, v, a);
    forward_pass(model, data, q, v, a, &v0, &a0);
    let off = model.v_offset;
    let pb = usize::from(floating); // parameter block of body i is i + pb
    let r = &mut data.regressor;
    if floating {
        // The base body's own block: its local force is already in base coordinates.
        let y0 = body_regressor(&v0, &a0);
        r.fixed_view_mut::<6, 10>(0, 0).copy_from(&y0);
    }
    for i in 0..model.nbodies {
        let yb = base_frame_columns(&data.b_m_i[i], &body_regressor(&data.v[i], &data.a[i]));
        let col0 = 10 * (i + pb);
        let mut j = i;
        while j != BASE {
            for k in 0..model.joint_types[j].nv() {
                let row = model.idx_v[j] + k;
                let s = &data.s[row - off];
                // Columns 1-3 and the mass's have both parts; the rotational
                // inertia's have no force part (s.v . 0 adds nothing).
                for (c, f) in yb.iter().enumerate().take(4) {
                    r[(row, col0 + c)] = s.dot(f);
                }
                for (c, f) in yb.iter().enumerate().skip(4) {
                    r[(row, col0 + c)] = s.w.dot(&f.n);
                }
            }
            j = model.parents[j];
        }
        if floating {
            for (c, f) in yb.iter().enumerate() {
                f.write_to(&mut r.column_mut(col0 + c).as_mut_slice()[0..6]);
            }
        }
    }
    &data.regressor
}

/// The parameter vector the regressor multiplies: each body's 10 dynamic parameters
/// in its own frame, floating base first.
pub fn body_parameters(model: &Model) -> Vec<f64> {
    let mut out = Vec::with_capacity(10 * (model.nbodies + 1));
    if model.is_floating() {
        out.extend(model.base_inertia.dynamic_parameters());
    }
    for y in &model.inertias {
        out.extend(y.dynamic_parameters());
    }
    out
}

/// Parameter block (column offset / 10) of the body a description link belongs to,
/// or `None` if the link is welded to the world (fixed base).
pub fn parameter_block_of_link(model: &Model, link: usize) -> Option<usize> {
    let b = model.links[link].body;
    let pb = usize::from(model.is_floating());
    if b == BASE {
        model.is_floating().then_some(0)
    } else {
        Some(b + pb)
    }
}

/// The 10x10 matrix `T` with `phi_body = T phi_link`: the parameters of an inertia
/// given in a link frame, re-expressed in the body frame where the link sits at
/// `placement`. Linear in `phi_link`, so a per-link regressor is `Y_body T`.
pub fn link_to_body_parameter_map(placement: &Se3) -> SMatrix<f64, 10, 10> {
    let mut t = SMatrix::<f64, 10, 10>::zeros();
    for k in 0..10 {
        let mut e = [0.0; 10];
        e[k] = 1.0;
        // The map is linear in (m, h, I_O) even where an inertia with these
        // parameters is not physical, so transform the linear form directly.
        let col = transform_parameters(&e, placement);
        for (r, x) in col.iter().enumerate() {
            t[(r, k)] = *x;
        }
    }
    t
}

/// Transform linear-form parameters (m, h, I about the origin) by `x = bodyMlink`.
fn transform_parameters(p: &[f64; 10], x: &Se3) -> [f64; 10] {
    let m = p[0];
    let h = Vector3::new(p[1], p[2], p[3]);
    let io = nalgebra::Matrix3::new(p[4], p[5], p[7], p[5], p[6], p[8], p[7], p[8], p[9]);
    let r = x.rotation;
    let t = x.translation;
    let rh = r * h;
    let h2 = rh + t * m;
    // I about the new origin: R I R^T shifted by t: I' = R I R^T - m [t]x[t]x - [t]x[Rh]x - [Rh]x[t]x
    let st = skew(&t);
    let srh = skew(&rh);
    let i2 = r * io * r.transpose() - st * st * m - st * srh - srh * st;
    [
        m,
        h2.x,
        h2.y,
        h2.z,
        i2[(0, 0)],
        i2[(0, 1)],
        i2[(1, 1)],
        i2[(0, 2)],
        i2[(1, 2)],
        i2[(2, 2)],
    ]
}

/// Per description link: its 10 parameters in its own frame (zero for a link without inertial).
pub fn link_parameters(model: &Model) -> Vec<f64> {
    let mut out = Vec::with_capacity(10 * model.links.len());
    for l in &model.links {
        out.extend(l.inertia.dynamic_parameters());
    }
    out
}

/// The static CoM regressor (`data.static_regressor`, 3 x 4 per description link):
/// `M c = G(q) [m_1, m_1 c_1, ..., m_L, m_L c_L]`, where `c_l` is link l's CoM in its
/// own frame. The CoM is linear in each link's mass and first moment (seed 004, eq 8),
/// so static identification is a linear least-squares problem. Columns of each link:
/// its world origin, then its world rotation.
pub fn static_com_regressor<'a>(model: &Model, data: &'a mut Data, q: &[f64]) -> &'a DMatrix<f64> {
    forward_kinematics(model, data, q);
    for (l, info) in model.links.iter().enumerate() {
        let parent = if info.body == BASE {
            data.base_placement
        } else {
            data.o_m_i[info.body]
        };
        let x = parent * info.placement;
        let g = &mut data.static_regressor;
        g.fixed_view_mut::<3, 1>(0, 4 * l).copy_from(&x.translation);
        g.fixed_view_mut::<3, 3>(0, 4 * l + 1)
            .copy_from(&x.rotation);
    }
    &data.static_regressor
}

/// Per description link: mass then first moment `m c` in the link frame, the vector
/// the static CoM regressor multiplies.
pub fn link_static_parameters(model: &Model) -> Vec<f64> {
    let mut out = Vec::with_capacity(4 * model.links.len());
    for l in &model.links {
        let y: &Inertia = &l.inertia;
        let h = y.com * y.mass;
        out.extend([y.mass, h.x, h.y, h.z]);
    }
    out
}
