//! `inbetween inspect FILE`: what the tool finds in a file before anything is run. For glTF:
//! morph meshes (targets, names, vertices, triangles), animations (channels, keys, key rate
//! and grid, duration, interpolation), the tracks `tween` would use with its default options
//! and what it would write (frames, new targets, about how many bytes), the skinned clips
//! `blend` can mix (each with what it finds in the clip alone: `blend::clip_gaits`), and the
//! required extensions with whether they are decoded. For a BVH
//! capture, see [`bvh`]. Text, or JSON (`schemas/inspect.schema.json`).

use crate::gltf::{
    arr, begin, clip_name, listed, quoted_name, target_names, weights_target, Access, Container,
    Document, PASSED_THROUGH,
};
use crate::tween::{
    find_morph_meshes, grid_of, plan, skeletal_clips, targets_given_normals, KeyOptions, KeySource,
    MorphMesh, TrackOrigin, TweenOptions,
};
use anyhow::Result;
use glam::DVec3;
use serde::Serialize;
use serde_json::Value;
use std::collections::BTreeSet;
use std::path::Path;

mod bvh;

pub use bvh::BvhInspection;

/// What `inspect` found: a glTF file or a BVH capture.
#[derive(Serialize)]
#[serde(untagged)]
pub enum Found {
    Gltf(Inspection),
    Bvh(BvhInspection),
}

/// Inspect the file at `path`: a BVH capture (by its `.bvh` extension or its first word,
/// HIERARCHY), else glTF.
pub fn inspect(path: &Path, access: &Access) -> Result<Found> {
    match crate::blend::is_capture(path) {
        true => bvh::inspect(path).map(Found::Bvh),
        false => inspect_gltf(path, access).map(Found::Gltf),
    }
}

/// The inspection as text for a person.
pub fn text(found: &Found) -> String {
    match found {
        Found::Gltf(i) => gltf_text(i),
        Found::Bvh(i) => bvh::text(i),
    }
}

#[derive(Serialize)]
pub struct Inspection {
    pub file: String,
    pub bytes: u64,
    pub generator: Option<String>,
    pub extensions: Vec<Extension>,
    /// What a glTF output of the file is written with that the file breaks of glTF's rules or
    /// spells otherwise, a line each (as `tween` and `blend` say them).
    pub mended: Vec<String>,
    pub morph_meshes: Vec<MorphMeshInfo>,
    pub animations: Vec<AnimationInfo>,
    pub tween: TweenInfo,
    pub blend: BlendInfo,
}

#[derive(Serialize)]
pub struct Extension {
    pub name: String,
    pub required: bool,
    /// `decoded` (decompressed on read), `kept` (read as it is: quantized data), `passed
    /// through` (not read, written back unchanged) or `unknown`.
    pub status: &'static str,
}

#[derive(Serialize)]
pub struct MorphMeshInfo {
    pub mesh: usize,
    pub name: String,
    pub primitives: usize,
    pub vertices: usize,
    pub triangles: usize,
    pub targets: usize,
    pub target_names: Vec<String>,
}

#[derive(Serialize)]
pub struct AnimationInfo {
    pub index: usize,
    pub name: String,
    pub channels: usize,
    /// Channels that drive morph weights.
    pub weights_channels: usize,
    /// Keys of the sampler with the most.
    pub keys: usize,
    /// Keys per second of the densest sampler.
    pub key_rate: f64,
    /// The frame grid every key time lies on (per second), if any.
    pub grid: Option<f64>,
    pub duration: f64,
    pub interpolation: Vec<String>,
}

#[derive(Serialize)]
pub struct TweenInfo {
    pub tracks: Vec<TrackInfo>,
    /// Why `tween` would refuse the file, when it would.
    pub refused: Option<String>,
}

#[derive(Serialize)]
pub struct TrackInfo {
    pub mesh: String,
    /// `animation NAME` or `targets`.
    pub keys_from: String,
    pub keys: usize,
    pub frames: usize,
    /// Targets a glTF output adds (frames between keys).
    pub new_targets: usize,
    /// About how many bytes a glTF output adds for this track.
    pub added_bytes: u64,
}

