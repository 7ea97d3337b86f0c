//! Interpolate stage: one segment (a pair of consecutive keys) of a track, ready to produce
//! frames by the chosen [`Method`]: [`SeedSegment`], [`SplineSegment`], or vertex lerp; each
//! follows a clip's eases where it has them (see [`Eases`]).

use super::keys::eases_apply;
use super::options::Method;
use super::seed::SeedSegment;
use super::solve::{Pattern, MAX_BLOCK};
use super::spline::{self, is_loop, SplineSegment, SplineTrack};
use anyhow::Result;
use glam::DVec3;

/// The tween of one pair of keys, ready to produce frames.
pub enum Segment {
    Linear {
        x0: Vec<DVec3>,
        x1: Vec<DVec3>,
    },
    /// `linear` between keys with authored eases (see [`Eases`]): the cubic Hermite of the
    /// keys' positions with the tangents the eases give them (per unit of the segment), which
    /// is the blend the clip plays at each time; past the ends, the line along the tangent.
    Eased {
        x: [Vec<DVec3>; 2],
        tangents: [Vec<DVec3>; 2],
    },
    Seed(Box<SeedSegment>),
    Spline(Box<SplineSegment>),
}

impl Segment {
    /// Prepare the tween from `x0` to `x1` (welded positions). `pattern` is the mesh's
    /// analysed system and `triangles` its welded triangles (same order as the pattern's).
    pub fn new(
        method: Method,
        x0: Vec<DVec3>,
        x1: Vec<DVec3>,
        pattern: Option<&Pattern>,
        triangles: &[[u32; 3]],
    ) -> Result<Segment> {
        match method {
            Method::Linear => Ok(Segment::Linear { x0, x1 }),
            Method::Seed | Method::Spline => {
                let pattern = pattern.expect("the seed method needs the mesh's pattern");
                Ok(Segment::Seed(Box::new(SeedSegment::new(
                    x0, x1, pattern, triangles,
                )?)))
            }
        }
    }

    /// The frame at `t` in [0, 1] (or beyond, to extrapolate).
    ///
    /// A solving method's frame runs on rayon's threads as one job (see [`on_the_pool`]).
    pub fn frame(&self, t: f64) -> Vec<DVec3> {
        match self {
            Segment::Linear { x0, x1 } => x0.iter().zip(x1).map(|(a, b)| a.lerp(*b, t)).collect(),
            Segment::Eased { x, tangents } => {
                let w = spline::hermite_beyond(t, true);
                (x[0]
                    .iter()
                    .zip(&tangents[0])
                    .zip(x[1].iter().zip(&tangents[1])))
                .map(|((&a, &ta), (&b, &tb))| spline::hermite_point(w, [a, ta, b, tb]))
                .collect()
            }
            Segment::Seed(s) => on_the_pool(|| s.frame(t)),
            Segment::Spline(s) => on_the_pool(|| s.frame(t)),
        }
    }

    /// The frames at `ts`, as [`Segment::frame`] gives each; the solving methods share each
    /// pass over their factor between up to [`MAX_BLOCK`] frames.
    pub fn frames(&self, ts: &[f64]) -> Vec<Vec<DVec3>> {
        match self {
            Segment::Linear { .. } | Segment::Eased { .. } => {
                ts.iter().map(|&t| self.frame(t)).collect()
            }
            Segment::Seed(s) => on_the_pool(|| s.frames(ts)),
            Segment::Spline(s) => on_the_pool(|| s.frames(ts)),
        }
    }

    /// How many of `count` frames to solve together on `threads` threads: up to [`MAX_BLOCK`],
    /// as long as every thread still gets a block (a block of 4 costs 0.56-0.68x the time of 4
    /// single frames on one thread at 16k-1M triangles, `inbetween bench`).
    /// `linear` solves nothing: one frame at a time.
    pub fn block(&self, count: usize, threads: usize) -> usize {
        match self {
            Segment::Linear { .. } | Segment::Eased { .. } => 1,
            _ => count.div_ceil(threads.max(1)).clamp(1, MAX_BLOCK),
        }
    }

