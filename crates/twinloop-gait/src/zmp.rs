//! ZMP walking references and the LIPM CoM reference (seed 002, eq 12-13).
//!
//! # Formulation
//!
//! The footstep plan places the feet alternately at `y = -w/2` (right) and `y = +w/2`
//! (left). Both feet start side by side at `x = 0`; swing `j` (1..=N) lands its foot at
//! `x = j * sl`, the first swing being the left foot. The ZMP reference is piecewise
//! linear in time:
//!
//! 1. standing for `t_start`: the ZMP holds the mid-point of the feet;
//! 2. double support `Tdb`: the ZMP moves in a straight line to the first support foot;
//! 3. for each swing: single support `Tss` with the ZMP at the centre of the support
//!    foot, then (between swings) double support `Tdb` moving it to the next foot;
//! 4. after the last swing, double support `Tdb` to the mid-point of the last two feet,
//!    then standing for `t_end`.
//!
//! The CoM reference solves the LIPM of eq 12-13, `x'' = (x - p) / Tc^2` with
//! `Tc = sqrt(Zc / g)`, in closed form per phase. The pendulum itself (the time constant,
//! the per-phase solution and its boundary fits) is twinloop-reduced's
//! ([`twinloop_reduced::lipm::LipmPhase`], seed 000's LIPM); this module plans the
//! footsteps and phases and chains the boundary conditions. With the divergent component of
//! motion `xi = x + Tc x'` the LIPM splits into `xi' = (xi - p) / Tc` (unstable) and
//! `x' = (xi - x) / Tc` (stable). For a linear ZMP `p(t) = p0 + s tau` on a phase of
//! length `D` (tau = t - t0) the exact solution is
//!
//! ```text
//! x(tau) = p0 + s tau + A exp(-tau/Tc) + B exp((tau - D)/Tc)
//! B = (xi(t1) - p(t1) - Tc s) / 2,   A = x(t0) - p0 - B exp(-D/Tc)
//! xi(t0) = p0 + Tc s + 2 B exp(-D/Tc)
//! ```
//!
//! (equivalently `x = p + (x0 - p0) cosh(tau/Tc) + Tc (v0 - s) sinh(tau/Tc)`).
//! Boundary conditions: `xi(T) = p(T)` at the end of the plan (the unique bounded
//! solution: the CoM comes to rest over the final ZMP) solved backwards phase by phase,
//! and `x(0) = p(0)` at the start, solved forwards. The CoM starts over the ZMP with the
//! small velocity `(xi(0) - x(0)) / Tc`, which decays as `exp(-t_start / Tc)`
//! ([`ZmpReference::initial_velocity`] reports it). Both x and x' are continuous across
//! phases, x'' = (x - p)/Tc^2 holds exactly, and the gait far from both ends is
//! periodic: a step later the CoM is shifted by `sl` in x and mirrored in y.

use crate::error::{GaitError, err};
use twinloop_reduced::lipm::{self, LipmPhase};

/// The most samples one plan is sampled at: 10 million, 2.8 h at 1 ms (the CLI's bound
/// on any command's rows, issue 29), some 1 GB of samples.
pub const MAX_SAMPLES: usize = 10_000_000;

/// Which foot bears the robot.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Foot {
    Right,
    Left,
}

/// The phase of the gait at a time.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Phase {
    /// Standing on both feet at the start or end.
    Standing,
    /// Double support: the ZMP moves from one foot to the next.
    Double,
    /// Single support on one foot.
    Single(Foot),
}

impl Phase {
    /// The seed's phase code: 0 single support, 1 double support (standing included).
    pub fn code(self) -> u8 {
        match self {
            Phase::Single(_) => 0,
            Phase::Double | Phase::Standing => 1,
        }
    }
}

