//! The decoders of compressed glTF data, fed through the reader: the input's first bytes pick
//! a meshopt buffer view (mode, filter, stride, count) or a Draco primitive, the rest is the
//! compressed stream.
#![no_main]

use inbetween::gltf::{Access, Document};
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    if data.len() < 4 {
        return;
    }
    let (head, stream) = data.split_at(4);
    let count = 1 + (u16::from_le_bytes([head[2], head[3]]) as usize % 4096);
    let json = if head[0] % 4 == 3 {
        // Draco: a primitive whose positions and indices come from the stream.
        serde_json::json!({
            "asset": { "version": "2.0" },
            "extensionsUsed": ["KHR_draco_mesh_compression"],
            "extensionsRequired": ["KHR_draco_mesh_compression"],
            "buffers": [{ "byteLength": stream.len() }],
            "bufferViews": [{ "buffer": 0, "byteLength": stream.len() }],
            "accessors": [
                { "componentType": 5126, "count": count, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 1] },
                { "componentType": 5125, "count": count, "type": "SCALAR" }
            ],
            "meshes": [{ "primitives": [{
                "attributes": { "POSITION": 0 }, "indices": 1,
                "extensions": { "KHR_draco_mesh_compression": { "bufferView": 0, "attributes": { "POSITION": head[1] % 4 } } }
            }]}]
        })
    } else {
        let mode = ["ATTRIBUTES", "TRIANGLES", "INDICES"][head[0] as usize % 4];
        let filter = ["NONE", "OCTAHEDRAL", "QUATERNION", "EXPONENTIAL", "COLOR"][head[1] as usize % 5];
        let stride = match mode {
            "ATTRIBUTES" => 4 * (1 + (head[1] as usize / 5) % 4),
            _ => 2 + 2 * (head[1] as usize % 2),
        };
        let count = if mode == "TRIANGLES" { 3 * count } else { count };
        serde_json::json!({
            "asset": { "version": "2.0" },
            "extensionsUsed": [if head[1] & 0x80 != 0 { "KHR_meshopt_compression" } else { "EXT_meshopt_compression" }],
            "buffers": [{ "byteLength": stream.len() }, { "byteLength": count * stride, "extensions": { "EXT_meshopt_compression": { "fallback": true } } }],
            "bufferViews": [{ "buffer": 1, "byteLength": count * stride, "byteStride": if mode == "ATTRIBUTES" { Some(stride) } else { None },
                "extensions": { "EXT_meshopt_compression": { "buffer": 0, "byteLength": stream.len(), "byteStride": stride, "count": count, "mode": mode, "filter": filter } } }],
            "accessors": [{ "bufferView": 0, "componentType": if stride == 2 { 5123 } else { 5126 }, "count": count, "type": "SCALAR" }]
        })
    };
    let mut js = serde_json::to_vec(&json).unwrap();
    while js.len() % 4 != 0 {
        js.push(b' ');
    }
    let mut bin = stream.to_vec();
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let total = 28 + js.len() + bin.len();
    let mut glb = b"glTF".to_vec();
    glb.extend(2u32.to_le_bytes());
    glb.extend((total as u32).to_le_bytes());
    glb.extend((js.len() as u32).to_le_bytes());
    glb.extend(b"JSON");
    glb.extend(&js);
    glb.extend((bin.len() as u32).to_le_bytes());
    glb.extend(b"BIN\0");
    glb.extend(&bin);
    if let Ok(doc) = Document::from_bytes(Path::new("fuzz/in.glb"), &glb, &Access::default()) {
        let _ = doc.read_f64(0);
        let _ = doc.read_f64(1);
    }
});
