//! Reorder stage (with meshopt, so `--compact`): a primitive's triangles put in the order a
//! GPU's vertex cache likes (meshoptimizer's `optimizeVertexCache`), and its vertices renumbered
//! in the order the triangles first use them, as gltfpack does: every vertex stream (positions,
//! morph targets, colours, texture coordinates, skin weights) then runs in mesh order, which
//! meshopt's codec compresses much better, and the index codec sees mostly new or recent
//! vertices. What is drawn is the same: every attribute and morph target of the primitive is
//! permuted alike (sparse ones too), min/max do not change, unused vertices keep their place
//! after the used ones. Alpha-blended primitives keep their triangle order (it is their draw
//! order); only their vertices are renumbered. A primitive whose vertex data another primitive
//! also uses, one with extensions of its own, or one that is not an indexed triangle list is
//! left as it is.
//!
//! ```text
//! inbetween tween face.glb -o face_small.glb --compact   # vertices in mesh order
//! ```

use super::accessor::{comp_size, components, read_uint};
use super::build::Output;
use super::compact::{visit_mesh_refs, AccessorRefs};
use super::encode::{ELEMENT_MARK, FILTER_GROUP, FILTER_MARK, OCT_MARK};
use serde_json::{json, Value};
use std::collections::{BTreeMap, BTreeSet};

/// Reorder primitive `prim` of mesh `mesh` in `out`: new accessors for its indices and every
/// vertex accessor, the old ones added to `replaced` (for the compact stage to drop). `outside`
/// counts the references from outside the mesh (the mesh left out, see [`AccessorRefs`]).
/// Returns whether it was reordered.
pub fn reorder(
    out: &mut Output,
    mesh: usize,
    prim: usize,
    outside: &AccessorRefs,
    replaced: &mut BTreeSet<usize>,
) -> bool {
    let p = out.json["meshes"][mesh]["primitives"][prim].clone();
    if p["mode"].as_u64().unwrap_or(4) != 4
        || p.get("extensions")
            .is_some_and(|e| e.as_object().is_some_and(|o| !o.is_empty()))
    {
        return false;
    }
    let Some(index_acc) = p["indices"].as_u64().map(|i| i as usize) else {
        return false;
    };
    // (JSON pointer under the primitive, accessor) of every vertex accessor; an attribute's
    // name escaped as a pointer needs ("_A/B" is "_A~1B").
    let escape = |k: &str| k.replace('~', "~0").replace('/', "~1");
    let mut refs: Vec<(String, usize)> = Vec::new();
    if let Some(a) = p["attributes"].as_object() {
        for (k, v) in a {
            refs.extend(
                v.as_u64()
                    .map(|i| (format!("/attributes/{}", escape(k)), i as usize)),
            );
        }
    }
    for (t, target) in p["targets"].as_array().into_iter().flatten().enumerate() {
        for (k, v) in target.as_object().into_iter().flatten() {
            refs.extend(
                v.as_u64()
                    .map(|i| (format!("/targets/{t}/{}", escape(k)), i as usize)),
            );
        }
    }

    let Some(vertices) = refs
        .iter()
        .find(|(path, _)| path == "/attributes/POSITION")
        .and_then(|(_, a)| out.json["accessors"][*a]["count"].as_u64())
        .map(|c| c as usize)
    else {
        return false;
    };
    // Accessors of zeros alone (no view, no sparse part) read the same in any order: they stay
    // as they are, shared or not.
    let acc = |a: usize| &out.json["accessors"][a];
    refs.retain(|r| acc(r.1).get("bufferView").is_some() || acc(r.1).get("sparse").is_some());
    // Vertex data used anywhere else would be renumbered under the other user too.
    let mine: BTreeSet<usize> = refs.iter().map(|r| r.1).collect();
    let mut users: usize = mine.iter().map(|&a| outside.outside(a)).sum();
    visit_mesh_refs(&mut out.json["meshes"][mesh], &mut |a| {
        users += mine.contains(a) as usize
    });
    if users != refs.len() {
        return false;
    }
    let Some(mut indices) = read_indices(out, index_acc) else {
        return false;
    };
    if indices.is_empty()
        || !indices.len().is_multiple_of(3)
        || indices.iter().any(|&i| i as usize >= vertices)
        || mine.iter().any(|&a| {
            out.json["accessors"][a]["count"].as_u64() != Some(vertices as u64) || !readable(out, a)
        })
    {
        return false;
    }
    let material = &out.json["materials"][p["material"].as_u64().unwrap_or(u64::MAX) as usize];
    if material["alphaMode"] != "BLEND" {
        indices = meshopt::optimize_vertex_cache(&indices, vertices);
    }
    // New number of each old vertex: first use, then the unused ones in their order.
    let mut remap = vec![u32::MAX; vertices];
    let mut next = 0u32;
    for &i in &indices {
        if remap[i as usize] == u32::MAX {
            remap[i as usize] = next;
            next += 1;
        }
    }
    for r in remap.iter_mut().filter(|r| **r == u32::MAX) {
        *r = next;
        next += 1;
    }
    for i in &mut indices {
        *i = remap[*i as usize];
    }
    // New accessors in the order of the old views, so that views the writer grouped stay
    // side by side for the encoder to merge.
    let mut order: Vec<usize> = mine.iter().copied().collect();
    order.sort_by_key(|&a| (out.json["accessors"][a]["bufferView"].as_u64(), a));
    let mut new_of: BTreeMap<usize, usize> = BTreeMap::new();
    for a in order {
        new_of.insert(a, permuted(out, a, &remap));
    }
    let new_indices = write_indices(out, index_acc, &indices);
    let p = &mut out.json["meshes"][mesh]["primitives"][prim];
    for (path, a) in &refs {
        let v = p
            .pointer_mut(path)
            .expect("a path read from this primitive");
        *v = json!(new_of[a]);
        replaced.insert(*a);
    }
    replaced.insert(index_acc);
    p["indices"] = json!(new_indices);
    true
}

