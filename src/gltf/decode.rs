//! Decode stage (on read): data compressed by `EXT_meshopt_compression` /
//! `KHR_meshopt_compression` (buffer views, with their octahedral, quaternion, exponential and
//! colour filters; meshoptimizer's own decoders through the `meshopt` crate) and by
//! `KHR_draco_mesh_compression` (primitives; the `draco-core` decoder) is decoded into one new
//! buffer, and the views and accessors are pointed at it, so the rest of the pipeline reads
//! plain accessors and the writer writes them uncompressed. The extensions are then no longer
//! used and leave `extensionsUsed` / `extensionsRequired`. Where decoding is lossy (Draco's
//! quantization, meshopt's filters) the accessors' declared min/max, the encoder's bounds of the
//! values before it, are set from the decoded values, which the output holds. Quantized attributes
//! (`KHR_mesh_quantization`) need no decoding: accessors read them as they are.
//!
//! Sizes are checked before decoding: a view decodes to at most its declared length, and all
//! decoded data together to at most [`MAX_DECODED`] bytes.

use super::accessor::{components, raw_component};
use super::read::arr;
use serde_json::{json, Value};

/// The compression extensions this stage removes.
pub const DECODED_EXTENSIONS: &[&str] = &[
    "EXT_meshopt_compression",
    "KHR_meshopt_compression",
    "KHR_draco_mesh_compression",
];

/// Most bytes all compressed data of one file may decode to (16 GiB): a hostile header that
/// claims more is refused before anything is allocated.
pub const MAX_DECODED: u64 = 16 << 30;

/// Decode every compressed view and primitive of `json` whose data are in `buffers`, appending
/// the decoded data as a new buffer; returns the extensions decoded. Errors say what is wrong
/// (the caller names the file).
pub fn decode(json: &mut Value, buffers: &mut Vec<Vec<u8>>) -> Result<Vec<String>, String> {
    let decoded: Vec<String> = arr(json, "extensionsUsed")
        .iter()
        .filter_map(Value::as_str)
        .filter(|e| DECODED_EXTENSIONS.contains(e))
        .map(str::to_owned)
        .collect();
    if decoded.is_empty() {
        return Ok(decoded);
    }
    let mut out = Decoded {
        bytes: Vec::new(),
        buffer: buffers.len(),
    };
    let mut filtered = Vec::new();
    for v in 0..arr(json, "bufferViews").len() {
        if meshopt_view(json, buffers, v, &mut out)? {
            filtered.push(v);
        }
    }
    rebound_filtered(json, &out.bytes, &filtered);
    // Draco streams may themselves sit in views that meshopt decoded.
    for m in 0..arr(json, "meshes").len() {
        for p in 0..arr(&json["meshes"][m], "primitives").len() {
            draco_primitive(json, buffers, m, p, &mut out)?;
        }
    }
    json["buffers"]
        .as_array_mut()
        .ok_or("has compressed data but no buffers")?
        .push(json!({ "byteLength": out.bytes.len() }));
    buffers.push(out.bytes);
    remove_extensions(json);
    Ok(decoded)
}

/// The decoded data so far, to become buffer `buffer`.
struct Decoded {
    bytes: Vec<u8>,
    buffer: usize,
}

impl Decoded {
    /// Append `data` (4-byte aligned) and return its offset; refused past [`MAX_DECODED`].
    fn push(&mut self, data: &[u8]) -> Result<usize, String> {
        pad4(&mut self.bytes);
        if (self.bytes.len() + data.len()) as u64 > MAX_DECODED {
            return Err(format!(
                "compressed data decode to more than {} GiB",
                MAX_DECODED >> 30
            ));
        }
        let at = self.bytes.len();
        self.bytes.extend_from_slice(data);
        Ok(at)
    }
}

fn pad4(v: &mut Vec<u8>) {
    while !v.len().is_multiple_of(4) {
        v.push(0);
    }
}

/// The meshopt extension object of a buffer view, under either name.
fn meshopt_ext(view: &Value) -> Option<&Value> {
    let ext = &view["extensions"];
    ext.get("KHR_meshopt_compression")
        .or_else(|| ext.get("EXT_meshopt_compression"))
}

