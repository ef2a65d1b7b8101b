//! The files a command will write, checked against the rules of
//! `twinloop_io::output` as soon as the command line is parsed, before any work: a
//! 92 s tip-over on a bus must not be thrown away at the end because its `--json`
//! folder does not exist, and `simulate --trajectory G.csv --out G.csv` must not
//! destroy its own input. One place for every command: an option is an output by its
//! name ([`OUTPUT_OPTIONS`]), every other value that names an existing file is an
//! input. The writes themselves go through `twinloop_io::output` (atomic).

use crate::error::CliError;
use clap::ArgMatches;
use std::path::{Path, PathBuf};
use twinloop_io::output::Output;

/// Options whose value is a file the command writes, wherever they appear.
pub const OUTPUT_OPTIONS: &[&str] = &[
    "out",
    "json",
    "report",
    "report-arx",
    "export",
    "frames-out",
    "record",
    "suggest-out",
    "mcap",
    "mjcf-actuators",
];

/// Outputs that only some commands have, or that are outputs only sometimes:
/// (command, option, when another option is given or "" for always).
const OUTPUTS_OF: &[(&str, &str, &str)] = &[
    // adapt --port runs the tip-over and writes it to --tipover; without, it reads it.
    ("adapt", "tipover", "port"),
];

/// Options named like outputs that may be folders: (command, option, whether a file
/// is also taken). A folder that exists is written into; anything else is checked as
/// a file output (a device, a FIFO, an input, a missing parent folder refused), and
/// where only a folder is taken, a file there is refused.
const FOLDER_OUTPUTS: &[(&str, &str, bool)] =
    &[("identify servo", "out", true), ("demo", "out", false)];

/// Recordings (and results as MCAP) that may be rosbag2 folders: (command, option;
/// "" for every command). A value ending in `/` or naming an existing folder is
/// written as a bag there (docs/logs.md, Writing), so its file is what is checked.
const BAG_OUTPUTS: &[(&str, &str)] = &[
    ("simulate", "out"),
    ("link record", "out"),
    ("experiment servo", "out"),
    ("experiment lean", "out"),
    ("experiment lean", "record"),
    ("experiment tipover", "record"),
    ("adapt", "record"),
    ("", "mcap"),
];

/// Refuse the command line's outputs that break a rule (exit 2, naming the option).
pub fn check(cli: &clap::Command, matches: &ArgMatches) -> Result<(), CliError> {
    let (mut cmd, mut m, mut path) = (cli, matches, Vec::new());
    while let Some((name, sub)) = m.subcommand() {
        let Some(next) = cmd.find_subcommand(name) else {
            return Ok(());
        };
        path.push(name);
        (cmd, m) = (next, sub);
    }
    let path = path.join(" ");
    let given = |id: &str| m.try_contains_id(id).unwrap_or(false);
    let (mut outputs, mut inputs, mut folder_outputs) = (Vec::new(), Vec::new(), Vec::new());
    let mut bag_outputs = Vec::new();
    for arg in cmd.get_arguments() {
        let id = arg.get_id().as_str();
        let Ok(Some(values)) = m.try_get_raw(id) else {
            continue;
        };
        let long = arg.get_long().unwrap_or(id);
        let flag = match arg.get_long() {
            Some(l) => format!("--{l}"),
            None => id.to_uppercase(),
        };
        let is_output = OUTPUT_OPTIONS.contains(&long)
            || OUTPUTS_OF
                .iter()
                .any(|(c, o, when)| *c == path && *o == long && (when.is_empty() || given(when)));
        let folder = FOLDER_OUTPUTS
            .iter()
            .find(|(c, o, _)| *c == path && *o == long);
        let bag = BAG_OUTPUTS
            .iter()
            .any(|(c, o)| (c.is_empty() || *c == path) && *o == long);
        for v in values {
            let p = PathBuf::from(v);
            if bag && twinloop_io::sink::is_folder_output(&p) {
                bag_outputs.push((flag.clone(), p));
            } else if let Some(&(_, _, file_too)) = folder {
                folder_outputs.push((flag.clone(), p, file_too));
            } else if is_output {
                outputs.push((flag.clone(), p));
            } else if path_names_a_file(&p) {
                inputs.push((flag.clone(), p));
            }
        }
    }
    let all: Vec<(&String, &PathBuf)> = outputs
        .iter()
        .chain(&bag_outputs)
        .map(|(f, p)| (f, p))
        .chain(folder_outputs.iter().map(|(f, p, _)| (f, p)))
        .filter(|(_, p)| p.as_os_str() != "-")
        .collect();
    one_file_each(&all)?;
    for (flag, p) in &outputs {
        if p.as_os_str() != "-" {
            Output::check(flag, p, &inputs)?;
        }
    }
    for (flag, p, file_too) in &folder_outputs {
        check_folder_output(flag, p, *file_too, &inputs)?;
    }
    for (flag, p) in &bag_outputs {
        check_bag_output(flag, p, &inputs)?;
    }
    if path == "serve"
        && let Some(link) = m
            .try_get_raw("link")
            .ok()
            .flatten()
            .and_then(|mut v| v.next())
    {
        check_pty_link(Path::new(link))?;
    }
    Ok(())
}

