//! `twinloop serve`: put a virtual robot on a pseudo-terminal or TCP port that any
//! Dynamixel program can talk to.

use crate::bus_args::interrupt_flag;
use crate::common::hinges_only;
use crate::common::{ROBOT_HELP, load_description, print};
use crate::error::{CliError, CliResult, Outcome};
use clap::Args;
use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;
use std::time::Duration;
use twinloop_description::Description;
use twinloop_link::servo::{ServeOptions, serve as serve_bus};
use twinloop_link::transport::{NoisyTransport, PtyTransport, TcpTransport, Transport};
use twinloop_link::{BusServo, RobotMapping, VirtualBus};

/// A probability per byte, 0..=1.
fn probability(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(p) if (0.0..=1.0).contains(&p) => Ok(p),
        _ => Err(format!("{s:?} is not a probability (0 to 1)")),
    }
}

/// The robot served when neither --robot nor --map is given.
const DEFAULT_ROBOT: &str = "builtin:km20";

#[derive(Args)]
pub struct ServeArgs {
    #[arg(
        long,
        value_name = "ROBOT",
        help = ROBOT_HELP,
        long_help = "Robot description: a URDF or MJCF file, or builtin:NAME. builtin:km20 (the \
default without --map) is simulated on RX-28/RX-64 servos on Protocol 1.0 with its own mapping; \
a file needs --map. Without --robot, the description is the mapping's `urdf` (if any)"
    )]
    pub robot: Option<String>,
    /// Servo mapping: a TOML file or builtin:km20 / builtin:op3 (servo ids, models and
    /// protocols of the robot's joints; default: the built-in robot's own). builtin:op3
    /// alone is 20 XM430 on Protocol 2.0, stand-in servos
    #[arg(long, value_name = "MAPPING")]
    pub map: Option<String>,
    /// What moves the servos: sim (the physics simulation of the robot standing on the
    /// ground, in real time), ideal (each servo tracks its goal, no physics: for
    /// protocol-only benchmarks) or auto (sim when the robot has a description)
    #[arg(long, default_value = "auto", value_parser = ["auto", "sim", "ideal"])]
    pub servo_model: String,
    /// Simulated robot: servos power on limp, as real ones do (the robot falls)
    #[arg(long)]
    pub torque_off: bool,
    /// Simulated robot: simulated seconds per wall-clock second
    #[arg(long, default_value_t = 1.0, value_name = "FACTOR", value_parser = crate::bounds::realtime_factor)]
    pub realtime_factor: f64,
    /// Simulated robot: an operator catches the robot when its trunk tilts past 30
    /// deg and stands it up in the pose its servos are commanded to, as a person does
    /// between the runs of `experiment tipover --port`
    #[arg(long)]
    pub catch_falls: bool,
    /// Simulated robot: held in the air, its trunk fixed upright (base welded, no
    /// ground), each servo holding its joint at 0: the rig of `experiment servo --map
    /// MAP --joint NAME`, which moves one limb while the others hold
    #[arg(long, conflicts_with_all = ["catch_falls", "ground_sink", "bench"])]
    pub held: bool,
    /// Simulated robot: how far its weight sinks into the ground, m (the floor's
    /// stiffness; default 0.001). 1e-5 is the near-rigid floor of the simulated
    /// tip-over study (`experiment tipover --robot`), whose angles it then gives
    #[arg(long, value_name = "M", value_parser = crate::common::positive)]
    pub ground_sink: Option<f64>,
    /// Where to serve: pty (a new pseudo-terminal) or tcp:ADDR (e.g. tcp:127.0.0.1:5555)
    #[arg(long, default_value = "pty", value_name = "PORT")]
    pub port: String,
    /// With a pty: also make this path a symbolic link to it (a stable name for scripts)
    #[arg(long, value_name = "PATH")]
    pub link: Option<PathBuf>,
    /// Bit rate whose wire time (and each servo's Return Delay Time) is emulated
    #[arg(long, default_value_t = 1_000_000, value_parser = crate::common::baud)]
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
    /// Damage the line: each byte, both ways, is hit with this probability (a bit
    /// flipped, the byte dropped or a random byte inserted after it, equally likely),
    /// as a bad cable or a noisy supply would; the counts are told on exit. Tests
    /// that no corrupted or stale reply is accepted (docs/link.md)
    #[arg(long, default_value_t = 0.0, value_name = "RATE", value_parser = probability)]
    pub line_noise: f64,
    /// The random draw of --line-noise
    #[arg(long, default_value_t = 1, requires = "line_noise")]
    pub seed: u64,
    /// Simulated robot only (not --servo-model ideal).
    #[command(flatten)]
    pub view: crate::live_view::LiveViewArgs,
    /// Serve one servo of this type (id 1: RX-28, RX-64, MX-64(2.0), XM430-W350)
    /// swinging the pendulum of --load, moved by its servo model (docs/servo-models.md),
    /// instead of a robot: the bench of `experiment servo`
    #[arg(long, value_name = "MODEL", requires = "load")]
    pub bench: Option<String>,
    /// The bench's pendulum: a TOML file with mass (kg), length (m, axis to the mass)
    /// and arm_inertia (kg m^2, the arm alone about the axis)
    #[arg(long, value_name = "LOAD.toml")]
    pub load: Option<PathBuf>,
    /// Servo model parameters (`identify servo --out` or `--defaults`;
    /// docs/servo-models.md): FILE.toml for every servo of its type, or ID=FILE.toml
    /// (bus id) or JOINT=FILE.toml for one servo, repeatable; the others keep their
    /// datasheet's. The simulated robot's servos then run that model (the bench's
    /// equations: firmware on encoder counts, motor, friction, backlash, delays);
    /// with --bench, one FILE.toml
    #[arg(long, value_name = "[ID=]FILE.toml")]
    pub servo_params: Vec<String>,
    /// The robot you have, not the one modelled: a part the description lacks
    /// (a camera, a battery), or taken off with a negative mass; the virtual robot
    /// carries it, the bus does not tell.
    #[command(flatten)]
    pub added: crate::units::AddMassArgs,
}