    /// Done with: the factor's buffer goes back to `pattern` (see
    /// [`super::solve::Placement::recycle`]).
    pub fn recycle(self, pattern: Option<&Pattern>) {
        let Some(pattern) = pattern else { return };
        match self {
            Segment::Linear { .. } | Segment::Eased { .. } => {}
            Segment::Seed(s) => s.into_placement().recycle(pattern),
            Segment::Spline(s) => s.into_placement().recycle(pattern),
        }
    }

    /// Nonzeros of the Cholesky factor used by the solves (0 for `linear`).
    pub fn factor_nonzeros(&self) -> usize {
        match self {
            Segment::Linear { .. } | Segment::Eased { .. } => 0,
            Segment::Seed(s) => s.factor_nonzeros(),
            Segment::Spline(s) => s.factor_nonzeros(),
        }
    }
}

/// A track's welded keys at their times, and the mesh they share (its welded triangles and,
/// for the methods that solve, its analysed system): what a segment is built from.
pub struct KeyTrack<'a> {
    pub keys: &'a [Vec<DVec3>],
    pub times: &'a [f64],
    pub pattern: Option<&'a Pattern>,
    pub triangles: &'a [[u32; 3]],
    /// A CUBICSPLINE clip's eases, which every method follows between keys.
    pub eases: Option<Eases<'a>>,
}

/// A clip's authored eases into and out of its keys (CUBICSPLINE tangents). A segment from key
/// a to b that follows them takes its end tangents from them, not from the keys around it:
/// `spline` from the welded poses a short step ([`EASE_STEP`]) outside the segment along a's
/// out-tangent and b's in-tangent, decomposed as keys are (so the tangent it gives the
/// rotations and stretches is the derivative of the clip's own motion there, to about that
/// step); `linear` from the targets blended by the tangents (the clip's blend at every time,
/// exactly: a pose is linear in the weights); `seed`, whose path from a to b is fixed, takes
/// it at the pace of those tangents along the keys' chord ([`SeedSegment::paced`]).
pub struct Eases<'a> {
    /// Each key's weights (the track's) and in- and out-tangents, weights per second.
    pub weights: &'a [Vec<f64>],
    pub tangents: &'a [[Vec<f64>; 2]],
    /// The mesh, posed by a set of weights.
    pub mesh: &'a dyn WeldedPose,
}

/// A mesh's welded pose at a set of weights (its blend of the targets).
pub trait WeldedPose: Sync {
    fn welded_pose(&self, weights: &[f64]) -> Vec<DVec3>;
}

/// The step outside a segment, as a fraction of its span, at which [`Eases`] takes the poses
/// its end tangents come from: a tangent is then off by about this fraction of the change of
/// the motion's speed over the segment (none where the tangent is zero: the pose outside is the
/// key's), and its round-off (a decomposition's 1e-15, divided by the step) near 1e-10.
pub const EASE_STEP: f64 = 1e-5;

impl Eases<'_> {
    /// The welded poses `e` seconds before key a along its out-tangent and after key b along
    /// its in-tangent.
    fn outside(&self, a: usize, b: usize, e: f64) -> [Vec<DVec3>; 2] {
        let along = |k: usize, side: usize, step: f64| {
            let w: Vec<f64> = (self.weights[k].iter())
                .zip(&self.tangents[k][side])
                .map(|(w, m)| w + step * m)
                .collect();
            self.mesh.welded_pose(&w)
        };
        [along(a, 1, -e), along(b, 0, e)]
    }

    /// The positions' own tangents at a (out) and b (in) over a segment of `h` seconds: the
    /// targets' deltas blended by the tangents' weights, times h.
    fn slopes(&self, a: usize, b: usize, h: f64) -> [Vec<DVec3>; 2] {
        let base = self.mesh.welded_pose(&vec![0.0; self.weights[a].len()]);
        [(a, 1), (b, 0)].map(|(k, side)| {
            let moved = self.mesh.welded_pose(&self.tangents[k][side]);
            moved
                .iter()
                .zip(&base)
                .map(|(m, o)| (*m - *o) * h)
                .collect()
        })
    }
}

