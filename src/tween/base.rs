//! Base stage (with `--meshopt`, so `--compact`): the processed primitives' own POSITION,
//! NORMAL, TANGENT and TEXCOORD_n stored again through meshoptimizer's EXPONENTIAL filter, at
//! the fewest mantissa bits their tolerance allows: POSITION, NORMAL and TANGENT as the
//! compaction chose and measured them (their rounding is part of every frame's measured
//! deviation), texture coordinates within [`UV_FACTOR`] x the tolerance. They stay f32 to a
//! reader (no quantization extension, no node transform). Only plain f32 accessors are stored
//! again; quantized or sparse ones stay as they are, and so do the meshes not processed.
//!
//! ```text
//! inbetween tween face.glb -o face_small.glb --compact   # base, targets and animation compressed
//! ```

use super::compact::{fewest_bits, snorm16, BaseBits, Restorable, UV_FACTOR};
use super::frames::MeshFrames;
use crate::gltf::{exp_roundtrip, set_bounds, Document, Output, FILTER_MARK, OCT_MARK};
use anyhow::Result;
use serde_json::{json, Value};
use std::collections::{BTreeMap, BTreeSet};

/// Whether accessor `a` of `json` is plain f32 data in a buffer view (no sparse part).
pub(super) fn plain(json: &Value, a: Option<u64>) -> bool {
    let Some(a) = a else { return false };
    let acc = &json["accessors"][a as usize];
    acc["componentType"] == 5126 && acc["bufferView"].is_u64() && acc.get("sparse").is_none()
}

/// Which own attributes of each processed primitive of `frames` can be stored again.
pub fn restorable(json: &Value, frames: &MeshFrames) -> Vec<Restorable> {
    frames
        .primitives
        .iter()
        .map(|p| {
            let attrs = &json["meshes"][frames.mesh]["primitives"][p.index]["attributes"];
            let ok = |name: &str| plain(json, attrs[name].as_u64());
            Restorable {
                position: ok("POSITION"),
                normal: ok("NORMAL"),
                tangent: ok("TANGENT"),
            }
        })
        .collect()
}

/// Store the own attributes of the processed primitives again as `bits` says (one entry per
/// primitive of `frames`), texture coordinates within `UV_FACTOR * tolerance`; the accessors
/// replaced go into `replaced`. An accessor shared by several of them is stored once, and so
/// are two attributes of a primitive with the same values (TEXCOORD_1 a copy of TEXCOORD_0).
pub fn reencode(
    out: &mut Output,
    doc: &Document,
    frames: &MeshFrames,
    bits: &[BaseBits],
    tolerance: f64,
    replaced: &mut BTreeSet<usize>,
) -> Result<()> {
    let mut done: BTreeMap<u64, u64> = BTreeMap::new();
    for (p, b) in frames.primitives.iter().zip(bits) {
        // (values, bits, type) of the accessors stored again for this primitive.
        let mut stored: Vec<(Vec<f32>, i32, Value, u64)> = Vec::new();
        let path = format!("/meshes/{}/primitives/{}/attributes", frames.mesh, p.index);
        let names: Vec<(String, u64)> = out
            .json
            .pointer(&path)
            .and_then(Value::as_object)
            .map(|o| {
                o.iter()
                    .filter_map(|(k, v)| Some((k.clone(), v.as_u64()?)))
                    .collect()
            })
            .unwrap_or_default();
        for (name, a) in names {
            if let Some(&new) = done.get(&a) {
                set_attribute(out, &path, &name, new);
                continue;
            }
            if !plain(&out.json, Some(a)) {
                continue;
            }
            let (values, n) = doc.read_f64(a as usize)?;
            let values: Vec<f32> = values.iter().map(|&x| x as f32).collect();
            let chosen = match name.as_str() {
                "POSITION" => b.position,
                "NORMAL" => b.normal,
                "TANGENT" => b.tangent,
                t if t.starts_with("TEXCOORD_") && n == 2 => {
                    fewest_bits(&values, 2, UV_FACTOR * tolerance).map(|(b, _)| b)
                }
                _ => None,
            };
            let Some(bits) = chosen else { continue };
            let old = out.json["accessors"][a as usize].clone();
            let oct = match name.as_str() {
                "NORMAL" => b.normal_oct,
                "TANGENT" => b.tangent_oct,
                _ => false,
            };
            let same = stored
                .iter()
                .find(|(v, b, ty, _)| *b == bits && *ty == old["type"] && *v == values);
            let new = if oct {
                push_octahedral(out, &values, n, bits, &old) as u64
            } else if let Some(&(.., new)) = same {
                new
            } else {
                let new = push_filtered(out, &values, n, bits, &old) as u64;
                stored.push((values, bits, old["type"].clone(), new));
                new
            };
            replaced.insert(a as usize);
            done.insert(a, new);
            set_attribute(out, &path, &name, new);
        }
    }
    Ok(())
}

fn set_attribute(out: &mut Output, path: &str, name: &str, accessor: u64) {
    if let Some(attrs) = out.json.pointer_mut(path) {
        attrs[name] = json!(accessor);
    }
}

/// A new accessor like `old` (type, name, normalized) holding `values` (`n` components each)
/// in a view of its own marked for the EXPONENTIAL filter at `bits`; min/max, where `old` had
/// them, of the values as a reader decodes them.
fn push_filtered(out: &mut Output, values: &[f32], n: usize, bits: i32, old: &Value) -> usize {
    let ty = old["type"].as_str().unwrap_or("VEC3");
    let bounds = old.get("min").is_some() || old.get("max").is_some();
    let new = out.push_f32(values, ty, n, false, Some(34962));
    let view = out.json["accessors"][new]["bufferView"]
        .as_u64()
        .unwrap_or(0) as usize;
    out.bin.views[view][FILTER_MARK] = json!(bits);
    let acc = &mut out.json["accessors"][new];
    if let Some(name) = old.get("name") {
        acc["name"] = name.clone();
    }
    if bounds && !values.is_empty() {
        set_bounds(acc, &exp_roundtrip(values, n, bits), n);
    }
    new
}

/// A new accessor like `old` (a NORMAL or TANGENT: type, name) holding the unit vectors
/// `values` (`n` components each) as normalized SHORT, 8-byte elements, in a view of its own
/// marked for the OCTAHEDRAL filter at `bits` (`KHR_mesh_quantization`).
fn push_octahedral(out: &mut Output, values: &[f32], n: usize, bits: i32, old: &Value) -> usize {
    let bytes: Vec<u8> = values
        .chunks_exact(n)
        .flat_map(|v| {
            let w = if n == 4 { v[3] } else { 0.0 };
            [v[0], v[1], v[2], w].map(|x| snorm16(x as f64).to_le_bytes())
        })
        .flatten()
        .collect();
    let view = out.bin.push_view(&bytes, Some(34962));
    out.bin.views[view]["byteStride"] = json!(8);
    out.bin.views[view][OCT_MARK] = json!(bits);
    let mut acc = json!({
        "bufferView": view,
        "componentType": 5122,
        "normalized": true,
        "count": values.len() / n.max(1),
        "type": old["type"].clone(),
    });
    if let Some(name) = old.get("name") {
        acc["name"] = name.clone();
    }
    out.require("KHR_mesh_quantization");
    out.push_accessor(acc)
}
