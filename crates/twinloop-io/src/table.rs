use crate::output::{AtomicFile, Output};
use std::fmt;
use std::io::Write;
use std::path::{Path, PathBuf};

/// An error in a data file: names the file, the line and the column at fault.
#[derive(Debug, Clone, PartialEq)]
pub struct IoError {
    pub file: Option<PathBuf>,
    pub line: Option<usize>,
    pub column: Option<String>,
    pub message: String,
}

impl IoError {
    pub fn new(message: impl Into<String>) -> Self {
        IoError {
            file: None,
            line: None,
            column: None,
            message: message.into(),
        }
    }

    pub fn in_file(mut self, file: impl Into<PathBuf>) -> Self {
        self.file = Some(file.into());
        self
    }
}

impl fmt::Display for IoError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(p) = &self.file {
            write!(f, "{}", p.display())?;
            if let Some(l) = self.line {
                write!(f, ":{l}")?;
            }
            write!(f, ": ")?;
        } else if let Some(l) = self.line {
            write!(f, "line {l}: ")?;
        }
        if let Some(c) = &self.column {
            write!(f, "column \"{c}\": ")?;
        }
        write!(f, "{}", self.message)
    }
}

impl std::error::Error for IoError {}

/// The units a time column's header may name (`t[ms]`), with how many make a second
/// (a division by 1000 gives 3699 ms as the double nearest 3.699 s; a product with
/// 1e-3 may not).
const TIME_UNITS: [(&str, f64); 3] = [("s", 1.0), ("ms", 1e3), ("us", 1e6)];

/// A numeric table with named columns.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Table {
    pub path: Option<PathBuf>,
    pub columns: Vec<String>,
    pub rows: Vec<Vec<f64>>,
    /// The 1-based file line of each data row, when the table was read from text
    /// (empty for a table built in memory), so an error about row `r` can name its line.
    pub lines: Vec<usize>,
}

impl Table {
    pub fn new(columns: Vec<String>) -> Self {
        Table {
            path: None,
            columns,
            rows: Vec::new(),
            lines: Vec::new(),
        }
    }

    pub fn read(path: impl AsRef<Path>) -> Result<Table, IoError> {
        let path = path.as_ref();
        let text = crate::input::read_text(path)?;
        let mut t = Table::parse(&text).map_err(|e| e.in_file(path))?;
        t.path = Some(path.to_path_buf());
        Ok(t)
    }

    /// Parse CSV text: a header row, then rows of numbers (empty lines and lines
    /// starting with `#` are skipped). Every row must have as many cells as the header.
    pub fn parse(text: &str) -> Result<Table, IoError> {
        // A UTF-8 byte order mark (spreadsheets on Windows write one) is not part of
        // the first column's name.
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let mut lines = text.lines().enumerate().filter(|(_, l)| {
            let l = l.trim();
            !l.is_empty() && !l.starts_with('#')
        });
        let Some((hl, header)) = lines.next() else {
            return Err(IoError::new("the file is empty: a header row is needed"));
        };
        let (columns, time_scale) = read_header(header, hl)?;
        let mut rows = Vec::new();
        let mut row_lines = Vec::new();
        for (ln, line) in lines {
            let mut row = Vec::with_capacity(columns.len());
            for (k, cell) in line.split(',').enumerate() {
                let Some(name) = columns.get(k) else {
                    return Err(IoError {
                        line: Some(ln + 1),
                        ..IoError::new(format!(
                            "{} cells or more, but the header has {}",
                            k + 1,
                            columns.len()
                        ))
                    });
                };
                let cell = cell.trim();
                let x: f64 = cell.parse().map_err(|_| IoError {
                    line: Some(ln + 1),
                    column: Some(name.clone()),
                    ..IoError::new(format!("\"{cell}\" is not a number"))
                })?;
                row.push(x);
            }
            if row.len() != columns.len() {
                return Err(IoError {
                    line: Some(ln + 1),
                    ..IoError::new(format!(
                        "{} cells, but the header has {}",
                        row.len(),
                        columns.len()
                    ))
                });
            }
            if let Some((k, per_second)) = time_scale {
                row[k] /= per_second;
            }
            rows.push(row);
            row_lines.push(ln + 1);
        }
        if rows.is_empty() {
            return Err(IoError {
                line: Some(hl + 1),
                ..IoError::new("no data rows, only the header: there is nothing to read")
            });
        }
        let table = Table {
            path: None,
            columns,
            rows,
            lines: row_lines,
        };
        table.check_time()?;
        if time_scale.is_none() {
            table.check_seconds()?;
        }
        Ok(table)
    }

