//! `twinloop experiment tipover --port PTY --map builtin:km20` as a user runs it: the
//! tip-over experiment on km20 served behind its virtual bus (`twinloop serve`),
//! against the same experiment on the simulator directly; and a servo that does not
//! answer stops it with exit 2, naming the servo, every row read in the record.

use nalgebra::Vector3;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;
use twinloop_experiments::tipover::{Direction, TipoverConfig, run_direction};
use twinloop_sim::{Actuator, SimConfig, Simulator};

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_twinloop")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

fn scratch(name: &str) -> PathBuf {
    Path::new(env!("CARGO_TARGET_TMPDIR")).join(name)
}

#[path = "support/served.rs"]
mod served;
use served::serve;

/// The forward tip of km20 on the simulator directly, with the CLI's settings
/// (ramp 5 deg/s, 1 s settle, no tilt predictor).
fn simulated_forward_tip_deg() -> f64 {
    let robot = twinloop_description::builtin::resolve("builtin:km20").unwrap();
    let mut sim = Simulator::new(&robot, SimConfig::default()).unwrap();
    for i in 0..sim.model.nbodies {
        sim.actuators[i] =
            Actuator::Dynamixel(twinloop_sim::servo_for_joint(&robot.name, &sim.model, i));
    }
    let standing = vec![0.0; sim.model.nbodies];
    sim.place_on_ground(&standing).unwrap();
    sim.run(1.0).unwrap();
    let m = sim.model.clone();
    let mut data = twinloop_dynamics::Data::new(&m);
    let q0 = m.neutral_configuration();
    let s = |n: &str| sim.joint_index(n).unwrap();
    let pitch = [s("l_ank_pitch"), s("r_ank_pitch")];
    let roll = [s("l_ank_roll"), s("r_ank_roll")];
    let fs = twinloop_sim::statics::lean_signs(&m, &mut data, &q0, pitch, Vector3::x());
    let ls = twinloop_sim::statics::lean_signs(&m, &mut data, &q0, roll, Vector3::y());
    let mut cfg = TipoverConfig::new(pitch, roll, fs, ls);
    cfg.ramp_deg_per_s = 5.0;
    run_direction(&mut sim, &standing, Direction::Forward, &cfg, None)
        .unwrap()
        .commanded_deg
}

#[test]
fn tipover_over_the_bus_of_a_served_km20_tips_forward_where_the_simulator_does() {
    let link = scratch("km20-tipover-link");
    let _ = std::fs::remove_file(&link);
    // An operator stands the robot up between the two runs; 4x real time.
    let (mut server, _pty) = serve(&[
        "--robot",
        "builtin:km20",
        "--link",
        link.to_str().unwrap(),
        "--catch-falls",
        "--realtime-factor",
        "4",
    ]);
    // The raw record as MCAP (the other tests record CSV).
    let record = scratch("tipover-forward.mcap");
    let t0 = Instant::now();
    let o = Command::new(bin())
        .args(["experiment", "tipover", "--port", link.to_str().unwrap()])
        .args([
            "--map",
            "builtin:km20",
            "--directions",
            "forward",
            "--ramp",
            "5",
            "--slow-ramp",
            "0.2",
            "--realtime-factor",
            "4",
        ])
        .args(["--json", "-", "--record"])
        .arg(&record)
        .output()
        .unwrap();
    let took = t0.elapsed();
    server.kill().unwrap();
    server.wait().unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let bus = v["forward"]["commanded_deg"].as_f64().unwrap();
    let measured = v["forward"]["measured_deg"].as_f64().unwrap();
    let sim = simulated_forward_tip_deg();
    eprintln!(
        "forward tip: over the bus {bus:.3} deg commanded ({measured:.3} measured), \
         simulator {sim:.3} deg; bus run {:.1} s",
        took.as_secs_f64()
    );
    assert!(
        (bus - sim).abs() < 1.5,
        "bus {bus} deg, simulator {sim} deg"
    );
    // The record: a row per cycle read, every column named; the robot on
    // /robot_description, as `link record` writes it.
    let table = twinloop_logs::read_log(&record, &Default::default()).unwrap();
    let info = twinloop_logs::log_info(&record).unwrap();
    let description = info.iter().find(|t| t.topic == "/robot_description");
    assert_eq!(description.map(|t| t.messages), Some(1), "{info:?}");
    assert!(table.rows.len() > 20, "{} rows", table.rows.len());
    for c in [
        "t",
        "q:l_ank_pitch",
        "goal:l_ank_pitch",
        "imu:accel_z",
        "tilt:pitch",
    ] {
        assert!(table.columns.iter().any(|x| x == c), "no column {c}");
    }
}

