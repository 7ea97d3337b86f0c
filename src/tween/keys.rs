//! Keyframes stage: find every mesh with morph targets and the key poses that drive it.
//!
//! A *track* is one sequence of keys for one mesh: the keys of a weights animation channel
//! (`--keys animation`), or the base mesh followed by each target at weight 1 (`--keys targets`).
//! A key pose is `base + sum_i w_i * delta_i` over the mesh's targets.

use super::timegrid::snap;
use crate::gltf::{
    arr, clip_by, clip_name, defined_keys, defined_only, listed, mesh_nodes, quoted_name,
    read_attribute, read_attribute3, read_triangles, read_vec3, weights_target, Document,
    WeightsTarget,
};
use anyhow::{bail, Result};
use glam::DVec3;
use serde_json::Value;
use std::collections::HashMap;

/// Where the keys come from (`--keys`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum KeySource {
    /// `animation` for meshes whose weights the file animates (a morph mesh beside them that no
    /// clip animates keeps its pose); `targets` when no clip animates weights or moves a node
    /// (beside a character's skeletal clips, morph targets are blend shapes, not keys).
    #[default]
    Auto,
    /// Key 0 = base mesh, key k = base + target k at weight 1; key times 0, 1, 2, ... s.
    Targets,
    /// The key times of the weights channel that animates the mesh's node.
    Animation,
}

/// Geometry of one primitive of a morph mesh, in the mesh's own space.
pub struct Primitive {
    /// Index of the primitive in `mesh.primitives`.
    pub index: usize,
    pub base: Vec<DVec3>,
    pub normals: Option<Vec<DVec3>>,
    /// TANGENT xyzw; only the xyz part is morphed.
    pub tangents: Option<Vec<[f64; 4]>>,
    /// POSITION deltas per target.
    pub target_pos: Vec<Vec<DVec3>>,
    /// NORMAL deltas per target, when the target has them.
    pub target_nrm: Vec<Option<Vec<DVec3>>>,
    /// TANGENT (xyz) deltas per target, when the target has them.
    pub target_tan: Vec<Option<Vec<DVec3>>>,
    /// The targets' other attributes (TEXCOORD_n, COLOR_n, ...), in name order.
    pub target_other: Vec<OtherDeltas>,
    /// Triangles in local vertex indices.
    pub triangles: Vec<[u32; 3]>,
}

/// Deltas of a target attribute that is not solved (TEXCOORD_n, COLOR_n, ...): a frame gets
/// them blended by its authored weights, as a renderer blends them between keys.
pub struct OtherDeltas {
    /// The attribute's name.
    pub name: String,
    /// Components per vertex (2 for TEXCOORD_n, 3 or 4 for COLOR_n).
    pub components: usize,
    /// Per target, `components` values per vertex, when the target has the attribute.
    pub deltas: Vec<Option<Vec<f32>>>,
}

/// One key sequence for a mesh.
#[derive(Clone)]
pub struct Track {
    pub origin: TrackOrigin,
    /// Key times in seconds, non-decreasing.
    pub times: Vec<f64>,
    /// `weights[k][i]`: weight of target i at key k.
    pub weights: Vec<Vec<f64>>,
    /// A CUBICSPLINE clip's tangents: `eases[k]` holds key k's in- and out-tangents (weights
    /// per second), the eases into and out of it that frames between keys follow; `None` for
    /// other clips and for keys from the targets.
    pub eases: Option<Vec<[Vec<f64>; 2]>>,
}

impl Track {
    /// Whether the segment from key a to b follows the track's eases: a clip that has them,
    /// and a segment [`eases_apply`] to.
    pub fn eased(&self, a: usize, b: usize) -> bool {
        self.eases.is_some() && eases_apply(&self.times, a, b)
    }
}

/// Whether a segment from key a to b of keys at `times` can follow eases: two consecutive
/// keys at different times (not a cut, not a track's single key time).
pub fn eases_apply(times: &[f64], a: usize, b: usize) -> bool {
    b == a + 1 && times[b] > times[a]
}

#[derive(Clone, Debug, PartialEq)]
pub enum TrackOrigin {
    /// Keys made from the targets; a new animation will drive these nodes.
    Targets { nodes: Vec<usize> },
    /// Keys of sampler `sampler` of animation `animation`, used by these channels.
    Animation {
        animation: usize,
        sampler: usize,
        channels: Vec<usize>,
    },
}

