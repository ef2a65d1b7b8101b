//! `twinloop bench dynamics|sim|link`: benchmarks against peers. `dynamics` reports
//! the median nanoseconds per call of each algorithm over random (or given) states,
//! like MuJoCo's `testspeed`; the peer bench in bench/pinocchio runs Pinocchio on the
//! same model and the same states file.

mod link;
mod sim;

use crate::common::{ROBOT_HELP, emit, load_model};
use crate::error::{CliError, CliResult, Outcome};
use crate::progress;
use crate::units::read_trajectory;
use clap::{Args, Subcommand};
use serde::Serialize;
use std::hint::black_box;
use std::path::PathBuf;
use std::time::Instant;
use twinloop_dynamics::configuration::{random_configuration, random_tangent};
use twinloop_dynamics::{BaseKind, Data, Model};
use twinloop_io::{Quantity, StateColumns};
use twinloop_random::SplitMix64;

#[derive(Subcommand, Debug)]
pub enum BenchCommand {
    /// Time the dynamics algorithms on a model.
    ///
    /// Runs forward kinematics (fk), centre of mass (com), RNEA, CRBA, ABA, the
    /// world-frame joint Jacobians (jacobians) and the joint-torque regressor over a
    /// set of states, repeating rounds until each algorithm has run for about
    /// --seconds, and reports the median over rounds of the time per call.
    ///
    /// Example:
    ///   twinloop bench dynamics --robot models/op3/robotis_op3.urdf
    ///   twinloop bench dynamics --robot models/talos/mjcf/talos.xml --states states.csv --json -
    ///
    /// With --states, the states come from a trajectory CSV (q:, v:, a:, tau: columns);
    /// bench/pinocchio/make_states.py writes one, and bench/pinocchio runs Pinocchio on
    /// the same file, so the two are compared on identical inputs.
    ///
    /// Output: the median ns per call of each algorithm; --json FILE (- for stdout)
    /// writes {"model", "nv", "states", "ns_per_call": {"fk", "com", "rnea", "crba",
    /// "aba", "jacobians", "regressor"}}.
    #[command(verbatim_doc_comment)]
    Dynamics(DynamicsBenchArgs),
    /// Time the simulator: microseconds per step of a robot standing on its servos.
    ///
    /// The robot is placed on the ground, settles for 0.5 s, then --rounds rounds of
    /// --steps steps are timed; the median is reported. bench/mujoco/bench_sim.py times
    /// MuJoCo on the same robot for the comparison in BENCHMARKS.md.
    ///
    /// Example:
    ///   twinloop bench sim --robot models/op3/mjcf/op3.xml --dt 0.002 --json -
    ///   twinloop bench sim --robot models/op3/mjcf/op3.xml --trajectory op3_walk.csv
    ///
    /// With --trajectory the timed steps follow its goals from 0 s (the walking case).
    ///
    /// Output: us per step, steps per second, the robot's nv and contact points.
    #[command(verbatim_doc_comment)]
    Sim(sim::SimBenchArgs),
    /// Time the Dynamixel link: software overhead of a control cycle, and
    /// transactions per second against a served robot.
    ///
    /// Without --port: the client's own work per 20-servo control cycle (encode,
    /// decode, CRC, checks; the replies are replayed from memory, so neither a wire nor
    /// a servo costs anything), against that cycle's wire time at 1 Mbps
    /// (`twinloop link plan`).
    /// With --port (a robot from `twinloop serve --map builtin:op3 --no-timing`):
    /// also READ, SYNC_READ, FAST_SYNC_READ and a whole cycle over that port, timed the
    /// same way bench/dynamixel_sdk/bench_sdk.py times the official Python SDK.
    ///
    /// Example:
    ///   twinloop bench link
    ///   twinloop bench link --port /dev/pts/5 --json bench.json
    ///
    /// Output: per case the median time (us), the rate, and for cycles the wire time
    /// and overhead / wire ratio.
    #[command(verbatim_doc_comment)]
    Link(link::LinkBenchArgs),
}

#[derive(Args, Debug)]
pub struct DynamicsBenchArgs {
    #[arg(long, value_name = "ROBOT", help = ROBOT_HELP)]
    pub robot: String,
    /// States to use (trajectory CSV with q:, v:, a:, tau: columns).
    #[arg(long, value_name = "CSV")]
    pub states: Option<PathBuf>,
    /// Number of random states when --states is not given.
    #[arg(long, default_value_t = 1000, value_parser = crate::bounds::count)]
    pub count: usize,
    /// Seed of the random states.
    #[arg(long, default_value_t = 0x7417_1009)]
    pub seed: u64,
    /// Minimum time spent on each algorithm, in seconds.
    #[arg(long, default_value_t = 0.3, value_parser = crate::bounds::wall_seconds)]
    pub seconds: f64,
    /// Write JSON {"model", "nv", "states", "ns_per_call": {"fk", ...}} to FILE (-: to
    /// stdout, in place of the text).
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
}

#[derive(Serialize)]
struct NsPerCall {
    fk: f64,
    com: f64,
    rnea: f64,
    crba: f64,
    aba: f64,
    jacobians: f64,
    regressor: f64,
}

#[derive(Serialize)]
struct Report {
    model: String,
    nv: usize,
    states: usize,
    ns_per_call: NsPerCall,
}

struct States {
    q: Vec<Vec<f64>>,
    v: Vec<Vec<f64>>,
    a: Vec<Vec<f64>>,
    tau: Vec<Vec<f64>>,
}

