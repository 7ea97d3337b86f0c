//! Shared helpers of the integration tests.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

pub fn sample(name: &str) -> PathBuf {
    root().join("samples").join(name)
}

/// `../shared/fixtures`, or `None` (with the reason printed) when it is not there.
pub fn fixtures() -> Option<PathBuf> {
    let dir = root().join("../shared/fixtures");
    if dir.is_dir() {
        Some(dir)
    } else {
        skipped(&format!(
            "{} is missing (real-file fixtures are optional)",
            dir.display()
        ));
        None
    }
}

fn require_tools() -> bool {
    std::env::var_os("INBETWEEN_REQUIRE_TOOLS").is_some()
}

/// Announce a missing test tool: fail when tools are required, else skip with the reason.
/// Say that a test skips part of its work, on stderr and in the file `INBETWEEN_SKIP_LOG`
/// names (scripts/test.sh prints that file's lines after the run, so the summary shows them).
pub fn skipped(why: &str) {
    let test = std::thread::current().name().unwrap_or("?").to_string();
    let bin = std::env::current_exe()
        .ok()
        .and_then(|p| {
            p.file_stem().map(|s| {
                s.to_string_lossy()
                    .split('-')
                    .next()
                    .unwrap_or("")
                    .to_string()
            })
        })
        .unwrap_or_default();
    eprintln!("skipped: {why}");
    if let Some(log) = std::env::var_os("INBETWEEN_SKIP_LOG") {
        use std::io::Write;
        if let Ok(mut f) = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(log)
        {
            let _ = writeln!(f, "{bin}::{test}: {why}");
        }
    }
}

pub fn missing_tool(what: &str) -> bool {
    if require_tools() {
        panic!("{what} is missing; run scripts/setup-tools.sh");
    }
    skipped(&format!("{what} is missing (run scripts/setup-tools.sh)"));
    true
}

pub fn inbetween(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_inbetween"))
        .args(args)
        .output()
        .expect("run inbetween")
}

