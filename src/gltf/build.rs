//! The output document under construction: the input's JSON plus one binary buffer that new
//! buffer views and accessors are appended to.

use rayon::prelude::*;
use serde_json::{json, Value};
use std::path::PathBuf;

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
        let view = self.open_view(data.len(), target);
        self.bytes.extend_from_slice(data);
        view
    }

    /// [`BinBuilder::push_view`] of f32 values (little-endian), converted in parallel straight
    /// into the buffer.
    pub fn push_f32_view(&mut self, data: &[f32], target: Option<u32>) -> usize {
        let view = self.open_view(4 * data.len(), target);
        let start = self.bytes.len();
        self.bytes.resize(start + 4 * data.len(), 0);
        self.bytes[start..]
            .par_chunks_mut(4 * PARALLEL_CHUNK)
            .zip(data.par_chunks(PARALLEL_CHUNK))
            .for_each(|(out, values)| {
                for (o, x) in out.chunks_exact_mut(4).zip(values) {
                    o.copy_from_slice(&x.to_le_bytes());
                }
            });
        view
    }

    /// A new view of `len` bytes starting at the buffer's end (padded to 4 bytes), to be
    /// filled by the caller; its index.
    fn open_view(&mut self, len: usize, target: Option<u32>) -> usize {
        while !self.bytes.len().is_multiple_of(4) {
            self.bytes.push(0);
        }
        let mut v = json!({ "buffer": 0, "byteOffset": self.bytes.len(), "byteLength": len });
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        self.views.push(v);
        self.views.len() - 1
    }
}

/// Values a parallel task takes at once where a frame's arrays are converted or scanned.
const PARALLEL_CHUNK: usize = 1 << 16;

/// How a VEC3 array of a morph target is stored.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Storage {
    /// f32; with meshopt, through the EXPONENTIAL filter at these mantissa bits.
    Float { exp_bits: Option<i32> },
    /// Normalized i16 (values in [-1, 1]), 8-byte elements (`KHR_mesh_quantization`).
    Short,
    /// Normalized i8, 4-byte elements (`KHR_mesh_quantization`).
    Byte,
}

impl Storage {
    /// A value as a reader decodes it once stored.
    pub fn stored(self, x: f32) -> f32 {
        match self {
            Storage::Float { .. } => x,
            Storage::Short => (x.clamp(-1.0, 1.0) * 32767.0).round() / 32767.0,
            Storage::Byte => (x.clamp(-1.0, 1.0) * 127.0).round() / 127.0,
        }
    }

    /// (componentType, bytes of a VEC3 element in a vertex view, bytes tightly packed).
    fn layout(self) -> (u32, usize, usize) {
        match self {
            Storage::Float { .. } => (5126, 12, 12),
            Storage::Short => (5122, 8, 6),
            Storage::Byte => (5120, 4, 3),
        }
    }

    /// The bytes of VEC3 values, `stride` bytes an element.
    fn bytes(self, values: &[f32], stride: usize) -> Vec<u8> {
        let mut out = Vec::with_capacity(values.len() / 3 * stride);
        for v in values.chunks_exact(3) {
            let start = out.len();
            for &x in v {
                match self {
                    Storage::Float { .. } => out.extend(x.to_le_bytes()),
                    Storage::Short => out.extend(((self.stored(x) * 32767.0) as i16).to_le_bytes()),
                    Storage::Byte => out.push((self.stored(x) * 127.0) as i8 as u8),
                }
            }
            out.resize(start + stride, 0);
        }
        out
    }
}

/// f32 values as JSON numbers written as short as they read back exactly as f32 (serde_json
/// would write each as the f64 it widens to: `0.04999995231628418` for `0.049999952`), whole
/// ones without a fraction (`2`, not `2.0`).
pub(super) fn f32_json(values: &[f32]) -> Value {
    Value::Array(
        values
            .iter()
            .map(|x| match format!("{x}").parse::<f64>() {
                // Whole numbers (a normalized integer accessor's bounds) without a fraction.
                Ok(v) if v.fract() == 0.0 && v.abs() < 1e15 => json!(v as i64),
                Ok(v) if x.is_finite() => json!(v),
                _ => json!(*x),
            })
            .collect(),
    )
}

/// Per component, the smallest and largest of `data` (elements of `ncomp` values).
pub(super) fn min_max(data: &[f32], ncomp: usize) -> (Vec<f32>, Vec<f32>) {
    let none = || (vec![f32::INFINITY; ncomp], vec![f32::NEG_INFINITY; ncomp]);
    let whole = data.len() - data.len() % ncomp;
    data[..whole]
        .par_chunks(ncomp * PARALLEL_CHUNK)
        .map(|part| {
            let (mut lo, mut hi) = none();
            for e in part.chunks_exact(ncomp) {
                for c in 0..ncomp {
                    lo[c] = lo[c].min(e[c]);
                    hi[c] = hi[c].max(e[c]);
                }
            }
            (lo, hi)
        })
        .reduce(none, |(mut lo, mut hi), (l, h)| {
            for c in 0..ncomp {
                lo[c] = lo[c].min(l[c]);
                hi[c] = hi[c].max(h[c]);
            }
            (lo, hi)
        })
}

/// Set accessor `acc`'s min and max to those of `data` (elements of `ncomp` values), as f32.
pub fn set_bounds(acc: &mut Value, data: &[f32], ncomp: usize) {
    let (lo, hi) = min_max(data, ncomp);
    acc["min"] = f32_json(&lo);
    acc["max"] = f32_json(&hi);
}

