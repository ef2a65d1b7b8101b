//! `twinloop adapt`: the model adapted to a hardware change from the tip-over angles
//! (seed 000 sections III and V.B); the algorithm is `twinloop_ident::adapt`.

use crate::common::{JSON_HELP, ROBOT_HELP, emit, load_description};
use crate::error::{CliError, CliResult, Outcome};
use clap::Args;
use std::path::PathBuf;
use twinloop_ident::adapt::{AdaptOptions, adapt, check, html_report};
use twinloop_ident::tipover_study::{StudyOptions, StudyReport};

#[derive(Args, Debug)]
pub struct AdaptArgs {
    #[arg(long, value_name = "ROBOT", help = ROBOT_HELP)]
    pub robot: String,
    /// The tip-over experiment's JSON (`twinloop experiment tipover --json`).
    #[arg(long, value_name = "TIP.json")]
    pub tipover: PathBuf,
    /// The changed robot's total mass, kg: the added mass is this minus the prior's.
    #[arg(long, value_name = "KG")]
    pub total_mass: Option<f64>,
    /// The link the mass was added to (with --total-mass it only names the host).
    #[arg(long = "where", value_name = "LINK")]
    pub host: Option<String>,
    /// Merge the mass into the host link's inertial instead of a fixed `added_mass` link.
    #[arg(long)]
    pub merge: bool,
    /// Resolution of the measured angles, deg.
    #[arg(long, default_value_t = 0.05, value_name = "DEG")]
    pub resolution: f64,
    /// The adapted URDF to write.
    #[arg(long, value_name = "ADAPTED.urdf")]
    pub out: Option<PathBuf>,
    #[arg(long, value_name = "FILE", help = JSON_HELP)]
    pub json: Option<PathBuf>,
    /// HTML report to write.
    #[arg(long, value_name = "FILE.html")]
    pub report: Option<PathBuf>,
    /// Run the simulated tip-over study on the adapted model and compare its angles.
    #[arg(long)]
    pub check: bool,
}

pub fn run(a: AdaptArgs) -> CliResult {
    let (prior, _) = load_description(&a.robot)?;
    let text = std::fs::read_to_string(&a.tipover)
        .map_err(|e| CliError::io(&a.tipover, e).context("--tipover"))?;
    let tip: StudyReport = serde_json::from_str(&text)
        .map_err(|e| CliError::new(format!("{}: {e}", a.tipover.display())).context("--tipover"))?;
    if a.total_mass.is_none() && a.host.is_none() && (a.out.is_some() || a.check) {
        return Err(CliError::new(
            "the tip-over angles fix only m_a (p - c_meas) = M0 (c_meas - c0): give --total-mass KG or --where LINK to place the mass",
        ));
    }
    let opts = AdaptOptions {
        total_mass: a.total_mass,
        host: a.host.clone(),
        merge: a.merge,
        angle_resolution_deg: Some(a.resolution),
    };
    let mut adapted = adapt(&prior, &tip, &opts).map_err(where_flag)?;
    if a.check {
        check(&mut adapted, &StudyOptions::default()).map_err(where_flag)?;
    }
    if let (Some(out), Some(robot)) = (&a.out, &adapted.robot) {
        twinloop_description::urdf::write_file(robot, out)
            .map_err(|e| CliError::new(format!("{}: {e}", out.display())).context("--out"))?;
        adapted.report.files.push(out.display().to_string());
    }
    if let Some(p) = &a.report {
        adapted.report.files.push(p.display().to_string());
        html_report(&adapted.report)
            .write(p)
            .map_err(|e| CliError::new(e).context("--report"))?;
    }
    let r = &adapted.report;
    let mm = |v: [f64; 3]| {
        format!(
            "[{:.1}, {:.1}, {:.1}] mm",
            v[0] * 1e3,
            v[1] * 1e3,
            v[2] * 1e3
        )
    };
    let mut t = format!(
        "measured fall angles {} deg (forward, backward, left, right)\n\
         prior CoM {}, measured CoM {} (sigma {})\n",
        r.measured_deg
            .iter()
            .map(|a| format!("{a:.2}"))
            .collect::<Vec<_>>()
            .join(" / "),
        mm(r.prior_com),
        mm(r.measured_com),
        mm(r.measured_com_sigma)
    );
    match &r.added {
        Some(m) => {
            t += &format!(
                "added {:.3} kg on {} at {} in its frame ({} standing; sigma {}); {} iterations\n",
                m.mass,
                m.host,
                mm(m.position_host),
                mm(m.position),
                mm(m.position_sigma),
                r.iterations
            );
        }
        None => {
            t += &format!(
                "m_a (p - c_meas) = {} kg mm: give --total-mass or --where to place it\n",
                mm(r.family_moment)
            );
        }
    }
    if let Some(c) = r.check_deg {
        t += &format!("adapted model's fall angles {c:?} deg\n");
    }
    for f in &r.files {
        t += &format!("wrote {f}\n");
    }
    emit(&t, a.json.as_ref(), r)?;
    Ok(Outcome::Ok)
}

/// The library's `host` option is the `--where` flag (the seed's word for the general
/// location of the change; `where` cannot name a field).
fn where_flag(mut e: twinloop_ident::IdentError) -> CliError {
    if e.option.as_deref() == Some("host") {
        e.option = Some("where".into());
    }
    CliError::from(e)
}