impl KeyTrack<'_> {
    /// The segment from key a to key b (a + 1, or a itself for a track with a single key time)
    /// by `method`; with `wrap`, `spline` wraps around a track whose last key repeats its
    /// first; with the track's eases, the segment follows them (see [`Eases`]).
    /// `pattern` is required by `seed` and `spline`.
    pub fn segment(&self, method: Method, wrap: bool, a: usize, b: usize) -> Result<Segment> {
        let (keys, pattern, triangles) = (self.keys, self.pattern, self.triangles);
        if let Some(eases) = self.eases_of(a, b) {
            return self.eased(eases, method, a, b);
        }
        match method {
            Method::Spline if b == a + 1 => {
                let pattern = pattern.expect("the spline method needs the mesh's pattern");
                let looped = wrap && is_loop(keys);
                let track = SplineTrack::new(keys, self.times, looped, pattern, triangles)?;
                Ok(Segment::Spline(Box::new(track.segment(a)?)))
            }
            Method::Spline => Segment::new(
                Method::Seed,
                keys[a].clone(),
                keys[b].clone(),
                pattern,
                triangles,
            ),
            m => Segment::new(m, keys[a].clone(), keys[b].clone(), pattern, triangles),
        }
    }

    /// The eases the segment from key a to b follows, where the clip has them and they apply
    /// (`keys::eases_apply`).
    fn eases_of(&self, a: usize, b: usize) -> Option<&Eases<'_>> {
        (self.eases.as_ref()).filter(|_| eases_apply(self.times, a, b))
    }

    /// The segment from key a to b = a + 1 following `eases` (see [`Eases`]).
    fn eased(&self, eases: &Eases, method: Method, a: usize, b: usize) -> Result<Segment> {
        let h = self.times[b] - self.times[a];
        let (xa, xb) = (&self.keys[a], &self.keys[b]);
        let pattern = self.pattern;
        match method {
            Method::Linear => Ok(Segment::Eased {
                tangents: eases.slopes(a, b, h),
                x: [xa.clone(), xb.clone()],
            }),
            Method::Seed => {
                let pace = along_chord(xa, xb, eases.slopes(a, b, h));
                let pattern = pattern.expect("the seed method needs the mesh's pattern");
                let seed = SeedSegment::new(xa.clone(), xb.clone(), pattern, self.triangles)?;
                Ok(Segment::Seed(Box::new(seed.paced(pace))))
            }
            Method::Spline => {
                let e = EASE_STEP * h;
                let [before, after] = eases.outside(a, b, e);
                // A track of the two keys and the poses just outside them, whose tangents are
                // the slopes over those steps.
                let (ta, tb) = (self.times[a], self.times[b]);
                let keys = [before, xa.clone(), xb.clone(), after];
                let times = [ta - e, ta, tb, tb + e];
                let pattern = pattern.expect("the spline method needs the mesh's pattern");
                let track = SplineTrack::new(&keys, &times, false, pattern, self.triangles)?;
                let segment = track.stepped_ends().segment(1)?;
                Ok(Segment::Spline(Box::new(segment.straight_beyond())))
            }
        }
    }
}

/// The slopes (per unit of the segment) of the positions' own `tangents` at a and b along the
/// chord from `xa` to `xb`, as fractions of it (summed over the vertices, so each weighs by how
/// far it moves): the pace at which [`SeedSegment::paced`] takes the seed's path. Keys that
/// do not differ give the seed's own pace (slopes 1): its frames hold still there.
fn along_chord(xa: &[DVec3], xb: &[DVec3], tangents: [Vec<DVec3>; 2]) -> [f64; 2] {
    let chord: Vec<DVec3> = xa.iter().zip(xb).map(|(a, b)| *b - *a).collect();
    let length2: f64 = chord.iter().map(|d| d.length_squared()).sum();
    if length2 <= 0.0 || !length2.is_finite() {
        return [1.0; 2];
    }
    tangents.map(|t| t.iter().zip(&chord).map(|(t, d)| t.dot(*d)).sum::<f64>() / length2)
}

