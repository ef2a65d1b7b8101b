//! Input/output records: the u and y sequences an identification works on.

use crate::error::{Result, SysidError};
use nalgebra::DMatrix;

/// Fewest samples a record may hold (a channel must be able to vary).
pub const MIN_SAMPLES: usize = 2;

/// A record of `N` samples of `nu` inputs and `ny` outputs, equally spaced.
///
/// Stored one sample per column (`u` is `nu x N`, `y` is `ny x N`) so that the
/// recursions, which walk through time, read contiguous memory.
#[derive(Debug, Clone, PartialEq)]
pub struct IoData {
    pub input_names: Vec<String>,
    pub output_names: Vec<String>,
    /// Inputs, `nu x N`.
    pub u: DMatrix<f64>,
    /// Outputs, `ny x N`.
    pub y: DMatrix<f64>,
    /// Sampling period in seconds, when known (frequencies are then in rad/s,
    /// otherwise in rad/sample).
    pub sample_time: Option<f64>,
}

impl IoData {
    /// A record from sample-major rows: `u[k]` holds the `nu` inputs of sample `k`,
    /// `y[k]` its `ny` outputs. Every value must be finite; rows must have as many
    /// values as names. Errors name the data row (1-based) and the channel.
    pub fn from_samples(
        input_names: Vec<String>,
        output_names: Vec<String>,
        u: &[Vec<f64>],
        y: &[Vec<f64>],
        sample_time: Option<f64>,
    ) -> Result<IoData> {
        let (nu, ny) = (input_names.len(), output_names.len());
        if u.len() != y.len() {
            return Err(SysidError::data(format!(
                "{} input samples but {} output samples",
                u.len(),
                y.len()
            )));
        }
        let n = u.len();
        let mut um = DMatrix::zeros(nu, n);
        let mut ym = DMatrix::zeros(ny, n);
        for k in 0..n {
            if u[k].len() != nu {
                return Err(SysidError::data(format!(
                    "data row {}: {} input values for {} input names",
                    k + 1,
                    u[k].len(),
                    nu
                ))
                .at_row(k + 1));
            }
            if y[k].len() != ny {
                return Err(SysidError::data(format!(
                    "data row {}: {} output values for {} output names",
                    k + 1,
                    y[k].len(),
                    ny
                ))
                .at_row(k + 1));
            }
            um.column_mut(k).copy_from_slice(&u[k]);
            ym.column_mut(k).copy_from_slice(&y[k]);
        }
        IoData::new(input_names, output_names, um, ym, sample_time)
    }

    /// A record from channel-major matrices (`u`: `nu x N`, `y`: `ny x N`).
    pub fn new(
        input_names: Vec<String>,
        output_names: Vec<String>,
        u: DMatrix<f64>,
        y: DMatrix<f64>,
        sample_time: Option<f64>,
    ) -> Result<IoData> {
        if u.nrows() != input_names.len() || y.nrows() != output_names.len() {
            return Err(SysidError::data(format!(
                "{} input names for {} input rows, {} output names for {} output rows",
                input_names.len(),
                u.nrows(),
                output_names.len(),
                y.nrows()
            )));
        }
        if u.ncols() != y.ncols() {
            return Err(SysidError::data(format!(
                "{} input samples but {} output samples",
                u.ncols(),
                y.ncols()
            )));
        }
        if output_names.is_empty() {
            return Err(SysidError::data("no output channel: name at least one"));
        }
        // Fewer than two samples cannot vary, and every estimator indexes the first
        // sample: refused here so that no caller (CLI, Python, a library user) panics.
        if u.ncols() < MIN_SAMPLES {
            return Err(SysidError::data(format!(
                "{} samples: an identification needs a record of at least {MIN_SAMPLES}",
                u.ncols()
            )));
        }
        if let Some(ts) = sample_time
            && !(ts.is_finite() && ts > 0.0)
        {
            return Err(SysidError::data(format!(
                "sample time {ts} s: must be a positive number"
            )));
        }
        for (names, m, what) in [(&input_names, &u, "input"), (&output_names, &y, "output")] {
            for k in 0..m.ncols() {
                for (i, name) in names.iter().enumerate() {
                    let x = m[(i, k)];
                    if !x.is_finite() {
                        return Err(SysidError::data(format!(
                            "data row {}, {what} \"{name}\": {x} is not a finite number; \
                             remove the row or fill the gap before identifying",
                            k + 1
                        ))
                        .at_row(k + 1));
                    }
                }
            }
        }
        Ok(IoData {
            input_names,
            output_names,
            u,
            y,
            sample_time,
        })
    }

