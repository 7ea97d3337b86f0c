//! Foot clean-up: while a foot is planted in the blend, it is pinned to one spot of the ground
//! (the spot where the sources' feet, blended, are on average during that contact; on an
//! in-place clip the ground moves under it at the blend's treadmill speed) by analytic two-bone
//! IK on the leg, the knee bending to the side it bends to over the clip; the spot moved, where
//! the leg cannot reach it on every frame of the contact, to the nearest one it can ([`pin`]).
//! Around each contact the correction (pin minus the foot's own position) is carried on at the
//! rate it was changing, the rate faded out over [`EASE_SECONDS`] and the weight over that
//! before a touchdown and over [`RELEASE_SECONDS`] after a lift-off (a swing shorter than two
//! eases gets one cubic from one contact's correction to the next), so the foot keeps its
//! position and velocity where a pin starts or ends: no pop. Before the IK the root takes up
//! what the legs share, as smooth curves over the clip: a horizontal shift toward the planted
//! feet's corrections ([`root_shift`]) and a rise or fall that keeps each stance leg as long as
//! it was ([`root_rise`]), so that a nearly straight knee, where a small change of the hip-foot
//! distance turns the knee a lot, is left as the blend had it. Where a leg still cannot reach,
//! the root is lowered just enough (at most [`MAX_DROP`]), eased the same way. Joints outside
//! the legs keep their rotations.

use super::legs::Leg;
use super::rig::{flat, Pose, Rig, UP};
use glam::{DMat4, DQuat, DVec3};

/// A thigh or shin shorter than this (scene units) is not bent by the IK.
const MIN_BONE: f64 = 1e-12;
/// A knee whose bones' cross product is below this fraction of their lengths' product (the
/// sine of the knee angle, unitless) is straight: it bends about the leg's knee axis.
const STRAIGHT_LEG: f64 = 1e-9;

/// A leg is stretched to at most this fraction of its hip-knee-ankle length, or as far as the
/// pose being cleaned stretches it, up to [`FULL_STRETCH`].
pub const MAX_STRETCH: f64 = 0.999;

/// The most a leg that the blend already stretches past [`MAX_STRETCH`] is left stretched
/// (fraction of its hip-knee-ankle length): clamping it back to `MAX_STRETCH` bent knees that
/// the blend held at 176-179 degrees to 175 within a frame.
pub const FULL_STRETCH: f64 = 0.99995;

/// Time scale (seconds) of the root's horizontal shift: the weight of its third differences
/// is `(SHIFT_SECONDS / dt)^6` against one planted foot's correction (see [`smooth`]).
pub const SHIFT_SECONDS: f64 = 0.1;

/// Time scale (seconds) of the root's rise or fall that keeps the stance legs' lengths. At
/// 0.05 s (1.5 frames of a capture at 30 a second) the root's height followed each frame's
/// need, and that jitter moves every joint: Bandai Namco's walk_normal + walk_tired at 0.5 /
/// 0.75 had jerk ratios 1.17 / 1.23 with it, 1.15 / 1.21 with this (1.16 / 1.21 since the body,
/// not the root, is turned: [`super::align::move_body`]; CesiumMan's nearly straight knees,
/// with itself half a cycle later, 1.05-1.07 -> 1.06-1.08).
pub const RISE_SECONDS: f64 = 0.1;

/// A stance leg asks the root to rise or fall by at most this fraction of its length; a leg
/// whose target is farther off (a foot pinned far from where the blend put it) is left to the
/// IK.
const MAX_RISE: f64 = 0.05;

/// A stance leg asks the root to rise or fall only where its hip is above its target by at
/// least this cosine of the hip-target line's angle from the vertical (else a height change
/// hardly changes the leg's length).
const MIN_UPRIGHT: f64 = 0.3;

/// How long a leg may be (scene units) in a frame where it stands `own` from hip to ankle, its
/// bones `lab` and `lcb` long.
fn longest(lab: f64, lcb: f64, own: f64) -> f64 {
    (MAX_STRETCH * (lab + lcb)).max(own.min(FULL_STRETCH * (lab + lcb)))
}

/// What one leg should do: per output frame, whether it is planted and where its end should be.
pub struct LegGoal {
    pub planted: Vec<bool>,
    pub target: Vec<DVec3>,
}

/// Ground velocity: the mean horizontal velocity of the targets over steps where they are
/// planted, all legs together (zero for a clip with root motion, the treadmill speed in place).
pub fn ground_velocity(goals: &[LegGoal], times: &[f64]) -> DVec3 {
    let (mut sum, mut count) = (DVec3::ZERO, 0usize);
    for g in goals {
        for j in 0..times.len().saturating_sub(1) {
            if g.planted[j] && g.planted[j + 1] && times[j + 1] > times[j] {
                let d = g.target[j + 1] - g.target[j];
                sum += flat(d) / (times[j + 1] - times[j]);
                count += 1;
            }
        }
    }
    if count > 0 {
        sum / count as f64
    } else {
        DVec3::ZERO
    }
}

/// Where a leg can put its foot on one frame: within `radius` of `centre` horizontally (the
/// disc its hip, knee and ankle reach at the foot's target height; see [`Reach::of`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reach {
    pub centre: DVec3,
    pub radius: f64,
}

impl Reach {
    /// The disc a leg reaches on a frame where its joints stand at `p` (world positions), its
    /// foot to be at height `height`: the ankle as far from the hip as the IK stretches the leg
    /// ([`longest`]), the foot below the ankle as the frame has it. `None` for a leg without IK
    /// joints or a height it cannot reach.
    pub fn of(leg: &Leg, p: &[DVec3], height: f64) -> Option<Reach> {
        let [a, b, c] = leg.ik?;
        let length = longest(
            (p[b] - p[a]).length(),
            (p[c] - p[b]).length(),
            (p[c] - p[a]).length(),
        );
        // The foot at `want` puts the ankle at want - (end - ankle): the hip-ankle line must be
        // at most `length`.
        let d = p[a] + (p[leg.end()] - p[c]);
        let rise = height - d.dot(UP);
        let r2 = length * length - rise * rise;
        (r2 > 0.0).then(|| Reach {
            centre: flat(d),
            radius: r2.sqrt(),
        })
    }
}

