//! `twinloop bench link`: the software overhead of a Dynamixel control cycle
//! (replies replayed from memory) and, with --port, transactions per second against
//! a served robot.

use crate::bus_args::{PortArgs, open_client};
use crate::common::emit;
use crate::error::{CliError, CliResult, Outcome};
use clap::Args;
use serde::Serialize;
use std::path::PathBuf;
use std::time::{Duration, Instant};
use twinloop_link::control_cycle::ReadMethod;
use twinloop_link::transport::Transport;
use twinloop_link::{BusServo, Client, Protocol, ServoModel, VirtualBus, plan_cycle};

#[derive(Args, Debug)]
pub struct LinkBenchArgs {
    /// A served robot (`twinloop serve --map builtin:op3 --no-timing`) to time real
    /// transactions against; without it only the software overhead is measured
    #[arg(long, value_name = "PATH")]
    pub port: Option<String>,
    /// Servos in the cycle (ids 1..=N)
    #[arg(long, default_value_t = 20)]
    pub servos: u8,
    /// Seconds per case
    #[arg(long, default_value_t = 1.0, value_parser = crate::bounds::wall_seconds)]
    pub seconds: f64,
    /// With --port: busy-check the pty for up to this many microseconds before
    /// sleeping for a reply (0: sleep at once)
    #[arg(long, default_value_t = 0, value_name = "US")]
    pub spin_us: u64,
    /// Write JSON {"cases": [{"name", "median_us", "cpu_us", "per_second", "wire_us",
    /// "overhead_ratio"}]} to FILE (-: to stdout, in place of the text)
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
}

#[derive(Serialize)]
struct BenchCase {
    name: String,
    median_us: f64,
    /// CPU time of this thread per call, us (Linux /proc/thread-self/schedstat):
    /// what the client itself burns, whatever the scheduler does to the wall clock.
    cpu_us: Option<f64>,
    per_second: f64,
    wire_us: Option<f64>,
    overhead_ratio: Option<f64>,
}

/// Replies recorded from a real virtual bus, replayed by request: what is left to
/// time is the client (and one hash lookup).
struct Replay {
    bus: VirtualBus<twinloop_link::TrackingServoModel>,
    cache: std::collections::HashMap<Vec<u8>, Vec<u8>>,
}

impl twinloop_link::transport::Responder for Replay {
    fn respond(&mut self, input: &[u8], reply: &mut Vec<u8>) {
        if let Some(r) = self.cache.get(input) {
            reply.extend_from_slice(r);
            return;
        }
        let start = reply.len();
        twinloop_link::transport::Responder::respond(&mut self.bus, input, reply);
        self.cache.insert(input.to_vec(), reply[start..].to_vec());
    }
}

/// This thread's CPU time so far, ns (first field of /proc/thread-self/schedstat).
fn thread_cpu_ns() -> Option<u64> {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()?
        .split_whitespace()
        .next()?
        .parse()
        .ok()
}

/// Median over batches of the wall time per call of `f`, and the mean CPU time per
/// call, both in us.
fn median_us(seconds: f64, batch: usize, mut f: impl FnMut()) -> (f64, Option<f64>) {
    for _ in 0..batch.min(50) {
        f();
    }
    let mut samples = Vec::new();
    let start = Instant::now();
    let cpu0 = thread_cpu_ns();
    while samples.len() < 7 || (start.elapsed().as_secs_f64() < seconds && samples.len() < 10_000) {
        let t = Instant::now();
        for _ in 0..batch {
            f();
        }
        samples.push(t.elapsed().as_secs_f64() * 1e6 / batch as f64);
    }
    let calls = (samples.len() * batch) as f64;
    let cpu = cpu0
        .zip(thread_cpu_ns())
        .map(|(a, b)| (b - a) as f64 / 1e3 / calls);
    samples.sort_by(f64::total_cmp);
    (samples[samples.len() / 2], cpu)
}

