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
//!
//! The same pendulum is seed 002's eq 12-13, `x'' = (x - p) / Tc^2` with the ZMP `p`
//! as input; its closed-form solutions for a ZMP constant or linear in time are here
//! ([`linear_zmp_closed_form`] from an initial state, [`LipmPhase`] for a phase fitted
//! to boundary conditions), so the ZMP references of twinloop-gait plan footsteps and
//! phases without writing the pendulum again.

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

    /// `Tc = sqrt(l / g)`, s: the time in which an unbraked lean grows by a factor e
    /// (seed 000 eq. 1; [`time_constant`]).
    pub fn time_constant(&self) -> f64 {
        time_constant(self.length, self.gravity)
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
    /// `x - p = (x0 - p) cosh(t/Tc) + Tc v0 sinh(t/Tc)` with `p = -M / (m g)` (a
    /// constant ZMP: [`linear_zmp_closed_form`] with no slope).
    pub fn closed_form(&self, x0: f64, v0: f64, moment: f64, t: f64) -> (f64, f64) {
        let p = -moment / (self.mass * self.gravity);
        linear_zmp_closed_form(self.time_constant(), x0, v0, p, 0.0, t)
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

    /// One RK4 step of eq. 1 over `h` with the inputs at the step's start, middle and end.
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
        rk4_step(x, v, h, [&|x| a(x, u0), &|x| a(x, um), &|x| a(x, u1)])
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

/// One classical Runge-Kutta 4 step of a second-order equation `x'' = a(t, x)` from
/// `(x, v)` over `h`, with `accel = [a(t0, .), a(t0 + h/2, .), a(t0 + h, .)]`: the
/// acceleration as a function of position at the step's start, middle and end (the
/// caller fixes the time-dependent inputs there, so inputs that jump between steps are
/// read once per stage time). Shared by the LIPM (seed 000 eq. 1) and the three-mass
/// LIPM (eq. 6-7).
pub(crate) fn rk4_step(x: f64, v: f64, h: f64, accel: [&dyn Fn(f64) -> f64; 3]) -> (f64, f64) {
    let [a0, am, a1] = accel;
    let (k1x, k1v) = (v, a0(x));
    let (k2x, k2v) = (v + 0.5 * h * k1v, am(x + 0.5 * h * k1x));
    let (k3x, k3v) = (v + 0.5 * h * k2v, am(x + 0.5 * h * k2x));
    let (k4x, k4v) = (v + h * k3v, a1(x + h * k3x));
    (
        x + h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x),
        v + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v),
    )
}

/// The pendulum's time constant `Tc = sqrt(height / gravity)`, s (seed 000 eq. 1 with
/// `l` the height; seed 002 eq 12, `Tc = sqrt(Zc / g)`).
pub fn time_constant(height: f64, gravity: f64) -> f64 {
    (height / gravity).sqrt()
}

/// The LIPM `x'' = (x - p) / Tc^2` (seed 000 eq. 1 with `z'' = 0` and the ankle moment
/// placing the ZMP, `M = -m g p`; seed 002 eq 12-13) solved in closed form for a ZMP
/// linear in time, `p(t) = p0 + slope t` (constant: `slope = 0`), from `(x0, v0)` at
/// `t = 0`: position and velocity at `t`,
///
/// ```text
/// x - p = (x0 - p0) cosh(t/Tc) + Tc (v0 - slope) sinh(t/Tc)
/// ```
///
/// (the ramp `p` is itself a solution of the forced pendulum, so only the homogeneous
/// part, in `x - p`, swings).
pub fn linear_zmp_closed_form(
    tc: f64,
    x0: f64,
    v0: f64,
    p0: f64,
    slope: f64,
    t: f64,
) -> (f64, f64) {
    let (s, c) = ((t / tc).sinh(), (t / tc).cosh());
    let p = p0 + slope * t;
    (
        p + (x0 - p0) * c + tc * (v0 - slope) * s,
        slope + (x0 - p0) * s / tc + (v0 - slope) * c,
    )
}