    /// [`IoData::from_table`] on a table read from a CSV file: an error about a
    /// data row also names the file and its line (`walk.csv:43: data row 42, ...`).
    pub fn from_io_table(
        table: &twinloop_io::Table,
        inputs: &[String],
        outputs: &[String],
    ) -> Result<IoData> {
        IoData::from_table(&table.columns, &table.rows, inputs, outputs).map_err(|mut e| {
            let line = e.row.and_then(|r| table.line_of_row(r - 1));
            e.place = match (&table.path, line) {
                (Some(p), Some(l)) => Some(format!("{}:{l}", p.display())),
                (Some(p), None) => Some(p.display().to_string()),
                (None, Some(l)) => Some(format!("line {l}")),
                (None, None) => None,
            };
            e
        })
    }

    /// Pick named input and output columns from a numeric table (`columns` is the
    /// header, `rows` the data rows), e.g. a `twinloop_io::Table`. A name ending
    /// in `*` selects every column starting with what precedes it, in table order.
    /// The sample time is taken from a `t` column when it is present and uniform.
    pub fn from_table(
        columns: &[String],
        rows: &[Vec<f64>],
        inputs: &[String],
        outputs: &[String],
    ) -> Result<IoData> {
        let pick = |names: &[String], what: &str| -> Result<Vec<usize>> {
            let mut idx = Vec::new();
            for n in names {
                if let Some(prefix) = n.strip_suffix('*') {
                    let before = idx.len();
                    for (i, c) in columns.iter().enumerate() {
                        if c.starts_with(prefix) && !idx.contains(&i) {
                            idx.push(i);
                        }
                    }
                    if idx.len() == before {
                        return Err(SysidError::data(format!(
                            "no {what} column matches \"{n}\" (columns: {})",
                            columns.join(", ")
                        )));
                    }
                } else {
                    match columns.iter().position(|c| c == n) {
                        Some(i) => idx.push(i),
                        None => {
                            return Err(SysidError::data(format!(
                                "no column named \"{n}\" for the {what}s (columns: {})",
                                columns.join(", ")
                            )));
                        }
                    }
                }
            }
            Ok(idx)
        };
        let ui = pick(inputs, "input")?;
        let yi = pick(outputs, "output")?;
        for i in &ui {
            if yi.contains(i) {
                return Err(SysidError::data(format!(
                    "column \"{}\" is both an input and an output",
                    columns[*i]
                )));
            }
        }
        let n = rows.len();
        let mut u = DMatrix::zeros(ui.len(), n);
        let mut y = DMatrix::zeros(yi.len(), n);
        for (k, r) in rows.iter().enumerate() {
            if r.len() != columns.len() {
                return Err(SysidError::data(format!(
                    "data row {}: {} cells, but the header has {}",
                    k + 1,
                    r.len(),
                    columns.len()
                ))
                .at_row(k + 1));
            }
            for (j, &c) in ui.iter().enumerate() {
                u[(j, k)] = r[c];
            }
            for (j, &c) in yi.iter().enumerate() {
                y[(j, k)] = r[c];
            }
        }
        let t_col = columns.iter().position(|c| c == "t");
        if let Some(t) = t_col {
            no_missing_rows(rows.iter().map(|r| r[t]))?;
        }
        let sample_time = t_col.and_then(|t| uniform_step(rows.iter().map(|r| r[t])));
        let names = |idx: &[usize]| idx.iter().map(|&i| columns[i].clone()).collect();
        IoData::new(names(&ui), names(&yi), u, y, sample_time)
    }

    pub fn len(&self) -> usize {
        self.u.ncols()
    }

    pub fn is_empty(&self) -> bool {
        self.u.ncols() == 0
    }

    pub fn nu(&self) -> usize {
        self.u.nrows()
    }

