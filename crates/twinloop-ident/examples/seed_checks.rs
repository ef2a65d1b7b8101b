//! The numbers of docs/reduced-models.md: the seed robots' CoM and tip angles, seed
//! 001's three-mass check, seed 000 Table V, and km20 with seed 000's batteries.
//!
//! cargo run --release -p twinloop-ident --example seed_checks

use nalgebra::{Rotation3, Vector3};
use twinloop_description::builtin::{FootGeometry, foot_geometry, km20};
use twinloop_dynamics::Model;
use twinloop_ident::tipover::{
    FeetMass, FrontalLever, SEED_000_CONSTANTS, SeedAngles, SeedConstants, TipAngles, exact_method,
    feet_mass, frontal_lever, sagittal_tip_angles, seed_method, seed_method_sagittal_angles,
    tip_angles,
};
use twinloop_reduced::{
    LegMotion, Lipm, Plane, PointMass, ThreeMassLipm, ThreeMasses, com_relative_to_ankles,
};

fn cm(v: [f64; 3]) -> String {
    format!(
        "{:.2}, {:.2}, {:.2}",
        v[0] * 100.0,
        v[1] * 100.0,
        v[2] * 100.0
    )
}

fn seed_angles(a: &TipAngles) -> SeedAngles {
    let [f, b, l, r] = a.to_degrees();
    SeedAngles {
        alpha1: f,
        beta1: b,
        alpha2: l,
        beta2: r,
    }
}

fn err_mm(a: [f64; 3], b: [f64; 3]) -> String {
    format!(
        "{:.1}, {:.1}, {:.1}",
        (a[0] - b[0]) * 1000.0,
        (a[1] - b[1]) * 1000.0,
        (a[2] - b[2]) * 1000.0
    )
}

/// The frontal lever of the parallelogram sideways lean (hip rolls turned with the
/// ankle rolls), from the model.
fn model_lever(model: &Model, q: &[f64]) -> FrontalLever {
    frontal_lever(
        model,
        q,
        ["l_hip_roll", "r_hip_roll"],
        ["l_ank_roll", "r_ank_roll"],
    )
    .unwrap()
}

/// Standing model: CoM relative to the ankles, three masses, tip angles, both estimators.
fn robot_report(
    robot: &twinloop_description::Description,
    foot: &FootGeometry,
    hips: (&str, &str),
) {
    let model = Model::from_description(robot).unwrap();
    let q = model.neutral_configuration();
    let com = com_relative_to_ankles(&model, &q, &foot.left_ankle_pitch, &foot.right_ankle_pitch)
        .unwrap();
    let mid = twinloop_reduced::ankle_midpoint(
        &model,
        &q,
        &foot.left_ankle_pitch,
        &foot.right_ankle_pitch,
    )
    .unwrap();
    let three = ThreeMasses::from_model(&model, &q, hips.0, hips.1)
        .unwrap()
        .relative_to(mid);
    let lever = model_lever(&model, &q);
    let feet = feet_mass(
        &model,
        &q,
        [&foot.left_ankle_pitch, &foot.right_ankle_pitch],
    )
    .unwrap();
    let a = tip_angles(com, &feet, &lever, foot).unwrap();
    let d = a.to_degrees();
    let exact = exact_method(&a, &feet, foot).unwrap();

    let seed = seed_method(&seed_angles(&a), &SeedConstants::from_foot(foot)).unwrap();
    println!(
        "{}: mass {:.4} kg; CoM (cm, from ankle midpoint) {}",
        robot.name,
        model.total_mass,
        cm(com)
    );
    for (n, p) in [
        ("left leg", three.left_leg),
        ("right leg", three.right_leg),
        ("hip", three.hip),
    ] {
        println!("  {n:9} {:.4} kg at {}", p.mass, cm(p.position));
    }
    println!(
        "  static tip angles (deg): forward {:.2} backward {:.2} left {:.2} right {:.2}",
        d[0], d[1], d[2], d[3]
    );
    let light = tip_angles(com, &FeetMass::NONE, &lever, foot)
        .unwrap()
        .to_degrees();
    let feet_line = format!(
        "  feet {:.1} % of the mass at x {:.2} z {:.2} cm; with massless feet the tips would be forward {:.2} backward {:.2}",
        feet.fraction * 100.0,
        feet.x * 100.0,
        feet.z * 100.0,
        light[0],
        light[1]
    );
    println!("{feet_line}");
    println!(
        "  exact method {} (error mm {}), frontal lever {:.2} cm (model {:.2} cm, C {:.3} cm)",
        cm(exact.com),
        err_mm(exact.com, com),
        exact.frontal_lever * 100.0,
        lever.sin * 100.0,
        lever.cos * 100.0
    );
    println!(
        "  seed method  {} (error mm {}); L1 {:.2} cm, gamma1 {:.2} deg",
        cm(seed.com),
        err_mm(seed.com, com),
        seed.l1 * 100.0,
        seed.gamma1
    );
}

