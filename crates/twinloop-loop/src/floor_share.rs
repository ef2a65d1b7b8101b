//! The floor's share of the CoM's resolution. Over a bus the floor the protocol
//! passes replay on is found from readings on the same counts as the tip angles (the
//! left and right angles' mean, or the feet's roll), and the floor and the CoM's
//! height trade against each other: on km20 about 22 mm of CoM per mm of floor (seed 1
//! of the served sweep: one place on floors of 0.965 and 0.875 mm, 2.1 mm apart). So
//! the CoM is known no better than the floor's reading lets the floor move, times how
//! far the CoM moves with the floor: measured here by replaying the kept model on two
//! floors either side of the one found, and added to the angles' share
//! ([`twinloop_ident::adapt::with_floor`]).

use crate::LoopError;
use crate::protocol_bias::{Calibration, Reading, Replay, angles_of, protocol_reading_with_roll};
use rayon::prelude::*;
use twinloop_description::Description;
use twinloop_ident::adapt::{AdaptOptions, Adapted, FloorPath, FloorReading, adapt, with_floor};
use twinloop_ident::tipover_study::{StudyReport, static_angles_at_onsets};
use twinloop_virtual::VirtualRobotOptions;

/// The two replays lie this far either side of the floor found, decades of sink: wide
/// enough that the replays' whole-count readings move by several counts (km20's
/// sideways mean moves about 4 deg per decade near 1 mm), narrow enough to stay
/// near linear (the effect grows faster than the logarithm).
const STEP_DECADES: f64 = 0.1;

/// Add the floor's share to `found`'s `com_resolution` (and a note saying it), when
/// its passes replayed on a floor found from the readings: two replays of the kept
/// model. A floor the user gave (`--ground-sink`), or no passes: nothing to add.
pub(crate) fn add_floor_share(
    prior: &Description,
    study: &StudyReport,
    opts: &AdaptOptions,
    replay: &Replay<'_>,
    found: &mut (Adapted, Option<Calibration>),
    log: &mut dyn FnMut(&str),
) -> Result<(), LoopError> {
    let (adapted, Some(calibration)) = found else {
        return Ok(());
    };
    let (reading, sink) = match (&calibration.floor, calibration.floor_by_roll_m) {
        (Some(f), _) => (FloorReading::Sideways, f.sink_m),
        (None, Some(s)) => (FloorReading::Roll, s),
        (None, None) => return Ok(()),
    };
    let (Some(model), Some(angles)) = (&adapted.robot, &adapted.report.com_resolution) else {
        return Ok(());
    };
    let res = adapted.report.angle_resolution_deg;
    let sinks = [-STEP_DECADES, STEP_DECADES].map(|d| sink * 10f64.powf(d));
    let read = |s: f64| {
        let on = VirtualRobotOptions {
            ground_sink: Some(s),
            ..replay.options.clone()
        };
        protocol_reading_with_roll(study, replay.model_spec, replay.host, model, &on)
            .map_err(|e| e.context("replaying the protocol either side of the floor found"))
    };
    let (firm, soft) = rayon::join(|| read(sinks[0]), || read(sinks[1]));
    let (firm, soft) = (firm?, soft?);
    let robot_roll = angles_of(study, |d| d.excess_deg);
    let slope = slopes(
        &angles.per_angle_m,
        res,
        reading,
        robot_roll,
        [&firm, &soft],
        sinks,
    );
    let reading_per_angle = match reading {
        FloorReading::Sideways => sideways_floor_per_angle(prior, study, opts, &adapted.report)?,
        FloorReading::Roll => [0.0; 4],
    };
    let path = FloorPath {
        reading,
        sink_m: sink,
        sink_per_deg: slope.sink_per_deg,
        reading_per_angle,
        com_per_sink: slope.com_per_sink,
    };
    let bound = with_floor(angles, res, path);
    let line = describe(&bound, res);
    log(&line);
    adapted.report.notes.push(line);
    adapted.report.com_resolution = Some(bound);
    Ok(())
}

