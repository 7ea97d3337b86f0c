//! Files from strangers: a file reads only what belongs to it (external references stay in its
//! folder), malformed values are refused with one line instead of a panic or an abort (one
//! regression test per crash found by mutation), and every output of a run appears together
//! or not at all, also when the report cannot be written or the disk fills up.

mod common;

use common::*;
use serde_json::json;
use std::path::{Path, PathBuf};
use std::process::Command;

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

const SECRET: &[u8] = b"TOP-SECRET-0123456789-TOP-SECRET-0123456789-TOP-SECRET-012345678";

/// A `.gltf` morph file with an external buffer in `dir/model`, and a secret file in
/// `dir/secret`; returns (the model's JSON, the model folder, the secret file).
fn model_and_secret(dir: &Path) -> (serde_json::Value, PathBuf, PathBuf) {
    let model = dir.join("model");
    let secret_dir = dir.join("secret");
    std::fs::create_dir_all(&secret_dir).unwrap();
    std::fs::create_dir_all(&model).unwrap();
    let secret = secret_dir.join("secret.bin");
    std::fs::write(&secret, SECRET).unwrap();
    // A .png that is only a PNG by its first bytes, the secret after them.
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    png.extend_from_slice(SECRET);
    std::fs::write(secret_dir.join("secret.png"), &png).unwrap();
    tween_quietly(&sample("bar_twist.glb"), &model.join("base.gltf"), &[]);
    let json = read_json(model.join("base.gltf"));
    (json, model, secret)
}

/// No file under `dir` but the inputs holds the secret's bytes.
fn assert_no_leak(dir: &Path, inputs: &[PathBuf]) {
    for e in walk(dir) {
        if inputs.contains(&e) || e.starts_with(dir.join("secret")) {
            continue;
        }
        let bytes = std::fs::read(&e).unwrap_or_default();
        assert!(
            !bytes.windows(16).any(|w| w == &SECRET[..16]),
            "{} holds the secret",
            e.display()
        );
    }
}

