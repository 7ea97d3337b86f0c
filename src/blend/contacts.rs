//! Foot contacts (the seed's test): a foot touches the floor while it is near its floor and
//! barely moves vertically, unless it swings forward of its hip (see [`drop_swings`]): the
//! touches time the blend ([`flags`]). Of each touch, the foot stands planted from where it
//! stops moving over the ground to where it starts again ([`settle`]): the clean-up pins
//! those frames and the figures measure sliding on them. Only a touch's ends are judged by
//! speed, so a foot that slides through its contact is still measured sliding.

use super::legs::{self, Leg};
use super::rig::flat;
use super::track::Track;
use glam::{DQuat, DVec3};
use serde::Serialize;

/// Height above the foot's lowest point, as a fraction of the leg scale.
pub const HEIGHT_TOLERANCE: f64 = 0.06;
/// Vertical speed, in leg scales per second.
pub const SPEED_TOLERANCE: f64 = 1.5;
/// Shortest contact kept, in seconds; shorter gaps between contacts are closed (in samples of
/// the analysis rate, 120 a second at least: runs of up to `ceil(MIN_CONTACT / dt)` samples, 3 at
/// 120 a second). RobotExpressive's run touches the floor for 0.03-0.06 s a step; with its shins'
/// end nodes dropped (glTF-Transform's `prune`, gltfpack), the shins end where their meshes end,
/// off the ankle, and its right foot's contact was four samples long: at 0.03 s it was dropped,
/// the run had one planted foot, and the blend at 0.75 pinned none of that foot's steps.
pub const MIN_CONTACT: f64 = 0.02;
/// Half the span (seconds) over which a foot's floor is taken: a capture whose ground drifts
/// or slopes (CMU walks rise 0.05 leg over 2.5 s) has a floor that follows it. A clip no longer
/// than the whole span has one floor, as before.
pub const FLOOR_WINDOW: f64 = 1.0;

/// One contact: from touchdown to lift-off (seconds on the clip's timeline; on a looping clip
/// `end` may pass the clip's end, the contact wrapping round).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Contact {
    pub start: f64,
    pub end: f64,
}

/// A planted foot moves over the ground (its contact's own median velocity: still ground, or
/// a treadmill) by at most this many leg lengths a second at either end of its contact ...
pub const SETTLE_SPEED: f64 = 0.3;
/// ... or this many times its median speed over that ground through the contact, where more
/// (a hand-keyed foot on a treadmill whose speed varies through its stance: Fox's).
pub const SETTLE_SPREAD: f64 = 3.0;

/// Per-frame planted flags of `leg` on `track`: the frames it touches the floor ([`flags`]),
/// settled ([`settle`]). `scale` is the character's leg length.
pub fn planted_flags(track: &Track, leg: &Leg, scale: f64) -> Vec<bool> {
    let mut f = flags(track, leg, scale);
    settle(track, leg, scale, &mut f);
    f
}

