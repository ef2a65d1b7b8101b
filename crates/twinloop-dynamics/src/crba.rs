//! Composite rigid-body algorithm: the joint-space inertia matrix (Featherstone,
//! RBDA table 6.2), with all bodies in base coordinates so each entry is a dot product.

use crate::data::Data;
use crate::kinematics::{base_frame_pass, base_placement, check_q, check_v};
use crate::model::{BASE, JointType, Model};
use crate::rnea::base_armature_force;
use nalgebra::{DMatrix, DVector};
use twinloop_spatial::{Force, LinearInertia, Motion};

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
    body_inertias_in_base(model, data);
    composite_pass(model, data);
    &data.mass_matrix
}

/// [`crba_from_kinematics`] and the bias forces `C(q, v) v + g(q)` (`data.tau`, as
/// [`crate::nonlinear_effects`] lays them out) in one sweep: RNEA in base coordinates
/// on CRBA's body inertias there (`data.s` the subspaces, velocities and
/// accelerations summed down the tree as Featherstone's world-frame form, RBDA 5.3,
/// with the base frame as the reference: every quantity is the body-frame one mapped
/// by the joint-angle-only transform to the base, under which the cross products are
/// equivariant). No placement products in the passes and no inertia transformed
/// twice; the sums differ from the body-frame RNEA's, so the bias forces agree with
/// [`crate::nonlinear_effects`] to rounding (`tests/identities.rs`), not to the bit.
pub fn crba_and_bias_from_kinematics<'a>(
    model: &Model,
    data: &'a mut Data,
    v: &[f64],
) -> (&'a DMatrix<f64>, &'a DVector<f64>) {
    check_v(model, v, "v");
    body_inertias_in_base(model, data);
    let f0 = bias_forward(model, data, v);
    composite_pass(model, data);
    bias_backward(model, data, f0);
    (&data.mass_matrix, &data.tau)
}

/// Each body's inertia in base coordinates (`data.ycrb`, before the composite sums).
#[inline(always)]
fn body_inertias_in_base(model: &Model, data: &mut Data) {
    for i in 0..model.nbodies {
        data.ycrb[i] = LinearInertia::from_inertia(&model.inertias[i].transformed(&data.b_m_i[i]));
    }
}

/// RNEA's forward pass in base coordinates at zero joint acceleration (gravity as the
/// base's upward acceleration): `data.v`, `data.a`, `data.f` per body; returns the
/// base's own force.
fn bias_forward(model: &Model, data: &mut Data, v: &[f64]) -> Force {
    let up = data.base_placement.rotation.tr_mul(&(-model.gravity));
    let mut a0 = Motion::ZERO;
    a0.v += up;
    let (v0, f0) = if model.is_floating() {
        let v0 = Motion::from_slice(&v[0..6]);
        let i0 = &model.base_inertia;
        let f0 = i0.mul_motion(&a0)
            + v0.cross_force(&i0.mul_motion(&v0))
            + base_armature_force(model, &v0, &[0.0; 6]);
        (v0, f0)
    } else {
        (Motion::ZERO, Force::ZERO)
    };
    let off = model.v_offset;
    for i in 0..model.nbodies {
        let p = model.parents[i];
        let (vp, ap) = if p == BASE {
            (v0, a0)
        } else {
            (data.v[p], data.a[p])
        };
        let (iv, d) = (model.idx_v[i], model.idx_v[i] - off);
        let s = data.s[d];
        let mut vj = Motion::new(s.v * v[iv], s.w * v[iv]);
        for k in 1..model.joint_types[i].nv() {
            let s = data.s[d + k];
            vj += Motion::new(s.v * v[iv + k], s.w * v[iv + k]);
        }
        let vi = vp + vj;
        let ai = ap + vi.cross(&vj);
        let y = &data.ycrb[i];
        data.f[i] = y.mul_motion(&ai) + vi.cross_force(&y.mul_motion(&vi));
        data.v[i] = vi;
        data.a[i] = ai;
    }
    f0
}

/// RNEA's backward pass in base coordinates: subtree forces summed without transforms,
/// `tau = S^T f`, the base's wrench (base frame) in `tau[0..6]`.
fn bias_backward(model: &Model, data: &mut Data, mut f0: Force) {
    let off = model.v_offset;
    for i in (0..model.nbodies).rev() {
        let fi = data.f[i];
        let (iv, d) = (model.idx_v[i], model.idx_v[i] - off);
        for k in 0..model.joint_types[i].nv() {
            data.tau[iv + k] = data.s[d + k].dot(&fi);
        }
        let p = model.parents[i];
        if p == BASE {
            f0 += fi;
        } else {
            data.f[p] += fi;
        }
    }
    if model.is_floating() {
        f0.write_to(&mut data.tau.as_mut_slice()[0..6]);
    }
}

/// CRBA's composite sums over the body inertias in base coordinates and the matrix's
/// columns.
fn composite_pass(model: &Model, data: &mut Data) {
    let nb = model.nbodies;
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
