//! External references of a `.gltf` (buffer and image URIs): what a file may make us read.
//!
//! A URI is read only when it is a relative reference that stays inside the input file's
//! folder (or a root the user named with `--allow-external`): after `%XX` decoding and `..`
//! resolved, and again after symbolic links are followed. Absolute paths, `file:` and other
//! schemes, references that climb out, device files and anything else that is not a regular
//! file are refused with an error naming the URI. A buffer is read up to its declared
//! `byteLength` and no further; an image up to [`MAX_IMAGE_BYTES`], and only when its first
//! bytes are those of an image type glTF allows.

use anyhow::{anyhow, bail, Result};
use std::io::Read;
use std::path::{Component, Path, PathBuf};

/// Largest image file read (bytes): 512 MiB, far above any texture a real asset carries.
pub const MAX_IMAGE_BYTES: u64 = 512 << 20;

/// Where external references may lead: the input file's folder and the extra roots.
#[derive(Clone, Debug, Default)]
pub struct Access {
    /// Folders the user allowed besides the input's own (`--allow-external`).
    pub roots: Vec<PathBuf>,
}

/// Where a URI points, after the lexical checks: inside the input's folder (its path relative
/// to it, normalised), or outside it (an absolute path, or one that climbs out), which only
/// the extra roots may allow.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Reference {
    Inside(PathBuf),
    Outside(PathBuf, &'static str),
}

/// Decode `%XX` escapes of a relative URI into a file path.
pub fn percent_decode(uri: &str) -> String {
    String::from_utf8_lossy(&percent_bytes(uri)).into_owned()
}

/// The bytes `%XX` escapes stand for, the other characters as they are.
fn percent_bytes(uri: &str) -> Vec<u8> {
    let b = uri.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' && i + 2 < b.len() {
            if let Some(v) = std::str::from_utf8(&b[i + 1..i + 3])
                .ok()
                .and_then(|h| u8::from_str_radix(h, 16).ok())
            {
                out.push(v);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    out
}

/// The bytes of a `data:` URI (RFC 2397), read as browsers read it (WHATWG's data: URL
/// processor): its data `%XX`-decoded, then, where its header ends `;base64` (in any case),
/// base64 with ASCII whitespace skipped and the padding optional. Writers wrap base64 in lines
/// (Python's `base64.encodebytes`, 76 characters a line, its newlines escaped in the JSON),
/// leave out its padding, or write the bytes themselves `%XX`-escaped, as RFC 2397 allows
/// (the validator takes those; Blender's importer, its issue 635, did not).
pub fn data_uri(uri: &str) -> Option<Vec<u8>> {
    use base64::engine::{DecodePaddingMode, GeneralPurpose, GeneralPurposeConfig};
    use base64::Engine;
    const FORGIVING: GeneralPurpose = GeneralPurpose::new(
        &base64::alphabet::STANDARD,
        GeneralPurposeConfig::new()
            .with_decode_padding_mode(DecodePaddingMode::Indifferent)
            .with_decode_allow_trailing_bits(true),
    );
    let (head, data) = uri.strip_prefix("data:")?.split_once(',')?;
    let bytes = percent_bytes(data);
    let base64 = (head.rsplit(';').next()).is_some_and(|p| p.trim().eq_ignore_ascii_case("base64"));
    if !base64 {
        return Some(bytes);
    }
    let text: Vec<u8> = bytes
        .into_iter()
        .filter(|b| !b.is_ascii_whitespace())
        .collect();
    FORGIVING.decode(text).ok()
}

const ABSOLUTE: &str = "is an absolute path (only references inside the input file's folder are read; --allow-external names other folders that may be)";
const CLIMBS: &str =
    "climbs out of the input file's folder (--allow-external names other folders that may be read)";

/// The lexical checks: no scheme (`file:`, `http:`), no NUL, and a path that names a file.
/// Returns where it points, `..` resolved.
pub fn reference(uri: &str) -> Result<Reference, String> {
    // A scheme is letters, digits, '+', '-' or '.' before the first ':' (RFC 3986), and it
    // comes before any '/', '?' or '#'.
    if let Some(colon) = uri.find(':') {
        let head = &uri[..colon];
        if !head.is_empty()
            && !head.contains(['/', '?', '#'])
            && head
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || matches!(c, '+' | '-' | '.'))
        {
            return Err("is an absolute URI (only relative references are read)".into());
        }
    }
    // A backslash is no URI character: Windows exporters write their paths' separators so
    // (`textures\wood.png`: AWS iot-app-kit's pull request 417), read as the folders they
    // are (`%5C`, a backslash escaped, stays a character of a name).
    let uri = uri.replace('\\', "/");
    let path = percent_decode(uri.split(['?', '#']).next().unwrap_or(""));
    if path.contains('\0') {
        return Err("holds a NUL character".into());
    }
    if path.starts_with('/') || path.starts_with('\\') {
        return Ok(Reference::Outside(PathBuf::from(path), ABSOLUTE));
    }
    let mut out = PathBuf::new();
    let mut climbs = false;
    for c in Path::new(&path).components() {
        match c {
            Component::Normal(part) => out.push(part),
            Component::CurDir => {}
            Component::ParentDir => climbs |= !out.pop(),
            Component::RootDir | Component::Prefix(_) => {
                return Ok(Reference::Outside(PathBuf::from(path), ABSOLUTE))
            }
        }
    }
    if climbs {
        return Ok(Reference::Outside(PathBuf::from(path), CLIMBS));
    }
    if out.as_os_str().is_empty() {
        return Err("names no file".into());
    }
    Ok(Reference::Inside(out))
}

