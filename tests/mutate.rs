//! Bounded mutation testing of the whole command on hostile inputs: real files edited at
//! random (from a fixed seed) in the ways that found crashes before (JSON fields set to huge,
//! negative, fractional or wrongly typed values, objects deleted, floats in the binary set to
//! NaN, infinity or 1e30, key times reversed, bytes flipped, files truncated), then run through
//! `tween` and `blend` under an address-space limit. Every run must exit 0 or 2 (no panic, no
//! abort, no signal), an exit 2 must print one line, and no output or temporary file may be
//! left behind by a failed run.

mod common;

use common::*;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::process::Command;

/// Address-space limit of every run (KiB for `ulimit -v`): 3 GiB, far above what the inputs
/// need, so an allocation sized from a hostile count fails the run instead of the machine.
const MEMORY_LIMIT_KIB: u64 = 3 << 20;

/// splitmix64: a small deterministic generator, so every run sees the same mutations.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
    fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

/// A glTF file as its JSON and binary chunk (empty for a `.gltf` with external buffers).
#[derive(Clone)]
struct Parts {
    json: Value,
    bin: Vec<u8>,
}

fn split(bytes: &[u8]) -> Parts {
    if !bytes.starts_with(b"glTF") {
        return Parts {
            json: serde_json::from_slice(bytes).unwrap(),
            bin: Vec::new(),
        };
    }
    let word = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
    let jlen = word(12);
    let json = serde_json::from_slice(&bytes[20..20 + jlen]).unwrap();
    let bin = if bytes.len() > 28 + jlen {
        let blen = word(20 + jlen);
        bytes[28 + jlen..28 + jlen + blen].to_vec()
    } else {
        Vec::new()
    };
    Parts { json, bin }
}

fn join(p: &Parts, glb: bool) -> Vec<u8> {
    if !glb {
        return serde_json::to_vec(&p.json).unwrap();
    }
    let mut bin = p.bin.clone();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    glb_bytes(&p.json, &bin)
}

/// Values that broke readers before: sizes past any buffer, negative and fractional numbers,
/// the wrong kinds of value.
fn evil(rng: &mut Rng) -> Value {
    rng.pick(&[
        json!(0),
        json!(1),
        json!(2),
        json!(3),
        json!(-1),
        json!(4294967295u64),
        json!(2147483647),
        json!(18446744073709551615u64),
        json!(1e30),
        json!(-1e30),
        json!(0.5),
        json!(5120),
        json!(5126),
        json!("VEC3"),
        json!("MAT4"),
        json!("x"),
        json!(null),
        json!({}),
        json!([]),
        json!([1e30, -1e30, 0.0, 1.0]),
        json!(true),
    ])
    .clone()
}

