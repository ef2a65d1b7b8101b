//! Tip-over CoM estimators against analytic truth, hand-computed seed formulas, and
//! seed 001's three-mass check.

use nalgebra::{Rotation3, Vector3};
use twinloop_description::builtin::{FootGeometry, foot_geometry};
use twinloop_dynamics::{Data, Model, center_of_mass, forward_kinematics};
use twinloop_ident::tipover::{
    FeetMass, FrontalLever, SEED_000_CONSTANTS, SeedAngles, SeedConstants, TipAngles, exact_method,
    feet_mass, frontal_lever, sagittal_tip_angles, seed_method, seed_method_sagittal_angles,
    tip_angles,
};

fn km20_foot() -> FootGeometry {
    foot_geometry("km20").unwrap()
}

/// Rotate the CoM as the tipping robot does and check it is exactly above each edge:
/// an independent check of the angles (rotation matrices, not the tip equation).
fn check_above_edges(com: [f64; 3], a: &TipAngles, feet: &FeetMass, foot: &FootGeometry) {
    let c = Vector3::new(com[0], com[1], com[2]);
    // The feet stay, the rest (its CoM is (c - mu p) / (1 - mu)) turns.
    let mu = feet.fraction;
    let p = Vector3::new(feet.x, 0.0, feet.z);
    let turning = (c - p * mu) / (1.0 - mu);
    // Leaning forward by t turns the body about +y by +t (up tilts towards +x).
    let fwd =
        p * mu + Rotation3::from_axis_angle(&Vector3::y_axis(), a.forward) * turning * (1.0 - mu);
    assert!((fwd.x - foot.front).abs() < 1e-12, "forward {}", fwd.x);
    let bwd =
        p * mu + Rotation3::from_axis_angle(&Vector3::y_axis(), -a.backward) * turning * (1.0 - mu);
    assert!((bwd.x + foot.back).abs() < 1e-12, "backward {}", bwd.x);
    // Sideways the parallelogram carries the CoM to y + S sin - C (1 - cos): at the
    // outer sole edges.
    let e = foot.ankle_half_spacing + foot.outer;
    let y = |t: f64| c.y + LEVER.sin * t.sin() - LEVER.cos * (1.0 - t.cos());
    assert!((y(a.left) - e).abs() < 1e-12, "left {}", y(a.left));
    assert!((y(-a.right) + e).abs() < 1e-12, "right {}", y(-a.right));
}

/// Feet like km20's: 11 % of the mass, 25 mm behind and 11 mm below the ankle axes.
const FEET: FeetMass = FeetMass {
    fraction: 0.114,
    x: -0.025,
    z: -0.011,
};

/// A lever like km20's (S 0.154 m) with a small lateral offset of the leg links.
const LEVER: FrontalLever = FrontalLever {
    sin: 0.154,
    cos: 0.002,
};

#[test]
fn exact_method_recovers_a_known_com() {
    for (foot, com) in [
        (km20_foot(), [0.012, -0.004, 0.21]),
        (km20_foot(), [-0.02, 0.006, 0.25]),
        (foot_geometry("lab17").unwrap(), [0.005, 0.003, 0.14]),
        (foot_geometry("lab17").unwrap(), [-0.01, -0.004, 0.12]),
    ] {
        let a = tip_angles(com, &FEET, &LEVER, &foot).unwrap();
        check_above_edges(com, &a, &FEET, &foot);
        let light = tip_angles(com, &FeetMass::NONE, &LEVER, &foot).unwrap();
        check_above_edges(com, &light, &FeetMass::NONE, &foot);
        // The exact method takes the leg links' lateral offset C as zero: with C = 0 it
        // is exact, with C = 2 mm it is off by about C (1 - cos) (a quarter millimetre
        // at km20's 28 degrees).
        let flat = FrontalLever { cos: 0.0, ..LEVER };
        let e = exact_method(&tip_angles(com, &FEET, &flat, &foot).unwrap(), &FEET, &foot).unwrap();
        for k in 0..3 {
            assert!((e.com[k] - com[k]).abs() < 1e-9, "{:?} vs {com:?}", e.com);
        }
        assert!((e.frontal_lever - LEVER.sin).abs() < 1e-9);
        let e = exact_method(&a, &FEET, &foot).unwrap();
        let bound = 1.1 * LEVER.cos * (1.0 - a.left.max(a.right).cos());
        assert!((e.com[1] - com[1]).abs() < bound, "{:?} vs {com:?}", e.com);
        // Taking heavy feet as turning with the body puts the CoM about a millimetre off.
        let rigid = exact_method(&a, &FeetMass::NONE, &foot).unwrap();
        assert!((rigid.com[2] - com[2]).abs() > 5e-4, "{:?}", rigid.com);
    }
}

