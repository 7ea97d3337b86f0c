//! The blended clip as one more animation of the input document: one time accessor shared by
//! LINEAR samplers, a channel for every property either source animates and for every joint the
//! alignment or the clean-up moved. Nothing else in the document changes, but a node given by
//! a matrix that a channel now animates, which is written as its translation, rotation and
//! scale (glTF animates those alone).

use super::rig::{Path, Pose, Rig, Trs};
use crate::gltf::Output;
use glam::DQuat;
use serde_json::json;
use std::collections::BTreeSet;

/// A property whose values stay within this of the rest value is not given a channel (unless a
/// source animates it).
pub const UNCHANGED: f64 = 1e-9;

fn component(t: &Trs, path: Path) -> Vec<f64> {
    match path {
        Path::Translation => t.t.to_array().to_vec(),
        Path::Rotation => t.r.to_array().to_vec(),
        Path::Scale => t.s.to_array().to_vec(),
        Path::Weights => Vec::new(),
    }
}

/// Every (node, path) to write: `animated` plus whatever differs from the rest pose.
pub fn channels(
    rig: &Rig,
    poses: &[Pose],
    animated: &BTreeSet<(usize, Path)>,
) -> BTreeSet<(usize, Path)> {
    let mut out = animated.clone();
    for j in 0..rig.file_nodes {
        for path in [Path::Translation, Path::Rotation, Path::Scale] {
            let rest = component(&rig.rest.local[j], path);
            let moved = poses.iter().any(|p| {
                let v = component(&p.local[j], path);
                let same_rotation = path == Path::Rotation
                    && 1.0 - p.local[j].r.dot(rig.rest.local[j].r).abs() <= UNCHANGED;
                !same_rotation && v.iter().zip(&rest).any(|(a, b)| (a - b).abs() > UNCHANGED)
            });
            if moved {
                out.insert((j, path));
            }
        }
    }
    out
}

/// Node `node` of `out` with its `matrix`, if it has one, written as the translation, rotation
/// and scale it is ([`crate::gltf::rest_trs`]): glTF animates those alone, so a channel on a
/// node given by a matrix (a joint the sources leave still, which the alignment or the
/// clean-up moves) is refused by the validator and left unplayed by players.
fn trs_instead_of_matrix(out: &mut Output, node: usize) {
    let n = &mut out.json["nodes"][node];
    if n.get("matrix").is_none() {
        return;
    }
    let (t, r, s) = crate::gltf::rest_trs(n);
    let o = n
        .as_object_mut()
        .expect("a node with a matrix is an object");
    o.remove("matrix");
    o.insert("translation".into(), json!(t.to_array()));
    o.insert("rotation".into(), json!(r.to_array()));
    o.insert("scale".into(), json!(s.to_array()));
}

/// Append the clip as animation `name`; returns its index.
pub fn append_animation(
    out: &mut Output,
    name: &str,
    times: &[f64],
    poses: &[Pose],
    channels: &BTreeSet<(usize, Path)>,
) -> usize {
    let t: Vec<f32> = times.iter().map(|&x| x as f32).collect();
    let input = out.push_f32(&t, "SCALAR", 1, true, None);
    let mut samplers = Vec::new();
    let mut chans = Vec::new();
    for &(node, path) in channels {
        let (data, ty, ncomp): (Vec<f32>, &str, usize) = match path {
            Path::Rotation => {
                let mut prev: Option<DQuat> = None;
                let mut v = Vec::with_capacity(poses.len() * 4);
                for p in poses {
                    let mut q = p.local[node].r.normalize();
                    if prev.is_some_and(|r| r.dot(q) < 0.0) {
                        q = -q;
                    }
                    prev = Some(q);
                    v.extend(q.to_array().map(|x| x as f32));
                }
                (v, "VEC4", 4)
            }
            Path::Translation | Path::Scale => {
                let v = poses
                    .iter()
                    .flat_map(|p| component(&p.local[node], path))
                    .map(|x| x as f32)
                    .collect();
                (v, "VEC3", 3)
            }
            Path::Weights => {
                let width = poses
                    .iter()
                    .map(|p| p.weights[node].len())
                    .max()
                    .unwrap_or(0);
                if width == 0 {
                    continue;
                }
                let v = poses
                    .iter()
                    .flat_map(|p| {
                        (0..width).map(move |k| p.weights[node].get(k).copied().unwrap_or(0.0))
                    })
                    .map(|x| x as f32)
                    .collect();
                (v, "SCALAR", 1)
            }
        };
        if path != Path::Weights {
            trs_instead_of_matrix(out, node);
        }
        let output = out.push_f32(&data, ty, ncomp, false, None);
        samplers.push(json!({ "input": input, "output": output, "interpolation": "LINEAR" }));
        chans.push(json!({
            "sampler": samplers.len() - 1,
            "target": { "node": node, "path": path.name() }
        }));
    }
    out.push_to(
        "animations",
        json!({ "name": name, "channels": chans, "samplers": samplers }),
    )
}