/// Unflag the frames at either end of each contact of `f` where the foot still moves over the
/// ground, landing or lifting off: faster than [`SETTLE_SPEED`] (and than [`SETTLE_SPREAD`]
/// times its median) relative to the contact's median velocity. A contact keeps more than
/// [`MIN_CONTACT`]. The contact test alone takes a foot low and level enough as planted: a
/// walk backwards lands on its toe still moving back at 1.7 leg/s and lifts it with the heel
/// still down (Bandai Namco's walk-back_normal: the toe flagged for 0.1 s at either end of its
/// stance, moving 0.7-1.7 leg/s); the clean-up pinned those frames against the sources' own
/// motion, and the blend of that capture with itself had 3.00 times its jerk (1.10 settled).
/// Over Bandai's walks and runs (each style's walk with its run, 66 cells) jerk ratios above
/// 1.15 went from 28 to 2.
///
/// A contact is dropped whole where its median velocity is off the ground under the foot's
/// contacts together (their geometric median) by more than that limit, their spread standing
/// for its own: a toe skimming the floor as the heel lands, still moving 1 leg/s. Bandai
/// Namco's walk_sad has such touches of 0.02 s and of 0.04 s, 0.08 s before its stance; pinned
/// by the clean-up, the foot stopped for a frame or two and then caught up 0.13 leg in two
/// (the walk's two takes blended at jerk ratios of 1.36 / 1.21 at 0.25 / 0.5 while the short
/// one was pinned; with walk_tired 1.13 at 0.25 while the longer one was, now 0.89). Judged
/// for contacts too short to settle alone (at most [`MIN_CONTACT`] and a sample), Bandai's
/// cross-style pairs (180 cells) had jerk ratios above 1.15 in 1, their mean 0.876; judged
/// for every contact, none, mean 0.866.
pub fn settle(track: &Track, leg: &Leg, scale: f64, f: &mut [bool]) {
    let n = f.len();
    let short = shortest_contact(track);
    let e = leg.end();
    let over_ground = |i: usize| flat(track.velocity(i, e)) / scale;
    let all: Vec<DVec3> = (0..n).filter(|&i| f[i]).map(over_ground).collect();
    let (under, spread) = if all.is_empty() {
        (DVec3::ZERO, 0.0)
    } else {
        let g = geometric_median(&all);
        (
            g,
            legs::median(all.iter().map(|v| (*v - g).length()).collect()),
        )
    };
    for (s, len) in runs(f, track.looping) {
        if !f[s] || len == n {
            continue;
        }
        let at = |k: usize| (s + k) % n;
        let v: Vec<DVec3> = (0..len).map(|k| over_ground(at(k))).collect();
        // The ground under the contact: the same however the clip is turned.
        let ground = geometric_median(&v);
        if (ground - under).length() > SETTLE_SPEED.max(SETTLE_SPREAD * spread) {
            for k in 0..len {
                f[at(k)] = false;
            }
            continue;
        }
        if len <= short + 1 {
            continue;
        }
        let off: Vec<f64> = v.iter().map(|v| (*v - ground).length()).collect();
        let limit = SETTLE_SPEED.max(SETTLE_SPREAD * legs::median(off.clone()));
        let (mut lo, mut hi) = (0, len);
        while hi - lo > short + 1 && off[lo] > limit {
            lo += 1;
        }
        while hi - lo > short + 1 && off[hi - 1] > limit {
            hi -= 1;
        }
        for k in (0..lo).chain(hi..len) {
            f[at(k)] = false;
        }
    }
}

/// The longest run of samples of `track` a contact is dropped at, or a gap closed at
/// ([`MIN_CONTACT`]).
fn shortest_contact(track: &Track) -> usize {
    ((MIN_CONTACT / track.dt).ceil() as usize).max(1)
}

/// Per-frame flags of `leg` on `track` where its foot touches the floor (the contact test);
/// `scale` is the character's leg length.
pub fn flags(track: &Track, leg: &Leg, scale: f64) -> Vec<bool> {
    let e = leg.end();
    let floor = local_floor(
        &track.pos.iter().map(|p| p[e].y).collect::<Vec<_>>(),
        track.dt,
    );
    let mut f: Vec<bool> = (0..track.len())
        .map(|i| {
            track.pos[i][e].y - floor[i] <= HEIGHT_TOLERANCE * scale
                && track.velocity(i, e).y.abs() <= SPEED_TOLERANCE * scale
        })
        .collect();
    drop_swings(track, leg, scale, &mut f);
    let short = shortest_contact(track);
    // Close short gaps, then drop short contacts.
    for (value, max_run) in [(false, short), (true, short)] {
        for (s, len) in runs(&f, track.looping) {
            if f[s] == value && len <= max_run && len < f.len() {
                for k in 0..len {
                    let i = (s + k) % f.len();
                    f[i] = !value;
                }
            }
        }
    }
    f
}

/// Let a looping foot planted on every frame swing where it moves fastest: the run of steps
/// round its longest one (`moves[i]`: its move from frame `i` to the next, round the loop) that
/// are longer than their mean, both ends of each, at least one frame kept planted.
pub fn swing_where_fastest(planted: &mut [bool], moves: &[f64]) {
    let n = moves.len();
    let Some(fastest) = (0..n).max_by(|&a, &b| moves[a].total_cmp(&moves[b])) else {
        return;
    };
    let mean = moves.iter().sum::<f64>() / n as f64;
    let (mut lo, mut hi) = (fastest, fastest);
    let mut len = 1;
    while len < n && moves[(lo + n - 1) % n] > mean {
        lo = (lo + n - 1) % n;
        len += 1;
    }
    while len < n && moves[(hi + 1) % n] > mean {
        hi = (hi + 1) % n;
        len += 1;
    }
    for k in 0..(len + 1).min(n - 1) {
        planted[(lo + k) % n] = false;
    }
}

