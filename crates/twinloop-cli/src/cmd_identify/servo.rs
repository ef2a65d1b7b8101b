//! `twinloop identify servo`: a servo model fitted to `experiment servo` logs.

use crate::common::{JSON_HELP, emit};
use crate::error::{CliError, CliResult, Outcome};
use clap::Args;
use serde_json::json;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;
use twinloop_actuator::group::{
    Comparison, DIFFER_P, GroupFit, GroupIdentification, MIN_SPREAD, ServoData, identify_servos,
};
use twinloop_actuator::identify::{Identification, IdentifyOptions, identify_with};
use twinloop_actuator::log::{SERVO_LOG_NOTE, ServoLog};
use twinloop_actuator::params::{N_PARAMS, NONSMOOTH, PARAM_NAMES};
use twinloop_actuator::replay::replay;
use twinloop_actuator::{Load, ModelLevel, Pendulum, ServoParams, ServoType, bam_log, datasheet};

#[derive(Args, Debug)]
pub struct ServoIdArgs {
    /// Logs to fit (`experiment servo --out`, or BAM's pendulum logs: `.json`, or its
    /// column form, whose first line is a JSON object); with no --holdout, the last
    /// --holdout-fraction of each is kept out of the fit and scored. `ID=LOG.csv`
    /// says which servo a log is of (else the id its first line names): logs of
    /// several servos of one type are fitted together (see --shared)
    #[arg(long, value_name = "[ID=]LOG.csv", num_args = 1.., required_unless_present = "defaults")]
    pub data: Vec<String>,
    /// Logs scored but not fitted (`ID=LOG.csv` as for --data)
    #[arg(long, value_name = "[ID=]LOG.csv", num_args = 1..)]
    pub holdout: Vec<String>,
    /// The pendulum the logs were recorded with (mass, length, arm_inertia); several
    /// servos: `ID=LOAD.toml` for one servo's, repeatable, a plain file for the rest.
    /// BAM's logs name theirs; without it, the logs of a limb (`experiment servo --map
    /// --joint`) rebuild their load from the robot, joint and held pose they record
    #[arg(long, value_name = "[ID=]LOAD.toml", num_args = 1..)]
    pub load: Vec<String>,
    /// Limb logs: compute the load from this description instead of the one the log
    /// names (a file moved, or a corrected model)
    #[arg(long, value_name = "ROBOT", conflicts_with = "load")]
    pub robot: Option<String>,
    /// Several servos: the parameters held in common (comma list; `none`: every
    /// parameter per servo); the rest are fitted per servo. Default: the test
    /// decides (each servo fitted alone; a parameter is per servo where the servos'
    /// values differ beyond their deviations, chi-square p < 0.01 over the
    /// parameters tested)
    #[arg(long, value_delimiter = ',', value_name = "LIST")]
    pub shared: Vec<String>,
    /// Threads: servos simulated at once, or one servo's fit's simulations (the
    /// Jacobian's columns, the CMA-ES population) (0: every core)
    #[arg(long, default_value_t = 0, value_name = "N")]
    pub threads: usize,
    /// The model ladder's rung: m1 (Coulomb + viscous), m2 (+ Stribeck), m3 (+ load-dependent), m4 (both)
    #[arg(long, default_value = "m1", value_name = "NAME")]
    pub model: String,
    /// The servo type, where the logs' first line does not name it
    #[arg(long, value_name = "MODEL")]
    pub servo: Option<String>,
    /// Start from these parameters (default: the datasheet's)
    #[arg(long, value_name = "FILE.toml")]
    pub start: Option<PathBuf>,
    /// Share of each log held out when no --holdout is given
    #[arg(long, default_value_t = 0.25, value_parser = crate::common::positive)]
    pub holdout_fraction: f64,
    /// Also fit these (comma list): backlash (by CMA-ES, alternating with LM: the dead
    /// band is not smooth), sensing_delay, bus_delay (by LM with the rest). Needs the
    /// excitation's slow back-and-forth through zero load (backlash) and its steps
    #[arg(long, value_delimiter = ',', value_name = "LIST")]
    pub fit: Vec<String>,
    /// Write the datasheet parameters of MODEL to --out and stop
    #[arg(long, value_name = "MODEL")]
    pub defaults: Option<String>,
    /// The parameter file written (`serve --servo-params` reads it); several servos:
    /// a directory, one `id-N.toml` per servo (`--servo-params N=DIR/id-N.toml`)
    #[arg(long, value_name = "FILE.toml|DIR")]
    pub out: Option<PathBuf>,
    /// Also write the result as one MCAP (docs/logs.md): each log's measured
    /// signals, the start's and the fitted parameters' replay of them, the fitted
    /// parameter file attached; several servos: each on topics of its own
    /// (`/id3/measured` ..), each file attached
    #[arg(long, value_name = "RESULT.mcap")]
    pub mcap: Option<PathBuf>,
    #[arg(long, value_name = "FILE", help = JSON_HELP)]
    pub json: Option<PathBuf>,
}

fn parse_servo(text: &str, option: &str) -> Result<ServoType, CliError> {
    ServoType::parse(text).ok_or_else(|| {
        CliError::new(format!(
            "{option} {text:?}: no servo model (known: {})",
            ServoType::known_names()
        ))
    })
}