#[test]
fn external_references_stay_inside_the_input_folder() {
    let dir = tempfile::tempdir().unwrap();
    let (json, model, secret) = model_and_secret(dir.path());
    std::os::unix::fs::symlink("../secret/secret.bin", model.join("leak.bin")).unwrap();
    std::os::unix::fs::symlink("../secret/secret.png", model.join("leak.png")).unwrap();
    std::os::unix::fs::symlink("/dev/zero", model.join("zero.bin")).unwrap();
    std::fs::create_dir(model.join("folder.bin")).unwrap();
    let abs = s(&secret).to_string();
    let out = dir.path().join("out.glb");
    let mut inputs = Vec::new();
    let bad_uris = [
        (abs.clone(), "absolute path"),
        ("../secret/secret.bin".into(), "climbs out"),
        (format!("file://{abs}"), "absolute URI"),
        ("leak.bin".into(), "leads outside"),
        ("/dev/zero".into(), "absolute path"),
        ("zero.bin".into(), "leads outside"),
        ("folder.bin".into(), "not a regular file"),
        ("%2e%2e/secret/secret.bin".into(), "climbs out"),
    ];
    for (k, (uri, why)) in bad_uris.iter().enumerate() {
        // As the buffer ...
        let mut j = json.clone();
        j["buffers"][0]["uri"] = json!(uri);
        let input = model.join(format!("buffer{k}.gltf"));
        std::fs::write(&input, serde_json::to_vec(&j).unwrap()).unwrap();
        assert_refused(&["tween", s(&input), "-o", s(&out)], uri, why, &out);
        inputs.push(input);
        // ... and as an image, read to be embedded in a .glb.
        let mut j = json.clone();
        j["images"] = json!([{ "uri": uri.replace("secret.bin", "secret.png").replace("leak.bin", "leak.png") }]);
        let input = model.join(format!("image{k}.gltf"));
        std::fs::write(&input, serde_json::to_vec(&j).unwrap()).unwrap();
        let r = inbetween(&["tween", s(&input), "-o", s(&out)]);
        let err = String::from_utf8_lossy(&r.stderr);
        if *why == "not a regular file" {
            // Not read either: an image that cannot be read stays the reference it was.
            assert_eq!(r.status.code(), Some(0), "image {uri}: {err}");
            assert!(
                err.contains("is not a regular file; left as a reference"),
                "{err}"
            );
            std::fs::remove_file(&out).unwrap();
        } else {
            assert_eq!(r.status.code(), Some(2), "image {uri}: {err}");
            assert!(
                err.contains("image 0 uri") && !out.exists(),
                "image {uri}: {err}"
            );
        }
        inputs.push(input);
    }
    // A buffer is read up to its byteLength and refused when its file is shorter.
    let bin = model.join("base.bin");
    let mut padded = std::fs::read(&bin).unwrap();
    let declared = padded.len();
    padded.extend_from_slice(SECRET);
    std::fs::write(&bin, &padded).unwrap();
    tween_quietly(&model.join("base.gltf"), &out, &[]);
    inputs.push(bin.clone());
    assert_no_leak(dir.path(), &inputs);
    std::fs::write(&bin, &padded[..declared - 4]).unwrap();
    let out2 = dir.path().join("short.glb");
    assert_refused(
        &["tween", s(&model.join("base.gltf")), "-o", s(&out2)],
        "base.bin",
        "fewer than",
        &out2,
    );
    std::fs::write(&bin, &padded[..declared]).unwrap();
    // --allow-external opens other folders, and only those.
    let mut j = json.clone();
    j["images"] = json!([{ "uri": "../secret/secret.png" }, { "uri": "leak.png" }]);
    let input = model.join("allowed.gltf");
    std::fs::write(&input, serde_json::to_vec(&j).unwrap()).unwrap();
    let secret_dir = dir.path().join("secret");
    let gltf_out = dir.path().join("elsewhere/allowed.gltf");
    std::fs::create_dir_all(gltf_out.parent().unwrap()).unwrap();
    run_ok(&[
        "tween",
        s(&input),
        "-o",
        s(&gltf_out),
        "-q",
        "--allow-external",
        s(&secret_dir),
    ]);
    // Both copies beside the output under their own names, never outside its folder.
    let copied = std::fs::read_dir(gltf_out.parent().unwrap())
        .unwrap()
        .count();
    assert_eq!(copied, 4, "allowed.gltf, allowed.bin and two images");
    let written: serde_json::Value = read_json(&gltf_out);
    assert_eq!(written["images"][0]["uri"], "secret.png");
    assert_eq!(written["images"][1]["uri"], "leak.png");
    let other = dir.path().join("other");
    std::fs::create_dir_all(&other).unwrap();
    let refused = dir.path().join("refused.glb");
    assert_refused(
        &[
            "tween",
            s(&input),
            "-o",
            s(&refused),
            "--allow-external",
            s(&other),
        ],
        "../secret/secret.png",
        "leads outside",
        &refused,
    );
    assert!(temporaries(dir.path()).is_empty());
}

/// Fox with its JSON edited; `None` without the fixtures.
fn fox() -> Option<PathBuf> {
    fixtures().map(|f| f.join("skinned/Fox.glb"))
}

/// The accessors of Fox's "Walk" channels on `path` (input, output).
fn walk_sampler(path: &str) -> (usize, usize) {
    let doc = inbetween::gltf::Document::open(&fox().unwrap()).unwrap();
    let anim = doc.json["animations"]
        .as_array()
        .unwrap()
        .iter()
        .find(|a| a["name"] == "Walk")
        .unwrap()
        .clone();
    let ch = anim["channels"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["target"]["path"] == path)
        .unwrap()
        .clone();
    let s = &anim["samplers"][ch["sampler"].as_u64().unwrap() as usize];
    (
        s["input"].as_u64().unwrap() as usize,
        s["output"].as_u64().unwrap() as usize,
    )
}

