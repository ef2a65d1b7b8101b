//! Composite rigid-body algorithm: the joint-space inertia matrix (Featherstone,
//! RBDA table 6.2), with all bodies in base coordinates so each entry is a dot product.

use crate::data::Data;
use crate::kinematics::{base_frame_pass, base_placement, check_q};
use crate::model::{BASE, JointType, Model};
use nalgebra::DMatrix;
use twinloop_spatial::{LinearInertia, Motion};

/// The mass matrix M(q) (`data.mass_matrix`, upper triangle as Pinocchio fills it;
/// [`Data::symmetrize_mass_matrix`] completes it). For a floating base the first six
/// rows and columns belong to the base velocity in the base frame.
pub fn crba<'a>(model: &Model, data: &'a mut Data, q: &[f64]) -> &'a DMatrix<f64> {
    check_q(model, q);
    data.base_placement = base_placement(model, q);
    base_frame_pass(model, data, q);
    crba_from_kinematics(model, data)
}

/// [`crba`] at the configuration of the last [`kinematics_pass`], whose base-frame
/// placements and subspaces (`data.b_m_i`, `data.s`) it takes as computed: the same
/// operations on the same values, so the same bits.
///
/// [`kinematics_pass`]: crate::kinematics::kinematics_pass
pub fn crba_from_kinematics<'a>(model: &Model, data: &'a mut Data) -> &'a DMatrix<f64> {
    let nb = model.nbodies;
    for i in 0..nb {
        data.ycrb[i] = LinearInertia::from_inertia(&model.inertias[i].transformed(&data.b_m_i[i]));
    }
    let off = model.v_offset;
    let mut base = LinearInertia::from_inertia(&model.base_inertia);
    let (m, nv) = (&mut data.mass_matrix, model.nv);
    let one_dof = !model.has_spherical_joints();
    for i in (0..nb).rev() {
        let yi = data.ycrb[i];
        let p = model.parents[i];
        if p == BASE {
            base.add(&yi);
        } else {
            data.ycrb[p].add(&yi);
        }
        if one_dof {
            // Every joint one column (no spherical joint): body i is column off + i.
            // Kept apart from the general loop below, which costs 20 % more on OP3.
            // The column as a slice: one bounds check a store.
            let col = off + i;
            let mc = &mut m.as_mut_slice()[col * nv..(col + 1) * nv];
            let f = yi.mul_motion(&data.s[i]);
            mc[col] = data.s[i].dot(&f) + model.armature[i];
            let mut j = p;
            while j != BASE {
                mc[off + j] = data.s[j].dot(&f);
                j = model.parents[j];
            }
            if off == 6 {
                f.write_to(&mut mc[0..6]);
            }
            continue;
        }
        let (iv, n) = (model.idx_v[i], model.joint_types[i].nv());
        for k in 0..n {
            let col = iv + k;
            let f = yi.mul_motion(&data.s[col - off]);
            // The joint's own block (the whole block for a spherical joint).
            if n == 1 {
                m[(col, col)] = data.s[col - off].dot(&f) + model.armature[i];
            } else {
                for r in 0..n {
                    m[(iv + r, col)] = data.s[iv + r - off].dot(&f);
                }
                m[(col, col)] += model.armature[i];
            }
            let mut j = p;
            while j != BASE {
                // Unrolled by joint type: a loop over nv here costs 25 % of CRBA.
                let row = model.idx_v[j];
                m[(row, col)] = data.s[row - off].dot(&f);
                if model.joint_types[j] == JointType::Spherical {
                    m[(row + 1, col)] = data.s[row + 1 - off].dot(&f);
                    m[(row + 2, col)] = data.s[row + 2 - off].dot(&f);
                }
                j = model.parents[j];
            }
            if off == 6 {
                base_rows(m, col, &f);
            }
        }
    }
    if off == 6 {
        // The locked robot's inertia seen from the base frame.
        let mut sub = m.fixed_view_mut::<6, 6>(0, 0);
        for k in 0..6 {
            let mut e = Motion::ZERO;
            if k < 3 {
                e.v[k] = 1.0;
            } else {
                e.w[k - 3] = 1.0;
            }
            let f = base.mul_motion(&e);
            sub[(0, k)] = f.f.x;
            sub[(1, k)] = f.f.y;
            sub[(2, k)] = f.f.z;
            sub[(3, k)] = f.n.x;
            sub[(4, k)] = f.n.y;
            sub[(5, k)] = f.n.z;
            // MuJoCo's free-joint armature (see `Model::base_armature`).
            sub[(k, k)] += model.base_armature;
        }
    }
    &data.mass_matrix
}

/// The base rows of column `col`: the base's subspace is the identity in base
/// coordinates, so they are the column's force itself.
#[inline]
fn base_rows(m: &mut DMatrix<f64>, col: usize, f: &twinloop_spatial::Force) {
    m[(0, col)] = f.f.x;
    m[(1, col)] = f.f.y;
    m[(2, col)] = f.f.z;
    m[(3, col)] = f.n.x;
    m[(4, col)] = f.n.y;
    m[(5, col)] = f.n.z;
}
