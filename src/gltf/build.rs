//! The output document under construction: the input's JSON plus one binary buffer that new
//! buffer views and accessors are appended to.

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
    /// External images of a `.gltf` output: (their bytes, the copy beside the output).
    pub(crate) copies: Vec<(Vec<u8>, PathBuf)>,
}

impl Output {
    /// A new document with `json` and no binary data yet.
    pub fn new(json: Value) -> Output {
        Output {
            json,
            bin: BinBuilder::new(),
            copies: Vec::new(),
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