/// Iterations of Dykstra's alternating projection (see [`reachable`]).
const REACH_ITERATIONS: usize = 200;

/// Bisection steps for the least widening of discs with no common point (see [`reachable`]).
const WIDEN_STEPS: usize = 40;

/// How far (scene units, as a fraction of the largest radius) a point may lie outside a disc
/// and count as inside (what the projection leaves after [`REACH_ITERATIONS`]).
const REACH_TOLERANCE: f64 = 1e-9;

/// The point nearest `x` (horizontal) inside every disc of `discs`: `x` itself where it is
/// inside them all. Where they have no common point (a contact longer than the leg can stay
/// planted through: Fox's run, whose front feet slide in the clip itself), the point nearest
/// `x` inside them all widened by the least amount that gives them one, so that the leg falls
/// short of it by as little as it can on its worst frame.
fn reachable(x: DVec3, discs: &[Reach]) -> DVec3 {
    let outside = |y: DVec3, widen: f64| {
        discs
            .iter()
            .map(|d| (y - d.centre).length() - d.radius - widen)
            .fold(0.0, f64::max)
    };
    let Some(scale) = discs.iter().map(|d| d.radius).reduce(f64::max) else {
        return x;
    };
    if outside(x, 0.0) <= 0.0 {
        return x;
    }
    // Dykstra's alternating projection onto the discs widened by `widen`.
    let project = |widen: f64| {
        let mut y = x;
        let mut carry = vec![DVec3::ZERO; discs.len()];
        for _ in 0..REACH_ITERATIONS {
            for (d, p) in discs.iter().zip(&mut carry) {
                let z = y + *p;
                let off = z - d.centre;
                let r = d.radius + widen;
                let next = if off.length() > r {
                    d.centre + off * (r / off.length())
                } else {
                    z
                };
                *p = z - next;
                y = next;
            }
        }
        y
    };
    let fits = |y: DVec3, widen: f64| outside(y, widen) <= REACH_TOLERANCE * scale;
    let y = project(0.0);
    if fits(y, 0.0) {
        return y;
    }
    // x itself fits once the discs are widened by its own distance outside them.
    let (mut lo, mut hi) = (0.0, outside(x, 0.0));
    for _ in 0..WIDEN_STEPS {
        let mid = 0.5 * (lo + hi);
        if fits(project(mid), mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    project(hi)
}

/// Pinned targets: within each run of planted frames the horizontal position of `target` minus
/// the ground's travel is replaced by its mean over the run (heights are kept), moved as little
/// as it takes to lie within the leg's `reach` on every frame of the run (a source whose planted
/// foot slides far asks for a spot the leg cannot reach at the contact's ends: Fox's run, its
/// front feet sliding a quarter leg, with straight front legs). `times` are the frames' times;
/// on a looping clip (last frame = first) a run may wrap, the frames after the wrap shifted by
/// one loop (`loop_time`, `loop_shift`).
pub fn pin(
    planted: &[bool],
    target: &[DVec3],
    reach: &[Option<Reach>],
    times: &[f64],
    looping: bool,
    ground: DVec3,
    loop_shift: DVec3,
) -> Vec<DVec3> {
    let n = planted.len();
    let loop_time = times[n - 1] - times[0];
    let mut out = target.to_vec();
    let distinct = distinct(n, looping);
    let mut done = vec![false; n];
    for s in 0..distinct {
        if !planted[s] || done[s] {
            continue;
        }
        // Walk back to the run's first frame (wrapping on a loop), then forward over it.
        let mut first = s;
        let mut back = 0;
        while back + 1 < distinct {
            let p = if first == 0 {
                if !looping {
                    break;
                }
                distinct - 1
            } else {
                first - 1
            };
            if !planted[p] {
                break;
            }
            first = p;
            back += 1;
        }
        let mut run = Vec::new();
        let mut j = first;
        let mut wraps = 0.0;
        loop {
            run.push((j, wraps));
            let next = j + 1;
            let (next, w) = if next >= distinct {
                if !looping {
                    break;
                }
                (0, wraps + 1.0)
            } else {
                (next, wraps)
            };
            if !planted[next] || run.len() >= distinct {
                break;
            }
            j = next;
            wraps = w;
        }
        let anchor: DVec3 = run
            .iter()
            .map(|&(j, k)| flat(target[j] + k * loop_shift) - ground * (times[j] + k * loop_time))
            .sum::<DVec3>()
            / run.len() as f64;
        // Each frame's disc carried back to the anchor's frame (the spot = anchor + travel).
        let discs: Vec<Reach> = run
            .iter()
            .filter_map(|&(j, k)| {
                let r = reach.get(j).copied().flatten()?;
                Some(Reach {
                    centre: r.centre - ground * (times[j] + k * loop_time) + k * flat(loop_shift),
                    ..r
                })
            })
            .collect();
        let anchor = reachable(anchor, &discs);
        for &(j, k) in &run {
            let spot = anchor + ground * (times[j] + k * loop_time) - k * loop_shift;
            out[j] = spot + UP * target[j].dot(UP);
            done[j] = true;
        }
    }
    if looping && n > 1 {
        out[n - 1] = out[0] + loop_shift;
    }
    out
}

/// The root is lowered at most this fraction of a leg's length (its chain's) for the leg to
/// reach its target; a target farther off is left short, the foot sliding rather than the body
/// dipping. Fox's run blended with itself asked for half a leg with its pins at the contacts'
/// mean spots (its front feet slide a quarter leg within a contact in the clip itself, and its
/// front legs stand straight), 0.14 with the spots its legs miss by least ([`pin`]); the
/// fixtures' other blends ask for at most 0.06.
pub const MAX_DROP: f64 = 0.1;

/// How long (seconds) the rate a contact's correction was changing at, carried on into the
/// swing, takes to fade out on either side of the contact, and the correction's weight before
/// it (after it: [`RELEASE_SECONDS`]); a swing shorter than two of these gets one cubic from
/// one contact's correction to the next instead.
pub const EASE_SECONDS: f64 = 0.125;

/// How long (seconds) a contact's correction takes to fade out into the swing after its
/// lift-off (its weight; the rate carried on fades over [`EASE_SECONDS`]). The jerk of a fade
/// goes with the correction over the fade's length cubed, and 0.125 s is under four frames of a
/// capture at 30 a second: Bandai Namco's walk_normal + walk_tired at 0.25 / 0.5 / 0.75 had jerk
/// ratios 1.23 / 1.31 / 1.36 with it, 1.14 / 1.20 / 1.26 with this. Longer fades turn nearly
/// straight knees for longer: CesiumMan's walk with itself half a cycle later goes from 1.13
/// to 1.14 at 0.25, and to 1.16 with 0.2 s before touchdowns too or with 0.25 s after.
pub const RELEASE_SECONDS: f64 = 0.2;

/// The root's drop at each frame: each frame's `need` spread over `ease` frames either side
/// with the same smoothstep (the largest share reaching a frame), so the root sinks and rises
/// without a kink; `looping`: across the seam of a loop whose last frame is its first. Only
/// frames less than `ease` away reach a frame (a share is 0 beyond), so each looks at those
/// alone: summing over every frame for every frame took 4.5 s of a 4-minute capture's blend.
fn spread_drop(need: &[f64], ease: f64, looping: bool) -> Vec<f64> {
    let n = need.len();
    let period = if looping && n > 1 { n - 1 } else { 0 };
    let window = ease.ceil() as usize;
    let near = |j: usize| {
        let around = |c: usize| c.saturating_sub(window)..(c + window + 1).min(n);
        let wrapped = (period > 0).then(|| [around(j + period), around(j.saturating_sub(period))]);
        std::iter::once(around(j))
            .chain(wrapped.into_iter().flatten())
            .flatten()
    };
    (0..n)
        .map(|j| {
            near(j)
                .map(|i| {
                    let x = (loop_distance(i, j, period) as f64 / ease).min(1.0);
                    need[i] * (1.0 - smoothstep(x))
                })
                .fold(0.0, f64::max)
        })
        .collect()
}

/// Frames between `i` and `j`, round a loop of `period` frames (0: none).
fn loop_distance(i: usize, j: usize, period: usize) -> usize {
    let d = i.abs_diff(j);
    match period {
        0 => d,
        _ => d.min(period - d % period),
    }
}

/// [`EASE_SECONDS`] in frames of `dt` seconds (at least one).
fn ease_frames(dt: f64) -> f64 {
    (EASE_SECONDS / dt).max(1.0)
}

/// 0 at 0, 1 at 1, with zero slope at both ends (`x` in [0, 1]).
pub fn smoothstep(x: f64) -> f64 {
    x * x * (3.0 - 2.0 * x)
}

/// A foot's correction on one frame: the offset that moves the foot onto its target, and how
/// much of it applies. A pin's correction fades out in the swing through `weight`, applied to
/// the leg's joint rotations, not to the foot's position: near a straight knee a small change
/// of the foot's distance from the hip turns the knee a lot, and a fading position made
/// CesiumMan's straight-legged walk bend and straighten its knees within a few frames.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Correction {
    pub offset: DVec3,
    pub weight: f64,
}

impl Correction {
    fn full(offset: DVec3) -> Correction {
        Correction {
            offset,
            weight: 1.0,
        }
    }

    /// The part of the offset that applies to the foot's position.
    pub fn applied(&self) -> DVec3 {
        self.offset * self.weight
    }
}

/// The correction (target minus the foot's own position `ends`) per frame: in contact, what
/// moves the foot onto its target; in the swing around it, the contact's first or last correction
/// carried on at the rate it was changing, that rate fading linearly over the ease window and
/// the weight with a smoothstep over it before a touchdown and over the release window after a
/// lift-off ([`RELEASE_SECONDS`]), so the foot's path keeps its position and velocity where a
/// pin starts or ends (no pop); between two contacts nearer than two ease windows, one cubic at
/// full weight.
/// `None` where no correction applies. On a looping clip (last frame = first) gaps wrap.
pub fn corrections(
    planted: &[bool],
    target: &[DVec3],
    ends: &[DVec3],
    dt: f64,
    looping: bool,
) -> Vec<Option<Correction>> {
    let n = planted.len();
    let distinct = distinct(n, looping);
    let off = |j: usize| target[j] - ends[j];
    let at = |j: usize, d: i64| wrap(j as i64 + d, distinct, looping);
    // The nearest planted frame in direction `dir` from `j`, and its distance in frames.
    let nearest = |j: usize, dir: i64| -> Option<(usize, usize)> {
        (1..distinct).find_map(|d| {
            at(j, dir * d as i64)
                .filter(|&i| planted[i])
                .map(|i| (i, d))
        })
    };
    let ease = ease_frames(dt);
    let release = (RELEASE_SECONDS / dt).max(ease);
    // The rate (per frame, going away from the contact) at which a contact's correction was
    // changing at its end frame `i`, one-sided (zero for a contact of one frame).
    let rate = |i: usize, inward: i64| {
        at(i, inward)
            .filter(|&k| planted[k])
            .map_or(DVec3::ZERO, |k| off(i) - off(k))
    };
    let mut out: Vec<Option<Correction>> = (0..distinct)
        .map(|j| {
            if planted[j] {
                return Some(Correction::full(off(j)));
            }
            let (back, ahead) = (nearest(j, -1), nearest(j, 1));
            if let (Some((i0, d0)), Some((i1, d1))) = (back, ahead) {
                let gap = (d0 + d1) as f64;
                if gap <= 2.0 * ease {
                    // A short swing: one cubic from the last correction to the next, matching
                    // both corrections and their rates.
                    let t = d0 as f64 / gap;
                    let (t2, t3) = (t * t, t * t * t);
                    return Some(Correction::full(
                        off(i0) * (2.0 * t3 - 3.0 * t2 + 1.0)
                            + rate(i0, -1) * gap * (t3 - 2.0 * t2 + t)
                            + off(i1) * (3.0 * t2 - 2.0 * t3)
                            - rate(i1, 1) * gap * (t3 - t2),
                    ));
                }
            }
            // A long swing: the neighbouring contact's correction, carried on at its rate over
            // the ease window, its weight fading out over that window before a touchdown and
            // over the release window after a lift-off.
            let fading: Vec<Correction> = [(back, -1i64), (ahead, 1)]
                .into_iter()
                .filter_map(|(found, inward)| {
                    let (i, d) = found?;
                    let x = d as f64 / if inward < 0 { release } else { ease };
                    // The rate fades over the ease window: the foot keeps its position and
                    // velocity where the pin ends, but a source whose planted foot slides fast
                    // is not carried far off (Fox's run, its front feet sliding a quarter leg
                    // a frame, was carried 0.7 leg), nor a foot held low and slow after its
                    // lift-off, where the contact test finds it planted (a weight and rate
                    // fading over 0.3 s after lift-offs slid 3e-3 leg a frame after clean-up
                    // on Bandai Namco's walk_normal + run_normal).
                    let carried = (1.0 - d as f64 / ease).max(0.0);
                    (x < 1.0).then(|| Correction {
                        offset: off(i) + rate(i, inward) * d as f64 * carried,
                        weight: 1.0 - smoothstep(x),
                    })
                })
                .collect();
            match fading[..] {
                [] => None,
                [one] => Some(one),
                _ => Some(Correction::full(
                    fading.iter().map(Correction::applied).sum(),
                )),
            }
        })
        .collect();
    if looping && n > 1 {
        out.push(out[0]);
    }
    out
}

/// Apply the clean-up to `frames` in place. Returns how far the root is lowered per frame
/// (world units; by [`root_rise`] and where a leg cannot reach).
pub fn clean(
    rig: &Rig,
    legs: &[Leg],
    goals: &[LegGoal],
    frames: &mut [Pose],
    forward: DVec3,
    dt: f64,
    looping: bool,
) -> Vec<f64> {
    let n = frames.len();
    let positions =
        |frames: &[Pose]| -> Vec<Vec<DVec3>> { frames.iter().map(|p| rig.positions(p)).collect() };
    let stance = |ends| Stance {
        legs,
        goals,
        ends,
        dt,
        looping,
    };
    let before = positions(frames);
    let shift = stance(&before).root_shift();
    move_roots(rig, frames, &shift);
    let shifted = positions(frames);
    let rise = stance(&shifted).root_rise();
    move_roots(rig, frames, &rise);
    let ends = positions(frames);
    // Per leg and frame: where the IK puts the foot, and how much of that pose applies.
    let wants: Vec<Vec<Option<(DVec3, f64)>>> = legs
        .iter()
        .zip(goals)
        .map(|(leg, g)| {
            let own: Vec<DVec3> = ends.iter().map(|p| p[leg.end()]).collect();
            corrections(&g.planted, &g.target, &own, dt, looping)
                .into_iter()
                .zip(&own)
                .map(|(c, e)| c.map(|c| (*e + c.offset, c.weight)))
                .collect()
        })
        .collect();
    let bend: Vec<DVec3> = legs
        .iter()
        .map(|leg| knee_axis(leg, &ends, forward))
        .collect();
    // Root drop where a leg cannot reach its target (in a contact or its ease).
    let mut need = vec![0.0f64; n];
    for (j, p) in ends.iter().enumerate() {
        for (leg, want) in legs.iter().zip(&wants) {
            let (Some([a, b, c]), Some((want, weight))) = (leg.ik, want[j]) else {
                continue;
            };
            let want = p[leg.end()].lerp(want, weight);
            let reach = longest(
                (p[b] - p[a]).length(),
                (p[c] - p[b]).length(),
                (p[c] - p[a]).length(),
            );
            let ankle = want - (p[leg.end()] - p[c]);
            let d = p[a] - ankle;
            if d.length() <= reach {
                continue;
            }
            let h = d.dot(UP);
            let disc = h * h - d.length_squared() + reach * reach;
            let drop = if disc >= 0.0 { h - disc.sqrt() } else { h };
            need[j] = need[j].max(drop.clamp(0.0, MAX_DROP * leg.length));
        }
    }
    let drop = spread_drop(&need, ease_frames(dt) + 1.0, looping);
    let lowered: Vec<DVec3> = drop.iter().map(|d| -UP * *d).collect();
    move_roots(rig, frames, &lowered);
    for (j, pose) in frames.iter_mut().enumerate() {
        for (l, (leg, want)) in legs.iter().zip(&wants).enumerate() {
            let Some((want, weight)) = want[j] else {
                continue;
            };
            let world = rig.world(pose);
            let unclean = leg.ik.map(|joints| joints.map(|k| (k, pose.local[k].r)));
            reach(rig, leg, pose, &world, want, bend[l]);
            if weight < 1.0 {
                // Part of the way: the leg's joints turned that part of the IK's turn.
                for (k, r) in unclean.into_iter().flatten() {
                    pose.local[k].r = r.slerp(pose.local[k].r, weight);
                }
            }
        }
    }
    drop.iter()
        .zip(&rise)
        .map(|(d, r)| (d - r.dot(UP)).max(0.0))
        .collect()
}

/// Move each frame's body ([`super::align::move_body`]) by its `offset` (world units).
fn move_roots(rig: &Rig, frames: &mut [Pose], offset: &[DVec3]) {
    for (pose, o) in frames.iter_mut().zip(offset) {
        if *o != DVec3::ZERO {
            super::align::move_body(rig, pose, &DMat4::from_translation(*o));
        }
    }
}

/// The legs' goals over a clip whose joints are at `ends` per frame (`dt` seconds apart; on a
/// loop the last frame repeats the first): what the root's curves are found from.
struct Stance<'a> {
    legs: &'a [Leg],
    goals: &'a [LegGoal],
    ends: &'a [Vec<DVec3>],
    dt: f64,
    looping: bool,
}

