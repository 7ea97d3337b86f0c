//! The character and its clips: every node of the scene as a joint (so any node a clip animates
//! has a place), the skin in use marking the skeleton, and clips evaluated as local poses.

use crate::gltf::{arr, clip_name, read_channels, Document};
pub use crate::gltf::{push_key, slerp, Channel, Interp, Path};
use anyhow::{bail, Result};
use glam::{DMat4, DQuat, DVec3};
use serde_json::Value;
use std::collections::BTreeSet;

/// Shortest key span (seconds) a channel's key rate is measured over.
const MIN_SPAN: f64 = 1e-9;

/// World up: +Y in glTF and in the BVH files we read.
pub const UP: DVec3 = DVec3::Y;

/// The horizontal part of `v` (across [`UP`]).
pub fn flat(v: DVec3) -> DVec3 {
    v - UP * v.dot(UP)
}

/// The angle `a` (radians) taken round by whole turns to within a half turn of `last`: a
/// sequence of angles unwrapped.
pub fn unwrapped(last: f64, a: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    last + (a - last + PI).rem_euclid(TAU) - PI
}

/// A local transform.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Trs {
    pub t: DVec3,
    pub r: DQuat,
    pub s: DVec3,
}

impl Trs {
    pub const IDENTITY: Trs = Trs {
        t: DVec3::ZERO,
        r: DQuat::IDENTITY,
        s: DVec3::ONE,
    };

    pub fn matrix(&self) -> DMat4 {
        DMat4::from_scale_rotation_translation(self.s, self.r, self.t)
    }

    pub fn from_matrix(m: &DMat4) -> Trs {
        let (s, r, t) = m.to_scale_rotation_translation();
        Trs { t, r, s }
    }
}

/// Local transforms (and morph weights) of every node.
#[derive(Clone, Debug, PartialEq)]
pub struct Pose {
    pub local: Vec<Trs>,
    /// Morph weights per node (empty for nodes without a mesh with targets).
    pub weights: Vec<Vec<f64>>,
}

/// An animation clip.
#[derive(Clone, Debug)]
pub struct Clip {
    pub name: String,
    /// Index of the animation in the file.
    pub index: usize,
    pub channels: Vec<Channel>,
    pub start: f64,
    pub end: f64,
    /// Key rate (keys per second of the densest channel).
    pub key_rate: f64,
}

impl Clip {
    pub fn duration(&self) -> f64 {
        self.end - self.start
    }

    /// The (node, path) pairs the clip animates.
    pub fn animated(&self) -> BTreeSet<(usize, Path)> {
        self.channels.iter().map(|c| (c.node, c.path)).collect()
    }

    /// The pose at time `t` (clamped to the clip): the rest pose with every channel applied.
    pub fn pose(&self, rig: &Rig, t: f64) -> Pose {
        let mut pose = rig.rest.clone();
        let mut buf = [0.0f64; 4];
        for c in &self.channels {
            match c.path {
                Path::Weights => {
                    let w = &mut pose.weights[c.node];
                    w.resize(c.width, 0.0);
                    c.sample(t, w);
                }
                _ => {
                    let v = &mut buf[..c.width];
                    c.sample(t, v);
                    let l = &mut pose.local[c.node];
                    match c.path {
                        Path::Translation => l.t = DVec3::from_slice(v),
                        Path::Scale => l.s = DVec3::from_slice(v),
                        _ => l.r = DQuat::from_slice(v).normalize(),
                    }
                }
            }
        }
        pose
    }
}

/// The scene as a joint hierarchy.
#[derive(Clone, Debug)]
pub struct Rig {
    pub names: Vec<String>,
    pub parent: Vec<Option<usize>>,
    /// Every node, parents before children.
    pub order: Vec<usize>,
    pub rest: Pose,
    /// Members of the skeleton in use (the skin's joints and their plain descendants).
    pub skeleton: Vec<bool>,
    /// The skeleton's topmost joint (where alignment moves the character).
    pub root: usize,
    /// The joint whose position is the body's (root speed, travel, feet relative to the body):
    /// the root, or the joint below it that carries the clips over the floor ([`Rig::carried_by`]).
    pub body: usize,
    /// How many of the nodes are the file's: the chain ends [`use_skin`] adds come after them
    /// and are never written.
    pub file_nodes: usize,
}