#[test]
fn each_crash_found_by_mutation_is_a_clean_refusal() {
    let dir = tempfile::tempdir().unwrap();
    let p = |n: &str| dir.path().join(n);
    let out = p("out.glb");
    let tween = |input: &Path, what: &str| {
        assert_refused(&["tween", s(input), "-o", s(&out)], s(input), what, &out)
    };
    // 3. An accessor claiming 4294967295 elements (tween: positions).
    edited_glb(&sample("bar_twist.glb"), &p("count.glb"), |j| {
        let acc = j["meshes"][0]["primitives"][0]["attributes"]["POSITION"]
            .as_u64()
            .unwrap() as usize;
        j["accessors"][acc]["count"] = json!(4294967295u64);
    });
    tween(&p("count.glb"), "reads past the end");
    // ... and without a buffer view, where nothing backs it.
    edited_glb(&sample("bar_twist.glb"), &p("unbacked.glb"), |j| {
        let acc = j["meshes"][0]["primitives"][0]["targets"][0]["POSITION"]
            .as_u64()
            .unwrap() as usize;
        j["accessors"][acc]["count"] = json!(4294967295u64);
        j["accessors"][acc]
            .as_object_mut()
            .unwrap()
            .remove("bufferView");
    });
    tween(&p("unbacked.glb"), "more than any accessor the file holds");
    // 5. A NORMAL accessor shorter than POSITION.
    edited_glb(&sample("flag_wave.glb"), &p("normals.glb"), |j| {
        let acc = j["meshes"][0]["primitives"][0]["attributes"]["NORMAL"]
            .as_u64()
            .unwrap() as usize;
        let n = j["accessors"][acc]["count"].as_u64().unwrap();
        j["accessors"][acc]["count"] = json!(n - 1);
    });
    tween(&p("normals.glb"), "NORMAL");
    // 7. A buffer view that is not an object.
    edited_glb(&sample("bar_twist.glb"), &p("view.glb"), |j| {
        j["bufferViews"][0] = json!(7);
    });
    tween(&p("view.glb"), "bufferViews[0] is not an object");
    let Some(fox) = fox() else { return };
    let blend = |input: &Path, what: &str| {
        assert_refused(
            &["blend", s(input), "-o", s(&out), "--clips", "Walk", "Run"],
            s(input),
            what,
            &out,
        )
    };
    let (times, rotations) = walk_sampler("rotation");
    // 1. A rotation accessor without its buffer view: every key a zero quaternion. (An
    // infinite or NaN key among defined ones is left out, its neighbours played across:
    // `cli::undefined_keys_are_left_out`.)
    edited_glb(&fox, &p("noview.glb"), |j| {
        j["accessors"][rotations]
            .as_object_mut()
            .unwrap()
            .remove("bufferView");
    });
    blend(&p("noview.glb"), "not a unit quaternion");
    // 2. Key times in decreasing order.
    let f = p("decreasing.glb");
    poke_f32(&fox, &f, times, 1, 0, -5.0);
    blend(&f, "key times of accessor 27 decrease");
    // 4. A key time of 1e30.
    let doc = inbetween::gltf::Document::open(&fox).unwrap();
    let last = doc.json["accessors"][times]["count"].as_u64().unwrap() as usize - 1;
    let f = p("late.glb");
    poke_f32(&fox, &f, times, last, 0, 1e30);
    blend(&f, "samples to analyse");
    // 3 again, on the blend path.
    edited_glb(&fox, &p("foxcount.glb"), |j| {
        j["accessors"][times]["count"] = json!(4294967295u64);
    });
    blend(&p("foxcount.glb"), "reads past the end");
    assert!(temporaries(dir.path()).is_empty());
}

/// Run inbetween in `sh` with `prefix` (ulimit and trap lines) first.
fn run_in_shell(prefix: &str, args: &[&str]) -> std::process::Output {
    Command::new("sh")
        .arg("-c")
        .arg(format!("{prefix} exec \"$0\" \"$@\""))
        .arg(env!("CARGO_BIN_EXE_inbetween"))
        .args(args)
        .output()
        .unwrap()
}

/// [`run_in_shell`], insisting on a refusal: exit 2, one line saying each of `what`, `out` not
/// written and no temporary left beside it.
fn refused_in_shell(prefix: &str, args: &[&str], what: &[&str], out: &Path) {
    let r = run_in_shell(prefix, args);
    let err = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(2), "{args:?}: {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
    assert!(
        what.iter().all(|w| err.contains(w)),
        "{args:?}: {what:?} in {err}"
    );
    let folder = out.parent().expect("a folder");
    assert!(!out.exists() && temporaries(folder).is_empty(), "{args:?}");
}

/// [`run_in_shell`], insisting on success (its error output shown otherwise).
fn succeeds_in_shell(prefix: &str, args: &[&str]) {
    let r = run_in_shell(prefix, args);
    let err = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(0), "{args:?}: {err}");
}

