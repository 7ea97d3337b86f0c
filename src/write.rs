//! Write stage: the input document with dense morph animation, as `.glb` or `.gltf`.
//!
//! * Every buffer view of the input is copied into one output buffer (the GLB binary chunk, or
//!   `<output stem>.bin` beside a `.gltf`); accessors, images and everything else keep their
//!   indices, so references from extensions we do not know stay valid.
//! * External images are embedded in a `.glb`, or copied beside a `.gltf` written elsewhere.
//! * A processed mesh gets one morph target per output frame; its tracks' samplers get one key
//!   per frame with one-hot weights (LINEAR between consecutive frames).
//! * Accessor data the new targets and samplers replaced is dropped when no other object can
//!   refer to it (see [`compact`]).
//! * The file is written to a temporary name beside the target and renamed on success, so an
//!   existing output is only replaced by a complete file.

use crate::read::{arr, percent_decode, Document};
use crate::tween::MeshFrames;
use anyhow::{bail, Context, Result};
use serde_json::{json, Map, Value};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// Output container, from the file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Container {
    Glb,
    Gltf,
}

/// Binary data being assembled for the single output buffer.
#[derive(Default)]
pub struct BinBuilder {
    pub bytes: Vec<u8>,
    pub(crate) views: Vec<Value>,
}

impl BinBuilder {
    pub fn new() -> BinBuilder {
        BinBuilder::default()
    }

    /// Append `data` as a new buffer view (4-byte aligned) and return its index.
    pub fn push_view(&mut self, data: &[u8], target: Option<u32>) -> usize {
        while !self.bytes.len().is_multiple_of(4) {
            self.bytes.push(0);
        }
        let mut v =
            json!({ "buffer": 0, "byteOffset": self.bytes.len(), "byteLength": data.len() });
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        self.bytes.extend_from_slice(data);
        self.views.push(v);
        self.views.len() - 1
    }
}

/// The output document under construction.
pub struct Output {
    pub json: Value,
    pub bin: BinBuilder,
}

impl Output {
    /// Add a float accessor of `ncomp`-component elements; with `bounds`, min/max are set from
    /// the stored f32 values.
    pub fn push_f32(
        &mut self,
        data: &[f32],
        ty: &str,
        ncomp: usize,
        bounds: bool,
        target: Option<u32>,
    ) -> usize {
        let bytes: Vec<u8> = data.iter().flat_map(|v| v.to_le_bytes()).collect();
        let view = self.bin.push_view(&bytes, target);
        let count = data.len() / ncomp;
        let mut acc =
            json!({ "bufferView": view, "componentType": 5126, "count": count, "type": ty });
        if bounds && count > 0 {
            let mut lo = vec![f32::INFINITY; ncomp];
            let mut hi = vec![f32::NEG_INFINITY; ncomp];
            for e in data.chunks_exact(ncomp) {
                for c in 0..ncomp {
                    lo[c] = lo[c].min(e[c]);
                    hi[c] = hi[c].max(e[c]);
                }
            }
            acc["min"] = json!(lo);
            acc["max"] = json!(hi);
        }
        self.push_accessor(acc)
    }

    /// Append an accessor to the document and return its index.
    pub fn push_accessor(&mut self, acc: Value) -> usize {
        self.push_to("accessors", acc)
    }

    /// Append `value` to the document's top-level array `key` (created if absent) and return
    /// its index there.
    pub fn push_to(&mut self, key: &str, value: Value) -> usize {
        let entry = self
            .json
            .as_object_mut()
            .unwrap()
            .entry(key)
            .or_insert_with(|| json!([]));
        let list = entry.as_array_mut().unwrap();
        list.push(value);
        list.len() - 1
    }
}

/// Output format, chosen by the output file's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutputFormat {
    Gltf(Container),
    Usd(crate::usd::UsdFormat),
}

