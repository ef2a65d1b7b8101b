//! `twinloop link ...` (talk to the servos of a robot) and `twinloop serve` (put a
//! virtual robot on a pseudo-terminal or TCP port that any Dynamixel program can
//! talk to).

use crate::common::{EXIT_BAD_INPUT, EXIT_OK, num, print, print_json};
use clap::{Args, Subcommand};
use serde::Serialize;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};
use twinloop_io::CsvWriter;
use twinloop_link::control_cycle::ReadMethod;
use twinloop_link::servo::{ServeOptions, serve as serve_bus};
use twinloop_link::transport::{self, PtyTransport, SerialOptions, TcpTransport, Transport};
use twinloop_link::{
    BusServo, Client, ClientConfig, DynamixelRobot, FoundServo, JointMapping, Protocol,
    RobotMapping, ServoModel as Model, VirtualBus, plan_cycle,
};
use twinloop_robot::{Robot, RobotState};

#[derive(Subcommand)]
pub enum LinkCommand {
    /// Find the servos on a bus: id, model, firmware
    #[command(
        long_about = "Ping every id on the bus and list who answers: Protocol 2.0 with one broadcast \
PING (each servo answers in turn), Protocol 1.0 with a PING per id followed by a READ of the model \
number (1.0 ping replies carry no data). Without --protocol both protocols are scanned: 1.0 and 2.0 \
servos may share one line.",
        after_long_help = "Example:\n  twinloop link scan --port /dev/ttyUSB0 --baud 1000000 --protocol 2\n  \
twinloop link scan --port /dev/pts/5 --baud 1000000      # a robot from `twinloop serve`\n\n\
Output: one line per servo:\n  \
PROTOCOL  1.0 or 2.0\n  \
ID        servo id\n  \
MODEL     model name (\"unknown\" if twinloop has no control table for the number)\n  \
NUMBER    Model Number register\n  \
FIRMWARE  Firmware Version register\n\
then a count. --json prints [{protocol, id, model, model_number, firmware}].\n\n\
Exit code 0 (also when nothing answered), 2 when the port cannot be opened."
    )]
    Scan(ScanArgs),

    /// Read a servo's control table, with values in SI units
    #[command(
        long_about = "Read a servo's whole control table (one READ) and print every register \
(or the ones named) with its raw value and its value in SI units. The model is found by PING unless \
--model says it.",
        after_long_help = "Example:\n  twinloop link read --port /dev/ttyUSB0 --protocol 1 --id 3\n  \
twinloop link read --port /dev/pts/5 --protocol 2 --id 1 \"present position\" \"present current\"\n\n\
Output: one line per register:\n  \
ADDR    address, SIZE bytes, ACCESS R or RW, AREA eeprom or ram\n  \
NAME    e-manual name\n  \
RAW     decoded raw value (signed where the register is)\n  \
VALUE   in SI: rad, rad/s, A, V, s, load as a fraction of max torque, degC\n\
--json prints {protocol, id, model, registers: [{address, name, size, access, raw, value, unit}]}.\n\n\
Exit code 0; 2 when the port cannot be opened, the servo does not answer, or a name matches no\n\
register (the message names the servo id)."
    )]
    Read(ReadArgs),

    /// Record joint positions, velocities and torques to CSV until Ctrl-C or --duration
    #[command(
        long_about = "Read every joint of a robot (given by a mapping file, or by --protocol and \
--ids) in a loop and write one CSV row per read: t (s since start), q:<joint> (rad), v:<joint> \
(rad/s), tau:<joint> (N m, from Present Load or Present Current and the datasheet's stall torque: an \
estimate). Every row is flushed as it is written, so an interrupted recording (Ctrl-C, unplugged \
adapter, servo power lost) leaves a valid file with every row read so far. A joint whose servo did not \
answer in a read is NaN in that row; the others are kept.",
        after_long_help = "Example:\n  twinloop link record --port /dev/ttyUSB0 --robot robot.toml --duration 10 --out walk.csv\n  \
twinloop link record --port /dev/pts/5 --robot builtin:km20 --duration 5 --out km20.csv --rate 50\n  \
twinloop link record --port /dev/ttyUSB0 --protocol 2 --ids 1-20 --duration 3 --out raw.csv\n\n\
Output: the CSV file (columns t, q:*, v:*, tau:*, joints in mapping order; numbers at full\n\
precision), and on stderr a summary: rows written, reads per second, failed reads per joint.\n\n\
Exit code 0 when the duration ran out or Ctrl-C stopped it; 2 when the link failed (the rows\n\
read until then are in the file) or the input is bad."
    )]
    Record(RecordArgs),

    /// Print the wire-time budget of one control cycle
    #[command(
        long_about = "Compute the bytes and wire time of one control cycle (SYNC_WRITE of every goal \
position, then reading every servo) for each way the protocol offers, at the given bit rate: 10 bits \
per byte (8N1) plus each servo's Return Delay Time before its status packet. This is the floor no \
software can beat; twinloop's own overhead is measured against it (BENCHMARKS.md).",
        after_long_help = "Example:\n  twinloop link plan --servos 20 --protocol 2 --baud 1000000\n  \
twinloop link plan --servos 20 --protocol 1 --baud 1000000 --return-delay-us 500\n\n\
Output: one line per cycle variant:\n  \
READ          how the servos are read (READ per servo, BULK_READ, SYNC_READ, FAST_SYNC_READ)\n  \
BYTES/SERVO   bytes read per servo (position only, or load/current + velocity + position)\n  \
WRITE / READ  bytes of the goal SYNC_WRITE and of the read (requests and replies)\n  \
WIRE MS       time on the wire per cycle, ms; HZ the cycles per second that allows\n  \
TRIPS         request/reply round trips (each also pays the USB adapter's latency)\n  \
5% BUDGET     the software time per cycle that stays under 5 % of the wire time, us\n\
--json prints the same as a list of objects."
    )]
    Plan(PlanArgs),
}

