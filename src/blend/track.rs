//! A clip sampled for analysis: world positions of every node at a fixed rate.
//!
//! A looping clip (last pose equal to the first, root motion aside) is sampled over one period
//! without repeating its first frame, and frame indices wrap around; any other clip is sampled
//! from its first to its last key.

use super::rig::{flat, push_key, Clip, Interp, Path, Pose, Rig};
use glam::DVec3;

/// Smallest size (scene units) a skeleton is given, so that a collapsed rest pose still scales
/// every tolerance.
const MIN_SIZE: f64 = 1e-9;

/// Analysis rate floor, in samples per second (key rates above it are kept).
pub const MIN_RATE: f64 = 120.0;

/// How close the last pose must come to the first for a clip to loop: the largest joint
/// displacement relative to the root, over the character's size.
pub const LOOP_TOLERANCE: f64 = 0.03;

/// Longest seam (in key spacings) between a clip's last key and its first pose that
/// [`close_open_loop`] closes: FBX2glTF's 60 per second resample of a run Blender exported on
/// its 24 frames a second, one frame short of the loop, ends 2.5 spacings short.
pub const MAX_SEAM_STEPS: f64 = 3.0;

/// Longest seam in seconds that [`close_open_loop`] closes, however fine the keys (where it
/// is longer than [`MAX_SEAM_STEPS`] key spacings): one spacing of the coarsest bake read as
/// animation, 12 keys a second (animation on twos), as a loop so baked and then resampled
/// finer keeps it (Blender's every-other-frame FBX through FBX2glTF's 60 per second bake;
/// Fox's run so: 4.3 spacings at 60 a second, 8.6 at 120).
pub const MAX_SEAM_SECONDS: f64 = 1.0 / 12.0;

/// How well the motion at a clip's ends must explain its seam for [`close_open_loop`]: the
/// worst joint's miss within this part of the largest joint step there (or within
/// [`LOOP_TOLERANCE`], or within the distance the fastest joint covers across the seam: see
/// [`close_open_loop`]). Loops baked short measure 0.09-0.28 (Blender's every-other-frame
/// samples at 12 a second, FBX2glTF's at 60); clips that do not loop, 2.7 and more, save a
/// jump that lands where it took off (0.41).
pub const SEAM_FIT: f64 = 1.0 / 3.0;

pub struct Track {
    pub start: f64,
    pub dt: f64,
    pub looping: bool,
    /// World positions, frame by frame.
    pub pos: Vec<Vec<DVec3>>,
    /// On a loop, the root's horizontal travel from the first frame to where the loop comes
    /// back to it (the frame after the last); zero otherwise.
    pub travel: DVec3,
}

impl Track {
    pub fn new(rig: &Rig, clip: &Clip, looping: bool) -> Track {
        let rate = clip.key_rate.max(MIN_RATE);
        let dur = clip.duration();
        let intervals = ((dur * rate).round() as usize).max(1);
        let dt = if dur > 0.0 {
            dur / intervals as f64
        } else {
            1.0 / rate
        };
        let pos = (0..=intervals)
            .map(|i| rig.positions(&clip.pose(rig, clip.start + i as f64 * dt)))
            .collect();
        Track::closed(clip.start, dt, looping, pos, rig.body)
    }

    /// The track of frames `pos` of joint positions, `dt` apart from `start`, the last frame
    /// the first again one loop on: on a loop that repeated frame is dropped, so speeds and
    /// steps at the ends wrap as it plays, and kept as the loop's travel (of joint `root`);
    /// otherwise every frame is kept.
    pub fn closed(
        start: f64,
        dt: f64,
        looping: bool,
        mut pos: Vec<Vec<DVec3>>,
        root: usize,
    ) -> Track {
        let mut travel = DVec3::ZERO;
        if looping {
            let back = pos.pop().expect("a loop's frames and its repeated one");
            travel = flat(back[root] - pos[0][root]);
        }
        Track {
            start,
            dt,
            looping,
            pos,
            travel,
        }
    }

    pub fn len(&self) -> usize {
        self.pos.len()
    }

    pub fn is_empty(&self) -> bool {
        self.pos.is_empty()
    }

    pub fn duration(&self) -> f64 {
        self.len() as f64 * self.dt - if self.looping { 0.0 } else { self.dt }
    }

    pub fn time(&self, i: usize) -> f64 {
        self.start + i as f64 * self.dt
    }

    /// Frame `i + k`, wrapped for a looping track and clamped otherwise.
    pub fn step(&self, i: usize, k: isize) -> usize {
        let n = self.len() as isize;
        let j = i as isize + k;
        if self.looping {
            j.rem_euclid(n) as usize
        } else {
            j.clamp(0, n - 1) as usize
        }
    }

