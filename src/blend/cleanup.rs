//! Foot clean-up: while a foot is planted in the blend, it is pinned to one spot of the ground
//! (the spot where the sources' feet, blended, are on average during that contact; on an
//! in-place clip the ground moves under it at the blend's treadmill speed) by analytic two-bone
//! IK on the leg, eased in and out over [`EASE_FRAMES`] frames that already aim at the pinned
//! spot (so the correction grows from nothing, with no jump at touchdown or lift-off); where a
//! leg cannot reach, the root is lowered just enough (eased the same way). Joints outside the
//! legs keep their rotations.

use super::legs::Leg;
use super::rig::{flat, Pose, Rig, UP};
use glam::{DMat4, DQuat, DVec3};

/// A thigh or shin shorter than this (scene units) is not bent by the IK.
const MIN_BONE: f64 = 1e-12;
/// A knee whose bones' cross product is below this fraction of their lengths' product (the
/// sine of the knee angle, unitless) is straight: it bends about the sideways axis.
const STRAIGHT_LEG: f64 = 1e-9;

/// Frames over which a contact's correction fades in before touchdown and out after lift-off.
pub const EASE_FRAMES: usize = 3;
/// A leg is stretched to at most this fraction of its hip-knee-ankle length.
pub const MAX_STRETCH: f64 = 0.999;

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

/// Pinned targets: within each run of planted frames the horizontal position of `target` minus
/// the ground's travel is replaced by its mean over the run (heights are kept). `times` are the
/// frames' times; on a looping clip (last frame = first) a run may wrap, the frames after the
/// wrap shifted by one loop (`loop_time`, `loop_shift`).
pub fn pin(
    planted: &[bool],
    target: &[DVec3],
    times: &[f64],
    looping: bool,
    ground: DVec3,
    loop_shift: DVec3,
) -> Vec<DVec3> {
    let n = planted.len();
    let loop_time = times[n - 1] - times[0];
    let mut out = target.to_vec();
    let distinct = if looping && n > 1 { n - 1 } else { n };
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
        for &(j, k) in &run {
            let spot = anchor + ground * (times[j] + k * loop_time) - k * loop_shift;
            out[j] = spot + UP * target[j].dot(UP);
            done[j] = true;
        }
    }
    // The frames easing in and out of a contact aim at its spot too (moving with the ground),
    // so that the correction grows from nothing to the pin instead of jumping at touchdown.
    let pinned = out.clone();
    for (j, o) in out.iter_mut().enumerate().take(distinct) {
        if planted[j] {
            continue;
        }
        let Some((i, k)) = nearest_planted(planted, j, distinct, looping) else {
            continue;
        };
        // `k` loops between frame `i` and frame `j` (-1, 0 or 1).
        let dt = times[j] - (times[i] + k * loop_time);
        let spot = flat(pinned[i] + k * loop_shift) + ground * dt;
        *o = spot + UP * target[j].dot(UP);
    }
    if looping && n > 1 {
        out[n - 1] = out[0] + loop_shift;
    }
    out
}

/// The planted frame nearest frame `j` within [`EASE_FRAMES`] (of `distinct` frames; on a loop
/// distances wrap), and how many loops lie between them: -1 when it is one loop earlier, 1 one
/// loop later.
fn nearest_planted(
    planted: &[bool],
    j: usize,
    distinct: usize,
    looping: bool,
) -> Option<(usize, f64)> {
    let mut best: Option<(usize, usize, f64)> = None;
    for d in 1..=EASE_FRAMES {
        for (step, sign) in [(j.checked_sub(d), -1i64), (Some(j + d), 1)] {
            let (i, k) = match step {
                Some(i) if i < distinct => (i, 0.0),
                _ if looping && distinct > 0 => {
                    let i = (j as i64 + sign * d as i64).rem_euclid(distinct as i64) as usize;
                    (i, sign as f64)
                }
                _ => continue,
            };
            if planted[i] && best.is_none_or(|b| d < b.1) {
                best = Some((i, d, k));
            }
        }
        if best.is_some() {
            break;
        }
    }
    best.map(|(i, _, k)| (i, k))
}

