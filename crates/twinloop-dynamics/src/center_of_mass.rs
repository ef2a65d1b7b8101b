//! Centre of mass, its Jacobian, and the ground-projected CoM.

use crate::data::Data;
use crate::joint::subspace_column;
use crate::kinematics::forward_kinematics;
use crate::model::{BASE, Model};
use nalgebra::{DMatrix, Vector2, Vector3};

/// World position of the whole-body CoM (`data.com`); runs forward kinematics.
pub fn center_of_mass(model: &Model, data: &mut Data, q: &[f64]) -> Vector3<f64> {
    forward_kinematics(model, data, q);
    let mut moment = if model.is_floating() {
        data.base_placement.act_point(&model.base_inertia.com) * model.base_inertia.mass
    } else {
        Vector3::zeros()
    };
    for i in 0..model.nbodies {
        let y = &model.inertias[i];
        moment += data.o_m_i[i].act_point(&y.com) * y.mass;
    }
    data.com = moment / model.total_mass;
    data.com
}

/// The CoM projected on the ground plane (world x, y): where a force plate under a
/// statically standing robot sees the centre of pressure.
pub fn ground_projected_com(model: &Model, data: &mut Data, q: &[f64]) -> Vector2<f64> {
    let c = center_of_mass(model, data, q);
    Vector2::new(c.x, c.y)
}

/// Jacobian of the CoM (3 x nv, world frame; `data.com_jacobian`); also sets `data.com`.
pub fn jacobian_center_of_mass<'a>(
    model: &Model,
    data: &'a mut Data,
    q: &[f64],
) -> &'a DMatrix<f64> {
    forward_kinematics(model, data, q);
    let nb = model.nbodies;
    for i in 0..nb {
        let y = &model.inertias[i];
        data.subtree_mass[i] = y.mass;
        data.subtree_moment[i] = data.o_m_i[i].act_point(&y.com) * y.mass;
    }
    let total = model.total_mass;
    // Leaves to root: subtree sums, and each joint's column from its subtree.
    for i in (0..nb).rev() {
        let (m, h) = (data.subtree_mass[i], data.subtree_moment[i]);
        for k in 0..model.joint_types[i].nv() {
            let s = subspace_column(model, i, k, &data.o_m_i[i]);
            // A unit joint velocity moves the subtree's CoM at v + w x c.
            let col = (s.v * m + s.w.cross(&h)) / total;
            data.com_jacobian
                .fixed_view_mut::<3, 1>(0, model.idx_v[i] + k)
                .copy_from(&col);
        }
        let p = model.parents[i];
        if p != BASE {
            data.subtree_mass[p] += m;
            data.subtree_moment[p] += h;
        }
    }
    let mut moment = if model.is_floating() {
        data.base_placement.act_point(&model.base_inertia.com) * model.base_inertia.mass
    } else {
        Vector3::zeros()
    };
    for i in 0..nb {
        if model.parents[i] == BASE {
            moment += data.subtree_moment[i];
        }
    }
    data.com = moment / total;
    if model.is_floating() {
        // Base twist (base frame): the CoM moves at R (v + w x (c - p)) with c - p from the base origin.
        let r = data.base_placement.rotation;
        let rel = r.tr_mul(&(data.com - data.base_placement.translation));
        data.com_jacobian.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
        data.com_jacobian
            .fixed_view_mut::<3, 3>(0, 3)
            .copy_from(&(-(r * twinloop_spatial::skew(&rel))));
    }
    &data.com_jacobian
}
