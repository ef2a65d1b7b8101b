//! Inputs in the wrong units by 1000x (issue 17), caught where every command reads
//! them: a `--dt` in milliseconds, a mass in grams on `--total-mass` or `--add-mass`,
//! an offset in millimetres, a trajectory in degrees where radians are expected. (A
//! description in millimetres or grams is lint's `unit-scale`, refused by
//! [`crate::common::load_description`].)
//!
//! Each check is an error naming the option or column and the unit the value looks
//! like, and each has a bound that legitimate input stays far from: a 0.001 s step, a
//! 150 kg robot, a knee at 2.6 rad pass.

use crate::error::CliError;
use twinloop_description::Description;
use twinloop_description::lint::unit_scale;
use twinloop_dynamics::Model;
use twinloop_io::{IoError, Table};

/// The longest time step or sample period, s, of any command: 0.1 s is a 10 Hz
/// control loop; a contact simulation diverges well before. `--dt 1` meant 1 ms.
pub const MAX_STEP_S: f64 = 0.1;

/// The shortest time step or sample period, s: 1 us, a million steps per second of
/// robot time; the simulators step at 1 ms and the fastest bus here reads at 1 kHz, so
/// a shorter step is a typo (`--dt 1e-300`), and every second would be more steps than
/// a command computes (`crate::bounds::MAX_STEPS`).
pub const MIN_STEP_S: f64 = 1e-6;

/// A time step or sample period, s: a finite number in [[`MIN_STEP_S`],
/// [`MAX_STEP_S`]]. As a clap value parser: `#[arg(long, value_parser =
/// crate::units::time_step)]`.
pub fn time_step(s: &str) -> Result<f64, String> {
    let x = crate::common::positive(s)?;
    if x < MIN_STEP_S {
        Err(format!(
            "{} s is shorter than the {MIN_STEP_S} s a time step may be (a million steps \
             per second of robot time; the simulators step at 0.001 s)",
            crate::common::num(x)
        ))
    } else if x <= MAX_STEP_S {
        Ok(x)
    } else {
        Err(format!(
            "{} s is too long for a time step (at most {MAX_STEP_S} s); the step is in \
             seconds: for {} ms write {}",
            crate::common::num(x),
            crate::common::num(x),
            crate::common::num(x / 1000.0)
        ))
    }
}

/// The longest length, m, of a walking robot's gait (a CoM height, a step, a foot
/// lift, the distance between the feet): 3 m, past the tallest robot here (TALOS,
/// 1.75 m). `--com-height 500` meant millimetres and planned a 7 s pendulum.
pub const MAX_GAIT_LENGTH_M: f64 = 3.0;

/// A gait length in metres (`--com-height`, `--step-width`, `--swing-height`), as a
/// clap value parser: finite, > 0, at most [`MAX_GAIT_LENGTH_M`].
pub fn gait_length(s: &str) -> Result<f64, String> {
    let x = crate::common::positive(s)?;
    gait_bound(x)
}

/// A gait length that may be 0 (`--swing-height`: a shuffle), in metres.
pub fn gait_lift(s: &str) -> Result<f64, String> {
    let x = crate::common::non_negative(s)?;
    gait_bound(x)
}

/// A signed gait length in metres (`--step-length`: negative walks backwards).
pub fn signed_gait_length(s: &str) -> Result<f64, String> {
    let x = crate::common::finite(s)?;
    gait_bound(x)
}

fn gait_bound(x: f64) -> Result<f64, String> {
    if x.abs() <= MAX_GAIT_LENGTH_M {
        return Ok(x);
    }
    let (unit, factor) = if x.abs() >= 100.0 {
        ("millimetres", 1000.0)
    } else {
        ("centimetres", 100.0)
    };
    Err(format!(
        "{} m is longer than any length of a walking robot's gait (at most {} m); \
         lengths are metres: in {unit}, write {}",
        crate::common::num(x),
        crate::common::num(MAX_GAIT_LENGTH_M),
        crate::common::num(x / factor)
    ))
}

