//! The `tween` command from file to file: read, keyframes, tween, write, summary.

use crate::interpolate::Method;
use crate::keyframes::{find_morph_meshes, KeyOptions, KeySource};
use crate::progress::Progress;
use crate::read::Document;
use crate::tween::{close_loop, collect_mesh, plan, tween_mesh, Timing, TweenOptions};
use crate::usd::{self, MeshPlan};
use crate::write;
use anyhow::Result;
use std::path::PathBuf;
use std::time::Instant;

/// Everything `inbetween tween` was asked to do.
#[derive(Clone, Debug)]
pub struct TweenJob {
    pub input: PathBuf,
    pub output: PathBuf,
    pub method: Method,
    pub keys: KeySource,
    pub animation: Option<String>,
    pub timing: Timing,
    pub quiet: bool,
    /// `Some(true)`: close every track into a loop (`--loop`); `Some(false)`: never wrap
    /// (`--no-loop`); `None`: wrap tracks whose last key equals the first.
    pub looping: Option<bool>,
    /// Seconds to continue the motion before the first key and after the last.
    pub extend: [f64; 2],
    /// Where to write the per-frame quality report (JSON).
    pub report: Option<PathBuf>,
}

/// What was done, for the summary line.
#[derive(Clone, Debug, Default)]
pub struct Summary {
    pub meshes: Vec<crate::tween::MeshStats>,
    pub seconds: f64,
    /// Peak resident memory of the process, MiB (Linux; 0 elsewhere).
    pub peak_rss_mib: f64,
}

impl Summary {
    pub fn line(&self, job: &TweenJob) -> String {
        let frames: usize = self.meshes.iter().map(|m| m.frames).sum();
        let tris: usize = self.meshes.iter().map(|m| m.triangles).sum();
        let keys: usize = self.meshes.iter().map(|m| m.keys).sum();
        let setup: f64 = self.meshes.iter().map(|m| m.setup.as_secs_f64()).sum();
        let solve: f64 = self.meshes.iter().map(|m| m.solve.as_secs_f64()).sum();
        format!(
            "{}: {} mesh{} ({} triangles), {} keys -> {} frames by the {} method; {:.3} s (set-up {:.3} s, frames {:.3} s), peak memory {:.0} MiB",
            job.output.display(),
            self.meshes.len(),
            if self.meshes.len() == 1 { "" } else { "es" },
            tris,
            keys,
            frames,
            job.method.name(),
            self.seconds,
            setup,
            solve,
            self.peak_rss_mib,
        )
    }
}

/// The `--report` file's path and contents, if one was asked for.
fn report_file(
    job: &TweenJob,
    meshes: Vec<crate::report::MeshReport>,
) -> Result<Option<(PathBuf, Vec<u8>)>> {
    let Some(path) = &job.report else {
        return Ok(None);
    };
    let report = crate::report::Report {
        input: job.input.display().to_string(),
        output: job.output.display().to_string(),
        meshes,
    };
    Ok(Some((path.clone(), serde_json::to_vec_pretty(&report)?)))
}

/// Run the tween job. Nothing is written unless every step succeeds (a `.usd*` output is
/// written before its `--report`, whose figures exist only once the frames have streamed).
pub fn run_tween(job: &TweenJob) -> Result<Summary> {
    let started = Instant::now();
    let format = write::format_for(&job.output)?;
    if let Timing::Fps(f) = job.timing {
        anyhow::ensure!(
            f.is_finite() && f > 0.0,
            "--fps must be a positive number (got {f})"
        );
    }
    let doc = Document::open(&job.input)?;
    let meshes = find_morph_meshes(
        &doc,
        &KeyOptions {
            source: job.keys,
            animation: job.animation.as_deref(),
        },
    )?;
    let mut meshes = meshes;
    if job.looping == Some(true) {
        meshes
            .iter_mut()
            .flat_map(|m| m.tracks.iter_mut())
            .for_each(close_loop);
    }
    let opts = TweenOptions {
        method: job.method,
        timing: job.timing,
        report: job.report.is_some(),
        wrap: job.looping != Some(false),
        extend: job.extend,
    };
    let total: usize = meshes
        .iter()
        .flat_map(|m| m.tracks.iter().map(|t| plan(&t.times, &opts).len()))
        .sum();
    let progress = Progress::new(total as u64, "tween", job.quiet);
    let mut stats = Vec::new();
    let mut reports = Vec::new();
    match format {
        write::OutputFormat::Gltf(container) => {
            let mut results = Vec::new();
            for m in &meshes {
                progress.message(m.name.clone());
                results.push(collect_mesh(m, &opts, &|| progress.inc())?);
            }
            progress.finish();
            let mut out = write::begin(&doc, container, &job.output)?;
            write::apply_frames(&mut out, &results)?;
            for r in results {
                stats.push(r.stats);
                reports.extend(r.report);
            }
            let report = report_file(job, std::mem::take(&mut reports))?;
            write::finish_with(out, container, &job.output, report.into_iter().collect())?;
        }
        write::OutputFormat::Usd(usd_format) => {
            let fps = match job.timing {
                Timing::Fps(f) => Some(f),
                Timing::Tweens(_) => None,
            };
            let plans: Vec<MeshPlan> = meshes
                .iter()
                .map(|m| MeshPlan {
                    mesh: m.mesh,
                    tracks: m
                        .tracks
                        .iter()
                        .map(|t| plan(&t.times, &opts).iter().map(|f| f.time).collect())
                        .collect(),
                })
                .collect();
            let stage = usd::build_stage(&doc, &plans, fps)?;
            // Frames stream from the solver to the file, one chunk at a time.
            usd::write_file(&stage, usd_format, &job.output, &mut |sink| {
                for (k, m) in meshes.iter().enumerate() {
                    progress.message(m.name.clone());
                    let done = tween_mesh(m, &opts, &|| progress.inc(), &mut |f, deltas| {
                        sink(k, f, &deltas)
                    })?;
                    stats.push(done.stats);
                    reports.extend(done.report);
                }
                Ok(())
            })?;
            progress.finish();
            // The report is complete only once the frames have streamed into the stage.
            if let Some(file) = report_file(job, reports)? {
                write::atomic_write(&[file])?;
            }
        }
    }
    Ok(Summary {
        meshes: stats,
        seconds: started.elapsed().as_secs_f64(),
        peak_rss_mib: crate::bench::peak_rss_mib(),
    })
}
