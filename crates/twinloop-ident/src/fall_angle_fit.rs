//! Placing an added mass of known size on a known link by the fall angles themselves
//! (seed 000 section V.B's adaptation, refined): the position in the link's frame
//! whose model, at the postures the robot had at its four onsets, has static tipping
//! angles equal to the measured ones, in the least-squares sense.
//!
//! Why beside the CoM inversion of [`crate::adapt`]: that inversion treats the robot
//! as one body turning about its ankles, with the feet (everything below the ankle
//! pitch joints) apart. A part on a link between the ankle pitch and roll joints turns
//! with the sideways lean but not with the fore-aft one, and one on a foot turns with
//! neither; the CoM inversion places such parts centimetres off (a 0.36 kg part on
//! km20's ankle cross 25 mm, with the CoM 2.5 mm off). The static tipping analysis of
//! the whole model (`twinloop_sim::statics`) knows which link turns with which joint,
//! so fitting the position to the angles it predicts places every link's part alike,
//! and makes the adapted model's fall angles the measured ones as nearly as the
//! measurement allows: the check the adaptation is judged by.
//!
//! Method: Levenberg-Marquardt on the four residuals `static_d(p) - measured_d - o_d`
//! (deg) over the three coordinates of `p` and one offset `o` common to the left and
//! right angles (`o_d = o` sideways, 0 fore and aft), with forward-difference
//! derivatives (each residual is a smooth function of `p`: a static analysis of a
//! model whose one inertial changes smoothly), each step projected onto the box the
//! part may be in. Why the offset: the CoM's height is weakly seen (moving a 0.2 kg
//! part 1 cm up moves km20's CoM 0.6 mm and its fall angles 0.03-0.05 deg), and over
//! a bus the sideways pair is measured less sharply than the fore-aft one (its onset
//! is read from a lean of a few degrees through a 0.45 deg accelerometer): a common
//! error of both sideways angles would otherwise be fitted by moving the part
//! decimetres up or down against the fore-aft angles. The offset is itself a
//! residual, weighted by [`OFFSET_WEIGHT`]: a sideways pair that agrees with the
//! fore-aft one still informs the height (a part on a link that turns only with the
//! sideways lean is seen mostly there), one that does not is set aside as in the
//! exact method (whose frontal lever is free). The offset found is reported.

use crate::error::IdentError;
use crate::tipover_study::{StudyReport, static_angles_at_onsets};
use nalgebra::{Matrix4, SMatrix, SVector, Vector3, Vector4};
use twinloop_description::Description;

/// Forward-difference step of the position, m: well above the static analysis's
/// own resolution (its bisection ends at 1e-10 rad, 0.03 um of lever at km20's height)
/// and small against any outline.
const STEP: f64 = 5e-4;
/// Stop when a step moves the part by less than this, m.
const TOLERANCE: f64 = 1e-5;
const MAX_ITERATIONS: usize = 12;
/// Weight of the sideways offset against the angles' residuals: the ratio of how
/// sharply a fore-aft angle is measured (about 0.1 deg over a bus) to how far the
/// sideways pair's common error goes (about 0.3 deg), so the offset takes what the
/// sideways pair cannot share with the fore-aft one and no more.
pub const OFFSET_WEIGHT: f64 = 1.0 / 3.0;
/// The same once the measuring protocol's bias is taken off the angles (simulated on
/// the adapted model, `AdaptOptions::protocol_bias_deg`): the sideways pair's common
/// error over a bus is then what the protocol reads past the statics, which the bias
/// accounts for, so an offset costs as much as an angle's residual. Measured on six
/// kept bus tip-overs (docs/adaptation.md): at 1/3 the sideways pair stayed 0.4-0.7
/// deg off the robot on two of them; at 1 every direction came within a count.
pub const PROTOCOL_OFFSET_WEIGHT: f64 = 1.0;

/// The fitted position and how well the four angles agree.
#[derive(Debug, Clone)]
pub struct FallAngleFit {
    /// The part's position in the host link's frame, m.
    pub position_host: [f64; 3],
    /// Static minus measured angle per direction (forward, backward, left, right) at
    /// the start and at the end, deg (the offset not taken off).
    pub start_residual_deg: [f64; 4],
    pub residual_deg: [f64; 4],
    /// The common part of the sideways pair's residuals the fit set aside, deg.
    pub sideways_offset_deg: f64,
    pub iterations: usize,
}

/// The model with the part at a position (host frame): the caller's (the prior with
/// the part merged into its host).
pub type ModelWithPart<'a> = &'a dyn Fn(Vector3<f64>) -> Result<Description, IdentError>;

