//! `inbetween bench`: speed figures on generated meshes (never a timed test).
//!
//! For each size, a closed tube bent 150 degrees and twisted 60 degrees between two keys:
//! * symbolic analysis (weld, pattern, AMD ordering) once per mesh;
//! * set-up of a key pair: per-triangle polar decomposition plus the numeric factorization;
//! * set-up of a `spline` segment in the middle of 8 keys (a full window: 4 keys besides its own);
//! * per-frame time of `seed`, `spline` and `linear` on one thread (median over frames at t in (0,1)),
//!   and spline / seed over frames timed back to back;
//! * frames per second with every thread;
//! * peak resident memory of the process so far;
//! * where python3 with numpy/scipy is available, the same workload through
//!   `../shared/peers/ref_tween.py` (set-up and per-frame median) and the ratios.

use super::synth;
use crate::memory::peak_rss_mib;
use crate::tween::{KeyTrack, Method, Pattern, Segment, MAX_BLOCK};
use anyhow::{Context, Result};
use glam::DVec3;
use rayon::prelude::*;
use serde::Serialize;
use std::path::PathBuf;
use std::time::Instant;

#[derive(Clone, Debug)]
pub struct BenchOptions {
    /// Triangle counts to generate.
    pub sizes: Vec<usize>,
    /// Frames timed per method and size.
    pub frames: usize,
    /// Python with numpy and scipy for the peer, and the peers folder.
    pub peer: Option<(PathBuf, PathBuf)>,
    /// Largest mesh given to the peer (its set-up takes minutes at 1M triangles).
    pub peer_max_triangles: usize,
}

#[derive(Clone, Debug, Default, Serialize)]
pub struct BenchRow {
    pub triangles: usize,
    pub vertices: usize,
    pub factor_nonzeros: usize,
    pub symbolic_s: f64,
    pub setup_s: f64,
    /// Median milliseconds of a seed frame solved alone, one frame after the other, each on
    /// every thread (its triangles' terms and the independent parts of its solves).
    pub seed_frame_ms: f64,
    /// Fastest single seed frame (the VM's noise only ever adds time).
    pub seed_frame_min_ms: f64,
    /// Seed milliseconds per frame where frames are solved [`MAX_BLOCK`] at a time (one pass
    /// over the factor for the block; median over blocks).
    pub seed_block_frame_ms: f64,
    /// Set-up of a spline segment in the middle of 8 keys (the two keys alternating): the
    /// polar decompositions of its whole window plus the numeric factorization.
    pub spline_setup_s: f64,
    pub spline_frame_ms: f64,
    /// Fastest single spline frame.
    pub spline_frame_min_ms: f64,
    /// Median over frames of spline time / seed time, the two timed back to back at the same
    /// t (order alternating), so that the VM's drift between the two series cancels.
    pub spline_seed_paired: f64,
    pub linear_frame_ms: f64,
    pub threads: usize,
    pub seed_fps_all_threads: f64,
    pub peak_rss_mib: f64,
    pub peer_setup_s: Option<f64>,
    pub peer_frame_ms: Option<f64>,
}

/// Tube dimensions (segments, rings) giving exactly `triangles = 2 * segments * rings`
/// for the standard sizes, close to it otherwise.
pub fn tube_for(triangles: usize) -> (usize, usize) {
    match triangles {
        16020 => (90, 89),
        100_000 => (250, 200),
        1_000_000 => (1000, 500),
        t => {
            let s = ((t as f64 / 4.0).sqrt().round() as usize).max(3);
            (s, (t / (2 * s)).max(2))
        }
    }
}

