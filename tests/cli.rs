//! `inbetween tween` from file to file: outputs validate, read back, keep the rest of the file;
//! bad input fails cleanly.

mod common;

use common::*;
use glam::DVec3;
use inbetween::gltf::Document;
use inbetween::tween::Method;
use inbetween::tween::{track_frames_welded, Timing, TweenOptions};
use std::path::{Path, PathBuf};

fn out_in(dir: &tempfile::TempDir, name: &str) -> PathBuf {
    dir.path().join(name)
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Assert that the animation `out` plays (first weights channel of mesh 0, primitive 0) shows
/// `frames` (welded positions, expanded through `of_vertex`) within 1e-6 of the diagonal `d`.
fn assert_plays(
    out: &Path,
    frames: &[Vec<DVec3>],
    of_vertex: &[u32],
    d: f64,
    what: &str,
) -> Played {
    let played = played(out, 0, 0, 0);
    assert_eq!(
        played.times.len(),
        frames.len(),
        "{what}: one key per frame"
    );
    assert!(played.times.windows(2).all(|w| w[1] > w[0]), "{what}");
    for (f, (want, got)) in frames.iter().zip(&played.positions).enumerate() {
        for (v, g) in got.iter().enumerate() {
            let g = DVec3::new(g[0] as f64, g[1] as f64, g[2] as f64);
            let w = want[of_vertex[v] as usize];
            assert!(
                (g - w).length() <= 1e-6 * d,
                "{what} frame {f} vertex {v}: {g} vs {w}"
            );
        }
    }
    played
}

#[test]
fn samples_tween_to_valid_files_with_the_computed_frames() {
    let dir = tempfile::tempdir().unwrap();
    for (name, tweens) in [
        ("bar_twist.glb", 4),
        ("tube_bend.glb", 6),
        ("flag_wave.glb", 3),
    ] {
        let input = sample(name);
        // Frames from the library, expanded to input vertices.
        let meshes = morph_meshes(&input);
        let opts = TweenOptions::new(Method::Spline, Timing::Tweens(tweens));
        let (welded, frames) =
            track_frames_welded(&meshes[0], &meshes[0].tracks[0], &opts).unwrap();
        let keys = meshes[0].tracks[0].times.len();
        assert_eq!(frames.len(), (keys - 1) * (tweens + 1) + 1);
        let d = diag(&meshes[0].primitives[0].base);
        let authored = meshes[0].target_count;
        for (ext, layout) in [("glb", "rig"), ("gltf", "rig"), ("glb", "frames")] {
            let out = out_in(&dir, &format!("{name}.{layout}.{ext}"));
            tween_quietly(
                &input,
                &out,
                &["--tweens", &tweens.to_string(), "--layout", layout],
            );
            assert_valid(&out);
            let what = format!("{name} {layout} .{ext}");
            let p = assert_plays(&out, &frames, &welded.of_vertex, d, &what);
            // rig: the authored targets and one per frame between keys; frames: one per frame.
            let expected = match layout {
                "rig" => authored + (keys - 1) * tweens,
                _ => frames.len(),
            };
            assert_eq!(p.targets, expected, "{what}: targets");
            let doc = Document::open(&out).unwrap();
            let names = &doc.json["meshes"][0]["extras"]["targetNames"];
            assert_eq!(
                names.as_array().map(Vec::len),
                Some(expected),
                "{what}: {names}"
            );
        }
    }
}

#[test]
fn fps_and_tweens_set_the_frame_count() {
    let dir = tempfile::tempdir().unwrap();
    let out = out_in(&dir, "flag.glb");
    // Keys at 0, 0.5, ..., 2.0 s.
    run_ok(&[
        "tween",
        s(&sample("flag_wave.glb")),
        "-o",
        s(&out),
        "--fps",
        "30",
        "-q",
    ]);
    assert_eq!(played(&out, 0, 0, 0).times.len(), 61);
    tween_quietly(&sample("flag_wave.glb"), &out, &["--tweens", "0"]);
    assert_eq!(played(&out, 0, 0, 0).times.len(), 5);
    // The default: 30 frames a second between keys 0.5 s apart, keys kept: 4 x 15 + 1.
    tween_quietly(&sample("flag_wave.glb"), &out, &[]);
    let p = played(&out, 0, 0, 0);
    assert_eq!(p.times.len(), 61);
    let want: Vec<f32> = (0..61).map(|i| (i as f64 / 30.0) as f32).collect();
    assert_eq!(p.times, want, "frames on the 30 per second grid");
    // --keys targets ignores the animation: base + 4 targets at 0..4 s, 2 tweens between.
    tween_quietly(
        &sample("flag_wave.glb"),
        &out,
        &["--keys", "targets", "--tweens", "2"],
    );
    // The new animation follows the file's own (kept, padded for the new targets).
    assert_eq!(played(&out, 0, 0, 1).times.len(), 13);
    assert_eq!(played(&out, 0, 0, 0).times.len(), 5);
    assert_valid(&out);
}

#[test]
fn everything_else_comes_through() {
    let dir = tempfile::tempdir().unwrap();
    let input = sample("flag_wave.glb");
    let out = out_in(&dir, "flag.glb");
    tween_quietly(&input, &out, &[]);
    let a = Document::open(&input).unwrap();
    let b = Document::open(&out).unwrap();
    for key in ["materials", "nodes", "scenes", "scene", "asset"] {
        assert_eq!(a.json[key], b.json[key], "{key} changed");
    }
    // The pole (mesh 1) is untouched, and its data reads the same.
    assert_eq!(a.json["meshes"][1]["name"], b.json["meshes"][1]["name"]);
    let pa = a.json["meshes"][1]["primitives"][0]["attributes"]["POSITION"]
        .as_u64()
        .unwrap() as usize;
    let pb = b.json["meshes"][1]["primitives"][0]["attributes"]["POSITION"]
        .as_u64()
        .unwrap() as usize;
    assert_eq!(a.read_f64(pa).unwrap(), b.read_f64(pb).unwrap());
    assert_eq!(b.json["animations"][0]["name"], "keys");
    // The 4 authored targets (names kept) and the 56 frames between the 5 keys.
    let names = b.json["meshes"][0]["extras"]["targetNames"]
        .as_array()
        .unwrap();
    assert_eq!(names.len(), 60);
    let authored = a.json["meshes"][0]["extras"]["targetNames"]
        .as_array()
        .cloned();
    if let Some(authored) = authored {
        assert_eq!(&names[..authored.len()], &authored[..]);
    }
}

/// Target names a primitive carries (`primitives[].extras.targetNames`: assimp's exporter and
/// UniVRM's VRM 0 files put them there, not on the mesh), or each target (early UniVRM's
/// `targets[i].extras.targetName`, an entry glTF refuses: 24 validator errors on Parrot) are
/// the authored names too: Parrot so written tweens (plain and `--compact`) validator-clean to
/// its 12 authored names and then its frames' on the mesh, a primitive's list naming the same;
/// `inspect` lists them. (The authored names were written as target_0 ... on the mesh.)
#[test]
fn target_names_a_primitive_carries_are_kept() {
    let Some(fx) = fixtures() else { return };
    let parrot = fx.join("morph-keyframes/Parrot.glb");
    let doc = Document::open(&parrot).unwrap();
    let authored = doc.json["meshes"][0]["extras"]["targetNames"].clone();
    let dir = tempfile::tempdir().unwrap();
    for each in [false, true] {
        let input = dir.path().join("named.glb");
        edited_glb(&parrot, &input, |j| {
            let mesh = j["meshes"][0].as_object_mut().unwrap();
            let extras = mesh.remove("extras").unwrap();
            let p = &mut j["meshes"][0]["primitives"][0];
            match each {
                // Early UniVRM: each target names itself.
                true => {
                    let targets = p["targets"].as_array_mut().unwrap();
                    for (t, n) in targets
                        .iter_mut()
                        .zip(extras["targetNames"].as_array().unwrap())
                    {
                        t["extras"] = serde_json::json!({ "targetName": n });
                    }
                }
                false => p["extras"] = extras,
            }
        });
        let listed = run_ok(&["inspect", s(&input)]);
        let listed = String::from_utf8_lossy(&listed.stdout);
        assert!(
            listed.contains("12 targets (parrot_A_001, parrot_A_002"),
            "{listed}"
        );
        for extra in [&[][..], &["--compact"][..]] {
            let out = dir.path().join("out.glb");
            run_ok(&[&["tween", s(&input), "-o", s(&out), "-q"][..], extra].concat());
            assert_valid(&out);
            let (j, _) = glb_parts(&out);
            let names = j["meshes"][0]["extras"]["targetNames"]
                .as_array()
                .unwrap()
                .clone();
            let prim = &j["meshes"][0]["primitives"][0];
            assert_eq!(
                names.len(),
                prim["targets"].as_array().unwrap().len(),
                "{extra:?}"
            );
            assert_eq!(&names[..12], &authored.as_array().unwrap()[..], "{extra:?}");
            if !each {
                assert_eq!(prim["extras"]["targetNames"], serde_json::json!(names));
            }
        }
    }
}

/// A VRM avatar (a face rig's usual home) is a GLB file: read as one, and `-o face.vrm`
/// written as one, the same bytes as `-o face.glb` (it was refused: "unknown output
/// extension").
#[test]
fn a_vrm_is_read_and_written_as_the_glb_it_is() {
    let dir = tempfile::tempdir().unwrap();
    let vrm = dir.path().join("face.vrm");
    std::fs::copy(sample("flag_wave.glb"), &vrm).unwrap();
    let (a, b) = (dir.path().join("out.vrm"), dir.path().join("out.glb"));
    run_ok(&["tween", s(&vrm), "-o", s(&a), "-q"]);
    run_ok(&["tween", s(&vrm), "-o", s(&b), "-q"]);
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
    assert_valid(&b);
}

/// flag_wave with texture-coordinate deltas in every target (VEC2) and colour deltas in the
/// first (VEC4, the others lacking them), as a UV-animating face rig has.
fn flag_with_uv_and_colour_deltas(path: &Path) {
    let doc = Document::open(&sample("flag_wave.glb")).unwrap();
    let mut json = doc.json.clone();
    let mut bin = doc.buffers[0].clone();
    let n = doc
        .read_f64(
            json["meshes"][0]["primitives"][0]["attributes"]["POSITION"]
                .as_u64()
                .unwrap() as usize,
        )
        .unwrap()
        .0
        .len()
        / 3;
    let mut push = |json: &mut serde_json::Value, values: Vec<f32>, ty: &str| -> usize {
        let offset = bin.len();
        bin.extend(values.iter().flat_map(|x| x.to_le_bytes()));
        let views = json["bufferViews"].as_array_mut().unwrap();
        views.push(
            serde_json::json!({"buffer": 0, "byteOffset": offset, "byteLength": 4 * values.len()}),
        );
        let view = views.len() - 1;
        let accessors = json["accessors"].as_array_mut().unwrap();
        accessors.push(
            serde_json::json!({"bufferView": view, "componentType": 5126, "count": n, "type": ty}),
        );
        accessors.len() - 1
    };
    let colour = push(&mut json, [0.5, 0.5, 0.5, 1.0].repeat(n), "VEC4");
    json["meshes"][0]["primitives"][0]["attributes"]["COLOR_0"] = colour.into();
    for t in 0..4 {
        let uv: Vec<f32> = (0..n)
            .flat_map(|v| [0.01 * (t + 1) as f32 * (v % 7) as f32, -0.02 * t as f32])
            .collect();
        let a = push(&mut json, uv, "VEC2");
        json["meshes"][0]["primitives"][0]["targets"][t]["TEXCOORD_0"] = a.into();
    }
    let red = push(&mut json, [0.4, -0.3, -0.3, 0.0].repeat(n), "VEC4");
    json["meshes"][0]["primitives"][0]["targets"][0]["COLOR_0"] = red.into();
    json["buffers"][0]["byteLength"] = bin.len().into();
    write_glb(path, &json, &bin);
}

/// Attribute `name` of mesh 0 primitive 0 as played at each key of its first weights channel
/// (base + weights x target deltas), flat.
fn played_attribute(path: &Path, name: &str) -> Vec<Vec<f64>> {
    let doc = Document::open(path).unwrap();
    let p = &doc.json["meshes"][0]["primitives"][0];
    let read = |a: &serde_json::Value| doc.read_f64(a.as_u64().unwrap() as usize).unwrap().0;
    let base = read(&p["attributes"][name]);
    let deltas: Vec<Vec<f64>> = p["targets"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| read(&t[name]))
        .collect();
    let (a, s) = mesh0_samplers(&doc)[0];
    let out = doc.json["animations"][a]["samplers"][s]["output"]
        .as_u64()
        .unwrap() as usize;
    let weights = doc.read_f64(out).unwrap().0;
    weights
        .chunks(deltas.len())
        .map(|w| {
            let mut v = base.clone();
            for (w, d) in w.iter().zip(&deltas) {
                for (x, d) in v.iter_mut().zip(d) {
                    *x += w * d;
                }
            }
            v
        })
        .collect()
}

#[test]
fn texture_coordinate_and_colour_deltas_play_in_both_layouts() {
    let dir = tempfile::tempdir().unwrap();
    let input = out_in(&dir, "uv.glb");
    flag_with_uv_and_colour_deltas(&input);
    assert_valid(&input);
    let rig = out_in(&dir, "rig.glb");
    let frames = out_in(&dir, "frames.glb");
    tween_quietly(&input, &rig, &[]);
    tween_quietly(&input, &frames, &["--layout", "frames"]);
    let compact = out_in(&dir, "compact.glb");
    tween_quietly(&input, &compact, &["--compact"]);
    // Every target of a primitive carries the attribute, with its own type (the rig's new
    // targets refer to zeros of VEC2 and VEC4).
    for out in [&rig, &frames, &compact] {
        assert_no_new_issues(&input, out);
    }
    let keys = played_attribute(&input, "TEXCOORD_0");
    for name in ["TEXCOORD_0", "COLOR_0"] {
        let a = played_attribute(&rig, name);
        let b = played_attribute(&frames, name);
        assert_eq!(a.len(), 61, "{name}: 5 keys and the 56 frames between them");
        assert_eq!(a.len(), b.len());
        for (f, (a, b)) in a.iter().zip(&b).enumerate() {
            let most = a
                .iter()
                .zip(b)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max);
            assert!(most < 1e-6, "{name} frame {f}: layouts differ by {most}");
        }
        // Compaction reorders the vertices: each frame's mean value per component.
        let c = if name == "COLOR_0" { 4 } else { 2 };
        let mean = |f: &[f64]| -> Vec<f64> {
            (0..c)
                .map(|k| f.iter().skip(k).step_by(c).sum::<f64>() * c as f64 / f.len() as f64)
                .collect()
        };
        let packed = played_attribute(&compact, name);
        assert_eq!(packed.len(), a.len());
        for (f, (a, p)) in a.iter().zip(&packed).enumerate() {
            let (a, p) = (mean(a), mean(p));
            let most = a
                .iter()
                .zip(&p)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max);
            assert!(
                most < 1e-4,
                "{name} frame {f}: compacted {p:?} against {a:?}"
            );
        }
        if name == "TEXCOORD_0" {
            // Keys play the input's; frames between keys move between them.
            let first_key = &a[0];
            assert!(first_key
                .iter()
                .zip(&keys[0])
                .all(|(x, y)| (x - y).abs() < 1e-6));
            assert!(a
                .iter()
                .skip(1)
                .any(|f| f.iter().zip(first_key).any(|(x, y)| (x - y).abs() > 1e-3)));
        }
    }
    // A USD point cache cannot play them: said, not dropped silently.
    let usd = out_in(&dir, "uv.usda");
    let said = run_ok(&["tween", s(&input), "-o", s(&usd)]);
    let said =
        String::from_utf8_lossy(&said.stderr).to_string() + &String::from_utf8_lossy(&said.stdout);
    assert!(
        said.contains("warning:") && said.contains("morphs COLOR_0, TEXCOORD_0 too"),
        "{said}"
    );
    let refused = out_in(&dir, "refused.glb");
    assert_refused(
        &[
            "tween",
            s(&input),
            "-o",
            s(&refused),
            "--layout",
            "frames",
            "--compact",
        ],
        "uv.glb",
        "COLOR_0 morph deltas, which --compact cannot keep",
        &refused,
    );
}

/// `target` as a KHR_animation_pointer channel target aimed at `pointer`.
fn pointer_target(pointer: &str) -> serde_json::Value {
    serde_json::json!({"path": "pointer", "extensions": {"KHR_animation_pointer": {"pointer": pointer}}})
}

#[test]
fn weights_animated_through_animation_pointers_are_keys() {
    let dir = tempfile::tempdir().unwrap();
    let plain = sample("flag_wave.glb");
    for pointer in ["/nodes/0/weights", "/meshes/0/weights"] {
        let input = out_in(&dir, "pointer.glb");
        edited_glb(&plain, &input, |j| {
            j["animations"][0]["channels"][0]["target"] = pointer_target(pointer);
            j["extensionsUsed"] = serde_json::json!(["KHR_animation_pointer"]);
        });
        for args in [&[][..], &["--layout", "frames"], &["--keys", "targets"]] {
            let (a, b) = (out_in(&dir, "a.glb"), out_in(&dir, "b.glb"));
            tween_quietly(&plain, &a, args);
            tween_quietly(&input, &b, args);
            assert_no_new_issues(&input, &b);
            // The same file as from the plain weights channel, the channel's target aside:
            // its sampler rewritten (or, under --keys targets, padded) alike.
            let (a, b) = (Document::open(&a).unwrap(), Document::open(&b).unwrap());
            assert!(a.buffers == b.buffers, "{pointer} {args:?}: other data");
            let mut json = b.json.clone();
            let channel = &mut json["animations"][0]["channels"][0]["target"];
            assert_eq!(*channel, pointer_target(pointer), "{args:?}");
            *channel = serde_json::json!({"node": 0, "path": "weights"});
            json.as_object_mut().unwrap().remove("extensionsUsed");
            assert_eq!(json, a.json, "{pointer} {args:?}");
        }
    }
}

#[test]
fn keys_at_one_time_play_as_a_jump() {
    // flag_wave's key times 0, 0.5, 1, 1.5, 2 s with the third moved onto the second: a pose
    // that jumps at 0.5 s, as exporters write a cut (the validator asks for increasing times).
    let dir = tempfile::tempdir().unwrap();
    let plain = sample("flag_wave.glb");
    let input = out_in(&dir, "cut.glb");
    let doc = Document::open(&plain).unwrap();
    let (a, s) = mesh0_samplers(&doc)[0];
    let times = doc.json["animations"][a]["samplers"][s]["input"]
        .as_u64()
        .unwrap() as usize;
    assert_eq!(doc.read_f64(times).unwrap().0, [0.0, 0.5, 1.0, 1.5, 2.0]);
    poke_f32(&plain, &input, times, 2, 0, 0.5);
    let keys = played(&input, 0, 0, 0);
    for args in [&[][..], &["--layout", "frames"], &["--tweens", "2"]] {
        let out = out_in(&dir, "out.glb");
        tween_quietly(&input, &out, args);
        assert_no_new_issues(&input, &out);
        let p = played(&out, 0, 0, 0);
        assert!(
            p.times.windows(2).all(|w| w[1] > w[0]),
            "{args:?}: increasing times"
        );
        // Both sides of the jump are played as authored, one float32 step apart.
        let at = p
            .times
            .iter()
            .position(|&t| t == 0.5)
            .expect("a frame at the cut");
        assert_eq!(p.times[at + 1], 0.5f32.next_up(), "{args:?}");
        for (frame, key) in [(at, 1), (at + 1, 2)] {
            let most = p.positions[frame]
                .iter()
                .zip(&keys.positions[key])
                .map(|(a, b)| (0..3).map(|c| (a[c] - b[c]).abs()).fold(0.0, f32::max))
                .fold(0.0, f32::max);
            assert!(
                most < 1e-6,
                "{args:?}: frame {frame} is key {key} within {most}"
            );
        }
        assert!(p
            .positions
            .iter()
            .flatten()
            .flatten()
            .all(|x| x.is_finite()));
    }
    let usd = out_in(&dir, "cut.usda");
    tween_quietly(&input, &usd, &[]);
    let text = std::fs::read_to_string(&usd).unwrap();
    assert!(!text.contains("NaN"), "no NaN in the point cache");
    assert!(
        text.contains(" 15: ") && text.contains(" 15.000000000000002: "),
        "the cut's samples"
    );
}