/// The mapping: --map, or the built-in robot's own.
fn serve_mapping(a: &ServeArgs) -> Result<RobotMapping, CliError> {
    if let Some(m) = &a.map {
        return Ok(RobotMapping::resolve(m)?);
    }
    let spec = a.robot.as_deref().unwrap_or(DEFAULT_ROBOT);
    match spec.strip_prefix("builtin:") {
        Some(name) => RobotMapping::builtin(name).ok_or_else(|| {
            CliError::new(format!(
                "--robot {spec}: no built-in mapping for {name:?} (built-in: {}); give --map MAPPING",
                RobotMapping::BUILTINS.join(", ")
            ))
        }),
        None => Err(CliError::new(format!(
            "--robot {spec}: a description file needs --map MAPPING (which servo drives which joint)"
        ))),
    }
}

/// The robot's description: --robot, else the mapping's `urdf` (relative to the
/// mapping file), else none (a mapping-only bus).
fn serve_description(
    a: &ServeArgs,
    mapping: &RobotMapping,
) -> Result<Option<Description>, CliError> {
    if let Some(spec) = &a.robot {
        let (mut robot, _) = load_description(spec)?;
        hinges_only(&robot, spec, "the virtual robot")?;
        a.added.apply(&mut robot)?;
        return Ok(Some(robot));
    }
    if a.map.is_none() {
        let mut robot = load_description(DEFAULT_ROBOT)?.0;
        a.added.apply(&mut robot)?;
        return Ok(Some(robot));
    }
    match crate::common::profile_description(mapping) {
        Ok(r) => {
            let mut robot = r.map(|(robot, _)| robot);
            if let Some(r) = robot.as_mut() {
                a.added.apply(r)?;
            }
            Ok(robot)
        }
        Err(e) if a.servo_model == "sim" => Err(e),
        Err(_) => Ok(None),
    }
}

