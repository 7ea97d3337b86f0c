//! Keyframe extraction and the tween itself: morph meshes and their tracks found, then the
//! frames of small meshes computed by each method (weld, gradients, solve, normals), every
//! frame finite.
#![no_main]

use inbetween::gltf::{Access, Document};
use inbetween::tween::{derive_target_normals, find_morph_meshes, track_frames_welded, KeyOptions, KeySource, Method, Timing, TweenOptions};
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
        let Ok(mut meshes) = find_morph_meshes(&doc, &opts) else {
            continue;
        };
        for m in &mut meshes {
            if m.vertex_count() > 5000 {
                continue;
            }
            // The normals a position-only target is given (the glTF rig layout) are finite.
            derive_target_normals(m);
            for p in &m.primitives {
                let given = p.target_nrm.iter().chain(&p.target_tan).flatten().flatten();
                assert!(given.clone().all(|n| n.is_finite()), "a target's normal is not finite");
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
