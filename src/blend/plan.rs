//! From two analysed clips to the frames of their blend: cycles paired and synchronised, phases
//! warped by contact events, the second clip aligned to the first, poses mixed, feet cleaned up,
//! and the figures of the report measured on the sources, a naive blend and the result.

use super::align::{self, FloorTransform, MatchedTravel};
use super::analyze::{analyze_as, Analysis, Character};
use super::cleanup::{self, LegGoal};
use super::contacts::Contact;
use super::cycles::CycleMethod;
use super::legs::Side;
use super::measure::{self, Figures};
use super::mix::mix;
use super::rig::{flat, Clip, Pose, Rig, UP};
use super::timewarp::{self, Warp};
use super::track::{pose_unwrapped, Track};
use glam::{DMat4, DVec3};
use serde::Serialize;

/// Options of a blend, with their defaults in [`BlendOptions::new`].
#[derive(Clone, Debug)]
pub struct BlendOptions {
    /// 0 gives the first clip, 1 the second.
    pub weight: f64,
    pub cycles: CycleMethod,
    /// Enforce foot contacts on the blend.
    pub cleanup: bool,
}

impl BlendOptions {
    pub fn new(weight: f64) -> BlendOptions {
        BlendOptions {
            weight,
            cycles: CycleMethod::default(),
            cleanup: true,
        }
    }
}

/// The blended clip: poses at times (seconds from 0), LINEAR between them.
pub struct Blended {
    pub times: Vec<f64>,
    pub poses: Vec<Pose>,
    pub report: Report,
}