/// A footstep plan and the pendulum (seed 002, section 2.4).
#[derive(Debug, Clone, PartialEq)]
pub struct GaitPlan {
    /// Step length sl, m (the seed: 0.03).
    pub step_length: f64,
    /// Single-support duration Tss, s (the seed: 0.5).
    pub t_single: f64,
    /// Double-support duration Tdb, s (the seed: 0.2).
    pub t_double: f64,
    /// Lateral distance between the foot centres, m.
    pub step_width: f64,
    /// Number of swings N (at least 1).
    pub steps: usize,
    /// CoM height Zc, m.
    pub com_height: f64,
    /// Gravity g, m/s^2.
    pub gravity: f64,
    /// Standing time before the first step, s.
    pub t_start: f64,
    /// Standing time after the last step, s.
    pub t_end: f64,
    /// Foot sole length (x) and width (y), m, for the support polygon.
    pub foot_length: f64,
    pub foot_width: f64,
}

impl Default for GaitPlan {
    /// The seed's gait (sl 0.03 m, Tss 0.5 s, Tdb 0.2 s) with COMAN-like dimensions.
    fn default() -> Self {
        GaitPlan {
            step_length: 0.03,
            t_single: 0.5,
            t_double: 0.2,
            step_width: 0.14,
            steps: 10,
            com_height: 0.5,
            gravity: twinloop_description::GRAVITY,
            t_start: 1.0,
            t_end: 1.0,
            foot_length: 0.2,
            foot_width: 0.1,
        }
    }
}

impl GaitPlan {
    /// Checks every field; the error names the field at fault.
    pub fn validate(&self) -> Result<(), GaitError> {
        let finite = [
            ("step length", self.step_length),
            ("step width", self.step_width),
        ];
        for (name, value) in finite {
            if !value.is_finite() {
                return err(format!("{name} must be finite, got {value}"));
            }
        }
        let positive = [
            ("single-support duration Tss", self.t_single),
            ("double-support duration Tdb", self.t_double),
            ("CoM height Zc", self.com_height),
            ("gravity g", self.gravity),
            ("foot length", self.foot_length),
            ("foot width", self.foot_width),
        ];
        for (name, value) in positive {
            if !(value.is_finite() && value > 0.0) {
                return err(format!("{name} must be positive and finite, got {value}"));
            }
        }
        for (name, value) in [("start time", self.t_start), ("end time", self.t_end)] {
            if !(value.is_finite() && value >= 0.0) {
                return err(format!(
                    "{name} must be non-negative and finite, got {value}"
                ));
            }
        }
        if self.steps == 0 {
            return err("number of steps must be at least 1");
        }
        if self.steps > 1_000_000 {
            return err(format!(
                "number of steps {} is unreasonably large",
                self.steps
            ));
        }
        Ok(())
    }

    /// Pendulum time constant Tc = sqrt(Zc / g) (seed 002 eq 12).
    pub fn time_constant(&self) -> f64 {
        lipm::time_constant(self.com_height, self.gravity)
    }

    /// Footprint centre of swing `j` (j = 0: the right foot's start, j = -1 would be the
    /// left foot's start): x = j sl, left for odd j.
    fn footprint(&self, j: usize) -> [f64; 2] {
        let side = if j % 2 == 1 { 0.5 } else { -0.5 };
        [j as f64 * self.step_length, side * self.step_width]
    }
}

/// One phase of the piecewise-linear ZMP with its closed-form CoM solution per axis.
#[derive(Debug, Clone, PartialEq)]
struct Segment {
    t0: f64,
    t1: f64,
    phase: Phase,
    /// The pendulum on this phase, x and y.
    axes: [LipmPhase; 2],
    /// Support feet (centres) for the support polygon.
    feet: Vec<[f64; 2]>,
}

/// The ZMP reference and the LIPM CoM reference of a plan.
#[derive(Debug, Clone, PartialEq)]
pub struct ZmpReference {
    plan: GaitPlan,
    tc: f64,
    segments: Vec<Segment>,
}

/// The references at one time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ZmpSample {
    pub t: f64,
    pub phase: Phase,
    /// ZMP reference (x, y), m.
    pub zmp: [f64; 2],
    /// CoM reference position (x, y, z = Zc), m.
    pub com: [f64; 3],
    /// CoM reference velocity (x, y), m/s.
    pub vel: [f64; 2],
    /// CoM reference acceleration (x, y), m/s^2.
    pub acc: [f64; 2],
}