/// Feet rolled onto their outer edges: the robot at leg angle t, turned about the edge
/// by the roll, has its CoM above the edge (rotation matrices, found by bisection on
/// t); the exact method given the angle and the roll finds the CoM and the lever.
#[test]
fn exact_method_accounts_for_rolled_feet() {
    let foot = km20_foot();
    let com = [-0.004, 0.007, 0.24];
    let lever = FrontalLever { cos: 0.0, ..LEVER };
    let mu = FEET.fraction;
    let p = Vector3::new(FEET.x, 0.0, FEET.z);
    let c = Vector3::new(com[0], com[1], com[2]);
    let turning = (c - p * mu) / (1.0 - mu);
    // Forward (side +1) and backward (-1): the body turns by side t about the ankle
    // axis, the feet stay, then everything turns by side roll about the sole edge at
    // (side F, -L0).
    let sagittal = |side: f64, roll: f64| {
        let edge = Vector3::new(
            if side > 0.0 { foot.front } else { -foot.back },
            0.0,
            -foot.ankle_height,
        );
        let beyond = |t: f64| {
            let q = p * mu
                + Rotation3::from_axis_angle(&Vector3::y_axis(), side * t) * turning * (1.0 - mu);
            side * (Rotation3::from_axis_angle(&Vector3::y_axis(), side * roll) * (q - edge)).x
        };
        let (mut lo, mut hi) = (0.0, 1.2);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if beyond(mid) < 0.0 {
                lo = mid
            } else {
                hi = mid
            }
        }
        0.5 * (lo + hi)
    };
    let (rf, rb) = (0.2f64.to_radians(), 0.3f64.to_radians());
    let (tf, tb) = (sagittal(1.0, rf), sagittal(-1.0, rb));
    let e = foot.ankle_half_spacing + foot.outer;
    let h = com[2] + foot.ankle_height;
    // Side +1 left, -1 right: mirror the y axis for the right.
    let tip = |side: f64, roll: f64| {
        let beyond = |t: f64| {
            let y = side * com[1] + lever.sin * t.sin();
            let p = Vector3::new(0.0, y - e, h - lever.sin * (1.0 - t.cos()));
            // Leaning towards +y about the edge line (the x axis through it).
            (Rotation3::from_axis_angle(&Vector3::x_axis(), -roll) * p).y
        };
        let (mut lo, mut hi) = (0.0, 1.2);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if beyond(mid) < 0.0 {
                lo = mid
            } else {
                hi = mid
            }
        }
        0.5 * (lo + hi)
    };
    let (rl, rr) = (0.6f64.to_radians(), 0.4f64.to_radians());
    let a = TipAngles {
        forward: tf,
        backward: tb,
        left: tip(1.0, rl),
        right: tip(-1.0, rr),
        forward_roll: rf,
        backward_roll: rb,
        left_roll: rl,
        right_roll: rr,
    };
    // Rolled feet tip earlier than flat ones.
    let flat = tip_angles(com, &FEET, &lever, &foot).unwrap();
    assert!(a.left < flat.left - 0.01 && a.right < flat.right - 0.005);
    assert!(a.forward < flat.forward - 0.003 && a.backward < flat.backward - 0.003);
    let est = exact_method(&a, &FEET, &foot).unwrap();
    for k in 0..3 {
        assert!(
            (est.com[k] - com[k]).abs() < 1e-9,
            "{:?} vs {com:?}",
            est.com
        );
    }
    assert!((est.frontal_lever - lever.sin).abs() < 1e-9);
    // Ignoring the roll would put the CoM millimetres off.
    let naive = exact_method(
        &TipAngles {
            left_roll: 0.0,
            right_roll: 0.0,
            ..a
        },
        &FEET,
        &foot,
    )
    .unwrap();
    assert!((naive.com[1] - com[1]).abs() > 5e-4, "{:?}", naive.com);
    let naive = exact_method(
        &TipAngles {
            forward_roll: 0.0,
            backward_roll: 0.0,
            ..a
        },
        &FEET,
        &foot,
    )
    .unwrap();
    assert!((naive.com[2] - com[2]).abs() > 1e-3, "{:?}", naive.com);
}