/// The largest noise a synthetic measurement may be given, m or rad: 1, as large as
/// a humanoid here is tall or a joint's half range. A larger standard deviation
/// drowns the signal (a CoM 0.5 m up) and was meant in millimetres; `1e300` fills
/// the output with infinities.
pub const MAX_NOISE: f64 = 1.0;

/// A noise's standard deviation (m or rad), as a clap value parser: in [0, [`MAX_NOISE`]].
pub fn noise(s: &str) -> Result<f64, String> {
    let x = crate::common::non_negative(s)?;
    if x <= MAX_NOISE {
        Ok(x)
    } else {
        Err(format!(
            "{} is more noise than signal: a standard deviation of at most {MAX_NOISE} (m \
             or rad) is taken; for millimetres write {}",
            crate::common::num(x),
            crate::common::num(x / 1000.0)
        ))
    }
}

/// How far a robot's weight on a scale may be from its model's before the number is
/// taken for another unit: a robot ten times its model is not the robot modelled.
pub const MAX_MASS_RATIO: f64 = 10.0;

/// A robot's measured total mass (`option`, kg) against its model's: a value
/// [`MAX_MASS_RATIO`] times off is an error naming the option and the unit it looks
/// like (1000x: grams; 1/1000: tonnes).
pub fn total_mass(option: &str, kg: f64, robot: &Description) -> Result<(), CliError> {
    let model = robot.total_mass();
    if model.is_nan() || model <= 0.0 {
        return Ok(());
    }
    let ratio = kg / model;
    if (1.0 / MAX_MASS_RATIO..=MAX_MASS_RATIO).contains(&ratio) {
        return Ok(());
    }
    let hint = if ratio > 1.0 {
        format!("is it in grams? ({} kg)", crate::common::num(kg / 1000.0))
    } else {
        format!("is it in tonnes? ({} kg)", crate::common::num(kg * 1000.0))
    };
    Err(CliError::new(format!(
        "{option} {} kg is {}x the model's {} kg; {option} is in kilograms: {hint}",
        crate::common::num(kg),
        crate::common::num(ratio),
        crate::common::num(model)
    )))
}

/// The heaviest point mass, as a multiple of the robot's mass, that `--add-mass` takes
/// as kilograms (a 50 g payload in grams is 14x a 3.6 kg robot).
pub const MAX_ADDED_MASS_RATIO: f64 = 5.0;

/// How far from its link, as a multiple of the robot's extent, an added mass may sit
/// (5 mm in millimetres is 11 extents of a 0.45 m robot).
pub const MAX_OFFSET_EXTENTS: f64 = 5.0;

/// `--add-mass`, as every command that builds a robot from a description takes it:
/// `experiment tipover|lean`, `simulate`, `serve` and `model export`.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct AddMassArgs {
    /// Add a point mass to the description first (seed 000's batteries, a camera the
    /// model lacks), repeatable: KG@LINK:X,Y,Z with X,Y,Z in metres in the link
    /// frame, e.g. 0.2@torso:0.05,0,0. A negative mass takes a part off (a battery
    /// removed): -0.2@torso:0.05,0,0
    #[arg(
        long = "add-mass",
        value_name = "KG@LINK:X,Y,Z",
        allow_hyphen_values = true
    )]
    pub add_mass: Vec<String>,
}

impl AddMassArgs {
    /// The changes applied to `robot` ([`add_masses`]).
    pub fn apply(&self, robot: &mut Description) -> Result<(), CliError> {
        add_masses(robot, &self.add_mass)
    }
}

/// An added mass of `kg` on a robot of `own` kg, as every option that adds one
/// takes it (`--add-mass`, `adapt train --mass-range`): [`MAX_ADDED_MASS_RATIO`]
/// times the robot's or more is taken for grams, the reason returned.
pub fn added_mass(kg: f64, own: f64) -> Result<(), String> {
    if own > 0.0 && kg.abs() > MAX_ADDED_MASS_RATIO * own {
        return Err(format!(
            "{} kg is {}x the robot's {} kg; the mass is in kilograms: is it in grams? \
             ({} kg)",
            crate::common::num(kg),
            (kg / own).round(),
            crate::common::num(own),
            crate::common::num(kg / 1000.0)
        ));
    }
    Ok(())
}

