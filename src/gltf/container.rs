//! Container stage (on read): a `.glb` file split into its JSON and binary chunks.
//!
//! glTF's GLB is a 12-byte header (magic, version 2, the file's length) and chunks, each its
//! length, its type and its bytes: JSON first, then the binary buffer; chunks of other types are
//! skipped, as glTF asks. The chunks are read from the bytes the file has. Where the header's
//! length is not the file's, the file is read as its chunks say and the line is said
//! ([`Glb::said`]); the output's header is written right:
//!
//! - bytes after the declared length that are no whole chunk (a GLB cut out of a 3D Tiles b3dm
//!   keeps the 4 bytes the tile padded it with: three.js pull request 21122; a copy padded in
//!   transfer) are left out;
//! - chunks whole in the file past the declared length are read (a header counting the JSON
//!   chunk only: qmuntal/gltf issue 38, fixed in its pull request 39);
//! - a binary chunk the file ends inside (its padding counted and not written; assimp's
//!   exporter miscounted its chunk's padding, its issue 3176) is read as far as it goes:
//!   enough where its buffer's `byteLength` lies within it; a file cut short (a download
//!   stopped) is refused when its buffer is read ([`Glb::cut_short`] says so there).

use super::read::at;
use anyhow::{bail, Result};
use std::path::Path;

const JSON: u32 = 0x4E4F_534A;
const BIN: u32 = 0x004E_4942;

/// A GLB's chunks, as read.
pub struct Glb<'a> {
    pub json: &'a [u8],
    pub bin: Option<&'a [u8]>,
    /// Where the header's length is not the file's: what was read, a line.
    pub said: Vec<String>,
    /// Where the file ends inside its binary chunk: a clause naming the header's length and the
    /// file's, for the refusal of a buffer the chunk does not hold.
    pub cut_short: Option<String>,
}

/// Split a `.glb` file's bytes into its chunks (see the module comment).
pub fn split<'a>(path: &Path, bytes: &'a [u8]) -> Result<Glb<'a>> {
    let word = |at: usize| -> Option<u32> {
        bytes
            .get(at..at + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    let (Some(version), Some(declared)) = (word(4), word(8)) else {
        bail!(at(path, "truncated GLB header"));
    };
    if version != 2 {
        bail!(at(
            path,
            format!("GLB container version {version} is not supported (only 2)")
        ));
    }
    let (declared, len) = (declared as usize, bytes.len());
    let header_says =
        || format!("GLB header says the file is {declared} bytes but it is {len} bytes");
    let mut off = 12;
    let mut json = None;
    let mut bin = None;
    let mut cut_short = None;
    while let (Some(clen), Some(ctype)) = (word(off), word(off + 4)) {
        let end = off.saturating_add(8).saturating_add(clen as usize);
        if end > len {
            if off >= declared {
                break; // bytes past the declared length: not a chunk
            }
            if ctype == BIN && json.is_some() && bin.is_none() {
                bin = Some(&bytes[off + 8..]);
                cut_short = Some(header_says());
                off = len;
                break;
            }
            bail!(at(
                path,
                match declared > len {
                    true => format!("{}: it ends inside the chunk at byte {off}", header_says()),
                    false => format!("GLB chunk at byte {off} runs past the end of the file"),
                }
            ));
        }
        match ctype {
            JSON if json.is_none() => json = Some(&bytes[off + 8..end]),
            BIN if bin.is_none() => bin = Some(&bytes[off + 8..end]),
            _ => {}
        }
        off = end;
    }
    let Some(json) = json else {
        bail!(at(path, "GLB has no JSON chunk"));
    };
    let mut said = Vec::new();
    if declared != len {
        said.push(match () {
            _ if cut_short.is_some() && declared > len => format!("the GLB header declares {declared} bytes and the file ends {} bytes before, inside its binary chunk, which still holds the buffer's bytes (padding a writer left out): read, the output's header written right", declared - len),
            // The header's length short of the file's and the binary chunk's past both.
            _ if cut_short.is_some() => format!("the GLB's binary chunk runs past the end of the file (its header declares {declared} bytes, the file has {len}) and still holds the buffer's bytes: read, the output's header written right"),
            _ if off < len => format!("{} bytes after the GLB's chunks, which its header's length ({declared} bytes) leaves out, are no chunk: not read, the output written without them", len - off),
            _ => format!("the GLB header declares {declared} bytes where its chunks take {len}: read by its chunks, the output's header written right"),
        });
    }
    Ok(Glb {
        json,
        bin,
        said,
        cut_short,
    })
}