#[test]
fn outputs_appear_together_or_not_at_all() {
    let dir = tempfile::tempdir().unwrap();
    let input = sample("flag_wave.glb");
    std::fs::create_dir(dir.path().join("a-folder.json")).unwrap();
    for ext in ["glb", "gltf", "usda", "usdc", "usdz"] {
        let out = dir.path().join(format!("out.{ext}"));
        // The report cannot be written: its folder is missing, or a folder is in its place.
        for report in ["missing/r.json", "a-folder.json"] {
            let report = dir.path().join(report);
            assert_refused(
                &["tween", s(&input), "-o", s(&out), "--report", s(&report)],
                s(&report),
                "cannot write",
                &out,
            );
            assert!(!dir.path().join("out.bin").exists(), "{ext}: no .bin");
        }
        // The disk fills up (a file-size limit of 64 KiB; SIGXFSZ ignored, so the write fails).
        let r = run_in_shell(
            "trap '' XFSZ; ulimit -f 64;",
            &["tween", s(&input), "-o", s(&out), "--tweens", "40", "-q"],
        );
        let err = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{ext}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{ext}: {err}");
        assert!(
            err.contains("cannot write") && err.contains("out."),
            "{ext}: {err}"
        );
        assert!(
            !out.exists() && !dir.path().join("out.bin").exists(),
            "{ext}"
        );
        assert!(
            temporaries(dir.path()).is_empty(),
            "{ext}: temporaries left"
        );
    }
    // blend: the same for its report.
    if let Some(fox) = fox() {
        let out = dir.path().join("fox.glb");
        let report = dir.path().join("a-folder.json");
        assert_refused(
            &[
                "blend",
                s(&fox),
                "-o",
                s(&out),
                "--clips",
                "Walk",
                "Run",
                "--report",
                s(&report),
            ],
            "a-folder.json",
            "cannot write",
            &out,
        );
    }
}

#[test]
fn temporaries_of_a_killed_run_are_removed_by_the_next() {
    let dir = tempfile::tempdir().unwrap();
    // What a run killed while writing out.usda leaves: its file and spools, under a process
    // id that no longer runs; a file of a live process (this one) and others stay.
    let dead = "999999999";
    let names = [
        format!(".out.usda.inbetween-{dead}.tmp"),
        format!(".out.usda.inbetween-{dead}.0_0_2.tmp"),
    ];
    for n in &names {
        std::fs::write(dir.path().join(n), b"partial").unwrap();
    }
    let live = format!(".out.usda.inbetween-{}.tmp", std::process::id());
    std::fs::write(dir.path().join(&live), b"in use").unwrap();
    std::fs::write(dir.path().join("keep.tmp"), b"not ours").unwrap();
    let out = dir.path().join("out.usda");
    tween_quietly(&sample("bar_twist.glb"), &out, &[]);
    for n in &names {
        assert!(!dir.path().join(n).exists(), "{n} left");
    }
    assert!(dir.path().join(&live).exists() && dir.path().join("keep.tmp").exists());
    // A real kill in the middle of a long write: the next run at that path cleans up.
    let big = dir.path().join("big.glb");
    let (x0, x1, triangles) = inbetween::bench::bench_keys(100_000);
    let surface = inbetween::synth::Surface {
        positions: x0,
        triangles,
        ..Default::default()
    };
    inbetween::synth::KeyframeFile {
        meshes: vec![inbetween::synth::KeyedMesh::new("tube", surface, vec![x1])],
        key_times: None,
        key_weights: None,
    }
    .write(&big)
    .unwrap();
    let out = dir.path().join("killed.usda");
    let mut child = Command::new(env!("CARGO_BIN_EXE_inbetween"))
        .args(["tween", s(&big), "-o", s(&out), "--tweens", "200", "-q"])
        .spawn()
        .unwrap();
    // Wait until it has begun writing, then kill it.
    let started = std::time::Instant::now();
    while temporaries(dir.path())
        .iter()
        .all(|t| !t.to_string_lossy().contains("killed"))
        && started.elapsed().as_secs() < 60
    {
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let left: Vec<PathBuf> = temporaries(dir.path())
        .into_iter()
        .filter(|t| t.to_string_lossy().contains("killed"))
        .collect();
    assert!(!left.is_empty(), "the killed run had begun writing");
    tween_quietly(&sample("bar_twist.glb"), &out, &[]);
    for t in &left {
        assert!(!t.exists(), "{} left after the next run", t.display());
    }
}

/// `meshes` one-triangle meshes (one node each) with two targets, whose weights `clips`
/// animations each key three times (0, 1 and 2 s), as a GLB.
fn triangles_animated(path: &Path, meshes: usize, clips: usize) {
    let floats: [f32; 36] = [
        0., 0., 0., 1., 0., 0., 0., 1., 0., // base
        0., 0., 0., 0., 0., 0., 0., 0., 1., // target 0
        0., 0., 0., 0., 0., 1., 0., 0., 0., // target 1
        0., 1., 2., // times
        0., 0., 1., 0., 0., 1., // weights
    ];
    let bin: Vec<u8> = floats.iter().flat_map(|x| x.to_le_bytes()).collect();
    let view =
        |offset: usize, len: usize| json!({"buffer": 0, "byteOffset": offset, "byteLength": len});
    let vec3 = |view: usize| json!({"bufferView": view, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 1]});
    let mesh = json!({"primitives": [{"attributes": {"POSITION": 0},
        "targets": [{"POSITION": 1}, {"POSITION": 2}]}], "weights": [0, 0]});
    let json = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": (0..meshes).collect::<Vec<_>>()}],
        "nodes": (0..meshes).map(|m| json!({"mesh": m})).collect::<Vec<_>>(),
        "meshes": vec![mesh; meshes],
        "accessors": [vec3(0), vec3(1), vec3(2),
            {"bufferView": 3, "componentType": 5126, "count": 3, "type": "SCALAR", "min": [0], "max": [2]},
            {"bufferView": 4, "componentType": 5126, "count": 6, "type": "SCALAR"}],
        "bufferViews": [view(0, 36), view(36, 36), view(72, 36), view(108, 12), view(120, 24)],
        "buffers": [{"byteLength": bin.len()}],
        "animations": (0..clips).map(|i| json!({"name": format!("clip {i}"),
            "channels": (0..meshes).map(|m| json!({"sampler": 0, "target": {"node": m, "path": "weights"}})).collect::<Vec<_>>(),
            "samplers": [{"input": 3, "output": 4}]})).collect::<Vec<_>>(),
    });
    write_glb(path, &json, &bin);
}

