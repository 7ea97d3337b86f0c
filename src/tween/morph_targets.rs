//! The tween frames as glTF morph animation, in one of two layouts ([`Layout`]):
//!
//! * `rig` (default): the authored morph targets stay as they are (accessors, names, the
//!   other animations that drive them). A key is played by its authored weights; every frame
//!   between keys gets one target of its own, holding the correction from the blend of the
//!   authored targets at the frame (their weights interpolated linearly between the two keys)
//!   to the computed frame, and is played by those weights plus 1 on its own target. Keys are
//!   stored once, and a renderer interpolating linearly between samples shows the same motion
//!   as with one target per frame (weights and positions are linear in each other).
//! * `frames`: one target per frame (keys included) replaces the authored targets, played
//!   one-hot (LINEAR between consecutive frames); other weights animations of the mesh go.
//!
//! Every target of a primitive carries the same attributes: where one lacks an attribute the
//! others have, it refers to one shared accessor of zeros. Accessors the new targets and
//! samplers replaced are dropped when nothing else refers to them.

use super::frames::{MeshFrames, PrimitiveFrames, TrackFrames};
use super::keys::{MorphMesh, Primitive, TrackOrigin};
use super::options::Layout;
use super::schedule::FrameAt;
use crate::gltf::{arr, compact, drop_channels, Document, Output};
use anyhow::Result;
use glam::DVec3;
use serde_json::{json, Map, Value};
use std::collections::BTreeSet;

/// Accessors replaced by the new targets and samplers (dropped if nothing else refers to them),
/// and the animation `inbetween` made for tracks built from targets.
#[derive(Default)]
struct Edits {
    replaced: BTreeSet<usize>,
    samplers: Vec<Value>,
    channels: Vec<Value>,
}

/// One processed mesh as it is written: its frames, what was read of it, and the layout.
struct Written<'a> {
    frames: &'a MeshFrames,
    mesh: &'a MorphMesh,
    layout: Layout,
}

/// Where a frame's pose comes from in the output.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Played {
    /// Key k of its track: the authored weights.
    Key(usize),
    /// Its own target (index among the new targets), with the authored weights blended at
    /// `t` between keys a and b (rig layout).
    Target(usize),
}

impl Written<'_> {
    /// Authored targets kept in the output (none in the frames layout).
    fn kept(&self) -> usize {
        match self.layout {
            Layout::Rig => self.mesh.target_count,
            Layout::Frames => 0,
        }
    }

    /// How each frame of each track is played, and how many new targets there are.
    fn plays(&self) -> (Vec<Vec<Played>>, usize) {
        let mut next = 0;
        let plays = self
            .frames
            .tracks
            .iter()
            .map(|track| {
                track
                    .frames
                    .iter()
                    .map(|f| match (self.layout, key_of(f)) {
                        (Layout::Rig, Some(k)) => Played::Key(k),
                        _ => {
                            next += 1;
                            Played::Target(next - 1)
                        }
                    })
                    .collect()
            })
            .collect();
        (plays, next)
    }

    /// The authored weights a frame of `track` is blended from (linear between its keys,
    /// held at the ends; none in the frames layout).
    fn authored(&self, track: &TrackFrames, f: &FrameAt) -> Vec<f64> {
        if self.layout == Layout::Frames {
            return Vec::new();
        }
        let (a, b) = (&track.keys[f.key_a], &track.keys[f.key_b]);
        let t = f.t.clamp(0.0, 1.0);
        a.iter().zip(b).map(|(x, y)| x + (y - x) * t).collect()
    }

    /// The weights of every target (kept, then new) for each frame of `track`.
    fn weights(&self, track: &TrackFrames, plays: &[Played], new: usize) -> Vec<f32> {
        let width = self.kept() + new;
        let mut out = Vec::with_capacity(plays.len() * width);
        for (f, play) in track.frames.iter().zip(plays) {
            let mut w = vec![0.0f32; width];
            match *play {
                Played::Key(k) => {
                    for (o, x) in w.iter_mut().zip(&track.keys[k]) {
                        *o = *x as f32;
                    }
                }
                Played::Target(i) => {
                    for (o, x) in w.iter_mut().zip(self.authored(track, f)) {
                        *o = x as f32;
                    }
                    w[self.kept() + i] = 1.0;
                }
            }
            out.extend(w);
        }
        out
    }
}

/// The key a frame is, when it lies exactly on one.
fn key_of(f: &FrameAt) -> Option<usize> {
    if f.t == 0.0 {
        Some(f.key_a)
    } else if f.t == 1.0 {
        Some(f.key_b)
    } else {
        None
    }
}

/// The most morph targets one primitive got: (mesh name, primitive index, targets).
pub type MostTargets = Option<(String, usize, usize)>;

