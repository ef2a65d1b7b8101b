//! The tip-over experiment on a robot over its Dynamixel bus (`twinloop experiment
//! tipover --port --map`, what `adapt --port` and `demo` run, and the Python package's
//! `tipover(port=...)`): the study's protocol (each direction twice, the second time
//! creeping up to the tip) through nothing but the servos' registers and the IMU
//! board, on a [`Guarded`] robot; four directions give the same JSON as the
//! simulator's study ([`report_for_runs`]).

use crate::IdentError;
use crate::tipover_study::{StudyReport, TiltModel, report_for_runs};
use serde::Serialize;
use twinloop_description::Description;
use twinloop_experiments::guarded::Guarded;
use twinloop_experiments::stiffen::{
    check_stiffenable, restore_loops, save_loops, stiffen_for_lean,
};
use twinloop_experiments::tipover::{Direction, TipoverConfig, TipoverResult, run_direction, tilt};
use twinloop_robot::{Robot, RobotError, RobotState};

/// How the experiment runs over the bus.
#[derive(Debug, Clone)]
pub struct BusTipoverOptions {
    pub directions: Vec<Direction>,
    /// The second run's creep over the last degrees, deg/s.
    pub slow_ramp: f64,
    /// How stiff the servos that hold the pose are made, as an RX Compliance Slope
    /// (2: stiffest); every family through the servo catalogue
    /// (`twinloop_experiments::stiffen`).
    pub compliance_slope: i32,
    /// The same for the joints a direction ramps (see [`ANKLE_SLOPE`]).
    pub ankle_slope: i32,
    /// Leave every servo as it is (no stiffening, nothing restored): the run is
    /// marked soft in every output. Without it a servo model with no known way to
    /// stiffen stops the run before anything moves.
    pub soft_servos: bool,
    /// Creeping approaches per direction (at least 1); with two or more, the two that
    /// agree best are averaged, and one more is made when they differ by more than
    /// [`creeps_agree_deg`] (see [`combine_creeps`]).
    pub creeps: usize,
    /// Commanded tip angles known beforehand, deg, one per direction in `directions`'
    /// order: no first ramp, the creeps start [`SLOW_MARGIN_DEG`] before each. How an
    /// adapted model's simulation is checked against the robot's measurement: the
    /// same protocol from the same start.
    pub first_tips: Option<Vec<f64>>,
    /// Send the turned joints' goals dithered (`DynamixelRobot::set_dithered`): the
    /// lean then grows smoothly instead of in whole-count steps.
    pub dither: bool,
    /// A creep's tip is the mean reading over this long up to its onset, s of robot
    /// time (`TipoverConfig::onset_average_s`; [`ONSET_AVERAGE_S`]).
    pub onset_average_s: f64,
}

/// One direction over the bus.
#[derive(Debug, Clone, Serialize)]
pub struct BusDirection {
    pub commanded_deg: f64,
    pub measured_deg: f64,
    pub time_s: f64,
    pub excess_deg: f64,
    pub lean_deg: f64,
}

/// The directions run when not all four were asked for.
#[derive(Debug, Clone, Serialize)]
pub struct BusReport {
    pub robot: String,
    pub port: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub forward: Option<BusDirection>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub backward: Option<BusDirection>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub left: Option<BusDirection>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub right: Option<BusDirection>,
    /// The servos were left as they were (`--soft-servos`): not stiffened, the
    /// angles include the servos' give.
    pub soft_servos: bool,
    /// How the bus held up (retries, discarded packets, reads repeated).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bus: Option<twinloop_experiments::guarded::BusHealth>,
}

/// What a run over the bus gave.
#[derive(Debug, Clone)]
pub enum BusOutcome {
    /// All four directions: the study's report (static references and CoM from the
    /// model, `com.true` being the model's CoM).
    Study(Box<StudyReport>),
    Partial(Box<BusReport>),
}

