//! The long known-truth sweep of servo identification (docs/servo-models.md, "Honest
//! deviations"): `cargo run --profile ci -p twinloop-actuator --example servo_sweep
//! -- [TRUTHS_PER_TYPE] [FIRST_SEED]`. Each type gets that many hidden random truths
//! (every m1 parameter times 0.7-1.3, the voltage 0.9-1.1); every reported number
//! is checked: within max(5 %, 3 sd) of the truth, or not determined with the truth
//! in its interval. Prints one line per number and a summary; exits 1 on a failure.
//!
//! For the sweep over ptys (`bench/servo/honest_sweep.sh`): `servo_sweep truth SERVO
//! SEED OUT.toml` writes a drawn truth, `servo_sweep load SERVO OUT.toml` its
//! pendulum, and `servo_sweep check TRUTH.toml FIT.json` checks what `identify servo
//! --json` reported.

use std::path::Path;
use twinloop_actuator::ServoType;
use twinloop_actuator::params::{FRICTION_VISCOUS, KT, PARAM_NAMES, RESISTANCE, ServoParams};
use twinloop_actuator::sweep::{Check, bench_load, draw_truth, run_case};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("truth") => return write_truth(&args[1..]),
        Some("load") => return write_load(&args[1..]),
        Some("check") => return check_json(&args[1..]),
        _ => {}
    }
    let per_type: u64 = args.first().and_then(|a| a.parse().ok()).unwrap_or(5);
    let first: u64 = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(100);
    let (mut numbers, mut failed, mut worst_sigma) = (0, 0, 0.0f64);
    let mut worst_rel: Vec<(&str, f64)> = Vec::new();
    for servo in ServoType::ALL {
        for seed in first..first + per_type {
            let case = match run_case(servo, seed, 1.0) {
                Ok(c) => c,
                Err(e) => {
                    eprintln!("{servo} seed {seed}: {e}");
                    std::process::exit(1);
                }
            };
            println!(
                "{servo} seed {seed}: {:.2} s, held-out {:.3} mrad",
                case.seconds, case.heldout_rms_mrad
            );
            for c in &case.checks {
                numbers += 1;
                let ok = c.honest();
                if !ok {
                    failed += 1;
                }
                let shown = match c.interval {
                    Some((lo, hi)) => format!("not determined, in [{lo:.4}, {hi:.4}]"),
                    None => {
                        worst_sigma = worst_sigma.max(c.sigmas());
                        let key = format!("{servo} {}", c.name);
                        let e = c.error().abs();
                        match worst_rel.iter_mut().find(|(k, _)| *k == key) {
                            Some(w) => w.1 = w.1.max(e),
                            None => worst_rel.push((Box::leak(key.into_boxed_str()), e)),
                        }
                        format!(
                            "{:+.2} % ({:.2} sd, sd {:.2} %)",
                            100.0 * c.error(),
                            c.sigmas(),
                            100.0 * c.sd / c.truth
                        )
                    }
                };
                println!(
                    "  {} {:34} truth {:.5} fit {:.5} {shown}",
                    if ok { " " } else { "!" },
                    c.name,
                    c.truth,
                    c.value
                );
            }
        }
    }
    println!("worst relative error per servo and number:");
    for (k, e) in &worst_rel {
        println!("  {k:48} {:.2} %", 100.0 * e);
    }
    println!(
        "{numbers} numbers reported, {failed} outside max(5 %, 3 sd) and not reported as not determined; largest error of a determined one {worst_sigma:.2} sd"
    );
    if failed > 0 {
        std::process::exit(1);
    }
}

fn servo_arg(name: Option<&String>) -> ServoType {
    name.and_then(|n| ServoType::parse(n))
        .unwrap_or_else(|| fail(&format!("a servo type: {}", ServoType::known_names())))
}

fn fail(msg: &str) -> ! {
    eprintln!("servo_sweep: {msg}");
    std::process::exit(2)
}

fn write_truth(args: &[String]) {
    let servo = servo_arg(args.first());
    let seed: u64 = args
        .get(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or_else(|| fail("a seed"));
    let out = args.get(2).unwrap_or_else(|| fail("an output file"));
    let text = draw_truth(servo, seed).to_toml(&format!("hidden truth: {servo}, seed {seed}"));
    std::fs::write(out, text).unwrap_or_else(|e| fail(&format!("{out}: {e}")));
}

fn write_load(args: &[String]) {
    let servo = servo_arg(args.first());
    let out = args.get(1).unwrap_or_else(|| fail("an output file"));
    let p = bench_load(servo);
    let text = format!(
        "mass = {:?}\nlength = {:?}\narm_inertia = {:?}\n",
        p.mass, p.length, p.arm_inertia
    );
    std::fs::write(out, text).unwrap_or_else(|e| fail(&format!("{out}: {e}")));
}

/// `identify servo --json`'s report of one fit against the truth file.
fn check_json(args: &[String]) {
    let (Some(truth), Some(json)) = (args.first(), args.get(1)) else {
        fail("check TRUTH.toml FIT.json")
    };
    let truth = ServoParams::read(Path::new(truth)).unwrap_or_else(|e| fail(&e.to_string()));
    let text = std::fs::read_to_string(json).unwrap_or_else(|e| fail(&format!("{json}: {e}")));
    let v: serde_json::Value =
        serde_json::from_str(&text).unwrap_or_else(|e| fail(&format!("{json}: {e}")));
    let mut checks = Vec::new();
    let intervals = v["intervals"].as_array().cloned().unwrap_or_default();
    for (i, name) in PARAM_NAMES.iter().enumerate() {
        let interval = intervals.iter().find(|x| x["name"] == *name).map(|x| {
            (
                x["low"].as_f64().unwrap_or(f64::NAN),
                x["high"].as_f64().unwrap_or(f64::INFINITY),
            )
        });
        let p = &v["params"][*name];
        if p.is_null() && interval.is_none() {
            continue;
        }
        checks.push(Check {
            name,
            truth: truth.values[i],
            value: p["value"].as_f64().unwrap_or(f64::NAN),
            sd: p["sd"].as_f64().unwrap_or(f64::NAN),
            interval,
        });
    }
    let (kt, r, b) = (
        truth.values[KT],
        truth.values[RESISTANCE],
        truth.values[FRICTION_VISCOUS],
    );
    for c in v["combinations"].as_array().cloned().unwrap_or_default() {
        let name = c["name"].as_str().unwrap_or("");
        checks.push(Check {
            name: if name == "kt/resistance" {
                "kt/resistance"
            } else {
                "kt^2/resistance + friction_viscous"
            },
            truth: if name == "kt/resistance" {
                kt / r
            } else {
                kt * kt / r + b
            },
            value: c["value"].as_f64().unwrap_or(f64::NAN),
            sd: c["sd"].as_f64().unwrap_or(f64::NAN),
            interval: None,
        });
    }
    let mut failed = 0;
    for c in &checks {
        let ok = c.honest();
        failed += usize::from(!ok);
        match c.interval {
            Some((lo, hi)) => println!(
                "{} {:34} truth {:.5} not determined, in [{lo:.4}, {hi:.4}]",
                if ok { " " } else { "!" },
                c.name,
                c.truth
            ),
            None => println!(
                "{} {:34} truth {:.5} fit {:.5} {:+.2} % ({:.2} sd, sd {:.2} %)",
                if ok { " " } else { "!" },
                c.name,
                c.truth,
                c.value,
                100.0 * c.error(),
                c.sigmas(),
                100.0 * c.sd / c.truth
            ),
        }
    }
    if failed > 0 {
        std::process::exit(1);
    }
}