/// The feet from a full model, checked by turning km20's ankle pitches (forward
/// kinematics) and measuring its CoM against the left foot: the feet stay, the rest
/// turns rigidly about the ankle axes.
#[test]
fn km20_feet_stay_while_the_body_turns() {
    let model =
        Model::from_description(&twinloop_description::builtin::resolve("builtin:km20").unwrap())
            .unwrap();
    let q0 = model.neutral_configuration();
    let feet = feet_mass(&model, &q0, ["l_ank_pitch", "r_ank_pitch"]).unwrap();
    // km20's feet: sole plate, ankle-roll servo and cross bracket, 0.19 kg each.
    assert!((feet.fraction - 0.381 / 3.336).abs() < 1e-3, "{feet:?}");
    let mid = twinloop_reduced::ankle_midpoint(&model, &q0, "l_ank_pitch", "r_ank_pitch").unwrap();
    let com = twinloop_reduced::com_relative_to_ankles(&model, &q0, "l_ank_pitch", "r_ank_pitch")
        .unwrap();
    let mu = feet.fraction;
    let p = Vector3::new(feet.x, 0.0, feet.z);
    let turning = (Vector3::new(com[0], com[1], com[2]) - p * mu) / (1.0 - mu);
    let mut data = Data::new(&model);
    let foot = model.links.iter().position(|l| l.name == "l_foot").unwrap();
    for t in [0.1f64, 0.3, -0.3] {
        // Negative ankle pitch leans km20 forward (its pitch axes point left).
        let mut q = q0.clone();
        for name in ["l_ank_pitch", "r_ank_pitch"] {
            q[model.q_offset + model.joint_index(name).unwrap()] = -t;
        }
        let c = center_of_mass(&model, &mut data, &q);
        forward_kinematics(&model, &mut data, &q);
        let l = &model.links[foot];
        // Where the standing model's left foot is, relative to the ankle midpoint.
        let foot_now = data.o_m_i[l.body] * l.placement;
        forward_kinematics(&model, &mut data, &q0);
        let foot_then = data.o_m_i[l.body] * l.placement;
        let c = foot_then.act_point(&foot_now.act_inv_point(&c));
        let c = Vector3::new(c.x - mid[0], c.y - mid[1], c.z - mid[2]);
        let want =
            p * mu + Rotation3::from_axis_angle(&Vector3::y_axis(), t) * turning * (1.0 - mu);
        assert!((c - want).norm() < 1e-9, "t {t}: {c:?} vs {want:?}");
    }
}

/// The frontal lever from a full model, checked by moving km20's legs as a
/// parallelogram (forward kinematics) and measuring its CoM against the left foot.
#[test]
fn km20_frontal_lever_moves_the_com_as_the_model_does() {
    let model =
        Model::from_description(&twinloop_description::builtin::resolve("builtin:km20").unwrap())
            .unwrap();
    let q0 = model.neutral_configuration();
    let lever = frontal_lever(
        &model,
        &q0,
        ["l_hip_roll", "r_hip_roll"],
        ["l_ank_roll", "r_ank_roll"],
    )
    .unwrap();
    assert!(lever.sin > 0.1 && lever.sin < 0.25, "{lever:?}");
    let mut data = Data::new(&model);
    let foot = model.links.iter().position(|l| l.name == "l_foot").unwrap();
    let com_in_foot = |q: &[f64], data: &mut Data| {
        let c = center_of_mass(&model, data, q);
        forward_kinematics(&model, data, q);
        let link = &model.links[foot];
        (data.o_m_i[link.body] * link.placement).act_inv_point(&c)
    };
    let c0 = com_in_foot(&q0, &mut data);
    for t in [0.1f64, 0.3, 0.5] {
        // km20's roll axes are +x on both sides: +t on an ankle roll leans the leg left
        // over its foot, -t on a hip roll keeps the pelvis level.
        let mut q = q0.clone();
        for (name, v) in [
            ("l_ank_roll", t),
            ("r_ank_roll", t),
            ("l_hip_roll", -t),
            ("r_hip_roll", -t),
        ] {
            q[model.q_offset + model.joint_index(name).unwrap()] = v;
        }
        forward_kinematics(&model, &mut data, &q);
        let torso = data.base_placement.rotation;
        let l = &model.links[foot];
        let foot_rot = (data.o_m_i[l.body] * l.placement).rotation;
        // The pelvis keeps the feet's orientation: a parallelogram.
        assert!((torso - foot_rot).norm() < 1e-12);
        let c = com_in_foot(&q, &mut data);
        let want = c0.y + lever.sin * t.sin() - lever.cos * (1.0 - t.cos());
        assert!((c.y - want).abs() < 1e-9, "t {t}: {} vs {want}", c.y);
        // And the height drops by S (1 - cos) (+ C sin).
        let dz = c.z - c0.z;
        let want = -lever.sin * (1.0 - t.cos()) - lever.cos * t.sin();
        assert!((dz - want).abs() < 1e-9, "t {t}: dz {dz} vs {want}");
    }
}