#[derive(Args, Clone)]
pub struct PortArgs {
    /// Serial device (/dev/ttyUSB0), a pty path from `twinloop serve`, or tcp:HOST:PORT
    #[arg(long, value_name = "PATH")]
    pub port: Option<String>,
    /// Bit rate
    #[arg(long, default_value_t = 1_000_000)]
    pub baud: u32,
    /// Allowance per reply on top of its wire time, ms (USB latency, return delay)
    #[arg(long, default_value_t = 10.0)]
    pub timeout_ms: f64,
    /// Extra attempts after a lost or damaged reply
    #[arg(long, default_value_t = 2)]
    pub retries: u32,
    /// Set the USB adapter's latency timer to 1 ms (FTDI, via sysfs)
    #[arg(long)]
    pub low_latency: bool,
    /// Busy-check the port for up to this many microseconds before sleeping while
    /// waiting for a reply: shorter round trips, one busy core meanwhile
    #[arg(long, default_value_t = 0, value_name = "US")]
    pub spin_us: u64,
}

#[derive(Args)]
pub struct ScanArgs {
    #[command(flatten)]
    pub port: PortArgs,
    /// 1 or 2; both when omitted
    #[arg(long, value_parser = parse_protocol)]
    pub protocol: Option<Protocol>,
    /// Ids to try, e.g. 1-20 or 1,3,5 (Protocol 1.0 pings each; default all)
    #[arg(long, value_name = "LIST")]
    pub ids: Option<String>,
    /// Print JSON
    #[arg(long)]
    pub json: bool,
}

#[derive(Args)]
pub struct ReadArgs {
    #[command(flatten)]
    pub port: PortArgs,
    /// 1 or 2
    #[arg(long, value_parser = parse_protocol)]
    pub protocol: Protocol,
    /// Servo id
    #[arg(long)]
    pub id: u8,
    /// Model (found by PING when omitted)
    #[arg(long)]
    pub model: Option<String>,
    /// Registers to show (e-manual names, case and spaces ignored); all when omitted
    pub registers: Vec<String>,
    /// Print JSON
    #[arg(long)]
    pub json: bool,
}

#[derive(Args)]
pub struct RecordArgs {
    #[command(flatten)]
    pub port: PortArgs,
    /// Robot mapping: a TOML file or builtin:km20 / builtin:op3 (joint names, ids, models)
    #[arg(long, alias = "map", value_name = "MAPPING")]
    pub robot: Option<String>,
    /// Without --robot: the servos' protocol (models are found by PING)
    #[arg(long, value_parser = parse_protocol)]
    pub protocol: Option<Protocol>,
    /// Without --robot: the servo ids, e.g. 1-20; joints are named id<N>
    #[arg(long, value_name = "LIST")]
    pub ids: Option<String>,
    /// Seconds to record
    #[arg(long)]
    pub duration: f64,
    /// Output CSV file
    #[arg(long, value_name = "FILE.csv")]
    pub out: PathBuf,
    /// Reads per second (0: as fast as the bus allows)
    #[arg(long, default_value_t = 100.0)]
    pub rate: f64,
    /// How to read: auto (cheapest the servos have), read, bulk, sync, fast
    #[arg(long, default_value = "auto", value_parser = parse_method)]
    pub method: ReadMethod,
    /// Protocol 1.0 servos: read each twice and keep a value only when both replies
    /// agree byte for byte (the 8-bit checksum misses some damage; this catches it,
    /// at one more round trip per servo)
    #[arg(long)]
    pub verified_reads: bool,
}

#[derive(Args)]
pub struct PlanArgs {
    /// Number of servos
    #[arg(long, default_value_t = 20)]
    pub servos: usize,
    /// 1 or 2
    #[arg(long, value_parser = parse_protocol)]
    pub protocol: Protocol,
    /// Bit rate
    #[arg(long, default_value_t = 1_000_000)]
    pub baud: u32,
    /// Return Delay Time, us (register value x 2; factory setting 500)
    #[arg(long, default_value_t = 0.0)]
    pub return_delay_us: f64,
    /// Print JSON
    #[arg(long)]
    pub json: bool,
}

