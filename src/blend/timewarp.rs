//! Time warp by contact events: within a cycle, each foot's touchdown and lift-off in one clip is
//! matched with the same event of the same foot in the other, and the phase map passes through
//! the matched events (keytimes) on a monotone cubic ([`Warp::map`]), so feet land together in
//! the blend, as long as no segment between them plays a clip faster than [`MAX_WARP_SLOPE`]. The
//! blended cycle places each event at the weighted blend of its two phases.

use super::contacts::Contact;

/// Steepest phase map allowed (unitless: phase of a source per blended phase): between two
/// matched events no source plays faster on average than twice its cycle's rate nor slower than
/// half, as registration curves bound their slope (the monotone cubic through the events may
/// pass it inside a segment whose ends turn slower: at most 2.75 where a segment at 2 has ends
/// at 0.5). Matching every contact event of a walk (long stances) with a run's
/// (stances of one or two frames) otherwise nearly freezes one clip and races the other: on
/// RobotExpressive the rates ran from 0.05 to 3.6 and the blend's jerk was 1.5-2.0 times the
/// sources'.
pub const MAX_WARP_SLOPE: f64 = 2.0;

/// Events closer than this (in phase) to each other or to a cycle end are not used as knots.
pub const MIN_KNOT_GAP: f64 = 1e-3;

#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Kind {
    Touchdown,
    Liftoff,
}

/// A contact event at `phase` in [0, 1) of a cycle.
#[derive(Clone, Copy, Debug)]
pub struct Event {
    pub leg: usize,
    pub kind: Kind,
    pub phase: f64,
}

/// The events of one cycle `(start, period)` from each leg's contacts (`looping` wraps them).
pub fn events(contacts: &[Vec<Contact>], start: f64, period: f64, looping: bool) -> Vec<Event> {
    let mut out = Vec::new();
    for (leg, list) in contacts.iter().enumerate() {
        for c in list {
            for (kind, t) in [(Kind::Touchdown, c.start), (Kind::Liftoff, c.end)] {
                let x = (t - start) / period;
                if looping {
                    out.push(Event {
                        leg,
                        kind,
                        phase: x.rem_euclid(1.0),
                    });
                } else if (0.0..1.0).contains(&x) {
                    out.push(Event {
                        leg,
                        kind,
                        phase: x,
                    });
                }
            }
        }
    }
    out
}

/// Phase map of one blended cycle through its knots (blended, A, B), increasing in all
/// three, from (0, 0, 0) to (1, 1, 1) ([`Warp::map`]).
#[derive(Clone, Debug)]
pub struct Warp {
    pub knots: Vec<[f64; 3]>,
    /// Slopes of A's and B's phase at the cycle's start and end ([start, end], each [A, B]),
    /// where the cycles round it set them (see [`Warp::join`]); else each end segment's own.
    pub ends: [Option<[f64; 2]>; 2],
}

impl Warp {
    /// Match `a`'s events with `b`'s and blend their phases with weight `w` (0 = all A).
    pub fn new(a: &[Event], b: &[Event], w: f64) -> Warp {
        let mut pairs: Vec<(f64, f64)> = Vec::new();
        for ea in a {
            let same = |e: &&Event| e.leg == ea.leg && e.kind == ea.kind;
            let dist = |x: f64, y: f64| {
                let d = (x - y).rem_euclid(1.0);
                d.min(1.0 - d)
            };
            let Some(eb) = b
                .iter()
                .filter(same)
                .min_by(|p, q| dist(p.phase, ea.phase).total_cmp(&dist(q.phase, ea.phase)))
            else {
                continue;
            };
            // Mutual nearest only.
            let back = a
                .iter()
                .filter(|e| e.leg == eb.leg && e.kind == eb.kind)
                .min_by(|p, q| dist(p.phase, eb.phase).total_cmp(&dist(q.phase, eb.phase)));
            if back.map(|e| e.phase) != Some(ea.phase) {
                continue;
            }
            let mut pb = eb.phase;
            if pb - ea.phase > 0.5 {
                pb -= 1.0;
            } else if ea.phase - pb > 0.5 {
                pb += 1.0;
            }
            let inside = |x: f64| (MIN_KNOT_GAP..=1.0 - MIN_KNOT_GAP).contains(&x);
            if inside(ea.phase) && inside(pb) {
                pairs.push((ea.phase, pb));
            }
        }
        pairs.sort_by(|p, q| p.0.total_cmp(&q.0));
        let kept = increasing(&pairs);
        let mut knots = vec![[0.0, 0.0, 0.0]];
        for (pa, pb) in kept {
            let last = knots.last().unwrap();
            if pa - last[1] >= MIN_KNOT_GAP && pb - last[2] >= MIN_KNOT_GAP {
                knots.push([(1.0 - w) * pa + w * pb, pa, pb]);
            }
        }
        knots.push([1.0, 1.0, 1.0]);
        Warp {
            knots: gentlest(&knots),
            ends: [None; 2],
        }
    }

