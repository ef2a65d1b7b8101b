//! Client and virtual robot through a line that flips bits, drops and inserts bytes
//! (1 % of bytes, both directions) for 100 000 control cycles: every failure is
//! reported per servo, the client recovers, a recording over the noisy line keeps
//! every row it read, and no corrupted value is accepted from a Protocol 2.0 servo.
//!
//! Protocol 1.0 cannot promise the last with its checksum alone: it is an 8-bit
//! sum, so any damage whose byte sum is a multiple of 256 passes (a data bit and
//! the same checksum bit flipped opposite ways; the same bit flipped opposite ways
//! in two bytes; bit 7 flipped alike in two bytes). `protocol_1_defences` measures
//! what each defence on top leaves: reply checks (id, length, reserved error bit),
//! range checks, and verified reads (two consecutive replies must agree).

use twinloop_link::ModelTable;
use twinloop_link::transport::{LoopbackTransport, NoisyTransport};
use twinloop_link::{
    BusServo, Client, ClientConfig, ControlCycle, CycleServo, DynamixelRobot, Item, LinkError,
    ReadMethod, RobotMapping, ServoModel, ServoReading, TrackingServoModel, VirtualBus,
};
use twinloop_robot::{Robot, RobotState};

type Line = NoisyTransport<LoopbackTransport<VirtualBus<TrackingServoModel>>>;

fn noisy_client(servos: &[BusServo], rate: f64, seed: u64) -> Client<Line> {
    let bus = VirtualBus::with_tracking_model(servos);
    let config = ClientConfig {
        retries: 2,
        ..ClientConfig::default()
    };
    Client::with_config(
        NoisyTransport::new(LoopbackTransport::new(bus), rate, seed),
        config,
    )
}

fn bus(c: &mut Client<Line>) -> &mut VirtualBus<TrackingServoModel> {
    &mut c.transport_mut().inner.responder
}

#[derive(Default, Debug)]
struct Tally {
    accepted: u64,
    accepted_v1: u64,
    failed: u64,
    /// Accepted values that differ from the servo's registers, Protocol 2.0.
    corrupted_accepted: u64,
    /// The same for Protocol 1.0 servos.
    corrupted_accepted_v1: u64,
    timeouts: u64,
    corrupt: u64,
    other: u64,
}

/// Run `cycles` cycles; check every accepted value against the servo's registers.
fn run(c: &mut Client<Line>, servos: &[BusServo], method: ReadMethod, cycles: usize) -> Tally {
    run_with(c, servos, method, cycles, |_| {})
}

fn run_with(
    c: &mut Client<Line>,
    servos: &[BusServo],
    method: ReadMethod,
    cycles: usize,
    configure: impl Fn(&mut ControlCycle),
) -> Tally {
    let cs: Vec<CycleServo> = servos
        .iter()
        .map(|s| CycleServo::new(s.id, s.model))
        .collect();
    let mut cycle = ControlCycle::new(&cs, method).unwrap();
    configure(&mut cycle);
    let mut readings = vec![ServoReading::default(); cs.len()];
    let mut goals = vec![0i32; cs.len()];
    let mut tally = Tally::default();
    // Torque on (retried: the line is noisy).
    for _ in 0..5 {
        for s in servos {
            let _ = c.write(
                s.model.protocol(),
                s.id,
                s.model.table().item(Item::TorqueEnable).unwrap().address,
                &[1],
            );
        }
    }
    for k in 0..cycles {
        let t = k as f64 * 0.005;
        for (i, s) in cs.iter().enumerate() {
            let g = s.model.table().item(Item::GoalPosition).unwrap();
            goals[i] = g.from_si(0.8 * (1.3 * t + i as f64).sin());
        }
        let summary = cycle.run(c, Some(&goals), &mut readings).unwrap();
        assert_eq!(
            summary.ok + summary.failed,
            cs.len(),
            "every servo accounted for"
        );
        let truth = &bus(c).servos;
        for (i, r) in readings.iter().enumerate() {
            match &r.outcome {
                Ok(_) => {
                    tally.accepted += 1;
                    let v1 = cs[i].model.protocol() == twinloop_link::Protocol::V1;
                    tally.accepted_v1 += v1 as u64;
                    let s = &truth[i];
                    let effort = if cycle.effort_register(i).item == Some(Item::PresentLoad) {
                        s.value(Item::PresentLoad)
                    } else {
                        s.value(Item::PresentCurrent)
                    };
                    let real = (
                        s.value(Item::PresentPosition),
                        s.value(Item::PresentVelocity),
                        effort,
                    );
                    if (r.position, r.velocity, r.effort) != real {
                        if v1 {
                            tally.corrupted_accepted_v1 += 1;
                        } else {
                            tally.corrupted_accepted += 1;
                        }
                    }
                }
                Err(e) => {
                    tally.failed += 1;
                    match e {
                        LinkError::Timeout { .. } => tally.timeouts += 1,
                        LinkError::Corrupt { .. }
                        | LinkError::Implausible { .. }
                        | LinkError::Unverified { .. } => tally.corrupt += 1,
                        // Checksum/CRC error statuses left after the retries.
                        _ => tally.other += 1,
                    }
                }
            }
        }
        bus(c).step(0.005);
    }
    tally
}

