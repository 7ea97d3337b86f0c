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

/// Mesh `prim` of `usd` in world space at each of its samples (tools/usd_world_points.py).
fn world_points(python: &Path, usd: &Path, prim: &str, what: &str) -> serde_json::Value {
    let out = run_tool(
        python,
        "usd_world_points.py",
        &[usd.as_os_str(), prim.as_ref()],
        what,
    );
    serde_json::from_slice(&out).unwrap()
}

/// Blender's import of glTF `glb`: its character's skinned points at each of `seconds`,
/// playing `action` (tools/bpy_skinned_points.py).
fn blender_points(
    bpy: &Path,
    glb: &Path,
    action: Option<&str>,
    seconds: &[String],
) -> serde_json::Value {
    let mut args = vec![glb.as_os_str()];
    if let Some(a) = action {
        args.extend([std::ffi::OsStr::new("--action"), std::ffi::OsStr::new(a)]);
    }
    args.extend(seconds.iter().map(std::ffi::OsStr::new));
    bpy_result(
        bpy,
        "bpy_skinned_points.py",
        &args,
        "blender",
        "BPY_POINTS ",
    )
}

/// The largest difference of any coordinate between two lists of points (JSON), which must
/// be as long.
fn farthest(a: &serde_json::Value, b: &serde_json::Value) -> f64 {
    let (a, b) = (a.as_array().unwrap(), b.as_array().unwrap());
    assert_eq!(a.len(), b.len(), "point counts");
    (a.iter().zip(b))
        .flat_map(|(p, q)| {
            (0..3).map(move |c| (p[c].as_f64().unwrap() - q[c].as_f64().unwrap()).abs())
        })
        .fold(0.0f64, f64::max)
}

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
        let r = clean_usd_report(&python, &usd, &format!("{} .{fmt}", input.display()));
        let bytes = std::fs::read(usd.with_file_name("dump.bin")).unwrap();
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

/// MorphPrimitivesTest made to use every material feature the USD writer carries: images in
/// buffer views of a .glb, a clamp/mirror sampler, KHR_texture_transform on the base colour,
/// metallic-roughness, normal (scale 0.5, which USD cannot carry), occlusion (strength 0.7) and emissive textures
/// (KHR_materials_emissive_strength 2), alpha MASK at 0.3; its second material's base colour
/// is a texture with only a KTX2 source (KHR_texture_basisu), which USD cannot read; a third
/// material is used by no primitive.
fn every_material_feature(fx: &Path, out: &Path) {
    let input = fx.join("morph-khronos/MorphPrimitivesTest/glTF/MorphPrimitivesTest.gltf");
    let doc = inbetween::gltf::Document::open(&input).unwrap();
    let mut json = doc.json.clone();
    let mut bin = doc.buffers[0].clone();
    let mut push_view = |json: &mut serde_json::Value, data: &[u8]| {
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        let v = serde_json::json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": data.len()});
        bin.extend_from_slice(data);
        let views = json["bufferViews"].as_array_mut().unwrap();
        views.push(v);
        views.len() - 1
    };
    let jpeg = doc.image(0).unwrap().0;
    let mut ktx2 = b"\xABKTX 20\xBB\r\n\x1a\n".to_vec();
    ktx2.resize(64, 0);
    let jpeg_view = push_view(&mut json, &jpeg);
    let ktx2_view = push_view(&mut json, &ktx2);
    json["buffers"] = serde_json::json!([{"byteLength": bin.len()}]);
    json["images"] = serde_json::json!([
        {"bufferView": jpeg_view, "mimeType": "image/jpeg", "name": "grid"},
        {"bufferView": ktx2_view, "mimeType": "image/ktx2", "name": "compressed"}
    ]);
    json["samplers"] = serde_json::json!([{"wrapS": 33071, "wrapT": 33648}]);
    json["textures"] = serde_json::json!([
        {"sampler": 0, "source": 0},
        {"extensions": {"KHR_texture_basisu": {"source": 1}}}
    ]);
    json["extensionsUsed"] = serde_json::json!([
        "KHR_texture_transform",
        "KHR_texture_basisu",
        "KHR_materials_emissive_strength",
        "KHR_materials_clearcoat",
        "KHR_materials_ior",
        "KHR_materials_sheen"
    ]);
    json["materials"][0] = serde_json::json!({
        "name": "red",
        "pbrMetallicRoughness": {
            "baseColorFactor": [1, 0.5, 0.25, 0.8],
            "baseColorTexture": {"index": 0, "extensions": {"KHR_texture_transform":
                {"offset": [0.1, 0.2], "rotation": 0.3, "scale": [2, 3]}}},
            "metallicRoughnessTexture": {"index": 0},
            "metallicFactor": 0.2, "roughnessFactor": 0.9
        },
        "normalTexture": {"index": 0, "scale": 0.5},
        "occlusionTexture": {"index": 0, "strength": 0.7},
        "emissiveTexture": {"index": 0},
        "emissiveFactor": [0.5, 0.25, 1],
        "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 2},
            "KHR_materials_clearcoat": {"clearcoatFactor": 0.8, "clearcoatRoughnessFactor": 0.25,
                "clearcoatRoughnessTexture": {"index": 0}},
            "KHR_materials_ior": {"ior": 1.4},
            "KHR_materials_sheen": {"sheenColorFactor": [1, 1, 1]}},
        "alphaMode": "MASK", "alphaCutoff": 0.3
    });
    json["materials"][1]["pbrMetallicRoughness"]["baseColorTexture"] =
        serde_json::json!({"index": 1});
    json["materials"][1]["alphaMode"] = serde_json::json!("BLEND");
    // A material no primitive uses: written all the same.
    json["materials"]
        .as_array_mut()
        .unwrap()
        .push(serde_json::json!({"name": "unused", "emissiveFactor": [1, 1, 0]}));
    // Material variants choosing it or the first (USD: the root prim's variant set).
    json["extensionsUsed"]
        .as_array_mut()
        .unwrap()
        .push("KHR_materials_variants".into());
    json["extensions"] = serde_json::json!({"KHR_materials_variants":
        {"variants": [{"name": "day"}, {"name": "night"}]}});
    let unused = json["materials"].as_array().unwrap().len() - 1;
    json["meshes"][0]["primitives"][0]["extensions"] = serde_json::json!({"KHR_materials_variants":
        {"mappings": [{"material": 0, "variants": [0]}, {"material": unused, "variants": [1]}]}});
    write_glb(out, &json, &bin);
}

/// `tools/usd_looks.py`'s dump of USD file `file`, whose validation by usd-core must be clean.
fn clean_looks(python: &Path, file: &Path, what: &str) -> serde_json::Value {
    let out = run_tool(python, "usd_looks.py", &[file.as_os_str()], what);
    let looks: serde_json::Value = serde_json::from_slice(&out).unwrap();
    assert_eq!(looks["validation"], serde_json::json!([]), "{what}");
    looks
}

/// The shader at `path` in a usd_looks.py dump.
fn shader<'a>(looks: &'a serde_json::Value, path: &str) -> &'a serde_json::Value {
    looks["shaders"]
        .as_array()
        .unwrap()
        .iter()
        .find(|s| s["path"] == path)
        .unwrap_or_else(|| panic!("no shader {path}"))
}

fn close(v: &serde_json::Value, want: &[f64]) -> bool {
    let got: Vec<f64> = match v {
        serde_json::Value::Array(a) => a.iter().map(|x| x.as_f64().unwrap()).collect(),
        x => vec![x.as_f64().unwrap()],
    };
    got.len() == want.len() && got.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-6)
}

