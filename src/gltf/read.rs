//! Read stage: load a `.gltf` (embedded or external buffers) or `.glb` into a [`Document`].
//!
//! The JSON is kept as a `serde_json::Value` (with key order preserved) so that everything we do
//! not touch — unknown extensions, `extras`, names, vendor fields — is written back unchanged.
//! Accessors are decoded in [`super::accessor`].

use super::container;
use super::decode::decode;
use super::spelling;
use super::targets;
use super::uri::{
    data_uri, image_mime, read_image, read_prefix, reference, regular_file, uri_error, Access,
    Reference,
};
use anyhow::{anyhow, bail, Result};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// A loaded glTF asset: the JSON tree plus the bytes of every buffer.
pub struct Document {
    /// The file it was read from (used in every error message).
    pub path: PathBuf,
    pub json: Value,
    /// `buffers[i]` holds the bytes of `json.buffers[i]`.
    pub buffers: Vec<Vec<u8>>,
    /// Where external references (images) may lead.
    pub access: Access,
    /// Bytes of the input: the file, its external buffers and its external images.
    pub input_bytes: u64,
    /// The compression extensions decoded on read (no longer in the JSON).
    pub decoded: Vec<String>,
    /// What the reading of the JSON text passed over that glTF asks writers to leave out (a
    /// byte-order mark, a GLB's NUL padding: [`super::spelling`]), a line each.
    pub read_past: Vec<String>,
    /// The largest element count of an accessor its buffer view holds (found once, when an
    /// accessor without a buffer view is read).
    pub(crate) largest_backed: std::sync::OnceLock<usize>,
}

/// Prefix an error with the input path, so each message names its file.
pub fn at<P: AsRef<Path>>(path: P, msg: impl std::fmt::Display) -> anyhow::Error {
    anyhow!("{}: {}", path.as_ref().display(), msg)
}

/// Names of a file's parts for a one-line message: the first [`LISTED`], then how many more
/// (a file of 3,003 clips made a 40 KB error line).
pub fn listed(names: &[String]) -> String {
    let more = names.len().saturating_sub(LISTED);
    let shown = names[..names.len().min(LISTED)].join(", ");
    match more {
        0 => shown,
        _ => format!("{shown}, ... {more} more"),
    }
}

/// [`listed`], or `none` for no names (a message saying which a file has).
pub fn listed_or_none(names: &[String]) -> String {
    match names.is_empty() {
        true => "none".into(),
        false => listed(names),
    }
}

/// A part's `name` quoted for a message, or `fallback()` when it has none (`mesh 3`).
pub fn quoted_name(part: &Value, fallback: impl FnOnce() -> String) -> String {
    part["name"]
        .as_str()
        .map_or_else(fallback, |n| format!("{n:?}"))
}

/// The names of a mesh's morph targets: its `extras.targetNames` (Blender's and most tools'
/// place), else a primitive's (where assimp's exporter and UniVRM's VRM 0 files put them:
/// glTF issue 1036's first sketch), else each target's own `extras.targetName` (early
/// UniVRM's, which `mend::target_extras` moves to the mesh); empty where none names them.
pub fn target_names(mesh: &Value) -> Vec<String> {
    let names = |v: &Value| -> Vec<String> {
        arr(&v["extras"], "targetNames")
            .iter()
            .map(|n| n.as_str().unwrap_or("").to_string())
            .collect()
    };
    let own = names(mesh);
    if !own.is_empty() {
        return own;
    }
    let primitives = arr(mesh, "primitives");
    (primitives.iter().map(names))
        .chain(primitives.iter().map(names_of_each_target))
        .find(|n| !n.is_empty())
        .unwrap_or_default()
}

/// The names primitive `p`'s targets give themselves (`targets[i].extras.targetName`, early
/// UniVRM's), or none where no target names itself.
pub(crate) fn names_of_each_target(p: &Value) -> Vec<String> {
    let own: Vec<String> = (arr(p, "targets").iter())
        .map(|t| t["extras"]["targetName"].as_str().unwrap_or("").to_string())
        .collect();
    match own.iter().any(|n| !n.is_empty()) {
        true => own,
        false => Vec::new(),
    }
}

/// How many names [`listed`] shows.
const LISTED: usize = 8;

