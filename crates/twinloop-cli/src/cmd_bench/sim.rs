//! `twinloop bench sim`: microseconds per simulator step of a robot standing on its
//! servos, or following a goal trajectory (the walking case of
//! `bench/mujoco/compare_sim.py`).

use crate::common::{ROBOT_HELP, emit, load_description};
use crate::error::{CliError, CliResult, Outcome};
use crate::sim_args::Goals;
use crate::sim_args::{ServoChoice, standing_simulator};
use clap::Args;
use serde::Serialize;
use std::path::PathBuf;
use std::time::Instant;
use twinloop_sim::Simulator;

#[derive(Args, Debug)]
pub struct SimBenchArgs {
    #[arg(long, value_name = "ROBOT", help = ROBOT_HELP)]
    pub robot: String,
    /// Time step, s.
    #[arg(long, default_value_t = 1e-3, value_name = "S", value_parser = crate::units::time_step)]
    pub dt: f64,
    /// Steps per timed round.
    #[arg(long, default_value_t = 2000, value_parser = crate::bounds::count)]
    pub steps: usize,
    /// Timed rounds (the median is reported).
    #[arg(long, default_value_t = 11, value_parser = crate::bounds::count)]
    pub rounds: usize,
    #[arg(long, value_enum, default_value_t = ServoChoice::Auto)]
    pub servo: ServoChoice,
    /// Joint goals over time (`t`, `q:<joint>`, as `simulate --trajectory`), from 0 s
    /// after the settling: the timed steps follow it (the goals of each round are
    /// interpolated before its clock starts, as MuJoCo's rollout gets its controls).
    #[arg(long, value_name = "FILE.csv")]
    pub trajectory: Option<PathBuf>,
    /// Write JSON {"robot", "dt", "nv", "contact_points", "us_per_step",
    /// "steps_per_second"} to FILE (-: to stdout, in place of the text).
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
}

#[derive(Serialize)]
struct SimBenchReport {
    robot: String,
    dt: f64,
    nv: usize,
    contact_points: usize,
    us_per_step: f64,
    steps_per_second: f64,
}

pub fn run(a: &SimBenchArgs) -> CliResult {
    let (robot, _) = load_description(&a.robot)?;
    let mut sim = standing_simulator(&robot, a.dt, a.servo)?;
    // Settle first, so the timed steps are steady standing with feet in contact.
    sim.run(0.5)?;
    let goals = a
        .trajectory
        .as_ref()
        .map(|p| Goals::load(p, &sim.model))
        .transpose()?;
    let samples = timed_rounds(a, &mut sim, goals.as_ref())?;
    let us = samples[samples.len() / 2];
    let report = SimBenchReport {
        robot: a.robot.clone(),
        dt: a.dt,
        nv: sim.model.nv,
        contact_points: sim.contact_points().len(),
        us_per_step: us,
        steps_per_second: 1e6 / us,
    };
    let text = format!(
        "{}: {:.2} us per step ({:.0} steps/s), nv = {}, {} contact points, dt = {} s\n",
        report.robot,
        report.us_per_step,
        report.steps_per_second,
        report.nv,
        report.contact_points,
        report.dt
    );
    emit(&text, a.json.as_ref(), &report)?;
    Ok(Outcome::Ok)
}

/// The microseconds per step of each round, sorted. With goals, the walk's clock
/// starts at the first timed step; each round's goals are interpolated beforehand.
fn timed_rounds(
    a: &SimBenchArgs,
    sim: &mut Simulator,
    goals: Option<&Goals>,
) -> Result<Vec<f64>, CliError> {
    let (steps, nj) = (a.steps.max(1), sim.goals.len());
    let hold = sim.goals.clone();
    let mut round_goals = vec![0.0; if goals.is_some() { steps * nj } else { 0 }];
    let mut samples = Vec::with_capacity(a.rounds);
    let mut k = 0usize;
    for _ in 0..a.rounds.max(1) {
        if let Some(g) = goals {
            for (s, out) in round_goals.chunks_exact_mut(nj).enumerate() {
                g.at((k + s) as f64 * a.dt, &hold, out);
            }
        }
        let t = Instant::now();
        if goals.is_some() {
            for row in round_goals.chunks_exact(nj) {
                sim.goals.copy_from_slice(row);
                sim.step()?;
            }
        } else {
            for _ in 0..steps {
                sim.step()?;
            }
        }
        samples.push(t.elapsed().as_secs_f64() * 1e6 / steps as f64);
        k += steps;
    }
    samples.sort_by(f64::total_cmp);
    Ok(samples)
}
