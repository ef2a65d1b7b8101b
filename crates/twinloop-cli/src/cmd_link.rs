//! `twinloop link ...`: talk to the servos of a robot on a bus: scan, read,
//! record, plan a control cycle. The port options and the Ctrl-C flag are
//! `bus_args`'s, shared with every command that talks to a bus.

use crate::bus_args::{PortArgs, interrupt_flag, open_client};
use crate::common::{JSON_HELP, emit, num};
use crate::error::{CliError, CliResult, Outcome};
use crate::progress;
use clap::{Args, Subcommand};
use serde::Serialize;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};
use twinloop_link::ModelTable;
use twinloop_link::board_type::BoardType;
use twinloop_link::control_cycle::ReadMethod;
use twinloop_link::transport::Transport;
use twinloop_link::{DynamixelRobot, FoundServo, Protocol, RobotMapping, ServoModel, plan_cycle};
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
then a count. --json FILE (- for stdout) writes [{protocol, id, model, model_number,\n\
firmware}].\n\n\
Exit code 0 (also when nothing answered), 2 when the port cannot be opened."
    )]
    Scan(ScanArgs),

    /// Read a servo's control table, with values in SI units
    #[command(
        long_about = "Read a servo's whole control table (one READ) and print every register \
(or the ones named) with its raw value and its value in SI units. The model is found by PING unless \
--servo-model says it.",
        after_long_help = "Example:\n  twinloop link read --port /dev/ttyUSB0 --protocol 1 --id 3\n  \
twinloop link read --port /dev/pts/5 --protocol 2 --id 1 \"present position\" \"present current\"\n\n\
Output: one line per register:\n  \
ADDR    address, SIZE bytes, ACCESS R or RW, AREA eeprom or ram\n  \
NAME    e-manual name\n  \
RAW     decoded raw value (signed where the register is)\n  \
VALUE   in SI: rad, rad/s, A, V, s, load as a fraction of max torque, degC\n\
--json FILE (- for stdout) writes {protocol, id, model, registers: [{address, name, size,\n\
access, raw, value, unit}]}.\n\n\
Exit code 0; 2 when the port cannot be opened, the servo does not answer, or a name matches no\n\
register (the message names the servo id)."
    )]
    Read(ReadArgs),

    /// Record joint positions, velocities and torques to CSV until Ctrl-C or --duration
    #[command(
        long_about = "Read every joint of a robot (given by a mapping, --map, or by --protocol and \
--ids) in a loop and write one CSV row per read: t (s since start), q:<joint> (rad), v:<joint> \
(rad/s), tau:<joint> (N m, from Present Load or Present Current and the datasheet's stall torque: an \
estimate). Every row is flushed as it is written, so an interrupted recording (Ctrl-C, unplugged \
adapter, servo power lost) leaves a valid file with every row read so far. A joint whose servo did not \
answer in a read is NaN in that row; the others are kept.",
        after_long_help = "Example:\n  twinloop link record --port /dev/ttyUSB0 --map robot.toml --duration 10 --out walk.csv\n  \
twinloop link record --port /dev/pts/5 --map builtin:km20 --duration 5 --out km20.csv --rate 50\n  \
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
--json FILE (- for stdout) writes the same as a list of objects."
    )]
    Plan(PlanArgs),
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
    #[arg(long, value_name = "FILE", help = JSON_HELP)]
    pub json: Option<PathBuf>,
    /// Write a draft robot profile of what answered (servos and IMU boards) to FILE,
    /// matched to --robot's joints where a built-in profile has exactly these
    /// servos, else listing the joints to fill in; it says what it guessed
    #[arg(long, value_name = "PROFILE.toml", requires = "robot")]
    pub out: Option<PathBuf>,
    /// The robot the draft profile describes (builtin:NAME, URDF/MJCF, profile)
    #[arg(long, value_name = "ROBOT")]
    pub robot: Option<String>,
}