/// Whether `bytes` (a file's start; 64 are enough) begin as a BVH motion capture does: the
/// word HIERARCHY, after any byte-order mark and white space.
pub fn starts_like_bvh(bytes: &[u8]) -> bool {
    let start = String::from_utf8_lossy(&bytes[..bytes.len().min(64)]);
    start
        .trim_start_matches('\u{feff}')
        .trim_start()
        .starts_with("HIERARCHY")
}

/// What a file that is neither glTF nor BVH is instead, from its first bytes, where it is one
/// of the files that stand in for a pipeline's assets: a Git LFS pointer (a clone made
/// without fetching the LFS objects), a web page saved in place of the file, an FBX, a USD
/// stage or package, a ZIP or gzip archive, an image.
pub fn other_kind(bytes: &[u8]) -> Option<&'static str> {
    let head = &bytes[..bytes.len().min(256)];
    let text = String::from_utf8_lossy(head);
    let text = text.trim_start_matches('\u{feff}').trim_start();
    let lower = text.to_ascii_lowercase();
    let is_usd = |name: &[u8]| name.ends_with(b".usda") || name.ends_with(b".usdc");
    let kinds: [(bool, &str); 8] = [
        (
            text.starts_with("version https://git-lfs.github.com/spec/"),
            "a Git LFS pointer, not the file itself (its repository was cloned without its LFS objects: git lfs pull)",
        ),
        (
            lower.starts_with("<!doctype html") || lower.starts_with("<html"),
            "a web page (HTML), not the file itself (saved from a browser in its place? download the raw file)",
        ),
        (
            head.starts_with(b"Kaydara FBX Binary") || text.starts_with("; FBX"),
            "an FBX file (inbetween reads glTF and BVH: convert it first, with Blender or FBX2glTF)",
        ),
        (
            head.starts_with(b"PXR-USDC") || text.starts_with("#usda"),
            "a USD file (inbetween reads glTF and BVH, and writes USD)",
        ),
        (
            head.starts_with(b"PK\x03\x04") && zip_first_name(head).is_some_and(is_usd),
            "a USDZ package (inbetween reads glTF and BVH, and writes USD)",
        ),
        (
            head.starts_with(b"PK\x03\x04"),
            "a ZIP archive (unpack it first)",
        ),
        (
            head.starts_with(&[0x1f, 0x8b]),
            "a gzip archive (unpack it first)",
        ),
        (
            head.starts_with(b"\x89PNG") || head.starts_with(&[0xff, 0xd8, 0xff]),
            "an image, not a glTF file",
        ),
    ];
    kinds.iter().find(|(is, _)| *is).map(|(_, what)| *what)
}

/// The name of a ZIP archive's first entry (its local header's), where `head` holds it.
fn zip_first_name(head: &[u8]) -> Option<&[u8]> {
    let len = u16::from_le_bytes(head.get(26..28)?.try_into().ok()?) as usize;
    head.get(30..30 + len)
}

/// The error for a file whose JSON does not parse; a motion capture handed to a glTF command
/// is named as one, with what reads it, and the files that stand in for assets
/// ([`other_kind`]) as what they are.
fn not_gltf(path: &Path, bytes: &[u8], e: serde_json::Error) -> anyhow::Error {
    if starts_like_bvh(bytes) {
        at(
            path,
            "a BVH motion capture, not a glTF file (`inbetween blend`, `preview` and `inspect` read captures)",
        )
    } else if let Some(what) = other_kind(bytes) {
        at(path, what)
    } else {
        at(
            path,
            format!("not a glTF file (the JSON does not parse: {e})"),
        )
    }
}

/// Top-level arrays whose entries must be objects.
pub(crate) const OBJECT_ARRAYS: &[&str] = &[
    "accessors",
    "animations",
    "buffers",
    "bufferViews",
    "cameras",
    "images",
    "materials",
    "meshes",
    "nodes",
    "samplers",
    "scenes",
    "skins",
    "textures",
];

impl Document {
    /// Read and check a `.gltf` or `.glb` file, its external references confined to its own
    /// folder. Errors name the file and the problem.
    pub fn open(path: &Path) -> Result<Document> {
        Document::open_with(path, &Access::default())
    }

    /// [`Document::open`], external references also allowed under `access.roots`.
    pub fn open_with(path: &Path, access: &Access) -> Result<Document> {
        regular_file(path)?;
        let bytes = std::fs::read(path).map_err(|e| at(path, format!("cannot read: {e}")))?;
        Document::from_bytes(path, &bytes, access)
    }

