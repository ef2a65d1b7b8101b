//! Static-pose data (docs/architecture.md, "Data files"): one row per pose, the configuration
//! columns `q:base.x .. q:base.qw`, `q:<joint>` and the measured centre of pressure
//! `cop.x`, `cop.y` (world frame, metres). An optional `category` column holds the
//! seed's pose category (1-6, [`PoseCategory`]).

use crate::error::IdentError;
use std::path::Path;
use twinloop_dynamics::Model;
use twinloop_io::{CsvWriter, Quantity, StateColumns, Table};

/// The six pose categories of seed 004, section 3.1 (numbered as in the seed).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum PoseCategory {
    /// 1. Double support, feet 2 cm apart, focus on an arm.
    Arm = 1,
    /// 2. Single support on the left foot, focus on the right leg.
    LeftSupport = 2,
    /// 3. Single support on the right foot, focus on the left leg.
    RightSupport = 3,
    /// 4. Double support, feet 2 cm apart, focus on the torso joints.
    Torso = 4,
    /// 5. Double support, feet 2 cm apart, crouching.
    Crouch = 5,
    /// 6. Double support, feet 20 cm apart (wide stance).
    Wide = 6,
}

impl PoseCategory {
    pub const ALL: [PoseCategory; 6] = [
        PoseCategory::Arm,
        PoseCategory::LeftSupport,
        PoseCategory::RightSupport,
        PoseCategory::Torso,
        PoseCategory::Crouch,
        PoseCategory::Wide,
    ];

    /// The name used on the command line and in JSON.
    pub fn name(self) -> &'static str {
        match self {
            PoseCategory::Arm => "arm",
            PoseCategory::LeftSupport => "left",
            PoseCategory::RightSupport => "right",
            PoseCategory::Torso => "torso",
            PoseCategory::Crouch => "crouch",
            PoseCategory::Wide => "wide",
        }
    }

    pub fn from_name(s: &str) -> Option<PoseCategory> {
        PoseCategory::ALL.into_iter().find(|c| c.name() == s)
    }

    pub fn from_number(n: f64) -> Option<PoseCategory> {
        PoseCategory::ALL
            .into_iter()
            .find(|c| *c as i32 as f64 == n)
    }

    /// Standing on both feet?
    pub fn double_support(self) -> bool {
        !matches!(self, PoseCategory::LeftSupport | PoseCategory::RightSupport)
    }
}

/// One static pose: the configuration (model order, floating base first) and the
/// centre of pressure the force plate measured.
#[derive(Debug, Clone, PartialEq)]
pub struct StaticPose {
    pub q: Vec<f64>,
    pub cop: [f64; 2],
    pub category: Option<PoseCategory>,
}

/// Column names of a static-pose file for `model`: `category`, `q:*`, `cop.x`, `cop.y`.
pub fn pose_columns(model: &Model) -> Vec<String> {
    let mut cols = vec!["category".to_string()];
    cols.extend(Quantity::Q.column_names(&model.q_names()));
    cols.push("cop.x".into());
    cols.push("cop.y".into());
    cols
}

/// Write poses as CSV (numbers at full precision).
pub fn write_static_poses(
    path: &Path,
    model: &Model,
    poses: &[StaticPose],
) -> Result<(), IdentError> {
    let cols = pose_columns(model);
    let mut w = CsvWriter::create(path, &cols)?;
    let mut row = Vec::with_capacity(cols.len());
    for p in poses {
        row.clear();
        row.push(p.category.map_or(0.0, |c| c as i32 as f64));
        row.extend_from_slice(&p.q);
        row.extend_from_slice(&p.cop);
        w.write_row(&row)?;
    }
    w.finish()?;
    Ok(())
}

/// Read a static-pose file for `model`. Errors name the file, the data row and
/// the column: a column `q:<name>` that is not a coordinate of the model, a missing
/// coordinate or `cop` column, a cell that is NaN or infinite, a base quaternion
/// that is not of unit norm, a category outside 1-6.
pub fn read_static_poses(path: &Path, model: &Model) -> Result<Vec<StaticPose>, IdentError> {
    let table = Table::read(path)?;
    parse_static_poses(&table, model).map_err(
        |e| {
            if e.file.is_none() { e.in_file(path) } else { e }
        },
    )
}

/// [`read_static_poses`] on a table already read.
pub fn parse_static_poses(table: &Table, model: &Model) -> Result<Vec<StaticPose>, IdentError> {
    if !model.is_floating() {
        return Err(IdentError::new(
            "static poses need a floating-base model (the robot stands on a force plate)",
        ));
    }
    let known = Quantity::Q.column_names(&model.q_names());
    for c in &table.columns {
        if c.starts_with("q:") && !known.iter().any(|k| k == c) {
            let name = &c[2..];
            return Err(IdentError::new(format!(
                "\"{name}\" is not a joint of the model \"{}\" (its {} joints: {}{})",
                model.name,
                model.joint_names.len(),
                model
                    .joint_names
                    .iter()
                    .take(6)
                    .cloned()
                    .collect::<Vec<_>>()
                    .join(", "),
                if model.joint_names.len() > 6 {
                    ", ..."
                } else {
                    ""
                }
            ))
            .field(c.clone()));
        }
    }
    let qc = StateColumns::find(table, Quantity::Q, &model.q_names())?;
    let col = |name: &str| {
        table.column_index(name).ok_or_else(|| {
            IdentError::new("the measured centre of pressure is needed (world frame, metres)")
                .field(name)
        })
    };
    let (cx, cy) = (col("cop.x")?, col("cop.y")?);
    let cat = table.column_index("category");
    let mut out = Vec::with_capacity(table.rows.len());
    for (r, row) in table.rows.iter().enumerate() {
        for (k, x) in row.iter().enumerate() {
            if !x.is_finite() {
                return Err(IdentError::new(format!(
                    "{x} is not a finite number: every cell of a pose must be measured"
                ))
                .at_row(r)
                .field(table.columns[k].clone()));
            }
        }
        let mut q = vec![0.0; model.nq];
        qc.gather(row, &mut q);
        let n = (q[3] * q[3] + q[4] * q[4] + q[5] * q[5] + q[6] * q[6]).sqrt();
        if (n - 1.0).abs() > 1e-6 {
            return Err(IdentError::new(format!(
                "the base quaternion (q:base.qx .. q:base.qw) has norm {n}, not 1"
            ))
            .at_row(r)
            .field("q:base.qw"));
        }
        let category = match cat {
            None => None,
            Some(k) if row[k] == 0.0 => None,
            Some(k) => Some(PoseCategory::from_number(row[k]).ok_or_else(|| {
                IdentError::new(format!(
                    "{} is not a pose category (1-6, or 0 for none)",
                    row[k]
                ))
                .at_row(r)
                .field("category")
            })?),
        };
        out.push(StaticPose {
            q,
            cop: [row[cx], row[cy]],
            category,
        });
    }
    if out.is_empty() {
        return Err(IdentError::new("the file has a header but no pose rows"));
    }
    Ok(out)
}

impl serde::Serialize for PoseCategory {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}
