//! `--mcap FILE` of the identification, adaptation and validation commands: the
//! result as one MCAP that Foxglove or Rerun opens beside the measurement. The
//! measured signals, the prior's and the adapted model's predictions of them are
//! Float64MultiArray topics (`/measured`, `/prior`, `/adapted`; `validate`: `/model`,
//! `/compare`; each labelled with its column names), the configuration (when the
//! data have one) is `/joint_states` (and `/tf`) with the robot's URDF on
//! `/robot_description`; that URDF is also an attachment (`adapted.urdf`;
//! `validate`: `model.urdf`), as is any other file the result has (`identify
//! servo`'s `fitted.toml`), and two metadata records say how the file was made:
//! `twinloop` (`command`, `command_line` as a JSON array, `twinloop_version`) and
//! `twinloop.inputs` (each input as given -> the SHA-256 of its bytes, hex).

use crate::error::CliError;
use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::io::Read;
use std::path::Path;
use twinloop_description::Description;
use twinloop_io::Table;
use twinloop_logs::{ArrayTopic, McapLog};

/// A result to write: `table` has `t`, optionally `q:` columns (shown on the robot),
/// and the columns `measured` and each prediction's topic name.
pub struct ResultLog<'a> {
    pub table: Table,
    pub measured: Vec<String>,
    /// The models' predictions: `/prior` and `/adapted` (`validate`: `/model` and
    /// `/compare`), each of its own columns.
    pub predicted: Vec<ArrayTopic>,
    /// The adapted description: `/robot_description` and the attachment `robot_file`.
    pub robot: Option<&'a Description>,
    /// The robot's attachment's name: `adapted.urdf` (`validate`: `model.urdf`).
    pub robot_file: &'static str,
    /// The inputs as the command line gave them (files, folders, `builtin:NAME`).
    pub inputs: Vec<String>,
    /// Further attachments: (name, media type, bytes), such as a fitted parameter file.
    pub files: Vec<(String, &'static str, Vec<u8>)>,
    /// Parts on times of their own, written after `table`'s rows, each on its own
    /// Float64MultiArray topics (`adapt`: the lean's torques after the fall angles).
    pub parts: Vec<ResultPart>,
}

/// A part of a result: `table` (`t` and its columns) on the topics `topics`, which
/// name every one of its columns but `t`.
pub struct ResultPart {
    pub table: Table,
    pub topics: Vec<ArrayTopic>,
}

/// The columns of a measured-against-predicted table: the `prior.` and `adapted.`
/// names of each of `predicted`, and an empty table of `t`, `measured`, then those.
pub fn comparison_columns(
    measured: &[String],
    predicted: &[String],
) -> (Vec<String>, Vec<String>, Table) {
    let named = |p: &str| -> Vec<String> { predicted.iter().map(|c| format!("{p}{c}")).collect() };
    let (prior, adapted) = (named("prior."), named("adapted."));
    let columns = [&["t".to_string()][..], measured, &prior[..], &adapted[..]].concat();
    (prior, adapted, Table::new(columns))
}

/// The prior's and the adapted model's predictions, on `/prior` and `/adapted`.
pub fn prior_and_adapted(prior: Vec<String>, adapted: Vec<String>) -> Vec<ArrayTopic> {
    vec![
        ArrayTopic {
            topic: "/prior".into(),
            columns: prior,
        },
        ArrayTopic {
            topic: "/adapted".into(),
            columns: adapted,
        },
    ]
}