/// Decode buffer view `v` when it is meshopt-compressed: its data land in `out` and the view
/// points there. Returns whether a filter (lossy: exponential, octahedral, quaternion, colour)
/// was undone.
fn meshopt_view(
    json: &mut Value,
    buffers: &[Vec<u8>],
    v: usize,
    out: &mut Decoded,
) -> Result<bool, String> {
    let view = &json["bufferViews"][v];
    let Some(ext) = meshopt_ext(view) else {
        return Ok(false);
    };
    let what = format!("bufferView {v} (meshopt)");
    let num = |k: &str| ext[k].as_u64().ok_or(format!("{what} has no {k}"));
    let (buffer, offset, length) = (
        num("buffer")?,
        ext["byteOffset"].as_u64().unwrap_or(0),
        num("byteLength")?,
    );
    let (stride, count) = (num("byteStride")? as usize, num("count")? as usize);
    let source = buffers
        .get(buffer as usize)
        .and_then(|b| b.get(offset as usize..offset.checked_add(length)? as usize))
        .ok_or(format!(
            "{what}: its compressed bytes lie outside buffer {buffer}"
        ))?;
    let size = count
        .checked_mul(stride)
        .filter(|&s| s as u64 <= view["byteLength"].as_u64().unwrap_or(0))
        .ok_or(format!(
            "{what}: {count} elements of {stride} bytes exceed the view's byteLength"
        ))?;
    if (out.bytes.len() + size) as u64 > MAX_DECODED {
        return Err(format!(
            "compressed data decode to more than {} GiB",
            MAX_DECODED >> 30
        ));
    }
    let mode = ext["mode"].as_str().unwrap_or("");
    let filter = ext["filter"].as_str().unwrap_or("NONE").to_owned();
    let mut data = match mode {
        "ATTRIBUTES" => {
            if stride == 0 || !stride.is_multiple_of(4) || stride > 256 {
                return Err(format!(
                    "{what}: ATTRIBUTES byteStride {stride} is not a multiple of 4 up to 256"
                ));
            }
            let mut data = vec![0u8; size];
            // SAFETY: `data` holds count * stride bytes, what the decoder writes; it reads only
            // `source`, and is documented safe on untrusted input.
            let rc = unsafe {
                meshopt::ffi::meshopt_decodeVertexBuffer(
                    data.as_mut_ptr().cast(),
                    count,
                    stride,
                    source.as_ptr(),
                    source.len(),
                )
            };
            if rc != 0 {
                return Err(format!(
                    "{what}: the vertex stream does not decode (code {rc})"
                ));
            }
            data
        }
        "TRIANGLES" | "INDICES" => {
            if stride != 2 && stride != 4 || mode == "TRIANGLES" && !count.is_multiple_of(3) {
                return Err(format!(
                    "{what}: {mode} with byteStride {stride} and count {count}"
                ));
            }
            let bad =
                |e: meshopt::Error| format!("{what}: the index stream does not decode ({e:?})");
            match (mode, stride) {
                ("TRIANGLES", 2) => {
                    bytes_of(&meshopt::decode_index_buffer::<u16>(source, count).map_err(bad)?)
                }
                ("TRIANGLES", _) => {
                    bytes_of(&meshopt::decode_index_buffer::<u32>(source, count).map_err(bad)?)
                }
                (_, 2) => {
                    bytes_of(&meshopt::decode_index_sequence::<u16>(source, count).map_err(bad)?)
                }
                _ => bytes_of(&meshopt::decode_index_sequence::<u32>(source, count).map_err(bad)?),
            }
        }
        m => return Err(format!("{what}: unknown mode {m:?}")),
    };
    unfilter(&mut data, &filter, stride, count).map_err(|e| format!("{what}: {e}"))?;
    data.resize(view["byteLength"].as_u64().unwrap_or(0) as usize, 0);
    let at = out.push(&data)?;
    let buffer_index = out.buffer;
    let view = &mut json["bufferViews"][v];
    view["buffer"] = json!(buffer_index);
    view["byteOffset"] = json!(at);
    if let Some(o) = view.get_mut("extensions").and_then(Value::as_object_mut) {
        o.remove("EXT_meshopt_compression");
        o.remove("KHR_meshopt_compression");
        if o.is_empty() {
            view.as_object_mut().map(|v| v.remove("extensions"));
        }
    }
    Ok(filter != "NONE")
}