/// How far what the sideways floor search matches moves per degree of each tip angle,
/// deg/deg. The search finds the floor on which the replay's sideways mean (about the
/// model's static mean at the robot's onsets, plus the protocol's sideways bias) is
/// the robot's: half of each sideways angle, less how far the fitted model's
/// sideways statics at the robot's onsets (`static_angles_at_onsets` against the
/// tip-over as read: the replay starts from the commanded angles) move per degree of
/// each angle, by central differences of the static fit at the kept bias, each angle
/// moved by the resolution (eight fits, at once). On km20 the fit's place does not
/// move with the angles (its residual, statics at the onsets less the angles, carries
/// them both), so this is 0.5 for left and right, 0 fore and aft.
fn sideways_floor_per_angle(
    prior: &Description,
    study: &StudyReport,
    opts: &AdaptOptions,
    kept: &twinloop_ident::adapt::AdaptReport,
) -> Result<[f64; 4], LoopError> {
    let res = kept.angle_resolution_deg;
    // As the place's own passes ran (a sideways floor is the first place's: the CoM
    // inversion's link unless the user named one, its fit kept near the inversion's
    // point rather than in the link's outline).
    let o = AdaptOptions {
        protocol_bias_deg: kept.protocol_bias_deg,
        ..opts.clone()
    };
    let statics = |k: usize, step: f64| -> Result<f64, LoopError> {
        let mut s = study.clone();
        let d = [&mut s.forward, &mut s.backward, &mut s.left, &mut s.right];
        if let Some(d) = d.into_iter().nth(k) {
            d.measured_deg += step;
        }
        let model = adapt(prior, &s, &o)?
            .robot
            .ok_or_else(|| LoopError::new("the static fit at the kept place placed no part"))?;
        let a = static_angles_at_onsets(&model, study)?;
        Ok(0.5 * (a[2] + a[3]))
    };
    let moved: Vec<Result<f64, LoopError>> = (0..8)
        .into_par_iter()
        .with_max_len(1)
        .map(|i| statics(i / 2, if i % 2 == 0 { res } else { -res }))
        .collect();
    let mut out = [0.0; 4];
    for (k, o) in out.iter_mut().enumerate() {
        let (up, down) = (moved[2 * k].clone()?, moved[2 * k + 1].clone()?);
        let own = if k >= 2 { 0.5 } else { 0.0 };
        *o = own - (up - down) / (2.0 * res);
    }
    Ok(out)
}

/// How the floor and the CoM move, from two replays `read` on `sinks` (m).
struct Slopes {
    /// The floor's move per degree of its reading, m/deg.
    sink_per_deg: f64,
    /// The CoM's move per metre of floor, m/m.
    com_per_sink: [f64; 3],
}

/// The slopes from the two replays: the CoM moves with the protocol's bias, which
/// moves with the floor (`d read / d sink`, the model's statics do not), by minus the
/// exact method's move per angle (`per_angle`, per `res` deg of angle); the floor's
/// reading (the replay's sideways mean, or the median of the robot's roll less the
/// replay's) moves by its own slope. A reading the two replays do not tell apart is
/// a floor the step does not resolve: its move is then taken as the whole step.
fn slopes(
    per_angle: &[[f64; 3]; 4],
    res: f64,
    reading: FloorReading,
    robot_roll: [f64; 4],
    read: [&Reading; 2],
    sinks: [f64; 2],
) -> Slopes {
    let ds = sinks[1] - sinks[0];
    let d_read: [f64; 4] = std::array::from_fn(|k| (read[1].angles[k] - read[0].angles[k]) / ds);
    let com_per_sink: [f64; 3] = std::array::from_fn(|i| {
        -(0..4)
            .map(|k| per_angle[k][i] / res * d_read[k])
            .sum::<f64>()
    });
    let of = |r: &Reading| match reading {
        FloorReading::Sideways => 0.5 * (r.angles[2] + r.angles[3]),
        FloorReading::Roll => median(std::array::from_fn(|k| robot_roll[k] - r.roll[k])),
    };
    let d_reading = of(read[1]) - of(read[0]);
    let sink_per_deg = if d_reading.abs() > 1e-9 {
        ds / d_reading
    } else {
        ds / res
    };
    Slopes {
        sink_per_deg,
        com_per_sink,
    }
}

