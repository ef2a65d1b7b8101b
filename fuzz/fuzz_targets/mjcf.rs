//! Arbitrary text as MJCF: the reader (defaults, classes, compiler options, inertia
//! from geoms) returns a description or an error, never panics; what it accepts is
//! linted, written as URDF and compiled into a dynamics model without panicking.
#![no_main]

use libfuzzer_sys::fuzz_target;
use twinloop_description::{lint, mjcf, urdf};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(robot) = mjcf::from_str(text) {
        let _ = lint::lint(&robot);
        let _ = urdf::to_string(&robot);
        let _ = twinloop_dynamics::Model::from_description(&robot);
    }
});