/// How many times the body's speed a foot must lead its hip by, in a frame, to be swinging
/// rather than planted (see [`drop_swings`]): a planted foot trails its hip at the body's
/// speed; a walk's swing foot leads it by about 1.5 times that on average (its stance lasts
/// about 1.5 times its swing) and by more mid-swing; a landing foot, still moving forward
/// as its heel strikes, by less.
pub const SWING_LEAD: f64 = 2.0;
/// Least lead that makes a swing, in leg scales per second, for a motion whose body hardly
/// moves (an idle, a standing start): a foot shifting its weight leads by less.
pub const SWING_LEAD_MIN: f64 = 1.0;

/// The flagged frames' mean lead gives the way forward (see [`drop_swings`]) where the cosine
/// of its angle to their median lead is at least this (45 degrees): a forward taken from it is
/// then at most that far off, and a swing's lead along it at least 0.71 of its length.
pub const TRAIL_AGREES: f64 = std::f64::consts::FRAC_1_SQRT_2;

/// ... and where it is at least this long against their median lead: shorter, swings flagged
/// for much of their length cancel it, and its direction is noise. Bandai Namco's
/// walk-turn-left_elderly shuffles, its toe lifted under 1 cm through a swing: on its blend
/// with itself at the output's 30 samples a second (the analysis' 120 smooth it less) the mean
/// was 0.05 of the median's length at 40 degrees from it, the swing led its hip along it by
/// 0.92 leg/s, under [`SWING_LEAD_MIN`], and the clean-up pinned the foot through two stances
/// and the swing between them (a step erased, jerk ratio 1.33; 1.02 on the median).
pub const TRAIL_LONG: f64 = 0.5;

/// Unflag frames where the foot, low and level enough for the test above, swings: it moves forward
/// of its hip faster than [`SWING_LEAD`] times the speed at which the leg's flagged frames trail it
/// on average (the body's speed over the ground), and than [`SWING_LEAD_MIN`]; forward is the
/// opposite of that mean trail, unless it points farther from the way most flagged frames trail
/// (their leads' [`geometric_median`]) than [`TRAIL_AGREES`] allows or is shorter than
/// [`TRAIL_LONG`] of it: where a swing is low enough to
/// be flagged nearly throughout, the mean nears zero (a foot comes back to its hip once a cycle)
/// and points anywhere. Bandai Namco's walk_not-confident blended with its run at 0.25 on a stride
/// of its walk where 35 of 36 frames were flagged had the mean pointing backwards, and a swing
/// leading its hip by 4.6 leg/s was kept planted; its walk-back_masculinity blended with its
/// walk-back_normal at 0.5, the first clean-up pass's toe flagged on 124 of 127 frames, had it
/// 0.016 leg/s long, at 88 degrees from the median's 0.87 leg/s: every swing was kept planted, the
/// next pass pinned the toe from the first step to the last, and the jerk ratio was 4.05 (0.92 on
/// the median). The median alone, where the two agree, moves the swings of capture blends whose
/// swings are partly flagged: Bandai's walk_tired + run_tired went from a jerk ratio of 1.14 to
/// 1.19 at 0.25. A planted foot trails its hip, on a treadmill as on still ground; a foot dragged
/// low through the start of its swing leads it (CMU's start-walk-stop: a toe flagged for 0.15 s
/// after lift-off, leading its hip by 2.7 leg/s where its contacts trail by 0.6-1.1; kevinxie4c's
/// walk: 0.06-0.1 s fragments leading by about 5). Judged per frame, not on a run's mean: on a
/// cleaned motion the foot released at lift-off and eased back to its path joins the slow frames
/// after lift-off and the swing's fragment into one run of low mean lead, which the clean-up's next
/// pass then pinned.
fn drop_swings(track: &Track, leg: &Leg, scale: f64, f: &mut [bool]) {
    let (e, hip) = (leg.end(), leg.top());
    let turns = turns(track, hip, scale, TURN_WINDOW);
    let lead = |i: usize| {
        let v = track.velocity(i, e) - track.velocity(i, hip);
        let v = flat(v) / scale;
        turns
            .as_ref()
            .map_or(v, |t| DQuat::from_rotation_y(-t[i]) * v)
    };
    let flagged: Vec<usize> = (0..f.len()).filter(|&i| f[i]).collect();
    if flagged.is_empty() {
        return;
    }
    let leads: Vec<DVec3> = flagged.iter().map(|&i| lead(i)).collect();
    let trail = leads.iter().sum::<DVec3>() / leads.len() as f64;
    let most = geometric_median(&leads);
    let toward = if trail.dot(most) >= TRAIL_AGREES * trail.length() * most.length()
        && trail.length() >= TRAIL_LONG * most.length()
    {
        trail
    } else {
        most
    };
    let Some(forward) = (-toward).try_normalize() else {
        return;
    };
    let limit = SWING_LEAD_MIN.max(SWING_LEAD * trail.length());
    for i in flagged {
        if lead(i).dot(forward) > limit {
            f[i] = false;
        }
    }
}