/// Set the min and max of the accessors in `views` (decoded through a lossy meshopt filter, at
/// their offsets in `bytes`) that declare them to the decoded values': an encoder declares the
/// bounds of the values before its filter (gltfpack -cc -vpf: positions up to 4e-3 past them on
/// Flamingo), which no validator sees in the compressed file and every one sees once written
/// plain. Sparse accessors keep theirs.
fn rebound_filtered(json: &mut Value, bytes: &[u8], views: &[usize]) {
    for acc in 0..arr(json, "accessors").len() {
        let a = &json["accessors"][acc];
        let Some(v) = a["bufferView"].as_u64().map(|v| v as usize) else {
            continue;
        };
        if !views.contains(&v) || a.get("min").is_none() && a.get("max").is_none() {
            continue;
        }
        if a.get("sparse").is_some() {
            continue;
        }
        let view = &json["bufferViews"][v];
        let ty = a["componentType"].as_u64().unwrap_or(0) as u32;
        let known = matches!(ty, 5120..=5123 | 5125 | 5126);
        let Some(ncomp) = components(a["type"].as_str().unwrap_or("")).filter(|_| known) else {
            continue;
        };
        let size = component_size(ty);
        let stride = view["byteStride"]
            .as_u64()
            .map_or(size * ncomp, |s| s as usize);
        let width = size * ncomp;
        let count = a["count"].as_u64().unwrap_or(0) as usize;
        // Where the last element ends, in checked arithmetic (the numbers are the file's).
        let start = (view["byteOffset"].as_u64().unwrap_or(0))
            .checked_add(a["byteOffset"].as_u64().unwrap_or(0))
            .and_then(|s| usize::try_from(s).ok());
        let end = start.zip(count.checked_sub(1)).and_then(|(start, last)| {
            last.checked_mul(stride)?
                .checked_add(start)?
                .checked_add(width)
        });
        let (Some(start), Some(_)) = (start, end.filter(|&e| e <= bytes.len())) else {
            continue;
        };
        let element = |i: usize| &bytes[start + i * stride..start + i * stride + width];
        let stored: Vec<f64> = (0..count)
            .flat_map(|i| (0..ncomp).map(move |c| raw_component(element(i), c * size, ty)))
            .collect();
        declare_bounds(json, acc, &stored, ncomp);
    }
}

/// Set accessor `acc`'s min and max to those of `stored` (elements of `ncomp` values as
/// stored).
fn declare_bounds(json: &mut Value, acc: usize, stored: &[f64], ncomp: usize) {
    let bound = |pick: fn(f64, f64) -> f64| -> Vec<f64> {
        (0..ncomp)
            .map(|c| {
                stored
                    .iter()
                    .skip(c)
                    .step_by(ncomp)
                    .copied()
                    .reduce(pick)
                    .unwrap_or(0.0)
            })
            .collect()
    };
    json["accessors"][acc]["min"] = json!(bound(f64::min));
    json["accessors"][acc]["max"] = json!(bound(f64::max));
}

fn bytes_of<T: Copy + Into<u32>>(v: &[T]) -> Vec<u8> {
    let size = std::mem::size_of::<T>();
    v.iter()
        .flat_map(|&x| x.into().to_le_bytes().into_iter().take(size))
        .collect()
}

/// Undo a meshopt filter in place on `count` elements of `stride` bytes.
fn unfilter(data: &mut [u8], filter: &str, stride: usize, count: usize) -> Result<(), String> {
    type Filter = unsafe extern "C" fn(*mut std::ffi::c_void, usize, usize);
    let (run, allowed): (Filter, bool) = match filter {
        "NONE" => return Ok(()),
        "OCTAHEDRAL" => (
            meshopt::ffi::meshopt_decodeFilterOct,
            stride == 4 || stride == 8,
        ),
        "QUATERNION" => (meshopt::ffi::meshopt_decodeFilterQuat, stride == 8),
        "EXPONENTIAL" => (
            meshopt::ffi::meshopt_decodeFilterExp,
            stride.is_multiple_of(4),
        ),
        "COLOR" => (
            meshopt::ffi::meshopt_decodeFilterColor,
            stride == 4 || stride == 8,
        ),
        f => return Err(format!("unknown filter {f:?}")),
    };
    if !allowed {
        return Err(format!("filter {filter} with byteStride {stride}"));
    }
    // SAFETY: `data` holds at least count * stride bytes (checked by the caller), which is
    // what the filter reads and writes.
    unsafe { run(data.as_mut_ptr().cast(), count, stride) };
    Ok(())
}

