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
//! others have, it refers to one shared accessor of zeros of that attribute's type. Attributes
//! not solved (TEXCOORD_n, COLOR_n) play by the authored weights: zeros in a frame's own target
//! (rig), the authored deltas blended at the frame (frames). Accessors the new targets and
//! samplers replaced are dropped when nothing else refers to them.

use super::base;
use super::compact::{compact, sparse_pays, CompactFigures, CompactOptions, Compacted, Stored};
use super::frames::{MeshFrames, PrimitiveFrames, TrackFrames};
use super::keys::{MorphMesh, OtherDeltas, Primitive, TrackOrigin};
use super::options::Layout;
use super::schedule::FrameAt;
use crate::gltf::{
    self, arr, close_keys, compact as drop_unused, drop_channels, row_components, Document, Output,
    Storage, ELEMENT_MARK, FILTER_GROUP, FILTER_MARK,
};
use anyhow::{bail, Result};
use glam::DVec3;
use rayon::prelude::*;
use serde_json::{json, Map, Value};
use std::collections::{BTreeMap, BTreeSet};

/// Accessors replaced by the new targets and samplers (dropped if nothing else refers to them),
/// and the animation `inbetween` made for tracks built from targets.
#[derive(Default)]
struct Edits {
    replaced: BTreeSet<usize>,
    samplers: Vec<Value>,
    channels: Vec<Value>,
    /// Key times written so far, with their accessor: a track whose times are the first keys
    /// of another's (clips at one rate from 0) reads them from the same view.
    times: Vec<(Vec<f32>, usize)>,
    /// How many channels read each sampler of an animation, as the edits leave them (counted
    /// once per animation: a clip of 10,000 channels was looked through for each track).
    readers: std::collections::HashMap<usize, Vec<usize>>,
}

/// One processed mesh as it is written: its frames, what was read of it, the layout, and its
/// compacted form (`--compact` and its parts).
struct Written<'a> {
    frames: &'a MeshFrames,
    mesh: &'a MorphMesh,
    layout: Layout,
    compact: Option<Compacted>,
}

/// Where a frame's pose comes from in the output.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Played {
    /// Key k of its track: the authored weights.
    Key(usize),
    /// Its own target (index among the new targets), with the authored weights blended at
    /// `t` between keys a and b (rig layout).
    Target(usize),
    /// The basis targets, at the weights of frame g of the mesh (with the authored weights
    /// blended as for `Target`, rig layout).
    Basis(usize),
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
                    .enumerate()
                    .map(|(i, f)| match (self.layout, f.key(), &self.compact) {
                        (Layout::Rig, Some(k), _) => Played::Key(k),
                        (_, _, Some(_)) => Played::Basis(track.first + i),
                        _ => {
                            next += 1;
                            Played::Target(next - 1)
                        }
                    })
                    .collect()
            })
            .collect();
        let new = self.compact.as_ref().map_or(next, |c| c.targets.len());
        (plays, new)
    }

    /// The authored weights of every frame of the mesh, in order (empty in the frames layout).
    fn authored_rows(&self) -> Vec<Vec<f64>> {
        self.frames
            .tracks
            .iter()
            .flat_map(|t| t.frames.iter().map(move |f| self.authored(t, f)))
            .collect()
    }

    /// The authored weights a frame of `track` is blended from (linear between its keys,
    /// held at the ends; none in the frames layout).
    fn authored(&self, track: &TrackFrames, f: &FrameAt) -> Vec<f64> {
        if self.layout == Layout::Frames {
            return Vec::new();
        }
        blended(track, f)
    }

    /// The weights of every target (kept, then new) for each frame of `track`.
    fn weights(&self, track: &TrackFrames, plays: &[Played], new: usize) -> Vec<f32> {
        let width = self.kept() + new;
        let mut out = Vec::with_capacity(plays.len() * width);
        for (f, play) in track.frames.iter().zip(plays) {
            let mut w = vec![0.0f32; width];
            match *play {
                Played::Key(k) => {
                    for (o, x) in w.iter_mut().zip(&track.track.weights[k]) {
                        *o = *x as f32;
                    }
                }
                Played::Target(i) => {
                    for (o, x) in w.iter_mut().zip(self.authored(track, f)) {
                        *o = x as f32;
                    }
                    w[self.kept() + i] = 1.0;
                }
                Played::Basis(g) => {
                    let c = self.compact.as_ref().expect("compacted");
                    for (o, x) in w.iter_mut().zip(&c.authored_weights[g]) {
                        *o = *x as f32;
                    }
                    w[self.kept()..].copy_from_slice(&c.weights[g]);
                }
            }
            out.extend(w);
        }
        out
    }
}