/// Parse `KG@LINK:X,Y,Z` and add that point mass to `robot`, for each of `specs` (the
/// values of `--add-mass`): a mass [`MAX_ADDED_MASS_RATIO`] times the robot's is taken
/// for grams, an offset beyond [`MAX_OFFSET_EXTENTS`] of the robot's size for
/// millimetres; both are errors naming the option.
pub fn add_masses(robot: &mut Description, specs: &[String]) -> Result<(), CliError> {
    let own = robot.total_mass();
    let size = unit_scale::extent(robot).max(0.1);
    for s in specs {
        let (kg, link, xyz) = parse_added_mass(s)?;
        let bad = |why: String| CliError::new(format!("--add-mass \"{s}\": {why}"));
        added_mass(kg, own).map_err(bad)?;
        let r = xyz.iter().map(|v| v * v).sum::<f64>().sqrt();
        if r > MAX_OFFSET_EXTENTS * size {
            return Err(bad(format!(
                "the position is {} m from the link, {}x the robot's {} m size; X,Y,Z are in \
                 metres: are they in millimetres? ({})",
                crate::common::num(r),
                crate::common::num((r / size).round()),
                crate::common::num(size),
                xyz.map(|v| crate::common::num(v / 1000.0)).join(",")
            )));
        }
        twinloop_description::builtin::add_point_mass(robot, &link, kg, xyz)
            .map_err(|e| CliError::from(e).context(format!("--add-mass \"{s}\"")))?;
    }
    Ok(())
}

/// `KG@LINK:X,Y,Z` (X,Y,Z in metres in the link frame) as its three parts: the
/// description crate's parser (shared with the Python package), errors naming the
/// option.
pub fn parse_added_mass(s: &str) -> Result<(f64, String, [f64; 3]), CliError> {
    twinloop_description::builtin::parse_point_mass(s)
        .map_err(|e| CliError::new(format!("--add-mass {}", e.message)))
}

/// How far, rad, beyond its limits a hinge's angle may be before the column is taken
/// for degrees (when its values in degrees fit the limits).
pub const DEGREES_BEYOND_LIMIT_RAD: f64 = 1.0;

/// The `q:` columns of `table` against the model's joint limits: an angle beyond
/// its hinge's limits and beyond a full turn (or beyond the limits themselves, when
/// they are wider: ANYmal C's +-3 pi), or more than [`DEGREES_BEYOND_LIMIT_RAD`]
/// beyond its limits while the whole column read as degrees fits them, is an error
/// naming the file, line, column and the unit it looks like. An angle within its
/// joint's limits is never one. Hinges without limits (continuous joints: wheels, a
/// turntable) may turn any number of times.
pub fn check_angles(table: &Table, model: &Model) -> Result<(), IoError> {
    for i in 0..model.nbodies {
        if !model.joint_types[i].is_revolute() {
            continue;
        }
        let (lo, hi) = (model.lower_limits[i], model.upper_limits[i]);
        if !(lo.is_finite() && hi.is_finite() && lo < hi) {
            continue;
        }
        let name = &model.joint_names[i];
        let Some(c) = table.column_index(&format!("q:{name}")) else {
            continue;
        };
        let column = || table.rows.iter().map(move |r| r[c]);
        let fits_as_degrees = column()
            .filter(|x| x.is_finite())
            .all(|x| (lo - 0.1..=hi + 0.1).contains(&x.to_radians()));
        let beyond = |x: f64| (lo - x).max(x - hi);
        // The joint's own range may be wider than a turn (a neck rod, ANYmal's +-3 pi).
        let turn = std::f64::consts::TAU.max(lo.abs()).max(hi.abs());
        let bad = table.rows.iter().position(|r| {
            let x = r[c];
            x.is_finite()
                && beyond(x) > 0.0
                && (x.abs() > turn || (fits_as_degrees && beyond(x) > DEGREES_BEYOND_LIMIT_RAD))
        });
        let Some(r) = bad else { continue };
        let x = table.rows[r][c];
        let hint = if fits_as_degrees {
            format!(
                "the column looks like degrees ({} deg = {} rad, within the limits)",
                crate::common::num(x),
                crate::common::num(x.to_radians())
            )
        } else {
            "no hinge with limits turns that far".to_string()
        };
        return Err(IoError {
            file: table.path.clone(),
            line: table.line_of_row(r),
            column: Some(format!("q:{name}")),
            message: format!(
                "data row {}: {} rad is beyond the joint's limits [{}, {}] rad by {} rad; \
                 angles are radians: {hint}",
                r + 1,
                crate::common::num(x),
                crate::common::num(lo),
                crate::common::num(hi),
                crate::common::num(beyond(x))
            ),
        });
    }
    Ok(())
}

