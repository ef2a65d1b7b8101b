//! `twinloop simulate`: a robot standing on its servos in the simulator. The
//! standing simulator is `sim_args`'s, shared with `twinloop bench sim`.

use crate::common::{ROBOT_HELP, load_description};
use crate::error::{CliError, CliResult, Outcome};
use crate::progress;
use crate::sim_args::{Goals, ServoChoice, record_columns, standing_simulator, state_row};
use clap::Args;
use std::path::PathBuf;
use twinloop_robot::{Robot, RobotState};
use twinloop_sim::Simulator;

#[derive(Args, Debug)]
pub struct SimulateArgs {
    #[arg(long, value_name = "ROBOT", help = ROBOT_HELP)]
    pub robot: String,
    #[command(flatten)]
    pub added: crate::units::AddMassArgs,
    /// Simulated time, s [default: the --trajectory's last time, else 2].
    #[arg(long, value_name = "S", value_parser = crate::common::positive)]
    pub duration: Option<f64>,
    /// Hold the initial standing pose (the default when no --trajectory is given).
    #[arg(long)]
    pub hold: bool,
    /// Joint goals over time: a CSV with `t` and `q:<joint>` columns, linearly
    /// interpolated; joints without a column hold their initial position. A `q:`
    /// column that names no joint is an error (`twinloop model info --joints` lists
    /// them).
    #[arg(long, value_name = "FILE")]
    pub trajectory: Option<PathBuf>,
    /// Output CSV; an .mcap is written as ROS 2 messages (/joint_states, /tf, /imu,
    /// /robot_description; docs/logs.md).
    #[arg(long, value_name = "FILE.csv|FILE.mcap")]
    pub out: PathBuf,
    /// Time step, s.
    #[arg(long, default_value_t = 1e-3, value_name = "S", value_parser = crate::units::time_step)]
    pub dt: f64,
    /// Write one row every N steps.
    #[arg(long, default_value_t = 1, value_parser = crate::bounds::count)]
    pub every: usize,
    #[arg(long, value_enum, default_value_t = ServoChoice::Auto)]
    pub servo: ServoChoice,
    /// Servo model parameters (`identify servo --out` or `--defaults`;
    /// docs/servo-models.md) in place of --servo's: FILE.toml for every joint whose
    /// servo is of its type (a built-in robot's servo table says which; other robots:
    /// every joint), or JOINT=FILE.toml for one joint, repeatable
    #[arg(long, value_name = "[JOINT=]FILE.toml")]
    pub servo_params: Vec<String>,
    /// With --view the run waits for the page to connect, then goes at real time.
    #[command(flatten)]
    pub view: crate::live_view::LiveViewArgs,
}