/// The bytes of accessor `a` in `out`: (view bytes from the accessor's first element, element
/// stride, element size), no bytes for an accessor without a view; `None` when the accessor
/// does not fit its view or has a layout the reorder does not know.
fn raw(out: &Output, a: usize) -> Option<(Vec<u8>, usize, usize)> {
    let acc = &out.json["accessors"][a];
    let elem = comp_size(acc["componentType"].as_u64()? as u32)?
        * components(acc["type"].as_str()?).filter(|&n| n <= 4)?;
    let count = acc["count"].as_u64()? as usize;
    let Some(v) = acc["bufferView"].as_u64() else {
        // No view: zeros (and a sparse part, handled by the caller).
        return Some((Vec::new(), elem, elem));
    };
    let view = out.bin.views.get(v as usize)?;
    let stride = view["byteStride"].as_u64().map_or(elem, |s| s as usize);
    let start =
        view["byteOffset"].as_u64()? as usize + acc["byteOffset"].as_u64().unwrap_or(0) as usize;
    let end = view["byteOffset"].as_u64()? as usize + view["byteLength"].as_u64()? as usize;
    let need = if count == 0 {
        0
    } else {
        (count - 1) * stride + elem
    };
    (stride >= elem && start + need <= end && end <= out.bin.bytes.len())
        .then(|| (out.bin.bytes[start..start + need].to_vec(), stride, elem))
}

/// Whether accessor `a` can be permuted: its data (and sparse part) where it says.
fn readable(out: &Output, a: usize) -> bool {
    let Some((_, _, elem)) = raw(out, a) else {
        return false;
    };
    let sparse = &out.json["accessors"][a]["sparse"];
    !sparse.is_object() || sparse_entries(out, sparse, elem).is_some()
}

/// Accessor `a` with its vertices renumbered by `remap` (old -> new), as a new accessor in
/// views of its own (marks of the old view kept: the filters they ask for do not depend on the
/// order).
fn permuted(out: &mut Output, a: usize, remap: &[u32]) -> usize {
    let (data, stride, elem) = raw(out, a).expect("checked by the caller");
    let old = out.json["accessors"][a].clone();
    let mut acc = old.clone();
    if let Some(o) = acc.as_object_mut() {
        o.remove("byteOffset");
    }
    if let Some(v) = old["bufferView"].as_u64() {
        // Vertex elements 4-byte aligned in the new view.
        let new_stride = elem.next_multiple_of(4);
        let mut bytes = vec![0u8; remap.len() * new_stride];
        for (i, &n) in remap.iter().enumerate() {
            let at = n as usize * new_stride;
            bytes[at..at + elem].copy_from_slice(&data[i * stride..i * stride + elem]);
        }
        acc["bufferView"] = json!(push_like(out, v as usize, &bytes));
        if new_stride != elem {
            out.bin.views.last_mut().expect("pushed")["byteStride"] = json!(new_stride);
        }
    }
    if old["sparse"].is_object() {
        acc["sparse"] = sparse_permuted(out, &old["sparse"], elem, remap).unwrap_or(Value::Null);
    }
    out.push_accessor(acc)
}

