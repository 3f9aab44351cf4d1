//! PLY meshes: parsing and validation of any bytes return, never panic.
#![no_main]

use std::path::Path;

use epsm_scene::import::{ply, validate};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let file = Path::new("fuzz.ply");
    if let Ok(mesh) = ply::parse(data, file) {
        let _ = validate(&mesh, file);
    }
});