/// Run inbetween and insist on success.
pub fn run_ok(args: &[&str]) -> Output {
    let out = inbetween(args);
    assert!(
        out.status.success(),
        "inbetween {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// The validator report of a file: (errors, warnings, full JSON line); `None` if the validator
/// is not installed and tools are not required.
pub fn validate(file: &Path) -> Option<(u64, u64, String)> {
    let dir = root().join("tools/node");
    if !dir.join("node_modules/gltf-validator").is_dir()
        && missing_tool("the glTF validator (tools/node/node_modules)")
    {
        return None;
    }
    let out = Command::new("node")
        .arg(dir.join("validate.mjs"))
        .arg(file)
        .output()
        .expect("run node");
    let line = String::from_utf8_lossy(&out.stdout).trim().to_string();
    let v: serde_json::Value = serde_json::from_str(&line).unwrap_or_else(|e| {
        panic!(
            "validator output for {}: {e}: {line} {}",
            file.display(),
            String::from_utf8_lossy(&out.stderr)
        )
    });
    Some((
        v["errors"].as_u64().unwrap(),
        v["warnings"].as_u64().unwrap(),
        line,
    ))
}

/// Assert that the validator finds no error and no warning.
pub fn assert_valid(file: &Path) {
    if let Some((e, w, line)) = validate(file) {
        assert!(
            e == 0 && w == 0,
            "validator: {e} errors, {w} warnings: {line}"
        );
    }
}

/// The project's python (numpy, scipy, usd-core), if installed.
pub fn python() -> Option<PathBuf> {
    let p = root().join(".venv/bin/python");
    if p.exists() {
        Some(p)
    } else {
        missing_tool("the python venv (.venv)");
        None
    }
}

/// Morph target POSITION deltas of mesh `mesh` primitive `prim`, read back with the gltf crate.
pub fn read_targets(path: &Path, mesh: usize, prim: usize) -> (Vec<[f32; 3]>, Vec<Vec<[f32; 3]>>) {
    let (doc, buffers, _) = gltf::import(path).expect("gltf crate reads the output");
    let m = doc.meshes().nth(mesh).unwrap();
    let p = m.primitives().nth(prim).unwrap();
    let reader = p.reader(|b| Some(&buffers[b.index()]));
    let base: Vec<[f32; 3]> = reader.read_positions().unwrap().collect();
    let targets = reader
        .read_morph_targets()
        .map(|(pos, _, _)| pos.expect("POSITION delta").collect())
        .collect();
    (base, targets)
}

/// Per-component least and greatest of `values` (elements of `n` components), as an
/// accessor's min and max declare them.
pub fn column_bounds(values: &[f64], n: usize) -> (Vec<f64>, Vec<f64>) {
    let column = |c: usize| values.iter().skip(c).step_by(n).copied();
    (
        (0..n).map(|c| column(c).fold(f64::MAX, f64::min)).collect(),
        (0..n).map(|c| column(c).fold(f64::MIN, f64::max)).collect(),
    )
}

pub fn diag(points: &[glam::DVec3]) -> f64 {
    inbetween::tween::bbox_diagonal(points)
}

/// Error and warning codes the validator reports for a file, with their counts.
fn issue_counts(line: &str) -> std::collections::BTreeMap<String, usize> {
    let v: serde_json::Value = serde_json::from_str(line).unwrap();
    let mut out = std::collections::BTreeMap::new();
    for m in v["messages"].as_array().unwrap() {
        if matches!(m["severity"].as_str(), Some("error") | Some("warning")) {
            *out.entry(m["code"].as_str().unwrap().to_string())
                .or_default() += 1;
        }
    }
    out
}

/// Assert that `output` has no validator error or warning that `input` did not already have
/// (per issue code, at most as many).
pub fn assert_no_new_issues(input: &Path, output: &Path) {
    let (Some((_, _, a)), Some((_, _, b))) = (validate(input), validate(output)) else {
        return;
    };
    let (before, after) = (issue_counts(&a), issue_counts(&b));
    for (code, n) in &after {
        let m = before.get(code).copied().unwrap_or(0);
        assert!(
            *n <= m,
            "{}: {n} x {code} (the input had {m})",
            output.display()
        );
    }
}

/// `tools/check_usd.py`'s report of the USD file `usd` (its sample arrays dumped beside it,
/// to `dump.bin`), parsed. `what` prefixes a failure message.
pub fn usd_report(python: &Path, usd: &Path, what: &str) -> serde_json::Value {
    let dump = usd.with_file_name("dump.bin");
    let out = run_tool(
        python,
        "check_usd.py",
        &[usd.as_os_str(), dump.as_os_str()],
        what,
    );
    serde_json::from_slice(&out).unwrap()
}

/// [`usd_report`], insisting that it found no errors and usd-core's validators nothing.
pub fn clean_usd_report(python: &Path, usd: &Path, what: &str) -> serde_json::Value {
    let r = usd_report(python, usd, what);
    for key in ["errors", "validation"] {
        assert!(
            r[key].as_array().unwrap().is_empty(),
            "{what}: {key} {}",
            r[key]
        );
    }
    r
}

/// Run `tools/<script>` with the project's python and `args`, insisting on success; returns
/// its standard output. `what` prefixes the failure message.
pub fn run_tool(python: &Path, script: &str, args: &[&std::ffi::OsStr], what: &str) -> Vec<u8> {
    let out = Command::new(python)
        .arg(root().join("tools").join(script))
        .args(args)
        .output()
        .expect("run python");
    assert!(
        out.status.success(),
        "{what}: {script} failed: {}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    out.stdout
}

/// Check the JSON file `json` against `schemas/<schema>` with tools/check_schema.py (`what`
/// names it in a failure).
pub fn check_schema(python: &Path, schema: &str, json: &Path, what: &str) {
    let schema = root().join("schemas").join(schema);
    run_tool(
        python,
        "check_schema.py",
        &[schema.as_os_str(), json.as_os_str()],
        what,
    );
}

/// The morph meshes of a file, keys chosen as `--keys auto` does.
pub fn morph_meshes(path: &Path) -> Vec<inbetween::tween::MorphMesh> {
    let doc = inbetween::gltf::Document::open(path).unwrap();
    let opts = inbetween::tween::KeyOptions {
        source: inbetween::tween::KeySource::Auto,
        animation: None,
    };
    inbetween::tween::find_morph_meshes(&doc, &opts).unwrap()
}

/// `inbetween tween INPUT -o OUTPUT ARGS... -q`, insisting on success.
pub fn tween_quietly(input: &Path, output: &Path, args: &[&str]) -> Output {
    let mut all = vec![
        "tween",
        input.to_str().unwrap(),
        "-o",
        output.to_str().unwrap(),
    ];
    all.extend_from_slice(args);
    all.push("-q");
    run_ok(&all)
}

/// Write a copy of `input` with its JSON changed by `edit` (GLB in, GLB out).
pub fn edited_glb(input: &Path, out: &Path, edit: impl FnOnce(&mut serde_json::Value)) {
    let doc = inbetween::gltf::Document::open(input).unwrap();
    let mut json = doc.json.clone();
    edit(&mut json);
    write_glb(out, &json, &doc.buffers[0]);
}

/// `json` and `bin` as the bytes of a GLB file (JSON padded with spaces, `bin` as given).
pub fn glb_bytes(json: &serde_json::Value, bin: &[u8]) -> Vec<u8> {
    let mut js = serde_json::to_vec(json).unwrap();
    while !js.len().is_multiple_of(4) {
        js.push(b' ');
    }
    let total = 12 + 8 + js.len() + if bin.is_empty() { 0 } else { 8 + bin.len() };
    let mut f = b"glTF".to_vec();
    f.extend(2u32.to_le_bytes());
    f.extend((total as u32).to_le_bytes());
    f.extend((js.len() as u32).to_le_bytes());
    f.extend(0x4E4F534Au32.to_le_bytes());
    f.extend(&js);
    if !bin.is_empty() {
        f.extend((bin.len() as u32).to_le_bytes());
        f.extend(0x004E4942u32.to_le_bytes());
        f.extend(bin);
    }
    f
}

/// A GLB file's JSON and binary chunk as they are stored (nothing decoded).
pub fn glb_parts(path: &Path) -> (serde_json::Value, Vec<u8>) {
    let b = std::fs::read(path).unwrap();
    let word = |at: usize| u32::from_le_bytes(b[at..at + 4].try_into().unwrap()) as usize;
    let js = word(12);
    let json = serde_json::from_slice(&b[20..20 + js]).unwrap();
    let bin = b.get(28 + js..).unwrap_or_default().to_vec();
    (json, bin)
}

/// Write `json` and `bin` as a GLB file, byte for byte as given.
pub fn write_glb(path: &Path, json: &serde_json::Value, bin: &[u8]) {
    std::fs::write(path, glb_bytes(json, bin)).unwrap();
}

/// Write a copy of the GLB `input` with the f32 at element `element` (component `comp`) of
/// accessor `acc` set to `value`.
pub fn poke_f32(input: &Path, out: &Path, acc: usize, element: usize, comp: usize, value: f32) {
    let doc = inbetween::gltf::Document::open(input).unwrap();
    let a = &doc.json["accessors"][acc];
    let view = &doc.json["bufferViews"][a["bufferView"].as_u64().unwrap() as usize];
    let ncomp = match a["type"].as_str().unwrap() {
        "SCALAR" => 1,
        "VEC3" => 3,
        _ => 4,
    };
    let stride = view["byteStride"].as_u64().unwrap_or(4 * ncomp) as usize;
    let at = view["byteOffset"].as_u64().unwrap_or(0) as usize
        + a["byteOffset"].as_u64().unwrap_or(0) as usize
        + element * stride
        + 4 * comp;
    let mut bin = doc.buffers[0].clone();
    bin[at..at + 4].copy_from_slice(&value.to_le_bytes());
    write_glb(out, &doc.json, &bin);
}

/// Run inbetween and insist that it refuses: exit 2, one line naming `file` and saying
/// `what`, and `out` not written.
pub fn assert_refused(args: &[&str], file: &str, what: &str, out: &Path) {
    let r = inbetween(args);
    let err = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(2), "{args:?}: {err}");
    assert_eq!(
        err.trim_end().lines().count(),
        1,
        "{args:?}: one line: {err}"
    );
    assert!(
        err.contains(file),
        "{args:?}: the message names {file}: {err}"
    );
    assert!(err.contains(what), "{args:?}: expected {what:?} in {err}");
    assert!(!out.exists(), "{args:?}: no output file");
}

/// Files in `dir` (recursively) whose names end in `.tmp`.
pub fn temporaries(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).into_iter().flatten().flatten() {
        let p = e.path();
        if p.is_dir() {
            out.extend(temporaries(&p));
        } else if p.to_string_lossy().ends_with(".tmp") {
            out.push(p);
        }
    }
    out
}

/// Every file under `dir` (symbolic links left out).
pub fn walk(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).into_iter().flatten().flatten() {
        let p = e.path();
        if p.is_symlink() {
            continue;
        }
        if p.is_dir() {
            out.extend(walk(&p));
        } else {
            out.push(p);
        }
    }
    out
}