pub fn run(a: &ServoIdArgs) -> CliResult {
    let level = ModelLevel::parse(&a.model)
        .ok_or_else(|| CliError::new(format!("--model {:?}: m1, m2, m3 or m4", a.model)))?;
    if let Some(m) = &a.defaults {
        let p = datasheet::defaults(parse_servo(m, "--defaults")?, level);
        let out = a.out.as_ref().ok_or("--defaults needs --out FILE.toml")?;
        let text = p.to_toml("datasheet values (twinloop identify servo --defaults): docs/servo-models.md says where each comes from");
        twinloop_io::output::write_atomic(out, text)?;
        return Ok(Outcome::Ok);
    }
    let options = fit_options(a)?;
    if a.holdout_fraction >= 1.0 {
        return Err(CliError::new("--holdout-fraction must be below 1"));
    }
    let servo = a
        .servo
        .as_deref()
        .map(|s| parse_servo(s, "--servo"))
        .transpose()?;
    // The load files first: small, typed by hand, and cheaper to get right than a log.
    for arg in &a.load {
        Pendulum::read(Path::new(keyed(arg, "--load")?.1))?;
    }
    // BAM's logs (JSON, or its column form) carry their pendulum; ours name it in
    // --load.
    let mut bam_loads: Vec<(String, Pendulum)> = Vec::new();
    let logs = read_logs(&a.data, servo, &mut bam_loads)?;
    let holdout = read_logs(&a.holdout, servo, &mut bam_loads)?;
    let bam_load = one_bam_load(a, &bam_loads)?;
    // Limb logs (`experiment servo --map --joint`) rebuild their load.
    let limb = if a.load.is_empty() && bam_load.is_none() {
        let paths = a
            .data
            .iter()
            .chain(&a.holdout)
            .map(|arg| keyed(arg, "--data").map(|(_, p)| PathBuf::from(p)))
            .collect::<Result<Vec<_>, _>>()?;
        Some(limb_load(paths.iter(), a.robot.as_deref())?)
    } else {
        None
    };
    let servo = logs
        .first()
        .and_then(|(_, l)| l.servo)
        .ok_or("identify servo needs --data LOG.csv naming its servo (or --servo MODEL)")?;
    let start = match &a.start {
        Some(p) => ServoParams::read(p)?.with_level(level),
        None => datasheet::defaults(servo, level),
    };
    let mut ids: Vec<Option<u8>> = logs.iter().map(|(k, _)| *k).collect();
    ids.sort();
    ids.dedup();
    if ids.len() > 1 {
        if limb.is_some() {
            return Err(CliError::new(
                "limb logs of several servos: fit each servo's logs alone",
            ));
        }
        return run_group(a, &ids, logs, holdout, &start, level, bam_load);
    }
    if bam_load.is_none()
        && limb.is_none()
        && (a.load.len() != 1 || keyed(&a.load[0], "--load")?.0.is_some())
    {
        return Err(CliError::new(
            "--load: one servo's logs take one plain LOAD.toml",
        ));
    }
    if !a.shared.is_empty() {
        return Err(CliError::new(
            "--shared: the logs are of one servo (several: ID=LOG.csv or logs naming different ids)",
        ));
    }
    let load = match (bam_load, limb) {
        (Some(load), _) => Load::from(load),
        (None, Some(load)) => load,
        (None, None) => Load::from(Pendulum::read(Path::new(&a.load[0]))?),
    };
    let logs: Vec<ServoLog> = logs.into_iter().map(|(_, l)| l).collect();
    let holdout: Vec<ServoLog> = holdout.into_iter().map(|(_, l)| l).collect();
    run_one(a, &logs, &holdout, &load, &start, &options)
}

/// `--fit`: the non-smooth parameters fitted besides the rung's.
fn fit_options(a: &ServoIdArgs) -> Result<IdentifyOptions, CliError> {
    let mut options = IdentifyOptions::default();
    for name in &a.fit {
        let i = NONSMOOTH
            .into_iter()
            .find(|&i| PARAM_NAMES[i] == name.trim())
            .ok_or_else(|| {
                CliError::new(format!(
                    "--fit {name:?}: backlash, sensing_delay or bus_delay"
                ))
            })?;
        options.nonsmooth.push(i);
    }
    Ok(options)
}

/// The logs of `--data` or `--holdout` (`[ID=]PATH`), each with the servo id it is
/// of; a BAM log's pendulum is added to `bam_loads`.
fn read_logs(
    args: &[String],
    servo: Option<ServoType>,
    bam_loads: &mut Vec<(String, Pendulum)>,
) -> Result<Vec<(Option<u8>, ServoLog)>, CliError> {
    args.iter()
        .map(|arg| {
            let (key, path) = keyed(arg, "--data")?;
            let path = Path::new(path);
            let log = if bam_log::is_bam_log(path) {
                let b = bam_log::read(path, servo)?;
                bam_loads.push((path.display().to_string(), b.load));
                b.log
            } else if twinloop_logs::is_log(path) {
                read_recorded_log(path, servo)?
            } else {
                ServoLog::read(path, servo).map_err(CliError::from)?
            };
            Ok((key.or(log.id), log))
        })
        .collect()
}

