//! The lean experiment (seed 001, section F) on the simulated km20, checked against the
//! static analysis: an added point mass m on the torso changes the ankle torque by
//! m g times its horizontal lever about the ankle axis, which the lean turns by the
//! measured ankle angle: `m g (r_x cos(theta) + r_z sin(theta))`, (r_x, r_z) the mass's
//! offset from the ankle axis standing. And the validation: a run against itself
//! differs by nothing, the changed model against the unchanged one by that torque.

use twinloop_description::Description;
use twinloop_description::builtin::{add_point_mass, resolve};
use twinloop_dynamics::{Data, Model, forward_kinematics};
use twinloop_experiments::lean::{
    LeanConfig, LeanJointNames, LeanRecord, lean_config, lean_simulator, run_lean,
    sagittal_tip_angles,
};
use twinloop_experiments::lean_validation::{
    LeanSimOptions, align_and_compare, compare_leans, estimate_shift, lean_comparison,
    read_lean_record,
};

const ADDED_KG: f64 = 0.3;
const ADDED_AT: [f64; 3] = [0.06, 0.0, 0.05];

/// The lean of `robot` in the simulator on stiff servos (compliance slope 2),
/// amplitude half the model's smaller static tipping angle unless given, 2 deg/s
/// ramps, 1.5 s holds.
fn lean(robot: &Description, amplitude_deg: Option<f64>) -> (LeanRecord, LeanConfig, f64) {
    let (mut sim, standing) = lean_simulator(robot, Some(2.0)).unwrap();
    let names = LeanJointNames::default();
    let (f, b) = sagittal_tip_angles(&mut sim, &standing, &names).unwrap();
    let amplitude = amplitude_deg.unwrap_or(0.5 * f.min(b).to_degrees());
    let order = sim.model.joint_names.clone();
    let mut cfg = lean_config(&sim.model, &order, &names, amplitude).unwrap();
    cfg.ramp_deg_per_s = 2.0;
    cfg.hold_s = 1.5;
    cfg.settle_s = 1.0;
    let rec = run_lean(&mut sim, &standing, &cfg, &mut |_| Ok(())).unwrap();
    (rec, cfg, f.to_degrees())
}

fn km20() -> Description {
    resolve("builtin:km20").unwrap()
}

fn km20_with_mass() -> Description {
    let mut r = km20();
    add_point_mass(&mut r, "torso", ADDED_KG, ADDED_AT).unwrap();
    r
}

/// World direction of each ankle pitch axis along +y (its sign), and the added mass's
/// offset from the ankle axis midpoint (x forward, z up), standing at the zero pose.
fn ankle_geometry(model: &Model) -> ([f64; 2], [f64; 2]) {
    let mut data = Data::new(model);
    let q = model.neutral_configuration();
    forward_kinematics(model, &mut data, &q);
    let j = |n: &str| model.joint_index(n).unwrap();
    let ankles = [j("l_ank_pitch"), j("r_ank_pitch")];
    let axis_y = ankles.map(|a| (data.o_m_i[a].rotation * model.axes[a]).y);
    let mid = (data.o_m_i[ankles[0]].translation + data.o_m_i[ankles[1]].translation) * 0.5;
    let torso = model.links.iter().find(|l| l.name == "torso").unwrap();
    let at = nalgebra::Vector3::new(ADDED_AT[0], ADDED_AT[1], ADDED_AT[2]);
    let p = if torso.body == twinloop_dynamics::BASE {
        data.base_placement * torso.placement
    } else {
        data.o_m_i[torso.body] * torso.placement
    }
    .act_point(&at);
    (axis_y, [p.x - mid.x, p.z - mid.z])
}