impl Stance<'_> {
    /// The smooth curve ([`smooth`], time scale `seconds`) through the values that `add`
    /// gives each distinct frame, as `(weight, weight x value)` sums.
    fn curve(&self, seconds: f64, add: impl FnOnce(usize, &mut [f64], &mut [DVec3])) -> Vec<DVec3> {
        let m = distinct(self.ends.len(), self.looping);
        let (mut weight, mut sum) = (vec![0.0f64; m], vec![DVec3::ZERO; m]);
        add(m, &mut weight, &mut sum);
        smooth(&weight, &sum, seconds / self.dt, self.looping)
    }

    /// The root's horizontal shift per frame (world units): a smooth curve
    /// ([`SHIFT_SECONDS`]) through the mean horizontal correction (target minus the foot's own
    /// position) of the feet planted at each frame. In single support it takes up the stance
    /// foot's correction, so the hip moves with it and the leg keeps its shape.
    fn root_shift(&self) -> Vec<DVec3> {
        self.curve(SHIFT_SECONDS, |m, weight, sum| {
            for (leg, g) in self.legs.iter().zip(self.goals) {
                for j in (0..m).filter(|&j| g.planted[j]) {
                    weight[j] += 1.0;
                    sum[j] += flat(g.target[j] - self.ends[j][leg.end()]);
                }
            }
        })
    }

    /// The root's rise (fall where negative) per frame (world units, along [`UP`]): a smooth
    /// curve ([`RISE_SECONDS`]) through the heights that keep each leg's hip-ankle distance as
    /// the blend had it while its foot is moved onto its target, in contact and in the eases
    /// around it (weighted by how much of the correction applies there). Each leg weighs by
    /// how straight it is, 1 / (1.0001 - extension): the nearer the knee is to straight, the
    /// more a change of the leg's length would turn it.
    fn root_rise(&self) -> Vec<DVec3> {
        self.curve(RISE_SECONDS, |m, weight, sum| {
            for (leg, g) in self.legs.iter().zip(self.goals) {
                self.leg_rises(leg, g, &mut weight[..m], &mut sum[..m]);
            }
        })
    }

    /// [`Stance::root_rise`]'s sums for one leg.
    fn leg_rises(&self, leg: &Leg, g: &LegGoal, weight: &mut [f64], sum: &mut [DVec3]) {
        let (ends, m) = (self.ends, weight.len());
        let Some([a, b, c]) = leg.ik else {
            return;
        };
        let own: Vec<DVec3> = ends.iter().map(|p| p[leg.end()]).collect();
        let corrections = corrections(&g.planted, &g.target, &own, self.dt, self.looping);
        for (j, correction) in corrections.iter().enumerate().take(m) {
            let (Some(correction), p) = (correction, &ends[j]) else {
                continue;
            };
            let length = (p[b] - p[a]).length() + (p[c] - p[b]).length();
            let kept = (p[c] - p[a]).length();
            let to = p[a] - (p[c] + correction.offset);
            let upright = UP.dot(to) / to.length();
            if !(length > 0.0 && upright >= MIN_UPRIGHT) {
                continue;
            }
            // The height change that makes the hip-target distance `kept` (to first order).
            let rise = (kept - to.length()) / upright;
            if rise.abs() > MAX_RISE * length {
                continue;
            }
            let w = correction.weight / (1.0001 - kept / length).max(1e-4);
            weight[j] += w;
            sum[j] += UP * (rise * w);
        }
    }
}

