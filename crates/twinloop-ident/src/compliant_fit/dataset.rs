//! The fit's data: a CoM reference and the recorded CoM (seed 002, section 4).
//!
//! CSV with the columns `t, xr, zr, x, z, phase` (others ignored, any order): time in s,
//! the CoM reference, the recorded CoM (m), and the phase (0 single, 1 double support).
//! The sampling must be uniform (a gap means lost samples: the compact model's error over
//! it would be charged to the parameters). The model starts at the first row's x, z at
//! rest.

use crate::error::{IdentError, err};
use std::path::Path;
use twinloop_reduced::SagittalReference;

/// The columns the fit reads, in the order of [`Dataset::parse`]'s errors.
pub const COLUMNS: [&str; 6] = ["t", "xr", "zr", "x", "z", "phase"];

/// A reference and the CoM recorded along it.
#[derive(Debug, Clone, PartialEq)]
pub struct Dataset {
    pub reference: SagittalReference,
    pub x: Vec<f64>,
    pub z: Vec<f64>,
    /// Where it came from (a path), for messages.
    pub source: String,
}

impl Dataset {
    /// Reads a CSV file; errors name the file, line and column.
    pub fn read(path: &Path) -> Result<Dataset, IdentError> {
        let text = twinloop_io::input::read_to_string(path)
            .map_err(|e| IdentError::new(format!("{}: cannot read: {e}", path.display())))?;
        Dataset::parse(&text, &path.display().to_string())
    }

    /// Parses CSV text (a header, then numbers; blank lines and `#` lines skipped).
    /// Errors name `source`, the 1-based line and the column: a missing column, a cell
    /// that is not a number or is NaN/infinite, a phase other than 0 or 1, time that does
    /// not increase, and a gap (a time step unlike the first one).
    pub fn parse(text: &str, source: &str) -> Result<Dataset, IdentError> {
        let mut lines = text.lines().enumerate().filter(|(_, l)| {
            let l = l.trim();
            !l.is_empty() && !l.starts_with('#')
        });
        let Some((_, header)) = lines.next() else {
            return err(format!(
                "{source}: empty file; expected a header with columns t, xr, zr, x, z, phase"
            ));
        };
        let (ncols, index) = column_index(header, source)?;
        let mut reference = SagittalReference::default();
        let (mut x, mut z) = (Vec::new(), Vec::new());
        let mut first_step = None;
        for (ln, line) in lines {
            let line_no = ln + 1;
            let row = parse_row(line, ncols, &index, source, line_no)?;
            let at = format!("{source}, line {line_no}");
            push_row(row, &at, &mut first_step, &mut reference, (&mut x, &mut z))?;
        }
        finish(reference, x, z, source)
    }

    /// [`Dataset::parse`] of a table read already (an MCAP or a rosbag2 folder,
    /// through twinloop-logs: `x`, `z` and the rest are columns of a
    /// Float64MultiArray): the same columns and checks, a row named by its number.
    pub fn from_table(table: &twinloop_io::Table, source: &str) -> Result<Dataset, IdentError> {
        let (_, index) = column_index(&table.columns.join(","), source)?;
        let mut reference = SagittalReference::default();
        let (mut x, mut z) = (Vec::new(), Vec::new());
        let mut first_step = None;
        for (r, values) in table.rows.iter().enumerate() {
            let at = format!("{source}, data row {}", r + 1);
            let row = index.map(|i| values[i]);
            if let Some(k) = row.iter().position(|v| !v.is_finite()) {
                return err(format!(
                    "{at}, column {}: {} (the data must be finite; drop or repair the sample)",
                    COLUMNS[k], row[k]
                ));
            }
            push_row(row, &at, &mut first_step, &mut reference, (&mut x, &mut z))?;
        }
        finish(reference, x, z, source)
    }

    pub fn len(&self) -> usize {
        self.reference.t.len()
    }

    pub fn is_empty(&self) -> bool {
        self.reference.t.is_empty()
    }

    /// The sampling interval, s.
    pub fn step(&self) -> f64 {
        self.reference.t[1] - self.reference.t[0]
    }

    /// The CSV text of [`Dataset::parse`] (full precision).
    pub fn to_csv(&self) -> String {
        let mut s = String::from("t,xr,zr,x,z,phase\n");
        let r = &self.reference;
        for i in 0..self.len() {
            s += &format!(
                "{:e},{:e},{:e},{:e},{:e},{}\n",
                r.t[i],
                r.xr[i],
                r.zr[i],
                self.x[i],
                self.z[i],
                u8::from(r.double_support[i])
            );
        }
        s
    }
}

/// One row's `t, xr, zr, x, z, phase` after the ones before it (`at` names it).
fn push_row(
    [t, xr, zr, xm, zm, phase]: [f64; 6],
    at: &str,
    first_step: &mut Option<f64>,
    reference: &mut SagittalReference,
    (x, z): (&mut Vec<f64>, &mut Vec<f64>),
) -> Result<(), IdentError> {
    let double = double_support(phase, at)?;
    if let Some(&prev) = reference.t.last() {
        check_step(prev, t, first_step, at)?;
    }
    reference.t.push(t);
    reference.xr.push(xr);
    reference.zr.push(zr);
    reference.double_support.push(double);
    x.push(xm);
    z.push(zm);
    Ok(())
}

/// The dataset, if it has rows enough to fit.
fn finish(
    reference: SagittalReference,
    x: Vec<f64>,
    z: Vec<f64>,
    source: &str,
) -> Result<Dataset, IdentError> {
    if reference.t.len() < 3 {
        return err(format!(
            "{source}: {} data rows; the fit needs at least 3",
            reference.t.len()
        ));
    }
    Ok(Dataset {
        reference,
        x,
        z,
        source: source.to_string(),
    })
}

