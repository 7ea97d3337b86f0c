//! Skinning: a skinned primitive's points as the glTF's skin places them at a time code (linear
//! blend skinning, glTF 2.0 section 3.7.3), in the space of the mesh node (the USD point cache
//! bakes each sample of a skinned Mesh with it, under the node's Xform; `preview` draws a
//! skinned file in the pose its joints rest in).
//!
//! For a vertex with joints `j` and weights `w` (every `JOINTS_n`/`WEIGHTS_n` set, weights
//! scaled to sum to 1) at time code `c`:
//!
//! ```text
//! p(c) = inverse(W_mesh(c)) * sum_k w_k * W_joint_k(c) * IBM_k * p
//! ```
//!
//! where `W` is a node's world transform from its local transforms: each node's time samples
//! given by the caller (the USD stage's Xform samples where a clip on the stage moves the node:
//! held before the first and after the last, interpolated linearly between two, as USD reads a
//! `matrix4d`), else its rest transform. So a skinned mesh follows the same joints and nodes as
//! every Xform of the stage. Normals are turned by each vertex's blended matrix's cofactor (its
//! inverse transpose up to scale, which keeps them normal under non-uniform scale) and
//! renormalised.
//!
//! ```text
//! let skeleton = Skeleton::read(doc, node, &samples_of)?;  // None: the node has no skin
//! let skin = Skinning::read(doc, &skeleton, primitive, n, what)?;  // once per primitive
//! skin.apply(code, &mut points, normals.as_deref_mut());
//! ```

use super::{arr, node_parents, read_attribute, rest_matrix, Document};
use anyhow::{bail, Result};
use glam::{DMat3, DMat4, DVec3};
use rayon::prelude::*;
use serde_json::Value;
use std::sync::Arc;

/// A node a skinned mesh depends on: its parent's place in [`Skeleton::nodes`] (always
/// before it), its rest transform, and its local transform's time samples (time order).
struct NodeTrack {
    parent: Option<usize>,
    rest: DMat4,
    samples: Vec<(f64, DMat4)>,
}

impl NodeTrack {
    /// The local transform at time code `code`, as USD evaluates the Xform's samples.
    fn at(&self, code: f64) -> DMat4 {
        let s = &self.samples;
        let (Some(first), Some(last)) = (s.first(), s.last()) else {
            return self.rest;
        };
        if code <= first.0 {
            return first.1;
        }
        if code >= last.0 {
            return last.1;
        }
        // s[i].0 <= code < s[i + 1].0
        let i = s.partition_point(|(c, _)| *c <= code) - 1;
        let ((c0, m0), (c1, m1)) = (s[i], s[i + 1]);
        if code == c0 {
            return m0;
        }
        let u = (code - c0) / (c1 - c0);
        m0 * (1.0 - u) + m1 * u
    }
}

/// What skinning the primitives of one node needs, read once for all of them: the nodes its
/// skin's joints and the node itself hang from, and the joints' inverse bind matrices.
pub struct Skeleton {
    /// The skin's index, for what is said.
    skin: u64,
    nodes: Vec<NodeTrack>,
    /// The mesh node's place in `nodes`.
    mesh_node: usize,
    /// Each joint of the skin: its node's place in `nodes` and its inverse bind matrix.
    joints: Vec<(usize, DMat4)>,
}

/// One primitive's skinning: its node's [`Skeleton`] and each vertex's influences.
pub struct Skinning {
    skeleton: Arc<Skeleton>,
    /// `per` (joint of the skin, weight) pairs a vertex, weights summing to 1 (a vertex whose
    /// weights are all zero has none: it stays where the mesh node puts it).
    influences: Vec<(u32, f32)>,
    per: usize,
}

