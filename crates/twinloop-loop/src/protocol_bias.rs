//! Adapting to the protocol, not only to the statics (`demo`, `adapt
//! --protocol-passes`): the bus tip-over does not read a robot's static tipping
//! angles exactly (each goal count is a jolt to soft ankles on the edge of their
//! soles, the readings are whole counts), and how far it reads past them (its bias)
//! depends on the robot. So the adapted model's own measurement is simulated: the
//! protocol the robot was measured by (`StudyReport::protocol`), from the same
//! commanded starts, on the adapted model stepped in lockstep with its host
//! ([`crate::tipover_bus::tipover_in_lockstep`], the robot run's host cycle). What it reads minus the
//! model's static angles at the robot's onsets is the bias; the model is adapted again
//! to the robot's angles less that bias (`AdaptOptions::protocol_bias_deg`), and the
//! last pass is kept. docs/adaptation.md has the measurements.

use crate::LoopError;
use crate::bus_plan::BusPlan;
use crate::floor_fit::{FloorFit, fit_floor, sideways_mean};
use crate::tipover_bus::{BusOutcome, tipover_in_lockstep_with};
use serde::Serialize;
use twinloop_description::Description;
use twinloop_experiments::tipover::Direction;
use twinloop_ident::IdentError;
use twinloop_ident::adapt::{AdaptOptions, Adapted, adapt};
use twinloop_ident::tipover_study::{BusProtocol, StudyReport, static_angles_at_onsets};
use twinloop_virtual::VirtualRobotOptions;

/// How the protocol measured the adapted model, pass by pass (the JSON's
/// `calibration`).
#[derive(Debug, Clone, Serialize)]
pub struct Calibration {
    /// The protocol ran at the host cycle the tip-over's `protocol.cycle_s` keeps.
    pub passes: Vec<CalibrationPass>,
    /// The pass kept (0-based): the last.
    pub kept: usize,
    /// The floor the passes replayed on, found from the robot's sideways tips.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub floor: Option<FloorFit>,
    /// The floor the passes replayed on when it was found by the feet's roll
    /// ([`crate::other_places`]) rather than by `floor`, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub floor_by_roll_m: Option<f64>,
}

/// One pass (forward, backward, left, right, deg).
#[derive(Debug, Clone, Serialize)]
pub struct CalibrationPass {
    /// The protocol bias the model was fitted with (the previous pass's).
    pub bias_deg: [f64; 4],
    /// The adapted model's static angles at the robot's onsets.
    pub static_deg: [f64; 4],
    /// What the protocol, simulated on the adapted model, read.
    pub protocol_deg: [f64; 4],
    /// The feet's roll at those onsets in the simulation, deg (the robot's is its
    /// tip-over's `excess_deg`): how [`crate::other_places`] tells apart two places
    /// that explain the angles on two floors.
    pub protocol_roll_deg: [f64; 4],
    /// That pass's adapted CoM in the standing frame, m.
    pub adapted_com: Option<[f64; 3]>,
}

/// The simulated robot the protocol runs on: the operator who stands it up between
/// runs, a floor that sinks `ground_sink` m under the robot's weight (the demo's
/// 0.1 mm when the floor is unknown); datasheet servos.
pub fn replay_options(ground_sink: f64) -> VirtualRobotOptions {
    VirtualRobotOptions {
        catch_falls: true,
        ground_sink: Some(ground_sink),
        ..Default::default()
    }
}

/// The floor `adapt` replays the protocol on: the demo's.
pub const REPLAY_GROUND_SINK: f64 = 1e-4;

/// The passes stop once the protocol on the adapted model reads the robot's angles
/// to this, deg: a fifth of the half count two averaged ankles resolve, where each
/// creep's tip is a mean over a window (`BusProtocol::onset_average_s`); a quarter of
/// it where the tip is one sample, a whole count.
fn converged_deg(protocol: &BusProtocol) -> f64 {
    if protocol.onset_average_s > 0.0 {
        0.03
    } else {
        0.08
    }
}

/// One figure of each direction of `r` (forward, backward, left, right).
pub fn angles_of(
    r: &StudyReport,
    f: fn(&twinloop_ident::tipover_study::DirectionReport) -> f64,
) -> [f64; 4] {
    Direction::ALL.map(|d| f(r.direction(d)))
}

