//! 3D replays beside the `--report` pages, exported as one viewer page each
//! (twinloop-view's export): the tip-over of `demo` and `adapt --record --report`
//! (the robot's bus recording with the adapted and prior models simulated lean by
//! lean as ghosts), and any other report about a motion ([`motion_replay`]).

use crate::common;
use crate::error::CliError;
use crate::sim_args::{ServoChoice, record_columns, standing_simulator, state_row};
use std::path::{Path, PathBuf};
use twinloop_description::Description;
use twinloop_io::{CsvWriter, Table};
use twinloop_robot::{Robot, RobotState};
use twinloop_view::{Content, Recording, Scene};

/// The ghosts' time step, s.
const DT: f64 = 1e-3;
/// One ghost row every this many steps: 25 rows a second, finer than the bus record
/// (about 18), a fortieth of the steps (a 3 min tip-over at every step would be
/// 130 MB of CSV).
const EVERY: usize = 40;
/// A ghost has tipped once a foot tilts this much: it stands on an edge of the sole
/// (leaning, the feet stay flat however far the trunk goes).
const TIP_FOOT_DEG: f64 = 10.0;
/// A robot without feet to watch has tipped once its trunk tilts this much.
const TIP_TRUNK_DEG: f64 = 45.0;
/// The ghost stands still this long before each lean (as the experiment's robot
/// settles before its ramp), s; not recorded.
const SETTLE_S: f64 = 1.0;
/// The ramp's rate after the robot's last command is measured over this much of it, s.
const RATE_WINDOW_S: f64 = 0.5;

/// The tip-over's joint commands as the bus recorded them (`goal:<joint>`, as
/// `experiment tipover --record` writes them); rows with a command missing, or not
/// later than the one before, are left out.
struct Commands {
    t: Vec<f64>,
    joints: Vec<String>,
    /// Per row, the goal of each of `joints`.
    goals: Vec<Vec<f64>>,
}

impl Commands {
    fn read(recorded: &Path) -> Result<Commands, CliError> {
        let table = common::read_table(recorded)?;
        let tc = table
            .column_index("t")
            .ok_or_else(|| CliError::new(format!("{}: no `t` column", recorded.display())))?;
        let (cols, joints): (Vec<usize>, Vec<String>) = table
            .columns
            .iter()
            .enumerate()
            .filter_map(|(i, c)| c.strip_prefix("goal:").map(|j| (i, j.to_string())))
            .unzip();
        if cols.is_empty() {
            return Err(CliError::new(format!(
                "{}: no goal:<joint> columns to replay",
                recorded.display()
            )));
        }
        let mut c = Commands {
            t: Vec::new(),
            joints,
            goals: Vec::new(),
        };
        for row in &table.rows {
            let later = c.t.last().is_none_or(|&t| row[tc] > t);
            if later && row[tc].is_finite() && cols.iter().all(|&i| row[i].is_finite()) {
                c.t.push(row[tc]);
                c.goals.push(cols.iter().map(|&i| row[i]).collect());
            }
        }
        if c.t.is_empty() {
            return Err(CliError::new(format!(
                "{}: no row with every goal:<joint> to replay",
                recorded.display()
            )));
        }
        Ok(c)
    }

    /// Whether row `k` commands the standing pose (the first row's: the experiment
    /// starts standing and stands the robot up again between leans).
    fn standing(&self, k: usize) -> bool {
        self.goals[k]
            .iter()
            .zip(&self.goals[0])
            .all(|(a, b)| (a - b).abs() < 1e-9)
    }

    /// The leans: each stretch of rows that leave the standing pose, from the last
    /// standing row before it (the first lean from the recording's start) to the
    /// next lean's start (the last to the recording's end).
    fn leans(&self) -> Vec<Lean> {
        let n = self.t.len();
        let mut out: Vec<Lean> = Vec::new();
        for k in 1..n {
            if !self.standing(k) && self.standing(k - 1) {
                let start = if out.is_empty() { 0 } else { k - 1 };
                if let Some(prev) = out.last_mut() {
                    prev.end_t = self.t[start];
                }
                out.push(Lean {
                    start,
                    last: k,
                    end_t: self.t[n - 1],
                });
            } else if !self.standing(k)
                && let Some(l) = out.last_mut()
            {
                l.last = k;
            }
        }
        out
    }

