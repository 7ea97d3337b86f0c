//! The `tween` command from file to file: read, keyframes, frames, write (glTF morph animation
//! or a USD point cache), summary. Every file of the run is written in one all-or-nothing step.

use super::compact::CompactFigures;
use super::compact::{Basis, CompactOptions, MAX_FACTOR};
use super::frames::{
    collect_mesh, tween_mesh, MeshFrames, MeshStats, PrimitiveDelta, SIDE_BY_SIDE_POSITIONS,
    SIDE_BY_SIDE_TRIANGLES,
};
use super::keys::{
    find_morph_meshes, meshes_without_weights_animation, KeyOptions, KeySource, MorphMesh, Track,
    TrackOrigin,
};
use super::morph_targets::{apply_frames, Applied, MostTargets};
use super::options::{Layout, Method, Timing, TweenOptions};
use super::report::{CompactMesh, CompactReport, MeshReport, Report};
use super::schedule::{close_loop, frame_estimate, plan, MAX_FRAMES};
use super::target_normals;
use super::timegrid::{rate_text, timeline};
use crate::gltf::{self, Access, Container, Document};
use crate::memory::{memory_available, peak_rss_mib};
use crate::output::{Format, Outputs};
use crate::progress::Progress;
use crate::usd::{self, Delta, MeshPlan};
use anyhow::{bail, Result};
use rayon::prelude::*;
use std::collections::{BTreeMap, HashMap};
use std::ops::Range;
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
    /// How a glTF output carries the frames.
    pub layout: Layout,
    /// Compact a glTF output (`--compact` or its parts).
    pub compact: Option<CompactOptions>,
    /// Where external references of a `.gltf` input may lead besides its own folder.
    pub access: Access,
}

/// What was done, for the summary line.
#[derive(Clone, Debug, Default)]
pub struct Summary {
    pub meshes: Vec<MeshStats>,
    pub seconds: f64,
    /// Peak resident memory of the process, MiB (Linux; 0 elsewhere).
    pub peak_rss_mib: f64,
    /// Bytes read (the input and its buffers) and written (the output and its files).
    pub input_bytes: u64,
    pub output_bytes: u64,
    /// The primitive with the most morph targets in a glTF output (mesh, primitive, count).
    pub most_targets: MostTargets,
    /// The figures of each mesh compacted (`--compact` and its parts).
    pub compacted: Vec<(String, CompactFigures)>,
    /// Seconds of set-up by part (see `clock`): symbolic, key gradients and turns, numeric
    /// factorization, spline window.
    pub setup_parts: [f64; 4],
    /// What a user should know of the input or the output, one line each: keys held (STEP)
    /// that were tweened, eases (CUBICSPLINE) that `seed`'s frames hold still through,
    /// what a USD output could not carry (textures USD cannot read).
    pub warnings: Vec<String>,
    /// The compression extensions the input was decoded from (its size is the compressed one).
    pub input_compressed: Vec<String>,
}

/// Morph targets some engines blend at once (what glTF asks every client to support, and
/// three.js on WebGL1): a compacted mesh playing more is warned of.
pub const ACTIVE_TARGETS: usize = 8;

/// Output growth over the input above which the summary warns.
pub const GROWTH_WARNING: f64 = 10.0;

/// Morph targets per primitive above which web viewers stop animating: three.js packs one
/// texture-array layer per target, and WebGL2 guarantees 2,048 layers (MAX_ARRAY_TEXTURE_LAYERS
/// in headless Chromium, three.js 0.187): beyond them the mesh stays in its rest pose.
pub const WEB_TARGET_LIMIT: usize = 2048;

/// A size in bytes, in the unit that reads best.
fn size(bytes: u64) -> String {
    match bytes {
        b if b < 10 << 10 => format!("{b} B"),
        b if b < 10 << 20 => format!("{:.0} KB", b as f64 / 1024.0),
        b => format!("{:.1} MB", b as f64 / 1048576.0),
    }
}