/// Decode primitive `p` of mesh `m` when it is Draco-compressed: its attributes and indices
/// land in `out`, in the types their accessors declare, and the accessors point there.
/// The primitive's accessors say how many points and faces its stream decodes to (the extension
/// requires them to match): nothing larger is decoded, so a stream whose header claims billions
/// is refused there, before the decoder sizes anything by it.
fn draco_limits(json: &Value, prim: &Value) -> draco_core::DecodeLimits {
    let count = |a: &Value| {
        a.as_u64()
            .and_then(|a| json["accessors"][a as usize]["count"].as_u64())
    };
    let points = prim["attributes"]
        .as_object()
        .into_iter()
        .flatten()
        .filter_map(|(_, a)| count(a))
        .max()
        .unwrap_or(0);
    let faces = count(&prim["indices"]).map_or(points / 3, |n| n / 3);
    draco_core::DecodeLimits::default()
        .with_max_points(points)
        .with_max_faces(faces)
}

fn draco_primitive(
    json: &mut Value,
    buffers: &[Vec<u8>],
    m: usize,
    p: usize,
    out: &mut Decoded,
) -> Result<(), String> {
    let prim = json["meshes"][m]["primitives"][p].clone();
    let Some(ext) = prim["extensions"].get("KHR_draco_mesh_compression") else {
        return Ok(());
    };
    let mesh_name = super::read::quoted_name(&json["meshes"][m], || format!("{m}"));
    let what = format!("mesh {mesh_name} primitive {p} (Draco)");
    let view = ext["bufferView"]
        .as_u64()
        .ok_or(format!("{what} has no bufferView"))? as usize;
    let stream = view_bytes(json, buffers, out, view)
        .ok_or(format!("{what}: bufferView {view} lies outside its buffer"))?;
    let limits = draco_limits(json, &prim)
        .with_max_decoded_bytes(MAX_DECODED.saturating_sub(out.bytes.len() as u64));
    let mut reader = draco_core::DecoderBuffer::new(&stream).with_limits(limits);
    let mut mesh = draco_core::Mesh::new();
    draco_core::MeshDecoder::new()
        .decode(&mut reader, &mut mesh)
        .map_err(|e| format!("{what} does not decode: {e}"))?;
    let points = mesh.num_points();
    scrambled_targets(json, &prim, &stream, points).map_err(|e| format!("{what}: {e}"))?;
    for (name, id) in ext["attributes"].as_object().into_iter().flatten() {
        let id = id
            .as_u64()
            .ok_or(format!("{what}: attribute {name} has no id"))? as u32;
        let acc = prim["attributes"][name]
            .as_u64()
            .ok_or(format!("{what}: attribute {name} has no accessor"))? as usize;
        let attr = mesh
            .attribute_by_unique_id(id)
            .ok_or(format!("{what}: the stream has no attribute {id} ({name})"))?;
        let ty = json["accessors"][acc]["componentType"]
            .as_u64()
            .unwrap_or(5126) as u32;
        let ncomp = components(json["accessors"][acc]["type"].as_str().unwrap_or(""))
            .ok_or(format!("{what}: accessor {acc} has an unknown type"))?;
        let mut values = attr.read_f32s(points, ncomp);
        if name.starts_with("COLOR_") && ty == 5126 {
            // Colours are 0..1; Draco's dequantization can land a rounding step past 1.
            values.iter_mut().for_each(|v| *v = v.clamp(0.0, 1.0));
        }
        let at = out.push(&encode_as(&values, ty))?;
        let placed = Placed {
            at,
            ty,
            count: points,
            ncomp,
            target: 34962,
        };
        point_accessor(json, acc, placed, out.buffer);
        // The bounds the file declares are the values before Draco quantized them.
        if json["accessors"][acc].get("min").is_some() && points > 0 {
            let stored: Vec<f64> = values
                .iter()
                .map(|&v| match ty {
                    5126 => v as f64,
                    _ => v.round() as f64,
                })
                .collect();
            declare_bounds(json, acc, &stored, ncomp);
        }
    }
    if let Some(acc) = prim["indices"].as_u64().map(|a| a as usize) {
        let declared = json["accessors"][acc]["componentType"]
            .as_u64()
            .unwrap_or(5125) as u32;
        let ty = if points > 65_535 { 5125 } else { declared };
        let mut flat = Vec::with_capacity(mesh.num_faces() * 3);
        for f in 0..mesh.num_faces() {
            flat.extend(
                mesh.face(draco_core::FaceIndex(f as u32))
                    .map(|i| i.0 as f32),
            );
        }
        let at = out.push(&encode_as(&flat, ty))?;
        let placed = Placed {
            at,
            ty,
            count: flat.len(),
            ncomp: 1,
            target: 34963,
        };
        point_accessor(json, acc, placed, out.buffer);
    }
    let prim = &mut json["meshes"][m]["primitives"][p];
    if let Some(o) = prim.get_mut("extensions").and_then(Value::as_object_mut) {
        o.remove("KHR_draco_mesh_compression");
        if o.is_empty() {
            prim.as_object_mut().map(|v| v.remove("extensions"));
        }
    }
    Ok(())
}

