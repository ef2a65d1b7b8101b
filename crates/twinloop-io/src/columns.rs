use crate::table::{IoError, Table};

/// Which vector a column group fills.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Quantity {
    /// `q:` configuration (nq).
    Q,
    /// `v:` velocity (nv).
    V,
    /// `a:` acceleration (nv).
    A,
    /// `tau:` generalised force (nv).
    Tau,
}

impl Quantity {
    pub fn prefix(self) -> &'static str {
        match self {
            Quantity::Q => "q:",
            Quantity::V => "v:",
            Quantity::A => "a:",
            Quantity::Tau => "tau:",
        }
    }

    /// Column names for coordinates named `coordinates` (a model's `q_names()` for
    /// [`Quantity::Q`], its `v_names()` or `tau_names()` for the others), in that order.
    /// A ball joint `j` has four `q:j.qx` .. `q:j.qw` (its quaternion), three
    /// `v:j.wx` .. `v:j.wz` (and `a:`), three `tau:j.tx` .. `tau:j.tz`.
    pub fn column_names(self, coordinates: &[String]) -> Vec<String> {
        coordinates
            .iter()
            .map(|n| format!("{}{n}", self.prefix()))
            .collect()
    }
}

/// Column indices of one quantity in a table, in model order.
#[derive(Debug, Clone, PartialEq)]
pub struct StateColumns {
    pub quantity: Quantity,
    pub indices: Vec<usize>,
}

impl StateColumns {
    /// Find the column of every coordinate in `coordinates` (see
    /// [`Quantity::column_names`]); the error names a column of this quantity that
    /// no coordinate has (a misspelt `q:l_kne`, with the nearest names: see
    /// [`StateColumns::check_known`]), lists those missing, or names the first cell
    /// of these columns that is NaN or infinite (file, line, column), so every
    /// command that maps a table onto a model rejects unknown columns and
    /// non-finite input at read time.
    pub fn find(
        table: &Table,
        quantity: Quantity,
        coordinates: &[String],
    ) -> Result<StateColumns, IoError> {
        Self::check_known(table, quantity, coordinates)?;
        let names = quantity.column_names(coordinates);
        let mut indices = Vec::with_capacity(names.len());
        let mut missing = Vec::new();
        for n in &names {
            match table.column_index(n) {
                Some(i) => indices.push(i),
                None => missing.push(n.as_str()),
            }
        }
        if !missing.is_empty() {
            let shown: Vec<&str> = missing.iter().take(8).copied().collect();
            let more = if missing.len() > 8 {
                format!(" and {} more", missing.len() - 8)
            } else {
                String::new()
            };
            let mut e = IoError::new(format!(
                "{} of the model's {} columns are missing: {}{more}",
                missing.len(),
                names.len(),
                shown.join(", ")
            ));
            e.file = table.path.clone();
            return Err(e);
        }
        table.check_finite(&indices)?;
        Ok(StateColumns { quantity, indices })
    }

    /// Every column of `table` with `quantity`'s prefix must name one of
    /// `coordinates`: a misspelt `q:l_kne` is an error naming the column and the
    /// nearest coordinate names, never a column silently ignored. The one exception:
    /// `base.*` columns when the coordinates have no base (a fixed-base model reads
    /// a floating-base trajectory's joints and, as documented, not its base).
    pub fn check_known(
        table: &Table,
        quantity: Quantity,
        coordinates: &[String],
    ) -> Result<(), IoError> {
        let names = quantity.column_names(coordinates);
        let base = format!("{}base.", quantity.prefix());
        let fixed_base = !names.iter().any(|n| n.starts_with(&base));
        let unknown = table.columns.iter().find(|c| {
            c.starts_with(quantity.prefix())
                && !names.contains(c)
                && !(fixed_base && c.starts_with(&base))
        });
        let Some(c) = unknown else {
            return Ok(());
        };
        let mut e = IoError::new(format!(
            "names no coordinate of the model; did you mean {}? (the model has {} such \
             columns; `twinloop model info --joints` lists them)",
            nearest(c, &names, 3).join(", "),
            names.len()
        ));
        e.file = table.path.clone();
        e.column = Some(c.clone());
        Err(e)
    }

    /// Gather row `r` into `out` (model order).
    #[inline]
    pub fn gather(&self, row: &[f64], out: &mut [f64]) {
        for (o, &i) in out.iter_mut().zip(&self.indices) {
            *o = row[i];
        }
    }
}

/// The `n` names of `choices` nearest to `name` (Levenshtein distance, ties in the
/// order given), for "did you mean" in errors.
pub fn nearest<'a>(name: &str, choices: &'a [String], n: usize) -> Vec<&'a str> {
    let mut scored: Vec<(usize, usize)> = choices
        .iter()
        .enumerate()
        .map(|(i, c)| (strsim::levenshtein(name, c), i))
        .collect();
    scored.sort_unstable();
    scored
        .iter()
        .take(n)
        .map(|&(_, i)| choices[i].as_str())
        .collect()
}
