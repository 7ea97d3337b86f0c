//! Target maps ([`target_extras`]): a morph target maps attribute names to accessors, nothing
//! else. Early UniVRM (VRM 0 files, vrm-specification issue 199) named each target inside it,
//! `targets[i].extras.targetName`, which the validator refuses as an attribute
//! (MESH_PRIMITIVE_INVALID_ATTRIBUTE, INVALID_INDEX: two errors a target). Such an entry is left
//! out of the output, and the names it held become the mesh's `extras.targetNames` (where the
//! mesh names none), where every tool looks for them.

use crate::gltf::read::{arr, listed, names_of_each_target, quoted_name};
use serde_json::{json, Value};

/// Leave out of every morph target of `json` the entries that are not accessor indices, the
/// names early UniVRM put there moved to the mesh's `extras.targetNames`; returns a line for
/// the meshes that had such entries.
pub fn target_extras(json: &mut Value) -> Vec<String> {
    let mut meshes = Vec::new();
    for m in 0..arr(json, "meshes").len() {
        let mesh = &mut json["meshes"][m];
        let mut names: Option<Vec<String>> = None;
        let mut found = false;
        for p in mesh["primitives"].as_array_mut().into_iter().flatten() {
            let own = names_of_each_target(p);
            let Some(targets) = p.get_mut("targets").and_then(Value::as_array_mut) else {
                continue;
            };
            for t in targets.iter_mut().filter_map(Value::as_object_mut) {
                let before = t.len();
                t.retain(|_, v| v.is_u64());
                found |= t.len() < before;
            }
            if names.is_none() && !own.is_empty() {
                names = Some(own);
            }
        }
        if !found {
            continue;
        }
        if let Some(names) = names.filter(|_| arr(&mesh["extras"], "targetNames").is_empty()) {
            if !mesh.get("extras").is_some_and(Value::is_object) {
                mesh["extras"] = json!({});
            }
            mesh["extras"]["targetNames"] = json!(names);
        }
        meshes.push(quoted_name(mesh, || format!("{m}")));
    }
    let (what, their) = match meshes.len() {
        0 => return Vec::new(),
        1 => ("mesh", "its"),
        _ => ("meshes", "their"),
    };
    vec![format!(
        "{what} {}: morph targets holding entries that are not accessors (early UniVRM's per-target names), which glTF refuses; left out, the names kept as {their} extras.targetNames",
        listed(&meshes)
    )]
}
