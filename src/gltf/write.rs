//! Write stage: the output document as `.glb` or `.gltf`.
//!
//! * Every buffer view of the input is copied into one output buffer (the GLB binary chunk, or
//!   `<output stem>.bin` beside a `.gltf`); accessors, images and everything else keep their
//!   indices, so references from extensions we do not know stay valid.
//! * External images are embedded in a `.glb`, or copied beside a `.gltf` written elsewhere.
//! * Files are staged in an [`Outputs`] and renamed into place together.

use super::build::{BinBuilder, Output};
use super::encode;
use super::mend;
use super::read::{arr, quoted_name, Document};
use super::uri::{data_uri, image_mime, percent_decode, reference, Reference};
use crate::output::{folder_of, Format, Outputs};
use anyhow::{anyhow, Result};
use serde_json::{json, Value};
use std::io::Write;
use std::path::{Path, PathBuf};

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
/// embedded in a `.glb`, or copied beside a `.gltf` written elsewhere when it is finished; skin
/// weights that do not sum to one and rotation keys off unit length mended ([`mend::all`],
/// said in `Output::mended`).
pub fn begin(doc: &Document, container: Container, out_path: &Path) -> Result<Output> {
    let mut json = doc.json.clone();
    let mut bin = BinBuilder::new();
    let mut copies = Vec::new();
    for (i, bv) in arr(&doc.json, "bufferViews").iter().enumerate() {
        let data = doc.view(i)?;
        let mut view = bv.clone();
        let idx = bin.push_view(data, None);
        let placed = bin.views[idx].clone();
        view["buffer"] = json!(0);
        view["byteOffset"] = placed["byteOffset"].clone();
        bin.views[idx] = view;
    }
    let unread = embed_or_copy_images(doc, container, out_path, &mut json, &mut bin, &mut copies)?;
    let mut out = Output {
        json,
        bin,
        copies,
        meshopt: false,
        mended: Vec::new(),
        unread_images: unread,
    };
    let mut mended = mend::undefined_keys(&mut out);
    mended.extend(mend::inverse_binds(doc, &mut out));
    let (json, bin) = (&mut out.json, &mut out.bin);
    mended.extend(mend::all(json, bin));
    mended.extend(doc.read_past.iter().cloned());
    mended.extend(mend::bounds(doc, json));
    mended.extend(mend::normals(doc, json, bin));
    mended.extend(mend::tangents(doc, json, bin));
    mended.extend(mend::sparse_parts(doc, json, bin));
    mended.extend(mend::image_types(doc, json, bin));
    mended.extend(mend::image_data_uris(json));
    mended.extend(mend::undeclared_extensions(json));
    mended.extend(mend::scene_roots(json));
    mended.extend(mend::target_extras(json));
    mended.extend(mend::empty_animations(json));
    mended.extend(mend::repeated_channels(json));
    mended.extend(mend::negative_times(json, bin));
    mended.extend(mend::empty_lists(json));
    out.mended = mended;
    Ok(out)
}