/// Four angles, deg, as the demo and the log print them.
pub fn join(v: [f64; 4]) -> String {
    v.map(|a| format!("{a:5.2}")).join(" ")
}

/// How the protocol is simulated on the adapted models.
#[derive(Clone)]
pub struct Replay<'a> {
    /// The host's model of the robot (the prior's spec: the lean signs and the tilt
    /// reference, as on the robot's run).
    pub model_spec: &'a str,
    /// That model, as `model_spec` reads (the prior).
    pub host: &'a Description,
    /// Passes (0: the plain adaptation).
    pub passes: usize,
    /// The simulated robot (its floor the first guess when `fit_floor`).
    pub options: &'a VirtualRobotOptions,
    /// Find the floor the robot stood on from its sideways tips (`floor_fit`), rather
    /// than replay on `options`' floor.
    pub fit_floor: bool,
    /// With the total mass and no host named, also try the part on each link below
    /// the ankles on its side ([`crate::other_places`]); never a confident wrong
    /// answer where the angles fit two places.
    pub other_places: bool,
}

/// The protocol's reading of a model: the four fall angles and the feet's roll at
/// each onset, deg (forward, backward, left, right).
#[derive(Debug, Clone, Copy)]
pub struct Reading {
    pub angles: [f64; 4],
    pub roll: [f64; 4],
}

/// What the protocol `study` was measured by (`study.protocol`, creeping from the
/// robot's commanded tips, `host` read from `model_spec` as the host's model) reads on `model`
/// simulated in lockstep with its host at the robot run's cycle: the four fall angles,
/// deg (forward, backward, left, right).
pub fn protocol_reading(
    study: &StudyReport,
    model_spec: &str,
    host: &Description,
    model: &Description,
    options: &VirtualRobotOptions,
) -> Result<[f64; 4], LoopError> {
    Ok(protocol_reading_with_roll(study, model_spec, host, model, options)?.angles)
}

/// [`protocol_reading`] with the feet's roll at each onset.
pub fn protocol_reading_with_roll(
    study: &StudyReport,
    model_spec: &str,
    host: &Description,
    model: &Description,
    options: &VirtualRobotOptions,
) -> Result<Reading, LoopError> {
    let protocol = study.protocol.as_ref().ok_or_else(|| {
        LoopError::new("the tip-over was not measured over a bus (no `protocol`)")
    })?;
    let commanded = angles_of(study, |d| d.commanded_deg).to_vec();
    let plan = BusPlan::replaying(protocol, model_spec, commanded);
    let run = tipover_in_lockstep_with(&plan, host.clone(), model, options, protocol.cycle_s)?;
    match run.outcome {
        BusOutcome::Study(sim) => Ok(Reading {
            angles: angles_of(&sim, |d| d.measured_deg),
            roll: angles_of(&sim, |d| d.excess_deg),
        }),
        BusOutcome::Partial(_) => Err(LoopError::new("not all four directions ran")),
    }
}

/// [`crate::adaptation::adapt_to_protocol`] with the part on the link the CoM inversion (or `opts.host`)
/// gives.
pub(crate) fn adapt_on_one_place(
    prior: &Description,
    study: &StudyReport,
    opts: &AdaptOptions,
    replay: &Replay<'_>,
    log: &mut dyn FnMut(&str),
    map_err: &(dyn Fn(IdentError) -> LoopError + Sync),
) -> Result<(Adapted, Option<Calibration>), LoopError> {
    adapt_from(prior, study, opts, replay, Start::default(), log, map_err)
}

/// Where a place's passes start: the bias its first pass is fitted with, and the
/// passes already run (another place's bias on the same floor, or this place's own
/// earlier passes: [`crate::other_places`] screens places with one pass and goes on
/// with the best).
#[derive(Debug, Clone, Default)]
pub(crate) struct Start {
    pub bias: [f64; 4],
    pub done: Vec<CalibrationPass>,
}

