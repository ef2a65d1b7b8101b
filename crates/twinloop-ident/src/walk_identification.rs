//! Seed 003 section 7 on a recorded walk: the initial MIMO ARX model (section 7.1)
//! and the final state-space model by the prediction-error method started from it
//! (section 7.2), with the choices the walking record forces, argued here once.
//!
//! - **Inputs.** The ten offsets carry only seven distinct signals: the seed's code
//!   moves knee and hip pitch together on each side (C: -20/-20, F: +40/+40, J:
//!   +20/+20, K and N: 0/0) and both ankle rolls together (B, D, E, G, H, L, M,
//!   "A=0"). A regressor with two identical input columns is rank-deficient
//!   whatever the orders; MATLAB returns one of its infinitely many solutions with a
//!   rank warning, twinloop-sysid refuses it. Every `u:` column equal to an earlier
//!   one over the whole estimation record is dropped (the same information).
//! - **Operating point.** The seed linearises "in the neighbourhood of the joint
//!   angles equilibrium" (section 7.2): the estimation record's means are removed
//!   from both records (the gyro means are the slow turn of the walk, not dynamics).
//! - **ARX orders.** `na = 24` as the seed. With piecewise-constant, 100-sample
//!   periodic inputs a handful of steps per cycle, 24 input lags are linearly
//!   dependent; `nb = 12` is the largest round order with a full-rank regressor.
//! - **Final model.** ARX realised in state space (6 x 24 = 144 states), reduced by
//!   balanced truncation to `order`, refined by PEM. The order is chosen from the
//!   ARX's Hankel singular values: they decay slowly (the seed's Figure 51: "the
//!   order cannot be reduced considerably"), the only sharp gap is after state 4 (too
//!   few for a walk with two feet and three rates each), so we keep the states that
//!   carry 90 % of their sum: 35 on our record. The PEM focus is the simulation
//!   (output-error structure, K = 0, MATLAB's `ssest` with `Focus = 'simulation'`):
//!   the seed compares its models by simulated-output FIT, and the one-step
//!   (innovations, K free) PEM lowered the one-step error 5-8-fold on our record but
//!   left a model whose simulation FIT fell 2-24 points below the ARX's, or (at 24
//!   states) whose A was unstable (docs/lab17-walking-identification.md).

use crate::error::IdentError;
use twinloop_sysid::pem::{OutputWeight, PemProgress};
use twinloop_sysid::{
    ArxIdentification, ArxOrders, EvaluationOptions, IoData, SsMethod, SsOptions,
    StateSpaceIdentification, identify_arx, identify_state_space,
};

/// How to identify the walk.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WalkIdOptions {
    /// ARX orders of the initial model (seed 003: 24th order).
    pub arx: ArxOrders,
    /// States of the final model; `None`: the smallest order whose Hankel singular
    /// values carry [`WalkIdOptions::hsv_energy`] of their sum.
    pub order: Option<usize>,
    /// Share of the ARX's Hankel-singular-value sum the final model keeps.
    pub hsv_energy: f64,
    /// Simulation focus (output error, K = 0) or one-step prediction (K estimated).
    pub output_error: bool,
    /// How the outputs' errors are weighted. Default: by the inverse of the initial
    /// model's error covariance. MATLAB's multi-output PEM minimises det(E'E), whose
    /// gradient is that weighting at the current model; with the plain sum the large
    /// pitch-rate impacts (~250 deg/s) outweigh the yaw rates (the yaw FITs were 2-4
    /// points lower, docs/lab17-walking-identification.md).
    pub weight: OutputWeight,
    /// Remove the estimation record's means (the operating point).
    pub detrend: bool,
    /// Iteration limit of the prediction-error search.
    pub max_iterations: usize,
    /// Largest pole radius of the final model's `A` (a damping margin, see
    /// [`twinloop_sysid::pem::PemOptions::max_pole_radius`]). 0.999 at a 40 ms sample
    /// is a 40 s time constant, longer than the record, so no tighter damping can be
    /// told from the data; without it the search parks the walk's lightly damped
    /// 4.3 Hz servo-and-body oscillation at radius 1 - 1e-9 (a 200 dB resonance).
    pub max_pole_radius: f64,
}

impl Default for WalkIdOptions {
    fn default() -> Self {
        WalkIdOptions {
            arx: ArxOrders {
                na: 24,
                nb: 12,
                nk: 1,
            },
            order: None,
            hsv_energy: 0.9,
            output_error: true,
            weight: OutputWeight::InverseNoise,
            detrend: true,
            max_iterations: 100,
            max_pole_radius: 0.999,
        }
    }
}

/// The seed's two models of the walk.
pub struct WalkIdentification {
    /// The input columns used and the ones dropped as copies (`dropped`, `copy of`).
    pub inputs: Vec<String>,
    pub dropped: Vec<(String, String)>,
    pub outputs: Vec<String>,
    /// Input and output offsets removed (estimation means), if detrended.
    pub offsets: Option<(Vec<f64>, Vec<f64>)>,
    pub arx: ArxIdentification,
    pub ss: StateSpaceIdentification,
    /// The final model's order and how it was chosen.
    pub order: usize,
    pub order_reason: String,
    /// The records as identified (offsets removed), for reports.
    pub estimation: IoData,
    pub validation: Option<IoData>,
}