/// Seconds either side of a frame over which the hip's velocity gives the way a clip heads
/// there (see [`turns`]).
pub const TURN_WINDOW: f64 = 1.0;
/// A frame's hip speed counts in that average at most this many times its median over the clip.
pub const TURN_SPIKE: f64 = 3.0;
/// Least speed of the hip over such a window, in leg scales per second, for a clip to be judged
/// by its heading frame by frame (a clip in place, or standing anywhere, heads one way).
pub const TURN_SPEED: f64 = 0.3;

/// The way `track` heads at each frame (radians about +Y from +Z, unwrapped): the hip's
/// horizontal velocity averaged over `window` seconds either side ([`TURN_WINDOW`] for the swing
/// test). `None` where any window's is slower than [`TURN_SPEED`]: the clip heads one way. A
/// turning walk's swing heads sideways where it turns; judged along one forward it hardly led
/// its hip and was kept planted (Bandai Namco's walk-turn-left_feminine: touches of 0.05-0.1 s
/// inside its swings, pinned by the clean-up: blended with itself, jerk ratio 1.88; 1.11 judged
/// turn by turn).
fn turns(track: &Track, hip: usize, scale: f64, window: f64) -> Option<Vec<f64>> {
    let n = track.len();
    if n == 0 {
        return None;
    }
    let half = (window / track.dt).round() as usize;
    let v: Vec<DVec3> = (0..n)
        .map(|i| flat(track.velocity(i, hip)) / scale)
        .collect();
    // A jump of the root (takes joined end to end) counts no more than a fast frame.
    let cap = TURN_SPIKE * legs::median(v.iter().map(|v| v.length()).collect());
    let mut sum = vec![DVec3::ZERO; n + 1];
    for i in 0..n {
        sum[i + 1] = sum[i] + v[i].clamp_length_max(cap);
    }
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let (lo, hi) = (i.saturating_sub(half), (i + half).min(n - 1));
        let m = (sum[hi + 1] - sum[lo]) / (hi + 1 - lo) as f64;
        if m.length() <= TURN_SPEED {
            return None;
        }
        let a = m.x.atan2(m.z);
        let last = out.last().copied().unwrap_or(0.0);
        out.push(super::rig::unwrapped(last, a));
    }
    Some(out)
}

/// Seconds either side of a frame over which the hip's velocity gives the way a clip heads for
/// its sides and strides (see [`heads`]): a walk's sway turns it by less than 10 degrees, and a
/// walk circling in 1.8 s keeps 88% of its speed over it (over [`TURN_WINDOW`] a tenth, pointing
/// back).
pub const HEAD_WINDOW: f64 = 0.25;

/// The way `track` heads at each frame ([`turns`] over [`HEAD_WINDOW`]), or `forward`
/// throughout where it heads one way.
pub fn heads(track: &Track, hip: usize, scale: f64, forward: DVec3) -> Vec<DVec3> {
    match turns(track, hip, scale, HEAD_WINDOW) {
        Some(t) => t
            .iter()
            .map(|&a| DVec3::new(a.sin(), 0.0, a.cos()))
            .collect(),
        None => vec![forward; track.len()],
    }
}

/// The point of least summed distance to `points` (not empty; Weiszfeld's iteration from their
/// mean): the same for points turned about any axis, and within the majority's cluster.
fn geometric_median(points: &[DVec3]) -> DVec3 {
    let mut m = points.iter().sum::<DVec3>() / points.len() as f64;
    for _ in 0..GEOMETRIC_MEDIAN_STEPS {
        let (mut sum, mut weight) = (DVec3::ZERO, 0.0);
        for p in points {
            let d = p.distance(m).max(1e-12);
            sum += *p / d;
            weight += 1.0 / d;
        }
        m = sum / weight;
    }
    m
}

/// Weiszfeld steps of [`geometric_median`].
const GEOMETRIC_MEDIAN_STEPS: usize = 32;

