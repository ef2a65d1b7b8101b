//! `twinloop experiment static-poses`: the virtual force plate (seed 004, section 3.1).

use super::check_noise;
use crate::common::hinges_only;
use crate::common::load_model;
use crate::error::{CliError, CliResult, Outcome};
use crate::progress;
use clap::Args;
use std::path::PathBuf;
use twinloop_dynamics::{BaseKind, Model};
use twinloop_ident::plate::{PlateOptions, generate_static_poses};
use twinloop_ident::{IdentError, PoseCategory, write_static_poses};

#[derive(Args, Debug)]
pub struct StaticPosesArgs {
    /// The robot as it really is (the TRUTH): a URDF or MJCF file, or builtin:NAME.
    #[arg(long, value_name = "ROBOT")]
    pub robot: String,
    /// Number of poses, spread evenly over the categories.
    #[arg(long, default_value_t = 172, value_parser = pose_count)]
    pub count: usize,
    /// Categories, comma-separated: arm, left, right, torso, crouch, wide.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "arm,left,right,torso,crouch,wide"
    )]
    pub categories: Vec<String>,
    /// CoP noise, standard deviation per axis, metres.
    #[arg(long, default_value_t = 0.0, value_name = "M", value_parser = crate::units::noise)]
    pub cop_noise: f64,
    /// Joint-angle noise added to the written configuration, standard deviation, rad.
    #[arg(long, default_value_t = 0.0, value_name = "RAD", value_parser = crate::units::noise)]
    pub joint_noise: f64,
    /// Random seed (same seed, same poses).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Gap between the soles for the double-support categories, metres.
    #[arg(long, default_value_t = 0.02, value_name = "M", value_parser = crate::units::noise)]
    pub gap: f64,
    /// Gap between the soles for the wide stance, metres.
    #[arg(long, default_value_t = 0.20, value_name = "M", value_parser = crate::units::noise)]
    pub wide_gap: f64,
    /// Joints held at their neutral value in every pose, comma-separated.
    #[arg(long, value_delimiter = ',', value_name = "JOINTS")]
    pub hold: Vec<String>,
    /// The foot links, left then right, when they cannot be found from the geometry.
    #[arg(long, value_delimiter = ',', num_args = 2, value_name = "LEFT,RIGHT")]
    pub feet: Vec<String>,
    /// Output CSV.
    #[arg(long, value_name = "poses.csv")]
    pub out: PathBuf,
}

/// Joint names to joint indices; the error names the option and the unknown name.
fn joint_indices(model: &Model, names: &[String], option: &str) -> Result<Vec<usize>, CliError> {
    names
        .iter()
        .map(|n| {
            model.joint_index(n).ok_or_else(|| {
                IdentError::new(format!(
                    "no joint named \"{n}\" in the model \"{}\"",
                    model.name
                ))
                .field(option)
                .into()
            })
        })
        .collect()
}

fn parse_categories(names: &[String]) -> Result<Vec<PoseCategory>, CliError> {
    names
        .iter()
        .map(|n| {
            PoseCategory::from_name(n.trim()).ok_or_else(|| {
                IdentError::new(format!(
                    "\"{n}\" is not a category (arm, left, right, torso, crouch, wide)"
                ))
                .field("--categories")
                .into()
            })
        })
        .collect()
}

pub fn run(a: &StaticPosesArgs) -> CliResult {
    check_noise(a.cop_noise, "--cop-noise")?;
    check_noise(a.joint_noise, "--joint-noise")?;
    let (robot, model) = load_model(&a.robot, BaseKind::Floating)?;
    hinges_only(&robot, &a.robot, "the static-pose experiment")?;
    let options = PlateOptions {
        count: a.count,
        categories: parse_categories(&a.categories)?,
        cop_noise: a.cop_noise,
        joint_noise: a.joint_noise,
        seed: a.seed,
        gap: a.gap,
        wide_gap: a.wide_gap,
        hold: joint_indices(&model, &a.hold, "--hold")?,
        feet: (a.feet.len() == 2).then(|| (a.feet[0].clone(), a.feet[1].clone())),
    };
    let bar = progress::steps(a.count);
    bar.set_message("poses");
    let generated = generate_static_poses(&robot, &model, &options, |k| bar.set_position(k as u64))
        .map_err(|e| e.in_file(&a.robot))?;
    bar.finish_and_clear();
    for (c, why) in &generated.skipped {
        eprintln!("note: category \"{}\" skipped: {why}", c.name());
    }
    let poses: Vec<_> = generated.poses.iter().map(|g| g.pose.clone()).collect();
    write_static_poses(&a.out, &model, &poses)?;
    let mut text = format!(
        "{} poses of {} written to {}\n\ncategory  poses  systematic  GCOM margin min / median (mm)\n",
        poses.len(),
        model.name,
        a.out.display()
    );
    for c in PoseCategory::ALL {
        let mine: Vec<_> = generated
            .poses
            .iter()
            .filter(|g| g.pose.category == Some(c))
            .collect();
        if mine.is_empty() {
            continue;
        }
        let sys = mine
            .iter()
            .filter(|g| matches!(g.plan, twinloop_ident::plate::Plan::Systematic { .. }))
            .count();
        let mut m: Vec<f64> = mine.iter().map(|g| g.support_margin * 1e3).collect();
        m.sort_by(f64::total_cmp);
        text.push_str(&format!(
            "{:<8}  {:>5}  {:>10}  {:.1} / {:.1}\n",
            c.name(),
            mine.len(),
            sys,
            m[0],
            m[m.len() / 2]
        ));
    }
    crate::common::print(&text);
    Ok(Outcome::Ok)
}

/// The most poses one run makes: 20 000. Each pose is a balance solve (some 2.5 ms on a
/// loaded machine), so the bound is under a minute of work; the seed's data set has
/// 172 poses, and a count of a million was an hour.
const MAX_POSES: usize = 20_000;

/// `--count`: a count (crate::bounds::count) of at most [`MAX_POSES`].
fn pose_count(s: &str) -> Result<usize, String> {
    let n = crate::bounds::count(s)?;
    if n <= MAX_POSES {
        Ok(n)
    } else {
        Err(format!(
            "{n} poses is more than the {MAX_POSES} one run makes (each is a balance solve: \
             under a minute in all); split the run with other --seed values"
        ))
    }
}
