//! Empty lists ([`empty_lists`], [`drop_empty_lists`]): glTF gives every list it names at least one
//! entry (the validator's EMPTY_ENTITY), and writers leave empty ones: Babylon's 3ds Max exporter
//! `extensionsUsed` (BabylonJS/Exporters issue 152), COLLADA2GLTF and a Vulkan exporter `children`
//! and top-level lists (glTF-Sample-Models issue 52), three.js's exporter a scene's `nodes`
//! (three.js pull request 18933), UniVRM and gltf-rs a mesh with no `primitives` (UniVRM issue
//! 2612, gltf pull request 300). An optional list that is empty is left out of the output, which
//! reads the same; a mesh with no primitive, which draws nothing, is left out with the nodes'
//! references to it (and their `skin` and `weights`, which need one), unless an extension might
//! refer to meshes by index. Like the empty animations, they go when the output is written: until
//! then the other stages address the meshes by their index in the input.

use crate::gltf::compact::PASSED_THROUGH;
use crate::gltf::read::{arr, listed, quoted_name, OBJECT_ARRAYS};
use serde_json::Value;

/// The core schema's optional lists of the top level: the extension names, and its lists of
/// parts.
fn top_lists() -> impl Iterator<Item = &'static str> {
    ["extensionsUsed", "extensionsRequired"]
        .into_iter()
        .chain(OBJECT_ARRAYS.iter().copied())
}

/// The core schema's optional lists inside the top level's parts: `(part, list)`.
const INNER: [(&str, &str); 4] = [
    ("scenes", "nodes"),
    ("nodes", "children"),
    ("nodes", "weights"),
    ("meshes", "weights"),
];

/// Where each empty optional list of `json` stands: `(the JSON pointer of its object, its
/// key)`, in the file's order; a primitive's `targets` among them.
fn empty_in(json: &Value) -> Vec<(String, &'static str)> {
    let empty = |v: &Value, key: &str| {
        v.get(key)
            .and_then(Value::as_array)
            .is_some_and(Vec::is_empty)
    };
    let mut found = Vec::new();
    for (part, key) in INNER {
        for (i, v) in arr(json, part).iter().enumerate() {
            if empty(v, key) {
                found.push((format!("/{part}/{i}"), key));
            }
        }
    }
    for (m, mesh) in arr(json, "meshes").iter().enumerate() {
        for (p, prim) in arr(mesh, "primitives").iter().enumerate() {
            if empty(prim, "targets") {
                found.push((format!("/meshes/{m}/primitives/{p}"), "targets"));
            }
        }
    }
    for key in top_lists() {
        if empty(json, key) {
            found.push((String::new(), key));
        }
    }
    found
}

/// The meshes of `json` with no primitive (none, or an empty list); none where an extension
/// might refer to meshes by index (one not known to refer to none: VRM's blend shape binds,
/// KHR_animation_pointer's `/meshes/N/weights`), which leaving one out would renumber.
fn hollow_meshes(json: &Value) -> Vec<usize> {
    let known = |e: &Value| {
        e.as_str()
            .is_some_and(|e| PASSED_THROUGH.contains(&e) && e != "KHR_animation_pointer")
    };
    if !arr(json, "extensionsUsed").iter().all(known) {
        return Vec::new();
    }
    (arr(json, "meshes").iter().enumerate())
        .filter(|(_, m)| arr(m, "primitives").is_empty())
        .map(|(i, _)| i)
        .collect()
}

/// Lines naming the input's empty lists and meshes with no primitive, which the output leaves
/// out ([`drop_empty_lists`], when it is written).
pub fn empty_lists(json: &Value) -> Vec<String> {
    let mut lines = Vec::new();
    let lists: Vec<String> = (empty_in(json).into_iter())
        .map(|(at, key)| format!("{at}/{key}"))
        .collect();
    if !lists.is_empty() {
        let (s, them) = match lists.len() {
            1 => ("", "it"),
            _ => ("s", "them"),
        };
        lines.push(format!(
            "empty list{s} {} (glTF asks at least one entry where a list is written): left out, the file reading the same without {them}",
            listed(&lists)
        ));
    }
    let hollow: Vec<String> = (hollow_meshes(json).into_iter())
        .map(|m| quoted_name(&json["meshes"][m], || format!("{m}")))
        .collect();
    if !hollow.is_empty() {
        let (what, has) = match hollow.len() {
            1 => ("mesh", "has"),
            _ => ("meshes", "have"),
        };
        lines.push(format!(
            "{what} {} {has} no primitive (nothing to draw): left out, with the nodes' references",
            listed(&hollow)
        ));
    }
    lines
}

/// Remove every mesh with no primitive (the nodes' `mesh` renumbered, and a node's `mesh`,
/// `skin` and `weights` where it named a removed one), then every empty optional list; see
/// [`empty_lists`].
///
/// ```text
/// {"nodes": [{"mesh": 1, "children": []}], "meshes": [{"primitives": []}, {...}]}
///   -> {"nodes": [{"mesh": 0}], "meshes": [{...}]}
/// ```
pub fn drop_empty_lists(json: &mut Value) {
    let hollow = hollow_meshes(json);
    if !hollow.is_empty() {
        let mut kept = vec![true; arr(json, "meshes").len()];
        for &m in &hollow {
            kept[m] = false;
        }
        // The new index of each mesh kept.
        let mut next = 0u64;
        let new: Vec<Option<u64>> = (kept.iter())
            .map(|&k| {
                next += k as u64;
                k.then_some(next - 1)
            })
            .collect();
        if let Some(nodes) = json.get_mut("nodes").and_then(Value::as_array_mut) {
            for node in nodes.iter_mut().filter_map(Value::as_object_mut) {
                let Some(m) = node.get("mesh").and_then(Value::as_u64) else {
                    continue;
                };
                match new.get(m as usize) {
                    Some(Some(n)) => {
                        node.insert("mesh".into(), (*n).into());
                    }
                    Some(None) => {
                        for key in ["mesh", "skin", "weights"] {
                            node.remove(key);
                        }
                    }
                    None => {}
                }
            }
        }
        if let Some(meshes) = json.get_mut("meshes").and_then(Value::as_array_mut) {
            let mut k = kept.iter();
            meshes.retain(|_| *k.next().unwrap());
        }
    }
    for (at, key) in empty_in(json) {
        if let Some(o) = json.pointer_mut(&at).and_then(Value::as_object_mut) {
            o.remove(key);
        }
    }
}