/// Every glTF material becomes a bound UsdPreviewSurface material (issue 19): MorphStressTest
/// (external PNGs, occlusion on TEXCOORD_1), MorphPrimitivesTest (JPEG) and a variant using
/// every feature (see `every_material_feature`), in .usda, .usdc and .usdz: usd-core's
/// validators (UsdShade, usdz package, missing references) are clean, every mesh is bound to
/// the material named after its glTF one, every glTF material is written (used or not),
/// every texture file resolves (inside the package for
/// .usdz) to the bytes of its glTF image, and the inputs carry the glTF values; the KTX2
/// texture is left out with a warning naming it, its material keeping the factor; material
/// variants are a variant set on the root prim that binds each variant's materials.
#[test]
fn materials_and_textures_travel_to_usd() {
    let Some(fx) = fixtures() else { return };
    let Some(python) = python() else { return };
    let dir = tempfile::tempdir().unwrap();
    let variant = dir.path().join("every_feature.glb");
    every_material_feature(&fx, &variant);
    let inputs = [
        fx.join("morph-khronos/MorphStressTest/glTF/MorphStressTest.gltf"),
        fx.join("morph-khronos/MorphPrimitivesTest/glTF/MorphPrimitivesTest.gltf"),
        variant.clone(),
    ];
    for input in &inputs {
        let doc = inbetween::gltf::Document::open(input).unwrap();
        let images: Vec<u32> = (0..doc.json["images"].as_array().map_or(0, |a| a.len()))
            .map(|i| crc32fast::hash(&doc.image(i).unwrap().0))
            .collect();
        let materials = doc.json["materials"].as_array().unwrap();
        for fmt in FORMATS {
            // An output named with an @ (and a space and quotes): its texture files' asset
            // paths are delimited by @@@ in the text format (an unreadable .usda before).
            let out = dir.path().join(format!("look@v2 \"x\".{fmt}"));
            let run = run_ok(&["tween", s(input), "-o", s(&out), "--fps", "2"]);
            let stderr = String::from_utf8_lossy(&run.stderr);
            let what = format!("{} .{fmt}", input.display());
            let looks = clean_looks(&python, &out, &what);
            // Every primitive bound to the material named after its glTF material.
            let prims = doc.json["meshes"][0]["primitives"].as_array().unwrap();
            let meshes = looks["meshes"].as_array().unwrap();
            assert_eq!(meshes.len(), prims.len(), "{what}");
            for (m, p) in meshes.iter().zip(prims) {
                let gm = &materials[p["material"].as_u64().unwrap() as usize];
                let name = gm["name"].as_str().unwrap();
                let bound = m["material"].as_str().unwrap_or("");
                assert!(
                    bound.ends_with(&format!("/Materials/{name}")),
                    "{what}: {bound}"
                );
            }
            // Every glTF material is there, used or not.
            for gm in materials {
                let name = format!("/Materials/{}", gm["name"].as_str().unwrap());
                assert!(
                    looks["materials"]
                        .as_array()
                        .unwrap()
                        .iter()
                        .any(|m| m["path"].as_str().unwrap().ends_with(&name)),
                    "{what}: no {name}"
                );
            }
            // Every texture file resolves to the bytes of a glTF image.
            let textures: Vec<&serde_json::Value> = (looks["shaders"].as_array().unwrap())
                .iter()
                .filter(|s| s["id"] == "UsdUVTexture")
                .collect();
            assert!(!textures.is_empty(), "{what}");
            for t in &textures {
                let f = &t["files"]["file"];
                let crc = f["crc32"].as_u64().unwrap() as u32;
                assert!(f["bytes"].as_u64().unwrap() > 0, "{what}: {t}");
                assert!(
                    images.contains(&crc),
                    "{what}: {} is no glTF image",
                    f["resolved"]
                );
                if *fmt == "usdz" {
                    assert!(f["resolved"].as_str().unwrap().contains(".usdz["), "{what}");
                }
            }
            if input != &variant {
                assert!(!stderr.contains("left out"), "{what}: {stderr}");
                continue;
            }
            // The variant: every value as glTF has it.
            let red = |s: &str| format!("/Scene/Materials/red/{s}");
            let surface = &shader(&looks, &red("PreviewSurface"))["inputs"];
            let wired = |input: &str, from: &str| {
                assert_eq!(surface[input]["connect"], red(from), "{what}: {input}")
            };
            wired("diffuseColor", "BaseColor.outputs:rgb");
            wired("opacity", "BaseColor.outputs:a");
            wired("metallic", "MetallicRoughness.outputs:b");
            wired("roughness", "MetallicRoughness.outputs:g");
            wired("normal", "Normal.outputs:rgb");
            wired("occlusion", "Occlusion.outputs:r");
            wired("emissiveColor", "Emissive.outputs:rgb");
            assert!(close(&surface["opacityThreshold"], &[0.3]), "{what}");
            // KHR_materials_clearcoat and _ior carried; _sheen named as left out.
            assert!(close(&surface["clearcoat"], &[0.8]), "{what}");
            wired("clearcoatRoughness", "ClearcoatRoughness.outputs:g");
            assert!(close(&surface["ior"], &[1.4]), "{what}");
            assert!(
                stderr.contains("material 0 KHR_materials_sheen left out"),
                "{what}: {stderr}"
            );
            // The material variants: a variant set on the root prim, its selection the
            // default (each mesh its own material, as glTF shows it with no variant chosen),
            // "day" binding primitive 0 to material 0 ("red", its own), "night" to the
            // unused one; primitive 1, mapped by neither, keeps its own in every variant.
            assert!(!stderr.contains("variants"), "{what}: {stderr}");
            let set = &looks["variants"]["materialVariant"];
            assert_eq!(set["selection"], "default", "{what}");
            let bound = |variant: &str, mesh: usize| -> String {
                let path = meshes[mesh]["path"].as_str().unwrap();
                set["bindings"][variant][path]
                    .as_str()
                    .unwrap_or("")
                    .to_owned()
            };
            let own1 = meshes[1]["material"].as_str().unwrap();
            for (variant, zero) in [("default", "red"), ("day", "red"), ("night", "unused")] {
                let b0 = bound(variant, 0);
                assert!(
                    b0.ends_with(&format!("/Materials/{zero}")),
                    "{what} {variant}: {b0}"
                );
                assert_eq!(bound(variant, 1), own1, "{what} {variant}");
            }
            let names = set["bindings"]
                .as_object()
                .unwrap()
                .keys()
                .collect::<Vec<_>>();
            assert_eq!(names, ["day", "default", "night"], "{what}");
            let tex = |n: &str| &shader(&looks, &red(n))["inputs"];
            assert!(
                close(&tex("BaseColor")["scale"], &[1.0, 0.5, 0.25, 0.8]),
                "{what}"
            );
            assert_eq!(tex("BaseColor")["sourceColorSpace"], "sRGB");
            assert!(close(
                &tex("MetallicRoughness")["scale"],
                &[1.0, 0.9, 0.2, 1.0]
            ));
            assert_eq!(tex("MetallicRoughness")["sourceColorSpace"], "raw");
            // The normal scale cannot be carried (usd-core's validator requires the unscaled
            // mapping of 8-bit maps): left out, with a warning.
            assert!(
                close(&tex("Normal")["scale"], &[2.0, 2.0, 2.0, 1.0]),
                "{what}"
            );
            assert!(
                close(&tex("Normal")["bias"], &[-1.0, -1.0, -1.0, 0.0]),
                "{what}"
            );
            assert!(
                stderr.contains("normalTexture: scale 0.5 left out"),
                "{what}: {stderr}"
            );
            assert!(
                close(&tex("Occlusion")["scale"], &[0.7, 0.7, 0.7, 1.0]),
                "{what}"
            );
            assert!(
                close(&tex("Occlusion")["bias"], &[0.3, 0.3, 0.3, 0.0]),
                "{what}"
            );
            assert!(
                close(&tex("Emissive")["scale"], &[1.0, 0.5, 2.0, 1.0]),
                "{what}"
            );
            assert!(
                close(
                    &tex("ClearcoatRoughness")["scale"],
                    &[0.25, 0.25, 0.25, 1.0]
                ),
                "{what}"
            );
            for t in &textures {
                assert_eq!(t["inputs"]["wrapS"], "clamp", "{what}");
                assert_eq!(t["inputs"]["wrapT"], "mirror", "{what}");
            }
            // KHR_texture_transform: USD's st' = rotate(scale * st) + translation (rotation
            // counter-clockwise, degrees; st = (u, 1 - v)) samples where glTF's
            // uv' = T(offset) R(rotation) S(scale) uv does.
            assert_eq!(
                tex("BaseColor")["st"]["connect"],
                red("BaseColorTransform.outputs:result")
            );
            let t = tex("BaseColorTransform");
            let num = |v: &serde_json::Value, i: usize| v[i].as_f64().unwrap();
            let deg = t["rotation"].as_f64().unwrap().to_radians();
            let (sc, tr) = (&t["scale"], &t["translation"]);
            for (u, v) in [(0.0, 0.0), (1.0, 0.0), (0.3, 0.7), (0.9, 0.2)] {
                let (c, s) = (0.3f64.cos(), 0.3f64.sin());
                let (x, y) = (2.0 * u, 3.0 * v);
                let gltf = (c * x + s * y + 0.1, -s * x + c * y + 0.2);
                let (x, y) = (num(sc, 0) * u, num(sc, 1) * (1.0 - v));
                let usd = (
                    deg.cos() * x - deg.sin() * y + num(tr, 0),
                    deg.sin() * x + deg.cos() * y + num(tr, 1),
                );
                assert!(
                    (usd.0 - gltf.0).abs() < 1e-5 && (usd.1 - (1.0 - gltf.1)).abs() < 1e-5,
                    "{what}: uv ({u}, {v}): glTF {gltf:?}, USD {usd:?}"
                );
            }
            // The KTX2 texture: left out, named in a warning; the factor stays.
            assert!(
                stderr.contains("warning")
                    && stderr.contains("KTX2")
                    && stderr.contains("left out")
                    && stderr.contains("\"compressed\""),
                "{what}: {stderr}"
            );
            let green = &shader(&looks, "/Scene/Materials/green/PreviewSurface")["inputs"];
            assert!(
                close(&green["diffuseColor"], &[0.0, 1.0, 0.0]),
                "{what}: {green}"
            );
            assert!(close(&green["opacity"], &[1.0]), "{what}: {green}");
        }
    }
}

/// Blender (PyPI bpy 5.0.1, in .venv-bpy) imports the USD outputs with their look (issue 19):
/// MorphPrimitivesTest in every format gets its two materials with the JPEG texture found and
/// read (512 x 512) and the base colour wired to it; Flamingo (.usdz) gets the vertex-colour
/// material, its base colour read from the `displayColor` attribute, whose mean equals the
/// glTF COLOR_0 mean within 1/255.
#[test]
fn blender_imports_materials_and_colours() {
    let Some(fx) = fixtures() else { return };
    let Some(bpy) = bpy() else { return };
    let dir = tempfile::tempdir().unwrap();
    let import = |input: &Path, fmt: &str| -> serde_json::Value {
        let out = dir.path().join(format!("blender.{fmt}"));
        tween_quietly(input, &out, &["--fps", "2"]);
        let what = format!("{} .{fmt}", input.display());
        bpy_result(
            &bpy,
            "bpy_import.py",
            &[out.as_os_str()],
            &what,
            "BPY_IMPORT ",
        )
    };
    let mpt = fx.join("morph-khronos/MorphPrimitivesTest/glTF/MorphPrimitivesTest.gltf");
    for fmt in FORMATS {
        let objects = import(&mpt, fmt);
        let objects = objects.as_array().unwrap();
        assert_eq!(objects.len(), 2, ".{fmt}: {objects:?}");
        for (o, name) in objects.iter().zip(["red", "green"]) {
            assert_eq!(o["materials"], serde_json::json!([name]), ".{fmt}: {o}");
            let images = o["images"].as_array().unwrap();
            assert_eq!(images.len(), 1, ".{fmt}: {o}");
            assert_eq!(
                (images[0]["width"].as_u64(), images[0]["height"].as_u64()),
                (Some(512), Some(512)),
                ".{fmt}: {o}"
            );
            assert!(
                o["base_color"].is_string(),
                ".{fmt}: base colour not wired: {o}"
            );
        }
    }
    let flamingo = fx.join("morph-keyframes/Flamingo.glb");
    let objects = import(&flamingo, "usdz");
    let o = &objects[0];
    assert_eq!(
        o["materials"],
        serde_json::json!(["material0_vertexColor"]),
        "{o}"
    );
    assert_eq!(o["base_color"], "ATTRIBUTE", "{o}");
    let doc = inbetween::gltf::Document::open(&flamingo).unwrap();
    let acc = doc.json["meshes"][0]["primitives"][0]["attributes"]["COLOR_0"]
        .as_u64()
        .unwrap();
    let (colors, comps) = doc.read_f64(acc as usize).unwrap();
    let n = (colors.len() / comps) as f64;
    let mean = &o["color_attributes"]["displayColor"]["mean"];
    for c in 0..3 {
        let want = colors.iter().skip(c).step_by(comps).sum::<f64>() / n;
        let got = mean[c].as_f64().unwrap();
        assert!(
            (got - want).abs() <= 1.0 / 255.0,
            "channel {c}: Blender {got}, glTF {want}"
        );
    }
}