/// The entries of a sparse part: (vertex, value bytes) in the file's order.
fn sparse_entries(out: &Output, sparse: &Value, elem: usize) -> Option<Vec<(u32, Vec<u8>)>> {
    let count = sparse["count"].as_u64()? as usize;
    let it = sparse["indices"]["componentType"].as_u64()? as u32;
    let isz = comp_size(it)?;
    let bytes_of = |part: &Value, size: usize| -> Option<&[u8]> {
        let view = out.bin.views.get(part["bufferView"].as_u64()? as usize)?;
        let start = view["byteOffset"].as_u64()? as usize
            + part["byteOffset"].as_u64().unwrap_or(0) as usize;
        out.bin.bytes.get(start..start + count * size)
    };
    let (idx, vals) = (
        bytes_of(&sparse["indices"], isz)?,
        bytes_of(&sparse["values"], elem)?,
    );
    Some(
        (0..count)
            .map(|k| {
                let i = read_uint(idx, k * isz, it) as u32;
                (i, vals[k * elem..(k + 1) * elem].to_vec())
            })
            .collect(),
    )
}

/// A sparse part with its indices renumbered by `remap` and sorted, values alike, in new views.
fn sparse_permuted(out: &mut Output, sparse: &Value, elem: usize, remap: &[u32]) -> Option<Value> {
    let it = sparse["indices"]["componentType"].as_u64()?;
    let isz = comp_size(it as u32)?;
    let mut pairs: Vec<(u32, Vec<u8>)> = sparse_entries(out, sparse, elem)?
        .into_iter()
        .map(|(i, v)| Some((*remap.get(i as usize)?, v)))
        .collect::<Option<_>>()?;
    pairs.sort_by_key(|p| p.0);
    let new_idx: Vec<u8> = pairs
        .iter()
        .flat_map(|(i, _)| i.to_le_bytes()[..isz].to_vec())
        .collect();
    let new_vals: Vec<u8> = pairs.iter().flat_map(|(_, v)| v.clone()).collect();
    let iv = push_like(
        out,
        sparse["indices"]["bufferView"].as_u64()? as usize,
        &new_idx,
    );
    let vv = push_like(
        out,
        sparse["values"]["bufferView"].as_u64()? as usize,
        &new_vals,
    );
    let mut s = sparse.clone();
    s["indices"] = json!({ "bufferView": iv, "componentType": it });
    s["values"] = json!({ "bufferView": vv });
    Some(s)
}

/// A new view of `bytes` like view `like` (its target and the writer's marks).
fn push_like(out: &mut Output, like: usize, bytes: &[u8]) -> usize {
    let old = out.bin.views[like].clone();
    let target = old["target"].as_u64().map(|t| t as u32);
    let v = out.bin.push_view(bytes, target);
    for mark in [FILTER_MARK, FILTER_GROUP, ELEMENT_MARK, OCT_MARK] {
        if let Some(m) = old.get(mark) {
            out.bin.views[v][mark] = m.clone();
        }
    }
    v
}

/// Indices of accessor `a` (unsigned byte, short or int; no sparse part).
fn read_indices(out: &Output, a: usize) -> Option<Vec<u32>> {
    if out.json["accessors"][a]["sparse"].is_object() {
        return None;
    }
    let ty = out.json["accessors"][a]["componentType"].as_u64()? as u32;
    if !matches!(ty, 5121 | 5123 | 5125) || out.json["accessors"][a]["type"] != "SCALAR" {
        return None;
    }
    let (data, stride, _) = raw(out, a)?;
    if data.is_empty() {
        return None;
    }
    let count = out.json["accessors"][a]["count"].as_u64()? as usize;
    Some(
        (0..count)
            .map(|k| read_uint(&data, k * stride, ty) as u32)
            .collect(),
    )
}