/// The number of header cells and where each of [`COLUMNS`] is among them.
fn column_index(header: &str, source: &str) -> Result<(usize, [usize; 6]), IdentError> {
    let names: Vec<&str> = header
        .split(',')
        .map(|c| c.trim().trim_matches('"'))
        .collect();
    let mut index = [0usize; 6];
    for (k, want) in COLUMNS.iter().enumerate() {
        index[k] = names.iter().position(|n| n == want).ok_or_else(|| {
            IdentError::new(format!(
                "{source}: no column `{want}` (the fit needs t, xr, zr, x, z, phase; found {})",
                names.join(", ")
            ))
        })?;
    }
    Ok((names.len(), index))
}

/// The finite values of [`COLUMNS`] on one data line of `ncols` cells.
fn parse_row(
    line: &str,
    ncols: usize,
    index: &[usize; 6],
    source: &str,
    line_no: usize,
) -> Result<[f64; 6], IdentError> {
    let cells: Vec<&str> = line.split(',').map(str::trim).collect();
    if cells.len() != ncols {
        return err(format!(
            "{source}, line {line_no}: {} cells, but the header has {}",
            cells.len(),
            ncols
        ));
    }
    let mut row = [0.0; 6];
    for (k, col) in COLUMNS.iter().enumerate() {
        let cell = cells[index[k]];
        let v: f64 = cell.parse().map_err(|_| {
            IdentError::new(format!(
                "{source}, line {line_no}, column {col}: \"{cell}\" is not a number"
            ))
        })?;
        if !v.is_finite() {
            return err(format!(
                "{source}, line {line_no}, column {col}: {cell} (the data must be finite; \
                 drop or repair the sample)"
            ));
        }
        row[k] = v;
    }
    Ok(row)
}

/// The phase cell as double support (1) or single (0); nothing else is a phase.
fn double_support(phase: f64, at: &str) -> Result<bool, IdentError> {
    if phase == 0.0 {
        Ok(false)
    } else if phase == 1.0 {
        Ok(true)
    } else {
        err(format!(
            "{at}, column phase: {phase} (0 = single support, 1 = double)"
        ))
    }
}

/// Time must increase by the first step every row: a gap means lost samples.
fn check_step(prev: f64, t: f64, first_step: &mut Option<f64>, at: &str) -> Result<(), IdentError> {
    let h: f64 = t - prev;
    if h <= 0.0 {
        return err(format!(
            "{at}, column t: time {t} does not increase (previous {prev})"
        ));
    }
    match *first_step {
        None => *first_step = Some(h),
        Some(h0) => {
            if (h - h0).abs() > 1e-6 * h0 {
                return err(format!(
                    "{at}, column t: time step {h} after t = {prev}, \
                     but the sampling interval is {h0}: a gap or jitter (the fit needs uniform sampling)"
                ));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = "# recorded\nt,xr,zr,x,z,phase\n0,0,0.5,0,0.49,1\n0.001,0.001,0.5,0,0.49,1\n\n0.002,0.002,0.5,0.001,0.49,0\n";

    #[test]
    fn reads_columns_in_any_order() {
        let d = Dataset::parse(GOOD, "a.csv").unwrap();
        assert_eq!(d.len(), 3);
        assert_eq!(d.reference.double_support, vec![true, true, false]);
        assert_eq!(d.x[2], 0.001);
        let swapped = "phase,z,x,zr,xr,t,extra\n1,0.49,0,0.5,0,0,7\n1,0.49,0,0.5,0.001,0.001,7\n0,0.49,0.001,0.5,0.002,0.002,7\n";
        let e = Dataset::parse(swapped, "b.csv").unwrap();
        assert_eq!(e.reference, d.reference);
        assert_eq!((e.x.clone(), e.z.clone()), (d.x.clone(), d.z.clone()));
        let back = Dataset::parse(&d.to_csv(), "c.csv").unwrap();
        assert_eq!(back.reference, d.reference);
    }

    #[test]
    fn bad_rows_are_named_by_line_and_column() {
        let cases = [
            (
                GOOD.replace("0.001,0.001,0.5,0,0.49,1", "0.001,NaN,0.5,0,0.49,1"),
                "line 4, column xr",
            ),
            (
                GOOD.replace(
                    "0.002,0.002,0.5,0.001,0.49,0",
                    "0.0035,0.002,0.5,0.001,0.49,0",
                ),
                "line 6, column t: time step",
            ),
            (
                GOOD.replace(
                    "0.002,0.002,0.5,0.001,0.49,0",
                    "0.0005,0.002,0.5,0.001,0.49,0",
                ),
                "line 6, column t: time 0.0005 does not increase",
            ),
            (
                GOOD.replace(
                    "0.002,0.002,0.5,0.001,0.49,0",
                    "0.002,0.002,0.5,0.001,0.49,2",
                ),
                "line 6, column phase",
            ),
            (
                GOOD.replace("0.002,0.002,0.5,0.001,0.49,0", "0.002,0.002,0.5,abc,0.49,0"),
                "line 6, column x: \"abc\"",
            ),
            (
                GOOD.replace("0.001,0.001,0.5,0,0.49,1", "0.001,0.001,0.5,0,inf,1"),
                "line 4, column z",
            ),
            (
                GOOD.replace("t,xr,zr,x,z,phase", "t,xr,zr,x,height,phase"),
                "no column `z`",
            ),
        ];
        for (text, want) in cases {
            let e = Dataset::parse(&text, "walk.csv").unwrap_err();
            assert!(
                e.message.starts_with("walk.csv") && e.message.contains(want),
                "{e} (want {want})"
            );
        }
    }
}
