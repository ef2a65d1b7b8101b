//! COMAN walking in the full simulator (seed 002, section 4): a few seconds of the
//! seed's gait (the 30 s datasets are made by the CLI and committed with the fit that
//! reads them, under twinloop-ident's tests/data).

use nalgebra::{Matrix3, Vector3};
use twinloop_dynamics::{BaseKind, Data, Model, center_of_mass, generalized_gravity};
use twinloop_experiments::compliant_walk::{
    ComanWalker, DatasetRow, WalkingConfig, joint_actuators, write_csv,
};
use twinloop_gait::Phase;
use twinloop_gait::walking_ik::{IkTargets, WholeBodyIk};
use twinloop_reduced::{SupportLeg, coman_crouch};
use twinloop_sim::{Actuator, SimConfig, Simulator};
use twinloop_spatial::Se3;

fn coman() -> twinloop_description::Description {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/coman/coman.urdf");
    twinloop_description::load(std::path::Path::new(path)).unwrap()
}

fn short(duration: f64) -> WalkingConfig {
    WalkingConfig {
        duration,
        ..WalkingConfig::default()
    }
}

/// The seed's gait for 4 s (1 s standing, 3 steps, standing): no fall, no slip, the CoM
/// on its reference, the trunk upright. Bounds: the 30 s run measures x - xr RMS 3.5 mm
/// (max 15 mm), z - zr RMS 1.7 mm, slip 0.5 mm, tilt 0.037 rad (docs/coman-walking-dataset.md).
#[test]
fn coman_walks_the_seed_gait_without_falling_or_slipping() {
    let robot = coman();
    let mut walker = ComanWalker::new(&robot, &short(4.0)).unwrap();
    let data = walker.run(|_, _| {}).unwrap();
    let s = &data.summary;
    assert_eq!(s.samples, 4000);
    assert_eq!(s.steps, 3);
    assert!(s.max_foot_slip < 2e-3, "slip {}", s.max_foot_slip);
    assert!(
        s.max_landing_error < 1e-2,
        "landing {}",
        s.max_landing_error
    );
    assert!(
        s.rms_x < 6e-3 && s.max_abs_x < 2e-2,
        "x {} {}",
        s.rms_x,
        s.max_abs_x
    );
    assert!(
        s.rms_z < 4e-3 && s.max_abs_z < 6e-3,
        "z {} {}",
        s.rms_z,
        s.max_abs_z
    );
    assert!(s.rms_y < 6e-3, "y {}", s.rms_y);
    assert!(s.max_trunk_tilt < 0.08, "tilt {}", s.max_trunk_tilt);
    // The CoM stays over the support polygon of the feet that are down, as closely as
    // the LIPM reference does: at the start of single support the reference CoM is at
    // the stance foot's inner edge (it lags the ZMP), a few millimetres outside.
    let (m, m_ref) = (s.min_com_support_margin, s.min_reference_support_margin);
    assert!(m_ref > -5e-3 && m_ref < 0.0, "reference margin {m_ref}");
    assert!(m > m_ref - 5e-3, "support margin {m}, reference {m_ref}");
    assert!(s.ik_max_error < 1e-9 && s.online_ik_max_error < 1e-6);
    // The springs work: the knees and ankles deflect by centiradians, not micro-radians.
    assert!(
        s.max_deflection > 5e-3 && s.max_deflection < 0.2,
        "{}",
        s.max_deflection
    );
    // Rows: 1 kHz, both phases, reference height constant.
    for (i, r) in data.rows.iter().enumerate() {
        assert_eq!(r.t, i as f64 / 1000.0);
        assert_eq!(r.zr, s.com_height);
    }
    assert!(data.rows.iter().any(|r| r.phase == 0) && data.rows.iter().any(|r| r.phase == 1));
    // The robot got somewhere: after 3 steps the feet are at 2 sl and 3 sl, the CoM
    // reference comes to rest between them, at 2.5 sl = 0.075 m.
    let last = data.rows.last().unwrap();
    assert!((last.xr - 0.075).abs() < 2e-3, "xr {}", last.xr);
    assert!(
        (last.x - last.xr).abs() < 1e-2,
        "x {} xr {}",
        last.x,
        last.xr
    );
}

