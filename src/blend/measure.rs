//! Figures of a motion sampled at a fixed rate: foot sliding during contact, root and ground
//! speed, and jerk. All lengths are in leg scales (the character's longest leg).
//!
//! Sliding is the horizontal movement of a planted foot from one frame to the next, relative to
//! the ground: for a clip with root motion the ground is still; for an in-place clip (its root
//! travels less than its planted feet) it moves like a treadmill at the feet's mean planted
//! velocity.

use super::contacts;
use super::legs::Leg;
use super::rig::flat;
use super::track::Track;
use glam::DVec3;
use serde::Serialize;

/// The ground's velocity under planted feet whose mean velocity is `planted` while the root
/// travels at `root_speed` (horizontal, same units): a clip in place (its root travels less
/// than its planted feet) runs on a treadmill at `planted`; a clip with root motion on still
/// ground. The clean-up pins feet to this ground and the measure measures sliding against it.
pub fn ground_under(root_speed: f64, planted: DVec3) -> DVec3 {
    if root_speed < planted.length() {
        planted
    } else {
        DVec3::ZERO
    }
}

/// Mean and 95th percentile of per-frame values.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Spread {
    pub mean: f64,
    pub p95: f64,
    /// How many values (frame steps) the figures summarise.
    pub count: usize,
}

impl Spread {
    pub fn of(mut v: Vec<f64>) -> Spread {
        if v.is_empty() {
            return Spread::default();
        }
        v.sort_by(f64::total_cmp);
        Spread {
            mean: v.iter().sum::<f64>() / v.len() as f64,
            p95: v[((v.len() - 1) as f64 * 0.95).round() as usize],
            count: v.len(),
        }
    }
}

/// Figures of one motion.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Figures {
    /// Planted-foot sliding per frame, in leg scales.
    pub sliding: Spread,
    /// Horizontal root travel per second, in leg scales.
    pub root_speed: f64,
    /// Speed of the ground under planted feet per second (0 for a clip with root motion).
    pub ground_speed: f64,
    /// Mean magnitude of the joints' third derivative of position, leg scales per second cubed.
    pub jerk: f64,
}

/// How a motion travels, in scene units per second (horizontal): its root's mean velocity
/// from its first frame to its last, and the velocity of the ground under its planted feet
/// ([`ground_under`]: zero for a clip with root motion, the treadmill's for one in place).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Travel {
    pub root: DVec3,
    pub ground: DVec3,
}

impl Travel {
    /// Whether the motion steps in place: its ground moves under it.
    pub fn in_place(&self) -> bool {
        self.ground != DVec3::ZERO
    }
}

/// How `track` travels, each leg of `legs` planted where `flags` (per leg, the contact test's
/// [`contacts::flags`]) say.
pub fn travel(track: &Track, root: usize, legs: &[Leg], flags: &[Vec<bool>]) -> Travel {
    planted(track, root, legs, flags).travel
}

/// The horizontal moves of planted feet from frame to frame (a looping track's step from its
/// last frame back to the first too, so that the figures do not depend on where the loop
/// starts) and how the track travels, each leg planted where `flags` (per leg and frame) say.
fn planted(track: &Track, root: usize, legs: &[Leg], flags: &[Vec<bool>]) -> Planted {
    let n = track.len();
    let dt = track.dt;
    // Across a loop's seam the feet come back by the loop's travel (the root's, from its first
    // frame to where it comes back to it: was taken as the root's mean step times the frame
    // count, which a clean-up moving the root unevenly made wrong by up to 2.4e-3 leg across
    // the seam of Fox's walk): `Track::step_move`.
    let wraps = track.looping && n > 2;
    let steps = if wraps { n } else { n.saturating_sub(1) };
    let mut moves = Vec::new();
    for (leg, f) in legs.iter().zip(flags) {
        for i in 0..steps {
            if f[i] && f[(i + 1) % n] {
                moves.push(track.step_move(i, leg.end()));
            }
        }
    }
    let ground_step = if moves.is_empty() {
        DVec3::ZERO
    } else {
        moves.iter().sum::<DVec3>() / moves.len() as f64
    };
    let duration = (n.max(2) - 1) as f64 * dt;
    let shift = flat(track.pos[n - 1][root] - track.pos[0][root]);
    let root_speed = shift.length() / duration;
    let ground = ground_under(root_speed * dt, ground_step);
    Planted {
        moves,
        root_speed,
        ground,
        travel: Travel {
            root: shift / duration,
            ground: ground / dt,
        },
    }
}

/// What [`planted`] finds: the planted feet's moves, the root's speed (scene units per second)
/// and the ground's step per frame (the figures are made from these), and the travel.
struct Planted {
    moves: Vec<DVec3>,
    root_speed: f64,
    ground: DVec3,
    travel: Travel,
}