    /// Phases in A and B at blended phase `u` in [0, 1]: each a monotone cubic through the
    /// knots (see [`monotone`]), so a clip's rate changes smoothly where a segment meets the next
    /// (and, [`Warp::join`]ed, where its cycle meets the next).
    pub fn map(&self, u: f64) -> (f64, f64) {
        let u = u.clamp(0.0, 1.0);
        let k = self
            .knots
            .windows(2)
            .position(|w| u <= w[1][0])
            .unwrap_or(self.knots.len() - 2);
        (
            monotone(&self.knots, 1, k, u, self.ends.map(|e| e.map(|e| e[0]))),
            monotone(&self.knots, 2, k, u, self.ends.map(|e| e.map(|e| e[1]))),
        )
    }

    /// Make the rates of A and B run on where `left`'s cycle ends and `right`'s begins: each
    /// clip's rate there (its phase slope times its cycle's period over the blended one's,
    /// `pl` and `pr` [A, B, blended] of each) the weighted harmonic mean of the two end
    /// segments'.
    pub fn join(left: &mut Warp, right: &mut Warp, pl: [f64; 3], pr: [f64; 3]) {
        let (kl, kr) = (&left.knots, &right.knots);
        let n = kl.len();
        // The end segments' lengths in seconds of blend.
        let wl = (kl[n - 1][0] - kl[n - 2][0]) * pl[2];
        let wr = (kr[1][0] - kr[0][0]) * pr[2];
        let mut end = [0.0; 2];
        let mut start = [0.0; 2];
        for c in 0..2 {
            let rl = (kl[n - 1][c + 1] - kl[n - 2][c + 1]) * pl[c] / wl;
            let rr = (kr[1][c + 1] - kr[0][c + 1]) * pr[c] / wr;
            let m = knot_slope(rl, wl, rr, wr);
            end[c] = m * pl[2] / pl[c];
            start[c] = m * pr[2] / pr[c];
        }
        left.ends[1] = Some(end);
        right.ends[0] = Some(start);
    }
}

/// Column `c` (1: A, 2: B) of `knots` against their blended phase at `u` in segment `k`: the
/// cubic Hermite curve through the knots whose slope at each inner knot is the weighted harmonic
/// mean of its two segments' (Fritsch and Butland's, monotone, between the two: within the
/// warp's limit where they are), the segment's own at the first and last. Piecewise linear, a
/// clip's rate jumped at every knot, four to six a cycle, each a kick in the blend's jerk:
/// Bandai Namco's walks backwards and sideways in 14 styles blended with the normal one and 15
/// dashes with their runs (171 cells) had jerk ratios above 1.15 in 4 (1 now, mean 0.968 ->
/// 0.952), each style's walk with its walk backwards and with its dash and its walk-left with its
/// walk-right (135) in 17 (8). The cost is where a
/// segment is short between two long ones, its curve bends more than its line: Fox's Walk and
/// Run through gltfpack (30 keys a second) 0.82 / 1.02 / 1.01 -> 0.94 / 1.08 / 1.03.
fn monotone(knots: &[[f64; 3]], c: usize, k: usize, u: f64, ends: [Option<f64>; 2]) -> f64 {
    let n = knots.len();
    let width = |j: usize| knots[j + 1][0] - knots[j][0];
    let secant = |j: usize| {
        let h = width(j);
        if h > 0.0 {
            (knots[j + 1][c] - knots[j][c]) / h
        } else {
            0.0
        }
    };
    let slope = |j: usize| -> f64 {
        if j == 0 {
            return ends[0].unwrap_or_else(|| secant(0));
        }
        if j == n - 1 {
            return ends[1].unwrap_or_else(|| secant(n - 2));
        }
        knot_slope(secant(j - 1), width(j - 1), secant(j), width(j))
    };
    let h = width(k);
    if h <= 0.0 {
        return knots[k][c];
    }
    let t = (u - knots[k][0]) / h;
    let (t2, t3) = (t * t, t * t * t);
    knots[k][c] * (2.0 * t3 - 3.0 * t2 + 1.0)
        + slope(k) * h * (t3 - 2.0 * t2 + t)
        + knots[k + 1][c] * (3.0 * t2 - 2.0 * t3)
        + slope(k + 1) * h * (t3 - t2)
}