/// The output format for `path`, or an error naming it. The directory must exist.
pub fn format_for(path: &Path) -> Result<OutputFormat> {
    use crate::usd::UsdFormat;
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    let format = match ext.as_str() {
        "glb" => OutputFormat::Gltf(Container::Glb),
        "gltf" => OutputFormat::Gltf(Container::Gltf),
        "usda" => OutputFormat::Usd(UsdFormat::Usda),
        "usdc" | "usd" => OutputFormat::Usd(UsdFormat::Usdc),
        "usdz" => OutputFormat::Usd(UsdFormat::Usdz),
        _ => bail!(
            "{}: unknown output extension {ext:?} (use .glb, .gltf, .usda, .usdc or .usdz)",
            path.display()
        ),
    };
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        bail!(
            "{}: cannot write: directory {} does not exist",
            path.display(),
            dir.display()
        );
    }
    Ok(format)
}

/// Start an output from the input: all buffer views copied into one buffer.
pub fn begin(doc: &Document, container: Container, out_path: &Path) -> Result<Output> {
    let mut json = doc.json.clone();
    let mut bin = BinBuilder {
        bytes: Vec::new(),
        views: Vec::new(),
    };
    for (i, bv) in arr(&doc.json, "bufferViews").iter().enumerate() {
        let b = bv["buffer"].as_u64().unwrap_or(0) as usize;
        let start = bv["byteOffset"].as_u64().unwrap_or(0) as usize;
        let len = bv["byteLength"].as_u64().unwrap_or(0) as usize;
        let data = doc
            .buffers
            .get(b)
            .and_then(|d| d.get(start..start + len))
            .ok_or_else(|| doc.err(format!("bufferView {i} reaches past the end of buffer {b}")))?;
        let mut view = bv.clone();
        let idx = bin.push_view(data, None);
        let placed = bin.views[idx].clone();
        view["buffer"] = json!(0);
        view["byteOffset"] = placed["byteOffset"].clone();
        bin.views[idx] = view;
    }
    // Images referenced by file.
    let in_dir = doc.path.parent().unwrap_or(Path::new(".")).to_path_buf();
    let out_dir = out_path.parent().unwrap_or(Path::new(".")).to_path_buf();
    if let Some(images) = json.get_mut("images").and_then(Value::as_array_mut) {
        for (i, img) in images.iter_mut().enumerate() {
            let Some(uri) = img.get("uri").and_then(Value::as_str).map(str::to_owned) else {
                continue;
            };
            if uri.starts_with("data:") {
                continue;
            }
            let src = in_dir.join(percent_decode(&uri));
            match container {
                Container::Glb => {
                    let data = std::fs::read(&src).with_context(|| {
                        doc.err(format!("image {i} file {} cannot be read", src.display()))
                    })?;
                    let mime = img
                        .get("mimeType")
                        .and_then(Value::as_str)
                        .map(str::to_owned)
                        .or_else(|| mime_of(&uri).map(str::to_owned))
                        .unwrap_or_else(|| "image/png".into());
                    let view = bin.push_view(&data, None);
                    let o = img.as_object_mut().unwrap();
                    o.remove("uri");
                    o.insert("bufferView".into(), json!(view));
                    o.insert("mimeType".into(), json!(mime));
                }
                Container::Gltf => {
                    let dst = out_dir.join(percent_decode(&uri));
                    if !same_file(&src, &dst) {
                        if let Some(parent) = dst.parent() {
                            std::fs::create_dir_all(parent).ok();
                        }
                        std::fs::copy(&src, &dst).with_context(|| {
                            doc.err(format!(
                                "image {i} file {} cannot be copied to {}",
                                src.display(),
                                dst.display()
                            ))
                        })?;
                    }
                }
            }
        }
    }
    Ok(Output { json, bin })
}

fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => false,
    }
}

fn mime_of(uri: &str) -> Option<&'static str> {
    let lower = uri.to_ascii_lowercase();
    [
        (".png", "image/png"),
        (".jpg", "image/jpeg"),
        (".jpeg", "image/jpeg"),
        (".ktx2", "image/ktx2"),
        (".webp", "image/webp"),
    ]
    .iter()
    .find(|(e, _)| lower.ends_with(e))
    .map(|(_, m)| *m)
}

fn one_hot(len: usize, at: usize) -> Vec<f32> {
    let mut v = vec![0.0; len];
    if at < len {
        v[at] = 1.0;
    }
    v
}

