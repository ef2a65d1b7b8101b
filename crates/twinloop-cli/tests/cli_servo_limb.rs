//! Known-truth recovery on a limb of a held robot, over a pty: km20 served held in the
//! air (`serve --held`), its right hip pitch (an RX-28 swinging the whole leg, about
//! 0.78 N m at the horizontal: a fifth of its stall torque) given drawn m1
//! parameters (`--servo-params r_hip_pitch=FILE`), driven and logged by `experiment
//! servo --map builtin:km20 --joint r_hip_pitch` and fitted by `identify servo`
//! with no `--load` (the log rebuilds the limb's load from the description): every
//! parameter the data determines within 5 % (friction_base 10 %; or three stated
//! standard deviations), the held-out error within the encoder's resolution.
//!
//! Why 10 % for friction_base: the leg is a light load for the RX-28 (21 % of its
//! stall torque, below the 40 % docs/servo-models.md "Which load" finds a servo
//! without current sensing needs: at 20 % on the bench friction_base missed by up
//! to 8.3 %); and the truth runs in the simulator's servo
//! (twinloop-sim: 1 ms steps, its own friction and loop), the fit in the bench's
//! equations (twinloop-actuator), and the leg's other joints give a little under
//! the swing (the load is not exactly rigid), as on a real robot. Over seven runs of
//! this test friction_base came back 2.6 to 6.4 % high, the others within 3.2 %
//! (docs/servo-models.md); a systematic difference of the two implementations, not
//! noise (its stated deviation is 0.4 %).

#[path = "support/fit_check.rs"]
mod fit_check;

use std::path::PathBuf;
use std::process::{Command, Stdio};
use twinloop_actuator::datasheet::defaults;
use twinloop_actuator::{ModelLevel, ServoType};
use twinloop_random::SplitMix64;

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_twinloop")
}

/// Relative error allowed; friction_base's (module comment: why).
const TOLERANCE: f64 = 0.05;
const FRICTION_BASE_TOLERANCE: f64 = 0.10;

#[path = "support/linked.rs"]
mod linked;
use linked::serve_linked;

/// Serve km20 held with `params` on r_hip_pitch, run the experiment into `log`;
/// how far (s) the simulation fell behind the wall clock (0: it kept up).
fn record(dir: &std::path::Path, params: &std::path::Path, log: &std::path::Path) -> f64 {
    let link = dir.join("bus");
    let mut spec = std::ffi::OsString::from("r_hip_pitch=");
    spec.push(params);
    let server = serve_linked(
        Command::new(bin())
            .args([
                "serve",
                "--robot",
                "builtin:km20",
                "--held",
                "--servo-params",
            ])
            .arg(&spec)
            .arg("--link")
            .arg(&link)
            .stdout(Stdio::null())
            .stderr(Stdio::piped()),
        &link,
    );
    let out = Command::new(bin())
        .args(["experiment", "servo", "--port"])
        .arg(&link)
        .args([
            "--timeout-ms",
            "100",
            "--retries",
            "5",
            "--map",
            "builtin:km20",
            "--joint",
            "r_hip_pitch",
        ])
        .arg("--out")
        .arg(log)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // Ctrl-C: serve stops and says whether its simulation kept up.
    let mut server = server;
    let _ = Command::new("kill")
        .args(["-INT", &server.0.id().to_string()])
        .status();
    let mut err = String::new();
    if let Some(mut e) = server.0.stderr.take() {
        use std::io::Read;
        let _ = e.read_to_string(&mut err);
    }
    err.lines()
        .find_map(|l| {
            l.strip_prefix("the simulation fell ")
                .and_then(|r| r.split_whitespace().next())
                .and_then(|x| x.parse::<f64>().ok())
        })
        .unwrap_or(0.0)
}