/// A mesh to process, with all of its tracks.
pub struct MorphMesh {
    pub mesh: usize,
    pub name: String,
    pub primitives: Vec<Primitive>,
    pub target_count: usize,
    pub tracks: Vec<Track>,
    /// Weight channels on this mesh's nodes that no track keeps (dropped from the output).
    pub dropped_channels: Vec<(usize, usize)>,
    /// Authored targets given the normals of their shapes (`target_normals`, the glTF rig
    /// layout); 0 as read.
    pub normals_given: usize,
}

impl MorphMesh {
    pub fn vertex_count(&self) -> usize {
        self.primitives.iter().map(|p| p.base.len()).sum()
    }

    /// Key pose for weights `w`, all primitives concatenated.
    pub fn pose(&self, w: &[f64]) -> Vec<DVec3> {
        let mut out = Vec::with_capacity(self.vertex_count());
        for p in &self.primitives {
            let start = out.len();
            out.extend_from_slice(&p.base);
            for (i, &wi) in w.iter().enumerate() {
                if wi != 0.0 {
                    for (o, d) in out[start..].iter_mut().zip(&p.target_pos[i]) {
                        *o += wi * *d;
                    }
                }
            }
        }
        out
    }

    /// Normals for weights `w` (base + weighted NORMAL deltas, normalized), when every
    /// primitive has normals.
    pub fn pose_normals(&self, w: &[f64]) -> Option<Vec<DVec3>> {
        let mut out = Vec::with_capacity(self.vertex_count());
        for p in &self.primitives {
            let start = out.len();
            out.extend_from_slice(p.normals.as_ref()?);
            for (i, &wi) in w.iter().enumerate() {
                if let (true, Some(d)) = (wi != 0.0, &p.target_nrm[i]) {
                    for (o, d) in out[start..].iter_mut().zip(d) {
                        *o += wi * *d;
                    }
                }
            }
            for o in &mut out[start..] {
                *o = o.normalize_or_zero();
            }
        }
        Some(out)
    }
}

/// Options of the keyframes stage.
pub struct KeyOptions<'a> {
    pub source: KeySource,
    /// `--animation NAME|INDEX`.
    pub animation: Option<&'a str>,
}

/// Find every mesh with morph targets, its geometry and its tracks.
pub fn find_morph_meshes(doc: &Document, opts: &KeyOptions) -> Result<Vec<MorphMesh>> {
    let selected = match opts.animation {
        None => None,
        Some(sel) => Some(find_animation(doc, sel)?),
    };
    let mut out = Vec::new();
    // Why a morph mesh was passed over: its weights hold one pose, they change only targets
    // that move no vertex (normals, texture coordinates, colours), or no clip animates them.
    let (mut held_one_pose, mut moves_no_vertex, mut not_animated) = (false, false, false);
    let users = MeshUsers::of(&doc.json);
    // `--keys auto` tweens a mesh's targets only in a file with no clip (the clip picked by
    // `--animation`, when given) that animates weights or moves a node: beside a weights
    // animation, a morph mesh with none keeps its authored pose (a prop held by its default
    // weights), and a character's face shapes beside its skeletal clips are blend shapes, not
    // keys (RobotExpressive through gltfpack, which drops its constant weights channels, was
    // tweened through Angry, Surprised and Sad, where the original file is refused).
    let animates_weights =
        (users.channels.values().flatten()).any(|&(a, _, _)| selected.is_none_or(|s| s == a));
    let moves_nodes = arr(&doc.json, "animations")
        .iter()
        .enumerate()
        .any(|(a, anim)| selected.is_none_or(|s| s == a) && moves_a_node(anim));
    for mi in 0..arr(&doc.json, "meshes").len() {
        let found = morph_mesh(
            doc,
            mi,
            &users,
            opts,
            selected,
            animates_weights || moves_nodes,
        )?;
        let Some((mm, use_animation)) = found else {
            continue;
        };
        if mm.tracks.is_empty() {
            not_animated = true;
        } else if mm.tracks.iter().any(|t| has_distinct_keys(&mm, t)) {
            out.push(mm);
        } else if use_animation {
            let varies = |t: &Track| t.weights.iter().any(|w| *w != t.weights[0]);
            match mm.tracks.iter().any(varies) {
                true => moves_no_vertex = true,
                false => held_one_pose = true,
            }
        }
    }
    if out.is_empty() {
        let clips = skeletal_clips(&doc.json);
        let mut hint = if moves_no_vertex {
            " (its weights animations change only targets that move no vertex: normals, texture coordinates or colours, which a viewer blends as authored)"
        } else if held_one_pose {
            " (its weights animations hold a single pose; --keys targets tweens the targets)"
        } else if not_animated {
            " (no clip animates its weights; --keys targets tweens the targets)"
        } else {
            ""
        }
        .to_string();
        if !arr(&doc.json, "skins").is_empty() && !clips.is_empty() {
            hint += &format!(
                "; it has a skinned character with {} clip{} ({}): `inbetween blend` mixes skeletal clips",
                clips.len(),
                if clips.len() == 1 { "" } else { "s" },
                listed(&clips)
            );
        }
        let msg = format!("no mesh with morph targets and at least two distinct keys{hint}");
        return Err(NoMorphKeys(doc.err(msg).to_string()).into());
    }
    Ok(out)
}