/// One phase of the ZMP plan before the pendulum is solved on it: duration, phase, ZMP
/// at its start and end, support footprints.
struct Piece {
    duration: f64,
    phase: Phase,
    from: [f64; 2],
    to: [f64; 2],
    feet: Vec<[f64; 2]>,
}

/// The phases of a plan (see the module documentation): standing, the first double
/// support, then single support on each support foot and double support to the next,
/// ending between the last two feet.
fn plan_pieces(plan: &GaitPlan) -> Vec<Piece> {
    let piece = |duration, phase, from, to, feet| Piece {
        duration,
        phase,
        from,
        to,
        feet,
    };
    let mut pieces = Vec::new();
    let right0 = plan.footprint(0);
    let left0 = [0.0, 0.5 * plan.step_width];
    let mid0 = [0.0, 0.0];
    // support foot during swing j (1-based): j = 1 the right foot at start, else F_{j-1}
    let support = |j: usize| {
        if j == 1 {
            right0
        } else {
            plan.footprint(j - 1)
        }
    };
    let side = |j: usize| if j % 2 == 1 { Foot::Right } else { Foot::Left };
    if plan.t_start > 0.0 {
        let feet = vec![right0, left0];
        pieces.push(piece(plan.t_start, Phase::Standing, mid0, mid0, feet));
    }
    let feet = vec![right0, left0];
    pieces.push(piece(plan.t_double, Phase::Double, mid0, support(1), feet));
    for j in 1..=plan.steps {
        let s = support(j);
        pieces.push(piece(plan.t_single, Phase::Single(side(j)), s, s, vec![s]));
        let landed = plan.footprint(j);
        if j < plan.steps {
            let next = support(j + 1);
            pieces.push(piece(
                plan.t_double,
                Phase::Double,
                s,
                next,
                vec![s, landed],
            ));
        } else {
            let mid = [0.5 * (s[0] + landed[0]), 0.5 * (s[1] + landed[1])];
            pieces.push(piece(plan.t_double, Phase::Double, s, mid, vec![s, landed]));
            if plan.t_end > 0.0 {
                let feet = vec![s, landed];
                pieces.push(piece(plan.t_end, Phase::Standing, mid, mid, feet));
            }
        }
    }
    pieces
}

/// The pieces laid end to end in time, each with the pendulum of time constant `tc`
/// on its linear ZMP (coefficients not yet fitted).
fn timed_segments(pieces: Vec<Piece>, tc: f64) -> Vec<Segment> {
    let mut segments = Vec::with_capacity(pieces.len());
    let mut t = 0.0;
    for piece in pieces {
        let (t0, t1) = (t, t + piece.duration);
        let axis = |k: usize| {
            let slope = (piece.to[k] - piece.from[k]) / piece.duration;
            LipmPhase::new(tc, t1 - t0, piece.from[k], slope)
        };
        segments.push(Segment {
            t0,
            t1,
            phase: piece.phase,
            axes: [axis(0), axis(1)],
            feet: piece.feet,
        });
        t = t1;
    }
    segments
}

/// Fits every phase's pendulum to the plan's boundary conditions (seed 002 eq 12-13):
/// `xi(T) = p(T)` at the end, carried backwards on the divergent component, then
/// `x(0) = p(0)` at the start, carried forwards on the position.
/// An empty plan has no boundary to fit (a validated plan has at least one segment).
fn fit_boundary_conditions(segments: &mut [Segment]) {
    let Some(end) = segments.last().map(|s| s.axes) else {
        return;
    };
    for (k, last) in end.iter().enumerate() {
        let mut xi = last.zmp(last.duration);
        for seg in segments.iter_mut().rev() {
            xi = seg.axes[k].fit_end_divergent_component(xi);
        }
        let mut x = segments[0].axes[k].p0;
        for seg in segments.iter_mut() {
            x = seg.axes[k].fit_start_position(x);
        }
    }
}

