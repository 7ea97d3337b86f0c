//! `inbetween eval`: hold-out accuracy of the interpolation methods on a file's own keys.
//!
//! For each morph mesh (its first track), keep every `step`-th key, predict each dropped key
//! from the kept ones with each method, and measure the RMS vertex error divided by the
//! bounding-box diagonal of the true key. Dropped keys after the last kept one are not scored
//! (they would be extrapolation). Methods:
//! * `linear`: vertex lerp between the two kept keys around the dropped one;
//! * `poscr`: Catmull-Rom on vertex positions (uniform in key index, centripetal is not used);
//! * `seed`: the seed method between the two kept keys;
//! * `spline`: the C1 gradient-space spline over all kept keys.
//!
//! A clip's eases (CUBICSPLINE tangents) are left out: they are the clip's motion at each key
//! toward its neighbours, which a kept key no longer has (the Flamingo's conversion stops at
//! every key; kept with them, every other key would be a stop), so each method predicts from
//! the kept poses and their times alone.

use crate::gltf::Document;
use crate::tween::{
    bbox_diagonal, find_morph_meshes, is_loop, key_poses, rms_rel, KeyOptions, KeySource, KeyTrack,
    Method, MorphMesh, Pattern, Segment, Welded,
};
use anyhow::{bail, Result};
use glam::DVec3;
use serde::Serialize;
use std::path::Path;

/// One evaluated method on one mesh.
#[derive(Clone, Debug, Serialize)]
pub struct MethodScore {
    pub method: String,
    /// RMS vertex error / bounding-box diagonal, mean over the dropped keys.
    pub mean: f64,
    /// ... and the largest.
    pub max: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct MeshScore {
    pub mesh: String,
    pub keys: usize,
    pub step: usize,
    pub dropped: usize,
    pub looped: bool,
    pub scores: Vec<MethodScore>,
}

/// The methods `eval` knows.
pub const METHODS: &[&str] = &["linear", "poscr", "seed", "spline"];

/// Catmull-Rom through p0..p3 at t in [0, 1] between p1 and p2 (uniform parameterisation).
pub fn catmull_rom(p0: DVec3, p1: DVec3, p2: DVec3, p3: DVec3, t: f64) -> DVec3 {
    let t2 = t * t;
    let t3 = t2 * t;
    0.5 * ((2.0 * p1)
        + (p2 - p0) * t
        + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * t2
        + (3.0 * p1 - p0 - 3.0 * p2 + p3) * t3)
}

/// Score `methods` on every morph mesh of the file `input` (keys from `keys`), keeping every
/// `step`-th key.
pub fn run_eval(
    input: &Path,
    step: usize,
    methods: &[String],
    keys: KeySource,
) -> Result<Vec<MeshScore>> {
    let doc = Document::open(input)?;
    let opts = KeyOptions {
        source: keys,
        animation: None,
    };
    let methods: Vec<&str> = methods.iter().map(String::as_str).collect();
    find_morph_meshes(&doc, &opts)?
        .iter()
        .map(|m| evaluate(m, step, &methods).map_err(|e| doc.err(format!("{e:#}"))))
        .collect()
}

/// Score `methods` on `mesh` keeping every `step`-th key.
pub fn evaluate(mesh: &MorphMesh, step: usize, methods: &[&str]) -> Result<MeshScore> {
    if step < 2 {
        bail!("--step must be at least 2 (every key kept leaves nothing to predict)");
    }
    let track = &mesh.tracks[0];
    let welded = Welded::build(mesh);
    let keys: Vec<Vec<DVec3>> = key_poses(mesh, track)
        .iter()
        .map(|k| welded.weld(k))
        .collect();
    let times = &track.times;
    let kept: Vec<usize> = (0..keys.len()).step_by(step).collect();
    if kept.len() < 2 {
        bail!(
            "mesh {:?}: {} keys leave fewer than two kept at --step {step}",
            mesh.name,
            keys.len()
        );
    }
    let dropped: Vec<usize> = (0..*kept.last().unwrap())
        .filter(|i| i % step != 0)
        .collect();
    let pattern = Pattern::new(welded.n, &welded.triangles, &keys[0])?;
    let kept_keys: Vec<Vec<DVec3>> = kept.iter().map(|&i| keys[i].clone()).collect();
    let kept_times: Vec<f64> = kept.iter().map(|&i| times[i]).collect();
    // A cycle only when the kept keys close it.
    let looped = is_loop(&kept_keys);
    let mut scores = Vec::new();
    for &method in methods {
        let mut errs = Vec::new();
        // The segment of kept keys a, a + 1 last built (dropped keys come in order).
        let mut cache: Option<(usize, Segment)> = None;
        for &i in &dropped {
            let a = i / step; // index into kept
            let (ia, ib) = (kept[a], kept[a + 1]);
            let t = (times[i] - times[ia]) / (times[ib] - times[ia]);
            let predicted = match method {
                "linear" => keys[ia]
                    .iter()
                    .zip(&keys[ib])
                    .map(|(p, q)| p.lerp(*q, t))
                    .collect::<Vec<_>>(),
                "poscr" => {
                    let n = kept.len();
                    let prev = if a > 0 {
                        kept[a - 1]
                    } else if looped {
                        kept[n - 2]
                    } else {
                        ia
                    };
                    let next = if a + 2 < n {
                        kept[a + 2]
                    } else if looped {
                        kept[1]
                    } else {
                        ib
                    };
                    (0..welded.n)
                        .map(|v| {
                            catmull_rom(keys[prev][v], keys[ia][v], keys[ib][v], keys[next][v], t)
                        })
                        .collect()
                }
                "seed" | "spline" => {
                    if cache.as_ref().is_none_or(|(k, _)| *k != a) {
                        let m = if method == "seed" {
                            Method::Seed
                        } else {
                            Method::Spline
                        };
                        let s = KeyTrack {
                            keys: &kept_keys,
                            times: &kept_times,
                            pattern: Some(&pattern),
                            triangles: &welded.triangles,
                            eases: None,
                        }
                        .segment(m, true, a, a + 1)?;
                        cache = Some((a, s));
                    }
                    cache.as_ref().unwrap().1.frame(t)
                }
                m => bail!("unknown method {m:?} (known: {})", METHODS.join(", ")),
            };
            errs.push(rms_rel(&predicted, &keys[i], bbox_diagonal(&keys[i])));
        }
        let mean = errs.iter().sum::<f64>() / errs.len().max(1) as f64;
        let max = errs.iter().copied().fold(0.0, f64::max);
        scores.push(MethodScore {
            method: method.to_string(),
            mean,
            max,
        });
    }
    Ok(MeshScore {
        mesh: mesh.name.clone(),
        keys: keys.len(),
        step,
        dropped: dropped.len(),
        looped,
        scores,
    })
}

/// A plain-text table of the scores.
pub fn table(scores: &[MeshScore]) -> String {
    let mut s = String::new();
    for m in scores {
        s += &format!(
            "mesh {:?}: {} keys, step {}, {} dropped keys predicted{}\n",
            m.mesh,
            m.keys,
            m.step,
            m.dropped,
            if m.looped { ", looped" } else { "" }
        );
        s += "| method | mean RMS error / diagonal | max |\n|---|---|---|\n";
        for sc in &m.scores {
            s += &format!("| {} | {:.5} | {:.5} |\n", sc.method, sc.mean, sc.max);
        }
    }
    s
}
