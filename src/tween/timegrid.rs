//! Exact times: key times that lie on a frame grid (24, 25, 30, 60 ... per second, or the NTSC
//! rates 24000/1001 ...) within what float32 storage and an exporter's summing leave of them
//! are snapped onto it, so that frames land on the grid, USD time codes come out whole and
//! rates exact (a glTF stores 4.2 s as 4.19999743).

/// Frame rates a grid is looked for at, coarsest first (frames per second, as a fraction).
const RATES: &[(f64, f64)] = &[
    (1.0, 1.0),
    (2.0, 1.0),
    (4.0, 1.0),
    (5.0, 1.0),
    (8.0, 1.0),
    (10.0, 1.0),
    (12.0, 1.0),
    (15.0, 1.0),
    (20.0, 1.0),
    (24.0, 1.0),
    (25.0, 1.0),
    (30.0, 1.0),
    (40.0, 1.0),
    (48.0, 1.0),
    (50.0, 1.0),
    (60.0, 1.0),
    (72.0, 1.0),
    (75.0, 1.0),
    (90.0, 1.0),
    (96.0, 1.0),
    (100.0, 1.0),
    (120.0, 1.0),
    (144.0, 1.0),
    (150.0, 1.0),
    (180.0, 1.0),
    (200.0, 1.0),
    (240.0, 1.0),
    (300.0, 1.0),
    (24000.0, 1001.0),
    (25000.0, 1001.0),
    (30000.0, 1001.0),
    (48000.0, 1001.0),
    (60000.0, 1001.0),
    (120000.0, 1001.0),
];

/// How near a rate given as a decimal must lie to an NTSC rate of [`RATES`] (relative) to be
/// read as it: 29.97, 23.976 and 59.94 lie 1.0e-6 of themselves from 30000/1001, 24000/1001
/// and 60000/1001, the rates editing tools and DCCs mean by them; no other rate of the table
/// lies within 1e-3 of one.
pub const NTSC_TYPED: f64 = 1e-5;

/// The rate a decimal someone typed stands for: the NTSC rate of [`RATES`] within
/// [`NTSC_TYPED`] of it (29.97 is 30000/1001, so frames land on keys baked at 29.97 and a USD
/// output's time codes are whole), else the number itself.
pub fn typed_rate(rate: f64) -> f64 {
    RATES
        .iter()
        .map(|&(num, den)| num / den)
        .find(|r| r.fract() != 0.0 && (rate - r).abs() <= NTSC_TYPED * r)
        .unwrap_or(rate)
}

/// How far (relative) a frame time written as a decimal may lie from the frame time of a rate
/// of [`RATES`] and still be read as it, besides lying within half a unit of its last written
/// place: "0.0333" (4 places) lies 1.0e-3 of itself from 1/30, "0.03" 0.1 (read as written).
pub const WRITTEN_CLOSE: f64 = 2e-3;

/// The frame time (seconds) that `text`, a decimal as BVH's "Frame Time:" line writes it,
/// stands for: the frame time of the rate of [`RATES`] that rounds to it at the places written
/// (within half a unit of the last place other than a trailing zero, and [`WRITTEN_CLOSE`] of
/// itself; the nearest where several do), else the number itself. "0.008333" is 1/120 s
/// (120.0048 a second as written), ".0333333" 1/30, "0.033367" 1001/30000. `None` where
/// `text` is no number.
///
/// ```
/// assert_eq!(inbetween::tween::written_frame_time("0.008333"), Some(1.0 / 120.0));
/// ```
pub fn written_frame_time(text: &str) -> Option<f64> {
    let value: f64 = text.parse().ok().filter(|v: &f64| v.is_finite())?;
    let places = match text.split_once('.') {
        // Trailing zeros are padding (Blender writes 1/30 as "0.03333330").
        Some((_, fraction)) if fraction.bytes().all(|b| b.is_ascii_digit()) => {
            fraction.trim_end_matches('0').len()
        }
        _ => return Some(value),
    };
    let half_unit = 0.5 * 10f64.powi(-(places as i32));
    let off = |&(num, den): &(f64, f64)| (den / num - value).abs();
    Some(
        RATES
            .iter()
            .filter(|r| off(r) <= half_unit * (1.0 + 1e-9) && off(r) <= WRITTEN_CLOSE * value)
            .min_by(|a, b| off(a).total_cmp(&off(b)))
            .map_or(value, |&(num, den)| den / num),
    )
}

/// A rate as the summary shows it: an NTSC rate of [`RATES`] as its fraction (30000/1001),
/// any other as its number.
pub fn rate_text(rate: f64) -> String {
    match RATES
        .iter()
        .find(|&&(num, den)| den != 1.0 && num / den == rate)
    {
        Some((num, den)) => format!("{num}/{den}"),
        None => format!("{rate}"),
    }
}

