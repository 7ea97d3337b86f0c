//! Default timing and rigs on real and baked files: frames at 30 per second between keys with
//! every key kept, baked clips left as they are (no growth), authored targets kept and still
//! playing, key times snapped to their grid (whole USD time codes, `--fps` ending on the last
//! key), `inspect`, and the pointer to `blend` for skinned files.

mod common;

use common::*;
use glam::DVec3;
use inbetween::gltf::Document;
use inbetween::tween::{track_frames_welded, TweenOptions};
use std::path::{Path, PathBuf};

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Bytes of a file and the .bin files beside a .gltf.
fn file_bytes(path: &Path) -> u64 {
    let mut n = std::fs::metadata(path).unwrap().len();
    if path.extension().is_some_and(|e| e == "gltf") {
        let json: serde_json::Value = read_json(path);
        for b in json["buffers"].as_array().into_iter().flatten() {
            if let Some(uri) = b["uri"].as_str().filter(|u| !u.starts_with("data:")) {
                n += std::fs::metadata(path.with_file_name(uri)).unwrap().len();
            }
        }
    }
    n
}

/// The positions `path`'s first weights animation plays at each of its keys.
fn input_poses(path: &Path) -> (Vec<f64>, Vec<Vec<DVec3>>) {
    let doc = Document::open(path).unwrap();
    doc_poses(&doc, 0, mesh0_samplers(&doc)[0])
}

fn face(dir: &Path, rate: f64) -> PathBuf {
    let path = dir.join(format!("face{rate}.glb"));
    inbetween::synth::face_rig(52, rate, 2.0)
        .write(&path)
        .unwrap();
    path
}

#[test]
fn a_baked_face_rig_keeps_its_targets_and_grows_little() {
    let dir = tempfile::tempdir().unwrap();
    for (rate, tweens) in [(30.0, 0), (10.0, 2)] {
        let input = face(dir.path(), rate);
        let out = dir.path().join(format!("out{rate}.glb"));
        let r = tween_quietly(&input, &out, &[]);
        assert!(r.status.success());
        assert_valid(&out);
        // The 52 authored targets first, names kept; one more per frame between keys.
        let keys = (2.0 * rate) as usize + 1;
        let doc = Document::open(&out).unwrap();
        let names = doc.json["meshes"][0]["extras"]["targetNames"]
            .as_array()
            .unwrap();
        assert_eq!(names.len(), 52 + (keys - 1) * tweens, "rate {rate}");
        for (k, n) in names.iter().take(52).enumerate() {
            assert_eq!(n.as_str().unwrap(), format!("key{}", k + 1));
        }
        // Keys are played exactly as the input plays them; frames between are the computed ones.
        let (times, poses) = input_poses(&input);
        let played = played(&out, 0, 0, 0);
        assert_eq!(played.times.len(), keys + (keys - 1) * tweens);
        let meshes = morph_meshes(&input);
        let (welded, frames) =
            track_frames_welded(&meshes[0], &meshes[0].tracks[0], &TweenOptions::default())
                .unwrap();
        let d = diag(&meshes[0].primitives[0].base);
        let mut checked_keys = 0;
        for (f, (t, got)) in played.times.iter().zip(&played.positions).enumerate() {
            let key = times.iter().position(|k| (*k as f32 - t).abs() < 1e-6);
            for (v, g) in got.iter().enumerate() {
                let g = DVec3::new(g[0] as f64, g[1] as f64, g[2] as f64);
                let want = frames[f][welded.of_vertex[v] as usize];
                assert!(
                    (g - want).length() < 1e-6 * d,
                    "frame {f} vertex {v}: {g} vs {want}"
                );
                if let Some(k) = key {
                    assert!((g - poses[k][v]).length() < 1e-6 * d, "key {k} vertex {v}");
                }
            }
            checked_keys += key.is_some() as usize;
        }
        assert_eq!(checked_keys, keys);
        let growth = file_bytes(&out) as f64 / file_bytes(&input) as f64;
        eprintln!(
            "face rig baked at {rate}/s: {} -> {} bytes ({growth:.2}x)",
            file_bytes(&input),
            file_bytes(&out)
        );
        // With frames between keys the 52 position-only shapes are given the normals of their
        // shapes (target_normals): 2.44x without them, 2.71x with.
        assert!(growth <= if tweens == 0 { 1.1 } else { 2.8 }, "{growth}");
    }
}

