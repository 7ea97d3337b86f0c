//! Sparse parts ([`sparse_parts`]): a buffer view that only sparse parts use loses
//! `byteStride` and `target` (only vertex data may have them); a float sparse accessor whose
//! parts lie in a view that other accessors read as vertex data (the same writer's), or whose
//! indices are not strictly increasing (ACCESSOR_SPARSE_INDICES_NON_INCREASING: a reader that
//! stops at the first out of order, the validator among them, reads other values than one that
//! applies them all), is written dense, as it decodes.

use super::said_of;
use crate::gltf::build::BinBuilder;
use crate::gltf::read::{arr, Document};
use serde_json::Value;

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
    let (mut densified, mut unordered) = (Vec::new(), Vec::new());
    for i in 0..arr(json, "accessors").len() {
        let a = &json["accessors"][i];
        let shared = ["indices", "values"].iter().any(|part| {
            a["sparse"][part]["bufferView"]
                .as_u64()
                .is_some_and(|v| plain.contains(&v))
        });
        let out_of_order = (a.get("sparse"))
            .and_then(|sparse| doc.sparse_indices(i, sparse).ok())
            .is_some_and(|ix| ix.windows(2).any(|w| w[0] >= w[1]));
        if !(shared || out_of_order) || a["componentType"].as_u64() != Some(5126) {
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
        match out_of_order {
            true => unordered.push(i.to_string()),
            false => densified.push(i.to_string()),
        }
    }
    let mut said = said_of(&densified, |n, s, its, which| {
        format!("{n} sparse accessor{s} ({which}) kept {its} indices or values in a view that vertex data also uses; written dense")
    });
    said.extend(said_of(&unordered, |n, s, its, which| {
        format!("{n} sparse accessor{s} ({which}) listed {its} indices out of order or twice, which glTF does not allow (readers that stop at it, the validator among them, read other values); written dense as they decode, a repeated index's later value kept")
    }));
    said
}
