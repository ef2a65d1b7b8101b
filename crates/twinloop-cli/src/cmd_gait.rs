//! `twinloop gait sequence|dataset`: seed 003's walking sequence as joint goals, and
//! the walking identification dataset recorded on lab17 in the simulator.

use crate::common::EXIT_BAD_INPUT;
use clap::{Args, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;
use twinloop_gait::{
    DatasetOptions, SEED_CYCLE_PERIOD, SEED_SAMPLE_TIME, SEED_SAMPLES, SequenceOptions,
    record_walk, walking_sequence_with,
};
use twinloop_io::Table;

#[derive(Subcommand)]
pub enum GaitCommand {
    /// ZMP walking reference and the LIPM CoM reference from a footstep plan (seed 002, eq 12-13)
    ///
    /// Feet alternate at y = -w/2 and +w/2, step j landing at x = j * sl; the ZMP holds the
    /// support foot in single support and moves linearly between feet in double support.
    /// The CoM solves x'' = (g/Zc)(x - p) exactly per phase (the bounded solution: the CoM
    /// comes to rest over the final ZMP). Columns: t, zmp.x, zmp.y, xr, yr, zr, vxr, vyr,
    /// axr, ayr, phase (0 single support, 1 double support).
    ///
    /// Example: twinloop gait zmp --step-length 0.03 --tss 0.5 --tdb 0.2 --steps 40 --com-height 0.5 --out ref.csv
    Zmp(crate::cmd_zmp::ZmpArgs),
    /// Seed 003's 13-stage walking sequence (stages A..N) as joint goals over time
    ///
    /// The stages set the offsets of the ten Table 2 servos (ankle roll and pitch, knee,
    /// hip pitch, shoulder pitch per side) in their Step_State windows and hold them in
    /// between, as the seed's controller does; the other joints hold their trims.
    ///
    /// Example: twinloop gait sequence --robot builtin:lab17 --cycles 3 --out walk.csv
    ///
    /// Output: a CSV with `t` (s) and `q:<joint>` (goal joint angle, rad, lab17's joint
    /// zero being the Table 2 trim) for all 17 joints; feed it to `twinloop simulate --trajectory`.
    Sequence(SequenceArgs),
    /// Record seed 003's identification dataset: the walk on lab17 in the simulator
    ///
    /// The robot stands on two-loop servos (LD-2015 ratings), settles at its trims, then
    /// walks the sequence. Every tick it reads an MPU-6050 gyro on each foot (131 LSB per
    /// deg/s, 0.05 deg/s rms noise) and then sets that tick's goals.
    ///
    /// Example: twinloop gait dataset --robot builtin:lab17 --out lab17_walk.csv
    ///          twinloop gait dataset --seed 2 --skip-samples 1000 --out lab17_walk_val.csv
    ///
    /// Output: a CSV with `t` (s), `u:<joint>` (the ten offsets of seed 003 eq 6, servo
    /// degrees) and `gyro:l_foot.roll|pitch|yaw`, `gyro:r_foot.roll|pitch|yaw` (deg/s). Use
    /// another --seed for a validation record. stderr says whether the robot fell.
    Dataset(DatasetArgs),
}

#[derive(Args)]
pub struct TimingArgs {
    /// Robot: only builtin:lab17 carries seed 003's trims.
    #[arg(long, default_value = "builtin:lab17")]
    pub robot: String,
    /// Control tick and sample time, s (the seed's servos take a 20 ms PWM frame).
    #[arg(long, default_value_t = SEED_SAMPLE_TIME)]
    pub sample_time: f64,
    /// Duration of one step cycle (Step_State 0 to 100), s.
    #[arg(long, default_value_t = SEED_CYCLE_PERIOD)]
    pub cycle_period: f64,
    /// Factor on every offset (1 = the seed's numbers).
    #[arg(long, default_value_t = 1.0)]
    pub amplitude: f64,
}

#[derive(Args)]
pub struct SequenceArgs {
    #[command(flatten)]
    pub timing: TimingArgs,
    /// Number of step cycles.
    #[arg(long, default_value_t = 1)]
    pub cycles: usize,
    #[arg(long)]
    pub out: PathBuf,
}

#[derive(Args)]
pub struct DatasetArgs {
    #[command(flatten)]
    pub timing: TimingArgs,
    /// Samples to record (seed 003: 1000).
    #[arg(long, default_value_t = SEED_SAMPLES)]
    pub samples: usize,
    /// Seed of the gyro noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Ticks to walk before recording (the walk goes on seamlessly): --skip-samples 1000
    /// records cycles 11-20, a validation run that is a different stretch of the walk.
    #[arg(long, default_value_t = 0)]
    pub skip_samples: usize,
    /// Gyro noise, deg/s rms.
    #[arg(long, default_value_t = twinloop_gait::dataset::MPU6050_GYRO_NOISE_DEG_S)]
    pub gyro_noise: f64,
    /// Two-loop servo position gain, 1/s (60: full speed beyond 6 degrees of error).
    #[arg(long, default_value_t = twinloop_gait::dataset::LD2015_KP_POSITION)]
    pub kp_position: f64,
    #[arg(long)]
    pub out: PathBuf,
}

fn lab17_only(spec: &str) -> Result<twinloop_model::Robot, String> {
    let robot = twinloop_robots::resolve(spec).map_err(|e| format!("--robot: {e}"))?;
    if robot.name != twinloop_robots::lab17::NAME {
        return Err(format!(
            "--robot: seed 003's walking sequence is defined around lab17's Table 2 trims; \
             \"{}\" is not lab17 (use builtin:lab17)",
            robot.name
        ));
    }
    Ok(robot)
}

fn sequence_options(t: &TimingArgs, cycles: usize) -> SequenceOptions {
    SequenceOptions {
        cycles,
        sample_time: t.sample_time,
        cycle_period: t.cycle_period,
        amplitude: t.amplitude,
    }
}

/// Turn a library field name into the option that sets it.
fn flag(msg: String) -> String {
    let mut m = msg;
    for (field, opt) in [
        ("sample_time", "--sample-time"),
        ("cycle_period", "--cycle-period"),
        ("cycles", "--cycles"),
        ("amplitude", "--amplitude"),
        ("samples", "--samples"),
        ("gyro_noise", "--gyro-noise"),
        ("kp_position", "--kp-position"),
        ("skip_samples", "--skip-samples"),
    ] {
        if m.starts_with(field) {
            m = format!("{opt}{}", &m[field.len()..]);
            break;
        }
    }
    m
}

fn sequence(a: &SequenceArgs) -> Result<(), String> {
    lab17_only(&a.timing.robot)?;
    let g = walking_sequence_with(&sequence_options(&a.timing, a.cycles))
        .map_err(|e| flag(e.to_string()))?;
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
        .map_err(|e| format!("--out {}: {e}", a.out.display()))?;
    eprintln!(
        "wrote {} ticks ({} cycles of {} s) of {} joint goals to {}",
        g.len(),
        a.cycles,
        a.timing.cycle_period,
        g.joints.len(),
        a.out.display()
    );
    Ok(())
}

fn dataset(a: &DatasetArgs) -> Result<(), String> {
    let robot = lab17_only(&a.timing.robot)?;
    let o = DatasetOptions {
        sequence: sequence_options(&a.timing, 1),
        samples: a.samples,
        gyro_noise_deg_s: a.gyro_noise,
        noise_seed: a.seed,
        skip_samples: a.skip_samples,
        kp_position: a.kp_position,
        ..Default::default()
    };
    let d = record_walk(&robot, &o).map_err(|e| flag(e.to_string()))?;
    let mut table = Table::new(d.columns.clone());
    table.rows = d.rows;
    table
        .write(&a.out)
        .map_err(|e| format!("--out {}: {e}", a.out.display()))?;
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
    Ok(())
}

pub fn run(cmd: GaitCommand) -> ExitCode {
    let r = match cmd {
        GaitCommand::Zmp(a) => return crate::cmd_zmp::run(a),
        GaitCommand::Sequence(a) => sequence(&a),
        GaitCommand::Dataset(a) => dataset(&a),
    };
    match r {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(EXIT_BAD_INPUT)
        }
    }
}
