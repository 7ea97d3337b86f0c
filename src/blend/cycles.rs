//! Gait cycles: the stride period from the autocorrelation of the legs' motion, and cycle starts
//! at the maxima of one leg's signal (one per stride, so left and right are never confused).
//!
//! * `legs` (default, any rig): each foot's forward offset from the root; a cycle starts when
//!   the first leg (left, longest) is furthest forward. On a clip that does not loop the strides
//!   are then taken from the first leg's touchdowns (see [`touchdowns`]) where every leg steps
//!   once between two of them: sharper events than the broad peak of a forward offset.
//! * `thigh` (the seed's method): the angle between the two longest opposite legs' thighs,
//!   signed by which knee is ahead; a cycle starts at the widest stride with the left leg ahead.

use super::legs::{median, Leg, Side};
use super::rig::{flat, UP};
use super::track::Track;
use glam::DVec3;
use serde::Serialize;

/// How gait cycles are found (`--cycles`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum CycleMethod {
    /// From each foot's forward offset and touchdowns: any rig. The default.
    #[default]
    Legs,
    /// The seed paper's signed angle between the thighs (bipeds).
    Thigh,
    /// No cycles: each clip whole, blended on normalised time (clips that do not walk).
    None,
}

/// Least forward-and-back travel of a foot (relative to the root, in leg lengths) that makes a
/// stride: walks and runs measure 0.9-1.6, idles, dances, waves and T-poses below 0.01.
pub const MIN_STRIDE: f64 = 0.1;

/// Shortest stride period considered, in seconds.
pub const MIN_PERIOD: f64 = 0.25;
/// Autocorrelation a looping clip needs at lag `duration / k` to hold `k` strides.
pub const LOOP_REPEAT: f64 = 0.8;
/// Longest stride period considered, in seconds.
pub const MAX_PERIOD: f64 = 2.5;
/// A cycle start is the largest value of the reference signal within this many seconds ...
pub const START_WINDOW: f64 = 0.25;
/// ... and rises this much above the lowest value within half of [`MAX_PERIOD`] on both sides
/// (leg scales for `legs`, radians for `thigh`).
pub const MIN_SWING: f64 = 0.15;

/// Fewest strides a loop holds for [`meet_by_chance`] to ask that they repeat: a loop of two
/// strides cut from a capture by hand (a pose and the same pose two strides on) stays a loop.
pub const CHANCE_STRIDES: usize = 3;

/// A foot is in stance while its horizontal speed over the ground is below this fraction of
/// its fast swing speed (98th percentile) ...
pub const STANCE_SPEED: f64 = 0.1;
/// ... and swings once it passes this fraction; a touchdown is a swing ending in stance.
pub const SWING_SPEED: f64 = 0.5;

/// Shortest stance, in seconds.
pub const MIN_STANCE: f64 = 0.1;
/// A foot has touched down once it stays within this distance of where it stands, in leg
/// scales.
pub const LANDING: f64 = 0.05;

/// Cycles found in one clip: (start time, period) per cycle.
#[derive(Clone, Debug, Serialize)]
pub struct Cycles {
    pub spans: Vec<(f64, f64)>,
}