/// Frames of a clip of `n` that are distinct (a loop's last frame repeats its first).
pub fn distinct(n: usize, looping: bool) -> usize {
    if looping && n > 1 {
        n - 1
    } else {
        n
    }
}

/// Distinct frame `i` of `m`: wrapped round on a loop, `None` past either end otherwise.
fn wrap(i: i64, m: usize, looping: bool) -> Option<usize> {
    if looping {
        Some(i.rem_euclid(m as i64) as usize)
    } else {
        usize::try_from(i).ok().filter(|&i| i < m)
    }
}

/// The curve x over a clip's distinct frames that minimises sum_j (weight_j |x_j|^2 -
/// 2 x_j . sum_j) + lambda sum_j |x_{j+2} - 3 x_{j+1} + 3 x_j - x_{j-1}|^2 (the weighted least
/// squares through the values `sum_j / weight_j`, third differences wrapping on a loop: a
/// minimum-jerk curve, since the root carries every joint and the jerk it adds is what the
/// blend's jerk ratio counts), lambda = `frames^6` times the mean positive weight: `frames` is
/// the time scale of the smoothing in frames (with every frame at the mean weight, the curve
/// keeps half of a wave of `2 pi frames` frames and less of faster ones). The system is banded
/// (on a loop too, once its frames are taken in the order 0, m-1, 1, m-2, ...) and solved by a
/// banded Cholesky factorization in O(m), with a ridge of 1e-12 of the mean weight so that too
/// few weighted frames to fix a parabola still give the curve nearest zero. Zero where no frame
/// has a weight. On a loop the last frame repeats the first.
/// With second differences (stop 64's) Bandai Namco's captures had jerk ratios up to 0.03
/// higher (walk_tired + run_tired at 0.25 1.19 against 1.16).
fn smooth(weight: &[f64], sum: &[DVec3], frames: f64, looping: bool) -> Vec<DVec3> {
    let m = weight.len();
    let weighted = weight.iter().filter(|&&w| w > 0.0).count();
    let mut x = vec![DVec3::ZERO; m];
    if weighted > 0 && m >= 3 {
        let mean = weight.iter().sum::<f64>() / weighted as f64;
        let lambda = frames.powi(6) * mean;
        // Position of each frame in the band's order, and the band's half-width (four
        // consecutive frames lie within 6 of each other in the loop's order, 3 in order).
        let (at, half) = if looping {
            let zigzag = |j: usize| if j < m - j { 2 * j } else { 2 * (m - j) - 1 };
            ((0..m).map(zigzag).collect::<Vec<_>>(), 6)
        } else {
            ((0..m).collect(), 3)
        };
        let mut band = Band::new(m, half);
        for (j, w) in weight.iter().enumerate() {
            band.add(at[j], at[j], w + 1e-12 * mean);
        }
        let frame = |j: i64| wrap(j, m, looping);
        for c in 0..m as i64 {
            let Some(window) = jerk_window(c, frame) else {
                continue;
            };
            let terms = window.into_iter().zip(JERK);
            for (a, ca) in terms.clone() {
                for (b, cb) in terms.clone() {
                    band.add(at[a], at[b], lambda * ca * cb);
                }
            }
        }
        let mut rhs = vec![DVec3::ZERO; m];
        for (j, s) in sum.iter().enumerate() {
            rhs[at[j]] = *s;
        }
        band.factor();
        let solved = band.solve(rhs);
        for (j, x) in x.iter_mut().enumerate() {
            *x = solved[at[j]];
        }
    }
    if looping && m > 0 {
        x.push(x[0]);
    }
    x
}