fn load_states(model: &Model, args: &DynamicsBenchArgs) -> Result<States, CliError> {
    if let Some(path) = &args.states {
        let t = read_trajectory(path, model)?;
        let find = |qty| crate::common::state_columns(&t, model, qty);
        let cols = [
            find(Quantity::Q)?,
            find(Quantity::V)?,
            find(Quantity::A)?,
            find(Quantity::Tau)?,
        ];
        let mut s = States {
            q: vec![],
            v: vec![],
            a: vec![],
            tau: vec![],
        };
        for row in &t.rows {
            let g = |c: &StateColumns, n| {
                let mut x = vec![0.0; n];
                c.gather(row, &mut x);
                x
            };
            s.q.push(g(&cols[0], model.nq));
            s.v.push(g(&cols[1], model.nv));
            s.a.push(g(&cols[2], model.nv));
            s.tau.push(g(&cols[3], model.nv));
        }
        if s.q.is_empty() {
            return Err(CliError::new(format!(
                "{}: no states in the file",
                path.display()
            )));
        }
        Ok(s)
    } else {
        let mut rng = SplitMix64(args.seed);
        let n = args.count.max(1);
        let mut s = States {
            q: vec![],
            v: vec![],
            a: vec![],
            tau: vec![],
        };
        for _ in 0..n {
            s.q.push(random_configuration(model, &mut rng));
            s.v.push(random_tangent(model, &mut rng));
            s.a.push(random_tangent(model, &mut rng));
            s.tau.push(random_tangent(model, &mut rng));
        }
        Ok(s)
    }
}

/// Median over rounds of ns per call; each round runs `f` once per state.
fn time(n_states: usize, seconds: f64, mut round: impl FnMut()) -> f64 {
    round(); // warm-up
    let mut samples = Vec::new();
    let start = Instant::now();
    while samples.len() < 11 || (start.elapsed().as_secs_f64() < seconds && samples.len() < 100_000)
    {
        let t = Instant::now();
        round();
        samples.push(t.elapsed().as_nanos() as f64 / n_states as f64);
    }
    samples.sort_by(f64::total_cmp);
    samples[samples.len() / 2]
}

pub fn run(cmd: BenchCommand) -> CliResult {
    match cmd {
        BenchCommand::Dynamics(args) => dynamics(&args),
        BenchCommand::Sim(args) => sim::run(&args),
        BenchCommand::Link(args) => link::run(&args),
    }
}

fn dynamics(args: &DynamicsBenchArgs) -> CliResult {
    let (_, model) = load_model(&args.robot, BaseKind::Floating)?;
    let s = load_states(&model, args)?;
    let n = s.q.len();
    let bar = if crate::common::json_to_stdout(args.json.as_ref()) {
        indicatif::ProgressBar::hidden()
    } else {
        progress::steps(7)
    };
    let ns_per_call = time_algorithms(&model, &s, args.seconds, &bar);
    bar.finish_and_clear();
    let model_name = match args.robot.strip_prefix("builtin:") {
        Some(name) => name.to_string(),
        None => std::path::Path::new(&args.robot)
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default(),
    };
    let report = Report {
        model: model_name,
        nv: model.nv,
        states: n,
        ns_per_call,
    };
    let mut text = format!(
        "{} (nv = {}, {} states): median ns per call\n",
        report.model, report.nv, n
    );
    let p = &report.ns_per_call;
    for (k, v) in [
        ("fk", p.fk),
        ("com", p.com),
        ("rnea", p.rnea),
        ("crba", p.crba),
        ("aba", p.aba),
        ("jacobians", p.jacobians),
        ("regressor", p.regressor),
    ] {
        text += &format!("  {k:<10} {v:>10.1}\n");
    }
    emit(&text, args.json.as_ref(), &report)?;
    Ok(Outcome::Ok)
}

/// Median ns per call of each algorithm over the states.
fn time_algorithms(
    model: &Model,
    s: &States,
    secs: f64,
    bar: &indicatif::ProgressBar,
) -> NsPerCall {
    let n = s.q.len();
    let mut d = Data::new(model);
    let step = |name: &str| {
        bar.set_message(name.to_string());
        bar.inc(1);
    };
    use twinloop_dynamics as dy;
    step("fk");
    let fk = time(n, secs, || {
        for q in &s.q {
            dy::forward_kinematics(model, &mut d, black_box(q));
        }
        black_box(&d.o_m_i);
    });
    step("com");
    let com = time(n, secs, || {
        for q in &s.q {
            black_box(dy::center_of_mass(model, &mut d, black_box(q)));
        }
    });
    step("rnea");
    let rnea = time(n, secs, || {
        for i in 0..n {
            black_box(dy::rnea(
                model,
                &mut d,
                black_box(&s.q[i]),
                &s.v[i],
                &s.a[i],
            ));
        }
    });
    step("crba");
    let crba = time(n, secs, || {
        for q in &s.q {
            black_box(dy::crba(model, &mut d, black_box(q)));
        }
    });
    step("aba");
    let aba = time(n, secs, || {
        for i in 0..n {
            black_box(dy::aba(
                model,
                &mut d,
                black_box(&s.q[i]),
                &s.v[i],
                &s.tau[i],
            ));
        }
    });
    step("jacobians");
    let jacobians = time(n, secs, || {
        for q in &s.q {
            dy::compute_joint_jacobians(model, &mut d, black_box(q));
            black_box(&d.joint_jacobians);
        }
    });
    step("regressor");
    let regressor = time(n, secs, || {
        for i in 0..n {
            black_box(dy::joint_torque_regressor(
                model,
                &mut d,
                black_box(&s.q[i]),
                &s.v[i],
                &s.a[i],
            ));
        }
    });
    NsPerCall {
        fk,
        com,
        rnea,
        crba,
        aba,
        jacobians,
        regressor,
    }
}