#[test]
fn the_lean_goes_centre_forward_backward_centre_within_a_safe_fraction_of_the_tip() {
    let (rec, cfg, forward_tip) = lean(&km20(), None);
    let lean_of = |i: usize| {
        0.5 * (cfg.forward_sign[0] * rec.goal[0][i] + cfg.forward_sign[1] * rec.goal[1][i])
    };
    let cmd: Vec<f64> = (0..rec.t.len()).map(lean_of).collect();
    let max = cmd.iter().cloned().fold(f64::MIN, f64::max).to_degrees();
    let min = cmd.iter().cloned().fold(f64::MAX, f64::min).to_degrees();
    eprintln!(
        "km20 lean: {} rows over {:.2} s, commanded {min:.3} .. {max:.3} deg, forward tip {forward_tip:.2} deg",
        rec.t.len(),
        rec.t[rec.t.len() - 1]
    );
    assert!((max - cfg.amplitude_deg).abs() < 1e-9 && (min + cfg.amplitude_deg).abs() < 1e-9);
    assert!(cfg.amplitude_deg < 0.6 * forward_tip);
    // Forward first, then backward, and back to the centre.
    let first_fwd = cmd
        .iter()
        .position(|&c| c.to_degrees() > max - 1e-6)
        .unwrap();
    let first_bwd = cmd
        .iter()
        .position(|&c| c.to_degrees() < min + 1e-6)
        .unwrap();
    assert!(first_fwd < first_bwd);
    assert!(cmd[cmd.len() - 1].abs() < 1e-12);
    // The measured ankles follow within the servos' give; the knees are held.
    for k in 0..2 {
        let err = rec.q[k]
            .iter()
            .zip(&rec.goal[k])
            .map(|(q, g)| (q - g).abs())
            .fold(0.0, f64::max);
        assert!(
            err.to_degrees() < 1.5,
            "ankle {k}: {} deg",
            err.to_degrees()
        );
    }
    // Leaning forward loads the ankles one way, backward the other.
    let (axis_y, _) = ankle_geometry(&twinloop_dynamics::Model::from_description(&km20()).unwrap());
    let s = |i: usize| rec.tau[0][i] * axis_y[0].signum() + rec.tau[1][i] * axis_y[1].signum();
    assert!(
        s(first_fwd + 10) > s(first_bwd + 10) + 0.5,
        "{} {}",
        s(first_fwd + 10),
        s(first_bwd + 10)
    );
}

/// The body above the ankle pitch axes (everything but the feet) of `model` standing
/// at the zero pose: its mass and first moment about the ankle axis midpoint (x, z).
fn above_ankles(model: &Model) -> (f64, [f64; 2]) {
    let mut data = Data::new(model);
    let q = model.neutral_configuration();
    forward_kinematics(model, &mut data, &q);
    let j = |n: &str| model.joint_index(n).unwrap();
    let ankles = [j("l_ank_pitch"), j("r_ank_pitch")];
    let mid = (data.o_m_i[ankles[0]].translation + data.o_m_i[ankles[1]].translation) * 0.5;
    let (mut mass, mut first) = (0.0, [0.0; 2]);
    for link in &model.links {
        let base = link.body == twinloop_dynamics::BASE;
        if !base && model.ancestors(link.body).any(|a| ankles.contains(&a)) {
            continue;
        }
        let at = if base {
            data.base_placement
        } else {
            data.o_m_i[link.body]
        };
        let p = (at * link.placement).act_point(&link.inertia.com) - mid;
        mass += link.inertia.mass;
        first[0] += link.inertia.mass * p.x;
        first[1] += link.inertia.mass * p.z;
    }
    (mass, first)
}

/// Static analysis: the sum of the ankle pitch torques about +y that holds the body
/// above the ankles (mass first moment `first` about the ankle axis standing) turned
/// forward by `phi` (its measured pitch): `g (X cos(phi) + Z sin(phi))`.
fn static_ankle_torque(first: [f64; 2], phi: f64) -> f64 {
    twinloop_description::GRAVITY * (first[0] * phi.cos() + first[1] * phi.sin())
}

/// The rows of each hold (forward, backward, centre) of a lean, past the first 0.3 s
/// in which the servos settle.
fn holds(rec: &LeanRecord, cfg: &LeanConfig) -> [Vec<usize>; 3] {
    let r = cfg.amplitude_deg / cfg.ramp_deg_per_s;
    let starts = [r, 3.0 * r + cfg.hold_s, 4.0 * r + 2.0 * cfg.hold_s];
    starts.map(|s| {
        (0..rec.t.len())
            .filter(|&i| rec.t[i] > s + 0.3 && rec.t[i] < s + cfg.hold_s)
            .collect()
    })
}