/// Images referenced by file: embedded in a `.glb`, or (read, checked and) copied to the same
/// relative place beside a `.gltf` written in another folder; returns a line for each that
/// cannot be read (left the reference it was).
fn embed_or_copy_images(
    doc: &Document,
    container: Container,
    out_path: &Path,
    json: &mut Value,
    bin: &mut BinBuilder,
    copies: &mut Vec<(Vec<u8>, PathBuf)>,
) -> Result<Vec<String>> {
    let out_dir = folder_of(out_path);
    let Some(images) = json.get_mut("images").and_then(Value::as_array_mut) else {
        return Ok(Vec::new());
    };
    // Names of the images copied to their own relative places, which the others must not take.
    let mut taken: std::collections::HashSet<String> = images
        .iter()
        .filter_map(|img| match reference(img.get("uri")?.as_str()?) {
            Ok(Reference::Inside(rel)) => Some(rel.to_string_lossy().into_owned()),
            _ => None,
        })
        .collect();
    let mut lines = Vec::new();
    for (i, img) in images.iter_mut().enumerate() {
        let Some(uri) = img.get("uri").and_then(Value::as_str).map(str::to_owned) else {
            continue;
        };
        if uri.starts_with("data:") {
            // In a `.glb`, embedded in the binary chunk as a view (the validator warns of a
            // data URI there: DATA_URI_GLB); a `.gltf` keeps it ([`mend::image_data_uris`]).
            if container == Container::Glb {
                embed_data_uri(img, &uri, bin);
            }
            continue;
        }
        // An image file that cannot be read (a texture missing beside a downloaded .gltf)
        // stays the reference it was, said in a line; one leading outside is still refused.
        let mut read = |done: &str| -> Result<Option<(Vec<u8>, &'static str)>> {
            Ok(match doc.read_image_or_why(i, &uri)? {
                Ok(image) => Some(image),
                Err(why) => {
                    let name = quoted_name(img, || format!("{i}"));
                    lines.push(format!(
                        "image {name}: {uri:?} {why}; left as a reference to it, not {done}"
                    ));
                    None
                }
            })
        };
        match container {
            Container::Glb => {
                let Some((data, detected)) = read("embedded")? else {
                    continue;
                };
                let mime = img
                    .get("mimeType")
                    .and_then(Value::as_str)
                    .map(str::to_owned)
                    .unwrap_or_else(|| detected.to_owned());
                let view = bin.push_view(&data, None);
                let o = img.as_object_mut().expect("checked when read");
                o.remove("uri");
                o.insert("bufferView".into(), json!(view));
                o.insert("mimeType".into(), json!(mime));
            }
            Container::Gltf => match reference(&uri) {
                // Beside the output at the same relative place, unless that is the input's
                // own file.
                Ok(Reference::Inside(rel)) => {
                    let dst = out_dir.join(&rel);
                    if !same_file(&doc.folder().join(&rel), &dst) {
                        if let Some((data, _)) = read("copied")? {
                            copies.push((data, dst));
                        }
                    }
                    // A Windows path's separators written as a URI's.
                    if uri.contains('\\') {
                        img["uri"] = json!(uri.replace('\\', "/"));
                    }
                }
                // Outside the input's folder (allowed by --allow-external): copied beside the
                // output under its own name, and referred to by that name.
                _ => {
                    let Some((data, _)) = read("copied")? else {
                        continue;
                    };
                    let name = unique_name(&uri, &mut taken);
                    img["uri"] = json!(encode_uri(&name));
                    copies.push((data, out_dir.join(&name)));
                }
            },
        }
    }
    Ok(lines)
}

/// Image `img`'s data URI `uri` as a view of `bin`, typed as declared, else as its header or
/// its bytes say; left as it is where its bytes are no image type glTF allows.
fn embed_data_uri(img: &mut Value, uri: &str, bin: &mut BinBuilder) {
    let Some(data) = data_uri(uri) else {
        return;
    };
    let Some(detected) = image_mime(&data) else {
        return;
    };
    let header = (uri
        .strip_prefix("data:")
        .and_then(|u| u.split(&[';', ','][..]).next()))
    .filter(|m| m.starts_with("image/"));
    let mime = (img.get("mimeType").and_then(Value::as_str))
        .or(header)
        .unwrap_or(detected)
        .to_owned();
    let view = bin.push_view(&data, None);
    let o = img.as_object_mut().expect("checked when read");
    o.remove("uri");
    o.insert("bufferView".into(), json!(view));
    o.insert("mimeType".into(), json!(mime));
}

/// A file name for a copied image from outside the input's folder: the name it had, made
/// unique among the names already given with `_1`, `_2`, ... before the extension.
fn unique_name(uri: &str, taken: &mut std::collections::HashSet<String>) -> String {
    let decoded = percent_decode(uri);
    let path = Path::new(&decoded);
    let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("image");
    let ext = path
        .extension()
        .and_then(|s| s.to_str())
        .map(|e| format!(".{e}"))
        .unwrap_or_default();
    let mut name = format!("{stem}{ext}");
    let mut k = 0;
    while !taken.insert(name.clone()) {
        k += 1;
        name = format!("{stem}_{k}{ext}");
    }
    name
}

fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => false,
    }
}

/// Serialize `out` and write it (with a `.gltf`'s `.bin` and images) as one all-or-nothing step.
pub fn finish(out: Output, container: Container, path: &Path) -> Result<()> {
    let mut files = Outputs::new();
    stage(out, container, path, &mut files)?;
    files.commit()
}

