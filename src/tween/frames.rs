//! A mesh's frames: for each track, its keys welded, its frames scheduled, each segment
//! prepared once and its frames solved in parallel chunks, normals carried, and every frame
//! handed on as per-primitive deltas from the base (streamed to the writer, or collected).

use super::keys::{MorphMesh, Track, TrackOrigin};
use super::normals::{arc, carry, Smoothing};
use super::options::{Method, TweenOptions};
use super::report::{FrameReport, MeshReport, Shape};
use super::schedule::{plan, FrameAt};
use super::segment::{KeyTrack, Segment};
use super::solve::Pattern;
use super::weld::Welded;
use anyhow::Result;
use glam::DVec3;
use rayon::prelude::*;
use std::time::{Duration, Instant};

/// Output of one track: its frames are `first..first + frames.len()` of the mesh's frames.
pub struct TrackFrames {
    pub origin: TrackOrigin,
    pub first: usize,
    pub frames: Vec<FrameAt>,
    /// The authored weights of each key.
    pub keys: Vec<Vec<f64>>,
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

/// What every track of one mesh shares: the welded mesh, its analysed system, the base
/// normals and the report's measures.
struct MeshTween<'a> {
    mesh: &'a MorphMesh,
    opts: &'a TweenOptions,
    welded: Welded,
    pattern: Option<Pattern>,
    base: Vec<DVec3>,
    base_normals: Option<Vec<DVec3>>,
    has_normal_targets: bool,
    shape: Option<Shape>,
}

/// One track's keys, ready for its frames.
struct TrackKeys {
    welded: Vec<Vec<DVec3>>,
    normals: Option<NormalKeys>,
}