/// Write `result` to `path` for the command `command` (`identify static`).
pub fn write(path: &Path, command: &str, result: &ResultLog<'_>) -> Result<(), CliError> {
    let topic = |name: &str, columns: &[String]| ArrayTopic {
        topic: format!("/{name}"),
        columns: columns.to_vec(),
    };
    let groups: Vec<ArrayTopic> = std::iter::once(topic("measured", &result.measured))
        .chain(result.predicted.iter().cloned())
        .filter(|g| !g.columns.is_empty())
        .collect();
    let urdf = result.robot.map(twinloop_description::urdf::to_string);
    let root = result
        .robot
        .and_then(|r| r.root_links().first().map(|s| s.to_string()))
        .unwrap_or_else(|| "base_link".into());
    let context = |e: twinloop_logs::LogError| CliError::from(e).context("--mcap");
    let (columns, groups) = with_parts(&result.table.columns, groups, &result.parts);
    let mut log = McapLog::create_grouped(path, &columns, urdf.as_deref(), &root, &groups)
        .map_err(context)?;
    let in_parts = |topic: &str| {
        result
            .parts
            .iter()
            .any(|p| p.topics.iter().any(|g| g.topic == topic))
    };
    let mut row = vec![f64::NAN; columns.len()];
    for r in &result.table.rows {
        row[..r.len()].copy_from_slice(r);
        log.write_row_on(&row, |t| !in_parts(t)).map_err(context)?;
    }
    for part in &result.parts {
        // Where each of the part's columns is in the whole row.
        let at: Vec<usize> = part
            .table
            .columns
            .iter()
            .map(|c| columns.iter().position(|x| x == c).unwrap_or(0))
            .collect();
        let ours = |t: &str| part.topics.iter().any(|g| g.topic == t);
        for r in &part.table.rows {
            row.fill(f64::NAN);
            for (&i, &x) in at.iter().zip(r) {
                row[i] = x;
            }
            log.write_row_on(&row, ours).map_err(context)?;
        }
    }
    if let Some(u) = &urdf {
        log.attach(result.robot_file, "application/xml", u.as_bytes())
            .map_err(context)?;
    }
    for (name, media_type, data) in &result.files {
        log.attach(name, media_type, data).map_err(context)?;
    }
    log.metadata("twinloop", provenance(command)?)
        .map_err(context)?;
    log.metadata("twinloop.inputs", input_hashes(&result.inputs)?)
        .map_err(context)?;
    log.finish().map_err(context)
}

/// Every column (the table's, then each part's but its `t`) and every topic.
fn with_parts(
    columns: &[String],
    mut groups: Vec<ArrayTopic>,
    parts: &[ResultPart],
) -> (Vec<String>, Vec<ArrayTopic>) {
    let mut all = columns.to_vec();
    for p in parts {
        all.extend(p.table.columns.iter().filter(|c| *c != "t").cloned());
        groups.extend(p.topics.iter().cloned());
    }
    (all, groups)
}

/// The command, its command line and twinloop's version.
fn provenance(command: &str) -> Result<BTreeMap<String, String>, CliError> {
    let args: Vec<String> = std::env::args().collect();
    Ok(BTreeMap::from([
        ("command".to_string(), command.to_string()),
        ("command_line".to_string(), serde_json::to_string(&args)?),
        (
            "twinloop_version".to_string(),
            env!("CARGO_PKG_VERSION").to_string(),
        ),
    ]))
}

/// Each input -> the SHA-256 of its bytes: a file's; a folder's (a rosbag2 bag)
/// each file's, as `FOLDER/NAME`; a `builtin:NAME` robot's, of the URDF twinloop
/// writes for it (what this version of twinloop took as the robot).
fn input_hashes(inputs: &[String]) -> Result<BTreeMap<String, String>, CliError> {
    let mut out = BTreeMap::new();
    for spec in inputs {
        if spec.starts_with("builtin:") {
            let (robot, _) = crate::common::load_description(spec)?;
            let urdf = twinloop_description::urdf::to_string(&robot);
            out.insert(spec.clone(), hex(&Sha256::digest(urdf.as_bytes())));
            continue;
        }
        let path = Path::new(spec);
        if path.is_dir() {
            let mut files: Vec<_> = std::fs::read_dir(path)
                .map_err(|e| CliError::new(format!("{spec}: {e}")))?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.is_file())
                .collect();
            files.sort();
            for f in files {
                out.insert(f.display().to_string(), file_sha256(&f)?);
            }
        } else {
            out.insert(spec.clone(), file_sha256(path)?);
        }
    }
    Ok(out)
}

/// The SHA-256 of a file's bytes, read 64 KiB at a time.
fn file_sha256(path: &Path) -> Result<String, CliError> {
    let fail = |e: std::io::Error| CliError::new(format!("{}: {e}", path.display()));
    let mut f = std::fs::File::open(path).map_err(fail)?;
    let mut hasher = Sha256::new();
    let mut buf = vec![0u8; 1 << 16];
    loop {
        let n = f.read(&mut buf).map_err(fail)?;
        if n == 0 {
            break;
        }
        hasher.update(&buf[..n]);
    }
    Ok(hex(&hasher.finalize()))
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// FIPS 180-2's example "abc" (appendix B.1).
    #[test]
    fn sha256_of_abc_is_the_standard_s() {
        assert_eq!(
            hex(&Sha256::digest(b"abc")),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
    }
}
