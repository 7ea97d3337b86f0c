//! Space warp (ALGORITHMS.md B.3, Kovar, Gleicher & Pighin 2002): the rotation about the up axis
//! and the floor translation that best carry one clip's joint positions onto the other's
//! ([`fit`]); then, frame by frame, both clips moved onto the blend's own way ([`register`]), so
//! that clips that turn apart blend by their turns, not by their positions.

use super::measure::Travel;
use super::rig::{Pose, Rig};
use glam::{DMat4, DQuat, DVec3};
use serde::Serialize;

/// A velocity below this many leg lengths a second is no travel to match (a root drifting on
/// the spot; walks and runs travel 1-3 leg lengths a second, on still ground or a treadmill).
pub const STILL: f64 = 0.05;

/// How the second clip was made to travel as the first: the velocity (scene units per second,
/// on the floor) added to its root over its own time.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum MatchedTravel {
    /// It steps in place and the first clip has root motion: it moves along at its treadmill's
    /// speed, so that its planted feet stay still.
    Along([f64; 3]),
    /// It has root motion and the first clip steps in place: it is held on the spot, its root
    /// at its mean speed taken away, so that its planted feet move back as on a treadmill.
    OnTheSpot([f64; 3]),
}

impl MatchedTravel {
    /// Blending a clip that steps in place with one that travels mixes a still root with a
    /// moving one: the blend's root moves at the weight's share of one speed while its legs
    /// step at the mix of both strides (a walk with root motion and a run in place at 0.5:
    /// root 0.89 leg lengths a second, legs stepping for about 2), which the clean-up hides by
    /// stretching the legs. The second clip is made the first's kind (`a`, `b` their travels,
    /// `scale` the leg length); `None` where both are of one kind.
    pub fn of(a: &Travel, b: &Travel, scale: f64) -> Option<MatchedTravel> {
        // A clip whose root and feet both stay put (an idle) is of neither kind.
        let moving = |v: DVec3| v.length() > STILL * scale;
        let travels = |t: &Travel| !t.in_place() && moving(t.root);
        let steps = |t: &Travel| t.in_place() && moving(t.ground);
        if travels(a) && steps(b) {
            Some(MatchedTravel::Along((-b.ground).to_array()))
        } else if steps(a) && travels(b) {
            Some(MatchedTravel::OnTheSpot((-b.root).to_array()))
        } else {
            None
        }
    }

    /// The velocity added (scene units per second).
    pub fn velocity(&self) -> DVec3 {
        match self {
            MatchedTravel::Along(v) | MatchedTravel::OnTheSpot(v) => DVec3::from_array(*v),
        }
    }
}

/// A rotation by `angle` (radians) about +Y followed by a floor translation (x, 0, z).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FloorTransform {
    pub angle: f64,
    pub translation: DVec3,
}

impl FloorTransform {
    pub const IDENTITY: FloorTransform = FloorTransform {
        angle: 0.0,
        translation: DVec3::ZERO,
    };

    pub fn matrix(&self) -> DMat4 {
        DMat4::from_rotation_translation(DQuat::from_rotation_y(self.angle), self.translation)
    }

    /// The transform `w` of the way from identity (0) to `self` (1).
    pub fn scaled(&self, w: f64) -> FloorTransform {
        FloorTransform {
            angle: self.angle * w,
            translation: self.translation * w,
        }
    }
}

/// The transform T minimising sum |p - T p'|^2 over corresponding points (equal weights), in
/// closed form; `p` from the clip kept, `q` from the clip moved.
pub fn fit(p: &[DVec3], q: &[DVec3]) -> FloorTransform {
    let n = p.len().min(q.len());
    if n == 0 {
        return FloorTransform::IDENTITY;
    }
    let w = 1.0 / n as f64;
    let (mut xm, mut zm, mut xm2, mut zm2, mut a, mut b) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for (p, q) in p.iter().zip(q) {
        xm += w * p.x;
        zm += w * p.z;
        xm2 += w * q.x;
        zm2 += w * q.z;
        a += w * (p.x * q.x + p.z * q.z);
        b += w * (p.x * q.z - q.x * p.z);
    }
    let angle = (b - (xm * zm2 - xm2 * zm)).atan2(a - (xm * xm2 + zm * zm2));
    let (s, c) = angle.sin_cos();
    FloorTransform {
        angle,
        translation: DVec3::new(xm - xm2 * c - zm2 * s, 0.0, zm + xm2 * s - zm2 * c),
    }
}