/// Why the morph targets of primitive `prim` (stored outside its Draco `stream`, as the
/// extension has them) no longer fit the `points` vertices the stream decodes to, if they do
/// not: a count other than its accessors declare, or edgebreaker connectivity (the stream's
/// header: a triangle mesh, method 1), which numbers the vertices in its own traversal order.
/// Encoders keep the order for morph targets with the sequential method (glTF-Transform and
/// Blender do); FBX2glTF's `-d` does not, and every viewer then plays the targets on the wrong
/// vertices.
fn scrambled_targets(
    json: &Value,
    prim: &Value,
    stream: &[u8],
    points: usize,
) -> Result<(), String> {
    let targets = arr(prim, "targets").len();
    if targets == 0 {
        return Ok(());
    }
    let declared = prim["attributes"]["POSITION"]
        .as_u64()
        .and_then(|a| json["accessors"][a as usize]["count"].as_u64());
    let fix = "export it without Draco, or with its sequential method (gltf-transform draco \
               keeps the order for morph targets)";
    let (them, follow, fit, it) = match targets {
        1 => ("its morph target".to_owned(), "follows", "fits", "it"),
        n => (format!("its {n} morph targets"), "follow", "fit", "them"),
    };
    if let Some(n) = declared.filter(|&n| n as usize != points) {
        return Err(format!(
            "the stream decodes to {points} vertices where its accessors declare {n}, so {them} \
             (stored apart, {n} values each) no longer {fit}; {fix}"
        ));
    }
    if stream.get(7) == Some(&1) && stream.get(8) == Some(&1) {
        return Err(format!(
            "the stream is edgebreaker-encoded, which renumbers the vertices, but {them}, \
             stored apart, still {follow} the original order (every viewer plays {it} \
             scrambled); {fix}"
        ));
    }
    Ok(())
}

/// The bytes of buffer view `view`, from the buffers read or from what is decoded so far.
fn view_bytes(json: &Value, buffers: &[Vec<u8>], out: &Decoded, view: usize) -> Option<Vec<u8>> {
    let bv = json["bufferViews"].get(view)?;
    let buffer = bv["buffer"].as_u64()? as usize;
    let start = bv["byteOffset"].as_u64().unwrap_or(0) as usize;
    let len = bv["byteLength"].as_u64()? as usize;
    let data = if buffer == out.buffer {
        &out.bytes
    } else {
        buffers.get(buffer)?
    };
    data.get(start..start.checked_add(len)?).map(<[u8]>::to_vec)
}

/// Where decoded data of one accessor went: `count` elements of `ncomp` components of type
/// `ty`, `at` bytes into the decoded buffer, vertex (34962) or index (34963) data.
struct Placed {
    at: usize,
    ty: u32,
    count: usize,
    ncomp: usize,
    target: u32,
}

/// Point accessor `acc` at its decoded data `p` in buffer `buffer`, through a new view.
fn point_accessor(json: &mut Value, acc: usize, p: Placed, buffer: usize) {
    let view = json!({
        "buffer": buffer,
        "byteOffset": p.at,
        "byteLength": p.count * p.ncomp * component_size(p.ty),
        "target": p.target,
    });
    if !json["bufferViews"].is_array() {
        json["bufferViews"] = json!([]);
    }
    let views = json["bufferViews"].as_array_mut().expect("an array");
    views.push(view);
    let index = views.len() - 1;
    let a = &mut json["accessors"][acc];
    a["bufferView"] = json!(index);
    a["componentType"] = json!(p.ty);
    a["count"] = json!(p.count);
    if let Some(o) = a.as_object_mut() {
        o.remove("byteOffset");
    }
}

