//! Batched ABA: `crate::aba` (1-DoF joints, no external forces) on lanes, with the
//! floating base's 6 x 6 Cholesky solve written out as nalgebra does it.

use super::joint::{base_placement, compose, joint_placement, subspace_column};
use super::lanes::{Fo, In, LANES, M3, Mo, S6, V3, W};
use super::{BatchData, SingularRow, check_rows, dispatch, gather, rows, scatter, uses_lanes};
use crate::model::{BASE, Model};
use crate::singular::SINGULAR_RELATIVE_TOLERANCE;

/// [`crate::aba`] at N states: `qs` (N x nq), `vs` and `taus` (N x nv) row-major;
/// writes N x nv accelerations to `out`. Like `aba`, a singular mass matrix gives
/// infinite or NaN accelerations; [`try_aba_batch`] refuses it.
pub fn aba_batch(
    model: &Model,
    bd: &mut BatchData,
    qs: &[f64],
    vs: &[f64],
    taus: &[f64],
    out: &mut [f64],
) {
    run(model, bd, qs, vs, taus, out, false);
}

/// [`crate::try_aba`] at N states: the first row (lowest index) whose mass matrix is
/// singular is an error naming the row and the joint, as `try_aba` names the joint;
/// `out` then holds the rows before it and unspecified values after.
pub fn try_aba_batch(
    model: &Model,
    bd: &mut BatchData,
    qs: &[f64],
    vs: &[f64],
    taus: &[f64],
    out: &mut [f64],
) -> Result<(), SingularRow> {
    match run(model, bd, qs, vs, taus, out, true) {
        None => Ok(()),
        // The single call names the joint (the lanes found which row); from that row
        // on, the rows go one at a time, so a lane that ever disagreed with the single
        // call (they agree bit for bit in every test) costs time, never an answer.
        Some(row) => singly_from(model, bd, qs, vs, taus, out, row),
    }
}

/// [`crate::try_aba`] on rows `from..`, one at a time, writing each to `out`.
fn singly_from(
    model: &Model,
    bd: &mut BatchData,
    qs: &[f64],
    vs: &[f64],
    taus: &[f64],
    out: &mut [f64],
    from: usize,
) -> Result<(), SingularRow> {
    let w = model.nv;
    for row in from..out.len() / w.max(1) {
        let (q, v, t) = (
            &qs[row * model.nq..][..model.nq],
            &vs[row * w..][..w],
            &taus[row * w..][..w],
        );
        match crate::try_aba(model, &mut bd.single, q, v, t) {
            Err(joint) => return Err(SingularRow { row, joint }),
            Ok(ddq) => out[row * w..][..w].copy_from_slice(ddq.as_slice()),
        }
    }
    Ok(())
}