/// Replace the targets and weight animation of each processed mesh.
pub fn apply_frames(out: &mut Output, meshes: &[MeshFrames]) -> Result<()> {
    // glTF key times cannot be negative: a motion extended before 0 s shifts every written
    // timeline by the same amount.
    let earliest = meshes
        .iter()
        .flat_map(|m| &m.tracks)
        .flat_map(|t| t.frames.first())
        .map(|f| f.time)
        .fold(0.0, f64::min);
    let shift = -earliest;
    let mut replaced: BTreeSet<usize> = BTreeSet::new(); // accessors no longer referenced by us
    let mut new_animation_samplers: Vec<Value> = Vec::new();
    let mut new_animation_channels: Vec<Value> = Vec::new();
    let mut dropped: Vec<(usize, usize)> = Vec::new();
    for m in meshes {
        let frames = m.frame_count();
        // Targets.
        for p in &m.primitives {
            let mut targets = Vec::with_capacity(frames);
            for f in 0..frames {
                let mut t = Map::new();
                let pos: Vec<f32> = p.positions[f].iter().flatten().copied().collect();
                t.insert(
                    "POSITION".into(),
                    json!(out.push_f32(&pos, "VEC3", 3, true, Some(34962))),
                );
                if let Some(n) = &p.normals {
                    let d: Vec<f32> = n[f].iter().flatten().copied().collect();
                    t.insert(
                        "NORMAL".into(),
                        json!(out.push_f32(&d, "VEC3", 3, false, Some(34962))),
                    );
                }
                if let Some(tg) = &p.tangents {
                    let d: Vec<f32> = tg[f].iter().flatten().copied().collect();
                    t.insert(
                        "TANGENT".into(),
                        json!(out.push_f32(&d, "VEC3", 3, false, Some(34962))),
                    );
                }
                targets.push(Value::Object(t));
            }
            let prim = &mut out.json["meshes"][m.mesh]["primitives"][p.index];
            for old in arr(prim, "targets") {
                for a in old.as_object().into_iter().flat_map(|o| o.values()) {
                    if let Some(a) = a.as_u64() {
                        replaced.insert(a as usize);
                    }
                }
            }
            prim["targets"] = Value::Array(targets);
        }
        let mesh = &mut out.json["meshes"][m.mesh];
        mesh["weights"] = json!(one_hot(frames, 0));
        let names: Vec<String> = m
            .tracks
            .iter()
            .flat_map(|t| {
                t.frames
                    .iter()
                    .enumerate()
                    .map(move |(i, f)| (t.first + i, f.time + shift))
            })
            .map(|(i, time)| format!("f{i:04}_t{time:.4}"))
            .collect();
        if !mesh.get("extras").is_some_and(Value::is_object) {
            mesh["extras"] = json!({});
        }
        mesh["extras"]["targetNames"] = json!(names);
        // Nodes that override the mesh's weights.
        if let Some(nodes) = out.json.get_mut("nodes").and_then(Value::as_array_mut) {
            for n in nodes.iter_mut() {
                if n["mesh"].as_u64() == Some(m.mesh as u64) && n.get("weights").is_some() {
                    n["weights"] = json!(one_hot(frames, 0));
                }
            }
        }
        // Animation: one key per frame of each track, one-hot over the track's frames.
        for track in &m.tracks {
            let times: Vec<f32> = track
                .frames
                .iter()
                .map(|f| (f.time + shift) as f32)
                .collect();
            let mut weights = Vec::with_capacity(times.len() * frames);
            for i in 0..times.len() {
                weights.extend(one_hot(frames, track.first + i));
            }
            let input = out.push_f32(&times, "SCALAR", 1, true, None);
            let output = out.push_f32(&weights, "SCALAR", 1, false, None);
            match &track.origin {
                crate::keyframes::TrackOrigin::Animation {
                    animation, sampler, ..
                } => {
                    let s = &mut out.json["animations"][*animation]["samplers"][*sampler];
                    for k in ["input", "output"] {
                        if let Some(a) = s[k].as_u64() {
                            replaced.insert(a as usize);
                        }
                    }
                    s["input"] = json!(input);
                    s["output"] = json!(output);
                    s["interpolation"] = json!("LINEAR");
                }
                crate::keyframes::TrackOrigin::Targets { nodes } => {
                    if nodes.is_empty() {
                        continue;
                    }
                    let si = new_animation_samplers.len();
                    new_animation_samplers.push(
                        json!({ "input": input, "output": output, "interpolation": "LINEAR" }),
                    );
                    for &n in nodes {
                        new_animation_channels.push(
                            json!({ "sampler": si, "target": { "node": n, "path": "weights" } }),
                        );
                    }
                }
            }
        }
        dropped.extend(m.dropped_channels.iter().copied());
    }
    drop_channels(&mut out.json, &dropped, &mut replaced);
    if !new_animation_channels.is_empty() {
        let anims = out
            .json
            .as_object_mut()
            .unwrap()
            .entry("animations")
            .or_insert_with(|| json!([]));
        anims.as_array_mut().unwrap().push(json!({
            "name": "inbetween",
            "samplers": new_animation_samplers,
            "channels": new_animation_channels,
        }));
    }
    compact(out, &replaced);
    Ok(())
}

