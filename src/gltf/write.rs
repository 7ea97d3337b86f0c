//! Write stage: the output document as `.glb` or `.gltf`.
//!
//! * Every buffer view of the input is copied into one output buffer (the GLB binary chunk, or
//!   `<output stem>.bin` beside a `.gltf`); accessors, images and everything else keep their
//!   indices, so references from extensions we do not know stay valid.
//! * External images are embedded in a `.glb`, or copied beside a `.gltf` written elsewhere.
//! * Files are staged in an [`Outputs`] and renamed into place together.

use super::build::{BinBuilder, Output};
use super::read::{arr, percent_decode, Document};
use crate::output::{Format, Outputs};
use anyhow::{Context, Result};
use serde_json::{json, Value};
use std::path::Path;

/// Output container.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Container {
    Glb,
    Gltf,
}

impl Container {
    /// The container of an output format (`None` for USD).
    pub fn of(format: Format) -> Option<Container> {
        match format {
            Format::Glb => Some(Container::Glb),
            Format::Gltf => Some(Container::Gltf),
            _ => None,
        }
    }
}

/// Start an output from the input: all buffer views copied into one buffer; external images
/// embedded in a `.glb`, or copied beside a `.gltf` written elsewhere when it is finished.
pub fn begin(doc: &Document, container: Container, out_path: &Path) -> Result<Output> {
    let mut json = doc.json.clone();
    let mut bin = BinBuilder::new();
    let mut copies = Vec::new();
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
                        copies.push((src, dst));
                    }
                }
            }
        }
    }
    Ok(Output { json, bin, copies })
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

/// Serialize `out` and write it (with a `.gltf`'s `.bin` and images) as one all-or-nothing step.
pub fn finish(out: Output, container: Container, path: &Path) -> Result<()> {
    let mut files = Outputs::new();
    stage(out, container, path, &mut files)?;
    files.commit()
}

/// Serialize `out` into `files` (staged: the caller adds its other files and commits).
pub fn stage(
    mut out: Output,
    container: Container,
    path: &Path,
    files: &mut Outputs,
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
            files.write(path, &file)?;
        }
        Container::Gltf => {
            let js = serde_json::to_vec_pretty(&out.json)?;
            if let Some(name) = bin_name.filter(|_| !bin.is_empty()) {
                files.write(&path.with_file_name(name), &bin)?;
            }
            files.write(path, &js)?;
        }
    }
    for (src, dst) in &out.copies {
        files.copy(src, dst)?;
    }
    Ok(())
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