/// The output document under construction.
pub struct Output {
    pub json: Value,
    pub bin: BinBuilder,
    /// External images of a `.gltf` output: (their bytes, the copy beside the output).
    pub(crate) copies: Vec<(Vec<u8>, PathBuf)>,
    /// Compress the buffer views with `EXT_meshopt_compression` when written.
    pub meshopt: bool,
    /// What the output mends in the input's data, one line each, for the summary's warnings.
    pub mended: Vec<String>,
    /// The image files that could not be read, left as the references they were: one line
    /// each, for a glTF output's warnings (a USD output says its own).
    pub unread_images: Vec<String>,
}

impl Output {
    /// A new document with `json` and no binary data yet.
    pub fn new(json: Value) -> Output {
        Output {
            json,
            bin: BinBuilder::new(),
            copies: Vec::new(),
            meshopt: false,
            mended: Vec::new(),
            unread_images: Vec::new(),
        }
    }

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
        let view = self.bin.push_f32_view(data, target);
        let count = data.len() / ncomp;
        let mut acc =
            json!({ "bufferView": view, "componentType": 5126, "count": count, "type": ty });
        if bounds && count > 0 {
            set_bounds(&mut acc, data, ncomp);
        }
        self.push_accessor(acc)
    }

    /// Add a VEC3 morph-target accessor of `values` stored as `storage`: as a sparse accessor
    /// (only the vertices whose stored value is not zero) when `sparse`; min/max of the
    /// stored values when `bounds` (POSITION). Integer storage declares KHR_mesh_quantization.
    pub fn push_morph(
        &mut self,
        values: &[f32],
        storage: Storage,
        sparse: bool,
        bounds: bool,
    ) -> usize {
        let count = values.len() / 3;
        let (ty, stride, packed) = storage.layout();
        let normalized = !matches!(storage, Storage::Float { .. });
        let mut acc = json!({ "componentType": ty, "count": count, "type": "VEC3" });
        if normalized {
            acc["normalized"] = json!(true);
            self.require("KHR_mesh_quantization");
        }
        if sparse {
            let rows: Vec<usize> = (0..count)
                .filter(|&v| {
                    values[3 * v..3 * v + 3]
                        .iter()
                        .any(|&x| storage.stored(x) != 0.0)
                })
                .collect();
            let index_bytes: Vec<u8> = if count <= 65_536 {
                rows.iter()
                    .flat_map(|&r| (r as u16).to_le_bytes())
                    .collect()
            } else {
                rows.iter()
                    .flat_map(|&r| (r as u32).to_le_bytes())
                    .collect()
            };
            let picked: Vec<f32> = rows
                .iter()
                .flat_map(|&r| values[3 * r..3 * r + 3].to_vec())
                .collect();
            if !rows.is_empty() {
                let indices = self.bin.push_view(&index_bytes, None);
                let data = self.bin.push_view(&storage.bytes(&picked, packed), None);
                if let Storage::Float { exp_bits: Some(b) } = storage {
                    self.bin.views[data][super::encode::FILTER_MARK] = json!(b);
                }
                acc["sparse"] = json!({
                    "count": rows.len(),
                    "indices": { "bufferView": indices, "componentType": if count <= 65_536 { 5123 } else { 5125 } },
                    "values": { "bufferView": data },
                });
            }
        } else {
            let view = self
                .bin
                .push_view(&storage.bytes(values, stride), Some(34962));
            if stride != packed {
                self.bin.views[view]["byteStride"] = json!(stride);
            }
            if let Storage::Float { exp_bits: Some(b) } = storage {
                self.bin.views[view][super::encode::FILTER_MARK] = json!(b);
            }
            acc["bufferView"] = json!(view);
        }
        if bounds && count > 0 {
            let scale = match storage {
                Storage::Float { .. } => 1.0,
                Storage::Short => 32767.0,
                Storage::Byte => 127.0,
            };
            let bound = |init: f32, pick: fn(f32, f32) -> f32| -> Vec<f32> {
                (0..3)
                    .map(|c| {
                        values
                            .iter()
                            .skip(c)
                            .step_by(3)
                            .map(|&x| storage.stored(x) * scale)
                            .fold(init, pick)
                    })
                    .collect()
            };
            let (lo, hi) = (
                bound(f32::INFINITY, f32::min),
                bound(f32::NEG_INFINITY, f32::max),
            );
            acc["min"] = f32_json(&lo);
            acc["max"] = f32_json(&hi);
        }
        // A target that moves nothing has no data: one such accessor serves every target alike.
        if acc.get("bufferView").is_none() && acc.get("sparse").is_none() {
            if let Some(same) = super::read::arr(&self.json, "accessors")
                .iter()
                .position(|a| *a == acc)
            {
                return same;
            }
        }
        self.push_accessor(acc)
    }

    /// Declare `name` in extensionsUsed and extensionsRequired.
    pub fn require(&mut self, name: &str) {
        for key in ["extensionsUsed", "extensionsRequired"] {
            let list = self
                .json
                .as_object_mut()
                .expect("a glTF object")
                .entry(key)
                .or_insert_with(|| json!([]));
            if let Some(list) = list.as_array_mut() {
                if !list.iter().any(|e| e == name) {
                    list.push(json!(name));
                }
            }
        }
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