impl Summary {
    /// The summary line, and a warning line for each thing a user should know.
    pub fn line(&self, job: &TweenJob) -> String {
        let frames: usize = self.meshes.iter().map(|m| m.frames).sum();
        let tris: usize = self.meshes.iter().map(|m| m.triangles).sum();
        let keys: usize = self.meshes.iter().map(|m| m.keys).sum();
        let setup: f64 = self.meshes.iter().map(|m| m.setup.as_secs_f64()).sum();
        let solve: f64 = self.meshes.iter().map(|m| m.solve.as_secs_f64()).sum();
        let timing = match job.timing {
            Timing::Rate(r) => format!("every key kept, {} frames/s between keys", rate_text(r)),
            Timing::Tweens(n) => format!("{n} between each pair of keys"),
            Timing::Fps(f) => format!("{} frames/s over the keys' span", rate_text(f)),
        };
        let growth = self.output_bytes as f64 / self.input_bytes.max(1) as f64;
        let mut out = format!(
            "{}: {} mesh{} ({} triangles), {} keys -> {} frames ({timing}) by the {} method; {} -> {} ({growth:.1}x); {:.3} s (set-up {:.3} s{}, frames {:.3} s{}), peak memory {:.0} MiB",
            job.output.display(),
            self.meshes.len(),
            if self.meshes.len() == 1 { "" } else { "es" },
            tris,
            keys,
            frames,
            job.method.name(),
            size(self.input_bytes),
            size(self.output_bytes),
            self.seconds,
            setup,
            match self.setup_parts.iter().any(|&x| x > 0.0) {
                true => format!(
                    " [{}]",
                    (super::clock::NAMES.iter().zip(self.setup_parts))
                        .map(|(n, x)| format!("{n} {x:.3}"))
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
                false => String::new(),
            },
            solve,
            match self.meshes.iter().any(|m| m.side_by_side) {
                true => ", summed over the threads that ran side by side",
                false => "",
            },
            self.peak_rss_mib,
        );
        for (mesh, c) in &self.compacted {
            out += &format!(
                "\n{mesh:?} compacted: {} basis target{}{}, deviation from the dense frames {:.2e} RMS, {:.2e} max (of the diagonal){}",
                c.basis,
                if c.basis == 1 { "" } else { "s" },
                if c.authored > 0 { format!(" beside {} authored", c.authored) } else { String::new() },
                c.rms_deviation,
                c.max_deviation,
                if c.normal_rms_deviation > 0.0 { format!(", normals {:.2e} RMS", c.normal_rms_deviation) } else { String::new() },
            );
            // A capped basis (--basis N) keeps fewer directions than the tolerance asks for.
            if let Some(opts) = (job.compact.as_ref()).filter(|o| {
                c.rms_deviation > o.tolerance || c.max_deviation > MAX_FACTOR * o.tolerance
            }) {
                let why = match opts.basis {
                    Basis::Count(k) => format!(
                        ": --basis {k} caps the basis below what it asks for (--basis auto keeps the frames within it)"
                    ),
                    _ => String::new(),
                };
                out += &format!(
                    "\nwarning: {mesh:?}'s frames are {:.2e} RMS ({:.2e} at a vertex) from the dense ones, beyond --tolerance {:.0e}{why}",
                    c.rms_deviation, c.max_deviation, opts.tolerance
                );
            }
            if c.basis + c.authored > ACTIVE_TARGETS {
                out += &format!(
                    "\nwarning: {mesh:?} plays {} targets at once; some engines blend at most {ACTIVE_TARGETS} (the glTF minimum, three.js on WebGL1): --basis N caps the basis",
                    c.basis + c.authored
                );
            }
        }
        for what in &self.warnings {
            out += &format!("\nwarning: {what}");
        }
        if growth > GROWTH_WARNING {
            // A compressed input against an uncompressed glTF output: most of the growth may
            // be the compression undone (MorphStressTest through glTF-Transform optimize:
            // 10.3x, 2.9x with --meshopt).
            let gltf_out = matches!(Format::of(&job.output), Ok(Format::Glb | Format::Gltf));
            let compressed = job.compact.as_ref().is_some_and(|c| c.meshopt);
            let undone = match (self.input_compressed.is_empty(), gltf_out && !compressed) {
                (false, true) => format!(
                    " (the input is compressed by {}, the output is not: --meshopt compresses it)",
                    self.input_compressed.join(" and ")
                ),
                _ => String::new(),
            };
            out += &format!(
                "\nwarning: the output is {growth:.1}x the size of the input{undone}: --rate, --tweens or --fps set how many frames are written"
            );
        }
        if let Some((mesh, prim, n)) = self
            .most_targets
            .as_ref()
            .filter(|m| m.2 > WEB_TARGET_LIMIT)
        {
            out += &format!(
                "\nwarning: mesh {mesh:?} primitive {prim} has {n} morph targets; web viewers (three.js) animate at most {WEB_TARGET_LIMIT} and show the rest pose beyond: write fewer frames (--rate, --tweens, --fps)"
            );
        }
        out
    }
}

/// `meshes` in runs tweened together: consecutive meshes whose frames together hold at most
/// [`SIDE_BY_SIDE_POSITIONS`] and whose set-ups together at most [`SIDE_BY_SIDE_TRIANGLES`]
/// triangles; a mesh holding more is a run of its own. Several small meshes (a scene's props,
/// a crowd's faces) are each set up and solved on a thread of their own, where a mesh at a
/// time spread its few triangles over every thread, and the threads spent longer handing the
/// work over than doing it (3,000 meshes of 8 triangles, 2 threads: 2.9 s, 2.1 s of it in
/// the kernel, against 1.5 s and 0.2 s side by side). A larger mesh is tweened alone, on every
/// thread, its frames streamed.
pub fn side_by_side(meshes: &[MorphMesh], opts: &TweenOptions) -> Vec<Range<usize>> {
    let held = |m: &MorphMesh| {
        let frames: f64 = m
            .tracks
            .iter()
            .map(|t| frame_estimate(&t.times, opts))
            .sum();
        let triangles: usize = m.primitives.iter().map(|p| p.triangles.len()).sum();
        (m.vertex_count() as f64 * frames, triangles)
    };
    let mut runs = Vec::new();
    let (mut start, mut positions, mut triangles) = (0, 0.0, 0);
    for (i, m) in meshes.iter().enumerate() {
        let (p, t) = held(m);
        if i > start
            && (positions + p > SIDE_BY_SIDE_POSITIONS as f64
                || triangles + t > SIDE_BY_SIDE_TRIANGLES)
        {
            runs.push(start..i);
            (start, positions, triangles) = (i, 0.0, 0);
        }
        positions += p;
        triangles += t;
    }
    if start < meshes.len() {
        runs.push(start..meshes.len());
    }
    runs
}

/// The progress bar's name for a run of meshes: the mesh's, or how many.
fn run_name(meshes: &[MorphMesh]) -> String {
    match meshes {
        [m] => m.name.clone(),
        _ => format!("{} meshes side by side", meshes.len()),
    }
}

/// The run in progress: its input, meshes, options and what has been measured.
struct Run<'a> {
    job: &'a TweenJob,
    doc: Document,
    meshes: Vec<MorphMesh>,
    opts: TweenOptions,
    progress: Progress,
    stats: Vec<MeshStats>,
    reports: Vec<MeshReport>,
    output_bytes: u64,
    applied: Applied,
    warnings: Vec<String>,
}