    /// A document from the bytes of a `.gltf` or `.glb` file at `path` (which names it in
    /// errors and anchors its external references).
    pub fn from_bytes(path: &Path, bytes: &[u8], access: &Access) -> Result<Document> {
        let glb = bytes.starts_with(b"glTF");
        let container = match glb {
            true => container::split(path, bytes)?,
            false => container::Glb {
                json: bytes,
                bin: None,
                said: Vec::new(),
                cut_short: None,
            },
        };
        let (json_bytes, mut read_past) = spelling::json_text(container.json, glb);
        read_past.extend(container.said);
        let mut json: Value =
            serde_json::from_slice(json_bytes).map_err(|e| not_gltf(path, bytes, e))?;
        spelling::integers(&mut json);
        if !json.is_object() || !json.get("asset").is_some_and(Value::is_object) {
            return Err(at(path, "not a glTF file (no \"asset\" object)"));
        }
        let version = json["asset"]["version"].as_str().unwrap_or("");
        if !version.starts_with("2.") {
            return Err(at(
                path,
                format!("unsupported glTF version {version:?} (only 2.x is read)"),
            ));
        }
        check_structure(&json).map_err(|e| at(path, e))?;
        read_past.extend(spelling::signed_indices(&mut json));
        let folder = input_folder(path);
        let mut buffers = Vec::new();
        let mut bin = container.bin;
        let mut input_bytes = bytes.len() as u64;
        for (i, b) in arr(&json, "buffers").iter().enumerate() {
            let cut_short = container.cut_short.as_deref();
            buffers.push(read_buffer(
                path,
                &folder,
                access,
                (i, b),
                &mut bin,
                cut_short,
            )?);
            if b.get("uri")
                .and_then(Value::as_str)
                .is_some_and(|u| !u.starts_with("data:"))
            {
                input_bytes += buffers[i].len() as u64;
            }
        }
        let decoded = decode(&mut json, &mut buffers).map_err(|e| at(path, e))?;
        read_past.extend(targets::equal_counts(&mut json));
        read_past.extend(targets::weights_counts(&mut json));
        // Images are read only when an output needs them, but every reference is checked now.
        for (i, img) in arr(&json, "images").iter().enumerate() {
            if let Some(uri) = img.get("uri").and_then(Value::as_str) {
                if !uri.starts_with("data:") {
                    let why = match reference(uri) {
                        Err(why) => Some(why),
                        Ok(Reference::Outside(_, why)) if access.roots.is_empty() => {
                            Some(why.to_string())
                        }
                        Ok(_) => None,
                    };
                    if let Some(why) = why {
                        return Err(uri_error(path, &format!("image {i}"), uri, why));
                    }
                    // Counted with the input: a .glb output embeds it (a missing one is said
                    // when an output reads it).
                    let size = (access.resolve(&folder, uri).ok())
                        .and_then(|p| std::fs::metadata(p).ok())
                        .filter(std::fs::Metadata::is_file)
                        .map_or(0, |m| m.len());
                    input_bytes += size;
                }
            }
        }
        Ok(Document {
            path: path.to_path_buf(),
            json,
            buffers,
            access: access.clone(),
            input_bytes,
            decoded,
            read_past,
            largest_backed: std::sync::OnceLock::new(),
        })
    }

    pub fn err(&self, msg: impl std::fmt::Display) -> anyhow::Error {
        at(&self.path, msg)
    }

    /// The folder the input lies in (external references are relative to it).
    pub fn folder(&self) -> PathBuf {
        input_folder(&self.path)
    }

    /// The bytes and MIME type of image `i`'s external file `uri` (checked as every reference
    /// is, read up to the size limit, and only when it is an image type glTF allows).
    pub fn read_image(&self, i: usize, uri: &str) -> Result<(Vec<u8>, &'static str)> {
        self.read_image_or_why(i, uri)?
            .map_err(|why| uri_error(&self.path, &format!("image {i}"), uri, why))
    }