/// A joint ends a clip this far from where it began (horizontally, a fraction of the
/// character's size) to carry the character over the floor: a walk travels about 0.7 of its
/// size a second; a clip in place comes back to within [`super::track::LOOP_TOLERANCE`].
pub const CARRIES: f64 = 0.1;

/// The joint that carries the body holds at least this share of the skeleton's joints (itself
/// and those below it): the hips hold all but the root bones above them; a paw, a hand with its
/// fingers, a tail or a ponytail hold a few.
pub const BODY_SHARE: f64 = 0.5;

impl Rig {
    /// This rig with [`Rig::body`] the joint that carries `clips` over the floor: the topmost
    /// joint that carries every clip that travels. The root carries a clip it moves at least
    /// [`CARRIES`] of `size` from where it began; a joint below it holding [`BODY_SHARE`] of
    /// the skeleton carries one that translates it that far with the skeleton below it (root
    /// motion keyed on the hips under a root bone that stays put: Fox's hip, b_Hip_01, under
    /// _rootJoint; a capture retargeted onto a game skeleton whose pelvis travels). Where one
    /// clip travels on its root and the other on its hips below a still root, the hips carry
    /// both; taken as the root, the clip travelling on its hips was measured against a root
    /// that stays put and judged to step in place: Bandai Namco's dataset-1 walk_normal
    /// (travelling on its hips) with its run_normal (travelling on joint_Root), the walk "moved
    /// along at its treadmill's 0.14 leg/s" (it walks at 1.36), the blend did not travel.
    /// Positions relative to the body then repeat over a cycle however far the clip travels.
    /// Where no joint carries all, the topmost that carries one; the root where no clip
    /// travels.
    pub fn carried_by(&self, clips: &[&Clip], size: f64) -> Rig {
        let mut rig = self.clone();
        // Per clip, each joint's horizontal displacement from the clip's start to its end.
        let moves: Vec<(&Clip, Vec<DVec3>)> = clips
            .iter()
            .filter(|c| c.duration() > 0.0)
            .map(|c| {
                let [a, b] = [c.start, c.end].map(|t| self.positions(&c.pose(self, t)));
                (*c, a.iter().zip(&b).map(|(a, b)| flat(*b - *a)).collect())
            })
            .collect();
        // A joint carries a clip when it holds most of the skeleton ([`BODY_SHARE`]: not a
        // paw, nor a hand with its fingers, that a loop exported one key short of closing
        // leaves a key step away from where it began, as Blender bakes every bone of Fox's
        // walk or of Mixamo's run), the clip translates it that far and the skeleton below it
        // moves along, feet too (nine joints in ten within half of that of it: not hips that
        // sit down or fall over the feet, as RobotExpressive's Sitting and Death do).
        let skeleton = self.skeleton.iter().filter(|&&s| s).count();
        // Per joint, how many of the skeleton's joints are at or below it.
        let mut held = vec![0usize; self.len()];
        for k in (0..self.len()).filter(|&k| self.skeleton[k]) {
            let mut at = Some(k);
            while let Some(a) = at {
                held[a] += 1;
                at = self.parent[a];
            }
        }
        let carries = |j: usize, (clip, d): &(&Clip, Vec<DVec3>)| {
            if j == self.root {
                return d[j].length() > CARRIES * size;
            }
            if (held[j] as f64) < BODY_SHARE * skeleton as f64 || d[j].length() <= CARRIES * size {
                return false;
            }
            let below: Vec<usize> = (0..self.len())
                .filter(|&k| self.skeleton[k] && self.descends(k, j))
                .collect();
            let translated = clip
                .channels
                .iter()
                .any(|c| c.node == j && c.path == Path::Translation);
            let mut off: Vec<f64> = below.iter().map(|&k| (d[k] - d[j]).length()).collect();
            off.sort_by(f64::total_cmp);
            translated && off[(off.len() - 1) * 9 / 10] <= 0.5 * d[j].length()
        };
        let joints: Vec<usize> = (self.order.iter().copied())
            .filter(|&j| self.skeleton[j])
            .collect();
        // Per clip that travels (a joint carries it), whether each joint, top down, carries it.
        let travelling: Vec<Vec<bool>> = (moves.iter())
            .map(|m| joints.iter().map(|&j| carries(j, m)).collect::<Vec<bool>>())
            .filter(|c| c.contains(&true))
            .collect();
        let all =
            (0..joints.len()).find(|&k| !travelling.is_empty() && travelling.iter().all(|c| c[k]));
        let any = || (0..joints.len()).find(|&k| travelling.iter().any(|c| c[k]));
        if let Some(k) = all.or_else(any) {
            rig.body = joints[k];
        }
        rig
    }

