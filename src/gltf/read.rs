//! Read stage: load a `.gltf` (embedded or external buffers) or `.glb` into a [`Document`].
//!
//! The JSON is kept as a `serde_json::Value` (with key order preserved) so that everything we do
//! not touch — unknown extensions, `extras`, names, vendor fields — is written back unchanged.
//! Accessors are decoded in [`super::accessor`].

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
