//! The linear inverted pendulum (LIPM) of seed 000, section IV.A, eq. 1-3.
//!
//! A point mass `m` on a massless leg from the support ankle, its height kept at `l`
//! (the pendulum length). In the sagittal plane, with `x` the mass's horizontal
//! position relative to the ankle and `M` the ground reaction moment at the ankle:
//!
//! - eq. 1: `m l x'' = m (g + z'') x + M`
//! - eq. 2: `F = m x''` (horizontal ground reaction force)
//! - eq. 3: `dM = l dF`
//!
//! (the seed prints eq. 1 with a stray `*`; dimensionally every term is a moment, N m,
//! which is how it is read here). With `z'' = 0` and `M = 0` the solution is
//! `x(t) = x0 cosh(t/Tc) + Tc v0 sinh(t/Tc)`, `Tc = sqrt(l/g)`.
//!
//! What is simulated: eq. 1 integrated with the classical 4th-order Runge-Kutta method
//! at a fixed step for a given input (ankle moment `M(t)` and vertical acceleration
//! `z''(t)`), from a given state. Two uses are provided: a fall from an initial lean
//! (`M = 0`: the CoM runs away from the ankle) and walking, where the ankle moment
//! places the zero-moment point (ZMP) on the successive footholds,
//! `M = -m (g + z'') p` (from eq. 1: `x'' = (g + z'')/l (x - p)`).

use crate::error::{ReducedError, finite, non_negative, positive};

pub use twinloop_description::GRAVITY;

/// A linear inverted pendulum (seed 000 eq. 1-3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lipm {
    /// Pendulum mass, kg.
    pub mass: f64,
    /// Pendulum length: height of the mass above the ankle, m.
    pub length: f64,
    /// Gravitational acceleration, m/s^2.
    pub gravity: f64,
}

/// The inputs of eq. 1 at one instant.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LipmInput {
    /// Ground reaction moment at the ankle `M`, N m.
    pub moment: f64,
    /// Vertical acceleration of the mass `z''`, m/s^2 (0 for the linear model proper).
    pub vertical_acceleration: f64,
}

/// One sample of a simulation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LipmSample {
    pub t: f64,
    /// Horizontal position of the mass relative to the ankle, m.
    pub x: f64,
    pub xdot: f64,
    /// Acceleration from eq. 1.
    pub xddot: f64,
    /// Horizontal ground reaction force, eq. 2, N.
    pub force: f64,
    /// The input moment `M`, N m.
    pub moment: f64,
    /// Where the input puts the zero-moment point, m from the ankle: `-M / (m (g + z''))`.
    pub zmp: f64,
}

impl Lipm {
    /// A pendulum of `mass` kg at height `length` m, under [`GRAVITY`].
    pub fn new(mass: f64, length: f64) -> Result<Lipm, ReducedError> {
        Ok(Lipm {
            mass: positive("mass", mass)?,
            length: positive("length", length)?,
            gravity: GRAVITY,
        })
    }

    pub fn with_gravity(mut self, gravity: f64) -> Result<Lipm, ReducedError> {
        self.gravity = positive("gravity", gravity)?;
        Ok(self)
    }

    /// `Tc = sqrt(l / g)`, s: the time in which an unbraked lean grows by a factor e.
    pub fn time_constant(&self) -> f64 {
        (self.length / self.gravity).sqrt()
    }

    /// Seed 000 eq. 1 solved for `x''`: `x'' = ((g + z'') x + M / m) / l`.
    pub fn acceleration(&self, x: f64, input: LipmInput) -> f64 {
        ((self.gravity + input.vertical_acceleration) * x + input.moment / self.mass) / self.length
    }

    /// Seed 000 eq. 2: the horizontal ground reaction force `F = m x''`.
    pub fn ground_force(&self, xddot: f64) -> f64 {
        self.mass * xddot
    }

