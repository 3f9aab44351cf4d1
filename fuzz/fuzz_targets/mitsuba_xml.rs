//! Mitsuba XML scenes: any bytes must load or fail with an error, never panic.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = epsm_scene::import::mitsuba::from_str(text, Path::new("fuzz/fuzz.xml"));
    }
});
