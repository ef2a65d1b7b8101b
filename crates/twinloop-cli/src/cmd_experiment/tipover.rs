//! `twinloop experiment tipover`: the tip-over experiment of seeds 000 and 001 on the
//! simulator, with the CoM from the tip angles beside the model's.

use crate::common::{JSON_HELP, emit, load_description};
use crate::error::{CliError, CliResult, Outcome};
use clap::Args;
use std::path::PathBuf;
use twinloop_ident::tipover_study::{StudyOptions, StudyReport, run_study};

#[derive(Args, Debug)]
pub struct TipoverArgs {
    /// Robot description: builtin:km20, builtin:lab17, or a URDF/MJCF file whose ankle and hip roll
    /// joints are named like l_ank_pitch / r_ank_roll / l_hip_roll and whose feet have
    /// collision boxes. Sideways, the hip rolls turn with the ankle rolls (the legs lean
    /// as a parallelogram, feet flat, pelvis level).
    #[arg(long, value_name = "ROBOT")]
    pub robot: String,
    /// Add a point mass before the experiment (seed 000's batteries), repeatable:
    /// KG@LINK:X,Y,Z with X,Y,Z in metres in the link frame, e.g. 0.2@torso:0.05,0,0.
    #[arg(long = "add-mass", value_name = "KG@LINK:X,Y,Z")]
    pub add_mass: Vec<String>,
    #[arg(long, value_name = "FILE", help = JSON_HELP)]
    pub json: Option<PathBuf>,
    /// Ankle ramp speed, deg/s.
    #[arg(long, default_value_t = 0.5)]
    pub ramp: f64,
    /// Servo compliance slope during the experiment, Dynamixel RX units (2 = stiffest,
    /// the default). The CoM methods assume a rigid robot; stiffer servos bend less.
    #[arg(long, default_value_t = 2.0)]
    pub compliance_slope: f64,
    /// Ramp speed of the second run's slow final approach, deg/s: each direction is run
    /// twice, the second time up to half a degree before the first tip and then at this
    /// speed, so the tip is seen with less lag.
    #[arg(long, default_value_t = 0.05)]
    pub slow_ramp: f64,
    /// Quantise the ankle readings like Dynamixel RX encoders (1024 counts over 300 deg).
    #[arg(long)]
    pub encoders: bool,
}

/// Parse `KG@LINK:X,Y,Z`.
fn parse_mass(s: &str) -> Result<(f64, String, [f64; 3]), String> {
    let bad = |why: &str| format!("--add-mass \"{s}\": {why} (expected KG@LINK:X,Y,Z)");
    let (kg, rest) = s.split_once('@').ok_or_else(|| bad("no '@'"))?;
    let (link, xyz) = rest
        .rsplit_once(':')
        .ok_or_else(|| bad("no ':' before the position"))?;
    let kg: f64 = kg
        .trim()
        .parse()
        .map_err(|_| bad("the mass is not a number"))?;
    let v: Vec<f64> = xyz
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| bad("the position is not three numbers"))?;
    if v.len() != 3 {
        return Err(bad("the position needs three numbers"));
    }
    Ok((kg, link.to_string(), [v[0], v[1], v[2]]))
}

pub fn run(a: &TipoverArgs) -> CliResult {
    let (mut robot, _) = load_description(&a.robot)?;
    for m in &a.add_mass {
        let (kg, link, xyz) = parse_mass(m)?;
        twinloop_description::builtin::add_point_mass(&mut robot, &link, kg, xyz)
            .map_err(|e| CliError::from(e).context(format!("--add-mass \"{m}\"")))?;
    }
    let opts = StudyOptions {
        ramp_deg_per_s: a.ramp,
        dynamixel_encoders: a.encoders,
        slow_ramp_deg_per_s: a.slow_ramp,
        compliance_units: Some((a.compliance_slope, 0.0)),
        ..Default::default()
    };
    eprintln!("running the four tip-overs in the simulator ...");
    let r = run_study(&robot, &opts)?;
    emit(&summary(&r), a.json.as_ref(), &r)?;
    Ok(Outcome::Ok)
}

/// The table of tip angles and the CoM by each method.
fn summary(r: &StudyReport) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{}: tip-over (ankle angles from the standing pose, deg)",
        r.robot
    );
    let _ = writeln!(
        s,
        "  direction  commanded  measured  static(model)  feet-roll  time(s)"
    );
    for (name, d) in [
        ("forward", &r.forward),
        ("backward", &r.backward),
        ("left", &r.left),
        ("right", &r.right),
    ] {
        let _ = writeln!(
            s,
            "  {name:<9}  {:>9.3}  {:>8.3}  {:>13.3}  {:>9.3}  {:>7.2}",
            d.commanded_deg, d.measured_deg, d.static_deg, d.excess_deg, d.time_s
        );
    }
    let f = |c: [f64; 3]| format!("[{:+.4}, {:+.4}, {:+.4}]", c[0], c[1], c[2]);
    let _ = writeln!(
        s,
        "CoM relative to the ankle midpoint (m; x forward, y left, z up):"
    );
    let _ = writeln!(s, "  true          {}", f(r.com.truth));
    let _ = writeln!(
        s,
        "  exact method  {}  (off by {:.1} mm)",
        f(r.com.exact_method),
        r.com.exact_error * 1e3
    );
    let _ = writeln!(
        s,
        "  seed method   {}  (off by {:.1} mm; constants: {})",
        f(r.com.seed_method),
        r.com.seed_error * 1e3,
        r.seed_constants
    );
    let _ = writeln!(
        s,
        "  sideways lever  {:.4} m (model {:.4} m)",
        r.com.frontal_lever_exact, r.com.frontal_lever_true
    );
    s
}
