//! Batched dynamics: RNEA, ABA, CRBA and the CoM of one model at N states in one
//! call. The states are taken `LANES` (4) at a time and every scalar of the
//! single-call code becomes a lane group of 4 ([`lanes`]): one AVX2 instruction does
//! the same operation for 4 instances, where the single call's serial recursion
//! leaves the vector units mostly idle (issue 32, item 2). Each lane does the single
//! call's operations in its order, so a batched result equals [`crate::rnea`] etc.
//! bit for bit (`tests/batch.rs`).
//!
//! Inputs and outputs are row-major, one instance a row: `qs` is N x nq, `vs` N x nv.
//! N need not be a multiple of 4: the last group's missing lanes repeat its first
//! instance and are not written back. [`BatchData`] holds every buffer, so a call
//! allocates nothing.
//!
//! The lanes take 1-DoF joints; a model with a spherical joint runs the single call
//! row by row (same results, no speed-up). On x86-64 the lane code is compiled twice:
//! for the baseline target (SSE2, 2 doubles an instruction) and with AVX2 and FMA
//! enabled, picked at run time (`is_x86_feature_detected!`); FMA is only allowed, the
//! code never asks for a fused multiply-add, so both give the same bits.

// Lane loops index several arrays by the lane number.
#![allow(clippy::needless_range_loop)]

mod aba;
mod com;
mod crba;
mod joint;
pub mod lanes;
mod rnea;

use crate::data::Data;
use crate::model::Model;
use crate::singular::SingularJoint;
use lanes::{Fo, LANES, Li, Mo, S6, W, X};
use std::fmt;

pub use aba::{aba_batch, try_aba_batch};
pub use com::center_of_mass_batch;
pub use crba::{crba_batch, crba_batch_packed, packed_index, packed_len};
pub use rnea::rnea_batch;

/// The workspace of the batched algorithms for one model (one per thread).
#[derive(Debug, Clone)]
pub struct BatchData {
    /// The lane group's inputs: q (nq lanes), v and a or tau (nv lanes each).
    q: Vec<W>,
    v: Vec<W>,
    a: Vec<W>,
    /// Outputs of the group (tau or ddq).
    out: Vec<W>,
    /// Per body: joint placement, placement in the base (or world) frame, subspace
    /// column, velocity, acceleration, force, ABA's c, IA, pA, U, D^-1, u, CRBA's
    /// composite inertia.
    li: Vec<X>,
    x: Vec<X>,
    s: Vec<Mo>,
    vel: Vec<Mo>,
    acc: Vec<Mo>,
    f: Vec<Fo>,
    c: Vec<Mo>,
    ia: Vec<S6>,
    pa: Vec<Fo>,
    u_col: Vec<Fo>,
    d_inv: Vec<W>,
    u: Vec<W>,
    ycrb: Vec<Li>,
    /// CRBA's lane group of mass matrices (nv x nv lanes, both triangles).
    mlanes: Vec<W>,
    /// Per lane: the first body (leaves first) whose ABA pivot is singular.
    singular: [Option<(usize, f64)>; LANES],
    /// The single-call workspace: for models with spherical joints, and for naming a
    /// singular joint.
    pub single: Data,
}

impl BatchData {
    pub fn new(model: &Model) -> BatchData {
        let nb = model.nbodies;
        let zx = X::splat(&twinloop_spatial::Se3::IDENTITY);
        BatchData {
            q: vec![W::ZERO; model.nq],
            v: vec![W::ZERO; model.nv],
            a: vec![W::ZERO; model.nv],
            out: vec![W::ZERO; model.nv],
            li: vec![zx; nb],
            x: vec![zx; nb],
            s: vec![Mo::ZERO; nb],
            vel: vec![Mo::ZERO; nb],
            acc: vec![Mo::ZERO; nb],
            f: vec![Fo::ZERO; nb],
            c: vec![Mo::ZERO; nb],
            ia: vec![S6::ZERO; nb],
            pa: vec![Fo::ZERO; nb],
            u_col: vec![Fo::ZERO; nb],
            d_inv: vec![W::ZERO; nb],
            u: vec![W::ZERO; nb],
            ycrb: vec![Li::ZERO; nb],
            mlanes: vec![W::ZERO; model.nv * model.nv],
            singular: [None; LANES],
            single: Data::new(model),
        }
    }
}

/// Whether the model runs on the lanes (every joint 1-DoF).
pub fn uses_lanes(model: &Model) -> bool {
    !model.has_spherical_joints()
}

/// A batch row whose mass matrix is singular ([`try_aba_batch`]).
#[derive(Debug, Clone, PartialEq)]
pub struct SingularRow {
    /// The row (instance) index.
    pub row: usize,
    pub joint: SingularJoint,
}

impl fmt::Display for SingularRow {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "row {}: {}", self.row, self.joint)
    }
}

impl std::error::Error for SingularRow {}

/// Number of rows of a row-major batch of `width`-wide rows, checking the others'.
fn rows(name: &str, x: &[f64], width: usize) -> usize {
    assert!(
        width > 0 && x.len().is_multiple_of(width),
        "{name} has {} entries, not a whole number of rows of {width}",
        x.len()
    );
    x.len() / width
}

fn check_rows(name: &str, x: &[f64], width: usize, n: usize) {
    assert_eq!(
        x.len(),
        n * width,
        "{name} has {} entries, {n} rows of {width} expected",
        x.len()
    );
}

/// Rows `row0 ..` of `src` (`width` a row) into lanes; missing lanes repeat row `row0`.
/// Each lane group is built from the rows' entries in registers and stored once
/// (lane-by-lane stores into memory would stall the vector loads that follow).
#[inline(always)]
fn gather(src: &[f64], width: usize, row0: usize, count: usize, dst: &mut [W]) {
    let mut rows: [&[f64]; LANES] = [&src[row0 * width..(row0 + 1) * width]; LANES];
    for (l, r) in rows.iter_mut().enumerate().take(count).skip(1) {
        *r = &src[(row0 + l) * width..(row0 + l + 1) * width];
    }
    for (k, d) in dst.iter_mut().enumerate().take(width) {
        let mut w = [0.0; LANES];
        for l in 0..LANES {
            w[l] = rows[l][k];
        }
        *d = W(w);
    }
}

/// The first `count` lanes of `src` into rows `row0 ..` of `dst`.
#[inline(always)]
fn scatter(src: &[W], width: usize, row0: usize, count: usize, dst: &mut [f64]) {
    for l in 0..count {
        let row = &mut dst[(row0 + l) * width..(row0 + l + 1) * width];
        for (d, x) in row.iter_mut().zip(src) {
            *d = x.0[l];
        }
    }
}

/// Whether this CPU runs the AVX2 build of the lanes.
#[cfg(target_arch = "x86_64")]
pub fn has_avx2() -> bool {
    std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
}

/// Run a lane function compiled for AVX2 + FMA when the CPU has them, else the
/// baseline build. `$avx` must be a `#[target_feature(enable = "avx2,fma")]` wrapper
/// of `$base`.
macro_rules! dispatch {
    ($base:ident, $avx:ident, $($arg:expr),*) => {{
        #[cfg(target_arch = "x86_64")]
        {
            if $crate::batch::has_avx2() {
                // SAFETY: the CPU has AVX2 and FMA (checked just above).
                return unsafe { $avx($($arg),*) };
            }
        }
        $base($($arg),*)
    }};
}
pub(crate) use dispatch;