    /// Whether joint `j` is one of the skeleton's joints the body carries: at or below
    /// [`Rig::body`] (every one where the body is the root).
    pub fn carries(&self, j: usize) -> bool {
        self.skeleton[j] && (self.body == self.root || self.descends(j, self.body))
    }

    /// Whether joint `j` is `top` or below it.
    fn descends(&self, j: usize, top: usize) -> bool {
        let mut at = Some(j);
        while let Some(k) = at {
            if k == top {
                return true;
            }
            at = self.parent[k];
        }
        false
    }

    /// A rig from a parent list and a rest pose (nodes in any order).
    pub fn new(names: Vec<String>, parent: Vec<Option<usize>>, rest: Pose) -> Result<Rig> {
        let n = names.len();
        let mut children = vec![Vec::new(); n];
        for (i, p) in parent.iter().enumerate() {
            if let Some(p) = *p {
                children[p].push(i);
            }
        }
        let mut order = Vec::with_capacity(n);
        let mut stack: Vec<usize> = (0..n).rev().filter(|&i| parent[i].is_none()).collect();
        while let Some(i) = stack.pop() {
            order.push(i);
            stack.extend(children[i].iter().rev());
        }
        if order.len() != n {
            bail!("the node hierarchy has a cycle");
        }
        Ok(Rig {
            names,
            parent,
            order,
            rest,
            skeleton: vec![true; n],
            root: 0,
            body: 0,
            file_nodes: n,
        })
    }

    pub fn len(&self) -> usize {
        self.names.len()
    }

    pub fn is_empty(&self) -> bool {
        self.names.is_empty()
    }

    /// World matrices of every node.
    pub fn world(&self, pose: &Pose) -> Vec<DMat4> {
        let mut w = vec![DMat4::IDENTITY; self.len()];
        for &i in &self.order {
            let m = pose.local[i].matrix();
            w[i] = match self.parent[i] {
                Some(p) => w[p] * m,
                None => m,
            };
        }
        w
    }

    /// World positions of every node.
    pub fn positions(&self, pose: &Pose) -> Vec<DVec3> {
        self.world(pose)
            .iter()
            .map(|m| m.w_axis.truncate())
            .collect()
    }

    /// Each node's children, in node order (one pass over the parents: asking a node at a
    /// time by scanning every node made a skin of 80,000 joints take 14 s).
    pub fn children(&self) -> Vec<Vec<usize>> {
        let mut out = vec![Vec::new(); self.len()];
        for (i, p) in self.parent.iter().enumerate() {
            if let Some(p) = *p {
                out[p].push(i);
            }
        }
        out
    }

    /// How many skeleton children each node has.
    pub fn skeleton_child_counts(&self) -> Vec<usize> {
        let mut out = vec![0; self.len()];
        for (i, p) in self.parent.iter().enumerate() {
            if let Some(p) = p.filter(|_| self.skeleton[i]) {
                out[p] += 1;
            }
        }
        out
    }

    /// World matrix of the parent of `j` (identity for a scene root).
    pub fn parent_world(&self, world: &[DMat4], j: usize) -> DMat4 {
        self.parent[j].map_or(DMat4::IDENTITY, |p| world[p])
    }
}

