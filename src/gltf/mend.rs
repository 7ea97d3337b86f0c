//! Mend stage (on write): data the glTF specification constrains that an input breaks, made
//! right as the input is copied into the output, so that the Khronos validator accepts what we
//! write. Each fix is what every viewer that copes with the broken data does anyway; a line
//! names it where it is more than a codec's rounding.
//!
//! **Skin weights** ([`weights`]) must sum to one. Two kinds of file break the rule, and the
//! output would carry it: exporters that write weights summing to something else (FBX2glTF's
//! RobotExpressive: its hands up to 1.76, 752 validator errors), and Draco-compressed weights,
//! which decode with the codec's quantization in them (glTF-Transform `draco` at its default 12
//! bits: sums 1 +- 2.5e-4; the validator cannot look inside Draco, so the input passes and the
//! decoded output did not, 30-318 errors on the skinned fixtures). three.js's loader, Blender
//! and our own USD point cache divide by the sum: they show the same pose before and after.
//!
//! The check is the validator's own: per vertex, the weights of its distinct joints summed in
//! single precision, in attribute order, within [`PER_INFLUENCE`] times the influences of 1
//! (glTF-Validator 2.0.0-dev.3.10, the one the tests run; its source's other rule, [`SUM_STEP`]
//! times (influences / 2, rounded up, less one), exactly 1 for one or two influences, is
//! checked too). A vertex that fails is divided by its sum and its largest weight then moved
//! by single-precision steps until the sum passes. Normalized integer weights (8 or 16 bits) are
//! read as the validator reads them, each over its type's largest value; a vertex that fails is
//! made to sum to exactly that value, each weight its share rounded down and the units left
//! over given to the largest remainders (an exporter that rounds each weight alone sums to
//! 253/255-257/255: 202-320 errors on Fox and CesiumMan so written; gltfpack and glTF-Transform
//! make their sums whole). A joint with weight 0 is made joint 0 (the validator warns of one
//! that is not, which Draco leaves where it rounds a small weight to nothing: RobotExpressive's
//! hands, 5 warnings). A joint a vertex names twice (the validator's
//! ACCESSOR_JOINTS_INDEX_DUPLICATE) gets the two weights added in its first place (skinning
//! is linear in each joint's weight: the same pose). A vertex with a negative weight or no
//! weight at all is left as it is (normalizing cannot mend those).
//!
//! **Accessor bounds** ([`bounds`]): a float accessor's declared `min` and `max` must be its
//! values' (gltf-pipeline 4's Draco on a Blender morph file declared a target's max 0 where its
//! values reach 1.2): each component whose declared bound, read as a float, differs from the
//! values' is written as theirs; bounds right to a float's precision stay as written. SCALAR,
//! VEC2 and VEC3 from the input's values; the VEC4 skin weights, joints and rotation keys the
//! mends above may change, from the values written, integers as stored (assimp declares bounds
//! on every accessor, right for its weights before they were divided by their sums: 18-21
//! errors per blend).
//! Bounds glTF requires and a writer left out (every POSITION's, a morph target's included,
//! and every sampler's key times) are written from the values of a float accessor.
//!
//! **Sparse parts** ([`sparse_parts`]): a buffer view that only sparse parts use loses
//! `byteStride` and `target` (only vertex data may have them); a float sparse accessor whose
//! parts lie in a view that other accessors read as vertex data (the same writer's) is written
//! dense, as it decodes.
//!
//! **Rotation keys** ([`rotations`]) must be unit quaternions: a key farther from unit length
//! than the validator allows ([`UNIT_LENGTH`]) is divided by its length (a CUBICSPLINE key's
//! tangents by the same), as a player's slerp does; float outputs of `rotation` channels only.
//!
//! **Key times** ([`key_times`]) must increase: a time equal to the one before (an exporter's
//! hold, two samples of a bake rounded to one time), which the readers take as a step to the
//! later key, is moved a single-precision step on (the run's last back from a clip's end), the
//! first and last times kept so the accessor's bounds hold. A time that goes back is left (the
//! readers refuse it on a node's channel).
//!
//! **Normals** ([`normals`]) must be unit vectors: a float NORMAL attribute's vector farther
//! from unit length than the validator allows ([`UNIT_NORMAL`]) is divided by its length; a
//! zero (or not finite) one, which no division mends, is its vertex's area-weighted face normal
//! in its primitive (Babylon.js 9's export of Fox: 994 zero normals its outputs carried). What
//! a renderer shows there was undefined, black in three.js. Primitives without morph targets
//! only: a morph primitive's targets (and the frames `tween` adds) carry NORMAL deltas from
//! its normals as they were, which a different base would turn.
//!
//! **Indices** ([`restart_indices`]) must not hold the primitive restart value (255 in 8
//! bits, 65535 in 16): WebGL 2 always restarts there, so a writer that numbers 65,536 vertices
//! in 16 bits loses the triangles of its last; such an accessor is written as 32-bit indices.
//!
//! **Strides** ([`strides`]): only vertex data may be read through a `byteStride`; a view of
//! key times or values, inverse bind matrices, indices or an image loses it (Sketchfab's
//! exports and the old Khronos Fox stride their animation data), an accessor there whose
//! elements it spaced out first copied packed into a view of its own.
//!
//! **Empty animations** ([`empty_animations`], [`drop_empty_animations`]): an animation must
//! have a channel and a sampler (assimp 5.2's glTF-to-glTF export keeps a morph file's clip
//! with neither, having lost its weights): left out of the output, which plays the same. So
//! is a channel that repeats another's target and sampler ([`repeated_channels`],
//! [`drop_repeated_channels`]): glTF allows one channel a target, and the other plays the
//! same keys. Repeats on other samplers (which keys win is each player's choice) are left.

use super::accessor::{read_triangles, read_vec3};
use super::build::{f32_json, min_max, set_bounds, BinBuilder};
use super::read::{arr, listed, quoted_name, Document};
use serde_json::Value;
use std::collections::BTreeMap;

/// The validator's tolerance per influence (its release 2.0.0-dev.3.10).
const PER_INFLUENCE: f64 = 2e-7;

/// The validator's step of tolerance per two influences in its source's other rule: a little
/// over 1/255, the error of 8-bit quantization.
const SUM_STEP: f64 = 0.0039216;

/// Sums farther than this from 1 are named in a warning line (an exporter's error); nearer,
/// they are a codec's quantization and mended without a word.
const SAID_ABOVE: f64 = SUM_STEP;

/// Where one VEC3 or VEC4 attribute's elements lie in the output buffer.
#[derive(Clone, Copy)]
struct Column {
    start: usize,
    stride: usize,
    component: u64,
    /// Bytes of one component.
    size: usize,
}