/// The most morph targets one primitive got: (mesh name, primitive index, targets).
pub type MostTargets = Option<(String, usize, usize)>;

/// What writing the frames did: the primitive with the most targets, and each compacted
/// mesh's figures.
#[derive(Clone, Debug, Default)]
pub struct Applied {
    pub most_targets: MostTargets,
    pub compacted: Vec<(String, CompactFigures)>,
}

/// Write the frames of each processed mesh (`frames[i]` computed from `meshes[i]`) into `out`
/// as morph targets and weights animation, in `layout`, compacted as `compact` asks.
pub fn apply_frames(
    out: &mut Output,
    doc: &Document,
    frames: &[MeshFrames],
    meshes: &[MorphMesh],
    layout: Layout,
    compact_opts: Option<&CompactOptions>,
    loops: bool,
) -> Result<Applied> {
    let mut applied = Applied::default();
    if let (Layout::Frames, Some(_)) = (layout, compact_opts) {
        let other = meshes.iter().find_map(|m| {
            let o = m.primitives.iter().flat_map(|p| &p.target_other).next()?;
            Some((&m.name, &o.name))
        });
        if let Some((mesh, name)) = other {
            bail!(doc.err(format!(
                "mesh {mesh:?} has {name} morph deltas, which --compact cannot keep in the frames layout (the rig layout keeps them)"
            )));
        }
    }
    // Set first: the writers below decide sparse accessors by it, as the compaction did.
    out.meshopt = compact_opts.is_some_and(|o| o.meshopt);
    let shifts = ClipShifts::of(frames, loops);
    let carriers = gltf::mesh_nodes(&out.json);
    // Whose accessors the reorder stage may renumber (with meshopt): counted once.
    let mut refs = out.meshopt.then(|| gltf::AccessorRefs::of(&mut out.json));
    let mut edits = Edits::default();
    let mut dropped: Vec<(usize, usize)> = Vec::new();
    for (m, mesh) in frames.iter().zip(meshes) {
        let mut w = Written {
            frames: m,
            mesh,
            layout,
            compact: None,
        };
        if let Some(opts) = compact_opts {
            let (plays, _) = w.plays();
            let own: Vec<usize> = plays
                .iter()
                .flatten()
                .enumerate()
                .filter(|(_, p)| matches!(p, Played::Target(_)))
                .map(|(g, _)| g)
                .collect();
            let restorable = base::restorable(&out.json, m);
            let c = compact(m, mesh, w.authored_rows(), own, &restorable, opts)
                .map_err(|e| doc.err(format!("{e:#}")))?;
            applied
                .compacted
                .push((mesh.name.clone(), c.figures.clone()));
            w.compact = Some(c);
        }
        let (plays, new) = w.plays();
        let count = w.kept() + new;
        if applied.most_targets.as_ref().is_none_or(|m| m.2 < count) {
            let first = m.primitives.first().map_or(0, |p| p.index);
            applied.most_targets = Some((mesh.name.clone(), first, count));
        }
        if let Some(refs) = &mut refs {
            refs.leave_out(&mut out.json, m.mesh);
        }
        set_targets(out, &w, &plays, &mut edits.replaced);
        if let (Some(c), Some(opts @ CompactOptions { meshopt: true, .. }), Some(refs)) =
            (&w.compact, compact_opts, &mut refs)
        {
            base::reencode(out, doc, m, &c.base, opts.tolerance, &mut edits.replaced)?;
            for p in &m.primitives {
                gltf::reorder(out, m.mesh, p.index, refs, &mut edits.replaced);
            }
        }
        if let Some(refs) = &mut refs {
            refs.put_back(&mut out.json, m.mesh);
        }
        name_targets(out, &w, &plays, new, &shifts, &carriers[m.mesh]);
        let outputs = push_weights(out, &w, &plays, new);
        for (track, output) in m.tracks.iter().zip(outputs) {
            animate_track(out, track, output, shifts.of_track(track), &mut edits);
        }
        match layout {
            Layout::Frames => dropped.extend(m.dropped_channels.iter().copied()),
            Layout::Rig => pad_other_channels(out, doc, &w, new, &mut edits)?,
        }
    }
    shifts.move_other_channels(out, doc, &mut edits)?;
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
    drop_unused(out, &edits.replaced);
    Ok(applied)
}

