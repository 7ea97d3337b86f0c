//! Indices ([`restart_indices`]) must not hold the primitive restart value (255 in 8
//! bits, 65535 in 16): WebGL 2 always restarts there, so a writer that numbers 65,536 vertices
//! in 16 bits loses the triangles of its last; such an accessor is written as 32-bit indices.

use super::{said_of, Column};
use crate::gltf::build::BinBuilder;
use crate::gltf::read::arr;
use serde_json::Value;

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
