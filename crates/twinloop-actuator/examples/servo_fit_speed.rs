//! The richest servo fit (issue 32 item 5): the known-truth setup of
//! `tests/known_truth.rs::backlash_and_delays_recovered` (an XM430 on a 0.5 kg,
//! 15 cm pendulum, m1 plus backlash and both delays, 1 kHz log of the standard
//! excitation), timed on a given number of threads.
//!
//! `cargo run --release -p twinloop-actuator --example servo_fit_speed -- THREADS
//! [PERIOD_S] [SIMS]`: prints the wall and CPU time, the simulations, and the fitted
//! values with their bits (to compare runs on different thread counts). With SIMS,
//! runs only that many replays of the whole log with the truth's parameters (the
//! fit's unit of work, small enough for callgrind) and prints a checksum of them.

use twinloop_actuator::datasheet::defaults;
use twinloop_actuator::identify::{IdentifyOptions, identify_with};
use twinloop_actuator::params::*;
use twinloop_actuator::synthetic::synthetic_log;
use twinloop_actuator::{Excitation, Load, ModelLevel, Pendulum, ServoType};
use twinloop_optim::parallel::on_threads;
use twinloop_random::SplitMix64;

/// CPU time of this process, s (user + system, from /proc/self/stat).
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let fields: Vec<&str> = stat
        .rsplit_once(')')
        .map_or(vec![], |(_, r)| r.split_whitespace().collect());
    let ticks = |i: usize| {
        fields
            .get(i)
            .and_then(|v| v.parse::<f64>().ok())
            .unwrap_or(0.0)
    };
    // utime and stime are fields 14 and 15 (11 and 12 after the name); 100 Hz ticks.
    (ticks(11) + ticks(12)) / 100.0
}

/// `sims` replays of all of `log` with `params`; prints a hash of their bits.
fn replays(params: &ServoParams, load: &Load, log: &twinloop_actuator::log::ServoLog, sims: usize) {
    let (mut q, mut c) = (vec![0.0; log.len()], vec![0.0; log.len()]);
    let mut sum = 0xcbf2_9ce4_8422_2325u64;
    let c0 = cpu_seconds();
    for _ in 0..sims {
        twinloop_actuator::replay::replay(params, load, log, 0..log.len(), &mut q, &mut c);
        // FNV-1a over every value's bits: any changed bit shows.
        for v in q.iter().chain(&c[1..]) {
            sum = (sum ^ v.to_bits()).wrapping_mul(0x100_0000_01b3);
        }
    }
    println!(
        "{sims} replays of {} rows: cpu {:.3} s, bits' hash {sum:016x}",
        log.len(),
        cpu_seconds() - c0,
    );
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let threads: usize = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(1);
    let period: f64 = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(1e-3);
    let load = Load::from(Pendulum {
        mass: 0.5,
        length: 0.15,
        arm_inertia: 0.002,
    });
    let servo = ServoType::Xm430W350;
    let mut truth = defaults(servo, ModelLevel::M1);
    let mut rng = SplitMix64(40);
    for &i in &ModelLevel::M1.parameters() {
        truth.values[i] *= rng.uniform(0.7, 1.4);
    }
    let mut rng = SplitMix64(90);
    truth.values[BACKLASH] = rng.uniform(0.3, 0.8).to_radians();
    truth.values[SENSING_DELAY] = rng.uniform(0.5e-3, 2e-3);
    truth.values[BUS_DELAY] = rng.uniform(0.5e-3, 3e-3);
    let log = synthetic_log(
        &truth,
        &load,
        &Excitation::standard(servo, 1.0),
        period,
        0.2 * period,
        11,
    );
    if let Some(sims) = args.get(3).and_then(|a| a.parse::<usize>().ok()) {
        replays(&truth, &load, &log, sims);
        return;
    }
    let start = defaults(servo, ModelLevel::M1);
    let options = IdentifyOptions {
        nonsmooth: NONSMOOTH.to_vec(),
        ..Default::default()
    };
    let (t0, c0) = (std::time::Instant::now(), cpu_seconds());
    let id = on_threads(threads, || {
        identify_with(
            std::slice::from_ref(&log),
            &[],
            &load,
            &start,
            0.25,
            &options,
        )
    })
    .expect("the fit runs");
    let (wall, cpu) = (t0.elapsed().as_secs_f64(), cpu_seconds() - c0);
    println!(
        "threads {threads}: {} rows, wall {wall:.2} s, cpu {cpu:.2} s, {} LM iterations, {} LM simulations, {} CMA-ES, held-out {:.4} mrad",
        log.len(),
        id.iterations,
        id.evaluations,
        id.nonsmooth_evaluations,
        id.heldout_rms_mrad
    );
    for i in ModelLevel::M1.parameters().into_iter().chain(NONSMOOTH) {
        println!(
            "  {:18} {:.9e} {:016x}",
            PARAM_NAMES[i],
            id.params.values[i],
            id.params.values[i].to_bits()
        );
    }
}
