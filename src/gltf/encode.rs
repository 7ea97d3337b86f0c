//! Encode stage (on write, with `--meshopt`/`--compact`): every buffer view that holds vertex
//! attributes, morph targets, indices or animation data is compressed with
//! `EXT_meshopt_compression` by meshoptimizer's own encoders (the `meshopt` crate): vertex
//! codec version 0 (what every EXT decoder reads), TRIANGLES for triangle-list indices,
//! INDICES for other index data, and a view the writer marked for it is first put through the
//! EXPONENTIAL filter (floats with fewer mantissa bits: lossy, within the tolerance the marker
//! was chosen for). Compressed views point into a fallback buffer without data (so the
//! extension is required, as the spec allows); the compressed bytes sit in the binary buffer.
//! Views of images, or shared by accessors that disagree on their layout, stay as they are.

use super::accessor::components;
use super::build::{set_bounds, Output};
use super::read::arr;
use serde_json::{json, Value};
use std::collections::BTreeMap;

/// The private key a writer puts on a buffer view of f32 values to have it encoded with the
/// EXPONENTIAL filter at this many mantissa bits; removed from every view on write.
pub const FILTER_MARK: &str = "inbetweenExpBits";
/// Views marked for the EXPONENTIAL filter that carry the same group name (and bits) are merged
/// into one view: their exponents are then shared, as the writer of the mark measured them.
/// Removed from every view on write.
pub const FILTER_GROUP: &str = "inbetweenExpGroup";

/// The private key a writer puts on a buffer view of unit vectors stored as normalized SHORT
/// (x, y, z and w or padding: 8-byte elements) to have it encoded with meshopt's OCTAHEDRAL
/// filter at this many bits (2 to 16); removed from every view on write. See
/// [`oct_roundtrip`].
pub const OCT_MARK: &str = "inbetweenOctBits";

/// The private key a writer puts on a buffer view of scalars read as rows (a weights
/// animation's output: one row of targets per key) to have meshopt's codec (and the
/// EXPONENTIAL filter, one exponent per component) take elements of this many bytes; removed
/// from every view on write. See [`row_components`].
pub const ELEMENT_MARK: &str = "inbetweenElement";

/// How many scalars of a row of `width` (a weights animation's targets per key) make one
/// element of a view marked with [`ELEMENT_MARK`]: the whole row where the codec allows (at
/// most 64 four-byte components), else the largest divisor of it that fits.
pub fn row_components(width: usize) -> usize {
    (1..=width.clamp(1, 64))
        .rev()
        .find(|d| width.is_multiple_of(*d))
        .unwrap_or(1)
}

/// The filter a view is marked for.
#[derive(Clone, Copy)]
enum Filter {
    None,
    Exp(i32),
    Oct(i32),
}

/// How a buffer view is read, as far as the accessors that use it say.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Use {
    /// Vertex, target or animation data: elements of `stride` bytes.
    Attributes { stride: usize },
    /// Indices of `stride` bytes; `triangles` when they form a triangle list read whole.
    Indices { stride: usize, triangles: bool },
    /// Read in ways that cannot be compressed (mixed layouts, images, unknown).
    Other,
}

fn component_size(ty: u64) -> usize {
    match ty {
        5120 | 5121 => 1,
        5122 | 5123 => 2,
        _ => 4,
    }
}