#[test]
fn a_mesh_animated_by_many_clips_is_refused_before_its_weights_fill_memory() {
    // Each of n clips tweens to about 62 frames, and the mesh takes a target for every frame
    // of every clip, so each clip's weights animation has 62 n weights a key: 400 clips make
    // 24,800 keys of 24,800 weights, about 7 GiB (the vertices are nothing). Refused in a
    // line under a 2 GiB address-space limit instead of failing an allocation.
    let dir = tempfile::tempdir().unwrap();
    let (many, few) = (dir.path().join("many.glb"), dir.path().join("few.glb"));
    triangles_animated(&many, 1, 400);
    triangles_animated(&few, 1, 20);
    let out = dir.path().join("out.glb");
    let limit = "ulimit -v 2097152;";
    let args = ["tween", s(&many), "-o", s(&out), "-q"];
    let refusal = ["many.glb", "their weights need", "--compact"];
    refused_in_shell(limit, &args, &refusal, &out);
    // Compacted, the weights are a few a key (a basis no larger than the frames' rank, taken
    // from their covariance: 24,800 frames of 9 values): written, every clip kept.
    let args = ["tween", s(&many), "-o", s(&out), "--compact", "-q"];
    succeeds_in_shell(limit, &args);
    let doc = inbetween::gltf::Document::open(&out).unwrap();
    assert_eq!(doc.json["animations"].as_array().unwrap().len(), 400);
    std::fs::remove_file(&out).unwrap();
    // A USD point cache has no weights: it streams.
    let usd = dir.path().join("out.usdc");
    succeeds_in_shell(limit, &["tween", s(&many), "-o", s(&usd), "-q"]);
    // 20 clips (3 MiB of weights) go through under the same limit, every clip kept.
    succeeds_in_shell(limit, &["tween", s(&few), "-o", s(&out), "-q"]);
    let doc = inbetween::gltf::Document::open(&out).unwrap();
    assert_eq!(doc.json["animations"].as_array().unwrap().len(), 20);
}