/// The resolution's line for the log, the report's notes and the terminal.
pub fn describe(bound: &twinloop_ident::adapt::ComResolution, res: f64) -> String {
    let mm = |v: [f64; 3]| {
        format!(
            "x {:.2}, y {:.2}, z {:.2} mm",
            v[0] * 1e3,
            v[1] * 1e3,
            v[2] * 1e3
        )
    };
    let (Some(a), Some(f)) = (&bound.angles, &bound.floor) else {
        return format!(
            "the CoM's resolution: {} ({:.2} mm at worst)",
            mm(bound.axes_m),
            bound.worst_m * 1e3
        );
    };
    let per_mm = f
        .path
        .com_per_sink
        .iter()
        .fold(0.0_f64, |m, v| m.max(v.abs()));
    format!(
        "the CoM's resolution with the floor's share: {} ({:.2} mm at worst); the angles' \
         share (each within {res:.3} deg) {} ({:.2} mm), the floor's {} ({:.2} mm): the floor \
         found from the {} ({:.3} mm) is known to {:.3} mm, and the CoM moves up to {per_mm:.1} \
         mm per mm of floor",
        mm(bound.axes_m),
        bound.worst_m * 1e3,
        mm(a.axes_m),
        a.worst_m * 1e3,
        mm(f.share.axes_m),
        f.share.worst_m * 1e3,
        match f.path.reading {
            FloorReading::Sideways => "left and right angles' mean",
            FloorReading::Roll => "feet's roll",
        },
        f.path.sink_m * 1e3,
        f.resolution_m * 1e3,
    )
}

fn median(v: [f64; 4]) -> f64 {
    let mut a = v;
    a.sort_by(f64::total_cmp);
    0.5 * (a[1] + a[2])
}

#[cfg(test)]
mod tests {
    use super::*;
    use twinloop_description::builtin::{add_point_mass, resolve};
    use twinloop_ident::adapt::AdaptReport;
    use twinloop_ident::tipover_study::{StudyOptions, run_study};

    /// The protocol's bias per metre of floor (forward, backward, left, right), deg/m:
    /// softer tips earlier, the sideways pair most (km20's sideways mean about 4 deg
    /// per decade near 1 mm, 1.7 deg/mm), the fore-aft pair enough that the floor moves
    /// the CoM's height by tens of millimetres per millimetre, as served km20 does.
    const BIAS_PER_M: [f64; 4] = [-1500.0, -1200.0, -1800.0, -1600.0];
    const FLOOR_M: f64 = 1e-3;
    /// The replay's feet roll per metre of floor, deg/m (0.7 deg over OP3's 0.5 to 1
    /// mm).
    const ROLL_PER_M: f64 = 1700.0;
    const RES: f64 = 0.15;

    /// The full fit as the passes run it, on a floor whose bias is `BIAS_PER_M`: the
    /// first (no bias) model's sideways statics and that bias find the floor on which
    /// the replay's sideways mean is the robot's; the kept fit takes that floor's bias.
    fn full_fit(
        prior: &Description,
        robot: &StudyReport,
        study: &StudyReport,
        o: &AdaptOptions,
    ) -> AdaptReport {
        let first = adapt(prior, study, o).unwrap().robot.unwrap();
        // The replay's reading: the model's, from the commanded starts (`robot`'s
        // onsets, not the angles moved within their resolution).
        let statics = static_angles_at_onsets(&first, robot).unwrap();
        let m = angles_of(study, |d| d.measured_deg);
        let gap = 0.5 * (m[2] + m[3]) - 0.5 * (statics[2] + statics[3]);
        let s = FLOOR_M + gap / (0.5 * (BIAS_PER_M[2] + BIAS_PER_M[3]));
        let bias = BIAS_PER_M.map(|g| g * (s - FLOOR_M));
        let o = AdaptOptions {
            protocol_bias_deg: Some(bias),
            ..o.clone()
        };
        adapt(prior, study, &o).unwrap().report
    }

    /// The corners of `sides` readings each moved by +-1 (resolutions), fitted again
    /// by `fit`, against `bound`: the CoM's longest move within 10 % of the bound's
    /// worst corner, none longer per axis than its bound by 10 %.
    fn corners_within(
        sides: usize,
        centre: [f64; 3],
        bound: &twinloop_ident::adapt::ComResolution,
        fit: &(dyn Fn(&[f64]) -> [f64; 3] + Sync),
    ) {
        let moved: Vec<[f64; 3]> = (0..1_u32 << sides)
            .into_par_iter()
            .map(|signs| {
                let u: Vec<f64> = (0..sides)
                    .map(|k| if signs >> k & 1 == 1 { 1.0 } else { -1.0 })
                    .collect();
                let c = fit(&u);
                std::array::from_fn(|k| c[k] - centre[k])
            })
            .collect();
        let mut worst = 0.0_f64;
        for m in &moved {
            for k in 0..3 {
                assert!(
                    m[k].abs() <= 1.1 * bound.axes_m[k],
                    "axis {k}: {m:?} > {bound:?}"
                );
            }
            worst = worst.max(m.iter().map(|v| v * v).sum::<f64>().sqrt());
        }
        assert!(
            (worst - bound.worst_m).abs() <= 0.1 * bound.worst_m,
            "corners {worst} m, linearised {} m ({bound:?})",
            bound.worst_m
        );
    }