/// Read every node and every animation of a glTF document.
pub fn load_gltf(doc: &Document) -> Result<(Rig, Vec<Clip>)> {
    let nodes = arr(&doc.json, "nodes");
    let n = nodes.len();
    let mut parent = vec![None; n];
    for (i, node) in nodes.iter().enumerate() {
        for c in arr(node, "children") {
            let c = c.as_u64().unwrap_or(u64::MAX) as usize;
            if c >= n {
                bail!(doc.err(format!("node {i} has a child {c} that does not exist")));
            }
            if parent[c].is_some() {
                bail!(doc.err(format!("node {c} has two parents")));
            }
            parent[c] = Some(i);
        }
    }
    let num = |v: &Value, k: usize, d: f64| v.get(k).and_then(Value::as_f64).unwrap_or(d);
    let mut local = Vec::with_capacity(n);
    let mut weights = Vec::with_capacity(n);
    for node in nodes {
        let trs = if node.get("matrix").is_some_and(Value::is_array) {
            let cols: Vec<f64> = (0..16).map(|k| num(&node["matrix"], k, 0.0)).collect();
            Trs::from_matrix(&DMat4::from_cols_slice(&cols))
        } else {
            let t = &node["translation"];
            let r = &node["rotation"];
            let s = &node["scale"];
            Trs {
                t: DVec3::new(num(t, 0, 0.0), num(t, 1, 0.0), num(t, 2, 0.0)),
                r: DQuat::from_xyzw(
                    num(r, 0, 0.0),
                    num(r, 1, 0.0),
                    num(r, 2, 0.0),
                    num(r, 3, 1.0),
                )
                .normalize(),
                s: DVec3::new(num(s, 0, 1.0), num(s, 1, 1.0), num(s, 2, 1.0)),
            }
        };
        if !(trs.t.is_finite() && trs.r.is_finite() && trs.s.is_finite()) {
            bail!(doc.err(format!(
                "node {} has a transform that is not finite or cannot be decomposed",
                local.len()
            )));
        }
        local.push(trs);
        let mesh = node
            .get("mesh")
            .and_then(Value::as_u64)
            .and_then(|m| doc.json["meshes"].get(m as usize));
        let targets = mesh
            .map(|m| arr(&m["primitives"][0], "targets").len())
            .unwrap_or(0);
        let w: Vec<f64> = node
            .get("weights")
            .or_else(|| mesh.and_then(|m| m.get("weights")))
            .and_then(Value::as_array)
            .map(|a| a.iter().map(|x| x.as_f64().unwrap_or(0.0)).collect())
            .unwrap_or_else(|| vec![0.0; targets]);
        weights.push(w);
    }
    let names = nodes
        .iter()
        .enumerate()
        .map(|(i, nd)| {
            nd.get("name")
                .and_then(Value::as_str)
                .map(str::to_owned)
                .unwrap_or_else(|| format!("node {i}"))
        })
        .collect();
    let rig = Rig::new(names, parent, Pose { local, weights }).map_err(|e| doc.err(e))?;
    let clips = arr(&doc.json, "animations")
        .iter()
        .enumerate()
        .map(|(i, a)| read_clip(doc, &rig, i, a))
        .collect::<Result<Vec<_>>>()?;
    Ok((rig, clips))
}

fn read_clip(doc: &Document, rig: &Rig, index: usize, anim: &Value) -> Result<Clip> {
    let name = clip_name(anim, index);
    let channels = read_channels(doc, &name, anim, rig.len())?;
    Ok(clip_from_channels(name, index, channels))
}

/// A clip over its channels' time range, with the key rate of its densest channel.
pub fn clip_from_channels(name: String, index: usize, channels: Vec<Channel>) -> Clip {
    let start = channels
        .iter()
        .map(|c| c.times[0])
        .fold(f64::INFINITY, f64::min);
    let end = channels
        .iter()
        .map(|c| *c.times.last().unwrap())
        .fold(f64::NEG_INFINITY, f64::max);
    let key_rate = channels
        .iter()
        .filter(|c| c.times.len() > 1)
        .map(|c| {
            (c.times.len() - 1) as f64 / (c.times[c.times.len() - 1] - c.times[0]).max(MIN_SPAN)
        })
        .fold(0.0, f64::max);
    let (start, end) = if start.is_finite() {
        (start, end)
    } else {
        (0.0, 0.0)
    };
    Clip {
        name,
        index,
        channels,
        start,
        end,
        key_rate: if key_rate > 0.0 { key_rate } else { 30.0 },
    }
}

