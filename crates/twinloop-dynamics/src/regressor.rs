//! Regressors linear in the inertial parameters: the joint-torque regressor
//! `tau = Y(q, v, a) phi` and the static CoM regressor.

use crate::data::Data;
use crate::kinematics::{base_frame_pass, check_q, check_v, forward_kinematics};
use crate::model::{BASE, Model};
use crate::rnea::rnea_impl;
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
    // Body-frame velocities and accelerations (gravity included) from RNEA's forward pass.
    rnea_impl(model, data, q, v, Some(a), true);
    base_frame_pass(model, data, q);
    let floating = model.is_floating();
    let off = model.v_offset;
    let pb = usize::from(floating); // parameter block of body i is i + pb
    let r = &mut data.regressor;
    if floating {
        // The base body's own block: its local force is already in base coordinates.
        let v0 = Motion::from_slice(&v[0..6]);
        let up = data.base_placement.rotation.tr_mul(&(-model.gravity));
        let mut a0 = Motion::from_slice(&a[0..6]);
        a0.v += up;
        let y0 = body_regressor(&v0, &a0);
        r.fixed_view_mut::<6, 10>(0, 0).copy_from(&y0);
    }
    for i in 0..model.nbodies {
        let yl = body_regressor(&data.v[i], &data.a[i]);
        // Each parameter's force column, re-expressed in base coordinates.
        let b = &data.b_m_i[i];
        let mut yb = SMatrix::<f64, 6, 10>::zeros();
        for k in 0..10 {
            let c = yl.column(k);
            let f = b.act_force(&Force::new(
                Vector3::new(c[0], c[1], c[2]),
                Vector3::new(c[3], c[4], c[5]),
            ));
            yb.fixed_view_mut::<3, 1>(0, k).copy_from(&f.f);
            yb.fixed_view_mut::<3, 1>(3, k).copy_from(&f.n);
        }
        let col0 = 10 * (i + pb);
        let mut j = i;
        while j != BASE {
            for k in 0..model.joint_types[j].nv() {
                let row = model.idx_v[j] + k;
                let s = data.s[row - off].to_vector6();
                r.fixed_view_mut::<1, 10>(row, col0)
                    .copy_from(&(s.transpose() * yb));
            }
            j = model.parents[j];
        }
        if floating {
            r.fixed_view_mut::<6, 10>(0, col0).copy_from(&yb);
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