fn seed_001() {
    println!("\n== seed 001 section F: three masses -> fall angles ==");
    let masses = [
        (0.740, [15.23, 4.17, 8.81]),
        (0.738, [15.23, -3.92, 8.81]),
        (2.02, [38.8, -1.2, -4.7]),
    ];
    let m: f64 = masses.iter().map(|(m, _)| m).sum();
    let c = |k: usize| masses.iter().map(|(mi, p)| mi * p[k]).sum::<f64>() / m / 100.0;
    println!(
        "total {:.3} kg, CoM in the seed's (x, y, z) = ({:.3}, {:.3}, {:.3}) cm",
        m,
        c(0) * 100.0,
        c(1) * 100.0,
        c(2) * 100.0
    );
    let foot = foot_geometry("km20").unwrap();
    let readings = [
        (
            "A: x = height above the ankle axis, z backward",
            [-c(2), c(1), c(0)],
        ),
        (
            "B: x = height above the ankle axis, z forward",
            [c(2), c(1), c(0)],
        ),
        (
            "C: x = height above the sole, z backward",
            [-c(2), c(1), c(0) - km20::L0],
        ),
    ];
    for (name, com) in readings {
        // The seed's three point masses have no feet.
        let (f, b) = sagittal_tip_angles(com[0], com[2], &FeetMass::NONE, &foot).unwrap();
        let a = [f.to_degrees(), b.to_degrees()];
        let s = seed_method_sagittal_angles(com[0], com[2], &SEED_000_CONSTANTS);
        let s = match s {
            Ok((f, b)) => format!("forward {f:.2}, backward {b:.2}"),
            Err(e) => format!("none ({e})"),
        };
        println!(
            "{name}: exact forward {:.2} backward {:.2}; seed formulas give this CoM for {s}",
            a[0], a[1]
        );
    }
    for (name, f, b) in [("sim", 9.0, 16.8), ("real", 9.0, 16.0)] {
        let s = seed_method(
            &SeedAngles {
                alpha1: f,
                beta1: b,
                alpha2: 0.0,
                beta2: 0.0,
            },
            &SEED_000_CONSTANTS,
        )
        .unwrap();
        let e = exact_method(
            &TipAngles::from_degrees(f, b, 28.0, 28.0),
            &FeetMass::NONE,
            &foot,
        )
        .unwrap();
        println!(
            "angles {f}/{b} ({name}): seed method x {:.2} z {:.2} cm; exact method x {:.2} z {:.2} cm",
            s.com[0] * 100.0,
            s.com[2] * 100.0,
            e.com[0] * 100.0,
            e.com[2] * 100.0
        );
    }
}

fn seed_000_table_v() {
    println!("\n== seed 000 Table V: fall angles from the Table II / III CoMs (exact statics) ==");
    let foot = foot_geometry("km20").unwrap();
    // Table II geometry-based CoM, Table III three-mass CoM (cm, seed axes x up), Table V
    // angles: sent (= 3MLIPM), LIPM.
    let rows = [
        (
            "a",
            [21.0, 0.6, -2.2],
            [21.7, 0.8, 0.3],
            (8.78, 24.31),
            (8.78, 25.21),
        ),
        (
            "b",
            [25.1, 0.9, -1.8],
            [25.3, 0.8, 1.6],
            (8.78, 19.04),
            (9.39, 19.04),
        ),
        (
            "c",
            [23.8, 0.0, -2.3],
            [26.9, 0.5, 1.6],
            (7.61, 18.46),
            (7.61, 20.78),
        ),
        (
            "d",
            [26.5, -0.1, -2.1],
            [23.9, -0.5, 0.6],
            (9.38, 20.50),
            (9.59, 20.50),
        ),
        (
            "e",
            [26.0, 2.0, -2.1],
            [25.8, 1.9, 1.2],
            (7.91, 19.33),
            (8.58, 19.33),
        ),
        (
            "f",
            [27.6, 1.0, -1.9],
            [25.8, 1.0, 1.7],
            (8.49, 18.75),
            (8.68, 18.75),
        ),
    ];
    println!(
        "row | Table V 3MLIPM fw/bw | Table V LIPM fw/bw | Table II CoM z back: fw/bw | z fwd: fw/bw | Table III CoM z back: fw/bw | z fwd: fw/bw"
    );
    for (label, t2, t3, v3, vl) in rows {
        let angles = |p: [f64; 3], sign: f64| {
            let com = [sign * p[2] / 100.0, p[1] / 100.0, p[0] / 100.0];
            match sagittal_tip_angles(com[0], com[2], &FeetMass::NONE, &foot) {
                Ok((f, b)) => format!("{:.2}/{:.2}", f.to_degrees(), b.to_degrees()),
                Err(e) => format!("- ({})", e.field.as_deref().unwrap_or("")),
            }
        };
        println!(
            "{label} | {:.2}/{:.2} | {:.2}/{:.2} | {} | {} | {} | {}",
            v3.0,
            v3.1,
            vl.0,
            vl.1,
            angles(t2, -1.0),
            angles(t2, 1.0),
            angles(t3, -1.0),
            angles(t3, 1.0)
        );
    }
}