/// Static minus measured angles of the model with the part at `p`.
fn residuals(
    model_with_part: ModelWithPart<'_>,
    report: &StudyReport,
    p: &Vector3<f64>,
    measured: &Vector4<f64>,
) -> Result<Vector4<f64>, IdentError> {
    let robot = model_with_part(*p)?;
    let s = static_angles_at_onsets(&robot, report)?;
    Ok(Vector4::from(s) - measured)
}

/// Fit the position (host frame) of the part `model_with_part` places, starting
/// from `start`, kept within `bounds` (lowest and highest corner, host frame), to
/// the measured angles less `bias` (deg per direction: how far the measuring
/// protocol reads past a model's static angles; zeros for none), the sideways offset
/// weighted by `offset_weight` ([`OFFSET_WEIGHT`], or [`PROTOCOL_OFFSET_WEIGHT`] once
/// the protocol's bias is taken off).
pub fn fit_position(
    model_with_part: ModelWithPart<'_>,
    report: &StudyReport,
    start: Vector3<f64>,
    bounds: (Vector3<f64>, Vector3<f64>),
    bias: [f64; 4],
    offset_weight: f64,
) -> Result<FallAngleFit, IdentError> {
    let clamp = |p: Vector3<f64>| p.sup(&bounds.0).inf(&bounds.1);
    let measured = Vector4::new(
        report.forward.measured_deg - bias[0],
        report.backward.measured_deg - bias[1],
        report.left.measured_deg - bias[2],
        report.right.measured_deg - bias[3],
    );
    let sideways = Vector4::new(0.0, 0.0, 1.0, 1.0);
    let w = offset_weight;
    // The four angles less the sideways offset, and the offset itself, weighted.
    let stacked =
        |s: &Vector4<f64>, o: f64| SVector::<f64, 5>::new(s[0], s[1], s[2] - o, s[3] - o, w * o);
    let mut p = clamp(start);
    let mut s = residuals(model_with_part, report, &p, &measured)?;
    if s.iter().any(|v| !v.is_finite()) {
        return Err(IdentError::new(
            "the static tipping analysis found no tip for the part where the CoM puts it",
        ));
    }
    let start_residual = s;
    let mut o = 0.0;
    let mut lambda = 1e-3;
    let mut iterations = 0;
    while iterations < MAX_ITERATIONS {
        iterations += 1;
        let r = stacked(&s, o);
        // Jacobian of r over (p, o): deg per m, and -1 sideways for o.
        let mut jac = SMatrix::<f64, 5, 4>::zeros();
        for i in 0..3 {
            let mut q = p;
            q[i] += STEP;
            let sq = residuals(model_with_part, report, &q, &measured)?;
            jac.fixed_view_mut::<4, 1>(0, i)
                .copy_from(&((sq - s) / STEP));
        }
        jac.fixed_view_mut::<4, 1>(0, 3).copy_from(&(-sideways));
        jac[(4, 3)] = w;
        let jtj = jac.transpose() * jac;
        let jtr = jac.transpose() * r;
        // Damped Gauss-Newton; a step that does not lower the cost raises the damping.
        let mut accepted = false;
        for _ in 0..8 {
            let a = jtj + Matrix4::from_diagonal(&jtj.diagonal()) * lambda;
            let Some(step) = a.lu().solve(&(-jtr)) else {
                lambda *= 10.0;
                continue;
            };
            let next = clamp(p + step.fixed_rows::<3>(0));
            let on = o + step[3];
            let sn = residuals(model_with_part, report, &next, &measured)?;
            let rn = stacked(&sn, on);
            if rn.iter().all(|v| v.is_finite()) && rn.norm_squared() < r.norm_squared() {
                let moved = (next - p).norm();
                p = next;
                o = on;
                s = sn;
                lambda = (lambda * 0.3).max(1e-7);
                accepted = true;
                if moved < TOLERANCE {
                    return Ok(done(p, start_residual, s, o, iterations));
                }
                break;
            }
            lambda *= 10.0;
        }
        if !accepted {
            break;
        }
    }
    Ok(done(p, start_residual, s, o, iterations))
}

fn done(
    p: Vector3<f64>,
    start: Vector4<f64>,
    s: Vector4<f64>,
    o: f64,
    iterations: usize,
) -> FallAngleFit {
    FallAngleFit {
        position_host: [p.x, p.y, p.z],
        start_residual_deg: start.into(),
        residual_deg: s.into(),
        sideways_offset_deg: o,
        iterations,
    }
}