#[test]
fn a_refusal_lists_a_few_of_the_file_s_names_not_all() {
    // 400 clips: the line names the first eight and counts the rest (it was one name each).
    let dir = tempfile::tempdir().unwrap();
    let many = dir.path().join("many.glb");
    triangles_animated(&many, 1, 400);
    let out = dir.path().join("out.glb");
    assert_refused(
        &["tween", s(&many), "-o", s(&out), "--animation", "nope"],
        "many.glb",
        "\"clip 7\", ... 392 more)",
        &out,
    );
}

#[test]
fn a_stage_of_many_animated_meshes_is_written_under_the_usual_open_file_limit() {
    // 600 animated meshes to .usda under `ulimit -n 256`: their samples are spooled to one
    // scratch file (one file per attribute failed with "Too many open files"); every mesh's
    // points are sampled, and no scratch file is left.
    let dir = tempfile::tempdir().unwrap();
    let many = dir.path().join("many.glb");
    triangles_animated(&many, 600, 1);
    let out = dir.path().join("out.usda");
    succeeds_in_shell("ulimit -n 256;", &["tween", s(&many), "-o", s(&out), "-q"]);
    let text = std::fs::read_to_string(&out).unwrap();
    assert_eq!(text.matches("point3f[] points.timeSamples").count(), 600);
    assert!(temporaries(dir.path()).is_empty());
}

#[test]
fn a_long_baked_face_rig_is_written_in_little_memory() {
    // Two minutes of a 52-shape face rig baked at 60 keys/s (7,201 keys of 1,681 vertices),
    // under a 1 GiB address-space limit. Every frame lies on a key at the default 30 frames/s
    // between keys: the glTF keeps the file's targets and weights as they are, and the USD
    // point cache streams the keys' poses. Every key's pose and normals were held at once
    // (1.2 GiB: the USD run failed an allocation, the glTF was refused for memory) and every
    // key was solved (7,200 segments set up for no frame between keys).
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("face.glb");
    inbetween::synth::face_rig(52, 60.0, 120.0)
        .write(&input)
        .unwrap();
    let limit = "ulimit -v 1048576;";
    let glb = dir.path().join("out.glb");
    succeeds_in_shell(limit, &["tween", s(&input), "-o", s(&glb), "-q"]);
    let weights = |path: &Path| {
        let doc = inbetween::gltf::Document::open(path).unwrap();
        let targets = doc.json["meshes"][0]["primitives"][0]["targets"]
            .as_array()
            .unwrap()
            .len();
        let sampler = &doc.json["animations"][0]["samplers"][0];
        let read = |key: &str| {
            doc.read_f64(sampler[key].as_u64().unwrap() as usize)
                .unwrap()
                .0
        };
        (targets, read("input"), read("output"))
    };
    let (targets, times, played) = weights(&glb);
    assert_eq!(targets, 52);
    assert_eq!(times.len(), 7201);
    let (_, key_times, key_weights) = weights(&input);
    assert_eq!((times, played), (key_times, key_weights));
    // So the output is the input's size, as `inspect` says beforehand: the weights animation is
    // written anew in place of the one read, not beside it (it said 1.5 MB added to the 2.7 MB file).
    let size = |path: &Path| std::fs::metadata(path).unwrap().len() as f64;
    let grown = size(&glb) - size(&input);
    assert!(grown.abs() < 1e-3 * size(&input), "{grown} bytes");
    let said = inbetween(&["inspect", "--json", s(&input)]);
    let said: serde_json::Value = serde_json::from_slice(&said.stdout).unwrap();
    let added = &said["tween"]["tracks"][0]["added_bytes"];
    assert!(added.as_f64().unwrap() < 1e-3 * size(&input), "{said}");
    let usd = dir.path().join("out.usdc");
    let r = run_in_shell(limit, &["tween", s(&input), "-o", s(&usd)]);
    let err = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(0), "{err}");
    // Every key's points, 12 bytes a vertex (and its normals beside them).
    let size = std::fs::metadata(&usd).unwrap().len();
    assert!(size > 7201 * 1681 * 12, "{size}");
    // A few keys held at a time, also where segments are solved side by side (runs of them
    // holding every key they read: 498 MB, until a run was bounded to a few segments a
    // thread). The summary tells the peak.
    let peak = summary_peak_mib(&err);
    assert!(peak < 150.0, "peak {peak} MiB: {err}");
}