/// The third difference's coefficients over four consecutive frames.
const JERK: [f64; 4] = [-1.0, 3.0, -3.0, 1.0];

/// Frames `c - 1 ..= c + 2` by `frame` (a distinct frame or `None`), if all four are frames.
fn jerk_window(c: i64, frame: impl Fn(i64) -> Option<usize>) -> Option<[usize; 4]> {
    Some([frame(c - 1)?, frame(c)?, frame(c + 1)?, frame(c + 2)?])
}

/// A symmetric positive definite band matrix (half-width `half`), its lower band stored row by
/// row, factored in place as L L^T.
struct Band {
    half: usize,
    /// Row i's entries at columns i - half ..= i.
    rows: Vec<f64>,
}

impl Band {
    fn new(n: usize, half: usize) -> Band {
        Band {
            half,
            rows: vec![0.0; n * (half + 1)],
        }
    }

    fn at(&self, i: usize, j: usize) -> usize {
        i * (self.half + 1) + self.half + j - i
    }

    /// Adds `v` at (i, j); entries above the diagonal are the symmetric ones below.
    fn add(&mut self, i: usize, j: usize, v: f64) {
        if j <= i {
            let k = self.at(i, j);
            self.rows[k] += v;
        }
    }

    fn factor(&mut self) {
        let n = self.rows.len() / (self.half + 1);
        for i in 0..n {
            for j in i.saturating_sub(self.half)..=i {
                let mut s = self.rows[self.at(i, j)];
                for k in i.saturating_sub(self.half)..j {
                    s -= self.rows[self.at(i, k)] * self.rows[self.at(j, k)];
                }
                let v = if i == j {
                    s.max(f64::MIN_POSITIVE).sqrt()
                } else {
                    s / self.rows[self.at(j, j)]
                };
                let k = self.at(i, j);
                self.rows[k] = v;
            }
        }
    }