/// How each of `views` (the views being written) is used by the accessors of `json`.
fn uses(json: &Value, views: &[Value]) -> BTreeMap<usize, Use> {
    let mut out: BTreeMap<usize, Use> = BTreeMap::new();
    let mut meet = |view: Option<u64>, u: Use| {
        if let Some(v) = view {
            let e = out.entry(v as usize).or_insert(u);
            if *e != u {
                *e = Use::Other;
            }
        }
    };
    let index_accessors: BTreeMap<u64, bool> = arr(json, "meshes")
        .iter()
        .flat_map(|m| arr(m, "primitives"))
        .filter_map(|p| Some((p["indices"].as_u64()?, p["mode"].as_u64().unwrap_or(4) == 4)))
        .collect();
    for (i, a) in arr(json, "accessors").iter().enumerate() {
        let elem = component_size(a["componentType"].as_u64().unwrap_or(0))
            * components(a["type"].as_str().unwrap_or("")).unwrap_or(0);
        if let Some(v) = a["bufferView"].as_u64() {
            let Some(view) = views.get(v as usize) else {
                continue;
            };
            let stride = view["byteStride"].as_u64().map_or(elem, |s| s as usize);
            let whole = a["byteOffset"].as_u64().unwrap_or(0) == 0
                && view["byteLength"].as_u64() == a["count"].as_u64().map(|c| c * stride as u64);
            let u = match index_accessors.get(&(i as u64)) {
                Some(&tri) => Use::Indices {
                    stride,
                    triangles: tri && whole && a["count"].as_u64().unwrap_or(1) % 3 == 0,
                },
                None => Use::Attributes { stride },
            };
            meet(Some(v), if elem == 0 { Use::Other } else { u });
        }
        // Sparse parts are stored raw: cgltf (gltfpack's reader; Filament and raylib use it) reads
        // them from their buffer before any view is decoded, and the fallback buffer has no
        // data ("buffer has no data"); they are small where sparse storage pays.
        let sparse = &a["sparse"];
        if sparse.is_object() {
            meet(sparse["indices"]["bufferView"].as_u64(), Use::Other);
            meet(sparse["values"]["bufferView"].as_u64(), Use::Other);
        }
    }
    for img in arr(json, "images") {
        meet(img["bufferView"].as_u64(), Use::Other);
    }
    out
}

/// The compressed form of view data `data` used as `u`, with its extension object (less the
/// buffer offset and length, which the caller sets), if it can be compressed.
fn compress(data: &[u8], u: Use, filter: Filter) -> Option<(Vec<u8>, Value)> {
    match u {
        Use::Attributes { stride } => {
            if !filterable(data, stride) {
                return None;
            }
            let count = data.len() / stride;
            let mut data = data.to_vec();
            let filter = match filter {
                Filter::Oct(bits) if stride == 8 => {
                    let ints: Vec<i16> = data
                        .chunks_exact(2)
                        .map(|c| i16::from_le_bytes([c[0], c[1]]))
                        .collect();
                    data = oct_encode(&ints, bits)
                        .iter()
                        .flat_map(|v| v.to_le_bytes())
                        .collect();
                    "OCTAHEDRAL"
                }
                Filter::Oct(_) => return None,
                Filter::Exp(bits) => {
                    let encoded = exp_encode(&f32s(&data), count, stride, bits);
                    data = encoded.iter().flat_map(|v| v.to_le_bytes()).collect();
                    "EXPONENTIAL"
                }
                Filter::None => "NONE",
            };
            let bound = unsafe { meshopt::ffi::meshopt_encodeVertexBufferBound(count, stride) };
            let mut out = vec![0u8; bound];
            // SAFETY: `out` holds the bound the encoder asks for; `data` holds count * stride
            // bytes.
            let size = unsafe {
                meshopt::ffi::meshopt_encodeVertexBufferLevel(
                    out.as_mut_ptr(),
                    out.len(),
                    data.as_ptr().cast(),
                    count,
                    stride,
                    2,
                    0,
                )
            };
            if size == 0 {
                return None;
            }
            out.truncate(size);
            let mut ext = json!({ "byteStride": stride, "count": count, "mode": "ATTRIBUTES" });
            if filter != "NONE" {
                ext["filter"] = json!(filter);
            }
            Some((out, ext))
        }
        Use::Indices { stride, triangles } => {
            if (stride != 2 && stride != 4) || !data.len().is_multiple_of(stride) {
                return None;
            }
            let indices: Vec<u32> = data
                .chunks_exact(stride)
                .map(|c| match stride {
                    2 => u16::from_le_bytes([c[0], c[1]]) as u32,
                    _ => u32::from_le_bytes([c[0], c[1], c[2], c[3]]),
                })
                .collect();
            let vertices = indices.iter().max().map_or(0, |m| *m as usize + 1);
            let (encoded, mode) = if triangles {
                (
                    meshopt::encode_index_buffer(&indices, vertices).ok()?,
                    "TRIANGLES",
                )
            } else {
                (
                    meshopt::encode_index_sequence(&indices, vertices).ok()?,
                    "INDICES",
                )
            };
            Some((
                encoded,
                json!({ "byteStride": stride, "count": indices.len(), "mode": mode }),
            ))
        }
        Use::Other => None,
    }
}

