//! A running command's own live view (`simulate --view`, `serve --view`, `link
//! record --view`): the viewer page served for the robot, and the command's state
//! published to it as it runs.
//!
//! The producer calls [`LivePublisher::offer`] with every state it makes (1 kHz for
//! a simulation). Most are decimated away by one comparison; the few let through
//! (90 a second from the CLI) are copied into the feed's slot if no page is copying it out at
//! that instant, and skipped otherwise: the producer never waits for a page, never
//! allocates, and never makes JSON (each page's own thread does).

use crate::live::{Decimator, LiveFeed};
use crate::scene::{PackageDir, Scene};
use crate::server::{Content, Server};
use std::io;
use std::path::Path;
use std::time::{Duration, Instant};
use twinloop_description::Description;

/// What the producer's thread spent on the viewer, and how it kept time.
#[derive(Debug, Clone, Default)]
pub struct PublisherStats {
    /// States offered (every step of the producer).
    pub offered: u64,
    /// States copied into the feed.
    pub published: u64,
    /// States let through by the decimator but skipped because a page was copying
    /// the previous one out.
    pub skipped_busy: u64,
    /// Time spent in `offer` on the states let through (the others cost one
    /// comparison), s.
    pub publish_s: f64,
    /// Time slept by [`LivePublisher::keep_real_time`], s.
    pub slept_s: f64,
    /// Wall time from the first [`LivePublisher::keep_real_time`] to the last, s.
    pub wall_s: f64,
}

/// The viewer page for one robot and the state of whatever moves it.
pub struct LivePublisher {
    feed: LiveFeed,
    url: String,
    decimator: Decimator,
    /// For each of the scene's joints, its place in the producer's state.
    map: Vec<Option<usize>>,
    /// Where `base.x` (then y, z, qx, qy, qz, qw) is in the producer's state.
    base_at: Option<usize>,
    /// The scene's joints that the producer's state does not have.
    missing: Vec<String>,
    q: Vec<f64>,
    stats: PublisherStats,
    /// Wall clock and source time when keeping real time started.
    clock: Option<(Instant, f64)>,
    last_pace: Option<Instant>,
}

impl LivePublisher {
    /// Serve the page for `robot` (`source`: its file, for meshes named relative to
    /// it) on `addr` (e.g. `127.0.0.1:0`), for a producer whose state has the
    /// coordinates `names` (joint names, and `base.x` .. `base.qw` for a floating
    /// base, as `Model::q_names`), sent `rate` times a second of source time.
    pub fn start(
        robot: &Description,
        source: Option<&Path>,
        packages: &[PackageDir],
        addr: &str,
        names: &[String],
        rate: f64,
    ) -> io::Result<LivePublisher> {
        let scene = Scene::new(robot, source, packages);
        let find = |n: &str| names.iter().position(|m| m == n);
        let map: Vec<Option<usize>> = scene.info.joints.iter().map(|j| find(&j.name)).collect();
        let missing = scene
            .info
            .joints
            .iter()
            .zip(&map)
            .filter(|(_, m)| m.is_none())
            .map(|(j, _)| j.name.clone())
            .collect();
        // The seven base coordinates, in this order and side by side (q_names' layout).
        let base_at = find("base.x").filter(|&b| {
            crate::recording::BASE_COLUMNS
                .iter()
                .enumerate()
                .all(|(k, c)| names.get(b + k).map(String::as_str) == c.strip_prefix("q:"))
        });
        let feed = LiveFeed::new();
        let q = vec![f64::NAN; map.len()];
        let content = Content {
            scene,
            recordings: Vec::new(),
            live: Some(feed.clone()),
        };
        let server = Server::bind(addr, content)?;
        server.spawn();
        Ok(LivePublisher {
            feed,
            url: server.url(),
            decimator: Decimator::new(rate),
            map,
            base_at,
            missing,
            q,
            stats: PublisherStats::default(),
            clock: None,
            last_pace: None,
        })
    }

    /// The page's URL.
    pub fn url(&self) -> &str {
        &self.url
    }

    /// The robot's joints the producer's state does not have (drawn at 0).
    pub fn missing(&self) -> &[String] {
        &self.missing
    }

    /// The feed (pages connected, ...).
    pub fn feed(&self) -> &LiveFeed {
        &self.feed
    }

    /// Wait until a page has connected, or `stop` says so: a run that starts before
    /// anyone watches is missed.
    pub fn wait_for_page(&self, stop: &dyn Fn() -> bool) {
        while self.feed.connections() == 0 && !stop() {
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    /// The producer's state at source time `t` (coordinates in the order of the
    /// `names` given to [`LivePublisher::start`]).
    pub fn offer(&mut self, t: f64, state: &[f64]) {
        self.stats.offered += 1;
        if !self.decimator.admit(t) {
            return;
        }
        let start = Instant::now();
        for (v, m) in self.q.iter_mut().zip(&self.map) {
            *v = m.and_then(|i| state.get(i).copied()).unwrap_or(f64::NAN);
        }
        let base = self
            .base_at
            .and_then(|b| state.get(b..b + 7))
            .and_then(|s| <[f64; 7]>::try_from(s).ok());
        if self.feed.try_publish(t, &self.q, base) {
            self.stats.published += 1;
        } else {
            self.stats.skipped_busy += 1;
            self.decimator.retry();
        }
        self.stats.publish_s += start.elapsed().as_secs_f64();
    }

    /// Sleep until the wall clock, counted from the first call, has caught up with
    /// source time `t`: a simulation faster than real time is shown at real time.
    /// Sleeps only when more than a millisecond ahead (fewer wake-ups).
    pub fn keep_real_time(&mut self, t: f64) {
        let now = Instant::now();
        let (start, t0) = *self.clock.get_or_insert((now, t));
        let ahead = (t - t0) - now.duration_since(start).as_secs_f64();
        if ahead > 1e-3 {
            std::thread::sleep(Duration::from_secs_f64(ahead));
            self.stats.slept_s += ahead;
        }
        self.last_pace = Some(Instant::now());
        self.stats.wall_s = self
            .last_pace
            .map_or(0.0, |l| l.duration_since(start).as_secs_f64());
    }

    pub fn stats(&self) -> &PublisherStats {
        &self.stats
    }

    /// One line on what the viewer cost the producer.
    pub fn summary(&self) -> String {
        let s = &self.stats;
        let mut out = format!(
            "live view: {} of {} states sent ({} skipped while a page read the last), \
             {:.1} us each on the producer's thread ({:.1} ms in all)",
            s.published,
            s.offered,
            s.skipped_busy,
            1e6 * s.publish_s / (s.published + s.skipped_busy).max(1) as f64,
            1e3 * s.publish_s,
        );
        if s.wall_s > 0.0 {
            out += &format!(
                "; in {:.3} s of wall time the run was busy {:.0} % and waited for the clock the rest",
                s.wall_s,
                100.0 * (1.0 - s.slept_s / s.wall_s).max(0.0)
            );
        }
        out
    }
}

impl Drop for LivePublisher {
    /// The pages are told the source stopped.
    fn drop(&mut self) {
        self.feed.close();
    }
}