/// How far (in frames of the grid) a time may lie from a grid point and still be on it: a
/// float32 key time carries about 1e-7 of itself, and exporters that sum spans in float32 drift
/// by a few hundred of those over thousands of keys (AnimatedMorphSphere's 7.2 s is stored as
/// 7.19999456, 1.6e-4 of a frame at 30 per second).
pub const ON_GRID: f64 = 2e-3;

/// A frame grid: `rate` = num / den frames per second.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grid {
    pub num: f64,
    pub den: f64,
}

impl Grid {
    pub fn rate(&self) -> f64 {
        self.num / self.den
    }

    /// Frame number of time `t` on this grid, when it lies on it.
    pub fn frame(&self, t: f64) -> Option<f64> {
        let x = t * self.num / self.den;
        let n = x.round();
        ((x - n).abs() <= ON_GRID).then_some(n)
    }

    /// The time of frame `n`, as the nearest double to n den / num.
    pub fn time(&self, n: f64) -> f64 {
        n * self.den / self.num
    }
}

/// The coarsest grid every time of `times` lies on, if there is one. Times of several seconds
/// or more need not be integral multiples of the grid to be on it, but each one is.
pub fn grid_of(times: &[f64]) -> Option<Grid> {
    if times.is_empty() || times.iter().any(|t| !t.is_finite()) {
        return None;
    }
    // Distinct times must stay distinct frames on the grid.
    let distinct = |g: &Grid| {
        let frames: Option<Vec<f64>> = times.iter().map(|&t| g.frame(t)).collect();
        frames.is_some_and(|f| {
            let mut pairs: Vec<(f64, f64)> = times.iter().copied().zip(f).collect();
            pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
            pairs
                .windows(2)
                .all(|w| (w[0].0 == w[1].0) == (w[0].1 == w[1].1))
        })
    };
    RATES
        .iter()
        .map(|&(num, den)| Grid { num, den })
        .find(distinct)
}

/// `times` snapped onto their coarsest grid (unchanged when they lie on none), and the grid.
pub fn snap(times: &[f64]) -> (Vec<f64>, Option<Grid>) {
    match grid_of(times) {
        Some(g) => (
            times
                .iter()
                .map(|&t| g.time(g.frame(t).expect("on the grid")))
                .collect(),
            Some(g),
        ),
        None => (times.to_vec(), None),
    }
}