#[test]
fn a_clip_s_other_channels_keep_time_with_its_weights() {
    // The weights' frames are moved later when they would start before 0 s (glTF times are not
    // negative): motion extended before the first key, or a file whose keys start before 0.
    // The clip's other channels move with them, shared time accessor or not; other clips stay.
    let dir = tempfile::tempdir().unwrap();
    let plain = sample("flag_wave.glb");
    for (offset, args) in [(0.0, &["--extend-before", "0.5"][..]), (-0.5, &[][..])] {
        let input = out_in(&dir, "pole.glb");
        flag_with_moving_pole(&plain, &input, offset);
        let out = out_in(&dir, "out.glb");
        tween_quietly(&input, &out, args);
        assert_no_new_issues(&input, &out);
        let (a, b) = (
            Document::open(&input).unwrap(),
            Document::open(&out).unwrap(),
        );
        let times = |doc: &Document, anim: usize, channel: usize| -> Vec<f64> {
            let clip = &doc.json["animations"][anim];
            let s = clip["channels"][channel]["sampler"].as_u64().unwrap() as usize;
            let input = clip["samplers"][s]["input"].as_u64().unwrap() as usize;
            doc.read_f64(input).unwrap().0
        };
        // Both clips move 0.5 s later: the flag's first key, at `offset`, plays at `offset` + 0.5.
        let keys = played(&input, 0, 0, 0);
        let p = played(&out, 0, 0, 0);
        assert_eq!(p.times[0], 0.0, "{args:?}");
        let at = p
            .times
            .iter()
            .position(|&t| t == offset + 0.5)
            .expect("the first key");
        assert_eq!(p.positions[at], keys.positions[0], "{args:?}");
        for channel in [1, 2] {
            let before = times(&a, 0, channel);
            let after = times(&b, 0, channel);
            let moved: Vec<f64> = before.iter().map(|t| (*t as f32 + 0.5) as f64).collect();
            assert_eq!(
                after, moved,
                "{args:?}: channel {channel} keeps time with the weights"
            );
        }
        assert_eq!(
            times(&b, 1, 0),
            [0.0, 1.0],
            "{args:?}: another clip is left as it was"
        );
    }
}

#[test]
fn a_usd_stage_says_which_animated_meshes_its_scene_does_not_show() {
    // flag_wave with a second flag (its own mesh and node, animated by the same keys) in a
    // second scene: the file's scene 0 shows the first flag and the pole only.
    let dir = tempfile::tempdir().unwrap();
    let input = out_in(&dir, "scenes.glb");
    edited_glb(&sample("flag_wave.glb"), &input, |j| {
        let mesh = j["meshes"][0].clone();
        j["meshes"].as_array_mut().unwrap().push(mesh);
        j["nodes"]
            .as_array_mut()
            .unwrap()
            .push(serde_json::json!({"name": "second", "mesh": 2}));
        let channel = serde_json::json!({"sampler": 0, "target": {"node": 2, "path": "weights"}});
        j["animations"][0]["channels"]
            .as_array_mut()
            .unwrap()
            .push(channel);
        j["scenes"] = serde_json::json!([{"name": "shown", "nodes": [0, 1]}, {"name": "other", "nodes": [2]}]);
    });
    let usd = out_in(&dir, "scenes.usda");
    let r = run_ok(&["tween", s(&input), "-o", s(&usd)]);
    let said = String::from_utf8_lossy(&r.stderr).to_string() + &String::from_utf8_lossy(&r.stdout);
    assert!(
        said.contains("warning:") && said.contains("does not show \"flag\""),
        "{said}"
    );
    let text = std::fs::read_to_string(&usd).unwrap();
    assert_eq!(text.matches("points.timeSamples").count(), 1);
    // With the first flag's node gone from scene 0 too, nothing animated is left: refused.
    let none = out_in(&dir, "none.glb");
    edited_glb(&input, &none, |j| {
        j["scenes"][0]["nodes"] = serde_json::json!([1])
    });
    let out = out_in(&dir, "none.usda");
    assert_refused(
        &["tween", s(&none), "-o", s(&out)],
        "none.glb",
        "shows none of the animated meshes",
        &out,
    );
}

#[test]
fn meshes_sharing_a_sampler_each_play_their_own_frames() {
    // flag_wave and a second flag whose targets come in reverse order, both driven by the one
    // sampler of the file: compacted, each mesh has its own basis weights, and the first
    // played the second's (0.0196 off on a flag 3.6 across).
    let dir = tempfile::tempdir().unwrap();
    let input = out_in(&dir, "shared.glb");
    edited_glb(&sample("flag_wave.glb"), &input, |j| {
        let mut mesh = j["meshes"][0].clone();
        mesh["name"] = "reversed".into();
        let targets = mesh["primitives"][0]["targets"].as_array_mut().unwrap();
        targets.reverse();
        j["meshes"].as_array_mut().unwrap().push(mesh);
        j["nodes"]
            .as_array_mut()
            .unwrap()
            .push(serde_json::json!({"mesh": 2, "translation": [0, 0, 3]}));
        j["scenes"][0]["nodes"]
            .as_array_mut()
            .unwrap()
            .push(2.into());
        let channel = serde_json::json!({"sampler": 0, "target": {"node": 2, "path": "weights"}});
        j["animations"][0]["channels"]
            .as_array_mut()
            .unwrap()
            .push(channel);
    });
    let (dense, basis) = (out_in(&dir, "dense.glb"), out_in(&dir, "basis.glb"));
    tween_quietly(&input, &dense, &[]);
    tween_quietly(&input, &basis, &["--basis", "auto"]);
    for out in [&dense, &basis] {
        assert_no_new_issues(&input, out);
    }
    for mesh in [0, 2] {
        let (a, b) = (played(&dense, mesh, 0, 0), played(&basis, mesh, 0, 0));
        assert_eq!(a.times, b.times);
        let most = a
            .positions
            .iter()
            .flatten()
            .zip(b.positions.iter().flatten())
            .map(|(p, q)| (0..3).map(|c| (p[c] - q[c]).abs()).fold(0.0, f32::max))
            .fold(0.0, f32::max);
        // The flag's diagonal is about 3.6; --compact keeps every vertex within 3e-4 of it.
        assert!(
            most < 3e-4 * 3.7,
            "mesh {mesh}: {most} from its dense frames"
        );
    }
    // Tweened from the targets, the shared clip stays and is padded for each mesh's new
    // targets: a sampler each (the second mesh read the first's padding, an accessor the input
    // lacks: "accessor 251 does not exist").
    let targets = out_in(&dir, "targets.glb");
    tween_quietly(&input, &targets, &["--keys", "targets"]);
    assert_no_new_issues(&input, &targets);
    let doc = Document::open(&targets).unwrap();
    let clip = &doc.json["animations"][0];
    for (c, mesh) in [(0, 0), (1, 2)] {
        let s = clip["channels"][c]["sampler"].as_u64().unwrap() as usize;
        let output = clip["samplers"][s]["output"].as_u64().unwrap() as usize;
        let width = doc.json["meshes"][mesh]["primitives"][0]["targets"]
            .as_array()
            .unwrap()
            .len();
        assert_eq!(
            doc.read_f64(output).unwrap().0.len(),
            5 * width,
            "mesh {mesh}: 5 keys"
        );
    }
}

#[test]
fn output_is_deterministic_for_any_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let a = out_in(&dir, "a.glb");
    let b = out_in(&dir, "b.glb");
    tween_quietly(&sample("tube_bend.glb"), &a, &["--threads", "1"]);
    tween_quietly(&sample("tube_bend.glb"), &b, &["--threads", "2"]);
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
    // A mesh large enough for a supernodal factor, factored subtree by subtree on the threads
    // there are (72,000 triangles, two keys).
    use inbetween::synth::{bend, tube, KeyedMesh, KeyframeFile};
    let s = tube(300, 120, 6.0, 1.0, 1.0);
    let key = bend(&s.positions, 3.0, 120f64.to_radians(), 0.8);
    let input = out_in(&dir, "large.glb");
    KeyframeFile {
        meshes: vec![KeyedMesh::new("tube", s, vec![key])],
        key_times: None,
        key_weights: None,
    }
    .write(&input)
    .unwrap();
    let outputs: Vec<Vec<u8>> = ["1", "2", "3", "5"]
        .iter()
        .map(|t| {
            tween_quietly(&input, &a, &["--threads", t, "--tweens", "3"]);
            std::fs::read(&a).unwrap()
        })
        .collect();
    assert!(outputs.iter().all(|o| o == &outputs[0]));
}

#[test]
fn summary_unless_quiet() {
    let dir = tempfile::tempdir().unwrap();
    let out = out_in(&dir, "a.glb");
    let r = run_ok(&["tween", s(&sample("bar_twist.glb")), "-o", s(&out)]);
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        err.contains("2 keys -> 31 frames") && err.contains("spline") && err.contains(" B -> "),
        "{err}"
    );
    let r = run_ok(&[
        "tween",
        s(&sample("bar_twist.glb")),
        "-o",
        s(&out),
        "--quiet",
    ]);
    assert!(r.stderr.is_empty() && r.stdout.is_empty());
    let help = run_ok(&["tween", "--help"]);
    let help = String::from_utf8_lossy(&help.stdout);
    for word in [
        "--rate",
        "--layout",
        "--tweens",
        "--fps",
        "--method",
        "--keys",
        "--animation",
        "--quiet",
    ] {
        assert!(help.contains(word), "--help lacks {word}");
    }
}

#[test]
fn a_looped_clip_closes_its_other_channels_too() {
    // `--loop` appends the weights' first key one spacing (0.5 s) after the last (2 s): the
    // pole moved by the same clip gets its first key again at 2.5 s too (it held its last key
    // there, then jumped back), shared time accessor or not; another clip is left as it was.
    let dir = tempfile::tempdir().unwrap();
    let input = out_in(&dir, "pole.glb");
    flag_with_moving_pole(&sample("flag_wave.glb"), &input, 0.0);
    let out = out_in(&dir, "out.glb");
    tween_quietly(&input, &out, &["--loop"]);
    assert_no_new_issues(&input, &out);
    let (a, b) = (
        Document::open(&input).unwrap(),
        Document::open(&out).unwrap(),
    );
    let keys = |doc: &Document, anim: usize, channel: usize| -> (Vec<f64>, Vec<f64>) {
        let clip = &doc.json["animations"][anim];
        let s = &clip["samplers"][clip["channels"][channel]["sampler"].as_u64().unwrap() as usize];
        let read = |k: &str| doc.read_f64(s[k].as_u64().unwrap() as usize).unwrap().0;
        (read("input"), read("output"))
    };
    assert_eq!(played(&out, 0, 0, 0).times.last(), Some(&2.5));
    for (channel, width) in [(1, 3), (2, 4)] {
        let (t0, v0) = keys(&a, 0, channel);
        let (t1, v1) = keys(&b, 0, channel);
        assert_eq!(t1[..t0.len()], t0[..], "channel {channel}: its keys kept");
        assert_eq!(
            t1[t0.len()..],
            [2.5],
            "channel {channel}: closed at the clip's end"
        );
        assert_eq!(v1[..v0.len()], v0[..]);
        assert_eq!(
            v1[v0.len()..],
            v0[..width],
            "channel {channel}: its first key again"
        );
    }
    assert_eq!(
        keys(&b, 1, 0),
        keys(&a, 1, 0),
        "another clip is left as it was"
    );
}

#[test]
fn held_keys_are_tweened_and_said_so() {
    // A stepped clip (STEP: each key held until the next, a blocking pass as exporters write
    // it) is keys like any other: tweened, played LINEAR, and the summary says so.
    let dir = tempfile::tempdir().unwrap();
    let (plain, input) = (sample("flag_wave.glb"), out_in(&dir, "stepped.glb"));
    edited_glb(&plain, &input, |j| {
        j["animations"][0]["samplers"][0]["interpolation"] = serde_json::json!("STEP");
    });
    let (a, b) = (out_in(&dir, "a.glb"), out_in(&dir, "b.glb"));
    tween_quietly(&plain, &a, &[]);
    let r = run_ok(&["tween", s(&input), "-o", s(&b)]);
    let err = String::from_utf8_lossy(&r.stderr);
    let warned: Vec<&str> = err.lines().filter(|l| l.contains("STEP")).collect();
    assert_eq!(warned.len(), 1, "{err}");
    assert!(
        warned[0].starts_with("warning: ") && warned[0].contains("stepped.glb: animation \"keys\""),
        "{err}"
    );
    // The same file as from the clip played LINEAR.
    let quiet = tween_quietly(&input, &out_in(&dir, "c.glb"), &[]);
    assert!(quiet.stderr.is_empty());
    let (a, b) = (Document::open(&a).unwrap(), Document::open(&b).unwrap());
    assert!(a.buffers == b.buffers && a.json == b.json);
}

#[test]
fn eased_keys_the_seed_cannot_follow_are_said() {
    // The Flamingo converted with CUBICSPLINE weights (every tangent zero: an ease out of and
    // into each key): every method follows the eases between keys and says nothing. With key
    // 1's weights made key 0's and an ease out of key 0 toward target 2, the clip leaves key 0
    // and comes back: `seed`, whose path is the keys' chord, holds still there, and the
    // summary says so once; `spline` and `linear` follow; with no frame between keys
    // (`--rate 10`, its keys' own rate) nothing is said.
    let Some(fx) = fixtures() else { return };
    let dir = tempfile::tempdir().unwrap();
    let input = fx.join("morph-keyframes/Flamingo_cubicspline_unindexed.glb");
    let eased = |input: &Path, extra: &[&str]| -> Vec<String> {
        let out = out_in(&dir, "f.glb");
        let mut args = vec!["tween", s(input), "-o", s(&out)];
        args.extend_from_slice(extra);
        let r = run_ok(&args);
        let err = String::from_utf8_lossy(&r.stderr).into_owned();
        err.lines()
            .filter(|l| l.contains("CUBICSPLINE"))
            .map(str::to_owned)
            .collect()
    };
    for method in ["seed", "spline", "linear"] {
        assert!(eased(&input, &["--method", method]).is_empty(), "{method}");
    }
    // Sampler 0's output (accessor 18): per key, 14 in-tangents, 14 values, 14 out-tangents.
    let (a, b) = (out_in(&dir, "a.glb"), out_in(&dir, "b.glb"));
    let back = out_in(&dir, "back.glb");
    poke_f32(&input, &a, 18, 42 + 14, 0, 1.0);
    poke_f32(&a, &b, 18, 42 + 14 + 1, 0, 0.0);
    poke_f32(&b, &back, 18, 28 + 2, 0, 3.0);
    let warned = eased(&back, &["--method", "seed"]);
    assert_eq!(warned.len(), 1, "{warned:?}");
    assert!(
        warned[0].starts_with("warning: ")
            && warned[0].contains("animation \"KeyAction\" eases its weights away from and back to keys of the same weights")
            && warned[0].contains("the seed method"),
        "{warned:?}"
    );
    for extra in [
        &["--method", "spline"][..],
        &["--method", "linear"],
        &["--method", "seed", "--rate", "10"],
    ] {
        assert!(eased(&back, extra).is_empty(), "{extra:?}");
    }
}

#[test]
fn morph_targets_beside_clips_that_only_move_nodes_are_not_taken_as_keys() {
    // flag_wave with its weights clip replaced by one that turns its node: a file whose clips
    // move nodes and animate no weights, as RobotExpressive's face shapes beside its skeletal
    // clips come out of gltfpack (which drops constant weights channels). Its targets are
    // blend shapes, not keys: refused under `--keys auto` with the hint (the original Robot,
    // whose channels hold its weights still, is refused too), tweened with `--keys targets`.
    let dir = tempfile::tempdir().unwrap();
    let plain = sample("flag_wave.glb");
    let doc = Document::open(&plain).unwrap();
    let (mut json, mut bin) = (doc.json.clone(), doc.buffers[0].clone());
    let times = json["animations"][0]["samplers"][0]["input"]
        .as_u64()
        .unwrap() as usize;
    let n = json["accessors"][times]["count"].as_u64().unwrap() as usize;
    let turns: Vec<f32> = (0..n)
        .flat_map(|k| {
            let h = 0.1 * k as f32;
            [0.0, h.sin(), 0.0, h.cos()]
        })
        .collect();
    let rotation = push_f32_accessor(&mut json, &mut bin, &turns, "VEC4");
    let node = json["animations"][0]["channels"][0]["target"]["node"].clone();
    json["animations"][0] = serde_json::json!({
        "name": "turn",
        "samplers": [{"input": times, "output": rotation}],
        "channels": [{"sampler": 0, "target": {"node": node, "path": "rotation"}}],
    });
    let input = out_in(&dir, "turning.glb");
    write_glb(&input, &json, &bin);
    let out = out_in(&dir, "out.glb");
    assert_refused(
        &["tween", s(&input), "-o", s(&out)],
        "turning.glb",
        "no clip animates its weights; --keys targets tweens the targets",
        &out,
    );
    tween_quietly(&input, &out, &["--keys", "targets"]);
    let count = |j: &serde_json::Value| {
        j["meshes"][0]["primitives"][0]["targets"]
            .as_array()
            .map_or(0, Vec::len)
    };
    let (targets, authored) = (count(&Document::open(&out).unwrap().json), count(&json));
    assert!(targets > authored, "{targets} targets, {authored} authored");
}