    /// Solves L L^T x = b with the factor.
    fn solve(&self, mut b: Vec<DVec3>) -> Vec<DVec3> {
        let n = b.len();
        for i in 0..n {
            let s = (i.saturating_sub(self.half)..i)
                .fold(b[i], |s, k| s - b[k] * self.rows[self.at(i, k)]);
            b[i] = s / self.rows[self.at(i, i)];
        }
        for i in (0..n).rev() {
            let s = (i + 1..(i + self.half + 1).min(n))
                .fold(b[i], |s, k| s - b[k] * self.rows[self.at(k, i)]);
            b[i] = s / self.rows[self.at(i, i)];
        }
        b
    }
}

/// The side a leg's knee bends to over the clip (unit axis of the thigh-to-shin turn, weighted
/// by how far the knee bends in each frame of `positions`); sideways of `forward` for a leg
/// that never bends.
fn knee_axis(leg: &Leg, positions: &[Vec<DVec3>], forward: DVec3) -> DVec3 {
    let sideways = UP.cross(forward).try_normalize().unwrap_or(DVec3::X);
    let Some([a, b, c]) = leg.ik else {
        return sideways;
    };
    let sum: DVec3 = positions
        .iter()
        .map(|p| (p[a] - p[b]).cross(p[c] - p[b]))
        .sum();
    sum.try_normalize().unwrap_or(sideways)
}

fn rotation_of(m: &DMat4) -> DQuat {
    m.to_scale_rotation_translation().1
}