    /// A bare `t` column is seconds; one that looks like milliseconds (a logger's
    /// `millis()`, a spreadsheet's ms) would make a 10 ms step 10 s, and every rate,
    /// derivative and goal 1000x off without a word (issue 29, class 3). The evidence,
    /// over the median step between rows (robot records run at 1 Hz or faster):
    /// whole-number times a step of 10 or more apart; or, over 10 rows or more,
    /// whole-number times 2 or more apart (500 Hz in ms), 1 apart over more than an
    /// hour (1 kHz in ms; a shorter run 1 apart is as likely whole seconds: static
    /// poses a second apart), a step of 5 or more, or a record spanning over an hour at
    /// steps under a second. Such a file is refused,
    /// naming the column and the evidence; `t[ms]` or `t[s]` in the header says which.
    fn check_seconds(&self) -> Result<(), IoError> {
        let Some(tc) = self.column_index("t") else {
            return Ok(());
        };
        let n = self.rows.len();
        if n < 3 {
            return Ok(());
        }
        let t: Vec<f64> = self.rows.iter().map(|r| r[tc]).collect();
        let mut steps: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
        steps.sort_by(f64::total_cmp);
        let step = steps[steps.len() / 2];
        let whole = t.iter().all(|x| x.fract() == 0.0);
        let span = t[n - 1] - t[0];
        let evidence = if whole && step >= 10.0 {
            format!("every time a whole number, {} apart", clean_time(step))
        } else if n >= 10 && whole && (step >= 2.0 || (step >= 1.0 && span > 3600.0)) {
            format!(
                "every time a whole number, {} apart over {n} rows",
                clean_time(step)
            )
        } else if n >= 10 && step >= 5.0 {
            format!("rows {} apart (median) over {n} rows", clean_time(step))
        } else if n >= 10 && span > 3600.0 && step < 1.0 {
            format!(
                "{n} rows {} apart spanning {} (over an hour)",
                clean_time(step),
                clean_time(span)
            )
        } else {
            return Ok(());
        };
        Err(IoError {
            file: self.path.clone(),
            line: self.line_of_row(1),
            column: Some("t".into()),
            message: format!(
                "the times look like milliseconds, not seconds ({evidence}: in seconds, a \
                 sample every {} s); write them in seconds, or name the unit in the header: \
                 t[ms] (or t[s] if they are seconds)",
                clean_time(step)
            ),
        })
    }

    /// A `t` column is time in seconds: every cell finite and each row after the one
    /// before it. Rows out of order (a sort or a merge gone wrong) or a repeated time
    /// would otherwise be taken in file order (an ARX fit on swapped samples, a goal
    /// interpolated backwards): issue 29, class 3.
    pub fn check_time(&self) -> Result<(), IoError> {
        let Some(tc) = self.column_index("t") else {
            return Ok(());
        };
        self.check_finite(&[tc])?;
        for r in 1..self.rows.len() {
            let (prev, t) = (self.rows[r - 1][tc], self.rows[r][tc]);
            if t <= prev {
                let before = match self.line_of_row(r - 1) {
                    Some(l) => format!("line {l}"),
                    None => format!("data row {r}"),
                };
                return Err(IoError {
                    file: self.path.clone(),
                    line: self.line_of_row(r),
                    column: Some("t".into()),
                    message: format!(
                        "data row {}: time {} s is not after {} s ({before}): rows must \
                         be in time order, each time once",
                        r + 1,
                        clean_time(t),
                        clean_time(prev)
                    ),
                });
            }
        }
        Ok(())
    }

