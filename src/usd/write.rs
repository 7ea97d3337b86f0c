//! The USD file of a stage in the format its extension asks for, staged in the run's
//! [`Outputs`]: `.usda` text, a `.usdc` crate file, or a `.usdz` package holding the `.usdc`.

use super::stage::{FrameSource, Stage};
use super::{usda, usdc, usdz};
use crate::output::{Format, Outputs};
use anyhow::{bail, Result};
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
    match format {
        Format::Usda => usda::write(stage, path, source, files),
        Format::Usdc => files.write_with(path, |w| usdc::write_usdc(stage, w, source).map(|_| ())),
        Format::Usdz => {
            // The root layer, as .usdc, in a scratch file beside the output, then stored.
            let layer = files.scratch_with(path, ".usdc", |w| {
                usdc::write_usdc(stage, w, source).map(|_| ())
            })?;
            let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("stage");
            files.write_with(path, |w| {
                usdz::write_package(w, &[(format!("{stem}.usdc"), layer.clone())])
            })
        }
        Format::Glb | Format::Gltf => bail!("{}: not a USD format", path.display()),
    }
}