/// The report of `runs`: the study's when all four directions ran, else each
/// direction's angles.
pub fn bus_outcome(
    model: &Description,
    model_spec: &str,
    port: &str,
    runs: &[TipoverResult],
    joint_names: &[String],
    soft_servos: bool,
) -> Result<BusOutcome, IdentError> {
    if runs.len() == 4 {
        return Ok(BusOutcome::Study(Box::new(report_for_runs(
            model,
            runs,
            joint_names,
        )?)));
    }
    let mut r = BusReport {
        robot: model_spec.to_string(),
        port: port.to_string(),
        forward: None,
        backward: None,
        left: None,
        right: None,
        soft_servos,
        bus: None,
    };
    for run in runs {
        let d = Some(BusDirection {
            commanded_deg: run.commanded_deg,
            measured_deg: run.measured_deg,
            time_s: run.time_s,
            excess_deg: run.excess_deg,
            lean_deg: run.lean_deg,
        });
        match run.direction {
            Direction::Forward => r.forward = d,
            Direction::Backward => r.backward = d,
            Direction::Left => r.left = d,
            Direction::Right => r.right = d,
        }
    }
    Ok(BusOutcome::Partial(Box::new(r)))
}

/// The feet's roll at a creep's onset beyond which the creep is spoiled (a reading
/// taken across a fall the host did not see, a jolt), deg: a foot rolls onto its
/// edge by a few degrees before the robot tips; the exact method refuses 0.2 rad.
const SPOILED_EXCESS_DEG: f64 = 10.0;
/// Spoiled creeps in one direction after which the run stops.
const MAX_SPOILED_CREEPS: usize = 3;

/// Trunk tilt within which the robot counts as standing again, deg, and for how long
/// it must stay there, s of robot time.
const UPRIGHT_DEG: f64 = 3.0;
const UPRIGHT_HOLD_S: f64 = 1.0;
/// How far before the first run's tip the second run starts to creep, deg: more than
/// the simulator's half degree, because over a bus the first run's detection lags by a
/// cycle or more and the robot must not tip before the creep begins.
const SLOW_MARGIN_DEG: f64 = 1.5;
/// How far before the last creep's tip a repeated creep starts, deg: that creep saw the
/// tip within a fraction of a degree.
const REPEAT_MARGIN_DEG: f64 = 0.6;
/// Two creeps that tip within this many degrees of each other agree: about the
/// scatter of creeps on the virtual robot. Read at one sample, twice the ankle's
/// encoder count (0.29 deg on an RX); read over a window up to the onset
/// (`onset_average_s` > 0), two creeps mostly read within 0.01-0.06 deg and now and
/// then 0.15-0.4 apart, one of them spoiled (a stalled cycle, a jolt): 0.2 deg.
pub fn creeps_agree_deg(onset_average_s: f64) -> f64 {
    if onset_average_s > 0.0 { 0.2 } else { 0.6 }
}
/// How long a creep's tip reading is averaged up to its onset, s of robot time: about
/// a period of the rocking on the sole edges (1-1.5 s on km20), so that the ankles'
/// flips between two counts average out. Measured over the pty (docs/adaptation.md):
/// the onset sample alone read the same creep a count apart from run to run.
pub const ONSET_AVERAGE_S: f64 = 1.0;
/// How long a person (or the virtual robot's operator) has to stand the robot up, s.
const STAND_UP_TIMEOUT_S: f64 = 120.0;

/// Direction names (forward, backward, left, right); all four when `list` is empty.
pub fn parse_directions(list: &[String]) -> Result<Vec<Direction>, IdentError> {
    if list.is_empty() {
        return Ok(Direction::ALL.to_vec());
    }
    list.iter()
        .map(|s| {
            Direction::ALL
                .into_iter()
                .find(|d| d.name() == s.trim())
                .ok_or_else(|| {
                    IdentError::new(format!("\"{s}\" is not forward, backward, left or right"))
                })
        })
        .collect()
}

/// The trunk's (pitch, roll) from the IMU, rad.
fn trunk_tilt(st: &RobotState) -> Option<(f64, f64)> {
    st.imu.and_then(|i| i.orientation).map(tilt)
}