/// The floor under a joint at each frame of `heights` (one every `dt` seconds): the
/// [`legs::floor`] of the heights within [`FLOOR_WINDOW`] of it (the window kept inside the
/// clip), taken every eighth of a window and linearly interpolated between.
fn local_floor(heights: &[f64], dt: f64) -> Vec<f64> {
    let n = heights.len();
    let half = (FLOOR_WINDOW / dt).round() as usize;
    if n <= 2 * half + 1 {
        return vec![legs::floor(heights.to_vec()); n];
    }
    let step = (half / 4).max(1);
    let at = |c: usize| {
        let lo = c.saturating_sub(half).min(n - 1 - 2 * half);
        legs::floor(heights[lo..=lo + 2 * half].to_vec())
    };
    let centres: Vec<usize> = (0..n).step_by(step).chain([n - 1]).collect();
    let values: Vec<f64> = centres.iter().map(|&c| at(c)).collect();
    (0..n)
        .map(|i| {
            let k = (i / step).min(centres.len() - 2);
            let (c0, c1) = (centres[k], centres[k + 1]);
            let u = if c1 > c0 {
                (i - c0) as f64 / (c1 - c0) as f64
            } else {
                0.0
            };
            values[k] + u * (values[k + 1] - values[k])
        })
        .collect()
}

/// Runs of equal flags as (first frame, length); on a looping track a run may wrap.
fn runs(f: &[bool], looping: bool) -> Vec<(usize, usize)> {
    let n = f.len();
    if n == 0 {
        return Vec::new();
    }
    let first = if looping {
        match (0..n).find(|&i| f[i] != f[(i + n - 1) % n]) {
            Some(i) => i,
            None => return vec![(0, n)],
        }
    } else {
        0
    };
    let mut out = Vec::new();
    let mut s = first;
    let mut len = 0;
    for k in 0..n {
        let i = (first + k) % n;
        if len > 0 && f[i] != f[s] {
            out.push((s, len));
            s = i;
            len = 0;
        }
        len += 1;
    }
    out.push((s, len));
    out
}

/// Contact intervals from per-frame flags.
pub fn intervals(track: &Track, f: &[bool]) -> Vec<Contact> {
    let mut out: Vec<Contact> = runs(f, track.looping)
        .into_iter()
        .filter(|&(s, _)| f[s])
        .map(|(s, len)| Contact {
            start: track.time(s),
            end: track.time(s) + (len - 1) as f64 * track.dt,
        })
        .collect();
    out.sort_by(|a, b| a.start.total_cmp(&b.start));
    out
}