impl Start {
    /// Where `calibration`'s passes would go on (its last pass's bias), or `None`
    /// when that pass read the robot's angles to [`converged_deg`].
    pub(crate) fn after(calibration: &Calibration, study: &StudyReport) -> Option<Start> {
        let protocol = study.protocol.as_ref()?;
        let p = calibration.passes.last()?;
        let measured = angles_of(study, |d| d.measured_deg);
        let worst = (0..4).fold(0.0_f64, |w, k| {
            w.max((p.protocol_deg[k] - measured[k]).abs())
        });
        (worst >= converged_deg(protocol)).then(|| Start {
            bias: std::array::from_fn(|k| p.protocol_deg[k] - p.static_deg[k]),
            done: calibration.passes.clone(),
        })
    }
}

/// [`adapt_on_one_place`] from `start`: `replay.passes` more passes at most.
pub(crate) fn adapt_from(
    prior: &Description,
    study: &StudyReport,
    opts: &AdaptOptions,
    replay: &Replay<'_>,
    start: Start,
    log: &mut dyn FnMut(&str),
    map_err: &(dyn Fn(IdentError) -> LoopError + Sync),
) -> Result<(Adapted, Option<Calibration>), LoopError> {
    let Some(protocol) = study.protocol.as_ref().filter(|_| replay.passes > 0) else {
        return Ok((adapt(prior, study, opts).map_err(map_err)?, None));
    };
    let mut run = Passes {
        options: replay.options.clone(),
        floor: None,
        done: start.done,
    };
    let mut last = None;
    let mut bias = start.bias;
    for _ in 0..replay.passes {
        let pass_opts = AdaptOptions {
            protocol_bias_deg: Some(bias),
            ..opts.clone()
        };
        let adapted = adapt(prior, study, &pass_opts).map_err(map_err)?;
        if adapted.robot.is_none() {
            // Nothing placed (no --total-mass, nor --where): nothing to simulate.
            return Ok((adapted, None));
        }
        let converged = run.pass(study, replay, &adapted, bias, protocol, log)?;
        last = Some(adapted);
        if converged {
            break;
        }
        let Some(p) = run.done.last() else { break };
        bias = std::array::from_fn(|k| p.protocol_deg[k] - p.static_deg[k]);
    }
    // The last pass is kept: its bias comes from the model nearest the fixed point.
    // (Keeping the pass whose protocol read nearest the robot was tried: the readings
    // move in whole counts, and on seed 4 it kept 4.2 mm of CoM error over 1.9.)
    let adapted = last.ok_or_else(|| LoopError::new("no pass of the adaptation ran"))?;
    Ok(run.finish(adapted))
}

/// The protocol passes of one place as they run.
struct Passes {
    /// The simulated robot, on the floor found once it is.
    options: VirtualRobotOptions,
    floor: Option<FloorFit>,
    done: Vec<CalibrationPass>,
}

impl Passes {
    /// Simulate the protocol on `adapted`'s model (fitted with `bias`), finding the
    /// floor first when the replay fits it; whether the reading is the robot's to
    /// [`converged_deg`].
    fn pass(
        &mut self,
        study: &StudyReport,
        replay: &Replay<'_>,
        adapted: &Adapted,
        bias: [f64; 4],
        protocol: &BusProtocol,
        log: &mut dyn FnMut(&str),
    ) -> Result<bool, LoopError> {
        let model = adapted
            .robot
            .as_ref()
            .ok_or_else(|| LoopError::new("the adapted model has no part placed"))?;
        let read = if replay.fit_floor && self.floor.is_none() {
            let (fit, read) = replay_on_robots_floor(study, replay, model, &self.options)?;
            log(&format!(
                "the floor: the replay tips sideways at {:.2} deg (the robot at {:.2}) on a \
                 floor sinking {:.3} mm ({} replays)",
                sideways_mean(&read.angles),
                fit.measured_sideways_deg,
                fit.sink_m * 1e3,
                fit.tries.len()
            ));
            self.options.ground_sink = Some(fit.sink_m);
            self.floor = Some(fit);
            read
        } else {
            protocol_reading_with_roll(study, replay.model_spec, replay.host, model, &self.options)
                .map_err(|e| e.context("simulating the protocol on the adapted model"))?
        };
        // The model's own static angles at the robot's onsets: the fit may not reach
        // its targets (four angles, three coordinates, a bounded box).
        let statics = static_angles_at_onsets(model, study)?;
        log(&format!(
            "the protocol simulated on the adapted model (pass {}): {} (its statics {})",
            self.done.len() + 1,
            join(read.angles),
            join(statics)
        ));
        self.done.push(CalibrationPass {
            bias_deg: bias,
            static_deg: statics,
            protocol_deg: read.angles,
            protocol_roll_deg: read.roll,
            adapted_com: adapted.report.adapted_com,
        });
        let measured = angles_of(study, |d| d.measured_deg);
        let worst = (0..4).fold(0.0_f64, |w, k| w.max((read.angles[k] - measured[k]).abs()));
        Ok(worst < converged_deg(protocol))
    }

