//! Batched CRBA: `crate::crba` (1-DoF joints) on lanes. A lane group's matrices are
//! built in `BatchData` as one nv x nv matrix of lanes (each entry a vector store,
//! the buffer in cache), then written out four entries at a time per instance, either
//! whole ([`crba_batch`]) or as the packed triangle ([`crba_batch_packed`]): the
//! output, not the arithmetic, was half of the time when each entry went straight
//! to four scattered matrices (BENCHMARKS.md, issue 32 item 2).

use super::joint::{compose, joint_placement, subspace_column};
use super::lanes::{Fo, In, LANES, Li, Mo, W};
use super::{BatchData, dispatch, gather, rows, uses_lanes};
use crate::model::{BASE, Model};
use twinloop_spatial::LinearInertia;

/// Entries of an nv x nv symmetric matrix's packed lower triangle.
pub fn packed_len(nv: usize) -> usize {
    nv * (nv + 1) / 2
}

/// Where entry (r, c) (either triangle) is in a packed lower triangle: rows in order,
/// row r holding columns 0..=r. The same numbers as the upper triangle by columns.
#[inline(always)]
pub fn packed_index(r: usize, c: usize) -> usize {
    let (hi, lo) = if r >= c { (r, c) } else { (c, r) };
    hi * (hi + 1) / 2 + lo
}

/// How an instance's matrix is written.
#[derive(Clone, Copy, PartialEq)]
enum Layout {
    /// nv x nv, both triangles.
    Full,
    /// `packed_len(nv)` entries, [`packed_index`].
    Packed,
}

/// [`crate::crba`] at N configurations `qs` (N x nq, row-major): writes N mass
/// matrices of nv x nv to `out`, each complete (symmetric, so row- and column-major
/// alike), with the single call's numbers in its upper triangle and their mirror.
pub fn crba_batch(model: &Model, bd: &mut BatchData, qs: &[f64], out: &mut [f64]) {
    run(model, bd, qs, out, Layout::Full);
}

/// [`crba_batch`] writing each matrix's lower triangle packed by rows (`packed_len(nv)`
/// entries an instance, entry (r, c) at [`packed_index`]`(r, c)`): the same numbers in
/// about half the memory, for callers that read the matrix as symmetric.
pub fn crba_batch_packed(model: &Model, bd: &mut BatchData, qs: &[f64], out: &mut [f64]) {
    run(model, bd, qs, out, Layout::Packed);
}

