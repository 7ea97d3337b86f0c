//! Pose blending: every rotation by slerp on the nearer hemisphere, translations (the root's
//! included: its weighted average), scales and morph weights by lerp.

use super::rig::{slerp, Pose, Trs};

pub fn mix(a: &Pose, b: &Pose, w: f64) -> Pose {
    let local = a
        .local
        .iter()
        .zip(&b.local)
        .map(|(x, y)| Trs {
            t: x.t.lerp(y.t, w),
            r: slerp(x.r, y.r, w),
            s: x.s.lerp(y.s, w),
        })
        .collect();
    let weights = a
        .weights
        .iter()
        .zip(&b.weights)
        .map(|(x, y)| {
            (0..x.len().max(y.len()))
                .map(|k| {
                    let (p, q) = (
                        x.get(k).copied().unwrap_or(0.0),
                        y.get(k).copied().unwrap_or(0.0),
                    );
                    p + (q - p) * w
                })
                .collect()
        })
        .collect();
    Pose { local, weights }
}
