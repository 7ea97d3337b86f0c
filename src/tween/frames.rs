//! A mesh's frames: for each track, its keys welded, its frames scheduled, each segment
//! prepared once and its frames solved in parallel chunks, normals carried, and every frame
//! handed on as per-primitive deltas from the base (streamed to the writer, or collected).

use super::keys::{MorphMesh, Track};
use super::normals::{arc, carry, tangent_delta, Smoothing};
use super::options::{Method, TweenOptions};
use super::report::{FrameReport, MeshReport, Shape};
use super::schedule::{plan, FrameAt};
use super::segment::{keys_read, Eases, KeyTrack, Segment, WeldedPose};
use super::solve::Pattern;
use super::weld::Welded;
use anyhow::{bail, Result};
use glam::DVec3;
use rayon::prelude::*;
use std::time::{Duration, Instant};

/// From this many welded vertices a segment's freed memory goes back to the system after its
/// set-up and after its frames ([`crate::memory::release_freed_memory`]): there each frame's
/// buffers are megabytes and a worker thread's arena can hold hundreds of them; below, a
/// track of thousands of small segments would pay for a walk of the arenas twice a segment.
const RELEASE_MIN_VERTICES: usize = 100_000;

/// Output of one track: its frames are `first..first + frames.len()` of the mesh's frames.
pub struct TrackFrames {
    /// The keys the frames are made from (their origin, times, authored weights and eases).
    pub track: Track,
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
    /// Whether its segments, or it beside other meshes, ran side by side (its set-up and
    /// solve times are then the threads' summed).
    pub side_by_side: bool,
}

/// Key poses of a track, in input vertex order.
pub fn key_poses(mesh: &MorphMesh, track: &Track) -> Vec<Vec<DVec3>> {
    track.weights.iter().map(|w| mesh.pose(w)).collect()
}

/// Normals data of a mesh for one track, when every primitive has NORMAL: each held key's
/// recomputed and authored normals (empty for the keys not held).
struct NormalKeys {
    smoothing: Smoothing,
    /// The base's recomputed normals (what a key's authored normals turn from when no target
    /// has normals of its own).
    rec_base: Vec<DVec3>,
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
    /// Whether a frame on a key is handed on with its deltas (not where a key is played by its
    /// authored weights alone: the glTF rig layout, uncompacted).
    key_deltas: bool,
}

/// One track's keys as its segments read them: a key's welded pose and normals are made when
/// a segment first reads the key and dropped once the segments have passed it, so a track of
/// thousands of keys (a face rig baked at 60 keys/s) holds a few at a time, never all of them.
struct TrackKeys {
    /// Welded poses, empty for the keys not held.
    welded: Vec<Vec<DVec3>>,
    /// Poses in input vertex order, held only where frames on keys hand on their deltas
    /// (what those frames are); empty otherwise.
    poses: Vec<Vec<DVec3>>,
    normals: Option<NormalKeys>,
    /// The keys held, ascending.
    held: Vec<usize>,
}

impl WeldedPose for MeshTween<'_> {
    fn welded_pose(&self, weights: &[f64]) -> Vec<DVec3> {
        self.welded.weld(&self.mesh.pose(weights))
    }
}

