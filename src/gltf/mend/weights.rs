//! Skin weights ([`weights`]) must sum to one. Two kinds of file break the rule, and the
//! output would carry it: exporters that write weights summing to something else (FBX2glTF's
//! RobotExpressive: its hands up to 1.76, 752 validator errors), and Draco-compressed weights,
//! which decode with the codec's quantization in them (glTF-Transform `draco` at its default 12
//! bits: sums 1 +- 2.5e-4; the validator cannot look inside Draco, so the input passes and the
//! decoded output did not, 30-318 errors on the skinned fixtures). three.js's loader, Blender
//! and our own USD point cache divide by the sum: they show the same pose before and after.
//!
//! The check is the validator's own: per vertex, the weights of its distinct joints summed in
//! single precision, in attribute order, within [`PER_INFLUENCE`] times the influences of 1
//! (glTF-Validator 2.0.0-dev.3.10, the one the tests run; its source's other rule, [`SUM_STEP`]
//! times (influences / 2, rounded up, less one), exactly 1 for one or two influences, is
//! checked too). A vertex that fails is divided by its sum and its largest weight then moved
//! by single-precision steps until the sum passes. Normalized integer weights (8 or 16 bits) are
//! read as the validator reads them, each over its type's largest value; a vertex that fails is
//! made to sum to exactly that value, each weight its share rounded down and the units left
//! over given to the largest remainders (an exporter that rounds each weight alone sums to
//! 253/255-257/255: 202-320 errors on Fox and CesiumMan so written; gltfpack and glTF-Transform
//! make their sums whole). A joint with weight 0 is made joint 0 (the validator warns of one
//! that is not, which Draco leaves where it rounds a small weight to nothing: RobotExpressive's
//! hands, 5 warnings). A joint a vertex names twice (the validator's
//! ACCESSOR_JOINTS_INDEX_DUPLICATE) gets the two weights added in its first place (skinning
//! is linear in each joint's weight: the same pose). A vertex with a negative weight or no
//! weight at all is left as it is (normalizing cannot mend those).

use super::Column;
use crate::gltf::build::BinBuilder;
use crate::gltf::read::{arr, quoted_name};
use serde_json::Value;
use std::collections::BTreeMap;

/// The validator's tolerance per influence (its release 2.0.0-dev.3.10).
const PER_INFLUENCE: f64 = 2e-7;

/// The validator's step of tolerance per two influences in its source's other rule: a little
/// over 1/255, the error of 8-bit quantization.
const SUM_STEP: f64 = 0.0039216;

/// Sums farther than this from 1 are named in a warning line (an exporter's error); nearer,
/// they are a codec's quantization and mended without a word.
const SAID_ABOVE: f64 = SUM_STEP;

/// Whether weights `w` of joints `j` (each as the validator reads it: a float's value, a
/// normalized integer's over its type's largest) sum to one as the validator reckons it:
/// `None` where normalizing cannot mend them (a negative weight, a joint twice, no weight).
fn sums_to_one(w: impl IntoIterator<Item = f64>, j: &[u32]) -> Option<bool> {
    let (mut sum, mut seen) = (0f32, Vec::with_capacity(j.len()));
    for (w, &j) in w.into_iter().zip(j) {
        if w == 0.0 {
            continue;
        }
        if w < 0.0 || !w.is_finite() || seen.contains(&j) {
            return None;
        }
        seen.push(j);
        sum = (sum as f64 + w) as f32;
    }
    if seen.is_empty() {
        return None;
    }
    let n = seen.len();
    let tolerance = (PER_INFLUENCE * n as f64).min(SUM_STEP * (n.div_ceil(2) - 1) as f64);
    Some((sum as f64 - 1.0).abs() <= tolerance)
}

/// [`sums_to_one`] of float weights.
fn floats_sum_to_one(w: &[f32], j: &[u32]) -> Option<bool> {
    sums_to_one(w.iter().map(|&x| x as f64), j)
}

/// [`sums_to_one`] of normalized integer weights `k`, `unit` their type's largest (255, 65535).
fn units_sum_to_one(k: &[u32], unit: u32, j: &[u32]) -> Option<bool> {
    sums_to_one(k.iter().map(|&x| x as f64 / unit as f64), j)
}

