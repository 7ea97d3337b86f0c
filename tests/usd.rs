//! USD point caches: usd-core opens them, its validators pass, metadata and samples are right,
//! and the points equal the glTF output's frames for the same input.

mod common;

use common::*;
use std::path::{Path, PathBuf};

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// (mesh name, primitive index, primitive count, points of every frame)
type GltfPrimitiveFrames = (String, usize, usize, Vec<Vec<[f32; 3]>>);

/// Formats checked (each must open in usd-core).
const FORMATS: &[&str] = &["usda", "usdc", "usdz"];

/// Tween `input` to .glb and to each USD format with `args`; check every USD output against
/// the glTF frames. Returns the number of animated prims checked.
fn check_input(input: &Path, args: &[&str]) -> usize {
    let Some(python) = python() else { return 0 };
    let dir = tempfile::tempdir().unwrap();
    let glb = dir.path().join("out.glb");
    // One target per frame: each target's points are the frame's (base + delta, as the USD).
    let mut a = vec!["tween", s(input), "-o", s(&glb), "-q", "--layout", "frames"];
    a.extend_from_slice(args);
    run_ok(&a);
    let (gdoc, buffers, _) = gltf::import(&glb).unwrap();
    // Processed primitives of the glTF output: (mesh name, primitive index, frames of points).
    let mut gltf_frames: Vec<GltfPrimitiveFrames> = Vec::new();
    for m in gdoc.meshes() {
        let nprims = m.primitives().count();
        for p in m.primitives() {
            let r = p.reader(|b| Some(&buffers[b.index()]));
            let base: Vec<[f32; 3]> = r.read_positions().unwrap().collect();
            let frames: Vec<Vec<[f32; 3]>> = r
                .read_morph_targets()
                .map(|(pos, _, _)| {
                    pos.unwrap()
                        .zip(&base)
                        .map(|(d, b)| [b[0] + d[0], b[1] + d[1], b[2] + d[2]])
                        .collect()
                })
                .collect();
            if !frames.is_empty() {
                let name = m
                    .name()
                    .map(str::to_owned)
                    .unwrap_or_else(|| format!("mesh{}", m.index()));
                gltf_frames.push((name, p.index(), nprims, frames));
            }
        }
    }
    let mut checked = 0;
    for fmt in FORMATS {
        let usd = dir.path().join(format!("out.{fmt}"));
        let mut a = vec!["tween", s(input), "-o", s(&usd), "-q"];
        a.extend_from_slice(args);
        run_ok(&a);
        let dump = dir.path().join("dump.bin");
        let what = input.display().to_string();
        let stdout = run_tool(
            &python,
            "check_usd.py",
            &[usd.as_os_str(), dump.as_os_str()],
            &what,
        );
        let r: serde_json::Value = serde_json::from_slice(&stdout).unwrap();
        assert!(
            r["errors"].as_array().unwrap().is_empty(),
            "{} .{fmt}: {}",
            input.display(),
            r["errors"]
        );
        assert!(
            r["validation"].as_array().unwrap().is_empty(),
            "{} .{fmt}: {}",
            input.display(),
            r["validation"]
        );
        let bytes = std::fs::read(&dump).unwrap();
        let floats: Vec<f32> = bytes
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
            .collect();
        let mut at = 0;
        let animated: Vec<&serde_json::Value> = r["meshes"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|m| !m["static"].as_bool().unwrap())
            .collect();
        assert_eq!(
            animated.len(),
            gltf_frames.len(),
            "{}: animated prims",
            input.display()
        );
        let meta = &r["meta"];
        for m in animated {
            let path = m["path"].as_str().unwrap();
            let leaf = path.rsplit('/').next().unwrap();
            // Match the glTF primitive by name (mesh, or mesh_<index> when it has several).
            let (_, _, _, frames) = gltf_frames
                .iter()
                .find(|(name, pi, n, _)| {
                    let want = if *n == 1 {
                        inbetween::usd::identifier(name)
                    } else {
                        inbetween::usd::identifier(&format!("{name}_{pi}"))
                    };
                    leaf == want || leaf.starts_with(&format!("{want}_"))
                })
                .unwrap_or_else(|| panic!("no glTF primitive for {path}"));
            let samples = m["samples"].as_u64().unwrap() as usize;
            assert_eq!(samples, frames.len(), "{path}: one sample per frame");
            let times: Vec<f64> = m["times"]
                .as_array()
                .unwrap()
                .iter()
                .map(|t| t.as_f64().unwrap())
                .collect();
            assert_eq!(times[0], meta["start"].as_f64().unwrap().max(times[0]));
            assert!(times.windows(2).all(|w| w[1] > w[0]));
            assert!(*times.last().unwrap() <= meta["end"].as_f64().unwrap());
            let n = m["points"].as_u64().unwrap() as usize;
            let all: Vec<[f32; 3]> = frames.iter().flatten().copied().collect();
            let lo = all.iter().fold([f32::MAX; 3], |a, p| {
                [a[0].min(p[0]), a[1].min(p[1]), a[2].min(p[2])]
            });
            let hi = all.iter().fold([f32::MIN; 3], |a, p| {
                [a[0].max(p[0]), a[1].max(p[1]), a[2].max(p[2])]
            });
            let diag = ((hi[0] - lo[0]).powi(2) + (hi[1] - lo[1]).powi(2) + (hi[2] - lo[2]).powi(2))
                .sqrt() as f64;
            for (f, frame) in frames.iter().enumerate() {
                assert_eq!(frame.len(), n);
                for (v, p) in frame.iter().enumerate() {
                    for c in 0..3 {
                        let u = floats[at + (f * n + v) * 3 + c] as f64;
                        assert!(
                            (u - p[c] as f64).abs() <= 1e-6 * diag.max(1e-30),
                            "{path} frame {f} vertex {v}: usd {u} gltf {}",
                            p[c]
                        );
                    }
                }
            }
            at += samples * n * 3;
            checked += 1;
        }
        assert_eq!(at, floats.len());
    }
    // The binary layer holds exactly what the text layer holds.
    let (usda, usdc) = (dir.path().join("out.usda"), dir.path().join("out.usdc"));
    run_tool(
        &python,
        "same_layers.py",
        &[usda.as_os_str(), usdc.as_os_str()],
        &format!("{}: usda and usdc differ", input.display()),
    );
    checked
}

