//! Arbitrary text as a URDF: the reader returns a description or an error, never
//! panics; what it accepts, lint checks, the writer writes and the reader reads again,
//! and the dynamics compile (or refuse) without panicking.
#![no_main]

use libfuzzer_sys::fuzz_target;
use twinloop_description::{lint, urdf};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(robot) = urdf::from_str(text) {
        let _ = lint::lint(&robot);
        let _ = urdf::from_str(&urdf::to_string(&robot));
        let _ = twinloop_dynamics::Model::from_description(&robot);
    }
});