/// `u:` columns that repeat an earlier `u:` column over every row: `(column, copy of)`.
pub fn duplicate_inputs(columns: &[String], rows: &[Vec<f64>]) -> Vec<(String, String)> {
    let u: Vec<usize> = (0..columns.len())
        .filter(|&i| columns[i].starts_with("u:"))
        .collect();
    let mut out = Vec::new();
    for (k, &i) in u.iter().enumerate() {
        if let Some(&j) = u[..k]
            .iter()
            .filter(|&&j| !out.iter().any(|(d, _): &(String, String)| *d == columns[j]))
            .find(|&&j| rows.iter().all(|r| r[i] == r[j]))
        {
            out.push((columns[i].clone(), columns[j].clone()));
        }
    }
    out
}

/// The smallest order whose Hankel singular values (largest first) carry `share`
/// of their sum.
pub fn order_for_energy(hsv: &[f64], share: f64) -> usize {
    let total: f64 = hsv.iter().sum();
    let mut acc = 0.0;
    for (k, h) in hsv.iter().enumerate() {
        acc += h;
        if acc >= share * total {
            return k + 1;
        }
    }
    hsv.len()
}

/// Seed 003 section 7 on a walk record (the columns `experiment walk` writes): the ARX
/// initial model and the ARX -> balanced truncation -> PEM final model, evaluated on
/// `val` (or `est`).
pub fn identify_walk(
    columns: &[String],
    est_rows: &[Vec<f64>],
    val_rows: Option<&[Vec<f64>]>,
    o: &WalkIdOptions,
    progress: &mut dyn FnMut(&PemProgress),
) -> Result<WalkIdentification, IdentError> {
    if !(o.hsv_energy > 0.0 && o.hsv_energy <= 1.0) {
        return Err(IdentError::new(format!(
            "hsv_energy must be in (0, 1], got {}",
            o.hsv_energy
        )));
    }
    let dropped = duplicate_inputs(columns, est_rows);
    let inputs: Vec<String> = columns
        .iter()
        .filter(|c| c.starts_with("u:") && !dropped.iter().any(|(d, _)| d == *c))
        .cloned()
        .collect();
    if inputs.is_empty() {
        return Err(IdentError::new(
            "data: no `u:` input columns (the walk experiment records them)",
        ));
    }
    let outputs = vec!["gyro:*".to_string()];
    fn sysid(what: &'static str) -> impl Fn(twinloop_sysid::SysidError) -> IdentError {
        move |e| IdentError::new(format!("{what}: {e}"))
    }
    let mut est =
        IoData::from_table(columns, est_rows, &inputs, &outputs).map_err(sysid("data"))?;
    let mut val = match val_rows {
        Some(v) => Some(IoData::from_table(columns, v, &inputs, &outputs).map_err(sysid("val"))?),
        None => None,
    };
    let offsets = if o.detrend {
        let (u0, y0) = est.means();
        est.remove_offsets(&u0, &y0);
        if let Some(v) = val.as_mut() {
            v.remove_offsets(&u0, &y0);
        }
        Some((u0, y0))
    } else {
        None
    };
    let eopts = EvaluationOptions::default();
    let arx = identify_arx(&est, val.as_ref(), o.arx, &eopts).map_err(sysid("ARX"))?;
    let (order, order_reason) = match o.order {
        Some(n) => (n, format!("order {n} as asked")),
        None => {
            let hsv = arx
                .evaluation
                .hankel_singular_values
                .as_ref()
                .ok_or_else(|| {
                    IdentError::new(
                        "ARX: the model is unstable, so it has no Hankel singular values to choose \
                     the final order from; give the order",
                    )
                })?;
            let n = order_for_energy(hsv, o.hsv_energy);
            (
                n,
                format!(
                    "{n} of the ARX's {} states carry {:.0} % of its Hankel-singular-value sum",
                    hsv.len(),
                    100.0 * o.hsv_energy
                ),
            )
        }
    };
    let mut sopts = SsOptions {
        order,
        method: SsMethod::ArxReducePem,
        arx_orders: o.arx,
        evaluation: eopts,
        ..Default::default()
    };
    sopts.pem.output_error = o.output_error;
    sopts.pem.weight = o.weight;
    sopts.pem.max_iterations = o.max_iterations;
    sopts.pem.max_pole_radius = o.max_pole_radius;
    let ss =
        identify_state_space(&est, val.as_ref(), &sopts, progress).map_err(sysid("state space"))?;
    Ok(WalkIdentification {
        inputs,
        dropped,
        outputs: est.output_names.clone(),
        offsets,
        arx,
        ss,
        order,
        order_reason,
        estimation: est,
        validation: val,
    })
}