    /// Horizontal move of node `j` from frame `i` to the next (a loop's last frame to its first
    /// carried on by the loop's travel).
    pub fn step_move(&self, i: usize, j: usize) -> DVec3 {
        let k = (i + 1) % self.len();
        let seam = if k == 0 { self.travel } else { DVec3::ZERO };
        flat(self.pos[k][j] - self.pos[i][j]) + seam
    }

    /// Velocity of node `j` at frame `i` (central difference; on a loop, a neighbour across the
    /// seam carried on by the loop's travel: a clip with root motion looped at its last frame
    /// had its feet there move back by the whole loop's travel in two frames).
    pub fn velocity(&self, i: usize, j: usize) -> DVec3 {
        let (a, b) = (self.step(i, -1), self.step(i, 1));
        if self.looping {
            let seam = |wrapped: bool| if wrapped { self.travel } else { DVec3::ZERO };
            let d = (self.pos[b][j] + seam(b < i)) - (self.pos[a][j] - seam(a > i));
            return d / (2.0 * self.dt);
        }
        let span = (b as f64 - a as f64).max(1.0);
        (self.pos[b][j] - self.pos[a][j]) / (span * self.dt)
    }
}

/// Whether `clip` loops: its last pose equals its first, translations of the skeleton root's
/// descendants compared relative to the root (root motion may move on).
pub fn loops(rig: &Rig, clip: &Clip, size: f64) -> bool {
    if clip.duration() <= 0.0 {
        return false;
    }
    let a = rig.positions(&clip.pose(rig, clip.start));
    let b = rig.positions(&clip.pose(rig, clip.end));
    let (ra, rb) = (a[rig.body], b[rig.body]);
    let worst = (0..rig.len())
        .filter(|&j| rig.carries(j))
        .map(|j| ((a[j] - ra) - (b[j] - rb)).length())
        .fold(0.0, f64::max);
    worst <= LOOP_TOLERANCE * size
}

/// `clip` closed into a loop where its last key stops short of its first pose (an exclusive
/// end, as a loop resampled on a grid that its period does not fit leaves it: Blender's
/// re-export of Fox's run, 1.158 s on a 120 per second grid, keys every 1/24 s to 1.125 s; or
/// as a cycle is exported without the key that repeats its first, so that it plays without a
/// doubled frame: Fox's walk so, 17 keys at 24 a second, one spacing short). The skeleton's
/// joints (relative to the root, as [`loops`]) must come back to the first pose across a seam
/// of `f` key spacings at the mean of their velocities at the two ends (the last key step and
/// the first: a seam crossed at the speed the motion leaves and comes back with; least squares
/// over the joints; at most [`MAX_SEAM_STEPS`] spacings or [`MAX_SEAM_SECONDS`]), the worst
/// joint within [`SEAM_FIT`] of the largest joint step there, within [`LOOP_TOLERANCE`], or
/// within what the fastest joint covers across the seam (`f` times the largest step: a miss
/// smaller than the motion across the seam, whatever the key rate; Fox's walk one spacing
/// short misses by 0.52 of that where a paw touches down in the seam, RobotExpressive's walk
/// at 12 a second resampled at 60 by 0.86, while a jump that lands where it took off misses
/// by 4.3). Every channel then gets a key `f` spacings after the clip's end: its first value
/// again, or, for a translation that carrying on takes nearer its last key than its first
/// (root motion), its last step's value carried on, so that the loop moves on. None when the
/// clip loops already, has three key spacings or fewer, or does not come round so (Blender's
/// Fox run: f = 0.58, the true seam 0.79; its every-other-frame samples of the walk at 12 a
/// second: 0.42, true 0.5, the worst joint 0.22 of a step off; FBX2glTF's run at 60 a second:
/// 1.96, true 2.5).
pub fn close_open_loop(rig: &Rig, clip: &Clip, size: f64) -> Option<Clip> {
    let step = 1.0 / clip.key_rate;
    let (start, end) = (clip.start, clip.end);
    if clip.duration().partial_cmp(&(3.0 * step)) != Some(std::cmp::Ordering::Greater)
        || loops(rig, clip, size)
    {
        return None;
    }
    let at = |t: f64| rig.positions(&clip.pose(rig, t));
    let (first, second) = (at(start), at(start + step));
    let (last, before) = (at(end), at(end - step));
    let joints: Vec<usize> = (0..rig.len()).filter(|&j| rig.carries(j)).collect();
    // Per joint: the seam (last to first), the mean of the ends' key steps, the larger step.
    let parts: Vec<(DVec3, DVec3, f64)> = (joints.iter())
        .map(|&j| {
            let rel = |p: &[DVec3]| p[j] - p[rig.body];
            let (out, back) = (rel(&last) - rel(&before), rel(&second) - rel(&first));
            let seam = rel(&first) - rel(&last);
            (seam, 0.5 * (out + back), out.length().max(back.length()))
        })
        .collect();
    let (num, den) = (parts.iter()).fold((0.0, 0.0), |(n, d), (seam, v, _)| {
        (n + seam.dot(*v), d + v.dot(*v))
    });
    let f = num / den;
    if !(f > 0.0 && f * step <= (MAX_SEAM_STEPS * step).max(MAX_SEAM_SECONDS)) {
        return None;
    }
    let worst = (parts.iter())
        .map(|(seam, v, _)| (*seam - f * *v).length())
        .fold(0.0, f64::max);
    let largest_step = parts.iter().map(|p| p.2).fold(0.0, f64::max);
    if worst > (LOOP_TOLERANCE * size).max(SEAM_FIT.max(f) * largest_step) {
        return None;
    }
    let mut closed = clip.clone();
    for c in &mut closed.channels {
        let w = c.width;
        let (mut a, mut b, mut p) = (vec![0.0; w], vec![0.0; w], vec![0.0; w]);
        c.sample(start, &mut a);
        c.sample(end, &mut b);
        c.sample(end - step, &mut p);
        let next: Vec<f64> = b.iter().zip(&p).map(|(b, p)| b + f * (b - p)).collect();
        let dist =
            |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(x, y)| (x - y).powi(2)).sum::<f64>();
        let moves_on = c.path == Path::Translation && dist(&next, &a) > dist(&next, &b);
        let value = if moves_on { next } else { a };
        let cubic = c.interp == Interp::Cubic;
        push_key(&mut c.times, &mut c.values, cubic, end + f * step, &value);
    }
    closed.end = end + f * step;
    Some(closed)
}