#[derive(Clone, Debug, Serialize)]
pub struct CycleReport {
    pub start: f64,
    pub period: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct ContactReport {
    pub foot: String,
    pub side: Side,
    pub count: usize,
    /// (touchdown, lift-off) in seconds on the clip's timeline.
    pub intervals: Vec<(f64, f64)>,
}

#[derive(Clone, Debug, Serialize)]
pub struct ClipReport {
    pub name: String,
    pub duration: f64,
    pub looping: bool,
    /// Cycles found; empty when none was (then the whole clip is one cycle).
    pub cycles: Vec<CycleReport>,
    /// The cycle start used after synchronising on the first foot's touchdown.
    pub synced_start: f64,
    pub contacts: Vec<ContactReport>,
    pub figures: Figures,
}

#[derive(Clone, Debug, Serialize)]
pub struct LegReport {
    pub foot: String,
    pub side: Side,
    pub length: f64,
    pub chain: Vec<String>,
}

#[derive(Clone, Debug, Serialize)]
pub struct ResultReport {
    pub duration: f64,
    pub frames: usize,
    pub fps: f64,
    pub looping: bool,
    /// Cycle durations of the blend (seconds).
    pub cycle_periods: Vec<f64>,
    /// Matched contact events used as time-warp knots in the first cycle.
    pub warp_knots: usize,
    pub before_cleanup: Figures,
    pub after_cleanup: Figures,
    /// Jerk of the blend over the weighted jerk of the sources.
    pub jerk_ratio: f64,
    /// Largest drop of the root the clean-up made (where a leg could not reach, and where the
    /// root fell to keep a stance leg's length), in leg scales.
    pub max_root_drop: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct Report {
    pub weight: f64,
    pub cycle_method: CycleMethod,
    pub cleanup: bool,
    /// Length unit of every figure: the longest leg, in scene units.
    pub leg_scale: f64,
    pub forward: [f64; 3],
    pub legs: Vec<LegReport>,
    pub clips: [ClipReport; 2],
    /// Rotation (degrees, about +Y) and floor translation carrying the second clip onto the first.
    pub alignment_degrees: f64,
    pub alignment_translation: [f64; 3],
    /// How the second clip was made to travel as the first, where one steps in place and the
    /// other travels (`null` where both travel alike).
    pub matched_travel: Option<MatchedTravel>,
    /// The same two clips blended at normalised time: no sync, no alignment, no clean-up.
    pub naive: Figures,
    pub result: ResultReport,
}

/// Weights within this distance of 0 or 1 fade the clean-up out, so that the end weights give
/// the (time-warped) source clips themselves.
pub const CLEANUP_FADE: f64 = 0.1;

/// The clean-up pins what the contact test finds planted; pinning can make the test find a few
/// more frames planted, so it is repeated (from the unclean blend) until nothing new is found,
/// at most this many times.
pub const CLEANUP_PASSES: usize = 4;

/// A planted foot the clean-up leaves farther than this from its pin (fraction of the leg
/// scale) has a leg that could not reach it once the root moved: its pins are found again
/// from the cleaned poses' reach, and the clean-up repeated (within [`CLEANUP_PASSES`]). The
/// pins' reach is judged on the blend before clean-up, whose hips the root's shift, rise and
/// drop then move: Fox's run with itself left a straight front leg 0.07 leg short of its pin
/// at a touchdown (0.0005 leg a frame of sliding after clean-up; 1.1e-5 with this, the
/// slower fade after lift-offs of [`cleanup::RELEASE_SECONDS`] included).
pub const PIN_MISS: f64 = 1e-3;

/// Strength of the clean-up at weight `w`: 1 inside [`CLEANUP_FADE`], 1 - w, smoothly to 0.
pub fn cleanup_strength(w: f64) -> f64 {
    cleanup::smoothstep((w.min(1.0 - w) / CLEANUP_FADE).clamp(0.0, 1.0))
}

/// Shortest duration (seconds) a clip is given where it divides: a clip of a single key time
/// still has a frame spacing ...
const MIN_DURATION: f64 = 1e-9;
/// ... and a cycle of this period (seconds) when no cycle was found.
const MIN_CYCLE: f64 = 1e-6;

/// One clip's cycles as used: (start, period) per cycle, synchronised on a touchdown.
fn cycles_used(clip: &Clip, an: &Analysis) -> Vec<(f64, f64)> {
    let mut spans = an
        .cycles
        .as_ref()
        .map(|c| c.spans.clone())
        .unwrap_or_else(|| vec![(clip.start, clip.duration().max(MIN_CYCLE))]);
    if an.looping() {
        if spans.len() > 1 {
            if let Some(stride) = typical_stride(&an.touches, clip.duration(), spans[0].1) {
                spans = vec![stride];
            }
        }
        spans.truncate(1);
    }
    if let Some(first) = an.touches.first() {
        let dur = clip.duration();
        for (start, period) in &mut spans {
            let candidates = first.iter().flat_map(|c| {
                let t = c.start;
                if an.looping() {
                    vec![t - dur, t, t + dur]
                } else {
                    vec![t]
                }
            });
            if let Some(t) = candidates
                .filter(|t| (t - *start).abs() <= 0.5 * *period)
                .min_by(|x, y| (x - *start).abs().total_cmp(&(y - *start).abs()))
            {
                *start = t;
            }
        }
    }
    tile(&spans)
}

/// Cycles `spans` (start, period; in time order) made to tile the clip from the first's start
/// to the last's end, so that the blend's source time never jumps between them: each cycle
/// lasts to the next one's start, and a gap of more strides than one between two cycles (a
/// stride the cycle test did not take: its other feet touched down twice, or a stumble) is cut
/// into as many cycles of equal length as the strides round it fit. The gap was jumped over:
/// CMU's start-walk-stop played backwards has cycles at 2.37 s (1.15 s), 3.52 s (1.03 s) and
/// 5.76 s, and its blend with itself jumped 1.2 s of the capture between the second and third
/// (jerk ratio 11.0).
fn tile(spans: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut out = Vec::with_capacity(spans.len());
    for (k, &(s, p)) in spans.iter().enumerate() {
        let Some(&(next, _)) = spans.get(k + 1) else {
            out.push((s, p));
            break;
        };
        let gap = next - s;
        if gap > 1.5 * p {
            let strides = (gap / p).round() as usize;
            let each = gap / strides as f64;
            out.extend((0..strides).map(|i| (s + i as f64 * each, each)));
        } else if gap >= 0.5 * p {
            out.push((s, gap));
        } else {
            out.push((s, p));
        }
    }
    out
}

/// Of a loop that repeats a stride several times (a capture that ends as it began), the stride
/// the blend takes: from a touchdown of the first leg to its next, in which every other leg
/// touches down once, of the median length of such strides (ties: the earliest). It was the
/// loop's mean stride from its first touchdown, which does not come back to where it started
/// when the strides differ: Bandai Namco's walk_not-confident, whose first stride is 1.73 s long
/// where the mean is 1.46, had its left foot planted all through those 1.46 s, and blended with
/// its run at 0.25 / 0.5 / 0.75 the foot jumped across the loop's seam (after clean-up 1e-2 /
/// 2e-2 leg a frame of sliding, jerk ratios 4.96 / 4.10 / 1.99; now below 1e-15, 1.57 / 1.38 /
/// 1.35). Over Bandai's 22 walk+run pairs of one style each (66 cells) jerk ratios above 1.15
/// went from 30 to 28, their mean from 1.25 to 1.14, but not everywhere down: sad 1.22 / 1.16 /
/// 1.02 -> 1.37 / 1.48 / 1.09, proud 1.24 / 1.20 / 1.24 -> 1.31 / 1.37 / 1.46. Tried, not kept:
/// the stride whose last pose is nearest its first (the joints about the body): the strides'
/// mismatches differ by a tenth (164-183 cm summed over the joints of walk_normal), a choice
/// by noise (walk_normal + run_normal 1.88 / 1.86 / 1.32 with it, 1.42 / 1.49 / 1.23 with this).
/// `None` where no stride fits within half a `period` (the loop's mean stride) of it.
fn typical_stride(contacts: &[Vec<Contact>], dur: f64, period: f64) -> Option<(f64, f64)> {
    let downs: Vec<Vec<f64>> = (contacts.iter())
        .map(|c| c.iter().map(|c| c.start).collect())
        .collect();
    let first = downs.first()?;
    let touches = |l: usize, s: f64, e: f64| {
        (downs[l].iter())
            .flat_map(|&t| [t - dur, t, t + dur])
            .filter(|&t| t > s && t < e)
            .count()
    };
    let strides: Vec<(f64, f64)> = (0..first.len())
        .map(|i| {
            let next = first.get(i + 1).copied().unwrap_or(first[0] + dur);
            (first[i], next - first[i])
        })
        .filter(|&(s, p)| {
            (0.5 * period..=1.5 * period).contains(&p)
                && (1..contacts.len()).all(|l| touches(l, s, s + p) == 1)
        })
        .collect();
    if strides.is_empty() {
        return None;
    }
    let median = super::legs::median(strides.iter().map(|s| s.1).collect());
    strides
        .into_iter()
        .min_by(|a, b| (a.1 - median).abs().total_cmp(&(b.1 - median).abs()))
}

fn cycle_at(spans: &[(f64, f64)], looping: bool, k: usize) -> (f64, f64) {
    if looping {
        let (s, p) = spans[0];
        (s + k as f64 * p, p)
    } else {
        spans[k]
    }
}

/// Joint positions of `poses`, one every `dt` (see [`track_of`]).
fn positions_track(rig: &Rig, poses: &[Pose], dt: f64, looping: bool) -> Track {
    track_of(
        poses.iter().map(|p| rig.positions(p)).collect(),
        dt,
        looping,
        rig.body,
    )
}

/// A track of joint positions `pos`, one frame every `dt`; a looping motion (last frame =
/// first) of more than two frames becomes a looping track (see [`Track::closed`]).
fn track_of(pos: Vec<Vec<DVec3>>, dt: f64, looping: bool, root: usize) -> Track {
    let looping = looping && pos.len() > 2;
    Track::closed(0.0, dt, looping, pos, root)
}

/// Planted flags of `leg` per pose of `poses` (see [`positions_track`]; the repeated last pose
/// of a loop gets the first one's flag).
fn contact_flags(track: &Track, count: usize, leg: &super::legs::Leg, scale: f64) -> Vec<bool> {
    let mut f = super::contacts::planted_flags(track, leg, scale);
    while f.len() < count {
        f.push(f[0]);
    }
    f
}

/// The phase plan of a blend: per output frame (output time, time in A, time in B).
struct Phase {
    frames: Vec<(f64, f64, f64)>,
    /// Duration of each blended cycle, seconds.
    periods: Vec<f64>,
    /// Matched contact events (time-warp knots) of the first cycle.
    knots: usize,
    duration: f64,
    fps: f64,
    looping: bool,
}

/// A cycle's phase must reach this far (seconds) past its period to count as the next cycle.
const TIME_EPSILON: f64 = 1e-9;

/// Pair the clips' cycles, warp each pair's phase by its matched contact events and sample the
/// blended cycles at the faster clip's key rate.
fn phase(a: &Clip, b: &Clip, an: [&Analysis; 2], spans: [&[(f64, f64)]; 2], w: f64) -> Phase {
    let [an_a, an_b] = an;
    let [spans_a, spans_b] = spans;
    let count = match (an_a.looping(), an_b.looping()) {
        (true, true) => 1,
        (true, false) => spans_b.len(),
        (false, true) => spans_a.len(),
        (false, false) => spans_a.len().min(spans_b.len()),
    };
    let fps = a.key_rate.max(b.key_rate);
    let mut frames: Vec<(f64, f64, f64)> = Vec::new();
    let mut periods = Vec::new();
    let mut offset = 0.0;
    let mut cycles: Vec<(Warp, [f64; 3], f64, f64)> = (0..count)
        .map(|k| {
            let (sa, pa) = cycle_at(spans_a, an_a.looping(), k);
            let (sb, pb) = cycle_at(spans_b, an_b.looping(), k);
            let warp = Warp::new(
                &timewarp::events(&an_a.touches, sa, pa, an_a.looping()),
                &timewarp::events(&an_b.touches, sb, pb, an_b.looping()),
                w,
            );
            (warp, [pa, pb, (1.0 - w) * pa + w * pb], sa, sb)
        })
        .collect();
    // Each clip's rate runs on from one cycle into the next. Not round a loop's seam: joined
    // there, Fox through gltfpack at 15 keys a second (`-af 15`) with its run at 0.25 slid 0.024
    // leg a frame after clean-up, and the jerk ratios of its and RobotExpressive's other
    // variants rose by up to 0.04.
    for k in 1..count {
        let (done, rest) = cycles.split_at_mut(k);
        let (left, right) = (&mut done[k - 1], &mut rest[0]);
        Warp::join(&mut left.0, &mut right.0, left.1, right.1);
    }
    for (k, (warp, p, sa, sb)) in cycles.iter().enumerate() {
        let ([pa, pb, period], sa, sb) = (*p, *sa, *sb);
        let m = ((period * fps).round() as usize).max(2);
        let last = if k + 1 == count { m } else { m - 1 };
        for j in 0..=last {
            let u = j as f64 / m as f64;
            let (fa, fb) = warp.map(u);
            frames.push((offset + u * period, sa + fa * pa, sb + fb * pb));
        }
        periods.push(period);
        offset += period;
    }
    Phase {
        frames,
        periods,
        knots: cycles.first().map_or(0, |c| c.0.knots.len() - 2),
        duration: offset,
        fps,
        looping: an_a.looping() && an_b.looping(),
    }
}

/// The two clips sampled on the phase plan, B carried onto A's floor frame by the closed-form
/// fit of the first cycle's corresponding joint positions, and the world positions of both.
struct Sources {
    poses: [Vec<Pose>; 2],
    world: [Vec<Vec<DVec3>>; 2],
    fit: FloorTransform,
    /// How B was made to travel as A, where they differ.
    matched: Option<MatchedTravel>,
    /// The skeleton's joints the body carries (all of them but root joints that stay put).
    joints: Vec<usize>,
}

fn sources(
    rig: &Rig,
    ch: &Character,
    clips: [&Clip; 2],
    an: [&Analysis; 2],
    phase: &Phase,
    w: f64,
) -> Sources {
    let sample = |k: usize, pick: fn(&(f64, f64, f64)) -> f64| -> Vec<Pose> {
        phase
            .frames
            .iter()
            .map(|f| pose_unwrapped(rig, clips[k], an[k].looping(), pick(f)))
            .collect()
    };
    let mut poses_a = sample(0, |f| f.1);
    let mut poses_b = sample(1, |f| f.2);
    for (pose, under) in poses_b.iter_mut().zip(&poses_a) {
        align::under_joints_above_body(rig, pose, under);
    }
    // B made to travel as A does (moved along, or held on the spot) over its own time.
    let matched = MatchedTravel::of(&an[0].travel, &an[1].travel, ch.scale);
    if let (Some(m), Some(first)) = (matched, phase.frames.first()) {
        for (pose, f) in poses_b.iter_mut().zip(&phase.frames) {
            let moved = DMat4::from_translation(m.velocity() * (f.2 - first.2));
            align::move_body(rig, pose, &moved);
        }
    }
    let joints: Vec<usize> = (0..rig.len()).filter(|&j| rig.carries(j)).collect();
    let first_cycle = phase
        .frames
        .iter()
        .take_while(|f| f.0 <= phase.periods[0] + TIME_EPSILON)
        .count();
    let (mut p, mut q) = (Vec::new(), Vec::new());
    for i in 0..first_cycle {
        let (wa, wb) = (rig.positions(&poses_a[i]), rig.positions(&poses_b[i]));
        p.extend(joints.iter().map(|&j| wa[j]));
        q.extend(joints.iter().map(|&j| wb[j]));
    }
    let fit = align::fit(&p, &q);
    for pose in &mut poses_b {
        align::move_body(rig, pose, &fit.matrix());
    }
    // Headings averaged over a cycle (half the blend's mean cycle either side of a frame).
    let half = (0.5 * phase.duration / phase.periods.len().max(1) as f64 * phase.fps).round();
    align::register(
        rig,
        [&mut poses_a, &mut poses_b],
        w,
        ch.forward,
        half as usize,
        phase.looping,
    );
    // Where the sources' joints are in the blend (the clean-up's targets): registered.
    let world_a: Vec<Vec<DVec3>> = poses_a.iter().map(|p| rig.positions(p)).collect();
    let world_b: Vec<Vec<DVec3>> = poses_b.iter().map(|p| rig.positions(p)).collect();
    Sources {
        poses: [poses_a, poses_b],
        world: [world_a, world_b],
        fit,
        matched,
        joints,
    }
}

/// What the clean-up works from: the character, the phase plan, the sources' foot positions,
/// the blend before clean-up, and where the sources plant each foot by weighted vote.
struct Cleanup<'a> {
    rig: &'a Rig,
    ch: &'a Character,
    phase: &'a Phase,
    src: &'a Sources,
    before: &'a Track,
    before_loop: &'a Track,
    voted: &'a [Vec<bool>],
    w: f64,
}

impl Cleanup<'_> {
    /// Pin planted feet on `frames` (the blend before clean-up) by two-bone IK, repeating
    /// until the contact test finds nothing new; returns the largest root drop needed.
    fn run(&self, frames: &mut Vec<Pose>) -> f64 {
        let (rig, ch, plan) = (self.rig, self.ch, &self.phase.frames);
        let (strength, looping, dt) = (
            cleanup_strength(self.w),
            self.phase.looping,
            1.0 / self.phase.fps,
        );
        let times: Vec<f64> = plan.iter().map(|f| f.0).collect();
        let before = self.before;
        let shift = before.pos[before.len() - 1][rig.body] - before.pos[0][rig.body];
        let span = times[times.len() - 1] - times[0];
        let root_speed = flat(shift).length() / span.max(MIN_DURATION);
        // Planted: where the sources plant the foot by vote, or it is found planted in the
        // blend ([`contact_flags`]: before, and after a first pass, so that every contact the
        // figures see on the result is pinned), never so that a looping leg is planted
        // throughout ([`grow_planted`]).
        let mut planted: Vec<Vec<bool>> = (0..ch.legs.len())
            .map(|l| {
                let found = contact_flags(self.before_loop, plan.len(), &ch.legs[l], ch.scale);
                let mut p = self.voted[l].clone();
                grow_planted(&mut p, &found, looping);
                p
            })
            .collect();
        let [world_a, world_b] = &self.src.world;
        let raw: Vec<Vec<DVec3>> = (0..ch.legs.len())
            .map(|l| {
                let e = ch.legs[l].end();
                (0..plan.len())
                    .map(|i| {
                        let blended = world_a[i][e].lerp(world_b[i][e], self.w);
                        before.pos[i][e].lerp(blended, strength)
                    })
                    .collect()
            })
            .collect();
        // Where each leg can put its foot on each frame of the blend, at its target's height.
        let reach_on = |pos: &[Vec<DVec3>], l: usize| -> Vec<Option<cleanup::Reach>> {
            (pos.iter().zip(&raw[l]))
                .map(|(p, t)| cleanup::Reach::of(&ch.legs[l], p, t.dot(UP)))
                .collect()
        };
        let mut reach: Vec<Vec<Option<cleanup::Reach>>> = (0..ch.legs.len())
            .map(|l| reach_on(&before.pos, l))
            .collect();
        let unclean = frames.clone();
        let mut max_drop: f64 = 0.0;
        for pass in 0..CLEANUP_PASSES {
            let goals: Vec<LegGoal> = planted
                .iter()
                .zip(&raw)
                .map(|(p, t)| LegGoal {
                    planted: p.clone(),
                    target: t.clone(),
                })
                .collect();
            let ground =
                measure::ground_under(root_speed, cleanup::ground_velocity(&goals, &times));
            let goals: Vec<LegGoal> = (goals.into_iter().zip(&reach))
                .map(|(g, reach)| {
                    let pinned =
                        cleanup::pin(&g.planted, &g.target, reach, &times, looping, ground, shift);
                    let target = g
                        .target
                        .iter()
                        .zip(&pinned)
                        .map(|(t, p)| t.lerp(*p, strength))
                        .collect();
                    LegGoal { target, ..g }
                })
                .collect();
            *frames = unclean.clone();
            let drop = cleanup::clean(rig, &ch.legs, &goals, frames, ch.forward, dt, looping);
            max_drop = drop.iter().copied().fold(0.0, f64::max);
            // What a next pass would take (pins found again, contacts newly found) is left
            // unmeasured on the last.
            if pass + 1 == CLEANUP_PASSES {
                break;
            }
            let after = positions_track(rig, frames, dt, looping);
            let mut grew = false;
            for (l, leg) in ch.legs.iter().enumerate() {
                let e = leg.end();
                let short = (0..after.pos.len()).any(|i| {
                    planted[l][i]
                        && after.pos[i][e].distance(goals[l].target[i]) > PIN_MISS * ch.scale
                });
                if short {
                    let again = reach_on(&after.pos, l);
                    for (r, a) in reach[l].iter_mut().zip(again) {
                        *r = a.or(*r);
                    }
                    grew = true;
                }
            }
            for (l, p) in planted.iter_mut().enumerate() {
                let found = contact_flags(&after, plan.len(), &ch.legs[l], ch.scale);
                grew |= grow_planted(p, &found, looping);
            }
            if !grew {
                break;
            }
        }
        max_drop
    }
}

