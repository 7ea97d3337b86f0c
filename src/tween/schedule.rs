//! Schedule stage: where the output frames of a track lie in time, and between which keys.

use super::keys::Track;
use super::options::{Timing, TweenOptions};
use super::timegrid::ON_GRID;

/// One output frame of a track: the time and where it falls between keys.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameAt {
    pub time: f64,
    /// The segment's start and end keys (equal for a track with a single key time).
    pub key_a: usize,
    pub key_b: usize,
    /// Position within the segment, 0 at `key_a`, 1 at `key_b`.
    pub t: f64,
}

impl FrameAt {
    /// The key this frame is, when it lies exactly on one.
    pub fn key(&self) -> Option<usize> {
        if self.t == 0.0 {
            Some(self.key_a)
        } else if self.t == 1.0 {
            Some(self.key_b)
        } else {
            None
        }
    }
}

/// Most frames one track may have (a bound checked before any is planned): an hour at 277
/// frames a second. Key times or options asking for more are refused.
pub const MAX_FRAMES: f64 = 1e6;

/// About how many frames [`plan`] gives a track with keys at `times` (an upper bound, found
/// without planning them).
pub fn frame_estimate(times: &[f64], opts: &TweenOptions) -> f64 {
    let segments = times.windows(2).filter(|w| w[1] > w[0]).count() as f64;
    let span = times.last().copied().unwrap_or(0.0) - times.first().copied().unwrap_or(0.0);
    let gaps = || times.windows(2).map(|w| w[1] - w[0]).filter(|d| *d > 0.0);
    let (frames, spacing) = match opts.timing {
        Timing::Tweens(n) => {
            let per = n as f64 + 1.0;
            let shortest = gaps().fold(f64::INFINITY, f64::min);
            (segments * per + 1.0, shortest / per)
        }
        Timing::Rate(rate) => {
            let frames: f64 = gaps().map(|g| (g * rate).round().max(1.0)).sum();
            (frames + 1.0, 1.0 / rate)
        }
        Timing::Fps(fps) => (span * fps + 2.0, 1.0 / fps),
    };
    let [before, after] = opts.extend;
    let extra = if spacing > 0.0 && spacing.is_finite() {
        (before.max(0.0) + after.max(0.0)) / spacing
    } else {
        0.0
    };
    frames + extra + 1.0
}

/// Frames inserted between two keys `gap` seconds apart by `timing` (`Fps` places its own).
fn tweens_between(gap: f64, timing: Timing) -> usize {
    match timing {
        Timing::Tweens(n) => n,
        Timing::Rate(rate) => ((gap * rate).round() as usize).saturating_sub(1),
        Timing::Fps(_) => 0,
    }
}

/// Frame times for keys at `times` (non-decreasing).
pub fn schedule(times: &[f64], timing: Timing) -> Vec<FrameAt> {
    // Segments of positive duration, in order.
    let segments: Vec<(usize, usize)> = (0..times.len().saturating_sub(1))
        .filter(|&k| times[k + 1] > times[k])
        .map(|k| (k, k + 1))
        .collect();
    let Some(&(a, b)) = segments.last() else {
        return vec![FrameAt {
            time: times[0],
            key_a: 0,
            key_b: 0,
            t: 0.0,
        }];
    };
    let last = last_of(times, a, b);
    let mut out = Vec::new();
    if let Timing::Fps(fps) = timing {
        out = fixed_rate(times, &segments, fps);
        // The last key is always a frame.
        if out.last().is_some_and(|f| f.time < last.time) {
            out.push(last);
        }
        return out;
    }
    // Keys at one time are a cut (the pose jumps there): every key is still a frame, the
    // frames at a cut sharing its time (the writers keep their times apart by the smallest
    // step their formats store, so both sides of the jump play as authored).
    let key = |k: usize| FrameAt {
        time: times[k],
        key_a: k,
        key_b: k,
        t: 0.0,
    };
    for k in 0..segments[0].0 {
        out.push(key(k));
    }
    for (i, &(a, b)) in segments.iter().enumerate() {
        let n = tweens_between(times[b] - times[a], timing);
        for j in 0..=n {
            let t = j as f64 / (n + 1) as f64;
            out.push(FrameAt {
                time: times[a] + (times[b] - times[a]) * t,
                key_a: a,
                key_b: b,
                t,
            });
        }
        let next = segments.get(i + 1).map_or(times.len(), |s| s.0);
        if next > b {
            out.push(last_of(times, a, b));
            for k in b + 1..next {
                out.push(key(k));
            }
        }
    }
    out
}

/// The frame on key b of segment (a, b).
fn last_of(times: &[f64], a: usize, b: usize) -> FrameAt {
    FrameAt {
        time: times[b],
        key_a: a,
        key_b: b,
        t: 1.0,
    }
}

/// Frames every 1/fps s from the first key; one that falls on the last key (within
/// [`ON_GRID`] of a frame) is that key.
fn fixed_rate(times: &[f64], segments: &[(usize, usize)], fps: f64) -> Vec<FrameAt> {
    let start = times[segments[0].0];
    let end = times[segments[segments.len() - 1].1];
    let count = ((end - start) * fps + ON_GRID).floor() as usize;
    let mut seg = 0;
    let mut out = Vec::with_capacity(count + 2);
    for i in 0..=count {
        let mut time = start + i as f64 / fps;
        if i == count && (time - end).abs() * fps <= ON_GRID {
            time = end;
        }
        while seg + 1 < segments.len() && time >= times[segments[seg].1] {
            seg += 1;
        }
        let (a, b) = segments[seg];
        let t = ((time - times[a]) / (times[b] - times[a])).min(1.0);
        out.push(FrameAt {
            time,
            key_a: a,
            key_b: b,
            t,
        });
    }
    out
}

