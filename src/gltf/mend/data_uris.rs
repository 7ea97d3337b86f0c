//! Image data URIs ([`image_data_uris`]): an image embedded in a `.gltf` as a `data:` URI that
//! browsers read but the validator does not (INVALID_URI): base64 wrapped in lines (Python's
//! `base64.encodebytes` writes 76 characters a line), without its padding, or with its header
//! in another case, is written as plain base64. The bytes are those the reader took
//! ([`crate::gltf::uri::data_uri`]); a data URI of the bytes themselves, `%XX`-escaped as
//! RFC 2397 allows and the validator takes, is left as written.

use super::said_of;
use crate::gltf::read::quoted_name;
use crate::gltf::uri::{data_uri, image_mime};
use base64::Engine;
use serde_json::Value;

/// Rewrite as plain base64 each image data URI whose base64 is spelled otherwise; a line
/// naming them.
pub fn image_data_uris(json: &mut Value) -> Vec<String> {
    let mut fixed = Vec::new();
    let images = json.get_mut("images").and_then(Value::as_array_mut);
    for (i, img) in images.into_iter().flatten().enumerate() {
        let Some(uri) = img["uri"].as_str() else {
            continue;
        };
        let Some((head, text)) = uri.strip_prefix("data:").and_then(|u| u.split_once(',')) else {
            continue;
        };
        let Some(media) = head.strip_suffix(";base64").or_else(|| {
            let cut = head.len().checked_sub(7)?;
            head[cut..]
                .eq_ignore_ascii_case(";base64")
                .then(|| &head[..cut])
        }) else {
            continue;
        };
        let Some(bytes) = data_uri(uri) else {
            continue;
        };
        let plain = base64::engine::general_purpose::STANDARD.encode(&bytes);
        if head.ends_with(";base64") && text == plain {
            continue;
        }
        let media = match media.trim() {
            "" => image_mime(&bytes).unwrap_or("application/octet-stream"),
            m => m,
        };
        img["uri"] = format!("data:{media};base64,{plain}").into();
        fixed.push(quoted_name(img, || i.to_string()));
    }
    said_of(&fixed, |_, s, _, which| {
        format!("image{s} {which} embedded as data URIs whose base64 browsers read but glTF's validator does not (wrapped in lines, without padding or a header in another case): written as plain base64")
    })
}
