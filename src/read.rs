//! Read stage: load a `.gltf` (embedded or external buffers) or `.glb` into a [`Document`]
//! and decode accessors.
//!
//! The JSON is kept as a `serde_json::Value` (with key order preserved) so that everything we do
//! not touch — unknown extensions, `extras`, names, vendor fields — is written back unchanged.
//! Accessors are decoded here (strided, sparse, normalized and quantized integer types), so the
//! rest of the pipeline only ever sees `f64` or `u32` arrays.

use anyhow::{anyhow, bail, Context, Result};
use base64::Engine;
use serde_json::Value;
use std::path::{Path, PathBuf};

/// Extensions whose data we cannot decode: a file that *requires* one of them is refused.
pub const UNDECODABLE_EXTENSIONS: &[&str] = &[
    "EXT_meshopt_compression",
    "KHR_meshopt_compression",
    "KHR_draco_mesh_compression",
];

/// A loaded glTF asset: the JSON tree plus the bytes of every buffer.
pub struct Document {
    /// The file it was read from (used in every error message).
    pub path: PathBuf,
    pub json: Value,
    /// `buffers[i]` holds the bytes of `json.buffers[i]`.
    pub buffers: Vec<Vec<u8>>,
}

/// Prefix an error with the input path, so each message names its file.
pub fn at<P: AsRef<Path>>(path: P, msg: impl std::fmt::Display) -> anyhow::Error {
    anyhow!("{}: {}", path.as_ref().display(), msg)
}

impl Document {
    /// Read and check a `.gltf` or `.glb` file. Errors name the file and the problem.
    pub fn open(path: &Path) -> Result<Document> {
        let bytes = std::fs::read(path).map_err(|e| at(path, format!("cannot read: {e}")))?;
        let (json_bytes, bin) = if bytes.starts_with(b"glTF") {
            split_glb(path, &bytes)?
        } else {
            (&bytes[..], None)
        };
        let json: Value = serde_json::from_slice(json_bytes).map_err(|e| {
            at(
                path,
                format!("not a glTF file (the JSON does not parse: {e})"),
            )
        })?;
        if !json.is_object() || json.get("asset").is_none() {
            return Err(at(path, "not a glTF file (no \"asset\" object)"));
        }
        let version = json["asset"]["version"].as_str().unwrap_or("");
        if !version.starts_with("2.") {
            return Err(at(
                path,
                format!("unsupported glTF version {version:?} (only 2.x is read)"),
            ));
        }
        if let Some(req) = json.get("extensionsRequired").and_then(Value::as_array) {
            for ext in req.iter().filter_map(Value::as_str) {
                if UNDECODABLE_EXTENSIONS.contains(&ext) {
                    return Err(at(
                        path,
                        format!("requires extension {ext}, which inbetween cannot decode (decompress the file first)"),
                    ));
                }
            }
        }
        let dir = path.parent().unwrap_or(Path::new("."));
        let mut buffers = Vec::new();
        let mut bin = bin;
        for (i, b) in arr(&json, "buffers").iter().enumerate() {
            let declared = b["byteLength"].as_u64().unwrap_or(0) as usize;
            let data = match b.get("uri").and_then(Value::as_str) {
                None => {
                    let chunk = if i == 0 { bin.take() } else { None };
                    chunk.map(<[u8]>::to_vec).ok_or_else(|| {
                        at(
                            path,
                            format!(
                                "buffer {i} has no uri and there is no GLB binary chunk for it"
                            ),
                        )
                    })?
                }
                Some(uri) if uri.starts_with("data:") => decode_data_uri(uri).ok_or_else(|| {
                    at(
                        path,
                        format!("buffer {i} has a data URI that is not base64"),
                    )
                })?,
                Some(uri) => {
                    let file = dir.join(percent_decode(uri));
                    std::fs::read(&file).map_err(|e| {
                        at(
                            path,
                            format!("buffer {i} file {} cannot be read: {e}", file.display()),
                        )
                    })?
                }
            };
            if data.len() < declared {
                bail!(at(
                    path,
                    format!(
                        "buffer {i} declares {declared} bytes but holds {}",
                        data.len()
                    )
                ));
            }
            buffers.push(data);
        }
        Ok(Document {
            path: path.to_path_buf(),
            json,
            buffers,
        })
    }

    pub fn err(&self, msg: impl std::fmt::Display) -> anyhow::Error {
        at(&self.path, msg)
    }

