//! The `tween` job: keyframes -> weld -> interpolate/solve -> per-frame deltas for the writer.

use crate::interpolate::{Method, Segment};
use crate::keyframes::{MorphMesh, Track, TrackOrigin};
use crate::normals::{arc, carry, Smoothing};
use crate::report::{FrameReport, MeshReport, Shape};
use crate::solve::Pattern;
use crate::weld::Welded;
use anyhow::Result;
use glam::DVec3;
use rayon::prelude::*;
use std::time::{Duration, Instant};

/// How output frames are placed in time.
#[derive(Clone, Copy, Debug)]
pub enum Timing {
    /// N frames inserted evenly between each pair of consecutive keys.
    Tweens(usize),
    /// Frames at a fixed rate (per second) over the keys' time span.
    Fps(f64),
}

/// One output frame of a track: the time and where it falls between keys.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameAt {
    pub time: f64,
    /// The segment's start and end keys (equal for a track with a single key time).
    pub key_a: usize,
    pub key_b: usize,
    /// Position within the segment, 0 at `key_a`, 1 at `key_b`.
    pub t: f64,
}

/// Frame times for keys at `times` (non-decreasing).
pub fn schedule(times: &[f64], timing: Timing) -> Vec<FrameAt> {
    // Segments of positive duration, in order.
    let segments: Vec<(usize, usize)> = (0..times.len().saturating_sub(1))
        .filter(|&k| times[k + 1] > times[k])
        .map(|k| (k, k + 1))
        .collect();
    let Some(&(_, last_b)) = segments.last() else {
        return vec![FrameAt {
            time: times[0],
            key_a: 0,
            key_b: 0,
            t: 0.0,
        }];
    };
    let mut out = Vec::new();
    match timing {
        Timing::Tweens(n) => {
            for &(a, b) in &segments {
                for j in 0..=n {
                    let t = j as f64 / (n + 1) as f64;
                    out.push(FrameAt {
                        time: times[a] + (times[b] - times[a]) * t,
                        key_a: a,
                        key_b: b,
                        t,
                    });
                }
            }
            let (a, b) = segments[segments.len() - 1];
            out.push(FrameAt {
                time: times[last_b],
                key_a: a,
                key_b: b,
                t: 1.0,
            });
        }
        Timing::Fps(fps) => {
            let start = times[segments[0].0];
            let span = times[last_b] - start;
            let count = (span * fps + 1e-9).floor() as usize;
            let mut seg = 0;
            for i in 0..=count {
                let time = start + i as f64 / fps;
                while seg + 1 < segments.len() && time >= times[segments[seg].1] {
                    seg += 1;
                }
                let (a, b) = segments[seg];
                let t = ((time - times[a]) / (times[b] - times[a])).min(1.0);
                out.push(FrameAt {
                    time,
                    key_a: a,
                    key_b: b,
                    t,
                });
            }
        }
    }
    out
}

/// Options of the tween job.
#[derive(Clone, Copy, Debug)]
pub struct TweenOptions {
    pub method: Method,
    pub timing: Timing,
    /// Measure every frame for `--report`.
    pub report: bool,
    /// Let `spline` wrap around tracks whose last key equals the first (`--no-loop` clears it).
    pub wrap: bool,
    /// Seconds of motion continued before the first key and after the last
    /// (`--extend-before`, `--extend-after`).
    pub extend: [f64; 2],
}

impl TweenOptions {
    /// Options with every default: no report, wrapping on, no extension.
    pub fn new(method: Method, timing: Timing) -> TweenOptions {
        TweenOptions {
            method,
            timing,
            report: false,
            wrap: true,
            extend: [0.0, 0.0],
        }
    }
}

/// Frames of a track with keys at `times`: [`schedule`] plus the extensions of `opts`, which
/// continue the first and last segments' motion (t < 0 before the first key, t > 1 after the
/// last) at the frame spacing next to them.
pub fn plan(times: &[f64], opts: &TweenOptions) -> Vec<FrameAt> {
    let mut frames = schedule(times, opts.timing);
    let [before, after] = opts.extend;
    if frames.len() < 2 {
        return frames;
    }
    let span = |f: &FrameAt| times[f.key_b] - times[f.key_a];
    // `seconds` more of the segment of `from`, at `spacing` (negative: backwards in time),
    // nearest to `from` first.
    let continued = |from: FrameAt, spacing: f64, seconds: f64| -> Vec<FrameAt> {
        let n = (seconds.max(0.0) / spacing.abs() + 1e-9).floor() as usize;
        (1..=n)
            .map(|k| {
                let time = from.time + k as f64 * spacing;
                FrameAt {
                    time,
                    key_a: from.key_a,
                    key_b: from.key_b,
                    t: (time - times[from.key_a]) / span(&from),
                }
            })
            .collect()
    };
    let spacing = frames[1].time - frames[0].time;
    if spacing > 0.0 {
        let mut ext = continued(frames[0], -spacing, before);
        ext.reverse();
        frames.splice(0..0, ext);
    }
    let last = frames[frames.len() - 1];
    let spacing = last.time - frames[frames.len() - 2].time;
    if spacing > 0.0 {
        frames.extend(continued(last, spacing, after));
    }
    frames
}