/// One phase of the LIPM `x'' = (x - p) / Tc^2` (seed 002 eq 12-13; seed 000 eq. 1)
/// under a ZMP linear in time, `p(tau) = p0 + slope tau` for `tau` in `[0, duration]`,
/// solved in the exponential basis that boundary-value problems need:
///
/// ```text
/// x(tau) = p(tau) + A exp(-tau/Tc) + B exp((tau - D)/Tc)
/// ```
///
/// With the divergent component of motion `xi = x + Tc x'` the pendulum splits into
/// `xi' = (xi - p) / Tc` (unstable) and `x' = (xi - x) / Tc` (stable): `B` is fixed by
/// `xi` at the phase's end ([`LipmPhase::fit_end_divergent_component`]), `A` by `x`
/// at its start ([`LipmPhase::fit_start_position`]). Each coefficient multiplies an
/// exponential that is at most 1 on the phase, so long phases lose no accuracy
/// (the `cosh`/`sinh` form of [`linear_zmp_closed_form`] would cancel large terms).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LipmPhase {
    /// Pendulum time constant Tc, s.
    pub tc: f64,
    /// Phase length D, s.
    pub duration: f64,
    /// ZMP at the phase start, m, and its rate, m/s.
    pub p0: f64,
    pub slope: f64,
    /// Coefficient A of the decaying mode, m.
    pub decaying: f64,
    /// Coefficient B of the growing mode, m.
    pub growing: f64,
}

/// Position, velocity and acceleration of the pendulum at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LipmState {
    pub x: f64,
    pub v: f64,
    pub a: f64,
}

impl LipmPhase {
    /// A phase with both mode coefficients zero (fit them with the two `fit_` methods).
    pub fn new(tc: f64, duration: f64, p0: f64, slope: f64) -> LipmPhase {
        LipmPhase {
            tc,
            duration,
            p0,
            slope,
            decaying: 0.0,
            growing: 0.0,
        }
    }

    /// The ZMP at `tau` into the phase.
    pub fn zmp(&self, tau: f64) -> f64 {
        self.p0 + self.slope * tau
    }

    /// `exp(-D/Tc)`: how much each mode shrinks over the phase.
    fn decay(&self) -> f64 {
        (-self.duration / self.tc).exp()
    }

    /// Sets `B` so that the divergent component at the phase's end is `xi_end`,
    /// `B = (xi(D) - p(D) - Tc slope) / 2`, and returns the divergent component at the
    /// phase's start, `xi(0) = p0 + Tc slope + 2 B exp(-D/Tc)`: a backward pass over
    /// consecutive phases carries `xi` from a final condition to the start.
    pub fn fit_end_divergent_component(&mut self, xi_end: f64) -> f64 {
        let p1 = self.zmp(self.duration);
        self.growing = 0.5 * (xi_end - p1 - self.tc * self.slope);
        self.p0 + self.tc * self.slope + 2.0 * self.growing * self.decay()
    }

    /// Sets `A` so that the position at the phase's start is `x_start` (with `B`
    /// already fitted), `A = x(0) - p0 - B exp(-D/Tc)`, and returns the position at the
    /// phase's end, `x(D) = p(D) + A exp(-D/Tc) + B`: a forward pass carries `x` on.
    pub fn fit_start_position(&mut self, x_start: f64) -> f64 {
        let decay = self.decay();
        self.decaying = x_start - self.p0 - self.growing * decay;
        self.p0 + self.slope * self.duration + self.decaying * decay + self.growing
    }

    /// Position, velocity and acceleration at `tau` into the phase:
    /// `x = p + h`, `x' = slope + (B e+ - A e-) / Tc`, `x'' = h / Tc^2` with
    /// `h = A e- + B e+`, `e- = exp(-tau/Tc)`, `e+ = exp((tau - D)/Tc)`.
    pub fn state(&self, tau: f64) -> LipmState {
        let em = (-tau / self.tc).exp();
        let ep = ((tau - self.duration) / self.tc).exp();
        let h = self.decaying * em + self.growing * ep;
        LipmState {
            x: self.zmp(tau) + h,
            v: self.slope + (self.growing * ep - self.decaying * em) / self.tc,
            a: h / (self.tc * self.tc),
        }
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
