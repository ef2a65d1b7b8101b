//! `--view` (a live 3D page of the robot as it moves), shared by the commands that
//! move one (`simulate`, `serve`, `link record`) and `view --live`: the flags mapped
//! onto `twinloop_view::LivePublisher`.

use crate::common;
use crate::error::CliError;
use clap::Args;
use std::path::Path;
use twinloop_view::PackageDir;

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
pub const LIVE_RATE: f64 = 90.0;

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