#[test]
fn weights_that_move_no_vertex_are_refused_saying_why() {
    // flag_wave with its targets' POSITION deltas gone (targets of normals only, as shading
    // shapes are), and with one key: nothing to tween, each said as it is.
    let dir = tempfile::tempdir().unwrap();
    let plain = sample("flag_wave.glb");
    let normals = out_in(&dir, "normals.glb");
    edited_glb(&plain, &normals, |j| {
        for t in j["meshes"][0]["primitives"][0]["targets"]
            .as_array_mut()
            .unwrap()
        {
            t.as_object_mut().unwrap().remove("POSITION");
        }
    });
    let one = out_in(&dir, "one.glb");
    edited_glb(&plain, &one, |j| {
        let s = &mut j["animations"][0]["samplers"][0];
        *s = serde_json::json!({"input": s["input"], "output": s["output"], "interpolation": "LINEAR"});
        let times = j["animations"][0]["samplers"][0]["input"].as_u64().unwrap() as usize;
        j["accessors"][times]["count"] = 1.into();
        j["accessors"][times]["max"] = serde_json::json!([0.0]);
        let values = j["animations"][0]["samplers"][0]["output"]
            .as_u64()
            .unwrap() as usize;
        j["accessors"][values]["count"] = 4.into();
    });
    let out = out_in(&dir, "out.glb");
    for (input, name, why) in [
        (
            &normals,
            "normals.glb",
            "change only targets that move no vertex",
        ),
        (&one, "one.glb", "hold a single pose"),
    ] {
        assert_refused(&["tween", s(input), "-o", s(&out)], name, why, &out);
    }
}

#[test]
fn a_morph_mesh_no_clip_animates_keeps_its_pose_beside_an_animated_one() {
    // `--keys auto`: the flag is tweened from its clip; its posed copy, animated by nothing,
    // is left as authored and named in a warning (it was tweened through its targets, a new
    // clip making a still prop run through every blend shape).
    let dir = tempfile::tempdir().unwrap();
    let input = out_in(&dir, "posed.glb");
    flag_beside_a_posed_copy(&input);
    let out = out_in(&dir, "out.glb");
    let r = run_ok(&["tween", s(&input), "-o", s(&out)]);
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(err.contains("1 mesh (768 triangles)"), "{err}");
    assert!(
        err.contains("\"still_flag\" has morph targets and no weights animation: left as authored"),
        "{err}"
    );
    assert_no_new_issues(&input, &out);
    let (a, b) = (
        Document::open(&input).unwrap(),
        Document::open(&out).unwrap(),
    );
    assert_eq!(
        b.json["animations"].as_array().unwrap().len(),
        1,
        "no new clip"
    );
    assert_eq!(
        b.json["meshes"][2]["weights"],
        a.json["meshes"][2]["weights"]
    );
    assert_eq!(b.json["nodes"][2]["weights"], a.json["nodes"][2]["weights"]);
    let targets = |d: &Document| {
        d.json["meshes"][2]["primitives"][0]["targets"]
            .as_array()
            .unwrap()
            .len()
    };
    assert_eq!(targets(&b), targets(&a), "the copy's targets as authored");
    // --keys targets still tweens every mesh's targets.
    let all = out_in(&dir, "all.glb");
    let r = run_ok(&["tween", s(&input), "-o", s(&all), "--keys", "targets"]);
    assert!(String::from_utf8_lossy(&r.stderr).contains("2 meshes"));
}

#[test]
fn bad_input_fails_with_one_line_exit_2_and_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let good = sample("bar_twist.glb");
    let p = |n: &str| dir.path().join(n);
    std::fs::write(p("not.glb"), b"hello, not a gltf").unwrap();
    // A motion capture (with a byte-order mark and CRLF line ends, as some exporters write).
    std::fs::write(
        p("walk.bvh"),
        "\u{feff}HIERARCHY\r\nROOT Hips\r\n{\r\n\tOFFSET 0 0 0\r\n",
    )
    .unwrap();
    let mut short = std::fs::read(&good).unwrap();
    short.truncate(short.len() - 100);
    std::fs::write(p("short.glb"), &short).unwrap();
    // .gltf whose buffer file is missing.
    std::fs::write(
        p("nobuf.gltf"),
        r#"{"asset":{"version":"2.0"},"buffers":[{"uri":"missing.bin","byteLength":12}]}"#,
    )
    .unwrap();
    // .gltf whose buffer file is a Git LFS pointer (the repository cloned without its objects).
    std::fs::write(
        p("lfsbuf.gltf"),
        r#"{"asset":{"version":"2.0"},"buffers":[{"uri":"lfsbuf.bin","byteLength":69532}]}"#,
    )
    .unwrap();
    std::fs::write(p("lfsbuf.bin"), lfs_pointer(69532)).unwrap();
    std::fs::write(
        p("nomorph.gltf"),
        r#"{"asset":{"version":"2.0"},"meshes":[]}"#,
    )
    .unwrap();
    edited_glb(&good, &p("count.glb"), |j| {
        // The target's accessor is one element short.
        let acc = j["meshes"][0]["primitives"][0]["targets"][0]["POSITION"]
            .as_u64()
            .unwrap() as usize;
        let count = j["accessors"][acc]["count"].as_u64().unwrap();
        j["accessors"][acc]["count"] = (count - 1).into();
    });
    edited_glb(&good, &p("lines.glb"), |j| {
        j["meshes"][0]["primitives"][0]["mode"] = 1.into()
    });
    edited_glb(&good, &p("meshopt.glb"), |j| {
        // A meshopt view whose compressed bytes lie outside the buffer.
        j["extensionsUsed"] = serde_json::json!(["EXT_meshopt_compression"]);
        j["extensionsRequired"] = serde_json::json!(["EXT_meshopt_compression"]);
        j["bufferViews"][0]["extensions"] = serde_json::json!({ "EXT_meshopt_compression": {
            "buffer": 0, "byteOffset": 0, "byteLength": 1 << 30, "byteStride": 12,
            "count": 8, "mode": "ATTRIBUTES" } });
    });
    edited_glb(&good, &p("draco.glb"), |j| {
        // A Draco primitive whose stream is not Draco.
        j["extensionsUsed"] = serde_json::json!(["KHR_draco_mesh_compression"]);
        j["extensionsRequired"] = serde_json::json!(["KHR_draco_mesh_compression"]);
        j["meshes"][0]["primitives"][0]["extensions"] = serde_json::json!({
            "KHR_draco_mesh_compression": { "bufferView": 0, "attributes": { "POSITION": 0 } } });
    });
    // NaN positions: overwrite the first base position with NaN bytes.
    let doc = Document::open(&good).unwrap();
    let acc = doc.json["meshes"][0]["primitives"][0]["attributes"]["POSITION"]
        .as_u64()
        .unwrap() as usize;
    let view = doc.json["accessors"][acc]["bufferView"].as_u64().unwrap() as usize;
    let off = doc.json["bufferViews"][view]["byteOffset"]
        .as_u64()
        .unwrap_or(0) as usize;
    let mut bytes = std::fs::read(&good).unwrap();
    let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let bin_start = 20 + json_len + 8;
    bytes[bin_start + off..bin_start + off + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    std::fs::write(p("nan.glb"), &bytes).unwrap();

    // Files that stand in for a pipeline's assets, named as what they are.
    std::fs::write(p("pointer.glb"), lfs_pointer(182232)).unwrap();
    std::fs::write(
        p("page.glb"),
        "\n\n<!DOCTYPE html>\n<html lang=\"en\">\n<head><title>facecap.glb</title></head>",
    )
    .unwrap();
    std::fs::write(
        p("fbx.gltf"),
        b"Kaydara FBX Binary  \x00\x1a\x00\xe8\x1c\x00\x00",
    )
    .unwrap();
    let cases = [
        ("not.glb", "not a glTF"),
        ("pointer.glb", "a Git LFS pointer, not the file itself"),
        ("page.glb", "a web page (HTML), not the file itself"),
        ("fbx.gltf", "an FBX file (inbetween reads glTF and BVH"),
        (
            "walk.bvh",
            "a BVH motion capture, not a glTF file (`inbetween blend`",
        ),
        ("short.glb", "GLB header says"),
        ("nobuf.gltf", "missing.bin"),
        (
            "lfsbuf.gltf",
            "uri \"lfsbuf.bin\" is a Git LFS pointer, not the file itself",
        ),
        ("nomorph.gltf", "no mesh with morph targets"),
        ("count.glb", "deltas but the base has"),
        ("lines.glb", "not made of triangles"),
        ("draco.glb", "(Draco) does not decode"),
        ("meshopt.glb", "(meshopt): its compressed bytes lie outside"),
        ("nan.glb", "NaN or infinite"),
        ("does-not-exist.glb", "cannot read"),
    ];
    for (file, what) in cases {
        for out_name in ["fresh.glb", "existing.glb"] {
            let out = p(out_name);
            if out_name == "existing.glb" {
                std::fs::write(&out, b"previous").unwrap();
            }
            let r = inbetween(&["tween", s(&p(file)), "-o", s(&out)]);
            let err = String::from_utf8_lossy(&r.stderr);
            assert_eq!(r.status.code(), Some(2), "{file}: {err}");
            assert_eq!(err.trim_end().lines().count(), 1, "{file}: one line: {err}");
            assert!(
                err.contains(file),
                "{file}: the message names the file: {err}"
            );
            assert!(err.contains(what), "{file}: expected {what:?} in {err}");
            if out_name == "fresh.glb" {
                assert!(!out.exists(), "{file}: no output file");
            } else {
                assert_eq!(
                    std::fs::read(&out).unwrap(),
                    b"previous",
                    "{file}: existing output untouched"
                );
            }
        }
    }
    // No temporary file left behind.
    let leftovers: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty());
}

/// Timing values a run cannot use are refused by `tween` and `preview` alike, in one line,
/// before anything is read: a rate or frame rate of zero, below it or not a number, an
/// extension before or after the keys below zero or not a number (a negative value reaches
/// these checks rather than being taken for an option; `preview --fps 0` drew one frame, and
/// `--extend-after nan` was taken as 0).
#[test]
fn timing_values_a_run_cannot_use_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let input = sample("bar_twist.glb");
    for (option, value, said) in [
        (
            "--rate",
            "0",
            "--fps and --rate must be positive numbers (got 0)",
        ),
        (
            "--rate",
            "-5",
            "--fps and --rate must be positive numbers (got -5)",
        ),
        (
            "--fps",
            "nan",
            "--fps and --rate must be positive numbers (got NaN)",
        ),
        (
            "--extend-before",
            "-1",
            "--extend-before takes seconds, zero or more (got -1)",
        ),
        (
            "--extend-after",
            "nan",
            "--extend-after takes seconds, zero or more (got NaN)",
        ),
        (
            "--extend-after",
            "inf",
            "--extend-after takes seconds, zero or more (got inf)",
        ),
    ] {
        for (command, out) in [("tween", "t.glb"), ("preview", "p.png")] {
            let out = dir.path().join(out);
            let r = inbetween(&[command, s(&input), "-o", s(&out), option, value]);
            let err = String::from_utf8_lossy(&r.stderr);
            assert_eq!(
                r.status.code(),
                Some(2),
                "{command} {option} {value}: {err}"
            );
            assert_eq!(err.trim_end().lines().count(), 1, "{err}");
            assert!(err.contains(said), "{command} {option} {value}: {err}");
            assert!(!out.exists());
        }
    }
}

/// Two outputs of one run naming one file (`-o out.glb --report out.glb`, `--animate` on the
/// sheet) are refused in one line naming it, nothing written (they overwrote each other's
/// temporary and failed with "cannot write: No such file or directory").
#[test]
fn two_outputs_on_one_file_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let input = sample("bar_twist.glb");
    let out = dir.path().join("out.glb");
    let sheet = dir.path().join("out.png");
    let same = dir.path().join(".").join("out.glb");
    for args in [
        vec!["tween", s(&input), "-o", s(&out), "--report", s(&out)],
        vec!["tween", s(&input), "-o", s(&out), "--report", s(&same)],
        vec![
            "preview",
            s(&input),
            "-o",
            s(&sheet),
            "--animate",
            s(&sheet),
        ],
    ] {
        let r = inbetween(&args);
        let err = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{args:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(
            err.contains("two of the run's outputs name this file"),
            "{err}"
        );
        assert!(walk(dir.path()).is_empty(), "{:?}", walk(dir.path()));
    }
}

#[test]
fn usd_outputs_and_unknown_extensions_are_refused_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["a.obj", "b", "missing-dir/c.glb"] {
        let out = dir.path().join(name);
        let r = inbetween(&["tween", s(&sample("bar_twist.glb")), "-o", s(&out)]);
        assert_eq!(r.status.code(), Some(2), "{name}");
        assert_eq!(
            String::from_utf8_lossy(&r.stderr)
                .trim_end()
                .lines()
                .count(),
            1
        );
        assert!(!out.exists());
    }
}

#[test]
fn fixtures_tween_to_valid_files() {
    let Some(fx) = fixtures() else { return };
    let dir = tempfile::tempdir().unwrap();
    let mut files = Vec::new();
    for sub in ["morph-keyframes", "morph-khronos"] {
        for entry in walk(&fx.join(sub)) {
            let ext = entry.extension().and_then(|e| e.to_str()).unwrap_or("");
            if ext == "glb" || ext == "gltf" {
                files.push(entry);
            }
        }
    }
    files.sort();
    assert!(files.len() >= 9, "found {files:?}");
    for (i, f) in files.iter().enumerate() {
        for ext in ["glb", "gltf"] {
            let out = dir.path().join(format!("{i}.{ext}"));
            run_ok(&["tween", s(f), "-o", s(&out), "-q"]);
            if let Some((e, w, line)) = validate(&out) {
                assert!(e == 0 && w == 0, "{}: {line}", f.display());
            }
        }
    }
}

#[test]
fn external_images_are_embedded_or_copied() {
    let Some(fx) = fixtures() else { return };
    let input = fx.join("morph-khronos/MorphStressTest/glTF/MorphStressTest.gltf");
    let dir = tempfile::tempdir().unwrap();
    let glb = dir.path().join("m.glb");
    tween_quietly(&input, &glb, &[]);
    let doc = Document::open(&glb).unwrap();
    for img in doc.json["images"].as_array().unwrap() {
        assert!(
            img.get("uri").is_none() && img.get("bufferView").is_some(),
            "{img}"
        );
    }
    let gltf_out = dir.path().join("sub/m.gltf");
    std::fs::create_dir_all(gltf_out.parent().unwrap()).unwrap();
    tween_quietly(&input, &gltf_out, &[]);
    for img in Document::open(&gltf_out).unwrap().json["images"]
        .as_array()
        .unwrap()
    {
        assert!(dir
            .path()
            .join("sub")
            .join(img["uri"].as_str().unwrap())
            .exists());
    }
    assert_valid(&gltf_out);
    // Three clips animate the mesh: each keeps its channel, over its own frames.
    let (gdoc, _, _) = gltf::import(&gltf_out).unwrap();
    assert_eq!(gdoc.animations().count(), 3);
}

#[test]
fn samples_are_current() {
    let dir = tempfile::tempdir().unwrap();
    for (name, file) in inbetween::synth::samples() {
        let fresh = dir.path().join(name);
        file.write(&fresh).unwrap();
        assert_eq!(
            std::fs::read(&fresh).unwrap(),
            std::fs::read(sample(name)).unwrap(),
            "samples/{name} is stale: run cargo run --release --example make-samples"
        );
        assert_valid(&sample(name));
    }
}

/// A tube bent 150 degrees, written as two primitives that share the middle ring.
fn split_tube(dir: &Path, normals: bool) -> PathBuf {
    use inbetween::synth::{bend, smooth_normals, tube, KeyedMesh, KeyframeFile};
    let mut s = tube(31, 16, 6.0, 0.4, 0.4);
    let key = bend(&s.positions, 3.0, 150f64.to_radians(), 0.5);
    let mut m = KeyedMesh::new("split", s.clone(), vec![key.clone()]);
    if normals {
        s.normals = Some(smooth_normals(&s.positions, &s.triangles));
        m = KeyedMesh {
            target_normals: vec![smooth_normals(&key, &s.triangles)],
            ..KeyedMesh::new("split", s, vec![key])
        };
    }
    m.split = Some(2 * 16 * 15); // rings 0..15 in the first primitive
    let path = dir.join("split.glb");
    KeyframeFile {
        meshes: vec![m],
        key_times: None,
        key_weights: None,
    }
    .write(&path)
    .unwrap();
    path
}

#[test]
fn primitives_sharing_a_border_do_not_crack() {
    let dir = tempfile::tempdir().unwrap();
    let input = split_tube(dir.path(), true);
    let out = dir.path().join("out.glb");
    tween_quietly(&input, &out, &["--tweens", "5"]);
    assert_valid(&out);
    let (b0, t0) = read_targets(&out, 0, 0);
    let (b1, t1) = read_targets(&out, 0, 1);
    let pairs: Vec<(usize, usize)> = b0
        .iter()
        .enumerate()
        .flat_map(|(i, p)| {
            b1.iter()
                .enumerate()
                .filter(move |(_, q)| *q == p)
                .map(move |(j, _)| (i, j))
        })
        .collect();
    // Ring 15 (the split) and ring 0 (its cap is in the second primitive).
    assert_eq!(pairs.len(), 32, "the shared rings");
    for (f, (a, b)) in t0.iter().zip(&t1).enumerate() {
        for &(i, j) in &pairs {
            let pa = [b0[i][0] + a[i][0], b0[i][1] + a[i][1], b0[i][2] + a[i][2]];
            let pb = [b1[j][0] + b[j][0], b1[j][1] + b[j][1], b1[j][2] + b[j][2]];
            assert_eq!(pa, pb, "frame {f}: border vertex {i}/{j} cracked");
        }
    }
}

#[test]
fn primitives_over_one_vertex_buffer_share_their_frames() {
    let dir = tempfile::tempdir().unwrap();
    let input = out_in(&dir, "groups.glb");
    flag_in_two_groups(&input);
    assert_valid(&input);
    let single = out_in(&dir, "single.glb");
    tween_quietly(&sample("flag_wave.glb"), &single, &[]);
    for args in [&[][..], &["--layout", "frames"], &["--compact"]] {
        let out = out_in(&dir, "out.glb");
        tween_quietly(&input, &out, args);
        assert_no_new_issues(&input, &out);
        let doc = Document::open(&out).unwrap();
        let p = &doc.json["meshes"][0]["primitives"];
        assert!(p[0]["targets"].as_array().unwrap().len() > 4, "{args:?}");
        assert_eq!(
            p[0]["targets"], p[1]["targets"],
            "{args:?}: one set of targets"
        );
        if args.is_empty() {
            // Not twice the frames: about the size of the mesh drawn by one primitive.
            let (two, one) = (file_len(&out), file_len(&single));
            assert!(two < one + one / 20, "{two} bytes against {one}");
            // Both primitives play the frames the single one does.
            let want = played(&single, 0, 0, 0);
            for prim in 0..2 {
                let got = played(&out, 0, prim, 0);
                assert_eq!(got.times, want.times);
                assert_eq!(got.positions, want.positions, "primitive {prim}");
            }
        }
    }
}

fn file_len(p: &Path) -> u64 {
    std::fs::metadata(p).unwrap().len()
}