/// Merge runs of views that hold vertex data of one layout (same stride, target and filter
/// mark, each read only by plain accessors, e.g. the morph targets of a primitive) into one
/// view each, the accessors pointed into it: one meshopt stream instead of many (less JSON,
/// better compression).
fn coalesce(out: &mut Output) {
    let uses = uses(&out.json, &out.bin.views);
    let views = std::mem::take(&mut out.bin.views);
    // Accessors reading each view directly (sparse views are never merged).
    let mut readers: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    let mut sparse_views = std::collections::BTreeSet::new();
    for (i, a) in arr(&out.json, "accessors").iter().enumerate() {
        if let Some(v) = a["bufferView"].as_u64() {
            readers.entry(v as usize).or_default().push(i);
        }
        for k in ["indices", "values"] {
            if let Some(v) = a["sparse"][k]["bufferView"].as_u64() {
                sparse_views.insert(v as usize);
            }
        }
    }
    type Key = (usize, Option<u64>, Option<i64>, Option<String>);
    let key = |i: usize, v: &Value| -> Option<Key> {
        match uses.get(&i) {
            // Only vertex views (target ARRAY_BUFFER) may carry a byteStride.
            Some(Use::Attributes { stride })
                if !sparse_views.contains(&i)
                    && readers.contains_key(&i)
                    && v["target"].as_u64() == Some(34962)
                    && stride.is_multiple_of(4)
                    // The EXPONENTIAL filter shares one exponent per component over a view:
                    // merged, a small target would lose the precision it was marked for, unless
                    // its writer grouped it with the others knowingly.
                    && (v.get(FILTER_MARK).is_none() || v.get(FILTER_GROUP).is_some())
                    && v.get(OCT_MARK).is_none() =>
            {
                Some((
                    *stride,
                    v["target"].as_u64(),
                    v.get(FILTER_MARK).and_then(Value::as_i64),
                    v.get(FILTER_GROUP)
                        .and_then(Value::as_str)
                        .map(str::to_owned),
                ))
            }
            _ => None,
        }
    };
    let mut merged: Vec<Value> = Vec::with_capacity(views.len());
    let mut remap = vec![(0usize, 0usize); views.len()]; // (new view, byte offset in it)
    let mut bytes = Vec::with_capacity(out.bin.bytes.len());
    let mut open: Option<(Key, usize)> = None; // (key, view)
    for (i, v) in views.iter().enumerate() {
        let start = v["byteOffset"].as_u64().unwrap_or(0) as usize;
        let len = v["byteLength"].as_u64().unwrap_or(0) as usize;
        let k = key(i, v);
        match (&k, &open) {
            (Some(k), Some((ok, at))) if ok == k => {
                let at = *at;
                let view = &mut merged[at];
                let offset = view["byteLength"].as_u64().unwrap_or(0) as usize;
                view["byteLength"] = json!(offset + len);
                remap[i] = (at, offset);
            }
            _ => {
                while !bytes.len().is_multiple_of(4) {
                    bytes.push(0);
                }
                let mut nv = v.clone();
                nv["byteOffset"] = json!(bytes.len());
                if let Some((stride, ..)) = &k {
                    nv["byteStride"] = json!(stride);
                }
                merged.push(nv);
                remap[i] = (merged.len() - 1, 0);
                open = k.map(|k| (k, merged.len() - 1));
            }
        }
        bytes.extend_from_slice(&out.bin.bytes[start..start + len]);
    }
    let fix = |v: &mut Value, off: Option<&mut Value>| {
        if let Some(i) = v.as_u64() {
            let (to, shift) = remap[i as usize];
            *v = json!(to);
            if let Some(o) = off {
                *o = json!(o.as_u64().unwrap_or(0) as usize + shift);
            }
        }
    };
    let accessors = out.json.get_mut("accessors").and_then(Value::as_array_mut);
    for a in accessors.into_iter().flatten() {
        if a.get("bufferView").is_some() {
            let mut offset = a.get("byteOffset").cloned().unwrap_or(json!(0));
            fix(&mut a["bufferView"], Some(&mut offset));
            if offset != json!(0) {
                a["byteOffset"] = offset;
            }
        }
        for k in ["indices", "values"] {
            if let Some(v) = a.pointer_mut(&format!("/sparse/{k}/bufferView")) {
                fix(v, None);
            }
        }
    }
    let images = out.json.get_mut("images").and_then(Value::as_array_mut);
    for img in images.into_iter().flatten() {
        if let Some(v) = img.get_mut("bufferView") {
            fix(v, None);
        }
    }
    out.bin.views = merged;
    out.bin.bytes = bytes;
}