/// A skeleton stands when its height span is more than this share of its width (see
/// [`Extent`]).
const STANDS: f64 = 0.25;

/// Share of the skeleton's joints whose horizontal distance from their mean sets its width.
const WIDTH_SHARE: f64 = 0.9;

/// How far the skeleton's joints spread in one pose, the same however it heads.
struct Extent {
    /// Height span.
    height: f64,
    /// Twice the horizontal distance from the joints' mean within which [`WIDTH_SHARE`] of them
    /// lie: a root joint left at the origin far from the body does not widen it. By each
    /// axis's span, Bandai Namco's dataset-2 walk_active (joint_Root at the origin, the hips
    /// 504 cm from it) was 541 cm long at its first frame, did not stand, and took its rest
    /// pose's 432 cm for its size, or 119 cm beside a clip turned by 37 degrees.
    width: f64,
    /// Largest horizontal distance between two joints.
    span: f64,
}

/// The [`Extent`] of the skeleton's joints in `pose`.
fn extent(rig: &Rig, pose: &Pose) -> Extent {
    let p: Vec<DVec3> = (rig.positions(pose).into_iter().enumerate())
        .filter(|&(j, _)| rig.skeleton[j])
        .map(|(_, p)| p)
        .collect();
    if p.is_empty() {
        return Extent {
            height: 0.0,
            width: 0.0,
            span: 0.0,
        };
    }
    let mean = p.iter().map(|&q| flat(q)).sum::<DVec3>() / p.len() as f64;
    let mut out: Vec<f64> = p.iter().map(|&q| (flat(q) - mean).length()).collect();
    out.sort_by(f64::total_cmp);
    let span = (p.iter())
        .flat_map(|a| p.iter().map(move |b| flat(*a - *b).length()))
        .fold(0.0, f64::max);
    let (lo, hi) = (p.iter()).fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), q| {
        (lo.min(q.y), hi.max(q.y))
    });
    Extent {
        height: (hi - lo).max(0.0),
        width: 2.0 * out[((out.len() - 1) as f64 * WIDTH_SHARE).round() as usize],
        span,
    }
}

/// The height span of a skeleton of extent `e` where it stands ([`STANDS`]).
fn standing(e: &Extent) -> Option<f64> {
    (e.height > STANDS * e.width.max(e.height)).then_some(e.height)
}

/// The size of the skeleton in `pose`: its height span where it stands ([`STANDS`]), else its
/// largest extent.
pub fn size(rig: &Rig, pose: &Pose) -> f64 {
    size_of(&extent(rig, pose))
}

