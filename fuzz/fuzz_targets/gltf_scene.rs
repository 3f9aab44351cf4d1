//! glTF / GLB scenes: any bytes must load or fail with an error, never panic.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = epsm_scene::import::gltf_scene::from_slice(data, Path::new("fuzz/fuzz.gltf"));
});