impl Column {
    /// Attribute `acc` of `json` with its data in `bin` (views placed by `write::begin`), when
    /// it is a plain (not sparse) VEC4 accessor of `count` elements inside the buffer.
    fn of(json: &Value, bin: &BinBuilder, acc: usize, count: usize) -> Option<Column> {
        Column::of_width(json, bin, acc, count, 4)
    }

    /// As [`Column::of`], for a plain accessor of `width` components (SCALAR, VEC3, VEC4).
    fn of_width(
        json: &Value,
        bin: &BinBuilder,
        acc: usize,
        count: usize,
        width: u64,
    ) -> Option<Column> {
        let a = &json["accessors"][acc];
        let component = a["componentType"].as_u64()?;
        let size: u64 = match component {
            5121 => 1,
            5123 => 2,
            5126 => 4,
            _ => return None,
        };
        let ty = match width {
            1 => "SCALAR",
            3 => "VEC3",
            _ => "VEC4",
        };
        if a["type"].as_str() != Some(ty)
            || a.get("sparse").is_some()
            || a["count"].as_u64() != Some(count as u64)
        {
            return None;
        }
        let v = a["bufferView"].as_u64()? as usize;
        let view = bin.views.get(v)?;
        // Checked: a hostile file's counts and offsets must not wrap past the bounds test.
        let start = view["byteOffset"]
            .as_u64()?
            .checked_add(a["byteOffset"].as_u64().unwrap_or(0))?;
        let stride = view["byteStride"].as_u64().unwrap_or(width * size);
        let end = (count as u64)
            .checked_sub(1)?
            .checked_mul(stride)?
            .checked_add(start)?
            .checked_add(width * size)?;
        let view_end = view["byteOffset"]
            .as_u64()?
            .checked_add(view["byteLength"].as_u64()?)?;
        let (start, stride, size) = (start as usize, stride as usize, size as usize);
        (stride >= width as usize * size && end <= view_end && end <= bin.bytes.len() as u64)
            .then_some(Column {
                start,
                stride,
                component,
                size,
            })
    }

    fn at(&self, i: usize, c: usize) -> usize {
        self.start + i * self.stride + c * self.size
    }

    fn uint(&self, bytes: &[u8], i: usize, c: usize) -> u32 {
        let p = self.at(i, c);
        match self.component {
            5121 => bytes[p] as u32,
            _ => u16::from_le_bytes([bytes[p], bytes[p + 1]]) as u32,
        }
    }

    fn set_uint(&self, bytes: &mut [u8], i: usize, c: usize, j: u32) {
        let p = self.at(i, c);
        match self.component {
            5121 => bytes[p] = j as u8,
            _ => bytes[p..p + 2].copy_from_slice(&(j as u16).to_le_bytes()),
        }
    }

    fn float(&self, bytes: &[u8], i: usize, c: usize) -> f32 {
        let p = self.at(i, c);
        f32::from_le_bytes(bytes[p..p + 4].try_into().unwrap())
    }

    fn set_float(&self, bytes: &mut [u8], i: usize, c: usize, w: f32) {
        let p = self.at(i, c);
        bytes[p..p + 4].copy_from_slice(&w.to_le_bytes());
    }
}

/// Whether weights `w` of joints `j` (each as the validator reads it: a float's value, a
/// normalized integer's over its type's largest) sum to one as the validator reckons it:
/// `None` where normalizing cannot mend them (a negative weight, a joint twice, no weight).
fn sums_to_one(w: impl IntoIterator<Item = f64>, j: &[u32]) -> Option<bool> {
    let (mut sum, mut seen) = (0f32, Vec::with_capacity(j.len()));
    for (w, &j) in w.into_iter().zip(j) {
        if w == 0.0 {
            continue;
        }
        if w < 0.0 || !w.is_finite() || seen.contains(&j) {
            return None;
        }
        seen.push(j);
        sum = (sum as f64 + w) as f32;
    }
    if seen.is_empty() {
        return None;
    }
    let n = seen.len();
    let tolerance = (PER_INFLUENCE * n as f64).min(SUM_STEP * (n.div_ceil(2) - 1) as f64);
    Some((sum as f64 - 1.0).abs() <= tolerance)
}

/// [`sums_to_one`] of float weights.
fn floats_sum_to_one(w: &[f32], j: &[u32]) -> Option<bool> {
    sums_to_one(w.iter().map(|&x| x as f64), j)
}

/// [`sums_to_one`] of normalized integer weights `k`, `unit` their type's largest (255, 65535).
fn units_sum_to_one(k: &[u32], unit: u32, j: &[u32]) -> Option<bool> {
    sums_to_one(k.iter().map(|&x| x as f64 / unit as f64), j)
}

/// Normalized integer weights `k` scaled to sum to exactly `unit` (their type's largest):
/// each its share rounded down, the units left over given to the largest remainders (the
/// earlier first where they tie). Zero weights stay zero.
fn normalized_units(k: &mut [u32], unit: u32) {
    let sum: u64 = k.iter().map(|&x| x as u64).sum();
    if sum == 0 {
        return;
    }
    let share = |x: u32| x as u64 * unit as u64;
    let mut order: Vec<usize> = (0..k.len()).collect();
    // Remainders compared exactly, as numerators over `sum`.
    order.sort_by_key(|&i| std::cmp::Reverse(share(k[i]) % sum));
    let floors: Vec<u64> = k.iter().map(|&x| share(x) / sum).collect();
    let left = unit as u64 - floors.iter().sum::<u64>();
    for (i, f) in floors.iter().enumerate() {
        k[i] = *f as u32;
    }
    for &i in order.iter().take(left as usize) {
        k[i] += 1;
    }
}

/// Weights `w` divided by their sum, their largest then stepped until [`sums_to_one`] passes.
fn normalized(w: &mut [f32], j: &[u32]) {
    let sum: f64 = w.iter().map(|&x| x as f64).sum();
    for x in w.iter_mut() {
        *x = (*x as f64 / sum) as f32;
    }
    let k = (0..w.len()).fold(0, |k, i| if w[i] > w[k] { i } else { k });
    for _ in 0..64 {
        if floats_sum_to_one(w, j) != Some(false) {
            return;
        }
        let rest: f64 = (w.iter().enumerate())
            .filter(|&(i, _)| i != k)
            .map(|(_, &x)| x as f64)
            .sum();
        let want = (1.0 - rest) as f32;
        w[k] = match want == w[k] {
            // One single-precision step towards the sum's shortfall.
            true => {
                let total: f32 = w.iter().fold(0f32, |s, &x| (s as f64 + x as f64) as f32);
                let bits = w[k].to_bits();
                f32::from_bits(if total < 1.0 { bits + 1 } else { bits - 1 })
            }
            false => want,
        };
    }
}

