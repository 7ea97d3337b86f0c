//! Output files: the format a path asks for (by its extension), and the one way every command
//! writes files: each file of a run is written under a temporary name beside its target, and
//! all of them are renamed into place together once every one is complete. On any failure (or
//! when the [`Outputs`] is dropped without [`Outputs::commit`]) the temporaries are removed and
//! no target is touched, so an existing output is only ever replaced by a complete one.

use anyhow::{anyhow, bail, Result};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// Output format, chosen by the output file's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Glb,
    Gltf,
    Usda,
    /// `.usdc`, and `.usd` (written as crate files, as usd-core does).
    Usdc,
    Usdz,
}

impl Format {
    /// The format for `path`, or an error naming it; the directory must exist.
    pub fn of(path: &Path) -> Result<Format> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or("")
            .to_ascii_lowercase();
        let format = match ext.as_str() {
            "glb" => Format::Glb,
            "gltf" => Format::Gltf,
            "usda" => Format::Usda,
            "usdc" | "usd" => Format::Usdc,
            "usdz" => Format::Usdz,
            _ => bail!(
                "{}: unknown output extension {ext:?} (use .glb, .gltf, .usda, .usdc or .usdz)",
                path.display()
            ),
        };
        folder_exists(path)?;
        Ok(format)
    }
}

/// An error naming `path` unless the folder it lies in exists.
fn folder_exists(path: &Path) -> Result<()> {
    let dir = folder_of(path);
    if !dir.is_dir() {
        bail!(
            "{}: cannot write: directory {} does not exist",
            path.display(),
            dir.display()
        );
    }
    Ok(())
}

/// The folder a path lies in (`.` for a bare file name).
pub fn folder_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// A temporary file beside `path`, named after it, this process and `tag`.
fn temporary(path: &Path, tag: &str) -> PathBuf {
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("out");
    folder_of(path).join(format!(".{name}.{}{tag}.tmp", std::process::id()))
}

fn cannot_write(path: &Path, e: impl std::fmt::Display) -> anyhow::Error {
    anyhow!("{}: cannot write: {e}", path.display())
}

/// The files of one run, staged under temporary names until [`Outputs::commit`].
#[derive(Default)]
pub struct Outputs {
    /// (temporary, target), in the order they were staged (and are renamed).
    staged: Vec<(PathBuf, PathBuf)>,
    /// Scratch files (spools, intermediate layers): removed at the end either way.
    scratch: Vec<PathBuf>,
}

impl Outputs {
    pub fn new() -> Outputs {
        Outputs::default()
    }

    /// Stage `path`, streaming its contents through `fill`.
    pub fn write_with(
        &mut self,
        path: &Path,
        fill: impl FnOnce(&mut BufWriter<File>) -> Result<()>,
    ) -> Result<()> {
        folder_exists(path)?;
        let tmp = temporary(path, "");
        let file = File::create(&tmp).map_err(|e| cannot_write(path, e))?;
        // Registered before it is filled, so that a failure below removes it.
        self.staged.push((tmp, path.to_path_buf()));
        let mut w = BufWriter::with_capacity(1 << 20, file);
        fill(&mut w)?;
        w.flush().map_err(|e| cannot_write(path, e))?;
        Ok(())
    }

    /// Stage `path` with the bytes `data`.
    pub fn write(&mut self, path: &Path, data: &[u8]) -> Result<()> {
        self.write_with(path, |w| {
            w.write_all(data).map_err(|e| cannot_write(path, e))
        })
    }

    /// Stage `path` as a copy of the file `src`.
    pub fn copy(&mut self, src: &Path, path: &Path) -> Result<()> {
        self.write_with(path, |w| {
            let mut f =
                File::open(src).map_err(|e| anyhow!("{}: cannot read: {e}", src.display()))?;
            std::io::copy(&mut f, w).map_err(|e| cannot_write(path, e))?;
            Ok(())
        })
    }

    /// A scratch file beside `path` (tagged `tag`), removed when the run ends either way.
    pub fn scratch(&mut self, path: &Path, tag: &str) -> PathBuf {
        let p = temporary(path, tag);
        self.scratch.push(p.clone());
        p
    }

    /// A scratch file beside `path` (see [`Outputs::scratch`]) filled by `fill`.
    pub fn scratch_with(
        &mut self,
        path: &Path,
        tag: &str,
        fill: impl FnOnce(&mut BufWriter<File>) -> Result<()>,
    ) -> Result<PathBuf> {
        let p = self.scratch(path, tag);
        let file = File::create(&p).map_err(|e| cannot_write(path, e))?;
        let mut w = BufWriter::with_capacity(1 << 20, file);
        fill(&mut w)?;
        w.flush().map_err(|e| cannot_write(path, e))?;
        Ok(p)
    }

    /// Rename every staged file onto its target; on failure nothing more is renamed and the
    /// remaining temporaries are removed.
    pub fn commit(mut self) -> Result<()> {
        let staged = std::mem::take(&mut self.staged);
        for (i, (tmp, path)) in staged.iter().enumerate() {
            if let Err(e) = std::fs::rename(tmp, path) {
                for (t, _) in &staged[i..] {
                    let _ = std::fs::remove_file(t);
                }
                return Err(cannot_write(path, e));
            }
        }
        Ok(())
    }
}

impl Drop for Outputs {
    fn drop(&mut self) {
        for p in self.staged.iter().map(|(t, _)| t).chain(&self.scratch) {
            let _ = std::fs::remove_file(p);
        }
    }
}
