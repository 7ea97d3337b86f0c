//! Undefined keys ([`undefined_keys`]): a key whose time or value is NaN or infinite, or a
//! rotation key that is a zero quaternion, stands for no pose (the validator's
//! ACCESSOR_INVALID_FLOAT; an exporter that divides a zero by its length writes such:
//! COLLADA2GLTF of a Modo character, glTF issue 219; ValveResourceFormat's bones, its issue
//! 309). Players turn it into no pose at all (three.js draws nothing for those frames), and the
//! readers here refused the whole file, even for a clip the command does not use. It is left
//! out, as the readers leave it out (`gltf::defined_keys`): the keys beside it are played
//! across. The kept keys are packed into the sampler's own accessors, their counts and bounds
//! made theirs (a key-time accessor other samplers share with other keys left, and a copy
//! written); a sampler with no key left, or whose values another sampler reads with other
//! times, is left as it is.

use super::Column;
use crate::gltf::build::{set_bounds, Output};
use crate::gltf::channel::{defined_keys, defined_only};
use crate::gltf::read::{arr, quoted_name};
use std::collections::BTreeMap;

/// A float accessor of `out` (SCALAR, VEC3 or VEC4): where it lies, its values as stored and
/// its width.
fn floats(out: &Output, acc: usize) -> Option<(Column, Vec<f64>, usize)> {
    let width = match out.json["accessors"][acc]["type"].as_str()? {
        "SCALAR" => 1,
        "VEC3" => 3,
        "VEC4" => 4,
        _ => return None,
    };
    let (column, values) = Column::floats(&out.json, &out.bin, acc, width as u64)?;
    Some((column, values.into_iter().map(f64::from).collect(), width))
}

/// Write `values` (`width` a element) over the first elements of accessor `acc` (at `column`)
/// and make its count theirs, its bounds too where it declares them (or `bounds`).
fn pack(out: &mut Output, acc: usize, column: &Column, values: &[f64], width: usize, bounds: bool) {
    for (k, v) in values.iter().enumerate() {
        column.set_float(&mut out.bin.bytes, k / width, k % width, *v as f32);
    }
    let a = &mut out.json["accessors"][acc];
    a["count"] = (values.len() / width).into();
    if bounds || a.get("min").is_some() {
        let stored: Vec<f32> = values.iter().map(|&x| x as f32).collect();
        set_bounds(a, &stored, width);
    }
}

/// The samplers reading each key-time accessor: their value accessor and, where they have
/// undefined keys, which keys they keep.
type Readers = BTreeMap<usize, Vec<(usize, Option<Vec<bool>>)>>;

/// One sampler with undefined keys: where it is, its accessors, their data as the input has
/// them (read before any is packed: samplers share accessors) and what it keeps.
struct Undefined {
    animation: usize,
    sampler: usize,
    input: usize,
    output: usize,
    defined: Vec<bool>,
    times: (Column, Vec<f64>),
    values: (Column, Vec<f64>, usize),
}