impl Skeleton {
    /// The skeleton of node `node` of `doc`; `None` when the node has no skin.
    /// `samples_of(node)` gives a node's local transform at each time code it moves (the USD
    /// stage's node motion; none: the rest pose). An error says what breaks glTF's rules.
    pub fn read(
        doc: &Document,
        node: usize,
        samples_of: &dyn Fn(usize) -> Vec<(f64, [f64; 16])>,
    ) -> Result<Option<Arc<Skeleton>>> {
        let json = &doc.json;
        let Some(skin) = json["nodes"][node]["skin"].as_u64() else {
            return Ok(None);
        };
        let node_count = arr(json, "nodes").len();
        let skin_json = &json["skins"][skin as usize];
        if !skin_json.is_object() {
            bail!(doc.err(format!(
                "node {node} names skin {skin}, which the file does not have"
            )));
        }
        let joint_nodes: Vec<usize> = (arr(skin_json, "joints").iter())
            .map(|j| match j.as_u64() {
                Some(j) if (j as usize) < node_count => Ok(j as usize),
                _ => bail!(doc.err(format!("skin {skin} names a joint {j} that is not a node"))),
            })
            .collect::<Result<_>>()?;
        let ibms: Vec<DMat4> = match skin_json["inverseBindMatrices"].as_u64() {
            Some(acc) => {
                let (v, c) = doc.read_f64(acc as usize)?;
                if c != 16 {
                    bail!(doc.err(format!(
                        "skin {skin}'s inverseBindMatrices (accessor {acc}) is not MAT4"
                    )));
                }
                let stored: Vec<DMat4> = v.chunks_exact(16).map(DMat4::from_cols_slice).collect();
                match stored.len() < joint_nodes.len() {
                    true => inverse_binds(json, skin as usize, node, &stored),
                    false => stored,
                }
            }
            None => vec![DMat4::IDENTITY; joint_nodes.len()],
        };
        // The nodes the joints and the mesh node hang from, each after its parent.
        let parents = node_parents(json);
        let mut slot = vec![usize::MAX; node_count];
        let mut nodes: Vec<NodeTrack> = Vec::new();
        let mut place = |start: usize, nodes: &mut Vec<NodeTrack>| -> usize {
            // The chain up to the first node already placed (or the root), then placed down.
            let mut chain = vec![start];
            while let Some(parent) = parents[*chain.last().expect("a node")] {
                if slot[parent] != usize::MAX || chain.len() > node_count {
                    break;
                }
                chain.push(parent);
            }
            for &x in chain.iter().rev() {
                if slot[x] != usize::MAX {
                    continue;
                }
                let parent = parents[x].map(|q| slot[q]).filter(|&s| s != usize::MAX);
                let nd = &json["nodes"][x];
                slot[x] = nodes.len();
                nodes.push(NodeTrack {
                    parent,
                    rest: rest_matrix(nd),
                    samples: (samples_of(x).into_iter())
                        .map(|(c, m)| (c, DMat4::from_cols_array(&m)))
                        .collect(),
                });
            }
            slot[start]
        };
        let mesh_node = place(node, &mut nodes);
        let joints = (joint_nodes.iter().zip(ibms))
            .map(|(&j, ibm)| (place(j, &mut nodes), ibm))
            .collect();
        Ok(Some(Arc::new(Skeleton {
            skin,
            nodes,
            mesh_node,
            joints,
        })))
    }

    /// The time codes at which a node the skin depends on has a sample (time order): where
    /// the skinned points change without the mesh's own frames.
    pub fn codes(&self) -> Vec<f64> {
        let mut codes: Vec<f64> = (self.nodes.iter())
            .flat_map(|n| n.samples.iter().map(|s| s.0))
            .collect();
        codes.sort_by(f64::total_cmp);
        codes.dedup();
        codes
    }

    /// Each joint's skin matrix at `code`, relative to the mesh node; `None` where the mesh
    /// node's world transform has no inverse (scaled to nothing).
    fn matrices(&self, code: f64) -> Option<Vec<DMat4>> {
        let mut world: Vec<DMat4> = Vec::with_capacity(self.nodes.len());
        for n in &self.nodes {
            let local = n.at(code);
            world.push(match n.parent {
                Some(p) => world[p] * local,
                None => local,
            });
        }
        let mesh = world[self.mesh_node];
        let det = mesh.determinant();
        if !det.is_finite() || det.abs() < f64::MIN_POSITIVE {
            return None;
        }
        let to_mesh = mesh.inverse();
        let m: Vec<DMat4> = (self.joints.iter())
            .map(|&(slot, ibm)| to_mesh * world[slot] * ibm)
            .collect();
        m.iter().all(|m| m.is_finite()).then_some(m)
    }