impl Run<'_> {
    /// Stage the `--report` file, if one was asked for.
    fn stage_report(&mut self, files: &mut Outputs) -> Result<()> {
        let Some(path) = &self.job.report else {
            return Ok(());
        };
        let compact = self
            .opts
            .compact
            .filter(|_| !self.applied.compacted.is_empty())
            .map(|c| CompactReport {
                output_bytes: self.output_bytes,
                tolerance: c.tolerance,
                meshes: (self.applied.compacted.iter())
                    .map(|(mesh, figures)| CompactMesh {
                        mesh: mesh.clone(),
                        figures: figures.clone(),
                    })
                    .collect(),
            });
        let report = Report {
            input: self.job.input.display().to_string(),
            output: self.job.output.display().to_string(),
            meshes: std::mem::take(&mut self.reports),
            compact,
        };
        files.write(path, &serde_json::to_vec_pretty(&report)?)?;
        Ok(())
    }

    /// Every mesh's frames collected, then written as morph targets into the glTF output.
    fn gltf(&mut self, container: Container, files: &mut Outputs) -> Result<()> {
        let mut results = Vec::new();
        for run in side_by_side(&self.meshes, &self.opts) {
            let meshes = &self.meshes[run];
            self.progress.message(run_name(meshes));
            let inc = || self.progress.inc();
            let done: Vec<Result<MeshFrames>> = match meshes {
                [m] => vec![collect_mesh(m, &self.opts, &inc)],
                _ => (meshes.par_iter())
                    .map(|m| collect_mesh(m, &self.opts, &inc))
                    .collect(),
            };
            // The computation's own failures (the solve, the factorization) name the input.
            for d in done {
                let mut d = d.map_err(|e| self.doc.err(format!("{e:#}")))?;
                d.stats.side_by_side |= meshes.len() > 1;
                results.push(d);
            }
        }
        self.progress.finish();
        let mut out = gltf::begin(&self.doc, container, &self.job.output)?;
        let input = self.doc.path.display();
        (self.warnings).extend(
            (out.unread_images.iter().chain(&out.mended)).map(|what| format!("{input}: {what}")),
        );
        self.applied = apply_frames(
            &mut out,
            &self.doc,
            &results,
            &self.meshes,
            self.opts.layout,
            self.opts.compact.as_ref(),
            self.job.looping == Some(true),
        )?;
        for r in results {
            self.stats.push(r.stats);
            self.reports.extend(r.report);
        }
        self.output_bytes = gltf::stage(out, container, &self.job.output, files)?;
        Ok(())
    }

    /// The frames streamed from the solver into a USD point cache, one chunk at a time.
    fn usd(&mut self, format: Format, files: &mut Outputs) -> Result<()> {
        let fallback = match self.opts.timing {
            Timing::Fps(r) | Timing::Rate(r) => Some(r),
            Timing::Tweens(_) => None,
        };
        let times: Vec<Vec<Vec<f64>>> = self
            .meshes
            .iter()
            .map(|m| {
                m.tracks
                    .iter()
                    .map(|t| plan(&t.times, &self.opts).iter().map(|f| f.time).collect())
                    .collect()
            })
            .collect();
        let clip_of = |t: &Track| match t.origin {
            TrackOrigin::Animation { animation, .. } => Some(animation),
            TrackOrigin::Targets { .. } => None,
        };
        let clip_ids: Vec<Vec<Option<usize>>> = (self.meshes.iter())
            .map(|m| m.tracks.iter().map(clip_of).collect())
            .collect();
        let (rate, codes) = timeline(&times, &clip_ids, fallback);
        // Each clip whose frames the stage plays: its node motion is sampled at every code
        // its frames have (one place on the timeline, whichever meshes' tracks it drives).
        let mut clips: Vec<usd::ClipOnStage> = Vec::new();
        for ((m, times), codes) in self.meshes.iter().zip(&times).zip(&codes) {
            let mut at = 0;
            for (track, times) in m.tracks.iter().zip(times) {
                let codes = &codes[at..at + times.len()];
                at += times.len();
                let (Some(animation), false) = (clip_of(track), times.is_empty()) else {
                    continue;
                };
                match clips.iter_mut().find(|c| c.animation == animation) {
                    Some(c) => {
                        c.codes.extend_from_slice(codes);
                        c.codes.sort_by(f64::total_cmp);
                        c.codes.dedup();
                    }
                    None => clips.push(usd::ClipOnStage {
                        animation,
                        codes: codes.to_vec(),
                        offset: codes[0] - times[0] * rate,
                        loop_end: (self.job.looping == Some(true)).then(|| times[times.len() - 1]),
                    }),
                }
            }
        }
        let carriers = gltf::mesh_nodes(&self.doc.json);
        let plans: Vec<MeshPlan> = (self.meshes.iter().zip(&times).zip(codes))
            .map(|((m, times), codes)| MeshPlan {
                mesh: m.mesh,
                codes,
                played: played_by_node(
                    &self.doc.json,
                    m,
                    carriers.get(m.mesh).map_or(&[], Vec::as_slice),
                    times,
                ),
            })
            .collect();
        // Texture files beside the layer are named after it: `<stem>_<image>.png`.
        let stem = (self.job.output.file_stem())
            .and_then(|s| s.to_str())
            .unwrap_or("stage");
        let stage = usd::build_stage(&self.doc, &plans, clips, rate, &format!("{stem}_"))?;
        let input = self.doc.path.display();
        (self.warnings).extend((stage.look.left_out.iter()).map(|what| format!("{input}: {what}")));
        // A point cache animates points and normals; attributes the targets also move keep
        // the base's values.
        for m in &self.meshes {
            let names: std::collections::BTreeSet<&str> = (m.primitives.iter())
                .flat_map(|p| p.target_other.iter().map(|o| o.name.as_str()))
                .collect();
            if !names.is_empty() {
                let names: Vec<&str> = names.into_iter().collect();
                self.warnings.push(format!(
                    "{input}: mesh {:?} morphs {} too; a USD point cache animates points and normals only, so they keep the base's values (a glTF output plays them)",
                    m.name,
                    names.join(", ")
                ));
            }
        }
        let (meshes, opts, progress, doc) = (&self.meshes, &self.opts, &self.progress, &self.doc);
        let (stats, reports) = (&mut self.stats, &mut self.reports);
        self.output_bytes = usd::write_file(
            &stage,
            format,
            &self.job.output,
            &mut |sink| {
                for run in side_by_side(meshes, opts) {
                    progress.message(run_name(&meshes[run.clone()]));
                    let inc = || progress.inc();
                    // The computation's own failures name the input; the writer's name the
                    // file it could not write.
                    if let [m] = &meshes[run.clone()] {
                        let k = run.start;
                        let mut writing = false;
                        let done = tween_mesh(m, opts, true, &inc, &mut |f, deltas| {
                            sink(k, f, &usd_deltas(&deltas)).inspect_err(|_| writing = true)
                        })
                        .map_err(|e| {
                            if writing {
                                e
                            } else {
                                doc.err(format!("{e:#}"))
                            }
                        })?;
                        stats.push(done.stats);
                        reports.extend(done.report);
                        continue;
                    }
                    // Small meshes side by side, each one's frames held until its turn.
                    type Held = (MeshFrames, Vec<(usize, Vec<PrimitiveDelta>)>);
                    let done: Vec<Result<Held>> = (meshes[run.clone()].par_iter())
                        .map(|m| {
                            let mut frames = Vec::new();
                            let done = tween_mesh(m, opts, true, &inc, &mut |f, deltas| {
                                frames.push((f, deltas));
                                Ok(())
                            })?;
                            Ok((done, frames))
                        })
                        .collect();
                    for (k, done) in run.zip(done) {
                        let (done, frames) = done.map_err(|e| doc.err(format!("{e:#}")))?;
                        for (f, deltas) in frames {
                            sink(k, f, &usd_deltas(&deltas))?;
                        }
                        stats.push(MeshStats {
                            side_by_side: true,
                            ..done.stats
                        });
                        reports.extend(done.report);
                    }
                }
                Ok(())
            },
            files,
        )?;
        progress.finish();
        Ok(())
    }
}