/// Every mend, in place in `bin` (the views placed by `write::begin`) and, for the bounds of
/// the data they change, `json`; returns the lines.
pub fn all(json: &mut Value, bin: &mut BinBuilder) -> Vec<String> {
    let mut lines = weights(json, bin);
    lines.extend(rotations(json, bin));
    lines.extend(key_times(json, bin));
    lines.extend(restart_indices(json, bin));
    lines.extend(strides(json, bin));
    rebound_vec4(json, bin);
    lines
}

/// The views that vertex data reads (every primitive's and morph target's attributes, and
/// `EXT_mesh_gpu_instancing`'s): the only ones glTF lets have a `byteStride`.
fn vertex_views(json: &Value) -> std::collections::BTreeSet<u64> {
    let mut accessors = Vec::new();
    for mesh in arr(json, "meshes") {
        for p in arr(mesh, "primitives") {
            for attrs in std::iter::once(&p["attributes"]).chain(arr(p, "targets")) {
                accessors.extend(attrs.as_object().into_iter().flatten().map(|(_, a)| a));
            }
        }
    }
    for node in arr(json, "nodes") {
        let attrs = &node["extensions"]["EXT_mesh_gpu_instancing"]["attributes"];
        accessors.extend(attrs.as_object().into_iter().flatten().map(|(_, a)| a));
    }
    (accessors.into_iter())
        .filter_map(|a| json["accessors"][a.as_u64()? as usize]["bufferView"].as_u64())
        .collect()
}

/// A `byteStride` on a view that no vertex data reads (key times and values, inverse bind
/// matrices, indices, images: the validator's ..._WITH_BYTESTRIDE errors; Sketchfab's
/// exports and the old Khronos Fox stride their animation data) removed from it in `bin`; an
/// accessor there whose elements the stride spaced out (interleaved) is first copied packed
/// into a view of its own. Returns a line naming the views.
pub fn strides(json: &mut Value, bin: &mut BinBuilder) -> Vec<String> {
    // Views that sparse parts use are [`sparse_parts`]' to mend.
    let mut left = vertex_views(json);
    for a in arr(json, "accessors") {
        for part in ["indices", "values"] {
            left.extend(a["sparse"][part]["bufferView"].as_u64());
        }
    }
    let strided: Vec<usize> = (0..bin.views.len())
        .filter(|&v| bin.views[v].get("byteStride").is_some() && !left.contains(&(v as u64)))
        .collect();
    for &v in &strided {
        let stride = bin.views[v]["byteStride"].as_u64().unwrap_or(0) as usize;
        for a in 0..arr(json, "accessors").len() {
            let acc = &json["accessors"][a];
            if acc["bufferView"].as_u64() != Some(v as u64) {
                continue;
            }
            let size = (acc["componentType"].as_u64())
                .and_then(|t| super::accessor::comp_size(t as u32))
                .zip(acc["type"].as_str().and_then(super::accessor::components))
                .map(|(c, n)| c * n);
            let count = acc["count"].as_u64().unwrap_or(0) as usize;
            let Some(size) = size.filter(|&size| size != stride && count > 0) else {
                continue;
            };
            let start = (bin.views[v]["byteOffset"].as_u64().unwrap_or(0)
                + acc["byteOffset"].as_u64().unwrap_or(0)) as usize;
            let end = start + (count - 1) * stride + size;
            if stride < size || end > bin.bytes.len() {
                continue;
            }
            let packed: Vec<u8> = (0..count)
                .flat_map(|i| bin.bytes[start + i * stride..][..size].to_vec())
                .collect();
            let target = bin.views[v]["target"].as_u64().map(|t| t as u32);
            let view = bin.push_view(&packed, target);
            let acc = &mut json["accessors"][a];
            acc["bufferView"] = view.into();
            acc.as_object_mut().map(|o| o.remove("byteOffset"));
        }
        bin.views[v].as_object_mut().map(|o| o.remove("byteStride"));
    }
    let which: Vec<String> = strided.iter().map(|v| v.to_string()).collect();
    said_of(&which, |n, s, _, which| {
        format!("{n} buffer view{s} ({which}) of animation, skin, index or image data had a byteStride, which glTF allows vertex data alone; left out (interleaved elements written packed)")
    })
}

/// Rewrite as 32-bit every 8- or 16-bit index accessor of a primitive that holds its type's
/// largest value (255, 65535: the primitive restart index, which WebGL 2 always applies and
/// the validator refuses; a writer that numbers 65,536 vertices in 16 bits, as a 256 x 256
/// grid's, ends a strip there and drops the triangles of its last vertex), into a view of its
/// own in `bin`; returns a line naming them.
pub fn restart_indices(json: &mut Value, bin: &mut BinBuilder) -> Vec<String> {
    let mut accessors = std::collections::BTreeSet::new();
    for mesh in arr(json, "meshes") {
        for p in arr(mesh, "primitives") {
            accessors.extend(p["indices"].as_u64().map(|a| a as usize));
        }
    }
    let mut widened = Vec::new();
    for a in accessors {
        let count = json["accessors"][a]["count"].as_u64().unwrap_or(0) as usize;
        let Some(column) = Column::of_width(json, bin, a, count, 1) else {
            continue;
        };
        let restart = match column.component {
            5121 => 255,
            5123 => 65535,
            _ => continue,
        };
        let values: Vec<u32> = (0..count).map(|i| column.uint(&bin.bytes, i, 0)).collect();
        if !values.contains(&restart) {
            continue;
        }
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let view = bin.push_view(&bytes, Some(34963));
        let acc = &mut json["accessors"][a];
        acc["bufferView"] = view.into();
        acc["componentType"] = 5125.into();
        acc.as_object_mut().map(|o| o.remove("byteOffset"));
        widened.push(a.to_string());
    }
    said_of(&widened, |n, s, its, which| {
        format!("{n} index accessor{s} ({which}) held {its} type's largest value, the primitive restart index that WebGL 2 applies and glTF forbids; written as 32-bit indices")
    })
}

