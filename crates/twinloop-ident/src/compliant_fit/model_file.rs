//! PLANT.toml: m, g and the x-z stiffness and damping at the CoM for the compact model
//! (seed 002, eq 11), given as numbers or computed from a URDF and a configuration by
//! K_C = J^-T K_j J^-1, D_C = J^-T D_j J^-1 (seed 002, eq 7-8).
//!
//! ```toml
//! # either the entries ...
//! m = 32.05
//! g = 9.81
//! Kxx = 57188.0
//! Kxz = 217400.0
//! Kzx = 217400.0
//! Kzz = 916201.0
//! Dxx = 14.53
//! Dxz = -3.33
//! Dzx = -3.33
//! Dzz = 667.4
//!
//! # ... or a URDF (path relative to this file) and a pose; any entry given above then
//! # overrides the computed one (m defaults to the URDF's total mass, g to 9.81)
//! urdf = "../models/coman/coman.urdf"
//! support = "left"          # or "right"
//! knee_bend = 0.5           # flat-footed crouch, rad
//! k_harmonic = 8000.0       # N m/rad
//! k_series = 100.0          # N m/rad, knee and ankle pitch
//! d_stiff = 1.0             # N m s/rad
//! d_compliant = 1.0
//! pelvis = "held"           # x-z block of K_C; "free": x-z stiffness under forces
//!                           # alone (pelvis free to turn; damping stays the block)
//! [q]                       # joint overrides, rad
//! LKneeSag = 0.6
//! ```

use crate::error::{IdentError, err};
use std::path::Path;
use twinloop_dynamics::{Data, Model};
use twinloop_reduced::SagittalCompliance;
use twinloop_reduced::stiffness::{
    JointCompliance, SupportLeg, cartesian_compliance, coman_crouch,
};

const ENTRIES: [&str; 8] = ["Kxx", "Kxz", "Kzx", "Kzz", "Dxx", "Dxz", "Dzx", "Dzz"];
const URDF_KEYS: [&str; 9] = [
    "urdf",
    "pelvis",
    "support",
    "knee_bend",
    "k_harmonic",
    "k_series",
    "d_stiff",
    "d_compliant",
    "q",
];

/// PLANT.toml, or the JSON `twinloop compliant stiffness --json` writes (`mass`,
/// `gravity` and the `sagittal` block's Kxx .. Dzz); errors name the file and the key.
pub fn read_plant(path: &Path) -> Result<SagittalCompliance, IdentError> {
    if path.extension().is_some_and(|e| e == "json") {
        read_plant_json(path)
    } else {
        read_model_file(path)
    }
}

fn read_plant_json(path: &Path) -> Result<SagittalCompliance, IdentError> {
    let at = |m: String| IdentError::new(m).in_file(path);
    let text = twinloop_io::input::read_to_string(path).map_err(|e| at(e.to_string()))?;
    let v: serde_json::Value = serde_json::from_str(&text).map_err(|e| at(e.to_string()))?;
    let get = |key: &str, v: &serde_json::Value| {
        v.get(key)
            .and_then(|x| x.as_f64())
            .ok_or_else(|| at(format!("missing number `{key}`")))
    };
    let s = v
        .get("sagittal")
        .ok_or_else(|| at("missing object `sagittal`".into()))?;
    Ok(SagittalCompliance {
        m: get("mass", &v)?,
        g: get("gravity", &v)?,
        Kxx: get("Kxx", s)?,
        Kxz: get("Kxz", s)?,
        Kzx: get("Kzx", s)?,
        Kzz: get("Kzz", s)?,
        Dxx: get("Dxx", s)?,
        Dxz: get("Dxz", s)?,
        Dzx: get("Dzx", s)?,
        Dzz: get("Dzz", s)?,
    })
}

/// Reads PLANT.toml; errors name the file and the key.
pub fn read_model_file(path: &Path) -> Result<SagittalCompliance, IdentError> {
    let text = twinloop_io::input::read_to_string(path)
        .map_err(|e| IdentError::new(format!("{}: cannot read: {e}", path.display())))?;
    let base = path.parent().unwrap_or(Path::new("."));
    parse_model_file(&text, base).map_err(|e| IdentError::new(format!("{}: {e}", path.display())))
}

