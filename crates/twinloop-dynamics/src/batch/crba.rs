//! Batched CRBA: `crate::crba` (1-DoF joints) on lanes; each instance's matrix is
//! written whole (both triangles).

use super::joint::{compose, joint_placement, subspace_column};
use super::lanes::{Fo, In, LANES, Li, Mo, W};
use super::{BatchData, dispatch, gather, rows, uses_lanes};
use crate::model::{BASE, Model};
use twinloop_spatial::LinearInertia;

/// [`crate::crba`] at N configurations `qs` (N x nq, row-major): writes N mass
/// matrices of nv x nv to `out`, each complete (symmetric, so row- and column-major
/// alike), with the single call's numbers in its upper triangle and their mirror.
pub fn crba_batch(model: &Model, bd: &mut BatchData, qs: &[f64], out: &mut [f64]) {
    let n = rows("qs", qs, model.nq);
    let nn = model.nv * model.nv;
    assert_eq!(
        out.len(),
        n * nn,
        "out has {} entries, {n} matrices of {nn} expected",
        out.len()
    );
    if !uses_lanes(model) {
        for r in 0..n {
            crate::crba(model, &mut bd.single, &qs[r * model.nq..][..model.nq]);
            bd.single.symmetrize_mass_matrix();
            // Symmetric: column-major storage is the row-major matrix.
            out[r * nn..(r + 1) * nn].copy_from_slice(bd.single.mass_matrix.as_slice());
        }
        return;
    }
    dispatch!(crba_groups, crba_groups_avx2, model, bd, qs, out)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn crba_groups_avx2(model: &Model, bd: &mut BatchData, qs: &[f64], out: &mut [f64]) {
    crba_groups(model, bd, qs, out)
}

#[inline(always)]
fn crba_groups(model: &Model, bd: &mut BatchData, qs: &[f64], out: &mut [f64]) {
    let n = qs.len() / model.nq;
    let nv = model.nv;
    for row0 in (0..n).step_by(LANES) {
        let count = LANES.min(n - row0);
        gather(qs, model.nq, row0, count, &mut bd.q);
        let m = &mut out[row0 * nv * nv..(row0 + count) * nv * nv];
        // Entries off every ancestor chain stay zero, as in the single call's matrix;
        // zeroed group by group, so the entries are in cache when written.
        m.fill(0.0);
        crba_lanes(model, bd, m, count);
    }
}

/// Entry (r, c) of every lane's matrix and its mirror.
#[inline(always)]
fn put(m: &mut [f64], nv: usize, count: usize, r: usize, c: usize, x: W) {
    for l in 0..count {
        let ml = &mut m[l * nv * nv..(l + 1) * nv * nv];
        ml[r * nv + c] = x.0[l];
        ml[c * nv + r] = x.0[l];
    }
}

/// The base rows of column `col` (`crba::base_rows`).
#[inline(always)]
fn base_rows(m: &mut [f64], nv: usize, count: usize, col: usize, f: &Fo) {
    for (r, x) in f.lanes().into_iter().enumerate() {
        put(m, nv, count, r, col, x);
    }
}

#[inline(always)]
fn crba_lanes(model: &Model, bd: &mut BatchData, m: &mut [f64], count: usize) {
    let nb = model.nbodies;
    let nv = model.nv;
    // `kinematics::base_frame_pass`, one-DoF branch.
    for i in 0..nb {
        let li = joint_placement(model, i, &bd.q);
        let p = model.parents[i];
        let b = if p == BASE {
            li
        } else {
            compose(model, i, &bd.x[p], &li)
        };
        bd.x[i] = b;
        bd.s[i] = subspace_column(model, i, &b);
        bd.ycrb[i] = Li::from_inertia(&In::splat(&model.inertias[i]).transformed(&b));
    }
    let off = model.v_offset;
    let mut base = Li::splat(&LinearInertia::from_inertia(&model.base_inertia));
    for i in (0..nb).rev() {
        let yi = bd.ycrb[i];
        let p = model.parents[i];
        if p == BASE {
            base.add(&yi);
        } else {
            bd.ycrb[p].add(&yi);
        }
        let col = off + i;
        let f = yi.mul_motion(&bd.s[i]);
        put(
            m,
            nv,
            count,
            col,
            col,
            bd.s[i].dot(&f) + W::splat(model.armature[i]),
        );
        let mut j = p;
        while j != BASE {
            put(m, nv, count, off + j, col, bd.s[j].dot(&f));
            j = model.parents[j];
        }
        if off == 6 {
            base_rows(m, nv, count, col, &f);
        }
    }
    if off == 6 {
        for k in 0..6 {
            let mut e = [W::ZERO; 6];
            e[k] = W::splat(1.0);
            let f = base.mul_motion(&Mo::from_lanes(&e));
            base_rows(m, nv, count, k, &f);
        }
    }
}
