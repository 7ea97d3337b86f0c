//! Extensions ([`undeclared_extensions`]): every extension a file uses must be named in its
//! `extensionsUsed`, and every one it requires too (the validator's UNDECLARED_EXTENSION and
//! UNUSED_EXTENSION_REQUIRED). Writers leave some out: CesiumLab's and Babylon's 3ds Max
//! exporter `KHR_materials_unlit` (three.js issue 17057, BabylonJS/Exporters issue 340).
//! Declared in the output, as the glTF tools for VS Code offer to (their quick fix): the file
//! uses the extension, and a reader that looks at the list (three.js does) now sees it.

use crate::gltf::read::{arr, listed};
use serde_json::Value;

/// Every extension name `json` uses: the keys of each `extensions` object (outside `extras`,
/// which hold anything), then the required ones, each once, in the file's order.
fn used(json: &Value) -> Vec<String> {
    fn walk(v: &Value, names: &mut Vec<String>) {
        match v {
            Value::Object(o) => {
                for (k, x) in o {
                    if k == "extras" {
                        continue;
                    }
                    if k == "extensions" {
                        for name in x.as_object().into_iter().flat_map(|e| e.keys()) {
                            if !names.contains(name) {
                                names.push(name.clone());
                            }
                        }
                    }
                    walk(x, names);
                }
            }
            Value::Array(a) => a.iter().for_each(|x| walk(x, names)),
            _ => {}
        }
    }
    let mut names = Vec::new();
    walk(json, &mut names);
    for name in arr(json, "extensionsRequired")
        .iter()
        .filter_map(Value::as_str)
    {
        if !names.iter().any(|n| n == name) {
            names.push(name.to_owned());
        }
    }
    names
}

/// Name in `extensionsUsed` each extension `json` uses or requires that the list leaves out;
/// returns a line naming them.
///
/// ```text
/// {"materials": [{"extensions": {"KHR_materials_unlit": {}}}]}
///   -> {"materials": [...], "extensionsUsed": ["KHR_materials_unlit"]}
/// ```
pub fn undeclared_extensions(json: &mut Value) -> Vec<String> {
    let declared: Vec<String> = (arr(json, "extensionsUsed").iter())
        .filter_map(|e| e.as_str().map(str::to_owned))
        .collect();
    let missing: Vec<String> = (used(json).into_iter())
        .filter(|n| !declared.contains(n))
        .collect();
    if missing.is_empty() {
        return Vec::new();
    }
    let Some(o) = json.as_object_mut() else {
        return Vec::new();
    };
    let list = o
        .entry("extensionsUsed")
        .or_insert_with(|| Value::Array(Vec::new()));
    if !list.is_array() {
        *list = Value::Array(Vec::new());
    }
    let list = list.as_array_mut().expect("made a list");
    list.extend(missing.iter().map(|n| Value::from(n.as_str())));
    let quoted: Vec<String> = missing.iter().map(|n| format!("{n:?}")).collect();
    let (s, is) = match missing.len() {
        1 => ("", "is"),
        _ => ("s", "are"),
    };
    vec![format!(
        "extension{s} {} {is} used but not named in extensionsUsed (glTF asks each named): named",
        listed(&quoted)
    )]
}