/// Compress every view of `out` that can be, in place (runs of views of one vertex layout
/// merged first): the binary buffer is rebuilt with the compressed streams and the views left
/// raw; returns the size of the fallback buffer (0 when nothing was compressed).
///
/// A view marked for the EXPONENTIAL filter holds, compressed or left raw, the values a reader
/// decodes from the filtered stream, and the bounds of the accessors reading it are theirs:
/// writers mark a view and declare bounds before it is known which of the two it becomes.
pub fn meshopt(out: &mut Output) -> usize {
    coalesce(out);
    let uses = uses(&out.json, &out.bin.views);
    let mut bytes = Vec::with_capacity(out.bin.bytes.len() / 2);
    let mut fallback = 0usize;
    // Marked views as decoded (f32 values, from the view's start).
    let mut decoded: BTreeMap<usize, Vec<f32>> = BTreeMap::new();
    for (i, view) in out.bin.views.iter_mut().enumerate() {
        let start = view["byteOffset"].as_u64().unwrap_or(0) as usize;
        let len = view["byteLength"].as_u64().unwrap_or(0) as usize;
        let data = &out.bin.bytes[start..start + len];
        let mark = |key: &str| view.get(key).and_then(Value::as_i64).map(|b| b as i32);
        let filter = match (mark(FILTER_MARK), mark(OCT_MARK)) {
            (Some(b), _) => Filter::Exp(b),
            (_, Some(b)) => Filter::Oct(b),
            _ => Filter::None,
        };
        let mut u = uses.get(&i).copied().unwrap_or(Use::Other);
        if let (Use::Attributes { .. }, Some(e)) =
            (u, view.get(ELEMENT_MARK).and_then(Value::as_u64))
        {
            u = Use::Attributes { stride: e as usize };
        }
        if let (Filter::Exp(bits), Use::Attributes { stride }) = (filter, u) {
            if filterable(data, stride) {
                decoded.insert(i, exp_roundtrip(&f32s(data), stride / 4, bits));
            }
        }
        while !bytes.len().is_multiple_of(4) {
            bytes.push(0);
        }
        match compress(data, u, filter).filter(|(c, _)| c.len() < len) {
            Some((compressed, mut ext)) => {
                ext["buffer"] = json!(0);
                ext["byteOffset"] = json!(bytes.len());
                ext["byteLength"] = json!(compressed.len());
                bytes.extend_from_slice(&compressed);
                while !fallback.is_multiple_of(4) {
                    fallback += 1;
                }
                view["buffer"] = json!(1);
                view["byteOffset"] = json!(fallback);
                view["extensions"] = json!({ "EXT_meshopt_compression": ext });
                fallback += len;
            }
            None => {
                view["byteOffset"] = json!(bytes.len());
                match decoded.get(&i) {
                    Some(values) => bytes.extend(values.iter().flat_map(|v| v.to_le_bytes())),
                    None => bytes.extend_from_slice(data),
                }
            }
        }
    }
    out.bin.bytes = bytes;
    rebound(out, &decoded);
    fallback
}

/// Whether view data read as elements of `stride` bytes can go through the EXPONENTIAL
/// filter (meshopt's limits).
fn filterable(data: &[u8], stride: usize) -> bool {
    stride > 0 && stride.is_multiple_of(4) && stride <= 256 && data.len().is_multiple_of(stride)
}

/// The declared min/max of every float accessor reading a view of `decoded` set to those of the
/// values it decodes to (sparse parts are never filtered: see [`uses`]).
fn rebound(out: &mut Output, decoded: &BTreeMap<usize, Vec<f32>>) {
    let views = &out.bin.views;
    let Some(accessors) = out.json.get_mut("accessors").and_then(Value::as_array_mut) else {
        return;
    };
    for a in accessors {
        let n = components(a["type"].as_str().unwrap_or("")).unwrap_or(0);
        let count = a["count"].as_u64().unwrap_or(0) as usize;
        if n == 0 || count == 0 || a["componentType"].as_u64() != Some(5126) {
            continue;
        }
        if a.get("min").is_none() && a.get("max").is_none() {
            continue;
        }
        let Some(v) = a["bufferView"]
            .as_u64()
            .filter(|_| !a["sparse"].is_object())
        else {
            continue;
        };
        let Some(floats) = decoded.get(&(v as usize)) else {
            continue;
        };
        let stride = views[v as usize]["byteStride"]
            .as_u64()
            .map_or(n, |s| s as usize / 4);
        let first = a["byteOffset"].as_u64().unwrap_or(0) as usize / 4;
        let values: Vec<f32> = (0..count)
            .filter_map(|e| floats.get(first + e * stride..first + e * stride + n))
            .flatten()
            .copied()
            .collect();
        if values.len() != count * n {
            continue;
        }
        set_bounds(a, &values, n);
    }
}