#[test]
fn limb_servo_parameters_recovered_over_a_pty() {
    let t_start = std::time::Instant::now();
    let dir: PathBuf =
        std::env::temp_dir().join(format!("twinloop-servo-limb-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let servo = ServoType::Rx28;
    let mut rng = SplitMix64(29);
    let mut truth = defaults(servo, ModelLevel::M1);
    for &i in &ModelLevel::M1.parameters() {
        truth.values[i] *= rng.uniform(0.7, 1.4);
    }
    let params = dir.join("truth.toml");
    std::fs::write(&params, truth.to_toml("drawn truth")).unwrap();
    let log = dir.join("hip.csv");
    // The virtual robot runs on the wall clock: on a loaded machine its simulation
    // can fall behind (it then drops the time, and the log's clock no longer is the
    // robot's). Such a run is recorded again, up to three times in all.
    let mut attempts = 0;
    loop {
        attempts += 1;
        let behind = record(&dir, &params, &log);
        if behind == 0.0 {
            break;
        }
        eprintln!("the simulation fell {behind} s behind the wall clock: recording again");
        assert!(
            attempts < 3,
            "the simulation fell behind in each of {attempts} runs: the machine is too loaded"
        );
    }
    let text = std::fs::read_to_string(&log).unwrap();
    assert!(text.contains("# limb: joint r_hip_pitch zero 0 direction 1\n"));
    // Gravity from the held trunk's IMU board: upright within the accelerometer's
    // counts (4 g over 512).
    let g: Vec<f64> = text
        .lines()
        .find_map(|l| l.strip_prefix("# limb: gravity "))
        .expect("a gravity line")
        .split_whitespace()
        .take(3)
        .map(|x| x.parse().unwrap())
        .collect();
    eprintln!("gravity in the base frame {g:?}");
    let tilt = (g[0].hypot(g[1]) / -g[2]).atan().to_degrees();
    assert!(tilt < 1.0 && g[2] < 0.0, "trunk tilt {tilt} deg: {g:?}");
    assert!(text.contains("from board"), "{}", &text[..400]);
    // The sequence stayed inside the joint's range (-100 to 30 deg) less 0.1 rad.
    let (lo, hi) = (-100f64.to_radians() + 0.1, 30f64.to_radians() - 0.1);
    let q: Vec<f64> = text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with('t'))
        .map(|l| l.split(',').nth(3).unwrap().parse().unwrap())
        .collect();
    let (qmin, qmax) = q
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    eprintln!(
        "{} rows, hip pitch from {qmin:.3} to {qmax:.3} rad",
        q.len()
    );
    assert!(qmin > lo && qmax < hi, "{qmin} {qmax} outside {lo} {hi}");
    assert!(
        qmax - qmin > 0.8,
        "the sequence hardly moved: {qmin} to {qmax}"
    );
    let out = Command::new(bin())
        .args(["identify", "servo", "--data"])
        .arg(&log)
        .args(["--model", "m1", "--json", "-"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let fit: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let heldout = fit["heldout_rms_mrad"].as_f64().unwrap();
    let res_mrad = 1e3 * servo.resolution();
    eprintln!("held-out {heldout:.3} mrad RMS (resolution {res_mrad:.3} mrad)");
    let mut failures = Vec::new();
    if heldout.is_nan() || heldout >= res_mrad {
        failures.push(format!("held-out {heldout} mrad"));
    }
    let (more, checked) = fit_check::check_fit("", &fit, &truth, |name| {
        if name == "friction_base" {
            FRICTION_BASE_TOLERANCE
        } else {
            TOLERANCE
        }
    });
    failures.extend(more);
    assert_eq!(
        checked, 4,
        "armature, friction_base and the two motor combinations"
    );
    // The same fit with the description given again (--robot) and the load refused
    // for a bench log's missing limb lines.
    let again = Command::new(bin())
        .args(["identify", "servo", "--data"])
        .arg(&log)
        .args(["--robot", "builtin:km20", "--model", "m1", "--json", "-"])
        .output()
        .unwrap();
    assert!(
        again.status.success(),
        "{}",
        String::from_utf8_lossy(&again.stderr)
    );
    let fit2: serde_json::Value = serde_json::from_slice(&again.stdout).unwrap();
    assert_eq!(fit2["params"], fit["params"]);
    let _ = std::fs::remove_dir_all(&dir);
    eprintln!("{:.1} s in all", t_start.elapsed().as_secs_f64());
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Refusals name what is wrong: a joint the mapping lacks, a bench log with no
/// load, --id with --joint.
#[test]
fn limb_route_refusals() {
    let dir: PathBuf =
        std::env::temp_dir().join(format!("twinloop-servo-limb-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let link = dir.join("bus");
    let _server = serve_linked(
        Command::new(bin())
            .args(["serve", "--robot", "builtin:km20", "--held", "--link"])
            .arg(&link)
            .stdout(Stdio::null())
            .stderr(Stdio::null()),
        &link,
    );
    let out = Command::new(bin())
        .args(["experiment", "servo", "--port"])
        .arg(&link)
        .args(["--map", "builtin:km20", "--joint", "r_tail", "--out"])
        .arg(dir.join("x.csv"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("--joint \"r_tail\": not a joint"), "{err}");
    let out = Command::new(bin())
        .args(["experiment", "servo", "--port"])
        .arg(&link)
        .args(["--id", "1", "--joint", "r_knee", "--out"])
        .arg(dir.join("x.csv"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let bench_log = dir.join("bench.csv");
    let mut text = String::from("# twinloop experiment servo: RX-28 id 1 on x\n");
    text.push_str("t,goal,t_goal,q,v,load,current,voltage,temperature,compliance_slope,compliance_margin,punch\n");
    for k in 0..20 {
        text.push_str(&format!(
            "{},0,0,0,0,0,NaN,12,30,32,1,32\n",
            k as f64 * 0.01
        ));
    }
    std::fs::write(&bench_log, text).unwrap();
    let out = Command::new(bin())
        .args(["identify", "servo", "--data"])
        .arg(&bench_log)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("give --load LOAD.toml"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}