    /// [`Document::read_image`], telling a file that cannot be read (missing, not a regular
    /// file, not an image type glTF allows, too large: the inner `Err`, why) from a reference
    /// that leads outside the folders it may read (the outer error, a refusal): a texture
    /// missing beside a downloaded `.gltf` need not stop the work on its geometry.
    pub fn read_image_or_why(
        &self,
        i: usize,
        uri: &str,
    ) -> Result<std::result::Result<(Vec<u8>, &'static str), String>> {
        let file = match self.access.resolve(&self.folder(), uri) {
            Ok(file) => file,
            Err(why) if why.starts_with("cannot be read") || why == "is not a regular file" => {
                return Ok(Err(why))
            }
            Err(why) => return Err(uri_error(&self.path, &format!("image {i}"), uri, why)),
        };
        Ok(read_image(&file))
    }

    /// The bytes of buffer view `v` (an error naming it when it reaches past its buffer).
    pub fn view(&self, v: usize) -> Result<&[u8]> {
        let bv = &self.json["bufferViews"][v];
        let b = bv["buffer"].as_u64().unwrap_or(0) as usize;
        let start = bv["byteOffset"].as_u64().unwrap_or(0) as usize;
        let len = bv["byteLength"].as_u64().unwrap_or(0) as usize;
        self.buffers
            .get(b)
            .and_then(|d| d.get(start..start.checked_add(len)?))
            .ok_or_else(|| self.err(format!("bufferView {v} reaches past the end of buffer {b}")))
    }

    /// The bytes of image `i` wherever they are (a buffer view, a data URI or an external file)
    /// and their type as their first bytes say (`None` when they are none glTF allows).
    pub fn image(&self, i: usize) -> Result<(Vec<u8>, Option<&'static str>)> {
        let img = &self.json["images"][i];
        let data = if let Some(v) = img["bufferView"].as_u64() {
            self.view(v as usize)?.to_vec()
        } else {
            match img["uri"].as_str() {
                Some(uri) if uri.starts_with("data:") => data_uri(uri).ok_or_else(|| {
                    self.err(format!(
                        "image {i} has a data URI whose base64 does not decode"
                    ))
                })?,
                Some(uri) => self.read_image(i, uri)?.0,
                None => bail!(self.err(format!("image {i} has neither a uri nor a bufferView"))),
            }
        };
        let mime = image_mime(&data);
        Ok((data, mime))
    }
}