    /// Decode accessor `index` as `f64` values, `count * components` of them, row-major.
    pub fn read_f64(&self, index: usize) -> Result<(Vec<f64>, usize)> {
        let acc = self.accessor(index)?;
        let ncomp = acc.ncomp;
        let mut out = vec![0.0f64; acc.count * ncomp];
        if let Some(view) = acc.view {
            let (bytes, stride) = self.view_slice(view, acc.offset, acc.count, acc.elem_size())?;
            for i in 0..acc.count {
                let base = i * stride;
                for c in 0..ncomp {
                    out[i * ncomp + c] = acc.decode(bytes, base + c * acc.comp_size());
                }
            }
        }
        if let Some(sparse) = self.json["accessors"][index].get("sparse") {
            let n = sparse["count"].as_u64().unwrap_or(0) as usize;
            let ind = &sparse["indices"];
            let idx_ty = ind["componentType"].as_u64().unwrap_or(0) as u32;
            let idx_size = comp_size(idx_ty)
                .ok_or_else(|| self.err(format!("accessor {index}: bad sparse index type")))?;
            let iv = ind["bufferView"].as_u64().ok_or_else(|| {
                self.err(format!(
                    "accessor {index}: sparse indices without bufferView"
                ))
            })? as usize;
            let io = ind["byteOffset"].as_u64().unwrap_or(0) as usize;
            let (ibytes, _) = self.view_slice(iv, io, n, idx_size)?;
            let val = &sparse["values"];
            let vv = val["bufferView"].as_u64().ok_or_else(|| {
                self.err(format!(
                    "accessor {index}: sparse values without bufferView"
                ))
            })? as usize;
            let vo = val["byteOffset"].as_u64().unwrap_or(0) as usize;
            let (vbytes, _) = self.view_slice(vv, vo, n, acc.elem_size())?;
            let sparse_acc = Accessor {
                view: None,
                offset: 0,
                ..acc
            };
            for k in 0..n {
                let target = read_uint(ibytes, k * idx_size, idx_ty) as usize;
                if target >= acc.count {
                    bail!(self.err(format!(
                        "accessor {index}: sparse index {target} is out of range"
                    )));
                }
                for c in 0..ncomp {
                    out[target * ncomp + c] =
                        sparse_acc.decode(vbytes, k * acc.elem_size() + c * acc.comp_size());
                }
            }
        }
        Ok((out, ncomp))
    }

    /// Decode an index accessor (unsigned integer scalars).
    pub fn read_indices(&self, index: usize) -> Result<Vec<u32>> {
        let (v, ncomp) = self.read_f64(index)?;
        if ncomp != 1 {
            bail!(self.err(format!("accessor {index} used as indices is not SCALAR")));
        }
        Ok(v.into_iter().map(|x| x as u32).collect())
    }

    /// Element count of accessor `index`.
    pub fn accessor_count(&self, index: usize) -> Result<usize> {
        Ok(self.accessor(index)?.count)
    }

    fn accessor(&self, index: usize) -> Result<Accessor> {
        let a = self
            .json
            .get("accessors")
            .and_then(|a| a.get(index))
            .ok_or_else(|| self.err(format!("accessor {index} does not exist")))?;
        let ty = a["componentType"].as_u64().unwrap_or(0) as u32;
        comp_size(ty)
            .ok_or_else(|| self.err(format!("accessor {index} has unknown componentType {ty}")))?;
        let ncomp = match a["type"].as_str().unwrap_or("") {
            "SCALAR" => 1,
            "VEC2" => 2,
            "VEC3" => 3,
            "VEC4" | "MAT2" => 4,
            "MAT3" => 9,
            "MAT4" => 16,
            t => bail!(self.err(format!("accessor {index} has unknown type {t:?}"))),
        };
        Ok(Accessor {
            view: a["bufferView"].as_u64().map(|v| v as usize),
            offset: a["byteOffset"].as_u64().unwrap_or(0) as usize,
            count: a["count"].as_u64().unwrap_or(0) as usize,
            ty,
            ncomp,
            normalized: a["normalized"].as_bool().unwrap_or(false),
        })
    }

    /// The bytes of `count` elements of `elem` bytes starting `offset` bytes into buffer view
    /// `view`, and the stride between elements.
    fn view_slice(
        &self,
        view: usize,
        offset: usize,
        count: usize,
        elem: usize,
    ) -> Result<(&[u8], usize)> {
        let bv = self
            .json
            .get("bufferViews")
            .and_then(|v| v.get(view))
            .ok_or_else(|| self.err(format!("bufferView {view} does not exist")))?;
        let buffer = bv["buffer"].as_u64().unwrap_or(u64::MAX) as usize;
        let data = self
            .buffers
            .get(buffer)
            .ok_or_else(|| self.err(format!("bufferView {view} names missing buffer {buffer}")))?;
        let start = bv["byteOffset"].as_u64().unwrap_or(0) as usize;
        let len = bv["byteLength"].as_u64().unwrap_or(0) as usize;
        let stride = bv["byteStride"]
            .as_u64()
            .map(|s| s as usize)
            .unwrap_or(elem);
        if start + len > data.len() {
            bail!(self.err(format!(
                "bufferView {view} reaches past the end of buffer {buffer}"
            )));
        }
        let need = if count == 0 {
            0
        } else {
            offset + (count - 1) * stride + elem
        };
        if need > len {
            bail!(self.err(format!(
                "an accessor reads past the end of bufferView {view}"
            )));
        }
        Ok((&data[start + offset..start + len], stride))
    }
}

