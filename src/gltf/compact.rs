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
    // Taken out and filtered, not copied: a file of many meshes writes 100,000 accessors.
    let accessors: Vec<Value> = match json.get_mut("accessors").map(Value::take) {
        Some(Value::Array(list)) => (list.into_iter().zip(&keep))
            .filter_map(|(a, k)| k.then_some(a))
            .collect(),
        _ => Vec::new(),
    };
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
    // The kept views' data packed in their order, 4-byte aligned: moved down in place where
    // each lands at or before where it was (views laid out in their order, as the writer lays
    // them), else copied into a new buffer.
    let span = |v: &Value| {
        let s = v["byteOffset"].as_u64().unwrap_or(0) as usize;
        (s, s + v["byteLength"].as_u64().unwrap_or(0) as usize)
    };
    // Where each kept view's data goes, in view order.
    let mut places = Vec::new();
    let (mut end, mut in_order, mut last_end) = (0usize, true, 0usize);
    for (i, v) in out.bin.views.iter().enumerate() {
        if view_used[i] {
            let (s, e) = span(v);
            let at = end.next_multiple_of(4);
            in_order &= at <= s && last_end <= s;
            places.push(at);
            (end, last_end) = (at + (e - s), e);
        }
    }
    let mut bytes = match in_order {
        true => std::mem::take(&mut out.bin.bytes),
        false => vec![0; end],
    };
    let mut new_views = Vec::new();
    let mut vremap = vec![usize::MAX; views];
    let kept =
        (std::mem::take(&mut out.bin.views).into_iter().enumerate()).filter(|(i, _)| view_used[*i]);
    let mut packed = 0;
    for ((i, mut nv), &at) in kept.zip(&places) {
        let (s, e) = span(&nv);
        match in_order {
            true => {
                bytes[packed..at].fill(0);
                bytes.copy_within(s..e, at);
            }
            false => bytes[at..at + (e - s)].copy_from_slice(&out.bin.bytes[s..e]),
        }
        packed = at + (e - s);
        nv["byteOffset"] = json!(at);
        vremap[i] = new_views.len();
        new_views.push(nv);
    }
    bytes.truncate(end);
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

/// How many references each accessor has from outside one mesh: every reference in the file
/// counted once ([`AccessorRefs::of`]), then a mesh's own left out while a stage edits it and
/// counted again after, so that asking whether a mesh's accessor is shared costs a look at that
/// mesh, not at the whole file (asked of the whole file for each primitive, 3,000 one-triangle
/// meshes took 16 s to write with --meshopt, 10,000 took 179 s).
pub struct AccessorRefs {
    counts: Vec<u32>,
}

impl AccessorRefs {
    /// Every accessor's references in `json`.
    pub fn of(json: &mut Value) -> AccessorRefs {
        let mut refs = AccessorRefs { counts: Vec::new() };
        visit_accessor_refs(json, &mut |a| refs.add(*a, 1));
        refs
    }

    /// Take mesh `mesh`'s references out (before a stage edits it).
    pub fn leave_out(&mut self, json: &mut Value, mesh: usize) {
        visit_mesh_refs(&mut json["meshes"][mesh], &mut |a| self.add(*a, -1));
    }

    /// Count mesh `mesh`'s references again (after a stage edited it).
    pub fn put_back(&mut self, json: &mut Value, mesh: usize) {
        visit_mesh_refs(&mut json["meshes"][mesh], &mut |a| self.add(*a, 1));
    }

    /// References to accessor `a` outside the mesh left out (all of them if none is).
    pub fn outside(&self, a: usize) -> usize {
        self.counts.get(a).map_or(0, |&c| c as usize)
    }

    fn add(&mut self, a: usize, by: i32) {
        if a >= self.counts.len() {
            self.counts.resize(a + 1, 0);
        }
        self.counts[a] = self.counts[a].saturating_add_signed(by);
    }
}

/// `f` on the accessor index `v` holds (where it holds one), written back.
fn visit_index(v: &mut Value, f: &mut dyn FnMut(&mut usize)) {
    if let Some(i) = v.as_u64() {
        let mut i = i as usize;
        f(&mut i);
        *v = json!(i);
    }
}

/// The items of the array `v[key]` (none where it is not an array).
pub(crate) fn items_mut<'a>(v: &'a mut Value, key: &str) -> impl Iterator<Item = &'a mut Value> {
    v.get_mut(key)
        .and_then(Value::as_array_mut)
        .into_iter()
        .flatten()
}

/// `f` on every accessor index of a mesh's primitives (indices, attributes, morph targets).
pub(super) fn visit_mesh_refs(mesh: &mut Value, f: &mut dyn FnMut(&mut usize)) {
    for p in items_mut(mesh, "primitives") {
        if let Some(i) = p.get_mut("indices") {
            visit_index(i, f);
        }
        if let Some(a) = p.get_mut("attributes").and_then(Value::as_object_mut) {
            a.values_mut().for_each(|v| visit_index(v, f));
        }
        for t in items_mut(p, "targets").filter_map(Value::as_object_mut) {
            t.values_mut().for_each(|v| visit_index(v, f));
        }
    }
}