#[derive(Args)]
pub struct ReadArgs {
    #[command(flatten)]
    pub port: PortArgs,
    /// 1 or 2
    #[arg(long, value_parser = parse_protocol)]
    pub protocol: Protocol,
    /// Servo id (0 to 253)
    #[arg(long, value_parser = crate::common::servo_id)]
    pub id: u8,
    /// Servo model, e.g. XM430-W350 (found by PING when omitted)
    #[arg(long, value_parser = crate::common::servo_model_name)]
    pub servo_model: Option<String>,
    /// Registers to show (e-manual names, case and spaces ignored); all when omitted
    pub registers: Vec<String>,
    #[arg(long, value_name = "FILE", help = JSON_HELP)]
    pub json: Option<PathBuf>,
}

#[derive(Args)]
pub struct RecordArgs {
    #[command(flatten)]
    pub port: PortArgs,
    /// Servo mapping: a TOML file or builtin:km20 / builtin:op3 (joint names, ids, models)
    #[arg(long, value_name = "MAPPING")]
    pub map: Option<String>,
    /// Without --map: the servos' protocol (models are found by PING)
    #[arg(long, value_parser = parse_protocol, conflicts_with = "map")]
    pub protocol: Option<Protocol>,
    /// Without --map: the servo ids, e.g. 1-20; joints are named id<N> (with --map,
    /// the mapping's servos are read: the two are not given together)
    #[arg(long, value_name = "LIST", conflicts_with = "map")]
    pub ids: Option<String>,
    /// Seconds to record
    #[arg(long, value_parser = crate::common::positive)]
    pub duration: f64,
    /// Output file: CSV, or MCAP (ROS 2 /joint_states, and the mapping's robot on
    /// /robot_description) when it ends in .mcap. Repeatable: one recording written
    /// to each (a CSV kept row by row and an MCAP for Foxglove or Rerun)
    #[arg(long, value_name = "FILE.csv|FILE.mcap", required = true)]
    pub out: Vec<PathBuf>,
    /// Reads per second (0: as fast as the bus allows)
    #[arg(long, default_value_t = 100.0, value_parser = crate::common::non_negative)]
    pub rate: f64,
    /// How to read: auto (cheapest the servos have), read, bulk, sync, fast
    #[arg(long, default_value = "auto", value_parser = parse_method)]
    pub method: ReadMethod,
    /// Protocol 1.0 servos: read each twice and keep a value only when both replies
    /// agree byte for byte (the 8-bit checksum misses some damage; this catches it,
    /// at one more round trip per servo)
    #[arg(long)]
    pub verified_reads: bool,
    /// The robot comes from the mapping's `urdf`.
    #[command(flatten)]
    pub view: crate::live_view::LiveViewArgs,
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
    #[arg(long, default_value_t = 1_000_000, value_parser = crate::common::baud)]
    pub baud: u32,
    /// Return Delay Time, us (register value x 2; factory setting 500)
    #[arg(long, default_value_t = 0.0, value_parser = crate::common::non_negative)]
    pub return_delay_us: f64,
    #[arg(long, value_name = "FILE", help = JSON_HELP)]
    pub json: Option<PathBuf>,
}

pub fn parse_protocol(s: &str) -> Result<Protocol, String> {
    Protocol::parse(s).ok_or_else(|| format!("protocol must be 1 or 2, not {s:?}"))
}

fn parse_method(s: &str) -> Result<ReadMethod, String> {
    ReadMethod::parse(s)
        .ok_or_else(|| format!("method must be auto, read, bulk, sync or fast, not {s:?}"))
}