/// Join the frames the contact test finds planted (`found`, before clean-up or on a cleaned
/// pass) to a leg's `planted` frames (last = first on a loop), so that every contact the test
/// sees on the result is pinned; but not where that would leave a looping leg planted on
/// every frame: its one contact round the whole loop would be held by one pin, which has to
/// jump back by the loop's travel once a loop (Fox resampled at 15 keys a second by gltfpack,
/// `-af 15`, at 0.25: a front foot's swing of four frames, held low by the clean-up's eases,
/// was found planted and the next pass pinned that foot for the whole loop: 0.49 leg in one
/// frame, jerk ratio 1.33).
/// Returns whether any frame joined.
fn grow_planted(planted: &mut [bool], found: &[bool], looping: bool) -> bool {
    let joined: Vec<bool> = planted.iter().zip(found).map(|(p, f)| *p || *f).collect();
    let distinct = cleanup::distinct(planted.len(), looping);
    if looping && joined[..distinct].iter().all(|&x| x) {
        return false;
    }
    let grew = joined.iter().zip(planted.iter()).any(|(j, p)| *j && !*p);
    planted.copy_from_slice(&joined);
    grew
}

/// A looping leg that `planted` holds on every frame (last = first) is let go where its foot,
/// on `track` (the blend before clean-up, the loop's travel carried across its seam), moves
/// fastest: the run of frame steps round the fastest one that move more than the loop's mean
/// step. One contact round the whole loop would be held by one pin, which has to jump back by
/// the loop's travel once a loop: Bandai Namco's walk_not-confident, its left foot planted
/// through the whole of a stride it took as the loop, blended with its run at 0.25 had its
/// left foot jump 0.75 leg in one frame after clean-up.
fn keep_a_swing(planted: &mut [bool], track: &Track, foot: usize) {
    let n = planted.len().min(track.len());
    let distinct = cleanup::distinct(n, true);
    if distinct < 2 || !planted[..distinct].iter().all(|&x| x) {
        return;
    }
    // Step `i` goes from frame `i` to `i + 1`; the last one to the loop's last frame, its
    // first carried on by the loop's travel.
    let moves: Vec<f64> = (0..distinct)
        .map(|i| flat(track.pos[i + 1][foot] - track.pos[i][foot]).length())
        .collect();
    super::contacts::swing_where_fastest(&mut planted[..distinct], &moves);
    planted[n - 1] = planted[0];
}