#[test]
fn hard_edges_stay_hard_and_key_normals_are_kept() {
    use inbetween::synth::{bend, tube, KeyedMesh, KeyframeFile, Surface};
    // A tube whose caps have their own vertices and flat normals: the rim is a hard edge.
    let t = tube(21, 12, 4.0, 0.5, 0.5);
    let ring = |i: usize| -> Vec<u32> { (0..12).map(|j| (i * 12 + j) as u32).collect() };
    let mut positions = t.positions[..21 * 12].to_vec();
    let mut normals: Vec<DVec3> = positions
        .iter()
        .map(|p| DVec3::new(0.0, p.y, p.z).normalize())
        .collect();
    let mut triangles: Vec<[u32; 3]> = t.triangles[..2 * 12 * 20].to_vec();
    for (end, x, nx) in [(0usize, 0.0, -1.0), (20, 4.0, 1.0)] {
        let start = positions.len() as u32;
        for &v in &ring(end) {
            positions.push(positions[v as usize]);
            normals.push(DVec3::new(nx, 0.0, 0.0));
        }
        let c = positions.len() as u32;
        positions.push(DVec3::new(x, 0.0, 0.0));
        normals.push(DVec3::new(nx, 0.0, 0.0));
        for j in 0..12u32 {
            let (a, b) = (start + j, start + (j + 1) % 12);
            triangles.push(if nx < 0.0 { [c, b, a] } else { [c, a, b] });
        }
    }
    let surface = Surface {
        positions: positions.clone(),
        normals: Some(normals.clone()),
        uvs: None,
        triangles,
    };
    let key = bend(&positions, 2.0, 120f64.to_radians(), 0.5);
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("hard.glb");
    KeyframeFile {
        meshes: vec![KeyedMesh::new("hard", surface, vec![key])],
        key_times: None,
        key_weights: None,
    }
    .write(&input)
    .unwrap();
    let out = dir.path().join("out.glb");
    tween_quietly(&input, &out, &["--tweens", "3"]);
    assert_valid(&out);
    let (doc, buffers, _) = gltf::import(&out).unwrap();
    let prim = doc.meshes().next().unwrap().primitives().next().unwrap();
    let r = prim.reader(|b| Some(&buffers[b.index()]));
    let base: Vec<[f32; 3]> = r.read_normals().unwrap().collect();
    let frames = played(&out, 0, 0, 0).normals.unwrap();
    let pos: Vec<[f32; 3]> = r.read_positions().unwrap().collect();
    let rim_pairs: Vec<(usize, usize)> = (0..pos.len())
        .flat_map(|i| (i + 1..pos.len()).map(move |j| (i, j)))
        .filter(|&(i, j)| pos[i] == pos[j])
        .collect();
    assert_eq!(rim_pairs.len(), 24);
    let v = |a: [f32; 3]| DVec3::new(a[0] as f64, a[1] as f64, a[2] as f64);
    for (f, n) in frames.iter().enumerate() {
        for &(i, j) in &rim_pairs {
            let (ni, nj) = (v(n[i]), v(n[j]));
            assert!((ni.length() - 1.0).abs() < 1e-5 && (nj.length() - 1.0).abs() < 1e-5);
            assert!(
                ni.dot(nj).abs() < 0.2,
                "frame {f}: rim normals {ni} {nj} were smoothed together"
            );
        }
    }
    // Frame 0 is key 0: the authored normals exactly.
    for (k, (n, b)) in frames[0].iter().zip(&base).enumerate() {
        assert!(
            (v(*n) - v(*b)).length() < 1e-6,
            "vertex {k}: {n:?} vs {b:?}"
        );
    }
}

/// Targets that move positions only, beside base normals: the glTF rig layout plays a key by its
/// authored weights, so each target is given the normals of its shape and every frame, keys
/// and the frames between them, shades as its surface (without them, a key of the 90-degree
/// bend below shows the straight tube's normals, between frames that follow the bend).
#[test]
fn position_only_targets_shade_through_their_keys() {
    use inbetween::synth::{bend, smooth_normals, tube, KeyedMesh, KeyframeFile};
    let mut s = tube(31, 16, 6.0, 0.4, 0.4);
    s.normals = Some(smooth_normals(&s.positions, &s.triangles));
    let up = bend(&s.positions, 3.0, 90f64.to_radians(), 0.5);
    let down = bend(&s.positions, 3.0, -90f64.to_radians(), 0.5);
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("bends.glb");
    KeyframeFile {
        meshes: vec![KeyedMesh::new("bends", s, vec![up, down])],
        key_times: Some(vec![0.0, 1.0, 2.0, 3.0]),
        key_weights: Some(vec![
            vec![0.0, 0.0],
            vec![1.0, 0.0],
            vec![0.0, 1.0],
            vec![0.0, 0.0],
        ]),
    }
    .write(&input)
    .unwrap();
    let (_, authored) = read_targets(&input, 0, 0);
    // (--compact keeps the normals within its tolerance of these: compact_table's face rig.)
    let out = dir.path().join("out.glb");
    let report = dir.path().join("report.json");
    tween_quietly(
        &input,
        &out,
        &["--tweens", "3", "--report", report.to_str().unwrap()],
    );
    assert_no_new_issues(&input, &out);
    assert_eq!(read_json(&report)["meshes"][0]["targets_given_normals"], 2);
    // The frames layout replaces the authored targets: none given.
    let frames = dir.path().join("frames.glb");
    tween_quietly(
        &input,
        &frames,
        &[
            "--tweens",
            "3",
            "--layout",
            "frames",
            "--report",
            report.to_str().unwrap(),
        ],
    );
    assert_eq!(read_json(&report)["meshes"][0]["targets_given_normals"], 0);
    // The authored positions as they were, each target with normals now.
    let (_, targets) = read_targets(&out, 0, 0);
    assert_eq!(targets[..2], authored[..]);
    let doc = Document::open(&out).unwrap();
    for t in doc.json["meshes"][0]["primitives"][0]["targets"]
        .as_array()
        .unwrap()
    {
        assert!(t["NORMAL"].is_u64(), "{t}");
    }
    let p = played(&out, 0, 0, 0);
    assert_eq!(p.times.len(), 13);
    {
        let (doc, buffers, _) = gltf::import(&out).unwrap();
        let prim = doc.meshes().next().unwrap().primitives().next().unwrap();
        let indices: Vec<u32> = (prim.reader(|b| Some(&buffers[b.index()])))
            .read_indices()
            .unwrap()
            .into_u32()
            .collect();
        let triangles: Vec<[u32; 3]> = indices.chunks(3).map(|t| [t[0], t[1], t[2]]).collect();
        for (f, (pos, nrm)) in p
            .positions
            .iter()
            .zip(p.normals.as_ref().unwrap())
            .enumerate()
        {
            let v = |a: &[f32; 3]| DVec3::new(a[0] as f64, a[1] as f64, a[2] as f64);
            let pos: Vec<DVec3> = pos.iter().map(v).collect();
            let surface = smooth_normals(&pos, &triangles);
            let worst = (nrm.iter().zip(&surface))
                .map(|(n, s)| v(n).angle_between(*s).to_degrees())
                .fold(0.0f64, f64::max);
            assert!(
                worst < 0.1,
                "frame {f} (t {}): a normal {worst:.2} degrees off its surface",
                p.times[f]
            );
        }
    }
}