/// Time codes of a USD point cache: the rate (per second) and every frame's code, for meshes
/// whose tracks have frames at `tracks[mesh][track][frame]` seconds, each track playing clip
/// `clips[mesh][track]` (an animation; `None` for the keys made from the targets). On a grid
/// (the coarsest one all frames lie on) the rate is the grid's and every code is whole;
/// elsewhere the rate is `fallback` (or one over the shortest spacing). Each clip has one
/// place on the timeline, shared by every mesh and node it drives (two nodes sharing a mesh,
/// each with its own weights channel in one clip, play side by side, as in the glTF); clips
/// follow one another one frame apart, the targets' keys first, then animations in file order.
pub fn timeline(
    tracks: &[Vec<Vec<f64>>],
    clips: &[Vec<Option<usize>>],
    fallback: Option<f64>,
) -> (f64, Vec<Vec<f64>>) {
    let all: Vec<f64> = tracks.iter().flatten().flatten().copied().collect();
    let grid = grid_of(&all);
    let rate = match (grid, fallback) {
        (Some(g), _) => g.rate(),
        (None, Some(r)) => r,
        (None, None) => {
            let spacing = tracks
                .iter()
                .flatten()
                .flat_map(|t| t.windows(2).map(|w| w[1] - w[0]))
                .filter(|d| *d > 0.0)
                .fold(f64::INFINITY, f64::min);
            if spacing.is_finite() {
                ((1.0 / spacing) * 1e6).round() / 1e6
            } else {
                24.0
            }
        }
    };
    let code = |time: f64| match grid {
        Some(g) => g.frame(time).unwrap_or(time * rate),
        None => (time * rate * 1e9).round() / 1e9,
    };
    let mut codes: Vec<Vec<Vec<f64>>> = tracks
        .iter()
        .map(|mesh| vec![Vec::new(); mesh.len()])
        .collect();
    let mut order: Vec<Option<usize>> = clips.iter().flatten().copied().collect();
    order.sort_unstable();
    order.dedup();
    let mut next_start: Option<f64> = None;
    for clip in order {
        let of_clip = || {
            (tracks.iter().zip(clips).enumerate()).flat_map(move |(m, (mesh, ids))| {
                (mesh.iter().zip(ids).enumerate())
                    .filter(move |(_, (_, id))| **id == clip)
                    .map(move |(k, (t, _))| (m, k, t))
            })
        };
        let first = (of_clip())
            .filter_map(|(_, _, t)| t.first().copied().map(code))
            .fold(f64::INFINITY, f64::min);
        let offset = match next_start {
            Some(s) if s > first => s - first,
            _ => 0.0,
        };
        let mut last: Option<f64> = None;
        for (m, k, t) in of_clip() {
            let out = &mut codes[m][k];
            for &time in t {
                // Frames at a cut in the keys share its time: one double step apart here,
                // as USD time samples must be.
                let c = code(time) + offset;
                out.push(out.last().map_or(c, |&prev: &f64| c.max(prev.next_up())));
            }
            if let Some(&l) = out.last() {
                last = Some(last.map_or(l, |x: f64| x.max(l)));
            }
        }
        if let Some(l) = last {
            next_start = Some(l + 1.0);
        }
    }
    let codes = codes.into_iter().map(|m| m.concat()).collect();
    (rate, codes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn written_frame_times_stand_for_their_rates() {
        for (text, seconds) in [
            ("0.008333", 1.0 / 120.0),
            (".0083333", 1.0 / 120.0),
            ("0.0333333", 1.0 / 30.0),
            ("0.03333330", 1.0 / 30.0),
            ("0.0333", 1.0 / 30.0),
            ("0.041667", 1.0 / 24.0),
            ("0.033367", 1001.0 / 30000.0),
            ("0.016667", 1.0 / 60.0),
            ("0.04", 1.0 / 25.0),
            ("0.0200", 1.0 / 50.0),
        ] {
            assert_eq!(written_frame_time(text), Some(seconds), "{text}");
        }
        // Read as written: too far from 1/30 or 1/120 for the places written, a rate off the
        // table (80), an exponent.
        for (text, seconds) in [
            ("0.03", 0.03),
            ("0.0330", 0.033),
            ("0.0083", 0.0083),
            ("0.0125", 0.0125),
            ("8.333e-3", 8.333e-3),
        ] {
            assert_eq!(written_frame_time(text), Some(seconds), "{text}");
        }
        assert_eq!(written_frame_time("x"), None);
    }

    #[test]
    fn float32_key_times_snap_to_their_grid() {
        // Flamingo's keys: 0.1 s apart as float32.
        let keys: Vec<f64> = (0..15).map(|k| (k as f32 * 0.1f32) as f64).collect();
        let (snapped, grid) = snap(&keys);
        assert_eq!(grid.unwrap().rate(), 10.0);
        assert_eq!(snapped[14], 1.4);
        assert_eq!(snapped[3], 0.3);
        // AnimatedMorphCube's last key, 4.2 s as an exporter summed it.
        let (snapped, grid) = snap(&[0.0, 0.033333335, 4.199997425079346]);
        assert_eq!(grid.unwrap().rate(), 30.0);
        assert_eq!(snapped[2], 4.2);
        // NTSC: 1001/24000 steps are not 24 per second.
        let ntsc: Vec<f64> = (0..100).map(|k| k as f64 * 1001.0 / 24000.0).collect();
        let g = grid_of(&ntsc).unwrap();
        assert_eq!((g.num, g.den), (24000.0, 1001.0));
        // Off any grid: left alone.
        let odd = [0.0, 0.137, 0.291];
        assert_eq!(snap(&odd), (odd.to_vec(), None));
    }

    #[test]
    fn typed_ntsc_rates_are_their_fractions() {
        for (typed, num) in [(29.97, 30000.0), (23.976, 24000.0), (59.94, 60000.0)] {
            assert_eq!(typed_rate(typed), num / 1001.0);
            assert_eq!(rate_text(typed_rate(typed)), format!("{num}/1001"));
        }
        for other in [30.0, 24.0, 25.0, 29.9, 23.97, 1000.0, 0.0, -29.97] {
            assert_eq!(typed_rate(other), other);
        }
        assert!(typed_rate(f64::NAN).is_nan());
        assert_eq!(rate_text(30.0), "30");
        assert_eq!(rate_text(29.97), "29.97");
    }

    #[test]
    fn each_clip_has_one_place_on_the_timeline() {
        let keys = |n: usize| (0..n).map(|k| k as f64 / 10.0).collect::<Vec<f64>>();
        // Mesh 0: clips 0 and 1; mesh 1: clip 1 only; mesh 2: two tracks of clip 0 (two nodes).
        let tracks = [
            vec![keys(5), keys(3)],
            vec![keys(3)],
            vec![keys(5), keys(5)],
        ];
        let clips = [
            vec![Some(0), Some(1)],
            vec![Some(1)],
            vec![Some(0), Some(0)],
        ];
        let (rate, codes) = timeline(&tracks, &clips, None);
        assert_eq!(rate, 10.0);
        assert_eq!(codes[0], [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]);
        assert_eq!(codes[1], [5.0, 6.0, 7.0]);
        assert_eq!(codes[2], [0.0, 1.0, 2.0, 3.0, 4.0, 0.0, 1.0, 2.0, 3.0, 4.0]);
        // The keys made from the targets come first.
        let (_, codes) = timeline(
            &[vec![keys(2)], vec![keys(2)]],
            &[vec![Some(3)], vec![None]],
            None,
        );
        assert_eq!(codes, [vec![2.0, 3.0], vec![0.0, 1.0]]);
    }
}
