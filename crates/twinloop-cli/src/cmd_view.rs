//! `twinloop view`: the robot and its recordings in the browser (twinloop-view).

use crate::common::{self, ROBOT_HELP};
use crate::error::{CliError, CliResult, Outcome};
use crate::live_view::LIVE_RATE;
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
    if let Some(live) = &args.live
        && twinloop_logs::is_log(live)
    {
        // An MCAP is written as FILE.partial, its messages in zstd chunks of
        // hundreds of kB and its index at the end: nothing of it can be followed
        // row by row while its run goes on.
        return Err(CliError::new(format!(
            "--live {}: a log is complete only when its run ends (an .mcap is written as \
             .partial, in compressed chunks); record to a CSV to follow it live, give the \
             recording command --view, or open the finished log as a recording",
            live.display()
        )));
    }
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
        twinloop_io::output::write_atomic(out, html)
            .map_err(|e| CliError::from(e).context("--export"))?;
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
