use twinloop_io::{Table, format_f64};

#[test]
fn floats_round_trip_bit_for_bit() {
    let mut x = 0.1f64;
    for k in 0..2000 {
        x = (x * 1.618_033_988_7 + k as f64 * 1e-7).sin() * 10f64.powi((k % 40) - 20);
        let s = format_f64(x);
        assert_eq!(s.parse::<f64>().unwrap().to_bits(), x.to_bits(), "{s}");
    }
    for x in [0.0, -0.0, f64::MIN_POSITIVE, f64::MAX, 1e-300, 5e-324] {
        assert_eq!(format_f64(x).parse::<f64>().unwrap().to_bits(), x.to_bits());
    }
}

#[test]
fn write_then_read_is_identical() {
    let mut t = Table::new(vec!["t".into(), "q:a/b".into(), "v:c".into()]);
    t.rows.push(vec![0.0, 1.0 / 3.0, -2.5e-17]);
    t.rows.push(vec![0.001, std::f64::consts::PI, 1e300]);
    let dir = std::env::temp_dir().join(format!("twinloop-io-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("t.csv");
    t.write(&p).unwrap();
    let back = Table::read(&p).unwrap();
    assert_eq!(back.columns, t.columns);
    assert_eq!(back.rows, t.rows);
}

#[test]
fn errors_name_line_and_column() {
    let e = Table::parse("t,q:knee\n0,1\n0.1,abc\n").unwrap_err();
    assert_eq!(e.line, Some(3));
    assert_eq!(e.column.as_deref(), Some("q:knee"));
    assert!(e.to_string().contains("\"abc\" is not a number"), "{e}");
    let e = Table::parse("t,q:knee\n0,1,2\n").unwrap_err();
    assert_eq!(e.line, Some(2));
    let e = Table::parse("t,q:knee\n0\n").unwrap_err();
    assert!(
        e.to_string().contains("1 cells, but the header has 2"),
        "{e}"
    );
    let e = Table::parse("").unwrap_err();
    assert!(e.to_string().contains("empty"));
    let e = Table::parse("t,t\n").unwrap_err();
    assert!(e.to_string().contains("twice"));
}

/// Issue 29, class 3: a table is read in time order or not at all. A header without
/// rows, time running backwards, a time repeated or not finite: errors naming the
/// line and the column, never rows taken in file order.
#[test]
fn time_out_of_order_and_tables_without_rows_are_refused() {
    let e = Table::parse("# a comment\nt,u:a\n")
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("line 2: ") && e.contains("no data rows"),
        "{e}"
    );
    for (text, line) in [
        ("t,u:a\n0,1\n0.02,2\n0.01,3\n", 4),
        ("t,u:a\n0,1\n0,2\n", 3),
        ("t,u:a\n0,1\nnan,2\n", 3),
        ("t,u:a\n-inf,1\n0,2\n", 2),
    ] {
        let e = Table::parse(text).unwrap_err().to_string();
        assert!(
            e.starts_with(&format!("line {line}: column \"t\"")),
            "{text:?}: {e}"
        );
    }
    // Other columns may go down, and a table without `t` is in no particular order.
    assert!(Table::parse("t,u:a\n-1,3\n0,2\n1e-9,1\n").is_ok());
    assert!(Table::parse("pose,u:a\n2,1\n1,2\n").is_ok());
}

#[test]
fn a_non_finite_cell_in_a_used_column_names_file_line_and_column() {
    use twinloop_io::{Quantity, StateColumns};
    let names = vec!["knee".to_string(), "hip".to_string()];
    // Comment and blank lines shift the file lines: the error names the file's line.
    let text = "t,q:knee,q:hip,cop.x\n# a comment\n0,1,2,NaN\n\n0.1,1,inf,NaN\n";
    let t = Table::parse(text).unwrap();
    let e = StateColumns::find(&t, Quantity::Q, &names).unwrap_err();
    assert_eq!(e.line, Some(5), "{e}");
    assert_eq!(e.column.as_deref(), Some("q:hip"), "{e}");
    assert!(e.to_string().contains("data row 2"), "{e}");
    assert!(e.to_string().contains("not a finite number"), "{e}");
    // NaN in a column the caller does not use (cop.x) is no error.
    let ok = Table::parse("t,q:knee,q:hip,cop.x\n0,1,2,NaN\n").unwrap();
    assert!(StateColumns::find(&ok, Quantity::Q, &names).is_ok());
    let e = ok.check_finite(&[3]).unwrap_err();
    assert_eq!((e.line, e.column.as_deref()), (Some(2), Some("cop.x")));
}

#[test]
fn a_misspelt_column_is_named_with_the_nearest_names() {
    use twinloop_io::{Quantity, StateColumns};
    let names: Vec<String> = ["l_knee", "r_knee", "l_hip_pitch", "base.x"]
        .map(String::from)
        .to_vec();
    let t = Table::parse("t,q:l_kne,q:base.x,tau:anything\n0,1,2,3\n").unwrap();
    let e = StateColumns::check_known(&t, Quantity::Q, &names).unwrap_err();
    assert_eq!(e.column.as_deref(), Some("q:l_kne"), "{e}");
    let s = e.to_string();
    assert!(s.contains("did you mean q:l_knee, q:r_knee"), "{s}");
    // Other prefixes are not this quantity's business.
    let ok = Table::parse("t,q:l_knee,tau:x\n0,1,2\n").unwrap();
    assert!(StateColumns::check_known(&ok, Quantity::Q, &names).is_ok());
}

#[test]
fn find_refuses_an_extra_column_the_model_does_not_have() {
    use twinloop_io::{Quantity, StateColumns};
    let names: Vec<String> = ["l_knee", "r_knee"].map(String::from).to_vec();
    // Every column the model needs is there, plus a misspelt one: not ignored.
    let t = Table::parse("t,q:l_knee,q:r_knee,q:l_kne\n0,1,2,3\n").unwrap();
    let e = StateColumns::find(&t, Quantity::Q, &names).unwrap_err();
    assert_eq!(e.column.as_deref(), Some("q:l_kne"), "{e}");
    assert!(
        e.to_string().contains("did you mean q:l_knee, q:r_knee"),
        "{e}"
    );
    // A misspelt column in place of a needed one names the misspelling, not only
    // the missing name.
    let t = Table::parse("t,q:l_kne,q:r_knee\n0,1,2\n").unwrap();
    let e = StateColumns::find(&t, Quantity::Q, &names).unwrap_err();
    assert_eq!(e.column.as_deref(), Some("q:l_kne"), "{e}");
    // A fixed-base model (no base coordinates) reads past a floating-base
    // trajectory's base columns; a floating-base model refuses an unknown base one.
    let t = Table::parse("t,q:base.x,q:base.qw,q:l_knee,q:r_knee\n0,0,1,1,2\n").unwrap();
    assert!(StateColumns::find(&t, Quantity::Q, &names).is_ok());
    let floating: Vec<String> = ["base.x", "l_knee", "r_knee"].map(String::from).to_vec();
    let e = StateColumns::find(&t, Quantity::Q, &floating).unwrap_err();
    assert_eq!(e.column.as_deref(), Some("q:base.qw"), "{e}");
}

#[test]
fn csv_times_are_written_clean_to_the_nanosecond() {
    // Issue 30 item 10: a time summed step by step was written 1.9999999999998905.
    let mut summed = 0.0;
    for _ in 0..2000 {
        summed += 0.001;
    }
    assert_ne!(summed, 2.0);
    let mut t = Table::new(vec!["t".into(), "q:a".into()]);
    t.rows.push(vec![summed, summed]);
    t.rows.push(vec![3.0 * 0.1, 3.0 * 0.1]);
    let dir = std::env::temp_dir().join(format!("twinloop-io-time-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("t.csv");
    t.write(&p).unwrap();
    let text = std::fs::read_to_string(&p).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    // The time is clean; other columns keep every bit.
    assert_eq!(lines[1], format!("2.0,{summed:?}"));
    assert_eq!(lines[2], "0.3,0.30000000000000004");
}

/// Whole-number times 1 apart are seconds or milliseconds alike over a short run
/// (static poses a second apart, or 1 kHz in ms): taken; over more than an hour they
/// are a 1 kHz logger's ms (an hour of 1 Hz poses is not a robot record), and 2 apart
/// (500 Hz in ms) at any length is refused, naming the column.
#[test]
fn whole_times_one_apart_are_ms_only_over_an_hour() {
    let csv = |n: usize, step: usize| {
        let mut s = String::from("t,x\n");
        for k in 0..n {
            s.push_str(&format!("{},{k}\n", k * step));
        }
        s
    };
    assert!(Table::parse(&csv(172, 1)).is_ok(), "poses a second apart");
    for (n, step) in [(3700, 1), (20, 2)] {
        let e = Table::parse(&csv(n, step)).unwrap_err().to_string();
        assert!(
            e.contains("\"t\"") && e.contains("milliseconds"),
            "{n} x {step}: {e}"
        );
    }
    let named = csv(3700, 1).replacen("t,", "t[ms],", 1);
    let t = Table::parse(&named).unwrap();
    assert_eq!(t.rows[3699][0], 3.699);
}