/// Pixels of a PNG file, as RGBA.
fn png_rgba(path: &Path) -> (u32, u32, Vec<[u8; 4]>) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.bit_depth, png::BitDepth::Eight, "{}", path.display());
    let channels = info.color_type.samples();
    let pixels = buf[..info.buffer_size()]
        .chunks_exact(channels)
        .map(|p| match p {
            [g] => [*g, *g, *g, 255],
            [g, a] => [*g, *g, *g, *a],
            [r, g, b] => [*r, *g, *b, 255],
            [r, g, b, a] => [*r, *g, *b, *a],
            _ => unreachable!(),
        })
        .collect();
    (info.width, info.height, pixels)
}

/// WebP textures made by a real tool (`gltf-transform webp` on MorphStressTest:
/// EXT_texture_webp, no PNG fallback) are written as PNG files, which USD reads: every
/// texture of the original is read by the USD materials (in a .usdz too, validator-clean), no
/// warning, and each PNG shows the original image as the lossy WebP keeps it (same size, mean
/// difference within 3 of 255 a channel). They were left out before, with a warning.
#[test]
fn webp_textures_are_written_as_png() {
    let Some(fx) = fixtures() else { return };
    let Some(python) = python() else { return };
    let bin = node_modules_bin().join("gltf-transform");
    if !bin.exists() && missing_tool("gltf-transform (tools/node)") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let webp = dir.path().join("webp.glb");
    let original = fx.join("morph-khronos/MorphStressTest/glTF");
    let input = original.join("MorphStressTest.gltf");
    let made = std::process::Command::new(&bin)
        .args(["webp", s(&input), s(&webp)])
        .output()
        .unwrap();
    assert!(
        made.status.success(),
        "{}",
        String::from_utf8_lossy(&made.stderr)
    );
    let made = String::from_utf8_lossy(&std::fs::read(&webp).unwrap()).into_owned();
    assert!(made.contains("EXT_texture_webp"));
    for format in ["usdz", "usda"] {
        let out = dir.path().join(format!("webp.{format}"));
        let run = run_ok(&["tween", s(&webp), "-o", s(&out), "--fps", "2"]);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert!(!stderr.contains("left out"), "{format}: {stderr}");
        let looks = clean_looks(&python, &out, "webp");
        assert_eq!(looks["materials"].as_array().unwrap().len(), 2);
        let readers: Vec<&serde_json::Value> = (looks["shaders"].as_array().unwrap())
            .iter()
            .filter(|s| s["id"] == "UsdUVTexture")
            .collect();
        assert_eq!(readers.len(), 3, "{format}");
        for r in readers {
            let f = &r["files"]["file"];
            assert!(f["bytes"].as_u64().unwrap() > 0, "{format}: {r}");
            let resolved = f["resolved"].as_str().unwrap().trim_end_matches(']');
            assert!(resolved.ends_with(".png"), "{format}: {r}");
        }
    }
    for image in ["TinyGrid", "Base_AO", "ColorSwatches"] {
        let (w, h, want) = png_rgba(&original.join(format!("{image}.png")));
        let (gw, gh, got) = png_rgba(&dir.path().join(format!("webp_{image}.png")));
        assert_eq!((gw, gh), (w, h), "{image}");
        let diff: u64 = (want.iter().zip(&got))
            .flat_map(|(a, b)| (0..4).map(move |c| a[c].abs_diff(b[c]) as u64))
            .sum();
        let mean = diff as f64 / (4 * want.len()) as f64;
        assert!(mean <= 3.0, "{image}: mean difference {mean:.2} of 255");
    }
}

/// The flag sample with a node "second" carrying mesh `mesh` off to the side, then `edit`.
fn flag_and_second(path: &Path, mesh: usize, edit: impl FnOnce(&mut serde_json::Value)) {
    edited_glb(&sample("flag_wave.glb"), path, |j| {
        let node = serde_json::json!({"name": "second", "mesh": mesh, "translation": [0, 0, 3]});
        j["nodes"].as_array_mut().unwrap().push(node);
        j["scenes"][0]["nodes"]
            .as_array_mut()
            .unwrap()
            .push(2.into());
        edit(j);
    });
}

/// A mesh carried by two nodes: each node's Mesh plays the frames of the clips that drive its
/// node, and a node no clip drives stays still, as in the glTF (both nodes played every clip
/// before, the still one included). A clip has one place on the timeline, whichever meshes and
/// nodes it drives: a clip per node follow one another; two nodes each with its own weights
/// sampler in one clip play side by side (the second a clip's length later before); a copy
/// of the mesh driven by the second clip only plays it where the flag does (at the start,
/// beside the first clip, before).
#[test]
fn each_instance_plays_the_clips_that_drive_its_node() {
    let Some(python) = python() else { return };
    let dir = tempfile::tempdir().unwrap();
    let input = |name: &str, mesh: usize, edit: &dyn Fn(&mut serde_json::Value)| {
        let path = dir.path().join(name);
        flag_and_second(&path, mesh, edit);
        path
    };
    let still = input("still.glb", 0, &|_| {});
    let clips = input("clips.glb", 0, &|j| {
        let mut a = j["animations"][0].clone();
        a["name"] = "second".into();
        a["channels"][0]["target"]["node"] = 2.into();
        j["animations"].as_array_mut().unwrap().push(a);
    });
    let twin = input("twin.glb", 0, &|j| {
        let a = &mut j["animations"][0];
        let s = a["samplers"][0].clone();
        a["samplers"].as_array_mut().unwrap().push(s);
        let c = serde_json::json!({"sampler": 1, "target": {"node": 2, "path": "weights"}});
        a["channels"].as_array_mut().unwrap().push(c);
    });
    let copy = input("copy.glb", 2, &|j| {
        let mesh = j["meshes"][0].clone();
        j["meshes"].as_array_mut().unwrap().push(mesh);
        let mut b = j["animations"][0].clone();
        b["name"] = "both".into();
        let c = serde_json::json!({"sampler": 0, "target": {"node": 2, "path": "weights"}});
        b["channels"].as_array_mut().unwrap().push(c);
        j["animations"].as_array_mut().unwrap().push(b);
    });
    for (input, flag, second) in [
        (&still, (0.0, 60.0, 61), None),
        (&clips, (0.0, 60.0, 61), Some((61.0, 121.0, 61))),
        (&twin, (0.0, 60.0, 61), Some((0.0, 60.0, 61))),
        (&copy, (0.0, 121.0, 122), Some((61.0, 121.0, 61))),
    ] {
        for fmt in ["usda", "usdc"] {
            let what = format!("{} {fmt}", input.display());
            let usd = dir.path().join(format!("out.{fmt}"));
            tween_quietly(input, &usd, &[]);
            let r = clean_usd_report(&python, &usd, fmt);
            let mesh = |path: &str| {
                let m = (r["meshes"].as_array().unwrap().iter()).find(|m| m["path"] == path);
                m.unwrap_or_else(|| panic!("{path} in {}", r["meshes"]))
                    .clone()
            };
            let span = |m: &serde_json::Value| {
                let t = m["times"].as_array().unwrap();
                let f = |v: &serde_json::Value| v.as_f64().unwrap();
                (f(&t[0]), f(&t[t.len() - 1]), t.len())
            };
            assert_eq!(span(&mesh("/samples/flag/flag")), flag, "{what}");
            let other = mesh("/samples/second/flag");
            match second {
                None => assert_eq!(other["static"], true, "{what}: the undriven instance"),
                Some(s) => assert_eq!(span(&other), s, "{what}"),
            }
        }
    }
}