/// The VEC4 data [`weights`] and [`rotations`] may change (skin weights and their joints,
/// rotation keys): where an accessor of them declares min/max that no longer match its values
/// in `bin` (compared as floats, as [`bounds`] does), they are set to the values'. Writers that
/// declare bounds on every accessor (assimp) had them right for the values before.
fn rebound_vec4(json: &mut Value, bin: &BinBuilder) {
    let mut vec4 = std::collections::BTreeSet::new();
    for mesh in arr(json, "meshes") {
        for p in arr(mesh, "primitives") {
            let attrs = p["attributes"].as_object().into_iter().flatten();
            vec4.extend(
                attrs
                    .filter(|(k, _)| k.starts_with("WEIGHTS_") || k.starts_with("JOINTS_"))
                    .filter_map(|(_, a)| a.as_u64()),
            );
        }
    }
    for anim in arr(json, "animations") {
        for ch in arr(anim, "channels") {
            if ch["target"]["path"].as_str() == Some("rotation") {
                let sampler = ch["sampler"].as_u64().unwrap_or(u64::MAX) as usize;
                vec4.extend(anim["samplers"][sampler]["output"].as_u64());
            }
        }
    }
    for a in vec4.into_iter().map(|a| a as usize) {
        let acc = &json["accessors"][a];
        if acc.get("min").is_none() && acc.get("max").is_none() {
            continue;
        }
        let count = acc["count"].as_u64().unwrap_or(0) as usize;
        // Integers (joints, normalized weights) are bounded by their stored values.
        let Some(column) = Column::of(json, bin, a, count).filter(|_| count > 0) else {
            continue;
        };
        let values: Vec<f32> = (0..count)
            .flat_map(|i| (0..4).map(move |c| (i, c)))
            .map(|(i, c)| match column.component {
                5126 => column.float(&bin.bytes, i, c),
                _ => column.uint(&bin.bytes, i, c) as f32,
            })
            .collect();
        let (lo, hi) = min_max(&values, 4);
        for (key, actual) in [("min", lo), ("max", hi)] {
            let Some(declared) = json["accessors"][a][key].as_array() else {
                continue;
            };
            let wrong = declared.len() != 4
                || (declared.iter().zip(&actual))
                    .any(|(d, &v)| d.as_f64().map(|d| d as f32) != Some(v));
            if wrong {
                json["accessors"][a][key] = match column.component {
                    5126 => f32_json(&actual),
                    _ => actual.iter().map(|&v| v as u64).collect(),
                };
            }
        }
    }
}

/// Make every `WEIGHTS_n` set of the output (float or normalized integer) sum to one per
/// vertex, each joint named once (see the module comment), in place in `bin`; returns a line
/// for each mesh with joints named twice, and each whose sums were off by more than
/// quantization.
pub fn weights(json: &Value, bin: &mut BinBuilder) -> Vec<String> {
    // Mesh -> (vertices mended, the sums' range before), and vertices with a joint named
    // twice, for the lines.
    let mut said: BTreeMap<usize, (usize, f64, f64)> = BTreeMap::new();
    let mut repeated: BTreeMap<usize, usize> = BTreeMap::new();
    for (m, mesh) in arr(json, "meshes").iter().enumerate() {
        for p in arr(mesh, "primitives") {
            let attrs = &p["attributes"];
            let pairs: Vec<(u64, u64)> = (0..)
                .map_while(|n| {
                    let j = attrs[format!("JOINTS_{n}")].as_u64()?;
                    Some((j, attrs[format!("WEIGHTS_{n}")].as_u64()?))
                })
                .collect();
            let Some(count) = pairs
                .first()
                .and_then(|&(_, w)| json["accessors"][w as usize]["count"].as_u64())
            else {
                continue;
            };
            let count = count as usize;
            let normalized_int = |w: u64| json["accessors"][w as usize]["normalized"] == true;
            let columns: Option<Vec<(Column, Column)>> = (pairs.iter())
                .map(|&(j, w)| {
                    let jc = Column::of(json, bin, j as usize, count)?;
                    let wc = Column::of(json, bin, w as usize, count)?;
                    let readable = wc.component == 5126 || normalized_int(w);
                    (jc.component != 5126 && readable).then_some((jc, wc))
                })
                .collect();
            let Some(columns) = columns.filter(|c| !c.is_empty()) else {
                continue;
            };
            // Float weights, or normalized integers of one type (their largest value is 1).
            let n = 4 * columns.len();
            let mut w = match columns[0].1.component {
                5126 => VertexWeights::Floats(vec![0.0; n]),
                5121 => VertexWeights::Units(vec![0; n], 255),
                _ => VertexWeights::Units(vec![0; n], 65535),
            };
            if (columns.iter()).any(|c| c.1.component != columns[0].1.component) {
                continue;
            }
            let mut j = vec![0u32; n];
            for i in 0..count {
                for (s, (jc, _)) in columns.iter().enumerate() {
                    for c in 0..4 {
                        j[4 * s + c] = jc.uint(&bin.bytes, i, c);
                    }
                }
                w.read(&columns, &bin.bytes, i);
                let merged = w.merge_repeated_joints(&j);
                if merged {
                    *repeated.entry(m).or_insert(0) += 1;
                }
                let fits = w.sums_to_one(&j);
                if fits == Some(false) {
                    let before = w.sum();
                    w.normalize(&j);
                    let e = said
                        .entry(m)
                        .or_insert((0, f64::INFINITY, f64::NEG_INFINITY));
                    *e = (e.0 + 1, e.1.min(before), e.2.max(before));
                }
                if merged || fits == Some(false) {
                    w.write(&columns, &mut bin.bytes, i);
                }
                // A joint with no weight is joint 0 (the validator warns of others): Draco's
                // quantization rounds a small weight to 0 and keeps its joint, and so may an
                // integer weight's share above.
                for (s, (jc, _)) in columns.iter().enumerate() {
                    for c in 0..4 {
                        if w.is_zero(4 * s + c) && j[4 * s + c] != 0 {
                            jc.set_uint(&mut bin.bytes, i, c, 0);
                        }
                    }
                }
            }
        }
    }
    let mesh = |m: usize| quoted_name(&json["meshes"][m], || format!("{m}"));
    let mut lines: Vec<String> = (repeated.into_iter())
        .map(|(m, n)| {
            format!(
                "mesh {}: {n} vertices name a joint more than once (glTF allows it once); written with its weights added",
                mesh(m)
            )
        })
        .collect();
    lines.extend(
        (said.into_iter())
            .filter(|&(_, (_, lo, hi))| (1.0 - lo).max(hi - 1.0) > SAID_ABOVE)
            .map(|(m, (n, lo, hi))| {
                format!(
                    "mesh {}: the skin weights of {n} vertices summed to {lo:.4}-{hi:.4}, not 1 as glTF requires; written divided by their sums",
                    mesh(m)
                )
            }),
    );
    lines
}