/// A helper leaf nearer its joint's origin than this fraction of the skin's longest joint
/// offset (in their parents' frames) is taken as no end at all.
const END_ON_JOINT: f64 = 1e-6;

/// Mark the skeleton of skin `skin`: its joints plus their descendants that carry nothing,
/// themselves or below them (end-of-chain helper nodes such as `LowerLeg.L_end`), and find its
/// topmost joint. A node whose mesh hangs from a child of its own (gltfpack moves a mesh on a
/// joint's child into a new node below it) is an attachment, not a bone: taken as one, it ended
/// RobotExpressive's legs at the knee and the blend planted its fingers. So is a helper leaf on
/// its joint's origin ([`END_ON_JOINT`]): it marks nothing (assimp's glTF export writes every
/// end node there, and the same fingers were planted).
pub fn use_skin(doc: &Document, rig: &mut Rig, skin: usize) {
    let nodes = arr(&doc.json, "nodes");
    let joints: BTreeSet<usize> = arr(&doc.json["skins"][skin], "joints")
        .iter()
        .filter_map(|j| j.as_u64().map(|j| j as usize))
        .filter(|&j| j < rig.len())
        .collect();
    let carries = |i: usize| {
        let nd = &nodes[i];
        nd.get("mesh").is_some() || nd.get("camera").is_some() || nd.get("skin").is_some()
    };
    // Whether a node or one below it carries something (children before parents).
    let mut loaded: Vec<bool> = (0..rig.len()).map(carries).collect();
    for &i in rig.order.iter().rev() {
        if let Some(p) = rig.parent[i] {
            loaded[p] |= loaded[i] && !joints.contains(&i);
        }
    }
    // A helper leaf written on its joint's origin marks no end (assimp's glTF export writes
    // every end node so): left out, the joint is the leaf and [`add_ends`] may give it one.
    let reach = joints
        .iter()
        .map(|&j| rig.rest.local[j].t.length())
        .fold(0.0, f64::max);
    let children = rig.children();
    let on_joint =
        |i: usize| children[i].is_empty() && rig.rest.local[i].t.length() <= END_ON_JOINT * reach;
    let mut member = vec![false; rig.len()];
    for &i in &rig.order {
        member[i] = joints.contains(&i)
            || (!loaded[i]
                && !on_joint(i)
                && rig.parent[i].is_some_and(|p| member[p])
                && !joints.is_empty());
    }
    rig.root = rig.order.iter().copied().find(|&i| member[i]).unwrap_or(0);
    rig.body = rig.root;
    rig.skeleton = member;
    add_ends(doc, rig, &joints);
}

/// Give each leaf joint that carries rigid geometry and nothing to mark where it ends an end
/// node where that geometry ends ([`geometry_end`], in the joint's frame), named `<joint>_end`
/// as Blender names such nodes. gltfpack drops end nodes no skin uses, and assimp writes them
/// on their joints' origins ([`use_skin`] leaves those out): on RobotExpressive, whose shins
/// are rigid meshes hung from the knee joints and whose `LowerLeg.L_end` nodes were the only
/// mark of where they end, the legs then stopped at the knee and the blend took the fingers for
/// feet. Joints whose geometry is skinned (Fox, CesiumMan: their foot joints are the leaves)
/// are left as they are. An unreadable mesh adds no end (the blend then goes on as before).
fn add_ends(doc: &Document, rig: &mut Rig, joints: &BTreeSet<usize>) {
    let nodes = arr(&doc.json, "nodes");
    let world = rig.world(&rig.rest);
    let children = rig.children();
    let mut ends = Vec::new();
    for &j in joints {
        if j >= rig.file_nodes || children[j].iter().any(|&c| rig.skeleton[c]) {
            continue;
        }
        // The joint and its non-joint descendants, each with its transform into the joint's
        // frame.
        let mut stack = vec![(j, DMat4::IDENTITY)];
        let mut points: Vec<DVec3> = Vec::new();
        while let Some((i, to_joint)) = stack.pop() {
            let node = &nodes[i];
            if let (Some(mesh), None) = (node.get("mesh").and_then(Value::as_u64), node.get("skin"))
            {
                for prim in arr(&doc.json["meshes"][mesh as usize], "primitives") {
                    let Some(acc) = prim["attributes"].get("POSITION").and_then(Value::as_u64)
                    else {
                        continue;
                    };
                    let Ok((p, 3)) = doc.read_f64(acc as usize) else {
                        continue;
                    };
                    points.extend(
                        p.chunks_exact(3)
                            .map(|v| to_joint.transform_point3(DVec3::new(v[0], v[1], v[2]))),
                    );
                }
            }
            stack.extend(
                children[i]
                    .iter()
                    .filter(|&&c| c < rig.file_nodes && !joints.contains(&c))
                    .map(|&c| (c, to_joint * rig.rest.local[c].matrix())),
            );
        }
        if let Some(at) = geometry_end(&points, world[j]) {
            ends.push((j, at));
        }
    }
    for (j, at) in ends {
        let end = rig.len();
        rig.names.push(format!("{}_end", rig.names[j]));
        rig.parent.push(Some(j));
        rig.order.push(end);
        rig.rest.local.push(Trs {
            t: at,
            r: DQuat::IDENTITY,
            s: DVec3::ONE,
        });
        rig.rest.weights.push(Vec::new());
        rig.skeleton.push(true);
    }
}