/// Serialize `out` into `files` (staged: the caller adds its other files and commits); returns
/// the bytes of every file staged.
pub fn stage(
    mut out: Output,
    container: Container,
    path: &Path,
    files: &mut Outputs,
) -> Result<u64> {
    let (bin, bin_name) = assemble(&mut out, container, path);
    let mut bytes = 0;
    match container {
        Container::Glb => {
            let (js, total) = glb_json(&out, &bin, path)?;
            bytes += files.write_with(path, |w| write_glb(w, &js, &bin, total))?;
        }
        Container::Gltf => {
            let js = serde_json::to_vec_pretty(&out.json)?;
            if let Some(name) = bin_name.filter(|_| !bin.is_empty()) {
                bytes += files.write(&path.with_file_name(name), &bin)?;
            }
            bytes += files.write(path, &js)?;
        }
    }
    for (data, dst) in &out.copies {
        if let Some(parent) = dst.parent() {
            std::fs::create_dir_all(parent)
                .map_err(|e| anyhow!("{}: cannot write: {e}", dst.display()))?;
        }
        bytes += files.write(dst, data)?;
    }
    Ok(bytes)
}

/// `out` as the bytes of a `.glb` held in memory (its images are embedded: nothing is copied
/// beside it); `path` names the file in what is said. `blend` stages its USD point cache from it.
pub fn glb_bytes(mut out: Output, path: &Path) -> Result<Vec<u8>> {
    let (bin, _) = assemble(&mut out, Container::Glb, path);
    let (js, total) = glb_json(&out, &bin, path)?;
    let mut bytes = Vec::with_capacity(total as usize);
    write_glb(&mut bytes, &js, &bin, total)?;
    Ok(bytes)
}

/// Finish `out`'s JSON for writing: meshopt compression where asked, the views and buffers in
/// place; returns the binary chunk (padded to 4 bytes) and, for a `.gltf`, the `.bin`'s name.
fn assemble(out: &mut Output, container: Container, path: &Path) -> (Vec<u8>, Option<String>) {
    mend::start_at_zero(out);
    mend::drop_repeated_channels(&mut out.json);
    mend::drop_empty_animations(&mut out.json);
    mend::drop_empty_lists(&mut out.json);
    let fallback = if out.meshopt { encode::meshopt(out) } else { 0 };
    encode::clear_marks(out);
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
        let mut buffers = vec![b];
        // The views compressed by meshopt point into a buffer that holds no data.
        if fallback > 0 {
            buffers.push(json!({
                "byteLength": fallback,
                "extensions": { "EXT_meshopt_compression": { "fallback": true } }
            }));
            for key in ["extensionsUsed", "extensionsRequired"] {
                let list = json.entry(key).or_insert_with(|| json!([]));
                if let Some(list) = list.as_array_mut() {
                    if !list.iter().any(|e| e == "EXT_meshopt_compression") {
                        list.push(json!("EXT_meshopt_compression"));
                    }
                }
            }
        }
        json.insert("buffers".into(), json!(buffers));
    }
    (bin, bin_name)
}

/// A `.glb`'s JSON chunk (padded with spaces to 4 bytes) and its total length, or an error
/// where it would pass the 4 GiB a GLB's header can count.
fn glb_json(out: &Output, bin: &[u8], path: &Path) -> Result<(Vec<u8>, u32)> {
    let mut js = serde_json::to_vec(&out.json)?;
    while js.len() % 4 != 0 {
        js.push(b' ');
    }
    let total = 12 + 8 + js.len() + if bin.is_empty() { 0 } else { 8 + bin.len() };
    let total = u32::try_from(total).map_err(|_| {
        anyhow!(
            "{}: cannot write: {total} bytes is more than a GLB can hold (4 GiB); write .gltf or a USD point cache",
            path.display()
        )
    })?;
    Ok((js, total))
}

/// The `.glb` container: header, JSON chunk, binary chunk (where there is one).
fn write_glb(w: &mut impl Write, js: &[u8], bin: &[u8], total: u32) -> Result<()> {
    w.write_all(b"glTF")?;
    w.write_all(&2u32.to_le_bytes())?;
    w.write_all(&total.to_le_bytes())?;
    w.write_all(&(js.len() as u32).to_le_bytes())?;
    w.write_all(&0x4E4F_534Au32.to_le_bytes())?;
    w.write_all(js)?;
    if !bin.is_empty() {
        w.write_all(&(bin.len() as u32).to_le_bytes())?;
        w.write_all(&0x004E_4942u32.to_le_bytes())?;
        w.write_all(bin)?;
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