/// What a clip's other channels (a node's transforms, another mesh's weights) take from its
/// weights' frames, so the clip plays as one:
/// * the seconds its written key times move later: glTF key times cannot be negative, so a
///   clip whose frames would start before 0 s (motion extended before its first key, or a file
///   whose keys start before 0) moves as a whole; other clips keep their times;
/// * with `--loop`, the end its weights' loop closes at: each other channel ending before it
///   gets its first key again there, so the whole clip loops (a node moved by the clip held
///   its last key over the appended spacing, then jumped).
struct ClipShifts {
    /// By animation index; `None`: the new animation of keys made from targets.
    by_clip: BTreeMap<Option<usize>, f64>,
    /// By animation index: the time (before the shift) of the clip's last frame, when `--loop`
    /// closed its weights.
    loop_ends: BTreeMap<usize, f64>,
}

impl ClipShifts {
    fn of(frames: &[MeshFrames], loops: bool) -> Self {
        let mut by_clip: BTreeMap<Option<usize>, f64> = BTreeMap::new();
        let mut loop_ends: BTreeMap<usize, f64> = BTreeMap::new();
        for track in frames.iter().flat_map(|m| &m.tracks) {
            let (Some(first), Some(last)) = (track.frames.first(), track.frames.last()) else {
                continue;
            };
            let shift = by_clip.entry(Self::clip(track)).or_insert(0.0);
            *shift = shift.max(-first.time);
            if let (true, Some(a)) = (loops, Self::clip(track)) {
                let end = loop_ends.entry(a).or_insert(f64::NEG_INFINITY);
                *end = end.max(last.time);
            }
        }
        Self { by_clip, loop_ends }
    }

    fn clip(track: &TrackFrames) -> Option<usize> {
        match track.track.origin {
            TrackOrigin::Animation { animation, .. } => Some(animation),
            TrackOrigin::Targets { .. } => None,
        }
    }

    fn of_track(&self, track: &TrackFrames) -> f64 {
        self.by_clip.get(&Self::clip(track)).copied().unwrap_or(0.0)
    }

    /// The samplers of a moved or looped clip that no track rewrote: their key times moved
    /// with it, and a loop closed at its end (into accessors of their own: an accessor may be
    /// shared with other clips).
    fn move_other_channels(
        &self,
        out: &mut Output,
        doc: &Document,
        edits: &mut Edits,
    ) -> Result<()> {
        let file_accessors = arr(&doc.json, "accessors").len();
        for (&clip, &shift) in &self.by_clip {
            let Some(a) = clip else {
                continue;
            };
            let end = self.loop_ends.get(&a).copied();
            if shift <= 0.0 && end.is_none() {
                continue;
            }
            for s in 0..arr(&out.json["animations"][a], "samplers").len() {
                let sampler = &out.json["animations"][a]["samplers"][s];
                let (Some(input), Some(output)) =
                    (sampler["input"].as_u64(), sampler["output"].as_u64())
                else {
                    continue;
                };
                let cubic = sampler["interpolation"].as_str() == Some("CUBICSPLINE");
                let (input, output) = (input as usize, output as usize);
                let written = edits.times.iter().any(|(_, acc)| *acc == input);
                if written || input >= file_accessors || output >= file_accessors {
                    continue;
                }
                let (mut times, _) = doc.read_f64(input)?;
                // The loop closed: the first key again at the clip's end.
                if let Some(end) = end.filter(|&e| times.last().is_some_and(|&t| t < e)) {
                    let (mut values, width) = doc.read_f64(output)?;
                    close_keys(&mut times, &mut values, cubic, end);
                    let values: Vec<f32> = values.iter().map(|&v| v as f32).collect();
                    let ty = doc.json["accessors"][output]["type"]
                        .as_str()
                        .unwrap_or("SCALAR");
                    let acc = out.push_f32(&values, ty, width, false, None);
                    edits.replaced.insert(output);
                    out.json["animations"][a]["samplers"][s]["output"] = json!(acc);
                }
                let moved: Vec<f32> = times.iter().map(|t| (t + shift) as f32).collect();
                let moved = key_times(out, &moved, &mut edits.times);
                edits.replaced.insert(input);
                out.json["animations"][a]["samplers"][s]["input"] = json!(moved);
            }
        }
        Ok(())
    }
}

