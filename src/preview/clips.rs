//! Posing (the scene of a file without morph keys): its meshes as the file shows them, each
//! placed by every node that instances it, skinned meshes through their skin
//! ([`Skinning`]) and rigid ones by their node's world transform, either with no clip playing
//! (the pose the joints rest in: band `as stored`) or played by each of its clips that move
//! nodes (a band per clip, labelled with its name, the frames spread over the clip from its
//! first key to its last), as a glTF viewer plays them.
//!
//! ```text
//! let (scene, clips_left, instances_left) = clips::scene(&doc, Some("Walk"), 12, false, quiet)?.unwrap(); // None: no clip moves a node
//! let (still, instances_left) = clips::still(&doc)?;
//! ```

use super::{Column, Scene, MAX_ANIMATION_FRAMES};
use crate::gltf::{
    self, arr, clip_by, clip_name, listed_or_none, local_at, mesh_nodes, node_parents,
};
use crate::gltf::{read_channels, rest_matrix, rest_trs};
use crate::gltf::{Channel, Document, Path, Skeleton, Skinning};
use crate::progress::Progress;
use crate::tween::mesh_geometry;
use anyhow::{bail, Result};
use glam::{DMat4, DVec3, Vec3};
use serde_json::Value;
use std::collections::BTreeMap;
use std::sync::Arc;

/// Frames a second of a clip's animation (`--animate`).
pub const ANIMATION_RATE: f64 = 30.0;

/// Most clips drawn (a band each): the first ones in the file; `--animation` picks any.
pub const MAX_BANDS: usize = 16;

/// Most points posed for one picture or animation (24 bytes each: 1.2 GB): a large mesh gets
/// fewer bands, then fewer animation frames (a 1M-vertex character: 4 bands of 12 frames, or
/// an animation of 50 frames).
pub const MAX_POINTS: usize = 50_000_000;

/// Each node a clip moves: its local transform at every time of the frames drawn.
type Samples = BTreeMap<usize, Vec<(f64, [f64; 16])>>;

/// World-space points of every drawn primitive at every time: `[primitive][time][vertex]`.
type Points = Vec<Vec<Vec<DVec3>>>;

/// Each drawn primitive's triangles.
type Triangles = Vec<Vec<[u32; 3]>>;

/// A clip that moves nodes: its name, animation index, time span (first to last key) and
/// the channels that move them (read once, for its span and its samples).
struct ClipSpan {
    name: String,
    animation: usize,
    span: (f64, f64),
    channels: Vec<Channel>,
}

/// The clips of `doc` that move nodes (translation, rotation or scale channels).
fn moving_clips(doc: &Document) -> Result<Vec<ClipSpan>> {
    let nodes = arr(&doc.json, "nodes").len();
    let mut out = Vec::new();
    for (a, anim) in arr(&doc.json, "animations").iter().enumerate() {
        let name = clip_name(anim, a);
        let mut channels = read_channels(doc, &name, anim, nodes)?;
        channels.retain(|c| c.path != Path::Weights);
        let times = channels.iter().flat_map(|c| c.times.iter().copied());
        let span = times.fold(None, |s: Option<(f64, f64)>, t| {
            Some(s.map_or((t, t), |(a, b)| (a.min(t), b.max(t))))
        });
        if let Some(span) = span {
            out.push(ClipSpan {
                name,
                animation: a,
                span,
                channels,
            });
        }
    }
    Ok(out)
}

/// The local transforms `clip` gives the nodes it moves, at each of `times`.
fn samples(doc: &Document, clip: &ClipSpan, times: &[f64]) -> Samples {
    let mut by_node: BTreeMap<usize, Vec<_>> = BTreeMap::new();
    for c in &clip.channels {
        by_node.entry(c.node).or_default().push(c);
    }
    by_node
        .into_iter()
        .map(|(node, chans)| {
            let rest = rest_trs(&doc.json["nodes"][node]);
            let at = |&t: &f64| (t, local_at(rest, chans.iter().copied(), t).to_cols_array());
            (node, times.iter().map(at).collect())
        })
        .collect()
}

