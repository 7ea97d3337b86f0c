//! The USD file of a stage in the format its extension asks for, staged in the run's
//! [`Outputs`]: `.usda` text or a `.usdc` crate file with the materials' textures beside it,
//! or a `.usdz` package holding the `.usdc` and the textures.

use super::stage::{FrameSource, Stage};
use super::{usda, usdc, usdz};
use crate::output::{folder_of, Format, Outputs};
use anyhow::{bail, Result};
use std::io::Write;
use std::path::Path;

/// Stage `stage` at `path` in `format` in `files`, taking the frames from `source` as they
/// are computed; returns the file's size in bytes.
pub fn write_file(
    stage: &Stage,
    format: Format,
    path: &Path,
    source: &mut FrameSource,
    files: &mut Outputs,
) -> Result<u64> {
    let textures = &stage.look.textures;
    let layer = match format {
        Format::Usda => usda::write(stage, path, source, files)?,
        Format::Usdc => {
            files.write_with(path, |w| usdc::write_usdc(stage, w, source).map(|_| ()))?
        }
        Format::Usdz => {
            // The root layer, as .usdc, in a scratch file beside the output, then stored with
            // the textures after it.
            let layer = files.scratch_with(path, ".usdc", |w| {
                usdc::write_usdc(stage, w, source).map(|_| ())
            })?;
            let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("stage");
            let mut entries = vec![(format!("{stem}.usdc"), layer)];
            for (k, t) in textures.iter().enumerate() {
                let file = files
                    .scratch_with(path, &format!(".texture{k}"), |w| Ok(w.write_all(&t.data)?))?;
                entries.push((t.file.clone(), file));
            }
            return files.write_with(path, |w| usdz::write_package(w, &entries));
        }
        Format::Glb | Format::Gltf => bail!("{}: not a USD format", path.display()),
    };
    // Textures beside a .usda or .usdc, where its relative asset paths find them.
    let mut bytes = layer;
    for t in textures {
        bytes += files.write(&folder_of(path).join(&t.file), &t.data)?;
    }
    Ok(bytes)
}