/// A .gltf's external images count with its input (a .glb output embeds them): the 49.5 KB
/// texture of MorphPrimitivesTest made its tween read as 7122 B -> 100 KB, "14.4x", and warned.
#[test]
fn a_gltf_s_external_images_count_with_its_input() {
    let Some(fx) = fixtures() else { return };
    let input = fx.join("morph-khronos/MorphPrimitivesTest/glTF/MorphPrimitivesTest.gltf");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.glb");
    let told = run_ok(&[
        "tween",
        input.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    let text =
        String::from_utf8_lossy(&told.stdout).to_string() + &String::from_utf8_lossy(&told.stderr);
    // 5,610 + 1,512 + 49,535 bytes.
    assert!(text.contains(" 55 KB -> "), "{text}");
    assert!(!text.contains("x the size of the input"), "{text}");
    let doc = Document::open(&input).unwrap();
    assert_eq!(doc.input_bytes, 56_657);
}

/// `tween INPUT -o OUT` (each of `said` in what it says; validator-clean), and the output's JSON
/// and binary chunk; with no `said`, quietly.
fn tweened(input: &Path, out: &Path, said: &[&str]) -> (serde_json::Value, Vec<u8>) {
    let mut args = vec!["tween", s(input), "-o", s(out)];
    if said.is_empty() {
        args.push("-q");
    }
    said_by(&args, said);
    assert_valid(out);
    glb_parts(out)
}

/// `inbetween ARGS`, each of `said` in what it says on stderr; all it said there.
fn said_by(args: &[&str], said: &[&str]) -> String {
    let told = run_ok(args);
    let err = String::from_utf8_lossy(&told.stderr).into_owned();
    for line in said {
        assert!(err.contains(line), "{line} in {err}");
    }
    err
}

/// `blend INPUT --clips Walk Run -o OUT -q` (Fox, edited), and the output's JSON and binary
/// chunk.
fn walked_and_run(input: &Path, out: &Path) -> (serde_json::Value, Vec<u8>) {
    run_ok(&[
        "blend",
        s(input),
        "--clips",
        "Walk",
        "Run",
        "-o",
        s(out),
        "-q",
    ]);
    glb_parts(out)
}

/// A channel that repeats another's target and sampler (glTF allows one channel a target; the
/// validator refuses the repeat): left out of the output, which plays the same keys, said in a
/// line. Parrot's weights channel repeated tweens to the frames of the original; Fox's walk
/// with two of its channels repeated blends to the very bytes of the original's blend. So is
/// one shadowed by a later channel of the same target with other keys (below).
#[test]
fn a_channel_repeating_another_is_left_out() {
    let Some(fx) = fixtures() else { return };
    let dir = tempfile::tempdir().unwrap();
    let repeat = |file: &str, anim: usize, channels: &[usize]| -> PathBuf {
        let name = Path::new(file).file_name().unwrap().to_str().unwrap();
        let out = dir.path().join(format!("repeated_{name}"));
        edited_glb(&fx.join(file), &out, |j| {
            let list = j["animations"][anim]["channels"].as_array_mut().unwrap();
            for &c in channels {
                let copy = list[c].clone();
                list.push(copy);
            }
        });
        out
    };
    let parrot = repeat("morph-keyframes/Parrot.glb", 0, &[0]);
    let (a, b) = (dir.path().join("a.glb"), dir.path().join("b.glb"));
    let said = "1 channel repeating another's target and sampler";
    let (ja, ba) = tweened(&parrot, &a, &[said]);
    let (jb, bb) = tweened(&fx.join("morph-keyframes/Parrot.glb"), &b, &[]);
    assert_eq!(ja["animations"], jb["animations"]);
    assert_eq!(ba, bb);
    let fox = repeat("skinned/Fox.glb", 1, &[3, 5]);
    assert_eq!(
        walked_and_run(&fox, &a),
        walked_and_run(&fx.join("skinned/Fox.glb"), &b)
    );
    // A channel whose target a later channel animates with other keys (the validator's
    // ANIMATION_DUPLICATE_TARGETS, in and out before): left out, the later one playing, its
    // sampler with it where no other channel plays it. Parrot with a STEP copy of its clip
    // first tweens to the original's frames; Fox's walk with a channel on a joint another
    // channel turns, with a third's keys, first, blends to the original's bytes.
    let shadowed = |file: &str, anim: usize, edit: &dyn Fn(&mut serde_json::Value)| {
        let name = Path::new(file).file_name().unwrap().to_str().unwrap();
        let out = dir.path().join(format!("shadowed_{name}"));
        edited_glb(&fx.join(file), &out, |j| edit(&mut j["animations"][anim]));
        out
    };
    let parrot = shadowed("morph-keyframes/Parrot.glb", 0, &|a| {
        let mut step = a["samplers"][0].clone();
        step["interpolation"] = "STEP".into();
        a["samplers"].as_array_mut().unwrap().push(step);
        let mut first = a["channels"][0].clone();
        first["sampler"] = 1.into();
        a["channels"].as_array_mut().unwrap().insert(0, first);
    });
    let said = "1 channel whose target a later channel animates with other keys";
    let (ja, _) = tweened(&parrot, &a, &[said]);
    // The same clip (the left-out sampler's accessors stay in the file, unused).
    let clip = |j: &serde_json::Value| {
        let mut c = j["animations"].clone();
        c[0]["samplers"][0]["input"] = 0.into();
        c[0]["samplers"][0]["output"] = 0.into();
        c
    };
    assert_eq!(clip(&ja), clip(&jb));
    let b_out = dir.path().join("parrot.glb");
    tweened(&fx.join("morph-keyframes/Parrot.glb"), &b_out, &[]);
    assert_eq!(read_targets(&a, 0, 0), read_targets(&b_out, 0, 0));
    assert_eq!(weight_keys(&a), weight_keys(&b_out));
    let fox = shadowed("skinned/Fox.glb", 1, &|a| {
        let list = a["channels"].as_array().unwrap();
        let c = (list.iter().skip(4))
            .find(|c| c["target"]["path"] == list[3]["target"]["path"])
            .unwrap();
        let first = serde_json::json!({"sampler": c["sampler"], "target": list[3]["target"]});
        a["channels"].as_array_mut().unwrap().insert(0, first);
    });
    assert_eq!(
        walked_and_run(&fox, &a),
        walked_and_run(&fx.join("skinned/Fox.glb"), &b)
    );
}

/// The key times and weights of the first channel of the first animation (the gltf crate).
fn weight_keys(path: &Path) -> (Vec<f32>, Vec<f32>) {
    let (doc, buffers, _) = gltf::import(path).unwrap();
    let channel = doc.animations().next().unwrap().channels().next().unwrap();
    let reader = channel.reader(|b| Some(&buffers[b.index()]));
    let times = reader.read_inputs().unwrap().collect();
    match reader.read_outputs().unwrap() {
        gltf::animation::util::ReadOutputs::MorphTargetWeights(w) => {
            (times, w.into_f32().collect())
        }
        _ => panic!("{}: no weights", path.display()),
    }
}

/// Empty lists (glTF asks at least one entry of every list written: the validator's
/// EMPTY_ENTITY) as exporters leave them: `extensionsUsed`, `extensionsRequired`, `cameras`,
/// `images`, a node's `children`, a scene's `nodes`, and a mesh with no `primitives` placed by
/// a node with a skin. Left out of the output, said in a line: Parrot so written tweens to the
/// original's animations and binary; Fox so written blends to the original's binary; both
/// validator-clean (9 and 7 errors in: Parrot's holder names a skin the file lacks, which goes
/// with the mesh).
#[test]
fn empty_lists_and_meshes_with_no_primitive_are_left_out() {
    use serde_json::json;
    let Some(fx) = fixtures() else { return };
    let dir = tempfile::tempdir().unwrap();
    let emptied = |file: &str| -> PathBuf {
        let name = Path::new(file).file_name().unwrap().to_str().unwrap();
        let out = dir.path().join(format!("emptied_{name}"));
        edited_glb(&fx.join(file), &out, |j| {
            for key in ["extensionsUsed", "extensionsRequired", "cameras", "images"] {
                j.as_object_mut()
                    .unwrap()
                    .entry(key)
                    .or_insert_with(|| json!([]));
            }
            let nodes = j["nodes"].as_array_mut().unwrap();
            let leaf = nodes.iter().position(|n| n.get("children").is_none());
            nodes[leaf.unwrap()]["children"] = json!([]);
            // The hollow mesh first, so that every other mesh is renumbered on write.
            for n in nodes.iter_mut().filter(|n| n.get("mesh").is_some()) {
                n["mesh"] = json!(n["mesh"].as_u64().unwrap() + 1);
            }
            nodes.push(json!({ "name": "holder", "mesh": 0, "skin": 0, "children": [] }));
            let holder = nodes.len() - 1;
            j["meshes"]
                .as_array_mut()
                .unwrap()
                .insert(0, json!({ "primitives": [] }));
            j["scenes"][0]["nodes"]
                .as_array_mut()
                .unwrap()
                .push(json!(holder));
            j["scenes"]
                .as_array_mut()
                .unwrap()
                .push(json!({ "nodes": [] }));
        });
        out
    };
    let (a, b) = (dir.path().join("a.glb"), dir.path().join("b.glb"));
    let parrot = emptied("morph-keyframes/Parrot.glb");
    let said = [
        "empty lists /scenes/1/nodes, /nodes/0/children, /nodes/1/children, /extensionsUsed, /extensionsRequired, /cameras, /images",
        "mesh 0 has no primitive",
    ];
    let (ja, ba) = tweened(&parrot, &a, &said);
    let (jb, bb) = tweened(&fx.join("morph-keyframes/Parrot.glb"), &b, &[]);
    assert_eq!(
        (&ja["animations"], &ja["meshes"]),
        (&jb["animations"], &jb["meshes"])
    );
    assert_eq!(ja["nodes"][0], jb["nodes"][0]);
    assert_eq!(ja["nodes"][1], json!({ "name": "holder" }));
    assert_eq!(ba, bb);
    let (ja, ba) = walked_and_run(&emptied("skinned/Fox.glb"), &a);
    let (jb, bb) = walked_and_run(&fx.join("skinned/Fox.glb"), &b);
    assert_valid(&a);
    assert_eq!(
        (&ja["animations"], &ja["meshes"]),
        (&jb["animations"], &jb["meshes"])
    );
    assert_eq!(ba, bb);
}

/// JSON that glTF's readers accept though no writer here spells it so: every integer written
/// as a decimal (`24.0`: JSON does not tell them apart, the validator takes it; it made
/// Parrot "have no POSITION", and Fox no clip keys), and a `.gltf` behind a UTF-8
/// byte-order mark (which RFC 8259 lets a parser ignore; it did not parse), or a GLB whose JSON
/// chunk is padded with NUL bytes (which JSON parsers refuse). Parrot tweens and Fox blends to
/// the originals' binaries and JSON values; the mark and the padding are said in a line.
#[test]
fn integers_written_as_decimals_and_a_byte_order_mark_are_read() {
    fn decimals(v: &mut serde_json::Value) {
        use serde_json::Value;
        match v {
            Value::Number(n) if n.is_u64() => *v = Value::from(n.as_f64().unwrap()),
            Value::Array(a) => a.iter_mut().for_each(decimals),
            Value::Object(o) => o.values_mut().for_each(decimals),
            _ => {}
        }
    }
    let Some(fx) = fixtures() else { return };
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.glb"), dir.path().join("b.glb"));
    for (file, args) in [
        ("morph-keyframes/Parrot.glb", &["tween"][..]),
        ("skinned/Fox.glb", &["blend", "--clips", "Walk", "Run"][..]),
    ] {
        let input = dir.path().join("decimals.glb");
        edited_glb(&fx.join(file), &input, decimals);
        let text = std::fs::read(&input).unwrap();
        assert!(String::from_utf8_lossy(&text).contains("\"componentType\":5126.0"));
        let run = |input: &Path, out: &Path| {
            run_ok(&[args, &[s(input), "-o", s(out), "-q"]].concat());
            glb_parts(out)
        };
        let (ja, ba) = run(&input, &a);
        let (jb, bb) = run(&fx.join(file), &b);
        assert_valid(&a);
        assert_eq!(ba, bb, "{file}");
        // The same values, however spelled (the decimals stay where glTF asks a float).
        let mut jb = jb;
        decimals(&mut jb);
        let mut ja = ja;
        decimals(&mut ja);
        assert_eq!(ja, jb, "{file}");
    }
    let cube = fx.join("morph-khronos/AnimatedMorphCube/glTF");
    let marked = dir.path().join("AnimatedMorphCube.gltf");
    let text = std::fs::read(cube.join("AnimatedMorphCube.gltf")).unwrap();
    std::fs::write(&marked, [&b"\xEF\xBB\xBF"[..], &text].concat()).unwrap();
    std::fs::copy(
        cube.join("AnimatedMorphCube.bin"),
        dir.path().join("AnimatedMorphCube.bin"),
    )
    .unwrap();
    let told = run_ok(&["tween", s(&marked), "-o", s(&a)]);
    let err = String::from_utf8_lossy(&told.stderr);
    assert!(err.contains("a byte-order mark ahead of the JSON"), "{err}");
    assert_valid(&a);
    run_ok(&[
        "tween",
        s(&cube.join("AnimatedMorphCube.gltf")),
        "-o",
        s(&b),
        "-q",
    ]);
    assert_eq!(glb_parts(&a), glb_parts(&b));
    // A GLB's JSON chunk padded with NUL bytes (the Rust gltf crate's writer before its pull
    // request 174): read past, the output the original's to the byte.
    let parrot = fx.join("morph-keyframes/Parrot.glb");
    let (json, bin) = glb_parts(&parrot);
    let mut bytes = glb_bytes(&json, &bin);
    let js = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let spaces = bytes[20..20 + js]
        .iter()
        .rev()
        .take_while(|&&c| c == b' ')
        .count();
    let nul_padded = dir.path().join("nul.glb");
    if spaces == 0 {
        // Make room: four NULs, the chunk and the file four bytes longer.
        bytes.splice(20 + js..20 + js, [0u8; 4]);
        bytes[12..16].copy_from_slice(&((js + 4) as u32).to_le_bytes());
        let total = bytes.len() as u32;
        bytes[8..12].copy_from_slice(&total.to_le_bytes());
    } else {
        bytes[20 + js - spaces..20 + js].fill(0);
    }
    std::fs::write(&nul_padded, &bytes).unwrap();
    let told = run_ok(&["tween", s(&nul_padded), "-o", s(&a)]);
    let err = String::from_utf8_lossy(&told.stderr);
    assert!(
        err.contains("the JSON chunk padded with NUL bytes"),
        "{err}"
    );
    run_ok(&["tween", s(&parrot), "-o", s(&b), "-q"]);
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
}

/// A GLB whose header's length is not the file's, as real writers left them: 4 bytes after the
/// chunks (a GLB cut out of a 3D Tiles b3dm: three.js pull request 21122), a header counting
/// the JSON chunk only (qmuntal/gltf issue 38), a binary chunk whose padding the file lacks
/// (assimp's exporter miscounted that padding: its issue 3176). Each is read by its chunks, said in a line (and by `inspect`), and
/// tweens (Parrot) or blends (Fox) to the original's bytes; a file cut short is still refused,
/// saying so.
#[test]
fn a_glb_whose_header_length_is_wrong_is_read_by_its_chunks() {
    let Some(fx) = fixtures() else { return };
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.glb"), dir.path().join("b.glb"));
    let set_total = |bytes: &mut Vec<u8>, total: usize| {
        bytes[8..12].copy_from_slice(&(total as u32).to_le_bytes());
    };
    for (file, args) in [
        ("morph-keyframes/Parrot.glb", &["tween"][..]),
        ("skinned/Fox.glb", &["blend", "--clips", "Walk", "Run"][..]),
    ] {
        let original = std::fs::read(fx.join(file)).unwrap();
        let js = u32::from_le_bytes(original[12..16].try_into().unwrap()) as usize;
        let mut b3dm = original.clone();
        b3dm.extend_from_slice(b"    ");
        let mut json_only = original.clone();
        set_total(&mut json_only, 20 + js);
        // One byte more in the buffer, its chunk (and the header) counting the padding to 4
        // that the file does not have.
        let (mut json, mut bin) = glb_parts(&fx.join(file));
        bin.truncate(json["buffers"][0]["byteLength"].as_u64().unwrap() as usize);
        bin.push(7);
        json["buffers"][0]["byteLength"] = bin.len().into();
        bin.extend([0; 3]);
        let mut unpadded = glb_bytes(&json, &bin);
        unpadded.truncate(unpadded.len() - 3);
        let mut cut = original.clone();
        cut.truncate(cut.len() - 100);
        let run = |input: &Path, out: &Path| {
            let told = run_ok(&[args, &[s(input), "-o", s(out)]].concat());
            String::from_utf8_lossy(&told.stderr).into_owned()
        };
        run(&fx.join(file), &b);
        for (name, bytes, line) in [
            ("b3dm.glb", &b3dm, "4 bytes after the GLB's chunks"),
            ("json_only.glb", &json_only, "read by its chunks"),
            ("unpadded.glb", &unpadded, "the file ends 3 bytes before"),
        ] {
            let input = dir.path().join(name);
            std::fs::write(&input, bytes).unwrap();
            let err = run(&input, &a);
            assert!(err.contains(line), "{file} {name}: {err}");
            assert_valid(&a);
            assert_eq!(glb_parts(&a), glb_parts(&b), "{file} {name}");
            // `inspect` says it too, in its text and its JSON.
            let text = run_ok(&["inspect", s(&input)]).stdout;
            let text = String::from_utf8_lossy(&text);
            assert!(
                text.contains("mended in a glTF output: ") && text.contains(line),
                "{text}"
            );
            let json = run_ok(&["inspect", s(&input), "--json"]).stdout;
            let json: serde_json::Value = serde_json::from_slice(&json).unwrap();
            let mended = json["mended"].as_array().unwrap();
            assert!(
                mended.iter().any(|m| m.as_str().unwrap().contains(line)),
                "{json}"
            );
            if let Some(py) = python() {
                let report = dir.path().join("inspect.json");
                std::fs::write(&report, json.to_string()).unwrap();
                check_schema(&py, "inspect.schema.json", &report, name);
            }
        }
        let input = dir.path().join("cut.glb");
        std::fs::write(&input, &cut).unwrap();
        let r = inbetween(&[args, &[s(&input), "-o", s(&a)]].concat());
        let err = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{file}: {err}");
        assert!(err.contains("cut short"), "{file}: {err}");
    }
}

/// A face whose morph targets a writer listed on some primitives only: UniGLTF (UniVRM's core)
/// wrote them on a mesh's first primitive (its issue 18), SharpGLTF's builder leaves out the
/// trailing targets a primitive's vertices do not move (its issue 281). RobotExpressive's head
/// (three primitives, three targets, only the mouth's moving) so written was refused ("primitive
/// 1 has 0 morph targets but primitive 0 has 3"); it is read as viewers play it, a missing
/// target moving nothing, said in a line, and tweens as the file its writer meant: every
/// primitive's targets and positions as the whole file's tween gives them, validator-clean
/// plain, `--compact` and `--meshopt`, and blends. So are default weights of another count
/// than the targets.
#[test]
fn morph_targets_on_some_primitives_only_are_read_as_targets_of_zeros() {
    let Some(fx) = fixtures() else { return };
    let dir = tempfile::tempdir().unwrap();
    let robot = fx.join("skinned/RobotExpressive.glb");
    let head = |j: &mut serde_json::Value| j["meshes"][2]["primitives"].take();
    let mouth_first = |j: &mut serde_json::Value| {
        let mut p = head(j);
        let p = p.as_array_mut().unwrap();
        p.rotate_right(1);
        j["meshes"][2]["primitives"] = serde_json::json!(p);
    };
    let whole = dir.path().join("whole.glb");
    edited_glb(&robot, &whole, mouth_first);
    let unigltf = dir.path().join("unigltf.glb");
    edited_glb(&robot, &unigltf, |j| {
        mouth_first(j);
        for p in j["meshes"][2]["primitives"].as_array_mut().unwrap()[1..].iter_mut() {
            p.as_object_mut().unwrap().remove("targets");
        }
    });
    let sharp = dir.path().join("sharp.glb");
    edited_glb(&robot, &sharp, |j| {
        mouth_first(j);
        let targets = j["meshes"][2]["primitives"][2]["targets"]
            .as_array_mut()
            .unwrap();
        targets.pop();
    });
    let tween = |input: &Path, out: &Path, extra: &[&str]| {
        let args = [
            &["tween", s(input), "--keys", "targets", "-o", s(out)][..],
            extra,
        ]
        .concat();
        String::from_utf8_lossy(&run_ok(&args).stderr).into_owned()
    };
    // The head's own input has the validator's warnings on its skinned nodes: none added, and
    // no error.
    let clean = |out: &Path| {
        assert_no_new_issues(&robot, out);
        if let Some((errors, _, report)) = validate(out) {
            assert_eq!(errors, 0, "{report}");
        }
    };
    let reference = dir.path().join("reference.glb");
    tween(&whole, &reference, &["-q"]);
    let want = Document::open(&reference).unwrap();
    let values =
        |d: &Document, a: &serde_json::Value| d.read_f64(a.as_u64().unwrap() as usize).unwrap().0;
    for (input, fewer) in [
        (&unigltf, "but 0 on primitive 1, 0 on primitive 2"),
        (&sharp, "but 2 on primitive 2"),
    ] {
        let out = dir.path().join("out.glb");
        let err = tween(input, &out, &[]);
        assert!(
            err.contains(&format!(
                "\"Head\" lists 3 morph targets on primitive 0 {fewer}"
            )),
            "{err}"
        );
        clean(&out);
        let got = Document::open(&out).unwrap();
        let (pw, pg) = (
            &want.json["meshes"][2]["primitives"],
            &got.json["meshes"][2]["primitives"],
        );
        for pi in 0..3 {
            let (tw, tg) = (
                pw[pi]["targets"].as_array().unwrap(),
                pg[pi]["targets"].as_array().unwrap(),
            );
            assert_eq!(tw.len(), tg.len(), "primitive {pi}");
            for (a, b) in tw.iter().zip(tg) {
                assert_eq!(
                    values(&want, &a["POSITION"]),
                    values(&got, &b["POSITION"]),
                    "primitive {pi}"
                );
            }
            let pos = |p: &serde_json::Value| p["attributes"]["POSITION"].clone();
            assert_eq!(values(&want, &pos(&pw[pi])), values(&got, &pos(&pg[pi])));
        }
        for extra in ["--compact", "--meshopt"] {
            tween(input, &out, &[extra, "-q"]);
            clean(&out);
        }
        run_ok(&[
            "blend",
            s(input),
            "--clips",
            "Walking",
            "Running",
            "-o",
            s(&out),
            "-q",
        ]);
        clean(&out);
    }
    // Default weights of another count than the targets: the head's two for its three targets,
    // its node's four. Blended as glTF's readers play them: the missing weight 0, the one past
    // the targets left out.
    let weights = dir.path().join("weights.glb");
    edited_glb(&robot, &weights, |j| {
        j["meshes"][2]["weights"] = serde_json::json!([0.0, 0.5]);
        let node = (j["nodes"].as_array_mut().unwrap().iter_mut())
            .find(|n| n["mesh"] == 2)
            .unwrap();
        node["weights"] = serde_json::json!([0.0, 0.5, 0.0, 1.0]);
    });
    let out = dir.path().join("out.glb");
    said_by(
        &["blend", s(&weights), "--clips", "Walking", "Running", "-o", s(&out)],
        &[
            "mesh \"Head\" lists 2 default weights for 3 morph targets (glTF asks one each): written with the missing ones 0",
            "node \"Head\" lists 4 default weights for 3 morph targets (glTF asks one each): written with the ones past the targets left out",
        ],
    );
    clean(&out);
    let (json, _) = glb_parts(&out);
    assert_eq!(
        json["meshes"][2]["weights"],
        serde_json::json!([0.0, 0.5, 0.0])
    );
    let node = json["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .find(|n| n["mesh"] == 2)
        .unwrap();
    assert_eq!(node["weights"], serde_json::json!([0.0, 0.5, 0.0]));
}

/// Data URIs as writers spell them and browsers read them: base64 wrapped in lines (Python's
/// `base64.encodebytes`: 76 characters and a newline, which the validator calls an invalid
/// URI), without its padding, or the bytes themselves `%XX`-escaped (RFC 2397; the validator
/// takes it). Each was refused ("a data URI that is not base64"); AnimatedMorphCube's buffer so
/// written tweens to the original's bytes, and Fox with its buffer and its texture wrapped
/// blends validator-clean: to a `.gltf` the texture written as plain base64 (said), to a `.glb`
/// embedded in the binary chunk (a data URI there is the validator's DATA_URI_GLB warning),
/// the same bytes either way.
#[test]
fn data_uris_are_read_as_browsers_read_them() {
    use base64::Engine;
    let b64 = |b: &[u8]| base64::engine::general_purpose::STANDARD.encode(b);
    let wrapped = |b: &[u8]| {
        let text = b64(b);
        let lines: Vec<&str> = (0..text.len())
            .step_by(76)
            .map(|i| &text[i..(i + 76).min(text.len())])
            .collect();
        lines.join("\n") + "\n"
    };
    let Some(fx) = fixtures() else { return };
    let dir = tempfile::tempdir().unwrap();
    let cube = fx.join("morph-khronos/AnimatedMorphCube/glTF");
    let bin = std::fs::read(cube.join("AnimatedMorphCube.bin")).unwrap();
    let json = read_json(cube.join("AnimatedMorphCube.gltf"));
    let (a, b) = (dir.path().join("a.glb"), dir.path().join("b.glb"));
    tweened(&cube.join("AnimatedMorphCube.gltf"), &b, &[]);
    // A length base64 pads (not a multiple of 3).
    let mut bin = bin;
    if bin.len() % 3 == 0 {
        bin.push(0);
    }
    let percent: String = bin.iter().map(|v| format!("%{v:02X}")).collect();
    for data in [
        format!("data:application/octet-stream;base64,{}", wrapped(&bin)),
        format!(
            "data:application/octet-stream;base64,{}",
            b64(&bin).trim_end_matches('=')
        ),
        format!("data:application/octet-stream,{percent}"),
    ] {
        let mut json = json.clone();
        json["buffers"][0] = serde_json::json!({ "uri": data, "byteLength": bin.len() });
        let input = dir.path().join("cube.gltf");
        std::fs::write(&input, serde_json::to_vec(&json).unwrap()).unwrap();
        run_ok(&["tween", s(&input), "-o", s(&a), "-q"]);
        assert_eq!(
            std::fs::read(&a).unwrap(),
            std::fs::read(&b).unwrap(),
            "{}",
            &data[..60]
        );
    }
    // Fox as a .gltf, its buffer and its texture as wrapped base64.
    let fox = fx.join("skinned/Fox.glb");
    let (mut json, bin) = glb_parts(&fox);
    let view = json["images"][0]["bufferView"].as_u64().unwrap() as usize;
    let start = json["bufferViews"][view]["byteOffset"]
        .as_u64()
        .unwrap_or(0) as usize;
    let len = json["bufferViews"][view]["byteLength"].as_u64().unwrap() as usize;
    let png = bin[start..start + len].to_vec();
    let image = json["images"][0].as_object_mut().unwrap();
    image.remove("bufferView");
    image.remove("mimeType");
    image.insert(
        "uri".into(),
        format!("data:image/png;base64,{}", wrapped(&png)).into(),
    );
    json["buffers"][0]["uri"] =
        format!("data:application/octet-stream;base64,{}", wrapped(&bin)).into();
    let input = dir.path().join("fox.gltf");
    std::fs::write(&input, serde_json::to_vec(&json).unwrap()).unwrap();
    // A .gltf keeps the texture a data URI, written as plain base64 (said); a .glb embeds it
    // in its binary chunk (the validator warns of a data URI there).
    let gltf_out = dir.path().join("fox_out.gltf");
    said_by(
        &[
            "blend",
            s(&input),
            "--clips",
            "Walk",
            "Run",
            "-o",
            s(&gltf_out),
        ],
        &["embedded as data URIs whose base64 browsers read but glTF's validator does not"],
    );
    assert_valid(&gltf_out);
    assert_eq!(
        read_json(&gltf_out)["images"][0]["uri"],
        format!("data:image/png;base64,{}", b64(&png))
    );
    walked_and_run(&input, &a);
    assert_valid(&a);
    let doc = Document::open(&a).unwrap();
    assert_eq!(doc.image(0).unwrap(), (png, Some("image/png")));
    assert_eq!(doc.json["images"][0]["mimeType"], "image/png");
}

/// A skin whose inverse bind matrices a writer left short (the validator's
/// INVALID_IBM_ACCESSOR_COUNT; glTF-Blender-IO issue 2532: a Fox with 51 for 64 joints, which
/// Blender imports): Fox with the last 4 of its 24 left out (10 of 24 in a second variant) was
/// blended with the error carried, and refused by the USD output and the preview ("holds 20
/// MAT4s for 24 joints"). Each missing joint's matrix is rebuilt from its parent joint's and its
/// own rest transform, said; written, they are the original's to within 1e-6 relative, and the
/// USD output and the preview are made.
#[test]
fn inverse_bind_matrices_left_short_are_rebuilt_from_the_rest_pose() {
    let Some(fx) = fixtures() else { return };
    let fox = fx.join("skinned/Fox.glb");
    let doc = Document::open(&fox).unwrap();
    let acc = doc.json["skins"][0]["inverseBindMatrices"]
        .as_u64()
        .unwrap() as usize;
    let (want, _) = doc.read_f64(acc).unwrap();
    let dir = tempfile::tempdir().unwrap();
    for left_out in [4, 10] {
        let short = dir.path().join("short.glb");
        edited_glb(&fox, &short, |j| {
            j["accessors"][acc]["count"] = (24 - left_out).into()
        });
        let out = dir.path().join("out.glb");
        let line = format!("skin 0's inverseBindMatrices hold {} matrices for 24 joints (glTF asks one each): the other {left_out} written", 24 - left_out);
        said_by(
            &["blend", s(&short), "--clips", "Walk", "Run", "-o", s(&out)],
            &[&line],
        );
        assert_valid(&out);
        let written = Document::open(&out).unwrap();
        let acc = written.json["skins"][0]["inverseBindMatrices"]
            .as_u64()
            .unwrap() as usize;
        let (got, _) = written.read_f64(acc).unwrap();
        assert_eq!(got.len(), want.len());
        for (k, (a, b)) in got.chunks(16).zip(want.chunks(16)).enumerate() {
            let scale = b.iter().fold(1.0f64, |m, x| m.max(x.abs()));
            let off = a
                .iter()
                .zip(b)
                .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
            assert!(off <= 1e-6 * scale, "joint {k}: {off} of {scale}");
        }
        let usd = dir.path().join("out.usda");
        run_ok(&[
            "blend",
            s(&short),
            "--clips",
            "Walk",
            "Run",
            "-o",
            s(&usd),
            "-q",
        ]);
        let png = dir.path().join("walk.png");
        run_ok(&[
            "preview",
            s(&short),
            "--animation",
            "Walk",
            "-o",
            s(&png),
            "-q",
        ]);
    }
}

/// Clips that share a name (glTF does not ask names to be unique: Mixamo names every clip
/// "mixamo.com", files merged from several repeat theirs; google/model-viewer issue 3224): a
/// name several carry picked the first silently (`blend --clips mixamo.com mixamo.com` blended
/// Survey with itself and said it had no stride cycle). Now refused, one line naming the
/// indices, by which each is picked: Fox's clips all named so blend by index to the bytes of the
/// named original's blend; the preview and tween (Parrot's clip twice) alike.
#[test]
fn clips_sharing_a_name_are_picked_by_index() {
    let Some(fx) = fixtures() else { return };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.glb");
    let fox = dir.path().join("mixamo.glb");
    edited_glb(&fx.join("skinned/Fox.glb"), &fox, |j| {
        for a in j["animations"].as_array_mut().unwrap() {
            a["name"] = "mixamo.com".into();
        }
    });
    let named = "3 animations are named \"mixamo.com\" (animations 0, 1, 2): name one by its index";
    let blend = [
        "blend",
        s(&fox),
        "--clips",
        "mixamo.com",
        "mixamo.com",
        "-o",
        s(&out),
    ];
    assert_refused(&blend, "mixamo.glb", named, &out);
    let png = dir.path().join("walk.png");
    let preview = [
        "preview",
        s(&fox),
        "--animation",
        "mixamo.com",
        "-o",
        s(&png),
    ];
    assert_refused(&preview, "mixamo.glb", named, &png);
    run_ok(&["preview", s(&fox), "--animation", "1", "-o", s(&png), "-q"]);
    run_ok(&["blend", s(&fox), "--clips", "1", "2", "-o", s(&out), "-q"]);
    let original = dir.path().join("original.glb");
    walked_and_run(&fx.join("skinned/Fox.glb"), &original);
    assert_eq!(glb_parts(&out).1, glb_parts(&original).1);
    let parrot = dir.path().join("twice.glb");
    edited_glb(&fx.join("morph-keyframes/Parrot.glb"), &parrot, |j| {
        let mut clip = j["animations"][0].clone();
        clip["name"] = "fly".into();
        j["animations"][0]["name"] = "fly".into();
        j["animations"].as_array_mut().unwrap().push(clip);
    });
    let tween = ["tween", s(&parrot), "--animation", "fly", "-o", s(&out)];
    std::fs::remove_file(&out).unwrap();
    assert_refused(
        &tween,
        "twice.glb",
        "2 animations are named \"fly\" (animations 0, 1)",
        &out,
    );
    run_ok(&["tween", s(&parrot), "--animation", "1", "-o", s(&out), "-q"]);
}

/// A reader that stops reading (`inbetween inspect face.glb | head -1`): the output was
/// printed with `println!`, which panicked on the closed pipe ("failed printing to stdout:
/// Broken pipe", a backtrace, exit 101). Now what cannot be written is dropped: exit 0, nothing
/// on stderr. The pipe is closed before inspect writes (its read end dropped at once); so is
/// tween's stderr before its summary.
#[test]
fn a_reader_that_stops_reading_is_no_error() {
    use std::process::{Command, Stdio};
    let input = sample("flag_wave.glb");
    for json in [false, true] {
        let mut args = vec!["inspect", s(&input)];
        if json {
            args.push("--json");
        }
        let mut child = Command::new(env!("CARGO_BIN_EXE_inbetween"))
            .args(&args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        drop(child.stdout.take());
        let out = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(0), "{args:?}: {err}");
        assert!(err.is_empty(), "{args:?}: {err}");
    }
    // The summary on stderr (`tween ... 2>&1 | head -1`), its reader gone: the file written.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.glb");
    let mut child = Command::new(env!("CARGO_BIN_EXE_inbetween"))
        .args(["tween", s(&input), "-o", s(&out)])
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stderr.take());
    assert_eq!(child.wait().unwrap().code(), Some(0));
    assert_valid(&out);
}

/// A sparse accessor whose indices are out of order or repeated (glTF asks them strictly
/// increasing; ACCESSOR_SPARSE_INDICES_NON_INCREASING): the reader here applies them in turn,
/// the validator stops at the first out of order and reads other values, so its bounds
/// disagreed and the error was carried. Parrot's first target as such a sparse accessor (indices
/// 5, 2, 9, 2) tweens validator-clean, the target written dense as it decodes (vertex 2 the
/// later value), said.
#[test]
fn sparse_indices_out_of_order_are_written_dense() {
    let Some(fx) = fixtures() else { return };
    let parrot = fx.join("morph-keyframes/Parrot.glb");
    let doc = Document::open(&parrot).unwrap();
    let (mut json, mut bin) = (doc.json.clone(), doc.buffers[0].clone());
    let target = json["meshes"][0]["primitives"][0]["targets"][0]["POSITION"]
        .as_u64()
        .unwrap() as usize;
    let count = json["accessors"][target]["count"].clone();
    let mut view = |json: &mut serde_json::Value, bytes: Vec<u8>| {
        while bin.len() % 4 != 0 {
            bin.push(0);
        }
        let at = bin.len();
        bin.extend(&bytes);
        let views = json["bufferViews"].as_array_mut().unwrap();
        views.push(serde_json::json!({"buffer": 0, "byteOffset": at, "byteLength": bytes.len()}));
        views.len() - 1
    };
    let indices: Vec<u8> = [5u16, 2, 9, 2]
        .iter()
        .flat_map(|i| i.to_le_bytes())
        .collect();
    let values: Vec<u8> = [
        0.1f32, 0.0, 0.0, 0.0, 0.2, 0.0, 0.0, 0.0, 0.3, 0.0, 0.4, 0.0,
    ]
    .iter()
    .flat_map(|v| v.to_le_bytes())
    .collect();
    let (iv, vv) = (view(&mut json, indices), view(&mut json, values));
    let accessors = json["accessors"].as_array_mut().unwrap();
    accessors.push(
        serde_json::json!({"componentType": 5126, "count": count, "type": "VEC3",
        "min": [0, 0, 0], "max": [0.1, 0.4, 0.3],
        "sparse": {"count": 4, "indices": {"bufferView": iv, "componentType": 5123},
            "values": {"bufferView": vv}}}),
    );
    let sparse = accessors.len() - 1;
    json["meshes"][0]["primitives"][0]["targets"][0]["POSITION"] = sparse.into();
    json["buffers"][0]["byteLength"] = bin.len().into();
    let dir = tempfile::tempdir().unwrap();
    let (input, out) = (dir.path().join("sparse.glb"), dir.path().join("out.glb"));
    write_glb(&input, &json, &bin);
    if let Some((_, _, report)) = validate(&input) {
        assert!(
            report.contains("ACCESSOR_SPARSE_INDICES_NON_INCREASING"),
            "{report}"
        );
    }
    tweened(
        &input,
        &out,
        &[&format!(
            "1 sparse accessor ({sparse}) listed its indices out of order or twice"
        )],
    );
    // The output's accessors renumbered (those nothing uses left out): its first target's.
    let written = Document::open(&out).unwrap();
    let first = written.json["meshes"][0]["primitives"][0]["targets"][0]["POSITION"]
        .as_u64()
        .unwrap() as usize;
    let acc = &written.json["accessors"][first];
    assert!(
        acc.get("sparse").is_none() && acc["bufferView"].is_u64(),
        "{acc}"
    );
    let (got, _) = written.read_f64(first).unwrap();
    let mut want = vec![0.0; got.len()];
    for (v, xyz) in [
        (5, [0.1, 0.0, 0.0]),
        (9, [0.0, 0.0, 0.3]),
        (2, [0.0, 0.4, 0.0]),
    ] {
        for c in 0..3 {
            want[3 * v + c] = xyz[c] as f32 as f64;
        }
    }
    assert_eq!(got, want);
}

/// Declarations a writer got wrong: an image labelled JPEG whose bytes are PNG (in the file,
/// and as an external file of a `.gltf`; another named by a Windows path, `tex\\fox.png`, as
/// AWS iot-app-kit's pull request 417 met them), extensions used but not named in `extensionsUsed`
/// (one of them required), a scene listing a child beside its ancestor and a root twice. Fox
/// so written blends validator-clean (7 errors in) to the original's binary, each said in a
/// line; the extensions named, the image declared PNG, the scene listing its two roots.
#[test]
fn declarations_a_writer_got_wrong_are_written_as_the_file_is() {
    use serde_json::json;
    let Some(fx) = fixtures() else { return };
    let fox = fx.join("skinned/Fox.glb");
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("mislabelled.glb");
    edited_glb(&fox, &input, |j| {
        j["images"][0]["mimeType"] = json!("image/jpeg");
        j["materials"][0]["extensions"] = json!({ "KHR_materials_unlit": {} });
        j["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"] =
            json!({ "KHR_texture_transform": { "offset": [0.5, 0.0] } });
        j["extensionsRequired"] = json!(["KHR_materials_unlit"]);
        assert_eq!(j["nodes"][0]["children"], json!([2]));
        j["scenes"][0]["nodes"] = json!([0, 1, 2, 1]);
    });
    let (a, b) = (dir.path().join("a.glb"), dir.path().join("b.glb"));
    let blend = |input: &Path, out: &Path| {
        run_ok(&["blend", s(input), "--clips", "Walk", "Run", "-o", s(out)])
    };
    let told = blend(&input, &a);
    let err = String::from_utf8_lossy(&told.stderr);
    for line in [
        "image 0 (image/jpeg, its bytes image/png) declared another type",
        "extensions \"KHR_texture_transform\", \"KHR_materials_unlit\" are used but not named in extensionsUsed",
        "nodes \"_rootJoint\", \"fox\" listed by a scene again or beside an ancestor",
    ] {
        assert!(err.contains(line), "{line} in {err}");
    }
    assert_valid(&a);
    blend(&fox, &b);
    let (ja, ba) = glb_parts(&a);
    let (jb, bb) = glb_parts(&b);
    assert_eq!(ba, bb);
    assert_eq!(ja["animations"], jb["animations"]);
    assert_eq!(ja["images"][0]["mimeType"], "image/png");
    assert_eq!(
        ja["extensionsUsed"],
        json!(["KHR_texture_transform", "KHR_materials_unlit"])
    );
    assert_eq!(ja["scenes"][0]["nodes"], json!([0, 1]));
    // The same image as a file beside a `.gltf`, labelled JPEG: declared PNG in a `.gltf` (the
    // file copied beside it) and in a `.glb` (embedded); and in a folder named with a Windows
    // path's backslash (`tex\\fox.png`, which was not found): read there, its URI written
    // with a slash.
    let (doc_json, doc_bin) = glb_parts(&fox);
    let view =
        &doc_json["bufferViews"][doc_json["images"][0]["bufferView"].as_u64().unwrap() as usize];
    let start = view["byteOffset"].as_u64().unwrap_or(0) as usize;
    let png = &doc_bin[start..start + view["byteLength"].as_u64().unwrap() as usize];
    std::fs::write(dir.path().join("fox.bin"), &doc_bin).unwrap();
    std::fs::create_dir(dir.path().join("tex")).unwrap();
    for (uri, file, mime, written_uri) in [
        (
            "fox%20tex.png",
            "fox tex.png",
            "image/jpeg",
            "fox%20tex.png",
        ),
        ("tex\\fox.png", "tex/fox.png", "image/png", "tex/fox.png"),
    ] {
        std::fs::write(dir.path().join(file), png).unwrap();
        let mut j = doc_json.clone();
        j["images"][0] = json!({ "uri": uri, "mimeType": mime });
        j["buffers"][0]["uri"] = json!("fox.bin");
        let gltf = dir.path().join("fox.gltf");
        std::fs::write(&gltf, serde_json::to_vec(&j).unwrap()).unwrap();
        let out = tempfile::tempdir().unwrap();
        for name in ["f.gltf", "f.glb"] {
            let written = out.path().join(name);
            let told = blend(&gltf, &written);
            let err = String::from_utf8_lossy(&told.stderr);
            assert_eq!(
                err.contains("its bytes image/png"),
                mime != "image/png",
                "{err}"
            );
            assert_valid(&written);
            let j = match name {
                "f.glb" => glb_parts(&written).0,
                _ => read_json(&written),
            };
            assert_eq!(j["images"][0]["mimeType"], "image/png", "{name}");
            if name == "f.gltf" {
                assert_eq!(j["images"][0]["uri"], written_uri);
            }
        }
        assert_eq!(std::fs::read(out.path().join(file)).unwrap(), png);
    }
}

/// A texture missing beside a downloaded `.gltf` (its file not shipped, or misspelt) stopped
/// every command ("image 0 uri ... cannot be read"); the work is on the geometry and the clips,
/// so the image stays the reference it was (nothing the input held is lost), said in a line,
/// and a USD output's material leaves the texture out, said. Fox as a `.gltf` with its image
/// file missing blends to .glb, .gltf and .usda; the validator finds only the missing file
/// (IO_ERROR, as in the input). A reference leading outside the input's folder is still refused
/// (`hostile::external_references_stay_inside_the_input_folder`).
#[test]
fn a_texture_missing_beside_a_gltf_is_left_the_reference_it_was() {
    use serde_json::json;
    let Some(fx) = fixtures() else { return };
    let dir = tempfile::tempdir().unwrap();
    let (mut j, bin) = glb_parts(&fx.join("skinned/Fox.glb"));
    std::fs::write(dir.path().join("fox.bin"), &bin).unwrap();
    j["images"][0] = json!({ "uri": "fox_texture.png", "mimeType": "image/png" });
    j["buffers"][0]["uri"] = json!("fox.bin");
    let gltf = dir.path().join("fox.gltf");
    std::fs::write(&gltf, serde_json::to_vec(&j).unwrap()).unwrap();
    let out = tempfile::tempdir().unwrap();
    let blend = |written: &Path| {
        let told = run_ok(&[
            "blend",
            s(&gltf),
            "--clips",
            "Walk",
            "Run",
            "-o",
            s(written),
        ]);
        String::from_utf8_lossy(&told.stderr).into_owned()
    };
    for (name, said) in [
        ("f.glb", "left as a reference to it, not embedded"),
        ("f.gltf", "left as a reference to it, not copied"),
        ("f.usda", "image 0 \"fox_texture.png\" cannot be read"),
    ] {
        let written = out.path().join(name);
        let err = blend(&written);
        assert!(
            err.contains(said) && err.contains("cannot be read"),
            "{name}: {err}"
        );
        if name == "f.usda" {
            continue;
        }
        let j = match name {
            "f.glb" => glb_parts(&written).0,
            _ => read_json(&written),
        };
        assert_eq!(j["images"][0]["uri"], "fox_texture.png", "{name}");
        if let Some((_, _, line)) = validate(&written) {
            let report: serde_json::Value = serde_json::from_str(&line).unwrap();
            let errors: Vec<&str> = (report["messages"].as_array().unwrap().iter())
                .filter(|m| m["severity"] == "error")
                .map(|m| m["code"].as_str().unwrap())
                .collect();
            assert_eq!(errors, ["IO_ERROR"], "{name}: {line}");
        }
    }
    // The texture there, but a Git LFS pointer (a clone without `git lfs pull`): the same,
    // the line saying what the file is.
    std::fs::write(dir.path().join("fox_texture.png"), lfs_pointer(1048576)).unwrap();
    let written = out.path().join("f.glb");
    let err = blend(&written);
    let said = "\"fox_texture.png\" is a Git LFS pointer, not the file itself";
    assert!(err.contains(said), "{err}");
    assert_eq!(glb_parts(&written).0["images"][0]["uri"], "fox_texture.png");
}

/// Keys that stand for no pose (a NaN or infinite time or value, as exporters that divide a
/// zero by its length write; the whole file was refused, even for a clip the command does not
/// use): left out, the keys beside them played across, said in a line. Fox with a NaN
/// rotation key in its Walk, a NaN time shared by all of the Walk's samplers and an infinite
/// key in its Survey blends validator-clean, the Walk written with one key fewer on every
/// sampler (two on the one with both); Parrot with a NaN weight at one of its 13 keys tweens on the other 12.
#[test]
fn undefined_keys_are_left_out() {
    let Some(fx) = fixtures() else { return };
    let fox = fx.join("skinned/Fox.glb");
    let doc = Document::open(&fox).unwrap();
    let clip = |name: &str| {
        (doc.json["animations"].as_array().unwrap().iter())
            .position(|a| a["name"] == name)
            .unwrap()
    };
    let (walk, survey) = (clip("Walk"), clip("Survey"));
    let sampler = |a: usize, k: &str| {
        doc.json["animations"][a]["samplers"][0][k]
            .as_u64()
            .unwrap() as usize
    };
    let dir = tempfile::tempdir().unwrap();
    let (one, two, three) = (
        dir.path().join("1.glb"),
        dir.path().join("2.glb"),
        dir.path().join("3.glb"),
    );
    poke_f32(&fox, &one, sampler(walk, "output"), 3, 1, f32::NAN);
    poke_f32(&one, &two, sampler(walk, "input"), 7, 0, f32::NAN);
    poke_f32(&two, &three, sampler(survey, "output"), 5, 0, f32::INFINITY);
    let out = dir.path().join("out.glb");
    let told = run_ok(&["blend", s(&three), "--clips", "Walk", "Run", "-o", s(&out)]);
    let err = String::from_utf8_lossy(&told.stderr);
    for line in [
        "animation \"Survey\": 1 key NaN, infinite or a zero rotation (no pose) left out",
        "animation \"Walk\": ",
    ] {
        assert!(err.contains(line), "{line} in {err}");
    }
    assert_valid(&out);
    let written = Document::open(&out).unwrap();
    let keys = |a: usize| -> Vec<u64> {
        (written.json["animations"][a]["samplers"]
            .as_array()
            .unwrap()
            .iter())
        .map(|s| {
            written.json["accessors"][s["input"].as_u64().unwrap() as usize]["count"]
                .as_u64()
                .unwrap()
        })
        .collect()
    };
    let before = doc.json["accessors"][sampler(walk, "input")]["count"]
        .as_u64()
        .unwrap();
    // Key 7's time on every sampler, and key 3's rotation on the first.
    let mut expected = vec![before - 1; keys(walk).len()];
    expected[0] -= 1;
    assert_eq!(keys(walk), expected, "of {before}");
    // Parrot: a NaN weight at key 4 of 13.
    let parrot = fx.join("morph-keyframes/Parrot.glb");
    let pdoc = Document::open(&parrot).unwrap();
    let weights = pdoc.json["animations"][0]["samplers"][0]["output"]
        .as_u64()
        .unwrap() as usize;
    let targets = pdoc.json["meshes"][0]["primitives"][0]["targets"]
        .as_array()
        .unwrap()
        .len();
    let nan = dir.path().join("parrot.glb");
    poke_f32(&parrot, &nan, weights, 4 * targets + 2, 0, f32::NAN);
    let tweened = dir.path().join("parrot_out.glb");
    let told = run_ok(&["tween", s(&nan), "-o", s(&tweened)]);
    let said = String::from_utf8_lossy(&told.stdout) + String::from_utf8_lossy(&told.stderr);
    assert!(said.contains("12 keys ->"), "{said}");
    assert_valid(&tweened);
}

/// Undefined keys in accessors samplers share: a NaN time in the key times every sampler of
/// Fox's Walk reads, and a second sampler reading the first one's times and rotations (as
/// exporters write one track for two joints). Each sampler keeps the same keys, so the times
/// and the shared values are packed once; each was read again after it was packed (the second
/// sampler's keys shifted, or a panic: `cargo fuzz`'s gltf_read found it). Every Walk sampler
/// is written with the original's keys less key 7, its values the original's.
#[test]
fn undefined_keys_in_shared_accessors_are_left_out_once() {
    let Some(fx) = fixtures() else { return };
    let fox = fx.join("skinned/Fox.glb");
    let doc = Document::open(&fox).unwrap();
    let walk = (doc.json["animations"].as_array().unwrap().iter())
        .position(|a| a["name"] == "Walk")
        .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let (shared, nan) = (dir.path().join("shared.glb"), dir.path().join("nan.glb"));
    edited_glb(&fox, &shared, |j| {
        let anim = &mut j["animations"][walk];
        let sampler = anim["samplers"][0].clone();
        let first = anim["channels"][0].clone();
        let animated: Vec<u64> = (anim["channels"].as_array().unwrap().iter())
            .map(|c| c["target"]["node"].as_u64().unwrap())
            .collect();
        let joints = j["skins"][0]["joints"].as_array().unwrap();
        let other = (joints.iter().map(|n| n.as_u64().unwrap()))
            .find(|n| !animated.contains(n))
            .unwrap();
        let anim = &mut j["animations"][walk];
        let samplers = anim["samplers"].as_array_mut().unwrap();
        samplers.push(sampler);
        let s = samplers.len() - 1;
        let mut channel = first;
        channel["sampler"] = s.into();
        channel["target"]["node"] = other.into();
        anim["channels"].as_array_mut().unwrap().push(channel);
    });
    let input = |d: &Document, s: &serde_json::Value| {
        d.read_f64(s["input"].as_u64().unwrap() as usize).unwrap().0
    };
    let output = |d: &Document, s: &serde_json::Value| {
        d.read_f64(s["output"].as_u64().unwrap() as usize)
            .unwrap()
            .0
    };
    let before = Document::open(&shared).unwrap();
    let samplers = before.json["animations"][walk]["samplers"]
        .as_array()
        .unwrap();
    poke_f32(
        &shared,
        &nan,
        samplers[0]["input"].as_u64().unwrap() as usize,
        7,
        0,
        f32::NAN,
    );
    let out = dir.path().join("out.glb");
    said_by(
        &["blend", s(&nan), "--clips", "Walk", "Run", "-o", s(&out)],
        &["animation \"Walk\": 22 keys NaN"],
    );
    assert_valid(&out);
    let after = Document::open(&out).unwrap();
    let written = after.json["animations"][walk]["samplers"]
        .as_array()
        .unwrap();
    assert_eq!(written.len(), samplers.len());
    for (i, (a, b)) in samplers.iter().zip(written).enumerate() {
        let (times, values) = (input(&before, a), output(&before, a));
        let per_key = values.len() / times.len();
        let mut want_times = times.clone();
        want_times.remove(7);
        let mut want_values = values.clone();
        want_values.drain(7 * per_key..8 * per_key);
        assert_eq!(input(&after, b), want_times, "sampler {i}");
        assert_eq!(output(&after, b), want_values, "sampler {i}");
    }
}

/// A grid of `n` x `n` vertices (n <= 16) with two morph targets and a weights clip, its
/// triangles indexed in 8 bits of `component` type (5121, or 5120 as writers with no unsigned
/// type store them): the glTF, its binary chunk and the index bytes.
fn byte_indexed_grid(n: u32, component: u32) -> (serde_json::Value, Vec<u8>, Vec<u8>) {
    use serde_json::json;
    let mut bin = Vec::new();
    let mut push = |bytes: Vec<u8>| -> (usize, usize) {
        while bin.len() % 4 != 0 {
            bin.push(0);
        }
        let at = bin.len();
        bin.extend(bytes);
        (at, bin.len() - at)
    };
    let last = (n - 1) as f32;
    let grid = |z: &dyn Fn(f32, f32) -> f32| -> Vec<u8> {
        (0..n * n)
            .flat_map(|v| {
                let (x, y) = ((v % n) as f32 / last, (v / n) as f32 / last);
                [x, y, z(x, y)]
            })
            .flat_map(f32::to_le_bytes)
            .collect()
    };
    let row = n as u8;
    let indices: Vec<u8> = (0..n - 1)
        .flat_map(|y| (0..n - 1).map(move |x| (y * n + x) as u8))
        .flat_map(|a| [a, a + row, a + 1, a + 1, a + row, a.wrapping_add(row + 1)])
        .collect();
    let views: Vec<(usize, usize)> = vec![
        push(grid(&|_, _| 0.0)),
        push(grid(&|_, y| 0.2 * y)),
        push(grid(&|x, _| (x * 3.0).sin() * 0.3)),
        push(indices.clone()),
        push([0f32, 1.0].iter().flat_map(|t| t.to_le_bytes()).collect()),
        push(
            [1f32, 0.0, 0.0, 1.0]
                .iter()
                .flat_map(|t| t.to_le_bytes())
                .collect(),
        ),
    ];
    let view =
        |(at, len): (usize, usize)| json!({ "buffer": 0, "byteOffset": at, "byteLength": len });
    let vec3 = |v: usize, hi: f32| {
        json!({ "bufferView": v, "componentType": 5126, "count": n * n,
        "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, hi] })
    };
    let wave = (0..n)
        .map(|v| (v as f32 / last * 3.0).sin() * 0.3)
        .fold(0f32, f32::max);
    let j = json!({
        "asset": { "version": "2.0" }, "scene": 0, "scenes": [{ "nodes": [0] }],
        "nodes": [{ "mesh": 0 }],
        "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0 }, "indices": 3,
            "targets": [{ "POSITION": 1 }, { "POSITION": 2 }] }], "weights": [0, 0] }],
        "animations": [{ "channels": [{ "sampler": 0, "target": { "node": 0, "path": "weights" } }],
            "samplers": [{ "input": 4, "output": 5 }] }],
        "accessors": [
            vec3(0, 0.0), vec3(1, 0.2), vec3(2, wave),
            { "bufferView": 3, "componentType": component, "count": indices.len(), "type": "SCALAR" },
            { "bufferView": 4, "componentType": 5126, "count": 2, "type": "SCALAR", "min": [0], "max": [1] },
            { "bufferView": 5, "componentType": 5126, "count": 4, "type": "SCALAR" }
        ],
        "bufferViews": views.iter().map(|&v| view(v)).collect::<Vec<_>>(),
        "buffers": [{ "byteLength": bin.len() }]
    });
    (j, bin, indices)
}