/// `twinloop serve`.
pub fn run(a: ServeArgs) -> CliResult {
    if let Some(model) = &a.bench {
        return serve_bench(&a, model);
    }
    let mapping = serve_mapping(&a)?;
    let robot = serve_description(&a, &mapping)?;
    if robot.is_none() && !a.added.add_mass.is_empty() {
        return Err(CliError::new(
            "--add-mass changes the simulated robot, and this bus serves servos with no description: give --robot",
        ));
    }
    // The joints' servos, then the mapping's boards (the CM-730 of the trunk IMU).
    let servos: Vec<BusServo> = mapping.bus();
    let simulate = match (a.servo_model.as_str(), &robot) {
        ("ideal", _) => false,
        ("sim", None) => {
            return Err(CliError::from(format!(
                "--servo-model sim: {} has no robot description to simulate (give --robot)",
                a.map.as_deref().unwrap_or("the mapping")
            )));
        }
        (_, r) => r.is_some(),
    };
    if !simulate && a.view.view.is_some() {
        return Err(CliError::new(
            "--view shows the simulated robot: it needs --servo-model sim (or auto with a description)",
        ));
    }
    if let (true, Some(robot)) = (simulate, &robot) {
        return serve_simulated(&a, &mapping, robot);
    }
    if a.held {
        return Err(CliError::new(
            "--held holds the simulated robot: it needs --servo-model sim (or auto with a description)",
        ));
    }
    if !a.servo_params.is_empty() {
        return Err(CliError::new(
            "--servo-params sets the simulated servos: it needs --servo-model sim (or auto with a description)",
        ));
    }
    let bus = VirtualBus::with_tracking_model_and_boards(&servos, &mapping.bus_boards());
    serve_on(
        &a,
        &mapping,
        bus,
        "stand-in servos (each tracks its goal, 50 ms lag; no physics)",
    )
}

/// Serve the physics simulation of the robot standing on the ground.
fn serve_simulated(a: &ServeArgs, mapping: &RobotMapping, robot: &Description) -> CliResult {
    let options = twinloop_virtual::VirtualRobotOptions {
        torque_on: !a.torque_off,
        realtime_factor: a.realtime_factor,
        catch_falls: a.catch_falls,
        ground_sink: a.ground_sink,
        held: a.held,
        servo_params: twinloop_actuator::params_set::ServoParamsSet::read(
            &a.servo_params,
            "--servo-params",
        )?,
        ..Default::default()
    };
    let mut vr = twinloop_virtual::VirtualRobot::new(robot, mapping, &options)?;
    let names = vr.simulator().model.q_names();
    let live = crate::live_view::start_live(&a.view, robot, a.robot.as_deref(), &names)?;
    if !vr.unmapped.is_empty() {
        eprintln!(
            "joints without a servo on the bus (they hold their pose): {}",
            vr.unmapped.join(", ")
        );
    }
    let bus = vr.bus();
    let sim = vr.spawn();
    let what = format!(
        "the physics simulation of {} {} (real time x{}, servos {})",
        robot.name,
        if a.held {
            "held in the air, trunk fixed upright"
        } else {
            "standing on the ground"
        },
        a.realtime_factor,
        if a.torque_off { "limp" } else { "torque on" }
    );
    let done = std::sync::atomic::AtomicBool::new(false);
    let code = std::thread::scope(|s| {
        s.spawn(|| warn_when_behind(&sim, &done));
        let code = serve_watched(a, mapping, bus, &what, &sim, live);
        done.store(true, Ordering::Relaxed);
        code
    });
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
    code
}

/// Say on stderr when the simulation falls behind the wall clock (at most once a
/// second): the host then reads a robot that moves slower than real time, and its
/// timing no longer says anything about a real one.
fn warn_when_behind(sim: &twinloop_virtual::SimHandle, done: &std::sync::atomic::AtomicBool) {
    let mut told = 0.0;
    while !done.load(Ordering::Relaxed) {
        std::thread::sleep(Duration::from_millis(200));
        let status = sim.status();
        if status.behind_s > told {
            eprintln!(
                "warning: the simulation fell {:.3} s behind the wall clock at simulated \
                 time {:.1} s ({:.3} s in all): the machine is too busy for this real-time \
                 factor",
                status.behind_s - told,
                status.time,
                status.behind_s
            );
            told = status.behind_s;
            std::thread::sleep(Duration::from_millis(800));
        }
    }
}