    fn moved(study: &StudyReport, u: &[f64]) -> StudyReport {
        let mut s = study.clone();
        let d = [&mut s.forward, &mut s.backward, &mut s.left, &mut s.right];
        for (k, d) in d.into_iter().enumerate() {
            d.measured_deg += u[k] * RES;
        }
        s
    }

    /// The floor's share against the full fit itself, on km20 with 0.3 kg on its
    /// torso (the simulator's study): every corner of the readings' box (each moved
    /// by +-RES) fitted again, floor and all ([`corners_within`]). The floor found
    /// from the sideways mean moves with the sideways angles (0.09 mm per 0.15 deg of
    /// their mean; the bound 4.0 mm against the angles' 2.2); found from the feet's
    /// roll, a fifth reading, as far per 0.15 deg of roll; the CoM 20 mm per mm of
    /// floor. The roll's bound at least 1.5 times the angles' alone, and the corners,
    /// 16 and 32, take both.
    #[test]
    fn the_floors_share_is_the_full_fits_corners() {
        // The CoM inversion's place, as a sideways floor's passes run it (a named torso
        // holds the fit at its outline's corner, where this part sits).
        let prior = resolve("builtin:km20").unwrap();
        let mut robot = prior.clone();
        add_point_mass(&mut robot, "torso", 0.3, [0.04, 0.02, 0.05]).unwrap();
        let study = run_study(&robot, &StudyOptions::default()).unwrap();
        let o = AdaptOptions {
            angle_resolution_deg: Some(RES),
            total_mass: Some(robot.total_mass()),
            ..Default::default()
        };
        let kept = full_fit(&prior, &study, &study, &o);
        let angles = kept.com_resolution.clone().unwrap();
        let sinks = [0.9e-3, 1.1e-3];
        let read = sinks.map(|s| Reading {
            angles: BIAS_PER_M.map(|g| g * s),
            roll: [ROLL_PER_M * s; 4],
        });
        let path = |reading| {
            let slope = slopes(
                &angles.per_angle_m,
                RES,
                reading,
                [0.0; 4],
                [&read[0], &read[1]],
                sinks,
            );
            FloorPath {
                reading,
                sink_m: FLOOR_M,
                sink_per_deg: slope.sink_per_deg,
                reading_per_angle: match reading {
                    FloorReading::Sideways => {
                        sideways_floor_per_angle(&prior, &study, &o, &kept).unwrap()
                    }
                    FloorReading::Roll => [0.0; 4],
                },
                com_per_sink: slope.com_per_sink,
            }
        };
        let sideways = with_floor(&angles, RES, path(FloorReading::Sideways));
        corners_within(4, kept.measured_com, &sideways, &|u| {
            full_fit(&prior, &study, &moved(&study, u), &o).measured_com
        });
        // The roll's floor: the one on which the replay's roll (ROLL_PER_M, more on a
        // softer floor) is the robot's, moved by u[4] resolutions.
        let roll = with_floor(&angles, RES, path(FloorReading::Roll));
        corners_within(5, kept.measured_com, &roll, &|u| {
            let s = FLOOR_M + u[4] * RES / ROLL_PER_M;
            let bias = BIAS_PER_M.map(|g| g * (s - FLOOR_M));
            let o = AdaptOptions {
                protocol_bias_deg: Some(bias),
                ..o.clone()
            };
            adapt(&prior, &moved(&study, u), &o)
                .unwrap()
                .report
                .measured_com
        });
        assert!(sideways.worst_m >= 1.5 * angles.worst_m, "{sideways:?}");
        assert!(roll.worst_m >= 1.5 * angles.worst_m, "{roll:?}");
    }
}