/// Move the body of `pose` (the joints [`Rig::body`] carries: the whole skeleton, or where the
/// travel is keyed on the hips under a root that stays put, the hips and all below them) by
/// the world transform `m`, through the body joint's own transform. Through the root instead,
/// a clip turned to head as the other one does kept its hips' local rotation heading the other
/// way, and the two clips' hips were slerped between opposite headings: Bandai Namco's
/// dataset-2 walk_active (heading +Z) and run_active (heading -Z), their travel on the hips
/// under a still joint_Root, blended with jerk ratios 8.5 / 13.7 / 8.4 at 0.25 / 0.5 / 0.75.
pub fn move_body(rig: &Rig, pose: &mut Pose, m: &DMat4) {
    let world = rig.world(pose);
    let parent = rig.parent_world(&world, rig.body);
    let local = pose.local[rig.body].matrix();
    let moved = parent.inverse() * *m * parent * local;
    pose.local[rig.body] = super::rig::Trs::from_matrix(&moved);
}

/// Carry `pose` (of the clip moved, at one moment) under the joints above the body of `under`
/// (the clip kept, at the same moment): those joints take `under`'s local transforms and the
/// body keeps its world transform, so that the blend mixes one chain above the body, not two.
/// Where the body is below the root and one clip's root bone is turned (a capture turned by
/// its root over hips that carry the travel), the two roots were slerped against each other
/// and the whole character turned by the weight's share of their difference: Bandai Namco's
/// dataset-1 walk_normal with run_active turned half round by its root, jerk ratios 11.1 /
/// 14.8 / 9.9 at 0.25 / 0.5 / 0.75 (0.96 / 0.96 / 0.97 unturned). Nothing changes where the
/// joints above the body are the same in both.
pub fn under_joints_above_body(rig: &Rig, pose: &mut Pose, under: &Pose) {
    let mut above = Vec::new();
    let mut j = rig.parent[rig.body];
    while let Some(p) = j {
        above.push(p);
        j = rig.parent[p];
    }
    if above.iter().all(|&p| pose.local[p] == under.local[p]) {
        return;
    }
    let body = rig.world(pose)[rig.body];
    for &p in &above {
        pose.local[p] = under.local[p];
    }
    let parent = rig.parent_world(&rig.world(pose), rig.body);
    pose.local[rig.body] = super::rig::Trs::from_matrix(&(parent.inverse() * body));
}

/// Where a clip heads at each frame: the body's facing on the floor (`reference`, a direction
/// in the body joint's own frame, carried to the world), unwrapped over the frames and averaged
/// over `half` frames either side (a stride's sway taken out: where the clip turns), radians
/// about +Y from +Z; and the body's floor position.
fn headings(
    rig: &Rig,
    poses: &[Pose],
    reference: DVec3,
    half: usize,
    looping: bool,
) -> Vec<(f64, DVec3)> {
    let n = poses.len();
    let mut raw: Vec<f64> = Vec::with_capacity(n);
    let mut floor = Vec::with_capacity(n);
    for pose in poses {
        let body = rig.world(pose)[rig.body];
        let dir = body.transform_vector3(reference);
        let mut yaw = dir.x.atan2(dir.z);
        if let Some(&last) = raw.last() {
            yaw = super::rig::unwrapped(last, yaw);
        }
        raw.push(yaw);
        let t = body.w_axis.truncate();
        floor.push(DVec3::new(t.x, 0.0, t.z));
    }
    // A loop's last frame is its first carried on by the loop: its turn carries on too.
    let distinct = if looping && n > 2 { n - 1 } else { n };
    let turn = if distinct < n {
        raw[n - 1] - raw[0]
    } else {
        0.0
    };
    let at = |i: i64| -> Option<f64> {
        if (0..distinct as i64).contains(&i) {
            return Some(raw[i as usize]);
        }
        if distinct == n {
            return None;
        }
        let m = distinct as i64;
        Some(raw[i.rem_euclid(m) as usize] + turn * i.div_euclid(m) as f64)
    };
    let smooth: Vec<f64> = (0..n as i64)
        .map(|i| {
            let h = if distinct < n {
                half as i64
            } else {
                (half as i64).min(i).min(n as i64 - 1 - i)
            };
            let vals: Vec<f64> = (i - h..=i + h).filter_map(at).collect();
            vals.iter().sum::<f64>() / vals.len() as f64
        })
        .collect();
    smooth.into_iter().zip(floor).collect()
}