    /// The commands of `lean` at time `t` (into `out`, one per joint): the recorded
    /// ones interpolated linearly, and after its last one the ramp going on at the
    /// rate it had (the robot tipped there; the model may need more).
    fn at(&self, lean: &Lean, t: f64, out: &mut [f64]) {
        let last = lean.last;
        if t >= self.t[last] {
            let t_last = self.t[last];
            let before = (lean.start..last)
                .rev()
                .find(|&k| self.t[k] <= t_last - RATE_WINDOW_S)
                .unwrap_or(lean.start);
            let span = t_last - self.t[before];
            for (j, o) in out.iter_mut().enumerate() {
                let g = self.goals[last][j];
                let rate = if span > 0.0 {
                    (g - self.goals[before][j]) / span
                } else {
                    0.0
                };
                *o = g + rate * (t - t_last);
            }
            return;
        }
        let k = self.t.partition_point(|&x| x <= t).max(1);
        let (a, b) = (self.t[k - 1], self.t[k]);
        let w = ((t - a) / (b - a)).clamp(0.0, 1.0);
        for (j, o) in out.iter_mut().enumerate() {
            *o = self.goals[k - 1][j] * (1.0 - w) + self.goals[k][j] * w;
        }
    }
}

/// One lean of the tip-over in the recording: rows `start ..= last`, and the time
/// the next lean starts.
struct Lean {
    start: usize,
    /// The last row that leans (the robot tipped there and the next row stands).
    last: usize,
    end_t: f64,
}

/// Whether the simulated robot has tipped: a foot (the simulator's force-sensing
/// links) tilts more than [`TIP_FOOT_DEG`], or without feet the trunk more than
/// [`TIP_TRUNK_DEG`].
fn has_tipped(sim: &mut twinloop_sim::Simulator, feet: &[String]) -> bool {
    let up = |r: &nalgebra::Matrix3<f64>| r[(2, 2)].clamp(-1.0, 1.0).acos().to_degrees();
    if feet.is_empty() {
        let (x, y) = (sim.q[3], sim.q[4]);
        return (1.0 - 2.0 * (x * x + y * y)).clamp(-1.0, 1.0).acos() > TIP_TRUNK_DEG.to_radians();
    }
    feet.iter().any(|f| {
        sim.link_placement(f)
            .is_some_and(|m| up(&m.rotation) > TIP_FOOT_DEG)
    })
}