fn component_size(ty: u32) -> usize {
    match ty {
        5120 | 5121 => 1,
        5122 | 5123 => 2,
        _ => 4,
    }
}

/// Values (as Draco gives them: floats, or raw integers widened) in component type `ty`.
fn encode_as(values: &[f32], ty: u32) -> Vec<u8> {
    let mut out = Vec::with_capacity(values.len() * component_size(ty));
    for &v in values {
        match ty {
            5120 => out.push(v.round().clamp(-128.0, 127.0) as i8 as u8),
            5121 => out.push(v.round().clamp(0.0, 255.0) as u8),
            5122 => out.extend((v.round().clamp(-32768.0, 32767.0) as i16).to_le_bytes()),
            5123 => out.extend((v.round().clamp(0.0, 65535.0) as u16).to_le_bytes()),
            5125 => out.extend((v.round().max(0.0) as u32).to_le_bytes()),
            _ => out.extend(v.to_le_bytes()),
        }
    }
    out
}

/// Take the decoded extensions out of `extensionsUsed` and `extensionsRequired`, and the
/// meshopt fallback markers off the buffers.
fn remove_extensions(json: &mut Value) {
    for key in ["extensionsUsed", "extensionsRequired"] {
        if let Some(list) = json.get_mut(key).and_then(Value::as_array_mut) {
            list.retain(|e| !DECODED_EXTENSIONS.contains(&e.as_str().unwrap_or("")));
            if list.is_empty() {
                json.as_object_mut().map(|o| o.remove(key));
            }
        }
    }
    for b in json["buffers"].as_array_mut().into_iter().flatten() {
        if let Some(o) = b.get_mut("extensions").and_then(Value::as_object_mut) {
            o.remove("EXT_meshopt_compression");
            o.remove("KHR_meshopt_compression");
            if o.is_empty() {
                b.as_object_mut().map(|v| v.remove("extensions"));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bounds_come_from_the_decoded_values_and_hostile_numbers_are_passed_over() {
        // View 0 decoded through a filter: two VEC3 floats and two normalized shorts after them.
        let mut bytes = Vec::new();
        for x in [1.5f32, -2.0, 3.0, -4.5, 5.0, 0.25] {
            bytes.extend(x.to_le_bytes());
        }
        for x in [-300i16, 7, 12, 900, -5, 0] {
            bytes.extend(x.to_le_bytes());
        }
        let stale = json!([0, 0, 0]);
        let mut j = json!({
            "bufferViews": [{ "buffer": 1, "byteOffset": 0, "byteLength": bytes.len() }],
            "accessors": [
                { "bufferView": 0, "componentType": 5126, "count": 2, "type": "VEC3",
                  "min": stale, "max": stale },
                { "bufferView": 0, "byteOffset": 24, "componentType": 5122, "normalized": true,
                  "count": 2, "type": "VEC3", "min": stale, "max": stale },
                // Past the data, overflowing counts and offsets: left as declared.
                { "bufferView": 0, "componentType": 5126, "count": 5, "type": "VEC3",
                  "min": stale, "max": stale },
                { "bufferView": 0, "componentType": 5126, "count": u64::MAX, "type": "VEC3",
                  "min": stale, "max": stale },
                { "bufferView": 0, "byteOffset": u64::MAX, "componentType": 5126, "count": 1,
                  "type": "VEC3", "min": stale, "max": stale },
            ]
        });
        rebound_filtered(&mut j, &bytes, &[0]);
        assert_eq!(j["accessors"][0]["min"], json!([-4.5, -2.0, 0.25]));
        assert_eq!(j["accessors"][0]["max"], json!([1.5, 5.0, 3.0]));
        assert_eq!(j["accessors"][1]["min"], json!([-300.0, -5.0, 0.0]));
        assert_eq!(j["accessors"][1]["max"], json!([900.0, 7.0, 12.0]));
        for a in 2..5 {
            assert_eq!(j["accessors"][a]["min"], stale, "accessor {a}");
        }
    }
}