/// Hold the standing pose until the robot stands again: its trunk within
/// [`UPRIGHT_DEG`] of `upright` for [`UPRIGHT_HOLD_S`]. A person stands a fallen
/// robot up (the virtual robot's operator does it by itself); a robot caught before
/// it fell is standing already.
fn wait_upright(
    g: &mut Guarded<'_>,
    standing: &[f64],
    upright: (f64, f64),
    period: f64,
) -> Result<(), RobotError> {
    let mut st = RobotState::default();
    let t0 = g.time();
    let mut since: Option<f64> = None;
    loop {
        g.command_positions(standing)?;
        g.advance(period)?;
        g.read(&mut st)?;
        let now = g.time();
        let ok = trunk_tilt(&st).is_some_and(|(p, r)| {
            (p - upright.0).abs().max((r - upright.1).abs()) < UPRIGHT_DEG.to_radians()
        });
        since = if ok { since.or(Some(now)) } else { None };
        if since.is_some_and(|s| now - s >= UPRIGHT_HOLD_S) {
            return Ok(());
        }
        if now - t0 > STAND_UP_TIMEOUT_S {
            let (p, r) = trunk_tilt(&st).unwrap_or((f64::NAN, f64::NAN));
            return Err(g.fail(format!(
                "the robot did not stand up again within {STAND_UP_TIMEOUT_S} s (trunk pitch {:.1} deg, roll {:.1} deg)",
                p.to_degrees(),
                r.to_degrees()
            )));
        }
    }
}

/// The ramped ankles' RX Compliance Slope over the bus: the factory value (RX only:
/// MX and X ankles are as stiff as the rest, `twinloop_experiments::stiffen::ramped_slope`). Goal
/// positions are whole counts (0.29 deg), so the ramp is a staircase; a servo at the
/// stiffest slope takes each count as a jolt, and a robot on the edge of its soles
/// tips up to a degree early (measured over the pty: forward and backward 1.1 deg
/// early at slope 2, within the count at 32). The hip rolls that turn with the ankle
/// rolls sideways stay stiff: soft, they let the legs' parallelogram shear and the
/// robot tips 3-4 deg early.
pub const ANKLE_SLOPE: i32 = 32;

/// The ankle joints a lean in `d` ramps.
fn ramped_ankles(cfg: &TipoverConfig, d: Direction) -> [usize; 2] {
    if d.is_pitch() {
        cfg.ankle_pitch
    } else {
        cfg.ankle_roll
    }
}

/// Each direction twice, as the study: a first ramp finds the tip, a second comes up
/// to [`SLOW_MARGIN_DEG`] before it and creeps; the robot stood up before each run.
///
/// `before(direction, k)` runs before each direction (the CLI asks a person on a
/// serial port to stand the robot up after the first); `log` hears what happens. An
/// error stops the run; the caller leaves the servos holding ([`hold_standing`]).
///
/// Unless `opts.soft_servos`, every servo is made stiff through the catalogue, and
/// the loop registers found before are written back at the end, on success and on
/// error alike.
pub fn run_directions(
    g: &mut Guarded<'_>,
    opts: &BusTipoverOptions,
    cfg: &TipoverConfig,
    tilt_model: &mut TiltModel,
    before: &mut dyn FnMut(Direction, usize) -> Result<(), IdentError>,
    log: &mut dyn FnMut(&str),
) -> Result<Vec<TipoverResult>, IdentError> {
    if opts.soft_servos {
        log("servos soft: left at their present settings (--soft-servos)");
        return lean_each(g, opts, cfg, tilt_model, before, log);
    }
    check_stiffenable(g.robot.mapping()).map_err(|e| e.message)?;
    let saved = save_loops(g.robot, g.silence_window).map_err(|e| e.message)?;
    let out = lean_each(g, opts, cfg, tilt_model, before, log);
    let restored = restore_loops(g.robot, &saved);
    match (out, restored) {
        (Ok(out), Ok(())) => Ok(out),
        (Ok(_), Err(e)) => Err(IdentError::new(format!(
            "restoring the servos' loop registers: {}",
            e.message
        ))),
        (Err(e), Ok(())) => Err(e),
        (Err(e), Err(r)) => Err(IdentError::new(format!(
            "{e} (and restoring the servos' loop registers failed: {})",
            r.message
        ))),
    }
}