fn cycle_servos(model: ServoModel, n: u8) -> Vec<twinloop_link::CycleServo> {
    (1..=n)
        .map(|id| twinloop_link::CycleServo::new(id, model))
        .collect()
}

/// READ, SYNC_READ, FAST_SYNC_READ and a whole cycle on XM430 ids 1..=n; false if
/// any failed.
fn transaction_cases<T: Transport>(
    c: &mut Client<T>,
    n: u8,
    seconds: f64,
    label: &str,
    cases: &mut Vec<BenchCase>,
) -> bool {
    let ids: Vec<u8> = (1..=n).collect();
    let mut out4 = vec![0u8; ids.len() * 4];
    let mut outcomes: Vec<twinloop_link::Outcome> = ids
        .iter()
        .map(|_| Ok(twinloop_link::StatusError::new(Protocol::V2, 0)))
        .collect();
    let mut ok = true;
    let mut b = [0u8; 4];
    let mut push = |name: String, (us, cpu): (f64, Option<f64>)| {
        cases.push(BenchCase {
            name,
            median_us: us,
            cpu_us: cpu,
            per_second: 1e6 / us,
            wire_us: None,
            overhead_ratio: None,
        })
    };
    push(
        format!("{label}: READ 4 B (one servo)"),
        median_us(seconds, 50, || {
            ok &= c.read(Protocol::V2, 1, 132, &mut b).is_ok()
        }),
    );
    push(
        format!("{label}: SYNC_READ 4 B x {n}"),
        median_us(seconds, 20, || {
            ok &= c.sync_read(132, 4, &ids, &mut out4, &mut outcomes).is_ok()
                && outcomes.iter().all(|o| o.is_ok())
        }),
    );
    push(
        format!("{label}: FAST_SYNC_READ 4 B x {n}"),
        median_us(seconds, 20, || {
            ok &= c
                .fast_sync_read(132, 4, &ids, &mut out4, &mut outcomes)
                .is_ok()
                && outcomes.iter().all(|o| o.is_ok())
        }),
    );
    let servos = cycle_servos(ServoModel::Xm430W350, n);
    let mut cycle =
        twinloop_link::ControlCycle::new(&servos, ReadMethod::FastSyncRead).expect("valid");
    let mut readings = vec![twinloop_link::ServoReading::default(); servos.len()];
    let goals = vec![2048; servos.len()];
    push(
        format!("{label}: cycle SYNC_WRITE + FAST_SYNC_READ 10 B x {n}"),
        median_us(seconds, 20, || {
            ok &= cycle
                .run(c, Some(&goals), &mut readings)
                .map(|s| s.failed == 0)
                .unwrap_or(false)
        }),
    );
    ok
}

pub fn run(a: &LinkBenchArgs) -> CliResult {
    if a.servos == 0 || a.servos > 252 {
        return Err(CliError::new(format!(
            "--servos {}: must be 1..=252",
            a.servos
        )));
    }
    let mut cases = software_cases(a)?;
    if let Some(port) = &a.port {
        port_cases(a, port, &mut cases)?;
    }
    #[derive(Serialize)]
    struct Out<'a> {
        cases: &'a [BenchCase],
    }
    emit(
        &cases_table(&cases),
        a.json.as_ref(),
        &Out { cases: &cases },
    )?;
    Ok(Outcome::Ok)
}