fn run(model: &Model, bd: &mut BatchData, qs: &[f64], out: &mut [f64], layout: Layout) {
    let n = rows("qs", qs, model.nq);
    let nv = model.nv;
    let per = match layout {
        Layout::Full => nv * nv,
        Layout::Packed => packed_len(nv),
    };
    assert_eq!(
        out.len(),
        n * per,
        "out has {} entries, {n} matrices of {per} expected",
        out.len()
    );
    if !uses_lanes(model) {
        for r in 0..n {
            crate::crba(model, &mut bd.single, &qs[r * model.nq..][..model.nq]);
            bd.single.symmetrize_mass_matrix();
            let m = &bd.single.mass_matrix;
            let o = &mut out[r * per..(r + 1) * per];
            match layout {
                // Symmetric: column-major storage is the row-major matrix.
                Layout::Full => o.copy_from_slice(m.as_slice()),
                Layout::Packed => {
                    for i in 0..nv {
                        for j in 0..=i {
                            o[packed_index(i, j)] = m[(i, j)];
                        }
                    }
                }
            }
        }
        return;
    }
    // Entries off every ancestor chain are never written: zero from the start.
    bd.mlanes.fill(W::ZERO);
    dispatch!(crba_groups, crba_groups_avx2, model, bd, qs, out, layout)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn crba_groups_avx2(
    model: &Model,
    bd: &mut BatchData,
    qs: &[f64],
    out: &mut [f64],
    layout: Layout,
) {
    crba_groups(model, bd, qs, out, layout)
}

#[inline(always)]
fn crba_groups(model: &Model, bd: &mut BatchData, qs: &[f64], out: &mut [f64], layout: Layout) {
    let n = qs.len() / model.nq;
    let nv = model.nv;
    for row0 in (0..n).step_by(LANES) {
        let count = LANES.min(n - row0);
        gather(qs, model.nq, row0, count, &mut bd.q);
        crba_lanes(model, bd);
        write_out(&bd.mlanes, nv, row0, count, out, layout);
    }
}

/// The group's lane matrices (`ml`, nv x nv lanes) into rows `row0 ..` of `out`.
#[inline(always)]
fn write_out(ml: &[W], nv: usize, row0: usize, count: usize, out: &mut [f64], layout: Layout) {
    let per = match layout {
        Layout::Full => nv * nv,
        Layout::Packed => packed_len(nv),
    };
    let o = &mut out[row0 * per..(row0 + count) * per];
    if count < LANES {
        for (l, ol) in o.chunks_exact_mut(per).enumerate() {
            for r in 0..nv {
                let (src, dst) = segment(ml, nv, r, layout);
                for (x, p) in ol[dst].iter_mut().zip(src) {
                    *x = p.0[l];
                }
            }
        }
        return;
    }
    let (o0, rest) = o.split_at_mut(per);
    let (o1, rest) = rest.split_at_mut(per);
    let (o2, o3) = rest.split_at_mut(per);
    match layout {
        Layout::Full => transpose_into(ml, [o0, o1, o2, o3]),
        Layout::Packed => {
            for r in 0..nv {
                let (src, dst) = segment(ml, nv, r, layout);
                let d = [
                    &mut o0[dst.clone()],
                    &mut o1[dst.clone()],
                    &mut o2[dst.clone()],
                    &mut o3[dst],
                ];
                transpose_into(src, d);
            }
        }
    }
}

/// Row `r` of the lane matrices as written: its lanes and where it goes in an
/// instance's output (the whole row, or its columns 0..=r in the packed triangle).
#[inline(always)]
fn segment(ml: &[W], nv: usize, r: usize, layout: Layout) -> (&[W], std::ops::Range<usize>) {
    match layout {
        Layout::Full => (&ml[r * nv..(r + 1) * nv], r * nv..(r + 1) * nv),
        Layout::Packed => {
            let start = r * (r + 1) / 2;
            (&ml[r * nv..=r * nv + r], start..start + r + 1)
        }
    }
}

/// Lane l of `src` into `dst[l]`, four entries at a time (a 4 x 4 transpose in
/// registers, then one vector store an instance) instead of one store an entry.
#[inline(always)]
fn transpose_into(src: &[W], dst: [&mut [f64]; LANES]) {
    let [d0, d1, d2, d3] = dst;
    let blocks = src
        .chunks_exact(LANES)
        .zip(d0.chunks_exact_mut(LANES))
        .zip(d1.chunks_exact_mut(LANES))
        .zip(d2.chunks_exact_mut(LANES))
        .zip(d3.chunks_exact_mut(LANES));
    for ((((s, e0), e1), e2), e3) in blocks {
        for j in 0..LANES {
            e0[j] = s[j].0[0];
            e1[j] = s[j].0[1];
            e2[j] = s[j].0[2];
            e3[j] = s[j].0[3];
        }
    }
    let done = src.len() / LANES * LANES;
    for (k, s) in src.iter().enumerate().skip(done) {
        d0[k] = s.0[0];
        d1[k] = s.0[1];
        d2[k] = s.0[2];
        d3[k] = s.0[3];
    }
}

/// Entry (r, c) of the lane matrices and its mirror.
#[inline(always)]
fn put(ml: &mut [W], nv: usize, r: usize, c: usize, x: W) {
    ml[r * nv + c] = x;
    ml[c * nv + r] = x;
}

/// Column `col`'s entries in the base rows (`crba::base_rows`), rows 0..=`last`:
/// the upper triangle's, which the single call keeps.
#[inline(always)]
fn base_rows(ml: &mut [W], nv: usize, col: usize, last: usize, f: &Fo) {
    for (r, x) in f.lanes().into_iter().enumerate().take(last + 1) {
        put(ml, nv, r, col, x);
    }
}

#[inline(always)]
fn crba_lanes(model: &Model, bd: &mut BatchData) {
    let nb = model.nbodies;
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
    let nv = model.nv;
    let ml = &mut bd.mlanes[..];
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
        let s = &bd.s;
        let f = yi.mul_motion(&s[i]);
        put(ml, nv, col, col, s[i].dot(&f) + W::splat(model.armature[i]));
        let mut j = p;
        while j != BASE {
            put(ml, nv, off + j, col, s[j].dot(&f));
            j = model.parents[j];
        }
        if off == 6 {
            base_rows(ml, nv, col, 5, &f);
        }
    }
    if off == 6 {
        for k in 0..6 {
            let mut e = [W::ZERO; 6];
            e[k] = W::splat(1.0);
            let f = base.mul_motion(&Mo::from_lanes(&e));
            base_rows(ml, nv, k, k, &f);
            // MuJoCo's free-joint armature (`Model::base_armature`), as the single call.
            ml[k * nv + k] += W::splat(model.base_armature);
        }
    }
}