/// Where a joint's rigid geometry ends, from `points` (its vertices in the joint's frame, `world`
/// the joint's rest matrix): along the axis from the joint to their centroid, on that axis at
/// their farthest extent along it (the tip of the bone the geometry shapes: RobotExpressive's
/// shin ends 0.0088 along its knee's axis, its lost end node at 0.0093 at the ankle); for
/// geometry centred on the joint, its lowest vertex in the rest pose. `None` for no points or
/// one that is not a number (a broken or hostile file).
fn geometry_end(points: &[DVec3], world: DMat4) -> Option<DVec3> {
    if points.is_empty() || !points.iter().all(|p| p.is_finite()) {
        return None;
    }
    let centroid = points.iter().sum::<DVec3>() / points.len() as f64;
    let reach = points.iter().map(|p| p.length()).fold(0.0, f64::max);
    if centroid.length() > CENTRED * reach {
        let axis = centroid.normalize();
        let far = points.iter().map(|p| p.dot(axis)).fold(f64::MIN, f64::max);
        return Some(axis * far);
    }
    let height = |p: &DVec3| world.transform_point3(*p).y;
    points
        .iter()
        .copied()
        .min_by(|a, b| height(a).total_cmp(&height(b)))
}

/// Geometry whose centroid is nearer its joint than this fraction of its farthest vertex is
/// centred on the joint (no bone direction to follow).
const CENTRED: f64 = 0.05;