/// A node the tweened clip also moves (the flag's pole, by a channel sharing the weights' key
/// times and one with times of its own) moves in the point cache as in the glTF: its local
/// transform time-sampled at every frame of the clip. A clip that tweens no mesh (`grow`) is
/// not on the timeline and is named in a warning; the pole stood still before.
#[test]
fn nodes_the_tweened_clip_moves_move_in_the_point_cache() {
    let Some(python) = python() else { return };
    let dir = tempfile::tempdir().unwrap();
    let plain = dir.path().join("pole.glb");
    flag_with_moving_pole(&sample("flag_wave.glb"), &plain, 0.0);
    // The same, the rise keyed through KHR_animation_pointer.
    let pointer = dir.path().join("pointer.glb");
    edited_glb(&plain, &pointer, |j| {
        j["animations"][0]["channels"][1]["target"] = serde_json::json!({"path": "pointer",
            "extensions": {"KHR_animation_pointer": {"pointer": "/nodes/1/translation"}}});
        j["extensionsUsed"] = serde_json::json!(["KHR_animation_pointer"]);
    });
    // The file's keys: the pole rises 0.1 per key (0, 0.5, ... 2 s) and turns from none at
    // 0.25 s to (0, 0.6, 0, 0.8) at 1.75 s.
    let turn = glam::DQuat::from_xyzw(0.0, 0.6, 0.0, 0.8);
    // With --loop the weights close at 2.5 s, and both channels return to their first key
    // there (without, the rotation holds its last key from 1.75 s).
    let expected = |t: f64, looped: bool| {
        let r = match (t > 1.75, looped) {
            (false, _) => glam::DQuat::IDENTITY.slerp(turn, ((t - 0.25) / 1.5).max(0.0)),
            (true, true) => turn.slerp(glam::DQuat::IDENTITY, (t - 1.75) / 0.75),
            (true, false) => turn,
        };
        let y = if t > 2.0 {
            0.4 * (2.5 - t) / 0.5
        } else {
            0.2 * t
        };
        glam::DMat4::from_rotation_translation(r, glam::DVec3::new(0.0, y, 0.0))
    };
    for (input, fmt, args) in [
        (&plain, "usda", &[][..]),
        (&plain, "usdc", &[]),
        (&pointer, "usda", &[]),
        (&plain, "usdc", &["--loop"]),
    ] {
        let usd = dir.path().join(format!("out.{fmt}"));
        let mut all = vec!["tween", s(input), "-o", s(&usd)];
        all.extend_from_slice(args);
        let r = run_ok(&all);
        let err = String::from_utf8_lossy(&r.stderr);
        assert!(
            err.lines()
                .any(|l| l.starts_with("warning: ") && l.contains("animation \"grow\" moves nodes")),
            "{err}"
        );
        let r = clean_usd_report(&python, &usd, fmt);
        let xforms = r["xforms"].as_array().unwrap();
        assert_eq!(xforms.len(), 1, "{fmt}: only the pole moves: {xforms:?}");
        assert_eq!(xforms[0]["path"], "/samples/pole", "{fmt}");
        let times = xforms[0]["times"].as_array().unwrap();
        let looped = !args.is_empty();
        let frames = if looped { 76 } else { 61 };
        assert_eq!(times.len(), frames, "{fmt}: a sample per frame");
        let mut most = 0.0f64;
        for (code, local) in times.iter().zip(xforms[0]["local"].as_array().unwrap()) {
            let code = code.as_f64().unwrap();
            let local: Vec<f64> = local
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect();
            // USD prints the matrix row by row, glam's columns.
            let want = expected(code / 30.0, looped).to_cols_array();
            for (a, b) in local.iter().zip(want) {
                most = most.max((a - b).abs());
            }
        }
        assert!(
            most < 1e-6,
            "{fmt}: the pole's transform within {most} of the file's keys"
        );
    }
}

/// A node drawing its mesh once per instance (`EXT_mesh_gpu_instancing`, as gltfpack `-mi`
/// writes scenes of repeated props) is a PointInstancer whose instances sit where the glTF
/// draws them: flag_wave's pole three times (moved, turned, scaled; one still child node
/// beside). Only the first instance was written before (as a plain mesh under the node).
#[test]
fn gpu_instances_become_a_point_instancer() {
    let Some(python) = python() else { return };
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("poles.glb");
    let doc = inbetween::gltf::Document::open(&sample("flag_wave.glb")).unwrap();
    let (mut json, mut bin) = (doc.json.clone(), doc.buffers[0].clone());
    let turn = glam::Quat::from_rotation_y(std::f32::consts::FRAC_PI_2);
    let t = [[0.0, 0.0, 0.0], [1.0, 0.0, 2.0], [-1.0, 0.5, 4.0]];
    let r = [[0.0, 0.0, 0.0, 1.0], turn.to_array(), [0.0, 0.0, 0.0, 1.0]];
    let sc = [[1.0, 1.0, 1.0], [2.0, 2.0, 2.0], [1.0, 0.5, 1.0]];
    let flat = |v: &[[f32; 3]]| v.iter().flatten().copied().collect::<Vec<f32>>();
    let attributes = serde_json::json!({
        "TRANSLATION": push_f32_accessor(&mut json, &mut bin, &flat(&t), "VEC3"),
        "ROTATION": push_f32_accessor(&mut json, &mut bin, &r.concat(), "VEC4"),
        "SCALE": push_f32_accessor(&mut json, &mut bin, &flat(&sc), "VEC3"),
    });
    json["nodes"][1]["extensions"] =
        serde_json::json!({"EXT_mesh_gpu_instancing": {"attributes": attributes}});
    json["nodes"][1]["children"] = serde_json::json!([2]);
    json["nodes"]
        .as_array_mut()
        .unwrap()
        .push(serde_json::json!({"name": "tip", "translation": [0, 3, 0]}));
    json["extensionsUsed"] = serde_json::json!(["EXT_mesh_gpu_instancing"]);
    write_glb(&input, &json, &bin);
    let glb = dir.path().join("out.glb");
    tween_quietly(&input, &glb, &[]);
    assert_no_new_issues(&input, &glb);
    // A zero rotation (a zero-filled accessor) is refused, not written as NaN.
    let zero = dir.path().join("zero.glb");
    let (mut j, mut b) = (json.clone(), bin.clone());
    let r0 = push_f32_accessor(&mut j, &mut b, &[0.0; 12], "VEC4");
    j["nodes"][1]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"]["ROTATION"] = r0.into();
    write_glb(&zero, &j, &b);
    let usd = dir.path().join("zero.usda");
    assert_refused(
        &["tween", s(&zero), "-o", s(&usd)],
        "zero.glb",
        "ROTATION of instance 0 is not a rotation",
        &usd,
    );
    for fmt in ["usda", "usdc"] {
        let usd = dir.path().join(format!("out.{fmt}"));
        tween_quietly(&input, &usd, &[]);
        let rep = clean_usd_report(&python, &usd, fmt);
        let instancers = rep["instancers"].as_array().unwrap();
        assert_eq!(instancers.len(), 1, "{fmt}");
        assert_eq!(instancers[0]["path"], "/samples/pole", "{fmt}");
        assert_eq!(
            instancers[0]["prototypes"],
            serde_json::json!(["/samples/pole/Prototypes/pole"])
        );
        let transforms = instancers[0]["transforms"].as_array().unwrap();
        assert_eq!(transforms.len(), 3, "{fmt}");
        let mut most = 0.0f64;
        for (i, m) in transforms.iter().enumerate() {
            let want = glam::Mat4::from_scale_rotation_translation(
                sc[i].into(),
                glam::Quat::from_array(r[i]),
                t[i].into(),
            )
            .to_cols_array();
            for (a, b) in m.as_array().unwrap().iter().zip(want) {
                most = most.max((a.as_f64().unwrap() - b as f64).abs());
            }
        }
        // Orientations are half floats in USD (quath).
        assert!(most < 2e-3, "{fmt}: instances within {most} of the glTF's");
        let paths: Vec<&str> = rep["meshes"]
            .as_array()
            .unwrap()
            .iter()
            .map(|m| m["path"].as_str().unwrap())
            .collect();
        assert_eq!(
            paths,
            ["/samples/flag/flag", "/samples/pole/Prototypes/pole/pole"],
            "{fmt}"
        );
        let text = std::fs::read_to_string(&usd).unwrap_or_default();
        if fmt == "usda" {
            assert!(
                text.contains("def Xform \"tip\""),
                "the node's child is kept"
            );
        }
    }
}

/// What a point cache cannot carry is named in a warning line, not dropped without a word: a
/// light's range, and clips that tween no mesh (RobotExpressive's, when the fixtures are here). Cameras and
/// lights travel (`usd_camera_and_light_prims_read_back`).
#[test]
fn what_a_point_cache_does_not_carry_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("lit.glb");
    lit_flag(&input);
    let warnings = |input: &Path, args: &[&str]| -> Vec<String> {
        let usd = dir.path().join("out.usda");
        let mut all = vec!["tween", s(input), "-o", s(&usd)];
        all.extend_from_slice(args);
        let r = run_ok(&all);
        (String::from_utf8_lossy(&r.stderr).lines())
            .filter(|l| l.starts_with("warning: ") && !l.contains("the size of the input"))
            .map(str::to_owned)
            .collect()
    };
    let w = warnings(&input, &[]);
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].ends_with("light \"key\"'s range (8) is not carried: UsdLux lights have none"),
        "{w:?}"
    );
    let Some(fx) = fixtures() else { return };
    let robot = fx.join("skinned/RobotExpressive.glb");
    let w = warnings(&robot, &["--keys", "targets"]);
    assert!(
        w.iter()
            .any(|l| l.contains("animations \"Dance\", \"Death\"")),
        "{w:?}"
    );
    // Its skinned hands are baked in the pose their joints rest in (`skin`): at the ends of
    // its hanging arms, where they floated 0.34 beside them, in the bind pose, before.
    assert!(w.iter().all(|l| !l.contains("bind pose")), "{w:?}");
    let Some(python) = python() else { return };
    let usd = dir.path().join("out.usda");
    let arm = "RobotArmature/Bone/Body/Hips/Abdomen/Torso/Shoulder_R/UpperArm_R/Arm_R/Arm_R";
    let boxes: Vec<(glam::DVec3, glam::DVec3)> = [arm, "Hand_R/Hand_R_0"]
        .iter()
        .map(|prim| {
            let path = format!("/Root_Scene/RootNode/{prim}");
            let r = world_points(&python, &usd, &path, prim);
            let points = r["points"][0].as_array().unwrap().iter().map(|p| {
                glam::DVec3::new(
                    p[0].as_f64().unwrap(),
                    p[1].as_f64().unwrap(),
                    p[2].as_f64().unwrap(),
                )
            });
            points.fold(
                (glam::DVec3::INFINITY, -glam::DVec3::INFINITY),
                |(lo, hi), p| (lo.min(p), hi.max(p)),
            )
        })
        .collect();
    let ((a_lo, a_hi), (h_lo, h_hi)) = (boxes[0], boxes[1]);
    let gap = (a_lo - h_hi)
        .max(h_lo - a_hi)
        .max(glam::DVec3::ZERO)
        .length();
    assert!(gap < 0.05, "the hand {gap} from the arm: {boxes:?}");
}