/// Close a track into a loop (`--loop`): unless its last key already equals its first, append
/// the first key again, one mean key spacing after the last.
pub fn close_loop(track: &mut Track) {
    let (k, times) = (track.times.len(), &track.times);
    if k < 2 || track.weights[k - 1] == track.weights[0] {
        return;
    }
    let spacing = (times[k - 1] - times[0]) / (k - 1) as f64;
    let spacing = if spacing > 0.0 { spacing } else { 1.0 };
    track.times.push(times[k - 1] + spacing);
    track.weights.push(track.weights[0].clone());
}

/// Output of one track: its frames occupy `first..first + frames.len()` of the mesh's targets.
pub struct TrackFrames {
    pub origin: TrackOrigin,
    pub first: usize,
    pub frames: Vec<FrameAt>,
}

/// Per-primitive morph target deltas, one entry per output frame.
pub struct PrimitiveFrames {
    pub index: usize,
    pub positions: Vec<Vec<[f32; 3]>>,
    pub normals: Option<Vec<Vec<[f32; 3]>>>,
    pub tangents: Option<Vec<Vec<[f32; 3]>>>,
}

/// Everything the writer needs for one processed mesh.
pub struct MeshFrames {
    pub mesh: usize,
    pub name: String,
    pub tracks: Vec<TrackFrames>,
    pub primitives: Vec<PrimitiveFrames>,
    pub dropped_channels: Vec<(usize, usize)>,
    pub stats: MeshStats,
    /// Per-frame figures, when asked for.
    pub report: Option<MeshReport>,
}

#[derive(Clone, Debug, Default)]
pub struct MeshStats {
    pub triangles: usize,
    pub keys: usize,
    pub frames: usize,
    pub setup: Duration,
    pub solve: Duration,
}

impl MeshFrames {
    pub fn frame_count(&self) -> usize {
        self.stats.frames
    }
}

/// Key poses of a track, in input vertex order.
pub fn key_poses(mesh: &MorphMesh, track: &Track) -> Vec<Vec<DVec3>> {
    track.weights.iter().map(|w| mesh.pose(w)).collect()
}

/// Normals data of a mesh for one track, when every primitive has NORMAL.
struct NormalKeys {
    smoothing: Smoothing,
    recomputed: Vec<Vec<DVec3>>,
    authored: Vec<Vec<DVec3>>,
}