impl<'a> MeshTween<'a> {
    fn new(mesh: &'a MorphMesh, opts: &'a TweenOptions, key_deltas: bool) -> Result<MeshTween<'a>> {
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
            key_deltas,
        })
    }

    /// The keys of `track`, none held yet; with `normals` (and normals in the mesh), each
    /// held key's recomputed and authored normals too.
    fn keys(&self, track: &Track, normals: bool) -> TrackKeys {
        let count = track.weights.len();
        let normals = self.base_normals.as_ref().filter(|_| normals).map(|bn| {
            let smoothing = Smoothing::new(&self.welded.of_vertex, bn);
            let rec_base = smoothing.normals(&self.base, &self.welded.input_triangles);
            NormalKeys {
                smoothing,
                rec_base,
                recomputed: vec![Vec::new(); count],
                authored: vec![Vec::new(); count],
            }
        });
        TrackKeys {
            welded: vec![Vec::new(); count],
            poses: vec![Vec::new(); count],
            normals,
            held: Vec::new(),
        }
    }

    /// The held keys of `track` with the mesh's system, for a segment between them.
    fn key_track<'k>(&'k self, track: &'k Track, keys: &'k TrackKeys) -> KeyTrack<'k> {
        KeyTrack {
            keys: &keys.welded,
            times: &track.times,
            pattern: self.pattern.as_ref(),
            triangles: &self.welded.triangles,
            eases: track.eases.as_ref().map(|tangents| Eases {
                weights: &track.weights,
                tangents,
                mesh: self,
            }),
        }
    }

    /// Hold exactly the keys `keep` (ascending) of `track`: those not held are made (side by
    /// side), the others dropped.
    fn hold(&self, track: &Track, keys: &mut TrackKeys, keep: &[usize]) {
        for &k in keys.held.iter().filter(|k| keep.binary_search(k).is_err()) {
            keys.welded[k] = Vec::new();
            keys.poses[k] = Vec::new();
            if let Some(nk) = &mut keys.normals {
                nk.recomputed[k] = Vec::new();
                nk.authored[k] = Vec::new();
            }
        }
        let (mesh, welded) = (self.mesh, &self.welded);
        let normals = keys.normals.as_ref();
        let made: Vec<_> = keep
            .par_iter()
            .filter(|k| keys.held.binary_search(k).is_err())
            .map(|&k| {
                let w = &track.weights[k];
                let pose = mesh.pose(w);
                let normals = normals.map(|nk| {
                    let rec = nk.smoothing.normals(&pose, &welded.input_triangles);
                    let authored = match self.has_normal_targets {
                        true => mesh.pose_normals(w).expect("normals present"),
                        false => (nk.rec_base.iter().zip(&rec))
                            .zip(self.base_normals.as_deref().expect("normals present"))
                            .map(|((rb, r), bn)| arc(*rb, *r) * *bn)
                            .collect(),
                    };
                    (rec, authored)
                });
                let welded = welded.weld(&pose);
                (k, welded, self.key_deltas.then_some(pose), normals)
            })
            .collect();
        for (k, welded, pose, normals) in made {
            keys.welded[k] = welded;
            keys.poses[k] = pose.unwrap_or_default();
            if let (Some(nk), Some((rec, authored))) = (&mut keys.normals, normals) {
                nk.recomputed[k] = rec;
                nk.authored[k] = authored;
            }
        }
        keys.held = keep.to_vec();
    }

    /// The frame `f` of a track (keys `keys`) whose welded positions its segment gave as `w`:
    /// its per-primitive deltas, and its figures when a report is asked for. A frame on a key
    /// is the key's own pose, every input vertex as authored (not welded).
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
        if let (Some(_), false) = (f.key(), self.key_deltas) {
            let none = || PrimitiveDelta {
                positions: Vec::new(),
                normals: Some(Vec::new()),
                tangents: Some(Vec::new()),
            };
            return (
                self.mesh.primitives.iter().map(|_| none()).collect(),
                figures,
            );
        }
        let unwelded: Vec<DVec3>;
        let positions: &[DVec3] = match f.key() {
            Some(k) => &keys.poses[k],
            None => {
                unwelded = (self.welded.of_vertex.iter())
                    .map(|&k| w[k as usize])
                    .collect();
                &unwelded
            }
        };
        drop(w);
        let normals = keys.normals.as_ref().map(|nk| {
            let rec = nk
                .smoothing
                .normals(positions, &self.welded.input_triangles);
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
            frame_deltas(self.mesh, positions, normals.as_deref()),
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
        let mut keys = self.keys(track, true);
        out.stats.keys += keys.welded.len();
        let frames = plan(&track.times, self.opts);
        out.tracks.push(TrackFrames {
            track: track.clone(),
            first: out.stats.frames,
            frames: frames.clone(),
        });
        // Frames grouped by segment, each segment prepared once. A frame on a key is that key
        // as it is (nothing solved), and a segment whose frames are all keys is not prepared
        // (a track baked at 60 keys/s and written at 30 frames/s between keys).
        let mut groups = Vec::new();
        let mut i = 0;
        while i < frames.len() {
            let (a, b) = (frames[i].key_a, frames[i].key_b);
            let j = i + frames[i..]
                .iter()
                .take_while(|f| f.key_a == a && f.key_b == b)
                .count();
            groups.push(i..j);
            i = j;
        }
        let threads = rayon::current_num_threads().max(1);
        // Segments in flight at once: as many as the triangles allow, a few a thread.
        let triangles = self.welded.triangles.len().max(1);
        let in_flight = (SIDE_BY_SIDE_TRIANGLES / triangles).min(SEGMENTS_A_THREAD * threads);
        if threads > 1 && groups.len() > 1 && in_flight > 1 {
            return self.track_side_by_side(
                track, &frames, &groups, in_flight, keys, out, progress, sink,
            );
        }
        for r in &groups {
            self.segment_streamed(track, &frames[r.clone()], &mut keys, out, progress, sink)?;
        }
        Ok(())
    }

    /// The segment over frames `fs` of `track` set up on every thread and its frames solved in
    /// chunks of a few a thread, each chunk handed on before the next is solved.
    fn segment_streamed(
        &self,
        track: &Track,
        fs: &[FrameAt],
        keys: &mut TrackKeys,
        out: &mut MeshFrames,
        progress: &(dyn Fn() + Sync),
        sink: &mut dyn FnMut(usize, Vec<PrimitiveDelta>) -> Result<()>,
    ) -> Result<()> {
        let (a, b) = (fs[0].key_a, fs[0].key_b);
        let t0 = Instant::now();
        if self.reads_keys(fs) {
            let count = keys.welded.len();
            let eased = track.eased(a, b);
            self.hold(
                track,
                keys,
                &keys_read(self.opts.method, count, a, b, eased),
            );
        }
        let segment = self.set_up(track, keys, fs)?;
        out.stats.setup += t0.elapsed();
        // A large mesh's set-up temporaries, freed on the worker threads, back to the system
        // before the frames allocate theirs (see `release_freed_memory`).
        let large = (self.pattern.as_ref()).is_some_and(|p| p.n >= RELEASE_MIN_VERTICES);
        if large && segment.is_some() {
            crate::memory::release_freed_memory();
        }
        let threads = rayon::current_num_threads().max(1);
        let block = segment.as_ref().map_or(1, |s| s.block(fs.len(), threads));
        // Two frames a thread at a time, or one block a thread.
        let chunk = threads * if block > 1 { block } else { 2 };
        for part in fs.chunks(chunk) {
            let t0 = Instant::now();
            // A last, shorter chunk is shared out over the threads too.
            let block = segment
                .as_ref()
                .map_or(1, |s| block.min(s.block(part.len(), threads)));
            let computed: Vec<Vec<Computed>> = part
                .par_chunks(block)
                .map(|fs| self.compute(keys, segment.as_ref(), fs, progress))
                .collect();
            out.stats.solve += t0.elapsed();
            let computed = computed.into_iter().flatten().collect();
            self.hand_on(track, (a, b), computed, out, sink)?;
        }
        if let Some(segment) = segment {
            segment.recycle(self.pattern.as_ref());
            if large {
                crate::memory::release_freed_memory();
            }
        }
        Ok(())
    }

    /// Whether the segment over frames `fs` reads its keys: keys played by their authored
    /// weights alone, unmeasured, read nothing.
    fn reads_keys(&self, fs: &[FrameAt]) -> bool {
        let on_keys = fs.iter().all(|f| f.key().is_some());
        !on_keys || self.key_deltas || self.shape.is_some()
    }

    /// The segment of `track` over frames `fs` (from `fs[0].key_a` to its `key_b`) set up from
    /// the held `keys`; none where every frame is on a key.
    fn set_up(&self, track: &Track, keys: &TrackKeys, fs: &[FrameAt]) -> Result<Option<Segment>> {
        if fs.iter().all(|f| f.key().is_some()) {
            return Ok(None);
        }
        let (a, b) = (fs[0].key_a, fs[0].key_b);
        let track = self.key_track(track, keys);
        Ok(Some(track.segment(
            self.opts.method,
            self.opts.wrap,
            a,
            b,
        )?))
    }

    /// Frames `fs` of `segment` (their solves sharing passes over its factor), each a key's
    /// own pose where it lies on one.
    fn compute(
        &self,
        keys: &TrackKeys,
        segment: Option<&Segment>,
        fs: &[FrameAt],
        progress: &(dyn Fn() + Sync),
    ) -> Vec<Computed> {
        let ts: Vec<f64> = (fs.iter())
            .filter(|f| f.key().is_none())
            .map(|f| f.t)
            .collect();
        let mut solved = match segment {
            Some(s) if !ts.is_empty() => s.frames(&ts),
            _ => Vec::new(),
        }
        .into_iter();
        fs.iter()
            .map(|f| {
                let w = match f.key() {
                    Some(k) => keys.welded[k].clone(),
                    None => solved.next().expect("a frame for each time"),
                };
                let done = self.frame(keys, f, w);
                progress();
                done
            })
            .collect()
    }

    /// [`MeshTween::track`] for a small mesh: its segments set up and solved side by side, a
    /// segment to a thread, in runs of at most `in_flight` segments (see
    /// [`SIDE_BY_SIDE_TRIANGLES`]) whose frames hold at most [`SIDE_BY_SIDE_POSITIONS`], each
    /// run's keys held together and its frames handed on in order (the same frames: a
    /// segment's do not depend on what else is solved, nor on how many are solved at once).
    #[allow(clippy::too_many_arguments)]
    fn track_side_by_side(
        &self,
        track: &'a Track,
        frames: &[FrameAt],
        groups: &[std::ops::Range<usize>],
        in_flight: usize,
        mut keys: TrackKeys,
        out: &mut MeshFrames,
        progress: &(dyn Fn() + Sync),
        sink: &mut dyn FnMut(usize, Vec<PrimitiveDelta>) -> Result<()>,
    ) -> Result<()> {
        let per_frame = self.mesh.vertex_count().max(1);
        let count = keys.welded.len();
        let mut g = 0;
        while g < groups.len() {
            let mut h = g + 1;
            let mut held = groups[g].len() * per_frame;
            while h < groups.len()
                && h - g < in_flight
                && held + groups[h].len() * per_frame <= SIDE_BY_SIDE_POSITIONS
            {
                held += groups[h].len() * per_frame;
                h += 1;
            }
            let run = &groups[g..h];
            if let [r] = run {
                // A segment alone (its frames more than a run holds) is streamed.
                self.segment_streamed(track, &frames[r.clone()], &mut keys, out, progress, sink)?;
                g = h;
                continue;
            }
            out.stats.side_by_side = true;
            let t0 = Instant::now();
            // The keys the run's segments read.
            let mut need: Vec<usize> = (run.iter())
                .filter(|r| self.reads_keys(&frames[(*r).clone()]))
                .flat_map(|r| {
                    let (a, b) = (frames[r.start].key_a, frames[r.start].key_b);
                    keys_read(self.opts.method, count, a, b, track.eased(a, b))
                })
                .collect();
            need.sort_unstable();
            need.dedup();
            if !need.is_empty() {
                self.hold(track, &mut keys, &need);
            }
            out.stats.setup += t0.elapsed();
            let done: Vec<Result<Solved>> = (run.par_iter())
                .map(|r| self.segment_frames(track, &keys, &frames[r.clone()], progress))
                .collect();
            for (r, done) in run.iter().zip(done) {
                let (computed, setup, solve) = done?;
                out.stats.setup += setup;
                out.stats.solve += solve;
                let f = &frames[r.start];
                self.hand_on(track, (f.key_a, f.key_b), computed, out, sink)?;
            }
            g = h;
        }
        Ok(())
    }

    /// Segment `fs[0].key_a` to `fs[0].key_b` of `track` set up (unless every frame is on a
    /// key) and its frames `fs` computed, with the set-up's and the frames' times.
    fn segment_frames(
        &self,
        track: &Track,
        keys: &TrackKeys,
        fs: &[FrameAt],
        progress: &(dyn Fn() + Sync),
    ) -> Result<Solved> {
        let t0 = Instant::now();
        let segment = self.set_up(track, keys, fs)?;
        let setup = t0.elapsed();
        let t0 = Instant::now();
        let computed = self.compute(keys, segment.as_ref(), fs, progress);
        if let Some(segment) = segment {
            segment.recycle(self.pattern.as_ref());
        }
        Ok((computed, setup, t0.elapsed()))
    }

    /// The computed frames of segment `(a, b)` of `track` checked, measured and handed to
    /// `sink` in order.
    fn hand_on(
        &self,
        track: &Track,
        (a, b): (usize, usize),
        computed: Vec<Computed>,
        out: &mut MeshFrames,
        sink: &mut dyn FnMut(usize, Vec<PrimitiveDelta>) -> Result<()>,
    ) -> Result<()> {
        for (frame, figures) in computed {
            // Key poses far beyond float32 (or slivers at that scale) can overflow a solve:
            // refused in a line rather than written as NaN.
            let finite = |v: &Vec<[f32; 3]>| v.iter().flatten().all(|x| x.is_finite());
            if !frame
                .iter()
                .all(|p| finite(&p.positions) && p.normals.as_ref().is_none_or(finite))
            {
                bail!(not_finite(self.mesh, track, (a, b)));
            }
            if let (Some(r), Some(mut fig)) = (out.report.as_mut(), figures) {
                fig.frame = out.stats.frames;
                r.frames.push(fig);
            }
            sink(out.stats.frames, frame)?;
            out.stats.frames += 1;
        }
        Ok(())
    }
}