/// Slope at a knot between a segment of slope `a` and width `h0` and the next, of slope `b`
/// and width `h1`: their harmonic mean weighted as Fritsch and Butland weigh it (monotone,
/// between the two), or flat where either is not rising.
fn knot_slope(a: f64, h0: f64, b: f64, h1: f64) -> f64 {
    if a <= 0.0 || b <= 0.0 {
        return 0.0;
    }
    let (w0, w1) = (2.0 * h1 + h0, h1 + 2.0 * h0);
    (w0 + w1) / (w0 / a + w1 / b)
}

/// The most knots of `knots` (first and last kept) no segment between which plays a clip
/// faster than [`MAX_WARP_SLOPE`] times its cycle's rate or slower than its inverse; of as
/// many, the gentlest (least steep segment the steepest).
fn gentlest(knots: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let n = knots.len();
    let limit = MAX_WARP_SLOPE.ln() + 1e-12;
    // best[j]: (knots kept up to j, steepest so far, previous kept knot).
    let mut best: Vec<Option<(usize, f64, usize)>> = vec![None; n];
    best[0] = Some((1, 0.0, 0));
    for j in 1..n {
        for i in 0..j {
            let Some((count, steep, _)) = best[i] else {
                continue;
            };
            let s = steepest(&[knots[i], knots[j]]);
            if s > limit {
                continue;
            }
            let cand = (count + 1, steep.max(s), i);
            let better = match best[j] {
                None => true,
                Some((c, st, _)) => cand.0 > c || (cand.0 == c && cand.1 < st),
            };
            if better {
                best[j] = Some(cand);
            }
        }
    }
    let mut out = vec![knots[n - 1]];
    let mut j = n - 1;
    while j > 0 {
        j = best[j]
            .expect("the first and last knots are always within the limit")
            .2;
        out.push(knots[j]);
    }
    out.reverse();
    out
}

/// The largest |ln slope| of A's or B's phase against the blended phase over `knots`.
fn steepest(knots: &[[f64; 3]]) -> f64 {
    knots
        .windows(2)
        .flat_map(|k| {
            let du = k[1][0] - k[0][0];
            [1, 2].map(|c| ((k[1][c] - k[0][c]) / du).ln().abs())
        })
        .fold(0.0, f64::max)
}

