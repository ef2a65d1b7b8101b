//! `twinloop view`: the robot and its recordings in the browser (twinloop-view).

use crate::common::{self, ROBOT_HELP};
use crate::error::{CliError, CliResult, Outcome};
use clap::Args;
use std::path::{Path, PathBuf};
use twinloop_view::{Content, LiveFeed, PackageDir, Recording, Scene, Server};

#[derive(Args)]
pub struct ViewArgs {
    #[arg(value_name = "ROBOT", help = ROBOT_HELP)]
    pub robot: String,
    /// CSV files to replay (t, q:<joint>, optional q:base.*); the second and later
    /// are drawn as translucent ghosts
    #[arg(value_name = "RECORDING.csv")]
    pub recordings: Vec<PathBuf>,
    /// The TCP port to serve on (0: a free one)
    #[arg(long, value_name = "PORT", default_value_t = 0)]
    pub port: u16,
    /// The address to listen on; the default serves this computer only
    #[arg(long, value_name = "ADDR", default_value = "127.0.0.1")]
    pub bind: String,
    /// Open the page in the default browser
    #[arg(long)]
    pub open: bool,
    /// Where package://NAME/ meshes are (repeat for several packages)
    #[arg(long = "package-dir", value_name = "NAME=DIR", value_parser = PackageDir::parse)]
    pub package_dirs: Vec<PackageDir>,
    /// Write one self-contained HTML file (robot, meshes, recordings, plots) and exit
    #[arg(long, value_name = "FILE.html", conflicts_with = "live")]
    pub export: Option<PathBuf>,
    /// Show the robot live from a CSV while another command writes it (simulate
    /// --out, link record --out): its newest row, --rate times a second
    #[arg(long, value_name = "FILE.csv")]
    pub live: Option<PathBuf>,
    /// States per second sent to the page in --live (a little above a 60 Hz screen,
    /// so that nearly every frame it draws has a new one)
    #[arg(long, value_name = "HZ", default_value_t = LIVE_RATE, value_parser = crate::common::positive)]
    pub rate: f64,
}

pub fn run(args: ViewArgs) -> CliResult {
    let (robot, format) = common::load_description(&args.robot)?;
    let source = (format != common::Format::Builtin).then(|| Path::new(&args.robot));
    let scene = Scene::new(&robot, source, &args.package_dirs);
    let mut recordings = Vec::with_capacity(args.recordings.len());
    for path in &args.recordings {
        let rec = Recording::from_table(&common::read_table(path)?, path, &scene.info)?;
        if let Some(w) = rec.warning() {
            eprintln!("warning: {w}");
        }
        recordings.push(rec);
    }
    for w in &scene.info.warnings {
        eprintln!("warning: {w}");
    }
    let live = args.live.as_ref().map(|_| LiveFeed::new());
    let joints: Vec<String> = scene.info.joints.iter().map(|j| j.name.clone()).collect();
    let content = Content {
        scene,
        recordings,
        live: live.clone(),
    };
    if let Some(out) = &args.export {
        let html =
            twinloop_view::export_html(&content).map_err(|e| CliError::new(e.to_string()))?;
        std::fs::write(out, html).map_err(|e| CliError::io(out, e).context("--export"))?;
        common::print(&format!("wrote {}\n", out.display()));
        return Ok(Outcome::Ok);
    }
    let addr = format!("{}:{}", args.bind, args.port);
    let server = Server::bind(&addr, content)
        .map_err(|e| CliError::new(format!("--bind {} --port {}: {e}", args.bind, args.port)))?;
    let url = server.url();
    common::print(&format!("{url}\n"));
    eprintln!(
        "serving {} with {} recording(s); Ctrl-C stops",
        robot.name,
        args.recordings.len()
    );
    if args.open {
        open_browser(&url);
    }
    if let (Some(path), Some(feed)) = (args.live.clone(), live) {
        let rate = args.rate;
        std::thread::spawn(move || {
            if let Err(e) = twinloop_view::follow_csv(&path, &joints, rate, &feed, &|| false) {
                eprintln!("warning: --live {}: {e}", path.display());
            }
        });
    }
    server.run();
    Ok(Outcome::Ok)
}