/// Read a CSV of configurations (`q:<joint>` columns) for `model`:
/// [`crate::common::read_table`], and every angle checked against its joint's limits
/// ([`check_angles`]), so a trajectory in degrees is an error naming the column in
/// every command that reads one.
pub fn read_trajectory(
    path: &std::path::Path,
    model: &twinloop_dynamics::Model,
) -> Result<Table, CliError> {
    let table = crate::common::read_table(path)?;
    check_angles(&table, model)?;
    Ok(table)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 30 item 2: ANYmal C's +-3 pi hinge (the MJCF edge case
    /// wide_range_hinge.xml, neck_yaw in [-9.42478, 9.42478]): 7 rad is inside the
    /// joint's limits, so it is no sign of degrees; 540 (degrees) still is.
    #[test]
    fn wide_range_hinge_angles_within_limits_are_not_degrees() {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../twinloop-description/tests/data/mjcf/edges/wide_range_hinge.xml"
        );
        let robot = twinloop_description::load(path).unwrap();
        let model = Model::from_description(&robot).unwrap();
        let table =
            |x: f64| Table::parse(&format!("t,q:neck_yaw,q:neck_pitch\n0,{x},0.1\n")).unwrap();
        for x in [7.0, -9.4, 9.42] {
            assert!(check_angles(&table(x), &model).is_ok(), "{x} rad");
        }
        let e = check_angles(&table(540.0), &model).unwrap_err().to_string();
        assert!(
            e.contains("looks like degrees") && e.contains("beyond"),
            "{e}"
        );
        // Beyond the limits and beyond any turn the joint makes: not degrees either.
        let e = check_angles(&table(2000.0), &model)
            .unwrap_err()
            .to_string();
        assert!(e.contains("no hinge with limits turns that far"), "{e}");
    }

    #[test]
    fn steps_in_seconds_pass_and_in_milliseconds_are_named() {
        assert_eq!(time_step("0.001"), Ok(0.001));
        assert_eq!(time_step("0.04"), Ok(0.04));
        assert_eq!(time_step("0.1"), Ok(0.1));
        let e = time_step("1").unwrap_err();
        assert!(e.contains("0.001") && e.contains("seconds"), "{e}");
        assert!(time_step("0").is_err() && time_step("nan").is_err());
    }

    #[test]
    fn masses_in_grams_and_offsets_in_millimetres_are_named() {
        let km20 = twinloop_description::builtin::resolve("builtin:km20").unwrap();
        let m = km20.total_mass();
        assert!(total_mass("--total-mass", m * 1.2, &km20).is_ok());
        assert!(total_mass("--total-mass", m * 0.5, &km20).is_ok());
        let e = total_mass("--total-mass", m * 1000.0, &km20).unwrap_err();
        assert!(e.to_string().contains("grams"), "{e}");
        let e = total_mass("--total-mass", m / 1000.0, &km20).unwrap_err();
        assert!(e.to_string().contains("tonnes"), "{e}");
        let link = km20.links[0].name.clone();
        let mut r = km20.clone();
        add_masses(&mut r, &[format!("0.3@{link}:0.05,0,0")]).unwrap();
        assert!((r.total_mass() - m - 0.3).abs() < 1e-12);
        let e = add_masses(&mut km20.clone(), &[format!("300@{link}:0.05,0,0")]).unwrap_err();
        assert!(e.to_string().contains("grams"), "{e}");
        let e = add_masses(&mut km20.clone(), &[format!("0.3@{link}:0,0,50")]).unwrap_err();
        assert!(e.to_string().contains("millimetres"), "{e}");
    }
}