/// `serve_on`, with `--view`'s page reading the simulation on its own thread.
fn serve_watched<B: twinloop_link::VirtualServoBackend>(
    a: &ServeArgs,
    mapping: &RobotMapping,
    bus: VirtualBus<B>,
    what: &str,
    sim: &twinloop_virtual::SimHandle,
    live: Option<twinloop_view::LivePublisher>,
) -> CliResult {
    let Some(mut live) = live else {
        return serve_on(a, mapping, bus, what);
    };
    let done = std::sync::atomic::AtomicBool::new(false);
    std::thread::scope(|s| {
        s.spawn(|| crate::live_view::watch_simulation(&mut live, sim, &done));
        let code = serve_on(a, mapping, bus, what);
        done.store(true, Ordering::Relaxed);
        code
    })
    .inspect(|_| eprintln!("{}", live.summary()))
}

/// Serve one servo on the pendulum bench (id 1).
fn serve_bench(a: &ServeArgs, model: &str) -> CliResult {
    use twinloop_actuator::{ModelLevel, Pendulum, ServoParams, ServoType, datasheet};
    let servo = ServoType::parse(model).ok_or_else(|| {
        CliError::new(format!(
            "--bench {model:?}: no servo model for it (known: {})",
            ServoType::known_names()
        ))
    })?;
    let load = Pendulum::read(a.load.as_deref().ok_or("--bench needs --load LOAD.toml")?)?;
    let params = match a.servo_params.as_slice() {
        [] => datasheet::defaults(servo, ModelLevel::M1),
        [path] => ServoParams::read(Path::new(path))?,
        _ => {
            return Err(CliError::new(
                "--bench serves one servo: give one --servo-params FILE.toml",
            ));
        }
    };
    if params.servo != servo {
        return Err(CliError::new(format!(
            "--servo-params {}: parameters of {}, but --bench is {servo}",
            a.servo_params[0], params.servo
        )));
    }
    let mut backend = twinloop_virtual::BenchBackend::new(params, load, a.realtime_factor)
        .ok_or_else(|| CliError::new(format!("--bench {servo}: no control table for it")))?;
    let text = format!(
        "[robot]\nname = \"bench\"\n[[joint]]\nname = \"pendulum\"\nid = 1\nmodel = \"{}\"\n",
        backend.model()
    );
    let mapping = RobotMapping::parse(&text, "bench")?;
    let servos = mapping.bus();
    let condition = std::sync::Arc::new(std::sync::atomic::AtomicU8::new(0));
    backend.condition = Some(condition.clone());
    let mut bus = VirtualBus::new(&servos, backend);
    bus.servos[0].condition = condition;
    let what = format!(
        "the servo model of docs/servo-models.md swinging a {} kg pendulum at {} m (real time x{})",
        load.mass, load.length, a.realtime_factor
    );
    serve_on(a, &mapping, bus, &what)
}

fn serve_on<B: twinloop_link::VirtualServoBackend>(
    a: &ServeArgs,
    mapping: &RobotMapping,
    mut bus: VirtualBus<B>,
    what: &str,
) -> CliResult {
    // Protocol Type as the mapping says, Baud Rate registers at the line's code.
    mapping.configure(&mut bus, a.baud);
    let options = ServeOptions {
        emulate_baud: (!a.no_timing).then_some(a.baud),
        stop_on_eof: true,
        warn_stalls: true,
    };
    let banner = Banner {
        mapping,
        servos: mapping.joints.len(),
        what,
        emulate_baud: options.emulate_baud,
    };
    if a.port == "pty" {
        return serve_pty(a, &mut bus, &options, &banner);
    }
    let Some(addr) = a.port.strip_prefix("tcp:") else {
        return Err(CliError::new(format!(
            "--port {:?}: use pty or tcp:ADDR",
            a.port
        )));
    };
    serve_tcp(addr, a, &mut bus, &options, &banner)
}