/// Node `x`'s world transform: the `local` transforms of it and its ancestors, composed up
/// the `parents` (a cycle in a broken file ends after as many steps as there are nodes).
pub(super) fn world_of(
    mut x: usize,
    parents: &[Option<usize>],
    local: impl Fn(usize) -> DMat4,
) -> DMat4 {
    let mut m = DMat4::IDENTITY;
    for _ in 0..=parents.len() {
        m = local(x) * m;
        match parents[x] {
            Some(p) => x = p,
            None => break,
        }
    }
    m
}

/// A mesh drawn at one of the nodes that instance it (and at one of that node's
/// `EXT_mesh_gpu_instancing` instances, `instance` its transform in the node's frame), with its
/// triangle primitives (their stored points and JSON), read once for every band.
struct Drawn<'a> {
    node: usize,
    instance: DMat4,
    primitives: Arc<Primitives<'a>>,
}

/// A mesh's triangle primitives: their stored points and JSON.
type Primitives<'a> = Vec<(Vec<[f32; 3]>, &'a Value)>;

/// The meshes drawn, one for each node that instances one and each of its GPU instances (a
/// mesh on two nodes, as two eyes share one, is drawn twice; a prop gltfpack `-mi` made 40
/// instances of, 40 times), the triangles of each primitive (in the same order), and how many
/// instances were left out: those beyond half of [`MAX_POINTS`] in all (two frames' worth).
fn drawn(doc: &Document) -> Result<(Vec<Drawn<'_>>, Triangles, usize)> {
    drawn_within(doc, MAX_POINTS / 2)
}

/// [`drawn`] with at most `budget` points in all (the first instance is always drawn).
fn drawn_within(doc: &Document, budget: usize) -> Result<(Vec<Drawn<'_>>, Triangles, usize)> {
    let json = &doc.json;
    let (mut meshes, mut triangles) = (Vec::new(), Vec::new());
    let (mut points, mut left) = (0usize, 0usize);
    for (mi, carriers) in mesh_nodes(json).iter().enumerate() {
        if carriers.is_empty() {
            continue;
        }
        let prims = (arr(&json["meshes"][mi], "primitives").iter())
            .filter(|p| p["mode"].as_u64().unwrap_or(4) == 4);
        let mut primitives: Primitives = Vec::new();
        let mut tris_of_mesh = Vec::new();
        for ((base, tris), p) in mesh_geometry(doc, mi)?.into_iter().zip(prims) {
            primitives.push((base.iter().map(|p| p.as_vec3().to_array()).collect(), p));
            tris_of_mesh.push(tris);
        }
        let size: usize = primitives.iter().map(|(p, _)| p.len()).sum();
        let primitives = Arc::new(primitives);
        for &node in carriers {
            let instances = match gltf::instances(doc, node)? {
                Some(inst) => (0..inst.len()).map(|k| inst.matrix(k)).collect(),
                None => vec![DMat4::IDENTITY],
            };
            for instance in instances {
                if points + size > budget && !meshes.is_empty() {
                    left += 1;
                    continue;
                }
                points += size;
                triangles.extend(tris_of_mesh.iter().cloned());
                meshes.push(Drawn {
                    node,
                    instance,
                    primitives: Arc::clone(&primitives),
                });
            }
        }
    }
    if triangles.is_empty() {
        bail!(doc.err("has no triangle mesh to draw"));
    }
    Ok((meshes, triangles, left))
}