#[test]
fn samples_as_usd_point_caches() {
    for (name, args) in [
        ("bar_twist.glb", &[][..]),
        ("tube_bend.glb", &["--tweens", "9"][..]),
        ("flag_wave.glb", &["--fps", "24"][..]),
    ] {
        check_input(&sample(name), args);
    }
}

#[test]
fn usd_stage_metadata_and_names() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("flag.usda");
    tween_quietly(&sample("flag_wave.glb"), &out, &["--fps", "30"]);
    let text = std::fs::read_to_string(&out).unwrap();
    for line in [
        "defaultPrim = \"samples\"",
        "upAxis = \"Y\"",
        "metersPerUnit = 1",
        "timeCodesPerSecond = 30",
        "framesPerSecond = 30",
        "startTimeCode = 0",
        "endTimeCode = 60",
    ] {
        assert!(text.contains(line), "missing {line}");
    }
    assert!(
        text.contains("def Mesh \"pole\"") && text.contains("point3f[] points = ["),
        "static mesh written once"
    );
    assert!(text.contains("uniform token subdivisionScheme = \"none\""));
    assert!(text.contains("texCoord2f[] primvars:st"));
    assert!(text.contains("primvars:displayColor = [(0.9, 0.1, 0.1)]"));
    assert_eq!(
        inbetween::usd::identifier("1 weird-name.x"),
        "_1_weird_name_x"
    );
}

