//! Bad logs give one-line errors naming the file, the topic and the message's time.
use std::path::PathBuf;
use twinloop_io::Table;
use twinloop_logs::{ReadOptions, read_log, write_mcap};

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("twinloop-logs-err-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join("log.mcap")
}

fn joints(times: &[f64]) -> Table {
    let mut t = Table::new(vec!["t".into(), "q:knee".into()]);
    t.rows = times.iter().map(|&x| vec![x, 0.5]).collect();
    t
}

#[test]
fn time_going_backwards_names_the_topic_and_both_times() {
    let p = scratch("back");
    write_mcap(&p, &joints(&[0.0, 0.002, 0.001]), None, "base").unwrap();
    let e = read_log(&p, &ReadOptions::default())
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        format!(
            "{}: topic /joint_states at t=0.001000000 s: time goes backwards (the previous message was at 0.002000000 s)",
            p.display()
        )
    );
}

#[test]
fn a_truncated_chunk_names_the_last_message_read() {
    let p = scratch("cut");
    let t = joints(&(0..20_000).map(|k| k as f64 * 1e-3).collect::<Vec<_>>());
    write_mcap(&p, &t, None, "base").unwrap();
    let bytes = std::fs::read(&p).unwrap();
    std::fs::write(&p, &bytes[..bytes.len() * 2 / 3]).unwrap();
    let e = read_log(&p, &ReadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with(&format!("{}: topic /joint_states at t=", p.display())),
        "{e}"
    );
    assert!(e.contains("truncated"), "{e}");
    assert!(!e.contains('\n'), "{e}");
}

#[test]
fn a_resampled_log_is_on_the_fixed_step_and_interpolated_linearly() {
    let p = scratch("dt");
    let mut t = joints(&[0.0, 0.003, 0.010]);
    t.rows[1][1] = 0.8;
    t.rows[2][1] = 1.5;
    write_mcap(&p, &t, None, "base").unwrap();
    let o = ReadOptions {
        dt: Some(0.002),
        ..ReadOptions::default()
    };
    let r = read_log(&p, &o).unwrap();
    let got: Vec<(f64, f64)> = r.rows.iter().map(|r| (r[0], r[1])).collect();
    let want = [
        (0.0, 0.5),
        (0.002, 0.7),
        (0.004, 0.9),
        (0.006, 1.1),
        (0.008, 1.3),
        (0.010, 1.5),
    ];
    assert_eq!(got.len(), want.len());
    for ((t, x), (tw, xw)) in got.iter().zip(want) {
        assert!((t - tw).abs() < 1e-12 && (x - xw).abs() < 1e-12, "{got:?}");
    }
}

#[test]
fn a_recording_described_before_its_first_row_carries_the_robot_and_after_it_is_refused() {
    let path = scratch("described.mcap");
    let t = joints(&[0.0, 0.01, 0.02]);
    let mut log = twinloop_logs::open_mcap_recording(&path, &t.columns).unwrap();
    log.describe("<robot name=\"r\"/>").unwrap();
    for row in &t.rows {
        log.write_row(row).unwrap();
    }
    let e = log.describe("<robot name=\"r\"/>").unwrap_err().to_string();
    assert!(
        e.contains("before the first row") && e.contains("described.mcap"),
        "{e}"
    );
    log.finish().unwrap();
    let info = twinloop_logs::log_info(&path).unwrap();
    let d = info
        .iter()
        .find(|t| t.topic == "/robot_description")
        .unwrap();
    assert_eq!((d.messages, d.first_ns), (1, 0));
    // The rows read back as written.
    assert_eq!(
        read_log(&path, &ReadOptions::default()).unwrap().rows,
        t.rows
    );
}

/// An output that is a folder (`run/`) is a rosbag2 bag: `run/run_0.mcap` and its
/// `metadata.yaml`, which twinloop reads back as the table it wrote; a folder that
/// holds other files is refused, and a bag whose writing failed leaves no folder.
#[test]
fn a_folder_output_is_a_rosbag2_bag_and_a_folder_of_other_files_is_refused() {
    let dir = scratch("bag").with_file_name("run");
    let _ = std::fs::remove_dir_all(&dir);
    let slash = PathBuf::from(format!("{}/", dir.display()));
    let table = joints(&[0.0, 0.001, 0.002]);
    write_mcap(&slash, &table, None, "base").unwrap();
    assert!(dir.join("run_0.mcap").is_file());
    let meta = std::fs::read_to_string(dir.join("metadata.yaml")).unwrap();
    for line in [
        "storage_identifier: mcap",
        "message_count: 3",
        "name: /joint_states",
        "type: sensor_msgs/msg/JointState",
        "- run_0.mcap",
        "duration:\n    nanoseconds: 2000000",
    ] {
        assert!(meta.contains(line), "{line} not in\n{meta}");
    }
    let back = read_log(&dir, &ReadOptions::default()).unwrap();
    assert_eq!(back.rows, table.rows);
    // Written again into the existing bag: replaced.
    write_mcap(&dir, &joints(&[0.0, 0.5]), None, "base").unwrap();
    assert_eq!(
        read_log(&dir, &ReadOptions::default()).unwrap().rows.len(),
        2
    );
    let other = scratch("notabag").with_file_name("docs");
    std::fs::create_dir_all(&other).unwrap();
    std::fs::write(other.join("notes.txt"), "keep").unwrap();
    let e = write_mcap(&other, &table, None, "base")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("notes.txt") && e.contains("not part of a bag"),
        "{e}"
    );
    // A bad table: the new folder is not left behind.
    let never = scratch("never").with_file_name("never");
    let e = write_mcap(
        &PathBuf::from(format!("{}/", never.display())),
        &Table::new(vec!["q:a".into()]),
        None,
        "base",
    );
    assert!(e.is_err() && !never.exists());
}