/// [`find_morph_meshes`]'s refusal of a file that reads well but holds no morph keys (as
/// against a file it cannot read): `preview` then plays the file's clips.
#[derive(Debug)]
pub struct NoMorphKeys(String);

impl std::fmt::Display for NoMorphKeys {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for NoMorphKeys {}

/// The meshes with morph targets that no weights channel animates, by index: under
/// `--keys auto` in a file that animates other meshes' weights, they keep their authored pose.
pub fn meshes_without_weights_animation(doc: &Document) -> Vec<usize> {
    let users = MeshUsers::of(&doc.json);
    (arr(&doc.json, "meshes").iter().enumerate())
        .filter(|(_, m)| {
            arr(m, "primitives")
                .iter()
                .any(|p| !arr(p, "targets").is_empty())
        })
        .filter(|(mi, _)| {
            let nodes = users.nodes.get(*mi).map_or(&[][..], Vec::as_slice);
            users.channels(nodes).is_empty()
        })
        .map(|(mi, _)| mi)
        .collect()
}

/// Mesh `mi` with its tracks, and whether they come from an animation (`clips_animate`: some
/// clip animates weights or moves a node, which `--keys auto` takes keys from); `None` when it
/// has no morph targets. Its tracks are empty where keys come from the animation and no clip (the one
/// `--animation` picks, when given) animates its weights.
fn morph_mesh(
    doc: &Document,
    mi: usize,
    users: &MeshUsers,
    opts: &KeyOptions,
    selected: Option<usize>,
    clips_animate: bool,
) -> Result<Option<(MorphMesh, bool)>> {
    let json = &doc.json;
    let mesh = &json["meshes"][mi];
    let prims = arr(mesh, "primitives");
    let target_count = prims.first().map(|p| arr(p, "targets").len()).unwrap_or(0);
    if target_count == 0 {
        return Ok(None);
    }
    let name = mesh["name"]
        .as_str()
        .map(str::to_owned)
        .unwrap_or_else(|| format!("mesh {mi}"));
    let mut primitives = Vec::new();
    for (pi, p) in prims.iter().enumerate() {
        primitives.push(read_primitive(doc, &name, pi, p, target_count)?);
    }
    let nodes = users.nodes.get(mi).cloned().unwrap_or_default();
    let channels = users.channels(&nodes);
    let use_animation = match opts.source {
        KeySource::Targets => false,
        KeySource::Animation => true,
        KeySource::Auto => clips_animate,
    };
    let (tracks, dropped) = if use_animation {
        let (tracks, dropped) = animation_tracks(doc, &channels, selected, target_count)?;
        if tracks.is_empty() && opts.source == KeySource::Animation {
            bail!(doc.err(format!(
                "--keys animation: no animation{} drives the weights of mesh {name:?}",
                opts.animation
                    .map(|a| format!(" {a:?}"))
                    .unwrap_or_default()
            )));
        }
        (tracks, dropped)
    } else {
        let dropped = channels.iter().map(|&(a, c, _)| (a, c)).collect();
        (vec![target_track(target_count, nodes)], dropped)
    };
    let mm = MorphMesh {
        mesh: mi,
        name,
        primitives,
        target_count,
        tracks,
        dropped_channels: dropped,
        normals_given: 0,
    };
    Ok(Some((mm, use_animation)))
}

/// Which nodes carry each mesh and which weights channels aim at each node, found in one pass
/// over the nodes and one over the channels (asked mesh by mesh, a file of 8,000 meshes each
/// animated by its own channel took 5 s to inspect).
struct MeshUsers {
    /// Mesh -> the nodes carrying it, in node order.
    nodes: Vec<Vec<usize>>,
    /// Node -> its weights channels: (animation, channel, sampler), in file order.
    channels: HashMap<usize, Vec<(usize, usize, usize)>>,
}

impl MeshUsers {
    fn of(json: &Value) -> MeshUsers {
        let nodes = mesh_nodes(json);
        let mut channels: HashMap<usize, Vec<(usize, usize, usize)>> = HashMap::new();
        for (ai, anim) in arr(json, "animations").iter().enumerate() {
            let shadowed = crate::gltf::shadowed(anim);
            for (ci, ch) in arr(anim, "channels").iter().enumerate() {
                if shadowed[ci] {
                    continue; // a later channel's keys play
                }
                let sampler = ch["sampler"].as_u64().unwrap_or(u64::MAX) as usize;
                let aimed: &[usize] = match weights_target(&ch["target"]) {
                    Some(WeightsTarget::Node(n)) => &[n],
                    Some(WeightsTarget::Mesh(m)) => nodes.get(m).map_or(&[], Vec::as_slice),
                    None => &[],
                };
                for &node in aimed {
                    channels.entry(node).or_default().push((ai, ci, sampler));
                }
            }
        }
        MeshUsers { nodes, channels }
    }