/// The static analysis checked on the lean: km20 with 0.3 kg added on its torso, 6 cm
/// ahead of the ankle axis, against km20 unchanged. The sum of the two ankle pitch
/// torques (about +y) holds the body above the ankles, so in each hold it must change
/// by what the added mass weighs times its lever, `m g (r_x cos(phi) + r_z sin(phi))`,
/// plus what the heavier robot's slightly larger lean `phi` (the trunk's measured
/// pitch; the servos and the soles give a little more) adds to the rest of the body's
/// lever: `g (X cos(phi) + Z sin(phi))` at each run's pitch, X, Z the first moment of
/// the body above the ankles from the description. In the holds the servos chatter
/// (the dead band of a Dynamixel position loop closed through both feet, the seed's
/// "higher frequency component"): a hold's mean is compared.
#[test]
fn an_added_mass_changes_the_ankle_torque_by_m_g_times_its_lever_about_the_ankle_axis() {
    let (base, cfg, _) = lean(&km20(), Some(4.0));
    let (changed, _, _) = lean(&km20_with_mass(), Some(4.0));
    assert_eq!(base.t, changed.t);
    let model = Model::from_description(&km20()).unwrap();
    let (axis_y, [rx, rz]) = ankle_geometry(&model);
    let (_, first) = above_ankles(&model);
    let g = twinloop_description::GRAVITY;
    let about_y = |r: &LeanRecord, i: usize| r.tau[0][i] * axis_y[0] + r.tau[1][i] * axis_y[1];
    let lever0 = ADDED_KG * g * rx;
    for (name, rows) in ["forward", "backward", "centre"]
        .iter()
        .zip(holds(&base, &cfg))
    {
        assert!(rows.len() > 100, "{name}: {} rows", rows.len());
        let mean =
            |f: &dyn Fn(usize) -> f64| rows.iter().map(|&i| f(i)).sum::<f64>() / rows.len() as f64;
        let added = mean(&|i| {
            let p = changed.tilt[i];
            ADDED_KG * g * (rx * p.cos() + rz * p.sin())
        });
        let predicted = added
            + mean(&|i| {
                static_ankle_torque(first, changed.tilt[i])
                    - static_ankle_torque(first, base.tilt[i])
            });
        let measured = mean(&|i| about_y(&changed, i) - about_y(&base, i));
        eprintln!(
            "{name} hold: ankle torque change {measured:.4} N m, static analysis {predicted:.4} \
             (the added mass's m g lever alone {added:.4}; m g r_x standing {lever0:.4})"
        );
        assert!(
            (measured - predicted).abs() < 0.04 * lever0,
            "{name}: {measured} vs {predicted}"
        );
    }
}

#[test]
fn validating_a_run_against_itself_gives_zero_and_the_changed_model_gives_the_added_torque() {
    let (base, _, _) = lean(&km20(), Some(4.0));
    let zero = compare_leans(&base, &base, "a", "a").unwrap();
    for j in &zero.joints {
        assert_eq!(j.torque_rms, 0.0);
        assert_eq!(j.angle_rms, Some(0.0));
    }
    let (changed, _, _) = lean(&km20_with_mass(), Some(4.0));
    let c = compare_leans(&changed, &base, "changed", "base").unwrap();
    let model = Model::from_description(&km20()).unwrap();
    let (_, [rx, rz]) = ankle_geometry(&model);
    let (_, first) = above_ankles(&model);
    let g = twinloop_description::GRAVITY;
    // Per ankle half of the static analysis's change (km20 is symmetric, the mass on
    // its mid-plane), sample by sample.
    let predicted: Vec<f64> = (0..base.t.len())
        .map(|i| {
            let (p0, p1) = (base.tilt[i], changed.tilt[i]);
            0.5 * (ADDED_KG * g * (rx * p1.cos() + rz * p1.sin()) + static_ankle_torque(first, p1)
                - static_ankle_torque(first, p0))
        })
        .collect();
    let rms = (predicted.iter().map(|x| x * x).sum::<f64>() / predicted.len() as f64).sqrt();
    for j in &c.joints[..2] {
        eprintln!(
            "{}: torque rms {:.4} N m (mean {:+.4}), predicted rms {rms:.4}",
            j.joint, j.torque_rms, j.torque_mean
        );
        assert!((j.torque_rms - rms).abs() < 0.05 * rms, "{j:?} vs {rms}");
    }
    // The adaptation's check: the changed robot's lean replayed on the unchanged model
    // (before) and on the changed one (after): after, only the replay's own error is left.
    let table = changed.to_table();
    let check = lean_comparison(
        &table,
        &km20(),
        &km20_with_mass(),
        &LeanSimOptions {
            settle_s: 0.5,
            period_s: 0.005,
            compliance_slope: Some(2.0),
        },
    )
    .unwrap();
    for k in 0..2 {
        let (b, a) = (&check.before.joints[k], &check.after.joints[k]);
        eprintln!(
            "{}: before adaptation {:.4} N m rms, after {:.4}",
            b.joint, b.torque_rms, a.torque_rms
        );
        assert!(a.torque_rms < 0.25 * b.torque_rms, "{b:?} {a:?}");
    }
    // Read back from CSV text: the same record, its times as written (to the
    // nanosecond, `twinloop_io::clean_time`).
    let text = {
        let p = std::env::temp_dir().join(format!("lean-{}.csv", std::process::id()));
        table.write(&p).unwrap();
        let t = twinloop_io::Table::read(&p).unwrap();
        let _ = std::fs::remove_file(&p);
        t
    };
    let mut expected = changed.clone();
    expected
        .t
        .iter_mut()
        .for_each(|t| *t = twinloop_io::clean_time(*t));
    assert_eq!(read_lean_record(&text).unwrap(), expected);
}