#[derive(Args)]
pub struct ServeArgs {
    /// The robot: builtin:km20 (simulated, RX-28/RX-64 on Protocol 1.0), builtin:op3
    /// (XM430 on 2.0, stand-in servos), a URDF/MJCF file (with --map) or a mapping TOML
    #[arg(long, default_value = "builtin:km20", value_name = "ROBOT")]
    pub robot: String,
    /// Mapping TOML: servo ids, models and protocols of the robot's joints (default:
    /// the built-in robot's own)
    #[arg(long, value_name = "FILE")]
    pub map: Option<PathBuf>,
    /// What moves the servos: sim (the physics simulation of the robot standing on the
    /// ground, in real time), ideal (each servo tracks its goal, no physics: for
    /// protocol-only benchmarks) or auto (sim when the robot has a model)
    #[arg(long, default_value = "auto", value_parser = ["auto", "sim", "ideal"])]
    pub servo_model: String,
    /// Simulated robot: servos power on limp, as real ones do (the robot falls)
    #[arg(long)]
    pub torque_off: bool,
    /// Simulated robot: simulated seconds per wall-clock second
    #[arg(long, default_value_t = 1.0, value_name = "FACTOR")]
    pub realtime_factor: f64,
    /// Where to serve: pty (a new pseudo-terminal) or tcp:ADDR (e.g. tcp:127.0.0.1:5555)
    #[arg(long, default_value = "pty")]
    pub port: String,
    /// With a pty: also make this path a symbolic link to it (a stable name for scripts)
    #[arg(long, alias = "pty", value_name = "PATH")]
    pub link: Option<PathBuf>,
    /// Serve on TCP instead of a pty (same as --port tcp:ADDR)
    #[arg(long, value_name = "ADDR", conflicts_with = "link")]
    pub tcp: Option<String>,
    /// Bit rate whose wire time (and each servo's Return Delay Time) is emulated
    #[arg(long, default_value_t = 1_000_000)]
    pub baud: u32,
    /// Answer at once instead of emulating wire time
    #[arg(long)]
    pub no_timing: bool,
    /// Busy-check the line for up to this many microseconds before sleeping while
    /// waiting for a request: requests are answered without a scheduler wake-up,
    /// at the cost of a busy core (helps only with idle cores: on a loaded machine
    /// the spinning steals the client's CPU and round trips get slower)
    #[arg(long, default_value_t = 0, value_name = "US")]
    pub spin_us: u64,
}

fn parse_protocol(s: &str) -> Result<Protocol, String> {
    Protocol::parse(s).ok_or_else(|| format!("protocol must be 1 or 2, not {s:?}"))
}

fn parse_method(s: &str) -> Result<ReadMethod, String> {
    ReadMethod::parse(s)
        .ok_or_else(|| format!("method must be auto, read, bulk, sync or fast, not {s:?}"))
}

/// `1-20`, `1,3,5`, `1-4,9`.
fn parse_ids(s: &str) -> Result<Vec<u8>, String> {
    let mut ids = Vec::new();
    for part in s.split(',').map(str::trim).filter(|p| !p.is_empty()) {
        let num = |t: &str| {
            t.trim()
                .parse::<u8>()
                .map_err(|_| format!("--ids: {t:?} is not an id (0..253)"))
        };
        match part.split_once('-') {
            Some((a, b)) => {
                let (a, b) = (num(a)?, num(b)?);
                if a > b {
                    return Err(format!("--ids: range {part} is empty"));
                }
                ids.extend(a..=b);
            }
            None => ids.push(num(part)?),
        }
    }
    if ids.is_empty() {
        return Err("--ids: no ids".into());
    }
    ids.sort_unstable();
    ids.dedup();
    Ok(ids)
}

fn fail(message: impl std::fmt::Display) -> ExitCode {
    eprintln!("error: {message}");
    ExitCode::from(EXIT_BAD_INPUT)
}

fn open_client(
    p: &PortArgs,
    default_port: Option<&str>,
) -> Result<Client<Box<dyn Transport>>, ExitCode> {
    let Some(port) = p.port.as_deref().or(default_port) else {
        return Err(fail(
            "--port is required (a serial device, a pty path or tcp:HOST:PORT)",
        ));
    };
    let options = SerialOptions {
        low_latency: p.low_latency,
    };
    let mut t =
        transport::open(port, p.baud, &options).map_err(|e| fail(format!("{port}: {e}")))?;
    t.set_spin(Duration::from_micros(p.spin_us));
    let config = ClientConfig {
        latency: Duration::from_secs_f64(p.timeout_ms.max(0.0) / 1000.0),
        retries: p.retries,
        baud: p.baud,
        write_replies: true,
    };
    Ok(Client::with_config(t, config))
}

pub fn run(cmd: LinkCommand) -> ExitCode {
    match cmd {
        LinkCommand::Scan(a) => scan(&a),
        LinkCommand::Read(a) => read(&a),
        LinkCommand::Record(a) => record(&a),
        LinkCommand::Plan(a) => plan(&a),
    }
}

#[derive(Serialize)]
struct ServoJson {
    protocol: u8,
    id: u8,
    model: Option<&'static str>,
    model_number: u16,
    firmware: u8,
}