/// `indices` as a new accessor like index accessor `a` (same component type: every new index
/// is below the vertex count, as every old one was).
fn write_indices(out: &mut Output, a: usize, indices: &[u32]) -> usize {
    let mut acc = out.json["accessors"][a].clone();
    let ty = acc["componentType"].as_u64().unwrap_or(5125);
    let size = comp_size(ty as u32).unwrap_or(4);
    let bytes: Vec<u8> = indices
        .iter()
        .flat_map(|&i| i.to_le_bytes()[..size].to_vec())
        .collect();
    let view = out.bin.push_view(&bytes, Some(34963));
    if let Some(o) = acc.as_object_mut() {
        o.remove("byteOffset");
    }
    acc["bufferView"] = json!(view);
    out.push_accessor(acc)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Six vertices, two triangles listed last-first, attributes of several layouts (f32 VEC3,
    /// u8 VEC4 joints in 4-byte elements, u16 VEC4 weights also read by an attribute named
    /// `_W/~`, a sparse target): after the reorder
    /// every vertex carries all of its own values, the triangles are the same ones, and the
    /// vertices run in the order the triangles first use them.
    #[test]
    fn every_attribute_moves_with_its_vertex() {
        let mut out = Output::new(json!({
            "asset": { "version": "2.0" },
            "meshes": [{ "primitives": [{
                "attributes": { "POSITION": 0, "JOINTS_0": 1, "WEIGHTS_0": 2, "_W/~": 2 },
                "indices": 3,
                "targets": [{ "POSITION": 4 }],
            }]}],
            "accessors": [],
        }));
        let push = |out: &mut Output, bytes: Vec<u8>, acc: Value| -> usize {
            let v = out.bin.push_view(&bytes, Some(34962));
            let mut acc = acc;
            acc["bufferView"] = json!(v);
            out.push_accessor(acc)
        };
        let pos: Vec<u8> = (0..6)
            .flat_map(|v| [v as f32, 0.0, 0.0])
            .flat_map(f32::to_le_bytes)
            .collect();
        push(
            &mut out,
            pos,
            json!({ "componentType": 5126, "count": 6, "type": "VEC3" }),
        );
        let joints: Vec<u8> = (0..6u8).flat_map(|v| [v, v + 1, v + 2, v + 3]).collect();
        push(
            &mut out,
            joints,
            json!({ "componentType": 5121, "count": 6, "type": "VEC4" }),
        );
        let weights: Vec<u8> = (0..6u16)
            .flat_map(|v| [100 * v, 1, 2, 3])
            .flat_map(u16::to_le_bytes)
            .collect();
        push(
            &mut out,
            weights,
            json!({ "componentType": 5123, "normalized": true, "count": 6, "type": "VEC4" }),
        );
        let indices: Vec<u8> = [3u16, 4, 5, 0, 1, 2]
            .iter()
            .flat_map(|i| i.to_le_bytes())
            .collect();
        push(
            &mut out,
            indices,
            json!({ "componentType": 5123, "count": 6, "type": "SCALAR" }),
        );
        // The target moves vertices 1 and 4 by (10 + v, 0, 0).
        let si = out
            .bin
            .push_view(&[1u16, 4].map(u16::to_le_bytes).concat(), None);
        let sv = out.bin.push_view(
            &[11f32, 0.0, 0.0, 14.0, 0.0, 0.0]
                .map(f32::to_le_bytes)
                .concat(),
            None,
        );
        out.push_accessor(json!({
            "componentType": 5126, "count": 6, "type": "VEC3",
            "sparse": { "count": 2, "indices": { "bufferView": si, "componentType": 5123 },
                        "values": { "bufferView": sv } },
        }));
        let mut replaced = BTreeSet::new();
        let mut refs = AccessorRefs::of(&mut out.json);
        refs.leave_out(&mut out.json, 0);
        assert!(reorder(&mut out, 0, 0, &refs, &mut replaced));
        assert_eq!(replaced.len(), 5);
        let p = out.json["meshes"][0]["primitives"][0].clone();
        // An attribute whose name a JSON pointer must escape follows its accessor too.
        assert_eq!(p["attributes"]["_W/~"], p["attributes"]["WEIGHTS_0"]);
        assert_ne!(p["attributes"]["_W/~"], json!(2));
        let at = |name: &str| p["attributes"][name].as_u64().unwrap() as usize;
        let values = |a: usize| raw(&out, a).unwrap();
        let (pos, ps, _) = values(at("POSITION"));
        let old_of: Vec<u32> = (0..6)
            .map(|i| f32::from_le_bytes(pos[i * ps..i * ps + 4].try_into().unwrap()) as u32)
            .collect();
        // First use: the second triangle's vertices (3, 4, 5) come first.
        assert_eq!(&old_of[..3], &[3, 4, 5]);
        let (j, js, _) = values(at("JOINTS_0"));
        let (w, ws, _) = values(at("WEIGHTS_0"));
        for (i, &v) in old_of.iter().enumerate() {
            assert_eq!(
                &j[i * js..i * js + 4],
                &[v as u8, v as u8 + 1, v as u8 + 2, v as u8 + 3]
            );
            assert_eq!(
                u16::from_le_bytes([w[i * ws], w[i * ws + 1]]),
                100 * v as u16
            );
        }
        let idx = read_indices(&out, p["indices"].as_u64().unwrap() as usize).unwrap();
        let mut tris: Vec<Vec<u32>> = idx
            .chunks(3)
            .map(|t| {
                let mut t: Vec<u32> = t.iter().map(|&i| old_of[i as usize]).collect();
                t.sort();
                t
            })
            .collect();
        tris.sort();
        assert_eq!(tris, vec![vec![0, 1, 2], vec![3, 4, 5]]);
        let target = p["targets"][0]["POSITION"].as_u64().unwrap() as usize;
        let entries = sparse_entries(&out, &out.json["accessors"][target]["sparse"], 12).unwrap();
        assert!(
            entries.windows(2).all(|e| e[0].0 < e[1].0),
            "indices increase"
        );
        for (i, value) in entries {
            let x = f32::from_le_bytes(value[..4].try_into().unwrap());
            assert_eq!(x, 10.0 + old_of[i as usize] as f32);
        }
    }
}