pub fn run(a: SimulateArgs) -> CliResult {
    if a.hold && a.trajectory.is_some() {
        return Err(CliError::new("--hold and --trajectory exclude each other"));
    }
    // Bounded before any work: a second of simulation at --dt, and --duration.
    crate::bounds::steps(
        1.0,
        a.dt,
        &format!("one second at --dt {} s", crate::common::num(a.dt)),
    )?;
    if let Some(d) = a.duration {
        crate::bounds::steps(
            d,
            a.dt,
            &format!(
                "--duration {} s at --dt {} s",
                crate::common::num(d),
                crate::common::num(a.dt)
            ),
        )?;
    }
    let (mut robot, _) = load_description(&a.robot)?;
    a.added.apply(&mut robot)?;
    let mut sim = standing_simulator(&robot, a.dt, a.servo)?;
    if !a.servo_params.is_empty() {
        let set =
            twinloop_sim::servo_params::ServoParamsSet::read(&a.servo_params, "--servo-params")?;
        let n = sim.apply_servo_params(&robot.name, &set, "--servo-params")?;
        eprintln!("{n} joints run the servo model of --servo-params");
    }
    let goals = a
        .trajectory
        .as_ref()
        .map(|p| Goals::load(p, &sim.model))
        .transpose()?;
    // A trajectory runs to its end unless --duration says otherwise.
    let duration = a
        .duration
        .unwrap_or_else(|| goals.as_ref().map_or(2.0, Goals::end));
    let what = match (&a.duration, &goals) {
        (None, Some(g)) => {
            let first = g.start();
            format!(
                "{}: the last goal, t = {} s, at --dt {} s{}",
                a.trajectory
                    .as_ref()
                    .map_or(String::new(), |p| p.display().to_string()),
                crate::common::num(g.end()),
                crate::common::num(a.dt),
                if first > 1e6 {
                    format!(
                        " (its times start at {} s: Unix times? they count from 0)",
                        crate::common::num(first)
                    )
                } else {
                    String::new()
                }
            )
        }
        _ => format!(
            "--duration {} s at --dt {} s",
            crate::common::num(duration),
            crate::common::num(a.dt)
        ),
    };
    crate::bounds::steps(duration, a.dt, &what)?;
    let cols = record_columns(&sim);
    let mut live = live_view(&a, &robot, &sim)?;
    let out = Output {
        robot: &robot,
        cols: &cols,
    };
    record(&a, duration, &mut sim, goals.as_ref(), out, live.as_mut())?;
    if let Some(live) = &live {
        eprintln!("{}", live.summary());
    }
    Ok(Outcome::Ok)
}

/// `--view`: the page, once a browser shows it (the run starts then).
fn live_view(
    a: &SimulateArgs,
    robot: &twinloop_description::Description,
    sim: &Simulator,
) -> Result<Option<twinloop_view::LivePublisher>, CliError> {
    let names = sim.model.q_names();
    let live = crate::live_view::start_live(&a.view, robot, Some(&a.robot), &names)?;
    if let Some(live) = &live {
        // Nothing is written yet: Ctrl-C may end the wait as it ends any program.
        eprintln!("the simulation starts when a page shows it (Ctrl-C stops)");
        live.wait_for_page(&|| false);
    }
    Ok(live)
}

/// Step the simulator for --duration, following the goals, writing every --every'th row.
/// What `record` writes: the columns, and the robot whose URDF an .mcap carries.
struct Output<'a> {
    robot: &'a twinloop_description::Description,
    cols: &'a [String],
}

fn record(
    a: &SimulateArgs,
    duration: f64,
    sim: &mut Simulator,
    goals: Option<&Goals>,
    out: Output,
    mut live: Option<&mut twinloop_view::LivePublisher>,
) -> Result<(), CliError> {
    let (robot, cols) = (out.robot, out.cols);
    let hold: Vec<f64> = sim.goals.clone();
    let mut w = crate::common::RowWriter::create(&a.out, cols, Some(robot), false)?;
    let steps = (duration / a.dt).round() as usize;
    let bar = progress::rows(if steps > 20_000 { steps } else { 0 });
    let mut st = RobotState::default();
    let mut g = vec![0.0; sim.model.joint_names.len()];
    let mut row = Vec::with_capacity(cols.len());
    let mut rows = 0usize;
    for k in 0..=steps {
        if k % a.every.max(1) == 0 || k == steps {
            state_row(sim, &mut st, sim.time, &mut row)?;
            w.write_row(&row)?;
            rows += 1;
        }
        if let Some(live) = live.as_deref_mut() {
            live.offer(sim.time, &sim.q);
            live.keep_real_time(sim.time);
        }
        if k == steps {
            break;
        }
        if let Some(goals) = goals {
            goals.at(sim.time, &hold, &mut g);
            sim.command_positions(&g)?;
        }
        sim.step()?;
        bar.inc(1);
    }
    bar.finish_and_clear();
    w.finish()?;
    // A run that succeeds says what it wrote (issue 30 item 10: it was silent).
    eprintln!(
        "wrote {}: {rows} rows of {} columns, t = 0 to {} s at --dt {} s",
        a.out.display(),
        cols.len(),
        twinloop_io::clean_time(sim.time),
        a.dt
    );
    Ok(())
}