/// Normalized integer weights `k` scaled to sum to exactly `unit` (their type's largest):
/// each its share rounded down, the units left over given to the largest remainders (the
/// earlier first where they tie). Zero weights stay zero.
fn normalized_units(k: &mut [u32], unit: u32) {
    let sum: u64 = k.iter().map(|&x| x as u64).sum();
    if sum == 0 {
        return;
    }
    let share = |x: u32| x as u64 * unit as u64;
    let mut order: Vec<usize> = (0..k.len()).collect();
    // Remainders compared exactly, as numerators over `sum`.
    order.sort_by_key(|&i| std::cmp::Reverse(share(k[i]) % sum));
    let floors: Vec<u64> = k.iter().map(|&x| share(x) / sum).collect();
    let left = unit as u64 - floors.iter().sum::<u64>();
    for (i, f) in floors.iter().enumerate() {
        k[i] = *f as u32;
    }
    for &i in order.iter().take(left as usize) {
        k[i] += 1;
    }
}

/// Weights `w` divided by their sum, their largest then stepped until [`sums_to_one`] passes.
fn normalized(w: &mut [f32], j: &[u32]) {
    let sum: f64 = w.iter().map(|&x| x as f64).sum();
    for x in w.iter_mut() {
        *x = (*x as f64 / sum) as f32;
    }
    let k = (0..w.len()).fold(0, |k, i| if w[i] > w[k] { i } else { k });
    for _ in 0..64 {
        if floats_sum_to_one(w, j) != Some(false) {
            return;
        }
        let rest: f64 = (w.iter().enumerate())
            .filter(|&(i, _)| i != k)
            .map(|(_, &x)| x as f64)
            .sum();
        let want = (1.0 - rest) as f32;
        w[k] = match want == w[k] {
            // One single-precision step towards the sum's shortfall.
            true => {
                let total: f32 = w.iter().fold(0f32, |s, &x| (s as f64 + x as f64) as f32);
                let bits = w[k].to_bits();
                f32::from_bits(if total < 1.0 { bits + 1 } else { bits - 1 })
            }
            false => want,
        };
    }
}

/// Make every `WEIGHTS_n` set of the output (float or normalized integer) sum to one per
/// vertex, each joint named once (see the module comment), in place in `bin`; returns a line
/// for each mesh with joints named twice, and each whose sums were off by more than
/// quantization.
pub fn weights(json: &Value, bin: &mut BinBuilder) -> Vec<String> {
    // Mesh -> (vertices mended, the sums' range before), and vertices with a joint named
    // twice, for the lines.
    let mut said: BTreeMap<usize, (usize, f64, f64)> = BTreeMap::new();
    let mut repeated: BTreeMap<usize, usize> = BTreeMap::new();
    for (m, mesh) in arr(json, "meshes").iter().enumerate() {
        for p in arr(mesh, "primitives") {
            let attrs = &p["attributes"];
            let pairs: Vec<(u64, u64)> = (0..)
                .map_while(|n| {
                    let j = attrs[format!("JOINTS_{n}")].as_u64()?;
                    Some((j, attrs[format!("WEIGHTS_{n}")].as_u64()?))
                })
                .collect();
            let Some(count) = pairs
                .first()
                .and_then(|&(_, w)| json["accessors"][w as usize]["count"].as_u64())
            else {
                continue;
            };
            let count = count as usize;
            let normalized_int = |w: u64| json["accessors"][w as usize]["normalized"] == true;
            let columns: Option<Vec<(Column, Column)>> = (pairs.iter())
                .map(|&(j, w)| {
                    let jc = Column::of(json, bin, j as usize, count)?;
                    let wc = Column::of(json, bin, w as usize, count)?;
                    let readable = wc.component == 5126 || normalized_int(w);
                    (jc.component != 5126 && readable).then_some((jc, wc))
                })
                .collect();
            let Some(columns) = columns.filter(|c| !c.is_empty()) else {
                continue;
            };
            // Float weights, or normalized integers of one type (their largest value is 1).
            let n = 4 * columns.len();
            let mut w = match columns[0].1.component {
                5126 => VertexWeights::Floats(vec![0.0; n]),
                5121 => VertexWeights::Units(vec![0; n], 255),
                _ => VertexWeights::Units(vec![0; n], 65535),
            };
            if (columns.iter()).any(|c| c.1.component != columns[0].1.component) {
                continue;
            }
            let mut j = vec![0u32; n];
            for i in 0..count {
                for (s, (jc, _)) in columns.iter().enumerate() {
                    for c in 0..4 {
                        j[4 * s + c] = jc.uint(&bin.bytes, i, c);
                    }
                }
                w.read(&columns, &bin.bytes, i);
                let merged = w.merge_repeated_joints(&j);
                if merged {
                    *repeated.entry(m).or_insert(0) += 1;
                }
                let fits = w.sums_to_one(&j);
                if fits == Some(false) {
                    let before = w.sum();
                    w.normalize(&j);
                    let e = said
                        .entry(m)
                        .or_insert((0, f64::INFINITY, f64::NEG_INFINITY));
                    *e = (e.0 + 1, e.1.min(before), e.2.max(before));
                }
                if merged || fits == Some(false) {
                    w.write(&columns, &mut bin.bytes, i);
                }
                // A joint with no weight is joint 0 (the validator warns of others): Draco's
                // quantization rounds a small weight to 0 and keeps its joint, and so may an
                // integer weight's share above.
                for (s, (jc, _)) in columns.iter().enumerate() {
                    for c in 0..4 {
                        if w.is_zero(4 * s + c) && j[4 * s + c] != 0 {
                            jc.set_uint(&mut bin.bytes, i, c, 0);
                        }
                    }
                }
            }
        }
    }
    let mesh = |m: usize| quoted_name(&json["meshes"][m], || format!("{m}"));
    let mut lines: Vec<String> = (repeated.into_iter())
        .map(|(m, n)| {
            format!(
                "mesh {}: {n} vertices name a joint more than once (glTF allows it once); written with its weights added",
                mesh(m)
            )
        })
        .collect();
    lines.extend(
        (said.into_iter())
            .filter(|&(_, (_, lo, hi))| (1.0 - lo).max(hi - 1.0) > SAID_ABOVE)
            .map(|(m, (n, lo, hi))| {
                format!(
                    "mesh {}: the skin weights of {n} vertices summed to {lo:.4}-{hi:.4}, not 1 as glTF requires; written divided by their sums",
                    mesh(m)
                )
            }),
    );
    lines
}