fn scan(a: &ScanArgs) -> ExitCode {
    let ids = match a.ids.as_deref().map(parse_ids).transpose() {
        Ok(ids) => ids,
        Err(e) => return fail(e),
    };
    let mut c = match open_client(&a.port, None) {
        Ok(c) => c,
        Err(code) => return code,
    };
    let protocols = match a.protocol {
        Some(p) => vec![p],
        None => vec![Protocol::V1, Protocol::V2],
    };
    let mut found: Vec<FoundServo> = Vec::new();
    for p in protocols {
        let result = match &ids {
            None => c.scan(p, 0..=p.max_id()),
            Some(ids) => {
                let (lo, hi) = (ids[0], *ids.last().expect("non-empty"));
                c.scan(p, lo..=hi)
                    .map(|v| v.into_iter().filter(|s| ids.contains(&s.id)).collect())
            }
        };
        match result {
            Ok(v) => found.extend(v),
            Err(e) => return fail(e),
        }
    }
    if a.json {
        let v: Vec<ServoJson> = found
            .iter()
            .map(|s| ServoJson {
                protocol: s.protocol.number(),
                id: s.id,
                model: s.model.map(|m| m.name()),
                model_number: s.model_number,
                firmware: s.firmware,
            })
            .collect();
        return if print_json(&v) {
            ExitCode::from(EXIT_OK)
        } else {
            ExitCode::from(EXIT_BAD_INPUT)
        };
    }
    let mut out = String::from("PROTOCOL   ID  MODEL        NUMBER  FIRMWARE\n");
    for s in &found {
        out += &format!(
            "{:<8} {:>4}  {:<12} {:>6}  {:>8}\n",
            format!("{}.0", s.protocol.number()),
            s.id,
            s.model.map(|m| m.name()).unwrap_or("unknown"),
            s.model_number,
            s.firmware
        );
    }
    out += &format!("{} servo(s) found\n", found.len());
    print(&out);
    ExitCode::from(EXIT_OK)
}

#[derive(Serialize)]
struct RegisterJson {
    address: u16,
    name: &'static str,
    size: u8,
    access: &'static str,
    raw: i32,
    value: f64,
    unit: &'static str,
}

fn unit_name(u: twinloop_link::Unit) -> &'static str {
    use twinloop_link::Unit::*;
    match u {
        Raw => "",
        Angle { .. } => "rad",
        AngularVelocity { .. } => "rad/s",
        LoadRatio { .. } => "of max torque",
        Current { .. } => "A",
        Voltage { .. } => "V",
        Celsius => "degC",
        Duration { .. } => "s",
    }
}

fn read(a: &ReadArgs) -> ExitCode {
    let mut c = match open_client(&a.port, None) {
        Ok(c) => c,
        Err(code) => return code,
    };
    let model = match &a.model {
        Some(name) => match Model::parse(name) {
            Some(m) => m,
            None => {
                return fail(format!(
                    "--model {name:?}: unknown; known: {}",
                    Model::known_names()
                ));
            }
        },
        None => match c.ping(a.protocol, a.id) {
            Ok(FoundServo { model: Some(m), .. }) => m,
            Ok(s) => {
                return fail(format!(
                    "servo id {}: model number {} has no control table in twinloop (known: {})",
                    a.id,
                    s.model_number,
                    Model::known_names()
                ));
            }
            Err(e) => return fail(e),
        },
    };
    if model.protocol() != a.protocol {
        return fail(format!(
            "servo id {}: {model} runs {}, not {}",
            a.id,
            model.protocol(),
            a.protocol
        ));
    }
    let table = model.table();
    let mut selected = Vec::new();
    if a.registers.is_empty() {
        selected.extend(table.registers.iter());
    } else {
        for name in &a.registers {
            match table.by_name(name) {
                Some(r) => selected.push(r),
                None => {
                    let names: Vec<&str> = table.registers.iter().map(|r| r.name).collect();
                    return fail(format!(
                        "{model} has no register {name:?}; it has: {}",
                        names.join(", ")
                    ));
                }
            }
        }
    }
    let mut memory = vec![0u8; table.len()];
    if let Err(e) = c.read(a.protocol, a.id, 0, &mut memory) {
        return fail(e);
    }
    let rows: Vec<RegisterJson> = selected
        .iter()
        .map(|r| {
            let raw = r.decode(&memory[r.address as usize..r.end() as usize]);
            RegisterJson {
                address: r.address,
                name: r.name,
                size: r.size,
                access: match r.access {
                    twinloop_link::Access::Read => "R",
                    twinloop_link::Access::ReadWrite => "RW",
                },
                raw,
                value: r.to_si(raw),
                unit: unit_name(r.unit),
            }
        })
        .collect();
    if a.json {
        #[derive(Serialize)]
        struct Out<'a> {
            protocol: u8,
            id: u8,
            model: &'static str,
            registers: &'a [RegisterJson],
        }
        let ok = print_json(&Out {
            protocol: a.protocol.number(),
            id: a.id,
            model: model.name(),
            registers: &rows,
        });
        return ExitCode::from(if ok { EXIT_OK } else { EXIT_BAD_INPUT });
    }
    let mut out = format!(
        "servo id {} ({model}, {})\nADDR SIZE ACCESS  NAME                       RAW        VALUE\n",
        a.id, a.protocol
    );
    for r in &rows {
        let value = if r.unit.is_empty() {
            String::new()
        } else {
            format!("{} {}", num(r.value), r.unit)
        };
        out += &format!(
            "{:>4} {:>4} {:<6}  {:<24} {:>11}  {}\n",
            r.address, r.size, r.access, r.name, r.raw, value
        );
    }
    print(&out);
    ExitCode::from(EXIT_OK)
}