/// The skin joints of the document: one set per skin.
pub fn skins(doc: &Document) -> Vec<BTreeSet<usize>> {
    arr(&doc.json, "skins")
        .iter()
        .map(|s| {
            arr(s, "joints")
                .iter()
                .filter_map(|j| j.as_u64().map(|j| j as usize))
                .collect()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A joint's helper children are skeleton; a child whose mesh hangs from a node below it
    /// (as gltfpack leaves a mesh on a joint's child) is not, nor is that mesh node.
    #[test]
    fn a_node_carrying_a_mesh_below_it_is_not_a_bone() {
        let json = serde_json::json!({
            "asset": {"version": "2.0"},
            "nodes": [
                {"name": "hip", "children": [1]},
                {"name": "shin", "children": [2, 3], "translation": [0.0, -1.0, 0.0]},
                {"name": "shin mesh", "children": [4]},
                {"name": "shin end", "translation": [0.0, -1.0, 0.0]},
                {"name": "", "mesh": 0},
            ],
            "meshes": [{"primitives": [{"attributes": {}}]}],
            "skins": [{"joints": [0, 1]}],
        });
        let rig = skinned(&json);
        assert_eq!(rig.skeleton, [true, true, false, true, false]);
        assert_eq!(rig.skeleton_child_counts()[1], 1);
        assert_eq!(rig.children()[1], [2, 3]);
    }

    /// The rig of `json`, a glTF document, with its skin 0 in use.
    fn skinned(json: &serde_json::Value) -> Rig {
        let bytes = serde_json::to_vec(json).unwrap();
        let path = std::path::Path::new("rig.gltf");
        let doc = Document::from_bytes(path, &bytes, &Default::default()).unwrap();
        let (mut rig, _) = load_gltf(&doc).unwrap();
        use_skin(&doc, &mut rig, 0);
        rig
    }

    /// The rig of a two-joint skin whose leaf joint (the shin, at y = -1) carries a rigid mesh
    /// of two vertices, `positions` as base64 of six little-endian f32.
    fn shin_with_mesh(positions: &str) -> Rig {
        shin_with_mesh_and_end(positions, None)
    }

    /// [`shin_with_mesh`] whose shin has a child `shin_end` at `end` (in its frame).
    fn shin_with_mesh_and_end(positions: &str, end: Option<[f64; 3]>) -> Rig {
        let mut shin =
            serde_json::json!({"name": "shin", "mesh": 0, "translation": [0.0, -1.0, 0.0]});
        let mut nodes = vec![serde_json::json!({"name": "hip", "children": [1]})];
        if let Some(end) = end {
            shin["children"] = serde_json::json!([2]);
            nodes.extend([
                shin,
                serde_json::json!({"name": "shin_end", "translation": end}),
            ]);
        } else {
            nodes.push(shin);
        }
        let json = serde_json::json!({
            "asset": {"version": "2.0"},
            "nodes": nodes,
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
            "accessors": [{"bufferView": 0, "componentType": 5126, "count": 2, "type": "VEC3"}],
            "bufferViews": [{"buffer": 0, "byteLength": 24}],
            "buffers": [{"byteLength": 24,
                "uri": format!("data:application/octet-stream;base64,{positions}")}],
            "skins": [{"joints": [0, 1]}],
        });
        skinned(&json)
    }

    /// A leaf joint's rigid mesh gives it an end where the mesh ends along the axis from the
    /// joint to its centroid, in the joint's frame, never written; a mesh centred on its joint
    /// at its lowest vertex in the rest pose; a mesh with a vertex that is not a number (a
    /// broken or hostile file) gives none rather than an end at NaN.
    #[test]
    fn a_leaf_joint_ends_where_its_mesh_ends() {
        // (0.1, -0.5, 0) and (-0.1, -1, 0): the axis is -y, the end at its farthest, y = -1.
        let rig = shin_with_mesh("zczMPQAAAL8AAAAAzczMvQAAgL8AAAAA");
        assert_eq!((rig.len(), rig.file_nodes), (3, 2));
        assert_eq!(rig.names[2], "shin_end");
        assert_eq!(rig.parent[2], Some(1));
        assert!(rig.skeleton[2]);
        assert!((rig.rest.local[2].t - DVec3::new(0.0, -1.0, 0.0)).length() < 1e-7);
        // (0, 0.5, 0) and (0, -0.5, 1/32): centred on the joint, the lower vertex.
        let rig = shin_with_mesh("AAAAAAAAAD8AAAAAAAAAAAAAAL8AAAA9");
        assert_eq!(rig.rest.local[2].t, DVec3::new(0.0, -0.5, 0.03125));
        // An end node on the joint's origin (as assimp writes them) marks no end: the mesh's
        // is given; one off it is kept.
        let mesh = "zczMPQAAAL8AAAAAzczMvQAAgL8AAAAA";
        let rig = shin_with_mesh_and_end(mesh, Some([0.0; 3]));
        assert_eq!((rig.len(), rig.file_nodes), (4, 3));
        assert!(!rig.skeleton[2] && rig.skeleton[3]);
        assert!((rig.rest.local[3].t - DVec3::new(0.0, -1.0, 0.0)).length() < 1e-7);
        let rig = shin_with_mesh_and_end(mesh, Some([0.0, -0.25, 0.0]));
        assert_eq!((rig.len(), rig.file_nodes), (3, 3));
        assert!(rig.skeleton[2]);
        // (NaN, NaN, NaN) and (0, -0.5, 0.25).
        let rig = shin_with_mesh("AADAfwAAwH8AAMB/AAAAAAAAAL8AAIA+");
        assert_eq!(rig.len(), 2);
    }
}