impl Access {
    /// The regular file `uri` names, seen from `folder` (the input's): lexically checked,
    /// symbolic links followed, and the result checked against `folder` and the extra roots.
    pub fn resolve(&self, folder: &Path, uri: &str) -> Result<PathBuf, String> {
        let joined = match reference(uri)? {
            Reference::Inside(rel) => folder.join(rel),
            Reference::Outside(_, why) if self.roots.is_empty() => return Err(why.into()),
            Reference::Outside(path, _) => folder.join(path),
        };
        let real = joined
            .canonicalize()
            .map_err(|e| format!("cannot be read: {e}"))?;
        let inside = |root: &Path| root.canonicalize().is_ok_and(|r| real.starts_with(r));
        if !inside(folder) && !self.roots.iter().any(|r| inside(r)) {
            return Err(
                "leads outside the input file's folder (through a symbolic link, or outside every --allow-external folder)"
                    .into(),
            );
        }
        let meta = std::fs::metadata(&real).map_err(|e| format!("cannot be read: {e}"))?;
        if !meta.is_file() {
            return Err("is not a regular file".into());
        }
        Ok(real)
    }
}

/// Read exactly `len` bytes from the start of the regular file `path` (an error when it is
/// shorter); nothing past them is read.
pub fn read_prefix(path: &Path, len: u64) -> Result<Vec<u8>, String> {
    let file = std::fs::File::open(path).map_err(|e| format!("cannot be read: {e}"))?;
    let size = file
        .metadata()
        .map_err(|e| format!("cannot be read: {e}"))?
        .len();
    if size < len {
        // A pointer or a page in the file's place is named as one.
        let mut head = Vec::new();
        let _ = (&file).take(256).read_to_end(&mut head);
        return Err(stand_in_or(&head, || {
            format!("holds {size} bytes, fewer than the {len} declared")
        }));
    }
    let mut data = Vec::with_capacity(len as usize);
    file.take(len)
        .read_to_end(&mut data)
        .map_err(|e| format!("cannot be read: {e}"))?;
    if (data.len() as u64) < len {
        return Err(format!(
            "holds {} bytes, fewer than the {len} declared",
            data.len()
        ));
    }
    Ok(data)
}

/// What is wrong with a referenced file whose first bytes are `head`: "is" the file that stands
/// in for it where it is one ([`super::read::other_kind`]: an LFS pointer, a web page), else
/// `otherwise`.
fn stand_in_or(head: &[u8], otherwise: impl FnOnce() -> String) -> String {
    match super::read::other_kind(head) {
        Some(what) => format!("is {what}"),
        None => otherwise(),
    }
}

/// The image types glTF allows (core PNG and JPEG; KTX2, WebP and AVIF by extension), told by
/// their first bytes.
pub fn image_mime(bytes: &[u8]) -> Option<&'static str> {
    if bytes.starts_with(b"\x89PNG\r\n\x1a\n") {
        Some("image/png")
    } else if bytes.starts_with(&[0xFF, 0xD8, 0xFF]) {
        Some("image/jpeg")
    } else if bytes.starts_with(b"\xABKTX 20\xBB\r\n\x1a\n") {
        Some("image/ktx2")
    } else if bytes.len() >= 12 && &bytes[..4] == b"RIFF" && &bytes[8..12] == b"WEBP" {
        Some("image/webp")
    } else if bytes.len() >= 12
        && &bytes[4..8] == b"ftyp"
        && matches!(&bytes[8..12], b"avif" | b"avis")
    {
        Some("image/avif")
    } else {
        None
    }
}

