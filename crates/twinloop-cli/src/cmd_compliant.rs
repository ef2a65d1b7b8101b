//! `twinloop compliant stiffness|simulate`: the compact compliant model of seed 002
//! (COMAN): its Cartesian stiffness and damping, and rolling it out.

use crate::common::hinges_only;
use crate::common::{emit, load_model, num, print, read_table};
use crate::error::{CliError, CliResult, Outcome};
use clap::{Args, Subcommand, ValueEnum};
use serde::Serialize;
use std::path::{Path, PathBuf};
use twinloop_dynamics::{BaseKind, Data, Model};
use twinloop_io::CsvWriter;
use twinloop_reduced::{
    CompactModel, Corrections, JointCompliance, SagittalCompliance, SagittalReference, SupportLeg,
    cartesian_compliance, coman_crouch,
};

#[derive(Subcommand, Debug)]
pub enum CompliantCommand {
    /// Cartesian stiffness K_C and damping D_C at the CoM (seed 002, eq 7-8)
    ///
    /// K_C = J^-T K_j J^-1 and D_C = J^-T D_j J^-1, with J the support-leg Jacobian from
    /// the sole frame to the CoM (linear rows) and the pelvis (angular rows), foot held,
    /// in the foot frame, and K_j = diag(k_j): k_j = K_h K_s/(K_h + K_s) on the knee and
    /// ankle pitch joints, K_h on the others. The pose is a flat-footed crouch
    /// (KneeSag = --knee-bend, HipSag = AnkSag = -bend/2 on both legs), then --q overrides.
    /// A stretched knee makes J singular: that is an error.
    ///
    /// Example:
    ///   twinloop compliant stiffness --robot models/coman/coman.urdf --support left --json kc.json
    ///
    /// Output: the x-z blocks (eq 11) and the 6x6 matrices on stdout; --json FILE (- for
    /// stdout) writes them with J, K_j and the `sagittal` entries `compliant simulate`
    /// and `identify compliant` read.
    #[command(verbatim_doc_comment)]
    Stiffness(StiffnessArgs),
    /// Roll the compact CoM model (seed 002, eq 9-11, 14-17) along a reference
    ///
    /// x'' = eta1 (-a1 Kxx/m (x - xr) - b1 Kxz/m (z - zr) - g1 Dxx/m x' - e1 Dxz/m z'),
    /// z'' = -g + eta2 (-a2 Kzx/m (x - xr) - b2 Kzz/m (z - zr) - g2 Dzx/m x' - e2 Dzz/m z'),
    /// eta = 1 in single support; RK4 at the reference's sample times.
    ///
    /// --noise adds white Gaussian noise: synthetic data for `twinloop identify compliant`.
    ///
    /// Example:
    ///   twinloop gait zmp --footsteps 3 --out ref.csv
    ///   twinloop compliant simulate --reference ref.csv --plant kc.json --table1 --out sim.csv
    ///
    /// Output: SIM.csv with t, xr, zr, x, z, phase; stdout gives the time taken and the
    /// RMS deviation from the reference.
    #[command(verbatim_doc_comment)]
    Simulate(SimulateArgs),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Side {
    Left,
    Right,
}

#[derive(Args, Debug)]
pub struct StiffnessArgs {
    /// COMAN's description: a URDF or MJCF file (models/coman/coman.urdf).
    #[arg(long, value_name = "ROBOT")]
    pub robot: String,
    /// Support leg.
    #[arg(long, value_enum, default_value_t = Side::Left)]
    pub support: Side,
    /// Knee bend of the crouched pose, rad.
    #[arg(long, default_value_t = 0.5, value_parser = crate::common::positive)]
    pub knee_bend: f64,
    /// Joint value override, NAME=RAD (repeatable).
    #[arg(long = "q", value_name = "NAME=RAD")]
    pub q: Vec<String>,
    /// Harmonic-drive stiffness K_h, N m/rad.
    #[arg(long, default_value_t = 8000.0, value_parser = crate::common::positive)]
    pub k_harmonic: f64,
    /// Series spring stiffness K_s, N m/rad.
    #[arg(long, default_value_t = 100.0, value_parser = crate::common::positive)]
    pub k_series: f64,
    /// Damping of the stiff joints, N m s/rad (the seed gives no value).
    #[arg(long, default_value_t = 1.0, value_parser = crate::common::non_negative)]
    pub d_stiff: f64,
    /// Damping of the compliant joints, N m s/rad (the seed gives no value).
    #[arg(long, default_value_t = 1.0, value_parser = crate::common::non_negative)]
    pub d_compliant: f64,
    /// Write the result as JSON to FILE (-: to stdout, in place of the text).
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
}

#[derive(Serialize)]
struct StiffnessReport {
    urdf: String,
    support: Side,
    foot_frame: String,
    mass: f64,
    gravity: f64,
    joints: Vec<String>,
    joint_positions: Vec<f64>,
    k_joint: Vec<f64>,
    d_joint: Vec<f64>,
    com_in_foot: [f64; 3],
    inverse_condition: f64,
    /// Rows x, y, z, wx, wy, wz; columns the leg joints.
    jacobian: Vec<Vec<f64>>,
    stiffness: Vec<Vec<f64>>,
    damping: Vec<Vec<f64>>,
    /// The entries of eq 11: Kxx, Kxz, Kzx, Kzz, Dxx, Dxz, Dzx, Dzz.
    sagittal: SagittalCompliance,
    /// x-z stiffness under forces alone (pelvis free to turn), for comparison.
    stiffness_xz_force_only: Option<[[f64; 2]; 2]>,
}

fn rows(m: &nalgebra::Matrix6<f64>) -> Vec<Vec<f64>> {
    (0..6)
        .map(|r| (0..6).map(|c| m[(r, c)]).collect())
        .collect()
}

pub fn run(cmd: CompliantCommand) -> CliResult {
    match cmd {
        CompliantCommand::Stiffness(args) => stiffness(&args),
        CompliantCommand::Simulate(args) => simulate(&args),
    }
}

/// The crouched pose with the --q overrides.
fn stiffness_pose(args: &StiffnessArgs, model: &Model) -> Result<Vec<f64>, CliError> {
    let mut q =
        coman_crouch(model, args.knee_bend).map_err(|e| CliError::from(e).context(&args.robot))?;
    for item in &args.q {
        let Some((name, value)) = item.split_once('=') else {
            return Err(CliError::new(format!("--q {item}: expected NAME=RAD")));
        };
        let Some(i) = model.joint_index(name.trim()) else {
            return Err(CliError::new(format!(
                "--q {item}: the model has no joint named {name}"
            )));
        };
        match value.trim().parse::<f64>() {
            Ok(v) if v.is_finite() => q[model.q_offset + i] = v,
            _ => {
                return Err(CliError::new(format!(
                    "--q {item}: {value} is not a finite number"
                )));
            }
        }
    }
    Ok(q)
}

fn stiffness(args: &StiffnessArgs) -> CliResult {
    let (robot, model) = load_model(&args.robot, BaseKind::Floating)?;
    hinges_only(&robot, &args.robot, "the compliant model")?;
    let q = stiffness_pose(args, &model)?;
    let leg = SupportLeg::coman(args.support == Side::Left);
    let joints = JointCompliance {
        k_harmonic: args.k_harmonic,
        k_series: args.k_series,
        d_stiff: args.d_stiff,
        d_compliant: args.d_compliant,
        ..JointCompliance::default()
    };
    let mut data = Data::new(&model);
    let cc = cartesian_compliance(&model, &mut data, &q, &leg, &joints)?;
    let (k, d) = (cc.stiffness_xz(), cc.damping_xz());
    let soft = cc.stiffness_xz_force_only();
    let report = StiffnessReport {
        urdf: args.robot.clone(),
        support: args.support,
        foot_frame: leg.foot_frame.clone(),
        mass: model.total_mass,
        gravity: twinloop_description::GRAVITY,
        joint_positions: leg
            .joints
            .iter()
            .map(|j| q[model.q_offset + model.joint_index(j).unwrap_or(0)])
            .collect(),
        joints: leg.joints.to_vec(),
        k_joint: cc.k_joint.iter().copied().collect(),
        d_joint: cc.d_joint.iter().copied().collect(),
        com_in_foot: cc.com_in_foot,
        inverse_condition: cc.inverse_condition,
        jacobian: rows(&cc.jacobian),
        stiffness: rows(&cc.stiffness),
        damping: rows(&cc.damping),
        stiffness_xz_force_only: soft.map(|m| [[m[(0, 0)], m[(0, 1)]], [m[(1, 0)], m[(1, 1)]]]),
        sagittal: SagittalCompliance::from_xz(
            model.total_mass,
            twinloop_description::GRAVITY,
            &k,
            &d,
        ),
    };
    let mut text = format!(
        "support {:?} ({}), mass {} kg, CoM in foot frame ({}, {}, {}) m\n\
         K_C x-z [N/m]:   [[{}, {}], [{}, {}]]\n\
         D_C x-z [N s/m]: [[{}, {}], [{}, {}]]\n",
        args.support,
        leg.foot_frame,
        num(model.total_mass),
        num(cc.com_in_foot[0]),
        num(cc.com_in_foot[1]),
        num(cc.com_in_foot[2]),
        num(k[(0, 0)]),
        num(k[(0, 1)]),
        num(k[(1, 0)]),
        num(k[(1, 1)]),
        num(d[(0, 0)]),
        num(d[(0, 1)]),
        num(d[(1, 0)]),
        num(d[(1, 1)]),
    );
    for (name, m) in [("K_C (6x6)", &cc.stiffness), ("D_C (6x6)", &cc.damping)] {
        text += &format!("{name}, rows/columns x, y, z, wx, wy, wz:\n");
        for r in 0..6 {
            let row: Vec<String> = (0..6).map(|c| format!("{:>13}", num(m[(r, c)]))).collect();
            text += &row.join(" ");
            text += "\n";
        }
    }
    emit(&text, args.json.as_ref(), &report)?;
    Ok(Outcome::Ok)
}

#[derive(Args, Debug)]
pub struct SimulateArgs {
    /// Reference CSV with columns t, xr, zr, phase (from `twinloop gait zmp`); optional x, z
    /// columns give the initial CoM, else the model starts at rest at its static
    /// equilibrium under the first row's reference.
    #[arg(long, value_name = "FILE.csv")]
    pub reference: PathBuf,
    /// The JSON written by `compliant stiffness --json` (mass, gravity, sagittal entries),
    /// or a PLANT.toml as `identify compliant` reads it.
    #[arg(long, value_name = "FILE.json|PLANT.toml")]
    pub plant: PathBuf,
    /// The ten corrections alpha1,beta1,gamma1,epsilon1,alpha2,beta2,gamma2,epsilon2,eta1,eta2
    /// (default all ones: eq 11 uncorrected).
    #[arg(long, value_name = "P1,..,P10", conflicts_with = "table1")]
    pub params: Option<String>,
    /// Use seed 002's Table 1 corrections (eta1 = eta2 = 1).
    #[arg(long)]
    pub table1: bool,
    /// White Gaussian noise added to x and z after the first row, m (synthetic data for
    /// `identify compliant`).
    #[arg(long, default_value_t = 0.0, value_parser = crate::units::noise)]
    pub noise: f64,
    /// Seed of the noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output CSV: t, xr, zr, x, z, phase.
    #[arg(long, value_name = "FILE.csv")]
    pub out: PathBuf,
}

/// PLANT.toml, or the JSON written by `compliant stiffness --json`.
pub fn read_plant_any(path: &Path) -> Result<SagittalCompliance, CliError> {
    Ok(twinloop_ident::compliant_fit::read_plant(path)?)
}

/// The corrections: --table1, --params, or all ones.
fn corrections(args: &SimulateArgs) -> Result<Corrections, CliError> {
    if args.table1 {
        return Ok(Corrections::seed_table1());
    }
    let Some(text) = &args.params else {
        return Ok(Corrections::default());
    };
    let values: Result<Vec<f64>, _> = text.split(',').map(|s| s.trim().parse::<f64>()).collect();
    match values {
        Ok(v) if v.len() == 10 => {
            let mut a = [0.0; 10];
            a.copy_from_slice(&v);
            Ok(Corrections::from_slice(&a))
        }
        _ => Err(CliError::new(format!(
            "--params {text}: expected 10 comma-separated numbers"
        ))),
    }
}

/// The reference and, when the file has `x` and `z` columns, the initial CoM.
fn read_reference(path: &Path) -> Result<(SagittalReference, Option<(f64, f64)>), CliError> {
    let table = read_table(path)?;
    let col = |name: &str| table.column_index(name);
    let (Some(it), Some(ix), Some(iz), Some(ip)) = (col("t"), col("xr"), col("zr"), col("phase"))
    else {
        return Err(CliError::new(format!(
            "{}: needs columns t, xr, zr, phase",
            path.display()
        )));
    };
    let reference = SagittalReference {
        t: table.rows.iter().map(|r| r[it]).collect(),
        xr: table.rows.iter().map(|r| r[ix]).collect(),
        zr: table.rows.iter().map(|r| r[iz]).collect(),
        double_support: table.rows.iter().map(|r| r[ip] >= 0.5).collect(),
    };
    reference
        .validate()
        .map_err(|e| CliError::from(e).context(path.display()))?;
    let start = match (col("x"), col("z")) {
        (Some(a), Some(b)) => Some((table.rows[0][a], table.rows[0][b])),
        _ => None,
    };
    Ok((reference, start))
}

fn simulate(args: &SimulateArgs) -> CliResult {
    let plant = read_plant_any(&args.plant)?;
    let corrections = corrections(args)?;
    let (reference, start) = read_reference(&args.reference)?;
    let model = CompactModel { plant, corrections };
    let (x0, z0) = match start {
        Some(s) => s,
        None => {
            let e = model
                .equilibrium(
                    reference.xr[0],
                    reference.zr[0],
                    reference.double_support[0],
                )
                .ok_or_else(|| {
                    CliError::new("the model's stiffness block is singular: no static equilibrium")
                })?;
            (e[0], e[1])
        }
    };
    let (mut x, mut z) = (Vec::new(), Vec::new());
    let started = std::time::Instant::now();
    model
        .rollout(&reference, x0, z0, &mut x, &mut z)
        .map_err(|e| CliError::from(e).context(format!("--plant {}", args.plant.display())))?;
    let elapsed = started.elapsed();
    if args.noise > 0.0 {
        // The first row stays exact: the fit starts the model there at rest.
        let mut rng = twinloop_random::SplitMix64(args.seed);
        for i in 1..x.len() {
            x[i] += args.noise * rng.normal();
            z[i] += args.noise * rng.normal();
        }
    }
    let rms = |a: &[f64], b: &[f64]| {
        (a.iter().zip(b).map(|(p, q)| (p - q) * (p - q)).sum::<f64>() / a.len() as f64).sqrt()
    };
    let (rms_x, rms_z) = (rms(&x, &reference.xr), rms(&z, &reference.zr));
    if !(rms_x.is_finite() && rms_z.is_finite()) {
        // Checked again before the result leaves (issue 29, class 3).
        return Err(CliError::new(format!(
            "--plant {}: the rollout's deviation from the reference is not finite (x {} \
             m, z {} m): no file written",
            args.plant.display(),
            num(rms_x),
            num(rms_z)
        )));
    }
    write_rollout(&args.out, &reference, &x, &z)?;
    let n = reference.t.len();
    print(&format!(
        "{n} samples in {} ms ({} us per 1000 samples) -> {}\nrms deviation from the reference: x {} m, z {} m\n",
        num(elapsed.as_secs_f64() * 1e3),
        num(elapsed.as_secs_f64() * 1e6 * 1000.0 / n as f64),
        args.out.display(),
        num(rms_x),
        num(rms_z),
    ));
    Ok(Outcome::Ok)
}

/// `t, xr, zr, x, z, phase` per sample.
fn write_rollout(
    out: &Path,
    reference: &SagittalReference,
    x: &[f64],
    z: &[f64],
) -> Result<(), CliError> {
    let columns: Vec<String> = ["t", "xr", "zr", "x", "z", "phase"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    let mut writer = CsvWriter::create(out, &columns)?;
    for i in 0..reference.t.len() {
        let phase = if reference.double_support[i] {
            1.0
        } else {
            0.0
        };
        writer.write_row(&[
            reference.t[i],
            reference.xr[i],
            reference.zr[i],
            x[i],
            z[i],
            phase,
        ])?;
    }
    Ok(writer.finish()?)
}