/// Indices written as signed integers (libGDX's gdx-gltf exporter writes SHORT indices, its
/// issue 103: Java has no unsigned short, so an index past 32767 is the negative number of the
/// same bits): a vertex past the signed range was read as vertex 0 (its negative value cast),
/// the frames solved on the wrong triangles and the error carried into the output. A 12 x 12
/// grid indexed in BYTE (indices 128-143 negative) tweens to the bytes of the same grid indexed
/// in UNSIGNED_BYTE, said in a line.
#[test]
fn indices_written_signed_are_read_as_the_unsigned_they_stand_for() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.glb"), dir.path().join("b.glb"));
    let (signed, unsigned) = (
        dir.path().join("signed.glb"),
        dir.path().join("unsigned.glb"),
    );
    let (j, bin, indices) = byte_indexed_grid(12, 5120);
    assert!(indices.iter().any(|&i| i > 127));
    write_glb(&signed, &j, &bin);
    let (j, bin, _) = byte_indexed_grid(12, 5121);
    write_glb(&unsigned, &j, &bin);
    tweened(&signed, &a, &["index accessor 3 written as signed integers, which glTF does not allow for indices: read and written as the unsigned integers of the same bits"]);
    tweened(&unsigned, &b, &[]);
    assert_eq!(glb_parts(&a), glb_parts(&b));
}

