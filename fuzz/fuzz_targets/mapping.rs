//! Arbitrary text as a servo mapping TOML: parsed into a mapping or an error with a
//! line and column inside the text, never a panic; an accepted mapping converts
//! angles both ways and builds its bus without panicking.
#![no_main]

use libfuzzer_sys::fuzz_target;
use twinloop_link::RobotMapping;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match RobotMapping::parse(text, "fuzz.toml") {
        Ok(m) => {
            for j in &m.joints {
                let raw = j.goal_raw(0.1);
                let _ = j.position(raw);
            }
            let _ = m.bus();
        }
        Err(e) => {
            let lines = text.lines().count().max(1);
            assert!(e.line <= lines + 1, "line {} of {lines}", e.line);
        }
    }
});