/// flag_wave with two cameras (a perspective one at (0, 1, 5), an orthographic one looking down
/// from (0, 10, 0)) and three lights (a point light of range 8 at (1, 2, 3), a spot, a sun).
fn lit_flag(out: &Path) {
    edited_glb(&sample("flag_wave.glb"), out, |j| {
        j["cameras"] = serde_json::json!([
            {"name": "shot", "type": "perspective",
             "perspective": {"yfov": 0.7, "aspectRatio": 1.5, "znear": 0.1}},
            {"name": "plan", "type": "orthographic",
             "orthographic": {"xmag": 2.0, "ymag": 1.0, "znear": 0.0, "zfar": 100.0}}]);
        j["extensions"] = serde_json::json!({"KHR_lights_punctual": {"lights": [
            {"name": "key", "type": "point", "intensity": 20.0, "range": 8.0},
            {"type": "spot", "intensity": 5.0, "color": [1.0, 0.5, 0.25],
             "spot": {"innerConeAngle": 0.3, "outerConeAngle": 0.6}},
            {"name": "sun", "type": "directional", "intensity": 2.0}]}});
        j["extensionsUsed"] = serde_json::json!(["KHR_lights_punctual"]);
        let nodes = j["nodes"].as_array_mut().unwrap();
        let first = nodes.len();
        let light = |l: usize| serde_json::json!({"KHR_lights_punctual": {"light": l}});
        nodes.extend([
            serde_json::json!({"name": "camera", "camera": 0, "translation": [0.0, 1.0, 5.0]}),
            serde_json::json!({"name": "top", "camera": 1, "translation": [0.0, 10.0, 0.0],
                "rotation": [-std::f64::consts::FRAC_1_SQRT_2, 0.0, 0.0, std::f64::consts::FRAC_1_SQRT_2]}),
            serde_json::json!({"name": "lamp", "extensions": light(0), "translation": [1.0, 2.0, 3.0]}),
            serde_json::json!({"name": "spot", "extensions": light(1)}),
            serde_json::json!({"name": "sky", "extensions": light(2)}),
        ]);
        let roots = j["scenes"][0]["nodes"].as_array_mut().unwrap();
        roots.extend((first..first + 5).map(|n| serde_json::json!(n)));
    });
}

/// glTF cameras and KHR_lights_punctual lights become UsdGeom cameras and UsdLux lights under
/// their nodes' Xforms, read back by usd-core as glTF has them: the perspective camera's field
/// of view (Gf.Camera's, from the apertures) and aspect ratio, the orthographic camera's
/// extents, each light's type, colour, cone and intensity (candela = a quarter of a normalized
/// sphere light's intensity), the nodes' transforms; usd-core's validators find nothing.
#[test]
fn usd_camera_and_light_prims_read_back() {
    let Some(python) = python() else { return };
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("lit.glb");
    lit_flag(&input);
    for fmt in ["usda", "usdc", "usdz"] {
        let usd = dir.path().join(format!("lit.{fmt}"));
        tween_quietly(&input, &usd, &[]);
        clean_usd_report(&python, &usd, fmt);
        let r: serde_json::Value =
            serde_json::from_slice(&run_tool(&python, "usd_scene.py", &[usd.as_os_str()], fmt))
                .unwrap();
        let prim = |path: &str| &r[format!("/samples/{path}")];
        let attr = |path: &str, name: &str| prim(path)["attrs"][name].clone();
        let shot = prim("camera/shot");
        assert_eq!(shot["type"], "Camera", "{fmt}: {r}");
        let fov = shot["vertical_fov_degrees"].as_f64().unwrap();
        assert!((fov - 0.7f64.to_degrees()).abs() < 1e-4, "{fmt}: {fov}");
        assert!((shot["aspect"].as_f64().unwrap() - 1.5).abs() < 1e-5);
        assert!(close(&shot["world"][3], &[0.0, 1.0, 5.0, 1.0]));
        assert_eq!(attr("top/plan", "projection"), "orthographic");
        assert!(close(&attr("top/plan", "horizontalAperture"), &[40.0]));
        assert!(close(&attr("top/plan", "clippingRange"), &[0.0, 100.0]));
        // The top camera looks down: its -Z is the world's -Y.
        assert!(close(&prim("top/plan")["world"][2], &[0.0, 1.0, 0.0, 0.0]));
        assert_eq!(prim("lamp/key")["type"], "SphereLight");
        assert!(close(&attr("lamp/key", "inputs:intensity"), &[80.0]));
        assert_eq!(attr("lamp/key", "treatAsPoint"), true);
        assert!(close(&prim("lamp/key")["world"][3], &[1.0, 2.0, 3.0, 1.0]));
        let spot = prim("spot/light");
        assert!(
            spot["api_schemas"]
                .as_array()
                .unwrap()
                .contains(&"ShapingAPI".into()),
            "{fmt}: {spot}"
        );
        assert!(close(
            &attr("spot/light", "inputs:color"),
            &[1.0, 0.5, 0.25]
        ));
        assert!(close(
            &attr("spot/light", "inputs:shaping:cone:angle"),
            &[0.6f64.to_degrees()]
        ));
        assert!(close(
            &attr("spot/light", "inputs:shaping:cone:softness"),
            &[0.5]
        ));
        assert_eq!(prim("sky/sun")["type"], "DistantLight");
        assert!(close(&attr("sky/sun", "inputs:intensity"), &[2.0]));
        assert_eq!(attr("sky/sun", "inputs:normalize"), true);
    }
}

/// Primitives drawing one vertex buffer (three.js' and Babylon.js' material groups) are one
/// Mesh with a GeomSubset per primitive, each bound to its material: flag_wave in two such
/// groups plays the single primitive's points exactly, at about half the size of a Mesh per
/// primitive (each carried every vertex's points at every frame before).
#[test]
fn material_groups_of_one_vertex_buffer_are_subsets_of_one_mesh() {
    let Some(python) = python() else { return };
    let dir = tempfile::tempdir().unwrap();
    let groups = dir.path().join("groups.glb");
    flag_in_two_groups(&groups);
    let dump = |input: &Path, fmt: &str| {
        let usd = dir.path().join(format!("out.{fmt}"));
        tween_quietly(input, &usd, &[]);
        let r = clean_usd_report(&python, &usd, fmt);
        let size = std::fs::metadata(&usd).unwrap().len();
        (
            r,
            std::fs::read(usd.with_file_name("dump.bin")).unwrap(),
            size,
            usd,
        )
    };
    for fmt in ["usda", "usdc"] {
        let (plain, plain_points, plain_size, _) = dump(&sample("flag_wave.glb"), fmt);
        let (r, points, size, usd) = dump(&groups, fmt);
        assert_eq!(
            r["meshes"], plain["meshes"],
            "{fmt}: one Mesh per mesh, the same samples"
        );
        assert!(
            points == plain_points,
            "{fmt}: the same points at every frame"
        );
        // The single primitive's file and the subsets' few lines.
        assert!(
            (size as f64) < 1.05 * plain_size as f64,
            "{fmt}: {size} bytes against {plain_size}"
        );
        let looks = clean_looks(&python, &usd, fmt);
        let subsets = looks["subsets"].as_array().unwrap();
        assert_eq!(subsets.len(), 2, "{fmt}: {subsets:?}");
        let bound: Vec<&str> = subsets
            .iter()
            .map(|s| s["material"].as_str().unwrap())
            .collect();
        assert!(
            bound[0].ends_with("/Materials/flag_material"),
            "{fmt}: {bound:?}"
        );
        assert!(bound[1].ends_with("/Materials/back"), "{fmt}: {bound:?}");
        let faces: usize = subsets
            .iter()
            .map(|s| s["faces"].as_u64().unwrap() as usize)
            .sum();
        assert_eq!(faces, 768, "{fmt}: the subsets cover the mesh's faces");
    }
}

/// A morph mesh written still shows the pose the glTF shows: its targets blended by its node's
/// weights (else the mesh's). The posed copy beside flag_wave was written at its base before.
#[test]
fn a_still_morph_mesh_is_written_in_its_pose() {
    let Some(python) = python() else { return };
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("posed.glb");
    flag_beside_a_posed_copy(&input);
    let (base, targets) = read_targets(&input, 2, 0);
    let want: Vec<[f32; 3]> = (base.iter().zip(&targets[3]))
        .map(|(b, d)| [b[0] + d[0], b[1] + d[1], b[2] + d[2]])
        .collect();
    for fmt in ["usda", "usdc"] {
        let usd = dir.path().join(format!("out.{fmt}"));
        tween_quietly(&input, &usd, &[]);
        let r = clean_usd_report(&python, &usd, fmt);
        let still = (r["meshes"].as_array().unwrap().iter())
            .find(|m| m["path"] == "/samples/still/still_flag")
            .unwrap_or_else(|| panic!("{fmt}: {}", r["meshes"]));
        assert_eq!(still["static"], true, "{fmt}");
        let text = run_tool(
            &python,
            "usd_points.py",
            &[usd.as_os_str(), "/samples/still/still_flag".as_ref()],
            fmt,
        );
        let points: Vec<[f32; 3]> = serde_json::from_slice(&text).unwrap();
        let most = (points.iter().zip(&want))
            .flat_map(|(a, b)| (0..3).map(move |c| (a[c] - b[c]).abs()))
            .fold(0.0f32, f32::max);
        assert!(
            most < 1e-6,
            "{fmt}: the copy's points within {most} of base + target 3"
        );
    }
}

