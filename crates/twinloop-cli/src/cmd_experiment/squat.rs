//! `twinloop experiment squat`: the validation motion of seed 004 (section 3.4, Fig. 4)
//! with force-plate readings, and optionally marker frames for `twinloop ik`.

use super::check_noise;
use crate::common::hinges_only;
use crate::common::load_model;
use crate::error::{CliError, CliResult, Outcome};
use crate::progress;
use clap::Args;
use std::path::{Path, PathBuf};
use twinloop_dynamics::{BaseKind, Data, Model};
use twinloop_ident::markers::{Marker, frame_columns, marker_positions, read_markers};
use twinloop_ident::validate::{Motion, SquatOptions, squat_motion, write_motion};
use twinloop_io::CsvWriter;
use twinloop_random::SplitMix64;

#[derive(Args, Debug)]
pub struct SquatArgs {
    /// The robot as it really is (the TRUTH): a URDF or MJCF file, or builtin:NAME.
    #[arg(long, value_name = "ROBOT")]
    pub robot: String,
    /// Output CSV (configuration and plate).
    #[arg(long, value_name = "squat.csv")]
    pub out: PathBuf,
    /// How far the pelvis goes down, m (default: 12 % of its standing height).
    #[arg(long, value_name = "M", value_parser = crate::common::positive)]
    pub depth: Option<f64>,
    /// Duration of the down-and-up motion, s.
    #[arg(long, default_value_t = 5.0, value_name = "S", value_parser = crate::common::positive)]
    pub duration: f64,
    /// Standing still before and after, s.
    #[arg(long, default_value_t = 1.0, value_name = "S", value_parser = crate::common::non_negative)]
    pub rest: f64,
    /// Sampling rate, Hz (seed 004's motion capture: 150 Hz).
    #[arg(long, default_value_t = 150.0, value_name = "HZ", value_parser = crate::common::positive)]
    pub rate: f64,
    /// How far the arms swing forward at the bottom, fraction of their range.
    #[arg(long, default_value_t = 0.35, value_parser = crate::common::non_negative)]
    pub arm_swing: f64,
    /// The foot links, left then right, when they cannot be found from the geometry.
    #[arg(long, value_delimiter = ',', num_args = 2, value_name = "LEFT,RIGHT")]
    pub feet: Vec<String>,
    /// Marker set (TOML) to write marker frames for.
    #[arg(long, value_name = "MARKERS.toml", requires = "frames_out")]
    pub markers: Option<PathBuf>,
    /// Where to write the marker frames.
    #[arg(long, value_name = "FRAMES.csv", requires = "markers")]
    pub frames_out: Option<PathBuf>,
    /// Marker noise, standard deviation per axis, m.
    #[arg(long, default_value_t = 0.0, value_name = "M", value_parser = crate::units::noise)]
    pub marker_noise: f64,
    /// Random seed of the marker noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

pub fn run(a: &SquatArgs) -> CliResult {
    check_noise(a.marker_noise, "--marker-noise")?;
    crate::bounds::steps(
        a.duration + 2.0 * a.rest,
        1.0 / a.rate,
        &format!(
            "--duration {} s and --rest {} s at --rate {} Hz",
            crate::common::num(a.duration),
            crate::common::num(a.rest),
            crate::common::num(a.rate)
        ),
    )?;
    let (robot, model) = load_model(&a.robot, BaseKind::Floating)?;
    hinges_only(&robot, &a.robot, "the squat experiment")?;
    let options = SquatOptions {
        rest: a.rest,
        duration: a.duration,
        rate: a.rate,
        depth: a.depth,
        arm_swing: a.arm_swing,
        feet: (a.feet.len() == 2).then(|| (a.feet[0].clone(), a.feet[1].clone())),
    };
    let markers = match &a.markers {
        Some(p) => Some(read_markers(p, &model)?),
        None => None,
    };
    let bar = progress::steps(1);
    bar.set_message("frames");
    let motion = squat_motion(&robot, &model, &options, |k, n| {
        bar.set_length(n as u64);
        bar.set_position(k as u64);
    })
    .map_err(|e| e.in_file(&a.robot))?;
    bar.finish_and_clear();
    write_motion(&a.out, &model, &motion)?;
    if let (Some(markers), Some(out)) = (markers, &a.frames_out) {
        write_marker_frames(a, &model, &motion, &markers, out)?;
    }
    crate::common::print(&summary(a, &model, &motion));
    Ok(Outcome::Ok)
}

/// The markers' world positions per frame, plus --marker-noise (drawn from --seed).
fn write_marker_frames(
    a: &SquatArgs,
    model: &Model,
    motion: &Motion,
    markers: &[Marker],
    out: &Path,
) -> Result<(), CliError> {
    let mut data = Data::new(model);
    let mut rng = SplitMix64(a.seed);
    let mut w = CsvWriter::create(out, &frame_columns(markers))?;
    let mut row = Vec::new();
    for (t, q) in motion.t.iter().zip(&motion.q) {
        twinloop_dynamics::forward_kinematics(model, &mut data, q);
        row.clear();
        row.push(*t);
        for p in marker_positions(model, &data, markers) {
            for k in 0..3 {
                row.push(p[k] + a.marker_noise * rng.normal());
            }
        }
        w.write_row(&row)?;
    }
    Ok(w.finish()?)
}

/// What stdout says: frames, pelvis height range, plate force range.
fn summary(a: &SquatArgs, model: &Model, motion: &Motion) -> String {
    let plate = motion.plate.as_deref().unwrap_or(&[]);
    let fz: Vec<f64> = plate.iter().map(|p| p.force[2]).collect();
    let (lo, hi) = fz
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &x| {
            (l.min(x), h.max(x))
        });
    let z: Vec<f64> = motion.q.iter().map(|q| q[2]).collect();
    let (zl, zh) = z
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &x| {
            (l.min(x), h.max(x))
        });
    format!(
        "{} frames of a squat of {} written to {} ({:.1} s at {} Hz)\n\
         pelvis height {:.4} .. {:.4} m; plate Fz {:.2} .. {:.2} N (weight {:.2} N)\n",
        motion.t.len(),
        model.name,
        a.out.display(),
        motion.t.last().copied().unwrap_or(0.0),
        a.rate,
        zl,
        zh,
        lo,
        hi,
        model.total_mass * twinloop_description::GRAVITY
    )
}