/// Each frame's value of one attribute as its new target stores it: its delta from the base
/// (`deltas`), less the authored targets' deltas blended by its `weights`.
fn corrections(
    deltas: &[&[[f32; 3]]],
    authored: &[Option<&Vec<DVec3>>],
    weights: &[&[f64]],
) -> Vec<Vec<f32>> {
    let n = deltas.first().map_or(0, |d| d.len());
    let mut out = vec![vec![0.0f32; 3 * n]; deltas.len()];
    // A few vertices at a time, target after target, every frame of the batch: each value takes
    // the targets in the same order as one vertex at a time would (the same bits), and each
    // target is read once a batch, as one run (a vertex and a frame at a time read 300 targets'
    // deltas side by side: a 300-shape face rig's 200 frames took 12 s).
    // Each tile's part of every frame's values, written in place.
    let mut tiles: Vec<Vec<&mut [f32]>> = (0..n.div_ceil(CHUNK)).map(|_| Vec::new()).collect();
    for o in out.iter_mut() {
        for (tile, part) in tiles.iter_mut().zip(o.chunks_mut(3 * CHUNK)) {
            tile.push(part);
        }
    }
    tiles.into_par_iter().enumerate().for_each(|(k, parts)| {
        let (v0, v1) = (k * CHUNK, ((k + 1) * CHUNK).min(n));
        let mut x: Vec<Vec<DVec3>> = (deltas.iter())
            .map(|d| {
                d[v0..v1]
                    .iter()
                    .map(|d| DVec3::from(d.map(f64::from)))
                    .collect()
            })
            .collect();
        for (i, t) in authored.iter().enumerate() {
            let Some(t) = t else { continue };
            let t = t.get(v0..).unwrap_or_default();
            for (x, w) in x.iter_mut().zip(weights) {
                let w = w.get(i).copied().unwrap_or(0.0);
                if w != 0.0 {
                    for (x, d) in x.iter_mut().zip(t) {
                        *x -= w * *d;
                    }
                }
            }
        }
        for (part, x) in parts.into_iter().zip(&x) {
            for (o, x) in part.chunks_exact_mut(3).zip(x) {
                o.copy_from_slice(&x.as_vec3().to_array());
            }
        }
    });
    out
}

/// Vertices a parallel task corrects at once (24 bytes each a frame: a few KB, in the nearest
/// caches).
const CHUNK: usize = 256;

/// Frames corrected together (see [`corrections`]): as many as keep a batch's values of one
/// attribute within [`BATCH_BYTES`], at most 16.
fn batch_frames(vertices: usize) -> usize {
    (BATCH_BYTES / (12 * vertices).max(1)).clamp(1, 16)
}

/// Bytes a batch of corrected frames holds per attribute.
const BATCH_BYTES: usize = 64 << 20;

/// The new targets of one primitive: one per frame played by its own target.
fn new_targets(
    out: &mut Output,
    w: &Written,
    p: &PrimitiveFrames,
    read: &Primitive,
    plays: &[Vec<Played>],
) -> Vec<Map<String, Value>> {
    let mut targets = Vec::new();
    if let Some(c) = &w.compact {
        let prim = w
            .frames
            .primitives
            .iter()
            .position(|x| x.index == p.index)
            .unwrap_or(0);
        for t in &c.targets {
            let mut m = Map::new();
            let mut put = |name: &str, s: &Stored, bounds: bool| {
                m.insert(
                    name.into(),
                    json!(out.push_morph(&s.values, s.storage, s.sparse, bounds)),
                );
            };
            put("POSITION", &t.position[prim], true);
            if let Some(n) = &t.normal {
                put("NORMAL", &n[prim], false);
            }
            if let Some(tg) = &t.tangent {
                put("TANGENT", &tg[prim], false);
            }
            targets.push(m);
        }
        return targets;
    }
    let m = w.frames;
    for (track, plays) in m.tracks.iter().zip(plays) {
        let own: Vec<(usize, &FrameAt)> = (track.frames.iter().enumerate())
            .zip(plays)
            .filter(|(_, play)| matches!(play, Played::Target(_)))
            .map(|((i, f), _)| (i, f))
            .collect();
        for batch in own.chunks(batch_frames(read.base.len())) {
            let weights: Vec<Vec<f64>> = batch.iter().map(|(_, f)| w.authored(track, f)).collect();
            let weights: Vec<&[f64]> = weights.iter().map(|w| &w[..]).collect();
            let of = |values: &[Vec<[f32; 3]>], authored: Vec<Option<&Vec<DVec3>>>| {
                let deltas: Vec<&[[f32; 3]]> = (batch.iter())
                    .map(|(i, _)| &values[track.first + i][..])
                    .collect();
                corrections(&deltas, &authored, &weights)
            };
            let mut positions = of(&p.positions, read.target_pos.iter().map(Some).collect());
            let mut normals = (p.normals.as_ref())
                .map(|n| of(n, read.target_nrm.iter().map(Option::as_ref).collect()));
            let mut tangents = (p.tangents.as_ref())
                .map(|t| of(t, read.target_tan.iter().map(Option::as_ref).collect()));
            for (b, (_, f)) in batch.iter().enumerate() {
                let mut t = Map::new();
                let mut put = |name: &str, v: &mut Vec<f32>, bounds: bool| {
                    let v = std::mem::take(v);
                    t.insert(
                        name.into(),
                        json!(out.push_f32(&v, "VEC3", 3, bounds, Some(34962))),
                    );
                };
                put("POSITION", &mut positions[b], true);
                if let Some(n) = &mut normals {
                    put("NORMAL", &mut n[b], false);
                }
                if let Some(tg) = &mut tangents {
                    put("TANGENT", &mut tg[b], false);
                }
                // Attributes not solved: in the frames layout no authored target is left to blend
                // them, so the frame's target holds their blend; in the rig layout the authored
                // targets play them and the new target holds zeros (set_targets).
                if w.layout == Layout::Frames {
                    let weights = blended(track, f);
                    for o in &read.target_other {
                        let v = blend_other(o, &weights, read.base.len());
                        let ty = vec_type(o.components);
                        t.insert(
                            o.name.clone(),
                            json!(out.push_f32(&v, ty, o.components, false, Some(34962))),
                        );
                    }
                }
                targets.push(t);
            }
        }
    }
    targets
}