/// Whether one of `contacts` comes within `half` of time `t` (on a looping clip of period
/// `period`, modulo it).
pub fn planted(contacts: &[Contact], t: f64, half: f64, period: Option<(f64, f64)>) -> bool {
    let near = |c: &Contact, x: f64| c.start - half <= x && x <= c.end + half;
    contacts.iter().any(|c| match period {
        Some((start, dur)) => {
            let x = start + (t - start).rem_euclid(dur);
            near(c, x) || near(c, x + dur)
        }
        None => near(c, t),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::blend::legs::Side;

    /// Frames of a one-second loop on a treadmill: 48 frames, a still hip (joint 0) 1 above the
    /// floor and a foot (joint 1) at `foot(frame, dt)`.
    fn treadmill_loop(foot: impl Fn(usize, f64) -> DVec3) -> Track {
        let n = 48;
        let dt = 1.0 / n as f64;
        Track {
            start: 0.0,
            dt,
            looping: true,
            pos: (0..n)
                .map(|i| vec![DVec3::new(0.0, 1.0, 0.0), foot(i, dt)])
                .collect(),
            travel: DVec3::ZERO,
        }
    }

    /// Leg length 1: the foot stepping back on the floor at 2 leg/s for frames 0-23, then
    /// dragged forward along the floor at `drag` leg/s for frames 24-29, then swinging forward
    /// 0.3 above the floor back to where it touches down.
    fn dragged_toe(drag: f64) -> Track {
        treadmill_loop(|i, dt| match i {
            0..=23 => DVec3::new(0.0, 0.0, 0.5 - 2.0 * dt * i as f64),
            24..=29 => DVec3::new(0.0, 0.0, -0.5 + drag * dt * (i - 23) as f64),
            _ => {
                let from = -0.5 + drag * dt * 6.0;
                let u = (i - 29) as f64 / 19.0;
                DVec3::new(0.0, 0.3, from + (0.5 - from) * u)
            }
        })
    }

    /// Leg length 1: the foot trails back at 1 leg/s for 40 frames, then swings forward at 5
    /// leg/s for 8, only 0.03 above the floor, low and level enough for the height test
    /// throughout; with `heel`, its heel lifts 0.2 at frame 20, so the height test misses frames
    /// 19-21 of the stance.
    fn shuffle(heel: bool) -> Track {
        treadmill_loop(|i, dt| {
            let z = if i <= 40 {
                0.4 - dt * i as f64
            } else {
                0.4 - dt * 40.0 + 5.0 * dt * (i - 40) as f64
            };
            let y = match i {
                20 if heel => 0.2,
                41.. => 0.03,
                _ => 0.0,
            };
            DVec3::new(0.0, y, z)
        })
    }

    fn one_leg() -> Leg {
        Leg {
            chain: vec![0, 1],
            ik: None,
            side: Side::Left,
            length: 1.0,
            name: "leg".into(),
        }
    }

    /// The mean lead of the flagged frames points forward here (the frames missed trail) or is
    /// zero but for rounding (none missed): the swing is found by the way most frames trail.
    #[test]
    fn a_low_swing_on_a_loop_is_swinging() {
        let f = flags(&shuffle(true), &one_leg(), 1.0);
        assert!((2..=18).chain(22..=38).all(|i| f[i]), "{f:?}");
        assert!((42..=46).all(|i| !f[i]), "{f:?}");
        let f = flags(&shuffle(false), &one_leg(), 1.0);
        assert!((2..=38).all(|i| f[i]), "{f:?}");
        assert!((42..=46).all(|i| !f[i]), "{f:?}");
    }

    /// Leg length 1, 30 frames a second, four strides of a second: the hip walks 1 leg/s
    /// along Z; the foot stands for 18 frames and swings 12 at 2.5 leg/s only 0.02 above the
    /// floor (flagged by the height test throughout), drifting sideways from the hip at 0.02
    /// leg/s: the flagged frames' mean lead is that drift, the swings' lead cancelling the
    /// stances' trail, and points across the walk.
    fn low_swings_drifting() -> Track {
        let dt = 1.0 / 30.0;
        let mut z = 0.0;
        let pos = (0..120)
            .map(|i| {
                let swing = i % 30 >= 18;
                if i > 0 && (i - 1) % 30 >= 18 {
                    z += 2.5 * dt;
                }
                let t = i as f64 * dt;
                let y = if swing { 0.02 } else { 0.0 };
                vec![DVec3::new(0.0, 1.0, t), DVec3::new(0.02 * t, y, z)]
            })
            .collect();
        open_track(dt, pos)
    }

    /// A track that does not loop, sampled every `dt` seconds.
    fn open_track(dt: f64, pos: Vec<Vec<DVec3>>) -> Track {
        Track {
            start: 0.0,
            dt,
            looping: false,
            pos,
            travel: DVec3::ZERO,
        }
    }

    /// A hip circling once in 1.8 s at 1.5 leg/s, swaying 0.03 leg across its way once a
    /// second (120 frames a second): the way it heads for its sides and strides ([`heads`])
    /// stays within 10 degrees of the circle's tangent where its window fits in the clip, and
    /// within 30 at the ends (a window cut short there heads along its chord, turned by half its
    /// turn); over the swing test's window ([`TURN_WINDOW`]) it keeps too little of its speed
    /// and heads one way.
    #[test]
    fn a_walk_circling_heads_round_its_circle() {
        let dt = 1.0 / 120.0;
        let (rate, speed) = (std::f64::consts::TAU / 1.8, 1.5);
        let radius = speed / rate;
        let at = |i: usize| {
            let (t, a) = (i as f64 * dt, rate * i as f64 * dt);
            let sway = 0.03 * (std::f64::consts::TAU * t).sin();
            DVec3::new(-a.cos(), 0.0, a.sin()) * (radius + sway) + DVec3::Y
        };
        let track = open_track(dt, (0..360).map(|i| vec![at(i)]).collect());
        assert!(turns(&track, 0, 1.0, TURN_WINDOW).is_none());
        let heads = heads(&track, 0, 1.0, DVec3::Z);
        for (i, h) in heads.iter().enumerate() {
            let a = rate * i as f64 * dt;
            let tangent = DVec3::new(a.sin(), 0.0, a.cos());
            let off = h.angle_between(tangent).to_degrees();
            let inside = (30..330).contains(&i);
            assert!(
                off < if inside { 10.0 } else { 30.0 },
                "frame {i}: {off} degrees"
            );
        }
    }

    /// A hip walking 1 leg/s round a circle (a quarter turn a second, 30 frames a second), one
    /// walking straight that jumps back half way (takes joined end to end), and one standing:
    /// the way the first heads turns by a quarter turn a second, the second's does not turn
    /// (the jump counts as one fast frame), the standing one heads one way.
    #[test]
    fn a_turning_walk_heads_where_its_hip_goes() {
        let dt = 1.0 / 30.0;
        let rate = std::f64::consts::FRAC_PI_2;
        let at = |i: usize| {
            let a = rate * i as f64 * dt;
            DVec3::new((1.0 - a.cos()) / rate, 1.0, a.sin() / rate)
        };
        let track = |pos: Vec<Vec<DVec3>>| open_track(dt, pos);
        let walk: Vec<Vec<DVec3>> = (0..150).map(|i| vec![at(i)]).collect();
        let t = turns(&track(walk), 0, 1.0, TURN_WINDOW).expect("it walks");
        for i in [40, 75, 110] {
            let slope = (t[i + 1] - t[i - 1]) / (2.0 * dt);
            assert!((slope - rate).abs() < 0.02 * rate, "frame {i}: {slope}");
        }
        // Straight ahead at 1 leg/s, jumping back 2.5 legs every 75 frames.
        let jumped: Vec<Vec<DVec3>> = (0..150)
            .map(|i| vec![DVec3::new(0.0, 1.0, (i % 75) as f64 * dt)])
            .collect();
        let t = turns(&track(jumped), 0, 1.0, TURN_WINDOW).expect("it walks");
        let most = t.iter().fold(0.0f64, |m, a| m.max(a.abs()));
        assert!(most < 1e-9, "{most}");
        let stands: Vec<Vec<DVec3>> = (0..150).map(|_| vec![DVec3::Y]).collect();
        assert!(turns(&track(stands), 0, 1.0, TURN_WINDOW).is_none());
    }

    /// The mean lead of the flagged frames is short and points across the walk: forward is
    /// taken from the way most frames trail, and the swings are found (a walk backwards on a
    /// cleaned pass, flagged on 124 of 127 frames, had its swings kept planted).
    #[test]
    fn a_low_swing_whose_mean_lead_points_across_is_swinging() {
        let f = flags(&low_swings_drifting(), &one_leg(), 1.0);
        for c in 0..4 {
            let at = |k: usize| f[30 * c + k];
            assert!((2..=16).all(at), "stride {c}: {f:?}");
            assert!((20..=27).all(|k| !at(k)), "stride {c}: {f:?}");
        }
    }

    /// Leg length 1, 30 frames a second, four strides of a second: the hip walks 1 leg/s along
    /// Z; the foot stands 18 frames and swings 12 leading its hip by 1.2 leg/s only 0.02 above
    /// the floor, sliding across the walk at 0.1 leg/s throughout. The flagged frames' mean
    /// lead, (0.1, -0.12), is 0.16 of their median's length at 34 degrees from it: along it the
    /// swings lead by 0.86 leg/s, under [`SWING_LEAD_MIN`], and were kept planted; along the
    /// median by 1.18.
    #[test]
    fn a_low_swing_whose_mean_lead_is_short_is_swinging() {
        let dt = 1.0 / 30.0;
        let mut z = 0.0;
        let pos = (0..120)
            .map(|i| {
                if i > 0 && (i - 1) % 30 >= 18 {
                    z += 2.2 * dt;
                }
                let t = i as f64 * dt;
                let y = if i % 30 >= 18 { 0.02 } else { 0.0 };
                vec![DVec3::new(0.0, 1.0, t), DVec3::new(0.1 * t, y, z)]
            })
            .collect();
        let f = flags(&open_track(dt, pos), &one_leg(), 1.0);
        for c in 0..4 {
            let at = |k: usize| f[30 * c + k];
            assert!((2..=16).all(at), "stride {c}: {f:?}");
            assert!((20..=27).all(|k| !at(k)), "stride {c}: {f:?}");
        }
    }

    #[test]
    fn a_toe_dragged_forward_fast_is_swinging_and_a_slow_one_planted() {
        let leg = one_leg();
        // Dragged at 4 leg/s: it leads its hip by twice the body's speed (2 leg/s) and more.
        let fast = flags(&dragged_toe(4.0), &leg, 1.0);
        assert!((1..=22).all(|i| fast[i]), "{fast:?}");
        assert!((24..=29).all(|i| !fast[i]), "{fast:?}");
        // Dragged at 1 leg/s it stays planted: half the body's speed, the foot still trailing
        // the ground it left.
        let slow = flags(&dragged_toe(1.0), &leg, 1.0);
        assert!(
            (1..=22).all(|i| slow[i]) && (25..=28).all(|i| slow[i]),
            "{slow:?}"
        );
    }

    /// Leg length 1, a hip walking 1 leg/s along Z over still ground, 48 frames a second: the
    /// foot lands at frame 4 still sliding back at `land` leg/s, eases to a stop by frame 8,
    /// stands until frame 30, then drags forward low at 1 leg/s (the heel still down, as a walk
    /// backwards lifts its toe) until frame 34, and swings high after.
    fn landing(land: f64) -> Track {
        let dt = 1.0 / 48.0;
        let mut z = 0.0;
        let pos = (0..48)
            .map(|i| {
                let v = match i {
                    0..=3 => 3.0,
                    4..=7 => land * (8 - i) as f64 / 4.0,
                    8..=29 => 0.0,
                    30..=33 => 1.0,
                    _ => 2.0,
                };
                z += v * dt;
                let y = if (4..=33).contains(&i) { 0.0 } else { 0.3 };
                vec![DVec3::new(0.0, 1.0, i as f64 * dt), DVec3::new(0.0, y, z)]
            })
            .collect();
        open_track(dt, pos)
    }

    /// A touch, too short to settle or not, is dropped where the foot moves over the ground
    /// under its other contacts (3 leg/s before it lands) and kept where it stands with them.
    #[test]
    fn a_touch_is_kept_only_where_the_foot_stands() {
        let leg = one_leg();
        let track = landing(0.0);
        let flagged = |runs: &[std::ops::RangeInclusive<usize>]| -> Vec<bool> {
            (0..48)
                .map(|i| runs.iter().any(|r| r.contains(&i)))
                .collect()
        };
        // (Frame 29 moves off at 0.5 leg/s, its neighbour dragging: settled off either way.)
        let cases = [
            // Two frames moving at 3 leg/s, too short to settle: dropped.
            (vec![1..=2, 8..=29], vec![8..=28]),
            (vec![12..=13, 20..=29], vec![12..=13, 20..=28]),
            // Four frames, long enough to settle, moving at 3 leg/s throughout: dropped whole.
            (vec![0..=3, 8..=29], vec![8..=28]),
            (vec![10..=14, 20..=29], vec![10..=14, 20..=28]),
        ];
        for (touched, kept) in cases {
            let mut f = flagged(&touched);
            settle(&track, &leg, 1.0, &mut f);
            assert_eq!(f, flagged(&kept), "{touched:?}");
        }
    }

    /// A foot low on the floor but still moving over it at either end of its contact touches
    /// the floor there and stands planted only where it stops; one sliding through its whole
    /// contact stays planted throughout (its sliding is measured).
    #[test]
    fn a_foot_stands_planted_from_where_it_stops_to_where_it_moves_off() {
        let leg = one_leg();
        let track = landing(1.6);
        let touch = flags(&track, &leg, 1.0);
        assert!((5..=32).all(|i| touch[i]), "{touch:?}");
        let planted = planted_flags(&track, &leg, 1.0);
        let kept: Vec<usize> = (0..48).filter(|&i| planted[i]).collect();
        assert!(
            kept.first() >= Some(&6) && kept.first() <= Some(&8),
            "{kept:?}"
        );
        assert!(
            kept.last() >= Some(&28) && kept.last() <= Some(&29),
            "{kept:?}"
        );
        // Sliding at 0.2 leg/s through its stance: below the settling speed, all kept.
        let mut sliding = landing(0.2);
        for (i, p) in sliding.pos.iter_mut().enumerate() {
            p[1].x += 0.2 * i as f64 * sliding.dt;
        }
        let touch = flags(&sliding, &leg, 1.0);
        let planted = planted_flags(&sliding, &leg, 1.0);
        assert!(
            (0..48)
                .filter(|&i| touch[i] && !planted[i])
                .all(|i| i >= 29),
            "{planted:?}"
        );
    }
}