/// Call `f` on every accessor index the core spec (and EXT_mesh_gpu_instancing) refers to.
pub(super) fn visit_accessor_refs(json: &mut Value, f: &mut dyn FnMut(&mut usize)) {
    for m in items_mut(json, "meshes") {
        visit_mesh_refs(m, f);
    }
    for s in items_mut(json, "skins") {
        if let Some(i) = s.get_mut("inverseBindMatrices") {
            visit_index(i, f);
        }
    }
    for a in items_mut(json, "animations") {
        for s in items_mut(a, "samplers") {
            for k in ["input", "output"] {
                if let Some(i) = s.get_mut(k) {
                    visit_index(i, f);
                }
            }
        }
    }
    for n in items_mut(json, "nodes") {
        if let Some(a) = n
            .pointer_mut("/extensions/EXT_mesh_gpu_instancing/attributes")
            .and_then(Value::as_object_mut)
        {
            a.values_mut().for_each(|v| visit_index(v, f));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Five views of odd lengths, one accessor each; the 2nd and 4th accessors dropped.
    fn output(reversed: bool) -> Output {
        let mut out = Output::new(json!({ "accessors": [], "meshes": [] }));
        let lengths = [5usize, 12, 3, 8, 7];
        let order: Vec<usize> = match reversed {
            // Views laid out in the buffer against their order (view 4's data first).
            true => (0..5).rev().collect(),
            false => (0..5).collect(),
        };
        let mut views = vec![Value::Null; 5];
        for &i in &order {
            let data: Vec<u8> = (0..lengths[i]).map(|k| (10 * i + k) as u8 + 1).collect();
            let v = out.bin.push_view(&data, None);
            views[i] = out.bin.views[v].clone();
        }
        out.bin.views = views;
        for i in 0..5 {
            out.json["accessors"].as_array_mut().unwrap().push(
                json!({ "bufferView": i, "count": 1, "type": "SCALAR", "componentType": 5121 }),
            );
        }
        // Accessors 0, 2 and 4 used by a mesh.
        out.json["meshes"] = json!([{ "primitives": [
            { "attributes": { "A": 0, "B": 2 }, "indices": 4 } ] }]);
        out
    }

    fn view_bytes(out: &Output, acc: usize) -> Vec<u8> {
        let a = &out.json["accessors"][acc];
        let v = &out.bin.views[a["bufferView"].as_u64().unwrap() as usize];
        let s = v["byteOffset"].as_u64().unwrap() as usize;
        assert_eq!(s % 4, 0);
        out.bin.bytes[s..s + v["byteLength"].as_u64().unwrap() as usize].to_vec()
    }

    #[test]
    fn dropped_accessors_take_their_views_and_bytes_with_them() {
        for reversed in [false, true] {
            let before = output(reversed);
            let kept: Vec<Vec<u8>> = [0, 2, 4].iter().map(|&a| view_bytes(&before, a)).collect();
            let mut out = output(reversed);
            compact(&mut out, &BTreeSet::from([1, 3]));
            assert_eq!(arr(&out.json, "accessors").len(), 3, "reversed {reversed}");
            assert_eq!(out.bin.views.len(), 3);
            let prim = &out.json["meshes"][0]["primitives"][0];
            let now: Vec<Vec<u8>> = [
                &prim["attributes"]["A"],
                &prim["attributes"]["B"],
                &prim["indices"],
            ]
            .iter()
            .map(|a| view_bytes(&out, a.as_u64().unwrap() as usize))
            .collect();
            assert_eq!(now, kept, "reversed {reversed}");
            // Packed: 5 bytes, padding, 3 bytes, padding, 7 bytes.
            assert_eq!(out.bin.bytes.len(), 8 + 4 + 7);
            assert_eq!(&out.bin.bytes[5..8], &[0, 0, 0]);
        }
    }

    /// With a mesh left out, each accessor's references are those of the rest of the file
    /// (other meshes, skins, animations, instancing), whatever the mesh was edited into; put
    /// back, they are the whole file's again.
    #[test]
    fn references_outside_a_mesh_left_out() {
        let mut json = json!({
            "meshes": [
                {"primitives": [{"indices": 0, "attributes": {"POSITION": 1, "NORMAL": 2},
                                 "targets": [{"POSITION": 3}]}]},
                {"primitives": [{"attributes": {"POSITION": 1}}, {"attributes": {"POSITION": 4}}]},
            ],
            "skins": [{"inverseBindMatrices": 5}],
            "animations": [{"samplers": [{"input": 6, "output": 2}]}],
            "nodes": [{"extensions": {"EXT_mesh_gpu_instancing": {"attributes": {"TRANSLATION": 4}}}}],
        });
        let mut refs = AccessorRefs::of(&mut json);
        let whole = [1, 2, 2, 1, 2, 1, 1, 0];
        assert_eq!((0..8).map(|a| refs.outside(a)).collect::<Vec<_>>(), whole);
        refs.leave_out(&mut json, 0);
        assert_eq!(
            (0..8).map(|a| refs.outside(a)).collect::<Vec<_>>(),
            [0, 1, 1, 0, 2, 1, 1, 0]
        );
        // The mesh edited while left out: its target now reads a new accessor 7.
        json["meshes"][0]["primitives"][0]["targets"][0]["POSITION"] = json!(7);
        refs.put_back(&mut json, 0);
        assert_eq!(
            (0..8).map(|a| refs.outside(a)).collect::<Vec<_>>(),
            [1, 2, 2, 0, 2, 1, 1, 1]
        );
        let mut recount = vec![0; 8];
        visit_accessor_refs(&mut json, &mut |a| recount[*a] += 1);
        assert_eq!((0..8).map(|a| refs.outside(a)).collect::<Vec<_>>(), recount);
    }
}
