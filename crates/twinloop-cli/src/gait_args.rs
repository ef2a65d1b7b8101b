//! The gait flags shared by `gait` and `experiment walk`/`compliant-walk`: seed
//! 003's timing, seed 002's footstep timing, the lab17-only robot and the options'
//! names in errors (argument mapping).

use crate::common::{hinges_only, load_description};
use crate::error::CliError;
use clap::Args;
use twinloop_gait::{SEED_CYCLE_PERIOD, SEED_SAMPLE_TIME, SequenceOptions};

#[derive(Args, Debug)]
pub struct TimingArgs {
    /// Robot description: only builtin:lab17 carries seed 003's trims.
    #[arg(long, default_value = "builtin:lab17", value_name = "ROBOT")]
    pub robot: String,
    /// Control tick and sample period, s (40 ms: two 20 ms servo PWM frames, and below
    /// the 57 ms the seed's 54.8 rad/s model bandwidth allows).
    #[arg(long, default_value_t = SEED_SAMPLE_TIME, value_name = "S", value_parser = crate::units::time_step)]
    pub dt: f64,
    /// Duration of one step cycle (Step_State 0 to 100), s. Below ~3.5 s lab17 falls (seed
    /// 003 section 5: too fast a step cycle leaves the inertial forces undamped).
    #[arg(long, default_value_t = SEED_CYCLE_PERIOD, value_parser = crate::common::positive)]
    pub cycle_period: f64,
    /// Factor on every offset (1 = the seed's numbers).
    #[arg(long, default_value_t = 1.0, value_parser = crate::common::non_negative)]
    pub amplitude: f64,
}

/// The footstep timing of seed 002's ZMP gait, shared by every command that plans one.
#[derive(Args, Debug, Clone, Copy)]
pub struct StepTiming {
    /// Step length sl, m.
    #[arg(long, default_value_t = 0.03, value_parser = crate::units::signed_gait_length)]
    pub step_length: f64,
    /// Single-support duration Tss, s.
    #[arg(long, default_value_t = 0.5, value_parser = crate::common::positive)]
    pub tss: f64,
    /// Double-support duration Tdb, s.
    #[arg(long, default_value_t = 0.2, value_parser = crate::common::non_negative)]
    pub tdb: f64,
}

/// The robot of --robot, which must be lab17.
pub fn lab17_only(spec: &str) -> Result<twinloop_description::Description, CliError> {
    let (robot, _) = load_description(spec).map_err(|e| e.context("--robot"))?;
    hinges_only(&robot, spec, "walking generation")?;
    if robot.name != twinloop_description::builtin::lab17::NAME {
        return Err(CliError::new(format!(
            "--robot: seed 003's walking sequence is defined around lab17's Table 2 trims; \
             \"{}\" is not lab17 (use builtin:lab17)",
            robot.name
        )));
    }
    Ok(robot)
}

pub fn sequence_options(t: &TimingArgs, cycles: usize) -> SequenceOptions {
    SequenceOptions {
        cycles,
        sample_time: t.dt,
        cycle_period: t.cycle_period,
        amplitude: t.amplitude,
    }
}

/// A library error about its fields (`sample_time must be ...`) with each field named
/// by the option that sets it: `--dt must be ...`.
pub fn option_names(e: impl std::fmt::Display) -> CliError {
    let fields = [
        ("sample_time", "--dt"),
        ("cycle_period", "--cycle-period"),
        ("cycles", "--cycles"),
        ("amplitude", "--amplitude"),
        ("samples", "--samples"),
        ("gyro_noise", "--gyro-noise"),
        ("kp_position", "--kp-position"),
        ("skip_samples", "--skip-samples"),
    ];
    // Every field the message names, first or further on, is the option that sets it.
    let worded = fields.iter().fold(format!(" {e}"), |m, (f, o)| {
        m.replace(&format!(" {f} "), &format!(" {o} "))
    });
    CliError::new(worded.trim_start())
}