/// Weights `w` of joints `j` with each joint named once: a weight on a joint named earlier
/// added to that one and made 0 (skinning is linear in each joint's weight, so the pose is
/// the same); whether any was.
fn merge_repeated_joints<T>(w: &mut [T], j: &[u32]) -> bool
where
    T: Copy + PartialEq + Default + std::ops::AddAssign,
{
    let zero = T::default();
    let mut merged = false;
    for x in 0..w.len() {
        if w[x] == zero {
            continue;
        }
        if let Some(y) = (0..x).find(|&y| w[y] != zero && j[y] == j[x]) {
            let v = w[x];
            w[y] += v;
            w[x] = zero;
            merged = true;
        }
    }
    merged
}

/// One vertex's skin weights as stored, across its `WEIGHTS_n` sets: floats, or normalized
/// integers with their type's largest value (255, 65535: the validator's 1).
enum VertexWeights {
    Floats(Vec<f32>),
    Units(Vec<u32>, u32),
}

impl VertexWeights {
    /// Vertex `i`'s weights from the weights columns of `columns` (joints, weights).
    fn read(&mut self, columns: &[(Column, Column)], bytes: &[u8], i: usize) {
        for (s, (_, wc)) in columns.iter().enumerate() {
            for c in 0..4 {
                match self {
                    VertexWeights::Floats(w) => w[4 * s + c] = wc.float(bytes, i, c),
                    VertexWeights::Units(k, _) => k[4 * s + c] = wc.uint(bytes, i, c),
                }
            }
        }
    }

    /// Vertex `i`'s weights written back into `columns`.
    fn write(&self, columns: &[(Column, Column)], bytes: &mut [u8], i: usize) {
        for (s, (_, wc)) in columns.iter().enumerate() {
            for c in 0..4 {
                match self {
                    VertexWeights::Floats(w) => wc.set_float(bytes, i, c, w[4 * s + c]),
                    VertexWeights::Units(k, _) => wc.set_uint(bytes, i, c, k[4 * s + c]),
                }
            }
        }
    }

    fn merge_repeated_joints(&mut self, j: &[u32]) -> bool {
        match self {
            VertexWeights::Floats(w) => merge_repeated_joints(w, j),
            VertexWeights::Units(k, _) => merge_repeated_joints(k, j),
        }
    }

    fn sums_to_one(&self, j: &[u32]) -> Option<bool> {
        match self {
            VertexWeights::Floats(w) => floats_sum_to_one(w, j),
            VertexWeights::Units(k, unit) => units_sum_to_one(k, *unit, j),
        }
    }

    /// The weights' sum, as the validator reads them.
    fn sum(&self) -> f64 {
        match self {
            VertexWeights::Floats(w) => w.iter().map(|&x| x as f64).sum(),
            VertexWeights::Units(k, unit) => {
                k.iter().map(|&x| x as f64).sum::<f64>() / *unit as f64
            }
        }
    }

    /// The weights made to sum to one ([`normalized`], [`normalized_units`]).
    fn normalize(&mut self, j: &[u32]) {
        match self {
            VertexWeights::Floats(w) => normalized(w, j),
            VertexWeights::Units(k, unit) => normalized_units(k, *unit),
        }
    }

    fn is_zero(&self, x: usize) -> bool {
        match self {
            VertexWeights::Floats(w) => w[x] == 0.0,
            VertexWeights::Units(k, _) => k[x] == 0,
        }
    }
}

/// Times `t` made increasing where a time equals the one before, each moved by
/// single-precision steps, the first and last kept (so the accessor's bounds hold): later ones
/// forward, then, where that reaches the last, earlier ones back. `None` where nothing moved,
/// where a time goes back (not a repeat: which key is where is not known) or where the times
/// leave no room (all equal).
fn increasing_times(t: &[f32]) -> Option<Vec<f32>> {
    let n = t.len();
    let goes_back = t.windows(2).any(|w| w[1] < w[0]);
    if n < 2 || goes_back || t.iter().any(|x| !x.is_finite()) || t.windows(2).all(|w| w[1] > w[0]) {
        return None;
    }
    let mut m = t.to_vec();
    for i in 1..n - 1 {
        if m[i] <= m[i - 1] {
            m[i] = m[i - 1].next_up();
        }
    }
    for i in (1..n - 1).rev() {
        if m[i] >= m[i + 1] {
            m[i] = m[i + 1].next_down();
        }
    }
    m.windows(2).all(|w| w[1] > w[0]).then_some(m)
}

/// Make every float key-time accessor of the output's animations increasing (see
/// [`increasing_times`]), in place in `bin`; returns a line for each animation with such
/// times. A repeated time is a step between its keys, which the moved time keeps within a
/// single-precision step (an exporter's hold, or two samples of a bake rounded to one time).
pub fn key_times(json: &Value, bin: &mut BinBuilder) -> Vec<String> {
    let mut lines = Vec::new();
    let mut done = std::collections::BTreeSet::new();
    for (a, anim) in arr(json, "animations").iter().enumerate() {
        let mut moved = 0;
        for sampler in arr(anim, "samplers") {
            let Some(input) = sampler["input"].as_u64().map(|i| i as usize) else {
                continue;
            };
            let count = json["accessors"][input]["count"].as_u64().unwrap_or(0) as usize;
            let column =
                Column::of_width(json, bin, input, count, 1).filter(|c| c.component == 5126);
            let Some(column) = column.filter(|_| done.insert(input)) else {
                continue;
            };
            let t: Vec<f32> = (0..count).map(|i| column.float(&bin.bytes, i, 0)).collect();
            let Some(m) = increasing_times(&t) else {
                continue;
            };
            for (i, (a, b)) in t.iter().zip(&m).enumerate() {
                if a != b {
                    column.set_float(&mut bin.bytes, i, 0, *b);
                    moved += 1;
                }
            }
        }
        if moved > 0 {
            let name = quoted_name(anim, || format!("{a}"));
            let s = if moved == 1 { "" } else { "s" };
            lines.push(format!(
                "animation {name}: {moved} key time{s} equal to the one before, moved by single-precision steps (glTF requires increasing times)"
            ));
        }
    }
    lines
}

/// How far from 1 the validator lets a rotation key's length be.
const UNIT_LENGTH: f64 = 0.00769;