#[derive(Clone, Copy)]
struct Accessor {
    view: Option<usize>,
    offset: usize,
    count: usize,
    ty: u32,
    ncomp: usize,
    normalized: bool,
}

impl Accessor {
    fn comp_size(&self) -> usize {
        comp_size(self.ty).unwrap_or(4)
    }
    fn elem_size(&self) -> usize {
        self.comp_size() * self.ncomp
    }
    fn decode(&self, b: &[u8], at: usize) -> f64 {
        let raw = match self.ty {
            5126 => return f32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]]) as f64,
            5120 => b[at] as i8 as f64,
            5122 => i16::from_le_bytes([b[at], b[at + 1]]) as f64,
            _ => read_uint(b, at, self.ty) as f64,
        };
        if !self.normalized {
            return raw;
        }
        // glTF 2.0 normalization rules (section 3.11).
        match self.ty {
            5120 => (raw / 127.0).max(-1.0),
            5121 => raw / 255.0,
            5122 => (raw / 32767.0).max(-1.0),
            5123 => raw / 65535.0,
            5125 => raw / 4294967295.0,
            _ => raw,
        }
    }
}

fn comp_size(ty: u32) -> Option<usize> {
    match ty {
        5120 | 5121 => Some(1),
        5122 | 5123 => Some(2),
        5125 | 5126 => Some(4),
        _ => None,
    }
}

fn read_uint(b: &[u8], at: usize, ty: u32) -> u64 {
    match ty {
        5121 | 5120 => b[at] as u64,
        5123 | 5122 => u16::from_le_bytes([b[at], b[at + 1]]) as u64,
        _ => u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]]) as u64,
    }
}

/// The array under `key`, or an empty slice.
pub fn arr<'a>(v: &'a Value, key: &str) -> &'a [Value] {
    v.get(key)
        .and_then(Value::as_array)
        .map(Vec::as_slice)
        .unwrap_or(&[])
}

fn split_glb<'a>(path: &Path, bytes: &'a [u8]) -> Result<(&'a [u8], Option<&'a [u8]>)> {
    let word = |at: usize| -> Option<u32> {
        bytes
            .get(at..at + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    let version = word(4).ok_or_else(|| at(path, "truncated GLB header"))?;
    let length = word(8).ok_or_else(|| at(path, "truncated GLB header"))? as usize;
    if version != 2 {
        bail!(at(
            path,
            format!("GLB container version {version} is not supported (only 2)")
        ));
    }
    if length != bytes.len() {
        bail!(at(
            path,
            format!(
                "GLB header says the file is {length} bytes but it is {} bytes",
                bytes.len()
            )
        ));
    }
    let mut off = 12;
    let mut json = None;
    let mut bin = None;
    while off + 8 <= bytes.len() {
        let clen = word(off).context("chunk")? as usize;
        let ctype = word(off + 4).context("chunk")?;
        let end = off + 8 + clen;
        if end > bytes.len() {
            bail!(at(
                path,
                format!("GLB chunk at byte {off} runs past the end of the file")
            ));
        }
        match ctype {
            0x4E4F_534A if json.is_none() => json = Some(&bytes[off + 8..end]),
            0x004E_4942 if bin.is_none() => bin = Some(&bytes[off + 8..end]),
            _ => {}
        }
        off = end;
    }
    let json = json.ok_or_else(|| at(path, "GLB has no JSON chunk"))?;
    Ok((json, bin))
}

fn decode_data_uri(uri: &str) -> Option<Vec<u8>> {
    let (head, data) = uri.split_once(',')?;
    if !head.ends_with(";base64") {
        return None;
    }
    base64::engine::general_purpose::STANDARD
        .decode(data.trim())
        .ok()
}

/// Decode `%XX` escapes of a relative URI into a file path.
pub fn percent_decode(uri: &str) -> String {
    let b = uri.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' && i + 2 < b.len() {
            if let Ok(v) = u8::from_str_radix(&uri[i + 1..i + 3], 16) {
                out.push(v);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}