#[derive(Serialize)]
pub struct BlendInfo {
    pub skins: usize,
    /// Animations that move joints of a skin: what `blend --clips` can name.
    pub clips: Vec<String>,
    /// What `blend` finds in each of them alone.
    pub gaits: Vec<ClipGait>,
}

#[derive(Serialize)]
pub struct ClipGait {
    pub clip: String,
    #[serde(flatten)]
    pub gait: GaitInfo,
}

/// What `blend` finds in one clip alone ([`crate::blend::Gait`]).
#[derive(Serialize)]
pub struct GaitInfo {
    /// The feet found (their chains' end joints).
    pub feet: Vec<String>,
    /// How far the feet travel forward and back relative to the root, in leg lengths.
    pub stride: f64,
    /// Stride cycles found: (start, period) in seconds.
    pub cycles: Vec<[f64; 2]>,
    /// Why `blend` would refuse the clip (without `--cycles none`).
    pub refused: Option<String>,
}

impl GaitInfo {
    pub fn of(g: crate::blend::Gait) -> GaitInfo {
        let (cycles, refused) = match g.cycles {
            Ok(spans) => (spans.iter().map(|&(a, b)| [a, b]).collect(), None),
            Err(e) => (Vec::new(), Some(format!("{e:#}"))),
        };
        GaitInfo {
            feet: g.feet,
            stride: g.stride,
            cycles,
            refused,
        }
    }
}

/// A clip's gait in words: its feet, stride and cycles, or why `blend` refuses it alone.
fn gait_line(g: &GaitInfo) -> String {
    if let Some(why) = &g.refused {
        return format!("refuses it alone: {why}");
    }
    let feet: Vec<String> = g.feet.iter().map(|f| format!("{f:?}")).collect();
    let periods: Vec<f64> = g.cycles.iter().map(|c| c[1]).collect();
    // A long capture's hundreds of cycles as their range (`--json` lists every one).
    let of = match periods.len() {
        0..=LISTED_CYCLES => {
            let each: Vec<String> = periods.iter().map(|p| format!("{p:.3}")).collect();
            each.join(", ")
        }
        _ => {
            let (lo, hi) = periods
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &p| {
                    (l.min(p), h.max(p))
                });
            let mean = periods.iter().sum::<f64>() / periods.len() as f64;
            format!("{lo:.3} to {hi:.3} (mean {mean:.3})")
        }
    };
    format!(
        "feet {}, stride {:.2} leg lengths, {} cycle{} of {of} s",
        feet.join(", "),
        g.stride,
        g.cycles.len(),
        if g.cycles.len() == 1 { "" } else { "s" },
    )
}

/// Most cycle periods a gait's line lists one by one.
const LISTED_CYCLES: usize = 8;

/// Inspect the file at `path`.
fn inspect_gltf(path: &Path, access: &Access) -> Result<Inspection> {
    let doc = Document::open_with(path, access)?;
    let json = &doc.json;
    let meshes = find_morph_meshes(
        &doc,
        &KeyOptions {
            source: KeySource::Auto,
            animation: None,
        },
    );
    let (tracks, refused) = match &meshes {
        Ok(m) => (tween_tracks(m), None),
        Err(e) => (Vec::new(), Some(format!("{e:#}"))),
    };
    let labels = clip_labels(json);
    Ok(Inspection {
        file: path.display().to_string(),
        bytes: doc.input_bytes,
        generator: json["asset"]["generator"].as_str().map(str::to_owned),
        extensions: extensions(&doc),
        // Nothing is written: the output is begun in memory only, for what it mends.
        mended: begin(&doc, Container::Glb, Path::new("inspect.glb"))
            .map(|out| out.mended)
            .unwrap_or_default(),
        morph_meshes: morph_meshes(&doc),
        animations: animations(&doc),
        tween: TweenInfo { tracks, refused },
        blend: BlendInfo {
            skins: arr(json, "skins").len(),
            clips: blend_clips(json),
            // A file `blend` cannot read (a broken rig) still shows the rest.
            gaits: (crate::blend::clip_gaits(&doc)
                .unwrap_or_default()
                .into_iter())
            .map(|(a, g)| ClipGait {
                // As `blend --clips` names it: its name, or its index where it has none or
                // shares it.
                clip: labels[a].clone(),
                gait: GaitInfo::of(g),
            })
            .collect(),
        },
    })
}

