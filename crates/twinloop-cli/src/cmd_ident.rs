//! Static identification (seed 004): `experiment static-poses` (the virtual force
//! plate), `identify static`, `ik` (marker fitting) and `validate residual`
//! (inverse-dynamics residual of the base).

use crate::common::EXIT_BAD_INPUT;
use crate::progress;
use clap::{Args, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;
use twinloop_dynamics::Model;
use twinloop_ident::plate::{PlateOptions, generate_static_poses};
use twinloop_ident::{IdentError, PoseCategory, write_static_poses};
use twinloop_model::Robot;

fn fail(msg: impl std::fmt::Display) -> ExitCode {
    eprintln!("error: {msg}");
    ExitCode::from(EXIT_BAD_INPUT)
}

fn finish(r: Result<(), String>) -> ExitCode {
    match r {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => fail(e),
    }
}

/// Load a description and compile it with a floating base.
fn load(path: &std::path::Path) -> Result<(Robot, Model), String> {
    let robot = twinloop_model::load(path).map_err(|e| e.to_string())?;
    let model = Model::from_robot(&robot).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok((robot, model))
}

/// Joint names to joint indices; the error names the option and the unknown name.
fn joint_indices(model: &Model, names: &[String], option: &str) -> Result<Vec<usize>, String> {
    names
        .iter()
        .map(|n| {
            model.joint_index(n).ok_or_else(|| {
                IdentError::new(format!(
                    "no joint named \"{n}\" in the model \"{}\"",
                    model.name
                ))
                .field(option)
                .to_string()
            })
        })
        .collect()
}

#[derive(Subcommand, Debug)]
pub enum ExperimentCommand {
    /// Virtual force plate: statically stable poses and the CoP each would give
    ///
    /// Stands the robot (the TRUTH description: the robot as it really is) in
    /// statically stable poses in the six categories of seed 004, section 3.1:
    ///
    ///   arm     double support, feet --gap apart (2 cm), arm joints swept
    ///   left    single support on the left foot, right leg swept
    ///   right   single support on the right foot, left leg swept
    ///   torso   double support, torso (and head) joints swept
    ///   crouch  double support, knees bent, upper body varied
    ///   wide    double support, feet --wide-gap apart (20 cm), upper body random
    ///
    /// Swept joints are set systematically below 10 % and above 90 % of their range,
    /// one at a time, then at random (at least a third of each category's poses, up
    /// to 10). The soles are put flat on the ground (z = 0) by inverse kinematics
    /// over the whole configuration; on one foot the CoM is brought over the sole
    /// centre. A pose is kept only if its ground-projected CoM (GCOM) lies inside
    /// the support polygon, nothing else touches the ground and every joint is in
    /// its limits; otherwise it is drawn again. A category the robot cannot stand in
    /// is skipped (said on stderr) and its share goes to the others.
    ///
    /// Feet are found from the geometry (the lowest primitive shapes on either side);
    /// name them with --feet when that fails. The sole is the lowest face of the
    /// foot's box/cylinder/sphere shapes.
    ///
    /// Example:
    ///   twinloop experiment static-poses --urdf models/unitree_h1/h1.urdf --count 172 \
    ///       --cop-noise 0.001 --joint-noise 0.0017 --seed 7 --out poses.csv
    ///
    /// Output: a CSV with one row per pose: `category` (1-6 as above), the
    /// configuration `q:base.x .. q:base.qw`, `q:<joint>` (with --joint-noise added to
    /// the joints) and the plate's centre of pressure `cop.x`, `cop.y` (the truth's
    /// GCOM plus --cop-noise), world frame, metres. stdout gets a summary: poses per
    /// category and how far inside the support polygon the GCOMs lie.
    StaticPoses(StaticPosesArgs),
}

#[derive(Args, Debug)]
pub struct StaticPosesArgs {
    /// The robot as it really is (URDF or MJCF).
    #[arg(long, value_name = "TRUTH.urdf")]
    pub urdf: PathBuf,
    /// Number of poses, spread evenly over the categories.
    #[arg(long, default_value_t = 172)]
    pub count: usize,
    /// Categories, comma-separated: arm, left, right, torso, crouch, wide.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "arm,left,right,torso,crouch,wide"
    )]
    pub categories: Vec<String>,
    /// CoP noise, standard deviation per axis, metres.
    #[arg(long, default_value_t = 0.0, value_name = "M")]
    pub cop_noise: f64,
    /// Joint-angle noise added to the written configuration, standard deviation, rad.
    #[arg(long, default_value_t = 0.0, value_name = "RAD")]
    pub joint_noise: f64,
    /// Random seed (same seed, same poses).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Gap between the soles for the double-support categories, metres.
    #[arg(long, default_value_t = 0.02, value_name = "M")]
    pub gap: f64,
    /// Gap between the soles for the wide stance, metres.
    #[arg(long, default_value_t = 0.20, value_name = "M")]
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

pub fn experiment(cmd: ExperimentCommand) -> ExitCode {
    match cmd {
        ExperimentCommand::StaticPoses(a) => finish(static_poses(&a)),
    }
}

fn parse_categories(names: &[String]) -> Result<Vec<PoseCategory>, String> {
    names
        .iter()
        .map(|n| {
            PoseCategory::from_name(n.trim()).ok_or_else(|| {
                IdentError::new(format!(
                    "\"{n}\" is not a category (arm, left, right, torso, crouch, wide)"
                ))
                .field("--categories")
                .to_string()
            })
        })
        .collect()
}

fn check_noise(x: f64, option: &str) -> Result<(), String> {
    if x.is_finite() && x >= 0.0 {
        Ok(())
    } else {
        Err(
            IdentError::new(format!("{x} is not a standard deviation (finite, >= 0)"))
                .field(option)
                .to_string(),
        )
    }
}

fn static_poses(a: &StaticPosesArgs) -> Result<(), String> {
    check_noise(a.cop_noise, "--cop-noise")?;
    check_noise(a.joint_noise, "--joint-noise")?;
    let (robot, model) = load(&a.urdf)?;
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
        .map_err(|e| e.in_file(&a.urdf).to_string())?;
    bar.finish_and_clear();
    for (c, why) in &generated.skipped {
        eprintln!("note: category \"{}\" skipped: {why}", c.name());
    }
    let poses: Vec<_> = generated.poses.iter().map(|g| g.pose.clone()).collect();
    write_static_poses(&a.out, &model, &poses).map_err(|e| e.to_string())?;
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
    Ok(())
}