/// A frame's per-primitive deltas and its figures (with a report).
type Computed = (Vec<PrimitiveDelta>, Option<FrameReport>);

/// A segment's frames, its set-up's time and its frames'.
type Solved = (Vec<Computed>, Duration, Duration);

/// Most welded triangles of segments set up side by side, a segment to a thread (see
/// [`MeshTween::track_side_by_side`]): a mesh of a few thousand triangles spent more in
/// hand-offs than it saved spreading one segment at a time over the threads (MorphStressTest,
/// 2,412 triangles, 531 keys written at 120 frames a second: 2.68 s on one thread, 2.50 s on
/// two), and side by side still gains at 60,000 (a bent tube's 20 keys at 10 frames a second,
/// 2 threads: 1.82-1.97 -> 1.51-1.69 s, peak 226-228 -> 272-275 MB). A set-up holds about 1.2
/// kilobytes a triangle, so this bounds what side by side adds to the peak to about 250 MB;
/// meshes of more than half this many triangles set up one segment at a time on every thread
/// (a 200,000-triangle tube, two at once: 2.24-2.31 -> 1.60-1.74 s but 338-368 -> 586-589 MB;
/// the 1M-triangle bench tube's peak stays what it was).
pub const SIDE_BY_SIDE_TRIANGLES: usize = 200_000;