/// Compute every frame of every track of `mesh` and hand each to `sink` in order (frame index,
/// per-primitive deltas), so a writer can stream them. Frames are computed in parallel in
/// chunks of a few per thread, so at most one chunk is held at a time. `progress` is called
/// once per frame done. The returned [`MeshFrames`] holds the tracks and figures but no
/// frame data (see [`collect_mesh`] for a mesh with all of its frames).
pub fn tween_mesh(
    mesh: &MorphMesh,
    opts: &TweenOptions,
    progress: &(dyn Fn() + Sync),
    sink: &mut dyn FnMut(usize, Vec<PrimitiveDelta>) -> Result<()>,
) -> Result<MeshFrames> {
    let welded = Welded::build(mesh);
    let mut stats = MeshStats {
        triangles: welded.input_triangles.len(),
        ..Default::default()
    };
    let started = Instant::now();
    let pattern = pattern_for(opts.method, &welded)?;
    stats.setup += started.elapsed();
    let base_normals: Option<Vec<DVec3>> = mesh.pose_normals(&vec![0.0; mesh.target_count]);
    let has_normal_targets = mesh
        .primitives
        .iter()
        .any(|p| p.target_nrm.iter().any(Option::is_some));
    let base: Vec<DVec3> = mesh.pose(&vec![0.0; mesh.target_count]);

    let shape = opts.report.then(|| Shape::new(&welded.triangles));
    let mut report = shape.as_ref().map(|shape| MeshReport {
        mesh: mesh.name.clone(),
        method: opts.method.name().to_string(),
        triangles: welded.triangles.len(),
        closed: shape.closed,
        frames: Vec::new(),
    });
    let mut tracks = Vec::new();
    for track in &mesh.tracks {
        let keys = key_poses(mesh, track);
        stats.keys += keys.len();
        let welded_keys: Vec<Vec<DVec3>> = keys.iter().map(|k| welded.weld(k)).collect();
        let normal_keys = base_normals.as_ref().map(|bn| {
            let smoothing = Smoothing::new(&welded.of_vertex, bn);
            let rec_base = smoothing.normals(&base, &welded.input_triangles);
            let recomputed: Vec<Vec<DVec3>> = keys
                .iter()
                .map(|k| smoothing.normals(k, &welded.input_triangles))
                .collect();
            let authored = track
                .weights
                .iter()
                .zip(&recomputed)
                .map(|(w, rec)| match has_normal_targets {
                    true => mesh.pose_normals(w).expect("normals present"),
                    false => (0..bn.len())
                        .map(|v| arc(rec_base[v], rec[v]) * bn[v])
                        .collect(),
                })
                .collect();
            NormalKeys {
                smoothing,
                recomputed,
                authored,
            }
        });
        let frames = plan(&track.times, opts);
        tracks.push(TrackFrames {
            origin: track.origin.clone(),
            first: stats.frames,
            frames: frames.clone(),
        });
        // Frames grouped by segment, each segment prepared once.
        let mut i = 0;
        while i < frames.len() {
            let (a, b) = (frames[i].key_a, frames[i].key_b);
            let j = i + frames[i..]
                .iter()
                .take_while(|f| f.key_a == a && f.key_b == b)
                .count();
            let t0 = Instant::now();
            let segment = Segment::for_key_pair(
                opts,
                &welded_keys,
                &track.times,
                a,
                b,
                pattern.as_ref(),
                &welded.triangles,
            )?;
            stats.setup += t0.elapsed();
            let chunk = 2 * rayon::current_num_threads().max(1);
            for start in (i..j).step_by(chunk) {
                let t0 = Instant::now();
                let computed: Vec<(Vec<PrimitiveDelta>, Option<FrameReport>)> = frames
                    [start..(start + chunk).min(j)]
                    .par_iter()
                    .map(|f| {
                        let w = segment.frame(f.t);
                        let figures = shape.as_ref().map(|shape| {
                            let (mean, max, area, volume, inverted) =
                                shape.measure(&w, &welded_keys[a], &welded_keys[b], f.t);
                            FrameReport {
                                frame: 0,
                                time: f.time,
                                key_a: a,
                                key_b: b,
                                t: f.t,
                                edge_distortion_mean: mean,
                                edge_distortion_max: max,
                                area_change: area,
                                volume_change: volume,
                                inverted_triangles: inverted,
                            }
                        });
                        let positions: Vec<DVec3> =
                            welded.of_vertex.iter().map(|&k| w[k as usize]).collect();
                        drop(w);
                        let normals = normal_keys.as_ref().map(|nk| {
                            let rec = nk.smoothing.normals(&positions, &welded.input_triangles);
                            (0..positions.len())
                                .map(|v| {
                                    carry(
                                        nk.authored[a][v],
                                        nk.recomputed[a][v],
                                        nk.authored[b][v],
                                        nk.recomputed[b][v],
                                        rec[v],
                                        f.t,
                                    )
                                })
                                .collect::<Vec<DVec3>>()
                        });
                        let deltas = frame_deltas(mesh, &positions, normals.as_deref());
                        progress();
                        (deltas, figures)
                    })
                    .collect();
                stats.solve += t0.elapsed();
                for (frame, figures) in computed {
                    if let (Some(r), Some(mut fig)) = (report.as_mut(), figures) {
                        fig.frame = stats.frames;
                        r.frames.push(fig);
                    }
                    sink(stats.frames, frame)?;
                    stats.frames += 1;
                }
            }
            i = j;
        }
    }
    Ok(MeshFrames {
        mesh: mesh.mesh,
        name: mesh.name.clone(),
        tracks,
        primitives: Vec::new(),
        dropped_channels: mesh.dropped_channels.clone(),
        stats,
        report,
    })
}