/// Serve on `t`, through its noise only with --line-noise: without, the line is
/// exactly the transport's (no re-chunking of what it reads).
fn serve_maybe_noisy<T: Transport, B: twinloop_link::VirtualServoBackend>(
    bus: &mut VirtualBus<B>,
    t: &mut NoisyTransport<T>,
    options: &ServeOptions,
    stop: &std::sync::atomic::AtomicBool,
) -> std::io::Result<()> {
    // This thread answers the host; every other thread (the simulation, the view)
    // was started before, at normal priority.
    if let twinloop_link::servo::ReplyPriority::Normal(why) =
        twinloop_link::servo::favour_reply_thread()
    {
        eprintln!(
            "note: the replies run at normal priority ({why}): on a busy machine they may \
             come later than the host waits"
        );
    }
    if t.rate > 0.0 {
        serve_bus(bus, t, options, stop)
    } else {
        serve_bus(bus, &mut t.inner, options, stop)
    }
}

/// What --line-noise did, on stderr (nothing without it).
fn tell_noise<T: Transport>(t: &NoisyTransport<T>, seed: u64) {
    if t.rate == 0.0 {
        return;
    }
    let s = t.stats;
    eprintln!(
        "line noise (rate {}, seed {seed}): {} bytes through, {} bits flipped, {} bytes \
         dropped, {} bytes inserted",
        t.rate, s.bytes, s.flipped, s.dropped, s.inserted
    );
}

/// What stderr says when serving starts.
struct Banner<'a> {
    mapping: &'a RobotMapping,
    servos: usize,
    what: &'a str,
    emulate_baud: Option<u32>,
}

impl Banner<'_> {
    fn text(&self, place: &str) -> String {
        let mut models: Vec<String> = Vec::new();
        for j in &self.mapping.joints {
            let m = format!("{} ({})", j.model, j.protocol);
            if !models.contains(&m) {
                models.push(m);
            }
        }
        for b in &self.mapping.boards {
            models.push(format!(
                "{} board at id {} ({})",
                b.kind.name, b.id, b.protocol
            ));
        }
        format!(
            "serving {} ({} servos: {}) on {place}\nmoved by {}\n{}\nCtrl-C stops.\n",
            if self.mapping.name.is_empty() {
                &self.mapping.source
            } else {
                &self.mapping.name
            },
            self.servos,
            models.join(", "),
            self.what,
            match self.emulate_baud {
                Some(b) =>
                    format!("wire time emulated at {b} bps, return delay per servo register"),
                None => "answering at once (no wire-time emulation)".to_string(),
            }
        )
    }
}

/// Serve on a new pseudo-terminal (and --link to it) until Ctrl-C.
fn serve_pty<B: twinloop_link::VirtualServoBackend>(
    a: &ServeArgs,
    bus: &mut VirtualBus<B>,
    options: &ServeOptions,
    banner: &Banner,
) -> CliResult {
    let stop = interrupt_flag();
    let mut pty = PtyTransport::open()
        .map_err(|e| CliError::new(format!("cannot open a pseudo-terminal: {e}")))?;
    pty.set_spin(Duration::from_micros(a.spin_us));
    let mut pty = NoisyTransport::new(pty, a.line_noise, a.seed);
    let path = pty.inner.path().to_path_buf();
    if let Some(link) = &a.link {
        // Only an old link is replaced, never a file (checked again: it may have appeared).
        crate::outputs::check_pty_link(link)?;
        let _ = std::fs::remove_file(link);
        std::os::unix::fs::symlink(&path, link).map_err(|e| {
            CliError::new(format!(
                "--link: cannot link {} to {}: {e}",
                link.display(),
                path.display()
            ))
        })?;
    }
    // The path first, alone on its line, for scripts.
    print(&format!("{}\n", path.display()));
    eprint!("{}", banner.text(&path.display().to_string()));
    let options = ServeOptions {
        stop_on_eof: false,
        ..*options
    };
    let r = serve_maybe_noisy(bus, &mut pty, &options, &stop);
    if let Some(link) = &a.link
        && std::fs::read_link(link).is_ok_and(|to| to == path)
    {
        let _ = std::fs::remove_file(link); // ours: a link to this pty
    }
    tell_noise(&pty, a.seed);
    r.map_err(|e| CliError::new(format!("{}: {e}", path.display())))?;
    Ok(Outcome::Ok)
}