/// The one pendulum BAM's logs name, when no --load is given.
fn one_bam_load(
    a: &ServoIdArgs,
    bam_loads: &[(String, Pendulum)],
) -> Result<Option<Pendulum>, CliError> {
    match bam_loads.first() {
        Some((first, load)) if a.load.is_empty() => {
            if let Some((p, _)) = bam_loads.iter().find(|(_, l)| l != load) {
                return Err(CliError::new(format!(
                    "{p}: a pendulum other than {first}'s (one fit, one load); give --load LOAD.toml"
                )));
            }
            Ok(Some(*load))
        }
        _ => Ok(None),
    }
}

/// One servo's fit and what it writes: the parameter file, the MCAP, the summary.
fn run_one(
    a: &ServoIdArgs,
    logs: &[ServoLog],
    holdout: &[ServoLog],
    load: &Load,
    start: &ServoParams,
    options: &IdentifyOptions,
) -> CliResult {
    let t0 = Instant::now();
    let id = twinloop_optim::parallel::on_threads(a.threads, || {
        identify_with(logs, holdout, load, start, a.holdout_fraction, options)
    })?;
    let seconds = t0.elapsed().as_secs_f64();
    let comment = format!(
        "fitted by twinloop identify servo ({} rows in {} logs); held-out error {:.3} mrad RMS",
        logs.iter().map(ServoLog::len).sum::<usize>(),
        logs.len(),
        id.heldout_rms_mrad
    ) + &not_determined_note(&id.intervals);
    let fitted = id.params.to_toml(&comment);
    if let Some(out) = &a.out {
        twinloop_io::output::write_atomic(out, &fitted)?;
    }
    if let Some(path) = &a.mcap {
        let all: Vec<&ServoLog> = logs.iter().chain(holdout).collect();
        write_result_mcap(path, a, &all, load, (start, &id.params), &fitted)?;
    }
    emit(&text(&id, seconds), a.json.as_ref(), &to_json(&id, seconds))?;
    Ok(Outcome::Ok)
}

/// `ID=PATH` (ID a servo id: digits before '=') or `PATH`.
fn keyed<'a>(arg: &'a str, option: &str) -> Result<(Option<u8>, &'a str), CliError> {
    match arg.split_once('=') {
        Some((k, path)) if !k.is_empty() && k.chars().all(|c| c.is_ascii_digit()) => {
            let id = k
                .parse::<u8>()
                .ok()
                .filter(|&id| id <= 253)
                .ok_or_else(|| CliError::new(format!("{option} {arg:?}: a servo id is 0-253")))?;
            Ok((Some(id), path))
        }
        _ => Ok((None, arg)),
    }
}

fn servo_name(id: Option<u8>) -> String {
    id.map_or_else(|| "no id".to_string(), |i| format!("id {i}"))
}

/// Several servos of one type: fitted alone and together, the parameters that
/// differ per servo and the rest shared (or as --shared says).
fn run_group(
    a: &ServoIdArgs,
    ids: &[Option<u8>],
    logs: Vec<(Option<u8>, ServoLog)>,
    holdout: Vec<(Option<u8>, ServoLog)>,
    start: &ServoParams,
    level: ModelLevel,
    bam_load: Option<Pendulum>,
) -> CliResult {
    check_group(a, ids, &logs, &holdout)?;
    let loads = group_loads(a, ids, bam_load)?;
    let shared = shared_list(a, level)?;
    let servos = group_servos(ids, &logs, &holdout, &loads)?;
    let threads = match a.threads {
        0 => std::thread::available_parallelism().map_or(1, |n| n.get()),
        n => n,
    };
    let t0 = Instant::now();
    let id = identify_servos(
        &servos,
        start,
        shared.as_deref(),
        a.holdout_fraction,
        threads,
    )?;
    let seconds = t0.elapsed().as_secs_f64();
    let fits = group_fits(&servos, &id);
    let mut files = Vec::new();
    if let Some(dir) = &a.out {
        std::fs::create_dir_all(dir).map_err(|e| CliError::io(dir, e))?;
        for (name, _, toml) in &fits {
            let path = dir.join(format!("{}.toml", name.replace(' ', "-")));
            twinloop_io::output::write_atomic(&path, toml)?;
            files.push(path);
        }
    }
    if let Some(path) = &a.mcap {
        write_group_mcap(path, a, &servos, start, &fits)?;
        files.push(path.clone());
    }
    emit(
        &group_text(&id, &files, seconds),
        a.json.as_ref(),
        &group_json(&id, &files, seconds),
    )?;
    Ok(Outcome::Ok)
}

/// What a group refuses before reading its loads: a log without a servo id, `--fit`,
/// a held-out log of a servo with no `--data` log.
fn check_group(
    a: &ServoIdArgs,
    ids: &[Option<u8>],
    logs: &[(Option<u8>, ServoLog)],
    holdout: &[(Option<u8>, ServoLog)],
) -> Result<(), CliError> {
    if let Some((_, l)) = logs.iter().find(|(k, _)| k.is_none()) {
        return Err(CliError::new(format!(
            "{}: line 1: names no servo id, and the other logs are of several servos: give ID={}",
            l.file, l.file
        )));
    }
    if !a.fit.is_empty() {
        return Err(CliError::new(
            "--fit: several servos are fitted with the rung's parameters only (fit backlash and delays per servo)",
        ));
    }
    if let Some((k, l)) = holdout.iter().find(|(k, _)| !ids.contains(k)) {
        return Err(CliError::new(format!(
            "--holdout {}: {} has no --data log",
            l.file,
            servo_name(*k)
        )));
    }
    Ok(())
}

