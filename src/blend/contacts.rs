//! Foot contacts (the seed's test): a foot is planted while it is near its floor and barely
//! moves vertically. Horizontal speed is not part of the test, so sliding can be measured on
//! the contacts it finds.

use super::legs::{self, Leg};
use super::track::Track;
use serde::Serialize;

/// Height above the foot's lowest point, as a fraction of the leg scale.
pub const HEIGHT_TOLERANCE: f64 = 0.06;
/// Vertical speed, in leg scales per second.
pub const SPEED_TOLERANCE: f64 = 1.5;
/// Shortest contact kept, in seconds; shorter gaps between contacts are closed.
pub const MIN_CONTACT: f64 = 0.03;
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

/// Per-frame contact flags of `leg` on `track`; `scale` is the character's leg length.
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
    let short = ((MIN_CONTACT / track.dt).ceil() as usize).max(1);
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
