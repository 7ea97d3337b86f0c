//! Real pipeline files: every morph fixture compressed by the real tools (gltfpack -cc with
//! EXT and KHR meshopt, glTF-Transform meshopt, draco and quantize) tweens to the frames of the
//! uncompressed file within the compression's quantization, and the output validates.

mod common;

use common::*;
use std::path::{Path, PathBuf};

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The compressors, as (name, command line after the tool's name with IN and OUT).
const VARIANTS: &[(&str, &str, &[&str])] = &[
    // -af 0: no resampling of the animation (gltfpack resamples at 30 Hz by default, which
    // makes new keys); -kn -km -ke: names, materials and extras kept.
    (
        "gltfpack -cc",
        "gltfpack",
        &[
            "-i", "IN", "-o", "OUT", "-cc", "-af", "0", "-kn", "-km", "-ke",
        ],
    ),
    // -vpf: float positions through the exponential filter, lossy: gltfpack declares the bounds
    // of the values before it, which the output, written plain, must not keep.
    (
        "gltfpack -cc -vpf",
        "gltfpack",
        &[
            "-i", "IN", "-o", "OUT", "-cc", "-vpf", "-af", "0", "-kn", "-km", "-ke",
        ],
    ),
    (
        "gltfpack -c -ce khr",
        "gltfpack",
        &[
            "-i", "IN", "-o", "OUT", "-c", "-ce", "khr", "-af", "0", "-kn", "-km", "-ke",
        ],
    ),
    (
        "gltf-transform meshopt",
        "gltf-transform",
        &["meshopt", "IN", "OUT"],
    ),
    (
        "gltf-transform draco",
        "gltf-transform",
        &["draco", "IN", "OUT"],
    ),
    (
        "gltf-transform quantize",
        "gltf-transform",
        &["quantize", "IN", "OUT"],
    ),
];

/// The morph fixtures with key animations.
fn morph_fixtures(fx: &Path) -> Vec<PathBuf> {
    [
        "morph-keyframes/Flamingo.glb",
        "morph-keyframes/Parrot.glb",
        "morph-keyframes/Flamingo_cubicspline_unindexed.glb",
        "morph-khronos/AnimatedMorphCube/glTF/AnimatedMorphCube.gltf",
        "morph-khronos/AnimatedMorphSphere/glTF/AnimatedMorphSphere.gltf",
        "morph-khronos/MorphStressTest/glTF/MorphStressTest.gltf",
        "morph-khronos/SimpleMorph/glTF/SimpleMorph.gltf",
    ]
    .iter()
    .map(|f| fx.join(f))
    .collect()
}

#[test]
fn compressed_fixtures_tween_to_the_frames_of_the_uncompressed_files() {
    let (Some(fx), Some(bin)) = (fixtures(), node_bin()) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let mut rows = Vec::new();
    // Compressed inputs whose output grew past the warning and was told why.
    let mut grown = 0;
    for (k, input) in morph_fixtures(&fx).iter().enumerate() {
        let plain = dir.path().join(format!("plain{k}.glb"));
        tween_quietly(input, &plain, &[]);
        let prims = Document::open(&plain).unwrap().json["meshes"][0]["primitives"]
            .as_array()
            .unwrap()
            .len();
        for (name, tool, args) in VARIANTS {
            let packed = dir
                .path()
                .join(format!("packed{k}_{}.glb", tool.len() + args.len()));
            let args: Vec<String> = args
                .iter()
                .map(|a| match *a {
                    "IN" => s(input).to_string(),
                    "OUT" => s(&packed).to_string(),
                    a => a.to_string(),
                })
                .collect();
            node_tool(&bin, tool, &args);
            let out = dir.path().join(format!("out{k}.glb"));
            let told = run_ok(&["tween", s(&packed), "-o", s(&out)]);
            assert_valid(&out);
            // A growth warning says when it is the compression undone.
            let err = String::from_utf8_lossy(&told.stderr);
            if let Some(w) = err.lines().find(|l| l.contains("x the size of the input")) {
                let names = w.contains("--meshopt compresses it");
                assert_eq!(names, !name.ends_with("quantize"), "{name}: {w}");
                grown += names as usize;
            }
            // The output is uncompressed: no compression extension is left.
            let written = Document::open(&out).unwrap().json;
            for e in [
                "EXT_meshopt_compression",
                "KHR_meshopt_compression",
                "KHR_draco_mesh_compression",
            ] {
                assert!(
                    !written.to_string().contains(e),
                    "{name}: {e} left in the output"
                );
            }
            // inspect says what it decodes.
            let v: serde_json::Value =
                serde_json::from_slice(&run_ok(&["inspect", s(&packed), "--json"]).stdout).unwrap();
            let decoded: Vec<&str> = v["extensions"]
                .as_array()
                .unwrap()
                .iter()
                .filter(|e| e["status"] == "decoded")
                .map(|e| e["name"].as_str().unwrap())
                .collect();
            assert_eq!(
                decoded.is_empty(),
                name.ends_with("quantize"),
                "{name}: {v}"
            );
            if let Some(py) = python() {
                let json = dir.path().join("inspect.json");
                std::fs::write(&json, v.to_string()).unwrap();
                check_schema(&py, "inspect.schema.json", &json, name);
            }
            let diag = {
                let (_, f) = world_frames(&plain, 0, 0);
                let (lo, hi) = f[0]
                    .iter()
                    .fold((glam::DVec3::MAX, glam::DVec3::MIN), |(l, h), p| {
                        (l.min(*p), h.max(*p))
                    });
                (hi - lo).length()
            };
            // Every primitive and every clip of mesh 0.
            let (mut worst_key, mut worst_frame, mut frames) = (0.0f64, 0.0f64, 0);
            for prim in 0..prims {
                for channel in 0.. {
                    if channel >= mesh0_samplers(&Document::open(&plain).unwrap()).len() {
                        break;
                    }
                    let (ta, fa) = world_frames(&plain, prim, channel);
                    let (tb, fb) = world_frames(&out, prim, channel);
                    assert_eq!(ta, tb, "{name} on {}: frame times", input.display());
                    let keys = key_times(input, channel);
                    let m = matching(&fb[0], &fa[0]);
                    for ((t, a), b) in ta.iter().zip(&fa).zip(&fb) {
                        let e = b
                            .iter()
                            .zip(&m)
                            .map(|(p, &i)| p.distance(a[i]))
                            .fold(0.0f64, f64::max);
                        if keys.iter().any(|k| (k - t).abs() < 1e-5) {
                            worst_key = worst_key.max(e);
                        }
                        worst_frame = worst_frame.max(e);
                        frames += 1;
                    }
                }
            }
            // In-between frames deviate no more than the keys' own quantization puts them off.
            assert!(
                worst_frame <= 2.0 * worst_key + 1e-6 * diag,
                "{name} on {}: frames {worst_frame} off, keys {worst_key}",
                input.display()
            );
            rows.push(format!(
                "{} | {name} | {} | {:.2e} | {:.2e}",
                input.file_name().unwrap().to_string_lossy(),
                frames,
                worst_key / diag,
                worst_frame / diag
            ));
        }
    }
    eprintln!("fixture | compressed by | frames | worst key / diagonal | worst frame / diagonal");
    for r in &rows {
        eprintln!("{r}");
    }
    eprintln!("{grown} outputs grew past the warning, the compression undone named");
    assert!(grown > 0);
}

/// Key times of the `channel`-th weights channel of mesh 0 in `path`.
fn key_times(path: &Path, channel: usize) -> Vec<f64> {
    let doc = Document::open(path).unwrap();
    let (anim, sampler) = mesh0_samplers(&doc)[channel];
    let input = doc.json["animations"][anim]["samplers"][sampler]["input"]
        .as_u64()
        .unwrap();
    doc.read_f64(input as usize).unwrap().0
}

use inbetween::gltf::Document;

/// A Draco stream with edgebreaker connectivity numbers the vertices in its own order, which
/// morph targets stored apart (as the extension has them) do not follow: FBX2glTF's `-d` writes
/// such files, and every viewer plays them scrambled (its Flamingo: each decoded vertex is an
/// original one, within Draco's quantization, at another index in 1625 of 1626). Refused with
/// one line saying so, as is a stream of more vertices than its accessors declare (its
/// synthetic face rig: 1684 against 1683). Built as FBX2glTF builds it: bar_twist without its
/// target through glTF-Transform's Draco (edgebreaker where a mesh has no targets), its target
/// then added beside the stream.
#[test]
fn morph_targets_beside_a_renumbering_draco_stream_are_refused() {
    let Some(bin) = node_bin() else { return };
    let dir = tempfile::tempdir().unwrap();
    let bare = dir.path().join("bare.glb");
    edited_glb(&sample("bar_twist.glb"), &bare, |j| {
        let m = &mut j["meshes"][0];
        m["primitives"][0]
            .as_object_mut()
            .unwrap()
            .remove("targets");
        m.as_object_mut().unwrap().remove("weights");
        m.as_object_mut().unwrap().remove("extras");
    });
    let packed = dir.path().join("packed.glb");
    node_tool(&bin, "gltf-transform", ["draco", s(&bare), s(&packed)]);
    let target = Document::open(&sample("bar_twist.glb"))
        .unwrap()
        .read_f64(2)
        .unwrap()
        .0
        .iter()
        .map(|&x| x as f32)
        .collect::<Vec<_>>();
    let (json, data) = glb_parts(&packed);
    // The stream's header: "DRACO", version, a triangle mesh (1), edgebreaker (1).
    let draco = &json["meshes"][0]["primitives"][0]["extensions"]["KHR_draco_mesh_compression"];
    let view = &json["bufferViews"][draco["bufferView"].as_u64().unwrap() as usize];
    let at = view["byteOffset"].as_u64().unwrap_or(0) as usize;
    assert_eq!(&data[at..at + 5], b"DRACO");
    assert_eq!(data[at + 7..at + 9], [1, 1], "edgebreaker");
    let with_target = |out: &Path, declared: Option<u64>| {
        let (mut json, mut data) = (json.clone(), data.clone());
        let t = push_f32_accessor(&mut json, &mut data, &target, "VEC3");
        let p = &mut json["meshes"][0]["primitives"][0];
        p["targets"] = serde_json::json!([{ "POSITION": t }]);
        if let Some(n) = declared {
            let a = p["attributes"]["POSITION"].as_u64().unwrap() as usize;
            json["accessors"][a]["count"] = n.into();
            json["accessors"][t]["count"] = n.into();
        }
        json["meshes"][0]["weights"] = serde_json::json!([0.0]);
        write_glb(out, &json, &data);
    };
    let n = (target.len() / 3) as u64;
    for (declared, what) in [
        (
            None,
            "the stream is edgebreaker-encoded, which renumbers the vertices",
        ),
        (
            Some(n - 1),
            &format!(
                "the stream decodes to {n} vertices where its accessors declare {}",
                n - 1
            )[..],
        ),
    ] {
        let input = dir.path().join("in.glb");
        with_target(&input, declared);
        let out = dir.path().join("out.glb");
        for args in [
            &["tween", s(&input), "-o", s(&out)][..],
            &["inspect", s(&input)][..],
        ] {
            assert_refused(args, "in.glb", what, &out);
        }
    }
}
