//! `twinloop gait zmp`: ZMP walking references and the LIPM CoM reference (seed 002, eq 12-13).
//!
//! A top-level command (not `gait zmp`) so it does not clash with the `gait` group
//! being added on another branch; it can move under `gait` when both merge.

use crate::common::{EXIT_BAD_INPUT, num, print};
use clap::Args;
use std::path::PathBuf;
use std::process::ExitCode;
use twinloop_gait::{GaitPlan, ZmpReference};
use twinloop_io::CsvWriter;

#[derive(Args, Debug)]
pub struct ZmpArgs {
    /// Step length sl, m.
    #[arg(long, default_value_t = 0.03)]
    pub step_length: f64,
    /// Single-support duration Tss, s.
    #[arg(long, default_value_t = 0.5)]
    pub tss: f64,
    /// Double-support duration Tdb, s.
    #[arg(long, default_value_t = 0.2)]
    pub tdb: f64,
    /// Number of steps (swings).
    #[arg(long, default_value_t = 10)]
    pub steps: usize,
    /// CoM height Zc, m.
    #[arg(long, default_value_t = 0.5)]
    pub com_height: f64,
    /// Lateral distance between the foot centres, m.
    #[arg(long, default_value_t = 0.14)]
    pub step_width: f64,
    /// Standing time before the first and after the last step, s.
    #[arg(long, default_value_t = 1.0)]
    pub settle: f64,
    /// Gravity, m/s^2.
    #[arg(long, default_value_t = twinloop_description::GRAVITY)]
    pub gravity: f64,
    /// Sample time, s.
    #[arg(long, default_value_t = 1e-3)]
    pub dt: f64,
    /// Output CSV.
    #[arg(long, value_name = "FILE.csv")]
    pub out: PathBuf,
}

fn fail(msg: impl std::fmt::Display) -> ExitCode {
    eprintln!("error: {msg}");
    ExitCode::from(EXIT_BAD_INPUT)
}

pub fn run(args: ZmpArgs) -> ExitCode {
    let plan = GaitPlan {
        step_length: args.step_length,
        t_single: args.tss,
        t_double: args.tdb,
        step_width: args.step_width,
        steps: args.steps,
        com_height: args.com_height,
        gravity: args.gravity,
        t_start: args.settle,
        t_end: args.settle,
        ..GaitPlan::default()
    };
    let reference = match ZmpReference::new(&plan) {
        Ok(r) => r,
        Err(e) => return fail(e),
    };
    let samples = match reference.sample(args.dt) {
        Ok(s) => s,
        Err(e) => return fail(e),
    };
    let columns: Vec<String> = [
        "t", "zmp.x", "zmp.y", "xr", "yr", "zr", "vxr", "vyr", "axr", "ayr", "phase",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let mut writer = match CsvWriter::create(&args.out, &columns) {
        Ok(w) => w,
        Err(e) => return fail(e),
    };
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
        if let Err(e) = writer.write_row(&row) {
            return fail(e);
        }
    }
    if let Err(e) = writer.finish() {
        return fail(e);
    }
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
    ExitCode::SUCCESS
}