/// flag_wave skinned: the flag (its node moved by 10 along x, which glTF ignores for a skinned
/// mesh) and the pole hang from an armature lifted 0.5, with a `base` joint at its origin and a
/// `tip` joint 1.5 along x that the flag's clip turns by a quarter turn about y over its two
/// seconds. The flag's vertices left of x = 1.5 follow `base`, those right of it blend into
/// `tip` over 0.75; the pole follows `tip` alone. Returns the tip's turn at time `t` (s).
fn skinned_flag(out: &Path) -> impl Fn(f64) -> glam::DQuat {
    let doc = inbetween::gltf::Document::open(&sample("flag_wave.glb")).unwrap();
    let mut json = doc.json.clone();
    let mut bin = doc.buffers[0].clone();
    let quarter = glam::DQuat::from_rotation_y(std::f64::consts::FRAC_PI_2);
    let push_u16 = |json: &mut serde_json::Value, bin: &mut Vec<u8>, values: &[u16]| {
        let views = json["bufferViews"].as_array_mut().unwrap();
        views.push(serde_json::json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": 2 * values.len()}));
        let view = views.len() - 1;
        bin.extend(values.iter().flat_map(|v| v.to_le_bytes()));
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        let accessors = json["accessors"].as_array_mut().unwrap();
        accessors.push(
            serde_json::json!({"bufferView": view, "componentType": 5123,
            "count": values.len() / 4, "type": "VEC4"}),
        );
        accessors.len() - 1
    };
    let influences = |json: &mut serde_json::Value, bin: &mut Vec<u8>, mesh: usize| {
        let pos = json["meshes"][mesh]["primitives"][0]["attributes"]["POSITION"]
            .as_u64()
            .unwrap() as usize;
        let xs: Vec<f64> = (doc.read_f64(pos).unwrap().0.chunks(3))
            .map(|p| p[0])
            .collect();
        let w: Vec<f32> = (xs.iter())
            .map(|&x| {
                if mesh == 1 {
                    1.0
                } else {
                    ((x - 1.5) / 0.75).clamp(0.0, 1.0) as f32
                }
            })
            .collect();
        let joints: Vec<u16> = w.iter().flat_map(|_| [0, 1, 0, 0]).collect();
        let weights: Vec<f32> = w.iter().flat_map(|&w| [1.0 - w, w, 0.0, 0.0]).collect();
        let j = push_u16(json, bin, &joints);
        let wt = push_f32_accessor(json, bin, &weights, "VEC4");
        let attributes = &mut json["meshes"][mesh]["primitives"][0]["attributes"];
        attributes["JOINTS_0"] = serde_json::json!(j);
        attributes["WEIGHTS_0"] = serde_json::json!(wt);
    };
    influences(&mut json, &mut bin, 0);
    influences(&mut json, &mut bin, 1);
    let ibm: Vec<f32> = [[0.0, -0.5, 0.0], [-1.5, -0.5, 0.0]]
        .iter()
        .flat_map(|t| glam::Mat4::from_translation(glam::Vec3::from(*t)).to_cols_array())
        .collect();
    let mut push = |json: &mut serde_json::Value, values: &[f32], ty: &str| {
        push_f32_accessor(json, &mut bin, values, ty)
    };
    let ibm = push(&mut json, &ibm, "MAT4");
    json["accessors"][ibm]["count"] = serde_json::json!(2);
    let times = push(&mut json, &[0.0, 2.0], "SCALAR");
    let q = quarter.as_quat();
    let turns = push(&mut json, &[0.0, 0.0, 0.0, 1.0, q.x, q.y, q.z, q.w], "VEC4");
    json["buffers"][0]["byteLength"] = serde_json::json!(bin.len());
    json["nodes"][0]["skin"] = serde_json::json!(0);
    json["nodes"][0]["translation"] = serde_json::json!([10.0, 0.0, 0.0]);
    json["nodes"][1]["skin"] = serde_json::json!(0);
    json["nodes"].as_array_mut().unwrap().extend([
        serde_json::json!({"name": "armature", "translation": [0.0, 0.5, 0.0], "children": [3]}),
        serde_json::json!({"name": "base", "children": [4]}),
        serde_json::json!({"name": "tip", "translation": [1.5, 0.0, 0.0]}),
    ]);
    json["scenes"][0]["nodes"]
        .as_array_mut()
        .unwrap()
        .push(2.into());
    json["skins"] = serde_json::json!([{"joints": [3, 4], "inverseBindMatrices": ibm}]);
    let clip = &mut json["animations"][0];
    clip["samplers"]
        .as_array_mut()
        .unwrap()
        .push(serde_json::json!({"input": times, "output": turns}));
    clip["channels"]
        .as_array_mut()
        .unwrap()
        .push(serde_json::json!({"sampler": 1, "target": {"node": 4, "path": "rotation"}}));
    write_glb(out, &json, &bin);
    move |t: f64| glam::DQuat::IDENTITY.slerp(quarter, (t / 2.0).clamp(0.0, 1.0))
}

/// A skinned mesh is baked into the point cache: each sample's points are where the glTF's
/// skin puts them at that time (every vertex within 1e-4 of linear blend skinning computed
/// here from the unskinned file's frames), with the mesh node's own transform cancelled as
/// glTF ignores it; a still mesh whose joints move (the pole) gets samples of its own, its
/// normals turned with it. Both were written in the bind pose before, with a warning line.
#[test]
fn skinned_meshes_are_baked_into_the_point_cache() {
    let Some(python) = python() else { return };
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("skinned.glb");
    let turn = skinned_flag(&input);
    let plain = dir.path().join("plain.usda");
    tween_quietly(&sample("flag_wave.glb"), &plain, &[]);
    let unskinned = world_points(&python, &plain, "/samples/flag/flag", "plain");
    let pole = world_points(&python, &plain, "/samples/pole/pole", "plain");
    let to_vec = |v: &serde_json::Value| {
        glam::DVec3::new(
            v[0].as_f64().unwrap(),
            v[1].as_f64().unwrap(),
            v[2].as_f64().unwrap(),
        )
    };
    // The skin's matrices at t: base at (0, 0.5, 0) as bound; tip turned about its origin.
    let lift = glam::DMat4::from_translation(glam::DVec3::new(0.0, 0.5, 0.0));
    // The flag's weights, from its stored (bind pose) x.
    let doc = inbetween::gltf::Document::open(&sample("flag_wave.glb")).unwrap();
    let weights: Vec<f64> = (doc.read_f64(0).unwrap().0.chunks(3))
        .map(|p| ((p[0] - 1.5) / 0.75).clamp(0.0, 1.0))
        .collect();
    let skinned = |p: glam::DVec3, w: f64, t: f64| {
        {
            let tip = lift
                * glam::DMat4::from_translation(glam::DVec3::new(1.5, 0.0, 0.0))
                * glam::DMat4::from_quat(turn(t))
                * glam::DMat4::from_translation(glam::DVec3::new(-1.5, -0.5, 0.0));
            (lift * glam::DMat4::from_translation(-glam::DVec3::Y * 0.5)) * (1.0 - w) + tip * w
        }
        .transform_point3(p)
    };
    for fmt in ["usda", "usdc", "usdz"] {
        let usd = dir.path().join(format!("skinned.{fmt}"));
        let r = tween_quietly(&input, &usd, &[]);
        let err = String::from_utf8_lossy(&r.stderr);
        assert!(!err.contains("bind pose"), "{fmt}: {err}");
        clean_usd_report(&python, &usd, fmt);
        let flag = world_points(&python, &usd, "/samples/flag/flag", fmt);
        let times = flag["times"].as_array().unwrap();
        assert_eq!(times.len(), 61, "{fmt}: a sample per frame");
        assert_eq!(flag["times"], unskinned["times"], "{fmt}");
        let mut most = 0.0f64;
        for (k, t) in times.iter().enumerate() {
            let t = t.as_f64().unwrap() / 30.0;
            let got = flag["points"][k].as_array().unwrap();
            for (v, p) in unskinned["points"][k]
                .as_array()
                .unwrap()
                .iter()
                .enumerate()
            {
                let want = skinned(to_vec(p), weights[v], t);
                most = most.max((to_vec(&got[v]) - want).length());
            }
        }
        assert!(most < 1e-4, "{fmt}: the flag within {most} of its skinning");
        // The pole: no frames of its own, but its joint turns over the clip's two seconds.
        let moved = world_points(&python, &usd, "/samples/pole/pole", fmt);
        let times = moved["times"].as_array().unwrap();
        assert!(times.len() >= 2, "{fmt}: the pole is sampled: {times:?}");
        let (mut most, mut most_normal) = (0.0f64, 0.0f64);
        let rest = pole["points"][0].as_array().unwrap();
        for (k, t) in times.iter().enumerate() {
            let t = t.as_f64().unwrap() / 30.0;
            for (v, p) in rest.iter().enumerate() {
                let want = skinned(to_vec(p), 1.0, t);
                most = most.max((to_vec(&moved["points"][k][v]) - want).length());
                let n = to_vec(&pole["normals"][0][v]);
                let want = turn(t) * n;
                most_normal = most_normal.max((to_vec(&moved["normals"][k][v]) - want).length());
            }
        }
        assert!(most < 1e-4, "{fmt}: the pole within {most} of its skinning");
        assert!(
            most_normal < 1e-4,
            "{fmt}: the pole's normals within {most_normal}"
        );
        let last = times.last().unwrap().as_f64().unwrap();
        assert!(last >= 60.0, "{fmt}: sampled to the clip's end: {times:?}");
    }
    // A second clip tweens the flag on another node (a copy off to the side) and turns the
    // tip again: the skinned flag plays none of its frames but follows its joint there, in
    // its still pose (the base: the mesh's default weights are zero), one sample per frame.
    let two = dir.path().join("two.glb");
    edited_glb(&input, &two, |j| {
        let clip = j["animations"][0].clone();
        let nodes = j["nodes"].as_array_mut().unwrap();
        nodes.push(serde_json::json!({"name": "copy", "mesh": 0, "translation": [0.0, 0.0, -5.0]}));
        let copy = nodes.len() - 1;
        j["scenes"][0]["nodes"]
            .as_array_mut()
            .unwrap()
            .push(copy.into());
        let mut second = clip;
        second["name"] = "second".into();
        second["channels"][0]["target"]["node"] = copy.into();
        j["animations"].as_array_mut().unwrap().push(second);
    });
    let base: Vec<glam::DVec3> = (doc.read_f64(0).unwrap().0.chunks(3))
        .map(|p| glam::DVec3::new(p[0], p[1], p[2]))
        .collect();
    for fmt in ["usda", "usdc"] {
        let usd = dir.path().join(format!("two.{fmt}"));
        tween_quietly(&two, &usd, &[]);
        clean_usd_report(&python, &usd, fmt);
        let flag = world_points(&python, &usd, "/samples/flag/flag", fmt);
        let times: Vec<f64> = (flag["times"].as_array().unwrap().iter())
            .map(|t| t.as_f64().unwrap())
            .collect();
        assert_eq!(times.len(), 122, "{fmt}: both clips' frames: {times:?}");
        assert!(
            times.windows(2).all(|w| w[0] < w[1]),
            "{fmt}: in time order"
        );
        let start = times[61];
        let mut most = 0.0f64;
        for (k, &code) in times.iter().enumerate().skip(61) {
            let t = (code - start) / 30.0;
            for (v, p) in base.iter().enumerate() {
                let want = skinned(*p, weights[v], t);
                most = most.max((to_vec(&flag["points"][k][v]) - want).length());
            }
        }
        assert!(
            most < 1e-4,
            "{fmt}: the flag in the second clip within {most}"
        );
    }
    // A mesh node scaled to nothing cannot hold the skinned points: said, written unskinned.
    let flat = dir.path().join("flat.glb");
    edited_glb(&input, &flat, |j| {
        j["nodes"][0]["scale"] = serde_json::json!([0.0, 0.0, 0.0])
    });
    let usd = dir.path().join("flat.usda");
    let r = run_ok(&["tween", s(&flat), "-o", s(&usd)]);
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        err.contains(
            "node \"flag\" is scaled to nothing, so mesh \"flag\"'s skin cannot be placed in it"
        ),
        "{err}"
    );
    clean_usd_report(&python, &usd, "flat");
}

