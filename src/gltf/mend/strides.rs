//! Strides ([`strides`]): only vertex data may be read through a `byteStride`; a view of
//! key times or values, inverse bind matrices, indices or an image loses it (Sketchfab's
//! exports and the old Khronos Fox stride their animation data), an accessor there whose
//! elements it spaced out first copied packed into a view of its own.

use super::{attribute_sets, said_of};
use crate::gltf::build::BinBuilder;
use crate::gltf::read::arr;
use serde_json::Value;

/// The views that vertex data reads (every primitive's and morph target's attributes, and
/// `EXT_mesh_gpu_instancing`'s): the only ones glTF lets have a `byteStride`.
fn vertex_views(json: &Value) -> std::collections::BTreeSet<u64> {
    let mut accessors = Vec::new();
    for attrs in attribute_sets(json) {
        accessors.extend(attrs.as_object().into_iter().flatten().map(|(_, a)| a));
    }
    for node in arr(json, "nodes") {
        let attrs = &node["extensions"]["EXT_mesh_gpu_instancing"]["attributes"];
        accessors.extend(attrs.as_object().into_iter().flatten().map(|(_, a)| a));
    }
    (accessors.into_iter())
        .filter_map(|a| json["accessors"][a.as_u64()? as usize]["bufferView"].as_u64())
        .collect()
}

/// A `byteStride` on a view that no vertex data reads (key times and values, inverse bind
/// matrices, indices, images: the validator's ..._WITH_BYTESTRIDE errors; Sketchfab's
/// exports and the old Khronos Fox stride their animation data) removed from it in `bin`; an
/// accessor there whose elements the stride spaced out (interleaved) is first copied packed
/// into a view of its own. Returns a line naming the views.
pub fn strides(json: &mut Value, bin: &mut BinBuilder) -> Vec<String> {
    // Views that sparse parts use are [`sparse_parts`]' to mend.
    let mut left = vertex_views(json);
    for a in arr(json, "accessors") {
        for part in ["indices", "values"] {
            left.extend(a["sparse"][part]["bufferView"].as_u64());
        }
    }
    let strided: Vec<usize> = (0..bin.views.len())
        .filter(|&v| bin.views[v].get("byteStride").is_some() && !left.contains(&(v as u64)))
        .collect();
    for &v in &strided {
        let stride = bin.views[v]["byteStride"].as_u64().unwrap_or(0) as usize;
        for a in 0..arr(json, "accessors").len() {
            let acc = &json["accessors"][a];
            if acc["bufferView"].as_u64() != Some(v as u64) {
                continue;
            }
            let size = (acc["componentType"].as_u64())
                .and_then(|t| crate::gltf::accessor::comp_size(t as u32))
                .zip(
                    acc["type"]
                        .as_str()
                        .and_then(crate::gltf::accessor::components),
                )
                .map(|(c, n)| c * n);
            let count = acc["count"].as_u64().unwrap_or(0) as usize;
            let Some(size) = size.filter(|&size| size != stride && count > 0) else {
                continue;
            };
            let start = (bin.views[v]["byteOffset"].as_u64().unwrap_or(0)
                + acc["byteOffset"].as_u64().unwrap_or(0)) as usize;
            let end = start + (count - 1) * stride + size;
            if stride < size || end > bin.bytes.len() {
                continue;
            }
            let mut packed = Vec::with_capacity(count * size);
            for i in 0..count {
                packed.extend_from_slice(&bin.bytes[start + i * stride..][..size]);
            }
            let target = bin.views[v]["target"].as_u64().map(|t| t as u32);
            let view = bin.push_view(&packed, target);
            let acc = &mut json["accessors"][a];
            acc["bufferView"] = view.into();
            acc.as_object_mut().map(|o| o.remove("byteOffset"));
        }
        bin.views[v].as_object_mut().map(|o| o.remove("byteStride"));
    }
    let which: Vec<String> = strided.iter().map(|v| v.to_string()).collect();
    said_of(&which, |n, s, _, which| {
        format!("{n} buffer view{s} ({which}) of animation, skin, index or image data had a byteStride, which glTF allows vertex data alone; left out (interleaved elements written packed)")
    })
}