/// The longest subsequence of `pairs` (sorted by their first value) whose second values
/// increase too.
fn increasing(pairs: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let n = pairs.len();
    let mut len = vec![1usize; n];
    let mut prev = vec![usize::MAX; n];
    for i in 0..n {
        for j in 0..i {
            if pairs[j].1 < pairs[i].1 && pairs[j].0 < pairs[i].0 && len[j] + 1 > len[i] {
                len[i] = len[j] + 1;
                prev[i] = j;
            }
        }
    }
    let Some(mut i) = (0..n).max_by_key(|&i| (len[i], usize::MAX - i)) else {
        return Vec::new();
    };
    let mut out = vec![pairs[i]];
    while prev[i] != usize::MAX {
        i = prev[i];
        out.push(pairs[i]);
    }
    out.reverse();
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ev(leg: usize, kind: Kind, phase: f64) -> Event {
        Event { leg, kind, phase }
    }

    #[test]
    fn weight_zero_is_identity_on_a_and_events_meet() {
        let a = [ev(0, Kind::Liftoff, 0.3), ev(1, Kind::Touchdown, 0.5)];
        let b = [ev(0, Kind::Liftoff, 0.4), ev(1, Kind::Touchdown, 0.55)];
        let w0 = Warp::new(&a, &b, 0.0);
        for u in [0.0, 0.2, 0.3, 0.45, 0.9, 1.0] {
            assert!((w0.map(u).0 - u).abs() < 1e-12);
        }
        let half = Warp::new(&a, &b, 0.5);
        let (pa, pb) = half.map(0.35);
        assert!((pa - 0.3).abs() < 1e-12 && (pb - 0.4).abs() < 1e-12);
    }

    /// The map passes through every knot, rises throughout, and a clip's rate (its slope) runs
    /// on through each knot instead of jumping there.
    #[test]
    fn a_clips_rate_changes_smoothly_through_the_knots() {
        let a = [ev(0, Kind::Liftoff, 0.3), ev(1, Kind::Touchdown, 0.5)];
        let b = [ev(0, Kind::Liftoff, 0.4), ev(1, Kind::Touchdown, 0.55)];
        let warp = Warp::new(&a, &b, 0.5);
        assert_eq!(warp.knots.len(), 4);
        let h = 1e-6;
        for k in &warp.knots[1..3] {
            let (pa, pb) = warp.map(k[0]);
            assert!((pa - k[1]).abs() < 1e-12 && (pb - k[2]).abs() < 1e-12);
            let (l, r) = (warp.map(k[0] - h), warp.map(k[0] + h));
            let (left, right) = ((pa - l.0) / h, (r.0 - pa) / h);
            assert!(
                (left - right).abs() < 1e-4,
                "A's rate {left} -> {right} at {k:?}"
            );
            let (left, right) = ((pb - l.1) / h, (r.1 - pb) / h);
            assert!(
                (left - right).abs() < 1e-4,
                "B's rate {left} -> {right} at {k:?}"
            );
        }
        let mut last = (-1.0, -1.0);
        for i in 0..=1000 {
            let m = warp.map(i as f64 / 1000.0);
            assert!(m.0 > last.0 && m.1 > last.1, "{i}: {m:?} after {last:?}");
            last = m;
        }
    }

    /// Joined, each clip's rate in seconds of clip per second of blend runs on from the end of
    /// one cycle (A 1.0 s, B 0.8 s, blended 0.9 s) into the next (A 1.1 s, B 0.7 s, 0.9 s).
    #[test]
    fn joined_cycles_keep_each_clips_rate_across_their_seam() {
        let mut left = Warp::new(
            &[ev(0, Kind::Liftoff, 0.6)],
            &[ev(0, Kind::Liftoff, 0.7)],
            0.5,
        );
        let mut right = Warp::new(
            &[ev(0, Kind::Liftoff, 0.3)],
            &[ev(0, Kind::Liftoff, 0.2)],
            0.5,
        );
        let (pl, pr) = ([1.0, 0.8, 0.9], [1.1, 0.7, 0.9]);
        let h = 1e-6;
        let rates = |l: &Warp, r: &Warp| {
            let (e0, e1) = (l.map(1.0 - h), l.map(1.0));
            let (s0, s1) = (r.map(0.0), r.map(h));
            [
                (
                    (e1.0 - e0.0) * pl[0] / (h * pl[2]),
                    (s1.0 - s0.0) * pr[0] / (h * pr[2]),
                ),
                (
                    (e1.1 - e0.1) * pl[1] / (h * pl[2]),
                    (s1.1 - s0.1) * pr[1] / (h * pr[2]),
                ),
            ]
        };
        let apart = rates(&left, &right);
        assert!(apart.iter().all(|(a, b)| (a - b).abs() > 0.1), "{apart:?}");
        Warp::join(&mut left, &mut right, pl, pr);
        for (end, start) in rates(&left, &right) {
            assert!((end - start).abs() < 1e-4, "{end} -> {start}");
        }
        // The knots are still passed through.
        assert!((left.map(left.knots[1][0]).0 - 0.6).abs() < 1e-12);
        assert!((right.map(right.knots[1][0]).1 - 0.2).abs() < 1e-12);
    }

    #[test]
    fn no_segment_is_steeper_than_the_limit() {
        // A walk's lift-off at 0.3 (a long stance) against a run's at 0.05 (a stance of a frame
        // or two): matching them would play B at 0.29 times its rate, then A at 0.62.
        let a = [ev(0, Kind::Liftoff, 0.3), ev(1, Kind::Touchdown, 0.5)];
        let b = [ev(0, Kind::Liftoff, 0.05), ev(1, Kind::Touchdown, 0.5)];
        let warp = Warp::new(&a, &b, 0.5);
        assert!(steepest(&warp.knots) <= MAX_WARP_SLOPE.ln() + 1e-12);
        assert_eq!(warp.knots.len(), 3);
        // The touchdowns still meet; the lift-offs do not.
        let u = warp
            .knots
            .iter()
            .find(|k| (k[1] - 0.5).abs() < 1e-12)
            .unwrap()[0];
        let (pa, pb) = warp.map(u);
        assert!((pa - 0.5).abs() < 1e-12 && (pb - 0.5).abs() < 1e-12);
        // Gentle warps keep every matched event.
        let b = [ev(1, Kind::Touchdown, 0.45), ev(1, Kind::Liftoff, 0.15)];
        let a = [ev(1, Kind::Touchdown, 0.5), ev(1, Kind::Liftoff, 0.1)];
        assert_eq!(Warp::new(&a, &b, 0.5).knots.len(), 4);
    }

    #[test]
    fn of_as_many_matched_events_the_gentlest_warp_is_kept() {
        // RobotExpressive's walk (A) and run (B), weight 0.25: left lift-off, right touchdown
        // and lift-off. Only one pair fits the slope bound at a time; the right touchdowns
        // (0.504 and 0.513) warp least, where dropping the steepest knot first kept the right
        // lift-offs (0.835 against 0.548: B played at 0.72 then 1.9 times its rate).
        let a = [
            ev(0, Kind::Liftoff, 0.487),
            ev(1, Kind::Touchdown, 0.504),
            ev(1, Kind::Liftoff, 0.835),
        ];
        let b = [
            ev(0, Kind::Liftoff, 0.06),
            ev(1, Kind::Touchdown, 0.513),
            ev(1, Kind::Liftoff, 0.548),
        ];
        let warp = Warp::new(&a, &b, 0.25);
        assert_eq!(warp.knots.len(), 3, "{:?}", warp.knots);
        assert_eq!(warp.knots[1][1], 0.504);
        assert_eq!(warp.knots[1][2], 0.513);
    }

    #[test]
    fn the_most_knots_within_the_slope_bound_are_kept() {
        // Random increasing knots against every subset: none keeps more within the bound.
        let mut lcg = crate::dev::synth::Lcg(0x2545_f491_4f6c_dd1d);
        let mut next = || lcg.unit();
        for _ in 0..300 {
            let n = 1 + (next() * 7.0) as usize;
            let mut pa: Vec<f64> = (0..n).map(|_| next()).collect();
            let mut pb: Vec<f64> = (0..n).map(|_| next()).collect();
            pa.sort_by(f64::total_cmp);
            pb.sort_by(f64::total_cmp);
            let w = next();
            let mut knots = vec![[0.0, 0.0, 0.0]];
            knots.extend(
                pa.iter()
                    .zip(&pb)
                    .map(|(a, b)| [(1.0 - w) * a + w * b, *a, *b]),
            );
            knots.push([1.0, 1.0, 1.0]);
            let kept = gentlest(&knots);
            assert!(steepest(&kept) <= MAX_WARP_SLOPE.ln() + 1e-12);
            assert_eq!(kept.first(), knots.first());
            assert_eq!(kept.last(), knots.last());
            let most = (0..1u32 << n)
                .filter_map(|mask| {
                    let mut v = vec![knots[0]];
                    v.extend((0..n).filter(|i| mask >> i & 1 == 1).map(|i| knots[i + 1]));
                    v.push(knots[n + 1]);
                    (steepest(&v) <= MAX_WARP_SLOPE.ln() + 1e-12).then_some(v.len())
                })
                .max()
                .unwrap();
            assert_eq!(kept.len(), most);
        }
    }
}