/// Hand the URL to the desktop's browser; a failure is a note, not an error (the
/// URL is printed).
fn open_browser(url: &str) {
    let program = if cfg!(target_os = "macos") {
        "open"
    } else if cfg!(windows) {
        "explorer"
    } else {
        "xdg-open"
    };
    if let Err(e) = std::process::Command::new(program).arg(url).spawn() {
        eprintln!("note: could not run {program} ({e}); open {url} yourself");
    }
}

/// `--view`, shared by the commands that move a robot as they run (`simulate`,
/// `serve`, `link record`).
#[derive(Args, Debug, Clone, Default)]
pub struct LiveViewArgs {
    /// Show the robot live in the browser as it moves: serve the viewer page on ADDR
    /// (default 127.0.0.1 and a free port); its URL is printed on stderr
    #[arg(
        long,
        value_name = "ADDR",
        num_args = 0..=1,
        require_equals = true,
        default_missing_value = "127.0.0.1:0"
    )]
    pub view: Option<String>,
    /// With --view: where package://NAME/ meshes are, as for `twinloop view` (repeat for
    /// several packages)
    #[arg(long = "package-dir", value_name = "NAME=DIR", value_parser = PackageDir::parse, requires = "view")]
    pub package_dirs: Vec<PackageDir>,
}

/// States per second sent to the page by `--view` and `view --live`: a little above
/// a 60 Hz screen, so that the page, drawing every frame with the newest state, has a
/// new one for nearly every frame (at exactly 60 the two clocks beat, and a frame in
/// every few shows the state before again).
const LIVE_RATE: f64 = 90.0;

/// Start `--view`'s page for `robot` (`spec`: what --robot said, for meshes named
/// relative to its file), fed with states whose coordinates are `names`.
pub fn start_live(
    args: &LiveViewArgs,
    robot: &twinloop_description::Description,
    spec: Option<&str>,
    names: &[String],
) -> Result<Option<twinloop_view::LivePublisher>, CliError> {
    let Some(addr) = &args.view else {
        return Ok(None);
    };
    let source = spec.filter(|s| !s.starts_with("builtin:")).map(Path::new);
    let live = twinloop_view::LivePublisher::start(
        robot,
        source,
        &args.package_dirs,
        addr,
        names,
        LIVE_RATE,
    )
    .map_err(|e| CliError::new(format!("--view {addr}: {e}")))?;
    eprintln!("live view: {}", live.url());
    if !live.missing().is_empty() {
        eprintln!(
            "warning: --view: no state for joints {} (drawn at 0)",
            live.missing().join(", ")
        );
    }
    Ok(Some(live))
}

/// `serve --view`: read the simulation's snapshot `LIVE_RATE` times a second on this
/// thread (the simulation's own thread is not touched) until `done`; the state sent
/// is the simulator's whole configuration, the floating base's pose with the joints
/// (the live page is started with `Model::q_names`).
pub fn watch_simulation(
    live: &mut twinloop_view::LivePublisher,
    sim: &twinloop_virtual::SimHandle,
    done: &std::sync::atomic::AtomicBool,
) {
    let mut snap = twinloop_virtual::Snapshot::default();
    let period = std::time::Duration::from_secs_f64(0.5 / LIVE_RATE);
    while !done.load(std::sync::atomic::Ordering::Relaxed) {
        sim.snapshot(&mut snap);
        live.offer(snap.time, &snap.q);
        std::thread::sleep(period);
    }
}

/// `link record --view`: the page for the robot a servo mapping names (its `urdf`:
/// `builtin:NAME`, or a file relative to the mapping's), fed with the mapping's
/// joints.
pub fn start_live_for_mapping(
    args: &LiveViewArgs,
    mapping: &twinloop_link::RobotMapping,
) -> Result<Option<twinloop_view::LivePublisher>, CliError> {
    if args.view.is_none() {
        return Ok(None);
    }
    let Some(urdf) = &mapping.urdf else {
        return Err(CliError::new(format!(
            "--view: the mapping {} names no robot description (add urdf = \"FILE\" to it)",
            mapping.source
        )));
    };
    let spec = urdf.display().to_string();
    let (robot, _) = common::load_description(&spec)?;
    start_live(args, &robot, Some(&spec), &mapping.joint_names())
}