/// [`size`] of a skeleton of extent `e`.
fn size_of(e: &Extent) -> f64 {
    standing(e).unwrap_or_else(|| e.span.max(e.height).max(MIN_SIZE))
}

/// The character's size: its height span in the rest pose; where the rest pose does not stand
/// (a capture's offsets laid along each joint's own axis, as Bandai Namco's are: 457 cm
/// across, the figure 131 cm tall as it runs), the tallest the clips stand at their first
/// frames; where none does, the rest pose's largest extent.
pub fn character_size(rig: &Rig, clips: &[&Clip]) -> f64 {
    let rest = extent(rig, &rig.rest);
    standing(&rest)
        .or_else(|| {
            (clips.iter())
                .filter_map(|c| standing(&extent(rig, &c.pose(rig, c.start))))
                .reduce(f64::max)
        })
        .unwrap_or_else(|| size_of(&rest))
}

/// The pose at `t` on an endless timeline: a looping clip repeats, its translations carried on
/// by the displacement of each loop (root motion keeps going).
pub fn pose_unwrapped(rig: &Rig, clip: &Clip, looping: bool, t: f64) -> Pose {
    let dur = clip.duration();
    if !looping || dur <= 0.0 {
        return clip.pose(rig, t);
    }
    let k = ((t - clip.start) / dur).floor();
    let local_t = t - k * dur;
    let mut pose = clip.pose(rig, local_t.clamp(clip.start, clip.end));
    if k != 0.0 {
        for c in clip.channels.iter().filter(|c| c.path == Path::Translation) {
            let (mut a, mut b) = ([0.0; 3], [0.0; 3]);
            c.sample(clip.start, &mut a);
            c.sample(clip.end, &mut b);
            let d = DVec3::from_array(b) - DVec3::from_array(a);
            pose.local[c.node].t += k * d;
        }
    }
    pose
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::blend::rig::Trs;
    use glam::DQuat;

    /// A figure 170 tall (head at 170, feet at 0, hands 80 either side) standing 1000 from a
    /// root left at the origin (as Bandai Namco's captures stand 500 from their joint_Root; by
    /// the span of each axis it was 1000 long and did not stand), turned by `degrees` through
    /// that root.
    fn far_from_its_root(degrees: f64) -> (Rig, Pose) {
        let names = [
            "root", "hips", "head", "foot.L", "foot.R", "hand.L", "hand.R",
        ];
        let parent = vec![None, Some(0), Some(1), Some(1), Some(1), Some(1), Some(1)];
        let at = |t: DVec3| Trs { t, ..Trs::IDENTITY };
        let local = vec![
            Trs {
                r: DQuat::from_rotation_y(degrees.to_radians()),
                ..Trs::IDENTITY
            },
            at(DVec3::new(0.0, 90.0, -1000.0)),
            at(DVec3::new(0.0, 80.0, 0.0)),
            at(DVec3::new(10.0, -90.0, 0.0)),
            at(DVec3::new(-10.0, -90.0, 0.0)),
            at(DVec3::new(80.0, 50.0, 0.0)),
            at(DVec3::new(-80.0, 50.0, 0.0)),
        ];
        let pose = Pose {
            weights: vec![Vec::new(); local.len()],
            local,
        };
        let names = names.iter().map(|s| s.to_string()).collect();
        (Rig::new(names, parent, pose.clone()).unwrap(), pose)
    }

    #[test]
    fn a_figure_far_from_its_root_stands_its_height_at_any_heading() {
        for degrees in [0.0, 37.0, 90.0, 180.0, 250.0] {
            let (rig, pose) = far_from_its_root(degrees);
            let s = size(&rig, &pose);
            assert!((s - 170.0).abs() < 1e-9, "{degrees} degrees: size {s}");
        }
    }

    /// A loop with root motion: one joint walking 1 a second along Z for 10 frames, the loop
    /// travelling 1: its velocity is 1 on every frame, the seam's two included.
    #[test]
    fn a_loop_s_velocity_carries_on_across_its_seam() {
        let dt = 0.1;
        let pos: Vec<Vec<DVec3>> = (0..=10)
            .map(|i| vec![DVec3::new(0.0, 0.0, i as f64 * dt)])
            .collect();
        let track = Track::closed(0.0, dt, true, pos, 0);
        assert_eq!(track.len(), 10);
        for i in 0..10 {
            let v = track.velocity(i, 0);
            assert!((v - DVec3::Z).length() < 1e-12, "frame {i}: {v}");
        }
    }
}