/// Set by SIGINT/SIGTERM; a second Ctrl-C ends the process at once.
fn interrupt_flag() -> Arc<AtomicBool> {
    let flag = Arc::new(AtomicBool::new(false));
    for sig in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        // Order matters: the conditional shutdown fires only if the flag is already set.
        let _ = signal_hook::flag::register_conditional_shutdown(sig, 130, flag.clone());
        let _ = signal_hook::flag::register(sig, flag.clone());
    }
    flag
}

/// A mapping for servos given by protocol and ids: joints `id<N>`, models by PING.
fn mapping_from_ids(
    c: &mut Client<Box<dyn Transport>>,
    protocol: Protocol,
    ids: &[u8],
) -> Result<RobotMapping, String> {
    let mut joints = Vec::new();
    for &id in ids {
        let s = c.ping(protocol, id).map_err(|e| e.to_string())?;
        let model = s.model.ok_or_else(|| {
            format!(
                "servo id {id}: model number {} has no control table in twinloop",
                s.model_number
            )
        })?;
        let (min, max) = JointMapping::servo_range(model);
        joints.push(JointMapping {
            name: format!("id{id}"),
            id,
            protocol,
            model,
            zero: 0.0,
            direction: 1.0,
            min,
            max,
            line: 0,
        });
    }
    Ok(RobotMapping {
        name: "servos".into(),
        urdf: None,
        port: None,
        baud: None,
        joints,
        source: "--ids".into(),
    })
}

fn record(a: &RecordArgs) -> ExitCode {
    if !a.duration.is_finite() || a.duration <= 0.0 {
        return fail(format!(
            "--duration {}: must be a positive number of seconds",
            a.duration
        ));
    }
    if !a.rate.is_finite() || a.rate < 0.0 {
        return fail(format!("--rate {}: must be 0 or a positive number", a.rate));
    }
    let mapping = match &a.robot {
        Some(spec) => match RobotMapping::resolve(spec) {
            Ok(m) => Some(m),
            Err(e) => return fail(e),
        },
        None => None,
    };
    let default_port = mapping.as_ref().and_then(|m| m.port.clone());
    let mut c = match open_client(&a.port, default_port.as_deref()) {
        Ok(c) => c,
        Err(code) => return code,
    };
    let mapping = match mapping {
        Some(m) => m,
        None => {
            let (Some(protocol), Some(ids)) = (a.protocol, a.ids.as_deref()) else {
                return fail("give --robot MAPPING, or --protocol and --ids");
            };
            let ids = match parse_ids(ids) {
                Ok(ids) => ids,
                Err(e) => return fail(e),
            };
            match mapping_from_ids(&mut c, protocol, &ids) {
                Ok(m) => m,
                Err(e) => return fail(e),
            }
        }
    };
    let names = mapping.joint_names();
    let mut robot = match DynamixelRobot::new(c, mapping, a.method) {
        Ok(r) => r,
        Err(e) => return fail(e),
    };
    robot.cycle_mut().verify_v1 = a.verified_reads;
    let mut columns = vec!["t".to_string()];
    for prefix in ["q", "v", "tau"] {
        columns.extend(names.iter().map(|n| format!("{prefix}:{n}")));
    }
    let mut writer = match CsvWriter::create(&a.out, &columns) {
        Ok(w) => w,
        Err(e) => return fail(e),
    };
    // Every row reaches the file as soon as it is read: nothing is lost on Ctrl-C
    // or when the adapter is unplugged.
    writer.flush_each_row = true;
    let stop = interrupt_flag();
    let n = names.len();
    let mut state = RobotState::default();
    let mut row = vec![0.0; 1 + 3 * n];
    let mut failures = vec![0usize; n];
    let mut rows = 0usize;
    let start = Instant::now();
    let dt = if a.rate > 0.0 { 1.0 / a.rate } else { 0.0 };
    let mut link_error = None;
    while start.elapsed().as_secs_f64() < a.duration && !stop.load(Ordering::Relaxed) {
        let r = robot.read(&mut state);
        if let Err(e) = &r
            && e.joint.is_none()
        {
            link_error = Some(e.to_string());
            break;
        }
        for (k, (_, o)) in robot.outcomes().enumerate() {
            if o.is_err() {
                failures[k] += 1;
            }
        }
        row[0] = state.time;
        row[1..1 + n].copy_from_slice(&state.positions);
        row[1 + n..1 + 2 * n].copy_from_slice(state.velocities.as_deref().unwrap_or(&[]));
        row[1 + 2 * n..].copy_from_slice(state.efforts.as_deref().unwrap_or(&[]));
        if let Err(e) = writer.write_row(&row) {
            link_error = Some(e.to_string());
            break;
        }
        rows += 1;
        if dt > 0.0 {
            let _ = robot.advance(dt);
        }
    }
    let elapsed = start.elapsed().as_secs_f64();
    let finished = writer.finish();
    let mut summary = format!(
        "{rows} rows in {:.3} s ({:.1} reads/s) written to {}",
        elapsed,
        rows as f64 / elapsed.max(1e-9),
        a.out.display()
    );
    if stop.load(Ordering::Relaxed) {
        summary += " (interrupted)";
    }
    eprintln!("{summary}");
    for (k, f) in failures.iter().enumerate() {
        if *f > 0 {
            eprintln!("  joint {}: {f} failed reads (NaN in those rows)", names[k]);
        }
    }
    if let Err(e) = finished {
        return fail(e);
    }
    match link_error {
        Some(e) => fail(format!(
            "recording stopped: {e}; the {rows} rows read before are in the file"
        )),
        None => ExitCode::from(EXIT_OK),
    }
}