/// [`run_directions`] after the stiffening.
fn lean_each(
    g: &mut Guarded<'_>,
    opts: &BusTipoverOptions,
    cfg: &TipoverConfig,
    tilt_model: &mut TiltModel,
    before: &mut dyn FnMut(Direction, usize) -> Result<(), IdentError>,
    log: &mut dyn FnMut(&str),
) -> Result<Vec<TipoverResult>, IdentError> {
    let standing = &vec![0.0; g.robot.mapping().joints.len()][..];
    // Upright is the trunk's tilt the model gives standing with the feet flat (the
    // robot's first readings may still rock from the stiffening).
    // (`tilt` counts roll the other way: positive leaning right.)
    let t = tilt_model.predict(Direction::Forward, standing);
    let upright = (t[0], -t[1]);
    let mut out = Vec::with_capacity(opts.directions.len());
    for (k, &d) in opts.directions.iter().enumerate() {
        before(d, k)?;
        log(&format!("leaning {} ...", d.name()));
        // Every servo stiff but the two ankles this direction ramps.
        let ankles = ramped_ankles(cfg, d);
        if !opts.soft_servos {
            let slope = |s: i32| s.clamp(1, 255) as u8;
            stiffen_for_lean(
                g.robot,
                slope(opts.compliance_slope),
                slope(opts.ankle_slope),
                |k| ankles.contains(&k),
            )
            .map_err(|e| e.to_string())?;
        }
        if opts.dither {
            let hips = if d.is_pitch() { None } else { cfg.hip_roll };
            g.robot
                .set_dithered(|k| ankles.contains(&k) || hips.is_some_and(|h| h.contains(&k)));
        }
        let mut run =
            |cfg: &TipoverConfig, g: &mut Guarded<'_>| -> Result<TipoverResult, RobotError> {
                wait_upright(g, standing, upright, cfg.period_s)?;
                let mut predict = |q: &[f64]| tilt_model.predict(d, q);
                let r = run_direction(g, standing, d, cfg, Some(&mut predict));
                // The ramp ends at the first sign of tipping (or a fault): the ankles go
                // back to the standing pose at once.
                let _ = g.robot.command_positions(standing);
                r
            };
        let known = opts.first_tips.as_ref().and_then(|t| t.get(k)).copied();
        let first = match known {
            Some(_) => None,
            None => Some(run(cfg, g).map_err(|e| e.message)?),
        };
        let mut slow = cfg.clone();
        slow.slow_ramp_deg_per_s = opts.slow_ramp;
        slow.onset_average_s = opts.onset_average_s;
        let wanted = opts.creeps.max(1);
        let agree_deg = creeps_agree_deg(opts.onset_average_s);
        let mut creeps: Vec<TipoverResult> = Vec::with_capacity(wanted + 1);
        let mut spoiled = 0;
        let start = first
            .as_ref()
            .map_or(known.unwrap_or(0.0), |f| f.commanded_deg)
            - SLOW_MARGIN_DEG;
        loop {
            // A repeat starts closer (the last creep saw the tip finely), never earlier
            // than the first creep did.
            let from = creeps
                .last()
                .map_or(start, |c| (c.commanded_deg - REPEAT_MARGIN_DEG).max(start));
            slow.slow_from_deg = Some(from.max(0.0));
            let r = run(&slow, g).map_err(|e| e.message)?;
            if r.excess_deg.abs() > SPOILED_EXCESS_DEG {
                spoiled += 1;
                log(&format!(
                    "  {}: a creep read the feet rolled {:.1} deg at its onset, beyond the \
                     {SPOILED_EXCESS_DEG} deg a foot can roll standing: spoiled ({spoiled} of at most \
                     {MAX_SPOILED_CREEPS}), repeated",
                    d.name(),
                    r.excess_deg
                ));
                if spoiled >= MAX_SPOILED_CREEPS {
                    return Err(format!(
                        "{}: {spoiled} creeps spoiled (feet rolled beyond {SPOILED_EXCESS_DEG} \
                         deg at the onset): the IMU or the bus is not giving usable readings",
                        d.name()
                    )
                    .into());
                }
                continue;
            }
            log(&format!(
                "  {}: creep {} tipped at {:.2} deg",
                d.name(),
                creeps.len() + 1,
                r.measured_deg
            ));
            creeps.push(r);
            let n = creeps.len();
            let agree = n < 2 || combine_creeps(&creeps).1 <= agree_deg;
            if n >= wanted && (agree || n > wanted) {
                break;
            }
        }
        let (mut r, spread) = combine_creeps(&creeps);
        if creeps.len() > 1 && spread > agree_deg {
            log(&format!(
                "  {}: the creeps disagree by {spread:.2} deg at best; taking the closest two",
                d.name()
            ));
        }
        let whence = match &first {
            Some(first) => {
                r.time_s = first.time_s;
                format!("first ramp {:.2} deg", first.measured_deg)
            }
            None => format!(
                "creeping from the known tip, commanded {:.2} deg",
                known.unwrap_or(0.0)
            ),
        };
        log(&format!(
            "  {}: tipped at {:.2} deg ({whence}, {} creep(s))",
            d.name(),
            r.measured_deg,
            creeps.len()
        ));
        out.push(r);
        g.robot.set_dithered(|_| false);
    }
    wait_upright(g, standing, upright, cfg.period_s).map_err(|e| e.message)?;
    Ok(out)
}