/// Parses PLANT.toml text; a relative `urdf` path is taken from `base`.
pub fn parse_model_file(text: &str, base: &Path) -> Result<SagittalCompliance, IdentError> {
    let table: toml::Table = toml::from_str(text).map_err(|e| IdentError::new(e.to_string()))?;
    for key in table.keys() {
        let known = key == "m" || key == "g" || ENTRIES.contains(&key.as_str());
        if !known && !URDF_KEYS.contains(&key.as_str()) {
            return err(format!(
                "unknown key `{key}` (expected m, g, Kxx, Kxz, Kzx, Kzz, Dxx, Dxz, Dzx, Dzz, or urdf with support, pelvis, knee_bend, k_harmonic, k_series, d_stiff, d_compliant, [q])"
            ));
        }
    }
    let number = |key: &str| -> Result<Option<f64>, IdentError> {
        match table.get(key) {
            None => Ok(None),
            Some(toml::Value::Float(v)) => Ok(Some(*v)),
            Some(toml::Value::Integer(v)) => Ok(Some(*v as f64)),
            Some(other) => err(format!(
                "`{key}` must be a number, got a {}",
                other.type_str()
            )),
        }
    };
    let mut plant = match table.get("urdf") {
        Some(toml::Value::String(urdf)) => from_urdf(&table, &base.join(urdf), &number)?,
        Some(other) => {
            return err(format!(
                "`urdf` must be a path string, got a {}",
                other.type_str()
            ));
        }
        None => {
            for key in URDF_KEYS.iter().skip(1) {
                if table.contains_key(*key) {
                    return err(format!("`{key}` needs `urdf`"));
                }
            }
            let mut missing = Vec::new();
            for key in std::iter::once("m").chain(ENTRIES) {
                if number(key)?.is_none() {
                    missing.push(key);
                }
            }
            if !missing.is_empty() {
                return err(format!(
                    "missing {} (give all of m, Kxx, Kxz, Kzx, Kzz, Dxx, Dxz, Dzx, Dzz, or a urdf)",
                    missing.join(", ")
                ));
            }
            SagittalCompliance {
                m: 0.0,
                g: twinloop_description::GRAVITY,
                Kxx: 0.0,
                Kxz: 0.0,
                Kzx: 0.0,
                Kzz: 0.0,
                Dxx: 0.0,
                Dxz: 0.0,
                Dzx: 0.0,
                Dzz: 0.0,
            }
        }
    };
    // Entries given explicitly override the computed ones.
    let slots: [(&str, &mut f64); 10] = [
        ("m", &mut plant.m),
        ("g", &mut plant.g),
        ("Kxx", &mut plant.Kxx),
        ("Kxz", &mut plant.Kxz),
        ("Kzx", &mut plant.Kzx),
        ("Kzz", &mut plant.Kzz),
        ("Dxx", &mut plant.Dxx),
        ("Dxz", &mut plant.Dxz),
        ("Dzx", &mut plant.Dzx),
        ("Dzz", &mut plant.Dzz),
    ];
    for (key, slot) in slots {
        if let Some(v) = number(key)? {
            *slot = v;
        }
    }
    check_plant(&plant)?;
    Ok(plant)
}

/// The checks of [`SagittalCompliance::validate`] plus the one the dynamics need: the
/// x-z stiffness must be positive definite (else the CoM has no stable rest).
pub fn check_plant(p: &SagittalCompliance) -> Result<(), IdentError> {
    p.validate()?;
    if p.g.is_nan() || p.g <= 0.0 {
        return err(format!("gravity g must be positive, got {}", p.g));
    }
    // Positive definite symmetric part: Kxx > 0 (checked) and a positive determinant.
    let kxz = 0.5 * (p.Kxz + p.Kzx);
    let det = p.Kxx * p.Kzz - kxz * kxz;
    if det.is_nan() || det <= 0.0 {
        return err(format!(
            "the stiffness [[Kxx, Kxz], [Kzx, Kzz]] = [[{}, {}], [{}, {}]] is not positive definite \
             (det of its symmetric part {det:e} <= 0): the CoM would have no stable rest",
            p.Kxx, p.Kxz, p.Kzx, p.Kzz
        ));
    }
    Ok(())
}