/// Divide every float rotation key of the output's animations that is farther than
/// [`UNIT_LENGTH`] from unit length by its length (a CUBICSPLINE key's tangents by the same),
/// in place in `bin`; returns a line for each animation with such keys.
pub fn rotations(json: &Value, bin: &mut BinBuilder) -> Vec<String> {
    let mut lines = Vec::new();
    let mut done = std::collections::BTreeSet::new();
    for (a, anim) in arr(json, "animations").iter().enumerate() {
        let (mut keys, mut lo, mut hi) = (0, f64::INFINITY, f64::NEG_INFINITY);
        for ch in arr(anim, "channels") {
            if ch["target"]["path"].as_str() != Some("rotation") {
                continue;
            }
            let sampler = &anim["samplers"][ch["sampler"].as_u64().unwrap_or(u64::MAX) as usize];
            let Some(out) = sampler["output"].as_u64().map(|o| o as usize) else {
                continue;
            };
            let count = json["accessors"][out]["count"].as_u64().unwrap_or(0) as usize;
            let column = Column::of(json, bin, out, count).filter(|c| c.component == 5126);
            let Some(column) = column.filter(|_| done.insert(out)) else {
                continue;
            };
            // CUBICSPLINE: (in-tangent, value, out-tangent) per key.
            let per_key = match sampler["interpolation"].as_str() {
                Some("CUBICSPLINE") => 3,
                _ => 1,
            };
            for k in 0..count / per_key {
                let value = per_key * k + per_key / 2;
                let q: Vec<f64> = (0..4)
                    .map(|c| column.float(&bin.bytes, value, c) as f64)
                    .collect();
                let length = q.iter().map(|x| x * x).sum::<f64>().sqrt();
                if (length - 1.0).abs() <= UNIT_LENGTH || length <= 0.0 || !length.is_finite() {
                    continue;
                }
                for e in per_key * k..per_key * (k + 1) {
                    for c in 0..4 {
                        let x = column.float(&bin.bytes, e, c) as f64;
                        column.set_float(&mut bin.bytes, e, c, (x / length) as f32);
                    }
                }
                (keys, lo, hi) = (keys + 1, lo.min(length), hi.max(length));
            }
        }
        if keys > 0 {
            let name = quoted_name(anim, || format!("{a}"));
            lines.push(format!(
                "animation {name}: {keys} rotation keys of length {lo:.4}-{hi:.4}, not the unit quaternions glTF requires; written divided by their lengths"
            ));
        }
    }
    lines
}

/// Correct the declared `min`/`max` of the output's float accessors from the values `doc`
/// decodes (see the module comment), in `json` (the input's JSON, copied); returns a line when
/// any bound was wrong.
pub fn bounds(doc: &Document, json: &mut Value) -> Vec<String> {
    let (mut wrong, mut missing) = (Vec::new(), Vec::new());
    let required = bounded_by_rule(json);
    for i in 0..arr(json, "accessors").len() {
        let a = &json["accessors"][i];
        let ncomp = match a["type"].as_str() {
            Some("SCALAR") => 1,
            Some("VEC2") => 2,
            Some("VEC3") => 3,
            _ => continue,
        };
        let declared = |k: &str| -> Option<Vec<f64>> {
            let v: Vec<f64> = a[k].as_array()?.iter().filter_map(Value::as_f64).collect();
            (v.len() == ncomp).then_some(v)
        };
        if a["componentType"].as_u64() != Some(5126) || a["count"].as_u64().unwrap_or(0) == 0 {
            continue;
        }
        let (min, max) = (declared("min"), declared("max"));
        let absent = a.get("min").is_none() && a.get("max").is_none();
        if min.is_none() && max.is_none() && !(absent && required.contains(&i)) {
            continue;
        }
        let Ok((values, _)) = doc.read_f64(i) else {
            continue;
        };
        let values: Vec<f32> = values.iter().map(|&x| x as f32).collect();
        let (lo, hi) = min_max(&values, ncomp);
        if absent {
            json["accessors"][i]["min"] = f32_json(&lo);
            json["accessors"][i]["max"] = f32_json(&hi);
            missing.push(i.to_string());
            continue;
        }
        let mut mended = false;
        for (key, found, actual) in [("min", min, lo), ("max", max, hi)] {
            let Some(found) = found else {
                continue;
            };
            for (c, (&d, &v)) in found.iter().zip(&actual).enumerate() {
                if d as f32 != v {
                    json["accessors"][i][key][c] = f32_json(&[v])[0].take();
                    mended = true;
                }
            }
        }
        if mended {
            wrong.push(i.to_string());
        }
    }
    let mut lines = said_of(&wrong, |n, s, its, which| {
        format!("the declared min/max of {n} accessor{s} ({which}) did not match {its} values; written as the values are")
    });
    lines.extend(said_of(&missing, |n, s, its, which| {
        format!("{n} accessor{s} ({which}) of positions or key times had no min/max, which glTF requires; written from {its} values")
    }));
    lines
}

/// The accessors glTF requires `min` and `max` of: every primitive's and morph target's
/// POSITION, and every animation sampler's key times.
fn bounded_by_rule(json: &Value) -> std::collections::BTreeSet<usize> {
    let mut required = std::collections::BTreeSet::new();
    for mesh in arr(json, "meshes") {
        for p in arr(mesh, "primitives") {
            let targets = arr(p, "targets").iter();
            for attrs in std::iter::once(&p["attributes"]).chain(targets) {
                required.extend(attrs["POSITION"].as_u64().map(|a| a as usize));
            }
        }
    }
    for anim in arr(json, "animations") {
        for sampler in arr(anim, "samplers") {
            required.extend(sampler["input"].as_u64().map(|a| a as usize));
        }
    }
    required
}

/// A line about the accessors `which` (none: no line), `say` given their count, the plural's
/// `s`, `its` or `their`, and the list.
fn said_of(which: &[String], say: impl Fn(usize, &str, &str, &str) -> String) -> Vec<String> {
    let (s, its) = match which.len() {
        0 => return Vec::new(),
        1 => ("", "its"),
        _ => ("s", "their"),
    };
    vec![say(which.len(), s, its, &listed(which))]
}

/// Sparse parts stored where they may not be (see the module comment): `byteStride`/`target`
/// dropped from the views of `bin` (placed by `write::begin`) that only sparse parts use, and
/// a float sparse accessor whose parts lie in a view that other accessors read as vertex data
/// written dense into `bin`, as `doc` decodes it; returns a line when any was.
pub fn sparse_parts(doc: &Document, json: &mut Value, bin: &mut BinBuilder) -> Vec<String> {
    let mut plain = std::collections::BTreeSet::new();
    let mut sparse = std::collections::BTreeSet::new();
    for a in arr(json, "accessors") {
        if let Some(v) = a["bufferView"].as_u64() {
            plain.insert(v);
        }
        for part in ["indices", "values"] {
            if let Some(v) = a["sparse"][part]["bufferView"].as_u64() {
                sparse.insert(v);
            }
        }
    }
    for v in sparse.difference(&plain) {
        if let Some(view) = bin
            .views
            .get_mut(*v as usize)
            .and_then(Value::as_object_mut)
        {
            view.remove("byteStride");
            view.remove("target");
        }
    }
    let mut densified = Vec::new();
    for i in 0..arr(json, "accessors").len() {
        let a = &json["accessors"][i];
        let shared = ["indices", "values"].iter().any(|part| {
            a["sparse"][part]["bufferView"]
                .as_u64()
                .is_some_and(|v| plain.contains(&v))
        });
        if !shared || a["componentType"].as_u64() != Some(5126) {
            continue;
        }
        let Ok((values, _)) = doc.read_f64(i) else {
            continue;
        };
        let bytes: Vec<u8> = (values.iter())
            .flat_map(|&x| (x as f32).to_le_bytes())
            .collect();
        let view = bin.push_view(&bytes, Some(34962));
        if let Some(o) = json["accessors"][i].as_object_mut() {
            o.remove("sparse");
            o.remove("byteOffset");
            o.insert("bufferView".into(), serde_json::json!(view));
        }
        densified.push(i.to_string());
    }
    said_of(&densified, |n, s, its, which| {
        format!("{n} sparse accessor{s} ({which}) kept {its} indices or values in a view that vertex data also uses; written dense")
    })
}

