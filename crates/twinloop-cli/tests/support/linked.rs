//! `twinloop serve ... --link LINK` in the background, killed when dropped.

use std::path::Path;
use std::process::{Child, Command};

/// A served robot or bench; killed (and waited for) when dropped.
pub struct Server(pub Child);

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// Spawn `serve` (a `twinloop serve` command whose `--link` is `link`) and wait
/// until the link exists and the serve loop runs.
pub fn serve_linked(serve: &mut Command, link: &Path) -> Server {
    let server = Server(serve.spawn().unwrap());
    let t0 = std::time::Instant::now();
    while !link.exists() && t0.elapsed().as_secs() < 20 {
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    // The link is made just before the serve loop starts.
    std::thread::sleep(std::time::Duration::from_millis(300));
    server
}