/// Remove the given (animation, channel) pairs, the samplers only they used, and animations
/// left with no channel.
fn drop_channels(json: &mut Value, dropped: &[(usize, usize)], replaced: &mut BTreeSet<usize>) {
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
/// whose references [`compact`] rewrites). With any other extension present, nothing is dropped.
const KNOWN_EXTENSIONS: &[&str] = &[
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
    "KHR_materials_pbrSpecularGlossiness",
    "KHR_texture_transform",
    "KHR_texture_basisu",
    "KHR_lights_punctual",
    "KHR_mesh_quantization",
    "KHR_xmp_json_ld",
    "EXT_texture_webp",
    "EXT_texture_avif",
    "EXT_mesh_gpu_instancing",
];

/// Drop the accessors in `candidates` that nothing refers to any more, and the buffer views
/// only they used, renumbering every reference. Skipped when an unknown extension is present.
fn compact(out: &mut Output, candidates: &BTreeSet<usize>) {
    let json = &mut out.json;
    if candidates.is_empty()
        || arr(json, "extensionsUsed")
            .iter()
            .any(|e| !KNOWN_EXTENSIONS.contains(&e.as_str().unwrap_or("")))
    {
        return;
    }
    let accessor_count = arr(json, "accessors").len();
    let mut used = vec![false; accessor_count];
    visit_accessor_refs(json, &mut |a| {
        if let Some(u) = used.get_mut(*a) {
            *u = true;
        }
    });
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
    let mut mark = |v: &Value| {
        if let Some(i) = v.as_u64() {
            if let Some(u) = view_used.get_mut(i as usize) {
                *u = true;
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
    if view_used.iter().all(|&u| u) {
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
fn visit_accessor_refs(json: &mut Value, f: &mut dyn FnMut(&mut usize)) {
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

/// Serialize and write atomically: temporary files beside the target, renamed on success.
pub fn finish(out: Output, container: Container, path: &Path) -> Result<()> {
    finish_with(out, container, path, Vec::new())
}

/// [`finish`], writing `extra` files (a report) in the same all-or-nothing step.
pub fn finish_with(
    mut out: Output,
    container: Container,
    path: &Path,
    mut extra: Vec<(PathBuf, Vec<u8>)>,
) -> Result<()> {
    let views = std::mem::take(&mut out.bin.views);
    let json = out.json.as_object_mut().unwrap();
    if views.is_empty() {
        json.remove("bufferViews");
    } else {
        json.insert("bufferViews".into(), Value::Array(views));
    }
    let mut bin = std::mem::take(&mut out.bin.bytes);
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let bin_name = match container {
        Container::Gltf => Some(format!(
            "{}.bin",
            path.file_stem().and_then(|s| s.to_str()).unwrap_or("out")
        )),
        Container::Glb => None,
    };
    if bin.is_empty() {
        json.remove("buffers");
    } else {
        let mut b = json!({ "byteLength": bin.len() });
        if let Some(name) = &bin_name {
            b["uri"] = json!(encode_uri(name));
        }
        json.insert("buffers".into(), json!([b]));
    }
    match container {
        Container::Glb => {
            let mut js = serde_json::to_vec(&out.json)?;
            while js.len() % 4 != 0 {
                js.push(b' ');
            }
            let total = 12 + 8 + js.len() + if bin.is_empty() { 0 } else { 8 + bin.len() };
            let mut file = Vec::with_capacity(total);
            file.extend_from_slice(b"glTF");
            file.extend_from_slice(&2u32.to_le_bytes());
            file.extend_from_slice(&(total as u32).to_le_bytes());
            file.extend_from_slice(&(js.len() as u32).to_le_bytes());
            file.extend_from_slice(&0x4E4F_534Au32.to_le_bytes());
            file.extend_from_slice(&js);
            if !bin.is_empty() {
                file.extend_from_slice(&(bin.len() as u32).to_le_bytes());
                file.extend_from_slice(&0x004E_4942u32.to_le_bytes());
                file.extend_from_slice(&bin);
            }
            extra.push((path.to_path_buf(), file));
            atomic_write(&extra)
        }
        Container::Gltf => {
            let js = serde_json::to_vec_pretty(&out.json)?;
            let mut files = Vec::new();
            if let Some(name) = bin_name.filter(|_| !bin.is_empty()) {
                files.push((path.with_file_name(name), bin));
            }
            files.push((path.to_path_buf(), js));
            files.extend(extra);
            atomic_write(&files)
        }
    }
}

/// Minimal percent-encoding of a file name for a relative URI.
fn encode_uri(name: &str) -> String {
    name.bytes()
        .map(|b| match b {
            b'A'..=b'Z' | b'a'..=b'z' | b'0'..=b'9' | b'-' | b'_' | b'.' | b'~' => {
                (b as char).to_string()
            }
            _ => format!("%{b:02X}"),
        })
        .collect()
}

/// Stream one file through `fill` into a temporary file beside `path`, renamed on success;
/// on failure the temporary file is removed and `path` is not touched.
pub fn atomic_write_with(
    path: &Path,
    fill: impl FnOnce(&mut std::io::BufWriter<std::fs::File>) -> Result<()>,
) -> Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("out");
    let tmp = dir.join(format!(".{name}.{}.tmp", std::process::id()));
    let result = (|| -> Result<()> {
        let file = std::fs::File::create(&tmp)
            .map_err(|e| anyhow::anyhow!("{}: cannot write: {e}", path.display()))?;
        let mut w = std::io::BufWriter::with_capacity(1 << 20, file);
        fill(&mut w)?;
        use std::io::Write;
        w.flush()
            .map_err(|e| anyhow::anyhow!("{}: cannot write: {e}", path.display()))?;
        std::fs::rename(&tmp, path)
            .map_err(|e| anyhow::anyhow!("{}: cannot write: {e}", path.display()))
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Write every file under a temporary name in its own directory, then rename them all; on any
/// failure the temporaries are removed and no target is touched.
pub fn atomic_write(files: &[(PathBuf, Vec<u8>)]) -> Result<()> {
    let mut temps: Vec<(PathBuf, &PathBuf)> = Vec::new();
    let cleanup = |temps: &[(PathBuf, &PathBuf)]| {
        for (t, _) in temps {
            let _ = std::fs::remove_file(t);
        }
    };
    for (path, data) in files {
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        if !dir.is_dir() {
            cleanup(&temps);
            bail!(
                "{}: cannot write: directory {} does not exist",
                path.display(),
                dir.display()
            );
        }
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("out");
        let tmp = dir.join(format!(".{name}.{}.tmp", std::process::id()));
        if let Err(e) = std::fs::write(&tmp, data) {
            let _ = std::fs::remove_file(&tmp);
            cleanup(&temps);
            bail!("{}: cannot write: {e}", path.display());
        }
        temps.push((tmp, path));
    }
    for (tmp, path) in &temps {
        if let Err(e) = std::fs::rename(tmp, path) {
            cleanup(&temps);
            bail!("{}: cannot write: {e}", path.display());
        }
    }
    Ok(())
}
