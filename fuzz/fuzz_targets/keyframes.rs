//! Keyframe extraction and the tween itself: morph meshes and their tracks found, then the
//! frames of small meshes computed by each method (weld, gradients, solve, normals), every
//! frame finite.
#![no_main]

use inbetween::gltf::{Access, Document};
use inbetween::tween::{find_morph_meshes, track_frames_welded, KeyOptions, KeySource, Method, Timing, TweenOptions};
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Ok(doc) = Document::from_bytes(Path::new("fuzz/in.glb"), data, &Access::default()) else {
        return;
    };
    for source in [KeySource::Auto, KeySource::Targets] {
        let opts = KeyOptions {
            source,
            animation: None,
        };
        let Ok(meshes) = find_morph_meshes(&doc, &opts) else {
            continue;
        };
        for m in &meshes {
            if m.vertex_count() > 5000 {
                continue;
            }
            for t in m.tracks.iter().filter(|t| t.times.len() <= 32) {
                for method in [Method::Spline, Method::Seed, Method::Linear] {
                    // Inputs with a NaN or infinite value are refused when read: what is
                    // accepted must give finite frames (keys at one time once gave NaN).
                    if let Ok((_, frames)) = track_frames_welded(m, t, &TweenOptions::new(method, Timing::Tweens(1))) {
                        assert!(frames.iter().flatten().all(|p| p.is_finite()), "{method:?}: a frame is not finite");
                    }
                }
            }
        }
    }
});
