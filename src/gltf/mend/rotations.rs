//! Rotation keys ([`rotations`]) must be unit quaternions: a key farther from unit length
//! than the validator allows ([`UNIT_LENGTH`]) is divided by its length (a CUBICSPLINE key's
//! tangents by the same), as a player's slerp does; float outputs of `rotation` channels only.

use super::Column;
use crate::gltf::build::BinBuilder;
use crate::gltf::read::{arr, quoted_name};
use serde_json::Value;

/// How far from 1 the validator lets a rotation key's length be.
const UNIT_LENGTH: f64 = 0.00769;

/// Divide every float rotation key of the output's animations that is farther than
/// [`UNIT_LENGTH`] from unit length by its length (a CUBICSPLINE key's tangents by the same),
/// in place in `bin`; returns a line for each animation with such keys.
pub fn rotations(json: &Value, bin: &mut BinBuilder) -> Vec<String> {
    let mut lines = Vec::new();
    let mut done = std::collections::BTreeSet::new();
    for (a, anim) in arr(json, "animations").iter().enumerate() {
        let (mut keys, mut lo, mut hi) = (0, f64::INFINITY, f64::NEG_INFINITY);
        for ch in arr(anim, "channels") {
            if ch["target"]["path"].as_str() != Some("rotation") {
                continue;
            }
            let sampler = &anim["samplers"][ch["sampler"].as_u64().unwrap_or(u64::MAX) as usize];
            let Some(out) = sampler["output"].as_u64().map(|o| o as usize) else {
                continue;
            };
            let count = json["accessors"][out]["count"].as_u64().unwrap_or(0) as usize;
            let column = Column::of(json, bin, out, count).filter(|c| c.component == 5126);
            let Some(column) = column.filter(|_| done.insert(out)) else {
                continue;
            };
            // CUBICSPLINE: (in-tangent, value, out-tangent) per key.
            let per_key = match sampler["interpolation"].as_str() {
                Some("CUBICSPLINE") => 3,
                _ => 1,
            };
            for k in 0..count / per_key {
                let value = per_key * k + per_key / 2;
                let q: Vec<f64> = (0..4)
                    .map(|c| column.float(&bin.bytes, value, c) as f64)
                    .collect();
                let length = q.iter().map(|x| x * x).sum::<f64>().sqrt();
                if (length - 1.0).abs() <= UNIT_LENGTH || length <= 0.0 || !length.is_finite() {
                    continue;
                }
                for e in per_key * k..per_key * (k + 1) {
                    for c in 0..4 {
                        let x = column.float(&bin.bytes, e, c) as f64;
                        column.set_float(&mut bin.bytes, e, c, (x / length) as f32);
                    }
                }
                (keys, lo, hi) = (keys + 1, lo.min(length), hi.max(length));
            }
        }
        if keys > 0 {
            let name = quoted_name(anim, || format!("{a}"));
            lines.push(format!(
                "animation {name}: {keys} rotation keys of length {lo:.4}-{hi:.4}, not the unit quaternions glTF requires; written divided by their lengths"
            ));
        }
    }
    lines
}