    /// Every weights channel aimed at one of `nodes`: (animation, channel, sampler), in file
    /// order.
    fn channels(&self, nodes: &[usize]) -> Vec<(usize, usize, usize)> {
        let mut out: Vec<(usize, usize, usize)> = nodes
            .iter()
            .filter_map(|n| self.channels.get(n))
            .flatten()
            .copied()
            .collect();
        // A channel aimed at the mesh's own weights comes once per node carrying it.
        out.sort_unstable();
        out.dedup();
        out
    }
}

/// (animation, channel) of a weights channel.
type ChannelRef = (usize, usize);

/// One track per sampler of `channels` (those of animation `selected` only, when given; the
/// others are returned as dropped channels).
fn animation_tracks(
    doc: &Document,
    channels: &[(usize, usize, usize)],
    selected: Option<usize>,
    target_count: usize,
) -> Result<(Vec<Track>, Vec<ChannelRef>)> {
    let mut tracks: Vec<Track> = Vec::new();
    let mut dropped = Vec::new();
    for &(ai, ci, si) in channels {
        if selected.is_some_and(|s| s != ai) {
            dropped.push((ai, ci));
            continue;
        }
        let same = |t: &&mut Track| matches!(&t.origin, TrackOrigin::Animation { animation, sampler, .. } if *animation == ai && *sampler == si);
        if let Some(t) = tracks.iter_mut().find(same) {
            if let TrackOrigin::Animation { channels, .. } = &mut t.origin {
                channels.push(ci);
            }
            continue;
        }
        let (times, weights, eases) = read_weight_keys(doc, ai, si, target_count)?;
        tracks.push(Track {
            origin: TrackOrigin::Animation {
                animation: ai,
                sampler: si,
                channels: vec![ci],
            },
            times,
            weights,
            eases,
        });
    }
    Ok((tracks, dropped))
}

/// `--keys targets`: key 0 the base, key k target k at weight 1, at times 0, 1, 2, ... s.
fn target_track(target_count: usize, nodes: Vec<usize>) -> Track {
    let mut weights = vec![vec![0.0; target_count]];
    for k in 0..target_count {
        let mut w = vec![0.0; target_count];
        w[k] = 1.0;
        weights.push(w);
    }
    Track {
        origin: TrackOrigin::Targets { nodes },
        times: (0..=target_count).map(|k| k as f64).collect(),
        weights,
        eases: None,
    }
}

/// Names of the animations that move nodes (translation, rotation or scale channels).
pub fn skeletal_clips(json: &Value) -> Vec<String> {
    arr(json, "animations")
        .iter()
        .enumerate()
        .filter(|(_, a)| moves_a_node(a))
        .map(|(i, a)| quoted_name(a, || i.to_string()))
        .collect()
}

/// Whether an animation has a translation, rotation or scale channel.
fn moves_a_node(anim: &Value) -> bool {
    arr(anim, "channels").iter().any(|c| {
        matches!(
            c["target"]["path"].as_str(),
            Some("translation" | "rotation" | "scale")
        )
    })
}

/// True when at least two keys of the track give different poses.
fn has_distinct_keys(mesh: &MorphMesh, track: &Track) -> bool {
    let first = &track.weights[0];
    track.weights.iter().any(|w| {
        w.iter().zip(first).enumerate().any(|(i, (a, b))| {
            a != b
                && mesh
                    .primitives
                    .iter()
                    .any(|p| p.target_pos[i].iter().any(|d| *d != DVec3::ZERO))
        })
    })
}

fn find_animation(doc: &Document, sel: &str) -> Result<usize> {
    let anims = arr(&doc.json, "animations");
    let names: Vec<String> = (anims.iter().enumerate())
        .map(|(i, a)| clip_name(a, i))
        .collect();
    match clip_by(sel, names.iter().map(String::as_str).enumerate()).map_err(|e| doc.err(e))? {
        Some(i) => Ok(i),
        None => {
            let names: Vec<String> = anims
                .iter()
                .enumerate()
                .map(|(i, a)| quoted_name(a, || i.to_string()))
                .collect();
            bail!(doc.err(format!(
                "no animation {sel:?} (the file has: {})",
                listed(&names)
            )))
        }
    }
}

fn attr(p: &Value, name: &str) -> Option<usize> {
    p["attributes"][name].as_u64().map(|v| v as usize)
}

/// A primitive's base positions and triangles.
pub type Geometry = (Vec<DVec3>, Vec<[u32; 3]>);

/// Every primitive of mesh `mi` as it is stored (base positions and triangles; targets read but
/// not applied): what the preview draws of a mesh without morph keys.
pub fn mesh_geometry(doc: &Document, mi: usize) -> Result<Vec<Geometry>> {
    let mesh = &doc.json["meshes"][mi];
    let name = mesh["name"]
        .as_str()
        .map_or_else(|| format!("mesh {mi}"), str::to_owned);
    let prims = arr(mesh, "primitives");
    let targets = prims.first().map_or(0, |p| arr(p, "targets").len());
    prims
        .iter()
        .enumerate()
        .filter(|(_, p)| p["mode"].as_u64().unwrap_or(4) == 4)
        .map(|(pi, p)| read_primitive(doc, &name, pi, p, targets).map(|p| (p.base, p.triangles)))
        .collect()
}

fn read_primitive(
    doc: &Document,
    mesh: &str,
    pi: usize,
    p: &Value,
    target_count: usize,
) -> Result<Primitive> {
    let what = |s: &str| format!("mesh {mesh:?} primitive {pi} {s}");
    let pos = attr(p, "POSITION").ok_or_else(|| doc.err(what("has no POSITION")))?;
    let base = read_vec3(doc, pos, &what("POSITION"))?;
    let n = base.len();
    let here = what("").trim_end().to_string();
    let normals = read_attribute3(doc, p, "NORMAL", n, &here)?;
    let tangents = read_attribute(doc, p, "TANGENT", 4, n, &here)?.map(|v| {
        v.chunks_exact(4)
            .map(|c| [c[0], c[1], c[2], c[3]])
            .collect()
    });
    let targets = arr(p, "targets");
    if targets.len() != target_count {
        bail!(doc.err(what(&format!(
            "has {} morph targets but primitive 0 has {target_count}",
            targets.len()
        ))));
    }
    let delta = |ti: usize, t: &Value, name: &str| -> Result<Option<Vec<DVec3>>> {
        let Some(a) = t[name].as_u64() else {
            return Ok(None);
        };
        let d = read_vec3(doc, a as usize, &what(&format!("target {ti} {name}")))?;
        if d.len() != n {
            bail!(doc.err(what(&format!(
                "target {ti} has {} {name} deltas but the base has {n} vertices",
                d.len()
            ))));
        }
        Ok(Some(d))
    };
    let (mut target_pos, mut target_nrm, mut target_tan) = (Vec::new(), Vec::new(), Vec::new());
    for (ti, t) in targets.iter().enumerate() {
        target_pos.push(delta(ti, t, "POSITION")?.unwrap_or_else(|| vec![DVec3::ZERO; n]));
        target_nrm.push(delta(ti, t, "NORMAL")?);
        target_tan.push(delta(ti, t, "TANGENT")?);
    }
    let target_other = other_deltas(doc, targets, n, &what)?;
    let triangles = read_triangles(doc, p, n, &what(""))?;
    Ok(Primitive {
        index: pi,
        base,
        normals,
        tangents,
        target_pos,
        target_nrm,
        target_tan,
        target_other,
        triangles,
    })
}

/// The targets' attributes other than POSITION, NORMAL and TANGENT, each read as stored
/// (float or normalized integers) with the components its first accessor has.
fn other_deltas(
    doc: &Document,
    targets: &[Value],
    n: usize,
    what: &dyn Fn(&str) -> String,
) -> Result<Vec<OtherDeltas>> {
    let names: std::collections::BTreeSet<&str> = targets
        .iter()
        .filter_map(Value::as_object)
        .flat_map(|t| t.keys().map(String::as_str))
        .filter(|k| !matches!(*k, "POSITION" | "NORMAL" | "TANGENT"))
        .collect();
    let mut out = Vec::new();
    for name in names {
        let mut other = OtherDeltas {
            name: name.to_string(),
            components: 0,
            deltas: Vec::new(),
        };
        for (ti, t) in targets.iter().enumerate() {
            let Some(a) = t[name].as_u64() else {
                other.deltas.push(None);
                continue;
            };
            let (v, c) = doc.read_f64(a as usize)?;
            if other.components == 0 {
                other.components = c;
            }
            if c != other.components || v.len() != n * c {
                bail!(doc.err(what(&format!(
                    "target {ti} {name} (accessor {a}) has {} values of {c} components; the base has {n} vertices and target {name}s have {} components",
                    v.len() / c.max(1),
                    other.components
                ))));
            }
            other
                .deltas
                .push(Some(v.into_iter().map(|x| x as f32).collect()));
        }
        out.push(other);
    }
    Ok(out)
}

/// Key times and weights of sampler `si` of animation `ai`, and a CUBICSPLINE sampler's in-
/// and out-tangents (see [`Track::eases`]).
type WeightKeys = (Vec<f64>, Vec<Vec<f64>>, Option<Vec<[Vec<f64>; 2]>>);

fn read_weight_keys(
    doc: &Document,
    ai: usize,
    si: usize,
    target_count: usize,
) -> Result<WeightKeys> {
    let s = &doc.json["animations"][ai]["samplers"][si];
    let what = format!("animation {ai} sampler {si}");
    let (input, output) = match (s["input"].as_u64(), s["output"].as_u64()) {
        (Some(i), Some(o)) => (i as usize, o as usize),
        _ => bail!(doc.err(format!("{what} has no input or output accessor"))),
    };
    let (times, _) = doc.read_f64_as_stored(input)?;
    let (values, _) = doc.read_f64_as_stored(output)?;
    let cubic = s["interpolation"].as_str() == Some("CUBICSPLINE");
    let per_key = if cubic {
        3 * target_count
    } else {
        target_count
    };
    if values.len() != times.len() * per_key {
        bail!(doc.err(format!(
            "{what} has {} weight values for {} keys and {target_count} targets",
            values.len(),
            times.len()
        )));
    }
    // Keys holding a NaN or infinite time or weight are left out (`defined_keys`).
    let defined = defined_keys(&times, &values, per_key, None);
    let (times, values) = defined_only(&times, &values, per_key, &defined);
    let k = times.len();
    if k == 0 {
        bail!(doc.err(format!(
            "{what} has no keys (none whose time and weights are numbers)"
        )));
    }
    if times.windows(2).any(|w| w[1] < w[0]) {
        bail!(doc.err(format!("{what} key times are not increasing")));
    }
    // A CUBICSPLINE key is its in-tangent, its value and its out-tangent.
    let part = |i: usize, p: usize| {
        let at = i * per_key + p * target_count;
        values[at..at + target_count].to_vec()
    };
    let weights = (0..k).map(|i| part(i, cubic as usize)).collect();
    let eases = cubic.then(|| (0..k).map(|i| [part(i, 0), part(i, 2)]).collect());
    // Key times on a frame grid within float32 precision are taken as the grid's.
    Ok((snap(&times).0, weights, eases))
}