#[derive(Serialize)]
struct PlanJson {
    read: &'static str,
    bytes_per_servo: usize,
    write_bytes: usize,
    read_bytes: usize,
    total_bytes: usize,
    wire_ms: f64,
    cycles_per_second: f64,
    round_trips: usize,
    budget_5_percent_us: f64,
}

fn plan(a: &PlanArgs) -> ExitCode {
    if a.servos == 0 || a.servos > 253 {
        return fail(format!("--servos {}: must be 1..=253", a.servos));
    }
    if !a.return_delay_us.is_finite() || a.return_delay_us < 0.0 {
        return fail("--return-delay-us must be >= 0");
    }
    let rdt = Duration::from_secs_f64(a.return_delay_us / 1e6);
    let (goal, cases): (usize, Vec<(ReadMethod, usize)>) = match a.protocol {
        Protocol::V1 => (
            2,
            vec![
                (ReadMethod::Read, 2),
                (ReadMethod::Read, 6),
                (ReadMethod::BulkRead, 2),
                (ReadMethod::BulkRead, 6),
            ],
        ),
        Protocol::V2 => (
            4,
            vec![
                (ReadMethod::SyncRead, 4),
                (ReadMethod::FastSyncRead, 4),
                (ReadMethod::SyncRead, 10),
                (ReadMethod::FastSyncRead, 10),
            ],
        ),
    };
    let plans: Vec<PlanJson> = cases
        .iter()
        .map(|&(m, l)| {
            let p = plan_cycle(a.protocol, m, a.servos, l, goal, a.baud, rdt);
            PlanJson {
                read: m.name(),
                bytes_per_servo: l,
                write_bytes: p.write_bytes,
                read_bytes: p.read_bytes,
                total_bytes: p.total_bytes(),
                wire_ms: p.wire.as_secs_f64() * 1e3,
                cycles_per_second: p.cycles_per_second(),
                round_trips: p.round_trips,
                budget_5_percent_us: p.wire.as_secs_f64() * 0.05 * 1e6,
            }
        })
        .collect();
    if a.json {
        return ExitCode::from(if print_json(&plans) {
            EXIT_OK
        } else {
            EXIT_BAD_INPUT
        });
    }
    let mut out = format!(
        "{} servos, {}, {} bps, return delay {} us; goal SYNC_WRITE of {} bytes each\n",
        a.servos, a.protocol, a.baud, a.return_delay_us, goal
    );
    if a.protocol == Protocol::V1 {
        out +=
            "(RX servos have no BULK_READ: READ per servo is their only way; BULK_READ needs MX)\n";
    }
    out +=
        "READ            BYTES/SERVO  WRITE  READ  TOTAL   WIRE MS      HZ  TRIPS  5% BUDGET US\n";
    for p in &plans {
        out += &format!(
            "{:<15} {:>11}  {:>5} {:>5} {:>6} {:>9.3} {:>7.0} {:>6} {:>13.1}\n",
            p.read,
            p.bytes_per_servo,
            p.write_bytes,
            p.read_bytes,
            p.total_bytes,
            p.wire_ms,
            p.cycles_per_second,
            p.round_trips,
            p.budget_5_percent_us
        );
    }
    out +=
        "bytes per servo: 2 or 4 = position only; 6 or 10 = load/current + velocity + position\n";
    print(&out);
    ExitCode::from(EXIT_OK)
}

/// The robot and mapping `twinloop serve` was asked for: the mapping always, the
/// robot's model when there is one (`None`: a mapping-only bus).
fn serve_robot(
    a: &ServeArgs,
) -> Result<(RobotMapping, Option<twinloop_description::Description>), String> {
    let is_mapping = a.robot.ends_with(".toml");
    let mapping = match (&a.map, is_mapping) {
        (Some(m), _) => RobotMapping::load(m).map_err(|e| e.to_string())?,
        (None, true) => RobotMapping::load(&a.robot).map_err(|e| e.to_string())?,
        (None, false) => match a.robot.strip_prefix("builtin:") {
            Some(name) => RobotMapping::builtin(name).ok_or_else(|| {
                format!(
                    "--robot {}: no built-in mapping for {name:?} (built-in: {}); give --map FILE",
                    a.robot,
                    RobotMapping::BUILTINS.join(", ")
                )
            })?,
            None => {
                return Err(format!(
                    "--robot {}: a description file needs --map FILE (which servo drives which joint)",
                    a.robot
                ));
            }
        },
    };
    // The robot's model: --robot itself unless it is a mapping; else the mapping's
    // `urdf`. A built-in mapping without a built-in robot (op3) has none.
    let spec = if is_mapping {
        // A relative path in a mapping file is relative to that file.
        let dir = std::path::Path::new(&mapping.source).parent();
        mapping.urdf.as_ref().map(|p| {
            let s = p.display().to_string();
            match dir {
                Some(d) if !s.starts_with("builtin:") && p.is_relative() => {
                    d.join(p).display().to_string()
                }
                _ => s,
            }
        })
    } else {
        Some(a.robot.clone())
    };
    let robot = match spec {
        Some(s) if s.starts_with("builtin:") => {
            twinloop_description::builtin::builtin(&s["builtin:".len()..])
        }
        Some(s) => match twinloop_description::load(&s) {
            Ok(r) => Some(r),
            Err(e) if a.servo_model == "sim" => return Err(format!("{s}: {e}")),
            Err(_) => None,
        },
        None => None,
    };
    Ok((mapping, robot))
}