fn extensions(doc: &Document) -> Vec<Extension> {
    let names = |key: &str| -> Vec<String> {
        arr(&doc.json, key)
            .iter()
            .filter_map(Value::as_str)
            .map(str::to_owned)
            .collect()
    };
    let required = names("extensionsRequired");
    let mut out: Vec<Extension> = doc
        .decoded
        .iter()
        .map(|n| Extension {
            name: n.clone(),
            // A compressed file requires its compression (or relies on a fallback).
            required: true,
            status: "decoded",
        })
        .collect();
    for name in names("extensionsUsed") {
        let status = match name.as_str() {
            "KHR_mesh_quantization" => "kept",
            n if PASSED_THROUGH.contains(&n) => "passed through",
            _ => "unknown",
        };
        out.push(Extension {
            required: required.contains(&name),
            name,
            status,
        });
    }
    out
}

fn morph_meshes(doc: &Document) -> Vec<MorphMeshInfo> {
    let json = &doc.json;
    arr(json, "meshes")
        .iter()
        .enumerate()
        .filter_map(|(mi, m)| {
            let prims = arr(m, "primitives");
            let targets = prims.first().map_or(0, |p| arr(p, "targets").len());
            if targets == 0 {
                return None;
            }
            let count = |acc: Option<u64>| {
                acc.and_then(|a| doc.accessor_count(a as usize).ok())
                    .unwrap_or(0)
            };
            let vertices = prims
                .iter()
                .map(|p| count(p["attributes"]["POSITION"].as_u64()))
                .sum();
            let triangles = prims
                .iter()
                .map(|p| {
                    count(
                        p["indices"]
                            .as_u64()
                            .or(p["attributes"]["POSITION"].as_u64()),
                    ) / 3
                })
                .sum();
            Some(MorphMeshInfo {
                mesh: mi,
                name: m["name"].as_str().unwrap_or("").to_string(),
                primitives: prims.len(),
                vertices,
                triangles,
                targets,
                target_names: target_names(m),
            })
        })
        .collect()
}

fn animations(doc: &Document) -> Vec<AnimationInfo> {
    arr(&doc.json, "animations")
        .iter()
        .enumerate()
        .map(|(ai, a)| {
            let samplers = arr(a, "samplers");
            let times: Vec<Vec<f64>> = samplers
                .iter()
                .filter_map(|s| doc.read_f64(s["input"].as_u64()? as usize).ok())
                .map(|(t, _)| t)
                .collect();
            let all: Vec<f64> = times.iter().flatten().copied().collect();
            let (lo, hi) = all
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &t| {
                    (l.min(t), h.max(t))
                });
            let rate = times
                .iter()
                .filter(|t| t.len() > 1)
                .map(|t| (t.len() - 1) as f64 / (t[t.len() - 1] - t[0]).max(1e-9))
                .fold(0.0, f64::max);
            let interpolation: BTreeSet<String> = samplers
                .iter()
                .map(|s| s["interpolation"].as_str().unwrap_or("LINEAR").to_string())
                .collect();
            AnimationInfo {
                index: ai,
                name: a["name"].as_str().unwrap_or("").to_string(),
                channels: arr(a, "channels").len(),
                weights_channels: arr(a, "channels")
                    .iter()
                    .filter(|c| weights_target(&c["target"]).is_some())
                    .count(),
                keys: times.iter().map(Vec::len).max().unwrap_or(0),
                key_rate: rate,
                grid: grid_of(&all).map(|g| g.rate()),
                duration: if hi >= lo { hi - lo } else { 0.0 },
                interpolation: interpolation.into_iter().collect(),
            }
        })
        .collect()
}

