//! Scenes ([`scene_roots`]): a scene lists its root nodes, each once (the validator's
//! SCENE_NON_ROOT_NODE and DUPLICATE_ELEMENTS). A writer that lists every node of a hierarchy
//! there (WickedEngine's exporter before its pull request 1583: Blender's importer then links
//! the same objects twice and fails with "Object already in collection") has the nodes whose
//! ancestor the scene also lists left out of the list, and repeats too: the scene holds the
//! very same nodes through their ancestors. A child whose ancestors the scene does not list is
//! kept (leaving it out would take it out of the scene).

use crate::gltf::channel::node_parents;
use crate::gltf::read::{arr, listed, quoted_name};
use serde_json::Value;

/// Leave out of each scene's `nodes` the repeats and the nodes one of whose ancestors the
/// scene also lists; returns a line naming them.
///
/// ```text
/// {"scenes": [{"nodes": [0, 1, 0]}], "nodes": [{"children": [1]}, {}]}
///   -> {"scenes": [{"nodes": [0]}], ...}
/// ```
pub fn scene_roots(json: &mut Value) -> Vec<String> {
    let nodes = arr(json, "nodes");
    let parent = node_parents(json);
    let mut left = Vec::new();
    let mut kept_lists = Vec::new();
    for scene in arr(json, "scenes") {
        let list: Vec<u64> = arr(scene, "nodes")
            .iter()
            .filter_map(Value::as_u64)
            .collect();
        if list.len() != arr(scene, "nodes").len() {
            // Something other than indices: left for the checks to refuse.
            kept_lists.push(None);
            continue;
        }
        let listed_here = |n: usize| list.contains(&(n as u64));
        // An ancestor of `n` the scene lists (a loop of parents ends the walk).
        let covered = |n: usize| {
            let mut at = parent.get(n).copied().flatten();
            for _ in 0..parent.len() {
                match at {
                    Some(p) if listed_here(p) => return true,
                    Some(p) => at = parent[p],
                    None => return false,
                }
            }
            false
        };
        let mut kept: Vec<u64> = Vec::new();
        for &n in &list {
            if kept.contains(&n) || covered(n as usize) {
                let name = nodes
                    .get(n as usize)
                    .map_or_else(|| n.to_string(), |node| quoted_name(node, || n.to_string()));
                if !left.contains(&name) {
                    left.push(name);
                }
            } else {
                kept.push(n);
            }
        }
        kept_lists.push((kept.len() != list.len()).then_some(kept));
    }
    if left.is_empty() {
        return Vec::new();
    }
    if let Some(scenes) = json.get_mut("scenes").and_then(Value::as_array_mut) {
        for (scene, kept) in scenes.iter_mut().zip(kept_lists) {
            if let Some(kept) = kept {
                scene["nodes"] = kept.into();
            }
        }
    }
    let (what, them) = match left.len() {
        1 => ("node", "it"),
        _ => ("nodes", "them"),
    };
    vec![format!(
        "{what} {} listed by a scene again or beside an ancestor (a scene lists its root nodes, each once): left out of that list, the scene holding {them} still",
        listed(&left)
    )]
}