/// Whether the sources plant leg `l` by weighted vote (the source of more weight decides; at
/// 0.5 either, which the naive blend's figures take, the blend itself [`even_vote`]) at their
/// times `t`, a frame standing for `half` (source seconds) either side of it so that a contact
/// shorter than a frame still plants the frame nearest it. The clean-up pins these frames and
/// the figures measure sliding there too (a naive blend's feet may never settle enough for the
/// contact test).
fn planted_by_vote(an: [&Analysis; 2], w: f64, l: usize, t: [f64; 2], half: [f64; 2]) -> bool {
    let x = |p: bool| if p { 1.0 } else { 0.0 };
    (1.0 - w) * x(an[0].planted(l, t[0], half[0])) + w * x(an[1].planted(l, t[1], half[1])) >= 0.5
}

/// The vote of two sources of equal weight: where both plant the foot, and of each run of frames
/// where only one does, the half next to a frame both plant (all of it between two such frames,
/// its middle half where it touches none), so that the blend's contact runs from about the mean
/// of the sources' touchdowns to the mean of their lift-offs (either source alone deciding
/// would plant the foot through the union of both contacts, much of it where the blended foot
/// already swings). `looping`: runs wrap round the plan.
fn even_vote(a: &[bool], b: &[bool], looping: bool) -> Vec<bool> {
    let n = a.len();
    let both: Vec<bool> = a.iter().zip(b).map(|(x, y)| *x && *y).collect();
    let one: Vec<bool> = a.iter().zip(b).map(|(x, y)| x != y).collect();
    let mut out = both.clone();
    // Frame `i` of the plan, wrapped on a loop.
    let at = |i: isize| -> Option<usize> {
        if (0..n as isize).contains(&i) {
            Some(i as usize)
        } else if looping && n > 0 {
            Some(i.rem_euclid(n as isize) as usize)
        } else {
            None
        }
    };
    if one.iter().all(|&x| x) {
        return a.to_vec();
    }
    // From the start of every run of `one` frames (on a loop, one that does not continue one
    // before it).
    for s in 0..n {
        if !one[s] || at(s as isize - 1).is_some_and(|p| one[p]) {
            continue;
        }
        let mut run = vec![s];
        while let Some(next) = at(*run.last().expect("a frame") as isize + 1) {
            if !one[next] || next == s {
                break;
            }
            run.push(next);
        }
        let before = at(s as isize - 1).is_some_and(|p| both[p]);
        let after = at(*run.last().expect("a frame") as isize + 1).is_some_and(|q| both[q]);
        let len = run.len();
        let keep: std::ops::Range<usize> = match (before, after) {
            (true, true) => 0..len,
            (true, false) => 0..len.div_ceil(2),
            (false, true) => len / 2..len,
            (false, false) => len / 4..(len - len / 4).max(len / 4 + 1),
        };
        for &j in &run[keep] {
            out[j] = true;
        }
    }
    out
}

