//! Properties of the CSV tables over random inputs: whatever the writer writes, the
//! reader reads back bit for bit; damaged text (a cell that is not a number, a row
//! cut short or too long, arbitrary bytes) is an error naming the line, never a
//! panic; a non-finite cell is found by `check_finite` with its line and column; a
//! writer dropped before `finish` leaves no file.

use proptest::prelude::*;
use twinloop_io::{CsvWriter, Table};

/// Distinct column names like the ones twinloop writes (`q:l_knee`, `com.x`); not `t`,
/// whose cells must increase (`tests/table.rs` has its cases).
fn columns() -> impl Strategy<Value = Vec<String>> {
    proptest::collection::btree_set("[a-z]{1,4}(:[a-z_]{1,6})?(\\.[xyz])?", 1..6)
        // `t` is the time, written to the nanosecond (`clean_time`), not bit for bit.
        .prop_filter("no time column", |s| !s.contains("t"))
        .prop_map(|s| s.into_iter().collect())
}

/// Any finite f64, subnormals and extremes included.
fn finite() -> impl Strategy<Value = f64> {
    any::<f64>().prop_filter("finite", |x| x.is_finite())
}

/// A table of one row or more (a header alone is refused as no data).
fn table() -> impl Strategy<Value = Table> {
    columns().prop_flat_map(|cols| {
        let n = cols.len();
        proptest::collection::vec(proptest::collection::vec(finite(), n), 1..20).prop_map(
            move |rows| Table {
                rows,
                ..Table::new(cols.clone())
            },
        )
    })
}

fn scratch(name: &str) -> std::path::PathBuf {
    std::env::temp_dir().join(format!("twinloop-io-prop-{}-{name}", std::process::id()))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn written_tables_read_back_bit_for_bit(t in table()) {
        let path = scratch("roundtrip.csv");
        t.write(&path).unwrap();
        let back = Table::read(&path).unwrap();
        prop_assert_eq!(&back.columns, &t.columns);
        prop_assert_eq!(back.rows.len(), t.rows.len());
        for (a, b) in back.rows.iter().zip(&t.rows) {
            for (x, y) in a.iter().zip(b) {
                prop_assert_eq!(x.to_bits(), y.to_bits());
            }
        }
        // Line numbers: the header is line 1, row r is line r + 2.
        for r in 0..back.rows.len() {
            prop_assert_eq!(back.line_of_row(r), Some(r + 2));
        }
    }

    #[test]
    fn a_damaged_cell_is_an_error_naming_its_line_and_column(
        t in table().prop_filter("rows", |t| !t.rows.is_empty()),
        pick in any::<prop::sample::Index>(),
        col in any::<prop::sample::Index>(),
        // Not starting with `#`: a line that does is a comment.
        junk in "[a-zA-Z@][a-zA-Z#@ ]{0,3}|1\\.2\\.3|--1|0x10",
    ) {
        // "inf", "NaN" are numbers to the reader (check_finite catches them).
        prop_assume!(junk.trim().parse::<f64>().is_err());
        let mut text = t.columns.join(",") + "\n";
        let (r, c) = (pick.index(t.rows.len()), col.index(t.columns.len()));
        for (k, row) in t.rows.iter().enumerate() {
            let cells: Vec<String> = row
                .iter()
                .enumerate()
                .map(|(j, x)| if (k, j) == (r, c) { junk.clone() } else { format!("{x:?}") })
                .collect();
            text += &(cells.join(",") + "\n");
        }
        let e = Table::parse(&text).unwrap_err();
        prop_assert_eq!(e.line, Some(r + 2));
        prop_assert_eq!(e.column.as_deref(), Some(t.columns[c].as_str()));
    }

    #[test]
    fn a_row_of_the_wrong_length_is_an_error_naming_its_line(
        t in table().prop_filter("rows", |t| !t.rows.is_empty()),
        pick in any::<prop::sample::Index>(),
        longer in any::<bool>(),
    ) {
        // One column cut short is an empty line, which the format skips.
        prop_assume!(longer || t.columns.len() > 1);
        let r = pick.index(t.rows.len());
        let mut text = t.columns.join(",") + "\n";
        for (k, row) in t.rows.iter().enumerate() {
            let mut cells: Vec<String> = row.iter().map(|x| format!("{x:?}")).collect();
            if k == r {
                if longer { cells.push("1".into()) } else { cells.pop(); }
            }
            text += &(cells.join(",") + "\n");
        }
        let e = Table::parse(&text).unwrap_err();
        prop_assert_eq!(e.line, Some(r + 2));
    }

    #[test]
    fn non_finite_cells_are_found_with_line_and_column(
        t in table().prop_filter("rows", |t| !t.rows.is_empty()),
        pick in any::<prop::sample::Index>(),
        col in any::<prop::sample::Index>(),
        bad in prop::sample::select(vec!["NaN", "nan", "inf", "-inf", "infinity", "1e999"]),
    ) {
        let (r, c) = (pick.index(t.rows.len()), col.index(t.columns.len()));
        let mut text = t.columns.join(",") + "\n";
        for (k, row) in t.rows.iter().enumerate() {
            let cells: Vec<String> = row
                .iter()
                .enumerate()
                .map(|(j, x)| if (k, j) == (r, c) { bad.to_string() } else { format!("{x:?}") })
                .collect();
            text += &(cells.join(",") + "\n");
        }
        let table = Table::parse(&text).unwrap();
        let all: Vec<usize> = (0..t.columns.len()).collect();
        let e = table.check_finite(&all).unwrap_err();
        prop_assert_eq!(e.line, Some(r + 2));
        prop_assert_eq!(e.column.as_deref(), Some(t.columns[c].as_str()));
    }

    #[test]
    fn arbitrary_text_never_panics(text in "\\PC{0,200}", bytes in proptest::collection::vec(any::<u8>(), 0..200)) {
        let _ = Table::parse(&text);
        let _ = Table::parse(&String::from_utf8_lossy(&bytes));
    }
}

#[test]
fn a_writer_dropped_unfinished_leaves_no_file() {
    let path = scratch("unfinished.csv");
    let _ = std::fs::remove_file(&path);
    {
        let mut w = CsvWriter::create(&path, &["t".to_string()]).unwrap();
        w.write_row(&[1.0]).unwrap();
        // A command failing here returns its error and drops the writer.
    }
    assert!(!path.exists(), "no file that looks complete");
    let partial = path.with_extension("csv.partial");
    assert!(!partial.exists(), "and no partial one either");
    let w = CsvWriter::create(&path, &["t".to_string()]).unwrap();
    w.finish().unwrap();
    assert!(path.exists() && !partial.exists());
}