impl<'a> MeshTween<'a> {
    fn new(mesh: &'a MorphMesh, opts: &'a TweenOptions) -> Result<MeshTween<'a>> {
        let welded = Welded::build(mesh);
        let pattern = pattern_for(opts.method, mesh, &welded)?;
        let shape = opts.report.then(|| Shape::new(&welded.triangles));
        Ok(MeshTween {
            mesh,
            opts,
            pattern,
            base: mesh.pose(&vec![0.0; mesh.target_count]),
            base_normals: mesh.pose_normals(&vec![0.0; mesh.target_count]),
            has_normal_targets: mesh
                .primitives
                .iter()
                .any(|p| p.target_nrm.iter().any(Option::is_some)),
            shape,
            welded,
        })
    }

    /// The keys of `track` (welded), with their recomputed and authored normals.
    fn keys(&self, track: &Track) -> TrackKeys {
        let (mesh, welded) = (self.mesh, &self.welded);
        let keys = key_poses(mesh, track);
        let normals = self.base_normals.as_ref().map(|bn| {
            let smoothing = Smoothing::new(&welded.of_vertex, bn);
            let rec_base = smoothing.normals(&self.base, &welded.input_triangles);
            let recomputed: Vec<Vec<DVec3>> = keys
                .iter()
                .map(|k| smoothing.normals(k, &welded.input_triangles))
                .collect();
            let authored = track
                .weights
                .iter()
                .zip(&recomputed)
                .map(|(w, rec)| match self.has_normal_targets {
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
        TrackKeys {
            welded: keys.iter().map(|k| welded.weld(k)).collect(),
            normals,
        }
    }

    /// The frame `f` of `keys` whose welded positions its segment gave as `w`: its
    /// per-primitive deltas, and its figures when a report is asked for.
    fn frame(
        &self,
        keys: &TrackKeys,
        f: &FrameAt,
        w: Vec<DVec3>,
    ) -> (Vec<PrimitiveDelta>, Option<FrameReport>) {
        let (a, b) = (f.key_a, f.key_b);
        let figures = self.shape.as_ref().map(|shape| {
            let (mean, max, area, volume, inverted) =
                shape.measure(&w, &keys.welded[a], &keys.welded[b], f.t);
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
        let positions: Vec<DVec3> = self
            .welded
            .of_vertex
            .iter()
            .map(|&k| w[k as usize])
            .collect();
        drop(w);
        let normals = keys.normals.as_ref().map(|nk| {
            let rec = nk
                .smoothing
                .normals(&positions, &self.welded.input_triangles);
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
        (
            frame_deltas(self.mesh, &positions, normals.as_deref()),
            figures,
        )
    }

    /// Every frame of `track`, in order, into `sink` (see [`tween_mesh`]).
    fn track(
        &self,
        track: &'a Track,
        out: &mut MeshFrames,
        progress: &(dyn Fn() + Sync),
        sink: &mut dyn FnMut(usize, Vec<PrimitiveDelta>) -> Result<()>,
    ) -> Result<()> {
        let keys = self.keys(track);
        let stats = &mut out.stats;
        stats.keys += keys.welded.len();
        let frames = plan(&track.times, self.opts);
        out.tracks.push(TrackFrames {
            origin: track.origin.clone(),
            first: stats.frames,
            frames: frames.clone(),
            keys: track.weights.clone(),
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
            let segment = KeyTrack {
                keys: &keys.welded,
                times: &track.times,
                pattern: self.pattern.as_ref(),
                triangles: &self.welded.triangles,
            }
            .segment(self.opts.method, self.opts.wrap, a, b)?;
            stats.setup += t0.elapsed();
            let threads = rayon::current_num_threads().max(1);
            let block = segment.block(j - i, threads);
            // Two frames a thread at a time, or one block a thread.
            let chunk = threads * if block > 1 { block } else { 2 };
            for start in (i..j).step_by(chunk) {
                let t0 = Instant::now();
                let end = (start + chunk).min(j);
                // A last, shorter chunk is shared out over the threads too.
                let block = block.min(segment.block(end - start, threads));
                let computed: Vec<Vec<(Vec<PrimitiveDelta>, Option<FrameReport>)>> = frames
                    [start..end]
                    .par_chunks(block)
                    .map(|fs| {
                        let ts: Vec<f64> = fs.iter().map(|f| f.t).collect();
                        fs.iter()
                            .zip(segment.frames(&ts))
                            .map(|(f, w)| {
                                let done = self.frame(&keys, f, w);
                                progress();
                                done
                            })
                            .collect()
                    })
                    .collect();
                let computed = computed.into_iter().flatten();
                stats.solve += t0.elapsed();
                for (frame, figures) in computed {
                    if let (Some(r), Some(mut fig)) = (out.report.as_mut(), figures) {
                        fig.frame = stats.frames;
                        r.frames.push(fig);
                    }
                    sink(stats.frames, frame)?;
                    stats.frames += 1;
                }
            }
            segment.recycle(self.pattern.as_ref());
            i = j;
        }
        Ok(())
    }
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
    let started = Instant::now();
    let tween = MeshTween::new(mesh, opts)?;
    let mut out = MeshFrames {
        mesh: mesh.mesh,
        tracks: Vec::new(),
        primitives: Vec::new(),
        dropped_channels: mesh.dropped_channels.clone(),
        stats: MeshStats {
            triangles: tween.welded.input_triangles.len(),
            setup: started.elapsed(),
            ..Default::default()
        },
        report: tween.shape.as_ref().map(|shape| MeshReport {
            mesh: mesh.name.clone(),
            method: opts.method.name().to_string(),
            triangles: tween.welded.triangles.len(),
            closed: shape.closed,
            frames: Vec::new(),
        }),
    };
    for track in &mesh.tracks {
        tween.track(track, &mut out, progress, sink)?;
    }
    Ok(out)
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
fn pattern_for(method: Method, mesh: &MorphMesh, welded: &Welded) -> Result<Option<Pattern>> {
    let t0 = Instant::now();
    let pattern = match method {
        Method::Seed | Method::Spline => {
            let base = welded.weld(&mesh.pose(&[]));
            Some(Pattern::new(welded.n, &welded.triangles, &base)?)
        }
        Method::Linear => None,
    };
    super::clock::add(super::clock::Part::Symbolic, t0);
    Ok(pattern)
}

/// Welded positions of every frame of one track (for tests and benchmarks).
pub fn track_frames_welded(
    mesh: &MorphMesh,
    track: &Track,
    opts: &TweenOptions,
) -> Result<(Welded, Vec<Vec<DVec3>>)> {
    frames_at(mesh, track, opts, &plan(&track.times, opts))
}

/// The frames `frames` of `track` (a selection of its plan), on the welded mesh, computed one
/// segment at a time (the preview's frames).
pub fn frames_at(
    mesh: &MorphMesh,
    track: &Track,
    opts: &TweenOptions,
    frames: &[FrameAt],
) -> Result<(Welded, Vec<Vec<DVec3>>)> {
    let welded = Welded::build(mesh);
    let pattern = pattern_for(opts.method, mesh, &welded)?;
    let keys: Vec<Vec<DVec3>> = key_poses(mesh, track)
        .iter()
        .map(|k| welded.weld(k))
        .collect();
    let mut out = Vec::new();
    let key_track = KeyTrack {
        keys: &keys,
        times: &track.times,
        pattern: pattern.as_ref(),
        triangles: &welded.triangles,
    };
    let mut current: Option<((usize, usize), Segment)> = None;
    for f in frames {
        if current
            .as_ref()
            .is_none_or(|(ab, _)| *ab != (f.key_a, f.key_b))
        {
            let s = key_track.segment(opts.method, opts.wrap, f.key_a, f.key_b)?;
            current = Some(((f.key_a, f.key_b), s));
        }
        out.push(current.as_ref().unwrap().1.frame(f.t));
    }
    Ok((welded, out))
}