#[test]
fn a_com_above_the_ankle_tips_at_asin_f_over_h() {
    let mut foot = km20_foot();
    foot.front = 0.05;
    foot.back = 0.05;
    let h = 0.2;
    let lever = FrontalLever {
        sin: 0.15,
        cos: 0.0,
    };
    let a = tip_angles([0.0, 0.0, h], &FeetMass::NONE, &lever, &foot).unwrap();
    // The CoM swings on a circle of radius h about the ankle axis and is above the
    // edge when h sin(theta) = F.
    assert!((a.forward - (0.05f64 / h).asin()).abs() < 1e-14);
    assert!((a.backward - (0.05f64 / h).asin()).abs() < 1e-14);
    // Sideways: the parallelogram carries the CoM by S sin(theta) to the outer edge
    // d + outer = 0.04 + 0.035.
    let want = (0.075f64 / 0.15).asin();
    assert!((a.left - want).abs() < 1e-15 && (a.right - want).abs() < 1e-15);
    let e = exact_method(&a, &FeetMass::NONE, &foot).unwrap();
    assert!(e.com[0].abs() < 1e-12 && e.com[1].abs() < 1e-12);
    assert!((e.com[2] - h).abs() < 1e-12);
}

#[test]
fn seed_method_is_eq_8_to_13_as_printed() {
    // Hand values (computed separately, F1 3.5 cm, F2 9.5 cm, L0 3.1 cm):
    // gamma1 = (9 + 16.8)/2 - 9 = 3.9; L1 = tan(73.2 deg) 0.095 = 0.314655...;
    // theta1 = atan((L1 + 0.031)/0.095) = 74.632...; L3 = 0.095 / cos(theta1);
    // D1 = L3 tan(3.9 deg); gamma2 = 7 - 5 = 2; alpha2 < beta2 so W1 = +L3 tan(2 deg).
    let a = SeedAngles {
        alpha1: 9.0,
        beta1: 16.8,
        alpha2: 5.0,
        beta2: 7.0,
    };
    let e = seed_method(&a, &SEED_000_CONSTANTS).unwrap();
    assert!((e.gamma1 - 3.9).abs() < 1e-12);
    assert!((e.l1 - 0.31465518059599057).abs() < 1e-12);
    assert!((e.theta1 - 74.63225182777434).abs() < 1e-9);
    assert!((e.l3 - 0.3584724590158172).abs() < 1e-12);
    assert!((e.d1 - 0.024438200553688973).abs() < 1e-12);
    assert!((e.gamma2 - 2.0).abs() < 1e-12);
    assert!((e.w1 - 0.012518134110431338).abs() < 1e-12);
    assert_eq!(e.com, [e.d1, e.w1, e.l3]);
    // alpha2 >= beta2 flips the sign of W1 (eq. 13's first case).
    let b = seed_method(
        &SeedAngles {
            alpha2: 7.0,
            beta2: 5.0,
            ..a
        },
        &SEED_000_CONSTANTS,
    )
    .unwrap();
    assert!((b.w1 + e.w1).abs() < 1e-15);
    // phi is in none of the formulas.
    let c = seed_method(
        &a,
        &SeedConstants {
            phi: 99.0,
            ..SEED_000_CONSTANTS
        },
    )
    .unwrap();
    assert_eq!(c, e);
    // Eq. 8: raw positions, 300 degrees over 1024 steps. 30 steps forward of centre and
    // 57 behind: alpha1 = 30 * 300/1024 = 8.7890625, beta1 = 57 * 300/1024 = 16.69921875.
    let p = SeedAngles::from_positions(512.0, 482.0, 569.0, 497.0, 530.0).unwrap();
    assert_eq!(p.alpha1, 8.7890625);
    assert_eq!(p.beta1, 16.69921875);
    assert_eq!(p.alpha2, 15.0 * 300.0 / 1024.0);
    assert_eq!(p.beta2, 18.0 * 300.0 / 1024.0);
    // The inverse used for seed 001's check gives the angles back.
    let (a1, b1) = seed_method_sagittal_angles(e.d1, e.l3, &SEED_000_CONSTANTS).unwrap();
    assert!(
        (a1 - 9.0).abs() < 1e-9 && (b1 - 16.8).abs() < 1e-9,
        "{a1} {b1}"
    );
}