/// `twinloop serve`.
pub fn serve(a: ServeArgs) -> ExitCode {
    let (mapping, robot) = match serve_robot(&a) {
        Ok(x) => x,
        Err(e) => return fail(e),
    };
    let servos: Vec<BusServo> = mapping
        .joints
        .iter()
        .map(|j| BusServo {
            id: j.id,
            model: j.model,
        })
        .collect();
    let simulate = match (a.servo_model.as_str(), &robot) {
        ("ideal", _) => false,
        ("sim", None) => {
            return fail(format!(
                "--servo-model sim: {} has no robot model to simulate (give --robot builtin:NAME or a URDF with --map)",
                a.robot
            ));
        }
        (_, r) => r.is_some(),
    };
    if simulate {
        let robot = robot.expect("checked above");
        let options = twinloop_virtual::VirtualRobotOptions {
            torque_on: !a.torque_off,
            realtime_factor: a.realtime_factor,
            ..Default::default()
        };
        if !(a.realtime_factor > 0.0 && a.realtime_factor.is_finite()) {
            return fail(format!(
                "--realtime-factor must be positive, not {}",
                a.realtime_factor
            ));
        }
        let vr = match twinloop_virtual::VirtualRobot::new(&robot, &mapping, &options) {
            Ok(v) => v,
            Err(e) => return fail(e),
        };
        if !vr.unmapped.is_empty() {
            eprintln!(
                "joints without a servo on the bus (they hold their pose): {}",
                vr.unmapped.join(", ")
            );
        }
        let bus = vr.bus();
        let sim = vr.spawn();
        let what = format!(
            "the physics simulation of {} standing on the ground (real time x{}, servos {})",
            robot.name,
            a.realtime_factor,
            if a.torque_off { "limp" } else { "torque on" }
        );
        let code = serve_on(&a, &mapping, &servos, bus, &what);
        let status = sim.status();
        if let Some(e) = &status.error {
            eprintln!("the simulation stopped: {e}");
        }
        if status.behind_s > 0.0 {
            eprintln!(
                "the simulation fell {:.3} s behind the wall clock in {:.1} s",
                status.behind_s, status.time
            );
        }
        return code;
    }
    let bus = VirtualBus::with_tracking_model(&servos);
    serve_on(
        &a,
        &mapping,
        &servos,
        bus,
        "stand-in servos (each tracks its goal, 50 ms lag; no physics)",
    )
}

fn serve_on<B: twinloop_link::VirtualServoBackend>(
    a: &ServeArgs,
    mapping: &RobotMapping,
    servos: &[BusServo],
    mut bus: VirtualBus<B>,
    what: &str,
) -> ExitCode {
    let options = ServeOptions {
        emulate_baud: (!a.no_timing).then_some(a.baud),
        stop_on_eof: true,
    };
    let stop = interrupt_flag();
    let port = match &a.tcp {
        Some(addr) => format!("tcp:{addr}"),
        None => a.port.clone(),
    };
    let describe = |place: &str| {
        let mut models: Vec<String> = Vec::new();
        for j in &mapping.joints {
            let m = format!("{} ({})", j.model, j.protocol);
            if !models.contains(&m) {
                models.push(m);
            }
        }
        format!(
            "serving {} ({} servos: {}) on {place}\nmoved by {what}\n{}\nCtrl-C stops.\n",
            if mapping.name.is_empty() {
                &mapping.source
            } else {
                &mapping.name
            },
            servos.len(),
            models.join(", "),
            match options.emulate_baud {
                Some(b) =>
                    format!("wire time emulated at {b} bps, return delay per servo register"),
                None => "answering at once (no wire-time emulation)".to_string(),
            }
        )
    };
    if port == "pty" {
        let mut pty = match PtyTransport::open() {
            Ok(p) => p,
            Err(e) => return fail(format!("cannot open a pseudo-terminal: {e}")),
        };
        pty.set_spin(Duration::from_micros(a.spin_us));
        let path = pty.path().to_path_buf();
        if let Some(link) = &a.link {
            let _ = std::fs::remove_file(link);
            if let Err(e) = std::os::unix::fs::symlink(&path, link) {
                return fail(format!(
                    "cannot link {} to {}: {e}",
                    link.display(),
                    path.display()
                ));
            }
        }
        // The path first, alone on its line, for scripts.
        print(&format!("{}\n", path.display()));
        eprint!("{}", describe(&path.display().to_string()));
        let options = ServeOptions {
            stop_on_eof: false,
            ..options
        };
        let r = serve_bus(&mut bus, &mut pty, &options, &stop);
        if let Some(link) = &a.link {
            let _ = std::fs::remove_file(link);
        }
        return match r {
            Ok(()) => ExitCode::from(EXIT_OK),
            Err(e) => fail(e),
        };
    }
    let Some(addr) = port.strip_prefix("tcp:") else {
        return fail(format!("--port {port:?}: use pty or tcp:ADDR"));
    };
    let listener = match std::net::TcpListener::bind(addr) {
        Ok(l) => l,
        Err(e) => return fail(format!("cannot listen on {addr}: {e}")),
    };
    let local = listener
        .local_addr()
        .map(|a| a.to_string())
        .unwrap_or_else(|_| addr.to_string());
    print(&format!("tcp:{local}\n"));
    eprint!("{}", describe(&format!("tcp:{local}")));
    let _ = listener.set_nonblocking(true);
    while !stop.load(Ordering::Relaxed) {
        match listener.accept() {
            Ok((stream, peer)) => {
                let _ = stream.set_nonblocking(false);
                eprintln!("client {peer} connected");
                let mut t = match TcpTransport::from_stream(stream) {
                    Ok(t) => t,
                    Err(e) => {
                        eprintln!("client {peer}: {e}");
                        continue;
                    }
                };
                if let Err(e) = serve_bus(&mut bus, &mut t, &options, &stop) {
                    eprintln!("client {peer}: {e}");
                }
                eprintln!("client {peer} left");
            }
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                std::thread::sleep(Duration::from_millis(50));
            }
            Err(e) => return fail(format!("accept on {addr}: {e}")),
        }
    }
    ExitCode::from(EXIT_OK)
}