/// A real character's skinned walk with a morph on top, baked: CesiumMan with a target (each
/// vertex 0.05 along its normal) that its walk clip weighs 0 -> 1 -> 0 over two seconds. With
/// `--method linear` (frames as a viewer blends targets) the point cache's world points equal
/// Blender's own import of the glTF (its armature and shape keys, PyPI bpy) at 0.5, 1 and 1.5
/// s within 1e-5 for every vertex; they were the bind pose before, 0.76 away at 1 s.
#[test]
fn a_skinned_walk_with_a_morph_matches_blender_s_import() {
    let Some(fx) = fixtures() else { return };
    let Some(bpy) = bpy() else { return };
    let Some(python) = python() else { return };
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("cesium_morph.glb");
    let doc = inbetween::gltf::Document::open(&fx.join("skinned/CesiumMan.glb")).unwrap();
    let mut json = doc.json.clone();
    let mut bin = doc.buffers[0].clone();
    let normal = json["meshes"][0]["primitives"][0]["attributes"]["NORMAL"]
        .as_u64()
        .unwrap() as usize;
    let bulge: Vec<f32> = (doc.read_f64(normal).unwrap().0.iter())
        .map(|n| (0.05 * n) as f32)
        .collect();
    let target = push_f32_accessor(&mut json, &mut bin, &bulge, "VEC3");
    let (lo, hi) = (bulge.chunks(3)).fold(([f32::MAX; 3], [f32::MIN; 3]), |(lo, hi), p| {
        (
            std::array::from_fn(|c| lo[c].min(p[c])),
            std::array::from_fn(|c| hi[c].max(p[c])),
        )
    });
    json["accessors"][target]["min"] = serde_json::json!(lo);
    json["accessors"][target]["max"] = serde_json::json!(hi);
    let times = push_f32_accessor(&mut json, &mut bin, &[0.0, 1.0, 2.0], "SCALAR");
    let weights = push_f32_accessor(&mut json, &mut bin, &[0.0, 1.0, 0.0], "SCALAR");
    json["meshes"][0]["primitives"][0]["targets"] = serde_json::json!([{"POSITION": target}]);
    json["meshes"][0]["weights"] = serde_json::json!([0.0]);
    let node = (json["nodes"].as_array().unwrap().iter())
        .position(|n| n["mesh"] == 0)
        .unwrap();
    let clip = &mut json["animations"][0];
    let samplers = clip["samplers"].as_array_mut().unwrap();
    samplers.push(serde_json::json!({"input": times, "output": weights}));
    let sampler = samplers.len() - 1;
    clip["channels"]
        .as_array_mut()
        .unwrap()
        .push(serde_json::json!({"sampler": sampler, "target": {"node": node, "path": "weights"}}));
    write_glb(&input, &json, &bin);
    let usd = dir.path().join("walk.usda");
    tween_quietly(&input, &usd, &["--method", "linear"]);
    clean_usd_report(&python, &usd, "walk");
    let prim = "/cesium_morph/Z_UP/Armature/Cesium_Man/Cesium_Man";
    let ours = world_points(&python, &usd, prim, "walk");
    let seconds = ["0.5", "1", "1.5"].map(String::from);
    let theirs = blender_points(&bpy, &input, None, &seconds);
    for (k, t) in seconds.iter().enumerate() {
        let code = t.parse::<f64>().unwrap() * 30.0;
        let at = (ours["times"].as_array().unwrap().iter())
            .position(|c| c.as_f64() == Some(code))
            .unwrap_or_else(|| panic!("no sample at {code}"));
        let most = farthest(&ours["points"][at], &theirs["points"][k]);
        assert!(most < 1e-5, "{t} s: within {most} of Blender's skinning");
    }
}

/// `blend` writes a USD point cache: Fox's Walk + Run at 0.5 as one Mesh sampled at each of the
/// blend's 23 frames (its skin baked), validators clean, every vertex within 1e-3 (of a fox 168
/// long) of Blender's import of the same blend written as .glb, playing it, at two frames. It
/// was refused ("a skeletal clip has no USD point-cache form here").
#[test]
fn a_blend_is_written_as_a_usd_point_cache() {
    let Some(fx) = fixtures() else { return };
    let Some(bpy) = bpy() else { return };
    let Some(python) = python() else { return };
    let dir = tempfile::tempdir().unwrap();
    let fox = fx.join("skinned/Fox.glb");
    let glb = dir.path().join("jog.glb");
    let blend = |out: &Path| {
        run_ok(&[
            "blend",
            s(&fox),
            "--clips",
            "Walk",
            "Run",
            "--weight",
            "0.5",
            "-o",
            s(out),
            "-q",
        ])
    };
    blend(&glb);
    let doc = inbetween::gltf::Document::open(&glb).unwrap();
    let jog = doc.json["animations"]
        .as_array()
        .unwrap()
        .last()
        .unwrap()
        .clone();
    assert_eq!(jog["name"], "Walk+Run");
    let input = jog["samplers"][0]["input"].as_u64().unwrap() as usize;
    let frames = doc.read_f64(input).unwrap().0;
    for fmt in ["usda", "usdc"] {
        let usd = dir.path().join(format!("jog.{fmt}"));
        blend(&usd);
        let r = clean_usd_report(&python, &usd, fmt);
        let rate = r["meta"]["timeCodesPerSecond"].as_f64().unwrap();
        let ours = world_points(&python, &usd, "/Fox/fox/fox1", fmt);
        let times = ours["times"].as_array().unwrap();
        assert_eq!(
            times.len(),
            frames.len(),
            "{fmt}: a sample per frame of the blend"
        );
        let picked = [6, 12];
        let seconds: Vec<String> = (picked.iter())
            .map(|&k| format!("{}", times[k].as_f64().unwrap() / rate))
            .collect();
        for (k, t) in picked.iter().zip(&seconds) {
            assert!(
                (t.parse::<f64>().unwrap() - frames[*k]).abs() < 1e-5,
                "{fmt}: {t}"
            );
        }
        let theirs = blender_points(&bpy, &glb, Some("Walk+Run"), &seconds);
        for (i, &k) in picked.iter().enumerate() {
            let most = farthest(&ours["points"][k], &theirs["points"][i]);
            assert!(most < 1e-3, "{fmt} frame {k}: within {most} of Blender's");
        }
    }
}

/// A blend that changes morph weights (RobotExpressive's Running with its face opening over
/// the clip) says in a line that its point cache does not play them (the head is written with
/// its default weights); the file as it is (its clips hold one face) says nothing of it.
#[test]
fn a_blend_s_changing_morph_weights_are_named() {
    let Some(fx) = fixtures() else { return };
    let dir = tempfile::tempdir().unwrap();
    let robot = fx.join("skinned/RobotExpressive.glb");
    let talking = dir.path().join("talking.glb");
    let doc = inbetween::gltf::Document::open(&robot).unwrap();
    let mut json = doc.json.clone();
    let mut bin = doc.buffers[0].clone();
    let running = (json["animations"].as_array().unwrap().iter())
        .position(|a| a["name"] == "Running")
        .unwrap();
    // 24 keys of 3 weights: the first target from 0 to 1.
    let ramp: Vec<f32> = (0..24).flat_map(|k| [k as f32 / 23.0, 0.0, 0.0]).collect();
    let opening = push_f32_accessor(&mut json, &mut bin, &ramp, "SCALAR");
    json["animations"][running]["samplers"][0]["output"] = opening.into();
    write_glb(&talking, &json, &bin);
    let line = "the blend changes the morph weights of \"Head\", which a point cache of its skeletal motion does not play";
    for (input, said) in [(&talking, true), (&robot, false)] {
        let usd = dir.path().join("out.usda");
        let r = run_ok(&[
            "blend",
            s(input),
            "--clips",
            "Walking",
            "Running",
            "-o",
            s(&usd),
        ]);
        let err =
            String::from_utf8_lossy(&r.stderr).to_string() + &String::from_utf8_lossy(&r.stdout);
        assert_eq!(err.contains(line), said, "{}: {err}", input.display());
    }
}