/// `vote` per frame of the phase plan, each frame standing for half the way to its neighbours.
fn voted_on(plan: &[(f64, f64, f64)], vote: impl Fn([f64; 2], [f64; 2]) -> bool) -> Vec<bool> {
    (0..plan.len())
        .map(|j| {
            let (p, q) = (plan[j.saturating_sub(1)], plan[(j + 1).min(plan.len() - 1)]);
            vote(
                [plan[j].1, plan[j].2],
                [0.25 * (q.1 - p.1), 0.25 * (q.2 - p.2)],
            )
        })
        .collect()
}

/// Refuse a clip without a stride cycle, saying why.
fn walks(clip: &Clip, an: &Analysis, ch: &Character) -> anyhow::Result<()> {
    if an.cycles.is_some() {
        return Ok(());
    }
    let why = if ch.legs.is_empty() {
        "no legs were found in its skeleton".to_string()
    } else if an.stride < super::cycles::MIN_STRIDE {
        format!(
            "its feet travel {:.3} leg lengths forward and back (a T-pose, an idle or a gesture, not a walk)",
            an.stride
        )
    } else {
        "its feet do not repeat a stride".to_string()
    };
    anyhow::bail!(
        "clip {:?} has no stride cycle: {why}; --cycles none blends the clips whole on normalised time",
        clip.name
    )
}