/// Find the cycles of `track` by `method`; `None` when no periodic leg motion is found.
/// `forward` is the clip's forward direction, `heads` the way it heads at each frame (a turning
/// clip's legs are judged along it: along one forward a quarter turn's strides fade into
/// sideways steps).
pub fn detect(
    method: CycleMethod,
    track: &Track,
    root: usize,
    legs: &[Leg],
    forward: DVec3,
    heads: &[DVec3],
    scale: f64,
) -> Option<Cycles> {
    let signals: Vec<Vec<f64>> = match method {
        CycleMethod::None => return None,
        CycleMethod::Legs => legs
            .iter()
            .map(|l| {
                (track.pos.iter().zip(heads))
                    .map(|(p, h)| (p[l.end()] - p[root]).dot(*h) / scale)
                    .collect()
            })
            .collect(),
        CycleMethod::Thigh => {
            let pick = |side| legs.iter().find(|l| l.side == side);
            let (l, r) = (pick(Side::Left)?, pick(Side::Right)?);
            let hk = |leg: &Leg| {
                leg.ik
                    .map_or([leg.chain[0], leg.chain[1]], |k| [k[0], k[1]])
            };
            let ([lh, lk], [rh, rk]) = (hk(l), hk(r));
            vec![(track.pos.iter().zip(heads))
                .map(|(p, h)| {
                    let angle = (p[lk] - p[lh]).angle_between(p[rk] - p[rh]);
                    if (p[lk] - p[rk]).dot(*h) >= 0.0 {
                        angle
                    } else {
                        -angle
                    }
                })
                .collect()]
        }
    };
    let raw_reference = signals.first()?.clone();
    let signals: Vec<Vec<f64>> = signals.into_iter().filter_map(normalized).collect();
    let reference = signals.first()?;
    let n = track.len();
    let corr = |lag: f64| -> f64 {
        let lo = lag.floor() as usize;
        let at = |l: usize| autocorrelation(&signals, l, track.looping);
        let f = lag - lo as f64;
        at(lo) * (1.0 - f) + if f > 0.0 { at(lo + 1) * f } else { 0.0 }
    };
    if track.looping {
        // As many strides as the loop repeats at a stride period (a capture of six strides
        // that ends as it began is six cycles, not three of two strides).
        let most = ((n as f64 * track.dt / MIN_PERIOD).floor() as usize).max(1);
        let k = (1..=most)
            .rev()
            .find(|&k| n / k >= 2 && corr(n as f64 / k as f64) >= LOOP_REPEAT)
            .unwrap_or(1);
        let per = n as f64 / k as f64;
        let first = (0..(per.ceil() as usize).min(n))
            .max_by(|&a, &b| reference[a].total_cmp(&reference[b]))?;
        let start = track.time(0) + refine(reference, first, track) * track.dt;
        let period = per * track.dt;
        return Some(Cycles {
            spans: (0..k)
                .map(|j| (start + j as f64 * period, period))
                .collect(),
        });
    }
    if method == CycleMethod::Legs {
        let spans = stepped(track, legs, forward, scale);
        if !spans.is_empty() {
            return Some(Cycles { spans });
        }
    }
    // Starts: prominent maxima of the reference signal (steps, not shuffles), a stride apart.
    let raw = &raw_reference;
    let near = ((START_WINDOW / track.dt).round() as usize).max(1);
    let side = ((MAX_PERIOD / 2.0 / track.dt).round() as usize).max(1);
    let starts: Vec<f64> = (1..n - 1)
        .filter(|&i| {
            let around = &raw[i.saturating_sub(near)..(i + near + 1).min(n)];
            let before = &raw[i.saturating_sub(side)..=i];
            let after = &raw[i..(i + side + 1).min(n)];
            let min = |w: &[f64]| w.iter().copied().fold(f64::INFINITY, f64::min);
            raw[i] >= around.iter().copied().fold(f64::NEG_INFINITY, f64::max)
                && raw[i] - min(before) >= MIN_SWING
                && raw[i] - min(after) >= MIN_SWING
        })
        .map(|i| track.time(0) + refine(raw, i, track) * track.dt)
        .collect();
    let spans: Vec<(f64, f64)> = starts
        .windows(2)
        .map(|w| (w[0], w[1] - w[0]))
        .filter(|&(_, p)| (MIN_PERIOD..=MAX_PERIOD).contains(&p))
        .collect();
    (!spans.is_empty()).then_some(Cycles { spans })
}

/// Strides of a capture (start, period; seconds) from the first leg's touchdowns
/// ([`touchdowns`]), each one where every other leg touches down once.
fn stepped(track: &Track, legs: &[Leg], forward: DVec3, scale: f64) -> Vec<(f64, f64)> {
    let ground = ground_velocity(track, legs, forward);
    let downs: Vec<Vec<f64>> = legs
        .iter()
        .map(|l| touchdowns(track, l.end(), ground, forward, scale))
        .collect();
    downs[0]
        .windows(2)
        .map(|w| (w[0], w[1] - w[0]))
        .filter(|&(s, p)| {
            (MIN_PERIOD..=MAX_PERIOD).contains(&p)
                && downs[1..]
                    .iter()
                    .all(|d| d.iter().filter(|&&t| t > s && t < s + p).count() == 1)
        })
        .collect()
}