/// Influence of the correction per frame: 1 in contact, easing to 0 over [`EASE_FRAMES`].
/// On a looping clip (last frame = first) distances wrap.
pub fn influence(planted: &[bool], looping: bool) -> Vec<f64> {
    let n = planted.len();
    let period = if looping && n > 1 { n - 1 } else { 0 };
    (0..n)
        .map(|j| {
            let d = (0..n)
                .filter(|&i| planted[i])
                .map(|i| {
                    let d = i.abs_diff(j);
                    if period > 0 {
                        d.min(period - d % period)
                    } else {
                        d
                    }
                })
                .min();
            match d {
                Some(0) => 1.0,
                Some(d) if d <= EASE_FRAMES => {
                    let x = 1.0 - d as f64 / (EASE_FRAMES + 1) as f64;
                    x * x * (3.0 - 2.0 * x)
                }
                _ => 0.0,
            }
        })
        .collect()
}

/// Apply the clean-up to `frames` in place. Returns the root drop per frame (world units).
pub fn clean(
    rig: &Rig,
    legs: &[Leg],
    goals: &[LegGoal],
    frames: &mut [Pose],
    forward: DVec3,
    looping: bool,
) -> Vec<f64> {
    let n = frames.len();
    let alphas: Vec<Vec<f64>> = goals
        .iter()
        .map(|g| influence(&g.planted, looping))
        .collect();
    // Root drop where a planted leg cannot reach its target, spread with a tent over the ease.
    let mut need = vec![0.0f64; n];
    for (j, pose) in frames.iter().enumerate() {
        let p = rig.positions(pose);
        for ((leg, goal), alpha) in legs.iter().zip(goals).zip(&alphas) {
            let (Some([a, b, c]), true) = (leg.ik, alpha[j] > 0.0) else {
                continue;
            };
            let reach = MAX_STRETCH * ((p[b] - p[a]).length() + (p[c] - p[b]).length());
            let want = p[leg.end()].lerp(goal.target[j], alpha[j]);
            let ankle = want - (p[leg.end()] - p[c]);
            let d = p[a] - ankle;
            if d.length() <= reach {
                continue;
            }
            let h = d.dot(UP);
            let disc = h * h - d.length_squared() + reach * reach;
            let drop = if disc >= 0.0 { h - disc.sqrt() } else { h };
            need[j] = need[j].max(drop.max(0.0));
        }
    }
    let drop: Vec<f64> = (0..n)
        .map(|j| {
            (0..n)
                .map(|i| {
                    let d = i.abs_diff(j) as f64;
                    need[i] * (1.0 - d / (EASE_FRAMES + 1) as f64).max(0.0)
                })
                .fold(0.0, f64::max)
        })
        .collect();
    for (j, pose) in frames.iter_mut().enumerate() {
        if drop[j] > 0.0 {
            super::align::move_skeleton(rig, pose, &DMat4::from_translation(-UP * drop[j]));
        }
        for ((leg, goal), alpha) in legs.iter().zip(goals).zip(&alphas) {
            if alpha[j] > 0.0 {
                let world = rig.world(pose);
                let end = world[leg.end()].w_axis.truncate();
                let want = end.lerp(goal.target[j], alpha[j]);
                reach(rig, leg, pose, &world, want, forward);
            }
        }
    }
    drop
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
fn reach(rig: &Rig, leg: &Leg, pose: &mut Pose, world: &[DMat4], want: DVec3, forward: DVec3) {
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
        MAX_STRETCH * (lab + lcb),
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
    let mut axis = (pa - pb).cross(pc - pb);
    if axis.length() < STRAIGHT_LEG * lab * lcb {
        axis = UP.cross(forward);
    }
    let r1 = DQuat::from_axis_angle(axis.normalize(), wanted - current);
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
