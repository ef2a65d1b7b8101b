//! `twinloop gait sequence|dataset`: seed 003's walking sequence as joint goals, and
//! the walking identification dataset recorded on lab17 in the simulator.

use crate::common::EXIT_BAD_INPUT;
use clap::{Args, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;
use twinloop_experiments::{DatasetOptions, record_walk};
use twinloop_gait::{
    SEED_CYCLE_PERIOD, SEED_SAMPLE_TIME, SEED_SAMPLES, SequenceOptions, walking_sequence_with,
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
    ///
    /// Validation run (cycles 11-20, other noise): twinloop gait dataset --seed 2 --skip-samples 1000 --out lab17_walk_val.csv
    ///
    /// Output: a CSV with `t` (s), `u:<joint>` (the ten offsets of seed 003 eq 6, servo
    /// degrees) and `gyro:l_foot.roll|pitch|yaw`, `gyro:r_foot.roll|pitch|yaw` (deg/s). Use
    /// another --seed for a validation record. stderr says whether the robot fell.
    Dataset(DatasetArgs),
    /// Seed 003's identification of a recorded walk: 24th-order ARX, then ARX -> reduce -> PEM
    ///
    /// The initial model is the MIMO ARX of section 7.1 (na 24, nb 12, nk 1); the final one
    /// the state-space model of section 7.2: the ARX realised in state space, reduced by
    /// balanced truncation to the order whose Hankel singular values carry 90 % of their
    /// sum (or --order), refined by the prediction-error method with the simulation focus
    /// (output error, K = 0; --focus prediction estimates K). Inputs are the record's `u:`
    /// columns minus exact copies (the seed's knee and hip pitch move together, and the
    /// two ankle rolls), outputs its six `gyro:` rates; the estimation record's means are
    /// removed first (--no-detrend keeps them).
    ///
    /// Example (estimation record, validation record = cycles 11-20, identification):
    ///
    /// twinloop gait dataset --out est.csv
    ///
    /// twinloop gait dataset --seed 2 --skip-samples 1000 --out val.csv
    ///
    /// twinloop gait identify --data est.csv --val val.csv --json walk_id.json --report-arx arx.html --report ss.html
    ///
    /// Output: a table of FIT per output (MATLAB compare: 100 (1 - |y - yhat| / |y - mean y|),
    /// simulation and one-step prediction, on --val when given) for both models beside the
    /// seed's; the JSON holds both models (ARX `A`, `B`; state space `A`, `B`, `C`, `D`, `K`),
    /// their `fit_percent`, Hankel singular values and residual tests.
    Identify(IdentifyArgs),
}

#[derive(Args)]
pub struct TimingArgs {
    /// Robot: only builtin:lab17 carries seed 003's trims.
    #[arg(long, default_value = "builtin:lab17")]
    pub robot: String,
    /// Control tick and sample time, s (40 ms: two 20 ms servo PWM frames, and below the
    /// 57 ms the seed's 54.8 rad/s model bandwidth allows).
    #[arg(long, default_value_t = SEED_SAMPLE_TIME)]
    pub sample_time: f64,
    /// Duration of one step cycle (Step_State 0 to 100), s. Below ~3.5 s lab17 falls (seed
    /// 003 section 5: too fast a step cycle leaves the inertial forces undamped).
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
    #[arg(long, default_value_t = twinloop_experiments::walk::MPU6050_GYRO_NOISE_DEG_S)]
    pub gyro_noise: f64,
    /// Two-loop servo position gain, 1/s (60: full speed beyond 6 degrees of error).
    #[arg(long, default_value_t = twinloop_experiments::walk::LD2015_KP_POSITION)]
    pub kp_position: f64,
    #[arg(long)]
    pub out: PathBuf,
}

#[derive(Clone, Copy, clap::ValueEnum)]
pub enum FocusArg {
    /// Output error (K = 0): the simulation error is minimised, as the seed compares models.
    Simulation,
    /// Innovations form (K estimated): the one-step prediction error is minimised.
    Prediction,
}

#[derive(Clone, Copy, clap::ValueEnum)]
pub enum WeightArg {
    Identity,
    Noise,
}

#[derive(Args)]
pub struct IdentifyArgs {
    /// Estimation record from `twinloop gait dataset`.
    #[arg(long, value_name = "FILE.csv")]
    pub data: PathBuf,
    /// Validation record (the FIT is reported on it): e.g. --skip-samples 1000 --seed 2.
    #[arg(long, value_name = "FILE.csv")]
    pub val: Option<PathBuf>,
    /// ARX output lags (seed 003: 24).
    #[arg(long, default_value_t = 24)]
    pub na: usize,
    /// ARX input lags (12: the largest full-rank order on the periodic walk inputs).
    #[arg(long, default_value_t = 12)]
    pub nb: usize,
    #[arg(long, default_value_t = 1)]
    pub nk: usize,
    /// States of the final model (default: from the ARX's Hankel singular values).
    #[arg(long)]
    pub order: Option<usize>,
    /// Share of the Hankel-singular-value sum the default order keeps.
    #[arg(long, default_value_t = 0.9)]
    pub hsv_energy: f64,
    /// What the prediction-error search minimises.
    #[arg(long, value_enum, default_value = "simulation")]
    pub focus: FocusArg,
    /// Output weighting of the prediction-error cost: `noise` (default) divides by the
    /// initial model's error covariance (MATLAB's det criterion at the start), `identity`
    /// sums the squared errors.
    #[arg(long, value_enum, default_value = "noise")]
    pub weight: WeightArg,
    /// Keep the records' means (default: remove the estimation record's).
    #[arg(long)]
    pub no_detrend: bool,
    /// Iteration limit of the prediction-error search.
    #[arg(long, default_value_t = 100)]
    pub max_iter: usize,
    /// Largest pole radius the search may give A: a damping margin (0.999 at 40 ms: a 40 s
    /// time constant, longer than the record).
    #[arg(long, default_value_t = 0.999)]
    pub max_pole_radius: f64,
    #[arg(long, value_name = "OUT.json")]
    pub json: Option<PathBuf>,
    /// HTML report of the final state-space model (the seed's Figs. 53-55 and residuals).
    #[arg(long, value_name = "OUT.html")]
    pub report: Option<PathBuf>,
    /// HTML report of the initial ARX model (the seed's Figs. 50-52 and residuals).
    #[arg(long, value_name = "OUT.html")]
    pub report_arx: Option<PathBuf>,
}

fn read_table(p: &std::path::Path, flag: &str) -> Result<Table, String> {
    Table::read(p).map_err(|e| format!("{flag} {}: {e}", p.display()))
}

fn identify(a: &IdentifyArgs) -> Result<(), String> {
    use serde_json::json;
    use twinloop_ident::walk_identification::{WalkIdOptions, identify_walk};
    use twinloop_sysid::report::{arx_report, seed_reference_fits, state_space_report};
    let est = read_table(&a.data, "--data")?;
    let val = match &a.val {
        Some(p) => Some(read_table(p, "--val")?),
        None => None,
    };
    if let Some(v) = &val
        && v.columns != est.columns
    {
        return Err(format!(
            "--val {}: its columns differ from --data's",
            a.val
                .as_ref()
                .map(|p| p.display().to_string())
                .unwrap_or_default()
        ));
    }
    let o = WalkIdOptions {
        arx: twinloop_sysid::ArxOrders {
            na: a.na,
            nb: a.nb,
            nk: a.nk,
        },
        order: a.order,
        hsv_energy: a.hsv_energy,
        output_error: matches!(a.focus, FocusArg::Simulation),
        weight: match a.weight {
            WeightArg::Identity => twinloop_sysid::pem::OutputWeight::Identity,
            WeightArg::Noise => twinloop_sysid::pem::OutputWeight::InverseNoise,
        },
        detrend: !a.no_detrend,
        max_iterations: a.max_iter,
        max_pole_radius: a.max_pole_radius,
    };
    let bar = crate::progress::steps(a.max_iter);
    bar.set_message("prediction-error search");
    let id = identify_walk(
        &est.columns,
        &est.rows,
        val.as_ref().map(|v| v.rows.as_slice()),
        &o,
        &mut |p| {
            bar.set_position(p.iteration as u64);
            bar.set_message(format!("cost {:.4e}", p.cost));
        },
    )
    .map_err(|e| {
        let m = e.to_string();
        match m.strip_prefix("hsv_energy") {
            Some(rest) => format!("--hsv-energy{rest}"),
            None => format!("{}: {m}", a.data.display()),
        }
    });
    bar.finish_and_clear();
    let id = id?;
    let refs = seed_reference_fits();
    let pct = |v: &Option<f64>| v.map_or("-".to_string(), |x| format!("{x:.1}"));
    println!(
        "inputs: {} ({} dropped as copies: {})",
        id.inputs.join(","),
        id.dropped.len(),
        id.dropped
            .iter()
            .map(|(d, c)| format!("{d} = {c}"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    println!(
        "final order: {}; PEM ({}): {}",
        id.order_reason,
        if o.output_error {
            "simulation focus, K = 0"
        } else {
            "prediction focus, K estimated"
        },
        id.ss
            .pem
            .as_ref()
            .map(|p| format!(
                "{} iterations, cost {:.4e} -> {:.4e} ({})",
                p.iterations, p.initial_cost, p.final_cost, p.termination
            ))
            .unwrap_or_default()
    );
    println!(
        "FIT % on the {} record (sim = simulation, pred = one-step prediction):",
        id.ss.evaluation.data
    );
    println!(
        "  {:<20} {:>8} {:>8} {:>8} | {:>8} {:>8} {:>8}",
        "output", "seed ARX", "ARX sim", "ARX pred", "seed SS", "SS sim", "SS pred"
    );
    let (af, sf) = (
        &id.arx.evaluation.fit_percent,
        &id.ss.evaluation.fit_percent,
    );
    for (k, name) in id.outputs.iter().enumerate() {
        let seed = |r: usize| {
            refs.get(r)
                .and_then(|r| r.values.get(k))
                .map_or("-".to_string(), |v| format!("{v:.0}"))
        };
        println!(
            "  {:<20} {:>8} {:>8} {:>8} | {:>8} {:>8} {:>8}",
            name,
            seed(0),
            pct(&af.simulation[k]),
            pct(&af.prediction[k]),
            seed(1),
            pct(&sf.simulation[k]),
            pct(&sf.prediction[k])
        );
    }
    let ev_arx = id.validation.as_ref().unwrap_or(&id.estimation);
    if let Some(p) = &a.report_arx {
        arx_report(&id.arx, ev_arx, &command_line(), &refs[..1]).write(p)?;
    }
    if let Some(p) = &a.report {
        state_space_report(&id.ss, ev_arx, &command_line(), &refs[1..]).write(p)?;
    }
    if let Some(p) = &a.json {
        let rows = |m: &nalgebra::DMatrix<f64>| {
            (0..m.nrows())
                .map(|i| m.row(i).iter().copied().collect::<Vec<f64>>())
                .collect::<Vec<_>>()
        };
        fn val<T: serde::Serialize>(x: &T) -> serde_json::Value {
            serde_json::to_value(x).unwrap_or(serde_json::Value::Null)
        }
        let m = &id.ss.model;
        let v = json!({
            "kind": "seed003_walk_identification",
            "data": {
                "estimation": a.data.display().to_string(),
                "validation": a.val.as_ref().map(|p| p.display().to_string()),
                "inputs": id.inputs,
                "dropped_inputs": id.dropped,
                "outputs": id.outputs,
                "offsets": id.offsets.as_ref().map(|(u, y)| json!({"inputs": u, "outputs": y})),
            },
            "arx": {
                "orders": {"na": a.na, "nb": a.nb, "nk": a.nk},
                "A": id.arx.model.a.iter().map(rows).collect::<Vec<_>>(),
                "B": id.arx.model.b.iter().map(rows).collect::<Vec<_>>(),
                "fit_percent": val(&id.arx.evaluation.fit_percent),
                "estimation_fit_percent": val(&id.arx.estimation_fit),
                "prediction_cost": id.arx.evaluation.prediction_cost,
                "hankel_singular_values": val(&id.arx.evaluation.hankel_singular_values),
                "frequency_response": val(&id.arx.evaluation.frequency_response),
                "residual_tests": val(&id.arx.evaluation.residual_tests),
            },
            "state_space": {
                "order": id.order,
                "order_reason": id.order_reason,
                "focus": if o.output_error { "simulation" } else { "prediction" },
                "weight": match a.weight { WeightArg::Identity => "identity", WeightArg::Noise => "inverse_noise" },
                "A": rows(&m.a), "B": rows(&m.b), "C": rows(&m.c), "D": rows(&m.d), "K": rows(&m.k),
                "spectral_radius": m.spectral_radius(),
                "fit_percent": val(&id.ss.evaluation.fit_percent),
                "estimation_fit_percent": val(&id.ss.estimation_fit),
                "prediction_cost": id.ss.evaluation.prediction_cost,
                "hankel_singular_values": val(&id.ss.evaluation.hankel_singular_values),
                "frequency_response": val(&id.ss.evaluation.frequency_response),
                "residual_tests": val(&id.ss.evaluation.residual_tests),
                "stages": val(&id.ss.stages),
                "pem": val(&id.ss.pem),
                "warnings": id.ss.warnings,
            },
            "seed_fit_percent": {"initial": refs.first().map(|r| r.values.clone()), "final": refs.get(1).map(|r| r.values.clone())},
        });
        let text =
            serde_json::to_string_pretty(&v).map_err(|e| format!("cannot write JSON: {e}"))?;
        std::fs::write(p, text + "\n").map_err(|e| format!("--json {}: {e}", p.display()))?;
    }
    Ok(())
}

fn command_line() -> String {
    std::env::args().collect::<Vec<_>>().join(" ")
}

fn lab17_only(spec: &str) -> Result<twinloop_description::Description, String> {
    let robot =
        twinloop_description::builtin::resolve(spec).map_err(|e| format!("--robot: {e}"))?;
    if robot.name != twinloop_description::builtin::lab17::NAME {
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
        GaitCommand::Identify(a) => identify(&a),
    };
    match r {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(EXIT_BAD_INPUT)
        }
    }
}
