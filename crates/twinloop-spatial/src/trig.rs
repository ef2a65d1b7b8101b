//! Sine and cosine together, for joint angles: a reduction to [-pi/4, pi/4] and the
//! Taylor series there. About 3x faster than the C library's `sincos` on the joint
//! loops (no call, no branches for the usual angles, independent joints overlap),
//! and within 2.3e-16 of it (test `sin_cos_matches_the_library`).

use std::f64::consts::FRAC_2_PI;

/// Adding then subtracting 1.5 * 2^52 rounds a double of magnitude under 2^51 to the
/// nearest integer, and leaves that integer in the low mantissa bits.
const SHIFTER: f64 = 6_755_399_441_055_744.0;
/// pi/2 in three parts (Cody and Waite's reduction): the double nearest pi/2 with its
/// low 20 mantissa bits cleared (k P1 is exact for |k| < 2^20), the rest of that
/// double (20 bits: k P2 exact too), and pi/2 minus the double nearest it
/// (6.123233995736766e-17: half of pi minus the double nearest pi, 1.2246467991473532e-16).
const P1: f64 = f64::from_bits(std::f64::consts::FRAC_PI_2.to_bits() & !0xF_FFFF);
const P2: f64 = std::f64::consts::FRAC_PI_2 - P1;
const P3: f64 = 6.123_233_995_736_766e-17;
/// Beyond this the reduction above loses accuracy; the library takes over.
const FAST_LIMIT: f64 = 1e5;

/// Inverse factorials 1/n! for the series.
const F3: f64 = 1.0 / 6.0;
const F4: f64 = 1.0 / 24.0;
const F5: f64 = 1.0 / 120.0;
const F6: f64 = 1.0 / 720.0;
const F7: f64 = 1.0 / 5040.0;
const F8: f64 = 1.0 / 40320.0;
const F9: f64 = 1.0 / 362_880.0;
const F10: f64 = 1.0 / 3_628_800.0;
const F11: f64 = 1.0 / 39_916_800.0;
const F12: f64 = 1.0 / 479_001_600.0;
const F13: f64 = 1.0 / 6_227_020_800.0;
const F14: f64 = 1.0 / 87_178_291_200.0;
const F15: f64 = 1.0 / 1_307_674_368_000.0;
const F16: f64 = 1.0 / 20_922_789_888_000.0;
const F17: f64 = 1.0 / 355_687_428_096_000.0;

/// `(sin x, cos x)`. NaN and infinities give NaN like `f64::sin_cos`.
#[inline(always)]
pub fn sin_cos(x: f64) -> (f64, f64) {
    if x.is_nan() || x.abs() >= FAST_LIMIT {
        return x.sin_cos();
    }
    let t = x * FRAC_2_PI + SHIFTER;
    let k = t - SHIFTER;
    let quadrant = t.to_bits() & 3; // k mod 4 (two's complement in the mantissa)
    // Exact for |k| < 2^20 up to the last subtraction (Sterbenz: x and k P1 are close).
    let r = ((x - k * P1) - k * P2) - k * P3;
    let z = r * r;
    // Truncation errors at |r| = pi/4: r^19/19! and r^18/18!, under 1e-17.
    let ps = F3 - z * (F5 - z * (F7 - z * (F9 - z * (F11 - z * (F13 - z * (F15 - z * F17))))));
    let s = r - r * z * ps;
    let pc = F4 - z * (F6 - z * (F8 - z * (F10 - z * (F12 - z * (F14 - z * F16)))));
    let c = 1.0 - (0.5 * z - z * z * pc);
    // The quadrant's swap and signs by bit masks: random angles would mispredict a branch.
    let swap = 0u64.wrapping_sub(quadrant & 1);
    let (sb, cb) = (s.to_bits(), c.to_bits());
    let sin = ((sb & !swap) | (cb & swap)) ^ ((quadrant & 2) << 62);
    let cos = ((cb & !swap) | (sb & swap)) ^ (((quadrant + 1) & 2) << 62);
    (f64::from_bits(sin), f64::from_bits(cos))
}

/// [`sin_cos`] of `L` angles at once, bit for bit the same numbers: the same
/// operations written lane by lane so the compiler can put the lanes of one
/// operation in one vector instruction (the batched dynamics of
/// twinloop-dynamics). A lane the fast reduction
/// does not cover (NaN, |x| >= 1e5) takes the library's value as [`sin_cos`] does.
// Lane loops index several arrays by the lane number.
#[allow(clippy::needless_range_loop)]
#[inline(always)]
pub fn sin_cos_lanes<const L: usize>(x: &[f64; L]) -> ([f64; L], [f64; L]) {
    let (mut t, mut r, mut z) = ([0.0; L], [0.0; L], [0.0; L]);
    for l in 0..L {
        t[l] = x[l] * FRAC_2_PI + SHIFTER;
    }
    for l in 0..L {
        let k = t[l] - SHIFTER;
        r[l] = ((x[l] - k * P1) - k * P2) - k * P3;
        z[l] = r[l] * r[l];
    }
    std::hint::black_box((&mut t, &mut r, &mut z));
    // LLVM's SLP vectoriser gives up on expression trees deeper than 12 operations,
    // and the series are about 16 deep: the halves meet in memory (`black_box` keeps
    // them there), so each half is a tree it takes. Only speed depends on this.
    let (mut ps, mut pc) = ([0.0; L], [0.0; L]);
    for l in 0..L {
        let z = z[l];
        ps[l] = F11 - z * (F13 - z * (F15 - z * F17));
        pc[l] = F12 - z * (F14 - z * F16);
    }
    std::hint::black_box((&mut ps, &mut pc, &mut z, &mut r));
    let (mut s, mut c) = ([0u64; L], [0u64; L]);
    for l in 0..L {
        let z = z[l];
        let ps = F3 - z * (F5 - z * (F7 - z * (F9 - z * ps[l])));
        s[l] = (r[l] - r[l] * z * ps).to_bits();
        let pc = F4 - z * (F6 - z * (F8 - z * (F10 - z * pc[l])));
        c[l] = (1.0 - (0.5 * z - z * z * pc)).to_bits();
    }
    let (mut sin, mut cos) = ([0.0; L], [0.0; L]);
    for l in 0..L {
        let quadrant = t[l].to_bits() & 3;
        let swap = 0u64.wrapping_sub(quadrant & 1);
        sin[l] = f64::from_bits(((s[l] & !swap) | (c[l] & swap)) ^ ((quadrant & 2) << 62));
        cos[l] = f64::from_bits(((c[l] & !swap) | (s[l] & swap)) ^ (((quadrant + 1) & 2) << 62));
    }
    // NaN fails `|x| < limit`, so this catches it with the large angles.
    let mut slow = 0u64;
    for xl in x {
        slow |= u64::from(xl.abs().partial_cmp(&FAST_LIMIT) != Some(std::cmp::Ordering::Less));
    }
    if slow != 0 {
        // Rare: redo the lanes the reduction cannot take (one branch per call).
        for l in 0..L {
            if x[l].is_nan() || x[l].abs() >= FAST_LIMIT {
                (sin[l], cos[l]) = x[l].sin_cos();
            }
        }
    }
    (sin, cos)
}
