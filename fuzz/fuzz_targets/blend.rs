//! The blend path on a glTF character: rig and clips read, skeleton found, the first two clips
//! blended (cycles, time warp, alignment, clean-up, figures); and the same as two files, the
//! second clip carried onto the first file's nodes by name.
#![no_main]

use inbetween::blend::{blend_clips, blend_files, BlendOptions};
use inbetween::gltf::{Access, Document};
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Ok(doc) = Document::from_bytes(Path::new("fuzz/in.glb"), data, &Access::default()) else {
        return;
    };
    let clips = ["0".to_string(), "1".to_string()];
    let _ = blend_clips(&doc, &clips, &BlendOptions::new(0.5));
    let _ = blend_files([&doc, &doc], Some(&clips), &BlendOptions::new(0.5));
});
