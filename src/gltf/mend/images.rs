//! Image types ([`image_types`]): an image's declared `mimeType` must be the type its bytes
//! are (the validator's IMAGE_MIME_TYPE_INVALID). Writers that name the type after a file's
//! extension label a JPEG saved as `.png` (common in bought and scanned texture sets) as PNG,
//! and a `.glb` embeds it so. Written as its bytes tell (PNG, JPEG, KTX2, WebP, AVIF: the
//! decoders that players pick by the bytes show it the same; those that go by the label fail
//! on the wrong one).

use super::said_of;
use crate::gltf::build::BinBuilder;
use crate::gltf::read::{arr, quoted_name, Document};
use crate::gltf::uri::image_mime;
use serde_json::Value;

/// Set each image's declared `mimeType` to the type its bytes are, where the two differ: the
/// bytes from its view in `bin` (placed by `write::begin`, images the output embeds among
/// them) or, for an image `json` still refers to by file, read through `doc`; returns a line
/// naming them.
pub fn image_types(doc: &Document, json: &mut Value, bin: &BinBuilder) -> Vec<String> {
    let mut fixed = Vec::new();
    for i in 0..arr(json, "images").len() {
        let img = &json["images"][i];
        let Some(declared) = img["mimeType"].as_str() else {
            continue;
        };
        let told = if let Some(v) = img["bufferView"].as_u64() {
            let Some(view) = bin.views.get(v as usize) else {
                continue;
            };
            let start = view["byteOffset"].as_u64().unwrap_or(0) as usize;
            let len = view["byteLength"].as_u64().unwrap_or(0) as usize;
            let end = start.saturating_add(len.min(16)).min(bin.bytes.len());
            image_mime(bin.bytes.get(start..end).unwrap_or_default())
        } else if img["uri"].as_str().is_some_and(|u| !u.starts_with("data:")) {
            doc.image(i).ok().and_then(|(_, mime)| mime)
        } else {
            None
        };
        let Some(told) = told.filter(|t| *t != declared) else {
            continue;
        };
        let name = quoted_name(img, || i.to_string());
        fixed.push(format!("{name} ({declared}, its bytes {told})"));
        json["images"][i]["mimeType"] = told.into();
    }
    said_of(&fixed, |_, s, its, which| {
        format!("image{s} {which} declared another type than {its} bytes are: declared as the bytes are")
    })
}
