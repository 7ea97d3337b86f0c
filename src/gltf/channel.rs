//! Animation channels as the file keys them: a node's translation, rotation, scale or morph
//! weights, read from their samplers (STEP, LINEAR, CUBICSPLINE) and evaluated at any time as
//! glTF asks (rotations by shortest-path slerp, cubic Hermite rotations normalised). Read by
//! `blend` for the clips it mixes and by the USD stage for the node motion it carries.

use super::{arr, node_target, Document};
use anyhow::{bail, Result};
use glam::{DMat4, DQuat, DVec3};
use serde_json::Value;

/// A rotation key shorter than this (unitless) is no rotation at all (a zero-filled accessor):
/// refused rather than normalised into NaN.
pub const MIN_QUATERNION: f64 = 1e-6;

/// An animation's name, or `animation <index>` when it has none.
pub fn clip_name(anim: &Value, index: usize) -> String {
    anim["name"]
        .as_str()
        .map_or_else(|| format!("animation {index}"), str::to_owned)
}

/// The clip `sel` picks among `clips` (each an animation's index in the file and its name, as
/// [`clip_name`] gives it): the one named `sel`, else the one at index `sel` in the file;
/// `Ok(None)` where none is. glTF does not ask names to be unique (files merged from several
/// carry one name many times; Mixamo names every clip "mixamo.com"): a name several clips
/// carry picks none, and the error names their indices, by which each can be picked.
pub fn clip_by<'a>(
    sel: &str,
    clips: impl Iterator<Item = (usize, &'a str)>,
) -> std::result::Result<Option<usize>, String> {
    let clips: Vec<(usize, &str)> = clips.collect();
    let named: Vec<String> = (clips.iter())
        .filter(|(_, name)| *name == sel)
        .map(|(i, _)| i.to_string())
        .collect();
    match named.len() {
        0 => Ok(sel
            .parse::<usize>()
            .ok()
            .filter(|i| clips.iter().any(|(c, _)| c == i))),
        1 => Ok(named[0].parse().ok()),
        n => Err(format!(
            "{n} animations are named {sel:?} (animations {}): name one by its index",
            super::read::listed(&named)
        )),
    }
}

/// A sampler's keys (`times`, and `values` with the same count per key) closed into a loop at
/// `end` (`--loop`): the first key again there, its tangents flat for a CUBICSPLINE sampler;
/// nothing when the keys already reach `end`.
pub fn close_keys(times: &mut Vec<f64>, values: &mut Vec<f64>, cubic: bool, end: f64) {
    if times.last().is_none_or(|&t| t >= end) {
        return;
    }
    let per_key = values.len() / times.len();
    // A CUBICSPLINE key is in-tangent, value, out-tangent.
    let (from, width) = match cubic {
        true => (per_key / 3, per_key / 3),
        false => (0, per_key),
    };
    let first = values[from..from + width].to_vec();
    push_key(times, values, cubic, end, &first);
}

/// A key at `t` holding `value` appended to a sampler's keys; a CUBICSPLINE key gets flat
/// tangents.
pub fn push_key(times: &mut Vec<f64>, values: &mut Vec<f64>, cubic: bool, t: f64, value: &[f64]) {
    if cubic {
        values.extend(std::iter::repeat_n(0.0, value.len()));
        values.extend_from_slice(value);
        values.extend(std::iter::repeat_n(0.0, value.len()));
    } else {
        values.extend_from_slice(value);
    }
    times.push(t);
}

/// What a channel animates.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Path {
    Translation,
    Rotation,
    Scale,
    Weights,
}