/// An index accessor holding its type's largest value (255 in 8 bits, 65535 in 16: the
/// primitive restart index, which WebGL 2 always applies and the validator refuses), as a
/// writer numbering a 16 x 16 grid's 256 vertices in 8 bits (or a 256 x 256 grid's in 16)
/// leaves it: the triangles of the last vertex were dropped by browsers, and the error carried
/// into the output. Written as 32-bit indices, the same values, said in a line.
#[test]
fn indices_holding_the_restart_value_are_written_in_32_bits() {
    let (j, bin, indices) = byte_indexed_grid(16, 5121);
    assert!(indices.contains(&255));
    let dir = tempfile::tempdir().unwrap();
    let (input, out) = (dir.path().join("grid.glb"), dir.path().join("out.glb"));
    write_glb(&input, &j, &bin);
    if let Some((_, _, line)) = validate(&input) {
        assert!(line.contains("ACCESSOR_INDEX_PRIMITIVE_RESTART"), "{line}");
    }
    let told = run_ok(&["tween", s(&input), "-o", s(&out)]);
    let err = String::from_utf8_lossy(&told.stderr);
    assert!(
        err.contains("1 index accessor (3) held its type's largest value"),
        "{err}"
    );
    assert_valid(&out);
    let written = Document::open(&out).unwrap();
    assert_eq!(written.json["accessors"][3]["componentType"], 5125);
    let read: Vec<u32> = written.read_indices(3).unwrap();
    assert_eq!(read, indices.iter().map(|&i| i as u32).collect::<Vec<_>>());
}

/// Bounds glTF requires and a writer left out (every morph target's POSITION and the weights'
/// key times of Parrot without their min/max: 13 validator errors, carried into the output):
/// written from the values, said in a line, the targets' the same as the original file
/// declares (the weights' key times are the frames' own in the output).
#[test]
fn required_bounds_a_writer_left_out_are_written() {
    let Some(fx) = fixtures() else { return };
    let parrot = fx.join("morph-keyframes/Parrot.glb");
    let original = Document::open(&parrot).unwrap();
    let mut bounded = Vec::new();
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("unbounded.glb");
    edited_glb(&parrot, &input, |j| {
        let p = &j["meshes"][0]["primitives"][0];
        let mut which: Vec<u64> = (p["targets"].as_array().unwrap().iter())
            .map(|t| t["POSITION"].as_u64().unwrap())
            .collect();
        bounded = which.iter().map(|&a| a as usize).collect();
        which.push(j["animations"][0]["samplers"][0]["input"].as_u64().unwrap());
        for a in which {
            let acc = j["accessors"][a as usize].as_object_mut().unwrap();
            assert!(acc.remove("min").is_some() && acc.remove("max").is_some());
        }
    });
    let out = dir.path().join("out.glb");
    let told = run_ok(&["tween", s(&input), "-o", s(&out)]);
    assert_valid(&out);
    let err = String::from_utf8_lossy(&told.stderr);
    assert!(
        err.contains("13 accessors") && err.contains("had no min/max, which glTF requires"),
        "{err}"
    );
    let (written, _) = glb_parts(&out);
    for a in bounded {
        for k in ["min", "max"] {
            let (w, o) = (
                &written["accessors"][a][k],
                &original.json["accessors"][a][k],
            );
            let as_f32 = |v: &serde_json::Value| -> Vec<f32> {
                (v.as_array().unwrap().iter())
                    .map(|x| x.as_f64().unwrap() as f32)
                    .collect()
            };
            assert_eq!(as_f32(w), as_f32(o), "accessor {a} {k}");
        }
    }
}

/// Bounds and sparse storage a writer got wrong, as gltf-pipeline 4's Draco writes a Blender
/// morph file (a target's max declared 0 where its values reach 1.2, kept as a sparse accessor
/// whose index and value views other accessors read as vertex data): mended on write, so the
/// output is validator-clean where the input was not, and plays the same values.
#[test]
fn wrong_bounds_and_sparse_parts_in_vertex_views_are_mended() {
    use serde_json::json;
    let doc = Document::open(&sample("flag_wave.glb")).unwrap();
    let (mut j, mut bin) = (doc.json.clone(), doc.buffers[0].clone());
    let target = j["meshes"][0]["primitives"][0]["targets"][0]["POSITION"]
        .as_u64()
        .unwrap() as usize;
    // Two views holding an index (vertex 3) and a value, each also read by a plain accessor.
    let mut view = |bytes: &[u8], j: &mut serde_json::Value| -> usize {
        while bin.len() % 4 != 0 {
            bin.push(0);
        }
        let offset = bin.len();
        bin.extend_from_slice(bytes);
        let views = j["bufferViews"].as_array_mut().unwrap();
        views.push(json!({ "buffer": 0, "byteOffset": offset, "byteLength": bytes.len(), "byteStride": 12, "target": 34962 }));
        views.len() - 1
    };
    let index = view(&[3, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0], &mut j);
    let value: Vec<u8> = [0.25f32, 1.2, -0.5]
        .iter()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    let values = view(&value, &mut j);
    let accessors = j["accessors"].as_array_mut().unwrap();
    for v in [index, values] {
        accessors
            .push(json!({ "bufferView": v, "componentType": 5126, "count": 1, "type": "VEC3" }));
    }
    accessors[target]["max"] = json!([0, 0, 0]);
    accessors[target]["sparse"] = json!({
        "count": 1,
        "indices": { "bufferView": index, "componentType": 5121 },
        "values": { "bufferView": values }
    });
    j["buffers"][0]["byteLength"] = json!(bin.len());
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("broken.glb");
    write_glb(&input, &j, &bin);
    let out = dir.path().join("out.glb");
    let told = run_ok(&["tween", s(&input), "-o", s(&out)]);
    assert_valid(&out);
    let err =
        String::from_utf8_lossy(&told.stdout).to_string() + &String::from_utf8_lossy(&told.stderr);
    assert!(err.contains("did not match its values"), "{err}");
    assert!(err.contains("written dense"), "{err}");
    // The target as read from the input, now dense: vertex 3 moved by the sparse value.
    let (_, targets) = read_targets(&out, 0, 0);
    assert_eq!(targets[0][3], [0.25, 1.2, -0.5]);
    let before = inbetween::gltf::Document::open(&input).unwrap();
    let (want, _) = before.read_f64(target).unwrap();
    let got: Vec<f64> = targets[0].iter().flatten().map(|&x| x as f64).collect();
    assert_eq!(got, want);
}

#[test]
fn loop_closes_the_motion_and_extension_adds_frames() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("loop.glb");
    // flag_wave: 5 keys; --loop appends the first key again: 5 segments of 5 frames + 1.
    tween_quietly(
        &sample("flag_wave.glb"),
        &out,
        &["--loop", "--method", "spline", "--tweens", "4"],
    );
    assert_valid(&out);
    let t = played(&out, 0, 0, 0).positions;
    assert_eq!(t.len(), 26);
    for (a, b) in t[0].iter().zip(&t[25]) {
        for c in 0..3 {
            assert!((a[c] - b[c]).abs() < 1e-5, "the loop ends where it starts");
        }
    }
    let ext = dir.path().join("ext.glb");
    tween_quietly(
        &sample("bar_twist.glb"),
        &ext,
        &[
            "--extend-before",
            "0.5",
            "--extend-after",
            "0.4",
            "--tweens",
            "4",
        ],
    );
    assert_valid(&ext);
    assert_eq!(played(&ext, 0, 0, 0).times.len(), 6 + 2 + 2);
    let r = inbetween(&[
        "tween",
        s(&sample("bar_twist.glb")),
        "-o",
        s(&ext),
        "--extend-after",
        "-1",
    ]);
    assert_eq!(r.status.code(), Some(2));
}

#[test]
fn quantized_positions_are_read() {
    // bar_twist with POSITION stored as int16 (KHR_mesh_quantization, not normalized) and the
    // node scaled by 1/1000.
    let dir = tempfile::tempdir().unwrap();
    let doc = Document::open(&sample("bar_twist.glb")).unwrap();
    let mut json = doc.json.clone();
    let pos = json["meshes"][0]["primitives"][0]["attributes"]["POSITION"]
        .as_u64()
        .unwrap() as usize;
    let (values, _) = doc.read_f64(pos).unwrap();
    let quantized: Vec<i16> = values.iter().map(|v| (v * 1000.0).round() as i16).collect();
    let mut bin = doc.buffers[0].clone();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let offset = bin.len();
    for chunk in quantized.chunks(3) {
        for q in chunk {
            bin.extend(q.to_le_bytes());
        }
        bin.extend([0u8, 0]); // 4-byte aligned elements
    }
    let views = json["bufferViews"].as_array_mut().unwrap();
    views.push(serde_json::json!({ "buffer": 0, "byteOffset": offset, "byteLength": bin.len() - offset, "byteStride": 8, "target": 34962 }));
    let view = views.len() - 1;
    let lo: Vec<i16> = (0..3)
        .map(|c| quantized.iter().skip(c).step_by(3).copied().min().unwrap())
        .collect();
    let hi: Vec<i16> = (0..3)
        .map(|c| quantized.iter().skip(c).step_by(3).copied().max().unwrap())
        .collect();
    let accessors = json["accessors"].as_array_mut().unwrap();
    accessors.push(serde_json::json!({ "bufferView": view, "componentType": 5122, "count": values.len() / 3, "type": "VEC3", "min": lo, "max": hi }));
    let acc = accessors.len() - 1;
    json["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = acc.into();
    // Target deltas in the quantized space: scale them by 1000 too.
    let tpos = json["meshes"][0]["primitives"][0]["targets"][0]["POSITION"]
        .as_u64()
        .unwrap() as usize;
    let (deltas, _) = doc.read_f64(tpos).unwrap();
    let scaled: Vec<f32> = deltas.iter().map(|d| (*d * 1000.0) as f32).collect();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let offset = bin.len();
    bin.extend(scaled.iter().flat_map(|f| f.to_le_bytes()));
    let views = json["bufferViews"].as_array_mut().unwrap();
    views.push(serde_json::json!({ "buffer": 0, "byteOffset": offset, "byteLength": bin.len() - offset, "target": 34962 }));
    let view = views.len() - 1;
    let lo: Vec<f32> = (0..3)
        .map(|c| {
            scaled
                .iter()
                .skip(c)
                .step_by(3)
                .copied()
                .fold(f32::MAX, f32::min)
        })
        .collect();
    let hi: Vec<f32> = (0..3)
        .map(|c| {
            scaled
                .iter()
                .skip(c)
                .step_by(3)
                .copied()
                .fold(f32::MIN, f32::max)
        })
        .collect();
    let accessors = json["accessors"].as_array_mut().unwrap();
    accessors.push(serde_json::json!({ "bufferView": view, "componentType": 5126, "count": scaled.len() / 3, "type": "VEC3", "min": lo, "max": hi }));
    let tacc = accessors.len() - 1;
    json["meshes"][0]["primitives"][0]["targets"][0]["POSITION"] = tacc.into();
    json["buffers"][0]["byteLength"] = bin.len().into();
    json["nodes"][0]["scale"] = serde_json::json!([0.001, 0.001, 0.001]);
    json["extensionsUsed"] = serde_json::json!(["KHR_mesh_quantization"]);
    json["extensionsRequired"] = serde_json::json!(["KHR_mesh_quantization"]);
    let input = dir.path().join("quantized.glb");
    write_glb(&input, &json, &bin);
    assert_valid(&input);
    let out = dir.path().join("out.glb");
    tween_quietly(&input, &out, &[]);
    assert_valid(&out);
    // Same frames as the float file, in the quantized space (x1000), within the rounding.
    let plain = dir.path().join("plain.glb");
    tween_quietly(&sample("bar_twist.glb"), &plain, &[]);
    let (qb, qt) = read_targets_any(&out);
    let (pb, pt) = read_targets_any(&plain);
    for (qf, pf) in qt.iter().zip(&pt) {
        for v in 0..qb.len() {
            for c in 0..3 {
                let q = (qb[v][c] + qf[v][c]) / 1000.0;
                let p = pb[v][c] + pf[v][c];
                assert!((q - p).abs() < 2e-3, "vertex {v}: {q} vs {p}");
            }
        }
    }
}

/// Base positions (decoded, any component type) and target deltas of mesh 0 primitive 0.
fn read_targets_any(path: &Path) -> (Vec<[f32; 3]>, Vec<Vec<[f32; 3]>>) {
    let doc = Document::open(path).unwrap();
    let p = &doc.json["meshes"][0]["primitives"][0];
    let v3 = |a: &serde_json::Value| -> Vec<[f32; 3]> {
        let (v, _) = doc.read_f64(a.as_u64().unwrap() as usize).unwrap();
        v.chunks(3)
            .map(|c| [c[0] as f32, c[1] as f32, c[2] as f32])
            .collect()
    };
    let base = v3(&p["attributes"]["POSITION"]);
    let targets = p["targets"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| v3(&t["POSITION"]))
        .collect();
    (base, targets)
}

#[test]
fn constant_weight_animations_point_to_keys_targets() {
    let Some(fx) = fixtures() else { return };
    let input = fx.join("skinned/RobotExpressive.glb");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("robot.glb");
    let r = inbetween(&["tween", s(&input), "-o", s(&out)]);
    assert_eq!(r.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&r.stderr).contains("--keys targets"));
    assert!(!out.exists());
    tween_quietly(&input, &out, &["--keys", "targets"]);
    // The input has validator errors of its own (skin weights that do not sum to 1).
    assert_no_new_issues(&input, &out);
    // The skins and the other animations come through.
    let a = Document::open(&input).unwrap();
    let b = Document::open(&out).unwrap();
    // (Accessors may be renumbered: the dropped weight channels' data is compacted away.)
    for (sa, sb) in a.json["skins"]
        .as_array()
        .unwrap()
        .iter()
        .zip(b.json["skins"].as_array().unwrap())
    {
        assert_eq!(sa["joints"], sb["joints"]);
        assert_eq!(sa["skeleton"], sb["skeleton"]);
        let ibm = |d: &Document, s: &serde_json::Value| {
            d.read_f64(s["inverseBindMatrices"].as_u64().unwrap() as usize)
                .unwrap()
        };
        assert_eq!(ibm(&a, sa), ibm(&b, sb));
    }
    assert_eq!(
        b.json["animations"].as_array().unwrap().len(),
        a.json["animations"].as_array().unwrap().len() + 1
    );
}

