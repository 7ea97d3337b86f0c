//! Accessor bounds ([`bounds`]): a float accessor's declared `min` and `max` must be its
//! values' (gltf-pipeline 4's Draco on a Blender morph file declared a target's max 0 where its
//! values reach 1.2): each component whose declared bound, read as a float, differs from the
//! values' is written as theirs; bounds right to a float's precision stay as written. SCALAR,
//! VEC2 and VEC3 from the input's values; the VEC4 skin weights, joints and rotation keys the
//! mends above may change, from the values written, integers as stored (assimp declares bounds
//! on every accessor, right for its weights before they were divided by their sums: 18-21
//! errors per blend).
//! Bounds glTF requires and a writer left out (every POSITION's, a morph target's included,
//! and every sampler's key times) are written from the values of a float accessor.

use super::{attribute_sets, said_of, Column};
use crate::gltf::build::{f32_json, min_max, set_bounds, BinBuilder};
use crate::gltf::read::{arr, Document};
use serde_json::Value;

/// The VEC4 data [`weights`](super::weights) and [`rotations`](super::rotations) may change
/// (skin weights and their joints, rotation keys): where an accessor of them declares min/max
/// that no longer match its values in `bin` (compared as floats, as [`bounds`] does), they are
/// set to the values'. Writers that declare bounds on every accessor (assimp) had them right
/// for the values before.
pub(super) fn rebound_vec4(json: &mut Value, bin: &BinBuilder) {
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
    for attrs in attribute_sets(json) {
        required.extend(attrs["POSITION"].as_u64().map(|a| a as usize));
    }
    for anim in arr(json, "animations") {
        for sampler in arr(anim, "samplers") {
            required.extend(sampler["input"].as_u64().map(|a| a as usize));
        }
    }
    required
}

/// The declared bounds (where an accessor declares them) of each accessor of `rebound` made
/// those of the values written to it (`width` a element).
pub(super) fn declared_follow(json: &mut Value, rebound: Vec<(usize, Vec<f32>)>, width: usize) {
    for (acc, written) in rebound {
        let a = &mut json["accessors"][acc];
        if a.get("min").is_some() || a.get("max").is_some() {
            set_bounds(a, &written, width);
        }
    }
}