/// `clips` analysed together, each as `closed` closes it into a loop where it stops short of one
/// ([`track::close_open_loop`](super::track::close_open_loop), once per clip), and as it is,
/// not looping, where its analysis finds a capture whose ends meet by chance
/// ([`Analysis::meets_by_chance`]); the clips as analysed are returned with it.
fn analysed<'c>(
    rig: &Rig,
    clips: &[&'c Clip],
    closed: &'c [Option<Clip>],
    method: CycleMethod,
) -> (Vec<&'c Clip>, Character, Vec<Analysis>) {
    let mut open = vec![false; clips.len()];
    loop {
        let taken: Vec<&Clip> = (clips.iter().zip(closed).zip(&open))
            .map(|((&clip, closed), &open)| match closed {
                Some(loop_) if !open => loop_,
                _ => clip,
            })
            .collect();
        let (ch, an) = analyze_as(rig, &taken, method, &open);
        let chance: Vec<usize> = (0..an.len()).filter(|&i| an[i].meets_by_chance).collect();
        if chance.is_empty() {
            return (taken, ch, an);
        }
        for i in chance {
            open[i] = true;
        }
    }
}

/// What `blend` finds in one clip alone (for `inspect`): the feet (their chains' end joints),
/// how far they stride (leg lengths), and its stride cycles (start and period, seconds), or
/// why blend refuses the clip.
pub struct Gait {
    pub feet: Vec<String>,
    pub stride: f64,
    pub cycles: anyhow::Result<Vec<(f64, f64)>>,
}

/// [`Gait`] of `clip`, analysed as `blend` analyses a clip (with the legs' default cycle
/// method), alone.
pub fn gait(rig: &Rig, clip: &Clip) -> Gait {
    let size = super::track::character_size(rig, &[clip]);
    let rig = &rig.carried_by(&[clip], size);
    let closed = [super::track::close_open_loop(rig, clip, size)];
    let (clips, ch, an) = analysed(rig, &[clip], &closed, CycleMethod::Legs);
    let (clip, an) = (clips[0], &an[0]);
    Gait {
        feet: ch.legs.iter().map(|l| rig.names[l.end()].clone()).collect(),
        stride: an.stride,
        cycles: walks(clip, an, &ch)
            .map(|_| an.cycles.as_ref().map_or(Vec::new(), |c| c.spans.clone())),
    }
}

/// Blend clip `a` with clip `b` (weight `opts.weight` on `b`).
/// Refused (unless `--cycles none`) when either clip has no stride cycle.
pub fn blend(rig: &Rig, a: &Clip, b: &Clip, opts: &BlendOptions) -> anyhow::Result<Blended> {
    let w = opts.weight;
    let size = super::track::character_size(rig, &[a, b]);
    let rig = &rig.carried_by(&[a, b], size);
    let closed = [a, b].map(|c| super::track::close_open_loop(rig, c, size));
    let (clips, ch, an) = analysed(rig, &[a, b], &closed, opts.cycles);
    let (a, b) = (clips[0], clips[1]);
    let (an_a, an_b) = (&an[0], &an[1]);
    if opts.cycles != CycleMethod::None {
        for (clip, an) in [(a, an_a), (b, an_b)] {
            walks(clip, an, &ch)?;
        }
    }
    let spans = [cycles_used(a, an_a), cycles_used(b, an_b)];
    // Each clip as the blend plays it alone (at weight 0 for A, 1 for B): its figures.
    let alone = [0.0, 1.0].map(|w| phase(a, b, [an_a, an_b], [&spans[0], &spans[1]], w));
    let phase = phase(a, b, [an_a, an_b], [&spans[0], &spans[1]], w);
    let mut src = sources(rig, &ch, [a, b], [an_a, an_b], &phase, w);
    // The sources' poses are mixed, then let go (the clean-up and the figures read their
    // positions): two copies of every frame fewer held through the clean-up.
    let [poses_a, poses_b] = std::mem::take(&mut src.poses);
    let mut frames: Vec<Pose> = (poses_a.iter().zip(&poses_b))
        .map(|(x, y)| mix(x, y, w))
        .collect();
    drop((poses_a, poses_b));
    let dt = 1.0 / phase.fps;
    let before = positions_track(rig, &frames, dt, false);
    let before_loop = track_of(before.pos.clone(), dt, phase.looping, rig.body);
    let vote = |l: usize, t: [f64; 2], half: [f64; 2]| planted_by_vote([an_a, an_b], w, l, t, half);
    let mut voted: Vec<Vec<bool>> = (0..ch.legs.len())
        .map(|l| match w == 0.5 {
            false => voted_on(&phase.frames, |t, half| vote(l, t, half)),
            true => {
                let one =
                    |s: usize| voted_on(&phase.frames, |t, half| an[s].planted(l, t[s], half[s]));
                even_vote(&one(0), &one(1), phase.looping)
            }
        })
        .collect();
    if phase.looping {
        for (flags, leg) in voted.iter_mut().zip(&ch.legs) {
            keep_a_swing(flags, &before, leg.end());
        }
    }
    let mut max_drop: f64 = 0.0;
    if opts.cleanup && !ch.legs.is_empty() && cleanup_strength(w) > 0.0 {
        let cleanup = Cleanup {
            rig,
            ch: &ch,
            phase: &phase,
            src: &src,
            before: &before,
            before_loop: &before_loop,
            voted: &voted,
            w,
        };
        max_drop = cleanup.run(&mut frames);
    }
    if src.fit != FloorTransform::IDENTITY {
        let back = src.fit.scaled(w).matrix().inverse();
        for pose in &mut frames {
            align::move_body(rig, pose, &back);
        }
    }
    let figures = Measured {
        rig,
        ch: &ch,
        joints: &src.joints,
        fps: phase.fps,
        w,
    };
    let taken = [Taken::of(a, an_a, &spans[0]), Taken::of(b, an_b, &spans[1])];
    let naive = figures.naive(&taken, phase.looping, &vote);
    let after = figures.of(&positions_track(rig, &frames, dt, phase.looping), &voted);
    let fig = [0, 1].map(|k| {
        figures.of(
            &figures.source([a, b][k], an[k].looping(), &alone[k], k),
            &[],
        )
    });
    let source_jerk = (1.0 - w) * fig[0].jerk + w * fig[1].jerk;
    let result = ResultReport {
        duration: phase.duration,
        frames: frames.len(),
        fps: phase.fps,
        looping: phase.looping,
        cycle_periods: phase.periods.clone(),
        warp_knots: phase.knots,
        before_cleanup: figures.of(&before_loop, &voted),
        after_cleanup: after,
        jerk_ratio: if source_jerk > 0.0 {
            after.jerk / source_jerk
        } else {
            1.0
        },
        max_root_drop: max_drop / ch.scale,
    };
    let [fig_a, fig_b] = fig;
    let report = Report {
        weight: w,
        cycle_method: opts.cycles,
        cleanup: opts.cleanup,
        leg_scale: ch.scale,
        forward: ch.forward.to_array(),
        legs: ch
            .legs
            .iter()
            .map(|l| LegReport {
                foot: l.name.clone(),
                side: l.side,
                length: l.length,
                chain: l.chain.iter().map(|&j| rig.names[j].clone()).collect(),
            })
            .collect(),
        clips: [
            clip_report(&ch, a, an_a, &spans[0], fig_a),
            clip_report(&ch, b, an_b, &spans[1], fig_b),
        ],
        alignment_degrees: src.fit.angle.to_degrees(),
        alignment_translation: src.fit.translation.to_array(),
        matched_travel: src.matched,
        naive,
        result,
    };
    Ok(Blended {
        times: phase.frames.iter().map(|f| f.0).collect(),
        poses: frames,
        report,
    })
}