#[test]
fn fixtures_as_usd_point_caches() {
    let Some(fx) = fixtures() else { return };
    let mut total = 0;
    for f in [
        "morph-keyframes/Flamingo.glb",
        "morph-keyframes/Parrot.glb",
        "morph-keyframes/Flamingo_cubicspline_unindexed.glb",
        "morph-khronos/AnimatedMorphCube/glTF/AnimatedMorphCube.gltf",
        "morph-khronos/MorphPrimitivesTest/glTF/MorphPrimitivesTest.gltf",
        "morph-khronos/SimpleMorph/glTF/SimpleMorph.gltf",
        "morph-khronos/MorphStressTest/glTF/MorphStressTest.gltf",
    ] {
        total += check_input(&fx.join(f), &["--tweens", "2"]);
    }
    if python().is_some() {
        assert!(total >= 7 * FORMATS.len(), "{total}");
    }
}

#[test]
fn bad_output_paths_fail_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let ro = dir.path().join("readonly");
    std::fs::create_dir(&ro).unwrap();
    let mut dirs: Vec<PathBuf> = vec![dir.path().join("missing"), PathBuf::from("/proc")];
    // A directory without write permission (root may still write there: checked only when it
    // really refuses a plain file).
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o500)).unwrap();
    if std::fs::write(ro.join("probe"), b"x").is_err() {
        dirs.push(ro.clone());
    }
    let mut cases: Vec<PathBuf> = vec![dir.path().join("out.usdx")];
    for d in &dirs {
        for ext in ["usda", "usdc", "usdz"] {
            cases.push(d.join(format!("inbetween-test-out.{ext}")));
        }
    }
    for out in cases {
        let r = inbetween(&["tween", s(&sample("bar_twist.glb")), "-o", s(&out)]);
        let err = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{}: {err}", out.display());
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(err.contains(out.to_str().unwrap()), "{err}");
        assert!(!out.exists());
    }
    std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o700)).unwrap();
    let leftovers = std::fs::read_dir(dir.path())
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
        .count();
    assert_eq!(leftovers, 0);
}

#[test]
fn usdc_size_is_close_to_usd_core_resave() {
    let Some(python) = python() else { return };
    let dir = tempfile::tempdir().unwrap();
    let (x0, x1, triangles) = inbetween::bench::bench_keys(16020);
    let surface = inbetween::synth::Surface {
        positions: x0,
        normals: None,
        uvs: None,
        triangles,
    };
    let keys = dir.path().join("keys.glb");
    inbetween::synth::KeyframeFile {
        meshes: vec![inbetween::synth::KeyedMesh::new("tube", surface, vec![x1])],
        key_times: None,
        key_weights: None,
    }
    .write(&keys)
    .unwrap();
    let ours = dir.path().join("cache.usdc");
    tween_quietly(&keys, &ours, &["--tweens", "98"]); // 100 frames
    let resaved = dir.path().join("resaved.usdc");
    let script =
        "import sys\nfrom pxr import Sdf\nSdf.Layer.FindOrOpen(sys.argv[1]).Export(sys.argv[2])\n";
    let out = std::process::Command::new(&python)
        .args(["-c", script])
        .arg(&ours)
        .arg(&resaved)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let a = std::fs::metadata(&ours).unwrap().len() as f64;
    let b = std::fs::metadata(&resaved).unwrap().len() as f64;
    eprintln!("100-frame cache of 16,020 triangles: ours {a} bytes, usd-core re-save {b} bytes, ratio {:.3}", a / b);
    assert!(a <= 1.5 * b, "ratio {}", a / b);
}