/// Frames of a track with keys at `times`: [`schedule`] plus the extensions of `opts`, which
/// continue the first and last segments' motion (t < 0 before the first key, t > 1 after the
/// last) at the frame spacing next to them.
pub fn plan(times: &[f64], opts: &TweenOptions) -> Vec<FrameAt> {
    let mut frames = schedule(times, opts.timing);
    let [before, after] = opts.extend;
    if frames.len() < 2 {
        return frames;
    }
    let span = |f: &FrameAt| times[f.key_b] - times[f.key_a];
    // `seconds` more of the segment of `from`, at `spacing` (negative: backwards in time),
    // nearest to `from` first.
    let continued = |from: FrameAt, spacing: f64, seconds: f64| -> Vec<FrameAt> {
        let n = (seconds.max(0.0) / spacing.abs() + 1e-9).floor() as usize;
        (1..=n)
            .map(|k| {
                let time = from.time + k as f64 * spacing;
                FrameAt {
                    time,
                    key_a: from.key_a,
                    key_b: from.key_b,
                    t: (time - times[from.key_a]) / span(&from),
                }
            })
            .collect()
    };
    // The first and last segments' own frames (keys repeated at a track's ends, a cut there,
    // are frames of no segment), and the spacing next to them.
    let in_segment = |f: &FrameAt| f.key_a != f.key_b;
    let (Some(i), Some(j)) = (
        frames.iter().position(in_segment),
        frames.iter().rposition(in_segment),
    ) else {
        return frames;
    };
    let (first, last) = (frames[i], frames[j]);
    let spacing = frames[i + 1].time - first.time;
    let mut ext = Vec::new();
    if spacing > 0.0 {
        ext = continued(first, -spacing, before);
        ext.reverse();
    }
    let spacing = last.time - frames[j - 1].time;
    if spacing > 0.0 {
        frames.extend(continued(last, spacing, after));
    }
    frames.splice(0..0, ext);
    frames
}

/// Close a track into a loop (`--loop`): unless its last key already equals its first, append
/// the first key again, one mean key spacing after the last.
pub fn close_loop(track: &mut Track) {
    let (k, times) = (track.times.len(), &track.times);
    if k < 2 || track.weights[k - 1] == track.weights[0] {
        return;
    }
    let spacing = (times[k - 1] - times[0]) / (k - 1) as f64;
    let spacing = if spacing > 0.0 { spacing } else { 1.0 };
    track.times.push(times[k - 1] + spacing);
    track.weights.push(track.weights[0].clone());
    if let Some(eases) = &mut track.eases {
        eases.push(eases[0].clone());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// (time, the key it is, if any) of each frame.
    fn frames(times: &[f64], timing: Timing) -> Vec<(f64, Option<usize>)> {
        schedule(times, timing)
            .iter()
            .map(|f| (f.time, f.key()))
            .collect()
    }

    #[test]
    fn keys_at_one_time_are_a_cut_with_every_key_a_frame() {
        let tw = Timing::Tweens(1);
        assert_eq!(
            frames(&[0.0, 1.0, 2.0], tw),
            [
                (0.0, Some(0)),
                (0.5, None),
                (1.0, Some(1)),
                (1.5, None),
                (2.0, Some(2))
            ]
        );
        // Interior cut: key 1 ends the first segment, key 2 starts the next at the same time.
        assert_eq!(
            frames(&[0.0, 1.0, 1.0, 2.0], tw),
            [
                (0.0, Some(0)),
                (0.5, None),
                (1.0, Some(1)),
                (1.0, Some(2)),
                (1.5, None),
                (2.0, Some(3))
            ]
        );
        // Three keys at one time, and cuts at both ends.
        assert_eq!(
            frames(&[0.0, 0.0, 1.0, 1.0, 1.0, 2.0, 2.0], Timing::Tweens(0)),
            [
                (0.0, Some(0)),
                (0.0, Some(1)),
                (1.0, Some(2)),
                (1.0, Some(3)),
                (1.0, Some(4)),
                (2.0, Some(5)),
                (2.0, Some(6))
            ]
        );
        // Every frame between keys has a finite position in its segment.
        for f in schedule(&[0.0, 0.5, 0.5, 1.5], Timing::Rate(30.0)) {
            assert!(f.t.is_finite() && f.key_a <= f.key_b, "{f:?}");
        }
    }

    #[test]
    fn extensions_continue_the_segments_next_to_a_cut_at_the_ends() {
        let opts = TweenOptions {
            timing: Timing::Tweens(1),
            extend: [1.0, 1.0],
            ..TweenOptions::default()
        };
        let f = plan(&[0.0, 0.0, 1.0, 1.0], &opts);
        let times: Vec<f64> = f.iter().map(|f| f.time).collect();
        assert_eq!(times, [-1.0, -0.5, 0.0, 0.0, 0.5, 1.0, 1.0, 1.5, 2.0]);
        assert!(f.iter().all(|f| f.t.is_finite()));
    }
}