/// A morph animation as a renderer plays it, at its key times: for each key of the `channel`-th
/// weights channel aimed at mesh `mesh`, primitive `prim`'s positions (and normals) =
/// base + sum of weight x target delta.
pub struct Played {
    pub times: Vec<f32>,
    pub positions: Vec<Vec<[f32; 3]>>,
    pub normals: Option<Vec<Vec<[f32; 3]>>>,
    /// Morph targets of the primitive.
    pub targets: usize,
}

pub fn played(path: &Path, mesh: usize, prim: usize, channel: usize) -> Played {
    let (doc, buffers, _) = gltf::import(path).expect("gltf crate reads the output");
    let m = doc.meshes().nth(mesh).unwrap();
    let p = m.primitives().nth(prim).unwrap();
    let r = p.reader(|b| Some(&buffers[b.index()]));
    let base: Vec<[f32; 3]> = r.read_positions().unwrap().collect();
    let base_n: Option<Vec<[f32; 3]>> = r.read_normals().map(|n| n.collect());
    let mut dp = Vec::new();
    let mut dn = Vec::new();
    for (pos, nrm, _) in r.read_morph_targets() {
        dp.push(
            pos.map(|i| i.collect::<Vec<_>>())
                .unwrap_or_else(|| vec![[0.0; 3]; base.len()]),
        );
        dn.push(nrm.map(|i| i.collect::<Vec<_>>()));
    }
    let nodes: Vec<usize> = doc
        .nodes()
        .filter(|n| n.mesh().is_some_and(|x| x.index() == mesh))
        .map(|n| n.index())
        .collect();
    let ch = doc
        .animations()
        .flat_map(|a| a.channels().collect::<Vec<_>>())
        .filter(|c| {
            c.target().property() == gltf::animation::Property::MorphTargetWeights
                && nodes.contains(&c.target().node().index())
        })
        .nth(channel)
        .expect("a weights channel for the mesh");
    let rd = ch.reader(|b| Some(&buffers[b.index()]));
    let times: Vec<f32> = rd.read_inputs().unwrap().collect();
    let weights: Vec<f32> = match rd.read_outputs().unwrap() {
        gltf::animation::util::ReadOutputs::MorphTargetWeights(w) => w.into_f32().collect(),
        _ => panic!("not weights"),
    };
    let n = dp.len();
    assert_eq!(
        weights.len(),
        times.len() * n,
        "one weight per target and key"
    );
    let blend = |b: &[[f32; 3]], deltas: &[Option<&Vec<[f32; 3]>>], w: &[f32]| -> Vec<[f32; 3]> {
        let mut out: Vec<[f64; 3]> = b.iter().map(|v| v.map(f64::from)).collect();
        for (d, &wi) in deltas.iter().zip(w) {
            if let (Some(d), true) = (d, wi != 0.0) {
                for (o, x) in out.iter_mut().zip(d.iter()) {
                    for c in 0..3 {
                        o[c] += wi as f64 * x[c] as f64;
                    }
                }
            }
        }
        out.iter().map(|v| v.map(|x| x as f32)).collect()
    };
    let pos_refs: Vec<Option<&Vec<[f32; 3]>>> = dp.iter().map(Some).collect();
    let nrm_refs: Vec<Option<&Vec<[f32; 3]>>> = dn.iter().map(Option::as_ref).collect();
    let positions = weights
        .chunks(n)
        .map(|w| blend(&base, &pos_refs, w))
        .collect();
    let normals = base_n.map(|bn| {
        weights
            .chunks(n)
            .map(|w| {
                blend(&bn, &nrm_refs, w)
                    .into_iter()
                    .map(|v| {
                        let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt().max(1e-30);
                        v.map(|x| x / l)
                    })
                    .collect()
            })
            .collect()
    });
    Played {
        times,
        positions,
        normals,
        targets: n,
    }
}