/// COLOR_0 becomes a per-vertex `primvars:displayColor` (issue 19): Flamingo and Parrot (float
/// RGB colours), and a copy of Flamingo whose colours are normalized unsigned-byte RGBA with
/// alpha, in every USD format; the colours equal the glTF's within 1/255, the alpha becomes
/// `primvars:displayOpacity`. usd-core reads them (the validators run in
/// `fixtures_as_usd_point_caches`).
#[test]
fn vertex_colours_become_display_colours() {
    let Some(fx) = fixtures() else { return };
    let Some(python) = python() else {
        missing_tool("python with usd-core (.venv)");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    // Flamingo's colours as UNSIGNED_BYTE normalized RGBA, alpha falling over the vertices.
    let rgba = dir.path().join("rgba.glb");
    let doc = inbetween::gltf::Document::open(&fx.join("morph-keyframes/Flamingo.glb")).unwrap();
    let acc = doc.json["meshes"][0]["primitives"][0]["attributes"]["COLOR_0"]
        .as_u64()
        .unwrap() as usize;
    let (colors, comps) = doc.read_f64(acc).unwrap();
    let n = colors.len() / comps;
    let mut json = doc.json.clone();
    let bin = doc.buffers[0].clone();
    let mut bytes = bin.clone();
    while !bytes.len().is_multiple_of(4) {
        bytes.push(0);
    }
    let offset = bytes.len();
    for v in 0..n {
        for c in 0..3 {
            bytes.push((colors[v * comps + c] * 255.0).round() as u8);
        }
        bytes.push((255 * v / n.max(1)) as u8);
    }
    json["bufferViews"].as_array_mut().unwrap().push(serde_json::json!({"buffer": 0, "byteOffset": offset, "byteLength": 4 * n, "byteStride": 4}));
    let view = json["bufferViews"].as_array().unwrap().len() - 1;
    json["accessors"].as_array_mut().unwrap().push(serde_json::json!({"bufferView": view, "componentType": 5121, "normalized": true, "count": n, "type": "VEC4"}));
    let new = json["accessors"].as_array().unwrap().len() - 1;
    json["meshes"][0]["primitives"][0]["attributes"]["COLOR_0"] = serde_json::json!(new);
    json["buffers"][0]["byteLength"] = serde_json::json!(bytes.len());
    write_glb(&rgba, &json, &bytes);
    for input in [
        fx.join("morph-keyframes/Flamingo.glb"),
        fx.join("morph-keyframes/Parrot.glb"),
        rgba,
    ] {
        let doc = inbetween::gltf::Document::open(&input).unwrap();
        let acc = doc.json["meshes"][0]["primitives"][0]["attributes"]["COLOR_0"]
            .as_u64()
            .unwrap() as usize;
        let (want, comps) = doc.read_f64(acc).unwrap();
        for fmt in FORMATS {
            let usd = dir.path().join(format!("c.{fmt}"));
            tween_quietly(&input, &usd, &["--tweens", "1"]);
            let out = run_tool(
                &python,
                "usd_colors.py",
                &[usd.as_os_str()],
                &input.display().to_string(),
            );
            let meshes: serde_json::Value = serde_json::from_slice(&out).unwrap();
            let m = &meshes[0];
            assert_eq!(m["interpolation"], "vertex", "{} .{fmt}", input.display());
            let got = m["color"].as_array().unwrap();
            assert_eq!(got.len() * comps, want.len());
            let worst = got
                .iter()
                .enumerate()
                .flat_map(|(v, c)| (0..3).map(move |k| (v, k, c[k].as_f64().unwrap())))
                .map(|(v, k, x)| (x - want[v * comps + k]).abs())
                .fold(0.0, f64::max);
            assert!(
                worst <= 1.0 / 255.0,
                "{} .{fmt}: colours off by {worst}",
                input.display()
            );
            if comps == 4 {
                assert_eq!(m["opacity_interpolation"], "vertex");
                let alpha = m["opacity"].as_array().unwrap();
                let worst = alpha
                    .iter()
                    .enumerate()
                    .map(|(v, a)| (a.as_f64().unwrap() - want[v * 4 + 3]).abs())
                    .fold(0.0, f64::max);
                assert!(
                    worst <= 1.0 / 255.0,
                    "{} .{fmt}: alpha off by {worst}",
                    input.display()
                );
            } else {
                assert!(m["opacity"].is_null());
            }
        }
    }
}