/// The seed's K_s = 100 N m/rad on the full 32 kg robot: k_j < m g Zc, so one ankle
/// spring cannot hold it on one foot (an inverted pendulum on a torsion spring weaker
/// than its gravitational stiffness). The simulation agrees: it falls in single support.
#[test]
fn seed_spring_on_the_full_robot_is_statically_unstable_and_falls() {
    let robot = coman();
    let config = WalkingConfig {
        k_series: 100.0,
        ..short(4.0)
    };
    let mut walker = ComanWalker::new(&robot, &config).unwrap();
    let m = walker.sim.model.total_mass;
    let zc = walker.reference.zmp.plan().com_height;
    assert!(config.ankle_stability_ratio(m, 9.81, zc) < 1.0);
    let e = walker.run(|_, _| {}).unwrap_err();
    assert!(e.0.contains("fell"), "{e}");
    // The default (K_s = 300) has the margin.
    assert!(WalkingConfig::default().ankle_stability_ratio(m, 9.81, zc) > 1.5);
}

/// Generalisation gaits (other sl and Tss) walk too (5 s here; 30 s in the docs).
#[test]
fn other_gaits_walk() {
    let robot = coman();
    for (sl, tss) in [
        (0.02, 0.4),
        (0.04, 0.6),
        (0.04, 0.5),
        (0.03, 0.4),
        (0.03, 0.6),
    ] {
        let config = WalkingConfig {
            step_length: sl,
            t_single: tss,
            ..short(5.0)
        };
        let mut walker = ComanWalker::new(&robot, &config).unwrap();
        let s = walker.run(|_, _| {}).unwrap().summary;
        // The tracking error grows with the step (30 s runs: RMS 2.6 mm at sl 0.02 up to
        // 6.6 mm at sl 0.04, Tss 0.6).
        assert!(
            s.rms_x < 1e-2 && s.max_abs_x < 3e-2 && s.max_foot_slip < 3e-3,
            "sl {sl} Tss {tss}: {s:?}"
        );
    }
}

/// Analytic check of the series-elastic joints: COMAN hung by its pelvis (fixed base),
/// legs crouched, the actuators of the walker. At rest each compliant joint's spring
/// holds the gravity torque of the links below it: k_j (theta - q) = g_k(q), so the
/// deflection is g_k / k_j with k_j = K_h K_s / (K_h + K_s) (seed 002, section 2.1).
#[test]
fn elastic_joints_deflect_as_k_j_predicts_under_static_load() {
    let robot = coman();
    let config = WalkingConfig::default();
    let model = Model::from_description_with_base(&robot, BaseKind::Fixed).unwrap();
    let sim_config = SimConfig {
        ground: false,
        ..SimConfig::default()
    };
    let mut sim = Simulator::from_model(&robot, model.clone(), sim_config).unwrap();
    let (actuators, compliant) = joint_actuators(&robot, &model, &config).unwrap();
    assert_eq!(compliant.len(), 4, "knee and ankle pitch of both legs");
    sim.actuators = actuators;
    let q0 = coman_crouch(&model, 0.8).unwrap();
    sim.set_joint_positions(&q0).unwrap();
    sim.goals.copy_from_slice(&q0);
    sim.run(4.0).unwrap();
    let k_j = 8000.0 * 300.0 / 8300.0;
    assert!((config.compliant_stiffness() - k_j).abs() < 1e-9);
    let mut data = Data::new(&model);
    let g = generalized_gravity(&model, &mut data, &sim.q).clone();
    let mut largest: f64 = 0.0;
    for &k in &compliant {
        let Actuator::SeriesElastic(a) = &sim.actuators[k] else {
            panic!("joint {k} is not series-elastic");
        };
        let deflection = a.theta - sim.q[k];
        let predicted = g[k] / k_j;
        largest = largest.max(predicted.abs());
        assert!(
            (deflection - predicted).abs() < 1e-4 * predicted.abs().max(1e-3) + 1e-7,
            "{}: deflection {deflection}, g/k_j {predicted}",
            model.joint_names[k]
        );
        // ... and the motor sits at its goal up to the loop's own stiffness.
        assert!((a.theta - q0[k]).abs() < 2.0 * g[k].abs() / config.motor_kp + 1e-6);
    }
    assert!(largest > 1e-3, "a real load: {largest} rad");
}

