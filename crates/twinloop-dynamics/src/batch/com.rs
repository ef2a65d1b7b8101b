//! Batched centre of mass: `crate::center_of_mass` on lanes.

use super::joint::{base_placement, compose, joint_placement};
use super::lanes::{LANES, V3, W};
use super::{BatchData, dispatch, gather, rows, scatter, uses_lanes};
use crate::model::{BASE, Model};

/// [`crate::center_of_mass`] at N configurations `qs` (N x nq, row-major): writes
/// N world CoM positions (x, y, z) to `out` (N x 3).
pub fn center_of_mass_batch(model: &Model, bd: &mut BatchData, qs: &[f64], out: &mut [f64]) {
    let n = rows("qs", qs, model.nq);
    assert_eq!(
        out.len(),
        n * 3,
        "out has {} entries, {n} rows of 3 expected",
        out.len()
    );
    if !uses_lanes(model) {
        for r in 0..n {
            let c = crate::center_of_mass(model, &mut bd.single, &qs[r * model.nq..][..model.nq]);
            out[3 * r..3 * r + 3].copy_from_slice(c.as_slice());
        }
        return;
    }
    dispatch!(com_groups, com_groups_avx2, model, bd, qs, out)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn com_groups_avx2(model: &Model, bd: &mut BatchData, qs: &[f64], out: &mut [f64]) {
    com_groups(model, bd, qs, out)
}

#[inline(always)]
fn com_groups(model: &Model, bd: &mut BatchData, qs: &[f64], out: &mut [f64]) {
    let n = qs.len() / model.nq;
    for row0 in (0..n).step_by(LANES) {
        let count = LANES.min(n - row0);
        gather(qs, model.nq, row0, count, &mut bd.q);
        let c = com_lanes(model, bd);
        scatter(&[c.x, c.y, c.z], 3, row0, count, out);
    }
}

/// Forward kinematics (world placements in `bd.x`) and the mass-weighted sum.
#[inline(always)]
fn com_lanes(model: &Model, bd: &mut BatchData) -> V3 {
    let base = base_placement(model, &bd.q);
    let mut moment = if model.is_floating() {
        let y = &model.base_inertia;
        base.act_point(&V3::splat(&y.com)).scale(W::splat(y.mass))
    } else {
        V3::ZERO
    };
    for i in 0..model.nbodies {
        let li = joint_placement(model, i, &bd.q);
        let p = model.parents[i];
        let parent = if p == BASE { &base } else { &bd.x[p] };
        let o = compose(model, i, parent, &li);
        bd.x[i] = o;
        let y = &model.inertias[i];
        moment += o.act_point(&V3::splat(&y.com)).scale(W::splat(y.mass));
    }
    let total = W::splat(model.total_mass);
    V3::new(moment.x / total, moment.y / total, moment.z / total)
}