    /// The kept (last) pass's adaptation with the passes and the floor in its notes,
    /// and its `one-part-explains` check made as the floor allows.
    fn finish(self, mut adapted: Adapted) -> (Adapted, Option<Calibration>) {
        let kept = self.done.len() - 1;
        let report = &mut adapted.report;
        report.notes.push(format!(
            "the model was fitted to the measured angles less the protocol's bias {} deg \
             (forward, backward, left, right: the protocol simulated in lockstep on the \
             adapted model minus its static angles; pass {} of {})",
            join(self.done[kept].bias_deg),
            kept + 1,
            self.done.len()
        ));
        if let Some(fit) = &self.floor {
            let tries: Vec<String> = fit
                .tries
                .iter()
                .map(|t| format!("{:.3} mm: {:.2} deg", t.sink_m * 1e3, t.sideways_deg))
                .collect();
            report.notes.push(format!(
                "the protocol was replayed on a floor sinking {:.3} mm under the robot's \
                 weight: the one on which the adapted model tips sideways as the robot did \
                 (left and right mean {:.2} deg; tried {})",
                fit.sink_m * 1e3,
                fit.measured_sideways_deg,
                tries.join(", ")
            ));
            floor_takes_sideways(report);
            report.checks.push(fit.check());
        }
        let calibration = Calibration {
            passes: self.done,
            kept,
            floor: self.floor,
            floor_by_roll_m: None,
        };
        (adapted, Some(calibration))
    }
}

/// On a floor fitted to the robot's sideways tips, the `one-part-explains` check
/// again with the sideways pair's common error left to the floor
/// ([`twinloop_ident::adapt_checks::one_part_explains`]): the floor, found on the first
/// pass's model, moves the sideways mean one for one, and a right answer (an OP3 part
/// 0.68 mm off) was refused for the 0.37 deg it left there.
fn floor_takes_sideways(report: &mut twinloop_ident::adapt::AdaptReport) {
    let Some(fit) = &report.fall_angle_fit else {
        return;
    };
    let check = twinloop_ident::adapt_checks::one_part_explains(
        &fit.residual_deg,
        report.angle_resolution_deg,
        false,
        true,
    );
    for c in report.checks.iter_mut() {
        if c.name == check.name {
            *c = check.clone();
        }
    }
}

/// The protocol on `model` on the floor on which it tips sideways as the robot did
/// ([`fit_floor`], from `options`' floor): the fit and that replay's reading.
fn replay_on_robots_floor(
    study: &StudyReport,
    replay: &Replay<'_>,
    model: &Description,
    options: &VirtualRobotOptions,
) -> Result<(FloorFit, Reading), LoopError> {
    let measured = sideways_mean(&angles_of(study, |d| d.measured_deg));
    let start = options.ground_sink.unwrap_or(REPLAY_GROUND_SINK);
    let mut readings: Vec<(f64, Reading)> = Vec::new();
    let (fit, angles) = fit_floor(measured, start, &mut |sink| {
        let on = VirtualRobotOptions {
            ground_sink: Some(sink),
            ..options.clone()
        };
        let r = protocol_reading_with_roll(study, replay.model_spec, replay.host, model, &on)
            .map_err(|e| e.context("simulating the protocol on the adapted model"))?;
        readings.push((sink, r));
        Ok(r.angles)
    })?;
    // The try kept is the one whose angles came back; its roll with it.
    let roll = readings
        .iter()
        .find(|(_, r)| r.angles == angles)
        .map_or([f64::NAN; 4], |(_, r)| r.roll);
    Ok((fit, Reading { angles, roll }))
}