/// Whether looping `track`, found to hold `cycles`, is a capture whose ends meet by chance
/// rather than a loop: stepped as a capture ([`stepped`]) it shows as many strides from
/// touchdown to touchdown as the loop holds or more (a loop of one stride shows none, one of
/// `k` equal strides `k - 1`), or, holding [`CHANCE_STRIDES`] or more, a stride's legs (their
/// joints relative to `root`) are more than `tolerance` (scene units) from the next stride's at
/// the same phase somewhere. Bandai Namco's walks of 7-16 s whose last pose comes within a
/// frame or two of their first were blended as loops of one stride cut from them, the seam a
/// jump: the takes with each other at jerk ratios of 1.33-1.66 (0.91-0.94 as the captures they
/// are); their strides part by 0.17-0.38 leg at the same phase, a loop's copies by nothing.
pub fn meet_by_chance(
    track: &Track,
    cycles: &Cycles,
    root: usize,
    legs: &[Leg],
    forward: DVec3,
    scale: f64,
    tolerance: f64,
) -> bool {
    let (n, k) = (track.len(), cycles.spans.len());
    if !track.looping || n < 2 || legs.is_empty() {
        return false;
    }
    if stepped(track, legs, forward, scale).len() >= k {
        return true;
    }
    if k < CHANCE_STRIDES {
        return false;
    }
    // A stride is `per` of the loop's `n` frames.
    let per = n as f64 / k as f64;
    let joints: Vec<usize> = legs.iter().flat_map(|l| l.chain.iter().copied()).collect();
    let rel = |i: usize, j: usize| {
        let p = &track.pos[i % n];
        p[j] - p[root]
    };
    (0..n).any(|i| {
        let x = i as f64 + per;
        let lo = x.floor() as usize;
        let f = x - lo as f64;
        joints.iter().any(|&j| {
            let next = rel(lo, j) * (1.0 - f) + rel(lo + 1, j) * f;
            (rel(i, j) - next).length() > tolerance
        })
    })
}

/// Horizontal median of `points` (not empty), per axis of the clip's own frame (`forward` and
/// the horizontal across it), so that a clip turned about the up axis gives its median turned.
/// Per axis of the world, the CMU run turned by 1-270 degrees had one cycle of 0.783-0.842 s,
/// 0.800 s as captured.
fn flat_median(points: &[DVec3], forward: DVec3) -> DVec3 {
    let across = UP.cross(forward);
    forward * median(points.iter().map(|v| v.dot(forward)).collect())
        + across * median(points.iter().map(|v| v.dot(across)).collect())
}

/// Velocity of the ground under the feet: the median horizontal velocity of the lowest foot of
/// `legs`; zero for a clip with root motion, the treadmill's for one in place.
fn ground_velocity(track: &Track, legs: &[Leg], forward: DVec3) -> DVec3 {
    let lowest: Vec<DVec3> = (0..track.len())
        .filter_map(|i| {
            let foot = legs
                .iter()
                .map(|l| l.end())
                .min_by(|&a, &b| track.pos[i][a].y.total_cmp(&track.pos[i][b].y))?;
            Some(flat(track.velocity(i, foot)))
        })
        .collect();
    if lowest.is_empty() {
        DVec3::ZERO
    } else {
        flat_median(&lowest, forward)
    }
}

/// Touchdowns of the foot `end` on a clip that does not loop (seconds). A stance lasts from the
/// foot's horizontal speed over the ground (moving at `ground`, see [`ground_velocity`])
/// falling below [`STANCE_SPEED`] until it passes [`SWING_SPEED`], at least [`MIN_STANCE`];
/// a stance's touchdown is the first moment from which the foot stays within [`LANDING`] of the
/// stance's spot (median position): from positions, so a capture's jitter in speed does not
/// move it. A foot already on its spot at the clip's first frame began that stance before the
/// clip: no touchdown. `forward` is the clip's forward direction, `scale` the leg scale.
pub fn touchdowns(
    track: &Track,
    end: usize,
    ground: DVec3,
    forward: DVec3,
    scale: f64,
) -> Vec<f64> {
    let n = track.len();
    let at = |i: usize| flat(track.pos[i][end]) - ground * track.time(i);
    let speed: Vec<f64> = (0..n)
        .map(|i| (flat(track.velocity(i, end)) - ground).length())
        .collect();
    let fast = {
        let mut s = speed.clone();
        s.sort_by(f64::total_cmp);
        s[(n - 1) * 98 / 100]
    };
    let (stance, swing) = (STANCE_SPEED * fast, SWING_SPEED * fast);
    // Stances: from the speed falling below `stance` until it passes `swing` again.
    let mut runs: Vec<(usize, usize)> = Vec::new();
    let mut from: Option<usize> = None;
    for (i, &v) in speed.iter().enumerate() {
        match from {
            None if v <= stance => from = Some(i),
            Some(f) if v > swing => {
                runs.push((f, i));
                from = None;
            }
            _ => {}
        }
    }
    runs.extend(from.map(|f| (f, n)));
    let min_run = ((MIN_STANCE / track.dt).ceil() as usize).max(1);
    runs.retain(|&(f, e)| e - f >= min_run);
    let mut downs = Vec::new();
    for &(first, last) in &runs {
        let spot = flat_median(&(first..last).map(at).collect::<Vec<_>>(), forward);
        let mut k = first;
        while k > 0 && (at(k - 1) - spot).length() < LANDING * scale {
            k -= 1;
        }
        if k > 0 {
            downs.push(track.time(k));
        }
    }
    downs
}