fn input_folder(path: &Path) -> PathBuf {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// The bytes of buffer `i`: the GLB binary chunk, a data URI, or an external file (read up to
/// its declared length); refused when they are fewer than declared.
fn read_buffer(
    path: &Path,
    folder: &Path,
    access: &Access,
    (i, b): (usize, &Value),
    bin: &mut Option<&[u8]>,
    cut_short: Option<&str>,
) -> Result<Vec<u8>> {
    let declared = b["byteLength"].as_u64().unwrap_or(0);
    let what = format!("buffer {i}");
    // A meshopt fallback buffer holds no data: its views are decoded from another buffer.
    let ext = &b["extensions"];
    let fallback = ["EXT_meshopt_compression", "KHR_meshopt_compression"]
        .iter()
        .any(|e| ext[*e]["fallback"].as_bool() == Some(true));
    let mut from_chunk = false;
    let data = match b.get("uri").and_then(Value::as_str) {
        None if fallback => Vec::new(),
        None => {
            from_chunk = true;
            let chunk = if i == 0 { bin.take() } else { None };
            chunk.map(<[u8]>::to_vec).ok_or_else(|| {
                at(
                    path,
                    format!("buffer {i} has no uri and there is no GLB binary chunk for it"),
                )
            })?
        }
        Some(uri) if uri.starts_with("data:") => data_uri(uri).ok_or_else(|| {
            at(
                path,
                format!("buffer {i} has a data URI whose base64 does not decode"),
            )
        })?,
        Some(uri) => {
            let file = access
                .resolve(folder, uri)
                .map_err(|why| uri_error(path, &what, uri, why))?;
            read_prefix(&file, declared).map_err(|why| uri_error(path, &what, uri, why))?
        }
    };
    if (data.len() as u64) < declared && !fallback {
        let held = data.len();
        bail!(at(
            path,
            match cut_short.filter(|_| from_chunk) {
                Some(header_says) => format!("{header_says}: cut short, buffer {i} declares {declared} bytes and {held} are there"),
                None => format!("buffer {i} declares {declared} bytes but holds {held}"),
            }
        ));
    }
    Ok(data)
}

/// The parts of the JSON that the reader and writer index into must have the right kind:
/// entries of the top-level arrays, primitives, attributes, targets, channels and samplers are
/// objects.
fn check_structure(json: &Value) -> std::result::Result<(), String> {
    let objects = |v: &Value, at: &str| -> std::result::Result<(), String> {
        match v {
            Value::Null => Ok(()),
            Value::Array(items) => match items.iter().position(|x| !x.is_object()) {
                Some(k) => Err(format!("{at}[{k}] is not an object")),
                None => Ok(()),
            },
            _ => Err(format!("{at} is not an array")),
        }
    };
    for key in OBJECT_ARRAYS {
        objects(&json[*key], key)?;
    }
    for (m, mesh) in arr(json, "meshes").iter().enumerate() {
        objects(&mesh["primitives"], &format!("meshes[{m}].primitives"))?;
        for (p, prim) in arr(mesh, "primitives").iter().enumerate() {
            let here = format!("meshes[{m}].primitives[{p}]");
            if !prim["attributes"].is_object() {
                return Err(format!("{here}.attributes is not an object"));
            }
            objects(&prim["targets"], &format!("{here}.targets"))?;
        }
    }
    for (a, anim) in arr(json, "animations").iter().enumerate() {
        objects(&anim["channels"], &format!("animations[{a}].channels"))?;
        objects(&anim["samplers"], &format!("animations[{a}].samplers"))?;
        for (c, ch) in arr(anim, "channels").iter().enumerate() {
            if !ch["target"].is_object() {
                return Err(format!(
                    "animations[{a}].channels[{c}].target is not an object"
                ));
            }
        }
    }
    for key in ["extensionsUsed", "extensionsRequired"] {
        match &json[key] {
            Value::Null => {}
            Value::Array(items) if items.iter().all(Value::is_string) => {}
            _ => return Err(format!("{key} is not an array of names")),
        }
    }
    Ok(())
}

/// What an animation channel's morph weights target is: the weights of a node (`path:
/// "weights"`, or a `KHR_animation_pointer` channel aimed at `/nodes/N/weights`) or of a mesh
/// (`/meshes/M/weights`: every node carrying it plays them).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WeightsTarget {
    Node(usize),
    Mesh(usize),
}

/// The weights a channel `target` animates, if it animates weights.
pub fn weights_target(target: &Value) -> Option<WeightsTarget> {
    match target["path"].as_str()? {
        "weights" => Some(WeightsTarget::Node(target["node"].as_u64()? as usize)),
        "pointer" => match pointer_parts(target)? {
            ("nodes", index, "weights") => Some(WeightsTarget::Node(index)),
            ("meshes", index, "weights") => Some(WeightsTarget::Mesh(index)),
            _ => None,
        },
        _ => None,
    }
}

/// The node and property (`translation`, `rotation`, `scale`, `weights`) a channel `target`
/// animates: its `node` and `path`, or a `KHR_animation_pointer` aimed at `/nodes/N/<property>`.
pub fn node_target(target: &Value) -> Option<(usize, &str)> {
    match target["path"].as_str()? {
        "pointer" => match pointer_parts(target)? {
            ("nodes", index, leaf) => Some((index, leaf)),
            _ => None,
        },
        path => Some((target["node"].as_u64()? as usize, path)),
    }
}

/// A `KHR_animation_pointer` target of the form `/<kind>/<index>/<property>`.
fn pointer_parts(target: &Value) -> Option<(&str, usize, &str)> {
    let pointer = target["extensions"]["KHR_animation_pointer"]["pointer"].as_str()?;
    let mut parts = pointer.strip_prefix('/')?.split('/');
    let (kind, index, leaf) = (parts.next()?, parts.next()?, parts.next()?);
    if parts.next().is_some() {
        return None;
    }
    // A JSON pointer's array index: digits, no leading zero.
    if index.is_empty()
        || !index.bytes().all(|b| b.is_ascii_digit())
        || (index.len() > 1 && index.starts_with('0'))
    {
        return None;
    }
    Some((kind, index.parse().ok()?, leaf))
}

/// The array under `key`, or an empty slice.
pub fn arr<'a>(v: &'a Value, key: &str) -> &'a [Value] {
    v.get(key)
        .and_then(Value::as_array)
        .map(Vec::as_slice)
        .unwrap_or(&[])
}