impl ZmpReference {
    /// Builds the ZMP reference of a plan and solves the LIPM exactly (seed 002, eq 12-13;
    /// the formulation is in the module documentation).
    pub fn new(plan: &GaitPlan) -> Result<ZmpReference, GaitError> {
        plan.validate()?;
        let tc = plan.time_constant();
        let mut segments = timed_segments(plan_pieces(plan), tc);
        fit_boundary_conditions(&mut segments);
        Ok(ZmpReference {
            plan: plan.clone(),
            tc,
            segments,
        })
    }

    pub fn plan(&self) -> &GaitPlan {
        &self.plan
    }

    /// Pendulum time constant Tc = sqrt(Zc/g), s.
    pub fn time_constant(&self) -> f64 {
        self.tc
    }

    /// Total duration of the plan, s.
    pub fn duration(&self) -> f64 {
        self.segments.last().map_or(0.0, |s| s.t1)
    }

    /// Start times of the phases (and the end time), s.
    pub fn phase_boundaries(&self) -> Vec<f64> {
        let mut out: Vec<f64> = self.segments.iter().map(|s| s.t0).collect();
        out.push(self.duration());
        out
    }

    /// CoM velocity at t = 0 (x, y), m/s: small, see the module documentation.
    pub fn initial_velocity(&self) -> [f64; 2] {
        self.at(0.0).vel
    }

    fn segment(&self, t: f64) -> &Segment {
        let i = self.segments.partition_point(|s| s.t1 <= t);
        &self.segments[i.min(self.segments.len() - 1)]
    }

    /// The references at time t (clamped to the plan's span): the ZMP and the LIPM CoM
    /// of seed 002 eq 12-13 on the phase that holds t.
    pub fn at(&self, t: f64) -> ZmpSample {
        let t = t.clamp(0.0, self.duration());
        let seg = self.segment(t);
        let tau = t - seg.t0;
        let [x, y] = seg.axes.map(|axis| (axis.zmp(tau), axis.state(tau)));
        ZmpSample {
            t,
            phase: seg.phase,
            zmp: [x.0, y.0],
            com: [x.1.x, y.1.x, self.plan.com_height],
            vel: [x.1.v, y.1.v],
            acc: [x.1.a, y.1.a],
        }
    }

    /// Samples every `dt` from 0 to the end of the plan, at most [`MAX_SAMPLES`].
    pub fn sample(&self, dt: f64) -> Result<Vec<ZmpSample>, GaitError> {
        if !(dt.is_finite() && dt > 0.0) {
            return err(format!(
                "sample time dt must be positive and finite, got {dt}"
            ));
        }
        // Counted in f64 first: a huge count must not wrap to 0 samples when cast.
        let n = (self.duration() / dt + 1e-9).floor() + 1.0;
        if !n.is_finite() || n > MAX_SAMPLES as f64 {
            return err(format!(
                "the plan lasts {:.4e} s (settle, steps and their phases): {n:.3e} samples at \
                 dt {dt:e} s, more than the {MAX_SAMPLES:e} one plan is sampled at",
                self.duration()
            ));
        }
        Ok((0..n as usize).map(|i| self.at(i as f64 * dt)).collect())
    }

    /// Signed distance (m) of the ZMP reference from the edge of the support polygon at
    /// time t: positive inside. The polygon is the convex hull of the support feet's
    /// soles (foot_length x foot_width rectangles centred on the footprints).
    pub fn support_margin(&self, t: f64) -> f64 {
        let sample = self.at(t);
        let seg = self.segment(sample.t);
        let (hl, hw) = (0.5 * self.plan.foot_length, 0.5 * self.plan.foot_width);
        let mut corners = Vec::with_capacity(4 * seg.feet.len());
        for f in &seg.feet {
            for (sx, sy) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                corners.push([f[0] + sx * hl, f[1] + sy * hw]);
            }
        }
        let hull = convex_hull(corners);
        let p = sample.zmp;
        let mut margin = f64::INFINITY;
        for i in 0..hull.len() {
            let a = hull[i];
            let b = hull[(i + 1) % hull.len()];
            let (ex, ey) = (b[0] - a[0], b[1] - a[1]);
            let len = ex.hypot(ey);
            // counter-clockwise hull: inside is to the left of each edge
            let dist = (ex * (p[1] - a[1]) - ey * (p[0] - a[0])) / len;
            margin = margin.min(dist);
        }
        margin
    }
}