fn from_urdf(
    table: &toml::Table,
    urdf: &Path,
    number: &dyn Fn(&str) -> Result<Option<f64>, IdentError>,
) -> Result<SagittalCompliance, IdentError> {
    let robot = twinloop_description::load(urdf)
        .map_err(|e| IdentError::new(format!("urdf {}: {e}", urdf.display())))?;
    let model = Model::from_description(&robot)
        .map_err(|e| IdentError::new(format!("urdf {}: {e}", urdf.display())))?;
    let left = match table.get("support") {
        None => true,
        Some(toml::Value::String(s)) if s == "left" => true,
        Some(toml::Value::String(s)) if s == "right" => false,
        Some(other) => {
            return err(format!(
                "`support` must be \"left\" or \"right\", got a {}",
                other.type_str()
            ));
        }
    };
    let mut q = coman_crouch(&model, number("knee_bend")?.unwrap_or(0.5))?;
    match table.get("q") {
        None => {}
        Some(toml::Value::Table(joints)) => {
            for (name, v) in joints {
                let Some(i) = model.joint_index(name) else {
                    return err(format!("[q] {name}: the model has no joint named {name}"));
                };
                let v = match v {
                    toml::Value::Float(v) => *v,
                    toml::Value::Integer(v) => *v as f64,
                    other => {
                        return err(format!(
                            "[q] {name} must be a number, got a {}",
                            other.type_str()
                        ));
                    }
                };
                q[model.q_offset + i] = v;
            }
        }
        Some(other) => {
            return err(format!(
                "`q` must be a table of joint = rad, got a {}",
                other.type_str()
            ));
        }
    }
    let defaults = JointCompliance::default();
    let joints = JointCompliance {
        k_harmonic: number("k_harmonic")?.unwrap_or(defaults.k_harmonic),
        k_series: number("k_series")?.unwrap_or(defaults.k_series),
        d_stiff: number("d_stiff")?.unwrap_or(defaults.d_stiff),
        d_compliant: number("d_compliant")?.unwrap_or(defaults.d_compliant),
        ..defaults
    };
    let mut data = Data::new(&model);
    let cc = cartesian_compliance(&model, &mut data, &q, &SupportLeg::coman(left), &joints)?;
    let k = match table.get("pelvis") {
        None => cc.stiffness_xz(),
        Some(toml::Value::String(s)) if s == "held" => cc.stiffness_xz(),
        Some(toml::Value::String(s)) if s == "free" => cc.stiffness_xz_force_only().ok_or_else(|| {
            IdentError::new("the x-z stiffness under forces alone does not exist here (singular rotational block)")
        })?,
        Some(other) => {
            return err(format!(
                "`pelvis` must be \"held\" or \"free\", got a {}",
                other.type_str()
            ));
        }
    };
    Ok(SagittalCompliance::from_xz(
        model.total_mass,
        twinloop_description::GRAVITY,
        &k,
        &cc.damping_xz(),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    const ENTRIES_TOML: &str = "m = 32.05\ng = 9.81\nKxx = 57188.0\nKxz = 217400.0\nKzx = 217400.0\nKzz = 916201\nDxx = 14.53\nDxz = -3.33\nDzx = -3.33\nDzz = 667.4\n";

    fn models_dir() -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/coman")
    }

    #[test]
    fn entries_are_read_and_bad_ones_named() {
        let p = parse_model_file(ENTRIES_TOML, Path::new(".")).unwrap();
        assert_eq!((p.m, p.Kzz, p.Dxz), (32.05, 916201.0, -3.33));
        let cases = [
            (ENTRIES_TOML.replace("Kzz = 916201", "Kzz = -5"), "Kzz"),
            (ENTRIES_TOML.replace("Kxx = 57188.0", "Kxx = 0.0"), "Kxx"),
            (
                ENTRIES_TOML.replace("Kxz = 217400.0", "Kxz = 917400.0"),
                "not positive definite",
            ),
            (ENTRIES_TOML.replace("Dzx = -3.33\n", ""), "missing Dzx"),
            (
                ENTRIES_TOML.replace("m = 32.05", "m = \"heavy\""),
                "`m` must be a number",
            ),
            (ENTRIES_TOML.to_string() + "Kyy = 3\n", "unknown key `Kyy`"),
        ];
        for (text, want) in cases {
            let e = parse_model_file(&text, Path::new(".")).unwrap_err();
            assert!(e.message.contains(want), "{e} (want {want})");
        }
    }

    #[test]
    fn urdf_gives_the_cartesian_compliance_and_a_stretched_knee_is_named() {
        let text = "urdf = \"coman.urdf\"\nsupport = \"left\"\nknee_bend = 0.5\nDxx = 20.0\n";
        let p = parse_model_file(text, &models_dir()).unwrap();
        // Independent: the same numbers straight from stiffness.rs (eq 7-8).
        let robot = twinloop_description::load(models_dir().join("coman.urdf")).unwrap();
        let model = Model::from_description(&robot).unwrap();
        let q = coman_crouch(&model, 0.5).unwrap();
        let mut data = Data::new(&model);
        let cc = cartesian_compliance(
            &model,
            &mut data,
            &q,
            &SupportLeg::coman(true),
            &JointCompliance::default(),
        )
        .unwrap();
        let k = cc.stiffness_xz();
        assert_eq!((p.Kxx, p.Kxz, p.Kzz), (k[(0, 0)], k[(0, 1)], k[(1, 1)]));
        assert_eq!(p.Dxx, 20.0, "explicit entries override");
        assert!((p.m - model.total_mass).abs() < 1e-12);
        let stretched = "urdf = \"coman.urdf\"\nknee_bend = 0.5\n[q]\nLKneeSag = 0.0\nLHipSag = 0.0\nLAnkSag = 0.0\n";
        let e = parse_model_file(stretched, &models_dir()).unwrap_err();
        assert!(
            e.message.contains("singular") && e.message.contains("knee"),
            "{e}"
        );
        let free =
            parse_model_file("urdf = \"coman.urdf\"\npelvis = \"free\"\n", &models_dir()).unwrap();
        let soft = cc.stiffness_xz_force_only().unwrap();
        assert_eq!((free.Kxx, free.Kzz), (soft[(0, 0)], soft[(1, 1)]));
        let e = parse_model_file("urdf = \"nope.urdf\"\n", &models_dir()).unwrap_err();
        assert!(e.message.contains("nope.urdf"), "{e}");
    }
}
