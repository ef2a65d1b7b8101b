//! `twinloop experiment walk`: seed 003's identification dataset, lab17 walking the
//! 13-stage sequence in the simulator with a gyro on each foot.

use crate::error::{CliError, CliResult, Outcome};
use crate::gait_args::{TimingArgs, lab17_only, option_names, sequence_options};
use clap::Args;
use std::path::PathBuf;
use twinloop_experiments::{DatasetOptions, record_walk};
use twinloop_gait::SEED_SAMPLES;
use twinloop_io::Table;

#[derive(Args, Debug)]
pub struct WalkArgs {
    #[command(flatten)]
    pub timing: TimingArgs,
    /// Samples to record (seed 003: 1000).
    #[arg(long, default_value_t = SEED_SAMPLES, value_parser = crate::bounds::count)]
    pub samples: usize,
    /// Seed of the gyro noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Ticks to walk before recording (the walk goes on seamlessly): --skip-samples 1000
    /// records cycles 11-20, a validation run that is a different stretch of the walk.
    #[arg(long, default_value_t = 0)]
    pub skip_samples: usize,
    /// Gyro noise, deg/s rms.
    #[arg(long, default_value_t = twinloop_experiments::walk::MPU6050_GYRO_NOISE_DEG_S, value_parser = crate::common::non_negative)]
    pub gyro_noise: f64,
    /// Two-loop servo position gain, 1/s (60: full speed beyond 6 degrees of error).
    #[arg(long, default_value_t = twinloop_experiments::walk::LD2015_KP_POSITION, value_parser = crate::common::positive)]
    pub kp_position: f64,
    /// Output CSV.
    #[arg(long, value_name = "FILE.csv")]
    pub out: PathBuf,
}

pub fn run(a: &WalkArgs) -> CliResult {
    let robot = lab17_only(&a.timing.robot)?;
    // Every sample, skipped or recorded, is --dt of walking in 1 ms simulator steps.
    let defaults = DatasetOptions::default();
    crate::bounds::steps(
        (a.samples + a.skip_samples) as f64 * a.timing.dt + defaults.settle,
        defaults.dt,
        &format!(
            "--samples {} and --skip-samples {} at --dt {} s",
            a.samples,
            a.skip_samples,
            crate::common::num(a.timing.dt)
        ),
    )?;
    let o = DatasetOptions {
        sequence: sequence_options(&a.timing, 1),
        samples: a.samples,
        gyro_noise_deg_s: a.gyro_noise,
        noise_seed: a.seed,
        skip_samples: a.skip_samples,
        kp_position: a.kp_position,
        ..Default::default()
    };
    let d = record_walk(&robot, &o).map_err(option_names)?;
    let mut table = Table::new(d.columns.clone());
    table.rows = d.rows;
    table
        .write(&a.out)
        .map_err(|e| CliError::from(e).context("--out"))?;
    eprintln!(
        "wrote {} samples to {}: trunk travel x {:.3} m, y {:.3} m, yaw {:.1} deg, max tilt {:.1} deg",
        table.rows.len(),
        a.out.display(),
        d.travel[0],
        d.travel[1],
        d.yaw_deg,
        d.max_tilt_deg
    );
    if let Some(t) = d.fell_at {
        eprintln!(
            "warning: the robot fell (trunk past 45 degrees) at t = {t:.2} s; the samples after \
             that are of a robot on the ground. See docs/lab17-walking-identification.md \
             (the defaults walk upright)"
        );
    }
    Ok(Outcome::Ok)
}