/// Remove the writer's private marks from every view.
pub fn clear_marks(out: &mut Output) {
    for view in &mut out.bin.views {
        if let Some(o) = view.as_object_mut() {
            o.remove(FILTER_MARK);
            o.remove(FILTER_GROUP);
            o.remove(ELEMENT_MARK);
            o.remove(OCT_MARK);
        }
    }
}

/// Little-endian bytes read as f32 values.
fn f32s(data: &[u8]) -> Vec<f32> {
    data.chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

/// `floats` (`count` vectors of `stride` bytes) through meshopt's EXPONENTIAL filter at `bits`
/// mantissa bits, one exponent per component over all of them.
fn exp_encode(floats: &[f32], count: usize, stride: usize, bits: i32) -> Vec<u32> {
    let mut encoded = vec![0u32; floats.len()];
    assert_eq!(floats.len() * 4, count * stride);
    // SAFETY: both arrays hold count * stride / 4 values of 4 bytes (checked above); the
    // encoder reads `floats` and writes `encoded`, one vector of stride bytes per element.
    unsafe {
        meshopt::ffi::meshopt_encodeFilterExp(
            encoded.as_mut_ptr().cast(),
            count,
            stride,
            bits,
            floats.as_ptr(),
            meshopt::EncodeExpMode::SharedComponent as meshopt::ffi::meshopt_EncodeExpMode,
        );
    }
    encoded
}

/// `values` (vectors of `components` f32) as a reader decodes them after the EXPONENTIAL filter
/// at `bits` mantissa bits, as [`meshopt`] encodes a marked view (one exponent per component
/// over the whole view).
pub fn exp_roundtrip(values: &[f32], components: usize, bits: i32) -> Vec<f32> {
    let stride = 4 * components;
    let count = values.len() / components.max(1);
    let mut encoded = exp_encode(values, count, stride, bits);
    // SAFETY: `encoded` holds count elements of stride bytes; decoded in place.
    unsafe {
        meshopt::ffi::meshopt_decodeFilterExp(encoded.as_mut_ptr().cast(), count, stride);
    }
    encoded.iter().map(|&b| f32::from_bits(b)).collect()
}

/// Unit vectors (x, y, z, w: normalized i16, 4 per element) through meshopt's OCTAHEDRAL filter
/// at `bits`, as the encoder stores them.
fn oct_encode(ints: &[i16], bits: i32) -> Vec<i16> {
    let floats: Vec<f32> = ints
        .iter()
        .map(|&i| (i as f32 / 32767.0).max(-1.0))
        .collect();
    let mut out = vec![0i16; ints.len() / 4 * 4];
    // SAFETY: `out` and `floats` hold count * 4 values; the encoder writes 8 bytes an element.
    unsafe {
        meshopt::ffi::meshopt_encodeFilterOct(
            out.as_mut_ptr().cast(),
            out.len() / 4,
            8,
            bits,
            floats.as_ptr(),
        );
    }
    out
}

/// Unit vectors stored as normalized i16 (x, y, z, w, 4 per element) as a reader decodes them
/// after the OCTAHEDRAL filter at `bits` (2 to 16), as the encoder applies it to a view marked
/// with [`OCT_MARK`].
pub fn oct_roundtrip(ints: &[i16], bits: i32) -> Vec<i16> {
    let mut e = oct_encode(ints, bits);
    // SAFETY: `e` holds count elements of 8 bytes, decoded in place.
    unsafe {
        meshopt::ffi::meshopt_decodeFilterOct(e.as_mut_ptr().cast(), e.len() / 4, 8);
    }
    e
}