/// What `tween` with its default options would do with each track.
fn tween_tracks(meshes: &[MorphMesh]) -> Vec<TrackInfo> {
    let opts = TweenOptions::default();
    let mut out = Vec::new();
    for m in meshes {
        let normals = m.primitives.iter().all(|p| p.normals.is_some());
        let tangents = normals && m.primitives.iter().all(|p| p.tangents.is_some());
        let per_vertex = 12 * (1 + normals as u64 + tangents as u64);
        for t in &m.tracks {
            let frames = plan(&t.times, &opts);
            let new_targets = frames.iter().filter(|f| f.t != 0.0 && f.t != 1.0).count();
            let targets = (m.target_count + new_targets) as u64;
            // Position-only targets beside base normals are given NORMAL (and TANGENT) deltas
            // of their own when frames go between the keys: sparse where that is smaller, about
            // where the positions move (the ring around them turns too, so a little more).
            let given: u64 = match new_targets {
                0 => 0,
                _ => (targets_given_normals(m).iter())
                    .map(|&i| {
                        let moved: u64 = (m.primitives.iter())
                            .map(|p| {
                                p.target_pos[i]
                                    .iter()
                                    .filter(|d| **d != DVec3::ZERO)
                                    .count()
                            })
                            .sum::<usize>() as u64;
                        let index = if m.vertex_count() <= 65_536 { 2 } else { 4 };
                        let dense = m.vertex_count() as u64 * 12;
                        dense.min(moved * (12 + index)) * (per_vertex / 12 - 1)
                    })
                    .sum(),
            };
            // The track's weights animation is written anew, frames by all targets; one
            // read from a clip replaces that clip's sampler (keys by its targets).
            let animation = frames.len() as u64 * (4 + 4 * targets);
            let replaced = match t.origin {
                TrackOrigin::Animation { .. } => {
                    t.times.len() as u64 * (4 + 4 * m.target_count as u64)
                }
                TrackOrigin::Targets { .. } => 0,
            };
            out.push(TrackInfo {
                mesh: m.name.clone(),
                keys_from: match &t.origin {
                    // Two nodes sharing the mesh, each with its own sampler in one clip: told
                    // apart by the sampler.
                    TrackOrigin::Animation {
                        animation, sampler, ..
                    } if (m.tracks.iter()).any(|o| {
                        matches!(&o.origin, TrackOrigin::Animation { animation: a, sampler: s, .. }
                            if a == animation && s != sampler)
                    }) =>
                    {
                        format!("animation {animation} sampler {sampler}")
                    }
                    TrackOrigin::Animation { animation, .. } => format!("animation {animation}"),
                    TrackOrigin::Targets { .. } => "targets".into(),
                },
                keys: t.times.len(),
                frames: frames.len(),
                new_targets,
                added_bytes: new_targets as u64 * m.vertex_count() as u64 * per_vertex
                    + given
                    + animation.saturating_sub(replaced),
            });
        }
    }
    out
}

/// Animations that move joints of a skin.
fn blend_clips(json: &Value) -> Vec<String> {
    let joints: BTreeSet<u64> = arr(json, "skins")
        .iter()
        .flat_map(|s| arr(s, "joints").iter().filter_map(Value::as_u64))
        .collect();
    let moving = skeletal_clips(json);
    arr(json, "animations")
        .iter()
        .enumerate()
        .filter(|(_, a)| {
            arr(a, "channels").iter().any(|c| {
                c["target"]["node"]
                    .as_u64()
                    .is_some_and(|n| joints.contains(&n))
                    && c["target"]["path"] != "weights"
            })
        })
        .map(|(i, a)| quoted_name(a, || i.to_string()))
        .filter(|n| moving.contains(n))
        .collect()
}