/// `1-20`, `1,3,5`, `1-4,9`. Every item is an id or a rising range: an empty item
/// (`1,,2`, `1,`, `,2`), a range backwards (`2-1`) or an id past 253 is refused,
/// naming the item, rather than read as something the user did not write.
fn parse_ids(s: &str) -> Result<Vec<u8>, String> {
    let mut ids = Vec::new();
    for (k, part) in s.split(',').map(str::trim).enumerate() {
        let item = || format!("--ids {s}: item {} ({part})", k + 1);
        if part.is_empty() {
            return Err(format!(
                "--ids {s}: item {} is empty; write ids or rising ranges between commas, \
                 e.g. 1-4,9",
                k + 1
            ));
        }
        let num = |t: &str| {
            t.trim()
                .parse::<u8>()
                .ok()
                .filter(|&id| id <= 253)
                .ok_or_else(|| {
                    format!(
                        "{}: \"{}\" is not a servo id (a whole number 0 to 253)",
                        item(),
                        t.trim()
                    )
                })
        };
        match part.split_once('-') {
            Some((a, b)) => {
                let (a, b) = (num(a)?, num(b)?);
                if a > b {
                    return Err(format!(
                        "{}: the range runs backwards; write {b}-{a}",
                        item()
                    ));
                }
                ids.extend(a..=b);
            }
            None => ids.push(num(part)?),
        }
    }
    ids.sort_unstable();
    ids.dedup();
    Ok(ids)
}

pub fn run(cmd: LinkCommand) -> CliResult {
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
    /// `servo`, or `board` for an IMU sub-controller (CM-730, OpenCR).
    kind: &'static str,
    model: Option<&'static str>,
    model_number: u16,
    firmware: u8,
}

/// The built-in IMU board a scanned device is (same protocol and model number), if
/// it is one: a sub-controller answers PING as a servo does, but is not one.
fn board_of(s: &FoundServo) -> Option<&'static str> {
    BoardType::BUILTIN
        .iter()
        .filter_map(|n| BoardType::builtin(n))
        .find(|b| b.protocol == s.protocol && b.model_number == s.model_number)
        .map(|b| b.name.as_str())
}

/// `20 servo(s) found`, and the IMU boards apart: `20 servo(s) and 1 IMU board
/// (OpenCR, id 200) found`.
fn found_line(found: &[FoundServo]) -> String {
    let boards: Vec<String> = found
        .iter()
        .filter_map(|s| board_of(s).map(|b| format!("{b}, id {}", s.id)))
        .collect();
    let servos = found.len() - boards.len();
    if boards.is_empty() {
        return format!("{servos} servo(s) found\n");
    }
    format!(
        "{servos} servo(s) and {} IMU board{} ({}) found\n",
        boards.len(),
        if boards.len() == 1 { "" } else { "s" },
        boards.join("; ")
    )
}