/// Most vertex positions (vertices times frames, over all primitives) that work done side by
/// side holds together before it is handed on, about 48 MB as deltas: the frames of a mesh's
/// segments solved side by side, and those of small meshes tweened side by side
/// (`tween::job::side_by_side`).
pub const SIDE_BY_SIDE_POSITIONS: usize = 4_000_000;

/// Most segments a thread is given in a run solved side by side: the run's keys are held
/// together, so a long track of keys baked close together holds a few keys a thread, not
/// thousands (a face rig of 1,681 vertices baked at 60 keys a second for two minutes, runs
/// bounded by their frames alone: 25 -> 498 MB to .usdc).
const SEGMENTS_A_THREAD: usize = 4;

/// Compute every frame of every track of `mesh` and hand each to `sink` in order (frame index,
/// per-primitive deltas), so a writer can stream them; without `key_deltas`, a frame on a key
/// is handed on with empty deltas (for a writer that plays keys by their authored weights). Frames are computed in parallel in
/// chunks of a few per thread, so at most one chunk is held at a time. `progress` is called
/// once per frame done. The returned [`MeshFrames`] holds the tracks and figures but no
/// frame data (see [`collect_mesh`] for a mesh with all of its frames).
pub fn tween_mesh(
    mesh: &MorphMesh,
    opts: &TweenOptions,
    key_deltas: bool,
    progress: &(dyn Fn() + Sync),
    sink: &mut dyn FnMut(usize, Vec<PrimitiveDelta>) -> Result<()>,
) -> Result<MeshFrames> {
    let started = Instant::now();
    let tween = MeshTween::new(mesh, opts, key_deltas)?;
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
            targets_given_normals: mesh.normals_given,
            frames: Vec::new(),
        }),
    };
    for track in &mesh.tracks {
        tween.track(track, &mut out, progress, sink)?;
    }
    Ok(out)
}