/// Weights `w` of joints `j` with each joint named once: a weight on a joint named earlier
/// added to that one and made 0 (skinning is linear in each joint's weight, so the pose is
/// the same); whether any was.
fn merge_repeated_joints<T>(w: &mut [T], j: &[u32]) -> bool
where
    T: Copy + PartialEq + Default + std::ops::AddAssign,
{
    let zero = T::default();
    let mut merged = false;
    for x in 0..w.len() {
        if w[x] == zero {
            continue;
        }
        if let Some(y) = (0..x).find(|&y| w[y] != zero && j[y] == j[x]) {
            let v = w[x];
            w[y] += v;
            w[x] = zero;
            merged = true;
        }
    }
    merged
}

/// One vertex's skin weights as stored, across its `WEIGHTS_n` sets: floats, or normalized
/// integers with their type's largest value (255, 65535: the validator's 1).
enum VertexWeights {
    Floats(Vec<f32>),
    Units(Vec<u32>, u32),
}

impl VertexWeights {
    /// Vertex `i`'s weights from the weights columns of `columns` (joints, weights).
    fn read(&mut self, columns: &[(Column, Column)], bytes: &[u8], i: usize) {
        for (s, (_, wc)) in columns.iter().enumerate() {
            for c in 0..4 {
                match self {
                    VertexWeights::Floats(w) => w[4 * s + c] = wc.float(bytes, i, c),
                    VertexWeights::Units(k, _) => k[4 * s + c] = wc.uint(bytes, i, c),
                }
            }
        }
    }

    /// Vertex `i`'s weights written back into `columns`.
    fn write(&self, columns: &[(Column, Column)], bytes: &mut [u8], i: usize) {
        for (s, (_, wc)) in columns.iter().enumerate() {
            for c in 0..4 {
                match self {
                    VertexWeights::Floats(w) => wc.set_float(bytes, i, c, w[4 * s + c]),
                    VertexWeights::Units(k, _) => wc.set_uint(bytes, i, c, k[4 * s + c]),
                }
            }
        }
    }

    fn merge_repeated_joints(&mut self, j: &[u32]) -> bool {
        match self {
            VertexWeights::Floats(w) => merge_repeated_joints(w, j),
            VertexWeights::Units(k, _) => merge_repeated_joints(k, j),
        }
    }

    fn sums_to_one(&self, j: &[u32]) -> Option<bool> {
        match self {
            VertexWeights::Floats(w) => floats_sum_to_one(w, j),
            VertexWeights::Units(k, unit) => units_sum_to_one(k, *unit, j),
        }
    }