fn scan(a: &ScanArgs) -> CliResult {
    let ids = a.ids.as_deref().map(parse_ids).transpose()?;
    let mut c = open_client(&a.port, None)?;
    let protocols = match a.protocol {
        Some(p) => vec![p],
        None => vec![Protocol::V1, Protocol::V2],
    };
    let mut found: Vec<FoundServo> = Vec::new();
    for p in protocols {
        // Exactly the ids asked for (`1,200` is two ids, not the span between).
        let pinged: Vec<u8> = match &ids {
            None => (0..=p.max_id()).collect(),
            Some(ids) => ids.iter().copied().filter(|&id| id <= p.max_id()).collect(),
        };
        // A scan takes seconds: say what it does, then count the ids pinged.
        eprintln!(
            "scanning protocol {}.0, {} id(s) ({}), at {} baud ...",
            p.number(),
            pinged.len(),
            a.ids.as_deref().unwrap_or("all"),
            a.port.baud
        );
        let bar = progress::steps(pinged.len());
        let mut done = 0u64;
        let result = c.scan_ids_with_progress(p, &pinged, |id| {
            bar.set_position(done);
            bar.set_message(format!("id {id}"));
            done += 1;
        });
        bar.finish_and_clear();
        found.extend(result?);
    }
    let v: Vec<ServoJson> = found
        .iter()
        .map(|s| ServoJson {
            protocol: s.protocol.number(),
            id: s.id,
            kind: if board_of(s).is_some() {
                "board"
            } else {
                "servo"
            },
            model: board_of(s).or(s.model.map(|m| m.name())),
            model_number: s.model_number,
            firmware: s.firmware,
        })
        .collect();
    let mut out = String::from("PROTOCOL   ID  MODEL        NUMBER  FIRMWARE\n");
    for s in &found {
        out += &format!(
            "{:<8} {:>4}  {:<12} {:>6}  {:>8}\n",
            format!("{}.0", s.protocol.number()),
            s.id,
            board_of(s)
                .or(s.model.map(|m| m.name()))
                .unwrap_or("unknown"),
            s.model_number,
            s.firmware
        );
    }
    out += &found_line(&found);
    if found.is_empty() {
        // Nothing answered: a check that found a problem (exit 1), said plainly.
        emit(&out, a.json.as_ref(), &v)?;
        eprintln!(
            "error: no servo answered on {} (check the port, --baud and --protocol)",
            a.port.port.as_deref().unwrap_or("?")
        );
        return Ok(Outcome::Problems);
    }
    emit(&out, a.json.as_ref(), &v)?;
    if let (Some(path), Some(robot)) = (&a.out, &a.robot) {
        let d = twinloop_loop::draft_profile::draft(&found, robot)?;
        twinloop_io::output::write_atomic(path, &d.toml)
            .map_err(|e| CliError::from(e).context("--out"))?;
        for n in &d.notes {
            eprintln!("guessed: {n}");
        }
        eprintln!("wrote the draft profile {} (check it)", path.display());
    }
    Ok(Outcome::Ok)
}

fn read(a: &ReadArgs) -> CliResult {
    let mut c = open_client(&a.port, None)?;
    let model = read_model(a, &mut c)?;
    let table = model.table();
    let selected = selected_registers(table, model, &a.registers)?;
    let mut memory = vec![0u8; table.len()];
    c.read(a.protocol, a.id, 0, &mut memory)?;
    let rows: Vec<twinloop_link::Reading> = selected.iter().map(|r| r.reading(&memory)).collect();
    #[derive(Serialize)]
    struct Out<'a> {
        protocol: u8,
        id: u8,
        model: &'static str,
        registers: &'a [twinloop_link::Reading],
    }
    let json = Out {
        protocol: a.protocol.number(),
        id: a.id,
        model: model.name(),
        registers: &rows,
    };
    emit(&register_text(a, model, &rows), a.json.as_ref(), &json)?;
    Ok(Outcome::Ok)
}

/// The servo model `link read` decodes with: `--servo-model` (checked against the
/// servo's Model Number) or the one the servo's PING names; it must speak the protocol.
fn read_model(
    a: &ReadArgs,
    c: &mut twinloop_link::Client<Box<dyn Transport>>,
) -> Result<ServoModel, CliError> {
    let model = match &a.servo_model {
        Some(name) => match ServoModel::parse(name) {
            Some(m) => m,
            None => {
                return Err(CliError::from(format!(
                    "--servo-model {name:?}: unknown; known: {}",
                    ServoModel::known_names()
                )));
            }
        },
        None => match c.ping(a.protocol, a.id) {
            Ok(FoundServo { model: Some(m), .. }) => m,
            Ok(s) => {
                return Err(CliError::from(format!(
                    "servo id {}: model number {} has no control table in twinloop (known: {})",
                    a.id,
                    s.model_number,
                    ServoModel::known_names()
                )));
            }
            Err(e) => return Err(e.into()),
        },
    };
    if !model.speaks(a.protocol) {
        return Err(CliError::from(format!(
            "servo id {}: {model} runs {}, not {}",
            a.id,
            model.protocol(),
            a.protocol
        )));
    }
    if a.servo_model.is_some() {
        // Checked, not trusted (issue 29, class 4): the Model Number register (address
        // 0 on every Dynamixel) says what answers; another model's table reads
        // registers that are not there ("range error") or mean something else.
        let found = c.ping(a.protocol, a.id)?;
        if found.model_number != model.model_number() {
            let answered = found.model.map_or_else(
                || "a model twinloop does not know".into(),
                |m| m.to_string(),
            );
            return Err(CliError::from(format!(
                "servo id {}: --servo-model {model} (model number {}), but the servo answers \
                 as {answered} (model number {}): give --servo-model {answered}, or leave it \
                 out and the servo's own is read",
                a.id,
                model.model_number(),
                found.model_number
            )));
        }
    }
    Ok(model)
}