/// The frames each of `carriers` (the nodes carrying mesh `m`) plays in a USD stage (its
/// tracks' frames, `times` per track, in order): those of the tracks whose channels drive it;
/// `None` when every node plays every frame (one node, or every track driving every node).
fn played_by_node(
    json: &serde_json::Value,
    m: &MorphMesh,
    carriers: &[usize],
    times: &[Vec<f64>],
) -> Option<HashMap<usize, Vec<usize>>> {
    let mut played: HashMap<usize, Vec<usize>> = HashMap::new();
    let mut first = 0;
    for (track, times) in m.tracks.iter().zip(times) {
        let driven: Vec<usize> = match &track.origin {
            TrackOrigin::Targets { nodes } => nodes.clone(),
            TrackOrigin::Animation {
                animation,
                channels,
                ..
            } => channels
                .iter()
                .flat_map(|&c| {
                    match gltf::weights_target(
                        &json["animations"][*animation]["channels"][c]["target"],
                    ) {
                        Some(gltf::WeightsTarget::Node(n)) => vec![n],
                        Some(gltf::WeightsTarget::Mesh(_)) => carriers.to_vec(),
                        None => Vec::new(),
                    }
                })
                .collect(),
        };
        for n in driven {
            played
                .entry(n)
                .or_default()
                .extend(first..first + times.len());
        }
        first += times.len();
    }
    for frames in played.values_mut() {
        frames.sort_unstable();
        frames.dedup();
    }
    let every = |n: &usize| played.get(n).is_some_and(|f| f.len() == first);
    (!carriers.iter().all(every)).then_some(played)
}