/// A group's loads: the plain one (a `--load FILE`, else BAM's) and each servo's own
/// (`--load ID=FILE`).
struct GroupLoads {
    plain: Option<Pendulum>,
    own: Vec<(u8, Pendulum)>,
}

fn group_loads(
    a: &ServoIdArgs,
    ids: &[Option<u8>],
    bam_load: Option<Pendulum>,
) -> Result<GroupLoads, CliError> {
    let mut plain = bam_load;
    let mut own: Vec<(u8, Pendulum)> = Vec::new();
    for arg in &a.load {
        match keyed(arg, "--load")? {
            (None, path) => {
                if plain.is_some() {
                    return Err(CliError::new(
                        "--load: two plain files; give ID=LOAD.toml for a servo's own",
                    ));
                }
                plain = Some(Pendulum::read(Path::new(path))?);
            }
            (Some(id), path) => {
                if !ids.contains(&Some(id)) {
                    return Err(CliError::new(format!(
                        "--load {arg}: no --data log is of servo id {id}"
                    )));
                }
                own.push((id, Pendulum::read(Path::new(path))?));
            }
        }
    }
    Ok(GroupLoads { plain, own })
}

/// `--shared`: the parameter indices held in common (None: the test decides).
fn shared_list(a: &ServoIdArgs, level: ModelLevel) -> Result<Option<Vec<usize>>, CliError> {
    if a.shared.is_empty() {
        return Ok(None);
    }
    let mut list = Vec::new();
    for name in &a.shared {
        let name = name.trim();
        if name == "none" {
            continue;
        }
        let i = level
            .parameters()
            .into_iter()
            .find(|&i| PARAM_NAMES[i] == name)
            .ok_or_else(|| {
                CliError::new(format!(
                    "--shared {name:?}: not a parameter of {} ({})",
                    level.name(),
                    level
                        .parameters()
                        .iter()
                        .map(|&i| PARAM_NAMES[i])
                        .collect::<Vec<_>>()
                        .join(", ")
                ))
            })?;
        list.push(i);
    }
    Ok(Some(list))
}

/// Each servo's logs, held-out logs and load, in the order of `ids`.
fn group_servos(
    ids: &[Option<u8>],
    logs: &[(Option<u8>, ServoLog)],
    holdout: &[(Option<u8>, ServoLog)],
    loads: &GroupLoads,
) -> Result<Vec<ServoData>, CliError> {
    let mut servos = Vec::new();
    for &id in ids {
        let id = id.expect("checked above");
        let load = loads
            .own
            .iter()
            .find(|(k, _)| *k == id)
            .map(|(_, l)| *l)
            .or(loads.plain)
            .ok_or_else(|| {
                CliError::new(format!(
                    "--load: no file for servo id {id} (ID=LOAD.toml or a plain LOAD.toml)"
                ))
            })?;
        servos.push(ServoData {
            name: servo_name(Some(id)),
            logs: logs
                .iter()
                .filter(|(k, _)| *k == Some(id))
                .map(|(_, l)| l.clone())
                .collect(),
            holdout: holdout
                .iter()
                .filter(|(k, _)| *k == Some(id))
                .map(|(_, l)| l.clone())
                .collect(),
            load,
        });
    }
    Ok(servos)
}

/// Each servo's fitted file: its name, parameters and text.
fn group_fits<'a>(
    servos: &[ServoData],
    id: &'a GroupIdentification,
) -> Vec<(String, &'a ServoParams, String)> {
    servos
        .iter()
        .zip(&id.chosen.servos)
        .map(|(s, f)| {
            let comment = format!(
                "fitted by twinloop identify servo with {} servos of one type ({} rows in {} logs of this one); shared: {}; own: {}; held-out error {:.3} mrad RMS",
                servos.len(),
                s.logs.iter().map(ServoLog::len).sum::<usize>(),
                s.logs.len(),
                names(&id.chosen.shared),
                names(&id.chosen.per_servo),
                f.heldout_rms_mrad
            );
            (f.name.clone(), &f.params, f.params.to_toml(&comment))
        })
        .collect()
}

fn names(list: &[usize]) -> String {
    if list.is_empty() {
        return "none".into();
    }
    list.iter()
        .map(|&i| PARAM_NAMES[i])
        .collect::<Vec<_>>()
        .join(", ")
}