/// The (animation, sampler) of every weights channel aimed at a node of mesh 0, in file order.
pub fn mesh0_samplers(doc: &inbetween::gltf::Document) -> Vec<(usize, usize)> {
    let nodes: Vec<u64> = doc.json["nodes"]
        .as_array()
        .into_iter()
        .flatten()
        .enumerate()
        .filter(|(_, n)| n["mesh"].as_u64() == Some(0))
        .map(|(i, _)| i as u64)
        .collect();
    let mut out = Vec::new();
    for (ai, a) in doc.json["animations"]
        .as_array()
        .into_iter()
        .flatten()
        .enumerate()
    {
        for c in a["channels"].as_array().into_iter().flatten() {
            if c["target"]["path"] == "weights"
                && c["target"]["node"]
                    .as_u64()
                    .is_some_and(|n| nodes.contains(&n))
            {
                out.push((ai, c["sampler"].as_u64().unwrap() as usize));
            }
        }
    }
    out
}

/// The positions (mesh space) primitive `prim` of mesh 0 takes at each key of sampler
/// `(animation, sampler)`, read with inbetween's own reader (quantized data decoded):
/// base + sum of weight x target delta. Returns the key times too.
pub fn doc_poses(
    doc: &inbetween::gltf::Document,
    prim: usize,
    (anim, sampler): (usize, usize),
) -> (Vec<f64>, Vec<Vec<glam::DVec3>>) {
    use glam::DVec3;
    let p = &doc.json["meshes"][0]["primitives"][prim];
    let vec3 = |a: u64| -> Vec<DVec3> {
        let (v, _) = doc.read_f64(a as usize).unwrap();
        v.chunks_exact(3)
            .map(|c| DVec3::new(c[0], c[1], c[2]))
            .collect()
    };
    let base = vec3(p["attributes"]["POSITION"].as_u64().unwrap());
    let targets: Vec<Vec<DVec3>> = p["targets"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| {
            t["POSITION"]
                .as_u64()
                .map_or_else(|| vec![DVec3::ZERO; base.len()], vec3)
        })
        .collect();
    let s = &doc.json["animations"][anim]["samplers"][sampler];
    let (times, _) = doc.read_f64(s["input"].as_u64().unwrap() as usize).unwrap();
    let (w, _) = doc
        .read_f64(s["output"].as_u64().unwrap() as usize)
        .unwrap();
    let poses = w
        .chunks(targets.len())
        .map(|w| {
            (0..base.len())
                .map(|v| {
                    base[v]
                        + w.iter()
                            .zip(&targets)
                            .map(|(x, t)| *x * t[v])
                            .sum::<DVec3>()
                })
                .collect()
        })
        .collect();
    (times, poses)
}