/// A frame's deltas as the USD writer takes them.
fn usd_deltas(deltas: &[PrimitiveDelta]) -> Vec<Delta<'_>> {
    deltas
        .iter()
        .map(|d| Delta {
            positions: &d.positions,
            normals: d.normals.as_deref(),
        })
        .collect()
}

/// Refuse, before any work, a job whose tracks would have more than [`MAX_FRAMES`] frames or
/// whose glTF output (every frame held until it is written) would not fit in memory: the
/// frames' vertex data, and the weights animations, each track one weight per target for each
/// of its frames while the mesh takes a target for every frame of every track (a mesh that
/// 2,000 clips animate: 122,000 targets, 122,000 keys of that many weights: about 170 GiB).
/// In the rig layout uncompacted a frame on a key holds no vertex data and takes no target (a
/// face rig baked at 60 keys/s and written as it is needs its weights only). Returns how many
/// frames the job has.
fn check_budget(
    doc: &Document,
    meshes: &[MorphMesh],
    opts: &TweenOptions,
    held: bool,
) -> Result<usize> {
    for m in meshes {
        for (k, t) in m.tracks.iter().enumerate() {
            let frames = frame_estimate(&t.times, opts);
            if frames > MAX_FRAMES {
                bail!(doc.err(format!(
                    "track {k} of mesh {:?} would have about {frames:.3e} frames (keys from {} s to {} s), more than {MAX_FRAMES}; ask for fewer with --fps or --tweens",
                    m.name,
                    t.times.first().copied().unwrap_or(0.0),
                    t.times.last().copied().unwrap_or(0.0)
                )));
            }
        }
    }
    let key_deltas = opts.gltf_reads_keys();
    let (mut bytes, mut total) = (0.0, 0);
    for m in meshes {
        let (mut frames, mut between) = (0.0, 0.0);
        for t in &m.tracks {
            let planned = plan(&t.times, opts);
            total += planned.len();
            frames += planned.len() as f64;
            between += planned.iter().filter(|f| f.key().is_none()).count() as f64;
        }
        // At most one new target a frame; a compacted basis no more than the frames' rank.
        let normals = m.primitives.iter().all(|p| p.normals.is_some());
        let tangents = normals && m.primitives.iter().all(|p| p.tangents.is_some());
        let attributes = 1.0 + normals as u8 as f64 + tangents as u8 as f64;
        let new = match (opts.compact, opts.layout) {
            (Some(_), _) => frames.min(3.0 * attributes * m.vertex_count() as f64),
            (None, Layout::Rig) => between,
            (None, Layout::Frames) => frames,
        };
        // f32 weights, built, packed and copied into the buffer.
        bytes += 3.0 * 4.0 * frames * (m.target_count as f64 + new);
        // The frames as computed and again in the output buffer.
        let computed = if key_deltas { frames } else { between };
        bytes += 2.0 * computed * m.vertex_count() as f64 * 12.0 * attributes;
    }
    let available = memory_available();
    if let Some(available) = available.filter(|&a| held && bytes > a as f64) {
        bail!(doc.err(format!(
            "its frames and their weights need about {:.1} GiB in memory for a glTF output, more than the {:.1} GiB available; write fewer frames (--fps, --tweens), one clip at a time (--animation), {}or a USD point cache (.usdc streams its frames)",
            bytes / GIB,
            available as f64 / GIB,
            if opts.compact.is_none() { "--compact (a basis of few targets), " } else { "" }
        )));
    }
    Ok(total)
}