/// Material variants on material groups (two primitives drawing one vertex buffer: one Mesh,
/// a GeomSubset each): each subset bound as its variants map it, one with no material of its
/// own unbound but where a variant maps it; a variant no primitive maps binds nothing new.
#[test]
fn material_variants_bind_subsets_as_the_gltf_maps_them() {
    let Some(python) = python() else { return };
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("groups.glb");
    edited_glb(&sample("flag_wave.glb"), &input, |j| {
        let materials = j["materials"].as_array_mut().unwrap();
        let red = materials.len();
        materials.push(serde_json::json!({"name": "red"}));
        materials.push(serde_json::json!({"name": "blue"}));
        j["extensionsUsed"] = serde_json::json!(["KHR_materials_variants"]);
        j["extensions"] = serde_json::json!({"KHR_materials_variants":
            {"variants": [{"name": "day"}, {"name": "night mode"}, {"name": "spare"}]}});
        let prims = j["meshes"][0]["primitives"].as_array_mut().unwrap();
        let mut second = prims[0].clone();
        second.as_object_mut().unwrap().remove("material");
        prims[0]["extensions"] = serde_json::json!({"KHR_materials_variants": {"mappings": [
            {"material": red, "variants": [0]}, {"material": red + 1, "variants": [1]}]}});
        second["extensions"] = serde_json::json!({"KHR_materials_variants":
            {"mappings": [{"material": red, "variants": [1]}]}});
        prims.push(second);
    });
    let own = inbetween::gltf::Document::open(&input).unwrap().json["materials"][0]["name"]
        .as_str()
        .unwrap()
        .to_owned();
    for fmt in FORMATS {
        let out = dir.path().join(format!("groups.{fmt}"));
        tween_quietly(&input, &out, &["--fps", "4"]);
        let what = format!("groups.{fmt}");
        let looks = clean_looks(&python, &out, &what);
        let set = &looks["variants"]["materialVariant"];
        assert_eq!(set["selection"], "default", "{what}");
        let subsets: Vec<&str> = (looks["subsets"].as_array().unwrap().iter())
            .map(|s| s["path"].as_str().unwrap())
            .collect();
        assert_eq!(subsets.len(), 2, "{what}");
        let ends = |variant: &str, subset: usize| -> String {
            let m = set["bindings"][variant][subsets[subset]].as_str().unwrap();
            m.rsplit('/').next().unwrap_or("").to_owned()
        };
        for (variant, want) in [
            ("default", [own.as_str(), ""]),
            ("day", ["red", ""]),
            ("night_mode", ["blue", "red"]),
            ("spare", [own.as_str(), ""]),
        ] {
            let got = [ends(variant, 0), ends(variant, 1)];
            assert_eq!(got, want, "{what} {variant}");
        }
    }
}

/// What each prim keeps of its glTF object, by `tools/usd_meta.py`: per path its
/// displayName (null for none) and its customData "extras" (null for none).
fn usd_meta(python: &Path, usd: &Path, what: &str) -> serde_json::Value {
    serde_json::from_slice(&run_tool(python, "usd_meta.py", &[usd.as_os_str()], what)).unwrap()
}

/// Names that are not USD identifiers (a Blender-style "flag.001", a space, a colon, a name
/// in Japanese, two nodes of one name) are made identifiers and unique, and each prim shows
/// the glTF name it was made from as its `displayName`, so that none is lost; a prim whose
/// name is the glTF one, or an unnamed object's, has none. The names were lost before.
#[test]
fn names_usd_cannot_hold_are_kept_as_display_names() {
    let Some(python) = python() else { return };
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("names.glb");
    edited_glb(&sample("flag_wave.glb"), &input, |j| {
        j["scenes"][0]["name"] = "Shot #1".into();
        j["nodes"][0]["name"] = "flag.001".into();
        j["nodes"][1]["name"] = "flag.001".into();
        j["meshes"][0]["name"] = "旗 mesh".into();
        j["materials"][0]["name"] = "Cloth: \"red\"".into();
        j["meshes"][1].as_object_mut().unwrap().remove("name");
    });
    for fmt in ["usda", "usdc", "usdz"] {
        let usd = dir.path().join(format!("out.{fmt}"));
        tween_quietly(&input, &usd, &[]);
        clean_usd_report(&python, &usd, fmt);
        let shown: serde_json::Map<String, serde_json::Value> =
            (usd_meta(&python, &usd, fmt).as_object().unwrap().iter())
                .filter(|(path, _)| path.as_str() != "/")
                .map(|(path, m)| (path.clone(), m["display"].clone()))
                .collect();
        let expect = serde_json::json!({
            "/Shot__1": "Shot #1",
            "/Shot__1/flag_001": "flag.001",
            "/Shot__1/flag_001/__mesh": "旗 mesh",
            "/Shot__1/flag_001_1": "flag.001",
            "/Shot__1/flag_001_1/mesh1": null,
            "/Shot__1/Materials": null,
            "/Shot__1/Materials/Cloth___red_": "Cloth: \"red\"",
            "/Shot__1/Materials/Cloth___red_/PreviewSurface": null,
            "/Shot__1/Materials/pole_material": null,
            "/Shot__1/Materials/pole_material/PreviewSurface": null,
        });
        assert_eq!(serde_json::Value::Object(shown), expect, "{fmt}");
    }
}

/// glTF `extras` (Blender's custom properties) of the scene, nodes, meshes and materials are
/// each prim's `customData = { dictionary extras = {...} }`, every JSON kind kept: booleans,
/// whole numbers (`int`, or `int64` past 32 bits), reals, strings, arrays of one kind, nested
/// objects, and a mixed array as its JSON text; null entries and empty objects are left out,
/// and a mesh's `targetNames` (a point cache has no targets); reals at the ends of their
/// range exactly (the text in exponent form, which usd-core reads without a warning). The asset's copyright, generator
/// and extras are the layer's `customLayerData`. They were lost before.
#[test]
fn extras_travel_to_usd_as_custom_data() {
    let Some(python) = python() else { return };
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("extras.glb");
    let props = serde_json::json!({
        "lod": 2, "visible": true, "weight": 0.25, "big": 1u64 << 40, "note": "a \"b\"\nc",
        "tags": ["hero", "cloth"], "ids": [1, 2, 3], "reals": [0.5, 1], "flags": [true, false],
        "none": [], "mixed": [1, "a", null], "gone": null, "empty": {},
        "nested": {"a b": {"deep": -1.5e-3}, "gone": null},
        "huge": 1e300, "tiny": 5e-324, "u64": u64::MAX, "nul": "a\u{0}b"
    });
    edited_glb(&sample("flag_wave.glb"), &input, |j| {
        j["scenes"][0]["extras"] = serde_json::json!({"shot": "sq010_sh020", "frameStart": 1001});
        j["nodes"][0]["extras"] = props.clone();
        j["meshes"][0]["extras"] = serde_json::json!({"targetNames": ["a", "b"], "scan": "v3"});
        j["materials"][0]["extras"] = serde_json::json!({"hint": "cloth"});
        j["nodes"][1]["extras"] = serde_json::json!({});
        j["asset"]["copyright"] = "© 2026 Studio \"X\"".into();
        j["asset"]["extras"] = serde_json::json!({"author": "someone", "license": "CC-BY-4.0"});
    });
    let generator =
        inbetween::gltf::Document::open(&input).unwrap().json["asset"]["generator"].clone();
    assert!(generator.is_string());
    let mut kept = props.clone();
    for k in ["gone", "empty"] {
        kept.as_object_mut().unwrap().remove(k);
    }
    kept["mixed"] = "[1,\"a\",null]".into();
    kept["nested"].as_object_mut().unwrap().remove("gone");
    kept["reals"] = serde_json::json!([0.5, 1.0]);
    // Past int64 a double; a NUL (which ends a string in .usdc's tables) the replacement.
    kept["u64"] = serde_json::json!(u64::MAX as f64);
    kept["nul"] = "a\u{fffd}b".into();
    for fmt in ["usda", "usdc", "usdz"] {
        let usd = dir.path().join(format!("out.{fmt}"));
        tween_quietly(&input, &usd, &[]);
        clean_usd_report(&python, &usd, fmt);
        let meta = usd_meta(&python, &usd, fmt);
        let extras = |path: &str| meta[path]["extras"].clone();
        let scene = serde_json::json!({"shot": "sq010_sh020", "frameStart": 1001});
        assert_eq!(extras("/samples"), scene, "{fmt}");
        assert_eq!(extras("/samples/flag"), kept, "{fmt}");
        assert_eq!(
            extras("/samples/flag/flag"),
            serde_json::json!({"scan": "v3"}),
            "{fmt}"
        );
        let material = serde_json::json!({"hint": "cloth"});
        assert_eq!(
            extras("/samples/Materials/flag_material"),
            material,
            "{fmt}"
        );
        for path in ["/samples/pole", "/samples/pole/pole", "/samples/Materials"] {
            assert_eq!(extras(path), serde_json::Value::Null, "{fmt} {path}");
        }
        // The asset's copyright, generator and extras (a licence to credit) are the layer's.
        let layer = serde_json::json!({
            "copyright": "© 2026 Studio \"X\"",
            "extras": {"author": "someone", "license": "CC-BY-4.0"},
            "sourceGenerator": generator,
        });
        assert_eq!(meta["/"], layer, "{fmt}");
    }
}