/// Every drawn primitive's world-space points at each of `times`, its nodes moved by
/// `samples` (empty: at rest).
fn pose(doc: &Document, meshes: &[Drawn], samples: &Samples, times: &[f64]) -> Result<Points> {
    let json = &doc.json;
    let nodes = arr(json, "nodes");
    let parents = node_parents(json);
    // A node's world transform at time t (the samples hold exactly the times drawn).
    let world = |x: usize, t: f64| -> DMat4 {
        world_of(x, &parents, |x| {
            (samples.get(&x))
                .and_then(|s| s.iter().find(|(c, _)| *c == t))
                .map_or_else(
                    || rest_matrix(&nodes[x]),
                    |(_, m)| DMat4::from_cols_array(m),
                )
        })
    };
    let samples_of = |x: usize| samples.get(&x).cloned().unwrap_or_default();
    let mut points: Points = Vec::new();
    for Drawn {
        node,
        instance,
        primitives,
    } in meshes
    {
        let node = *node;
        let skeleton = Skeleton::read(doc, node, &samples_of)?;
        for (stored, p) in primitives.iter() {
            let what = format!("node {node}'s mesh");
            let skin = match &skeleton {
                Some(s) => Skinning::read(doc, s, p, stored.len(), &what)?,
                None => None,
            };
            let at = |&t: &f64| -> Vec<DVec3> {
                let mut moved = stored.clone();
                if let Some(skin) = &skin {
                    skin.apply(t, &mut moved, None);
                }
                let w = world(node, t) * *instance;
                (moved.iter())
                    .map(|&p| w.transform_point3(Vec3::from(p).as_dvec3()))
                    .collect()
            };
            points.push(times.iter().map(at).collect());
        }
    }
    Ok(points)
}

/// The columns of `points` ([primitive][time]) at `times`.
fn columns(points: Points, times: &[f64]) -> Vec<Column> {
    let mut cols: Vec<Column> = (times.iter())
        .map(|&time| Column {
            meshes: Vec::new(),
            key: false,
            time,
        })
        .collect();
    for prim in points {
        for (col, p) in cols.iter_mut().zip(prim) {
            col.meshes.push(p);
        }
    }
    cols
}

/// Every drawn primitive's world-space points at each of `times` (seconds) as clip `clip`
/// (name or index) plays: `[primitive][time][vertex]`, the primitives in file order (each mesh
/// as each of its nodes places it), the vertices as stored.
pub fn posed(doc: &Document, clip: &str, times: &[f64]) -> Result<Points> {
    let found = find(doc, clip)?;
    let (meshes, _, _) = drawn(doc)?;
    pose(doc, &meshes, &samples(doc, &found, times), times)
}

/// The clip `name` (or index) among those that move nodes, or an error listing them.
fn find(doc: &Document, name: &str) -> Result<ClipSpan> {
    let mut clips = moving_clips(doc)?;
    let named = clips.iter().map(|c| (c.animation, c.name.as_str()));
    let picked = clip_by(name, named).map_err(|e| doc.err(e))?;
    match (clips.iter()).position(|c| Some(c.animation) == picked) {
        Some(k) => Ok(clips.swap_remove(k)),
        None => {
            let names: Vec<String> = clips.iter().map(|c| format!("{:?}", c.name)).collect();
            bail!(doc.err(format!(
                "has no clip {name:?} that moves nodes (those that do: {})",
                listed_or_none(&names)
            )))
        }
    }
}

/// The file's meshes with no clip playing: one column, band `as stored`; and how many mesh
/// instances were left out (see [`drawn`]).
pub fn still(doc: &Document) -> Result<(Scene, usize)> {
    let (meshes, triangles, left) = drawn(doc)?;
    let points = pose(doc, &meshes, &Samples::new(), &[0.0])?;
    let mut cols = columns(points, &[0.0]);
    cols[0].key = true;
    let scene = Scene {
        triangles,
        bands: vec![("as stored".into(), cols)],
    };
    Ok((scene, left))
}

/// The times a band draws over `(a, b)` (seconds, first key to last): `count` frames spread
/// evenly, first and last included, or with `animate` [`ANIMATION_RATE`] a second (at most
/// [`MAX_ANIMATION_FRAMES`]); at most `most` either way, and one (at `a`) for none.
pub(super) fn band_times((a, b): (f64, f64), count: usize, animate: bool, most: usize) -> Vec<f64> {
    let frames = match animate {
        true => (((b - a) * ANIMATION_RATE).round() as usize + 1).min(MAX_ANIMATION_FRAMES),
        false => count,
    }
    .min(most);
    match frames {
        0 | 1 => vec![a],
        _ => (0..frames)
            .map(|i| a + (b - a) * i as f64 / (frames - 1) as f64)
            .collect(),
    }
}