const GIB: f64 = (1u64 << 30) as f64;

/// Run the tween job. Nothing is written unless every step succeeds.
pub fn run_tween(job: &TweenJob) -> Result<Summary> {
    let started = Instant::now();
    crate::output::not_a_folder(&job.output, &job.input, "_tween.glb")?;
    let format = Format::of(&job.output)?;
    job.timing.check(job.extend)?;
    let doc = Document::open_with(&job.input, &job.access)?;
    let mut meshes = find_morph_meshes(
        &doc,
        &KeyOptions {
            source: job.keys,
            animation: job.animation.as_deref(),
        },
    )?;
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
        layout: job.layout,
        compact: job.compact,
    };
    let total = check_budget(&doc, &meshes, &opts, Container::of(format).is_some())?;
    let mut warnings = between_keys(&doc, &meshes, &opts);
    warnings.extend(left_as_authored(&doc, &meshes, job.keys));
    if let (Some(_), Layout::Rig) = (Container::of(format), opts.layout) {
        warnings.extend(shape_normals(&doc, &mut meshes, &opts));
    }
    let mut run = Run {
        job,
        doc,
        meshes,
        opts,
        progress: Progress::new(total as u64, "tween", job.quiet),
        stats: Vec::new(),
        reports: Vec::new(),
        output_bytes: 0,
        applied: Applied::default(),
        warnings,
    };
    let mut files = Outputs::new();
    match Container::of(format) {
        Some(container) => run.gltf(container, &mut files)?,
        None => run.usd(format, &mut files)?,
    }
    run.stage_report(&mut files)?;
    files.commit()?;
    Ok(Summary {
        meshes: run.stats,
        seconds: started.elapsed().as_secs_f64(),
        peak_rss_mib: peak_rss_mib(),
        input_bytes: run.doc.input_bytes,
        output_bytes: run.output_bytes,
        most_targets: run.applied.most_targets,
        compacted: run.applied.compacted,
        setup_parts: super::clock::seconds(),
        warnings: run.warnings,
        input_compressed: run.doc.decoded.clone(),
    })
}