    /// The file line of data row `row` (0-based), if the table was read from text.
    pub fn line_of_row(&self, row: usize) -> Option<usize> {
        self.lines.get(row).copied()
    }

    /// Every cell of `columns` (indices) must be a finite number: a NaN or an infinity
    /// in a column a command uses is an error naming the file, the line, the data row
    /// and the column, never a NaN carried into the results. Columns a command does not
    /// use may hold NaN (a simulation's centre of pressure while a foot is in the air).
    pub fn check_finite(&self, columns: &[usize]) -> Result<(), IoError> {
        for (r, row) in self.rows.iter().enumerate() {
            for &c in columns {
                let x = row[c];
                if !x.is_finite() {
                    return Err(IoError {
                        file: self.path.clone(),
                        line: self.line_of_row(r),
                        column: Some(self.columns[c].clone()),
                        message: format!(
                            "data row {}: {x} is not a finite number (every cell a command \
                             uses must be measured)",
                            r + 1
                        ),
                    });
                }
            }
        }
        Ok(())
    }

    pub fn column_index(&self, name: &str) -> Option<usize> {
        self.columns.iter().position(|c| c == name)
    }

    /// The 1-based line of data row `r` is not tracked after parsing; errors about a
    /// row name it by its index (row 1 = first data row).
    pub fn row_error(&self, row: usize, message: impl Into<String>) -> IoError {
        IoError {
            file: self.path.clone(),
            line: None,
            column: None,
            message: format!("data row {}: {}", row + 1, message.into()),
        }
    }

    pub fn write(&self, path: impl AsRef<Path>) -> Result<(), IoError> {
        let mut w = CsvWriter::create(path.as_ref(), &self.columns)?;
        for r in &self.rows {
            w.write_row(r)?;
        }
        w.finish()
    }
}

/// Format a float so that parsing the text gives the same bits back.
pub fn format_f64(x: f64) -> String {
    // Debug formatting is Rust's shortest round-trip representation.
    format!("{x:?}")
}

/// A CSV writer that writes rows as they come, through [`crate::output`].
///
/// An output ([`CsvWriter::create`]) goes to `FILE.partial` beside the file asked for,
/// renamed to it by [`CsvWriter::finish`]: a command that fails half-way leaves no file
/// that looks complete and the old file as it was (the partial one is removed when the
/// writer is dropped unfinished; a process killed outright leaves it under its
/// `.partial` name).
///
/// A recording ([`CsvWriter::recording`]) is flushed at every row into `FILE.partial`
/// (a viewer can follow it as it grows) and given its name however the run ends, when
/// it holds a row: the rows read from a robot are never lost, and a run that read
/// nothing leaves an older recording of the same name in place.
pub struct CsvWriter {
    out: AtomicFile,
    ncols: usize,
    line: String,
    /// The `t` column, written to the nanosecond ([`clean_time`]).
    time: Option<usize>,
}

/// A time in s as written: rounded to the nanosecond, so a time summed step by step
/// or made as `i * dt` is written as the instant it stands for (`2.0`, not
/// `1.9999999999998905`; `0.3`, not `0.30000000000000004`). No step of a simulation
/// or recording here is under a microsecond.
pub fn clean_time(t: f64) -> f64 {
    let ns = (t * 1e9).round() / 1e9;
    if ns.is_finite() { ns } else { t }
}

impl CsvWriter {
    /// An output file (see the type's documentation).
    pub fn create(path: &Path, columns: &[String]) -> Result<CsvWriter, IoError> {
        let out = AtomicFile::create(&Output::resolve("", path)?)?;
        CsvWriter::open(out, columns)
    }

    /// A recording: every row on disk at once, the file kept even if the run fails.
    pub fn recording(path: &Path, columns: &[String]) -> Result<CsvWriter, IoError> {
        let out = AtomicFile::recording(&Output::resolve("", path)?)?;
        CsvWriter::open(out, columns)
    }