/// The authored weights at a frame of `track`: linear between its keys, or on a CUBICSPLINE
/// clip's cubic through their tangents; held at the ends.
fn blended(frames: &TrackFrames, f: &FrameAt) -> Vec<f64> {
    let track = &frames.track;
    let (ka, kb) = (f.key_a, f.key_b);
    let (a, b) = (&track.weights[ka], &track.weights[kb]);
    let t = f.t.clamp(0.0, 1.0);
    match &track.eases {
        Some(eases) if track.eased(ka, kb) => {
            let h = track.times[kb] - track.times[ka];
            let c = super::spline::hermite(t);
            let (out_a, in_b) = (&eases[ka][1], &eases[kb][0]);
            (a.iter().zip(b).zip(out_a.iter().zip(in_b)))
                .map(|((x, y), (ma, mb))| c[0] * x + c[1] * h * ma + c[2] * y + c[3] * h * mb)
                .collect()
        }
        _ => a.iter().zip(b).map(|(x, y)| x + (y - x) * t).collect(),
    }
}

/// The blend of an unsolved attribute's authored deltas by `weights`, per vertex.
fn blend_other(o: &OtherDeltas, weights: &[f64], vertices: usize) -> Vec<f32> {
    let mut v = vec![0.0f64; o.components * vertices];
    for (w, d) in weights.iter().zip(&o.deltas) {
        if let (true, Some(d)) = (*w != 0.0, d) {
            for (x, d) in v.iter_mut().zip(d) {
                *x += *w * *d as f64;
            }
        }
    }
    v.into_iter().map(|x| x as f32).collect()
}