/// The nodes instancing each mesh, in node order (`mesh_nodes(json)[m]`), found in one pass
/// over the nodes; a node naming a mesh the file lacks is left out. (A scan of the nodes for
/// each mesh took 10 of the 10.2 s of a preview of 30,000 one-triangle morph meshes.)
pub fn mesh_nodes(json: &Value) -> Vec<Vec<usize>> {
    let mut out = vec![Vec::new(); arr(json, "meshes").len()];
    for (i, n) in arr(json, "nodes").iter().enumerate() {
        if let Some(list) = n["mesh"].as_u64().and_then(|m| out.get_mut(m as usize)) {
            list.push(i);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::{mesh_nodes, other_kind, weights_target, WeightsTarget};
    use serde_json::json;

    /// Files that stand in for assets are told by their first bytes; a glTF's are none.
    #[test]
    fn files_that_stand_in_for_assets_are_named() {
        let starts = |b: &[u8], want: Option<&str>| match (other_kind(b), want) {
            (Some(k), Some(w)) => k.starts_with(w),
            (k, w) => k.is_none() && w.is_none(),
        };
        let mut usdz = b"PK\x03\x04".to_vec();
        usdz.extend_from_slice(&[0; 22]);
        usdz.extend_from_slice(&10u16.to_le_bytes());
        usdz.extend_from_slice(&[0, 0]);
        usdz.extend_from_slice(b"blend.usdc");
        let mut zip = usdz.clone();
        zip.truncate(30);
        zip.extend_from_slice(b"walk.glb");
        for (bytes, want) in [
            (
                &b"version https://git-lfs.github.com/spec/v1\noid sha256:00"[..],
                Some("a Git LFS"),
            ),
            (b"\xef\xbb\xbf  <!doctype HTML><html>", Some("a web page")),
            (b"<html><body>", Some("a web page")),
            (b"Kaydara FBX Binary  \x00", Some("an FBX file")),
            (b"; FBX 7.4.0 project file", Some("an FBX file")),
            (b"#usda 1.0\n(", Some("a USD file")),
            (b"PXR-USDC\x00", Some("a USD file")),
            (&usdz, Some("a USDZ package")),
            (&zip, Some("a ZIP archive")),
            (b"\x1f\x8b\x08\x00", Some("a gzip archive")),
            (b"\x89PNG\r\n\x1a\n", Some("an image")),
            (b"{\"asset\":{\"version\":\"2.0\"}}", None),
            (b"", None),
        ] {
            let what = other_kind(bytes);
            let text = String::from_utf8_lossy(bytes);
            assert!(starts(bytes, want), "{text:?}: {what:?}");
        }
    }

    /// Each mesh's nodes in node order; a node naming a mesh the file lacks, or none, is passed.
    #[test]
    fn the_nodes_of_each_mesh_in_node_order() {
        let json = json!({
            "meshes": [{}, {}, {}],
            "nodes": [{"mesh": 1}, {}, {"mesh": 0}, {"mesh": 1}, {"mesh": 7}, {"mesh": "x"}],
        });
        assert_eq!(mesh_nodes(&json), vec![vec![2], vec![0, 3], vec![]]);
        assert!(mesh_nodes(&json!({"nodes": [{"mesh": 0}]})).is_empty());
    }

    #[test]
    fn weights_targets_by_path_and_by_pointer() {
        let pointer = |p: &str| {
            weights_target(
                &json!({"path": "pointer", "extensions": {"KHR_animation_pointer": {"pointer": p}}}),
            )
        };
        assert_eq!(
            weights_target(&json!({"node": 3, "path": "weights"})),
            Some(WeightsTarget::Node(3))
        );
        assert_eq!(
            weights_target(&json!({"node": 3, "path": "rotation"})),
            None
        );
        assert_eq!(pointer("/nodes/12/weights"), Some(WeightsTarget::Node(12)));
        assert_eq!(pointer("/meshes/0/weights"), Some(WeightsTarget::Mesh(0)));
        for not in [
            "/nodes/1/translation",
            "/nodes/01/weights",
            "/nodes//weights",
            "/nodes/1/weights/0",
            "/materials/0/weights",
            "nodes/1/weights",
        ] {
            assert_eq!(pointer(not), None, "{not}");
        }
    }
}
