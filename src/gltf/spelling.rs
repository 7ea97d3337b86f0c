//! Spelling stage (on read): JSON that glTF's readers accept, written as the stages look for
//! it.
//!
//! - A UTF-8 byte-order mark ahead of the JSON (Windows tools write one: KhronosGroup/glTF
//!   issue 1345) is read past, as glTF 2.0 asks of readers (RFC 8259 section 8.1: a parser
//!   may ignore it), and said in a line ([`Document::read_past`]): glTF asks writers for
//!   none, the validator counts it an error, and the output is written without it. So is a
//!   GLB's JSON chunk padded with NUL bytes where glTF asks spaces ([`json_text`]).
//! - A whole number written as a decimal (`5.0`, `5e0`, `1.2e1`) where glTF asks an integer
//!   (an index, a count, an offset, an enum: [`INTEGER`]) is read as that integer. JSON does
//!   not tell them apart and the validator takes either; the stages read such numbers as
//!   integers, and a writer whose numbers are all floats made its file "have no POSITION".
//!   Numbers elsewhere (factors, bounds, keys' values, `extras`) are left as written.
//!
//! [`Document::read_past`]: super::read::Document::read_past

use serde_json::Value;

/// Keys whose value glTF 2.0 and the extensions read here ask to be an integer, or a list of
/// integers (`children`, `joints`, a scene's `nodes`, `KHR_materials_variants`' `variants`,
/// `MSFT_lod`'s `ids`). The same names hold objects elsewhere (a channel's `target`, the
/// top-level `nodes`), which are left to the walk.
const INTEGER: [&str; 34] = [
    "buffer",
    "bufferView",
    "byteLength",
    "byteOffset",
    "byteStride",
    "camera",
    "children",
    "componentType",
    "count",
    "ids",
    "index",
    "indices",
    "input",
    "inverseBindMatrices",
    "joints",
    "light",
    "magFilter",
    "material",
    "mesh",
    "minFilter",
    "mode",
    "node",
    "nodes",
    "output",
    "sampler",
    "scene",
    "skeleton",
    "skin",
    "source",
    "target",
    "texCoord",
    "variants",
    "wrapS",
    "wrapT",
];

/// Keys whose value maps names to accessor indices (`attributes`), or is a list of such maps
/// (a primitive's `targets`).
const INTEGER_MAPS: [&str; 2] = ["attributes", "targets"];

/// The bytes of a JSON text past a UTF-8 byte-order mark and, in a GLB's JSON chunk
/// (`glb`), without the NUL bytes a writer padded it with where glTF asks spaces (the Rust
/// `gltf` crate's writer before its pull request 174, VReducer's before its 20th: JSON parsers,
/// three.js's and the validator's among them, refuse them); with a line for each read past.
pub fn json_text(json: &[u8], glb: bool) -> (&[u8], Vec<String>) {
    let mut said = Vec::new();
    let mut text = json;
    if let Some(rest) = text.strip_prefix(b"\xEF\xBB\xBF") {
        text = rest;
        said.push("a byte-order mark ahead of the JSON (glTF asks writers for none): read past, the output written without it".to_string());
    }
    let padded = text.iter().rev().take_while(|&&b| b == 0).count();
    if glb && padded > 0 {
        text = &text[..text.len() - padded];
        said.push("the JSON chunk padded with NUL bytes where glTF asks spaces (JSON parsers refuse them): read past, the output padded with spaces".to_string());
    }
    (text, said)
}

/// Indices and joint indices written as signed integers (BYTE, SHORT), which glTF does not
/// allow for them (MESH_PRIMITIVE_INDICES_ACCESSOR_INVALID_FORMAT): libGDX's gdx-gltf exporter
/// writes its indices as SHORT (its issue 103; Java has no unsigned short, so an index past
/// 32767 is stored as the negative number of the same bits). Read as the unsigned integers of
/// the same bits, as the writer meant (a SHORT -1 is vertex 65535): the accessors'
/// `componentType` made UNSIGNED_BYTE or UNSIGNED_SHORT; a line naming them.
pub fn signed_indices(json: &mut Value) -> Vec<String> {
    let mut used: Vec<usize> = Vec::new();
    for mesh in json["meshes"].as_array().into_iter().flatten() {
        for p in mesh["primitives"].as_array().into_iter().flatten() {
            let joints = (p["attributes"].as_object().into_iter().flatten())
                .filter(|(k, _)| k.starts_with("JOINTS_"))
                .map(|(_, a)| a);
            used.extend(
                std::iter::once(&p["indices"])
                    .chain(joints)
                    .filter_map(Value::as_u64)
                    .map(|a| a as usize),
            );
        }
    }
    used.sort_unstable();
    used.dedup();
    let mut fixed = Vec::new();
    for a in used {
        let Some(acc) = json["accessors"].get_mut(a) else {
            continue;
        };
        let unsigned = match acc["componentType"].as_u64() {
            Some(5120) => 5121,
            Some(5122) => 5123,
            _ => continue,
        };
        acc["componentType"] = unsigned.into();
        fixed.push(a.to_string());
    }
    super::mend::said_of(&fixed, |_, s, _, which| {
        format!("index accessor{s} {which} written as signed integers, which glTF does not allow for indices: read and written as the unsigned integers of the same bits")
    })
}

