//! Fuzzing harnesses shared by the cargo-fuzz targets (`fuzz/`) and the regression test that
//! replays what they found (`tests/fuzz_found.rs`, inputs in `tests/fuzz-found/<target>/`).

use crate::gltf::{Access, Document};
use std::path::Path;

/// The `decoders` target's GLB for `data`: its first four bytes pick a meshopt buffer view
/// (mode, filter, stride, count) or a Draco primitive, the rest is the compressed stream.
pub fn decoders_glb(data: &[u8]) -> Option<Vec<u8>> {
    if data.len() < 4 {
        return None;
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
        let filter =
            ["NONE", "OCTAHEDRAL", "QUATERNION", "EXPONENTIAL", "COLOR"][head[1] as usize % 5];
        let stride = match mode {
            "ATTRIBUTES" => 4 * (1 + (head[1] as usize / 5) % 4),
            _ => 2 + 2 * (head[1] as usize % 2),
        };
        let count = if mode == "TRIANGLES" {
            3 * count
        } else {
            count
        };
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
    Some(glb)
}

/// The `decoders` target: read the GLB and decode its accessors; errors are expected, panics
/// and unbounded allocations are not.
pub fn decoders(data: &[u8]) -> Option<anyhow::Result<()>> {
    let glb = decoders_glb(data)?;
    Some(
        Document::from_bytes(Path::new("fuzz/in.glb"), &glb, &Access::default()).and_then(|doc| {
            doc.read_f64(0)?;
            doc.read_f64(1)?;
            Ok(())
        }),
    )
}

/// The `tween_write` target: the whole `tween` job on `data` to .glb, in the rig and the frames
/// layouts, with `--compact` (the frames, the rig layout's targets less the authored blend,
/// basis, quantized and sparse targets, meshopt, the writer), in `dir`. `None` where the file is
/// passed over: unreadable, no morph mesh, or more than 8 morph meshes, 2,000 vertices, 64
/// targets or 16 keys a track (a run too long to fuzz); else each run's outcome.
pub fn tween_write(data: &[u8], dir: &Path) -> Option<Vec<anyhow::Result<()>>> {
    use crate::tween::{
        find_morph_meshes, run_tween, CompactOptions, KeyOptions, KeySource, Layout, Method,
        MorphMesh, Timing, TweenJob,
    };
    let input = dir.join("in.glb");
    let doc = Document::from_bytes(&input, data, &Access::default()).ok()?;
    let opts = KeyOptions {
        source: KeySource::Auto,
        animation: None,
    };
    let meshes = find_morph_meshes(&doc, &opts).ok()?;
    let small = |m: &MorphMesh| {
        m.vertex_count() <= 2000
            && m.target_count <= 64
            && m.tracks.iter().all(|t| t.times.len() <= 16)
    };
    if meshes.is_empty() || meshes.len() > 8 || !meshes.iter().all(small) {
        return None;
    }
    std::fs::write(&input, data).ok()?;
    let runs = [Layout::Rig, Layout::Frames].map(|layout| {
        let job = TweenJob {
            input: input.clone(),
            output: dir.join("out.glb"),
            method: Method::Spline,
            keys: KeySource::Auto,
            animation: None,
            timing: Timing::Tweens(2),
            quiet: true,
            looping: None,
            extend: [0.0, 0.0],
            report: None,
            layout,
            compact: Some(CompactOptions::all()),
            access: Access::default(),
        };
        run_tween(&job).map(|_| ())
    });
    Some(runs.into())
}