/// The group's summary: the fit, the spread test, the answer, the held-out errors
/// and values, what the logs leave open and the files written.
fn group_text(id: &GroupIdentification, files: &[PathBuf], seconds: f64) -> String {
    let c = &id.comparison;
    let chosen = &id.chosen;
    let first = &chosen.servos[0].params;
    let mut s = format!(
        "{} model {}, {} servos ({}), fitted in {seconds:.2} s ({} servo simulations)\n",
        first.servo,
        first.level.name(),
        chosen.servos.len(),
        chosen
            .servos
            .iter()
            .map(|f| f.name.as_str())
            .collect::<Vec<_>>()
            .join(", "),
        c.each.simulations + c.all_shared.simulations + chosen.simulations
    );
    spread_lines(&mut s, c);
    answer_line(&mut s, c, chosen);
    value_lines(&mut s, c, chosen);
    let _ = writeln!(
        s,
        "not determined by these logs: {}",
        if chosen.undetermined.is_empty() {
            "nothing".to_string()
        } else {
            chosen.undetermined.join(", ")
        }
    );
    for (f, path) in chosen.servos.iter().zip(files) {
        let _ = writeln!(
            s,
            "wrote {} (--servo-params {}={})",
            path.display(),
            f.name.trim_start_matches("id "),
            path.display()
        );
    }
    s
}

/// "Do the servos differ?": the chi-square test of each parameter's spread.
fn spread_lines(s: &mut String, c: &Comparison) {
    let tested = c.spreads.iter().filter(|p| p.tested).count();
    let _ = writeln!(
        s,
        "do the servos differ? each fitted alone; chi-square of the values' spread against their deviations (robust to correlated residuals); differs where p < {:.1e} ({} over the {tested} parameters tested) and the spread exceeds {} %",
        DIFFER_P / tested.max(1) as f64,
        DIFFER_P,
        100.0 * MIN_SPREAD
    );
    let _ = writeln!(
        s,
        "  {:18} {:>9} {:>9} {:>10} {:>9}  verdict",
        "parameter", "spread %", "sd %", "chi2 (dof)", "p"
    );
    for p in &c.spreads {
        let _ = writeln!(
            s,
            "  {:18} {:>9.3} {:>9.3} {:>10} {:>9.1e}  {}",
            p.name,
            100.0 * p.relative_spread,
            100.0 * p.relative_sd,
            format!("{:.1} ({})", p.chi2, p.dof),
            p.p_value,
            if p.differs {
                "differs: per servo"
            } else if !p.tested {
                "not determined: not tested"
            } else if p.p_value < DIFFER_P / tested.max(1) as f64 {
                "differs by less than the fit's accuracy: shared"
            } else {
                "alike: one shared value suffices"
            }
        );
    }
}

/// The answer: which parameters each servo needs its own of, and what sharing costs
/// in held-out error against each servo's own fit.
fn answer_line(s: &mut String, c: &Comparison, chosen: &GroupFit) {
    let differing = c.differing();
    let alike: Vec<usize> = c
        .spreads
        .iter()
        .filter(|p| p.tested && !p.differs)
        .map(|p| p.index)
        .collect();
    let worst = |g: &GroupFit| {
        g.servos
            .iter()
            .zip(&c.each.servos)
            .map(|(f, e)| 100.0 * (f.heldout_rms_mrad / e.heldout_rms_mrad - 1.0))
            .fold(f64::NEG_INFINITY, f64::max)
    };
    let _ = writeln!(
        s,
        "answer: {}; held-out error against each servo's own fit: all shared up to {:+.1} %, chosen up to {:+.1} %",
        if differing.is_empty() {
            format!("one shared set suffices ({} alike)", names(&alike))
        } else if alike.is_empty() {
            format!("each servo needs its own {}", names(&differing))
        } else {
            format!(
                "each servo needs its own {}; {} can be shared",
                names(&differing),
                names(&alike)
            )
        },
        worst(&c.all_shared),
        worst(chosen)
    );
}

/// Each servo's held-out error under the three fits, then the chosen fit's shared
/// and per-servo values with their deviations.
fn value_lines(s: &mut String, c: &Comparison, chosen: &GroupFit) {
    let _ = writeln!(
        s,
        "held-out position error, mrad RMS: each alone / all shared / chosen (shared: {}; per servo: {})",
        names(&chosen.shared),
        names(&chosen.per_servo)
    );
    for ((e, a), f) in c
        .each
        .servos
        .iter()
        .zip(&c.all_shared.servos)
        .zip(&chosen.servos)
    {
        let _ = writeln!(
            s,
            "  {:8} {:>8.3} {:>8.3} {:>8.3}",
            f.name, e.heldout_rms_mrad, a.heldout_rms_mrad, f.heldout_rms_mrad
        );
    }
    let first = &chosen.servos[0].params;
    let sd0 = first.uncertainty.unwrap_or([f64::NAN; N_PARAMS]);
    for &i in &chosen.shared {
        let _ = writeln!(
            s,
            "  shared {:18} {:>12.6} +- {:.2e}",
            PARAM_NAMES[i], first.values[i], sd0[i]
        );
    }
    for f in &chosen.servos {
        let sd = f.params.uncertainty.unwrap_or([f64::NAN; N_PARAMS]);
        for &i in &chosen.per_servo {
            let _ = writeln!(
                s,
                "  {:6} {:18} {:>12.6} +- {:.2e}",
                f.name, PARAM_NAMES[i], f.params.values[i], sd[i]
            );
        }
    }
}