/// Turn joint `j` of `pose` by the world rotation `r` (about its own origin).
fn turn(rig: &Rig, pose: &mut Pose, world: &[DMat4], j: usize, r: DQuat) {
    let parent = rotation_of(&rig.parent_world(world, j));
    let l = &mut pose.local[j].r;
    *l = (parent.inverse() * r * parent * *l).normalize();
}

/// Two-bone IK: bend the knee for the hip-ankle distance, swing the hip to the target, and keep
/// the ankle's world orientation (so the foot below it moves rigidly).
fn reach(rig: &Rig, leg: &Leg, pose: &mut Pose, world: &[DMat4], want: DVec3, bend: DVec3) {
    let pos = |j: usize| world[j].w_axis.truncate();
    let Some([a, b, c]) = leg.ik else {
        return;
    };
    let (pa, pb, pc) = (pos(a), pos(b), pos(c));
    let target = want - (pos(leg.end()) - pc);
    let (lab, lcb) = ((pb - pa).length(), (pc - pb).length());
    if lab < MIN_BONE || lcb < MIN_BONE {
        return;
    }
    // The reach of the two bones: a thigh a thousand times its shin's length (or the other
    // way round) leaves no range to clamp into, and the leg is left as it is.
    let (shortest, longest) = (
        (lab - lcb).abs() * 1.001 + MIN_BONE,
        longest(lab, lcb, (pc - pa).length()),
    );
    if shortest > longest {
        return;
    }
    let lat = (target - pa).length().clamp(shortest, longest);
    let ankle_world = rotation_of(&world[c]);
    // Knee: the interior angle that puts the ankle at distance `lat` from the hip.
    let current = (pa - pb).angle_between(pc - pb);
    let wanted = ((lab * lab + lcb * lcb - lat * lat) / (2.0 * lab * lcb))
        .clamp(-1.0, 1.0)
        .acos();
    // Bend about the leg's own knee axis: a knee the source passes through straight (its bend
    // axis flipping for a frame) is measured round that axis past 180 degrees, not flipped.
    let cross = (pa - pb).cross(pc - pb);
    let (axis, current) = if cross.length() < STRAIGHT_LEG * lab * lcb {
        (bend, current)
    } else if cross.dot(bend) < 0.0 {
        (-cross.normalize(), std::f64::consts::TAU - current)
    } else {
        (cross.normalize(), current)
    };
    let r1 = DQuat::from_axis_angle(axis, wanted - current);
    turn(rig, pose, world, b, r1);
    let pc1 = pb + r1 * (pc - pb);
    // Hip: swing the ankle onto the target direction.
    let from = (pc1 - pa).normalize_or_zero();
    let to = (target - pa).normalize_or_zero();
    let r2 = if from == DVec3::ZERO || to == DVec3::ZERO {
        DQuat::IDENTITY
    } else {
        DQuat::from_rotation_arc(from, to)
    };
    turn(rig, pose, world, a, r2);
    // Ankle: keep its world orientation.
    let new_world = rig.world(pose);
    let parent = rotation_of(&rig.parent_world(&new_world, c));
    pose.local[c].r = (parent.inverse() * ankle_world).normalize();
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_drop_spread_over_its_window_is_the_spread_over_every_frame() {
        let mut lcg = crate::dev::synth::Lcg(0x9e37_79b9_7f4a_7c15);
        for case in 0..200 {
            let n = 1 + (lcg.unit() * 60.0) as usize;
            // A few frames need a drop; ease windows from under a frame to past the loop.
            let need: Vec<f64> = (0..n)
                .map(|_| if lcg.unit() < 0.2 { lcg.unit() } else { 0.0 })
                .collect();
            let ease = 0.5 + lcg.unit() * 30.0;
            let looping = case % 2 == 0;
            let period = if looping && n > 1 { n - 1 } else { 0 };
            let every: Vec<f64> = (0..n)
                .map(|j| {
                    (0..n)
                        .map(|i| {
                            let x = (loop_distance(i, j, period) as f64 / ease).min(1.0);
                            need[i] * (1.0 - smoothstep(x))
                        })
                        .fold(0.0, f64::max)
                })
                .collect();
            let windowed = spread_drop(&need, ease, looping);
            assert_eq!(
                windowed.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                every.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                "n {n} ease {ease} looping {looping}"
            );
        }
    }

    /// Corrections of a foot standing at the origin whose target on frame `j` is `j` units along x.
    fn ramp(planted: &[bool]) -> Vec<Option<DVec3>> {
        let n = planted.len();
        let target: Vec<DVec3> = (0..n).map(|j| DVec3::X * j as f64).collect();
        corrections(planted, &target, &vec![DVec3::ZERO; n], 1.0 / 24.0, false)
            .into_iter()
            .map(|c| c.map(|c| c.applied()))
            .collect()
    }

    #[test]
    fn corrections_carry_on_and_fade_without_a_jump() {
        // A long swing after frames 0-4: the correction goes on rising at 1 a frame, that rate
        // fading linearly over 3 frames (0.125 s at 24 fps) and the weight by a smoothstep
        // over 4.8 (the release, 0.2 s), and is gone after it.
        let along = |planted: &[bool]| -> Vec<f64> {
            ramp(planted)
                .iter()
                .map(|c| c.map_or(0.0, |v| v.x))
                .collect()
        };
        let mut planted = vec![false; 16];
        planted[..5].fill(true);
        let c = along(&planted);
        assert_eq!(&c[..5], &[0.0, 1.0, 2.0, 3.0, 4.0]);
        for d in 1..5 {
            let carried = (1.0 - d as f64 / 3.0).max(0.0);
            let fade = 1.0 - smoothstep(d as f64 / 4.8);
            assert!((c[4 + d] - (4.0 + d as f64 * carried) * fade).abs() < 1e-12);
        }
        assert!(c[9..].iter().all(|&x| x == 0.0));
        // Before a touchdown at frame 11 (contact 11-15) weight and rate fade over 3 frames.
        let mut planted = vec![false; 16];
        planted[11..].fill(true);
        let c = along(&planted);
        for d in 1..3 {
            let x = d as f64 / 3.0;
            let fade = 1.0 - smoothstep(x);
            assert!((c[11 - d] - (11.0 - d as f64 * (1.0 - x)) * fade).abs() < 1e-12);
        }
        assert!(c[..9].iter().all(|&x| x == 0.0));
        // The fade is in the weight (applied to the leg's joint rotations); the offset is the
        // carried-on correction in full.
        let mut planted = vec![false; 12];
        planted[..5].fill(true);
        let target: Vec<DVec3> = (0..12).map(|j| DVec3::X * j as f64).collect();
        let full = corrections(&planted, &target, &[DVec3::ZERO; 12], 1.0 / 24.0, false);
        assert_eq!(full[4].unwrap().weight, 1.0);
        let c5 = full[5].unwrap();
        assert!((c5.offset.x - (4.0 + 2.0 / 3.0)).abs() < 1e-12);
        assert!((c5.weight - (1.0 - smoothstep(1.0 / 4.8))).abs() < 1e-12);
        // A swing of one frame between two contacts: the cubic through both, matching rates.
        let planted = [true, true, true, false, true, true];
        let c = ramp(&planted);
        assert!((c[3].unwrap().x - 3.0).abs() < 1e-12);
    }

    #[test]
    fn a_pin_moves_into_the_leg_s_reach_or_as_near_as_it_can() {
        let disc = |x: f64, radius: f64| Reach {
            centre: DVec3::X * x,
            radius,
        };
        // Inside every disc: the pin stays where it is, to the bit.
        let x = DVec3::new(0.7, 0.0, 0.2);
        assert_eq!(reachable(x, &[disc(0.0, 1.0), disc(1.5, 1.0)]), x);
        // Outside: the nearest point of the discs' common part (their lens starts at 0.5).
        let y = reachable(DVec3::X * -2.0, &[disc(0.0, 1.0), disc(1.5, 1.0)]);
        assert!((y - DVec3::X * 0.5).length() < 1e-6, "{y}");
        // No common part (a contact longer than the leg can stay planted through): the point
        // that falls short of both by as little as it can, halfway.
        let y = reachable(DVec3::ZERO, &[disc(0.0, 1.0), disc(4.0, 1.0)]);
        assert!((y - DVec3::X * 2.0).length() < 1e-6, "{y}");
    }

    #[test]
    fn smooth_curves_follow_lines_and_stay_at_zero_without_weights() {
        // Values on a line at every frame: third differences of a line are zero, so the
        // curve is the line itself at any smoothing.
        let m = 12;
        let line = |j: usize| DVec3::new(0.5 * j as f64 - 1.0, 0.0, 2.0 - 0.1 * j as f64);
        let sum: Vec<DVec3> = (0..m).map(|j| line(j) * 3.0).collect();
        let x = smooth(&[3.0; 12], &sum, 4.0, false);
        assert!((0..m).all(|j| (x[j] - line(j)).length() < 1e-9), "{x:?}");
        // On a loop, the same value on a few frames only: a constant has no third differences,
        // so the curve is that value everywhere (nothing pulls the unweighted frames to zero).
        let mut weight = vec![0.0; m];
        let mut sum = vec![DVec3::ZERO; m];
        for j in [2, 3, 8, 9] {
            weight[j] = 1.0;
            sum[j] = DVec3::X;
        }
        let x = smooth(&weight, &sum, 1.0, true);
        assert_eq!(x.len(), m + 1, "a loop's last frame repeats its first");
        assert_eq!(x[m], x[0]);
        assert!((0..m).all(|j| (x[j].x - 1.0).abs() < 1e-9), "{x:?}");
        // No weight anywhere: no shift.
        let x = smooth(&[0.0; 12], &[DVec3::ZERO; 12], 2.0, false);
        assert!(x.iter().all(|v| *v == DVec3::ZERO));
    }

    #[test]
    fn smooth_curves_solve_their_normal_equations() {
        // Uneven weights (some frames none) and values, on a loop and not: the banded solve
        // (the loop's frames reordered 0, m-1, 1, m-2, ...) satisfies W x + lambda D^T D x = s,
        // D the third differences.
        let mut rng = crate::synth::Lcg(7);
        for looping in [false, true] {
            let m = 61;
            let weight: Vec<f64> = (0..m)
                .map(|_| {
                    if rng.unit() < 0.3 {
                        0.0
                    } else {
                        rng.unit() * 5.0
                    }
                })
                .collect();
            let sum: Vec<DVec3> = (0..m)
                .map(|_| DVec3::new(rng.unit(), rng.unit(), rng.unit()) - 0.5)
                .collect();
            let frames = 2.5;
            let x = smooth(&weight, &sum, frames, looping);
            let weighted = weight.iter().filter(|&&w| w > 0.0).count() as f64;
            let lambda = frames.powi(6) * weight.iter().sum::<f64>() / weighted;
            let mut y: Vec<DVec3> = (0..m).map(|j| x[j] * weight[j]).collect();
            for c in 0..m as i64 {
                let Some([p, q, r, t]) = jerk_window(c, |j| wrap(j, m, looping)) else {
                    continue;
                };
                let d = (x[t] - 3.0 * x[r] + 3.0 * x[q] - x[p]) * lambda;
                y[p] -= d;
                y[q] += 3.0 * d;
                y[r] -= 3.0 * d;
                y[t] += d;
            }
            let worst = (0..m).map(|j| (y[j] - sum[j]).length()).fold(0.0, f64::max);
            assert!(worst < 1e-9, "looping {looping}: residual {worst}");
            assert_eq!(x.len(), if looping { m + 1 } else { m });
        }
    }
}