/// Counter-clockwise convex hull (Andrew's monotone chain), collinear points dropped.
fn convex_hull(mut points: Vec<[f64; 2]>) -> Vec<[f64; 2]> {
    points.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    points.dedup();
    if points.len() < 3 {
        return points;
    }
    let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| {
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    };
    let mut hull: Vec<[f64; 2]> = Vec::with_capacity(2 * points.len());
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &[f64; 2]>> = if pass == 0 {
            Box::new(points.iter())
        } else {
            Box::new(points.iter().rev())
        };
        for &p in iter {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0
            {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop();
    }
    hull
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plan(steps: usize) -> GaitPlan {
        GaitPlan {
            steps,
            ..GaitPlan::default()
        }
    }

    #[test]
    fn lipm_holds_along_the_reference_by_finite_differences() {
        // seed 002, eq 12-13: x'' = (g/Zc)(x - p), checked by a Richardson-extrapolated
        // central second difference of the position alone, away from the phase corners
        // (where x''' jumps).
        let r = ZmpReference::new(&plan(6)).unwrap();
        let w = r.plan().gravity / r.plan().com_height;
        let bounds = r.phase_boundaries();
        let h = 2e-3;
        let second = |t: f64, h: f64, k: usize| {
            (r.at(t + h).com[k] - 2.0 * r.at(t).com[k] + r.at(t - h).com[k]) / (h * h)
        };
        let mut worst: f64 = 0.0;
        let mut checked = 0;
        let n = 2000;
        for i in 1..n {
            let t = r.duration() * i as f64 / n as f64;
            if bounds.iter().any(|b| (t - b).abs() < 2.5 * h) {
                continue;
            }
            let s = r.at(t);
            for k in 0..2 {
                let fd = (4.0 * second(t, h / 2.0, k) - second(t, h, k)) / 3.0;
                let lipm = w * (s.com[k] - s.zmp[k]);
                worst = worst.max((fd - lipm).abs());
                // the analytic acceleration is the LIPM's to round-off
                assert!((s.acc[k] - lipm).abs() < 1e-12);
            }
            checked += 1;
        }
        assert!(checked > 1500);
        assert!(worst < 1e-9, "LIPM residual {worst:e}");
    }

    #[test]
    fn com_and_velocity_are_continuous_and_velocity_is_the_derivative() {
        let r = ZmpReference::new(&plan(4)).unwrap();
        for &b in &r.phase_boundaries()[1..r.phase_boundaries().len() - 1] {
            let (l, rr) = (r.at(b - 1e-12), r.at(b + 1e-12));
            for k in 0..2 {
                assert!((l.com[k] - rr.com[k]).abs() < 1e-10);
                assert!((l.vel[k] - rr.vel[k]).abs() < 1e-9);
                assert!((l.acc[k] - rr.acc[k]).abs() < 1e-8, "acc jumps at {b}");
            }
        }
        let h = 1e-5;
        for i in 1..500 {
            let t = r.duration() * i as f64 / 500.0;
            let s = r.at(t);
            for k in 0..2 {
                let fd = (r.at(t + h).com[k] - r.at(t - h).com[k]) / (2.0 * h);
                assert!((fd - s.vel[k]).abs() < 1e-8, "t {t}");
            }
        }
    }

    #[test]
    fn closed_form_matches_cosh_sinh_solution_per_phase() {
        // x(t) = p + (x0 - p0) cosh(t/Tc) + Tc (v0 - s) sinh(t/Tc) within each phase.
        let r = ZmpReference::new(&plan(3)).unwrap();
        let tc = r.time_constant();
        let b = r.phase_boundaries();
        for w in b.windows(2) {
            let s0 = r.at(w[0] + 1e-15);
            for i in 0..=20 {
                let tau = (w[1] - w[0]) * i as f64 / 20.0 * 0.999;
                let s = r.at(w[0] + tau);
                for k in 0..2 {
                    let slope = (s.zmp[k] - s0.zmp[k]) / tau.max(1e-300);
                    let slope = if i == 0 { 0.0 } else { slope };
                    let x = s.zmp[k]
                        + (s0.com[k] - s0.zmp[k]) * (tau / tc).cosh()
                        + tc * (s0.vel[k] - slope) * (tau / tc).sinh();
                    assert!((x - s.com[k]).abs() < 1e-10, "phase at {}", w[0]);
                }
            }
        }
    }

    #[test]
    fn zmp_stays_inside_the_support_polygon() {
        let p = plan(8);
        let r = ZmpReference::new(&p).unwrap();
        let mut min_margin = f64::INFINITY;
        for s in r.sample(1e-3).unwrap() {
            min_margin = min_margin.min(r.support_margin(s.t));
        }
        // single support: ZMP at the sole centre, margin half the width; never less
        assert!(min_margin >= 0.5 * p.foot_width - 1e-12, "{min_margin}");
    }

    #[test]
    fn ends_at_rest_over_the_final_zmp_and_starts_nearly_at_rest() {
        let p = plan(5);
        let r = ZmpReference::new(&p).unwrap();
        let end = r.at(r.duration());
        let final_mid = (p.steps as f64 - 0.5) * p.step_length;
        assert!((end.zmp[0] - final_mid).abs() < 1e-12);
        // xi(T) = p(T): x + Tc x' equals the ZMP at the end
        for k in 0..2 {
            assert!((end.com[k] + r.time_constant() * end.vel[k] - end.zmp[k]).abs() < 1e-12);
        }
        let v0 = r.initial_velocity();
        assert!(v0[0].abs() < 0.01 && v0[1].abs() < 0.01, "{v0:?}");
        assert_eq!(r.at(0.0).com[0], 0.0);
    }

    #[test]
    fn steady_gait_is_symmetric_step_to_step() {
        // Far from the ends, one step later the CoM is shifted by sl in x and mirrored in y.
        let p = plan(24);
        let r = ZmpReference::new(&p).unwrap();
        let period = p.t_single + p.t_double;
        let t0 = p.t_start + p.t_double + 11.0 * period;
        let mut worst: f64 = 0.0;
        for i in 0..200 {
            let t = t0 + period * i as f64 / 200.0;
            let (a, b) = (r.at(t), r.at(t + period));
            worst = worst.max((b.com[0] - a.com[0] - p.step_length).abs());
            worst = worst.max((b.com[1] + a.com[1]).abs());
            worst = worst.max((b.vel[0] - a.vel[0]).abs());
            worst = worst.max((b.vel[1] + a.vel[1]).abs());
        }
        assert!(worst < 1e-9, "asymmetry {worst:e}");
        // and the CoM sways less than the feet
        let s = r.at(t0 + 0.5 * p.t_single);
        assert!(s.com[1].abs() < 0.5 * p.step_width);
    }

    #[test]
    fn bad_plans_are_named() {
        let mut p = plan(3);
        p.com_height = 0.0;
        assert!(ZmpReference::new(&p).unwrap_err().0.contains("CoM height"));
        let mut p = plan(3);
        p.t_single = f64::NAN;
        assert!(ZmpReference::new(&p).unwrap_err().0.contains("Tss"));
        assert!(ZmpReference::new(&plan(0)).unwrap_err().0.contains("steps"));
        let r = ZmpReference::new(&plan(1)).unwrap();
        assert!(r.sample(0.0).is_err());
        assert!(r.sample(-1.0).is_err());
    }
}
