//! Batched RNEA: `crate::rnea::rnea_impl` (with velocity and acceleration) on lanes.

use super::joint::{base_placement, joint_placement, subspace_dot, subspace_times};
use super::lanes::{Fo, In, LANES, Mo, V3, W};
use super::{BatchData, check_rows, dispatch, gather, rows, scatter, uses_lanes};
use crate::model::{BASE, Model};

/// [`crate::rnea`] at N states: `qs` (N x nq), `vs` and `accs` (N x nv) row-major;
/// writes N x nv torques (floating base: the base wrench first) to `out`.
pub fn rnea_batch(
    model: &Model,
    bd: &mut BatchData,
    qs: &[f64],
    vs: &[f64],
    accs: &[f64],
    out: &mut [f64],
) {
    let n = rows("qs", qs, model.nq);
    for (name, x) in [("vs", vs), ("accs", accs), ("out", &*out)] {
        check_rows(name, x, model.nv, n);
    }
    if !uses_lanes(model) {
        for r in 0..n {
            let (q, v, a) = (
                row(qs, model.nq, r),
                row(vs, model.nv, r),
                row(accs, model.nv, r),
            );
            let tau = crate::rnea(model, &mut bd.single, q, v, a);
            out[r * model.nv..(r + 1) * model.nv].copy_from_slice(tau.as_slice());
        }
        return;
    }
    dispatch!(rnea_groups, rnea_groups_avx2, model, bd, qs, vs, accs, out)
}

fn row(x: &[f64], w: usize, r: usize) -> &[f64] {
    &x[r * w..(r + 1) * w]
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn rnea_groups_avx2(
    model: &Model,
    bd: &mut BatchData,
    qs: &[f64],
    vs: &[f64],
    accs: &[f64],
    out: &mut [f64],
) {
    rnea_groups(model, bd, qs, vs, accs, out)
}

#[inline(always)]
fn rnea_groups(
    model: &Model,
    bd: &mut BatchData,
    qs: &[f64],
    vs: &[f64],
    accs: &[f64],
    out: &mut [f64],
) {
    let n = qs.len() / model.nq;
    for row0 in (0..n).step_by(LANES) {
        let count = LANES.min(n - row0);
        gather(qs, model.nq, row0, count, &mut bd.q);
        gather(vs, model.nv, row0, count, &mut bd.v);
        gather(accs, model.nv, row0, count, &mut bd.a);
        rnea_lanes(model, bd);
        scatter(&bd.out, model.nv, row0, count, out);
    }
}

/// One lane group: `bd.q`, `bd.v`, `bd.a` to `bd.out`.
#[inline(always)]
fn rnea_lanes(model: &Model, bd: &mut BatchData) {
    let floating = model.is_floating();
    let base = base_placement(model, &bd.q);
    let up = base.r.tr_mul_v(&V3::splat(&(-model.gravity)));
    let (v0, a0) = if floating {
        let mut a0 = Mo::from_lanes(&bd.a[0..6]);
        a0.v += up;
        (Mo::from_lanes(&bd.v[0..6]), a0)
    } else {
        (Mo::ZERO, Mo { v: up, w: V3::ZERO })
    };
    let mut f0 = if floating {
        let i0 = In::splat(&model.base_inertia);
        let f0 = i0.mul_motion(&a0).add(&v0.cross_force(&i0.mul_motion(&v0)));
        f0.add(&base_armature_force(
            model,
            &v0,
            &Mo::from_lanes(&bd.a[0..6]),
        ))
    } else {
        Fo::ZERO
    };
    for i in 0..model.nbodies {
        let li = joint_placement(model, i, &bd.q);
        bd.li[i] = li;
        let p = model.parents[i];
        let (vp, ap) = if p == BASE {
            (v0, a0)
        } else {
            (bd.vel[p], bd.acc[p])
        };
        let iv = model.idx_v[i];
        let aj = subspace_times(model, i, bd.a[iv]);
        let vj = subspace_times(model, i, bd.v[iv]);
        let vi = li.act_inv_motion(&vp).add(&vj);
        let ai = li.act_inv_motion(&ap).add(&aj).add(&vi.cross(&vj));
        bd.vel[i] = vi;
        bd.acc[i] = ai;
        let inertia = In::splat(&model.inertias[i]);
        bd.f[i] = inertia
            .mul_motion(&ai)
            .add(&vi.cross_force(&inertia.mul_motion(&vi)));
    }
    for i in (0..model.nbodies).rev() {
        let fi = bd.f[i];
        let iv = model.idx_v[i];
        bd.out[iv] = subspace_dot(model, i, &fi) + W::splat(model.armature[i]) * bd.a[iv];
        let fp = bd.li[i].act_force(&fi);
        let p = model.parents[i];
        if p == BASE {
            f0 = f0.add(&fp);
        } else {
            bd.f[p] = bd.f[p].add(&fp);
        }
    }
    if floating {
        bd.out[0..6].copy_from_slice(&f0.lanes());
    }
}

/// `rnea::base_armature_force`: the floating base's armature `a (a0.v + w x v, a0.w)`
/// (zero when it has none, which the single call adds too).
#[inline(always)]
fn base_armature_force(model: &Model, v0: &Mo, a0: &Mo) -> Fo {
    let k = model.base_armature;
    if k == 0.0 {
        return Fo::ZERO;
    }
    let k = W::splat(k);
    Fo {
        f: (a0.v + v0.w.cross(&v0.v)).scale(k),
        n: a0.w.scale(k),
    }
}
