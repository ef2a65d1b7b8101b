//! `twinloop ik`: joint angles and base pose from motion-capture markers (seed 004, eq 7).

use crate::common::hinges_only;
use crate::common::load_model;
use crate::error::{CliError, CliResult, Outcome};
use crate::progress;
use clap::Args;
use std::path::PathBuf;
use twinloop_dynamics::BaseKind;
use twinloop_ident::markers::{MarkerIk, POOR_FIT_RMS_M, read_frames, read_markers};
use twinloop_io::{CsvWriter, Quantity};

#[derive(Args, Debug)]
pub struct IkArgs {
    /// Robot description with the links the markers are on: a URDF or MJCF file, or
    /// builtin:NAME.
    #[arg(long, value_name = "ROBOT")]
    pub robot: String,
    /// Marker set: [[marker]] name, link, position (link frame, m).
    #[arg(long, value_name = "MARKERS.toml")]
    pub markers: PathBuf,
    /// Marker frames: t and marker:<name>.x .y .z (world, m); NaN = not seen.
    #[arg(long, value_name = "FRAMES.csv")]
    pub frames: PathBuf,
    /// Output trajectory.
    #[arg(long, value_name = "TRAJ.csv")]
    pub out: PathBuf,
}

pub fn run(a: &IkArgs) -> CliResult {
    let (robot, model) = load_model(&a.robot, BaseKind::Floating)?;
    hinges_only(&robot, &a.robot, "marker IK")?;
    let markers = read_markers(&a.markers, &model)?;
    // A log (an MCAP, a rosbag2 folder) is read as the table a CSV would give.
    let frames = if twinloop_logs::is_log(&a.frames) {
        let table = crate::common::read_table(&a.frames)?;
        twinloop_ident::markers::frames_from_table(&table, &markers)?
    } else {
        read_frames(&a.frames, &markers)?
    };
    let mut fitter = MarkerIk::new(&model, markers)?;
    let mut cols = vec!["t".to_string()];
    cols.extend(Quantity::Q.column_names(&model.q_names()));
    cols.push("ik.rms".into());
    cols.push("ik.max".into());
    let mut w = CsvWriter::create(&a.out, &cols)?;
    let bar = progress::rows(frames.t.len());
    let mut rms = Vec::with_capacity(frames.t.len());
    let mut worst: (f64, usize) = (0.0, 0);
    let mut row = Vec::with_capacity(cols.len());
    for (k, seen) in frames.positions.iter().enumerate() {
        let (q, fit) = fitter.fit(seen, k).map_err(|e| e.in_file(&a.frames))?;
        row.clear();
        row.push(frames.t[k]);
        row.extend_from_slice(q);
        row.push(fit.rms);
        row.push(fit.max);
        w.write_row(&row)?;
        rms.push(fit.rms);
        if fit.max > worst.0 {
            worst = (fit.max, k);
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    w.finish()?;
    let mean = rms.iter().sum::<f64>() / rms.len().max(1) as f64;
    crate::common::print(&format!(
        "{} frames fitted (seed 004, eq 7) to {}\nmarker distance: mean RMS {:.3} mm, worst {:.3} mm (data row {})\n",
        rms.len(),
        a.out.display(),
        mean * 1e3,
        worst.0 * 1e3,
        worst.1 + 1
    ));
    poor_fit(&rms, &a.frames)
}

/// An error with exit 1 when frames fit worse than [`POOR_FIT_RMS_M`]: their angles are written (the
/// `ik.rms` column says which), but are not the robot's (issue 29: never exit 0 with
/// a wrong result).
fn poor_fit(rms: &[f64], frames: &std::path::Path) -> CliResult {
    let poor: Vec<usize> = (0..rms.len())
        .filter(|&k| rms[k] > POOR_FIT_RMS_M)
        .collect();
    let Some(&first) = poor.first() else {
        return Ok(Outcome::Ok);
    };
    Err(CliError::problems(format!(
        "{}: {} of {} frames fit worse than {} mm RMS (first: data row {}, {:.1} mm): the \
         marker set does not match the robot or the frames (mislabelled or swapped markers?)",
        frames.display(),
        poor.len(),
        rms.len(),
        POOR_FIT_RMS_M * 1e3,
        first + 1,
        rms[first] * 1e3
    )))
}