#[test]
fn baked_fixtures_grow_at_most_tenfold_and_keep_their_clips() {
    let Some(fx) = fixtures() else { return };
    let dir = tempfile::tempdir().unwrap();
    for (file, clips) in [
        (
            "morph-khronos/AnimatedMorphCube/glTF/AnimatedMorphCube.gltf",
            1,
        ),
        (
            "morph-khronos/AnimatedMorphSphere/glTF/AnimatedMorphSphere.gltf",
            1,
        ),
        ("morph-khronos/MorphStressTest/glTF/MorphStressTest.gltf", 3),
    ] {
        let input = fx.join(file);
        let out = dir.path().join("out.glb");
        tween_quietly(&input, &out, &[]);
        assert_valid(&out);
        let growth = file_bytes(&out) as f64 / file_bytes(&input) as f64;
        eprintln!(
            "{file}: {} -> {} bytes ({growth:.2}x)",
            file_bytes(&input),
            file_bytes(&out)
        );
        assert!(growth <= 10.0, "{file}: {growth}x");
        assert_eq!(
            Document::open(&out).unwrap().json["animations"]
                .as_array()
                .unwrap()
                .len(),
            clips
        );
    }
    // --animation picks one clip; the others still play, padded for the new targets.
    let input = fx.join("morph-khronos/MorphStressTest/glTF/MorphStressTest.gltf");
    let out = dir.path().join("wave.glb");
    tween_quietly(&input, &out, &["--animation", "TheWave", "--tweens", "1"]);
    assert_valid(&out);
    let doc = Document::open(&out).unwrap();
    assert_eq!(doc.json["animations"].as_array().unwrap().len(), 3);
    let (_, poses) = input_poses(&input);
    let first = played(&out, 0, 0, 0); // "Individuals", untouched
    for (k, got) in first.positions.iter().enumerate() {
        for (v, g) in got.iter().enumerate() {
            let g = DVec3::new(g[0] as f64, g[1] as f64, g[2] as f64);
            assert!(
                (g - poses[k][v]).length() < 1e-5,
                "Individuals key {k} vertex {v}"
            );
        }
    }
}

#[test]
fn key_times_snap_to_their_grid() {
    let Some(fx) = fixtures() else { return };
    let dir = tempfile::tempdir().unwrap();
    // AnimatedMorphCube stores its last key, 4.2 s, as 4.19999743.
    let cube = fx.join("morph-khronos/AnimatedMorphCube/glTF/AnimatedMorphCube.gltf");
    let out = dir.path().join("cube.glb");
    tween_quietly(&cube, &out, &[]);
    let times = played(&out, 0, 0, 0).times;
    assert_eq!(times.len(), 127);
    for (k, t) in times.iter().enumerate() {
        assert_eq!(*t, (k as f64 / 30.0) as f32, "frame {k}");
    }
    // --fps ends on the last key, on its grid or off it.
    for (fps, frames) in [("24", 102), ("7", 31), ("10", 43)] {
        tween_quietly(&cube, &out, &["--fps", fps]);
        let times = played(&out, 0, 0, 0).times;
        assert_eq!(times.len(), frames, "--fps {fps}");
        assert_eq!(*times.last().unwrap(), 4.2f32, "--fps {fps}");
    }
    // USD: whole time codes per second and time codes on Flamingo and Parrot.
    let Some(python) = python() else { return };
    for bird in ["Flamingo", "Parrot"] {
        let usd = dir.path().join(format!("{bird}.usda"));
        tween_quietly(&fx.join(format!("morph-keyframes/{bird}.glb")), &usd, &[]);
        let r = usd_report(&python, &usd, bird);
        let meta = &r["meta"];
        assert_eq!(
            meta["timeCodesPerSecond"].as_f64(),
            Some(30.0),
            "{bird}: {meta}"
        );
        assert_eq!(meta["framesPerSecond"].as_f64(), Some(30.0), "{bird}");
        for m in r["meshes"].as_array().unwrap() {
            for t in m["times"].as_array().unwrap() {
                let t = t.as_f64().unwrap();
                assert_eq!(t, t.round(), "{bird}: time code {t}");
            }
        }
        assert_eq!(meta["end"].as_f64().unwrap().fract(), 0.0);
    }
}

/// Parrot with its keys moved onto the NTSC grid of 30000/1001 frames a second, three frames
/// apart (as a clip baked at 29.97 stores them), written to `out`.
fn parrot_at_ntsc(parrot: &Path, out: &Path) -> Vec<f32> {
    let (mut json, mut bin) = glb_parts(parrot);
    let input = json["animations"][0]["samplers"][0]["input"]
        .as_u64()
        .unwrap() as usize;
    let acc = json["accessors"][input].clone();
    let n = acc["count"].as_u64().unwrap() as usize;
    let times: Vec<f32> = (0..n)
        .map(|k| (3.0 * k as f64 * 1001.0 / 30000.0) as f32)
        .collect();
    json["accessors"][input]["min"] = serde_json::json!([times[0]]);
    json["accessors"][input]["max"] = serde_json::json!([times[n - 1]]);
    let view = &json["bufferViews"][acc["bufferView"].as_u64().unwrap() as usize];
    let at = view["byteOffset"].as_u64().unwrap_or(0) + acc["byteOffset"].as_u64().unwrap_or(0);
    for (k, t) in times.iter().enumerate() {
        let i = at as usize + 4 * k;
        bin[i..i + 4].copy_from_slice(&t.to_le_bytes());
    }
    write_glb(out, &json, &bin);
    times
}