/// One result from a direction's creeps and how far apart the two that agree best
/// are, deg (0 for one creep): the mean of that pair (angles, onset posture, lean),
/// so that one creep spoiled by a jolt or a stalled cycle does not decide the angle.
pub fn combine_creeps(creeps: &[TipoverResult]) -> (TipoverResult, f64) {
    let mut best = (0, 0, f64::INFINITY);
    for i in 0..creeps.len() {
        for j in i + 1..creeps.len() {
            let d = (creeps[i].measured_deg - creeps[j].measured_deg).abs();
            if d < best.2 {
                best = (i, j, d);
            }
        }
    }
    if creeps.len() < 2 {
        return (creeps[0].clone(), 0.0);
    }
    let (a, b) = (&creeps[best.0], &creeps[best.1]);
    let mean = |x: f64, y: f64| 0.5 * (x + y);
    let r = TipoverResult {
        direction: a.direction,
        commanded_deg: mean(a.commanded_deg, b.commanded_deg),
        measured_deg: mean(a.measured_deg, b.measured_deg),
        time_s: mean(a.time_s, b.time_s),
        fall_confirmed_s: mean(a.fall_confirmed_s, b.fall_confirmed_s),
        excess_deg: mean(a.excess_deg, b.excess_deg),
        lean_deg: mean(a.lean_deg, b.lean_deg),
        positions_at_onset: a
            .positions_at_onset
            .iter()
            .zip(&b.positions_at_onset)
            .map(|(x, y)| mean(*x, *y))
            .collect(),
    };
    (r, best.2)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn creep(measured: f64, onset: f64) -> TipoverResult {
        TipoverResult {
            direction: Direction::Left,
            commanded_deg: measured - 1.0,
            measured_deg: measured,
            time_s: 10.0,
            fall_confirmed_s: 11.0,
            excess_deg: 0.2,
            lean_deg: 4.0,
            positions_at_onset: vec![onset, -onset],
        }
    }

    #[test]
    fn the_two_creeps_that_agree_best_are_averaged() {
        let (one, spread) = combine_creeps(&[creep(20.0, 0.3)]);
        assert_eq!((one.measured_deg, spread), (20.0, 0.0));
        // A jolt tipped the second creep 2.3 deg early: the other two count.
        let (r, spread) = combine_creeps(&[creep(20.0, 0.3), creep(17.7, 0.1), creep(20.3, 0.5)]);
        assert!((spread - 0.3).abs() < 1e-12, "{spread}");
        assert!((r.measured_deg - 20.15).abs() < 1e-12);
        assert!((r.commanded_deg - 19.15).abs() < 1e-12);
        assert!((r.positions_at_onset[0] - 0.4).abs() < 1e-12);
        assert!((r.positions_at_onset[1] + 0.4).abs() < 1e-12);
    }
}