/// One JSON edit: a field of an accessor, buffer view, buffer, sampler, channel, node, skin,
/// primitive or sparse block set to an evil value or deleted, or a whole entry replaced.
fn edit_json(json: &mut Value, rng: &mut Rng) -> String {
    let mut places: Vec<String> = Vec::new();
    for key in [
        "accessors",
        "bufferViews",
        "buffers",
        "nodes",
        "skins",
        "meshes",
        "images",
    ] {
        for i in 0..json[key].as_array().map_or(0, Vec::len) {
            places.push(format!("/{key}/{i}"));
        }
    }
    for (a, anim) in json["animations"]
        .as_array()
        .cloned()
        .unwrap_or_default()
        .iter()
        .enumerate()
    {
        for kind in ["samplers", "channels"] {
            for i in 0..anim[kind].as_array().map_or(0, Vec::len) {
                places.push(format!("/animations/{a}/{kind}/{i}"));
            }
        }
    }
    for (m, mesh) in json["meshes"]
        .as_array()
        .cloned()
        .unwrap_or_default()
        .iter()
        .enumerate()
    {
        for p in 0..mesh["primitives"].as_array().map_or(0, Vec::len) {
            places.push(format!("/meshes/{m}/primitives/{p}"));
            places.push(format!("/meshes/{m}/primitives/{p}/attributes"));
            for t in 0..mesh["primitives"][p]["targets"]
                .as_array()
                .map_or(0, Vec::len)
            {
                places.push(format!("/meshes/{m}/primitives/{p}/targets/{t}"));
            }
        }
    }
    if places.is_empty() {
        return "nothing to edit".into();
    }
    let place = rng.pick(&places).clone();
    let fields = [
        "count",
        "byteOffset",
        "byteLength",
        "byteStride",
        "componentType",
        "type",
        "bufferView",
        "buffer",
        "input",
        "output",
        "sampler",
        "interpolation",
        "node",
        "children",
        "joints",
        "inverseBindMatrices",
        "matrix",
        "translation",
        "rotation",
        "scale",
        "mesh",
        "skin",
        "weights",
        "indices",
        "mode",
        "POSITION",
        "NORMAL",
        "TANGENT",
        "TEXCOORD_0",
        "target",
        "path",
        "sparse",
        "normalized",
        "uri",
        "min",
        "max",
        "primitives",
        "targets",
        "attributes",
    ];
    let Some(value) = json.pointer_mut(&place) else {
        return format!("{place} is gone");
    };
    match rng.below(10) {
        0 => {
            let v = evil(rng);
            *value = v.clone();
            format!("{place} = {v}")
        }
        1 => {
            if let Some(o) = value.as_object_mut() {
                let keys: Vec<String> = o.keys().cloned().collect();
                if let Some(k) = keys.get(rng.below(keys.len().max(1))) {
                    o.remove(k);
                    return format!("{place}: removed {k}");
                }
            }
            "no field to remove".into()
        }
        2 => {
            let sparse = json!({
                "count": evil(rng),
                "indices": { "bufferView": 0, "componentType": 5125 },
                "values": { "bufferView": 0 }
            });
            if let Some(o) = value.as_object_mut() {
                o.insert("sparse".into(), sparse.clone());
            }
            format!("{place}.sparse = {sparse}")
        }
        _ => {
            let f = *rng.pick(&fields);
            let v = evil(rng);
            if let Some(o) = value.as_object_mut() {
                o.insert(f.to_string(), v.clone());
            }
            format!("{place}.{f} = {v}")
        }
    }
}

/// Float accessors with a buffer view in the binary chunk: (byte offset of element 0, stride,
/// count), for pokes at real float data (positions, targets, key times, rotations).
fn float_spans(json: &Value) -> Vec<(usize, usize, usize)> {
    let mut out = Vec::new();
    for a in json["accessors"].as_array().cloned().unwrap_or_default() {
        if a["componentType"] != 5126 {
            continue;
        }
        let Some(v) = a["bufferView"].as_u64() else {
            continue;
        };
        let bv = &json["bufferViews"][v as usize];
        if bv["buffer"].as_u64().unwrap_or(0) != 0 {
            continue;
        }
        let start = bv["byteOffset"].as_u64().unwrap_or(0) + a["byteOffset"].as_u64().unwrap_or(0);
        let stride = bv["byteStride"].as_u64().unwrap_or(4);
        out.push((
            start as usize,
            stride as usize,
            a["count"].as_u64().unwrap_or(0) as usize,
        ));
    }
    out
}

