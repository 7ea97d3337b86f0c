//! Targets stage (on read): every primitive of a mesh given the same number of morph targets.
//!
//! glTF asks that the primitives of a mesh list the same number of targets in the same order
//! (the mesh's `weights` drive them all). Exporters have written a face's targets on some of its
//! primitives only: UniGLTF (UniVRM's glTF core) on the first primitive of a multi-material
//! mesh (its issue 18), SharpGLTF's builder leaving out trailing targets a primitive's vertices do
//! not move (its issue 281). Viewers play such a file as each primitive's own targets, a missing
//! one moving nothing (three.js), so that is how it is read: a primitive with fewer targets than
//! the mesh's most gets the missing ones as zero deltas, accessors with no buffer view (zeros by
//! glTF's rule; no bytes), of the attributes its own targets move (or, with none, those the
//! other primitives' target moves that it has). Every stage then reads the mesh as glTF asks,
//! and the output is written so; a line says it ([`super::read::Document::read_past`]).
//!
//! So are default weights listing another number than the targets (a mesh's or a node's
//! `weights`: the validator's MESH_INVALID_WEIGHTS_COUNT, NODE_WEIGHTS_INVALID), as glTF's
//! readers use them: a missing weight is 0, one past the targets drives nothing
//! ([`weights_counts`]).

use super::compact::items_mut;
use super::read::arr;
use serde_json::{json, Map, Value};

/// Pad each mesh's short primitives (see the module comment); a line for each mesh padded.
pub fn equal_counts(json: &mut Value) -> Vec<String> {
    let unequal = |m: &Value| {
        let counts = arr(m, "primitives").iter().map(|p| arr(p, "targets").len());
        counts.clone().min() != counts.max()
    };
    if !arr(json, "meshes").iter().any(unequal) {
        return Vec::new();
    }
    let mut said = Vec::new();
    let accessors = json["accessors"].clone();
    let first_new = accessors.as_array().map_or(0, Vec::len);
    let mut added: Vec<Value> = Vec::new();
    let Some(meshes) = json.get_mut("meshes").and_then(Value::as_array_mut) else {
        return said;
    };
    for (mi, mesh) in meshes.iter_mut().enumerate() {
        let prims = arr(mesh, "primitives");
        let most = prims
            .iter()
            .map(|p| arr(p, "targets").len())
            .max()
            .unwrap_or(0);
        let short: Vec<(usize, usize)> = (prims.iter().enumerate())
            .map(|(pi, p)| (pi, arr(p, "targets").len()))
            .filter(|&(_, n)| n < most)
            .collect();
        if short.is_empty() {
            continue;
        }
        let longest_at = (prims.iter())
            .position(|p| arr(p, "targets").len() == most)
            .unwrap_or(0);
        let longest = arr(&prims[longest_at], "targets").to_vec();
        for &(pi, _) in &short {
            let p = &mut mesh["primitives"][pi];
            let base = p["attributes"].clone();
            let Some(count) =
                (base["POSITION"].as_u64()).and_then(|a| accessors[a as usize]["count"].as_u64())
            else {
                continue;
            };
            let own: Vec<String> = (arr(p, "targets").iter())
                .filter_map(Value::as_object)
                .flat_map(|t| t.keys().cloned())
                .collect();
            let Some(targets) = (p.as_object_mut())
                .map(|o| o.entry("targets").or_insert_with(|| json!([])))
                .and_then(Value::as_array_mut)
            else {
                continue;
            };
            for t in targets.len()..most {
                let names: Vec<String> = match own.is_empty() {
                    false => own.clone(),
                    true => (longest[t].as_object().into_iter())
                        .flat_map(|o| o.keys().cloned())
                        .collect(),
                };
                let mut target = Map::new();
                for name in std::iter::once("POSITION").chain(names.iter().map(String::as_str)) {
                    if target.contains_key(name) || base.get(name).is_none() {
                        continue;
                    }
                    let zeros =
                        zero_accessor(like_accessor(&accessors, &longest, t, name), name, count);
                    target.insert(name.to_string(), json!(first_new + added.len()));
                    added.push(zeros);
                }
                targets.push(Value::Object(target));
            }
        }
        let name = mesh["name"]
            .as_str()
            .map_or_else(|| format!("mesh {mi}"), |n| format!("mesh {n:?}"));
        let fewer: Vec<String> = (short.iter())
            .map(|(pi, n)| format!("{n} on primitive {pi}"))
            .collect();
        said.push(format!(
            "{name} lists {most} morph targets on primitive {longest_at} but {} (glTF asks every primitive the same number; viewers play a missing one as moving nothing): read and written as targets of zeros",
            fewer.join(", ")
        ));
    }
    if let Some(a) = json.get_mut("accessors").and_then(Value::as_array_mut) {
        a.extend(added);
    }
    said
}