/// Every whole number written as a decimal where glTF asks an integer, made that integer, in
/// place; see the module comment.
///
/// ```text
/// {"accessors": [{"count": 24.0, "min": [0.0]}], "extras": {"n": 2.0}}
///   -> {"accessors": [{"count": 24, "min": [0.0]}], "extras": {"n": 2.0}}
/// ```
pub fn integers(v: &mut Value) {
    match v {
        Value::Object(o) => {
            for (k, x) in o.iter_mut() {
                if k == "extras" {
                    continue;
                }
                if INTEGER.contains(&k.as_str()) {
                    whole_or_list(x);
                }
                if INTEGER_MAPS.contains(&k.as_str()) {
                    match x.as_array_mut() {
                        Some(maps) => maps.iter_mut().for_each(map_values),
                        None => map_values(x),
                    }
                }
                integers(x);
            }
        }
        Value::Array(a) => a.iter_mut().for_each(integers),
        _ => {}
    }
}

/// A number, or each number of a list, made an integer where it is a whole decimal.
fn whole_or_list(x: &mut Value) {
    match x {
        Value::Array(a) => a.iter_mut().for_each(whole),
        x => whole(x),
    }
}

/// Each value of a map made an integer where it is a whole decimal.
fn map_values(map: &mut Value) {
    if let Value::Object(o) = map {
        o.values_mut().for_each(whole);
    }
}

/// `x` made an integer where it is a whole number written as a decimal within 2^53 (where
/// every integer is exact); anything else left.
fn whole(x: &mut Value) {
    let Value::Number(n) = x else { return };
    let Some(f) = n.as_f64().filter(|_| n.is_f64()) else {
        return;
    };
    if f.fract() != 0.0 || f.abs() > 9_007_199_254_740_992.0 {
        return;
    }
    *x = match f >= 0.0 {
        true => Value::from(f as u64),
        false => Value::from(f as i64),
    };
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn whole_decimals_become_integers_where_gltf_asks_one() {
        let mut j: Value = serde_json::from_str(
            r#"{"scene": 0.0, "scenes": [{"nodes": [0e0, 1.0]}],
                "nodes": [{"mesh": 0.0, "children": [1e0], "scale": [1.0, 2.0, 1.0]}, {}],
                "accessors": [{"bufferView": 0.0, "componentType": 5126.0, "count": 2.4e1,
                               "byteOffset": -4.0, "min": [0.0], "max": [1.0]}],
                "meshes": [{"primitives": [{"attributes": {"POSITION": 0.0},
                                            "targets": [{"POSITION": 1.0}], "mode": 4.0}],
                            "weights": [1.0]}],
                "animations": [{"channels": [{"sampler": 0.0, "target": {"node": 0.0, "path": "weights"}}]}],
                "extras": {"count": 3.0}, "asset": {"version": "2.0"}}"#,
        )
        .unwrap();
        integers(&mut j);
        let text = serde_json::to_string(&j).unwrap();
        for plain in [
            r#""scene":0"#,
            r#""nodes":[0,1]"#,
            r#""mesh":0"#,
            r#""children":[1]"#,
            r#""bufferView":0"#,
            r#""componentType":5126"#,
            r#""count":24"#,
            r#""byteOffset":-4"#,
            r#""POSITION":0"#,
            r#""POSITION":1"#,
            r#""mode":4"#,
            r#""sampler":0"#,
            r#""node":0"#,
        ] {
            assert!(text.contains(plain), "{plain} in {text}");
        }
        // Not integers in glTF: left as written.
        assert_eq!(j["nodes"][0]["scale"], json!([1.0, 2.0, 1.0]));
        assert!(j["nodes"][0]["scale"][0].is_f64());
        assert!(j["accessors"][0]["min"][0].is_f64());
        assert!(j["meshes"][0]["weights"][0].is_f64());
        assert!(j["extras"]["count"].is_f64());
        // A fraction is not an index: left for the checks to refuse.
        let mut half = json!({ "mesh": 0.5, "count": 1e300 });
        integers(&mut half);
        assert!(half["mesh"].is_f64() && half["count"].is_f64());
    }

    #[test]
    fn a_byte_order_mark_and_nul_padding_are_read_past() {
        let past = |json: &[u8], glb| {
            let (text, said) = json_text(json, glb);
            (text.to_vec(), said.len())
        };
        assert_eq!(past(b"\xEF\xBB\xBF{}", false), (b"{}".to_vec(), 1));
        assert_eq!(past(b"{}", false), (b"{}".to_vec(), 0));
        assert_eq!(past(b"{}\0\0", true), (b"{}".to_vec(), 1));
        assert_eq!(past(b"\xEF\xBB\xBF{}\0", true), (b"{}".to_vec(), 2));
        // A .gltf's NUL is its JSON's (refused as it is).
        assert_eq!(past(b"{}\0", false), (b"{}\0".to_vec(), 0));
    }
}