#[test]
fn a_servo_that_does_not_answer_stops_the_tipover_with_exit_2_naming_it_and_every_row_recorded() {
    let link = scratch("km20-tipover-silent-link");
    let _ = std::fs::remove_file(&link);
    let (mut server, _pty) = serve(&["--robot", "builtin:km20", "--link", link.to_str().unwrap()]);
    // The host's mapping has a servo (id 21) the bus does not have.
    let map = scratch("km20-with-id-21.toml");
    let km20 = include_str!("../../twinloop-link/src/mappings/km20.toml");
    std::fs::write(
        &map,
        format!("{km20}\n[[joint]]\nname = \"extra\"\nid = 21\nmodel = \"RX-28\"\n"),
    )
    .unwrap();
    let record = scratch("tipover-silent.csv");
    let o = Command::new(bin())
        .args(["experiment", "tipover", "--port", link.to_str().unwrap()])
        .args(["--map", map.to_str().unwrap(), "--robot", "builtin:km20"])
        .args(["--directions", "forward", "--ramp", "5", "--record"])
        .arg(&record)
        .output()
        .unwrap();
    server.kill().unwrap();
    server.wait().unwrap();
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    let last = err.lines().last().unwrap_or("");
    assert!(last.starts_with("error: "), "{err}");
    assert!(last.contains("servo id 21"), "{err}");
    assert!(last.contains("standing pose"), "{err}");
    // A servo that never answers is found when the loop registers to restore are
    // read, before anything moves (within the silence window): the record, if any,
    // holds what was read, and the terminal says how many rows.
    if let Ok(table) = twinloop_io::Table::read(&record) {
        let n = table.rows.len();
        assert!(n == 0 || err.contains(&format!("{n} rows")), "{err}");
    }
}

#[test]
fn a_servo_that_reports_overload_mid_ramp_stops_the_tipover_with_exit_2_naming_it_and_every_row_recorded()
 {
    use std::sync::Arc;
    use std::sync::atomic::{AtomicBool, Ordering};
    use twinloop_link::servo::{ServeOptions, VirtualBus, serve};
    use twinloop_link::transport::PtyTransport;
    // km20's bus with stand-in servos that track their goals and a level board: the
    // robot never tips, so the ramp runs until the overload.
    let mapping = twinloop_link::RobotMapping::builtin("km20").unwrap();
    let mut bus = VirtualBus::with_tracking_model(&mapping.bus());
    let k = mapping.joints.iter().position(|j| j.id == 7).unwrap();
    let condition = bus.servos[k].condition.clone();
    let mut pty = PtyTransport::open().unwrap();
    let path = pty.path().to_str().unwrap().to_string();
    let stop = Arc::new(AtomicBool::new(false));
    let stop2 = stop.clone();
    let server = std::thread::spawn(move || {
        let o = ServeOptions {
            emulate_baud: None,
            stop_on_eof: false,
            warn_stalls: false,
        };
        let _ = serve(&mut bus, &mut pty, &o, &stop2);
    });
    let record = scratch("tipover-overload.csv");
    let child = Command::new(bin())
        .args(["experiment", "tipover", "--port", &path])
        .args([
            "--map",
            "builtin:km20",
            "--directions",
            "forward",
            "--ramp",
            "5",
        ])
        .arg("--record")
        .arg(&record)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Standing upright for 1 s, 1 s of settling, then half a second into the ramp:
    // overload (Protocol 1.0 bit 5).
    std::thread::sleep(std::time::Duration::from_millis(2500));
    condition.store(0x20, Ordering::Relaxed);
    let o = child.wait_with_output().unwrap();
    stop.store(true, Ordering::Relaxed);
    server.join().unwrap();
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    let last = err.lines().last().unwrap_or("");
    assert!(last.starts_with("error: "), "{err}");
    assert!(last.contains("servo id 7"), "{err}");
    assert!(last.contains("overload"), "{err}");
    assert!(last.contains("standing pose"), "{err}");
    let table = twinloop_io::Table::read(&record).unwrap();
    assert!(table.rows.len() > 10, "{} rows", table.rows.len());
    assert!(err.contains(&format!("{} rows", table.rows.len())), "{err}");
}
