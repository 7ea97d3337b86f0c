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
            // A VRM avatar is a GLB file (its VRM extension passed through).
            "glb" | "vrm" => Format::Glb,
            "gltf" => Format::Gltf,
            "usda" => Format::Usda,
            "usdc" | "usd" => Format::Usdc,
            "usdz" => Format::Usdz,
            _ => bail!(
                "{}: unknown output extension {ext:?} (use .glb, .gltf, .usda, .usdc or .usdz; .vrm is written as the GLB it is)",
                path.display()
            ),
        };
        folder_exists(path)?;
        Ok(format)
    }
}

/// An error where the output `path` is a folder that exists (`-o renders/`), suggesting a file
/// in it named after the `input` (`renders/walk_tween.glb` for `suffix` "_tween.glb"), where
/// the output's missing extension was told instead.
pub fn not_a_folder(path: &Path, input: &Path, suffix: &str) -> Result<()> {
    if path.is_dir() {
        let stem = input
            .file_stem()
            .map_or_else(|| "out".into(), |s| s.to_string_lossy());
        bail!(
            "{}: is a folder: name the file to write in it (e.g. {})",
            path.display(),
            path.join(format!("{stem}{suffix}")).display()
        );
    }
    Ok(())
}

/// An error naming `path` unless the folder it lies in exists.
pub fn folder_exists(path: &Path) -> Result<()> {
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

/// What every temporary file of ours beside `path` starts with: `.<name>.inbetween-`, then
/// the process id, a tag and `.tmp`.
fn temporary_prefix(path: &Path) -> String {
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("out");
    format!(".{name}.inbetween-")
}

/// A temporary file beside `path`, named after it, this process and `tag`.
fn temporary(path: &Path, tag: &str) -> PathBuf {
    folder_of(path).join(format!(
        "{}{}{tag}.tmp",
        temporary_prefix(path),
        std::process::id()
    ))
}

/// Remove the temporary files an earlier run at the same output path left behind when it was
/// killed: ours by name, of a process that no longer runs (on systems without `/proc`, those
/// older than a day).
fn remove_stale(path: &Path) {
    let prefix = temporary_prefix(path);
    let Ok(entries) = std::fs::read_dir(folder_of(path)) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(rest) = name
            .to_str()
            .and_then(|n| n.strip_prefix(&prefix))
            .filter(|n| n.ends_with(".tmp"))
        else {
            continue;
        };
        let digits: String = rest.chars().take_while(char::is_ascii_digit).collect();
        let Ok(pid) = digits.parse::<u32>() else {
            continue;
        };
        let gone = if Path::new("/proc/self").exists() {
            pid != std::process::id() && !Path::new(&format!("/proc/{pid}")).exists()
        } else {
            entry
                .metadata()
                .and_then(|m| m.modified())
                .ok()
                .and_then(|t| t.elapsed().ok())
                .is_some_and(|age| age.as_secs() > 86_400)
        };
        if gone {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

fn cannot_write(path: &Path, e: impl std::fmt::Display) -> anyhow::Error {
    anyhow!("{}: cannot write: {e}", path.display())
}

/// An I/O error while writing `path` (a full disk, say) named with the file; other errors
/// (a failure computing what is written) as they are.
pub fn naming(path: &Path, e: anyhow::Error) -> anyhow::Error {
    match e.root_cause().downcast_ref::<std::io::Error>() {
        Some(io) if e.chain().count() == 1 => cannot_write(path, io),
        _ => e,
    }
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

    /// Stage `path`, streaming its contents through `fill`; returns its size in bytes.
    pub fn write_with(
        &mut self,
        path: &Path,
        fill: impl FnOnce(&mut BufWriter<File>) -> Result<()>,
    ) -> Result<u64> {
        folder_exists(path)?;
        // Two outputs of one run on one file (`-o out.glb --report out.glb`) would overwrite
        // each other's temporary and fail at the rename with an error that names neither.
        let whole = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
        if self.staged.iter().any(|(_, t)| whole(t) == whole(path)) {
            bail!(
                "{}: two of the run's outputs name this file (-o and --report, or --animate)",
                path.display()
            );
        }
        remove_stale(path);
        let tmp = temporary(path, "");
        let file = File::create(&tmp).map_err(|e| cannot_write(path, e))?;
        // Registered before it is filled, so that a failure below removes it.
        self.staged.push((tmp, path.to_path_buf()));
        let mut w = BufWriter::with_capacity(1 << 20, file);
        fill(&mut w).map_err(|e| naming(path, e))?;
        w.flush().map_err(|e| cannot_write(path, e))?;
        w.get_ref()
            .metadata()
            .map(|m| m.len())
            .map_err(|e| cannot_write(path, e))
    }

    /// Stage `path` with the bytes `data`; returns its size in bytes.
    pub fn write(&mut self, path: &Path, data: &[u8]) -> Result<u64> {
        self.write_with(path, |w| {
            w.write_all(data).map_err(|e| cannot_write(path, e))
        })
    }

    /// A scratch file beside `path` (tagged `tag`), removed when the run ends either way.
    pub fn scratch(&mut self, path: &Path, tag: &str) -> PathBuf {
        remove_stale(path);
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
        fill(&mut w).map_err(|e| naming(path, e))?;
        w.flush().map_err(|e| cannot_write(path, e))?;
        Ok(p)
    }

    /// Put every staged file in its target's place. Targets that exist are first moved aside,
    /// and if any rename fails every target is restored as it was, so the run's files appear
    /// together or not at all.
    pub fn commit(mut self) -> Result<()> {
        for (_, path) in &self.staged {
            if path.is_dir() {
                // Dropped on return: the temporaries go with it.
                return Err(cannot_write(path, "a folder is in its place"));
            }
        }
        let staged = std::mem::take(&mut self.staged);
        // (target, where its previous file was moved, whether the new file is in place).
        let mut done: Vec<(&Path, Option<PathBuf>)> = Vec::new();
        let mut failure = None;
        for (tmp, path) in &staged {
            let aside = match path.exists() {
                true => {
                    let aside = temporary(path, ".previous");
                    if let Err(e) = std::fs::rename(path, &aside) {
                        failure = Some(cannot_write(path, e));
                        break;
                    }
                    Some(aside)
                }
                false => None,
            };
            if let Err(e) = std::fs::rename(tmp, path) {
                if let Some(a) = &aside {
                    let _ = std::fs::rename(a, path);
                }
                failure = Some(cannot_write(path, e));
                break;
            }
            done.push((path, aside));
        }
        match failure {
            None => {
                for (_, aside) in done {
                    if let Some(a) = aside {
                        let _ = std::fs::remove_file(a);
                    }
                }
                // The temporaries are all renamed: nothing is left for drop to remove.
                Ok(())
            }
            Some(e) => {
                for (path, aside) in done.into_iter().rev() {
                    match aside {
                        Some(a) => {
                            let _ = std::fs::rename(a, path);
                        }
                        None => {
                            let _ = std::fs::remove_file(path);
                        }
                    }
                }
                for (tmp, _) in &staged {
                    let _ = std::fs::remove_file(tmp);
                }
                Err(e)
            }
        }
    }
}

impl Drop for Outputs {
    fn drop(&mut self) {
        for p in self.staged.iter().map(|(t, _)| t).chain(&self.scratch) {
            let _ = std::fs::remove_file(p);
        }
    }
}
