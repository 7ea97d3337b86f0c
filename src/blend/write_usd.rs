//! The blends as a USD point cache: the output glTF (the input with the blends appended, and
//! no other clip) read back and staged by [`crate::usd`] with the blends on its timeline one
//! after the other, each sampled at its own frames; the skinned meshes baked at every sample
//! ([`crate::usd`]'s `skin`), the nodes' transforms time-sampled.
//!
//! ```text
//! write_usd::write(out, &[(animation, times)], input, output, Format::Usdc, &access, &mut files)?;
//! ```

use crate::gltf::{self, Access, Container, Document, Output};
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
    let glb = files.scratch(output, ".blend.glb");
    let mut staged = Outputs::new();
    gltf::stage(out, Container::Glb, &glb, &mut staged)?;
    staged.commit()?;
    let bytes = std::fs::read(&glb).map_err(|e| anyhow::anyhow!("{}: {e}", glb.display()))?;
    let doc = Document::from_bytes(input, &bytes, access)?;
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
    Ok(stage.look.left_out.clone())
}