    pub fn ny(&self) -> usize {
        self.y.nrows()
    }

    /// Error unless every input and output varies: a constant channel carries no
    /// information about the dynamics (and makes the regressors rank-deficient).
    pub fn check_excitation(&self) -> Result<()> {
        // The fields are public: a record shortened after construction is refused
        // here too rather than indexed out of bounds.
        if self.len() < MIN_SAMPLES {
            return Err(SysidError::data(format!(
                "{} samples: an identification needs a record of at least {MIN_SAMPLES}",
                self.len()
            )));
        }
        for (names, m, what, advice) in [
            (
                &self.input_names,
                &self.u,
                "input",
                "remove it from the inputs or excite it",
            ),
            (
                &self.output_names,
                &self.y,
                "output",
                "a model of a constant needs no identification; remove it from the outputs",
            ),
        ] {
            for (i, name) in names.iter().enumerate() {
                let row = m.row(i);
                let first = row[0];
                let scale = row.iter().fold(0.0f64, |a, x| a.max(x.abs())).max(1e-300);
                if row.iter().all(|x| (x - first).abs() <= 1e-12 * scale) {
                    return Err(SysidError::data(format!(
                        "{what} \"{name}\" is constant ({first}) over all {} samples: {advice}",
                        m.ncols()
                    )));
                }
            }
        }
        Ok(())
    }

    /// Check that another record has the same channels (e.g. validation data).
    pub fn check_same_channels(&self, other: &IoData) -> Result<()> {
        if self.input_names != other.input_names || self.output_names != other.output_names {
            return Err(SysidError::data(format!(
                "the records' channels differ: inputs {:?} / outputs {:?} vs inputs {:?} / outputs {:?}",
                self.input_names, self.output_names, other.input_names, other.output_names
            )));
        }
        Ok(())
    }

    /// Subtract the given input and output offsets from every sample.
    pub fn remove_offsets(&mut self, u0: &[f64], y0: &[f64]) {
        for mut col in self.u.column_iter_mut() {
            for (x, o) in col.iter_mut().zip(u0) {
                *x -= o;
            }
        }
        for mut col in self.y.column_iter_mut() {
            for (x, o) in col.iter_mut().zip(y0) {
                *x -= o;
            }
        }
    }

    /// Mean of every input and output over the record.
    pub fn means(&self) -> (Vec<f64>, Vec<f64>) {
        let n = self.len().max(1) as f64;
        let mean = |m: &DMatrix<f64>| (0..m.nrows()).map(|i| m.row(i).sum() / n).collect();
        (mean(&self.u), mean(&self.y))
    }
}

/// Refuse a record whose time column jumps: a step over 10 times the record's median
/// step is rows missing (a gap, a pause of the logger), and the models here take row k-1
/// as the sample before row k, so they would be fitted across it. A bus recording's
/// jitter is taken: on a loaded machine its steps reach 5 times the median (a
/// `link record` of the served km20 here).
fn no_missing_rows(t: impl Iterator<Item = f64>) -> Result<()> {
    let t: Vec<f64> = t.collect();
    let mut steps: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    if steps.len() < 2 {
        return Ok(());
    }
    steps.sort_by(f64::total_cmp);
    let median = steps[steps.len() / 2];
    if let Some(k) = t
        .windows(2)
        .position(|w| w[1] - w[0] > 10.0 * median && median > 0.0)
    {
        return Err(SysidError::data(format!(
            "column \"t\": {} s after {} s, where the rows are {} s apart: rows are missing, \
             and the identification takes the rows as equally spaced samples; \
             identify each stretch on its own, or resample the record onto one step",
            to_ns(t[k + 1]),
            to_ns(t[k]),
            to_ns(median)
        ))
        .at_row(k + 2));
    }
    Ok(())
}

/// A time rounded to the nanosecond, as the tables write it (`0.01`, not
/// `0.010000000000000009`).
fn to_ns(t: f64) -> f64 {
    (t * 1e9).round() / 1e9
}