#[test]
fn ntsc_rates_typed_or_as_fractions_land_on_the_keys() {
    let Some(fx) = fixtures() else { return };
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("parrot_2997.glb");
    let keys = parrot_at_ntsc(&fx.join("morph-keyframes/Parrot.glb"), &input);
    let keyed = played(&input, 0, 0, 0);
    let mut outputs = Vec::new();
    for fps in ["29.97", "30000/1001"] {
        let out = dir.path().join(format!("fps{}.glb", outputs.len()));
        let r = run_ok(&["tween", s(&input), "-o", s(&out), "--fps", fps]);
        let summary = String::from_utf8_lossy(&r.stderr);
        assert!(
            summary.contains("(30000/1001 frames/s over"),
            "{fps}: {summary}"
        );
        let p = played(&out, 0, 0, 0);
        assert_eq!(p.times.len(), 3 * (keys.len() - 1) + 1, "--fps {fps}");
        for (j, t) in p.times.iter().enumerate() {
            assert_eq!(
                *t,
                (j as f64 * 1001.0 / 30000.0) as f32,
                "--fps {fps}: frame {j}"
            );
        }
        // Every key is a frame, posed as the input poses it at its time.
        for (k, pose) in keyed.positions.iter().enumerate() {
            for (a, b) in p.positions[3 * k].iter().zip(pose) {
                for c in 0..3 {
                    assert!(
                        (a[c] - b[c]).abs() <= 1e-4,
                        "--fps {fps}: key {k} {a:?} {b:?}"
                    );
                }
            }
        }
        outputs.push(std::fs::read(&out).unwrap());
    }
    assert!(
        outputs[0] == outputs[1],
        "29.97 and 30000/1001 write the same file"
    );
    // The rate's other spellings: 23.976 is 24000/1001, a plain decimal stays itself.
    let out = dir.path().join("film.glb");
    let r = run_ok(&["tween", s(&input), "-o", s(&out), "--rate", "23.976"]);
    assert!(String::from_utf8_lossy(&r.stderr).contains("24000/1001 frames/s between keys"));
    let r = run_ok(&["tween", s(&input), "-o", s(&out), "--fps", "29.9"]);
    assert!(String::from_utf8_lossy(&r.stderr).contains("(29.9 frames/s over"));
    let r = inbetween(&["tween", s(&input), "-o", s(&out), "--fps", "30000/x"]);
    assert_eq!(r.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&r.stderr).contains("a fraction such as 30000/1001"));
}

#[test]
fn inspect_describes_every_fixture_by_its_schema() {
    let dir = tempfile::tempdir().unwrap();
    let mut files = vec![sample("flag_wave.glb"), sample("bar_twist.glb")];
    let face = face(dir.path(), 30.0);
    files.push(face.clone());
    if let Some(fx) = fixtures() {
        for sub in ["morph-keyframes", "morph-khronos", "skinned"] {
            for f in walk(&fx.join(sub)) {
                if f.extension().is_some_and(|e| e == "glb" || e == "gltf") {
                    files.push(f);
                }
            }
        }
    }
    let python = python();
    for f in &files {
        let out = run_ok(&["inspect", s(f), "--json"]);
        let json = dir.path().join("inspect.json");
        std::fs::write(&json, &out.stdout).unwrap();
        if let Some(py) = &python {
            check_schema(py, "inspect.schema.json", &json, s(f));
        }
        let text = run_ok(&["inspect", s(f)]);
        assert!(
            String::from_utf8_lossy(&text.stdout).contains("blend:"),
            "{}",
            f.display()
        );
    }
    // What the face rig is: 52 targets, a clip of 61 keys on the 30 per second grid, nothing
    // added by tween's defaults.
    let v: serde_json::Value =
        serde_json::from_slice(&run_ok(&["inspect", s(&face), "--json"]).stdout).unwrap();
    assert_eq!(v["morph_meshes"][0]["targets"], 52);
    assert_eq!(v["animations"][0]["keys"], 61);
    assert_eq!(v["animations"][0]["grid"], 30.0);
    assert_eq!(v["tween"]["tracks"][0]["frames"], 61);
    assert_eq!(v["tween"]["tracks"][0]["new_targets"], 0);
}

#[test]
fn a_skinned_file_without_morph_keys_points_at_blend() {
    let Some(fx) = fixtures() else { return };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.glb");
    let fox = fx.join("skinned/Fox.glb");
    assert_refused(
        &["tween", s(&fox), "-o", s(&out)],
        "Fox.glb",
        "`inbetween blend`",
        &out,
    );
    let v: serde_json::Value =
        serde_json::from_slice(&run_ok(&["inspect", s(&fox), "--json"]).stdout).unwrap();
    assert_eq!(v["blend"]["clips"].as_array().unwrap().len(), 3);
    assert!(v["tween"]["refused"]
        .as_str()
        .unwrap()
        .contains("inbetween blend"));
}
