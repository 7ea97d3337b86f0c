//! The tween frames as glTF morph animation: one morph target per output frame on each
//! processed primitive, and the tracks' samplers keyed once per frame with one-hot weights
//! (LINEAR between consecutive frames); accessors the new targets and samplers replaced are
//! dropped when nothing else refers to them.

use super::frames::{MeshFrames, TrackFrames};
use super::keys::TrackOrigin;
use crate::gltf::{arr, compact, drop_channels, Output};
use anyhow::Result;
use serde_json::{json, Map, Value};
use std::collections::BTreeSet;

fn one_hot(len: usize, at: usize) -> Vec<f32> {
    let mut v = vec![0.0; len];
    if at < len {
        v[at] = 1.0;
    }
    v
}

/// Accessors replaced by the new targets and samplers (dropped if nothing else refers to them),
/// and the animation `inbetween` made for tracks built from targets.
#[derive(Default)]
struct Edits {
    replaced: BTreeSet<usize>,
    samplers: Vec<Value>,
    channels: Vec<Value>,
}

/// Replace the targets and weight animation of each processed mesh.
pub fn apply_frames(out: &mut Output, meshes: &[MeshFrames]) -> Result<()> {
    // glTF key times cannot be negative: a motion extended before 0 s shifts every written
    // timeline by the same amount.
    let earliest = meshes
        .iter()
        .flat_map(|m| &m.tracks)
        .flat_map(|t| t.frames.first())
        .map(|f| f.time)
        .fold(0.0, f64::min);
    let shift = -earliest;
    let mut edits = Edits::default();
    let mut dropped: Vec<(usize, usize)> = Vec::new();
    for m in meshes {
        set_targets(out, m, &mut edits.replaced);
        name_frames(out, m, shift);
        for track in &m.tracks {
            animate_track(out, m, track, shift, &mut edits);
        }
        dropped.extend(m.dropped_channels.iter().copied());
    }
    drop_channels(&mut out.json, &dropped, &mut edits.replaced);
    if !edits.channels.is_empty() {
        out.push_to(
            "animations",
            json!({
                "name": "inbetween",
                "samplers": edits.samplers,
                "channels": edits.channels,
            }),
        );
    }
    compact(out, &edits.replaced);
    Ok(())
}

/// One morph target per frame on every processed primitive of `m` (POSITION, and NORMAL and
/// TANGENT deltas where the input has them); the accessors of the old targets go to `replaced`.
fn set_targets(out: &mut Output, m: &MeshFrames, replaced: &mut BTreeSet<usize>) {
    let frames = m.frame_count();
    for p in &m.primitives {
        let mut targets = Vec::with_capacity(frames);
        for f in 0..frames {
            let mut t = Map::new();
            let pos: Vec<f32> = p.positions[f].iter().flatten().copied().collect();
            t.insert(
                "POSITION".into(),
                json!(out.push_f32(&pos, "VEC3", 3, true, Some(34962))),
            );
            if let Some(n) = &p.normals {
                let d: Vec<f32> = n[f].iter().flatten().copied().collect();
                t.insert(
                    "NORMAL".into(),
                    json!(out.push_f32(&d, "VEC3", 3, false, Some(34962))),
                );
            }
            if let Some(tg) = &p.tangents {
                let d: Vec<f32> = tg[f].iter().flatten().copied().collect();
                t.insert(
                    "TANGENT".into(),
                    json!(out.push_f32(&d, "VEC3", 3, false, Some(34962))),
                );
            }
            targets.push(Value::Object(t));
        }
        let prim = &mut out.json["meshes"][m.mesh]["primitives"][p.index];
        for old in arr(prim, "targets") {
            for a in old.as_object().into_iter().flat_map(|o| o.values()) {
                if let Some(a) = a.as_u64() {
                    replaced.insert(a as usize);
                }
            }
        }
        prim["targets"] = Value::Array(targets);
    }
}

/// The mesh's default weights (and its nodes' overrides) on frame 0, and the frames' names in
/// `extras.targetNames`.
fn name_frames(out: &mut Output, m: &MeshFrames, shift: f64) {
    let frames = m.frame_count();
    let mesh = &mut out.json["meshes"][m.mesh];
    mesh["weights"] = json!(one_hot(frames, 0));
    let names: Vec<String> = m
        .tracks
        .iter()
        .flat_map(|t| {
            t.frames
                .iter()
                .enumerate()
                .map(move |(i, f)| (t.first + i, f.time + shift))
        })
        .map(|(i, time)| format!("f{i:04}_t{time:.4}"))
        .collect();
    if !mesh.get("extras").is_some_and(Value::is_object) {
        mesh["extras"] = json!({});
    }
    mesh["extras"]["targetNames"] = json!(names);
    // Nodes that override the mesh's weights.
    if let Some(nodes) = out.json.get_mut("nodes").and_then(Value::as_array_mut) {
        for n in nodes.iter_mut() {
            if n["mesh"].as_u64() == Some(m.mesh as u64) && n.get("weights").is_some() {
                n["weights"] = json!(one_hot(frames, 0));
            }
        }
    }
}

/// One key per frame of `track`, one-hot over the mesh's frames: written into the sampler the
/// keys came from, or (keys made from targets) into the new animation in `edits`.
fn animate_track(
    out: &mut Output,
    m: &MeshFrames,
    track: &TrackFrames,
    shift: f64,
    edits: &mut Edits,
) {
    let frames = m.frame_count();
    let times: Vec<f32> = track
        .frames
        .iter()
        .map(|f| (f.time + shift) as f32)
        .collect();
    let mut weights = Vec::with_capacity(times.len() * frames);
    for i in 0..times.len() {
        weights.extend(one_hot(frames, track.first + i));
    }
    let input = out.push_f32(&times, "SCALAR", 1, true, None);
    let output = out.push_f32(&weights, "SCALAR", 1, false, None);
    match &track.origin {
        TrackOrigin::Animation {
            animation, sampler, ..
        } => {
            let s = &mut out.json["animations"][*animation]["samplers"][*sampler];
            for k in ["input", "output"] {
                if let Some(a) = s[k].as_u64() {
                    edits.replaced.insert(a as usize);
                }
            }
            s["input"] = json!(input);
            s["output"] = json!(output);
            s["interpolation"] = json!("LINEAR");
        }
        TrackOrigin::Targets { nodes } => {
            if nodes.is_empty() {
                return;
            }
            let si = edits.samplers.len();
            edits
                .samplers
                .push(json!({ "input": input, "output": output, "interpolation": "LINEAR" }));
            for &n in nodes {
                edits
                    .channels
                    .push(json!({ "sampler": si, "target": { "node": n, "path": "weights" } }));
            }
        }
    }
}