/// A band per clip that moves nodes (the first [`MAX_BANDS`], or only the one `only` names,
/// by name or index), each of `count` frames spread over the clip's keys, first and last
/// included (`animate`: frames [`ANIMATION_RATE`] a second, at most [`MAX_ANIMATION_FRAMES`]),
/// within [`MAX_POINTS`], how many clips were left out and how many mesh instances (see
/// [`drawn`]); `None` when no clip moves a node (and none is named).
pub fn scene(
    doc: &Document,
    only: Option<&str>,
    count: usize,
    animate: bool,
    quiet: bool,
) -> Result<Option<(Scene, usize, usize)>> {
    let mut clips = match only {
        Some(name) => vec![find(doc, name)?],
        None => moving_clips(doc)?,
    };
    if clips.is_empty() {
        return Ok(None);
    }
    let (meshes, triangles, instances_left) = drawn(doc)?;
    // Vertices posed a frame.
    let vertices: usize = (meshes.iter().flat_map(|m| m.primitives.iter()))
        .map(|(stored, _)| stored.len())
        .sum::<usize>()
        .max(1);
    let most_frames = (MAX_POINTS / vertices).max(2);
    let wanted = if animate {
        MAX_ANIMATION_FRAMES
    } else {
        count.max(1)
    };
    let bands = (most_frames / wanted).clamp(1, MAX_BANDS);
    let left = clips.len().saturating_sub(bands);
    clips.truncate(bands);
    let mut bands = Vec::new();
    let progress = Progress::new(clips.len() as u64, "preview", quiet);
    for clip in &clips {
        let times = band_times(clip.span, count, animate, most_frames);
        let points = pose(doc, &meshes, &samples(doc, clip, &times), &times)?;
        bands.push((clip.name.clone(), columns(points, &times)));
        progress.inc();
    }
    progress.finish();
    Ok(Some((Scene { triangles, bands }, left, instances_left)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Instances beyond the points budget are left out and counted, the first always drawn.
    #[test]
    fn instances_beyond_the_budget_are_left_out_and_counted() {
        let json = serde_json::json!({
            "asset": {"version": "2.0"},
            "nodes": [{"mesh": 0, "extensions": {"EXT_mesh_gpu_instancing":
                {"attributes": {"TRANSLATION": 1}}}}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
            "accessors": [
                {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"},
                {"bufferView": 1, "componentType": 5126, "count": 5, "type": "VEC3"},
            ],
            "bufferViews": [
                {"buffer": 0, "byteLength": 36},
                {"buffer": 0, "byteOffset": 36, "byteLength": 60},
            ],
            "buffers": [{"byteLength": 96,
                "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAQAAAAAAAAAAAAABAQAAAAAAAAAAAAACAQAAAAAAAAAAA"}],
        });
        let bytes = serde_json::to_vec(&json).unwrap();
        let path = std::path::Path::new("five.gltf");
        let doc = Document::from_bytes(path, &bytes, &Default::default()).unwrap();
        let counts = |budget: usize| {
            let (meshes, triangles, left) = drawn_within(&doc, budget).unwrap();
            assert_eq!(meshes.len(), triangles.len());
            (meshes.len(), left)
        };
        assert_eq!(counts(15), (5, 0));
        assert_eq!(counts(9), (3, 2));
        assert_eq!(counts(1), (1, 4));
        let (meshes, _, _) = drawn_within(&doc, 9).unwrap();
        let x: Vec<f64> = meshes.iter().map(|m| m.instance.w_axis.x).collect();
        assert_eq!(x, [0.0, 1.0, 2.0]);
    }
}