/// World matrix of the first node that instances mesh 0 (`inbetween`'s reader: the gltf crate
/// refuses KHR_mesh_quantization).
pub fn mesh_world(doc: &inbetween::gltf::Document) -> glam::DMat4 {
    let nodes = doc.json["nodes"].as_array().cloned().unwrap_or_default();
    let local = |n: &serde_json::Value| -> glam::DMat4 {
        let f = |k: &str| -> Option<Vec<f64>> {
            n[k].as_array()
                .map(|a| a.iter().filter_map(|x| x.as_f64()).collect())
        };
        if let Some(m) = f("matrix").filter(|m| m.len() == 16) {
            return glam::DMat4::from_cols_slice(&m);
        }
        let t = f("translation").map_or(glam::DVec3::ZERO, |v| glam::DVec3::new(v[0], v[1], v[2]));
        let r = f("rotation").map_or(glam::DQuat::IDENTITY, |v| {
            glam::DQuat::from_xyzw(v[0], v[1], v[2], v[3])
        });
        let s = f("scale").map_or(glam::DVec3::ONE, |v| glam::DVec3::new(v[0], v[1], v[2]));
        glam::DMat4::from_scale_rotation_translation(s, r, t)
    };
    let parent = |i: usize| {
        nodes.iter().position(|n| {
            n["children"]
                .as_array()
                .is_some_and(|c| c.iter().any(|x| x.as_u64() == Some(i as u64)))
        })
    };
    let Some(mut i) = nodes.iter().position(|n| n["mesh"].as_u64() == Some(0)) else {
        return glam::DMat4::IDENTITY;
    };
    let mut world = local(&nodes[i]);
    while let Some(p) = parent(i) {
        world = local(&nodes[p]) * world;
        i = p;
    }
    world
}

/// Every frame's world positions of mesh 0 primitive `prim` as its `channel`-th weights channel
/// plays it, read with inbetween's own reader (quantized attributes decoded).
pub fn world_frames(path: &Path, prim: usize, channel: usize) -> (Vec<f64>, Vec<Vec<glam::DVec3>>) {
    let doc = inbetween::gltf::Document::open(path).unwrap();
    let world = mesh_world(&doc);
    let (times, poses) = doc_poses(&doc, prim, mesh0_samplers(&doc)[channel]);
    let frames = poses
        .iter()
        .map(|f| f.iter().map(|p| world.transform_point3(*p)).collect())
        .collect();
    (times, frames)
}

/// For each vertex of `a`, the vertex of `b` nearest to it.
pub fn matching(a: &[glam::DVec3], b: &[glam::DVec3]) -> Vec<usize> {
    a.iter()
        .map(|p| {
            (0..b.len())
                .min_by(|&i, &j| {
                    p.distance_squared(b[i])
                        .total_cmp(&p.distance_squared(b[j]))
                })
                .unwrap()
        })
        .collect()
}

/// A JSON file (a report, a .gltf) as a value.
pub fn read_json(path: impl AsRef<Path>) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

/// Where the test command installs the node tools' commands (gltfpack, gltf-transform).
pub fn node_modules_bin() -> PathBuf {
    root().join("tools/node/node_modules/.bin")
}