/// The accessor type of `n` components (2, 3 or 4).
fn vec_type(n: usize) -> &'static str {
    match n {
        2 => "VEC2",
        4 => "VEC4",
        _ => "VEC3",
    }
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
    // Primitives drawing one vertex buffer (the same POSITION and target accessors, as three.js
    // and Babylon.js export a mesh's material groups) whose frames came out the same share the
    // first one's targets: (its vertex data, its frames, its targets as written).
    let mut written: Vec<(Value, &PrimitiveFrames, Value)> = Vec::new();
    for (p, read) in m.primitives.iter().zip(&w.mesh.primitives) {
        let prim = &out.json["meshes"][m.mesh]["primitives"][p.index];
        let data = json!([prim["attributes"], prim["targets"]]);
        if let Some((_, _, targets)) = written
            .iter()
            .find(|(d, f, _)| *d == data && same_frames(f, p))
        {
            out.json["meshes"][m.mesh]["primitives"][p.index]["targets"] = targets.clone();
            continue;
        }
        let new = new_targets(out, w, p, read, plays);
        let prim = &out.json["meshes"][m.mesh]["primitives"][p.index];
        let old: Vec<Map<String, Value>> = arr(prim, "targets")
            .iter()
            .filter_map(|t| t.as_object().cloned())
            .collect();
        let mut targets: Vec<Map<String, Value>> = match w.layout {
            Layout::Rig => reencode_authored(out, w, read, old, replaced),
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
        // Each attribute with the type its targets have (VEC2 for TEXCOORD_n, VEC3 or VEC4
        // for COLOR_n, VEC3 for the rest).
        let mut names: BTreeMap<String, usize> = BTreeMap::new();
        for (name, a) in targets.iter().flatten() {
            let ty = a
                .as_u64()
                .and_then(|a| out.json["accessors"][a as usize]["type"].as_str());
            let c = match ty {
                Some("VEC2") => 2,
                Some("VEC4") => 4,
                _ => 3,
            };
            names.entry(name.clone()).or_insert(c);
        }
        // One accessor of zeros per type serves every target that lacks an attribute the
        // others have.
        let mut zeros: BTreeMap<usize, usize> = BTreeMap::new();
        for t in &mut targets {
            for (name, &c) in &names {
                if !t.contains_key(name) {
                    let acc = *zeros.entry(c).or_insert_with(|| {
                        let z = vec![0.0f32; c * read.base.len()];
                        out.push_f32(&z, vec_type(c), c, true, Some(34962))
                    });
                    t.insert(name.clone(), json!(acc));
                }
            }
        }
        let targets: Vec<Value> = targets.into_iter().map(Value::Object).collect();
        out.json["meshes"][m.mesh]["primitives"][p.index]["targets"] = Value::Array(targets);
        let targets = out.json["meshes"][m.mesh]["primitives"][p.index]["targets"].clone();
        written.push((data, p, targets));
    }
}

/// Whether two primitives' frames hold the same values.
fn same_frames(a: &PrimitiveFrames, b: &PrimitiveFrames) -> bool {
    a.positions == b.positions && a.normals == b.normals && a.tangents == b.tangents
}

/// The authored targets of a primitive, stored again as the compaction chose (through the
/// EXPONENTIAL filter, and sparse where that pays) when they are plain float accessors; as
/// they are otherwise. Deltas the input lacks ([`super::target_normals`]: the normals of
/// position-only targets) are stored as the compaction chose, or as f32 (sparse where that
/// pays) without one.
fn reencode_authored(
    out: &mut Output,
    w: &Written,
    read: &Primitive,
    old: Vec<Map<String, Value>>,
    replaced: &mut BTreeSet<usize>,
) -> Vec<Map<String, Value>> {
    let compacted = w
        .compact
        .as_ref()
        .and_then(|c| Some((c.authored?, c.sparse)));
    // Attribute by attribute, so that each attribute's targets share one filtered view (the
    // compaction measured them so): the dense ones first, then the sparse ones, so that nothing
    // comes between the dense ones.
    let mut targets = old;
    for (name, bounds) in [("POSITION", true), ("NORMAL", false), ("TANGENT", false)] {
        let (storage, sparse) = match compacted {
            Some((storage, sparse)) => (storage.of(name), sparse),
            None => (Storage::Float { exp_bits: None }, true),
        };
        // (target, its values, sparse), each decided once.
        let mut chosen: Vec<(usize, Vec<f32>, bool)> = Vec::new();
        for (i, t) in targets.iter().enumerate() {
            let values = match name {
                "POSITION" => Some(&read.target_pos[i]),
                "NORMAL" => read.target_nrm[i].as_ref(),
                _ => read.target_tan[i].as_ref(),
            };
            let Some(values) = values else {
                continue;
            };
            match t.get(name).and_then(Value::as_u64) {
                Some(a) if compacted.is_some() && base::plain(&out.json, Some(a)) => {
                    replaced.insert(a as usize);
                }
                Some(_) => continue,
                None => {}
            }
            let flat: Vec<f32> = values.iter().flat_map(|d| d.as_vec3().to_array()).collect();
            let sparse = sparse && sparse_pays(&flat, storage, out.meshopt);
            chosen.push((i, flat, sparse));
        }
        chosen.sort_by_key(|c| c.2);
        for (i, flat, sparse) in chosen {
            let new = out.push_morph(&flat, storage, sparse, bounds);
            if let Some(view) = out.json["accessors"][new]["bufferView"].as_u64() {
                out.bin.views[view as usize][FILTER_GROUP] =
                    json!(format!("authored {} {} {name}", w.mesh.mesh, read.index));
            }
            targets[i].insert(name.into(), json!(new));
        }
    }
    targets
}