/// Serve one TCP client at a time on `addr` until Ctrl-C; a second client is
/// refused with a line saying who has the bus (a bus has one host).
fn serve_tcp<B: twinloop_link::VirtualServoBackend>(
    addr: &str,
    a: &ServeArgs,
    bus: &mut VirtualBus<B>,
    options: &ServeOptions,
    banner: &Banner,
) -> CliResult {
    let stop = interrupt_flag();
    let listener = std::net::TcpListener::bind(addr)
        .map_err(|e| CliError::new(format!("--port tcp:{addr}: cannot listen: {e}")))?;
    let local = listener
        .local_addr()
        .map(|a| a.to_string())
        .unwrap_or_else(|_| addr.to_string());
    print(&format!("tcp:{local}\n"));
    eprint!("{}", banner.text(&format!("tcp:{local}")));
    let _ = listener.set_nonblocking(true);
    // The client being served, if any: the acceptor refuses others while it is set.
    let serving: std::sync::Mutex<Option<String>> = std::sync::Mutex::new(None);
    let (hand, take) = std::sync::mpsc::channel();
    std::thread::scope(|s| {
        s.spawn(|| accept_clients(&listener, &serving, &hand, &stop));
        while !stop.load(Ordering::Relaxed) {
            let Ok((stream, peer)) = take.recv_timeout(Duration::from_millis(100)) else {
                continue;
            };
            serve_client(stream, peer, a, bus, options, &stop);
            *serving.lock().unwrap_or_else(|e| e.into_inner()) = None;
        }
    });
    Ok(Outcome::Ok)
}

/// Accept connections on `listener` until `stop`: the first while none is served
/// goes to the serving thread through `hand`, the others are refused.
fn accept_clients(
    listener: &std::net::TcpListener,
    serving: &std::sync::Mutex<Option<String>>,
    hand: &std::sync::mpsc::Sender<(std::net::TcpStream, std::net::SocketAddr)>,
    stop: &std::sync::atomic::AtomicBool,
) {
    while !stop.load(Ordering::Relaxed) {
        let (stream, peer) = match listener.accept() {
            Ok(c) => c,
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                std::thread::sleep(Duration::from_millis(20));
                continue;
            }
            Err(e) => {
                eprintln!("accept: {e}");
                std::thread::sleep(Duration::from_millis(200));
                continue;
            }
        };
        let mut current = serving.lock().unwrap_or_else(|e| e.into_inner());
        match current.as_ref() {
            None => {
                *current = Some(peer.to_string());
                let _ = hand.send((stream, peer));
            }
            Some(other) => {
                let why = format!("another client ({other}) is connected");
                eprintln!("client {peer} refused: {why}");
                // Off this thread: the refusal waits for the client to leave.
                std::thread::spawn(move || twinloop_link::transport::refuse(stream, &why));
            }
        }
    }
}

/// Serve one accepted client until it leaves (or Ctrl-C).
fn serve_client<B: twinloop_link::VirtualServoBackend>(
    stream: std::net::TcpStream,
    peer: std::net::SocketAddr,
    a: &ServeArgs,
    bus: &mut VirtualBus<B>,
    options: &ServeOptions,
    stop: &std::sync::atomic::AtomicBool,
) {
    let _ = stream.set_nonblocking(false);
    eprintln!("client {peer} connected");
    let t = match TcpTransport::from_stream(stream) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("client {peer}: {e}");
            return;
        }
    };
    let mut t = NoisyTransport::new(t, a.line_noise, a.seed);
    if let Err(e) = serve_maybe_noisy(bus, &mut t, options, stop) {
        eprintln!("client {peer}: {e}");
    }
    tell_noise(&t, a.seed);
    eprintln!("client {peer} left");
}