/// A mutated copy of `original` (a `.glb` or a `.gltf`), and what was done.
fn mutate(original: &[u8], glb: bool, rng: &mut Rng) -> (Vec<u8>, String) {
    let mut parts = split(original);
    match rng.below(20) {
        0..=9 => {
            let mut what = Vec::new();
            for _ in 0..1 + rng.below(3) {
                what.push(edit_json(&mut parts.json, rng));
            }
            (join(&parts, glb), what.join("; "))
        }
        10..=13 if !parts.bin.is_empty() => {
            let spans = float_spans(&parts.json);
            if spans.is_empty() {
                return (join(&parts, glb), "no float data".into());
            }
            let (start, stride, count) = *rng.pick(&spans);
            let at = start + stride * rng.below(count);
            let v = *rng.pick(&[f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 1e30, -1e30, 0.0]);
            if at + 4 <= parts.bin.len() {
                parts.bin[at..at + 4].copy_from_slice(&v.to_le_bytes());
            }
            (
                join(&parts, glb),
                format!("float at byte {at} of the binary chunk = {v}"),
            )
        }
        14 => {
            // Key times reversed: the input accessor of a sampler points at descending data.
            let mut samplers = Vec::new();
            for anim in parts.json["animations"]
                .as_array()
                .cloned()
                .unwrap_or_default()
            {
                for s in anim["samplers"].as_array().cloned().unwrap_or_default() {
                    samplers.extend(s["input"].as_u64());
                }
            }
            if samplers.is_empty() || parts.bin.is_empty() {
                return (join(&parts, glb), "no sampler".into());
            }
            let input = *rng.pick(&samplers) as usize;
            let spans = float_spans(&parts.json);
            let acc = &parts.json["accessors"][input];
            let count = acc["count"].as_u64().unwrap_or(0) as usize;
            if let Some(&(start, _, _)) = spans.iter().find(|s| s.2 == count) {
                let end = (start + 4 * count).min(parts.bin.len());
                let mut keys: Vec<[u8; 4]> = parts.bin[start..end]
                    .chunks_exact(4)
                    .map(|c| c.try_into().unwrap())
                    .collect();
                keys.reverse();
                for (k, b) in keys.iter().enumerate() {
                    parts.bin[start + 4 * k..start + 4 * k + 4].copy_from_slice(b);
                }
            }
            (
                join(&parts, glb),
                format!("key times of accessor {input} reversed"),
            )
        }
        15..=17 => {
            let mut bytes = original.to_vec();
            let n = 1 + rng.below(8);
            for _ in 0..n {
                let at = rng.below(bytes.len());
                bytes[at] ^= 1 << rng.below(8);
            }
            (bytes, format!("{n} bits flipped"))
        }
        _ => {
            let cut = rng.below(original.len());
            (
                original[..cut].to_vec(),
                format!("truncated to {cut} bytes"),
            )
        }
    }
}

/// Run `args` under the memory limit; the exit status and stderr.
fn run_limited(args: &[&str]) -> (Option<i32>, String) {
    let out = Command::new("sh")
        .arg("-c")
        .arg(format!("ulimit -v {MEMORY_LIMIT_KIB}; exec \"$0\" \"$@\""))
        .arg(env!("CARGO_BIN_EXE_inbetween"))
        .args(args)
        .output()
        .expect("run inbetween");
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Files in `dir` other than `keep`.
fn leftovers(dir: &Path, keep: &[PathBuf]) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| !keep.contains(p))
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect()
}

/// One source of mutations: the file, the extra files beside it (a `.gltf`'s `.bin`), and the
/// command to run on it.
struct Case {
    file: PathBuf,
    command: &'static [&'static str],
}

/// Flamingo compressed by gltfpack -cc (meshopt) and glTF-Transform draco, in `dir`, when the
/// node tools are installed: mutations then reach the decoders.
fn compressed_cases(dir: &Path) -> Vec<Case> {
    let (Some(fx), Some(bin)) = (fixtures(), node_bin()) else {
        return Vec::new();
    };
    let flamingo = fx.join("morph-keyframes/Flamingo.glb");
    let mut out = Vec::new();
    for (name, tool, args) in [
        ("meshopt.glb", "gltfpack", vec!["-cc", "-af", "0", "-i"]),
        ("draco.glb", "gltf-transform", vec!["draco"]),
    ] {
        let file = dir.join(name);
        let mut line: Vec<&std::ffi::OsStr> = args.iter().map(|a| a.as_ref()).collect();
        line.push(flamingo.as_os_str());
        if tool == "gltfpack" {
            line.push("-o".as_ref());
        }
        line.push(file.as_os_str());
        node_tool(&bin, tool, line);
        out.push(Case {
            file,
            command: &["tween"],
        });
    }
    out
}

