//! Logs written by the reference Python libraries (tools/oracle/logs_reference.py:
//! `mcap` + `mcap-ros2-support` with zstd and lz4 chunks, `rosbags` bag folders with
//! MCAP and SQLite storage) read back to the last bit of every value.
use std::path::{Path, PathBuf};
use twinloop_logs::{ReadOptions, TopicSpec, log_info, read_log};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

fn expected() -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(data("expected.json")).unwrap()).unwrap()
}

fn bits(v: &serde_json::Value) -> Vec<u64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|s| u64::from_str_radix(s.as_str().unwrap(), 16).unwrap())
        .collect()
}

fn topics(names: &[&str]) -> ReadOptions {
    ReadOptions {
        topics: names.iter().map(|t| t.parse().unwrap()).collect(),
        dt: None,
    }
}

const LOGS: [&str; 4] = ["joints_zstd.mcap", "joints_lz4.mcap", "bag_mcap", "bag_db3"];

#[test]
fn joint_states_read_to_the_last_bit_from_every_reference_writer() {
    let exp = expected();
    let joints: Vec<&str> = exp["joints"]
        .as_array()
        .unwrap()
        .iter()
        .map(|j| j.as_str().unwrap())
        .collect();
    for log in LOGS {
        let t = read_log(&data(log), &topics(&["/joint_states"])).unwrap();
        let mut want = vec!["t".to_string()];
        for p in ["q:", "v:", "tau:"] {
            want.extend(joints.iter().map(|j| format!("{p}{j}")));
        }
        assert_eq!(t.columns, want, "{log}");
        let rows = exp["rows"].as_array().unwrap();
        assert_eq!(t.rows.len(), rows.len(), "{log}");
        let t0 = rows[0]["stamp"].as_i64().unwrap();
        for (r, e) in t.rows.iter().zip(rows) {
            // Time is the header stamp (not the log time, 0.5 ms later), from the first row.
            let ns = e["stamp"].as_i64().unwrap() - t0;
            assert_eq!(r[0], ns as f64 / 1e9, "{log}");
            let mut w = bits(&e["q"]);
            w.extend(bits(&e["v"]));
            w.extend(bits(&e["tau"]));
            let got: Vec<u64> = r[1..].iter().map(|x| x.to_bits()).collect();
            assert_eq!(got, w, "{log} at {}", r[0]);
        }
    }
}

#[test]
fn imu_wrench_tf_and_named_arrays_read_to_the_last_bit() {
    let exp = expected();
    let rows = exp["rows"].as_array().unwrap();
    for log in LOGS {
        let o = topics(&["/imu", "/plate", "/tf", "/array=a.x,a.y"]);
        let t = read_log(&data(log), &o).unwrap();
        let cols: Vec<&str> = t.columns.iter().map(String::as_str).collect();
        assert_eq!(
            cols,
            [
                "t",
                "imu:imu_link.gx",
                "imu:imu_link.gy",
                "imu:imu_link.gz",
                "imu:imu_link.ax",
                "imu:imu_link.ay",
                "imu:imu_link.az",
                "wrench:plate.fx",
                "wrench:plate.fy",
                "wrench:plate.fz",
                "wrench:plate.tx",
                "wrench:plate.ty",
                "wrench:plate.tz",
                "q:base.x",
                "q:base.y",
                "q:base.z",
                "q:base.qx",
                "q:base.qy",
                "q:base.qz",
                "q:base.qw",
                "a.x",
                "a.y"
            ],
            "{log}"
        );
        // /imu (every other message) gives the rows; /plate and /tf have a message at
        // each of its times, so they are not interpolated. /array has no header, so
        // its time is the log time, 0.5 ms after the stamps: the first /imu row comes
        // before its first message and is left out.
        assert_eq!(t.rows.len(), 19, "{log}");
        for (r, e) in t.rows.iter().zip(rows.iter().step_by(2).skip(1)) {
            let mut w = bits(&e["imu"]);
            w.extend(bits(&e["wrench"]));
            w.extend(bits(&e["tf"]));
            let got: Vec<u64> = r[1..20].iter().map(|x| x.to_bits()).collect();
            assert_eq!(got, w, "{log} at {}", r[0]);
        }
        // The array is interpolated (exactly half-way) between two messages.
        let a = &t.rows[0];
        let k = 2.0 - 0.5;
        assert!(
            (a[20] - k / 3.0).abs() < 1e-15 && (a[21] + k * std::f64::consts::PI).abs() < 1e-14,
            "{log}: {a:?}"
        );
    }
}

#[test]
fn the_listing_names_every_topic_its_count_and_what_twinloop_reads() {
    for log in LOGS {
        let info = log_info(&data(log)).unwrap();
        let names: Vec<(&str, u64)> = info
            .iter()
            .map(|t| (t.topic.as_str(), t.messages))
            .collect();
        assert_eq!(
            names,
            [
                ("/joint_states", 40),
                ("/imu", 20),
                ("/plate", 20),
                ("/array", 40),
                ("/tf", 40),
                ("/chatter", 1)
            ],
            "{log}"
        );
        let js = &info[0];
        assert_eq!(js.schema, "sensor_msgs/msg/JointState");
        assert_eq!(js.columns.len(), 9);
        assert!(
            info[3]
                .note
                .as_deref()
                .unwrap()
                .contains("--topic /array=NAME"),
            "{:?}",
            info[3]
        );
        assert!(
            info[5]
                .note
                .as_deref()
                .unwrap()
                .contains("std_msgs/msg/String is not one twinloop reads")
        );
    }
}

#[test]
fn without_topics_every_usable_topic_is_read_on_the_joint_states_times() {
    let t = read_log(&data("joints_zstd.mcap"), &ReadOptions::default()).unwrap();
    // /joint_states has the most messages; /imu and /plate end one step earlier
    // (message 38), so the last row is left out rather than extrapolated.
    assert_eq!(t.rows.len(), 39);
    assert!(t.column_index("q:l_knee").is_some() && t.column_index("wrench:plate.fz").is_some());
    assert!(
        t.column_index("a.x").is_none(),
        "an unnamed array is not read by default"
    );
}

#[test]
fn a_topic_the_log_lacks_is_an_error_listing_what_it_holds() {
    let e = read_log(&data("bag_db3"), &topics(&["/joint_state"]))
        .unwrap_err()
        .to_string();
    assert!(e.contains("no message on topic /joint_state; the log holds /joint_states (sensor_msgs/msg/JointState)"), "{e}");
    assert!(e.contains("bag_db3"), "{e}");
}

#[test]
fn a_truncated_file_is_an_error_naming_the_last_topic_and_time_read() {
    let bytes = std::fs::read(data("joints_zstd.mcap")).unwrap();
    let dir = std::env::temp_dir().join(format!("twinloop-logs-trunc-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let cut = dir.join("cut.mcap");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let e = read_log(&cut, &topics(&["/joint_states"]))
        .unwrap_err()
        .to_string();
    assert!(e.starts_with(&format!("{}: topic /", cut.display())), "{e}");
    assert!(e.contains(" at t=1700000000."), "{e}");
    assert!(!e.contains('\n'), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_spec_with_an_empty_column_name_is_refused() {
    assert!("/x=a,,b".parse::<TopicSpec>().is_err());
    assert_eq!("/x".parse::<TopicSpec>().unwrap().columns, None);
}