impl Path {
    pub fn name(self) -> &'static str {
        match self {
            Path::Translation => "translation",
            Path::Rotation => "rotation",
            Path::Scale => "scale",
            Path::Weights => "weights",
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interp {
    Step,
    Linear,
    Cubic,
}

/// One animated property: keys and values (`width` numbers per key; CUBICSPLINE keeps its
/// in-tangent, value, out-tangent triples).
#[derive(Clone, Debug)]
pub struct Channel {
    pub node: usize,
    pub path: Path,
    pub interp: Interp,
    pub times: Vec<f64>,
    pub values: Vec<f64>,
    pub width: usize,
}

impl Channel {
    /// The value at time `t` (clamped to the keys).
    pub fn sample(&self, t: f64, out: &mut [f64]) {
        let w = self.width;
        let per_key = if self.interp == Interp::Cubic {
            3 * w
        } else {
            w
        };
        let value = |k: usize, part: usize| &self.values[k * per_key + part * w..][..w];
        let mid = if self.interp == Interp::Cubic { 1 } else { 0 };
        let n = self.times.len();
        if n == 1 || t <= self.times[0] {
            out.copy_from_slice(value(0, mid));
            return;
        }
        if t >= self.times[n - 1] {
            out.copy_from_slice(value(n - 1, mid));
            return;
        }
        let k = self.times.partition_point(|&x| x <= t) - 1;
        let (t0, t1) = (self.times[k], self.times[k + 1]);
        let dt = t1 - t0;
        let u = if dt > 0.0 { (t - t0) / dt } else { 0.0 };
        match self.interp {
            Interp::Step => out.copy_from_slice(value(k, 0)),
            Interp::Linear => {
                let (a, b) = (value(k, 0), value(k + 1, 0));
                if self.path == Path::Rotation {
                    let qa = DQuat::from_xyzw(a[0], a[1], a[2], a[3]);
                    let qb = DQuat::from_xyzw(b[0], b[1], b[2], b[3]);
                    let q = slerp(qa, qb, u);
                    out.copy_from_slice(&q.to_array());
                } else {
                    for c in 0..w {
                        out[c] = a[c] + (b[c] - a[c]) * u;
                    }
                }
            }
            Interp::Cubic => {
                let (p0, m0) = (value(k, 1), value(k, 2));
                let (p1, m1) = (value(k + 1, 1), value(k + 1, 0));
                let (u2, u3) = (u * u, u * u * u);
                let h00 = 2.0 * u3 - 3.0 * u2 + 1.0;
                let h10 = u3 - 2.0 * u2 + u;
                let h01 = -2.0 * u3 + 3.0 * u2;
                let h11 = u3 - u2;
                for c in 0..w {
                    out[c] = h00 * p0[c] + h10 * dt * m0[c] + h01 * p1[c] + h11 * dt * m1[c];
                }
                if self.path == Path::Rotation {
                    let q = DQuat::from_slice(out).normalize();
                    out.copy_from_slice(&q.to_array());
                }
            }
        }
    }
}

/// Shortest-path spherical interpolation (the hemisphere of `b` is flipped to `a`'s).
pub fn slerp(a: DQuat, b: DQuat, u: f64) -> DQuat {
    let b = if a.dot(b) < 0.0 { -b } else { b };
    a.slerp(b, u).normalize()
}

/// The channels of animation `anim` (named `name` in errors) that animate a node's
/// translation, rotation, scale or weights (by `node` and `path`, or a `KHR_animation_pointer`
/// aimed at `/nodes/N/...`), in the file's order; `nodes` is the node count. Channels aimed
/// elsewhere (a material's or a light's property) are passed over.
pub fn read_channels(
    doc: &Document,
    name: &str,
    anim: &Value,
    nodes: usize,
) -> Result<Vec<Channel>> {
    let samplers = arr(anim, "samplers");
    let mut channels = Vec::new();
    let shadowed = super::mend::shadowed(anim);
    for (ch, _) in arr(anim, "channels")
        .iter()
        .zip(shadowed)
        .filter(|(_, s)| !s)
    {
        // A node's property, by `node` and `path` or through KHR_animation_pointer; a
        // pointer to anything else (a material's colour, a light) is no node's.
        let Some((node, property)) = node_target(&ch["target"]) else {
            continue;
        };
        let path = match property {
            "translation" => Path::Translation,
            "rotation" => Path::Rotation,
            "scale" => Path::Scale,
            "weights" => Path::Weights,
            _ => continue,
        };
        if node >= nodes {
            bail!(doc.err(format!(
                "animation {name:?} targets node {node}, which does not exist"
            )));
        }
        let s = ch["sampler"]
            .as_u64()
            .and_then(|s| samplers.get(s as usize))
            .ok_or_else(|| {
                doc.err(format!(
                    "animation {name:?} has a channel without a sampler"
                ))
            })?;
        let interp = match s["interpolation"].as_str().unwrap_or("LINEAR") {
            "STEP" => Interp::Step,
            "CUBICSPLINE" => Interp::Cubic,
            _ => Interp::Linear,
        };
        let input = s["input"].as_u64().unwrap_or(u64::MAX) as usize;
        let output = s["output"].as_u64().unwrap_or(u64::MAX) as usize;
        let (times, _) = doc.read_f64_as_stored(input)?;
        let (values, ncomp) = doc.read_f64_as_stored(output)?;
        if times.is_empty() {
            bail!(doc.err(format!("animation {name:?} has a sampler without keys")));
        }
        let per_key_values =
            values.len() / times.len() / if interp == Interp::Cubic { 3 } else { 1 };
        let width = match path {
            Path::Weights => per_key_values,
            Path::Rotation => 4,
            _ => 3,
        };
        if path != Path::Weights && ncomp != width || per_key_values != width || width == 0 {
            bail!(doc.err(format!(
                "animation {name:?}: the {} values of node {node} do not match its {} keys",
                path.name(),
                times.len()
            )));
        }
        let (per_key, mid) = match interp {
            Interp::Cubic => (3 * width, width),
            _ => (width, 0),
        };
        let rotation = (path == Path::Rotation).then_some(mid);
        let defined = defined_keys(&times, &values, per_key, rotation);
        if !defined.contains(&true) {
            bail!(doc.err(format!(
                "animation {name:?}: no {} key of node {node} (accessor {output}) is defined: each is NaN, infinite{}",
                path.name(),
                if rotation.is_some() { " or not a unit quaternion" } else { "" }
            )));
        }
        let (times, mut values) = defined_only(&times, &values, per_key, &defined);
        // Equal times (glTF asks for increasing ones; some writers repeat a time) are a step
        // to the later key there, as `Channel::sample` and players read them.
        if times.windows(2).any(|w| w[1] < w[0]) {
            bail!(doc.err(format!(
                "animation {name:?}: the key times of accessor {input} decrease"
            )));
        }
        if let Some(mid) = rotation {
            unit_keys(&mut values, per_key, mid);
        }
        channels.push(Channel {
            node,
            path,
            interp,
            times,
            values,
            width,
        });
    }
    Ok(channels)
}

/// Which keys of a sampler are defined: the key's time and every value of it (`per_key` a key,
/// a CUBICSPLINE key's tangents with it) finite, and where `rotation` gives where a key's
/// quaternion starts, that quaternion not zero. An exporter that divides a zero by its length
/// writes NaN keys (COLLADA2GLTF's of a Modo character: glTF issue 219; ValveResourceFormat's
/// bones, its issue 309), which players turn into no pose at all (three.js draws nothing
/// there); the readers and the output leave them out, the keys beside them played across.
pub fn defined_keys(
    times: &[f64],
    values: &[f64],
    per_key: usize,
    rotation: Option<usize>,
) -> Vec<bool> {
    (times.iter().zip(values.chunks_exact(per_key.max(1))))
        .map(|(t, k)| {
            t.is_finite()
                && k.iter().all(|x| x.is_finite())
                && rotation
                    .is_none_or(|at| DQuat::from_slice(&k[at..at + 4]).length() >= MIN_QUATERNION)
        })
        .collect()
}

/// The times and values (`per_key` a key) of the keys `defined` marks.
pub fn defined_only(
    times: &[f64],
    values: &[f64],
    per_key: usize,
    defined: &[bool],
) -> (Vec<f64>, Vec<f64>) {
    let kept = |i: &usize| defined[*i];
    let times = (0..times.len()).filter(kept).map(|i| times[i]).collect();
    let values = (0..defined.len())
        .filter(kept)
        .flat_map(|i| values[i * per_key..(i + 1) * per_key].iter().copied())
        .collect();
    (times, values)
}

/// A rotation key farther from unit length than float32 rounding leaves one: some exporters
/// write such keys (the validator refuses them beyond 0.0077), and a player's slerp between
/// them turns by another angle than between the rotations they stand for.
const UNIT_KEY: f64 = 1e-6;

/// Divide each rotation key of `values` (`per_key` numbers a key, its quaternion from `mid`;
/// a CUBICSPLINE key's tangents with it) farther than [`UNIT_KEY`] from unit length by its
/// length, as the output's keys are written (`mend::rotations`).
fn unit_keys(values: &mut [f64], per_key: usize, mid: usize) {
    for key in values.chunks_exact_mut(per_key) {
        let length = DQuat::from_slice(&key[mid..mid + 4]).length();
        if (length - 1.0).abs() > UNIT_KEY {
            key.iter_mut().for_each(|x| *x /= length);
        }
    }
}

/// Each node's parent (the node listing it among its `children`; the last such where a broken
/// file lists it twice), `None` for a root.
pub fn node_parents(json: &Value) -> Vec<Option<usize>> {
    let nodes = arr(json, "nodes");
    let mut parents = vec![None; nodes.len()];
    for (i, n) in nodes.iter().enumerate() {
        for c in arr(n, "children").iter().filter_map(Value::as_u64) {
            if let Some(x) = parents.get_mut(c as usize) {
                *x = Some(i);
            }
        }
    }
    parents
}

/// A node's `matrix`, where it has one of 16 numbers.
fn matrix_of(node: &Value) -> Option<DMat4> {
    let m: Vec<f64> = node["matrix"]
        .as_array()?
        .iter()
        .filter_map(Value::as_f64)
        .collect();
    (m.len() == 16).then(|| DMat4::from_cols_slice(&m))
}

/// A node's rest transform: its `matrix`, else its translation, rotation and scale.
pub fn rest_matrix(node: &Value) -> DMat4 {
    matrix_of(node).unwrap_or_else(|| {
        let (t, r, s) = rest_trs(node);
        DMat4::from_scale_rotation_translation(s, r, t)
    })
}

/// A node's local transform at time `t` (seconds): its rest translation, rotation and scale
/// (`rest`, from [`rest_trs`], read once per node) with those its `channels` (of one clip)
/// key sampled at `t` in their place; weights channels are passed over.
pub fn local_at<'c>(
    rest: (DVec3, DQuat, DVec3),
    channels: impl IntoIterator<Item = &'c Channel>,
    t: f64,
) -> DMat4 {
    let (mut tr, mut r, mut s) = rest;
    let mut buf = [0.0f64; 4];
    for c in channels {
        if c.path == Path::Weights || c.width > buf.len() {
            continue;
        }
        let v = &mut buf[..c.width];
        c.sample(t, v);
        match c.path {
            Path::Translation => tr = DVec3::new(v[0], v[1], v[2]),
            Path::Rotation => r = DQuat::from_slice(v).normalize(),
            Path::Scale => s = DVec3::new(v[0], v[1], v[2]),
            Path::Weights => {}
        }
    }
    DMat4::from_scale_rotation_translation(s, r, tr)
}

/// A node's rest translation, rotation and scale (its `matrix` decomposed when it has one).
pub fn rest_trs(node: &Value) -> (DVec3, DQuat, DVec3) {
    let nums = |k: &str| -> Option<Vec<f64>> {
        node[k]
            .as_array()
            .map(|a| a.iter().filter_map(Value::as_f64).collect())
    };
    if let Some(m) = matrix_of(node) {
        let (s, r, t) = m.to_scale_rotation_translation();
        return (t, r, s);
    }
    let t = nums("translation")
        .filter(|v| v.len() == 3)
        .map_or(DVec3::ZERO, |v| DVec3::new(v[0], v[1], v[2]));
    let r = nums("rotation")
        .filter(|v| v.len() == 4)
        .map_or(DQuat::IDENTITY, |v| {
            DQuat::from_xyzw(v[0], v[1], v[2], v[3]).normalize()
        });
    let s = nums("scale")
        .filter(|v| v.len() == 3)
        .map_or(DVec3::ONE, |v| DVec3::new(v[0], v[1], v[2]));
    (t, r, s)
}