fn cases() -> Vec<Case> {
    let mut out = vec![
        Case {
            file: sample("flag_wave.glb"),
            command: &["tween"],
        },
        Case {
            file: sample("bar_twist.glb"),
            command: &["tween", "--fps", "24"],
        },
    ];
    if let Some(fx) = fixtures() {
        out.extend([
            Case {
                file: fx.join("morph-keyframes/Flamingo.glb"),
                command: &["tween"],
            },
            Case {
                file: fx.join("morph-khronos/AnimatedMorphCube/glTF/AnimatedMorphCube.gltf"),
                command: &["tween"],
            },
            Case {
                file: fx.join("skinned/Fox.glb"),
                command: &["blend", "--clips", "Walk", "Run"],
            },
            Case {
                file: fx.join("skinned/RobotExpressive.glb"),
                command: &["blend", "--clips", "Walking", "Running", "--weight", "0.25"],
            },
        ]);
    }
    out
}

#[test]
fn mutated_inputs_exit_cleanly_under_a_memory_limit() {
    let per_case: usize = std::env::var("INBETWEEN_MUTATIONS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(120);
    let seed = std::env::var("INBETWEEN_MUTATION_SEED")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0x1B_E7_EE);
    let mut rng = Rng(seed);
    let mut failures = Vec::new();
    let mut exits = [0usize; 2];
    let compressed = tempfile::tempdir().unwrap();
    for case in cases()
        .into_iter()
        .chain(compressed_cases(compressed.path()))
    {
        let original = std::fs::read(&case.file).unwrap();
        let glb = original.starts_with(b"glTF");
        let ext = if glb { "glb" } else { "gltf" };
        for k in 0..per_case {
            let dir = tempfile::tempdir().unwrap();
            let input = dir.path().join(format!("in.{ext}"));
            let (bytes, what) = mutate(&original, glb, &mut rng);
            std::fs::write(&input, &bytes).unwrap();
            let mut keep = vec![input.clone()];
            // A .gltf keeps its external buffers beside it.
            if !glb {
                for e in std::fs::read_dir(case.file.parent().unwrap())
                    .unwrap()
                    .flatten()
                {
                    if e.path().extension().is_some_and(|x| x == "bin") {
                        let to = dir.path().join(e.file_name());
                        std::fs::copy(e.path(), &to).unwrap();
                        keep.push(to);
                    }
                }
            }
            let output = dir.path().join("out.glb");
            let mut args: Vec<&str> = case.command.to_vec();
            args.extend([
                input.to_str().unwrap(),
                "-o",
                output.to_str().unwrap(),
                "-q",
            ]);
            let (code, stderr) = run_limited(&args);
            let label = format!("{} #{k} ({what})", case.file.display());
            match code {
                Some(0) => {
                    exits[0] += 1;
                    keep.push(output.clone());
                }
                Some(2) => {
                    exits[1] += 1;
                    let lines = stderr.trim_end().lines().count();
                    if lines != 1 || !stderr.starts_with("inbetween: error: ") {
                        failures.push(format!("{label}: exit 2 with {lines} lines: {stderr}"));
                    }
                    if output.exists() {
                        failures.push(format!("{label}: exit 2 left {}", output.display()));
                    }
                }
                other => failures.push(format!("{label}: exit {other:?}: {stderr}")),
            }
            let left = leftovers(dir.path(), &keep);
            if !left.is_empty() {
                failures.push(format!("{label}: left {left:?}"));
            }
        }
    }
    eprintln!(
        "mutation runs: {} exited 0, {} exited 2 with one line, {} failures",
        exits[0],
        exits[1],
        failures.len()
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