    /// Seed 000 eq. 3: the change of the ground reaction moment that goes with a change
    /// of the ground reaction force, `dM = l dF`.
    pub fn moment_change(&self, force_change: f64) -> f64 {
        self.length * force_change
    }

    /// The ankle moment that puts the ZMP at `zmp` (m from the ankle) with `z'' = 0`:
    /// `M = -m g p`, from eq. 1 written as `x'' = g/l (x - p)`.
    pub fn moment_for_zmp(&self, zmp: f64) -> f64 {
        -self.mass * self.gravity * zmp
    }

    /// The closed-form solution of eq. 1 for a constant moment and `z'' = 0`: position
    /// and velocity at time `t` from `(x0, v0)`:
    /// `x - p = (x0 - p) cosh(t/Tc) + Tc v0 sinh(t/Tc)` with `p = -M / (m g)`.
    pub fn closed_form(&self, x0: f64, v0: f64, moment: f64, t: f64) -> (f64, f64) {
        let tc = self.time_constant();
        let p = -moment / (self.mass * self.gravity);
        let (s, c) = ((t / tc).sinh(), (t / tc).cosh());
        (p + (x0 - p) * c + tc * v0 * s, (x0 - p) * s / tc + v0 * c)
    }

    fn sample(&self, t: f64, x: f64, xdot: f64, input: LipmInput) -> LipmSample {
        let xddot = self.acceleration(x, input);
        LipmSample {
            t,
            x,
            xdot,
            xddot,
            force: self.ground_force(xddot),
            moment: input.moment,
            zmp: -input.moment / (self.mass * (self.gravity + input.vertical_acceleration)),
        }
    }

    /// Integrate eq. 1 from `(x0, v0)` for `duration` s with fixed step `dt` (classical
    /// Runge-Kutta 4); `input(t)` is evaluated at the stage times, so it should be
    /// smooth (for piecewise-constant inputs use [`Lipm::simulate_segments`]). Returns
    /// the samples at `0, dt, 2 dt, ...` up to `duration` (the last step shortened to
    /// land on it).
    pub fn simulate(
        &self,
        x0: f64,
        v0: f64,
        mut input: impl FnMut(f64) -> LipmInput,
        dt: f64,
        duration: f64,
    ) -> Result<Vec<LipmSample>, ReducedError> {
        finite("x0", x0)?;
        finite("v0", v0)?;
        positive("dt", dt)?;
        non_negative("duration", duration)?;
        // Steps on the grid k dt; the last one shortened to land on `duration` (a
        // remainder below 1e-9 dt is round-off of `duration / dt`, not a step).
        let n = ((duration / dt) - 1e-9).ceil().max(0.0) as usize;
        let mut out = Vec::with_capacity(n + 1);
        let (mut t, mut x, mut v) = (0.0, x0, v0);
        out.push(self.sample(t, x, v, input(t)));
        for k in 1..=n {
            let next = if k == n { duration } else { k as f64 * dt };
            let h = next - t;
            let (nx, nv) = self.rk4(x, v, h, input(t), input(t + 0.5 * h), input(next));
            t = next;
            x = nx;
            v = nv;
            check_state(t, x, v)?;
            out.push(self.sample(t, x, v, input(t)));
        }
        Ok(out)
    }

    /// Integrate eq. 1 over consecutive segments, each with a constant input and its
    /// own duration (a walk: one segment per step, the ZMP on that step's foothold).
    /// Each segment is integrated on its own, so the jumps of the input between
    /// segments cost no accuracy; samples every `dt` within a segment and at each
    /// segment's end.
    pub fn simulate_segments(
        &self,
        x0: f64,
        v0: f64,
        segments: &[(f64, LipmInput)],
        dt: f64,
    ) -> Result<Vec<LipmSample>, ReducedError> {
        finite("x0", x0)?;
        finite("v0", v0)?;
        positive("dt", dt)?;
        let mut out = vec![];
        let (mut t0, mut x, mut v) = (0.0, x0, v0);
        for (k, &(duration, input)) in segments.iter().enumerate() {
            non_negative(&format!("segments[{k}].duration"), duration)?;
            finite(&format!("segments[{k}].moment"), input.moment)?;
            finite(
                &format!("segments[{k}].vertical_acceleration"),
                input.vertical_acceleration,
            )?;
            let part = self.simulate(x, v, |_| input, dt, duration)?;
            let skip = usize::from(k > 0);
            for s in &part[skip..] {
                out.push(LipmSample { t: t0 + s.t, ..*s });
            }
            let last = part.last().expect("a simulation has its initial sample");
            x = last.x;
            v = last.xdot;
            t0 += duration;
        }
        Ok(out)
    }