/// [`tween_mesh`] with every frame kept, per primitive (what the glTF writer needs).
pub fn collect_mesh(
    mesh: &MorphMesh,
    opts: &TweenOptions,
    progress: &(dyn Fn() + Sync),
) -> Result<MeshFrames> {
    let with_normals = mesh.primitives.iter().all(|p| p.normals.is_some());
    let all_tangents = mesh.primitives.iter().all(|p| p.tangents.is_some());
    let mut primitives: Vec<PrimitiveFrames> = mesh
        .primitives
        .iter()
        .map(|p| PrimitiveFrames {
            index: p.index,
            positions: Vec::new(),
            normals: with_normals.then(Vec::new),
            tangents: (with_normals && all_tangents).then(Vec::new),
        })
        .collect();
    let mut out = tween_mesh(mesh, opts, progress, &mut |_, frame| {
        for (out, d) in primitives.iter_mut().zip(frame) {
            out.positions.push(d.positions);
            if let (Some(all), Some(n)) = (&mut out.normals, d.normals) {
                all.push(n);
            }
            if let (Some(all), Some(t)) = (&mut out.tangents, d.tangents) {
                all.push(t);
            }
        }
        Ok(())
    })?;
    out.primitives = primitives;
    Ok(out)
}

/// One frame of one primitive, as morph target deltas from the primitive's base.
pub struct PrimitiveDelta {
    pub positions: Vec<[f32; 3]>,
    pub normals: Option<Vec<[f32; 3]>>,
    pub tangents: Option<Vec<[f32; 3]>>,
}

/// Split a frame (input vertex order) into per-primitive deltas from the base. Tangents are
/// the base tangents turned by the rotation of the base normal onto the frame's normal, kept
/// orthogonal to it.
fn frame_deltas(
    mesh: &MorphMesh,
    positions: &[DVec3],
    normals: Option<&[DVec3]>,
) -> Vec<PrimitiveDelta> {
    let delta = |vals: &[DVec3], reference: &[DVec3]| -> Vec<[f32; 3]> {
        vals.iter()
            .zip(reference)
            .map(|(v, r)| (*v - *r).as_vec3().to_array())
            .collect()
    };
    let mut offset = 0;
    mesh.primitives
        .iter()
        .map(|p| {
            let range = offset..offset + p.base.len();
            offset += p.base.len();
            let frame_normals = normals.map(|n| &n[range.clone()]);
            let tangents = match (&p.tangents, &p.normals, frame_normals) {
                (Some(tan), Some(bn), Some(nf)) => Some(
                    nf.iter()
                        .zip(bn)
                        .zip(tan)
                        .map(|((nf, nb), t)| {
                            let t3 = DVec3::new(t[0], t[1], t[2]);
                            let rotated = arc(nb.normalize_or_zero(), *nf) * t3;
                            let ortho = (rotated - *nf * nf.dot(rotated))
                                .try_normalize()
                                .unwrap_or(rotated);
                            (ortho * t3.length() - t3).as_vec3().to_array()
                        })
                        .collect(),
                ),
                _ => None,
            };
            PrimitiveDelta {
                positions: delta(&positions[range.clone()], &p.base),
                normals: match (&p.normals, frame_normals) {
                    (Some(bn), Some(nf)) => Some(delta(nf, bn)),
                    _ => None,
                },
                tangents,
            }
        })
        .collect()
}

/// The solve's sparsity pattern of `welded`, for the methods that solve (`seed`, `spline`).
fn pattern_for(method: Method, welded: &Welded) -> Result<Option<Pattern>> {
    Ok(match method {
        Method::Seed | Method::Spline => Some(Pattern::new(welded.n, &welded.triangles)?),
        Method::Linear => None,
    })
}

/// Welded positions of every frame of one track (for tests and benchmarks).
pub fn track_frames_welded(
    mesh: &MorphMesh,
    track: &Track,
    opts: &TweenOptions,
) -> Result<(Welded, Vec<Vec<DVec3>>)> {
    let welded = Welded::build(mesh);
    let pattern = pattern_for(opts.method, &welded)?;
    let keys: Vec<Vec<DVec3>> = key_poses(mesh, track)
        .iter()
        .map(|k| welded.weld(k))
        .collect();
    let mut out = Vec::new();
    let frames = plan(&track.times, opts);
    let mut current: Option<((usize, usize), Segment)> = None;
    for f in &frames {
        if current
            .as_ref()
            .is_none_or(|(ab, _)| *ab != (f.key_a, f.key_b))
        {
            let s = Segment::for_key_pair(
                opts,
                &keys,
                &track.times,
                f.key_a,
                f.key_b,
                pattern.as_ref(),
                &welded.triangles,
            )?;
            current = Some(((f.key_a, f.key_b), s));
        }
        out.push(current.as_ref().unwrap().1.frame(f.t));
    }
    Ok((welded, out))
}