/// The rows; with `check`, the first singular row (and no rows after it).
fn run(
    model: &Model,
    bd: &mut BatchData,
    qs: &[f64],
    vs: &[f64],
    taus: &[f64],
    out: &mut [f64],
    check: bool,
) -> Option<usize> {
    let n = rows("qs", qs, model.nq);
    for (name, x) in [("vs", vs), ("taus", taus), ("out", &*out)] {
        check_rows(name, x, model.nv, n);
    }
    if !uses_lanes(model) {
        let w = model.nv;
        for r in 0..n {
            let (q, v, t) = (
                &qs[r * model.nq..][..model.nq],
                &vs[r * w..][..w],
                &taus[r * w..][..w],
            );
            let ddq = if check {
                match crate::try_aba(model, &mut bd.single, q, v, t) {
                    Ok(x) => x,
                    Err(_) => return Some(r),
                }
            } else {
                crate::aba(model, &mut bd.single, q, v, t)
            };
            out[r * w..(r + 1) * w].copy_from_slice(ddq.as_slice());
        }
        return None;
    }
    dispatch!(
        aba_groups,
        aba_groups_avx2,
        model,
        bd,
        qs,
        vs,
        taus,
        out,
        check
    )
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn aba_groups_avx2(
    model: &Model,
    bd: &mut BatchData,
    qs: &[f64],
    vs: &[f64],
    taus: &[f64],
    out: &mut [f64],
    check: bool,
) -> Option<usize> {
    aba_groups(model, bd, qs, vs, taus, out, check)
}

#[inline(always)]
fn aba_groups(
    model: &Model,
    bd: &mut BatchData,
    qs: &[f64],
    vs: &[f64],
    taus: &[f64],
    out: &mut [f64],
    check: bool,
) -> Option<usize> {
    let n = qs.len() / model.nq;
    for row0 in (0..n).step_by(LANES) {
        let count = LANES.min(n - row0);
        gather(qs, model.nq, row0, count, &mut bd.q);
        gather(vs, model.nv, row0, count, &mut bd.v);
        gather(taus, model.nv, row0, count, &mut bd.a);
        let (mut ia0, mut pa0) = velocity_pass(model, bd);
        articulated_pass(model, bd, &mut ia0, &mut pa0, check);
        let base_ok = acceleration_pass(model, bd, &ia0, &pa0);
        if check && let Some(l) = (0..count).find(|&l| bd.singular[l].is_some() || !base_ok[l]) {
            scatter(&bd.out, model.nv, row0, l, out);
            return Some(row0 + l);
        }
        scatter(&bd.out, model.nv, row0, count, out);
    }
    None
}

/// `aba::velocity_pass` (one-DoF branch): placements in the base frame, subspaces,
/// velocities, c, rigid inertias and bias forces. Returns the base's (IA, pA).
#[inline(always)]
fn velocity_pass(model: &Model, bd: &mut BatchData) -> (S6, Fo) {
    let floating = model.is_floating();
    let (v0, ia0, pa0) = if floating {
        let v0 = Mo::from_lanes(&bd.v[0..6]);
        let i0 = In::splat(&model.base_inertia);
        let (mut ia0, mut pa0) = (i0.to_sym6(), v0.cross_force(&i0.mul_motion(&v0)));
        base_armature(model, &bd.q, &v0, &mut ia0, &mut pa0);
        (v0, ia0, pa0)
    } else {
        (Mo::ZERO, S6::ZERO, Fo::ZERO)
    };
    for i in 0..model.nbodies {
        let li = joint_placement(model, i, &bd.q);
        let p = model.parents[i];
        let (b, vp) = if p == BASE {
            (li, v0)
        } else {
            (compose(model, i, &bd.x[p], &li), bd.vel[p])
        };
        bd.x[i] = b;
        let s = subspace_column(model, i, &b);
        bd.s[i] = s;
        let sv = s.scale(bd.v[model.v_offset + i]);
        let vi = vp.add(&sv);
        bd.vel[i] = vi;
        bd.c[i] = vi.cross(&sv);
        let yb = In::splat(&model.inertias[i]).transformed(&b);
        bd.ia[i] = yb.to_sym6();
        bd.pa[i] = vi.cross_force(&yb.mul_motion(&vi));
    }
    (ia0, pa0)
}

/// The floating base's armature `a` in the base's (IA, pA), as `aba::velocity_pass`:
/// `a` on the diagonal of both 3 x 3 blocks, `a (w x v - up)` in the bias force.
#[inline(always)]
fn base_armature(model: &Model, q: &[W], v0: &Mo, ia0: &mut S6, pa0: &mut Fo) {
    let k = model.base_armature;
    if k == 0.0 {
        return;
    }
    // `Matrix3::identity() * k`, entry by entry.
    let (on, off) = (W::splat(1.0 * k), W::splat(0.0 * k));
    let ik = M3 {
        m: [[on, off, off], [off, on, off], [off, off, on]],
    };
    ia0.a = ia0.a.zip(&ik, |p, q| p + q);
    ia0.c = ia0.c.zip(&ik, |p, q| p + q);
    let up = base_placement(model, q)
        .r
        .tr_mul_v(&V3::splat(&(-model.gravity)));
    pa0.f += (v0.w.cross(&v0.v) - up).scale(W::splat(k));
}

/// `aba::articulated_pass` (one-DoF joints), leaves to root; with `check`, records
/// in `bd.singular` each lane's first pivot at or below `singular.rs`'s floor.
#[inline(always)]
fn articulated_pass(model: &Model, bd: &mut BatchData, ia0: &mut S6, pa0: &mut Fo, check: bool) {
    bd.singular = [None; LANES];
    for i in (0..model.nbodies).rev() {
        let d = i;
        let s = bd.s[d];
        // IA is reduced in place and added to the parent's from there (the parent
        // comes first in the body order): a copy of its 27 lanes was a memcpy a body.
        let (before, from_i) = bd.ia.split_at_mut(i);
        let ia = &mut from_i[0];
        let ucol = ia.mul_motion(&s);
        let arm = W::splat(model.armature[i]);
        let pivot = s.dot(&ucol) + arm;
        if check {
            record_singular(&mut bd.singular, ia, pivot, model.armature[i], i);
        }
        let d_inv = 1.0 / pivot;
        let u = bd.a[model.idx_v[i]] - s.dot(&bd.pa[i]);
        bd.u_col[d] = ucol;
        bd.d_inv[d] = d_inv;
        bd.u[d] = u;
        ia.sub_rank1(&ucol, d_inv);
        let pa_a = bd.pa[i]
            .add(&ia.mul_motion(&bd.c[i]))
            .add(&ucol.scale(d_inv * u));
        let p = model.parents[i];
        if p == BASE {
            ia0.add_assign(ia);
            *pa0 = pa0.add(&pa_a);
        } else {
            before[p].add_assign(ia);
            bd.pa[p] = bd.pa[p].add(&pa_a);
        }
    }
}

/// `singular::singular_pivot`'s test of one body, lane by lane.
#[inline(always)]
fn record_singular(
    singular: &mut [Option<(usize, f64)>; LANES],
    ia: &S6,
    pivot: W,
    armature: f64,
    i: usize,
) {
    for l in 0..LANES {
        if singular[l].is_some() {
            continue;
        }
        let mut scale: f64 = 0.0;
        for blk in [&ia.a, &ia.b, &ia.c] {
            for row in &blk.m {
                for x in row {
                    scale = scale.max(x.0[l].abs());
                }
            }
        }
        let p = pivot.0[l];
        if p.is_nan() || p <= SINGULAR_RELATIVE_TOLERANCE * (scale + armature) {
            singular[l] = Some((i, p));
        }
    }
}

/// `aba::acceleration_pass` (one-DoF joints), root to leaves, into `bd.out`. Returns
/// per lane whether the floating base's locked inertia was positive definite.
#[inline(always)]
fn acceleration_pass(model: &Model, bd: &mut BatchData, ia0: &S6, pa0: &Fo) -> [bool; LANES] {
    let base = base_placement(model, &bd.q);
    let up = Mo {
        v: base.r.tr_mul_v(&V3::splat(&(-model.gravity))),
        w: V3::ZERO,
    };
    let mut ok = [true; LANES];
    let a0 = if model.is_floating() {
        let rhs = Fo::from_lanes(&bd.a[0..6]).sub(pa0);
        let (x, pd) = cholesky_solve(ia0, &rhs.lanes());
        let mut a0 = Mo::from_lanes(&x);
        for l in 0..LANES {
            if !pd[l] {
                // Singular only for a massless robot: NaN, as the single call.
                ok[l] = false;
                for c in [&mut a0.v, &mut a0.w] {
                    for k in [&mut c.x, &mut c.y, &mut c.z] {
                        k.0[l] = f64::NAN;
                    }
                }
            }
        }
        let qdd0 = Mo {
            v: a0.v - up.v,
            w: a0.w - up.w,
        };
        bd.out[0..6].copy_from_slice(&[qdd0.v.x, qdd0.v.y, qdd0.v.z, qdd0.w.x, qdd0.w.y, qdd0.w.z]);
        a0
    } else {
        up
    };
    for i in 0..model.nbodies {
        let p = model.parents[i];
        let ap = if p == BASE { a0 } else { bd.acc[p] };
        let ai = ap.add(&bd.c[i]);
        let d = i;
        let qdd = bd.d_inv[d] * (bd.u[d] - ai.dot(&bd.u_col[d]));
        bd.out[model.idx_v[i]] = qdd;
        bd.acc[i] = ai.add(&bd.s[d].scale(qdd));
    }
    if model.is_floating() {
        for l in 0..LANES {
            ok[l] &= (0..6).all(|k| bd.out[k].0[l].is_finite());
        }
    }
    ok
}

/// `ia.to_matrix6().cholesky()` then `solve(rhs)`, as nalgebra 0.35 computes them
/// (`Cholesky::new`, `solve_lower_triangular_unchecked_mut`, then the adjoint solve
/// with its dot products summed from zero). Also per lane whether every pivot was
/// positive (nalgebra's `None` otherwise).
#[inline(always)]
fn cholesky_solve(ia: &S6, rhs: &[W; 6]) -> ([W; 6], [bool; LANES]) {
    let mut m = ia.to_matrix6();
    let mut pd = [true; LANES];
    for j in 0..6 {
        for k in 0..j {
            let factor = -m[j][k];
            for i in j..6 {
                m[i][j] = factor * m[i][k] + m[i][j];
            }
        }
        let diag = m[j][j];
        for l in 0..LANES {
            // nalgebra: a zero pivot or one whose square root fails (negative, NaN).
            pd[l] &= diag.0[l] > 0.0;
        }
        let denom = diag.sqrt();
        m[j][j] = denom;
        for row in m.iter_mut().skip(j + 1) {
            row[j] /= denom;
        }
    }
    let mut b = *rhs;
    for i in 0..6 {
        let coeff = b[i] / m[i][i];
        b[i] = coeff;
        for r in i + 1..6 {
            b[r] = -coeff * m[r][i] + b[r];
        }
    }
    for i in (0..6).rev() {
        let mut dot = W::ZERO;
        for r in i + 1..6 {
            dot += m[r][i] * b[r];
        }
        b[i] = (b[i] - dot) / m[i][i];
    }
    (b, pd)
}