fn group_fit_json(g: &GroupFit) -> serde_json::Value {
    json!({
        "shared": g.shared.iter().map(|&i| PARAM_NAMES[i]).collect::<Vec<_>>(),
        "per_servo": g.per_servo.iter().map(|&i| PARAM_NAMES[i]).collect::<Vec<_>>(),
        "n_params": g.n_params,
        "iterations": g.iterations,
        "simulations": g.simulations,
        "undetermined": g.undetermined,
        "servos": g.servos.iter().map(|f| {
            let sd = f.params.uncertainty.unwrap_or([f64::NAN; N_PARAMS]);
            let params: serde_json::Map<String, serde_json::Value> = g
                .shared
                .iter()
                .chain(&g.per_servo)
                .map(|&i| {
                    (
                        PARAM_NAMES[i].to_string(),
                        json!({"value": f.params.values[i], "sd": sd[i], "sd_independent": f.sd_independent[i]}),
                    )
                })
                .collect();
            json!({
                "name": f.name,
                "voltage": f.params.voltage,
                "params": params,
                "combinations": f.combinations.iter().map(|(n, v, s)| json!({"name": n, "value": v, "sd": s})).collect::<Vec<_>>(),
                "fit_rms_mrad": f.fit_rms_mrad,
                "heldout_rms_mrad": f.heldout_rms_mrad,
                "heldout_mae_mrad": f.heldout_mae_mrad,
                "heldout_rows": f.heldout_rows,
            })
        }).collect::<Vec<_>>(),
    })
}

fn group_json(id: &GroupIdentification, files: &[PathBuf], seconds: f64) -> serde_json::Value {
    let c = &id.comparison;
    let first = &id.chosen.servos[0].params;
    json!({
        "servo": first.servo.name(),
        "model": first.level.name(),
        "spreads": c.spreads.iter().map(|p| json!({
            "name": p.name,
            "values": p.values,
            "sd": p.sd,
            "relative_spread": p.relative_spread,
            "relative_sd": p.relative_sd,
            "chi2": p.chi2,
            "dof": p.dof,
            "p_value": p.p_value,
            "tested": p.tested,
            "differs": p.differs,
        })).collect::<Vec<_>>(),
        "differ_p": DIFFER_P,
        "min_spread": MIN_SPREAD,
        "differing": c.differing().iter().map(|&i| PARAM_NAMES[i]).collect::<Vec<_>>(),
        "each": group_fit_json(&c.each),
        "all_shared": group_fit_json(&c.all_shared),
        "chosen": group_fit_json(&id.chosen),
        "files": files.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
        "seconds": seconds,
    })
}

/// `--mcap`: the logs' rows one after another (`--data`, then `--holdout`; each log
/// after the first shifted to start a second after the previous one ends, since
/// each log has its own clock): the measured `goal q v` (and `current` where the
/// servo senses it), and the start's and the fitted parameters' replay of `q` (and
/// `current`) from each log's first row ([`replay`]: the model the fit scores).
fn write_result_mcap(
    path: &Path,
    a: &ServoIdArgs,
    logs: &[&ServoLog],
    load: &Load,
    (start, fitted): (&ServoParams, &ServoParams),
    fitted_toml: &str,
) -> Result<(), CliError> {
    let rows = servo_rows("", logs, load, start, fitted);
    let result = crate::result_mcap::ResultLog {
        table: rows.table,
        measured: rows.measured,
        predicted: crate::result_mcap::prior_and_adapted(rows.prior, rows.adapted),
        robot: None,
        robot_file: "adapted.urdf",
        inputs: result_inputs(a)?,
        files: vec![(
            "fitted.toml".into(),
            "application/toml",
            fitted_toml.as_bytes().to_vec(),
        )],
        parts: Vec::new(),
    };
    crate::result_mcap::write(path, "identify servo", &result)
}

/// `--mcap` of several servos: each servo's rows as one servo's are written
/// ([`servo_rows`], its columns prefixed `id3.`), on topics of its own
/// (`/id3/measured`, `/id3/prior`, `/id3/adapted`), each servo on its logs' own
/// clock; its fitted parameter file (what `--out DIR` writes) attached as
/// `id-3.toml`.
fn write_group_mcap(
    path: &Path,
    a: &ServoIdArgs,
    servos: &[ServoData],
    start: &ServoParams,
    fits: &[(String, &ServoParams, String)],
) -> Result<(), CliError> {
    let mut parts = Vec::new();
    let mut files = Vec::new();
    for (s, (name, fitted, toml)) in servos.iter().zip(fits) {
        let key = name.replace(' ', "");
        let logs: Vec<&ServoLog> = s.logs.iter().chain(&s.holdout).collect();
        let rows = servo_rows(
            &format!("{key}."),
            &logs,
            &Load::from(s.load),
            start,
            fitted,
        );
        let topic = |t: &str, columns: Vec<String>| twinloop_logs::ArrayTopic {
            topic: format!("/{key}/{t}"),
            columns,
        };
        parts.push(crate::result_mcap::ResultPart {
            table: rows.table,
            topics: vec![
                topic("measured", rows.measured),
                topic("prior", rows.prior),
                topic("adapted", rows.adapted),
            ],
        });
        files.push((
            format!("{}.toml", name.replace(' ', "-")),
            "application/toml",
            toml.as_bytes().to_vec(),
        ));
    }
    let result = crate::result_mcap::ResultLog {
        table: twinloop_io::Table::new(vec!["t".to_string()]),
        measured: Vec::new(),
        predicted: Vec::new(),
        robot: None,
        robot_file: "adapted.urdf",
        inputs: result_inputs(a)?,
        files,
        parts,
    };
    crate::result_mcap::write(path, "identify servo", &result)
}