/// The keys the segment from key a to key b of a track of `count` keys reads by `method` (see
/// [`KeyTrack::segment`]; `eased`: the segment follows its track's eases, `Track::eased`),
/// ascending: what a caller holding only some of a long track's keys must hold for it.
pub fn keys_read(method: Method, count: usize, a: usize, b: usize, eased: bool) -> Vec<usize> {
    match method {
        Method::Spline if b == a + 1 && !eased => spline::keys_read(count, a),
        _ if a == b => vec![a],
        _ => vec![a.min(b), a.max(b)],
    }
}

/// `work` on one of rayon's threads (at once where called on one): a frame's parallel steps
/// (its terms, its solves' parts) then hand work to the other threads from inside the pool,
/// where each step called from outside it (the bench's frames, a caller's own thread) would
/// send its work to the pool and wait to be woken, several times a frame.
fn on_the_pool<R: Send>(work: impl FnOnce() -> R + Send) -> R {
    rayon::scope(|_| work())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dev::synth;

    /// A spline segment reads WINDOW keys either side of its own two (past a track's ends
    /// round a loop) and the first and last keys, or its two where eases give its tangents;
    /// the other methods read their two.
    #[test]
    fn a_segment_reads_its_window_and_the_track_s_ends() {
        assert_eq!(
            keys_read(Method::Spline, 20, 5, 6, false),
            [0, 3, 4, 5, 6, 7, 8, 19]
        );
        // Segment 0: keys -2 and -1 of a loop of 19 are 17 and 18.
        assert_eq!(
            keys_read(Method::Spline, 20, 0, 1, false),
            [0, 1, 2, 3, 17, 18, 19]
        );
        assert_eq!(
            keys_read(Method::Spline, 20, 18, 19, false),
            [0, 1, 2, 16, 17, 18, 19]
        );
        assert_eq!(keys_read(Method::Spline, 2, 0, 1, false), [0, 1]);
        assert_eq!(keys_read(Method::Spline, 1, 0, 0, false), [0]);
        assert_eq!(keys_read(Method::Seed, 20, 5, 6, false), [5, 6]);
        assert_eq!(keys_read(Method::Linear, 20, 7, 7, false), [7]);
        // Eases give a spline segment its tangents: it reads its two keys.
        assert_eq!(keys_read(Method::Spline, 20, 5, 6, true), [5, 6]);
    }

    /// Frames solved together (one pass over the triangles' data and over the factor) are
    /// bit for bit the frames solved one at a time, for the solving methods, on a tube that
    /// twists past a whole turn and bends (so the spline splits it into twist and swing).
    #[test]
    fn frames_solved_together_are_each_frame_alone_bit_for_bit() {
        let s = synth::tube(24, 12, 6.0, 0.5, 0.4);
        let keys: Vec<Vec<DVec3>> = [0.0f64, 0.5, 1.0]
            .iter()
            .map(|&k| {
                let t = synth::twist(&s.positions, (400.0 * k).to_radians(), 6.0);
                synth::bend(&t, 3.0, (60.0 * k).to_radians(), 1.0)
            })
            .collect();
        let pattern = Pattern::new(keys[0].len(), &s.triangles, &keys[0]).unwrap();
        let track = KeyTrack {
            keys: &keys,
            times: &[0.0, 1.0, 2.0],
            pattern: Some(&pattern),
            triangles: &s.triangles,
            eases: None,
        };
        let us = [0.1, 0.3, 0.5, 0.7, 0.9];
        for method in [Method::Seed, Method::Spline] {
            let segment = track.segment(method, false, 0, 1).unwrap();
            for (f, together) in segment.frames(&us).iter().enumerate() {
                let alone = segment.frame(us[f]);
                let bits = |p: &[DVec3]| -> Vec<u64> {
                    p.iter()
                        .flat_map(|v| v.to_array().map(f64::to_bits))
                        .collect()
                };
                assert_eq!(bits(together), bits(&alone), "{method:?} frame {f}");
            }
        }
    }
}