/// Whether animation `anim` has what the specification asks of one: a channel and a sampler.
fn playable(anim: &Value) -> bool {
    !arr(anim, "channels").is_empty() && !arr(anim, "samplers").is_empty()
}

/// How far from 1 the validator lets a NORMAL's length be (glTF-Validator 2.0.0-dev.3.10: 1.005
/// passes, 1.0068 and 0.993 fail), with a margin.
const UNIT_NORMAL: f64 = 0.006;

/// Make every float NORMAL attribute of the output a unit vector (see the module comment), in
/// place in `bin` (the views placed by `write::begin`), from the values `doc` reads; returns a
/// line for each mesh with such normals.
pub fn normals(doc: &Document, json: &mut Value, bin: &mut BinBuilder) -> Vec<String> {
    let mut lines = Vec::new();
    let mut done = std::collections::BTreeSet::new();
    // Mended accessors and their values as written, for their declared bounds.
    let mut rebound: Vec<(usize, Vec<f32>)> = Vec::new();
    for (m, mesh) in arr(json, "meshes").iter().enumerate() {
        let (mut scaled, mut zero) = (0, 0);
        for p in arr(mesh, "primitives") {
            // A morph primitive's frames carry NORMAL deltas from the normals as read.
            let targets = !arr(p, "targets").is_empty();
            let acc = p["attributes"]["NORMAL"].as_u64().map(|a| a as usize);
            let Some(acc) = acc.filter(|_| !targets) else {
                continue;
            };
            let count = json["accessors"][acc]["count"].as_u64().unwrap_or(0) as usize;
            let column = Column::of_width(json, bin, acc, count, 3).filter(|c| c.component == 5126);
            let Some(column) = column.filter(|_| done.insert(acc)) else {
                continue;
            };
            let Ok((values, 3)) = doc.read_f64(acc) else {
                continue;
            };
            let off = |v: &[f64]| {
                let length = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                !(length.is_finite() && (length - 1.0).abs() <= UNIT_NORMAL)
            };
            if !values.chunks_exact(3).any(off) {
                continue;
            }
            let faces = face_normals(doc, p, count);
            let mut written: Vec<f32> = values.iter().map(|&x| x as f32).collect();
            for (i, v) in values.chunks_exact(3).enumerate() {
                if !off(v) {
                    continue;
                }
                let n = glam::DVec3::from_slice(v);
                let unit = match n.length() {
                    l if l.is_finite() && l > 1e-12 => {
                        scaled += 1;
                        n / l
                    }
                    _ => {
                        zero += 1;
                        faces[i].try_normalize().unwrap_or(glam::DVec3::Y)
                    }
                };
                for (c, x) in unit.to_array().into_iter().enumerate() {
                    column.set_float(&mut bin.bytes, i, c, x as f32);
                    written[3 * i + c] = x as f32;
                }
            }
            rebound.push((acc, written));
        }
        if scaled + zero > 0 {
            let name = quoted_name(mesh, || format!("{m}"));
            lines.push(format!(
                "mesh {name}: {} normals were not of unit length as glTF requires ({zero} of them zero); written divided by their lengths, the zero ones as the normals of their faces",
                scaled + zero
            ));
        }
    }
    for (acc, written) in rebound {
        let a = &mut json["accessors"][acc];
        if a.get("min").is_some() || a.get("max").is_some() {
            set_bounds(a, &written, 3);
        }
    }
    lines
}

/// The area-weighted sum of the face normals around each of the `count` vertices of triangle
/// primitive `p` (TRIANGLES, strips or fans; zero where none, or where its positions or
/// triangles do not read).
fn face_normals(doc: &Document, p: &Value, count: usize) -> Vec<glam::DVec3> {
    let mut out = vec![glam::DVec3::ZERO; count];
    let positions = (p["attributes"]["POSITION"].as_u64())
        .and_then(|a| read_vec3(doc, a as usize, "POSITION").ok())
        .filter(|v| v.len() == count);
    let triangles = read_triangles(doc, p, count, "primitive").ok();
    let (Some(at), Some(triangles)) = (positions, triangles) else {
        return out;
    };
    for t in triangles.iter().map(|t| t.map(|i| i as usize)) {
        let n = (at[t[1]] - at[t[0]]).cross(at[t[2]] - at[t[0]]);
        for i in t {
            out[i] += n;
        }
    }
    out
}

/// A line naming the input's animations that have no channel or no sampler, which the output
/// leaves out ([`drop_empty_animations`], when it is written: until then the other stages
/// address the animations by their index in the input).
pub fn empty_animations(json: &Value) -> Vec<String> {
    let empty: Vec<String> = (arr(json, "animations").iter().enumerate())
        .filter(|(_, a)| !playable(a))
        .map(|(i, a)| quoted_name(a, || format!("{i}")))
        .collect();
    let (what, has) = match empty.len() {
        0 => return Vec::new(),
        1 => ("animation", "has"),
        _ => ("animations", "have"),
    };
    vec![format!(
        "{what} {} {has} no channel or no sampler (nothing to play): left out",
        listed(&empty)
    )]
}

/// Channel `c` of `anim` when it repeats an earlier channel's target and sampler exactly (an
/// animation may target a node's property once; the repeat plays the very same keys).
fn repeats(anim: &Value, c: usize) -> bool {
    let channels = arr(anim, "channels");
    let key = |ch: &Value| (ch["target"].clone(), ch["sampler"].clone());
    channels[..c].iter().any(|e| key(e) == key(&channels[c]))
}