/// Each animation as `blend --clips` picks it: its name, where no other carries it, else its
/// index (an unnamed one, or one whose name others share: `gltf::clip_by` refuses that name).
fn clip_labels(json: &Value) -> Vec<String> {
    let anims = arr(json, "animations");
    let names: Vec<String> = (anims.iter().enumerate())
        .map(|(i, anim)| clip_name(anim, i))
        .collect();
    let mut carried: std::collections::HashMap<&str, usize> = std::collections::HashMap::new();
    for name in &names {
        *carried.entry(name.as_str()).or_default() += 1;
    }
    (names.iter().enumerate())
        .map(
            |(a, name)| match anims[a]["name"].is_string() && carried[name.as_str()] == 1 {
                true => name.clone(),
                false => a.to_string(),
            },
        )
        .collect()
}

/// A glTF file's inspection as text for a person.
fn gltf_text(i: &Inspection) -> String {
    let mut s = format!("{}: {} bytes", i.file, i.bytes);
    if let Some(g) = &i.generator {
        s += &format!(", written by {g}");
    }
    s += "\n";
    for e in &i.extensions {
        s += &format!(
            "extension {}{}: {}\n",
            e.name,
            if e.required { " (required)" } else { "" },
            e.status
        );
    }
    for line in &i.mended {
        s += &format!("mended in a glTF output: {line}\n");
    }
    for m in &i.morph_meshes {
        s += &format!(
            "morph mesh {} {:?}: {} primitive{}, {} vertices, {} triangles, {} targets",
            m.mesh,
            m.name,
            m.primitives,
            if m.primitives == 1 { "" } else { "s" },
            m.vertices,
            m.triangles,
            m.targets
        );
        if !m.target_names.is_empty() {
            s += &format!(" ({})", listed(&m.target_names));
        }
        s += "\n";
    }
    for a in &i.animations {
        s += &format!(
            "animation {} {:?}: {} channels ({} weights), {} keys, {:.3} s, {:.2} keys/s{}, {}\n",
            a.index,
            a.name,
            a.channels,
            a.weights_channels,
            a.keys,
            a.duration,
            a.key_rate,
            a.grid
                .map_or(String::new(), |g| format!(" on a {g} per second grid")),
            a.interpolation.join("/")
        );
    }
    match &i.tween.refused {
        Some(why) => s += &format!("tween: refuses it: {why}\n"),
        None => {
            for t in &i.tween.tracks {
                s += &format!(
                    "tween (defaults): mesh {:?}, keys from {}: {} keys -> {} frames, {} new targets, about {} KB added\n",
                    t.mesh,
                    t.keys_from,
                    t.keys,
                    t.frames,
                    t.new_targets,
                    t.added_bytes.div_ceil(1024)
                );
            }
        }
    }
    let moving: Vec<&str> = (i.animations.iter())
        .filter(|a| a.channels > a.weights_channels)
        .map(|a| a.name.as_str())
        .collect();
    if i.blend.skins == 0 && i.morph_meshes.is_empty() && !moving.is_empty() {
        let names: Vec<String> = moving.iter().map(|n| format!("{n:?}")).collect();
        s += &format!(
            "blend: no skin; its clips that move nodes ({}) can be the second file of `inbetween blend character.glb {}` (carried onto the character's nodes by name)\n",
            listed(&names),
            std::path::Path::new(&i.file)
                .file_name()
                .map_or(i.file.clone(), |f| f.to_string_lossy().into_owned())
        );
    } else if i.blend.clips.is_empty() {
        s += "blend: no skinned clips\n";
    } else {
        s += &format!(
            "blend: {} skin{}, clips {}\n",
            i.blend.skins,
            if i.blend.skins == 1 { "" } else { "s" },
            listed(&i.blend.clips)
        );
    }
    for g in &i.blend.gaits {
        s += &format!("  clip {:?}: {}\n", g.clip, gait_line(&g.gait));
    }
    s
}