/// Position-only targets given the NORMAL deltas of their shapes ([`target_normals`]), so
/// that the keys of the glTF rig layout (played by their authored weights) shade as the frames
/// between them; a line saying so, as the output's authored targets then differ from the
/// input's. Not for a mesh with no frame between keys (a rig baked at the output's rate goes
/// out as it came in).
fn shape_normals(doc: &Document, meshes: &mut [MorphMesh], opts: &TweenOptions) -> Option<String> {
    meshes.par_iter_mut().for_each(|m| {
        if (m.tracks.iter()).any(|t| plan(&t.times, opts).iter().any(|f| f.key().is_none())) {
            target_normals::derive(m);
        }
    });
    let names: Vec<String> = (meshes.iter())
        .filter(|m| m.normals_given > 0)
        .map(|m| format!("{:?}", m.name))
        .collect();
    let total: usize = meshes.iter().map(|m| m.normals_given).sum();
    (total > 0).then(|| {
        format!(
            "{}: {total} morph target{} of {} carr{} no NORMAL deltas: given those of {} shape{}, so that keys shade as the frames between them (the positions as authored)",
            doc.path.display(),
            if total == 1 { "" } else { "s" },
            gltf::listed(&names),
            if total == 1 { "ies" } else { "y" },
            if total == 1 { "its" } else { "their" },
            if total == 1 { "" } else { "s" },
        )
    })
}