/// Zero-mean, unit-variance copy; `None` for a flat signal.
fn normalized(s: Vec<f64>) -> Option<Vec<f64>> {
    let n = s.len() as f64;
    let mean = s.iter().sum::<f64>() / n;
    let var = s.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / n;
    (var > 1e-18).then(|| s.iter().map(|x| (x - mean) / var.sqrt()).collect())
}

/// Mean autocorrelation of normalized signals at `lag` frames (circular when `looping`).
fn autocorrelation(signals: &[Vec<f64>], lag: usize, looping: bool) -> f64 {
    let mut sum = 0.0;
    for s in signals {
        let n = s.len();
        let m = if looping { n } else { n.saturating_sub(lag) };
        if m == 0 {
            continue;
        }
        let acc: f64 = (0..m).map(|i| s[i] * s[(i + lag) % n]).sum();
        sum += acc / m as f64;
    }
    sum / signals.len().max(1) as f64
}

/// Offset of the extremum of the parabola through three equally spaced values.
fn parabola(a: f64, b: f64, c: f64) -> f64 {
    let d = a - 2.0 * b + c;
    if d.abs() < 1e-15 {
        0.0
    } else {
        (0.5 * (a - c) / d).clamp(-0.5, 0.5)
    }
}

/// Sub-frame position of the maximum at frame `i`.
fn refine(s: &[f64], i: usize, track: &Track) -> f64 {
    let (a, c) = (track.step(i, -1), track.step(i, 1));
    if !track.looping && (i == 0 || i + 1 == s.len()) {
        return i as f64;
    }
    i as f64 + parabola(s[a], s[i], s[c])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An in-place loop of `strides.len()` strides at 120 frames a second, each stride 1 s and
    /// its feet (joints 1 and 2, half a stride apart) reaching `strides[j]` legs ahead of the
    /// hip (joint 0): back along the treadmill on the floor for 0.6 s, forward through the air
    /// for 0.4 s.
    fn treadmill_loop(strides: &[f64]) -> (Track, Vec<Leg>, Cycles) {
        let per = 120;
        let n = per * strides.len();
        let foot = |i: usize, reach: f64| {
            let u = (i % per) as f64 / per as f64;
            if u < 0.6 {
                DVec3::new(0.0, 0.0, reach * (1.0 - 2.0 * u / 0.6))
            } else {
                let v = (u - 0.6) / 0.4;
                let lift = 0.2 * (std::f64::consts::PI * v).sin();
                DVec3::new(0.0, lift, reach * (2.0 * v - 1.0))
            }
        };
        let pos = (0..n)
            .map(|i| {
                let hip = DVec3::new(0.0, 1.0, 0.0);
                let j = i / per;
                let other = (i + n - per / 2) % n;
                vec![
                    hip,
                    foot(i, strides[j]) + DVec3::X * 0.1,
                    foot(other, strides[other / per]) - DVec3::X * 0.1,
                ]
            })
            .collect();
        let track = Track {
            start: 0.0,
            dt: 1.0 / per as f64,
            looping: true,
            pos,
            travel: DVec3::ZERO,
        };
        let leg = |j: usize, side: Side| Leg {
            chain: vec![j],
            ik: None,
            side,
            length: 1.0,
            name: format!("foot{j}"),
        };
        let legs = vec![leg(1, Side::Left), leg(2, Side::Right)];
        let cycles = Cycles {
            spans: (0..strides.len()).map(|j| (j as f64, 1.0)).collect(),
        };
        (track, legs, cycles)
    }

    /// A loop of four strides that repeat is a loop; four that part by 0.1 leg at the same
    /// phase (a capture whose ends meet by chance) is not; two strides that part so (a loop
    /// cut from a capture by hand) are still a loop.
    #[test]
    fn a_loop_of_strides_that_do_not_repeat_is_a_capture() {
        let judge = |strides: &[f64]| {
            let (track, legs, cycles) = treadmill_loop(strides);
            meet_by_chance(&track, &cycles, 0, &legs, DVec3::Z, 1.0, 0.05)
        };
        assert!(!judge(&[0.5, 0.5, 0.5, 0.5]));
        assert!(judge(&[0.5, 0.55, 0.5, 0.45]));
        assert!(!judge(&[0.5, 0.55]));
        assert!(!judge(&[0.5]));
    }
}