    fn open(out: AtomicFile, columns: &[String]) -> Result<CsvWriter, IoError> {
        // A column name that a comma, a quote or a line break splits would shift every
        // column after it when the file is read back (issue 29, class 3).
        if let Some(c) = columns
            .iter()
            .find(|c| c.is_empty() || c.trim() != *c || c.contains([',', '"', '\n', '\r']))
        {
            let mut e = IoError::new(
                "a column name may not be empty, hold a comma, a quote or a line break, or \
                 start or end with a space: the file would not read back (rename what it names)",
            )
            .in_file(out.path());
            e.column = Some(c.clone());
            return Err(e);
        }
        let mut w = CsvWriter {
            out,
            ncols: columns.len(),
            line: String::new(),
            time: columns.iter().position(|c| c == "t"),
        };
        let header = columns.join(",");
        w.write_line(&header)?;
        Ok(w)
    }

    fn write_line(&mut self, s: &str) -> Result<(), IoError> {
        let r = writeln!(self.out, "{s}");
        r.map_err(|e| self.out.error(e))
    }

    pub fn write_row(&mut self, row: &[f64]) -> Result<(), IoError> {
        if row.len() != self.ncols {
            // A caller's bug, but a recording must not end in a panic: the rows
            // written so far stay, and the error says what happened.
            return Err(IoError::new(format!(
                "a row of {} values for {} columns was not written",
                row.len(),
                self.ncols
            ))
            .in_file(self.out.path()));
        }
        let mut line = std::mem::take(&mut self.line);
        line.clear();
        for (k, x) in row.iter().enumerate() {
            if k > 0 {
                line.push(',');
            }
            use std::fmt::Write as _;
            let x = if Some(k) == self.time {
                clean_time(*x)
            } else {
                *x
            };
            let _ = write!(line, "{x:?}");
        }
        let r = self.write_line(&line);
        self.line = line;
        r
    }

    /// Flush the rows, make them durable and give the file its name.
    pub fn finish(self) -> Result<(), IoError> {
        self.out.commit()
    }

    /// Give up the file: nothing is written, an older file of the name stays.
    pub fn discard(self) {
        self.out.discard()
    }
}

/// The `t` column's index and how many of its header's unit make a second.
type TimeUnit = (usize, f64);

/// A header line (line `hl`, 0-based): its column names, and the `t` column with how
/// many of its header's unit make a second where the header names one (`t[ms]`).
fn read_header(header: &str, hl: usize) -> Result<(Vec<String>, Option<TimeUnit>), IoError> {
    let mut columns: Vec<String> = header
        .split(',')
        .map(|c| c.trim().trim_matches('"').to_string())
        .collect();
    // `t[ms]`, `t[us]`, `t[s]`: a time column whose header names its unit, read as
    // seconds (the one unit of every table) under the name `t`.
    let time_scale = columns.iter().enumerate().find_map(|(k, c)| {
        TIME_UNITS
            .iter()
            .find(|(u, _)| c == &format!("t[{u}]"))
            .map(|&(_, scale)| (k, scale))
    });
    if let Some((k, _)) = time_scale {
        columns[k] = "t".into();
    }
    // A spreadsheet in a locale with decimal commas exports `;` (or tabs): the
    // header is then one column named after the whole line.
    if let [only] = columns.as_slice()
        && let Some((sep, name)) = [(';', "semicolons"), ('\t', "tabs")]
            .into_iter()
            .find(|(c, _)| only.contains(*c))
    {
        return Err(IoError {
            line: Some(hl + 1),
            ..IoError::new(format!(
                "the header is separated by {name} ({} names joined by '{}'): the file \
                 must be comma-separated with '.' decimals; export it as CSV with commas",
                only.split(sep).count(),
                sep.escape_default()
            ))
        });
    }
    for (i, c) in columns.iter().enumerate() {
        if c.is_empty() {
            return Err(IoError {
                line: Some(hl + 1),
                ..IoError::new(format!("header cell {} is empty", i + 1))
            });
        }
        if columns[..i].contains(c) {
            return Err(IoError {
                line: Some(hl + 1),
                column: Some(c.clone()),
                ..IoError::new("column name appears twice")
            });
        }
    }
    Ok((columns, time_scale))
}
