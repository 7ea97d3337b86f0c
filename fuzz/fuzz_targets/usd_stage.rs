//! The USD stage model of any glTF the reader accepts: nodes, meshes, materials, instancing
//! (`EXT_mesh_gpu_instancing`), cameras and lights, and the node motion of every clip, each
//! clip placed on the timeline at four time codes, and the samples of skinned meshes baked. What the stage holds is written as text that
//! usd-core must read, so every transform, instance, point and camera or light number must be
//! finite.
#![no_main]

use inbetween::gltf::{Access, Document};
use inbetween::usd::{build_stage, for_each_skin_sample, ClipOnStage, Prim};
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fn finite(p: &Prim) {
    let all = |v: &[f32]| v.iter().all(|x| x.is_finite());
    match p {
        Prim::Xform {
            matrix,
            motion,
            children,
            ..
        } => {
            assert!(
                matrix.iter().flatten().all(|x| x.is_finite()),
                "a matrix is not finite"
            );
            assert!(
                motion
                    .iter()
                    .all(|(t, m)| t.is_finite() && m.iter().all(|x| x.is_finite())),
                "motion"
            );
            children.iter().for_each(finite);
        }
        Prim::Mesh(m) => assert!(all(m.points.as_flattened()), "points"),
        Prim::Plain(p) => {
            // Cameras and lights: every number written finite (Debug prints inf and NaN).
            let text = format!("{:?}", p.attrs);
            assert!(!text.contains("inf") && !text.contains("NaN"), "{text}");
        }
        Prim::Instancer(i) => {
            let n = &i.instances;
            assert!(
                all(n.positions.as_flattened())
                    && all(n.orientations.as_flattened())
                    && all(n.scales.as_flattened()),
                "instances"
            );
            finite(&i.prototype);
            i.children.iter().for_each(finite);
        }
    }
}

fuzz_target!(|data: &[u8]| {
    let Ok(doc) = Document::from_bytes(Path::new("fuzz/in.glb"), data, &Access::default()) else {
        return;
    };
    let clips = (0..doc.json["animations"]
        .as_array()
        .map_or(0, Vec::len)
        .min(16))
        .map(|animation| ClipOnStage {
            animation,
            codes: vec![0.0, 1.0, 2.5, 30.0],
            offset: 0.0,
            loop_end: Some(1.0),
        })
        .collect();
    if let Ok(stage) = build_stage(&doc, &[], clips, 30.0, "x_") {
        stage.children.iter().for_each(finite);
        // Still skinned meshes whose joints move: their samples, baked.
        let all = |v: &[f32]| v.iter().all(|x| x.is_finite());
        let _ = for_each_skin_sample(&stage, &mut |_, _, s| {
            assert!(all(s.points.as_flattened()), "skinned points");
            assert!(all(s.extent.as_flattened()), "skinned extent");
            Ok(())
        });
    }
});
