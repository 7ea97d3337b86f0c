//! Dropping what no longer belongs: animation channels a tween replaced, and accessors (and the
//! buffer views only they used) that nothing refers to any more, every reference renumbered.

use super::build::Output;
use super::read::arr;
use serde_json::{json, Value};
use std::collections::BTreeSet;

/// Remove the given (animation, channel) pairs, the samplers only they used, and animations
/// left with no channel.
pub fn drop_channels(json: &mut Value, dropped: &[(usize, usize)], replaced: &mut BTreeSet<usize>) {
    if dropped.is_empty() {
        return;
    }
    let Some(anims) = json.get_mut("animations").and_then(Value::as_array_mut) else {
        return;
    };
    for (ai, anim) in anims.iter_mut().enumerate() {
        let gone: BTreeSet<usize> = dropped
            .iter()
            .filter(|(a, _)| *a == ai)
            .map(|(_, c)| *c)
            .collect();
        if gone.is_empty() {
            continue;
        }
        let channels: Vec<Value> = arr(anim, "channels")
            .iter()
            .enumerate()
            .filter(|(i, _)| !gone.contains(i))
            .map(|(_, c)| c.clone())
            .collect();
        let used: BTreeSet<u64> = channels
            .iter()
            .filter_map(|c| c["sampler"].as_u64())
            .collect();
        let mut remap = Vec::new();
        let mut samplers = Vec::new();
        for (si, s) in arr(anim, "samplers").iter().enumerate() {
            if used.contains(&(si as u64)) {
                remap.push(Some(samplers.len()));
                samplers.push(s.clone());
            } else {
                remap.push(None);
                for k in ["input", "output"] {
                    if let Some(a) = s[k].as_u64() {
                        replaced.insert(a as usize);
                    }
                }
            }
        }
        let channels: Vec<Value> = channels
            .into_iter()
            .map(|mut c| {
                let s = c["sampler"].as_u64().unwrap_or(0) as usize;
                c["sampler"] = json!(remap.get(s).copied().flatten().unwrap_or(0));
                c
            })
            .collect();
        anim["channels"] = Value::Array(channels);
        anim["samplers"] = Value::Array(samplers);
    }
    anims.retain(|a| !arr(a, "channels").is_empty());
}

/// Extensions whose objects we know not to refer to accessors or buffer views by index (or
/// whose references [`compact`] rewrites): carried through as they are (`inspect` lists them
/// as passed through). With any other extension present, nothing is dropped.
pub const PASSED_THROUGH: &[&str] = &[
    "KHR_materials_emissive_strength",
    "KHR_materials_clearcoat",
    "KHR_materials_ior",
    "KHR_materials_iridescence",
    "KHR_materials_sheen",
    "KHR_materials_specular",
    "KHR_materials_transmission",
    "KHR_materials_unlit",
    "KHR_materials_variants",
    "KHR_materials_volume",
    "KHR_materials_anisotropy",
    "KHR_materials_dispersion",
    "KHR_materials_diffuse_transmission",
    "KHR_materials_pbrSpecularGlossiness",
    "KHR_texture_transform",
    "KHR_texture_basisu",
    "KHR_lights_punctual",
    "KHR_mesh_quantization",
    "KHR_xmp_json_ld",
    "EXT_texture_webp",
    "EXT_texture_avif",
    "EXT_mesh_gpu_instancing",
    // JSON pointers to animated properties (node, mesh, material, camera, light values),
    // never to accessors or views.
    "KHR_animation_pointer",
];