/// Register two clips' frames (each pair one moment of the blend; `b` already fitted onto `a`)
/// frame by frame: both are moved onto the blend's own way, which turns and travels each frame
/// by the weighted mix of the sources' turns and steps, each step taken in its source's heading
/// ([`headings`]), so that a left turn and a right turn blend into a walk straight ahead. Mixed
/// as they were (the root's position averaged, its rotation slerped), two clips whose headings
/// part by more than a half turn were slerped the short way round, and the body flipped by a
/// half turn in a frame (Bandai Namco's walk-turn-left and walk-turn-right: jerk ratios up to
/// 6.5); where the two head alike the blend is as before: each step is the same, and each body
/// moved by the weight's share of their difference, which the slerp would have turned it by.
/// `forward` is the character's forward on the floor, `half` the frames averaged either side.
pub fn register(
    rig: &Rig,
    [a, b]: [&mut [Pose]; 2],
    w: f64,
    forward: DVec3,
    half: usize,
    looping: bool,
) {
    let n = a.len().min(b.len());
    if n == 0 {
        return;
    }
    let body0 = rig.world(&a[0])[rig.body];
    let reference = body0.inverse().transform_vector3(forward);
    let ha = headings(rig, &a[..n], reference, half, looping);
    let hb = headings(rig, &b[..n], reference, half, looping);
    let turn = |yaw: f64| DQuat::from_rotation_y(yaw);
    let mut pos = ha[0].1.lerp(hb[0].1, w);
    for i in 0..n {
        let yaw = (1.0 - w) * ha[i].0 + w * hb[i].0;
        if i > 0 {
            let step = |h: &[(f64, DVec3)]| {
                let mid = 0.5 * (h[i - 1].0 + h[i].0);
                turn(-mid) * (h[i].1 - h[i - 1].1)
            };
            let mid = 0.5 * ((1.0 - w) * (ha[i - 1].0 + ha[i].0) + w * (hb[i - 1].0 + hb[i].0));
            pos += turn(mid) * step(&ha).lerp(step(&hb), w);
        }
        for (pose, h) in [(&mut a[i], ha[i]), (&mut b[i], hb[i])] {
            let m = DMat4::from_rotation_translation(turn(yaw - h.0), pos)
                * DMat4::from_translation(-h.1);
            move_body(rig, pose, &m);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A hip with a toe ahead of it (a BVH of one joint and its end), and `n` poses of it
    /// walking 1 unit a frame while turning `degrees` a frame about +Y (left for positive).
    fn turning(n: usize, degrees: f64) -> (Rig, Vec<Pose>) {
        let text = "HIERARCHY\nROOT hip\n{\n\tOFFSET 0 0 0\n\tCHANNELS 6 Xposition Yposition \
                    Zposition Zrotation Yrotation Xrotation\n\tEnd Site\n\t{\n\t\tOFFSET 0 -1 \
                    0.3\n\t}\n}\nMOTION\nFrames: 1\nFrame Time: 0.1\n0 1 0 0 0 0\n";
        let (rig, clip) = crate::blend::bvh::parse(text).unwrap();
        let rest = clip.pose(&rig, 0.0);
        let mut at = DVec3::new(0.0, 1.0, 0.0);
        let poses = (0..n)
            .map(|i| {
                let yaw = (degrees * i as f64).to_radians();
                let mut pose = rest.clone();
                pose.local[rig.body].r = DQuat::from_rotation_y(yaw);
                pose.local[rig.body].t = at;
                at += DQuat::from_rotation_y(yaw + 0.5 * degrees.to_radians()) * DVec3::Z;
                pose
            })
            .collect();
        (rig, poses)
    }

    /// Clips that head alike are left where they are; a left and a right turn are both moved
    /// onto one straight way at 0.5, each step as long as theirs, facing ahead.
    #[test]
    fn registered_turns_blend_by_their_turns() {
        let (rig, a) = turning(60, 0.0);
        let (mut x, mut y) = (a.clone(), a.clone());
        register(&rig, [&mut x, &mut y], 0.3, DVec3::Z, 5, false);
        for (p, q) in a.iter().zip(&x).chain(a.iter().zip(&y)) {
            let (p, q) = (p.local[rig.body], q.local[rig.body]);
            assert!(p.t.distance(q.t) < 1e-9 && p.r.angle_between(q.r) < 1e-9);
        }
        // Headings 354 degrees apart at the end.
        let (_, mut left) = turning(60, 3.0);
        let (_, mut right) = turning(60, -3.0);
        register(&rig, [&mut left, &mut right], 0.5, DVec3::Z, 5, false);
        for (i, (l, r)) in left.iter().zip(&right).enumerate() {
            for pose in [l, r] {
                let body = pose.local[rig.body];
                let ahead = body.r * DVec3::Z;
                assert!(ahead.distance(DVec3::Z) < 1e-6, "frame {i}: facing {ahead}");
                let expect = DVec3::new(0.0, 1.0, i as f64);
                assert!(body.t.distance(expect) < 1e-6, "frame {i}: at {}", body.t);
            }
        }
    }

    #[test]
    fn recovers_a_known_floor_transform() {
        let truth = FloorTransform {
            angle: 0.7,
            translation: DVec3::new(1.5, 0.0, -2.0),
        };
        let q: Vec<DVec3> = (0..20)
            .map(|i| {
                DVec3::new(
                    (i as f64).sin() * 3.0,
                    i as f64 * 0.1,
                    (i as f64 * 0.7).cos(),
                )
            })
            .collect();
        let p: Vec<DVec3> = q
            .iter()
            .map(|&x| truth.matrix().transform_point3(x))
            .collect();
        let fitted = fit(&p, &q);
        assert!((fitted.angle - truth.angle).abs() < 1e-12);
        assert!((fitted.translation - truth.translation).length() < 1e-12);
    }
}
