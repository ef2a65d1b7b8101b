//! Static identification (seed 004): `experiment static-poses` (the virtual force
//! plate), `identify static`, `ik` (marker fitting) and `validate residual`
//! (inverse-dynamics residual of the base).

use crate::common::EXIT_BAD_INPUT;
use crate::progress;
use clap::{Args, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;
use twinloop_description::Description;
use twinloop_dynamics::{Data, Model};
use twinloop_ident::html::{residual_sections, static_sections};
use twinloop_ident::markers::{
    MarkerIk, frame_columns, marker_positions, read_frames, read_markers,
};
use twinloop_ident::plate::{PlateOptions, generate_static_poses};
use twinloop_ident::static_ident::{
    StaticProblem, StaticWorkspace, assemble, candidate_poses, solve, suggest_poses,
};
use twinloop_ident::validate::{
    ResidualSummary, Smoothing, SquatOptions, read_motion, read_plate, residual_wrench,
    squat_motion, write_motion,
};
use twinloop_ident::{
    IdentError, PoseCategory, StaticOptions, adapted_robot, identify_static, read_static_poses,
    write_static_poses,
};
use twinloop_io::{CsvWriter, Quantity};
use twinloop_random::SplitMix64;
use twinloop_report::Report;

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
fn load(path: &std::path::Path) -> Result<(Description, Model), String> {
    let robot = twinloop_description::load(path).map_err(|e| e.to_string())?;
    let model = Model::from_description(&robot).map_err(|e| format!("{}: {e}", path.display()))?;
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
    /// Ramp both ankles forward, backward, left and right until the robot tips over
    ///
    /// The robot stands on its servos in the simulator (compliance slope 2: stiff). Forward
    /// and backward, both ankle pitches ramp (--ramp deg/s); left and right, both ankle
    /// rolls and both hip rolls turn together, so the legs lean as a parallelogram with the
    /// feet flat and the pelvis level (with the hips held, the two ankle axes would lock the
    /// lean into a closed chain through the ground). Each direction runs twice: a first ramp
    /// finds the tip, a second ramps to 0.5 deg before it and creeps slowly (--slow-ramp) so
    /// the detection lag does not inflate the angle. The tip is where the trunk tilts beyond
    /// what the joints explain. Recorded: the angle commanded and measured at the onset and
    /// the time taken (seed 000 Table IV), beside the model's static tipping angle (CoM over
    /// the support edge, from the joints measured at the onset; `rigid_static_deg` from the
    /// rigid standing pose). From the four angles, the CoM by the seed's geometric method
    /// (seed 000 eq 8-13) and by the exact method, next to the model's true CoM, all relative
    /// to the midpoint of the ankle axes (x forward, y left, z up).
    ///
    /// Example:
    ///   twinloop experiment tipover --robot builtin:km20 --add-mass 0.2@torso:0.05,0,0 --json tip.json
    Tipover(crate::cmd_experiment::TipoverArgs),
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
    #[command(verbatim_doc_comment)]
    StaticPoses(StaticPosesArgs),
    /// Squat-like validation motion with force-plate readings (seed 004, Fig. 4)
    ///
    /// Makes the validation motion of seed 004, section 3.4 with the TRUTH description:
    /// standing on both feet, the pelvis goes down by --depth and up again (each half a
    /// minimum-jerk move) while the arms swing forward and the CoM stays over the middle
    /// of the feet, between --rest seconds of standing still. Each frame is solved
    /// exactly (feet flat where they stand); the plate readings are what the truth's
    /// inverse dynamics needs from the ground.
    ///
    /// Example:
    ///   twinloop experiment squat --urdf models/unitree_h1/h1.urdf --out squat.csv
    ///   twinloop experiment squat --urdf truth.urdf --out squat.csv \
    ///       --markers markers.toml --frames-out frames.csv --marker-noise 0.0005
    ///
    /// Output: a CSV with `t`, the configuration `q:*` and the plate: `grf.fx grf.fy
    /// grf.fz` (ground reaction on the robot, world, N), `cop.x cop.y` (m) and `grf.tz`
    /// (free moment, N m). With --markers, --frames-out gets the markers' world positions
    /// `marker:<name>.x .y .z` per frame (plus --marker-noise), input for `twinloop ik`.
    #[command(verbatim_doc_comment)]
    Squat(SquatArgs),
}

#[derive(Args, Debug)]
pub struct SquatArgs {
    /// The robot as it really is (URDF or MJCF).
    #[arg(long, value_name = "TRUTH.urdf")]
    pub urdf: PathBuf,
    /// Output CSV (configuration and plate).
    #[arg(long, value_name = "squat.csv")]
    pub out: PathBuf,
    /// How far the pelvis goes down, m (default: 12 % of its standing height).
    #[arg(long, value_name = "M")]
    pub depth: Option<f64>,
    /// Duration of the down-and-up motion, s.
    #[arg(long, default_value_t = 5.0, value_name = "S")]
    pub duration: f64,
    /// Standing still before and after, s.
    #[arg(long, default_value_t = 1.0, value_name = "S")]
    pub rest: f64,
    /// Sampling rate, Hz (seed 004's motion capture: 150 Hz).
    #[arg(long, default_value_t = 150.0, value_name = "HZ")]
    pub rate: f64,
    /// How far the arms swing forward at the bottom, fraction of their range.
    #[arg(long, default_value_t = 0.35)]
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
    #[arg(long, default_value_t = 0.0, value_name = "M")]
    pub marker_noise: f64,
    /// Random seed of the marker noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
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
        ExperimentCommand::Squat(a) => finish(squat(&a)),
        ExperimentCommand::Tipover(a) => crate::cmd_experiment::tipover(a),
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

fn squat(a: &SquatArgs) -> Result<(), String> {
    check_noise(a.marker_noise, "--marker-noise")?;
    let (robot, model) = load(&a.urdf)?;
    let options = SquatOptions {
        rest: a.rest,
        duration: a.duration,
        rate: a.rate,
        depth: a.depth,
        arm_swing: a.arm_swing,
        feet: (a.feet.len() == 2).then(|| (a.feet[0].clone(), a.feet[1].clone())),
    };
    let markers = match &a.markers {
        Some(p) => Some(read_markers(p, &model).map_err(|e| e.to_string())?),
        None => None,
    };
    let bar = progress::steps(1);
    bar.set_message("frames");
    let motion = squat_motion(&robot, &model, &options, |k, n| {
        bar.set_length(n as u64);
        bar.set_position(k as u64);
    })
    .map_err(|e| e.in_file(&a.urdf).to_string())?;
    bar.finish_and_clear();
    write_motion(&a.out, &model, &motion).map_err(|e| e.to_string())?;
    if let (Some(markers), Some(out)) = (markers, &a.frames_out) {
        let mut data = Data::new(&model);
        let mut rng = SplitMix64(a.seed);
        let mut w = CsvWriter::create(out, &frame_columns(&markers)).map_err(|e| e.to_string())?;
        let mut row = Vec::new();
        for (t, q) in motion.t.iter().zip(&motion.q) {
            twinloop_dynamics::forward_kinematics(&model, &mut data, q);
            row.clear();
            row.push(*t);
            for p in marker_positions(&model, &data, &markers) {
                for k in 0..3 {
                    row.push(p[k] + a.marker_noise * rng.normal());
                }
            }
            w.write_row(&row).map_err(|e| e.to_string())?;
        }
        w.finish().map_err(|e| e.to_string())?;
    }
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
    crate::common::print(&format!(
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
    ));
    Ok(())
}

#[derive(Subcommand, Debug)]
pub enum IdentifyCommand {
    /// Link masses and CoMs from static poses on a force plate (seed 004, eq 8-9)
    ///
    /// In a static pose the force plate's centre of pressure (CoP) is the
    /// ground-projected centre of mass (GCOM). The CoM is linear in each link's mass m and
    /// first moment m c, so the masses and CoMs that bring the model's GCOM closest
    /// to the measured CoPs, with the masses adding up to --total-mass (the robot on
    /// a scale), are the solution of a linear least-squares problem. It is solved
    /// exactly, with the masses kept positive and each CoM inside a box around its
    /// link (the link's primitive geometry and prior CoM, plus --com-margin).
    ///
    /// What the poses cannot see is kept at the prior (the PRIOR description): each
    /// unknown is weighted by its prior (100 % of each mass) against the plate noise
    /// --cop-sigma, so well-excited directions come from the data and unseen ones
    /// (links welded to one body, a joint that never moves) stay at the CAD values.
    /// From CoP data alone a link's mass and its first moment along its joint axis
    /// can always be traded for its parent's: those directions never move (see the
    /// identifiability section of the output).
    ///
    /// Example:
    ///   twinloop identify static --urdf prior.urdf --poses poses.csv --total-mass 59.34 \
    ///       --out-urdf adapted.urdf --json result.json --report report.html
    ///   twinloop identify static --urdf prior.urdf --poses poses.csv --total-mass 59.34 \
    ///       --links torso_link,pelvis --cop-sigma 0 --out-urdf adapted.urdf --json r.json
    ///
    /// Output: the adapted URDF (only the identified links' <inertial> mass and origin
    /// xyz change; inertia tensors and everything else are untouched), the JSON result
    /// (per link: prior and identified mass and CoM with standard deviations and how
    /// much the poses determine them; GCOM-to-CoP distance per pose before and after;
    /// identifiability: rank, singular values, condition number, what is not
    /// determined and why; suggested poses), and on stdout a summary. With --squat, the
    /// residual base wrench of the prior and adapted models on that motion (seed 004,
    /// Table 1) is added. --report writes an HTML page with the seed's Fig. 5 (and
    /// Fig. 6 with --squat).
    #[command(verbatim_doc_comment)]
    Static(IdentifyStaticArgs),
}

#[derive(Args, Debug)]
pub struct IdentifyStaticArgs {
    /// The prior description (CAD model): starting point and regulariser.
    #[arg(long, value_name = "PRIOR.urdf")]
    pub urdf: PathBuf,
    /// Static poses: configuration and measured CoP per row.
    #[arg(long, value_name = "poses.csv")]
    pub poses: PathBuf,
    /// The robot's mass on a scale, kg (seed 004, eq 9).
    #[arg(long, value_name = "KG")]
    pub total_mass: f64,
    /// Links to identify, comma-separated (default: every link with mass).
    #[arg(long, value_delimiter = ',', value_name = "LINKS")]
    pub links: Vec<String>,
    /// CoP noise per axis the regulariser assumes, m (0: exact data, prior only where
    /// the data see nothing).
    #[arg(long, default_value_t = 0.001, value_name = "M")]
    pub cop_sigma: f64,
    /// How far a CoM may leave its link's geometry box, m.
    #[arg(long, default_value_t = 0.03, value_name = "M")]
    pub com_margin: f64,
    /// Adapted description to write.
    #[arg(long, value_name = "ADAPTED.urdf")]
    pub out_urdf: Option<PathBuf>,
    /// JSON result to write.
    #[arg(long, value_name = "RESULT.json")]
    pub json: Option<PathBuf>,
    /// HTML report to write.
    #[arg(long, value_name = "OUT.html")]
    pub report: Option<PathBuf>,
    /// A validation motion with plate columns (from `experiment squat` or a
    /// recording): the residual base wrench of prior and adapted models is reported.
    #[arg(long, value_name = "MOTION.csv")]
    pub squat: Option<PathBuf>,
    /// How many further poses to suggest (from the virtual force plate on the prior).
    #[arg(long, default_value_t = 5)]
    pub suggest: usize,
    /// Where to write the suggested poses (category and configuration, no CoP).
    #[arg(long, value_name = "SUGGESTED.csv")]
    pub suggest_out: Option<PathBuf>,
    /// Repeat the fit (regressor and constrained solve) N times and print the median time.
    #[arg(long, value_name = "N")]
    pub time: Option<usize>,
}

pub fn identify(cmd: IdentifyCommand) -> ExitCode {
    match cmd {
        IdentifyCommand::Static(a) => finish(identify_static_cmd(&a)),
    }
}

fn mm(x: f64) -> String {
    format!("{:.3}", x * 1e3)
}

fn identify_static_cmd(a: &IdentifyStaticArgs) -> Result<(), String> {
    let (robot, model) = load(&a.urdf)?;
    let poses = read_static_poses(&a.poses, &model).map_err(|e| e.to_string())?;
    let options = StaticOptions {
        links: (!a.links.is_empty()).then(|| a.links.clone()),
        cop_sigma: a.cop_sigma,
        com_margin: a.com_margin,
        ..StaticOptions::default()
    };
    let problem =
        StaticProblem::new(&robot, &model, a.total_mass, &options).map_err(|e| e.to_string())?;
    let result = identify_static(&robot, &model, &poses, a.total_mass, &options).map_err(|e| {
        if e.field.as_deref() == Some("--poses") {
            e.in_file(&a.poses).to_string()
        } else {
            e.to_string()
        }
    })?;
    let mut timing = None;
    if let Some(n) = a.time {
        let mut ws = StaticWorkspace::new(&model, &problem, poses.len());
        let mut samples = Vec::with_capacity(n.max(1));
        for _ in 0..n.max(1) {
            let t0 = Instant::now();
            assemble(&model, &problem, &poses, &mut ws);
            let fit = solve(&problem, &ws).map_err(|e| e.to_string())?;
            std::hint::black_box(&fit.x);
            samples.push(t0.elapsed().as_secs_f64());
        }
        samples.sort_by(f64::total_cmp);
        timing = Some(samples[samples.len() / 2]);
    }
    let adapted = adapted_robot(&robot, &result);
    if let Some(p) = &a.out_urdf {
        twinloop_description::urdf::write_file(&adapted, p).map_err(|e| e.to_string())?;
    }
    // Suggestions from the virtual force plate on the prior.
    let mut suggestions = Vec::new();
    if a.suggest > 0 {
        let bar = progress::steps(1);
        bar.set_message("candidate poses for suggestions");
        match candidate_poses(&robot, &model, 12, 7) {
            Ok(cands) => {
                let mut ws = StaticWorkspace::new(&model, &problem, poses.len());
                assemble(&model, &problem, &poses, &mut ws);
                let fit = solve(&problem, &ws).map_err(|e| e.to_string())?;
                suggestions = suggest_poses(&model, &problem, &fit.gram, &cands, a.suggest);
            }
            Err(e) => eprintln!("note: no pose suggestions: {e}"),
        }
        bar.finish_and_clear();
    }
    if let Some(p) = &a.suggest_out {
        let mut cols = vec!["category".to_string()];
        cols.extend(Quantity::Q.column_names(&model.q_names()));
        let mut w = CsvWriter::create(p, &cols).map_err(|e| e.to_string())?;
        for s in &suggestions {
            let mut row = vec![s.category as i32 as f64];
            row.extend_from_slice(&s.q);
            w.write_row(&row).map_err(|e| e.to_string())?;
        }
        w.finish().map_err(|e| e.to_string())?;
    }
    // Validation on a motion: prior and adapted.
    let mut validation = None;
    if let Some(m) = &a.squat {
        let motion = read_motion(m, &model).map_err(|e| e.to_string())?;
        let adapted_model = Model::from_description(&adapted).map_err(|e| e.to_string())?;
        let prior_res = residual_wrench(&model, &motion, Some(Smoothing::default()))
            .map_err(|e| e.in_file(m).to_string())?;
        let adapted_res = residual_wrench(&adapted_model, &motion, Some(Smoothing::default()))
            .map_err(|e| e.in_file(m).to_string())?;
        validation = Some((prior_res, adapted_res));
    }
    let json = serde_json::json!({
        "schema": "twinloop-static-identification/1",
        "prior": a.urdf.display().to_string(),
        "poses_file": a.poses.display().to_string(),
        "cop_sigma": a.cop_sigma,
        "com_margin": a.com_margin,
        "result": &result,
        "suggested_poses": &suggestions,
        "validation": validation.as_ref().map(|(p, q)| serde_json::json!({
            "motion": a.squat.as_ref().map(|m| m.display().to_string()),
            "prior": p.summary,
            "adapted": q.summary,
        })),
        "fit_seconds_median": timing,
    });
    if let Some(p) = &a.json {
        let text = serde_json::to_string_pretty(&json).map_err(|e| e.to_string())?;
        std::fs::write(p, text + "\n")
            .map_err(|e| format!("{}: cannot write: {e}", p.display()))?;
    }
    if let Some(p) = &a.report {
        let mut r = Report::new(format!("Static identification of {}", model.name));
        r.preformatted(format!(
            "twinloop identify static --urdf {} --poses {} --total-mass {}",
            a.urdf.display(),
            a.poses.display(),
            a.total_mass
        ));
        static_sections(&mut r, &result, &suggestions);
        if let Some((p0, p1)) = &validation {
            residual_sections(&mut r, &[("prior", p0), ("adapted", p1)]);
        }
        r.write(p)?;
    }
    // Summary on stdout.
    let id = &result.identifiability;
    let mut t = format!(
        "static identification of {} from {} poses (seed 004, eq 8-9)\n\
         total mass: measured {:.3} kg, prior {:.3} kg, {:.3} kg on {} links kept fixed\n\
         GCOM to CoP distance (mm): before mean {} std {} max {}  ->  after mean {} std {} max {}\n\
         identifiability: {} parameters, rank {}, {} above the noise ({:.2e} kg m), condition number {:.3e}\n\
         \x20 {} directions no static pose can determine (kept at the prior)\n",
        model.name,
        result.poses,
        result.total_mass,
        result.prior_total_mass,
        result.fixed_mass,
        result.fixed_links.len(),
        mm(result.before.mean),
        mm(result.before.std),
        mm(result.before.max),
        mm(result.after.mean),
        mm(result.after.std),
        mm(result.after.max),
        id.parameters,
        id.rank,
        id.well_determined,
        id.noise_level,
        id.condition_number,
        id.structural_null,
    );
    for g in &id.welded {
        t.push_str(&format!(
            "  welded to one body (only their sum is seen): {}\n",
            g.join(", ")
        ));
    }
    for g in &id.unidentifiable {
        t.push_str(&format!(
            "  not excited by these poses ({} directions): {}\n",
            g.directions,
            g.links.join(", ")
        ));
    }
    t.push_str("\nlink                              prior kg        kg   ± kg   CoM (mm, link frame)        determined m\n");
    for l in &result.links {
        t.push_str(&format!(
            "{:<32} {:>9.4} {:>9.4} {:>6.3}   {:>7.1} {:>7.1} {:>7.1}   {:>5.2}{}\n",
            l.name,
            l.prior_mass,
            l.mass,
            l.mass_std,
            l.com[0] * 1e3,
            l.com[1] * 1e3,
            l.com[2] * 1e3,
            l.mass_determined,
            if l.at_bounds.is_empty() {
                String::new()
            } else {
                format!("  at {}", l.at_bounds.join(", "))
            }
        ));
    }
    if !suggestions.is_empty() {
        t.push_str("\nposes that would help most (smallest singular value before -> after):\n");
        for (i, s) in suggestions.iter().enumerate() {
            t.push_str(&format!(
                "  {}. {:<6} {:.3e} -> {:.3e}\n",
                i + 1,
                s.category.name(),
                s.smallest_singular_value_before,
                s.smallest_singular_value_after
            ));
        }
    }
    if let Some((p0, p1)) = &validation {
        t.push_str(
            "\nresidual base wrench on the motion, mean [std] of |.| (seed 004, Table 1):\n",
        );
        t.push_str(&residual_table(&[
            ("prior", &p0.summary),
            ("adapted", &p1.summary),
        ]));
    }
    if let Some(s) = timing {
        t.push_str(&format!(
            "\nfit time (regressor + constrained solve), median: {:.3} ms\n",
            s * 1e3
        ));
    }
    crate::common::print(&t);
    Ok(())
}

fn residual_table(rows: &[(&str, &ResidualSummary)]) -> String {
    let mut t = String::from(
        "model          |Fx| N         |Fy| N         |Fz| N         |Tx| Nm        |Ty| Nm        |Tz| Nm\n",
    );
    for (name, s) in rows {
        t.push_str(&format!("{name:<10}"));
        for k in 0..6 {
            t.push_str(&format!(" {:>7.3} [{:>5.3}]", s.mean_abs[k], s.std_abs[k]));
        }
        t.push('\n');
    }
    t
}

#[derive(Args, Debug)]
pub struct IkArgs {
    /// Description description with the links the markers are on.
    #[arg(long, value_name = "FILE")]
    pub urdf: PathBuf,
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

pub fn ik(a: IkArgs) -> ExitCode {
    finish(ik_impl(&a))
}

fn ik_impl(a: &IkArgs) -> Result<(), String> {
    let (_robot, model) = load(&a.urdf)?;
    let markers = read_markers(&a.markers, &model).map_err(|e| e.to_string())?;
    let frames = read_frames(&a.frames, &markers).map_err(|e| e.to_string())?;
    let mut fitter = MarkerIk::new(&model, markers).map_err(|e| e.to_string())?;
    let mut cols = vec!["t".to_string()];
    cols.extend(Quantity::Q.column_names(&model.q_names()));
    cols.push("ik.rms".into());
    cols.push("ik.max".into());
    let mut w = CsvWriter::create(&a.out, &cols).map_err(|e| e.to_string())?;
    let bar = progress::rows(frames.t.len());
    let mut rms = Vec::with_capacity(frames.t.len());
    let mut worst: (f64, usize) = (0.0, 0);
    let mut row = Vec::with_capacity(cols.len());
    for (k, seen) in frames.positions.iter().enumerate() {
        let (q, fit) = fitter
            .fit(seen, k)
            .map_err(|e| e.in_file(&a.frames).to_string())?;
        row.clear();
        row.push(frames.t[k]);
        row.extend_from_slice(q);
        row.push(fit.rms);
        row.push(fit.max);
        w.write_row(&row).map_err(|e| e.to_string())?;
        rms.push(fit.rms);
        if fit.max > worst.0 {
            worst = (fit.max, k);
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    w.finish().map_err(|e| e.to_string())?;
    let mean = rms.iter().sum::<f64>() / rms.len().max(1) as f64;
    crate::common::print(&format!(
        "{} frames fitted (seed 004, eq 7) to {}\nmarker distance: mean RMS {:.3} mm, worst {:.3} mm (data row {})\n",
        rms.len(),
        a.out.display(),
        mean * 1e3,
        worst.0 * 1e3,
        worst.1 + 1
    ));
    Ok(())
}

#[derive(Subcommand, Debug)]
pub enum ValidateCommand {
    /// Residual base wrench by inverse dynamics (seed 004, section 3.4, Table 1)
    ///
    /// For a motion (configuration over time) and the force plate's ground reaction,
    /// computes the 6-D wrench at the floating base that the model cannot explain:
    /// inverse dynamics' base wrench minus the ground reaction, about the base origin,
    /// in world-aligned axes. Velocities and accelerations come from the configuration
    /// by a zero-phase Butterworth low-pass (--cutoff 10 Hz, as in the seed) and central
    /// differences. A perfect model leaves only the differentiation error; a model
    /// 10 kg too light leaves about 98 N in Fz.
    ///
    /// Example:
    ///   twinloop validate residual --urdf adapted.urdf --motion squat.csv --out res.csv
    ///   twinloop validate residual --urdf prior.urdf --compare adapted.urdf \
    ///       --motion traj.csv --plate squat.csv --out res.csv --report fig6.html
    ///
    /// Output: RES.csv with `t` and `res.fx res.fy res.fz` (N), `res.tx res.ty res.tz`
    /// (N m) per frame (with --compare, `cmp.*` for the second model), and on stdout
    /// the mean and standard deviation of |Fx| .. |Tz| (the seed's Table 1).
    #[command(verbatim_doc_comment)]
    Residual(ResidualArgs),
}

#[derive(Args, Debug)]
pub struct ResidualArgs {
    /// Description description to validate.
    #[arg(long, value_name = "FILE")]
    pub urdf: PathBuf,
    /// A second description to compare with (e.g. the adapted one).
    #[arg(long, value_name = "FILE")]
    pub compare: Option<PathBuf>,
    /// Motion: t and q:* columns (plate columns too, unless --plate).
    #[arg(long, value_name = "TRAJ.csv")]
    pub motion: PathBuf,
    /// Plate readings (grf.fx grf.fy grf.fz cop.x cop.y grf.tz), one row per motion frame.
    #[arg(long, value_name = "PLATE.csv")]
    pub plate: Option<PathBuf>,
    /// Output CSV.
    #[arg(long, value_name = "RES.csv")]
    pub out: PathBuf,
    /// Low-pass cut-off, Hz.
    #[arg(long, default_value_t = 10.0, value_name = "HZ")]
    pub cutoff: f64,
    /// Butterworth order (applied forwards and backwards).
    #[arg(long, default_value_t = 4)]
    pub filter_order: usize,
    /// Differentiate without smoothing (exact, noise-free data).
    #[arg(long)]
    pub no_smoothing: bool,
    /// JSON summary to write.
    #[arg(long, value_name = "OUT.json")]
    pub json: Option<PathBuf>,
    /// HTML report (the seed's Fig. 6) to write.
    #[arg(long, value_name = "OUT.html")]
    pub report: Option<PathBuf>,
}

pub fn validate(cmd: ValidateCommand) -> ExitCode {
    match cmd {
        ValidateCommand::Residual(a) => finish(residual_impl(&a)),
    }
}

fn residual_impl(a: &ResidualArgs) -> Result<(), String> {
    let (_r, model) = load(&a.urdf)?;
    let mut motion = read_motion(&a.motion, &model).map_err(|e| e.to_string())?;
    if let Some(p) = &a.plate {
        let table = twinloop_io::Table::read(p).map_err(|e| e.to_string())?;
        motion.plate = read_plate(&table).map_err(|e| e.in_file(p).to_string())?;
        if motion.plate.is_none() {
            return Err(IdentError::new(
                "no plate columns (grf.fx grf.fy grf.fz cop.x cop.y grf.tz)",
            )
            .in_file(p)
            .to_string());
        }
    }
    let smoothing = (!a.no_smoothing).then_some(Smoothing {
        cutoff_hz: a.cutoff,
        order: a.filter_order,
    });
    let file = a.plate.as_ref().unwrap_or(&a.motion);
    let res =
        residual_wrench(&model, &motion, smoothing).map_err(|e| e.in_file(file).to_string())?;
    let cmp = match &a.compare {
        Some(c) => {
            let (_r2, m2) = load(c)?;
            Some(
                residual_wrench(&m2, &motion, smoothing)
                    .map_err(|e| e.in_file(file).to_string())?,
            )
        }
        None => None,
    };
    let names = ["fx", "fy", "fz", "tx", "ty", "tz"];
    let mut cols = vec!["t".to_string()];
    cols.extend(names.iter().map(|n| format!("res.{n}")));
    if cmp.is_some() {
        cols.extend(names.iter().map(|n| format!("cmp.{n}")));
    }
    let mut w = CsvWriter::create(&a.out, &cols).map_err(|e| e.to_string())?;
    let mut row = Vec::with_capacity(cols.len());
    for k in 0..res.t.len() {
        row.clear();
        row.push(res.t[k]);
        row.extend_from_slice(&res.wrench[k]);
        if let Some(c) = &cmp {
            row.extend_from_slice(&c.wrench[k]);
        }
        w.write_row(&row).map_err(|e| e.to_string())?;
    }
    w.finish().map_err(|e| e.to_string())?;
    let label0 = a
        .urdf
        .file_name()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_default();
    let label1 = a
        .compare
        .as_ref()
        .and_then(|c| c.file_name())
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_default();
    let mut rows = vec![(label0.as_str(), &res.summary)];
    if let Some(c) = &cmp {
        rows.push((label1.as_str(), &c.summary));
    }
    if let Some(p) = &a.json {
        let j = serde_json::json!({
            "schema": "twinloop-residual/1",
            "motion": a.motion.display().to_string(),
            "smoothing": smoothing.map(|s| serde_json::json!({"cutoff_hz": s.cutoff_hz, "order": s.order})),
            "models": rows.iter().map(|(n, s)| serde_json::json!({"model": n, "summary": s})).collect::<Vec<_>>(),
        });
        std::fs::write(
            p,
            serde_json::to_string_pretty(&j).map_err(|e| e.to_string())? + "\n",
        )
        .map_err(|e| format!("{}: cannot write: {e}", p.display()))?;
    }
    if let Some(p) = &a.report {
        let mut r = Report::new(format!("Residual base wrench of {}", model.name));
        let mut runs = vec![(label0.as_str(), &res)];
        if let Some(c) = &cmp {
            runs.push((label1.as_str(), c));
        }
        residual_sections(&mut r, &runs);
        r.write(p)?;
    }
    crate::common::print(&format!(
        "residual base wrench over {} frames written to {} (world axes at the base origin)\n\
         mean [std] of the absolute values (seed 004, Table 1):\n{}",
        res.t.len(),
        a.out.display(),
        residual_table(&rows)
    ));
    Ok(())
}