    /// Whether the mesh node can be skinned at every code of `codes` (its world transform
    /// invertible there).
    pub fn works_at(&self, codes: &[f64]) -> bool {
        codes.iter().all(|&c| self.matrices(c).is_some())
    }
}

impl Skinning {
    /// The skinning of primitive `p` (of `n` vertices) drawn by the node of `skeleton`;
    /// `None` when the primitive has no `JOINTS_0`. An error names `what` (the primitive) when
    /// its influences break glTF's rules.
    pub fn read(
        doc: &Document,
        skeleton: &Arc<Skeleton>,
        p: &Value,
        n: usize,
        what: &str,
    ) -> Result<Option<Skinning>> {
        let skin = skeleton.skin;
        // Every JOINTS_n / WEIGHTS_n set, four influences each.
        let mut sets = Vec::new();
        for set in 0.. {
            let joints = read_attribute(doc, p, &format!("JOINTS_{set}"), 4, n, what)?;
            let weights = read_attribute(doc, p, &format!("WEIGHTS_{set}"), 4, n, what)?;
            match (joints, weights) {
                (Some(j), Some(w)) => sets.push((j, w)),
                (None, None) => break,
                _ => bail!(doc.err(format!(
                    "{what} has JOINTS_{set} or WEIGHTS_{set} without the other"
                ))),
            }
        }
        if sets.is_empty() {
            return Ok(None);
        }
        let per = 4 * sets.len();
        let mut influences = Vec::with_capacity(n * per);
        for v in 0..n {
            let start = influences.len();
            let mut sum = 0.0;
            for (j, w) in &sets {
                for c in 0..4 {
                    let (joint, weight) = (j[4 * v + c], w[4 * v + c]);
                    if weight <= 0.0 {
                        influences.push((0, 0.0));
                        continue;
                    }
                    if joint as usize >= skeleton.joints.len() {
                        bail!(doc.err(format!(
                            "{what} vertex {v} is weighted to joint {joint} of skin {skin}, which has {}",
                            skeleton.joints.len()
                        )));
                    }
                    influences.push((joint as u32, weight as f32));
                    sum += weight;
                }
            }
            if sum > 0.0 {
                for x in &mut influences[start..] {
                    x.1 = (x.1 as f64 / sum) as f32;
                }
            }
        }
        Ok(Some(Skinning {
            skeleton: Arc::clone(skeleton),
            influences,
            per,
        }))
    }

    /// Skin `points` (and `normals`) at time code `code`, in place; left as they are where
    /// the mesh node's world transform has no inverse (see [`Skeleton::works_at`]).
    pub fn apply(&self, code: f64, points: &mut [[f32; 3]], normals: Option<&mut [[f32; 3]]>) {
        let Some(mats) = self.skeleton.matrices(code) else {
            return;
        };
        let blended = |v: usize| -> Option<DMat4> {
            let inf = &self.influences[v * self.per..(v + 1) * self.per];
            let mut m = DMat4::ZERO;
            let mut any = false;
            for &(j, w) in inf.iter().filter(|x| x.1 > 0.0) {
                m += mats[j as usize] * w as f64;
                any = true;
            }
            any.then_some(m)
        };
        let skin = |v: usize, p: &mut [f32; 3], n: Option<&mut [f32; 3]>| {
            let Some(m) = blended(v) else { return };
            let q = m.transform_point3(DVec3::from(p.map(f64::from))).as_vec3();
            // A point the skin throws past f32 (a hostile file's matrices) stays as stored.
            if !q.is_finite() {
                return;
            }
            *p = q.to_array();
            if let Some(n) = n {
                // The cofactor matrix: the inverse transpose times the determinant.
                let (x, y, z) = (
                    m.x_axis.truncate(),
                    m.y_axis.truncate(),
                    m.z_axis.truncate(),
                );
                let cof = DMat3::from_cols(y.cross(z), z.cross(x), x.cross(y));
                let turned = cof * DVec3::from(n.map(f64::from)) * x.dot(y.cross(z)).signum();
                *n = turned.normalize_or_zero().as_vec3().to_array();
            }
        };
        const CHUNK: usize = 4096;
        match normals {
            Some(ns) if ns.len() == points.len() => (points.par_chunks_mut(CHUNK))
                .zip(ns.par_chunks_mut(CHUNK))
                .enumerate()
                .for_each(|(k, (ps, ns))| {
                    for (i, (p, n)) in ps.iter_mut().zip(ns).enumerate() {
                        skin(k * CHUNK + i, p, Some(n));
                    }
                }),
            _ => (points.par_chunks_mut(CHUNK).enumerate()).for_each(|(k, ps)| {
                for (i, p) in ps.iter_mut().enumerate() {
                    skin(k * CHUNK + i, p, None);
                }
            }),
        }
    }
}