/// Read an image file (at most [`MAX_IMAGE_BYTES`]) and check that it is one of the types glTF
/// allows; returns the bytes and the MIME type.
pub fn read_image(path: &Path) -> Result<(Vec<u8>, &'static str), String> {
    let file = std::fs::File::open(path).map_err(|e| format!("cannot be read: {e}"))?;
    let mut data = Vec::new();
    file.take(MAX_IMAGE_BYTES + 1)
        .read_to_end(&mut data)
        .map_err(|e| format!("cannot be read: {e}"))?;
    if data.len() as u64 > MAX_IMAGE_BYTES {
        return Err(format!("is larger than {} MiB", MAX_IMAGE_BYTES >> 20));
    }
    let mime = image_mime(&data).ok_or_else(|| {
        stand_in_or(&data, || {
            "is not a PNG, JPEG, KTX2, WebP or AVIF image".to_string()
        })
    })?;
    Ok((data, mime))
}

/// An error naming the input file, the object and its URI.
pub fn uri_error(file: &Path, what: &str, uri: &str, why: impl std::fmt::Display) -> anyhow::Error {
    let shown: String = uri.chars().take(120).collect();
    anyhow!("{}: {what} uri {shown:?} {why}", file.display())
}

/// Refuse a file that is not a regular file (a device, a folder, a pipe) before reading it.
pub fn regular_file(path: &Path) -> Result<()> {
    let meta =
        std::fs::metadata(path).map_err(|e| anyhow!("{}: cannot read: {e}", path.display()))?;
    if !meta.is_file() {
        bail!("{}: cannot read: not a regular file", path.display());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Data URIs as writers spell them: base64 padded or not, wrapped in lines, `;BASE64`, or
    /// the bytes themselves `%XX`-escaped; base64 that does not decode is none.
    #[test]
    fn data_uris_are_read_as_browsers_read_them() {
        let bytes = [0u8, 1, 2, 250, 255, 64, 65];
        for uri in [
            "data:application/octet-stream;base64,AAEC+v9AQQ==",
            "data:application/octet-stream;base64,AAEC+v9AQQ",
            "data:application/gltf-buffer;BASE64,AAEC\r\n+v9A\nQQ==",
            "data:;base64, AAEC +v9AQQ%3D%3D",
            "data:application/octet-stream,%00%01%02%FA%FF@A",
            "data:,%00%01%02%fa%ff%40A",
        ] {
            assert_eq!(data_uri(uri).as_deref(), Some(&bytes[..]), "{uri:?}");
        }
        assert_eq!(data_uri("data:;base64,AAE*"), None);
        assert_eq!(data_uri("data:;base64,A"), None);
        assert_eq!(data_uri("data:application/octet-stream"), None);
    }

    #[test]
    fn references_are_normalised_and_escapes_told_apart() {
        let inside = |u: &str| match reference(u) {
            Ok(Reference::Inside(p)) => p,
            other => panic!("{u:?}: {other:?}"),
        };
        assert_eq!(inside("a/./b/../c.bin"), PathBuf::from("a/c.bin"));
        assert_eq!(inside("My%20File.bin"), PathBuf::from("My File.bin"));
        // A Windows path's backslashes are folders; an escaped one is a name's character.
        assert_eq!(
            inside("textures\\wood.png"),
            PathBuf::from("textures/wood.png")
        );
        assert_eq!(inside("a%5Cb.png"), PathBuf::from("a\\b.png"));
        for outside in [
            "/etc/hostname",
            "../a.bin",
            "a/../../b.bin",
            "%2e%2e/secret",
            "%2Fetc%2Fpasswd",
            "..\\..\\secret",
            "\\etc\\hostname",
            "a\\..\\..\\b.bin",
        ] {
            assert!(
                matches!(reference(outside), Ok(Reference::Outside(..))),
                "{outside:?}"
            );
        }
        for bad in [
            "C:\\Users\\a.bin",
            "file:///etc/hostname",
            "FILE:x",
            "http://example.com/a.bin",
            "a%00b",
            "",
            ".",
        ] {
            assert!(reference(bad).is_err(), "{bad:?} was accepted");
        }
    }

    #[test]
    fn images_are_told_by_their_first_bytes() {
        assert_eq!(image_mime(b"\x89PNG\r\n\x1a\nrest"), Some("image/png"));
        assert_eq!(image_mime(&[0xFF, 0xD8, 0xFF, 0xE0]), Some("image/jpeg"));
        assert_eq!(image_mime(b"RIFF\0\0\0\0WEBPVP8 "), Some("image/webp"));
        assert_eq!(image_mime(b"root:x:0:0:root"), None);
    }
}