/// The inputs a result names (and hashes): the logs, the loads, the start.
fn result_inputs(a: &ServoIdArgs) -> Result<Vec<String>, CliError> {
    let mut inputs: Vec<String> = a
        .data
        .iter()
        .chain(&a.holdout)
        .map(|d| keyed(d, "--data").map(|(_, p)| p.to_string()))
        .collect::<Result<_, _>>()?;
    inputs.extend(
        a.load
            .iter()
            .map(|l| keyed(l, "--load").map(|(_, p)| p.to_string()))
            .collect::<Result<Vec<_>, _>>()?,
    );
    inputs.extend(a.start.iter().map(|p| p.display().to_string()));
    Ok(inputs)
}

/// One servo's logs as a result's rows: the table (`t`, then the measured, the
/// start's and the fit's columns, each name after `prefix`) and those three lists.
struct ServoRows {
    table: twinloop_io::Table,
    measured: Vec<String>,
    prior: Vec<String>,
    adapted: Vec<String>,
}

fn servo_rows(
    prefix: &str,
    logs: &[&ServoLog],
    load: &Load,
    start: &ServoParams,
    fitted: &ServoParams,
) -> ServoRows {
    let current = logs.iter().all(|l| l.current.is_some());
    let signals: &[&str] = if current { &["q", "current"] } else { &["q"] };
    let measured: Vec<String> = ["goal", "q", "v"]
        .iter()
        .chain(if current { &["current"][..] } else { &[] })
        .map(|c| format!("{prefix}{c}"))
        .collect();
    let predicted: Vec<String> = signals.iter().map(|c| format!("{prefix}{c}")).collect();
    let (prior, adapted, mut table) = crate::result_mcap::comparison_columns(&measured, &predicted);
    let mut offset = 0.0;
    for (k, log) in logs.iter().enumerate() {
        if k > 0 && !log.is_empty() {
            offset = table.rows.last().map_or(0.0, |r| r[0]) + 1.0 - log.t[0];
        }
        let n = log.len();
        let (mut q0, mut c0, mut q1, mut c1) =
            (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        replay(start, load, log, 0..n, &mut q0, &mut c0);
        replay(fitted, load, log, 0..n, &mut q1, &mut c1);
        for i in 0..n {
            let mut row = vec![log.t[i] + offset, log.goal[i], log.q[i], log.v[i]];
            let measured_current = log.current.as_ref().map(|c| c[i]);
            row.extend(measured_current);
            row.push(q0[i]);
            row.extend(measured_current.map(|_| c0[i]));
            row.push(q1[i]);
            row.extend(measured_current.map(|_| c1[i]));
            table.rows.push(row);
        }
    }
    ServoRows {
        table,
        measured,
        prior,
        adapted,
    }
}

/// A servo log given as an MCAP or bag (`experiment servo --out X.mcap`): the
/// comment lines a CSV log starts with come from its note. (Its rows keep the run's
/// clock, on which `t_goal` is too: twinloop's logs read back with their own `t`.)
/// A log without the note (another recorder's) needs `--servo`.
fn read_recorded_log(path: &Path, servo: Option<ServoType>) -> Result<ServoLog, CliError> {
    let header = log_note(path)?;
    let table = crate::common::read_table(path)?;
    let file = path.display().to_string();
    Ok(ServoLog::from_table(
        &file,
        header.as_deref().unwrap_or(""),
        &table,
        servo,
    )?)
}

/// The comment lines an MCAP servo log keeps in its note, if it has one.
fn log_note(path: &Path) -> Result<Option<String>, CliError> {
    Ok(twinloop_logs::metadata(path, SERVO_LOG_NOTE)?.and_then(|mut m| m.remove("text")))
}

/// The load of limb logs: each rebuilt from the robot (or `robot`), joint and held
/// pose it records; all must be the same load (within 1e-6 relative).
fn limb_load<'a>(
    paths: impl Iterator<Item = &'a PathBuf>,
    robot: Option<&str>,
) -> Result<Load, CliError> {
    let mut load: Option<(Load, String)> = None;
    for p in paths {
        let file = p.display().to_string();
        let text = if twinloop_logs::is_log(p) {
            log_note(p)?.unwrap_or_default()
        } else {
            twinloop_io::input::read_to_string(p).map_err(|e| CliError::io(p, e))?
        };
        let limb = crate::limb::Limb::from_log(&text, &file)?.ok_or_else(|| {
            CliError::new(format!(
                "{file}: a bench log (no \"# limb:\" lines): give --load LOAD.toml"
            ))
        })?;
        let (l, _) = limb.load_from(robot)?;
        match &load {
            None => load = Some((l, file)),
            Some((first, name)) => {
                let same = |x: f64, y: f64| (x - y).abs() <= 1e-6 * (x.abs() + y.abs()).max(1e-9);
                if !(same(l.inertia, first.inertia)
                    && same(l.gravity_sin, first.gravity_sin)
                    && same(l.gravity_cos, first.gravity_cos)
                    && same(l.gravity_const, first.gravity_const))
                {
                    return Err(CliError::new(format!(
                        "{file}: its limb load differs from {name}'s (another joint or pose): fit them separately"
                    )));
                }
            }
        }
    }
    load.map(|l| l.0)
        .ok_or_else(|| CliError::new("identify servo needs --data LOG.csv"))
}