/// The report's figures, all at the output rate.
struct Measured<'a> {
    rig: &'a Rig,
    ch: &'a Character,
    joints: &'a [usize],
    fps: f64,
    w: f64,
}

impl Measured<'_> {
    fn of(&self, track: &Track, expected: &[Vec<bool>]) -> Figures {
        let ch = self.ch;
        measure::figures(
            track,
            self.rig.body,
            self.joints,
            &ch.legs,
            ch.scale,
            expected,
        )
    }

    /// Source `k` (0: A, 1: B) of the blend as the blend plays it at weight `k` (`alone`, its
    /// phase plan there: the clip on its own cycles, each resampled to a whole number of
    /// output frames), so that the blend at weight 0 or 1 measures as its source. Sampled
    /// uniformly over the part the blend takes, a capture of several cycles at 30 samples a
    /// second measured 0.94-1.20 times its own jerk in its blend with itself at weight 0 (the
    /// samples fall at another fraction of a key there, and resampling smooths a capture's
    /// jitter by as much as a fifth: Bandai Namco's walk_sad 1.20); sampled from the clip's
    /// start, RobotExpressive's blend at weight 0 had a jerk ratio of 0.71, Fox's run with
    /// itself measured 1.11 where it is 1.20.
    fn source(&self, clip: &Clip, looping: bool, alone: &Phase, k: usize) -> Track {
        let poses: Vec<Pose> = (alone.frames.iter())
            .map(|f| pose_unwrapped(self.rig, clip, looping, [f.1, f.2][k]))
            .collect();
        positions_track(self.rig, &poses, 1.0 / alone.fps, alone.looping)
    }

    /// The two clips blended at normalised time: no sync, no alignment, no clean-up; its
    /// sliding measured where the sources plant a foot by `vote`.
    fn naive(
        &self,
        [a, b]: &[Taken; 2],
        looping: bool,
        vote: &dyn Fn(usize, [f64; 2], [f64; 2]) -> bool,
    ) -> Figures {
        let w = self.w;
        let (la, lb) = (a.length(), b.length());
        let dur = (1.0 - w) * la + w * lb;
        let n = ((dur * self.fps).round() as usize).max(1);
        let at = |i: usize| {
            let u = i as f64 / n as f64;
            (a.start + u * la, b.start + u * lb)
        };
        let poses: Vec<Pose> = (0..=n)
            .map(|i| {
                mix(
                    &a.clip.pose(self.rig, at(i).0),
                    &b.clip.pose(self.rig, at(i).1),
                    w,
                )
            })
            .collect();
        let half = [0.5 * la / n as f64, 0.5 * lb / n as f64];
        let expected: Vec<Vec<bool>> = (0..self.ch.legs.len())
            .map(|l| (0..=n).map(|i| vote(l, [at(i).0, at(i).1], half)).collect())
            .collect();
        self.of(
            &positions_track(self.rig, &poses, dur.max(MIN_DURATION) / n as f64, looping),
            &expected,
        )
    }
}

/// The part of a source clip the blend takes, which the naive blend it is compared with is
/// made of: a looping clip whole, another (a capture) over its cycles, so that its standing
/// start and stop do not count (CMU's start-walk-stop blended with itself measured a naive
/// blend of 0.0029 leg a frame of sliding against the blend's 0.0052 over the whole capture,
/// where both are the same cycle).
struct Taken<'c> {
    clip: &'c Clip,
    /// Start and end on the clip's timeline (seconds).
    start: f64,
    end: f64,
}