    /// The weights' sum, as the validator reads them.
    fn sum(&self) -> f64 {
        match self {
            VertexWeights::Floats(w) => w.iter().map(|&x| x as f64).sum(),
            VertexWeights::Units(k, unit) => {
                k.iter().map(|&x| x as f64).sum::<f64>() / *unit as f64
            }
        }
    }

    /// The weights made to sum to one ([`normalized`], [`normalized_units`]).
    fn normalize(&mut self, j: &[u32]) {
        match self {
            VertexWeights::Floats(w) => normalized(w, j),
            VertexWeights::Units(k, unit) => normalized_units(k, *unit),
        }
    }

    fn is_zero(&self, x: usize) -> bool {
        match self {
            VertexWeights::Floats(w) => w[x] == 0.0,
            VertexWeights::Units(k, _) => k[x] == 0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn off_sums_are_mended_to_pass_the_validator_s_check() {
        let mut lcg = crate::dev::synth::Lcg(3);
        for case in 0..20_000 {
            let n = 1 + case % 8;
            let mut w: Vec<f32> = (0..8)
                .map(|i| match i < n {
                    true => (lcg.unit() * 0.9 + 0.01) as f32,
                    false => 0.0,
                })
                .collect();
            let j: Vec<u32> = (0..8).collect();
            let before: Vec<f64> = w.iter().map(|&x| x as f64).collect();
            let sum: f64 = before.iter().sum();
            normalized(&mut w, &j);
            assert_eq!(floats_sum_to_one(&w, &j), Some(true), "{before:?} -> {w:?}");
            // Each weight within a few single-precision steps of its share.
            for (a, b) in w.iter().zip(&before) {
                assert!((*a as f64 - b / sum).abs() < 1e-6, "{before:?} -> {w:?}");
            }
        }
        // Two influences must sum to exactly 1 in single precision.
        let (mut w, j) = (vec![0.30001, 0.70012, 0.0, 0.0], vec![3, 5, 0, 0]);
        assert_eq!(floats_sum_to_one(&w, &j), Some(false));
        normalized(&mut w, &j);
        assert_eq!(w[0] + w[1], 1.0);
        // What normalizing cannot mend is left.
        assert_eq!(
            floats_sum_to_one(&[0.5, 0.6, 0.0, 0.0], &[1, 1, 0, 0]),
            None
        );
        assert_eq!(
            floats_sum_to_one(&[-0.5, 1.5, 0.0, 0.0], &[1, 2, 0, 0]),
            None
        );
        assert_eq!(floats_sum_to_one(&[0.0; 4], &[0; 4]), None);
    }

    #[test]
    fn whole_integer_sums_pass_and_off_ones_are_made_whole() {
        let j = [0, 1, 2, 3];
        // Every 8-bit set of four summing to 255 passes the validator's single-precision sum.
        for a in 0..=255u32 {
            for b in 0..=255 - a {
                for c in 0..=255 - a - b {
                    let k = [a, b, c, 255 - a - b - c];
                    assert_eq!(units_sum_to_one(&k, 255, &j), Some(true), "{k:?}");
                }
            }
        }
        let mut lcg = crate::dev::synth::Lcg(5);
        for case in 0..20_000 {
            let unit = [255, 65535][case % 2];
            let n = 1 + case / 2 % 8;
            let mut k: Vec<u32> = (0..8)
                .map(|i| match i < n {
                    true => (lcg.unit() * 1.2 * unit as f64 / n as f64) as u32,
                    false => 0,
                })
                .collect();
            let (before, j): (Vec<u32>, Vec<u32>) = (k.clone(), (0..8).collect());
            let sum: u32 = before.iter().sum();
            if sum == 0 {
                continue;
            }
            normalized_units(&mut k, unit);
            assert_eq!(k.iter().sum::<u32>(), unit, "{before:?} -> {k:?}");
            assert_eq!(
                units_sum_to_one(&k, unit, &j),
                Some(true),
                "{before:?} -> {k:?}"
            );
            // Each within a unit of its share; zeros stay zero.
            for (now, was) in k.iter().zip(&before) {
                let share = *was as f64 * unit as f64 / sum as f64;
                assert!((*now as f64 - share).abs() < 1.0, "{before:?} -> {k:?}");
                assert!(*was != 0 || *now == 0, "{before:?} -> {k:?}");
            }
        }
    }
}