/// Figures of `track`. A foot counts as planted where the contact test finds it planted or,
/// per leg and frame, `expected` says it should be (empty: nothing more), so a motion whose
/// feet never settle is still measured where its sources plant them.
pub fn figures(
    track: &Track,
    root: usize,
    joints: &[usize],
    legs: &[Leg],
    scale: f64,
    expected: &[Vec<bool>],
) -> Figures {
    let n = track.len();
    let dt = track.dt;
    let flags: Vec<Vec<bool>> = legs
        .iter()
        .enumerate()
        .map(|(l, leg)| {
            let mut f = contacts::planted_flags(track, leg, scale);
            if let Some(e) = expected.get(l) {
                for (x, &y) in f.iter_mut().zip(e) {
                    *x |= y;
                }
            }
            // A looping foot found planted throughout swings where it moves fastest, as the
            // clean-up has it (it does not pin a looping foot throughout): a blend whose swing
            // is too weak for the contact test (RobotExpressive's Idle with its Walking at 0.5)
            // had that swing measured as sliding (0.005 leg/frame after clean-up).
            if track.looping && n > 2 && f.iter().all(|&x| x) {
                let moves: Vec<f64> = (0..n)
                    .map(|i| track.step_move(i, leg.end()).length())
                    .collect();
                contacts::swing_where_fastest(&mut f, &moves);
            }
            f
        })
        .collect();
    let Planted {
        moves: planted_moves,
        root_speed,
        ground,
        ..
    } = planted(track, root, legs, &flags);
    let wraps = track.looping && n > 2;
    let travel = if wraps { track.travel } else { DVec3::ZERO };
    let sliding = Spread::of(
        planted_moves
            .iter()
            .map(|m| (*m - ground).length() / scale)
            .collect(),
    );
    let mut jerk = 0.0;
    let mut count = 0usize;
    // On a loop every frame starts a window, those across the seam carried on by its travel.
    let windows = if wraps { n } else { n.saturating_sub(3) };
    for i in 0..windows {
        for &j in joints {
            let p = |k: usize| {
                let f = i + k;
                track.pos[f % n][j] + if f >= n { travel } else { DVec3::ZERO }
            };
            jerk += (p(3) - 3.0 * p(2) + 3.0 * p(1) - p(0)).length();
            count += 1;
        }
    }
    Figures {
        sliding,
        root_speed: root_speed / scale,
        ground_speed: ground.length() / dt / scale,
        jerk: jerk / count.max(1) as f64 / (dt * dt * dt) / scale,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::blend::legs::Side;

    /// A looping walk on a treadmill: joint 0 the root (still), joint 1 a foot that steps back
    /// on the floor for half the loop, a little unevenly, and swings forward above it.
    fn treadmill(start: usize) -> Track {
        let n = 24;
        let pos = (0..n)
            .map(|k| {
                let i = (k + start) % n;
                let u = i as f64 / n as f64;
                let foot = if u < 0.5 {
                    DVec3::new(0.02 * (i as f64).sin(), 0.0, 0.5 - 2.0 * u)
                } else {
                    DVec3::new(0.0, 0.3, -0.5 + 2.0 * (u - 0.5))
                };
                vec![DVec3::new(0.0, 1.0, 0.0), foot]
            })
            .collect();
        Track {
            start: 0.0,
            dt: 1.0 / 24.0,
            looping: true,
            pos,
            travel: DVec3::ZERO,
        }
    }

    /// The treadmill's one leg: joint 1, its foot.
    fn foot() -> Leg {
        Leg {
            chain: vec![1],
            ik: None,
            side: Side::Left,
            length: 1.0,
            name: "foot".into(),
        }
    }

    #[test]
    fn figures_of_a_loop_do_not_depend_on_where_it_starts() {
        let leg = foot();
        let figures = |start: usize| {
            figures(
                &treadmill(start),
                0,
                &[0, 1],
                std::slice::from_ref(&leg),
                1.0,
                &[],
            )
        };
        let first = figures(0);
        // The stance's steps but where the foot starts to rise; start 6 puts the loop's seam
        // mid-stance, 17 puts the stance inside the loop.
        assert!(first.sliding.count >= 8, "{:?}", first.sliding);
        assert!(first.sliding.mean > 0.0);
        for start in [5, 6, 17] {
            let other = figures(start);
            assert_eq!(other.sliding.count, first.sliding.count, "start {start}");
            assert!(
                (other.sliding.mean - first.sliding.mean).abs() < 1e-12,
                "start {start}"
            );
            assert!((other.ground_speed - first.ground_speed).abs() < 1e-12);
            assert!(
                (other.jerk - first.jerk).abs() < 1e-9 * first.jerk,
                "start {start}"
            );
        }
    }

    #[test]
    fn a_root_swaying_within_the_loop_is_not_travel() {
        // The same walk with its root swaying sideways and back within the loop (as the
        // clean-up's shift moves it): the feet are where they were, so the sliding is the same;
        // the root's last frame no longer tells the loop's travel.
        let leg = foot();
        let still = treadmill(0);
        let mut swaying = treadmill(0);
        let n = swaying.len();
        for (i, p) in swaying.pos.iter_mut().enumerate() {
            p[0].x += 0.1 * (std::f64::consts::TAU * i as f64 / n as f64).sin();
        }
        let of = |t: &Track| figures(t, 0, &[1], std::slice::from_ref(&leg), 1.0, &[]);
        let (a, b) = (of(&still), of(&swaying));
        assert_eq!(a.sliding.count, b.sliding.count);
        assert!(
            (a.sliding.mean - b.sliding.mean).abs() < 1e-12,
            "{a:?} {b:?}"
        );
        assert!((a.jerk - b.jerk).abs() < 1e-9 * a.jerk);
    }
}