#[test]
fn hundred_thousand_noisy_cycles_on_a_mixed_bus() {
    // The humanoid mix: 10 XM430 on Protocol 2.0 (FAST_SYNC_READ), 10 RX-28/64 on
    // Protocol 1.0 (one READ each), same line.
    let mut servos = Vec::new();
    for id in 1..=10 {
        servos.push(BusServo {
            id,
            model: ServoModel::Xm430W350,
        });
    }
    for id in 11..=20 {
        servos.push(BusServo {
            id,
            model: if id < 16 {
                ServoModel::Rx28
            } else {
                ServoModel::Rx64
            },
        });
    }
    let mut c = noisy_client(&servos, 0.01, 0x7711_2024);
    let tally = run(&mut c, &servos, ReadMethod::Auto, 100_000);
    let noise = c.transport().stats;
    println!("{tally:?}\n{noise:?}\n{:?}", c.stats);
    assert!(noise.flipped > 10_000 && noise.dropped > 10_000 && noise.inserted > 10_000);
    assert_eq!(tally.corrupted_accepted, 0, "Protocol 2.0: {tally:?}");
    let v1_rate = tally.corrupted_accepted_v1 as f64 / tally.accepted_v1 as f64;
    println!(
        "Protocol 1.0: {} of {} accepted reads corrupted ({v1_rate:.1e})",
        tally.corrupted_accepted_v1, tally.accepted_v1
    );
    assert!(v1_rate < 1e-4, "Protocol 1.0: {tally:?}");
    assert!(
        tally.failed > 1000,
        "the noise must have cost something: {tally:?}"
    );
    // Retries keep most reads: at 1 % noise at least 95 % of servo reads succeed.
    assert!(tally.accepted as f64 > 0.95 * 2_000_000.0, "{tally:?}");
    // The client recovers at once when the line is clean again.
    c.transport_mut().rate = 0.0;
    let clean = run(&mut c, &servos, ReadMethod::Auto, 200);
    assert_eq!(clean.failed, 0, "{clean:?}");
    assert_eq!(clean.corrupted_accepted + clean.corrupted_accepted_v1, 0);
}

#[test]
fn recording_over_a_noisy_line_keeps_every_row_it_read() {
    let mapping = RobotMapping::builtin("km20").unwrap();
    let servos: Vec<BusServo> = mapping.bus();
    let c = noisy_client(&servos, 0.01, 99);
    let mut robot = DynamixelRobot::new(c, mapping.clone(), ReadMethod::Auto).unwrap();
    let path = std::env::temp_dir().join(format!("twinloop-noisy-{}.csv", std::process::id()));
    let n = mapping.joints.len();
    let mut columns = vec!["t".to_string()];
    columns.extend(mapping.joints.iter().map(|j| format!("q:{}", j.name)));
    let mut w = twinloop_io::CsvWriter::recording(&path, &columns).unwrap();
    let mut state = RobotState::default();
    let mut written: Vec<Vec<f64>> = Vec::new();
    let mut joint_failures = 0;
    for k in 0..2000 {
        if robot.read(&mut state).is_err() {
            joint_failures += 1;
        }
        // Times are written to the nanosecond (`clean_time`).
        let mut row = vec![twinloop_io::clean_time(k as f64 * 0.01)];
        row.extend_from_slice(&state.positions);
        w.write_row(&row).unwrap();
        written.push(row);
        robot.client.transport_mut().inner.responder.step(0.01);
    }
    // Read the file back before closing the writer: a recording is on disk as
    // FILE.partial while it runs, and the flushed rows are all there.
    let table = twinloop_io::Table::read(twinloop_io::output::in_progress(&path)).unwrap();
    w.finish().unwrap();
    let _ = std::fs::remove_file(&path);
    assert_eq!(table.rows.len(), written.len());
    for (a, b) in table.rows.iter().zip(&written) {
        assert_eq!(a.len(), n + 1);
        for (x, y) in a.iter().zip(b) {
            assert!(x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()));
        }
    }
    let kept = written
        .iter()
        .flat_map(|r| &r[1..])
        .filter(|x| !x.is_nan())
        .count();
    assert!(
        kept as f64 > 0.95 * (2000 * n) as f64,
        "{kept} of {}",
        2000 * n
    );
    assert!(joint_failures > 0, "the line was noisy");
}

/// Protocol 1.0 alone (10 RX servos, one READ each) through the same noise, 100 000
/// cycles per defence. Reply checks (id, length, bit 7 of the error byte) are
/// always on; range checks discard values outside their register (RX position
/// above 1023, speed or load above 2047) after one re-read; verified reads accept a
/// servo's block only when two consecutive replies agree byte for byte.
#[test]
fn protocol_1_defences() {
    let servos: Vec<BusServo> = (1..=10)
        .map(|id| BusServo {
            id,
            model: if id % 2 == 0 {
                ServoModel::Rx64
            } else {
                ServoModel::Rx28
            },
        })
        .collect();
    let cycles = 100_000;
    let mut rates = Vec::new();
    for (name, range, verify) in [
        ("reply checks only", false, false),
        ("+ range checks", true, false),
        ("+ range checks + verified reads", true, true),
    ] {
        let mut c = noisy_client(&servos, 0.01, 0x5eed_0001);
        let t = run_with(&mut c, &servos, ReadMethod::Read, cycles, |cy| {
            cy.range_checks = range;
            cy.verify_v1 = verify;
        });
        let rate = t.corrupted_accepted_v1 as f64 / t.accepted_v1 as f64;
        println!(
            "{name}: {} of {} accepted reads corrupted ({rate:.1e}); {} failed; {} requests",
            t.corrupted_accepted_v1, t.accepted_v1, t.failed, c.stats.requests
        );
        assert!(
            t.accepted_v1 as f64 > 0.95 * (cycles * servos.len()) as f64,
            "{name}: {t:?}"
        );
        rates.push(t.corrupted_accepted_v1);
    }
    // The checksum alone lets corrupted values through at this noise level (the test
    // can see them), range checks remove some, verified reads all that occurred.
    assert!(rates[0] > 0, "{rates:?}");
    assert!(rates[1] <= rates[0], "{rates:?}");
    assert_eq!(rates[2], 0, "{rates:?}");
}