/// The two keys of the benchmark: a tube and the tube bent 150 degrees and twisted 60.
pub fn bench_keys(triangles: usize) -> (Vec<DVec3>, Vec<DVec3>, Vec<[u32; 3]>) {
    let (segments, rings) = tube_for(triangles);
    let s = synth::tube(rings, segments, 6.0, 1.0, 1.0);
    let twisted = synth::twist(&s.positions, 60f64.to_radians(), 6.0);
    let key = synth::bend(&twisted, 3.0, 150f64.to_radians(), 0.8);
    (s.positions, key, s.triangles)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Python with numpy and scipy for the peer, and the folder holding `ref_tween.py`: `python`
/// if given, else `.venv/bin/python` where it exists, else `python3`; `None` (with a note on
/// stderr) when that python lacks numpy or scipy or the folder lacks the script.
pub fn find_peer(python: Option<PathBuf>, peers: PathBuf) -> Option<(PathBuf, PathBuf)> {
    let python = python.unwrap_or_else(|| {
        let venv = PathBuf::from(".venv/bin/python");
        if venv.exists() {
            venv
        } else {
            PathBuf::from("python3")
        }
    });
    let works = peers.join("ref_tween.py").exists()
        && std::process::Command::new(&python)
            .args(["-c", "import numpy, scipy"])
            .output()
            .is_ok_and(|o| o.status.success());
    if !works {
        eprintln!(
            "bench: no python with numpy+scipy or no {}: peer columns left empty",
            peers.display()
        );
    }
    works.then_some((python, peers))
}

pub fn run(opts: &BenchOptions, report: &mut dyn FnMut(&BenchRow)) -> Result<Vec<BenchRow>> {
    let mut rows = Vec::new();
    for &size in &opts.sizes {
        let (x0, x1, triangles) = bench_keys(size);
        let mut row = BenchRow {
            triangles: triangles.len(),
            vertices: x0.len(),
            ..Default::default()
        };
        let t = Instant::now();
        let pattern = Pattern::new(x0.len(), &triangles, &x0)?;
        row.symbolic_s = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let seed = Segment::new(
            Method::Seed,
            x0.clone(),
            x1.clone(),
            Some(&pattern),
            &triangles,
        )?;
        row.setup_s = t.elapsed().as_secs_f64();
        row.factor_nonzeros = seed.factor_nonzeros();
        let ts: Vec<f64> = (0..opts.frames)
            .map(|i| (i as f64 + 0.5) / opts.frames as f64)
            .collect();
        let time_frame = |s: &Segment, t: f64| {
            let start = Instant::now();
            std::hint::black_box(s.frame(t));
            start.elapsed().as_secs_f64() * 1e3
        };
        // (median, minimum) milliseconds per frame.
        let time_frames = |s: &Segment| -> (f64, f64) {
            // Warm caches and clocks on a few frames first.
            for &t in ts.iter().take(5) {
                std::hint::black_box(s.frame(t));
            }
            let times: Vec<f64> = ts.iter().map(|&t| time_frame(s, t)).collect();
            let min = times.iter().copied().fold(f64::INFINITY, f64::min);
            (median(times), min)
        };
        (row.seed_frame_ms, row.seed_frame_min_ms) = time_frames(&seed);
        let per_block: Vec<f64> = ts
            .chunks_exact(MAX_BLOCK)
            .map(|block| {
                let start = Instant::now();
                std::hint::black_box(seed.frames(block));
                start.elapsed().as_secs_f64() * 1e3 / block.len() as f64
            })
            .collect();
        row.seed_block_frame_ms = if per_block.is_empty() {
            f64::NAN
        } else {
            median(per_block)
        };
        let linear = Segment::new(Method::Linear, x0.clone(), x1.clone(), None, &triangles)?;
        row.linear_frame_ms = time_frames(&linear).0;
        {
            let keys = [x0.clone(), x1.clone()];
            let spline = KeyTrack {
                keys: &keys,
                times: &[0.0, 1.0],
                pattern: Some(&pattern),
                triangles: &triangles,
                eases: None,
            }
            .segment(Method::Spline, true, 0, 1)?;
            (row.spline_frame_ms, row.spline_frame_min_ms) = time_frames(&spline);
            let ratios: Vec<f64> = ts
                .iter()
                .enumerate()
                .map(|(i, &t)| {
                    if i % 2 == 0 {
                        let seed_ms = time_frame(&seed, t);
                        time_frame(&spline, t) / seed_ms
                    } else {
                        let spline_ms = time_frame(&spline, t);
                        spline_ms / time_frame(&seed, t)
                    }
                })
                .collect();
            row.spline_seed_paired = median(ratios);
            let keys: Vec<Vec<DVec3>> = (0..8)
                .map(|k| if k % 2 == 0 { x0.clone() } else { x1.clone() })
                .collect();
            let times: Vec<f64> = (0..8).map(f64::from).collect();
            let t = Instant::now();
            let middle = KeyTrack {
                keys: &keys,
                times: &times,
                pattern: Some(&pattern),
                triangles: &triangles,
                eases: None,
            }
            .segment(Method::Spline, true, 3, 4)?;
            row.spline_setup_s = t.elapsed().as_secs_f64();
            std::hint::black_box(middle);
        }
        row.threads = rayon::current_num_threads();
        let count = (4 * row.threads).max(opts.frames);
        let start = Instant::now();
        (0..count).into_par_iter().for_each(|i| {
            std::hint::black_box(seed.frame((i as f64 + 0.5) / count as f64));
        });
        row.seed_fps_all_threads = count as f64 / start.elapsed().as_secs_f64();
        drop(seed);
        row.peak_rss_mib = peak_rss_mib();
        if let Some((python, peers)) = &opts.peer {
            if row.triangles <= opts.peer_max_triangles {
                let (setup, frame) =
                    run_peer(python, peers, &x0, &x1, &triangles, opts.frames.min(10))?;
                row.peer_setup_s = Some(setup);
                row.peer_frame_ms = Some(frame);
            }
        }
        report(&row);
        rows.push(row);
    }
    Ok(rows)
}

const PEER_SCRIPT: &str = r#"
import json, sys, time
import numpy as np
sys.path.insert(0, sys.argv[1])
from ref_tween import SeedTweener
d = sys.argv[2]
meta = json.load(open(d + "/meta.json"))
n, m = meta["n"], meta["m"]
x0 = np.fromfile(d + "/x0.bin", dtype="<f8").reshape(n, 3)
x1 = np.fromfile(d + "/x1.bin", dtype="<f8").reshape(n, 3)
tris = np.fromfile(d + "/tris.bin", dtype="<u4").reshape(m, 3).astype(np.int64)
t = time.perf_counter(); tw = SeedTweener(x0, x1, tris); setup = time.perf_counter() - t
times = []
for i in range(meta["frames"]):
    t = time.perf_counter(); tw.frame((i + 0.5) / meta["frames"]); times.append(time.perf_counter() - t)
print(json.dumps({"setup_s": setup, "frame_ms": 1e3 * sorted(times)[len(times) // 2]}))
"#;

fn run_peer(
    python: &PathBuf,
    peers: &PathBuf,
    x0: &[DVec3],
    x1: &[DVec3],
    tris: &[[u32; 3]],
    frames: usize,
) -> Result<(f64, f64)> {
    let dir = std::env::temp_dir().join(format!("inbetween-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let f64s = |v: &[DVec3]| -> Vec<u8> {
        v.iter()
            .flat_map(|p| p.to_array())
            .flat_map(f64::to_le_bytes)
            .collect()
    };
    std::fs::write(dir.join("x0.bin"), f64s(x0))?;
    std::fs::write(dir.join("x1.bin"), f64s(x1))?;
    std::fs::write(
        dir.join("tris.bin"),
        tris.iter()
            .flatten()
            .flat_map(|i| i.to_le_bytes())
            .collect::<Vec<u8>>(),
    )?;
    std::fs::write(
        dir.join("meta.json"),
        serde_json::json!({ "n": x0.len(), "m": tris.len(), "frames": frames.max(1) }).to_string(),
    )?;
    let out = std::process::Command::new(python)
        .arg("-c")
        .arg(PEER_SCRIPT)
        .arg(peers)
        .arg(&dir)
        .output()
        .context("running the python peer")?;
    let _ = std::fs::remove_dir_all(&dir);
    anyhow::ensure!(
        out.status.success(),
        "peer failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout)?;
    Ok((
        v["setup_s"].as_f64().unwrap_or(f64::NAN),
        v["frame_ms"].as_f64().unwrap_or(f64::NAN),
    ))
}

/// A markdown table of the rows.
pub fn table(rows: &[BenchRow]) -> String {
    let mut s = String::from(
        "| triangles | vertices | nnz(L) | symbolic s | set-up s | spline set-up s (8 keys) | seed ms/frame (median / min) | seed ms/frame, 4 solved at once | spline ms/frame (median / min) | spline / seed (min; paired median) | linear ms/frame | seed frames/s (all threads) | peak RSS MiB | peer set-up s | peer ms/frame | set-up ratio | frame ratio |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let opt = |v: Option<f64>, d: usize| v.map_or("-".to_string(), |v| format!("{v:.d$}"));
        let ratio =
            |p: Option<f64>, ours: f64| p.map_or("-".to_string(), |p| format!("{:.0}x", p / ours));
        s += &format!(
            "| {} | {} | {} | {:.3} | {:.3} | {:.3} | {:.2} / {:.2} | {:.2} | {:.2} / {:.2} | {:.2}x; {:.2}x | {:.3} | {:.0} ({} threads) | {:.0} | {} | {} | {} | {} |\n",
            r.triangles,
            r.vertices,
            r.factor_nonzeros,
            r.symbolic_s,
            r.setup_s,
            r.spline_setup_s,
            r.seed_frame_ms,
            r.seed_frame_min_ms,
            r.seed_block_frame_ms,
            r.spline_frame_ms,
            r.spline_frame_min_ms,
            r.spline_frame_min_ms / r.seed_frame_min_ms,
            r.spline_seed_paired,
            r.linear_frame_ms,
            r.seed_fps_all_threads,
            r.threads,
            r.peak_rss_mib,
            opt(r.peer_setup_s, 2),
            opt(r.peer_frame_ms, 1),
            ratio(r.peer_setup_s, r.symbolic_s + r.setup_s),
            ratio(r.peer_frame_ms, r.seed_frame_ms),
        );
    }
    s
}

/// Figures of one end-to-end `inbetween tween` run on a generated file.
#[derive(Clone, Debug, Serialize)]
pub struct EndToEnd {
    pub triangles: usize,
    pub vertices: usize,
    pub frames: usize,
    /// Size of the frames themselves: vertices x frames x 12 bytes (f32 points), MiB.
    pub frames_mib: f64,
    pub keys: usize,
    pub tweens: usize,
    /// The `tween` options given besides `--tweens`.
    pub args: Vec<String>,
    pub input_mib: f64,
    pub output_mib: f64,
    pub wall_s: f64,
    /// The same run by `--method linear` (reading and writing only), when no method was given.
    pub linear_wall_s: Option<f64>,
    pub summary: String,
}

/// A tube of about `triangles` (radius 1, length 6) with the keys `keys` makes of its positions,
/// written to `keys.glb` in a fresh temporary folder named by `tag`: (folder, file, triangles,
/// vertices).
fn tube_file(
    triangles: usize,
    tag: &str,
    keys: impl FnOnce(&[DVec3]) -> Vec<Vec<DVec3>>,
) -> Result<(PathBuf, PathBuf, usize, usize)> {
    let (segments, rings) = tube_for(triangles);
    let s = synth::tube(rings, segments, 6.0, 1.0, 1.0);
    let keys = keys(&s.positions);
    let dir = std::env::temp_dir().join(format!("inbetween-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let input = dir.join("keys.glb");
    let counts = (s.triangles.len(), s.positions.len());
    synth::KeyframeFile {
        meshes: vec![synth::KeyedMesh::new("tube", s, keys)],
        key_times: None,
        key_weights: None,
    }
    .write(&input)?;
    Ok((dir, input, counts.0, counts.1))
}

/// Write a tube of `triangles` with three keys (straight, bent 90, bent 150 and twisted 60) to
/// a temporary .glb, run `inbetween tween --tweens N EXTRA...` on it in a child process writing
/// `tween.<format>`, and time it.
pub fn end_to_end(
    triangles: usize,
    tweens: usize,
    format: &str,
    extra: &[String],
) -> Result<EndToEnd> {
    let (dir, input, tri_count, vertices) = tube_file(triangles, "e2e", |p| {
        let (_, k2, _) = bench_keys(triangles);
        vec![synth::bend(p, 3.0, 90f64.to_radians(), 0.8), k2]
    })?;
    let output = dir.join(format!("tween.{format}"));
    let frames = 2 * (tweens + 1) + 1;
    let count = tweens.to_string();
    let run = |more: &[&str]| -> Result<(f64, String)> {
        let mut args = vec!["tween", input.to_str().unwrap_or(""), "-o"];
        args.extend([output.to_str().unwrap_or(""), "--tweens", &count]);
        args.extend(extra.iter().map(String::as_str));
        args.extend(more);
        child(&args)
    };
    // The same input by `--method linear` (no set-up, no solve: reading and writing), one after
    // the other, unless the options name a method.
    let linear_wall_s = match extra.iter().any(|a| a.starts_with("--method")) {
        true => None,
        false => Some(run(&["--method", "linear"])?.0),
    };
    let (wall_s, summary) = run(&[])?;
    let mib = |p: &std::path::Path| {
        std::fs::metadata(p)
            .map(|m| m.len() as f64 / 1048576.0)
            .unwrap_or(0.0)
    };
    let r = EndToEnd {
        triangles: tri_count,
        vertices,
        frames,
        frames_mib: (vertices * frames * 12) as f64 / 1048576.0,
        keys: 3,
        tweens,
        args: extra.to_vec(),
        input_mib: mib(&input),
        output_mib: mib(&output),
        wall_s,
        linear_wall_s,
        summary,
    };
    let _ = std::fs::remove_dir_all(&dir);
    Ok(r)
}

/// This program run as a child with `args`, timed: (wall seconds, its standard error).
fn child(args: &[&str]) -> Result<(f64, String)> {
    let start = Instant::now();
    let out = std::process::Command::new(std::env::current_exe()?)
        .args(args)
        .output()?;
    let wall_s = start.elapsed().as_secs_f64();
    anyhow::ensure!(
        out.status.success(),
        "{} failed: {}",
        args.first().unwrap_or(&""),
        String::from_utf8_lossy(&out.stderr)
    );
    let stderr = String::from_utf8_lossy(&out.stderr).trim().to_string();
    Ok((wall_s, stderr))
}

/// A scene of many small morph meshes, each command timed on it in a child process
/// (`inbetween bench --scene N`): what grows with the number of meshes, nodes and accessors
/// rather than with triangles.
#[derive(Debug, Serialize)]
pub struct SceneBench {
    pub meshes: usize,
    pub input_mib: f64,
    /// (command line after the input, wall seconds), in order.
    pub runs: Vec<(String, f64)>,
}

/// Write `meshes` small tubes (8 triangles, one bent key each, a node each) to one .glb and
/// time on it `tween` to .glb, .glb with --meshopt, .usdc, and `preview`. Each mesh or
/// primitive scanning the whole file made these quadratic: at 30,000 meshes `tween` to .glb
/// took 50 s and `preview` 19 s (now about 10 and 1 s on 2 cores).
///
/// ```text
/// inbetween bench --scene 30000
/// ```
pub fn scene(meshes: usize) -> Result<SceneBench> {
    let each = |i: usize| {
        let mut s = synth::tube(2, 4, 1.0, 0.2, 0.2);
        let at = DVec3::new((i % 200) as f64 * 1.5, (i / 200) as f64 * 1.5, 0.0);
        s.positions.iter_mut().for_each(|p| *p += at);
        let key = synth::bend(&s.positions, at.x + 0.5, 0.5, 0.5);
        synth::KeyedMesh::new(&format!("prop{i}"), s, vec![key])
    };
    let file = synth::KeyframeFile {
        meshes: (0..meshes).map(each).collect(),
        key_times: None,
        key_weights: None,
    };
    let (input_mib, runs) = timed_runs(
        "scene",
        &file,
        &[
            ("tween", "out.glb", ""),
            ("tween", "meshopt.glb", "--meshopt"),
            ("tween", "out.usdc", ""),
            ("preview", "sheet.png", ""),
        ],
    )?;
    Ok(SceneBench {
        meshes,
        input_mib,
        runs,
    })
}

/// `file` written to a folder of its own (`inbetween-<what>-<process>` in the temporary
/// folder), then each of `cases` (command, output file name there, more options) run on it in
/// a child process, quietly; the folder removed. Returns the file's size in MiB and each run's
/// command line after the input with its wall seconds, in order.
fn timed_runs(
    what: &str,
    file: &synth::KeyframeFile,
    cases: &[(&str, &str, &str)],
) -> Result<(f64, Vec<(String, f64)>)> {
    let dir = std::env::temp_dir().join(format!("inbetween-{what}-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let input = dir.join(format!("{what}.glb"));
    let run = || -> Result<(f64, Vec<(String, f64)>)> {
        file.write(&input)?;
        let input_mib = std::fs::metadata(&input)?.len() as f64 / 1048576.0;
        let input = input.to_string_lossy().into_owned();
        let mut runs = Vec::new();
        for (command, output, more) in cases {
            let path = dir.join(output).to_string_lossy().into_owned();
            let mut args = vec![*command, &input, "-o", &path, "-q"];
            args.extend(more.split_whitespace());
            let (wall_s, _) = child(&args)?;
            let line = format!("{command} -o {output} {more}");
            runs.push((line.trim().to_string(), wall_s));
        }
        Ok((input_mib, runs))
    };
    let result = run();
    let _ = std::fs::remove_dir_all(&dir);
    result
}

/// A face rig of many shapes, each command timed on it in a child process (`inbetween bench
/// --rig N`): what grows with the number of authored targets rather than with triangles.
#[derive(Debug, Serialize)]
pub struct RigBench {
    pub shapes: usize,
    pub vertices: usize,
    pub keys: usize,
    pub input_mib: f64,
    /// (command line after the input, wall seconds), in order.
    pub runs: Vec<(String, f64)>,
}

/// Write a face of about 20,000 vertices with `shapes` blend shapes keyed by a weights
/// animation at 10 keys a second for 10 seconds (101 keys), and time on it `tween` to .glb,
/// .glb with --meshopt (every frame between keys a target of its own, less the authored
/// blend), with --compact (the authored targets fitted to every frame between keys, the basis
/// beside them) and .usdc. Passes a frame at a time over every shape made these grow with the
/// square of the shapes: at 300 shapes, on 2 cores, .glb 16.7 s, --meshopt 36 s and --compact
/// 342 s (now 7.0, 8.8 and 23.3 s).
///
/// ```text
/// inbetween bench --rig 300
/// ```
pub fn rig(shapes: usize) -> Result<RigBench> {
    let file = synth::face_rig_of(141, shapes, 10.0, 10.0);
    let (input_mib, runs) = timed_runs(
        "rig",
        &file,
        &[
            ("tween", "out.glb", ""),
            ("tween", "meshopt.glb", "--meshopt"),
            ("tween", "compact.glb", "--compact"),
            ("tween", "out.usdc", ""),
        ],
    )?;
    Ok(RigBench {
        shapes,
        vertices: file.meshes[0].surface.positions.len(),
        keys: file.key_times.as_ref().map_or(0, Vec::len),
        input_mib,
        runs,
    })
}

/// `inbetween preview` timed on a bent tube of `triangles` (two keys) drawn by `methods`
/// (12 frames, the default sheet): the whole run and the drawing of its cells.
#[derive(Debug, Serialize)]
pub struct PreviewBench {
    pub triangles: usize,
    pub methods: String,
    pub cells: usize,
    pub wall_s: f64,
    pub draw_s: f64,
    pub sheet_pixels: (usize, usize),
}

pub fn preview(triangles: usize, methods: &str) -> Result<PreviewBench> {
    let (dir, input, tri_count, _) = tube_file(triangles, "preview", |p| {
        vec![synth::bend(p, 3.0, 120f64.to_radians(), 0.8)]
    })?;
    let shown = methods
        .split(',')
        .map(|m| {
            crate::preview::Shown::parse(m)
                .filter(|s| matches!(s, crate::preview::Shown::Method(_)))
                .ok_or_else(|| anyhow::anyhow!("unknown method {m:?}"))
        })
        .collect::<Result<Vec<_>>>()?;
    let job = crate::preview::PreviewJob {
        input,
        output: dir.join("sheet.png"),
        shown: shown.clone(),
        frames: crate::preview::DEFAULT_FRAMES,
        size: None,
        view: None,
        shading: crate::preview::Shading::Flat,
        animate: None,
        keys: crate::tween::KeySource::default(),
        animation: None,
        timing: crate::tween::Timing::Tweens(10),
        looping: None,
        extend: [0.0, 0.0],
        access: Default::default(),
        quiet: true,
    };
    let start = Instant::now();
    let r = crate::preview::run_preview(&job);
    let wall_s = start.elapsed().as_secs_f64();
    let _ = std::fs::remove_dir_all(&dir);
    let r = r?;
    Ok(PreviewBench {
        triangles: tri_count,
        methods: methods.to_string(),
        cells: r.frames * shown.len(),
        wall_s,
        draw_s: r.draw_seconds,
        sheet_pixels: r.size,
    })
}

/// Least-squares slope of log(per-frame seed time) against log(triangles): how per-frame
/// time grows with mesh size (1 = linear). `None` with fewer than two sizes.
pub fn fitted_exponent(rows: &[BenchRow]) -> Option<f64> {
    if rows.len() < 2 {
        return None;
    }
    let pts: Vec<(f64, f64)> = rows
        .iter()
        .map(|r| ((r.triangles as f64).ln(), r.seed_frame_ms.ln()))
        .collect();
    let n = pts.len() as f64;
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
    Some(sxy / sxx)
}
