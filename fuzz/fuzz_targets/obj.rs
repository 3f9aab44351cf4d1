//! OBJ meshes: parsing and validation of any bytes return, never panic.
#![no_main]

use std::path::Path;

use epsm_scene::import::{obj, validate};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let file = Path::new("fuzz.obj");
    if let Ok(mesh) = obj::parse(data, file) {
        let _ = validate(&mesh, file);
    }
});