/// The client's own cost: a control cycle per read method and the single
/// transactions, replies replayed from memory.
fn software_cases(a: &LinkBenchArgs) -> Result<Vec<BenchCase>, CliError> {
    let n = a.servos;
    let mut cases = Vec::new();
    // Software overhead per cycle: replayed replies.
    for (model, method, len, label) in [
        (
            ServoModel::Xm430W350,
            ReadMethod::FastSyncRead,
            10,
            "FAST_SYNC_READ",
        ),
        (ServoModel::Xm430W350, ReadMethod::SyncRead, 10, "SYNC_READ"),
        (ServoModel::Rx28, ReadMethod::Read, 6, "READ x N"),
    ] {
        let servos = cycle_servos(model, n);
        let bus_servos: Vec<BusServo> = servos
            .iter()
            .map(|s| BusServo { id: s.id, model })
            .collect();
        let replay = Replay {
            bus: VirtualBus::with_tracking_model(&bus_servos),
            cache: Default::default(),
        };
        let mut c = Client::new(twinloop_link::transport::LoopbackTransport::new(replay));
        let mut cycle = twinloop_link::ControlCycle::new(&servos, method)?;
        let mut readings = vec![twinloop_link::ServoReading::default(); servos.len()];
        let goals: Vec<i32> = servos
            .iter()
            .map(|_| {
                if model.protocol() == Protocol::V1 {
                    512
                } else {
                    2048
                }
            })
            .collect();
        let (us, cpu) = median_us(a.seconds, 200, || {
            let s = cycle
                .run(&mut c, Some(&goals), &mut readings)
                .expect("in memory");
            debug_assert_eq!(s.failed, 0);
        });
        let goal = if model.protocol() == Protocol::V1 {
            2
        } else {
            4
        };
        let wire = plan_cycle(
            model.protocol(),
            method,
            n as usize,
            len,
            goal,
            1_000_000,
            Duration::ZERO,
        )
        .wire
        .as_secs_f64()
            * 1e6;
        cases.push(BenchCase {
            name: format!(
                "software: {n}-servo cycle, {} {model}, SYNC_WRITE + {label} ({len} B)",
                model.protocol()
            ),
            median_us: us,
            cpu_us: cpu,
            per_second: 1e6 / us,
            wire_us: Some(wire),
            overhead_ratio: Some(us / wire),
        });
    }
    // The same transactions as over a port, replies replayed from memory: the
    // client's own cost per transaction (bench_sdk.py --replay does the same for the
    // Python SDK).
    {
        let servos: Vec<BusServo> = (1..=n)
            .map(|id| BusServo {
                id,
                model: ServoModel::Xm430W350,
            })
            .collect();
        let replay = Replay {
            bus: VirtualBus::with_tracking_model(&servos),
            cache: Default::default(),
        };
        let mut c = Client::new(twinloop_link::transport::LoopbackTransport::new(replay));
        transaction_cases(&mut c, n, a.seconds, "replay", &mut cases);
    }
    Ok(cases)
}

/// The same transactions over a port to a served robot.
fn port_cases(a: &LinkBenchArgs, port: &str, cases: &mut Vec<BenchCase>) -> Result<(), CliError> {
    let n = a.servos;
    {
        let p = PortArgs {
            spin_us: a.spin_us,
            ..PortArgs::quick(Some(port.to_string()), 50.0, 0)
        };
        let mut c = open_client(&p, None)?;
        if !transaction_cases(&mut c, n, a.seconds, "pty", cases) {
            return Err(CliError::new(format!(
                "some transactions on {port} failed: serve a robot with XM430 ids 1..={n} \
                 (twinloop serve --map builtin:op3 --no-timing)"
            )));
        }
    }
    Ok(())
}

fn cases_table(cases: &[BenchCase]) -> String {
    let mut out = String::from(
        "CASE                                                                  MEDIAN US   CPU US       PER S   WIRE US  OVERHEAD/WIRE\n",
    );
    for c in cases {
        out += &format!(
            "{:<68} {:>10.2} {:>8} {:>11.0} {:>9} {:>14}\n",
            c.name,
            c.median_us,
            c.cpu_us.map(|x| format!("{x:.2}")).unwrap_or_default(),
            c.per_second,
            c.wire_us.map(|w| format!("{w:.0}")).unwrap_or_default(),
            c.overhead_ratio
                .map(|r| format!("{:.3} %", 100.0 * r))
                .unwrap_or_default()
        );
    }
    out
}