/// The step of an increasing, uniformly spaced sequence (relative spread below
/// 1e-6), else `None`.
fn uniform_step(t: impl Iterator<Item = f64>) -> Option<f64> {
    let t: Vec<f64> = t.collect();
    if t.len() < 2 {
        return None;
    }
    let dt = (t[t.len() - 1] - t[0]) / (t.len() - 1) as f64;
    if !(dt.is_finite() && dt > 0.0) {
        return None;
    }
    let uniform = t
        .windows(2)
        .all(|w| ((w[1] - w[0]) - dt).abs() <= 1e-6 * dt.max(1e-300));
    uniform.then_some(dt)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::ErrorKind;

    fn names(p: &str, n: usize) -> Vec<String> {
        (1..=n).map(|i| format!("{p}{i}")).collect()
    }

    #[test]
    fn nan_names_row_and_channel() {
        let u = vec![vec![1.0], vec![2.0], vec![f64::NAN]];
        let y = vec![vec![1.0], vec![2.0], vec![3.0]];
        let e = IoData::from_samples(names("u", 1), names("y", 1), &u, &y, None).unwrap_err();
        assert!(e.message.contains("data row 3"), "{e}");
        assert!(e.message.contains("\"u1\""), "{e}");
    }

    #[test]
    fn too_few_samples_are_refused_not_indexed() {
        for n in [0, 1] {
            let u = vec![vec![1.0]; n];
            let y = vec![vec![2.0]; n];
            let e = IoData::from_samples(names("u", 1), names("y", 1), &u, &y, None).unwrap_err();
            assert_eq!(e.kind, ErrorKind::Data);
            assert!(e.message.starts_with(&format!("{n} samples")), "{e}");
            assert!(e.message.contains("at least 2"), "{e}");
        }
        // A record emptied after construction (the fields are public) is an error too.
        let u: Vec<Vec<f64>> = (0..3).map(|k| vec![k as f64]).collect();
        let mut d = IoData::from_samples(names("u", 1), names("y", 1), &u, &u, None).unwrap();
        d.u = DMatrix::zeros(1, 0);
        d.y = DMatrix::zeros(1, 0);
        assert!(
            d.check_excitation()
                .unwrap_err()
                .message
                .contains("0 samples")
        );
    }

    #[test]
    fn constant_input_is_named() {
        let u = vec![vec![1.0, 0.5]; 5];
        let y: Vec<Vec<f64>> = (0..5).map(|k| vec![k as f64]).collect();
        let mut u2 = u.clone();
        for (k, r) in u2.iter_mut().enumerate() {
            r[0] = k as f64;
        }
        let d = IoData::from_samples(names("u", 2), names("y", 1), &u2, &y, None).unwrap();
        let e = d.check_excitation().unwrap_err();
        assert!(e.message.contains("input \"u2\" is constant"), "{e}");
    }

    #[test]
    fn table_selection_and_sample_time() {
        let cols: Vec<String> = ["t", "u:a", "u:b", "y:x"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        let rows: Vec<Vec<f64>> = (0..4)
            .map(|k| vec![0.02 * k as f64, k as f64, -(k as f64), 2.0 * k as f64])
            .collect();
        let d = IoData::from_table(&cols, &rows, &["u:*".into()], &["y:x".into()]).unwrap();
        assert_eq!(d.input_names, vec!["u:a", "u:b"]);
        assert!((d.sample_time.unwrap() - 0.02).abs() < 1e-15);
        let e = IoData::from_table(&cols, &rows, &["u:c".into()], &["y:x".into()]).unwrap_err();
        assert!(e.message.contains("\"u:c\""), "{e}");
    }

    #[test]
    fn a_bad_row_read_from_a_file_names_its_line() {
        // Line 1 header, line 2 a comment, line 3 blank: data row 2 is on line 5.
        let text = "t,u:a,y:x\n# recorded on the bench\n\n0,1,2\n0.1,NaN,3\n0.2,2,4\n";
        let mut table = twinloop_io::Table::parse(text).unwrap();
        table.path = Some("walk.csv".into());
        let e = IoData::from_io_table(&table, &["u:a".into()], &["y:x".into()]).unwrap_err();
        assert_eq!(e.row, Some(2));
        assert!(
            e.to_string().starts_with("walk.csv:5: data row 2, input"),
            "{e}"
        );
    }
}
