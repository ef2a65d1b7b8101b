//! Forward kinematics: body and frame placements, joint and frame Jacobians.

use crate::data::Data;
use crate::joint::{compose, joint_placement, subspace_column, subspace_in};
use crate::model::{BASE, Model};
use nalgebra::{DMatrix, Vector3};
use twinloop_spatial::{Motion, Se3, quaternion_xyzw_to_matrix};

/// World placement of the base from q (identity for a fixed base).
#[inline(always)]
pub(crate) fn base_placement(model: &Model, q: &[f64]) -> Se3 {
    if model.is_floating() {
        Se3::new(
            quaternion_xyzw_to_matrix(q[3], q[4], q[5], q[6]),
            Vector3::new(q[0], q[1], q[2]),
        )
    } else {
        Se3::IDENTITY
    }
}

#[inline(always)]
pub(crate) fn check_q(model: &Model, q: &[f64]) {
    assert_eq!(
        q.len(),
        model.nq,
        "q has {} entries, the model needs nq = {}",
        q.len(),
        model.nq
    );
}

#[inline(always)]
pub(crate) fn check_v(model: &Model, v: &[f64], what: &str) {
    assert_eq!(
        v.len(),
        model.nv,
        "{what} has {} entries, the model needs nv = {}",
        v.len(),
        model.nv
    );
}

/// World placement of every body (`data.o_m_i`) and joint placements (`data.li_m_i`).
pub fn forward_kinematics(model: &Model, data: &mut Data, q: &[f64]) {
    check_q(model, q);
    let base = base_placement(model, q);
    data.base_placement = base;
    for i in 0..model.nbodies {
        let li = joint_placement(model, i, q);
        data.li_m_i[i] = li;
        let p = model.parents[i];
        let parent = if p == BASE { &base } else { &data.o_m_i[p] };
        data.o_m_i[i] = compose(model, i, parent, &li);
    }
}

/// Placements in base coordinates (`data.b_m_i`) and joint subspaces there (`data.s`):
/// CRBA's first pass. Working in the base frame
/// rather than the world saves transforming the free-flyer's quantities.
#[inline]
pub(crate) fn base_frame_pass(model: &Model, data: &mut Data, q: &[f64]) {
    if !model.has_spherical_joints() {
        // One coordinate per joint: body i's subspace is column i (no index
        // lookups, no slice per body; this pass is a third of CRBA on OP3).
        // `li_m_i` is not stored: CRBA, the pass's one caller, does not read it.
        for i in 0..model.nbodies {
            let li = joint_placement(model, i, q);
            let p = model.parents[i];
            let b = if p == BASE {
                li
            } else {
                compose(model, i, &data.b_m_i[p], &li)
            };
            data.b_m_i[i] = b;
            data.s[i] = subspace_column(model, i, 0, &b);
        }
        return;
    }
    for i in 0..model.nbodies {
        let li = joint_placement(model, i, q);
        data.li_m_i[i] = li;
        let p = model.parents[i];
        let b = if p == BASE {
            li
        } else {
            compose(model, i, &data.b_m_i[p], &li)
        };
        data.b_m_i[i] = b;
        let d = model.idx_v[i] - model.v_offset;
        subspace_in(model, i, &b, &mut data.s[d..]);
    }
}

/// Every placement a simulator step reads, from one joint placement per body: the joint
/// placements (`data.li_m_i`), the world placements (`data.o_m_i`, as
/// [`forward_kinematics`]), the world joint Jacobians (`data.joint_jacobians`, as
/// [`compute_joint_jacobians`]), and CRBA's base-frame placements and subspaces
/// (`data.b_m_i`, `data.s`). Each is formed by the same operations as in the pass that
/// computes it alone, so the same bits; [`crate::crba::crba_from_kinematics`] and
/// [`crate::rnea::nonlinear_effects_from_kinematics`] then take them as given (the step
/// computed the kinematics three times before: 7 k of OP3's 82 k instructions a step).
pub fn kinematics_pass(model: &Model, data: &mut Data, q: &[f64]) {
    check_q(model, q);
    let base = base_placement(model, q);
    data.base_placement = base;
    let off = model.v_offset;
    for i in 0..model.nbodies {
        let li = joint_placement(model, i, q);
        data.li_m_i[i] = li;
        let p = model.parents[i];
        let (o, b) = if p == BASE {
            (compose(model, i, &base, &li), li)
        } else {
            (
                compose(model, i, &data.o_m_i[p], &li),
                compose(model, i, &data.b_m_i[p], &li),
            )
        };
        data.o_m_i[i] = o;
        data.b_m_i[i] = b;
        let iv = model.idx_v[i];
        subspace_in(model, i, &b, &mut data.s[iv - off..]);
        for k in 0..model.joint_types[i].nv() {
            write_motion(
                &mut data.joint_jacobians,
                iv + k,
                &subspace_column(model, i, k, &o),
            );
        }
    }
    if model.is_floating() {
        write_base_columns(&base, &mut data.joint_jacobians);
    }
}

