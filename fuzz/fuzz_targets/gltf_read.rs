//! The glTF/GLB reader: container, JSON, structure, buffers, and every accessor decoded; then
//! the output's start (`gltf::begin`: the views copied, skin weights and rotation keys mended)
//! and the preview's posing of the first clip (nodes sampled, meshes skinned).
#![no_main]

use inbetween::gltf::{begin, Access, Container, Document};
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Ok(doc) = Document::from_bytes(Path::new("fuzz/in.glb"), data, &Access::default()) else {
        return;
    };
    let accessors = doc.json["accessors"].as_array().map_or(0, Vec::len);
    for i in 0..accessors.min(64) {
        let _ = doc.read_f64(i);
        let _ = doc.read_indices(i);
    }
    let _ = begin(&doc, Container::Glb, Path::new("fuzz/out.glb"));
    let _ = inbetween::preview::posed(&doc, "0", &[0.0, 0.5]);
});
