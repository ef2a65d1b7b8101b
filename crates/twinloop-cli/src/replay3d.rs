//! The tip-over in 3D for `demo` and `adapt --record --report`: the robot's bus
//! recording with the adapted and prior models simulated on its joint commands as
//! ghosts, exported as one viewer page beside the report (twinloop-view's export).

use crate::cmd_simulate::{ServoChoice, SimulateArgs};
use crate::cmd_view::LiveViewArgs;
use crate::common;
use crate::error::CliError;
use std::path::{Path, PathBuf};
use twinloop_view::{Content, Recording, Scene};

/// The joint commands of a bus recording (`goal:<joint>`, as `experiment tipover
/// --record` writes them) as a `simulate --trajectory` file (`t`, `q:<joint>`);
/// rows with a command missing, or not later than the one before, are left out.
fn commands_as_trajectory(recorded: &Path, out: &Path) -> Result<(), CliError> {
    let table = common::read_table(recorded)?;
    let t = table
        .column_index("t")
        .ok_or_else(|| CliError::new(format!("{}: no `t` column", recorded.display())))?;
    let goals: Vec<(usize, String)> = table
        .columns
        .iter()
        .enumerate()
        .filter_map(|(i, c)| c.strip_prefix("goal:").map(|j| (i, format!("q:{j}"))))
        .collect();
    if goals.is_empty() {
        return Err(CliError::new(format!(
            "{}: no goal:<joint> columns to replay",
            recorded.display()
        )));
    }
    let mut columns = vec!["t".to_string()];
    columns.extend(goals.iter().map(|(_, c)| c.clone()));
    let mut traj = twinloop_io::Table::new(columns);
    for row in &table.rows {
        let later = traj.rows.last().is_none_or(|r: &Vec<f64>| row[t] > r[0]);
        if later && row[t].is_finite() && goals.iter().all(|(i, _)| row[*i].is_finite()) {
            traj.rows.push(
                std::iter::once(row[t])
                    .chain(goals.iter().map(|(i, _)| row[*i]))
                    .collect(),
            );
        }
    }
    traj.write(out)
        .map_err(|e| CliError::from(e).context("the replay's trajectory"))
}

/// `demo` and `adapt --port --record`: the tip-over in 3D, as one self-contained
/// HTML file (`out`): the robot's recording over the bus, with two ghosts, the
/// adapted model (`adapted`, a URDF) and the prior (`prior_spec`) simulated on the
/// same joint commands: the model before and after adaptation, tipping (or not)
/// beside the robot. Writes `replay_adapted.csv` and `replay_prior.csv` next to
/// `out`; returns the files written.
pub fn tipover_replay(
    recorded: &Path,
    prior_spec: &str,
    adapted: Option<&Path>,
    out: &Path,
) -> Result<Vec<PathBuf>, CliError> {
    let dir = out.parent().unwrap_or(Path::new("."));
    let trajectory = dir.join("replay_commands.csv");
    commands_as_trajectory(recorded, &trajectory)?;
    let mut csvs = vec![recorded.to_path_buf()];
    let models = [
        ("adapted", adapted.map(|p| p.display().to_string())),
        ("prior", Some(prior_spec.to_string())),
    ];
    for (name, spec) in models {
        let Some(robot) = spec else { continue };
        let sim_out = dir.join(format!("replay_{name}.csv"));
        crate::cmd_simulate::run(SimulateArgs {
            robot,
            duration: None,
            hold: false,
            trajectory: Some(trajectory.clone()),
            out: sim_out.clone(),
            dt: 1e-3,
            // 25 rows a second: finer than the bus record (about 18), a fortieth of
            // the file (a 3 min tip-over at every step would be 130 MB of CSV).
            every: 40,
            servo: ServoChoice::Auto,
            servo_params: Vec::new(),
            view: LiveViewArgs::default(),
        })
        .map_err(|e| {
            e.context(format!(
                "simulating the {name} model on the tip-over's commands"
            ))
        })?;
        csvs.push(sim_out);
    }
    let _ = std::fs::remove_file(&trajectory);
    let (robot, format) = common::load_description(prior_spec)?;
    let source = (format != common::Format::Builtin).then(|| Path::new(prior_spec));
    let scene = Scene::new(&robot, source, &[]);
    let recordings = csvs
        .iter()
        .map(|p| Recording::read(p, &scene.info))
        .collect::<Result<Vec<_>, _>>()?;
    let content = Content {
        scene,
        recordings,
        live: None,
    };
    let html = twinloop_view::export_html(&content).map_err(|e| CliError::new(e.to_string()))?;
    std::fs::write(out, html).map_err(|e| CliError::io(out, e))?;
    let mut files: Vec<PathBuf> = csvs.split_off(1);
    files.push(out.to_path_buf());
    Ok(files)
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
         prior (red) models simulated on the same joint commands: the model before and after \
         adaptation beside the robot. The recording has no base pose (the bus does not measure \
         it), so the robot stands where it started; the simulated ghosts fall.",
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