/// Leave the undefined keys (see the module comment) out of every sampler of `out`'s
/// animations; returns a line for each animation with such keys.
pub fn undefined_keys(out: &mut Output) -> Vec<String> {
    // Every sampler's (input, output) and, where it has undefined keys, which it keeps.
    let mut users: Readers = BTreeMap::new();
    let mut found = Vec::new();
    for (a, anim) in arr(&out.json, "animations").iter().enumerate() {
        // The samplers rotation channels read (once per clip: a clip of 10,000 channels looked
        // through them for each of its samplers).
        let rotating: std::collections::HashSet<u64> = (arr(anim, "channels").iter())
            .filter(|c| c["target"]["path"].as_str() == Some("rotation"))
            .filter_map(|c| c["sampler"].as_u64())
            .collect();
        for (s, sampler) in arr(anim, "samplers").iter().enumerate() {
            let (Some(input), Some(output)) =
                (sampler["input"].as_u64(), sampler["output"].as_u64())
            else {
                continue;
            };
            let (input, output) = (input as usize, output as usize);
            let cubic = sampler["interpolation"].as_str() == Some("CUBICSPLINE");
            let rotation = rotating.contains(&(s as u64));
            let data = floats(out, input).zip(floats(out, output));
            let defined = data
                .as_ref()
                .and_then(|((_, times, _), (_, values, width))| {
                    let per_key = values.len().checked_div(times.len())?;
                    let fits = per_key * times.len() == values.len()
                        && (!rotation || (*width == 4 && per_key == if cubic { 12 } else { 4 }));
                    let mid = if cubic { per_key / 3 } else { 0 };
                    fits.then(|| defined_keys(times, values, per_key, rotation.then_some(mid)))
                });
            let undefined = defined.filter(|d| d.contains(&true) && d.contains(&false));
            users
                .entry(input)
                .or_default()
                .push((output, undefined.clone()));
            if let (Some(defined), Some(((in_col, times, _), values))) = (undefined, data) {
                found.push(Undefined {
                    animation: a,
                    sampler: s,
                    input,
                    output,
                    defined,
                    times: (in_col, times),
                    values,
                });
            }
        }
    }
    // A value accessor that samplers read with other times, or keep other keys of: left.
    let shared_output = |u: &Undefined| {
        (users.iter())
            .flat_map(|(i, list)| list.iter().map(move |(o, d)| (*i, *o, d)))
            .any(|(i, o, d)| o == u.output && (i != u.input || d.as_ref() != Some(&u.defined)))
    };
    let mut left: BTreeMap<usize, usize> = BTreeMap::new();
    let mut packed_outputs = std::collections::BTreeSet::new();
    let mut copied_inputs: BTreeMap<(usize, Vec<bool>), usize> = BTreeMap::new();
    for u in found.iter().filter(|u| !shared_output(u)) {
        let ((in_col, times), (out_col, values, width)) = (&u.times, &u.values);
        let per_key = values.len() / times.len();
        let (times, values) = defined_only(times, values, per_key, &u.defined);
        if packed_outputs.insert(u.output) {
            pack(out, u.output, out_col, &values, *width, false);
        }
        // The key times: packed where every sampler reading them keeps the same keys, else a
        // copy of this sampler's own.
        let same = users[&u.input]
            .iter()
            .all(|(_, d)| d.as_ref() == Some(&u.defined));
        let input = *copied_inputs
            .entry((u.input, u.defined.clone()))
            .or_insert_with(|| {
                if same {
                    pack(out, u.input, in_col, &times, 1, true);
                    u.input
                } else {
                    let stored: Vec<f32> = times.iter().map(|&t| t as f32).collect();
                    out.push_f32(&stored, "SCALAR", 1, true, None)
                }
            });
        out.json["animations"][u.animation]["samplers"][u.sampler]["input"] = input.into();
        *left.entry(u.animation).or_default() += u.defined.iter().filter(|d| !**d).count();
    }
    // A key-time accessor with undefined times that no sampler reads any more (each now reads
    // a copy of its own keys): its defined times packed, so that it holds no NaN either.
    for &input in users.keys() {
        let read = (arr(&out.json, "animations").iter())
            .flat_map(|a| arr(a, "samplers"))
            .any(|s| s["input"].as_u64() == Some(input as u64));
        if let Some((column, times, _)) = floats(out, input).filter(|_| !read) {
            let finite: Vec<f64> = times.iter().copied().filter(|t| t.is_finite()).collect();
            if finite.len() < times.len() && !finite.is_empty() {
                pack(out, input, &column, &finite, 1, true);
            }
        }
    }
    (left.into_iter())
        .map(|(a, n)| {
            let name = quoted_name(&out.json["animations"][a], || format!("{a}"));
            let s = if n == 1 { "" } else { "s" };
            format!(
                "animation {name}: {n} key{s} NaN, infinite or a zero rotation (no pose) left out, the keys beside played across"
            )
        })
        .collect()
}