/// The whole-body IK reaches its targets: checked by forward kinematics alone.
#[test]
fn whole_body_ik_reaches_feet_com_and_pelvis_targets() {
    let robot = coman();
    let model = Model::from_description(&robot).unwrap();
    let legs = [SupportLeg::coman(true), SupportLeg::coman(false)];
    let mut ik = WholeBodyIk::new(
        &model,
        [&legs[0].joints, &legs[1].joints],
        ["l_sole", "r_sole"],
    )
    .unwrap();
    let mut data = Data::new(&model);
    let mut q = coman_crouch(&model, 0.8).unwrap();
    let rot = nalgebra::Rotation3::from_euler_angles(0.0, 0.0, 0.1).into_inner();
    let targets = IkTargets {
        soles: [
            Se3::new(rot, Vector3::new(0.05, 0.08, 0.02)),
            Se3::new(Matrix3::identity(), Vector3::new(-0.03, -0.07, 0.0)),
        ],
        com: Vector3::new(0.02, -0.03, 0.49),
        pelvis: Matrix3::identity(),
    };
    let rep = ik.solve(&model, &mut data, &mut q, &targets).unwrap();
    assert!(rep.error < 1e-10 && rep.iterations < 20, "{rep:?}");
    twinloop_dynamics::frames_forward_kinematics(&model, &mut data, &q);
    for (s, name) in ["l_sole", "r_sole"].iter().enumerate() {
        let f = model.frame_index(name).unwrap();
        let m = WholeBodyIk::frame_placement(&model, &data, f);
        assert!((m.translation - targets.soles[s].translation).norm() < 1e-9);
        assert!((m.rotation - targets.soles[s].rotation).norm() < 1e-9);
    }
    assert!((center_of_mass(&model, &mut data, &q) - targets.com).norm() < 1e-9);
    assert!((data.base_placement.rotation - Matrix3::identity()).norm() < 1e-9);
}

/// The feet follow the plan: both down while standing and in double support, the
/// swing foot lifted by `swing_height` at mid-swing and down at both ends, landing on
/// footprint j at x = j sl (foot centre).
#[test]
fn swing_feet_follow_the_footstep_plan() {
    let robot = coman();
    let walker = ComanWalker::new(&robot, &short(4.0)).unwrap();
    let r = &walker.reference;
    let p = r.zmp.plan().clone();
    let walk0 = p.t_start + p.t_double;
    for k in 0..4000 {
        let s = r.at(k as f64 / 1000.0);
        match s.phase {
            Phase::Single(twinloop_gait::Foot::Right) => assert!(s.stance == [false, true]),
            Phase::Single(twinloop_gait::Foot::Left) => assert!(s.stance == [true, false]),
            _ => assert!(s.stance == [true, true] && s.soles[0][2] == 0.0 && s.soles[1][2] == 0.0),
        }
    }
    // Mid-swing of swing 1 (the left foot) at full lift, landing at x = sl.
    let mid = r.at(walk0 + 0.5 * p.t_single);
    assert!((mid.soles[0][2] - walker.config.swing_height).abs() < 1e-12);
    let landed = r.at(walk0 + p.t_single + 0.01);
    assert!((landed.soles[0][0] - r.sole_offset[0] - p.step_length).abs() < 1e-12);
    // Swing 2 (the right foot) lands at x = 2 sl.
    let landed2 = r.at(walk0 + 2.0 * (p.t_single + p.t_double) - p.t_double + 0.01);
    assert!((landed2.soles[1][0] - r.sole_offset[0] - 2.0 * p.step_length).abs() < 1e-12);
}

#[test]
fn csv_has_the_seed_columns_at_1_khz() {
    let rows: Vec<DatasetRow> = (0..5)
        .map(|i| DatasetRow {
            t: i as f64 / 1000.0,
            xr: 0.1 * i as f64,
            zr: 0.5,
            x: 0.1 * i as f64 + 1e-3,
            z: 0.499,
            phase: (i % 2) as u8,
        })
        .collect();
    let dir = std::env::temp_dir().join(format!("twinloop-walk-csv-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("walk.csv");
    write_csv(&path, &rows).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("t,xr,zr,x,z,phase"));
    for (i, line) in lines.enumerate() {
        let f: Vec<&str> = line.split(',').collect();
        assert_eq!(f.len(), 6);
        assert_eq!(f[0].parse::<f64>().unwrap(), i as f64 / 1000.0);
        assert_eq!(f[5], if i % 2 == 0 { "0" } else { "1" });
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_inputs_are_named() {
    let robot = coman();
    let bad = |c: WalkingConfig| ComanWalker::new(&robot, &c).err().unwrap().0;
    let e = bad(WalkingConfig {
        k_series: 0.0,
        ..short(3.0)
    });
    assert!(
        e.contains("series stiffness K_s") && e.contains("positive"),
        "{e}"
    );
    let e = bad(WalkingConfig {
        k_harmonic: -8000.0,
        ..short(3.0)
    });
    assert!(e.contains("harmonic-drive stiffness K_h"), "{e}");
    let e = bad(WalkingConfig {
        step_length: f64::NAN,
        ..short(3.0)
    });
    assert!(e.contains("step length"), "{e}");
    // A 0.3 m step with 0.43 m legs: out of reach, said with the time.
    let e = bad(WalkingConfig {
        step_length: 0.3,
        ..short(3.0)
    });
    assert!(e.contains("reach") && e.contains("at t ="), "{e}");
    let e = bad(WalkingConfig {
        duration: 1.0,
        ..short(3.0)
    });
    assert!(e.contains("no room for a step"), "{e}");
}