/// The folder of the node tools' commands (gltfpack, gltf-transform), or None (noted as a
/// missing tool) where they are not installed.
pub fn node_bin() -> Option<PathBuf> {
    let bin = node_modules_bin();
    if bin.join("gltfpack").exists() && bin.join("gltf-transform").exists() {
        Some(bin)
    } else {
        missing_tool("gltfpack and gltf-transform (tools/node)");
        None
    }
}

/// Run `tool` (gltfpack, gltf-transform) from `bin` (see [`node_bin`]) with `args`, insisting on
/// success: a failure names the command line and shows the tool's error output.
pub fn node_tool<A: AsRef<std::ffi::OsStr>>(
    bin: &Path,
    tool: &str,
    args: impl IntoIterator<Item = A>,
) -> Output {
    let args: Vec<std::ffi::OsString> = args.into_iter().map(|a| a.as_ref().into()).collect();
    let out = Command::new(bin.join(tool)).args(&args).output().unwrap();
    assert!(
        out.status.success(),
        "{tool} {:?}: {}",
        args,
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// flag_wave with the pole (node 1) moved by a channel of the flag's clip that reads the
/// weights' key times (as Blender writes one time accessor for a clip), another channel of it
/// with times of its own, and a second clip of its own; the key times moved by `offset`.
pub fn flag_with_moving_pole(plain: &Path, out: &Path, offset: f32) {
    let doc = inbetween::gltf::Document::open(plain).unwrap();
    let mut json = doc.json.clone();
    let mut bin = doc.buffers[0].clone();
    let mut push = |json: &mut serde_json::Value, values: &[f32], ty: &str| {
        push_f32_accessor(json, &mut bin, values, ty)
    };
    let input = json["animations"][0]["samplers"][0]["input"]
        .as_u64()
        .unwrap() as usize;
    let times: Vec<f32> = doc
        .read_f64(input)
        .unwrap()
        .0
        .iter()
        .map(|&t| t as f32 + offset)
        .collect();
    let shared = push(&mut json, &times, "SCALAR");
    let up: Vec<f32> = (0..5).flat_map(|k| [0.0, 0.1 * k as f32, 0.0]).collect();
    let moved = push(&mut json, &up, "VEC3");
    let own_times = push(&mut json, &[0.25 + offset, 1.75 + offset], "SCALAR");
    let turned = push(&mut json, &[0.0, 0.0, 0.0, 1.0, 0.0, 0.6, 0.0, 0.8], "VEC4");
    let other_times = push(&mut json, &[0.0, 1.0], "SCALAR");
    let scaled = push(&mut json, &[1.0, 1.0, 1.0, 2.0, 2.0, 2.0], "VEC3");
    json["buffers"][0]["byteLength"] = serde_json::json!(bin.len());
    let clip = &mut json["animations"][0];
    clip["samplers"][0]["input"] = serde_json::json!(shared);
    clip["samplers"].as_array_mut().unwrap().extend([
        serde_json::json!({"input": shared, "output": moved}),
        serde_json::json!({"input": own_times, "output": turned}),
    ]);
    clip["channels"].as_array_mut().unwrap().extend([
        serde_json::json!({"sampler": 1, "target": {"node": 1, "path": "translation"}}),
        serde_json::json!({"sampler": 2, "target": {"node": 1, "path": "rotation"}}),
    ]);
    json["animations"]
        .as_array_mut()
        .unwrap()
        .push(serde_json::json!({
            "name": "grow",
            "samplers": [{"input": other_times, "output": scaled}],
            "channels": [{"sampler": 0, "target": {"node": 1, "path": "scale"}}],
        }));
    write_glb(out, &json, &bin);
}

/// Append float accessor `values` of type `ty` (SCALAR, VEC3, VEC4; SCALAR with its bounds)
/// to the GLB `json` and its buffer `bin`, in a view of its own; returns the accessor's index.
pub fn push_f32_accessor(
    json: &mut serde_json::Value,
    bin: &mut Vec<u8>,
    values: &[f32],
    ty: &str,
) -> usize {
    let views = json["bufferViews"].as_array_mut().unwrap();
    views.push(
        serde_json::json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": 4 * values.len()}),
    );
    let view = views.len() - 1;
    bin.extend(values.iter().flat_map(|v| v.to_le_bytes()));
    json["buffers"][0]["byteLength"] = serde_json::json!(bin.len());
    let n = values.len()
        / match ty {
            "VEC3" => 3,
            "VEC4" => 4,
            _ => 1,
        };
    let mut acc =
        serde_json::json!({"bufferView": view, "componentType": 5126, "count": n, "type": ty});
    if ty == "SCALAR" {
        let (lo, hi) = (values[0], values[values.len() - 1]);
        acc["min"] = serde_json::json!([lo]);
        acc["max"] = serde_json::json!([hi]);
    }
    let accessors = json["accessors"].as_array_mut().unwrap();
    accessors.push(acc);
    accessors.len() - 1
}

/// flag_wave's triangles drawn by two primitives (two materials) over one vertex buffer: the
/// same POSITION, NORMAL, TEXCOORD_0 and target accessors, half the indices each, as three.js
/// and Babylon.js export a mesh's material groups.
pub fn flag_in_two_groups(path: &Path) {
    let doc = inbetween::gltf::Document::open(&sample("flag_wave.glb")).unwrap();
    let mut json = doc.json.clone();
    let prim = json["meshes"][0]["primitives"][0].clone();
    let ia = prim["indices"].as_u64().unwrap() as usize;
    let whole = json["accessors"][ia].clone();
    assert_eq!(whole["componentType"], 5125);
    let count = whole["count"].as_u64().unwrap() as usize;
    let half = count / 6 * 3;
    let mut first = whole.clone();
    first["count"] = half.into();
    let mut second = whole.clone();
    second["count"] = (count - half).into();
    second["byteOffset"] = (whole["byteOffset"].as_u64().unwrap_or(0) as usize + 4 * half).into();
    for a in [&mut first, &mut second] {
        let a = a.as_object_mut().unwrap();
        a.remove("min");
        a.remove("max");
    }
    let accessors = json["accessors"].as_array_mut().unwrap();
    accessors.extend([first, second]);
    let n = accessors.len();
    let materials = json["materials"].as_array_mut().unwrap();
    materials.push(serde_json::json!({"name": "back", "pbrMetallicRoughness": {"baseColorFactor": [0.1, 0.1, 0.9, 1.0]}}));
    let back = materials.len() - 1;
    let (mut a, mut b) = (prim.clone(), prim);
    a["indices"] = (n - 2).into();
    b["indices"] = (n - 1).into();
    b["material"] = back.into();
    json["meshes"][0]["primitives"] = serde_json::json!([a, b]);
    write_glb(path, &json, &doc.buffers[0]);
}

/// flag_wave with a second morph mesh no clip animates (a copy of the flag, `still_flag`, its
/// default weights 1 on target 2, node `still` overriding them with 1 on target 3): a prop
/// held in a pose by its blend shapes beside an animated one.
pub fn flag_beside_a_posed_copy(out: &Path) {
    edited_glb(&sample("flag_wave.glb"), out, |j| {
        let mut copy = j["meshes"][0].clone();
        copy["name"] = "still_flag".into();
        copy["weights"] = serde_json::json!([0, 0, 1, 0]);
        j["meshes"].as_array_mut().unwrap().push(copy);
        j["nodes"].as_array_mut().unwrap().push(serde_json::json!(
            {"name": "still", "mesh": 2, "translation": [0, 0, 3], "weights": [0, 0, 0, 1]}));
        j["scenes"][0]["nodes"] = serde_json::json!([0, 1, 2]);
    });
}

/// Blender as a Python module (PyPI bpy, in .venv-bpy), or None (noted as a missing tool).
pub fn bpy() -> Option<PathBuf> {
    let bpy = root().join(".venv-bpy/bin/python");
    if !bpy.exists() && missing_tool("Blender as a Python module (.venv-bpy with bpy 5.0.1)") {
        return None;
    }
    Some(bpy)
}

/// Run the Blender script `script` (in `tools/`) with `args` (see [`run_tool`]) and parse the
/// JSON it prints on its line starting `prefix` (`BPY_POINTS ` ...); `what` names the case.
pub fn bpy_result(
    bpy: &Path,
    script: &str,
    args: &[&std::ffi::OsStr],
    what: &str,
    prefix: &str,
) -> serde_json::Value {
    let stdout = run_tool(bpy, script, args, what);
    let stdout = String::from_utf8_lossy(&stdout);
    let line = (stdout.lines())
        .find_map(|l| l.strip_prefix(prefix))
        .unwrap_or_else(|| panic!("{what}: no result from bpy: {stdout}"));
    serde_json::from_str(line).unwrap()
}

/// The peak memory (MiB) a command's summary line tells.
pub fn summary_peak_mib(summary: &str) -> f64 {
    summary
        .split("peak memory ")
        .nth(1)
        .and_then(|rest| rest.split(" MiB").next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no peak memory in {summary}"))
}

/// `path`'s capture under a root joint of its own that stays put (six channels, all zero), its
/// hip a joint with six channels below it, as a capture retargeted onto a game skeleton whose
/// root bone stays at the origin has it.
pub fn bvh_under_a_still_root(path: &Path) -> String {
    let (head, time, frames) = bvh_parts(path);
    let mut lines = head.lines().skip(1);
    let hip = lines.next().unwrap().replacen("ROOT", "JOINT", 1);
    let rest: Vec<String> = lines.map(|l| format!("\t{l}")).collect();
    let head = format!(
        "HIERARCHY\nROOT still\n{{\n\tOFFSET 0 0 0\n\tCHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation\n\t{hip}\n{}\n}}\n",
        rest.join("\n")
    );
    let moved: Vec<String> = frames.iter().map(|l| format!("0 0 0 0 0 0 {l}")).collect();
    bvh_text(&head, &time, &moved)
}

/// `path`'s capture under a root joint that carries its travel: as [`bvh_under_a_still_root`],
/// the hip's horizontal positions (its first and third channels, X and Z positions in the CMU
/// captures) moved onto the root, so every joint stays where it was (as Bandai Namco's
/// dataset-1 run_normal keys its travel on joint_Root, its other clips on their hips).
pub fn bvh_travelling_on_its_root(path: &Path) -> String {
    let (head, time, frames) = bvh_parts_of(&bvh_under_a_still_root(path));
    let moved: Vec<String> = (frames.iter())
        .map(|l| {
            let mut v: Vec<String> = l.split_whitespace().map(str::to_owned).collect();
            for k in [0, 2] {
                v.swap(k, 6 + k);
            }
            v.join(" ")
        })
        .collect();
    bvh_text(&head, &time, &moved)
}

/// A BVH capture turned half round about +Y through its root joint's own channels (the root's
/// rotation is pre-multiplied by a half turn: X and Z rotations before its Y rotation change
/// sign, the Y rotation gains 180 degrees; its X and Z positions change sign), so that it heads
/// the other way with the same hierarchy.
pub fn bvh_turned_half_round(path: &Path) -> String {
    let (head, time, frames) = bvh_parts(path);
    let channels: Vec<&str> = (head.lines())
        .find(|l| l.trim_start().starts_with("CHANNELS"))
        .unwrap()
        .split_whitespace()
        .skip(2)
        .collect();
    let y_turn = channels.iter().position(|c| *c == "Yrotation").unwrap();
    let turned: Vec<String> = (frames.iter())
        .map(|line| {
            let values = line.split_whitespace().enumerate().map(|(i, v)| {
                let v: f64 = v.parse().unwrap();
                match channels.get(i) {
                    Some(&"Xposition" | &"Zposition") => -v,
                    Some(&"Xrotation" | &"Zrotation") if i < y_turn => -v,
                    Some(&"Yrotation") => v + 180.0,
                    _ => v,
                }
            });
            values.map(|v| v.to_string()).collect::<Vec<_>>().join(" ")
        })
        .collect();
    bvh_text(&head, &time, &turned)
}

/// A BVH capture's hierarchy (up to MOTION), its frame time line and its frame lines (as many
/// as its Frames line says).
pub fn bvh_parts(path: &Path) -> (String, String, Vec<String>) {
    bvh_parts_of(&std::fs::read_to_string(path).unwrap())
}

/// [`bvh_parts`] of a capture's `text`.
pub fn bvh_parts_of(text: &str) -> (String, String, Vec<String>) {
    let text = text.replace("\r\n", "\n");
    let (head, motion) = text.split_once("MOTION\n").unwrap();
    let mut lines = motion.lines();
    let count: usize = lines.next().unwrap()["Frames:".len()..]
        .trim()
        .parse()
        .unwrap();
    let time = lines.next().unwrap().to_owned();
    let frames: Vec<String> = (lines.filter(|l| !l.trim().is_empty()))
        .map(str::to_owned)
        .collect();
    assert_eq!(frames.len(), count);
    (head.to_owned(), time, frames)
}

/// A BVH capture's text from its hierarchy `head`, frame time line and frame lines.
pub fn bvh_text(head: &str, time: &str, frames: &[String]) -> String {
    format!(
        "{head}MOTION\nFrames: {}\n{time}\n{}\n",
        frames.len(),
        frames.join("\n")
    )
}

/// What Git LFS leaves in a file's place when a repository is cloned without its LFS objects:
/// the pointer to an object of `size` bytes.
pub fn lfs_pointer(size: u64) -> String {
    format!(
        "version https://git-lfs.github.com/spec/v1\noid sha256:4d7a214614ab2935c943f9e0ff69d22eadbb8f32b1258daaa5e2ca24d17e2393\nsize {size}\n"
    )
}