/// A line naming the morph meshes `--keys auto` left as authored: in a file that animates
/// some meshes' weights, those with no weights animation keep their pose.
fn left_as_authored(doc: &Document, meshes: &[MorphMesh], keys: KeySource) -> Vec<String> {
    let from_clips = (meshes.iter().flat_map(|m| &m.tracks))
        .any(|t| matches!(t.origin, TrackOrigin::Animation { .. }));
    if keys != KeySource::Auto || !from_clips {
        return Vec::new();
    }
    let names: Vec<String> = meshes_without_weights_animation(doc)
        .into_iter()
        .map(|mi| gltf::quoted_name(&doc.json["meshes"][mi], || format!("mesh {mi}")))
        .collect();
    if names.is_empty() {
        return Vec::new();
    }
    vec![format!(
        "{}: {} {} morph targets and no weights animation: left as authored (--keys targets tweens every mesh's targets)",
        doc.path.display(),
        gltf::listed(&names),
        if names.len() == 1 { "has" } else { "have" }
    )]
}

/// A line for each clip whose motion between keys the output's frames do not follow: a clip
/// that holds each key until the next (STEP interpolation, as exporters write stepped or
/// "constant" keys: an animator's blocking pass) is tweened as poses like any other, so the
/// output moves where the input held; a clip whose keys carry CUBICSPLINE tangents (eases in
/// and out) is followed by every method (see `segment::Eases`), but `seed` takes its path
/// between two keys at the eases' pace, so between keys of the same weights that the eases
/// leave and come back to it holds still (said only where it writes frames there).
fn between_keys(doc: &Document, meshes: &[MorphMesh], opts: &TweenOptions) -> Vec<String> {
    let interpolation =
        |a: usize, s: usize| doc.json["animations"][a]["samplers"][s]["interpolation"].as_str();
    let clips: BTreeMap<usize, &str> = (meshes.iter().flat_map(|m| &m.tracks))
        .filter_map(|t| match t.origin {
            TrackOrigin::Animation {
                animation, sampler, ..
            } => Some((animation, sampler, t)),
            TrackOrigin::Targets { .. } => None,
        })
        .filter_map(|(a, s, t)| match interpolation(a, s) {
            Some("STEP") => Some((a, "STEP")),
            Some("CUBICSPLINE")
                if opts.method == Method::Seed
                    && (plan(&t.times, opts).iter())
                        .any(|f| f.key().is_none() && still_between(t, f.key_a, f.key_b)) =>
            {
                Some((a, "CUBICSPLINE"))
            }
            _ => None,
        })
        .collect();
    clips
        .into_iter()
        .map(|(a, interpolation)| {
            let name = gltf::quoted_name(&doc.json["animations"][a], || a.to_string());
            let path = doc.path.display();
            match interpolation {
                "STEP" => format!(
                    "{path}: animation {name} holds its weights from key to key (STEP interpolation); its keys are tweened as poses, so the output moves between them"
                ),
                _ => format!(
                    "{path}: animation {name} eases its weights away from and back to keys of the same weights (CUBICSPLINE tangents); the seed method's frames hold still between such keys (spline and linear follow the eases)"
                ),
            }
        })
        .collect()
}

/// Whether `track` eases away from key a and back into key b (a + 1) where the two keys have
/// the same weights: a motion the seed's path, a key's pose to the other's, cannot follow.
fn still_between(track: &Track, a: usize, b: usize) -> bool {
    let Some(eases) = &track.eases else {
        return false;
    };
    let moving = |m: &[f64]| m.iter().any(|&m| m != 0.0);
    track.eased(a, b)
        && track.weights[a] == track.weights[b]
        && (moving(&eases[a][1]) || moving(&eases[b][0]))
}