/// World placement of every frame (`data.o_m_f`); call after [`forward_kinematics`].
pub fn update_frame_placements(model: &Model, data: &mut Data) {
    for (k, f) in model.frames.iter().enumerate() {
        let parent = if f.body == BASE {
            data.base_placement
        } else {
            data.o_m_i[f.body]
        };
        data.o_m_f[k] = parent * f.placement;
    }
}

/// Forward kinematics and every frame's placement.
pub fn frames_forward_kinematics(model: &Model, data: &mut Data, q: &[f64]) {
    forward_kinematics(model, data, q);
    update_frame_placements(model, data);
}

/// World-frame Jacobians of all joints (`data.joint_jacobians`, 6 x nv): column k is
/// the spatial velocity (at the world origin, world axes) that a unit velocity of
/// coordinate k gives its body. Also runs forward kinematics.
pub fn compute_joint_jacobians(model: &Model, data: &mut Data, q: &[f64]) {
    forward_kinematics(model, data, q);
    let j = &mut data.joint_jacobians;
    if model.is_floating() {
        write_base_columns(&data.base_placement, j);
    }
    if !model.has_spherical_joints() {
        // One column per body (as in `base_frame_pass`): no index lookups.
        let off = model.v_offset;
        for (i, o) in data.o_m_i.iter().enumerate() {
            write_motion(j, off + i, &subspace_column(model, i, 0, o));
        }
        return;
    }
    for i in 0..model.nbodies {
        for k in 0..model.joint_types[i].nv() {
            let s = subspace_column(model, i, k, &data.o_m_i[i]);
            write_motion(j, model.idx_v[i] + k, &s);
        }
    }
}

#[inline(always)]
fn write_motion(j: &mut DMatrix<f64>, col: usize, m: &Motion) {
    // One bounds check for the six entries (a column view checks each).
    let c: &mut [f64; 6] = (&mut j.as_mut_slice()[6 * col..6 * col + 6])
        .try_into()
        .unwrap();
    *c = [m.v.x, m.v.y, m.v.z, m.w.x, m.w.y, m.w.z];
}

/// The free flyer's six world-frame columns: the base frame's unit twists mapped to
/// the world, `(R e_k, 0)` for a linear one and `(t x R e_k, R e_k)` for an angular one
/// (`act_motion` of a unit twist, whose other products are zeros).
fn write_base_columns(base: &Se3, j: &mut DMatrix<f64>) {
    for k in 0..3 {
        let w: Vector3<f64> = base.rotation.column(k).into();
        write_motion(j, k, &Motion::new(w, Vector3::zeros()));
        write_motion(j, k + 3, &Motion::new(base.translation.cross(&w), w));
    }
}

/// In which frame a Jacobian's twists are expressed (Pinocchio's `ReferenceFrame`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ReferenceFrame {
    /// The frame's own axes, velocity of its origin.
    Local,
    /// World axes, velocity of the point at the world origin (spatial velocity).
    World,
    /// World axes, velocity of the frame's origin.
    LocalWorldAligned,
}

/// Jacobian (6 x nv, linear rows first) of frame `frame`, written into `out`.
/// Requires [`compute_joint_jacobians`] (or [`forward_kinematics`] and the same q) first:
/// it reads `data.o_m_i` and `data.joint_jacobians`.
pub fn frame_jacobian(
    model: &Model,
    data: &Data,
    frame: usize,
    reference: ReferenceFrame,
    out: &mut DMatrix<f64>,
) {
    assert_eq!(
        out.shape(),
        (6, model.nv),
        "frame_jacobian: out must be 6 x nv"
    );
    out.fill(0.0);
    let f = &model.frames[frame];
    let o_m_f = if f.body == BASE {
        data.base_placement
    } else {
        data.o_m_i[f.body]
    } * f.placement;
    let mut put = |col: usize| {
        let m = Motion::from_slice(data.joint_jacobians.column(col).as_slice());
        let m = match reference {
            ReferenceFrame::World => m,
            ReferenceFrame::Local => o_m_f.act_inv_motion(&m),
            ReferenceFrame::LocalWorldAligned => {
                Motion::new(m.v + m.w.cross(&o_m_f.translation), m.w)
            }
        };
        write_motion(out, col, &m);
    };
    if model.is_floating() {
        for k in 0..6 {
            put(k);
        }
    }
    if f.body != BASE {
        for b in model.ancestors(f.body) {
            for k in 0..model.joint_types[b].nv() {
                put(model.idx_v[b] + k);
            }
        }
    }
}