    fn rk4(
        &self,
        x: f64,
        v: f64,
        h: f64,
        u0: LipmInput,
        um: LipmInput,
        u1: LipmInput,
    ) -> (f64, f64) {
        let a = |x: f64, u: LipmInput| self.acceleration(x, u);
        let (k1x, k1v) = (v, a(x, u0));
        let (k2x, k2v) = (v + 0.5 * h * k1v, a(x + 0.5 * h * k1x, um));
        let (k3x, k3v) = (v + 0.5 * h * k2v, a(x + 0.5 * h * k2x, um));
        let (k4x, k4v) = (v + h * k3v, a(x + h * k3x, u1));
        (
            x + h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x),
            v + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v),
        )
    }

    /// A fall from an initial lean: eq. 1 with no ankle moment, from the mass `lean` m
    /// ahead of the ankle at rest.
    pub fn fall(&self, lean: f64, dt: f64, duration: f64) -> Result<Vec<LipmSample>, ReducedError> {
        self.simulate(lean, 0.0, |_| LipmInput::default(), dt, duration)
    }

    /// The initial velocity of the periodic walk of [`Lipm::walk`]: the CoM starts each
    /// step `step_length / 2` behind the foothold and ends it `step_length / 2` ahead
    /// with the same velocity, `v0 = s (1 + cosh(T/Tc)) / (2 Tc sinh(T/Tc))`.
    pub fn periodic_walk_velocity(&self, step_length: f64, step_duration: f64) -> f64 {
        let tc = self.time_constant();
        let r = step_duration / tc;
        step_length * (1.0 + r.cosh()) / (2.0 * tc * r.sinh())
    }

    /// Walking in the sagittal plane: `steps` steps of `step_length` m, each lasting
    /// `step_duration` s, the ZMP held on the support foot (foothold k at
    /// `k step_length`) by the ankle moment of [`Lipm::moment_for_zmp`], starting at
    /// `x = -step_length / 2` with [`Lipm::periodic_walk_velocity`]. `x` is then
    /// measured from the first foothold.
    ///
    /// The LIPM is unstable: any error in the start state (round-off included) grows by
    /// `exp(T/Tc)` per step, so an open-loop walk stays periodic for a handful of steps
    /// only; a real walker closes the loop on the measured CoM.
    pub fn walk(
        &self,
        step_length: f64,
        step_duration: f64,
        steps: usize,
        dt: f64,
    ) -> Result<Vec<LipmSample>, ReducedError> {
        finite("step_length", step_length)?;
        positive("step_duration", step_duration)?;
        let v0 = self.periodic_walk_velocity(step_length, step_duration);
        let segments: Vec<(f64, LipmInput)> = (0..steps)
            .map(|k| {
                (
                    step_duration,
                    LipmInput {
                        moment: self.moment_for_zmp(k as f64 * step_length),
                        vertical_acceleration: 0.0,
                    },
                )
            })
            .collect();
        self.simulate_segments(-0.5 * step_length, v0, &segments, dt)
    }
}

fn check_state(t: f64, x: f64, v: f64) -> Result<(), ReducedError> {
    if x.is_finite() && v.is_finite() {
        Ok(())
    } else {
        Err(ReducedError::new(
            "input",
            format!("the state stopped being finite at t = {t} s (non-finite input?)"),
        ))
    }
}
