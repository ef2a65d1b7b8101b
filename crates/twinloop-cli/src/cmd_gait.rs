//! `twinloop gait sequence|zmp`: joint and CoM references for walking: seed 003's
//! walking sequence as joint goals, and seed 002's ZMP and LIPM CoM reference.

use crate::common::{num, print};
use crate::error::{CliError, CliResult, Outcome};
use crate::gait_args::{StepTiming, TimingArgs, lab17_only, option_names, sequence_options};
use clap::{Args, Subcommand};
use std::path::PathBuf;
use twinloop_gait::{GaitPlan, ZmpReference, walking_sequence_with};
use twinloop_io::{CsvWriter, Table};

#[derive(Subcommand, Debug)]
pub enum GaitCommand {
    /// Seed 003's 13-stage walking sequence (stages A..N) as joint goals over time
    ///
    /// The stages set the offsets of the ten Table 2 servos (ankle roll and pitch, knee,
    /// hip pitch, shoulder pitch per side) in their Step_State windows and hold them in
    /// between, as the seed's controller does; the other joints hold their trims.
    ///
    /// Example:
    ///   twinloop gait sequence --robot builtin:lab17 --cycles 3 --out walk.csv
    ///   twinloop simulate --robot builtin:lab17 --trajectory walk.csv --duration 60 --out sim.csv
    ///
    /// Output: a CSV with `t` (s) and `q:<joint>` (goal joint angle, rad, lab17's joint
    /// zero being the Table 2 trim) for all 17 joints; feed it to `twinloop simulate
    /// --trajectory`. stderr says how many ticks were written.
    #[command(verbatim_doc_comment)]
    Sequence(SequenceArgs),
    /// ZMP walking reference and the LIPM CoM reference from a footstep plan (seed 002, eq 12-13)
    ///
    /// Feet alternate at y = -w/2 and +w/2, footstep j landing at x = j * sl; the ZMP
    /// holds the support foot in single support and moves linearly between feet in
    /// double support. The CoM solves x'' = (g/Zc)(x - p) exactly per phase (the bounded
    /// solution: the CoM comes to rest over the final ZMP).
    ///
    /// Example:
    ///   twinloop gait zmp --step-length 0.03 --tss 0.5 --tdb 0.2 --footsteps 40 --com-height 0.5 --out ref.csv
    ///
    /// Output: a CSV with t, zmp.x, zmp.y, xr, yr, zr, vxr, vyr, axr, ayr, phase (0 single
    /// support, 1 double support), sampled every --dt; stdout gives the duration and the
    /// initial CoM velocity.
    #[command(verbatim_doc_comment)]
    Zmp(ZmpArgs),
}

pub fn run(cmd: GaitCommand) -> CliResult {
    match cmd {
        GaitCommand::Sequence(a) => sequence(&a),
        GaitCommand::Zmp(a) => zmp(&a),
    }
}

#[derive(Args, Debug)]
pub struct SequenceArgs {
    #[command(flatten)]
    pub timing: TimingArgs,
    /// Number of step cycles.
    #[arg(long, default_value_t = 1, value_parser = crate::bounds::count)]
    pub cycles: usize,
    /// Output CSV.
    #[arg(long, value_name = "FILE.csv")]
    pub out: PathBuf,
}

#[derive(Args, Debug)]
pub struct ZmpArgs {
    #[command(flatten)]
    pub steps: StepTiming,
    /// Number of footsteps (swings).
    #[arg(long, default_value_t = 10, value_parser = crate::bounds::count)]
    pub footsteps: usize,
    /// CoM height Zc, m.
    #[arg(long, default_value_t = 0.5, value_parser = crate::units::gait_length)]
    pub com_height: f64,
    /// Lateral distance between the foot centres, m.
    #[arg(long, default_value_t = 0.14, value_parser = crate::units::gait_length)]
    pub step_width: f64,
    /// Standing time before the first and after the last step, s.
    #[arg(long, default_value_t = 1.0, value_parser = crate::common::non_negative)]
    pub settle: f64,
    /// Gravity, m/s^2.
    #[arg(long, default_value_t = twinloop_description::GRAVITY, value_parser = crate::common::positive)]
    pub gravity: f64,
    /// Sample period, s.
    #[arg(long, default_value_t = 1e-3, value_name = "S", value_parser = crate::units::time_step)]
    pub dt: f64,
    /// Output CSV.
    #[arg(long, value_name = "FILE.csv")]
    pub out: PathBuf,
}

fn sequence(a: &SequenceArgs) -> CliResult {
    lab17_only(&a.timing.robot)?;
    let g = walking_sequence_with(&sequence_options(&a.timing, a.cycles)).map_err(option_names)?;
    let mut cols = vec!["t".to_string()];
    cols.extend(g.joints.iter().map(|j| format!("q:{j}")));
    let mut table = Table::new(cols);
    for k in 0..g.len() {
        let mut row = vec![g.times[k]];
        row.extend_from_slice(&g.goals[k]);
        table.rows.push(row);
    }
    table
        .write(&a.out)
        .map_err(|e| CliError::from(e).context("--out"))?;
    eprintln!(
        "wrote {} ticks ({} cycles of {} s) of {} joint goals to {}",
        g.len(),
        a.cycles,
        a.timing.cycle_period,
        g.joints.len(),
        a.out.display()
    );
    Ok(Outcome::Ok)
}

fn zmp(args: &ZmpArgs) -> CliResult {
    let plan = GaitPlan {
        step_length: args.steps.step_length,
        t_single: args.steps.tss,
        t_double: args.steps.tdb,
        step_width: args.step_width,
        steps: args.footsteps,
        com_height: args.com_height,
        gravity: args.gravity,
        t_start: args.settle,
        t_end: args.settle,
        ..GaitPlan::default()
    };
    let reference = ZmpReference::new(&plan)?;
    let samples = reference.sample(args.dt)?;
    let columns: Vec<String> = [
        "t", "zmp.x", "zmp.y", "xr", "yr", "zr", "vxr", "vyr", "axr", "ayr", "phase",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let mut writer = CsvWriter::create(&args.out, &columns)?;
    for s in &samples {
        let row = [
            s.t,
            s.zmp[0],
            s.zmp[1],
            s.com[0],
            s.com[1],
            s.com[2],
            s.vel[0],
            s.vel[1],
            s.acc[0],
            s.acc[1],
            f64::from(s.phase.code()),
        ];
        writer.write_row(&row)?;
    }
    writer.finish()?;
    let v0 = reference.initial_velocity();
    print(&format!(
        "{} samples over {} s (Tc {} s) -> {}\ninitial CoM velocity ({}, {}) m/s\n",
        samples.len(),
        num(reference.duration()),
        num(reference.time_constant()),
        args.out.display(),
        num(v0[0]),
        num(v0[1]),
    ));
    Ok(Outcome::Ok)
}