/// The accessor that attribute `name` of target `t` of the longest primitive names, or of any
/// of its targets: the type and component type its zero target copies.
fn like_accessor<'a>(
    accessors: &'a Value,
    longest: &[Value],
    t: usize,
    name: &str,
) -> Option<&'a Value> {
    std::iter::once(&longest[t])
        .chain(longest)
        .find_map(|target| target[name].as_u64())
        .map(|a| &accessors[a as usize])
        .filter(|a| a.is_object())
}

/// An accessor of `count` zeros with no buffer view, typed as `like` (float VEC3 without one),
/// with the bounds glTF asks of a POSITION.
fn zero_accessor(like: Option<&Value>, name: &str, count: u64) -> Value {
    let (component, ty) = like.map_or((json!(5126), json!("VEC3")), |l| {
        (l["componentType"].clone(), l["type"].clone())
    });
    let mut zeros = json!({ "componentType": component, "count": count, "type": ty });
    if let Some(n) = like.and_then(|l| l.get("normalized")) {
        zeros["normalized"] = n.clone();
    }
    if name == "POSITION" {
        let width = match zeros["type"].as_str() {
            Some("VEC2") => 2,
            Some("VEC4") => 4,
            _ => 3,
        };
        zeros["min"] = json!(vec![0; width]);
        zeros["max"] = json!(vec![0; width]);
    }
    zeros
}

/// Default weights (a mesh's `weights`, and a node's for its mesh) that list another number
/// than the mesh's targets: missing ones written 0, ones past the targets left out (a list left
/// with none removed); a line for each.
pub fn weights_counts(json: &mut Value) -> Vec<String> {
    let counts: Vec<usize> = (arr(json, "meshes").iter())
        .map(|m| {
            arr(m, "primitives")
                .first()
                .map_or(0, |p| arr(p, "targets").len())
        })
        .collect();
    let mut said = Vec::new();
    let mut fit = |owner: &mut Value, what: String, targets: usize| {
        let Some(w) = owner.get("weights").and_then(Value::as_array) else {
            return;
        };
        if w.len() == targets {
            return;
        }
        said.push(format!(
            "{what} lists {} default weights for {targets} morph targets (glTF asks one each): written with {}",
            w.len(),
            match targets {
                0 => "none".to_string(),
                _ if w.len() < targets => "the missing ones 0".to_string(),
                _ => "the ones past the targets left out".to_string(),
            }
        ));
        match targets {
            0 => _ = owner.as_object_mut().map(|o| o.remove("weights")),
            _ => {
                if let Some(w) = owner["weights"].as_array_mut() {
                    w.resize(targets, json!(0.0));
                }
            }
        }
    };
    let name = |v: &Value, kind: &str, i: usize| match v["name"].as_str() {
        Some(n) => format!("{kind} {n:?}"),
        None => format!("{kind} {i}"),
    };
    for (mi, mesh) in items_mut(json, "meshes").enumerate() {
        let what = name(mesh, "mesh", mi);
        fit(mesh, what, counts[mi]);
    }
    for (ni, node) in items_mut(json, "nodes").enumerate() {
        let Some(&targets) = node["mesh"].as_u64().and_then(|m| counts.get(m as usize)) else {
            continue;
        };
        let what = name(node, "node", ni);
        fit(node, what, targets);
    }
    said
}