/// Two outputs naming one file (`--out run.csv --json run.csv`): the second written
/// would replace the first, and the command would say it wrote both.
fn one_file_each(outputs: &[(&String, &PathBuf)]) -> Result<(), CliError> {
    for (k, (flag, p)) in outputs.iter().enumerate() {
        if let Some((first, _)) = outputs[..k]
            .iter()
            .find(|(_, q)| twinloop_io::output::same_place(p, q))
        {
            let what = if first == flag {
                "given twice".to_string()
            } else {
                format!("is also the {first} output of this command")
            };
            return Err(CliError::new(format!(
                "{flag} {}: {what}; give each output its own file",
                p.display()
            )));
        }
    }
    Ok(())
}

/// A folder output (`demo --out DIR`, `identify servo --out FILE.toml|DIR`): an
/// existing folder is written into (its files are checked as they are written);
/// anything else is what a file output may be, and a file only where one is taken.
fn check_folder_output(
    flag: &str,
    p: &Path,
    file_too: bool,
    inputs: &[(String, PathBuf)],
) -> Result<(), CliError> {
    if p.is_dir() {
        return Ok(());
    }
    Output::check(flag, p, inputs)?;
    if !file_too && std::fs::symlink_metadata(p).is_ok() {
        return Err(CliError::new(format!(
            "{flag} {}: is a file, and {flag} is the folder the files are written into; \
             give a folder (it is created when missing)",
            p.display()
        )));
    }
    Ok(())
}

/// A rosbag2 folder output (`--out run/`): a new folder's parent must exist (as a
/// file's must); in an existing one, its MCAP file (`run/run_0.mcap`) is checked as a
/// file output (not an input of the command, not a device).
fn check_bag_output(flag: &str, p: &Path, inputs: &[(String, PathBuf)]) -> Result<(), CliError> {
    let Some(name) = p.file_name() else {
        return Err(CliError::new(format!(
            "{flag} {}: a rosbag2 folder needs a name (run/)",
            p.display()
        )));
    };
    if p.is_dir() {
        let file = p.join(format!("{}_0.mcap", name.to_string_lossy()));
        Output::check(flag, &file, inputs)?;
    } else {
        // The folder as a new file's name: its parent must be there.
        let bare: PathBuf = p.components().collect();
        Output::check(flag, &bare, inputs)?;
    }
    Ok(())
}

fn path_names_a_file(p: &Path) -> bool {
    std::fs::metadata(p).is_ok_and(|m| m.is_file())
}

/// `serve --link PATH` puts a symlink to its pseudo-terminal at PATH, replacing an
/// old link there (a stale one from an earlier serve): never a file or anything
/// else, which it would delete.
pub fn check_pty_link(link: &Path) -> Result<(), CliError> {
    let place = |why: &str| CliError::new(format!("--link {}: {why}", link.display()));
    match std::fs::symlink_metadata(link) {
        Ok(m) if !m.file_type().is_symlink() => Err(place(
            "something that is not a symlink is there; serve puts a link to its \
             pseudo-terminal at --link and replaces only an old link: give another path",
        )),
        _ => match link.parent() {
            Some(d) if !d.as_os_str().is_empty() && !d.is_dir() => Err(place(&format!(
                "the folder {} does not exist; create it first",
                d.display()
            ))),
            _ => Ok(()),
        },
    }
}