fn text(id: &Identification, seconds: f64) -> String {
    let p = &id.params;
    let sd = p
        .uncertainty
        .unwrap_or([f64::NAN; twinloop_actuator::params::N_PARAMS]);
    let mut s = format!(
        "{} model {} at {:.2} V, fitted in {seconds:.2} s ({} iterations)\n",
        p.servo,
        p.level.name(),
        p.voltage,
        id.iterations
    );
    for &i in id.fitted.iter().chain(&id.nonsmooth) {
        if id.undetermined.contains(&PARAM_NAMES[i]) {
            continue;
        }
        let _ = writeln!(
            s,
            "  {:18} {:>12.6} +- {:.2e}",
            PARAM_NAMES[i], p.values[i], sd[i]
        );
    }
    for (name, lo, hi) in &id.intervals {
        let _ = writeln!(
            s,
            "  {name:18} not determined: the data allow {lo:.4} to {hi:.4} (file: {:.6}, one choice)",
            p.values[PARAM_NAMES.iter().position(|n| n == name).unwrap_or(0)]
        );
    }
    for (name, v, sd) in &id.combinations {
        let _ = writeln!(s, "  {name:34} {v:.6} +- {sd:.2e}");
    }
    let _ = writeln!(
        s,
        "position error: fitted {:.3} mrad RMS; held out {:.3} mrad RMS, {:.3} mrad mean absolute ({} rows)",
        id.fit_rms_mrad, id.heldout_rms_mrad, id.heldout_mae_mrad, id.heldout_rows
    );
    // A model that does not reproduce the held-out log: its deviations describe the
    // fit to these logs, not the servo (pty logs on an overloaded machine: 14-44 mrad),
    // so the library reported every parameter as not determined.
    if id.heldout_counts > twinloop_actuator::identify::HELDOUT_COUNTS {
        let _ = writeln!(
            s,
            "warning: the held-out error is {:.1} encoder counts ({:.2} mrad each): the model does not reproduce these logs (late samples? the wrong load?), so every parameter is not determined and its interval and the combinations' deviations are {:.1} times wider",
            id.heldout_counts,
            1e3 * p.servo.resolution(),
            id.heldout_counts
        );
    }
    let _ = writeln!(
        s,
        "condition number {:.3e}; not determined by these logs: {}",
        id.condition,
        if id.undetermined.is_empty() {
            "nothing".to_string()
        } else {
            id.undetermined.join(", ")
        }
    );
    s
}

/// The file's comment on what the logs did not determine: each parameter's interval,
/// and why its `[uncertainty]` is `inf`.
fn not_determined_note(intervals: &[(&str, f64, f64)]) -> String {
    if intervals.is_empty() {
        return String::new();
    }
    let list: Vec<String> = intervals
        .iter()
        .map(|(n, lo, hi)| format!("{n} in [{lo:.4}, {hi:.4}]"))
        .collect();
    format!(
        "\nnot determined by these logs (the value below is one choice; [uncertainty] inf): {}\n[uncertainty] holds one standard deviation: the larger of the Jacobian's and the block-robust one, with the 0.1 V voltage register's rounding",
        list.join(", ")
    )
}

fn to_json(id: &Identification, seconds: f64) -> serde_json::Value {
    let p = &id.params;
    let sd = p
        .uncertainty
        .unwrap_or([f64::NAN; twinloop_actuator::params::N_PARAMS]);
    let params: serde_json::Map<String, serde_json::Value> = id
        .fitted
        .iter()
        .chain(&id.nonsmooth)
        .map(|&i| {
            (
                PARAM_NAMES[i].to_string(),
                json!({"value": p.values[i], "sd": sd[i]}),
            )
        })
        .collect();
    json!({
        "servo": p.servo.name(),
        "model": p.level.name(),
        "voltage": p.voltage,
        "params": params,
        "fitted": id.fitted.iter().map(|&i| PARAM_NAMES[i]).collect::<Vec<_>>(),
        "correlation": id.correlation,
        "combinations": id.combinations.iter().map(|(n, v, s)| json!({"name": n, "value": v, "sd": s})).collect::<Vec<_>>(),
        "fit_rms_mrad": id.fit_rms_mrad,
        "heldout_rms_mrad": id.heldout_rms_mrad,
        "heldout_mae_mrad": id.heldout_mae_mrad,
        "heldout_rows": id.heldout_rows,
        "heldout_counts": id.heldout_counts,
        "singular_values": id.singular_values,
        "condition": id.condition,
        "undetermined": id.undetermined,
        "intervals": id.intervals.iter().map(|(n, lo, hi)| json!({"name": n, "low": lo, "high": hi})).collect::<Vec<_>>(),
        "weakest_direction": id.weakest_direction.iter().map(|(n, w)| json!({"name": n, "weight": w})).collect::<Vec<_>>(),
        "iterations": id.iterations,
        "evaluations": id.evaluations,
        "cmaes_evaluations": id.nonsmooth_evaluations,
        "seconds": seconds,
    })
}