/// The registers `--registers` names (all of the table when none), each checked.
fn selected_registers<'t>(
    table: &'t twinloop_link::ControlTable,
    model: ServoModel,
    registers: &[String],
) -> Result<Vec<&'t twinloop_link::register::Register>, CliError> {
    let mut selected = Vec::new();
    if registers.is_empty() {
        selected.extend(table.registers.iter());
    } else {
        for name in registers {
            match table.by_name(name) {
                Some(r) => selected.push(r),
                None => {
                    let names: Vec<&str> = table.registers.iter().map(|r| r.name).collect();
                    return Err(CliError::from(format!(
                        "{model} has no register {name:?}; it has: {}",
                        names.join(", ")
                    )));
                }
            }
        }
    }
    Ok(selected)
}

/// `link read`'s table: one line per register, its value in SI units where it has one.
fn register_text(a: &ReadArgs, model: ServoModel, rows: &[twinloop_link::Reading]) -> String {
    let mut out = format!(
        "servo id {} ({model}, {})\nADDR SIZE ACCESS  NAME                       RAW        VALUE\n",
        a.id, a.protocol
    );
    for r in rows {
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
    out
}

fn record(a: &RecordArgs) -> CliResult {
    crate::common::RowWriter::distinct_paths(&a.out)?;
    // The rows it will write: --rate a second (--rate 0: taken as 1 kHz).
    let rate = if a.rate > 0.0 { a.rate } else { 1000.0 };
    crate::bounds::steps(
        a.duration,
        1.0 / rate,
        &format!(
            "--duration {} s at {} rows/s",
            crate::common::num(a.duration),
            crate::common::num(rate)
        ),
    )?;
    let (c, mapping) = record_bus(a)?;
    let names = mapping.joint_names();
    let ids: Vec<String> = mapping
        .joints
        .iter()
        .map(|j| format!("{} (protocol {}.0)", j.id, j.protocol.number()))
        .collect();
    let mut live = crate::live_view::start_live_for_mapping(&a.view, &mapping)?;
    let mapping_urdf = mapping.urdf.as_ref().map(|u| u.display().to_string());
    let mut robot = DynamixelRobot::new(c, mapping, a.method)?;
    robot.cycle_mut().verify_v1 = a.verified_reads;
    let mut writer = record_writer(a, &names, mapping_urdf.as_deref())?;
    let stop = interrupt_flag();
    let rec = record_rows(&mut robot, &mut writer, a, &stop, live.as_mut());
    if let Some(live) = &live {
        eprintln!("{}", live.summary());
    }
    let nothing_measured = rec.link_error.is_none()
        && (1..=FIRST_CYCLES).contains(&rec.rows)
        && rec.failures.iter().all(|&f| f == rec.rows);
    if nothing_measured {
        // Nothing was measured: a file of NaN must not look like a recording, and an
        // older recording of the same name stays as it was.
        writer.discard();
        return Err(CliError::new(format!(
            "no servo of the mapping answered in the first {} cycles (ids {}); \
             check --map, the port and the baud rate (`twinloop link scan --port ...` \
             lists what answers)",
            rec.rows,
            ids.join(", ")
        )));
    }
    let finished = writer.finish();
    record_summary(
        a,
        &rec,
        &names,
        stop.load(Ordering::Relaxed),
        &robot.client.stats,
    );
    finished?;
    if let Some(why) = rec.silent {
        // The bus froze: the rows read before are a recording, but an incomplete one.
        eprintln!(
            "error: recording stopped: {why}; the {} rows read before are in {}",
            rec.rows,
            outs(&a.out)
        );
        return Ok(Outcome::Problems);
    }
    match rec.link_error {
        Some(e) => Err(CliError::new(format!(
            "recording stopped: {e}; the {} rows read before are in the file",
            rec.rows
        ))),
        None => Ok(Outcome::Ok),
    }
}

/// The bus `link record` reads and its mapping: `--map`'s (whose port is the default),
/// or one built from `--protocol` and `--ids` by asking each servo its model.
fn record_bus(
    a: &RecordArgs,
) -> Result<(twinloop_link::Client<Box<dyn Transport>>, RobotMapping), CliError> {
    // The list is checked before the port is opened: a typo is named, not a dead port.
    let ids = a.ids.as_deref().map(parse_ids).transpose()?;
    let mapping = a.map.as_deref().map(RobotMapping::resolve).transpose()?;
    let default_port = mapping.as_ref().and_then(|m| m.port.clone());
    let mut c = open_client(&a.port, default_port.as_deref())?;
    let mapping = match mapping {
        Some(m) => m,
        None => {
            let (Some(protocol), Some(ids)) = (a.protocol, ids) else {
                return Err(CliError::from(
                    "give --map MAPPING, or --protocol and --ids",
                ));
            };
            RobotMapping::from_ids(&mut c, protocol, &ids)?
        }
    };
    Ok((c, mapping))
}

/// The files `link record` writes: `t`, then each joint's q, v and tau.
fn record_writer(
    a: &RecordArgs,
    names: &[String],
    mapping_urdf: Option<&str>,
) -> Result<crate::common::RowWriter, CliError> {
    let mut columns = vec!["t".to_string()];
    for prefix in ["q", "v", "tau"] {
        columns.extend(names.iter().map(|n| format!("{prefix}:{n}")));
    }
    // Every row reaches a CSV as soon as it is read: nothing is lost on Ctrl-C or
    // when the adapter is unplugged. An .mcap is closed (summary written) on both.
    // The robot the mapping names goes on an MCAP's /robot_description, so a viewer
    // shows it moving with no twinloop installed.
    let description = match mapping_urdf {
        Some(spec) if a.out.iter().any(|p| crate::common::is_mcap(p)) => {
            Some(crate::common::load_description(spec)?.0)
        }
        _ => None,
    };
    crate::common::RowWriter::create_each(&a.out, &columns, description.as_ref(), true)
}

/// What a recording prints when it ends: rows, rate (and why it is low), each joint's
/// failed reads, the bus's health.
fn record_summary(
    a: &RecordArgs,
    rec: &Recording,
    names: &[String],
    interrupted: bool,
    stats: &twinloop_link::ClientStats,
) {
    let mut summary = format!(
        "{} rows in {:.3} s ({:.1} reads/s) written to {}",
        rec.rows,
        rec.seconds,
        rec.rows as f64 / rec.seconds.max(1e-9),
        outs(&a.out)
    );
    if interrupted {
        summary += " (interrupted)";
    }
    eprintln!("{summary}");
    let achieved = rec.rows as f64 / rec.seconds.max(1e-9);
    if rec.rows > FIRST_CYCLES && (a.rate == 0.0 || achieved < 0.9 * a.rate) {
        eprintln!("{}", rate_limit_note(a, names.len(), achieved));
    }
    for (k, f) in rec.failures.iter().enumerate() {
        if *f > 0 {
            eprintln!("  joint {}: {f} failed reads (NaN in those rows)", names[k]);
        }
    }
    let health = twinloop_experiments::guarded::BusHealth {
        reads: rec.rows as u64,
        reads_missed: rec.failed_rows as u64,
        longest_silence_s: rec.longest_silence.as_secs_f64(),
        silence_window_s: a.port.silence_window,
        ..Default::default()
    }
    .with_client(stats);
    eprintln!("{}", health.line());
}

/// The files a recording went to, for its summary line.
fn outs(paths: &[PathBuf]) -> String {
    let names: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
    names.join(" and ")
}

/// Why a recording ran slower than asked, and what raises its rate: each read is one
/// round trip per servo (or one for BULK/SYNC_READ), and every servo waits its Return
/// Delay Time before it answers.
fn rate_limit_note(a: &RecordArgs, servos: usize, achieved: f64) -> String {
    format!(
        "note: {achieved:.0} reads/s{}: the bus limits the rate. Each read asks {servos} servo(s) \
         with {}, each waits its Return Delay Time (factory 500 us) before answering, and \
         each round trip pays the USB adapter's latency (16 ms on FTDI unless --low-latency). \
         `twinloop link plan --servos {servos} --baud {} --protocol 1|2 --return-delay-us US` \
         gives the floor; raise the rate with --low-latency, a higher --baud, --method bulk or \
         sync where the servos have it, or a Return Delay Time of 0 on the servos",
        if a.rate > 0.0 {
            format!(" of the {} asked", a.rate)
        } else {
            String::new()
        },
        match a.method {
            ReadMethod::Auto => "the cheapest read they all have",
            m => m.name(),
        },
        a.port.baud
    )
}

/// After this many cycles, a recording in which no servo has answered stops.
const FIRST_CYCLES: usize = 3;

/// What the recording loop did.
struct Recording {
    rows: usize,
    seconds: f64,
    /// Failed reads per joint.
    failures: Vec<usize>,
    /// Why the recording stopped early: the link or the file failed.
    link_error: Option<String>,
    /// Why it stopped when every servo went silent past the silence window (the
    /// servos named): the rows before are kept and the command exits 1.
    silent: Option<String>,
    /// The longest time no servo answered.
    longest_silence: Duration,
    /// Rows with a servo that did not answer.
    failed_rows: usize,
}

/// Read the robot and write a row, at --rate, until --duration ran out, Ctrl-C set
/// `stop`, or the link failed.
fn record_rows<T: Transport>(
    robot: &mut DynamixelRobot<T>,
    writer: &mut crate::common::RowWriter,
    a: &RecordArgs,
    stop: &AtomicBool,
    mut live: Option<&mut twinloop_view::LivePublisher>,
) -> Recording {
    let n = robot.outcomes().count();
    let mut state = RobotState::default();
    let mut row = vec![0.0; 1 + 3 * n];
    let mut rec = Recording {
        rows: 0,
        seconds: 0.0,
        failures: vec![0usize; n],
        link_error: None,
        silent: None,
        longest_silence: Duration::ZERO,
        failed_rows: 0,
    };
    let start = Instant::now();
    let dt = if a.rate > 0.0 { 1.0 / a.rate } else { 0.0 };
    // When any servo last answered: a bus silent for the window is gone.
    let mut heard = start;
    while start.elapsed().as_secs_f64() < a.duration && !stop.load(Ordering::Relaxed) {
        let r = robot.read(&mut state);
        if let Err(e) = &r
            && e.joint.is_none()
        {
            rec.link_error = Some(e.to_string());
            break;
        }
        let mut answered = false;
        let mut missed = false;
        for (k, (_, o)) in robot.outcomes().enumerate() {
            if o.is_err() {
                rec.failures[k] += 1;
                missed = true;
            } else {
                answered = true;
            }
        }
        rec.failed_rows += usize::from(missed);
        let now = Instant::now();
        if answered {
            heard = now;
        }
        rec.longest_silence = rec.longest_silence.max(now - heard);
        row[0] = state.time;
        row[1..1 + n].copy_from_slice(&state.positions);
        row[1 + n..1 + 2 * n].copy_from_slice(state.velocities.as_deref().unwrap_or(&[]));
        row[1 + 2 * n..].copy_from_slice(state.efforts.as_deref().unwrap_or(&[]));
        if let Err(e) = writer.write_row(&row) {
            rec.link_error = Some(e.to_string());
            break;
        }
        rec.rows += 1;
        if let Some(live) = live.as_deref_mut() {
            live.offer(state.time, &state.positions);
        }
        if rec.rows == FIRST_CYCLES && never_answered(robot, &rec.failures, rec.rows) {
            break;
        }
        if now - heard >= a.port.silence_window() {
            rec.silent = Some(silent_servos(robot, (now - heard).as_secs_f64(), a));
            break;
        }
        if dt > 0.0 {
            let _ = robot.advance(dt);
        }
    }
    rec.seconds = start.elapsed().as_secs_f64();
    rec
}

/// Which servos went silent, for a recording stopped by the silence window.
fn silent_servos<T: Transport>(robot: &DynamixelRobot<T>, silent_s: f64, a: &RecordArgs) -> String {
    let servos: Vec<String> = robot
        .mapping()
        .joints
        .iter()
        .zip(robot.outcomes())
        .filter(|(_, (_, o))| o.is_err())
        .map(|(j, _)| format!("id {} ({})", j.id, j.name))
        .collect();
    let last = robot
        .outcomes()
        .find_map(|(name, o)| o.as_ref().err().map(|e| format!("joint {name}: {e}")))
        .unwrap_or_default();
    format!(
        "every servo went silent for {silent_s:.2} s, longer than the silence window \
         (--silence-window {} s): {}; the last: {last}",
        a.port.silence_window,
        servos.join(", ")
    )
}

/// After the first cycles: true when no servo has answered (the recording stops);
/// the servos that never answered while others did are named on stderr.
fn never_answered<T: Transport>(
    robot: &DynamixelRobot<T>,
    failures: &[usize],
    rows: usize,
) -> bool {
    let silent: Vec<&str> = robot
        .outcomes()
        .zip(failures)
        .filter(|(_, f)| **f == rows)
        .map(|((name, _), _)| name)
        .collect();
    if silent.len() == failures.len() {
        return true;
    }
    if !silent.is_empty() {
        eprintln!(
            "warning: {} joint(s) have not answered in the first {rows} cycles: {} (NaN in \
             their columns)",
            silent.len(),
            silent.join(", ")
        );
    }
    false
}

/// The Return Delay Time Dynamixel servos leave the factory with, us (register 250 x 2).
const FACTORY_RETURN_DELAY_US: u64 = 500;

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

fn plan(a: &PlanArgs) -> CliResult {
    if a.servos == 0 || a.servos > 253 {
        return Err(CliError::from(format!(
            "--servos {}: must be 1..=253",
            a.servos
        )));
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
    if a.return_delay_us == 0.0 {
        // The table assumes servos set to answer at once; out of the box they do not.
        let (m, l) = cases[0];
        let factory = plan_cycle(
            a.protocol,
            m,
            a.servos,
            l,
            goal,
            a.baud,
            Duration::from_micros(FACTORY_RETURN_DELAY_US),
        );
        out += &format!(
            "return delay 0 assumed: at the factory Return Delay Time ({FACTORY_RETURN_DELAY_US} us, \
             register 250) the first row runs at {:.0} Hz; give --return-delay-us (read it with \
             `twinloop link read --port PORT --protocol {} --id ID return_delay_time`)\n",
            factory.cycles_per_second(),
            a.protocol.number()
        );
    }
    emit(&out, a.json.as_ref(), &plans)?;
    Ok(Outcome::Ok)
}