/// An output that is a folder (`-o renders/`) is told as one, with a file in it to name, by
/// every command, in one line, nothing written; it was "unknown output extension """ (tween),
/// a list of the formats blend writes, or "the sheet must end in .png".
#[test]
fn an_output_that_is_a_folder_is_told_with_a_file_to_name_in_it() {
    let dir = tempfile::tempdir().unwrap();
    let folder = dir.path().join("renders");
    std::fs::create_dir(&folder).unwrap();
    let input = sample("bar_twist.glb");
    let sheet = dir.path().join("sheet.png");
    let mut cases = vec![
        (
            vec!["tween", s(&input), "-o", s(&folder)],
            "bar_twist_tween.glb",
        ),
        (
            vec!["preview", s(&input), "-o", s(&folder)],
            "bar_twist.png",
        ),
        (
            [
                &["preview", s(&input), "-o", s(&sheet)][..],
                &["--animate", s(&folder)],
            ]
            .concat(),
            "bar_twist.gif",
        ),
    ];
    let fx = fixtures();
    let (fox, walk) = match &fx {
        Some(fx) => (
            fx.join("skinned/Fox.glb"),
            fx.join("bvh/kevinxie4c_walk.bvh"),
        ),
        None => Default::default(),
    };
    if fx.is_some() {
        cases.push((
            vec!["blend", s(&fox), "--clips", "Walk", "Run", "-o", s(&folder)],
            "Fox_blend.glb",
        ));
        cases.push((
            vec!["blend", s(&walk), s(&walk), "-o", s(&folder)],
            "kevinxie4c_walk_blend.bvh",
        ));
    }
    for (args, named) in cases {
        let r = inbetween(&args);
        let err = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{args:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        let said = format!(
            "{}: is a folder: name the file to write in it (e.g. {})",
            folder.display(),
            folder.join(named).display()
        );
        assert!(err.contains(&said), "{args:?}: {err}");
        assert!(!sheet.exists());
        assert_eq!(std::fs::read_dir(&folder).unwrap().count(), 0);
    }
}

/// A negative count (`--tweens -1`, `--frames -3`, `--threads -2`) is told as an invalid value
/// of its option; it was taken for an unknown option, with the advice to pass it after `--`.
#[test]
fn a_negative_count_is_an_invalid_value_of_its_option() {
    let dir = tempfile::tempdir().unwrap();
    let input = sample("bar_twist.glb");
    let (glb, png) = (dir.path().join("t.glb"), dir.path().join("p.png"));
    for (args, option) in [
        (
            vec!["tween", s(&input), "-o", s(&glb), "--tweens", "-1"],
            "--tweens <N>",
        ),
        (
            vec!["tween", s(&input), "-o", s(&glb), "--threads", "-2"],
            "--threads <THREADS>",
        ),
        (
            vec!["preview", s(&input), "-o", s(&png), "--frames", "-3"],
            "--frames <FRAMES>",
        ),
    ] {
        let r = inbetween(&args);
        let err = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{err}");
        let value = args.last().unwrap();
        assert!(
            err.contains(&format!("invalid value '{value}' for '{option}'")),
            "{err}"
        );
        assert!(!err.contains("unexpected argument"), "{err}");
        assert!(!glb.exists() && !png.exists());
    }
}

/// A scene of many small morph meshes is tweened side by side, a mesh to a thread (where each
/// spread its few triangles over every thread, most of the run spent handing work over):
/// every mesh's frames are those it gets alone, and the output is the same for any number of
/// threads, glTF, USD and `preview`'s sheet.
#[test]
fn many_small_meshes_tween_side_by_side_as_each_alone() {
    use inbetween::synth::{bend, tube, KeyedMesh, KeyframeFile};
    let dir = tempfile::tempdir().unwrap();
    let mesh = |i: usize| {
        let s = tube(6, 8, 2.0, 0.3, 0.3);
        let key = bend(&s.positions, 1.0, (20.0 + 3.0 * i as f64).to_radians(), 0.5);
        KeyedMesh::new(&format!("prop{i}"), s, vec![key])
    };
    let file = |meshes: Vec<KeyedMesh>, name: &str| {
        let path = out_in(&dir, name);
        KeyframeFile {
            meshes,
            key_times: None,
            key_weights: None,
        }
        .write(&path)
        .unwrap();
        path
    };
    let scene = file((0..40).map(mesh).collect(), "scene.glb");
    for ext in ["glb", "usda"] {
        let outputs: Vec<Vec<u8>> = ["1", "2", "3"]
            .iter()
            .map(|t| {
                let out = out_in(&dir, &format!("scene_{t}.{ext}"));
                tween_quietly(&scene, &out, &["--threads", t]);
                std::fs::read(&out).unwrap()
            })
            .collect();
        assert!(outputs.iter().all(|o| o == &outputs[0]), "{ext}");
    }
    // `preview` draws them side by side too.
    let sheets: Vec<Vec<u8>> = ["1", "2"]
        .iter()
        .map(|t| {
            let png = out_in(&dir, &format!("scene_{t}.png"));
            run_ok(&["preview", s(&scene), "-o", s(&png), "-q", "--threads", t]);
            std::fs::read(&png).unwrap()
        })
        .collect();
    assert_eq!(sheets[0], sheets[1]);
    let tweened = out_in(&dir, "scene_1.glb");
    for i in [0, 17, 39] {
        let alone = file(vec![mesh(i)], &format!("alone{i}.glb"));
        let out = out_in(&dir, &format!("alone{i}_t.glb"));
        tween_quietly(&alone, &out, &[]);
        let (base, targets) = read_targets(&out, 0, 0);
        assert!(targets.len() > 20, "{}", targets.len());
        assert_eq!(read_targets(&tweened, i, 0), (base, targets), "mesh {i}");
    }
}

/// A small mesh's segments are set up and solved side by side, a segment to a thread, where
/// each spread its few triangles over every thread: the frames and the report's figures are
/// those of one segment at a time (one thread), glTF and USD.
#[test]
fn a_small_mesh_s_segments_solved_side_by_side_are_those_of_one_at_a_time() {
    let dir = tempfile::tempdir().unwrap();
    let input = bent_arm(&dir, (12, 10), 10, 15.0);
    for ext in ["glb", "usda"] {
        let runs: Vec<(Vec<u8>, serde_json::Value)> = ["1", "2", "3"]
            .iter()
            .map(|t| {
                let out = out_in(&dir, &format!("out.{ext}"));
                let report = out_in(&dir, "report.json");
                let args = ["--threads", t, "--fps", "24", "--report", s(&report)];
                tween_quietly(&input, &out, &args);
                let mut r: serde_json::Value =
                    serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
                r.as_object_mut().unwrap().remove("output");
                (std::fs::read(&out).unwrap(), r)
            })
            .collect();
        let frames = runs[0].1["meshes"][0]["frames"].as_array().unwrap().len();
        assert!(frames > 200, "{frames} frames");
        assert!(runs.iter().all(|r| r == &runs[0]), "{ext}");
    }
}

/// A small mesh's segment whose frames alone are more than a side-by-side run holds is
/// streamed in chunks as a large mesh's are: 1,300 frames of 2,000 vertices between each two
/// keys peaked at 105 MiB when such a segment was solved whole on one thread (18 MiB so).
#[test]
fn a_segment_of_many_frames_is_streamed_whatever_the_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let input = bent_arm(&dir, (50, 40), 3, 40.0);
    let out = out_in(&dir, "out.usdc");
    let r = run_ok(&["tween", s(&input), "-o", s(&out), "--fps", "1300"]);
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(err.contains("-> 2601 frames"), "{err}");
    let peak = summary_peak_mib(&err);
    assert!(peak < 60.0, "peak {peak} MiB: {err}");
}

/// A tube of `(rings, segments)` 3 long with `keys` keys one second apart (the base and its
/// targets), each bent `step` degrees more than the one before at its middle, written in `dir`.
fn bent_arm(
    dir: &tempfile::TempDir,
    (rings, segments): (usize, usize),
    keys: usize,
    step: f64,
) -> PathBuf {
    use inbetween::synth::{bend, tube, KeyedMesh, KeyframeFile};
    let arm = tube(rings, segments, 3.0, 0.4, 0.4);
    let targets: Vec<_> = (1..keys)
        .map(|k| bend(&arm.positions, 1.5, (step * k as f64).to_radians(), 0.6))
        .collect();
    let input = out_in(dir, "keys.glb");
    KeyframeFile {
        meshes: vec![KeyedMesh::new("arm", arm, targets)],
        key_times: None,
        key_weights: None,
    }
    .write(&input)
    .unwrap();
    input
}

/// `bench --end-to-end`, `bench --scene` and `bench --rig` run their commands in child
/// processes and print what they timed as JSON: every run there, each with its wall time, the
/// summary of the timed tween (and its linear twin) beside it. Every shape of the bench's JSON
/// (a `--json` row and `--preview` too) as schemas/bench.schema.json describes it.
#[test]
fn bench_times_whole_commands_in_child_processes() {
    // Each output read, and checked against schemas/bench.schema.json.
    let dir = tempfile::tempdir().unwrap();
    let python = python();
    let json = |args: &[&str]| -> serde_json::Value {
        let out = run_ok(args);
        if let Some(py) = &python {
            let file = dir.path().join("bench.json");
            std::fs::write(&file, &out.stdout).unwrap();
            check_schema(py, "bench.schema.json", &file, &args.join(" "));
        }
        serde_json::from_slice(&out.stdout).unwrap()
    };
    let e2e = json(&["bench", "--end-to-end", "2000", "--e2e-tweens", "3"]);
    assert!(e2e["wall_s"].as_f64().unwrap() > 0.0, "{e2e}");
    assert!(e2e["linear_wall_s"].as_f64().unwrap() > 0.0, "{e2e}");
    let summary = e2e["summary"].as_str().unwrap();
    assert!(summary.contains("3 keys -> 9 frames"), "{summary}");
    // Each run's command line, its time checked.
    fn commands(bench: &serde_json::Value) -> Vec<&str> {
        (bench["runs"].as_array().unwrap().iter())
            .map(|r| {
                assert!(r[1].as_f64().unwrap() > 0.0, "{r}");
                r[0].as_str().unwrap()
            })
            .collect()
    }
    let scene = json(&["bench", "--scene", "12"]);
    assert_eq!(scene["meshes"], 12);
    assert_eq!(
        commands(&scene),
        [
            "tween -o out.glb",
            "tween -o meshopt.glb --meshopt",
            "tween -o out.usdc",
            "preview -o sheet.png"
        ]
    );
    let row = json(&["bench", "--sizes", "2000", "--frames", "2", "--json"]);
    assert_eq!(row["triangles"], 1980);
    let preview = json(&["bench", "--preview", "2000"]);
    assert_eq!(preview["cells"], 12);
    let rig = json(&["bench", "--rig", "2"]);
    assert_eq!(
        (rig["shapes"].as_u64(), rig["keys"].as_u64()),
        (Some(2), Some(101))
    );
    assert_eq!(
        commands(&rig),
        [
            "tween -o out.glb",
            "tween -o meshopt.glb --meshopt",
            "tween -o compact.glb --compact",
            "tween -o out.usdc"
        ]
    );
}

/// An animation with no channel and no sampler (assimp 5.2's glTF-to-glTF export keeps a morph
/// file's clip so, having lost its weights: 2 validator errors its outputs carried) is left out
/// of the output with a line saying so; placed before the file's own clip, it moves that clip's
/// index, which the stages between read and write still address as the input has it: the
/// output is byte for byte the one written without it, in either container and with
/// `--compact`.
#[test]
fn empty_animations_are_left_out() {
    let doc = Document::open(&sample("flag_wave.glb")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("lost.glb");
    let mut j = doc.json.clone();
    let anims = j["animations"].as_array_mut().unwrap();
    anims.insert(
        0,
        serde_json::json!({"name": "lost", "channels": [], "samplers": []}),
    );
    write_glb(&input, &j, &doc.buffers[0]);
    for (ext, args) in [
        ("glb", &[][..]),
        ("gltf", &[][..]),
        ("glb", &["--compact"][..]),
    ] {
        // The same name in two folders: a .gltf names its .bin after itself.
        let [a, b] = ["a", "b"].map(|d| {
            std::fs::create_dir_all(dir.path().join(d)).unwrap();
            dir.path().join(d).join(format!("out.{ext}"))
        });
        tween_quietly(&sample("flag_wave.glb"), &a, args);
        let mut all = vec!["tween", s(&input), "-o", s(&b)];
        all.extend_from_slice(args);
        let told = run_ok(&all);
        let err = String::from_utf8_lossy(&told.stderr);
        assert!(
            err.contains(
                "animation \"lost\" has no channel or no sampler (nothing to play): left out"
            ),
            "{err}"
        );
        assert_valid(&b);
        let json = |p: &Path| -> serde_json::Value {
            match ext {
                "gltf" => read_json(p),
                _ => glb_parts(p).0,
            }
        };
        assert!(json(&a) == json(&b), "{ext} {args:?}: the JSON differs");
        let bin = |p: &Path| std::fs::read(p.with_extension("bin")).ok();
        assert!(bin(&a) == bin(&b), "{ext} {args:?}: the .bin differs");
        let same = std::fs::read(&a).unwrap() == std::fs::read(&b).unwrap();
        assert!(same, "{ext} {args:?}: the files differ");
    }
}

/// A mesh that two nodes draw, each with a weights channel of its own (two characters sharing
/// one face mesh, each with its own performance): a track each, in one mesh's targets; each
/// node plays its own keys where they were (within 1e-5 of the size) and frames of its own
/// between them.
#[test]
fn two_nodes_sharing_a_mesh_each_play_their_own_keys() {
    let dir = tempfile::tempdir().unwrap();
    let flag = sample("flag_wave.glb");
    let (mut json, mut bin) = glb_parts(&flag);
    let doc = Document::open(&flag).unwrap();
    let channel = json["animations"][0]["channels"][0].clone();
    let node = channel["target"]["node"].as_u64().unwrap() as usize;
    let sampler =
        json["animations"][0]["samplers"][channel["sampler"].as_u64().unwrap() as usize].clone();
    let (weights, _) = doc
        .read_f64(sampler["output"].as_u64().unwrap() as usize)
        .unwrap();
    let targets = json["meshes"][0]["primitives"][0]["targets"]
        .as_array()
        .unwrap()
        .len();
    // The second node plays the keys backwards.
    let reversed: Vec<f32> = (weights.chunks(targets).rev().flatten())
        .map(|&w| w as f32)
        .collect();
    let output = push_f32_accessor(&mut json, &mut bin, &reversed, "SCALAR");
    json["accessors"][output]
        .as_object_mut()
        .unwrap()
        .retain(|k, _| k != "min" && k != "max");
    let second = json["nodes"].as_array().unwrap().len();
    let mut copy = json["nodes"][node].clone();
    copy["translation"] = serde_json::json!([3.0, 0.0, 0.0]);
    copy.as_object_mut().unwrap().remove("children");
    json["nodes"].as_array_mut().unwrap().push(copy);
    json["scenes"][0]["nodes"]
        .as_array_mut()
        .unwrap()
        .push(second.into());
    let anim = &mut json["animations"][0];
    let samplers = anim["samplers"].as_array_mut().unwrap();
    samplers.push(serde_json::json!({"input": sampler["input"], "output": output}));
    let s = samplers.len() - 1;
    anim["channels"]
        .as_array_mut()
        .unwrap()
        .push(serde_json::json!({"sampler": s, "target": {"node": second, "path": "weights"}}));
    let input = out_in(&dir, "two.glb");
    write_glb(&input, &json, &bin);
    assert_valid(&input);
    let out = out_in(&dir, "out.glb");
    tween_quietly(&input, &out, &[]);
    assert_valid(&out);
    let size = diag(
        &(played(&input, 0, 0, 0).positions[0].iter())
            .map(|p| glam::Vec3::from(*p).as_dvec3())
            .collect::<Vec<_>>(),
    );
    let mut frames = Vec::new();
    for c in 0..2 {
        let (was, now) = (played(&input, 0, 0, c), played(&out, 0, 0, c));
        assert!(
            now.times.len() > was.times.len(),
            "channel {c}: frames between the keys"
        );
        for (t, keyed) in was.times.iter().zip(&was.positions) {
            let f = (now.times.iter().position(|x| (x - t).abs() < 1e-6))
                .unwrap_or_else(|| panic!("channel {c}: key {t} kept"));
            let off = (keyed.iter().zip(&now.positions[f]))
                .map(|(a, b)| (glam::Vec3::from(*a) - glam::Vec3::from(*b)).length())
                .fold(0.0f32, f32::max);
            assert!((off as f64) < 1e-5 * size, "channel {c} key {t}: {off} off");
        }
        frames.push(now);
    }
    // Between the keys, each node its own frame: the first frame after the start differs.
    let apart = (frames[0].positions[1].iter().zip(&frames[1].positions[1]))
        .map(|(a, b)| (glam::Vec3::from(*a) - glam::Vec3::from(*b)).length())
        .fold(0.0f32, f32::max);
    assert!(
        apart as f64 > 0.01 * size,
        "the two nodes play the same frame ({apart})"
    );
}