/// Write the frames of each processed mesh (`frames[i]` computed from `meshes[i]`) into `out`
/// as morph targets and weights animation, in `layout`; returns the primitive with the most
/// targets.
pub fn apply_frames(
    out: &mut Output,
    doc: &Document,
    frames: &[MeshFrames],
    meshes: &[MorphMesh],
    layout: Layout,
) -> Result<MostTargets> {
    let mut most: MostTargets = None;
    // glTF key times cannot be negative: a motion extended before 0 s shifts every written
    // timeline by the same amount.
    let earliest = frames
        .iter()
        .flat_map(|m| &m.tracks)
        .flat_map(|t| t.frames.first())
        .map(|f| f.time)
        .fold(0.0, f64::min);
    let shift = -earliest;
    let mut edits = Edits::default();
    let mut dropped: Vec<(usize, usize)> = Vec::new();
    for (m, mesh) in frames.iter().zip(meshes) {
        let w = Written {
            frames: m,
            mesh,
            layout,
        };
        let (plays, new) = w.plays();
        let count = w.kept() + new;
        if most.as_ref().is_none_or(|m| m.2 < count) {
            let first = m.primitives.first().map_or(0, |p| p.index);
            most = Some((mesh.name.clone(), first, count));
        }
        set_targets(out, &w, &plays, &mut edits.replaced);
        name_targets(out, &w, &plays, new, shift);
        for (track, plays) in m.tracks.iter().zip(&plays) {
            animate_track(out, &w, track, plays, new, shift, &mut edits);
        }
        match layout {
            Layout::Frames => dropped.extend(m.dropped_channels.iter().copied()),
            Layout::Rig => pad_other_channels(out, doc, &w, new, &mut edits)?,
        }
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
    Ok(most)
}

/// The frame's value of one attribute as the new target stores it: its delta from the base,
/// less the authored targets' deltas blended by `weights`.
fn correction(delta: &[[f32; 3]], authored: &[Option<&Vec<DVec3>>], weights: &[f64]) -> Vec<f32> {
    let mut out: Vec<DVec3> = delta
        .iter()
        .map(|d| DVec3::new(d[0] as f64, d[1] as f64, d[2] as f64))
        .collect();
    for (w, target) in weights.iter().zip(authored) {
        if let (true, Some(t)) = (*w != 0.0, target) {
            for (o, d) in out.iter_mut().zip(t.iter()) {
                *o -= *w * *d;
            }
        }
    }
    out.iter().flat_map(|v| v.as_vec3().to_array()).collect()
}

/// The new targets of one primitive: one per frame played by its own target.
fn new_targets(
    out: &mut Output,
    w: &Written,
    p: &PrimitiveFrames,
    read: &Primitive,
    plays: &[Vec<Played>],
) -> Vec<Map<String, Value>> {
    let mut targets = Vec::new();
    let m = w.frames;
    for (track, plays) in m.tracks.iter().zip(plays) {
        for (i, (f, play)) in track.frames.iter().zip(plays).enumerate() {
            if !matches!(play, Played::Target(_)) {
                continue;
            }
            let frame = track.first + i;
            let weights = w.authored(track, f);
            let mut t = Map::new();
            let mut put = |name: &str,
                           delta: &[[f32; 3]],
                           authored: Vec<Option<&Vec<DVec3>>>,
                           bounds: bool| {
                let v = correction(delta, &authored, &weights);
                t.insert(
                    name.into(),
                    json!(out.push_f32(&v, "VEC3", 3, bounds, Some(34962))),
                );
            };
            put(
                "POSITION",
                &p.positions[frame],
                read.target_pos.iter().map(Some).collect(),
                true,
            );
            if let Some(n) = &p.normals {
                put(
                    "NORMAL",
                    &n[frame],
                    read.target_nrm.iter().map(Option::as_ref).collect(),
                    false,
                );
            }
            if let Some(tg) = &p.tangents {
                put(
                    "TANGENT",
                    &tg[frame],
                    read.target_tan.iter().map(Option::as_ref).collect(),
                    false,
                );
            }
            targets.push(t);
        }
    }
    targets
}

/// The targets of every processed primitive of the mesh: the authored ones kept (rig) or
/// replaced (frames), then the new ones; every target given the attributes any of them has.
fn set_targets(
    out: &mut Output,
    w: &Written,
    plays: &[Vec<Played>],
    replaced: &mut BTreeSet<usize>,
) {
    let m = w.frames;
    for (p, read) in m.primitives.iter().zip(&w.mesh.primitives) {
        let new = new_targets(out, w, p, read, plays);
        let prim = &out.json["meshes"][m.mesh]["primitives"][p.index];
        let old: Vec<Map<String, Value>> = arr(prim, "targets")
            .iter()
            .filter_map(|t| t.as_object().cloned())
            .collect();
        let mut targets: Vec<Map<String, Value>> = match w.layout {
            Layout::Rig => old,
            Layout::Frames => {
                for a in old
                    .iter()
                    .flat_map(|o| o.values())
                    .filter_map(Value::as_u64)
                {
                    replaced.insert(a as usize);
                }
                Vec::new()
            }
        };
        targets.extend(new);
        let names: BTreeSet<String> = targets.iter().flat_map(|t| t.keys().cloned()).collect();
        // One accessor of zeros (on one zero-filled view) serves every target that lacks an
        // attribute the others have.
        let mut zeros: Option<usize> = None;
        for t in &mut targets {
            for name in &names {
                if !t.contains_key(name) {
                    let acc = *zeros.get_or_insert_with(|| {
                        let z = vec![0.0f32; 3 * read.base.len()];
                        out.push_f32(&z, "VEC3", 3, true, Some(34962))
                    });
                    t.insert(name.clone(), json!(acc));
                }
            }
        }
        let targets: Vec<Value> = targets.into_iter().map(Value::Object).collect();
        out.json["meshes"][m.mesh]["primitives"][p.index]["targets"] = Value::Array(targets);
    }
}

/// The mesh's default weights (and its nodes' overrides) padded for the new targets (frame 0
/// in the frames layout), and the targets' names in `extras.targetNames`: the authored names
/// kept, each new target named after its frame (`f0007_t0.2917`: frame 7 at 0.2917 s).
fn name_targets(out: &mut Output, w: &Written, plays: &[Vec<Played>], new: usize, shift: f64) {
    let m = w.frames;
    let kept = w.kept();
    let pad = |v: &Value| -> Value {
        let mut weights: Vec<f64> = arr(v, "weights")
            .iter()
            .map(|x| x.as_f64().unwrap_or(0.0))
            .collect();
        weights.resize(kept, 0.0);
        weights.resize(kept + new, 0.0);
        if w.layout == Layout::Frames && new > 0 {
            weights[0] = 1.0;
        }
        json!(weights)
    };
    let mesh_json = &out.json["meshes"][m.mesh];
    let weights = pad(mesh_json);
    let mut names: Vec<String> = arr(&mesh_json["extras"], "targetNames")
        .iter()
        .map(|n| n.as_str().unwrap_or("").to_string())
        .collect();
    names.resize_with(kept, String::new);
    for (i, name) in names.iter_mut().enumerate() {
        if name.is_empty() {
            *name = format!("target_{i}");
        }
    }
    for (track, plays) in m.tracks.iter().zip(plays) {
        for (i, (f, play)) in track.frames.iter().zip(plays).enumerate() {
            if matches!(play, Played::Target(_)) {
                names.push(format!("f{:04}_t{:.4}", track.first + i, f.time + shift));
            }
        }
    }
    let mesh = &mut out.json["meshes"][m.mesh];
    mesh["weights"] = weights;
    if !mesh.get("extras").is_some_and(Value::is_object) {
        mesh["extras"] = json!({});
    }
    mesh["extras"]["targetNames"] = json!(names);
    if let Some(nodes) = out.json.get_mut("nodes").and_then(Value::as_array_mut) {
        for n in nodes.iter_mut() {
            if n["mesh"].as_u64() == Some(m.mesh as u64) && n.get("weights").is_some() {
                n["weights"] = pad(n);
            }
        }
    }
}

/// One key per frame of `track`: written into the sampler the keys came from, or (keys made
/// from targets) into the new animation in `edits`.
fn animate_track(
    out: &mut Output,
    w: &Written,
    track: &TrackFrames,
    plays: &[Played],
    new: usize,
    shift: f64,
    edits: &mut Edits,
) {
    let times: Vec<f32> = track
        .frames
        .iter()
        .map(|f| (f.time + shift) as f32)
        .collect();
    let weights = w.weights(track, plays, new);
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

/// The weights channels of the mesh that no track rewrote (other clips, or every clip under
/// `--keys targets`): their values padded with zeros for the new targets, so they still play.
fn pad_other_channels(
    out: &mut Output,
    doc: &Document,
    w: &Written,
    new: usize,
    edits: &mut Edits,
) -> Result<()> {
    if new == 0 {
        return Ok(());
    }
    let kept = w.kept();
    let mut padded_samplers = BTreeSet::new();
    for &(a, c) in &w.frames.dropped_channels {
        let Some(s) = out.json["animations"][a]["channels"][c]["sampler"].as_u64() else {
            continue;
        };
        let sampler = &out.json["animations"][a]["samplers"][s as usize];
        let Some(output) = sampler["output"].as_u64().map(|o| o as usize) else {
            continue;
        };
        if !padded_samplers.insert((a, s)) {
            continue; // shared with a channel already padded
        }
        // CUBICSPLINE rows (in-tangent, value, out-tangent) are padded alike.
        let (values, _) = doc.read_f64(output)?;
        let rows = values.len() / kept.max(1);
        let mut padded = Vec::with_capacity(rows * (kept + new));
        for row in values.chunks(kept.max(1)) {
            padded.extend(row.iter().map(|&x| x as f32));
            padded.extend(std::iter::repeat_n(0.0f32, new));
        }
        let acc = out.push_f32(&padded, "SCALAR", 1, false, None);
        edits.replaced.insert(output);
        out.json["animations"][a]["samplers"][s as usize]["output"] = json!(acc);
    }
    Ok(())
}