#[derive(Args, Debug)]
pub struct LinkBenchArgs {
    /// A served robot (`twinloop serve --robot builtin:op3 --no-timing`) to time real
    /// transactions against; without it only the software overhead is measured
    #[arg(long, value_name = "PATH")]
    pub port: Option<String>,
    /// Servos in the cycle (ids 1..=N)
    #[arg(long, default_value_t = 20)]
    pub servos: u8,
    /// Seconds per case
    #[arg(long, default_value_t = 1.0)]
    pub seconds: f64,
    /// With --port: busy-check the pty for up to this many microseconds before
    /// sleeping for a reply (0: sleep at once)
    #[arg(long, default_value_t = 0, value_name = "US")]
    pub spin_us: u64,
    /// Print JSON: {"cases": [{"name", "median_us", "per_second", "wire_us", "overhead_ratio"}]}
    #[arg(long)]
    pub json: bool,
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

fn cycle_servos(model: Model, n: u8) -> Vec<twinloop_link::CycleServo> {
    (1..=n)
        .map(|id| twinloop_link::CycleServo { id, model })
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
    let servos = cycle_servos(Model::Xm430W350, n);
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

pub fn bench(a: &LinkBenchArgs) -> ExitCode {
    if a.servos == 0 || a.servos > 252 {
        return fail("--servos must be 1..=252");
    }
    let n = a.servos;
    let mut cases = Vec::new();
    // Software overhead per cycle: replayed replies.
    for (model, method, len, label) in [
        (
            Model::Xm430W350,
            ReadMethod::FastSyncRead,
            10,
            "FAST_SYNC_READ",
        ),
        (Model::Xm430W350, ReadMethod::SyncRead, 10, "SYNC_READ"),
        (Model::Rx28, ReadMethod::Read, 6, "READ x N"),
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
        let mut cycle = match twinloop_link::ControlCycle::new(&servos, method) {
            Ok(c) => c,
            Err(e) => return fail(e),
        };
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
                model: Model::Xm430W350,
            })
            .collect();
        let replay = Replay {
            bus: VirtualBus::with_tracking_model(&servos),
            cache: Default::default(),
        };
        let mut c = Client::new(twinloop_link::transport::LoopbackTransport::new(replay));
        transaction_cases(&mut c, n, a.seconds, "replay", &mut cases);
    }
    if let Some(port) = &a.port {
        let p = PortArgs {
            port: Some(port.clone()),
            baud: 1_000_000,
            timeout_ms: 50.0,
            retries: 0,
            low_latency: false,
            spin_us: a.spin_us,
        };
        let mut c = match open_client(&p, None) {
            Ok(c) => c,
            Err(code) => return code,
        };
        if !transaction_cases(&mut c, n, a.seconds, "pty", &mut cases) {
            return fail(format!(
                "some transactions on {port} failed: serve a robot with XM430 ids 1..={n} \
                 (twinloop serve --robot builtin:op3 --no-timing)"
            ));
        }
    }
    if a.json {
        #[derive(Serialize)]
        struct Out<'a> {
            cases: &'a [BenchCase],
        }
        return ExitCode::from(if print_json(&Out { cases: &cases }) {
            EXIT_OK
        } else {
            EXIT_BAD_INPUT
        });
    }
    let mut out = String::from(
        "CASE                                                                  MEDIAN US   CPU US       PER S   WIRE US  OVERHEAD/WIRE\n",
    );
    for c in &cases {
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
    print(&out);
    ExitCode::from(EXIT_OK)
}