/// Seed 001 section F: masses (kg) and positions (cm) "measured from the origin of the
/// virtual frame": left leg 0.740 at (15.23, 4.17, 8.81), right leg 0.738 at (15.23,
/// -3.92, 8.81), hip 2.02 at (38.8, -1.2, -4.7); the robot fell at 9 degrees forward
/// and (in simulation) 16.8 degrees backward.
const SEED_001: [(f64, [f64; 3]); 3] = [
    (0.740, [15.23, 4.17, 8.81]),
    (0.738, [15.23, -3.92, 8.81]),
    (2.02, [38.8, -1.2, -4.7]),
];

#[test]
fn seed_001_masses_fall_near_9_and_16_8_degrees() {
    // The seed's x is the height (its eq. 4 adds g to x''), y lateral; with x up and y
    // left a right-handed frame's z points backwards, so our forward x is -z_seed.
    let m: f64 = SEED_001.iter().map(|(m, _)| m).sum();
    let c = |k: usize| SEED_001.iter().map(|(mi, p)| mi * p[k]).sum::<f64>() / m / 100.0;
    let com = [-c(2), c(1), c(0)];
    // Point masses: the seed's model has no feet.
    let (f, b) = sagittal_tip_angles(com[0], com[2], &FeetMass::NONE, &km20_foot()).unwrap();
    let (f, b) = (f.to_degrees(), b.to_degrees());
    assert!((f - 9.0).abs() < 0.1, "forward {f}");
    assert!((b - 16.8).abs() < 0.5, "backward {b}");
    // And the exact method turns those angles back into the three masses' CoM.
    let none = FeetMass::NONE;
    let a = tip_angles(com, &none, &LEVER, &km20_foot()).unwrap();
    let e = exact_method(&a, &none, &km20_foot()).unwrap();
    assert!((e.com[0] - com[0]).abs() < 1e-12 && (e.com[2] - com[2]).abs() < 1e-12);
}

#[test]
fn bad_input_names_the_field() {
    let foot = km20_foot();
    // CoM beyond the front edge: the robot cannot stand.
    assert_eq!(
        tip_angles([0.05, 0.0, 0.2], &FEET, &LEVER, &foot)
            .unwrap_err()
            .field
            .as_deref(),
        Some("forward")
    );
    assert_eq!(
        tip_angles([0.0, 0.0, -0.1], &FEET, &LEVER, &foot)
            .unwrap_err()
            .field
            .as_deref(),
        Some("forward")
    );
    assert_eq!(
        tip_angles([0.0, f64::NAN, 0.2], &FEET, &LEVER, &foot)
            .unwrap_err()
            .field
            .as_deref(),
        Some("com.y")
    );
    let good = tip_angles([0.0, 0.0, 0.2], &FEET, &LEVER, &foot).unwrap();
    let e = exact_method(
        &TipAngles {
            backward: 0.0,
            ..good
        },
        &FEET,
        &foot,
    )
    .unwrap_err();
    assert_eq!(e.field.as_deref(), Some("angles.backward"));
    let e = exact_method(
        &TipAngles {
            left: f64::NAN,
            ..good
        },
        &FEET,
        &foot,
    )
    .unwrap_err();
    assert_eq!(e.field.as_deref(), Some("angles.left"));
    let heavy = FeetMass {
        fraction: 1.0,
        ..FEET
    };
    assert_eq!(
        exact_method(&good, &heavy, &foot)
            .unwrap_err()
            .field
            .as_deref(),
        Some("feet.fraction")
    );
    let mut flat = foot.clone();
    flat.front = 0.0;
    assert_eq!(
        exact_method(&good, &FEET, &flat)
            .unwrap_err()
            .field
            .as_deref(),
        Some("foot.front")
    );
    let e = seed_method(
        &SeedAngles {
            alpha1: 9.0,
            beta1: 0.0,
            alpha2: 1.0,
            beta2: 1.0,
        },
        &SEED_000_CONSTANTS,
    )
    .unwrap_err();
    assert_eq!(e.field.as_deref(), Some("angles.beta1"));
    assert_eq!(
        seed_method_sagittal_angles(0.0, 0.05, &SEED_000_CONSTANTS)
            .unwrap_err()
            .field
            .as_deref(),
        Some("z")
    );
    assert_eq!(
        SeedAngles::from_positions(512.0, f64::NAN, 0.0, 0.0, 0.0)
            .unwrap_err()
            .field
            .as_deref(),
        Some("max_forward")
    );
}