/// The mesh's default weights (and the overrides of its nodes, `carriers`) padded for the new
/// targets (frame 0 in the frames layout), and the targets' names in `extras.targetNames`: the
/// authored names kept, each new target named after its frame (`f0007_t0.2917`: frame 7 at
/// 0.2917 s) or, for a compaction's, its place among the basis targets (`basis0003`).
fn name_targets(
    out: &mut Output,
    w: &Written,
    plays: &[Vec<Played>],
    new: usize,
    shifts: &ClipShifts,
    carriers: &[usize],
) {
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
    let mut names = gltf::target_names(mesh_json);
    names.resize_with(kept, String::new);
    for (i, name) in names.iter_mut().enumerate() {
        if name.is_empty() {
            *name = format!("target_{i}");
        }
    }
    for (track, plays) in m.tracks.iter().zip(plays) {
        let shift = shifts.of_track(track);
        for (i, (f, play)) in track.frames.iter().zip(plays).enumerate() {
            if matches!(play, Played::Target(_)) {
                names.push(format!("f{:04}_t{:.4}", track.first + i, f.time + shift));
            }
        }
    }
    // A compaction's basis targets play no frame of their own: `basis0000`, ... (a name for
    // every target: cgltf's validation, and so gltfpack, refuses a mesh whose
    // targetNames are fewer than its targets).
    if w.compact.is_some() {
        names.extend((0..new).map(|k| format!("basis{k:04}")));
    }
    debug_assert_eq!(names.len(), kept + new);
    let mesh = &mut out.json["meshes"][m.mesh];
    mesh["weights"] = weights;
    if !mesh.get("extras").is_some_and(Value::is_object) {
        mesh["extras"] = json!({});
    }
    mesh["extras"]["targetNames"] = json!(names);
    // A primitive that names the targets too (assimp's exporter, VRM 0) names the new ones.
    for p in mesh["primitives"].as_array_mut().into_iter().flatten() {
        if p["extras"].get("targetNames").is_some() {
            p["extras"]["targetNames"] = json!(names);
        }
    }
    for &i in carriers {
        let n = &mut out.json["nodes"][i];
        if n.get("weights").is_some() {
            n["weights"] = pad(n);
        }
    }
}

/// The weights of every track of the mesh (one key per frame), in one view: one accessor per
/// track. With meshopt the codec takes a key's row of weights as one element, and the filter
/// (where the compaction chose one) gives each target one exponent over the view, as the
/// compaction measured it.
fn push_weights(out: &mut Output, w: &Written, plays: &[Vec<Played>], new: usize) -> Vec<usize> {
    let rows: Vec<Vec<f32>> = w
        .frames
        .tracks
        .iter()
        .zip(plays)
        .map(|(track, plays)| w.weights(track, plays, new))
        .collect();
    let bytes: Vec<u8> = rows
        .iter()
        .flatten()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    let view = out.bin.push_view(&bytes, None);
    if out.meshopt {
        let width = w.kept() + new;
        out.bin.views[view][ELEMENT_MARK] = json!(4 * row_components(width));
        if let Some(bits) = w.compact.as_ref().and_then(|c| c.weight_bits) {
            out.bin.views[view][FILTER_MARK] = json!(bits);
        }
    }
    let mut offset = 0;
    rows.iter()
        .map(|r| {
            let mut acc = json!({ "bufferView": view, "componentType": 5126, "count": r.len(), "type": "SCALAR" });
            if offset > 0 {
                acc["byteOffset"] = json!(offset);
            }
            offset += 4 * r.len();
            out.push_accessor(acc)
        })
        .collect()
}