/// `robot` simulated on the tip-over's commands, written to `out` on the
/// recording's clock: each lean from standing (a new simulator, standing on the
/// ground and settled, at the lean's start), its recorded commands and then its ramp
/// going on until the model tips (a foot on edge), when the commands go back to
/// standing as the experiment's do; the fallen model lies until the next lean
/// starts. So each model tips at its
/// own angle in every direction, beside the robot.
fn simulate_leans(
    robot: &Description,
    c: &Commands,
    leans: &[Lean],
    out: &Path,
) -> Result<(), CliError> {
    let mut sim = standing_simulator(robot, DT, ServoChoice::Auto)?;
    let at: Vec<Option<usize>> = c
        .joints
        .iter()
        .map(|j| sim.model.joint_names.iter().position(|n| n == j))
        .collect();
    if at.iter().all(Option::is_none) {
        return Err(CliError::new(format!(
            "no goal:<joint> column of the recording names a joint of {}",
            robot.name
        )));
    }
    if !sim.model.is_floating() {
        return Err(CliError::new(format!(
            "{} has no floating base to tip over",
            robot.name
        )));
    }
    let feet: Vec<String> = sim
        .sensors()
        .feet
        .iter()
        .map(|&l| sim.model.links[l].name.clone())
        .collect();
    let mut w = CsvWriter::create(out, &record_columns(&sim))?;
    let (mut st, mut row) = (RobotState::default(), Vec::new());
    let mut cmd = vec![0.0; c.joints.len()];
    for (i, lean) in leans.iter().enumerate() {
        if i > 0 {
            sim = standing_simulator(robot, DT, ServoChoice::Auto)?;
        }
        let mut goals = sim.goals.clone();
        let standing = goals.clone();
        sim.run(SETTLE_S)?;
        let t0 = c.t[lean.start];
        let is_last = i + 1 == leans.len();
        let steps = ((lean.end_t - t0) / DT).round() as usize;
        let mut tipped = false;
        for k in 0..=steps {
            let t = t0 + k as f64 * DT;
            if k == steps && !is_last {
                break; // the next lean's first row
            }
            if k % EVERY == 0 || k == steps {
                state_row(&mut sim, &mut st, t, &mut row)?;
                w.write_row(&row)?;
            }
            if k == steps {
                break;
            }
            if !tipped {
                c.at(lean, t, &mut cmd);
                // Every 10 ms: the feet's placements cost a kinematics pass.
                tipped = k % 10 == 0 && has_tipped(&mut sim, &feet);
                for (g, j) in cmd.iter().zip(&at) {
                    if let Some(j) = j {
                        goals[*j] = *g;
                    }
                }
                if tipped {
                    goals.copy_from_slice(&standing);
                }
            }
            sim.command_positions(&goals)?;
            sim.step()?;
        }
    }
    Ok(w.finish()?)
}

/// `demo` and `adapt --port --record`: the tip-over in 3D, as one self-contained
/// HTML file (`out`): the robot's recording over the bus, with two ghosts, the
/// adapted model (`adapted`, a URDF) and the prior (`prior_spec`) each doing every
/// lean from standing on the robot's commands ([`simulate_leans`]): the model
/// before and after adaptation, tipping at its own angle beside the robot. Writes
/// `replay_adapted.csv` and `replay_prior.csv` next to `out`; returns the files
/// written.
pub fn tipover_replay(
    recorded: &Path,
    prior_spec: &str,
    adapted: Option<&Path>,
    out: &Path,
) -> Result<Vec<PathBuf>, CliError> {
    let dir = out.parent().unwrap_or(Path::new("."));
    let commands = Commands::read(recorded)?;
    let leans = commands.leans();
    if leans.is_empty() {
        return Err(CliError::new(format!(
            "{}: the goals never leave the standing pose: no lean to replay",
            recorded.display()
        )));
    }
    let mut csvs = vec![recorded.to_path_buf()];
    let models = [
        ("adapted", adapted.map(|p| p.display().to_string())),
        ("prior", Some(prior_spec.to_string())),
    ];
    for (name, spec) in models {
        let Some(spec) = spec else { continue };
        let (robot, _) = common::load_description(&spec)?;
        let sim_out = dir.join(format!("replay_{name}.csv"));
        simulate_leans(&robot, &commands, &leans, &sim_out).map_err(|e| {
            e.context(format!(
                "simulating the {name} model on the tip-over's commands"
            ))
        })?;
        csvs.push(sim_out);
    }
    let tables = csvs
        .iter()
        .map(|p| Ok((p.clone(), common::read_table(p)?)))
        .collect::<Result<Vec<_>, CliError>>()?;
    export(prior_spec, &tables, out)?;
    let mut files: Vec<PathBuf> = csvs.split_off(1);
    files.push(out.to_path_buf());
    Ok(files)
}