/// [`tween_mesh`] with every frame kept, per primitive (what the glTF writer needs: a frame on
/// a key has empty deltas in the rig layout uncompacted, where keys play their authored
/// weights).
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
    let mut out = tween_mesh(
        mesh,
        opts,
        opts.gltf_reads_keys(),
        progress,
        &mut |_, frame| {
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
        },
    )?;
    out.primitives = primitives;
    Ok(out)
}

/// The refusal of a segment whose frames came out NaN or infinite.
fn not_finite(mesh: &MorphMesh, track: &Track, (a, b): (usize, usize)) -> String {
    format!(
        "mesh {:?}: the frames between its keys at {} s and {} s come out not finite (key poses beyond what float32 holds, or slivers at that scale)",
        mesh.name, track.times[a], track.times[b]
    )
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
                        .map(|((nf, nb), t)| tangent_delta(*nb, *nf, *t).as_vec3().to_array())
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
    let tween = MeshTween::new(mesh, opts, false)?;
    let mut keys = tween.keys(track, false);
    let mut out = Vec::new();
    let mut current: Option<((usize, usize), Segment)> = None;
    for f in frames {
        let ab = (f.key_a, f.key_b);
        if current.as_ref().is_none_or(|(held, _)| *held != ab) {
            tween.hold(
                track,
                &mut keys,
                &keys_read(
                    opts.method,
                    track.times.len(),
                    ab.0,
                    ab.1,
                    track.eased(ab.0, ab.1),
                ),
            );
            let s = tween
                .key_track(track, &keys)
                .segment(opts.method, opts.wrap, ab.0, ab.1)?;
            current = Some((ab, s));
        }
        let frame = current.as_ref().expect("made above").1.frame(f.t);
        if !frame.iter().all(|p| p.is_finite()) {
            bail!(not_finite(mesh, track, ab));
        }
        out.push(frame);
    }
    Ok((tween.welded, out))
}
