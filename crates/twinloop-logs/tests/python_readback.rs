//! MCAP files twinloop writes, read back by the reference libraries
//! (tools/oracle/logs_readback.py: `mcap` + `mcap-ros2-support`, which decode through
//! the schema text the file carries) and by Rerun (`rerun mcap convert`): same values
//! to the bit, counts, topics and schemas.
//!
//! Skips, with a note, when Python or a module is missing; with
//! TWINLOOP_REQUIRE_ORACLES=1 (set by .ci/run) that fails instead. Python is
//! $TWINLOOP_PYTHON, else the repository's .venv, else python3.
#[path = "support/python.rs"]
mod python;

use python::{mcap_readback, python_with};
use std::path::PathBuf;
use std::process::Command;
use twinloop_io::Table;
use twinloop_logs::{ReadOptions, read_log, write_mcap};

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("twinloop-logs-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

const URDF: &str = "<robot name=\"two\"><link name=\"base_link\"/></robot>";

/// 25 rows at 1 kHz: two joints with awkward values, a floating base turning about
/// z, one IMU and a column with no ROS type (`com.z`).
fn table() -> Table {
    let cols = [
        "t",
        "q:base.x",
        "q:base.y",
        "q:base.z",
        "q:base.qx",
        "q:base.qy",
        "q:base.qz",
        "q:base.qw",
        "q:hip",
        "q:knee",
        "v:hip",
        "v:knee",
        "imu:torso.gx",
        "imu:torso.gy",
        "imu:torso.gz",
        "imu:torso.ax",
        "imu:torso.ay",
        "imu:torso.az",
        "com.z",
    ];
    let mut t = Table::new(cols.iter().map(|s| s.to_string()).collect());
    for k in 0..25 {
        let kf = k as f64;
        let (s, c) = (0.02 * kf).sin_cos();
        t.rows.push(vec![
            kf / 1000.0,
            0.001 * kf,
            -0.0,
            0.75,
            0.0,
            0.0,
            s,
            c,
            kf / 3.0,
            -std::f64::consts::PI * kf / 7.0,
            1e-310 * kf,
            1e300 / (kf + 1.0),
            0.1,
            0.2,
            kf / 9.0,
            0.0,
            0.0,
            9.81,
            0.6 + kf / 11.0,
        ]);
    }
    t
}

fn hex(x: f64) -> String {
    format!("{:016x}", x.to_bits())
}

#[test]
fn an_mcap_twinloop_writes_reads_back_in_the_reference_library_bit_for_bit() {
    let Some(py) = python_with(
        "mcap, mcap_ros2",
        "an_mcap_twinloop_writes_reads_back_in_the_reference_library_bit_for_bit",
    ) else {
        return;
    };
    let dir = scratch("py");
    let path = dir.join("run.mcap");
    let tab = table();
    write_mcap(&path, &tab, Some(URDF), "base_link").unwrap();
    let v = mcap_readback(&py, &path);
    let topics = v["topics"].as_object().unwrap();
    let mut names: Vec<&str> = topics.keys().map(String::as_str).collect();
    names.sort();
    assert_eq!(
        names,
        [
            "/imu",
            "/joint_states",
            "/robot_description",
            "/tf",
            "/twinloop/columns"
        ]
    );
    for (topic, schema, count) in [
        ("/joint_states", "sensor_msgs/msg/JointState", 25),
        ("/tf", "tf2_msgs/msg/TFMessage", 25),
        ("/imu", "sensor_msgs/msg/Imu", 25),
        ("/twinloop/columns", "std_msgs/msg/Float64MultiArray", 25),
        ("/robot_description", "std_msgs/msg/String", 1),
    ] {
        let t = &topics[topic];
        assert_eq!(t["schema"], schema, "{topic}");
        assert_eq!(t["schema_encoding"], "ros2msg", "{topic}");
        assert_eq!(t["message_encoding"], "cdr", "{topic}");
        assert_eq!(t["count"], count, "{topic}");
    }
    assert_eq!(v["statistics_messages"], 25 * 4 + 1);
    let js = &topics["/joint_states"];
    assert_eq!(js["names"], serde_json::json!(["hip", "knee"]));
    for (k, (row, r)) in js["rows"]
        .as_array()
        .unwrap()
        .iter()
        .zip(&tab.rows)
        .enumerate()
    {
        let want = serde_json::json!([
            k as i64 * 1_000_000,
            hex(r[8]),
            hex(r[9]),
            hex(r[10]),
            hex(r[11])
        ]);
        assert_eq!(row, &want, "joint_states row {k}");
        let tf = &topics["/tf"]["rows"][k];
        let mut want = vec![
            serde_json::json!(k as i64 * 1_000_000),
            "world".into(),
            "base_link".into(),
        ];
        want.extend(r[1..8].iter().map(|&x| serde_json::json!(hex(x))));
        assert_eq!(tf, &serde_json::Value::Array(want), "tf row {k}");
        assert_eq!(topics["/imu"]["rows"][k][1], "torso");
        assert_eq!(topics["/imu"]["rows"][k][4], hex(r[14]));
        assert_eq!(
            topics["/twinloop/columns"]["rows"][k],
            serde_json::json!(["com.z", hex(r[18])])
        );
    }
    assert_eq!(
        topics["/robot_description"]["rows"][0],
        serde_json::json!([0, URDF])
    );
    let qos = topics["/robot_description"]["metadata"]["offered_qos_profiles"]
        .as_str()
        .unwrap();
    assert!(qos.contains("durability: 1"), "{qos}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_mcap_twinloop_writes_reads_back_in_twinloop_as_the_same_table() {
    let dir = scratch("rt");
    let path = dir.join("run.mcap");
    let tab = table();
    write_mcap(&path, &tab, Some(URDF), "base_link").unwrap();
    let back = read_log(&path, &ReadOptions::default()).unwrap();
    // Topics come back in file order: joints, tf (the base), imu, the extra columns.
    for c in &tab.columns {
        let (i, j) = (
            tab.column_index(c).unwrap(),
            back.column_index(c).unwrap_or_else(|| panic!("{c}")),
        );
        for (a, b) in tab.rows.iter().zip(&back.rows) {
            assert_eq!(a[i].to_bits(), b[j].to_bits(), "{c}");
        }
    }
    assert_eq!(back.rows.len(), tab.rows.len());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn rerun_loads_an_mcap_twinloop_wrote_and_finds_the_joint_states() {
    let Some(py) = python_with(
        "rerun",
        "rerun_loads_an_mcap_twinloop_wrote_and_finds_the_joint_states",
    ) else {
        return;
    };
    let dir = scratch("rerun");
    let path = dir.join("run.mcap");
    write_mcap(&path, &table(), Some(URDF), "base_link").unwrap();
    let rrd = dir.join("run.rrd");
    let out = Command::new(&py)
        .args(["-m", "rerun", "mcap", "convert"])
        .arg(&path)
        .arg("-o")
        .arg(&rrd)
        .output()
        .unwrap();
    let log =
        String::from_utf8_lossy(&out.stderr).to_string() + &String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{log}");
    for entity in [
        "/joint_states/position",
        "/joint_states/velocity",
        "/imu",
        "/tf",
    ] {
        assert!(
            log.contains(&format!("{entity},")),
            "rerun found no {entity}: {log}"
        );
    }
    assert!(rrd.metadata().unwrap().len() > 0);
    let _ = std::fs::remove_dir_all(&dir);
}
