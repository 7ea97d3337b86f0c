//! Outputs play in a real client: three.js 0.187 (npm) in headless Chromium (Debian package,
//! WebGL2 on SwiftShader), loading dense and `--compact` outputs (meshopt through three's own
//! MeshoptDecoder), playing their animation, and drawing silhouettes that must follow the frames
//! we computed (the same outputs evaluated on the CPU, through the same orthographic camera) and
//! change over time. The page is tools/browser/play.html, served by python's http.server.

mod common;

use common::*;
use glam::DVec3;
use inbetween::gltf::Document;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};

/// Pixels of the silhouettes, each way.
const SIZE: usize = 96;

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A static HTTP server on a free port for `dir`, stopped when dropped.
struct Server(Child, u16);

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn serve(dir: &Path) -> Server {
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let child = Command::new("python3")
        .args([
            "-m",
            "http.server",
            &port.to_string(),
            "--bind",
            "127.0.0.1",
            "--directory",
            s(dir),
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("python3 for the page server");
    for _ in 0..100 {
        if std::net::TcpStream::connect(("127.0.0.1", port)).is_ok() {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    Server(child, port)
}

/// Silhouette of mesh 0 (every primitive) at animation time `t`'s frame `f`, CPU side: pixel
/// centres inside a triangle, row by row from the top.
fn cpu_mask(tris: &[Vec<[u32; 3]>], frames: &[Vec<DVec3>], bounds: [f64; 4]) -> Vec<bool> {
    let [l, r, b, t] = bounds;
    let mut mask = vec![false; SIZE * SIZE];
    let px = |p: DVec3| {
        (
            (p.x - l) / (r - l) * SIZE as f64,
            (t - p.y) / (t - b) * SIZE as f64,
        )
    };
    for (tri, pts) in tris.iter().zip(frames) {
        for [i, j, k] in tri {
            let [a, bb, c] = [*i, *j, *k].map(|v| px(pts[v as usize]));
            let area = (bb.0 - a.0) * (c.1 - a.1) - (bb.1 - a.1) * (c.0 - a.0);
            if area.abs() < 1e-12 {
                continue;
            }
            let (x0, x1) = (
                a.0.min(bb.0).min(c.0).floor().max(0.0) as usize,
                a.0.max(bb.0).max(c.0).ceil().min(SIZE as f64) as usize,
            );
            let (y0, y1) = (
                a.1.min(bb.1).min(c.1).floor().max(0.0) as usize,
                a.1.max(bb.1).max(c.1).ceil().min(SIZE as f64) as usize,
            );
            for y in y0..y1 {
                for x in x0..x1 {
                    let (qx, qy) = (x as f64 + 0.5, y as f64 + 0.5);
                    let e = |p: (f64, f64), q: (f64, f64)| {
                        ((q.0 - p.0) * (qy - p.1) - (q.1 - p.1) * (qx - p.0)) / area
                    };
                    if e(a, bb) >= 0.0 && e(bb, c) >= 0.0 && e(c, a) >= 0.0 {
                        mask[y * SIZE + x] = true;
                    }
                }
            }
        }
    }
    mask
}

fn iou(a: &[bool], b: &[bool]) -> f64 {
    let inter = a.iter().zip(b).filter(|(x, y)| **x && **y).count();
    let union = a.iter().zip(b).filter(|(x, y)| **x || **y).count();
    inter as f64 / union.max(1) as f64
}

/// Play `file` in the browser at `times`; the silhouettes.
fn play(dir: &Path, port: u16, file: &str, bounds: [f64; 4], times: &[f64]) -> Vec<Vec<bool>> {
    // Animation 0: the CPU side follows the first weights channel, animation 0's.
    let params = serde_json::json!({ "file": file, "size": [SIZE, SIZE], "bounds": bounds, "times": times, "clip": 0 });
    let fragment: String = params
        .to_string()
        .bytes()
        .map(|b| {
            if b.is_ascii_alphanumeric() || b"-_.".contains(&b) {
                (b as char).to_string()
            } else {
                format!("%{b:02X}")
            }
        })
        .collect();
    let url = format!("http://127.0.0.1:{port}/play.html#{fragment}");
    let out = Command::new("timeout")
        .args([
            "180",
            "chromium",
            "--headless=new",
            "--no-sandbox",
            "--use-angle=swiftshader",
            "--enable-unsafe-swiftshader",
        ])
        .args(["--virtual-time-budget=60000", "--dump-dom", &url])
        .current_dir(dir)
        .output()
        .expect("chromium");
    let dom = String::from_utf8_lossy(&out.stdout);
    let json = dom
        .split("<pre id=\"out\">")
        .nth(1)
        .and_then(|r| r.split("</pre>").next())
        .unwrap_or("");
    let r: serde_json::Value = serde_json::from_str(json)
        .unwrap_or_else(|_| panic!("{file}: no result from the page: {dom}"));
    assert_eq!(r["ok"], true, "{file}: {}", r["error"]);
    assert_eq!(r["webgl2"], true);
    r["masks"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m.as_str().unwrap().bytes().map(|b| b == b'1').collect())
        .collect()
}

#[test]
fn dense_and_compact_outputs_play_in_three_js() {
    let Some(fx) = fixtures() else { return };
    let three = root().join("tools/node/node_modules/three/build/three.module.js");
    let chromium = Command::new("chromium")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    if (!three.exists() || !chromium) && missing_tool("three.js (tools/node) and chromium (apt)") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(
        root().join("tools/browser/play.html"),
        dir.path().join("play.html"),
    )
    .unwrap();
    std::os::unix::fs::symlink(
        root().join("tools/node/node_modules/three"),
        dir.path().join("three"),
    )
    .unwrap();
    let face = dir.path().join("face.glb");
    inbetween::synth::face_rig(52, 10.0, 2.0)
        .write(&face)
        .unwrap();
    let cases: Vec<(PathBuf, &[&str])> = vec![
        (fx.join("morph-keyframes/Flamingo.glb"), &[]),
        (fx.join("morph-keyframes/Flamingo.glb"), &["--compact"]),
        (fx.join("morph-keyframes/Parrot.glb"), &["--compact"]),
        (
            fx.join("morph-keyframes/Parrot.glb"),
            &["--compact", "--layout", "frames"],
        ),
        (
            fx.join("morph-khronos/MorphStressTest/glTF/MorphStressTest.gltf"),
            &[],
        ),
        (
            fx.join("morph-khronos/MorphStressTest/glTF/MorphStressTest.gltf"),
            &["--compact"],
        ),
        (face, &["--compact"]),
    ];
    let server = serve(dir.path());
    for (n, (input, args)) in cases.iter().enumerate() {
        let name = format!("out{n}.glb");
        let out = dir.path().join(&name);
        tween_quietly(input, &out, args);
        // The frames we computed, on the CPU: every primitive of mesh 0 through the first weights
        // channel, in world space.
        let doc = Document::open(&out).unwrap();
        let prims = doc.json["meshes"][0]["primitives"]
            .as_array()
            .unwrap()
            .len();
        let tris: Vec<Vec<[u32; 3]>> = inbetween::tween::mesh_geometry(&doc, 0)
            .unwrap()
            .into_iter()
            .map(|g| g.1)
            .collect();
        let per_prim: Vec<(Vec<f64>, Vec<Vec<DVec3>>)> =
            (0..prims).map(|p| world_frames(&out, p, 0)).collect();
        let times = &per_prim[0].0;
        // Six frames spread over the clip, tweens among them.
        let picked: Vec<usize> = (0..6).map(|i| i * (times.len() - 1) / 5).collect();
        let (mut lo, mut hi) = (DVec3::MAX, DVec3::MIN);
        for (_, frames) in &per_prim {
            for f in &picked {
                for p in &frames[*f] {
                    (lo, hi) = (lo.min(*p), hi.max(*p));
                }
            }
        }
        let (c, half) = ((lo + hi) / 2.0, 0.55 * (hi - lo).x.max((hi - lo).y));
        let bounds = [c.x - half, c.x + half, c.y - half, c.y + half];
        let at: Vec<f64> = picked.iter().map(|&f| times[f]).collect();
        let seen = play(dir.path(), server.1, &name, bounds, &at);
        let mut worst = 1.0f64;
        let mut ious = Vec::new();
        let mut cpu = Vec::new();
        for (k, &f) in picked.iter().enumerate() {
            let frames: Vec<Vec<DVec3>> = per_prim.iter().map(|(_, fr)| fr[f].clone()).collect();
            let want = cpu_mask(&tris, &frames, bounds);
            cpu.push(want.clone());
            let i = iou(&seen[k], &want);
            worst = worst.min(i);
            ious.push((
                at[k],
                i,
                want.iter().filter(|x| **x).count(),
                seen[k].iter().filter(|x| **x).count(),
            ));
        }
        assert!(
            worst >= 0.9,
            "{} {args:?}: silhouette IoU (time, IoU, CPU pixels, browser pixels) {ious:.3?}",
            input.display()
        );
        // It plays: the silhouette changes over time, as much as the CPU frames' does.
        let change = |m: &[Vec<bool>]| {
            (1..m.len())
                .map(|k| iou(&m[0], &m[k]))
                .fold(1.0f64, f64::min)
        };
        let (still, cpu_still) = (change(&seen), change(&cpu));
        eprintln!("{} {args:?}: {} frames, silhouettes match the CPU frames (IoU >= {worst:.3}), change over time (IoU to the first down to {still:.3}; CPU {cpu_still:.3})", input.display(), at.len());
        assert!(
            still < 0.99 && (still - cpu_still).abs() <= 0.02,
            "{} {args:?}: the picture changes to {still:.3}, the frames to {cpu_still:.3}",
            input.display()
        );
    }
}