/// Drop the accessors in `candidates` that nothing refers to any more, and the buffer views
/// only they used, renumbering every reference. Skipped when an unknown extension is present.
pub fn compact(out: &mut Output, candidates: &BTreeSet<usize>) {
    let json = &mut out.json;
    if candidates.is_empty()
        || arr(json, "extensionsUsed")
            .iter()
            .any(|e| !PASSED_THROUGH.contains(&e.as_str().unwrap_or("")))
    {
        return;
    }
    let accessor_count = arr(json, "accessors").len();
    let mut used = vec![false; accessor_count];
    let mut dangling = false;
    visit_accessor_refs(json, &mut |a| match used.get_mut(*a) {
        Some(u) => *u = true,
        None => dangling = true,
    });
    // A reference to an accessor that does not exist (the input's own error) would point at
    // another one once the list is renumbered: such a file is written with nothing dropped.
    if dangling {
        return;
    }
    let keep: Vec<bool> = (0..accessor_count)
        .map(|i| used[i] || !candidates.contains(&i))
        .collect();
    if keep.iter().all(|&k| k) {
        return;
    }
    let mut remap = vec![usize::MAX; accessor_count];
    let mut next = 0;
    for i in 0..accessor_count {
        if keep[i] {
            remap[i] = next;
            next += 1;
        }
    }
    visit_accessor_refs(json, &mut |a| *a = remap[*a]);
    let accessors: Vec<Value> = arr(json, "accessors")
        .iter()
        .zip(&keep)
        .filter(|(_, k)| **k)
        .map(|(a, _)| a.clone())
        .collect();
    json["accessors"] = Value::Array(accessors);
    // Buffer views: drop those nothing refers to any more that only dropped accessors used.
    let views = out.bin.views.len();
    let mut view_used = vec![false; views];
    let mut dangling = false;
    let mut mark = |v: &Value| {
        if let Some(i) = v.as_u64() {
            match view_used.get_mut(i as usize) {
                Some(u) => *u = true,
                None => dangling = true,
            }
        }
    };
    for a in arr(json, "accessors") {
        mark(&a["bufferView"]);
        mark(&a["sparse"]["indices"]["bufferView"]);
        mark(&a["sparse"]["values"]["bufferView"]);
    }
    for img in arr(json, "images") {
        mark(&img["bufferView"]);
    }
    if dangling || view_used.iter().all(|&u| u) {
        return;
    }
    let mut bytes = Vec::new();
    let mut new_views = Vec::new();
    let mut vremap = vec![usize::MAX; views];
    for (i, v) in out.bin.views.iter().enumerate() {
        if !view_used[i] {
            continue;
        }
        while bytes.len() % 4 != 0 {
            bytes.push(0);
        }
        let s = v["byteOffset"].as_u64().unwrap_or(0) as usize;
        let l = v["byteLength"].as_u64().unwrap_or(0) as usize;
        let mut nv = v.clone();
        nv["byteOffset"] = json!(bytes.len());
        bytes.extend_from_slice(&out.bin.bytes[s..s + l]);
        vremap[i] = new_views.len();
        new_views.push(nv);
    }
    let fix = |v: &mut Value| {
        if let Some(i) = v.as_u64() {
            *v = json!(vremap[i as usize]);
        }
    };
    if let Some(list) = json.get_mut("accessors").and_then(Value::as_array_mut) {
        for a in list {
            for path in [
                &["bufferView"][..],
                &["sparse", "indices", "bufferView"],
                &["sparse", "values", "bufferView"],
            ] {
                if let Some(v) = pointer_mut(a, path) {
                    fix(v);
                }
            }
        }
    }
    if let Some(list) = json.get_mut("images").and_then(Value::as_array_mut) {
        for img in list {
            if let Some(v) = img.get_mut("bufferView") {
                fix(v);
            }
        }
    }
    out.bin.bytes = bytes;
    out.bin.views = new_views;
}

fn pointer_mut<'a>(v: &'a mut Value, path: &[&str]) -> Option<&'a mut Value> {
    path.iter().try_fold(v, |v, k| v.get_mut(*k))
}

/// Call `f` on every accessor index the core spec (and EXT_mesh_gpu_instancing) refers to.
pub(super) fn visit_accessor_refs(json: &mut Value, f: &mut dyn FnMut(&mut usize)) {
    let mut visit = |v: &mut Value| {
        if let Some(i) = v.as_u64() {
            let mut i = i as usize;
            f(&mut i);
            *v = json!(i);
        }
    };
    if let Some(meshes) = json.get_mut("meshes").and_then(Value::as_array_mut) {
        for m in meshes {
            if let Some(prims) = m.get_mut("primitives").and_then(Value::as_array_mut) {
                for p in prims {
                    if let Some(i) = p.get_mut("indices") {
                        visit(i);
                    }
                    if let Some(a) = p.get_mut("attributes").and_then(Value::as_object_mut) {
                        a.values_mut().for_each(&mut visit);
                    }
                    if let Some(ts) = p.get_mut("targets").and_then(Value::as_array_mut) {
                        for t in ts.iter_mut().filter_map(Value::as_object_mut) {
                            t.values_mut().for_each(&mut visit);
                        }
                    }
                }
            }
        }
    }
    if let Some(skins) = json.get_mut("skins").and_then(Value::as_array_mut) {
        for s in skins {
            if let Some(i) = s.get_mut("inverseBindMatrices") {
                visit(i);
            }
        }
    }
    if let Some(anims) = json.get_mut("animations").and_then(Value::as_array_mut) {
        for a in anims {
            if let Some(ss) = a.get_mut("samplers").and_then(Value::as_array_mut) {
                for s in ss {
                    for k in ["input", "output"] {
                        if let Some(i) = s.get_mut(k) {
                            visit(i);
                        }
                    }
                }
            }
        }
    }
    if let Some(nodes) = json.get_mut("nodes").and_then(Value::as_array_mut) {
        for n in nodes {
            if let Some(a) = n
                .pointer_mut("/extensions/EXT_mesh_gpu_instancing/attributes")
                .and_then(Value::as_object_mut)
            {
                a.values_mut().for_each(&mut visit);
            }
        }
    }
}