/// One self-contained viewer page (`out`): the robot `spec` (a description file, or
/// `builtin:NAME`) with the recordings `tables` (each named by its file) replayed,
/// the second and later as ghosts.
fn export(spec: &str, tables: &[(PathBuf, Table)], out: &Path) -> Result<(), CliError> {
    let (robot, format) = common::load_description(spec)?;
    let source = (format != common::Format::Builtin).then(|| Path::new(spec));
    let scene = Scene::new(&robot, source, &[]);
    let recordings = tables
        .iter()
        .map(|(p, t)| Recording::from_table(t, p, &scene.info))
        .collect::<Result<Vec<_>, _>>()?;
    if let Some(r) = recordings
        .iter()
        .find(|r| r.info.missing.len() == scene.info.joints.len() && !r.info.has_base)
    {
        return Err(CliError::new(format!(
            "{}: no q:<joint> column names a joint of {}: nothing moves",
            r.info.name, robot.name
        )));
    }
    let content = Content {
        scene,
        recordings,
        live: None,
    };
    let html = twinloop_view::export_html(&content).map_err(|e| CliError::new(e.to_string()))?;
    Ok(twinloop_io::output::write_atomic(out, html)?)
}

/// The 3D replay of a `--report` page about a motion: `csvs` (the first drawn
/// solid, the others as ghosts) on the robot `spec`, written beside the report as
/// `<report's stem>_3d.html` (one file, works offline), and a section of `page`
/// linking to it that says what is shown (`what`). A replay that cannot be made
/// is a warning: the report does not depend on it. Returns the file written.
pub fn motion_replay(
    report: &Path,
    spec: &str,
    csvs: &[PathBuf],
    what: &str,
    page: &mut twinloop_report::Report,
) -> Option<PathBuf> {
    let tables: Result<Vec<_>, CliError> = csvs
        .iter()
        .map(|p| Ok((p.clone(), common::read_table(p)?)))
        .collect();
    match tables {
        Ok(t) => replay_tables(report, spec, &t, what, page),
        Err(e) => {
            eprintln!("warning: no 3D replay: {e}");
            None
        }
    }
}

/// [`motion_replay`] of recordings already read (or made: each named by `.0`).
pub fn replay_tables(
    report: &Path,
    spec: &str,
    tables: &[(PathBuf, Table)],
    what: &str,
    page: &mut twinloop_report::Report,
) -> Option<PathBuf> {
    let stem = report
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "report".into());
    let out = report.with_file_name(format!("{stem}_3d.html"));
    match export(spec, tables, &out) {
        Ok(()) => {
            let name = format!("{stem}_3d.html");
            page.heading("In 3D");
            page.paragraph(what);
            page.link(format!("Open {name} (one file; works offline)"), name);
            Some(out)
        }
        Err(e) => {
            eprintln!("warning: no 3D replay: {e}");
            None
        }
    }
}

/// A section of a `--report` page that links to the tip-over's 3D replay written
/// beside it ([`tipover_replay`]).
pub fn link_replay(report: &mut twinloop_report::Report, replay: &Path) {
    let name = replay
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    report.heading("In 3D");
    report.paragraph(
        "The robot's tip-over as recorded over the bus (grey), and the adapted (blue) and \
         prior (red) models simulated lean by lean: each lean from standing, on the robot's \
         joint commands and then its ramp going on until the model tips, so each tips at its \
         own angle in every direction beside the robot. The recording has no base pose (the \
         bus does not measure it), so the robot stands where it started; the ghosts fall.",
    );
    report.link(format!("Open {name} (one file; works offline)"), name);
}

/// [`tipover_replay`] for a `--report` page: the files written are added to `files`;
/// a replay that cannot be made is a warning (the report does not depend on it).
pub fn replay_for_report(
    recorded: &Path,
    prior_spec: &str,
    adapted: Option<&Path>,
    out: &Path,
    files: &mut Vec<String>,
) -> Option<PathBuf> {
    match tipover_replay(recorded, prior_spec, adapted, out) {
        Ok(written) => {
            files.extend(written.iter().map(|p| p.display().to_string()));
            Some(out.to_path_buf())
        }
        Err(e) => {
            eprintln!("warning: no 3D replay: {e}");
            None
        }
    }
}