#[test]
fn bad_tables_are_named_by_file_line_and_column() {
    let t = twinloop_io::Table::parse("t,q:a,tau:a\n0,0,1\n0.1,0,NaN\n").unwrap();
    let e = read_lean_record(&t).unwrap_err().to_string();
    assert!(
        e.contains("line 3") && e.contains("tau:a") && e.contains("finite"),
        "{e}"
    );
    let t = twinloop_io::Table::parse("time,tau:a\n0,1\n1,2\n").unwrap();
    let e = read_lean_record(&t).unwrap_err().to_string();
    assert!(e.contains("\"t\""), "{e}");
    let t = twinloop_io::Table::parse("t,q:a\n0,1\n1,2\n").unwrap();
    let e = read_lean_record(&t).unwrap_err().to_string();
    assert!(e.contains("tau:"), "{e}");
    // Time out of order is refused as the table is read (issue 29, class 3).
    let e = twinloop_io::Table::parse("t,tau:a\n0,1\n0,2\n")
        .unwrap_err()
        .to_string();
    assert!(e.contains("line 3") && e.contains("time order"), "{e}");
    let a = read_lean_record(&twinloop_io::Table::parse("t,tau:a\n0,1\n1,2\n").unwrap()).unwrap();
    let b = read_lean_record(&twinloop_io::Table::parse("t,tau:b\n0,1\n1,2\n").unwrap()).unwrap();
    let e = compare_leans(&a, &b, "a.csv", "b.csv")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("only in a.csv: a") && e.contains("only in b.csv: b"),
        "{e}"
    );
}

#[test]
fn a_run_whose_clock_started_late_is_found_and_aligned() {
    let (base, _, _) = lean(&km20(), Some(3.0));
    let mut late = base.clone();
    late.t.iter_mut().for_each(|t| *t += 0.2);
    let shift = estimate_shift(&base, &late, 0.5).unwrap();
    assert!((shift + 0.2).abs() < 1e-6, "{shift}");
    // From the commanded angles alone, too.
    let mut no_q = late.clone();
    no_q.q.iter_mut().for_each(Vec::clear);
    let shift = estimate_shift(&base, &no_q, 0.5).unwrap();
    assert!((shift + 0.2).abs() < 1e-6, "{shift}");
    let c = align_and_compare(&base, &late, "a", "late", 0.5).unwrap();
    assert!((c.shift_s + 0.2).abs() < 1e-6);
    for j in &c.joints {
        assert!(j.torque_rms < 1e-9, "{j:?}");
    }
    // Unaligned, the 0.2 s shows.
    let c = compare_leans(&base, &late, "a", "late").unwrap();
    assert!(c.joints[0].torque_rms > 0.01, "{:?}", c.joints[0]);
}