/// The inverse bind matrices of skin `skin`, the file's (`stored`, in joint order) and, for the
/// joints past them, each as its rest pose binds it: from its parent joint's matrix and its own
/// rest transform (the bind pose's offset from its parent as at rest), or where its parent is
/// no joint with a matrix, from its rest world transform and that of `mesh_node` (a node the
/// skin deforms; none, past the nodes: the scene's origin); a matrix with no inverse (a joint
/// scaled to nothing) gives the identity. Writers have left out the last joints' matrices
/// (glTF-Blender-IO issue 2532: a Fox with 51 for 64 joints, which Blender imports). On files
/// that have them all, the parent rule gives the stored matrix to within 4e-7 (relative) for
/// every joint below another of CesiumMan and Fox.
pub fn inverse_binds(json: &Value, skin: usize, mesh_node: usize, stored: &[DMat4]) -> Vec<DMat4> {
    let parents = node_parents(json);
    let nodes = arr(json, "nodes");
    let local = |n: usize| nodes.get(n).map_or(DMat4::IDENTITY, rest_matrix);
    let world = |mut n: usize| {
        let mut m = DMat4::IDENTITY;
        for _ in 0..=nodes.len() {
            m = local(n) * m;
            match parents.get(n).copied().flatten() {
                Some(p) => n = p,
                None => break,
            }
        }
        m
    };
    let inverse = |m: DMat4| match m.determinant().abs() > f64::MIN_POSITIVE {
        true => m.inverse(),
        false => DMat4::IDENTITY,
    };
    let joints: Vec<usize> = (arr(&json["skins"][skin], "joints").iter())
        .map(|j| j.as_u64().map_or(usize::MAX, |j| j as usize))
        .collect();
    let mut ibms: Vec<Option<DMat4>> = (0..joints.len()).map(|k| stored.get(k).copied()).collect();
    // Parents before children: at most one pass per level of the joint tree.
    for _ in 0..joints.len() {
        let mut missing = false;
        for k in 0..joints.len() {
            if ibms[k].is_some() {
                continue;
            }
            let parent = parents.get(joints[k]).copied().flatten();
            let parent_joint = parent.and_then(|p| joints.iter().position(|&j| j == p));
            ibms[k] = match parent_joint {
                Some(pk) => ibms[pk].map(|p| inverse(local(joints[k])) * p),
                None => Some(inverse(world(joints[k])) * world(mesh_node)),
            };
            missing |= ibms[k].is_none();
        }
        if !missing {
            break;
        }
    }
    ibms.into_iter()
        .map(|m| m.unwrap_or(DMat4::IDENTITY))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_node_s_transform_is_held_outside_its_samples_and_lerped_between() {
        let m = |x: f64| DMat4::from_translation(DVec3::new(x, 0.0, 0.0));
        let track = NodeTrack {
            parent: None,
            rest: m(-1.0),
            samples: vec![(2.0, m(1.0)), (4.0, m(3.0)), (5.0, m(4.0))],
        };
        for (code, x) in [
            (0.0, 1.0),
            (2.0, 1.0),
            (3.0, 2.0),
            (4.0, 3.0),
            (4.5, 3.5),
            (9.0, 4.0),
        ] {
            assert_eq!(track.at(code), m(x), "{code}");
        }
        let still = NodeTrack {
            samples: Vec::new(),
            ..track
        };
        assert_eq!(still.at(3.0), m(-1.0));
    }
}
