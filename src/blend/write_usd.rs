//! The blends as a USD point cache: the output glTF (the input with the blends appended, and
//! no other clip) made as a .glb in memory, read back and staged by [`crate::usd`] with the blends on its timeline one
//! after the other, each sampled at its own frames; the skinned meshes baked at every sample
//! ([`crate::usd`]'s `skin`), the nodes' transforms time-sampled.
//!
//! ```text
//! write_usd::write(out, &[(animation, times)], input, output, Format::Usdc, &access, &mut files)?;
//! ```

use crate::gltf::{
    self, arr, clip_name, listed, quoted_name, read_channels, Access, Document, Output,
    Path as Property,
};
use crate::output::{Format, Outputs};
use crate::usd::{self, ClipOnStage};
use anyhow::Result;
use serde_json::Value;
use std::path::Path;

/// Write `out` (the input document with the blends appended: animation `clips[k].0`, keyed at
/// times `clips[k].1` in seconds) as the USD file `output` in `format`, staged in `files`;
/// `input` names the file in what is said. Returns the lines of what the point cache does not
/// carry.
pub fn write(
    mut out: Output,
    clips: &[(usize, Vec<f64>)],
    input: &Path,
    output: &Path,
    format: Format,
    access: &Access,
    files: &mut Outputs,
) -> Result<Vec<String>> {
    // The blends alone: the source clips are not on the point cache's timeline.
    let all = out.json["animations"].take();
    let kept: Vec<Value> = (clips.iter()).map(|(a, _)| all[*a].clone()).collect();
    out.json["animations"] = Value::Array(kept);
    let bytes = gltf::glb_bytes(out, output)?;
    let doc = Document::from_bytes(input, &bytes, access)?;
    drop(bytes);
    // Time codes at the first blend's frame rate (its frames on whole codes), the blends one
    // frame apart.
    let rate = match &clips[0].1[..] {
        [first, .., last] if last > first => ((clips[0].1.len() - 1) as f64 / (last - first))
            .round()
            .max(1.0),
        _ => 30.0,
    };
    let mut offset = 0.0;
    let mut on_stage = Vec::new();
    for (k, (_, times)) in clips.iter().enumerate() {
        let start = times.first().copied().unwrap_or(0.0);
        let codes: Vec<f64> = times.iter().map(|t| offset + (t - start) * rate).collect();
        let next = codes.last().copied().unwrap_or(offset) + 1.0;
        on_stage.push(ClipOnStage {
            animation: k,
            codes,
            offset: offset - start * rate,
            loop_end: None,
        });
        offset = next;
    }
    let stem = output
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("blend");
    let stage = usd::build_stage(&doc, &[], on_stage, rate, &format!("{stem}_"))?;
    usd::write_file(&stage, format, output, &mut |_| Ok(()), files)?;
    let mut left_out = stage.look.left_out.clone();
    left_out.extend(moving_weights(&doc));
    Ok(left_out)
}

/// A line naming the meshes whose morph weights a blend changes over its frames: the point
/// cache has no frames of theirs (that is `tween`'s work), so they stand in their default pose.
fn moving_weights(doc: &Document) -> Option<String> {
    let nodes = arr(&doc.json, "nodes");
    let mut meshes = std::collections::BTreeSet::new();
    for (a, anim) in arr(&doc.json, "animations").iter().enumerate() {
        let Ok(channels) = read_channels(doc, &clip_name(anim, a), anim, nodes.len()) else {
            continue;
        };
        for c in channels.iter().filter(|c| c.path == Property::Weights) {
            let w = c.width.max(1);
            let moves = (c.values.chunks_exact(w).skip(1)).any(|v| {
                v.iter()
                    .zip(&c.values[..w])
                    .any(|(x, y)| (x - y).abs() > 1e-6)
            });
            if let (true, Some(m)) = (moves, nodes[c.node]["mesh"].as_u64()) {
                meshes.insert(quoted_name(&doc.json["meshes"][m as usize], || {
                    format!("mesh {m}")
                }));
            }
        }
    }
    if meshes.is_empty() {
        return None;
    }
    let meshes: Vec<String> = meshes.into_iter().collect();
    Some(format!(
        "the blend changes the morph weights of {}, which a point cache of its skeletal motion does not play: written with their default weights (a glTF output keeps them; `inbetween tween` writes morph frames)",
        listed(&meshes)
    ))
}