/// A line naming the input's animations with channels that repeat another's target and
/// sampler, which the output leaves out ([`drop_repeated_channels`], when it is written).
pub fn repeated_channels(json: &Value) -> Vec<String> {
    let mut lines = Vec::new();
    for (a, anim) in arr(json, "animations").iter().enumerate() {
        let n = (0..arr(anim, "channels").len())
            .filter(|&c| repeats(anim, c))
            .count();
        if n > 0 {
            let name = quoted_name(anim, || format!("{a}"));
            let (s, its) = if n == 1 { ("", "its") } else { ("s", "their") };
            lines.push(format!(
                "animation {name}: {n} channel{s} repeating another's target and sampler (glTF allows one channel a target): left out, {its} keys played by the other"
            ));
        }
    }
    lines
}

/// Remove every channel that repeats an earlier one of its animation exactly; see
/// [`repeated_channels`].
pub fn drop_repeated_channels(json: &mut Value) {
    let Some(anims) = json.get_mut("animations").and_then(Value::as_array_mut) else {
        return;
    };
    for anim in anims {
        let keep: Vec<bool> = (0..arr(anim, "channels").len())
            .map(|c| !repeats(anim, c))
            .collect();
        if let Some(channels) = anim.get_mut("channels").and_then(Value::as_array_mut) {
            let mut k = keep.iter();
            channels.retain(|_| *k.next().unwrap());
        }
    }
}

/// Remove the animations that have no channel or no sampler (and `animations`, if none is
/// left); see [`empty_animations`].
pub fn drop_empty_animations(json: &mut Value) {
    let Some(anims) = json.get_mut("animations").and_then(Value::as_array_mut) else {
        return;
    };
    anims.retain(playable);
    if anims.is_empty() {
        json.as_object_mut().map(|o| o.remove("animations"));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn off_sums_are_mended_to_pass_the_validator_s_check() {
        let mut lcg = crate::dev::synth::Lcg(3);
        for case in 0..20_000 {
            let n = 1 + case % 8;
            let mut w: Vec<f32> = (0..8)
                .map(|i| match i < n {
                    true => (lcg.unit() * 0.9 + 0.01) as f32,
                    false => 0.0,
                })
                .collect();
            let j: Vec<u32> = (0..8).collect();
            let before: Vec<f64> = w.iter().map(|&x| x as f64).collect();
            let sum: f64 = before.iter().sum();
            normalized(&mut w, &j);
            assert_eq!(floats_sum_to_one(&w, &j), Some(true), "{before:?} -> {w:?}");
            // Each weight within a few single-precision steps of its share.
            for (a, b) in w.iter().zip(&before) {
                assert!((*a as f64 - b / sum).abs() < 1e-6, "{before:?} -> {w:?}");
            }
        }
        // Two influences must sum to exactly 1 in single precision.
        let (mut w, j) = (vec![0.30001, 0.70012, 0.0, 0.0], vec![3, 5, 0, 0]);
        assert_eq!(floats_sum_to_one(&w, &j), Some(false));
        normalized(&mut w, &j);
        assert_eq!(w[0] + w[1], 1.0);
        // What normalizing cannot mend is left.
        assert_eq!(
            floats_sum_to_one(&[0.5, 0.6, 0.0, 0.0], &[1, 1, 0, 0]),
            None
        );
        assert_eq!(
            floats_sum_to_one(&[-0.5, 1.5, 0.0, 0.0], &[1, 2, 0, 0]),
            None
        );
        assert_eq!(floats_sum_to_one(&[0.0; 4], &[0; 4]), None);
    }

    #[test]
    fn repeated_key_times_move_by_single_precision_steps_within_the_bounds() {
        let up = |x: f32| x.next_up();
        let down = |x: f32| x.next_down();
        assert_eq!(increasing_times(&[0.0, 0.5, 1.0]), None);
        assert_eq!(
            increasing_times(&[0.0, 0.5, 0.5, 1.0]),
            Some(vec![0.0, 0.5, up(0.5), 1.0])
        );
        assert_eq!(
            increasing_times(&[0.0, 0.5, 0.5, 0.5, 1.0]),
            Some(vec![0.0, 0.5, up(0.5), up(up(0.5)), 1.0])
        );
        // At either end the end stays where it is.
        assert_eq!(
            increasing_times(&[0.0, 0.0, 1.0]),
            Some(vec![0.0, up(0.0), 1.0])
        );
        assert_eq!(
            increasing_times(&[0.0, 0.5, 1.0, 1.0]),
            Some(vec![0.0, 0.5, down(1.0), 1.0])
        );
        assert_eq!(
            increasing_times(&[0.0, 1.0, 1.0, 1.0]),
            Some(vec![0.0, down(down(1.0)), down(1.0), 1.0])
        );
        // A time going back, or no room: left as it is.
        assert_eq!(increasing_times(&[0.0, 0.5, 0.4, 1.0]), None);
        assert_eq!(increasing_times(&[1.0, 1.0]), None);
        assert_eq!(increasing_times(&[1.0, 1.0, up(1.0)]), None);
    }

    #[test]
    fn whole_integer_sums_pass_and_off_ones_are_made_whole() {
        let j = [0, 1, 2, 3];
        // Every 8-bit set of four summing to 255 passes the validator's single-precision sum.
        for a in 0..=255u32 {
            for b in 0..=255 - a {
                for c in 0..=255 - a - b {
                    let k = [a, b, c, 255 - a - b - c];
                    assert_eq!(units_sum_to_one(&k, 255, &j), Some(true), "{k:?}");
                }
            }
        }
        let mut lcg = crate::dev::synth::Lcg(5);
        for case in 0..20_000 {
            let unit = [255, 65535][case % 2];
            let n = 1 + case / 2 % 8;
            let mut k: Vec<u32> = (0..8)
                .map(|i| match i < n {
                    true => (lcg.unit() * 1.2 * unit as f64 / n as f64) as u32,
                    false => 0,
                })
                .collect();
            let (before, j): (Vec<u32>, Vec<u32>) = (k.clone(), (0..8).collect());
            let sum: u32 = before.iter().sum();
            if sum == 0 {
                continue;
            }
            normalized_units(&mut k, unit);
            assert_eq!(k.iter().sum::<u32>(), unit, "{before:?} -> {k:?}");
            assert_eq!(
                units_sum_to_one(&k, unit, &j),
                Some(true),
                "{before:?} -> {k:?}"
            );
            // Each within a unit of its share; zeros stay zero.
            for (now, was) in k.iter().zip(&before) {
                let share = *was as f64 * unit as f64 / sum as f64;
                assert!((*now as f64 - share).abs() < 1.0, "{before:?} -> {k:?}");
                assert!(*was != 0 || *now == 0, "{before:?} -> {k:?}");
            }
        }
    }
}
