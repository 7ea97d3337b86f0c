//! Key times ([`key_times`]) must increase: a time equal to the one before (an exporter's
//! hold, two samples of a bake rounded to one time), which the readers take as a step to the
//! later key, is moved a single-precision step on (the run's last back from a clip's end), the
//! first and last times kept so the accessor's bounds hold. A time that goes back is left (the
//! readers refuse it on a node's channel). A clip whose times start before 0 s (Blender's
//! exports have written such) is moved later as a whole when the output is written
//! ([`start_at_zero`]; `tween` moves a clip it tweens with its frames already), said at the
//! start ([`negative_times`]).

use super::Column;
use crate::gltf::build::{BinBuilder, Output};
use crate::gltf::read::{arr, quoted_name};
use serde_json::Value;
use std::collections::BTreeMap;

/// Times `t` made increasing where a time equals the one before, each moved by
/// single-precision steps, the first and last kept (so the accessor's bounds hold): later ones
/// forward, then, where that reaches the last, earlier ones back. `None` where nothing moved,
/// where a time goes back (not a repeat: which key is where is not known) or where the times
/// leave no room (all equal).
fn increasing_times(t: &[f32]) -> Option<Vec<f32>> {
    let n = t.len();
    let goes_back = t.windows(2).any(|w| w[1] < w[0]);
    if n < 2 || goes_back || t.iter().any(|x| !x.is_finite()) || t.windows(2).all(|w| w[1] > w[0]) {
        return None;
    }
    let mut m = t.to_vec();
    for i in 1..n - 1 {
        if m[i] <= m[i - 1] {
            m[i] = m[i - 1].next_up();
        }
    }
    for i in (1..n - 1).rev() {
        if m[i] >= m[i + 1] {
            m[i] = m[i + 1].next_down();
        }
    }
    m.windows(2).all(|w| w[1] > w[0]).then_some(m)
}

/// Make every float key-time accessor of the output's animations increasing (see
/// [`increasing_times`]), in place in `bin`; returns a line for each animation with such
/// times. A repeated time is a step between its keys, which the moved time keeps within a
/// single-precision step (an exporter's hold, or two samples of a bake rounded to one time).
pub fn key_times(json: &Value, bin: &mut BinBuilder) -> Vec<String> {
    let mut lines = Vec::new();
    let mut done = std::collections::BTreeSet::new();
    for (a, anim) in arr(json, "animations").iter().enumerate() {
        let mut moved = 0;
        for sampler in arr(anim, "samplers") {
            let Some(input) = sampler["input"].as_u64().map(|i| i as usize) else {
                continue;
            };
            let Some((column, t)) =
                Column::floats(json, bin, input, 1).filter(|_| done.insert(input))
            else {
                continue;
            };
            let Some(m) = increasing_times(&t) else {
                continue;
            };
            for (i, (a, b)) in t.iter().zip(&m).enumerate() {
                if a != b {
                    column.set_float(&mut bin.bytes, i, 0, *b);
                    moved += 1;
                }
            }
        }
        if moved > 0 {
            let name = quoted_name(anim, || format!("{a}"));
            let s = if moved == 1 { "" } else { "s" };
            lines.push(format!(
                "animation {name}: {moved} key time{s} equal to the one before, moved by single-precision steps (glTF requires increasing times)"
            ));
        }
    }
    lines
}

/// The key times of every sampler of animation `anim` in `json`/`bin` (float accessors), by
/// input accessor; `None` where one does not read so.
fn sampler_times(
    json: &Value,
    bin: &BinBuilder,
    anim: &Value,
) -> Option<BTreeMap<usize, Vec<f32>>> {
    let mut times = BTreeMap::new();
    for sampler in arr(anim, "samplers") {
        let input = sampler["input"].as_u64()? as usize;
        times.insert(input, Column::floats(json, bin, input, 1)?.1);
    }
    Some(times)
}

/// The earliest key time of `times`, where it is before 0 s.
fn negative_start(times: &BTreeMap<usize, Vec<f32>>) -> Option<f64> {
    let first = (times.values().flatten()).fold(f64::INFINITY, |m, &t| m.min(t as f64));
    (first < 0.0).then_some(first)
}

/// A line for each animation of the input whose key times start before 0 s (glTF's times may
/// not be negative; Blender's exports have written such clips): [`start_at_zero`] moves it when
/// the output is written.
pub fn negative_times(json: &Value, bin: &BinBuilder) -> Vec<String> {
    let mut lines = Vec::new();
    for (a, anim) in arr(json, "animations").iter().enumerate() {
        let Some(first) = sampler_times(json, bin, anim).and_then(|t| negative_start(&t)) else {
            continue;
        };
        let name = quoted_name(anim, || format!("{a}"));
        lines.push(format!(
            "animation {name}: key times from {first:.4} s, before the 0 s glTF starts at; written {:.4} s later, the clip as a whole",
            -first
        ));
    }
    lines
}

/// Every animation whose key times still start before 0 s when the output is written (one
/// `tween` did not move with its frames, or one copied as it was) moved later as a whole, its
/// first key at 0 s: each sampler's times into an accessor of their own (an accessor may be
/// shared with other clips), declared bounds with them.
pub fn start_at_zero(out: &mut Output) {
    for a in 0..arr(&out.json, "animations").len() {
        let anim = &out.json["animations"][a];
        let Some(times) = sampler_times(&out.json, &out.bin, anim) else {
            continue;
        };
        let Some(first) = negative_start(&times) else {
            continue;
        };
        let mut moved = BTreeMap::new();
        for (input, t) in times {
            let t: Vec<f32> = t.iter().map(|&x| (x as f64 - first) as f32).collect();
            let t = increasing_times(&t).unwrap_or(t);
            moved.insert(input, out.push_f32(&t, "SCALAR", 1, true, None));
        }
        for sampler in out.json["animations"][a]["samplers"]
            .as_array_mut()
            .into_iter()
            .flatten()
        {
            let input = sampler["input"].as_u64().unwrap_or(u64::MAX) as usize;
            if let Some(&m) = moved.get(&input) {
                sampler["input"] = m.into();
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn repeated_key_times_move_by_single_precision_steps_within_the_bounds() {
        let up = |x: f32| x.next_up();
        let down = |x: f32| x.next_down();
        assert_eq!(increasing_times(&[0.0, 0.5, 1.0]), None);
        assert_eq!(
            increasing_times(&[0.0, 0.5, 0.5, 1.0]),
            Some(vec![0.0, 0.5, up(0.5), 1.0])
        );
        assert_eq!(
            increasing_times(&[0.0, 0.5, 0.5, 0.5, 1.0]),
            Some(vec![0.0, 0.5, up(0.5), up(up(0.5)), 1.0])
        );
        // At either end the end stays where it is.
        assert_eq!(
            increasing_times(&[0.0, 0.0, 1.0]),
            Some(vec![0.0, up(0.0), 1.0])
        );
        assert_eq!(
            increasing_times(&[0.0, 0.5, 1.0, 1.0]),
            Some(vec![0.0, 0.5, down(1.0), 1.0])
        );
        assert_eq!(
            increasing_times(&[0.0, 1.0, 1.0, 1.0]),
            Some(vec![0.0, down(down(1.0)), down(1.0), 1.0])
        );
        // A time going back, or no room: left as it is.
        assert_eq!(increasing_times(&[0.0, 0.5, 0.4, 1.0]), None);
        assert_eq!(increasing_times(&[1.0, 1.0]), None);
        assert_eq!(increasing_times(&[1.0, 1.0, up(1.0)]), None);
    }
}