/// Time (s) for the CoM to run from 1 mm to 20 mm past the front edge, after the robot
/// has tipped over it: LIPM of the CoM vs the three masses on their support lines.
fn fall_times(three: &ThreeMasses, tip_forward: f64, foot: &FootGeometry) -> (f64, f64) {
    // Tipped pose: rotate about the ankle axis by the tip angle, then measure from the
    // front edge of the sole (x = F1, z = -L0), then 1 mm further.
    let rot = Rotation3::from_axis_angle(&Vector3::y_axis(), tip_forward);
    let place = |p: PointMass| {
        let v = rot * Vector3::new(p.position[0], p.position[1], p.position[2]);
        PointMass {
            mass: p.mass,
            position: [v.x - foot.front + 0.001, v.y, v.z + foot.ankle_height],
        }
    };
    let tipped = ThreeMasses::new(
        place(three.left_leg),
        place(three.right_leg),
        place(three.hip),
    )
    .unwrap();
    let c = tipped.com();
    let dt = 1e-4;
    let lipm = Lipm::new(tipped.total_mass(), c[2]).unwrap();
    let run = lipm.fall(c[0], dt, 2.0).unwrap();
    let t1 = run.iter().find(|s| s.x >= 0.02).map_or(f64::NAN, |s| s.t);
    let run = ThreeMassLipm::new(tipped)
        .unwrap()
        .simulate(
            Plane::Sagittal,
            (LegMotion::SupportLine, LegMotion::SupportLine),
            0.0,
            |_| 0.0,
            dt,
            2.0,
        )
        .unwrap();
    let t3 = run.iter().find(|s| s.com >= 0.02).map_or(f64::NAN, |s| s.t);
    (t1, t3)
}

fn km20_batteries() {
    println!("\n== km20 with seed 000's battery scenarios (0.2 kg) ==");
    let foot = foot_geometry("km20").unwrap();
    println!(
        "row | masses m1 m2 m3 (kg) | CoM (cm) | tip fw/bw/l/r (deg) | seed method CoM (cm) | seed error (mm) | exact error (mm) | fall 1->20 mm past the edge: LIPM / 3MLIPM (s)"
    );
    for s in km20::BATTERY_SCENARIOS {
        let r = km20::with_battery(&s).unwrap();
        let model = Model::from_description(&r).unwrap();
        let q = model.neutral_configuration();
        let com = com_relative_to_ankles(&model, &q, "l_ank_pitch", "r_ank_pitch").unwrap();
        let mid =
            twinloop_reduced::ankle_midpoint(&model, &q, "l_ank_pitch", "r_ank_pitch").unwrap();
        let three = ThreeMasses::from_model(&model, &q, "l_hip_yaw", "r_hip_yaw")
            .unwrap()
            .relative_to(mid);
        let feet = feet_mass(&model, &q, ["l_ank_pitch", "r_ank_pitch"]).unwrap();
        let a = tip_angles(com, &feet, &model_lever(&model, &q), &foot).unwrap();
        let d = a.to_degrees();
        let seed = seed_method(&seed_angles(&a), &SEED_000_CONSTANTS).unwrap();
        let exact = exact_method(&a, &feet, &foot).unwrap();
        let (t1, t3) = fall_times(&three, a.forward, &foot);
        println!(
            "{} {} | {:.3} {:.3} {:.3} | {} | {:.2}/{:.2}/{:.2}/{:.2} | {} | {} | {} | {:.3} / {:.3}",
            s.label,
            s.name,
            three.left_leg.mass,
            three.right_leg.mass,
            three.hip.mass,
            cm(com),
            d[0],
            d[1],
            d[2],
            d[3],
            cm(seed.com),
            err_mm(seed.com, com),
            err_mm(exact.com, com),
            t1,
            t3
        );
    }
}

fn main() {
    println!("== the seed robots standing (zero configuration) ==");
    robot_report(
        &twinloop_description::builtin::builtin("km20").unwrap(),
        &foot_geometry("km20").unwrap(),
        ("l_hip_yaw", "r_hip_yaw"),
    );
    robot_report(
        &twinloop_description::builtin::builtin("lab17").unwrap(),
        &foot_geometry("lab17").unwrap(),
        ("l_hip_roll", "r_hip_roll"),
    );
    seed_001();
    seed_000_table_v();
    km20_batteries();
}