/// One key per frame of `track` (weights in accessor `output`): written into the sampler the
/// keys came from, or (keys made from targets) into the new animation in `edits`.
fn animate_track(
    out: &mut Output,
    track: &TrackFrames,
    output: usize,
    shift: f64,
    edits: &mut Edits,
) {
    let times: Vec<f32> = track
        .frames
        .iter()
        .map(|f| (f.time + shift) as f32)
        .collect();
    let times = increasing_f32(times);
    let input = key_times(out, &times, &mut edits.times);
    match &track.track.origin {
        TrackOrigin::Animation {
            animation,
            sampler,
            channels,
        } => {
            // A sampler that channels of other meshes also read (each mesh its own frames and,
            // compacted, its own basis weights) stays theirs: this mesh's channels get a new one.
            let anim = &mut out.json["animations"][*animation];
            let readers = edits.readers.entry(*animation).or_insert_with(|| {
                let mut n = vec![0; arr(anim, "samplers").len()];
                for s in arr(anim, "channels")
                    .iter()
                    .filter_map(|c| c["sampler"].as_u64())
                {
                    if let Some(k) = n.get_mut(s as usize) {
                        *k += 1;
                    }
                }
                n
            });
            let mine = (channels.iter())
                .filter(|&&c| anim["channels"][c]["sampler"].as_u64() == Some(*sampler as u64))
                .count();
            let others = readers.get(*sampler).is_some_and(|&n| n > mine);
            if others {
                let samplers = anim["samplers"]
                    .as_array_mut()
                    .expect("the track's sampler");
                samplers
                    .push(json!({ "input": input, "output": output, "interpolation": "LINEAR" }));
                let new = samplers.len() - 1;
                for &c in channels {
                    anim["channels"][c]["sampler"] = json!(new);
                }
                readers[*sampler] -= mine;
                readers.resize(readers.len().max(new + 1), 0);
                readers[new] = channels.len();
                return;
            }
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

/// `times` (non-decreasing) made increasing, as glTF asks of key times: a time equal to the one
/// before it (the frames at a cut in the keys, where the pose jumps) moves one float32 step on.
fn increasing_f32(mut times: Vec<f32>) -> Vec<f32> {
    for i in 1..times.len() {
        if times[i] <= times[i - 1] {
            times[i] = times[i - 1].next_up();
        }
    }
    times
}

/// An accessor of key times `times`: one written before when it holds the same times, else a
/// new accessor (over the view of earlier times that begin with these, when there are some).
fn key_times(out: &mut Output, times: &[f32], written: &mut Vec<(Vec<f32>, usize)>) -> usize {
    let begins = |t: &[f32]| {
        t.len() >= times.len() && t.iter().zip(times).all(|(x, y)| x.to_bits() == y.to_bits())
    };
    let earlier = written.iter().find(|(t, _)| begins(t));
    let input = match earlier {
        Some((t, a)) if t.len() == times.len() => return *a,
        Some((_, a)) => {
            let mut acc = out.json["accessors"][*a].clone();
            acc["count"] = json!(times.len());
            gltf::set_bounds(&mut acc, times, 1);
            out.push_accessor(acc)
        }
        None => out.push_f32(times, "SCALAR", 1, true, None),
    };
    written.push((times.to_vec(), input));
    input
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
    // (animation, sampler) -> the sampler this mesh's channels on it play, padded.
    let mut padded: BTreeMap<(usize, usize), usize> = BTreeMap::new();
    for &(a, c) in &w.frames.dropped_channels {
        let Some(s) = out.json["animations"][a]["channels"][c]["sampler"].as_u64() else {
            continue;
        };
        let s = s as usize;
        if let Some(&own) = padded.get(&(a, s)) {
            out.json["animations"][a]["channels"][c]["sampler"] = json!(own);
            continue; // shared with a channel already padded
        }
        // The values as the file has them (another mesh may have padded or rewritten them).
        let original = &doc.json["animations"][a]["samplers"][s];
        let Some(output) = original["output"].as_u64().map(|o| o as usize) else {
            continue;
        };
        // CUBICSPLINE rows (in-tangent, value, out-tangent) are padded alike.
        let (values, _) = doc.read_f64(output)?;
        let rows = values.len() / kept.max(1);
        let mut rows_padded = Vec::with_capacity(rows * (kept + new));
        for row in values.chunks(kept.max(1)) {
            rows_padded.extend(row.iter().map(|&x| x as f32));
            rows_padded.extend(std::iter::repeat_n(0.0f32, new));
        }
        let acc = out.push_f32(&rows_padded, "SCALAR", 1, false, None);
        let current = &mut out.json["animations"][a]["samplers"][s];
        let own = if current["output"].as_u64() == Some(output as u64) {
            edits.replaced.insert(output);
            current["output"] = json!(acc);
            s
        } else {
            // Another mesh's channels read this sampler and it is theirs now: this mesh's
            // channels get one of their own, over the file's keys.
            let mut mine = original.clone();
            mine["output"] = json!(acc);
            let samplers = out.json["animations"][a]["samplers"]
                .as_array_mut()
                .expect("the channel's sampler");
            samplers.push(mine);
            samplers.len() - 1
        };
        padded.insert((a, s), own);
        out.json["animations"][a]["channels"][c]["sampler"] = json!(own);
    }
    Ok(())
}