impl<'c> Taken<'c> {
    fn of(clip: &'c Clip, an: &Analysis, spans: &[(f64, f64)]) -> Taken<'c> {
        let looping = an.looping();
        let end = clip.start + clip.duration();
        let (start, end) = match (looping, spans.first(), spans.last()) {
            (false, Some(&(first, _)), Some(&(last, period))) => {
                (first.max(clip.start), (last + period).min(end))
            }
            _ => (clip.start, end),
        };
        Taken { clip, start, end }
    }

    fn length(&self) -> f64 {
        (self.end - self.start).max(0.0)
    }
}

/// A clip's part of the report: cycles found and used, contacts, figures.
fn clip_report(
    ch: &Character,
    clip: &Clip,
    an: &Analysis,
    spans: &[(f64, f64)],
    figures: Figures,
) -> ClipReport {
    ClipReport {
        name: clip.name.clone(),
        duration: clip.duration(),
        looping: an.looping(),
        cycles: an
            .cycles
            .as_ref()
            .map(|c| {
                c.spans
                    .iter()
                    .map(|&(start, period)| CycleReport { start, period })
                    .collect()
            })
            .unwrap_or_default(),
        synced_start: spans[0].0,
        contacts: ch
            .legs
            .iter()
            .zip(&an.contacts)
            .map(|(l, c)| ContactReport {
                foot: l.name.clone(),
                side: l.side,
                count: c.len(),
                intervals: c.iter().map(|c| (c.start, c.end)).collect(),
            })
            .collect(),
        figures,
    }
}

#[cfg(test)]
mod tests {
    use super::{grow_planted, keep_a_swing, tile, typical_stride};
    use crate::blend::contacts::Contact;
    use crate::blend::track::Track;
    use glam::DVec3;

    /// Cycles a stride apart, two strides apart and overlapping: each lasts to the next one's
    /// start, the two strides' gap cut in two.
    #[test]
    fn cycles_tile_the_clip() {
        let got = tile(&[(0.0, 1.0), (1.1, 1.0), (3.2, 1.0), (3.5, 1.0)]);
        let want = [
            (0.0, 1.1),
            (1.1, 1.05),
            (2.15, 1.05),
            (3.2, 1.0),
            (3.5, 1.0),
        ];
        assert_eq!(got.len(), want.len(), "{got:?}");
        for (g, w) in got.iter().zip(want) {
            assert!(
                (g.0 - w.0).abs() < 1e-12 && (g.1 - w.1).abs() < 1e-12,
                "{got:?}"
            );
        }
    }

    fn flags(s: &str) -> Vec<bool> {
        s.chars().map(|c| c == 'P').collect()
    }

    /// Found frames join a leg's contacts, but never so that a looping leg is planted on every
    /// frame (one pin round the whole loop); a clip that does not loop may stand on a foot.
    #[test]
    fn a_looping_leg_keeps_a_swing() {
        let mut p = flags("PPPPPPP....PPP");
        assert!(grow_planted(&mut p, &flags(".......PP....."), true));
        assert_eq!(p, flags("PPPPPPPPP..PPP"));
        // The rest of the swing too: the loop would have no swing left.
        assert!(!grow_planted(&mut p, &flags(".........PP..."), true));
        assert_eq!(p, flags("PPPPPPPPP..PPP"));
        let mut open = flags("PPPPPPP....PPP");
        assert!(grow_planted(&mut open, &flags(".......PPPP..."), false));
        assert_eq!(open, flags("PPPPPPPPPPPPPP"));
        let mut same = flags("PPP...");
        assert!(!grow_planted(&mut same, &flags("PP...."), true));
    }

    fn contacts(spans: &[(f64, f64)]) -> Vec<Contact> {
        spans
            .iter()
            .map(|&(start, end)| Contact { start, end })
            .collect()
    }

    /// Of a loop's strides (first leg's touchdown to its next, the other leg touching down once
    /// in each), the one of median length; not the first, which is long here.
    #[test]
    fn a_loop_of_several_strides_takes_a_typical_one() {
        let left = contacts(&[(0.9, 2.4), (2.6, 3.8), (4.0, 5.1), (5.5, 6.6), (6.9, 7.9)]);
        let right = contacts(&[(0.2, 1.3), (1.7, 3.1), (3.4, 4.4), (4.7, 5.9), (6.2, 7.2)]);
        // Strides from 0.9: 1.7, 1.4, 1.5, 1.4, and round the 7.5 s loop 1.5.
        let (start, period) = typical_stride(&[left.clone(), right], 7.5, 1.5).unwrap();
        assert!((start - 4.0).abs() < 1e-12 && (period - 1.5).abs() < 1e-12);
        // A right leg that does not touch down in a stride rules the stride out.
        let lame = contacts(&[(0.2, 1.3), (1.7, 3.1), (4.7, 5.9), (6.2, 7.2)]);
        let (start, period) = typical_stride(&[left.clone(), lame], 7.5, 1.5).unwrap();
        assert!((start - 4.0).abs() < 1e-12 && (period - 1.5).abs() < 1e-12);
        assert_eq!(typical_stride(&[left, vec![]], 7.5, 1.5), None);
        assert_eq!(typical_stride(&[], 7.5, 1.5), None);
    }

    /// A looping leg planted on every frame is let go where its foot moves fastest; one planted
    /// on some frames is left as it is.
    #[test]
    fn a_looping_leg_planted_throughout_is_let_go_where_it_swings() {
        // Ten frames and the first again, one loop travelling 1: the foot creeps 0.02 a step
        // except over steps 6-8, where it moves the rest of the way.
        let steps = [0.02, 0.02, 0.02, 0.02, 0.02, 0.02, 0.3, 0.4, 0.14, 0.02];
        let mut z = 0.0;
        let mut pos = vec![vec![DVec3::ZERO]];
        for s in steps {
            z += s;
            pos.push(vec![DVec3::new(0.0, 0.0, z)]);
        }
        let track = Track {
            start: 0.0,
            dt: 0.1,
            looping: false,
            pos,
            travel: DVec3::ZERO,
        };
        let mut planted = vec![true; 11];
        keep_a_swing(&mut planted, &track, 0);
        let free: Vec<usize> = (0..11).filter(|&i| !planted[i]).collect();
        assert_eq!(free, [6, 7, 8, 9]);
        let mut some = planted.clone();
        keep_a_swing(&mut some, &track, 0);
        assert_eq!(some, planted);
    }
}
