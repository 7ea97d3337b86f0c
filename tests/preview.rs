//! `inbetween preview`: the contact sheet's size and bands, methods that differ, the same bytes
//! twice, animations that decode, tween outputs and skinned files, errors as everywhere.

mod common;

use common::*;
use inbetween::preview::BACKGROUND;
use std::path::Path;

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// (width, height, RGB bytes) of a PNG.
fn decode_png(path: &Path) -> (usize, usize, Vec<u8>) {
    let d = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut r = d.read_info().unwrap();
    let mut buf = vec![0; r.output_buffer_size().unwrap()];
    let info = r.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    buf.truncate(info.buffer_size());
    (info.width as usize, info.height as usize, buf)
}

/// Non-background pixels in rows `y0..y1` of a picture.
fn ink(rgb: &[u8], width: usize, y0: usize, y1: usize) -> usize {
    rgb[3 * width * y0..3 * width * y1]
        .chunks_exact(3)
        .filter(|c| *c != BACKGROUND)
        .count()
}

#[test]
fn a_waving_flag_is_seen_face_on() {
    // The flag moves most along its own normal, so the view along the axis of least motion
    // looked along its plane: a line, the cells left all but empty. Now the view must fill
    // its cells at least a quarter as well as the best one does.
    let dir = tempfile::tempdir().unwrap();
    let sheet = dir.path().join("flag.png");
    let r = run_ok(&[
        "preview",
        s(&sample("flag_wave.glb")),
        "-o",
        s(&sheet),
        "--size",
        "1200x240",
        "--frames",
        "6",
    ]);
    let said = String::from_utf8_lossy(&r.stdout).to_string() + &String::from_utf8_lossy(&r.stderr);
    assert!(said.contains("Front view"), "{said}");
    let (w, h, rgb) = decode_png(&sheet);
    let band = h / 2;
    for b in 0..2 {
        let rows = &rgb[3 * w * b * band..3 * w * (b + 1) * band];
        for c in 0..6 {
            let cell: usize = rows
                .chunks_exact(3 * w)
                .map(|row| ink(&row[3 * 200 * c..3 * 200 * (c + 1)], 200, 0, 1))
                .sum();
            // A cell is 200 x 120 pixels; the flag covers about half of it.
            assert!(
                cell > 200 * band / 4,
                "band {b} cell {c}: {cell} pixels of ink"
            );
        }
    }
}

#[test]
fn a_sheet_has_its_size_and_a_band_per_method_each_holding_the_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let sheet = dir.path().join("sheet.png");
    let input = sample("tube_bend.glb");
    let args = [
        "preview",
        s(&input),
        "-o",
        s(&sheet),
        "--methods",
        "linear,seed,spline",
        "--size",
        "1200x480",
        "--frames",
        "6",
        "-q",
    ];
    run_ok(&args);
    let (w, h, rgb) = decode_png(&sheet);
    assert_eq!((w, h), (1200, 480));
    // Three bands of equal height; each holds the tube in every one of its six cells.
    let band = 480 / 3;
    let mut bands = Vec::new();
    for b in 0..3 {
        let rows = &rgb[3 * w * b * band..3 * w * (b + 1) * band];
        let cells: Vec<usize> = (0..6)
            .map(|c| {
                rows.chunks_exact(3 * w)
                    .map(|row| ink(&row[3 * 200 * c..3 * 200 * (c + 1)], 200, 0, 1))
                    .sum()
            })
            .collect();
        assert!(
            cells.iter().all(|&n| n > 300),
            "band {b}: ink per cell {cells:?}"
        );
        bands.push(rows.to_vec());
    }
    // Linear shrinks the bent tube where seed and spline keep it, and seed slides the upper
    // tube (still in both keys) where linear and spline keep it still: every band differs from
    // spline's; the keys (first and last cells) are the same in all.
    let differ = |a: &[u8], b: &[u8]| {
        a.chunks_exact(3)
            .zip(b.chunks_exact(3))
            .filter(|(x, y)| x != y)
            .count()
    };
    let (ls, ss) = (differ(&bands[0], &bands[2]), differ(&bands[1], &bands[2]));
    eprintln!("pixels that differ: linear/spline {ls}, seed/spline {ss}");
    assert!(ls > 2000 && ss > 2000, "{ls} {ss}");
    // The same run twice: the same bytes.
    let again = dir.path().join("again.png");
    let mut args2 = args;
    args2[3] = s(&again);
    run_ok(&args2);
    assert_eq!(
        std::fs::read(&sheet).unwrap(),
        std::fs::read(&again).unwrap()
    );
    // Any number of threads: the same bytes.
    let one = dir.path().join("one.png");
    let mut args3 = args.to_vec();
    args3[3] = s(&one);
    args3.extend(["--threads", "1"]);
    run_ok(&args3);
    assert_eq!(std::fs::read(&sheet).unwrap(), std::fs::read(&one).unwrap());
}

#[test]
fn animations_decode_with_every_frame() {
    let dir = tempfile::tempdir().unwrap();
    let input = sample("bar_twist.glb");
    let gif_path = dir.path().join("a.gif");
    let apng_path = dir.path().join("a.apng");
    for anim in [&gif_path, &apng_path] {
        run_ok(&[
            "preview",
            s(&input),
            "-o",
            s(&dir.path().join("s.png")),
            "--tweens",
            "4",
            "--animate",
            s(anim),
            "-q",
        ]);
    }
    let keys = common::morph_meshes(&input)[0].tracks[0].times.len();
    let want = (keys - 1) * 5 + 1;
    // GIF: every frame, each with the mesh in it.
    let mut opts = gif::DecodeOptions::new();
    opts.set_color_output(gif::ColorOutput::RGBA);
    let mut d = opts
        .read_info(std::fs::File::open(&gif_path).unwrap())
        .unwrap();
    let mut frames = 0;
    while let Some(f) = d.read_next_frame().unwrap() {
        let inked = f
            .buffer
            .chunks_exact(4)
            .filter(|c| c[..3] != BACKGROUND)
            .count();
        assert!(inked > 200, "frame {frames}: {inked}");
        frames += 1;
    }
    assert_eq!(frames, want);
    // APNG: an animation control chunk with the same count.
    let r = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(&apng_path).unwrap(),
    ))
    .read_info()
    .unwrap();
    assert_eq!(
        r.info().animation_control.map(|a| a.num_frames as usize),
        Some(want)
    );
}

#[test]
fn a_tween_output_shows_its_own_frames() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("t.glb");
    tween_quietly(&sample("tube_bend.glb"), &out, &["--tweens", "3"]);
    let sheet = dir.path().join("t.png");
    let r = run_ok(&["preview", s(&out), "-o", s(&sheet)]);
    let line = String::from_utf8_lossy(&r.stderr);
    // One band, `file`: the output's five frames (its keys), all drawn.
    assert!(line.contains("1 band (file) x 5 frames"), "{line}");
    let (w, h, rgb) = decode_png(&sheet);
    assert_eq!((w, h), (5 * 160, h));
    assert!(ink(&rgb, w, 0, h) > 2000);
}

/// A skinned file without morph keys or clips is drawn as a glTF viewer shows it with no clip
/// playing: moved by its skin's joints in the pose they rest in, with a note. Fox (its clips
/// taken out) stands on its four feet (its rest pose is its bind pose); with its root joint
/// turned a quarter turn about x at rest it stands up on its hind legs, taller than long on the
/// picture (the stored vertices, which the preview drew before, lie as the first).
#[test]
fn a_skinned_file_without_clips_shows_its_rest_pose_with_a_note() {
    let Some(fx) = fixtures() else { return };
    let dir = tempfile::tempdir().unwrap();
    let fox = fx.join("skinned/Fox.glb");
    let still = dir.path().join("still.glb");
    edited_glb(&fox, &still, |j| {
        j.as_object_mut().unwrap().remove("animations");
    });
    let upright = dir.path().join("upright.glb");
    edited_glb(&still, &upright, |j| {
        let half = std::f64::consts::FRAC_1_SQRT_2;
        j["nodes"][2]["rotation"] = serde_json::json!([half, 0.0, 0.0, half]);
    });
    // (rows, columns) holding ink below the label and above the key bar.
    let extent = |input: &Path| -> (usize, usize) {
        let sheet = dir.path().join("fox.png");
        let r = run_ok(&["preview", s(input), "-o", s(&sheet)]);
        let line = String::from_utf8_lossy(&r.stderr);
        assert!(line.contains("note: no morph keys and no clip"), "{line}");
        assert!(line.contains("in the pose its joints rest in"), "{line}");
        let (w, h, rgb) = decode_png(&sheet);
        assert!(ink(&rgb, w, 0, h) > 1500, "{}", ink(&rgb, w, 0, h));
        let inked = |x: usize, y: usize| rgb[3 * (y * w + x)..3 * (y * w + x) + 3] != BACKGROUND;
        let band = 24..h - 8;
        let rows = band
            .clone()
            .filter(|&y| (0..w).any(|x| inked(x, y)))
            .count();
        let cols = (0..w)
            .filter(|&x| band.clone().any(|y| inked(x, y)))
            .count();
        (rows, cols)
    };
    let (rows, cols) = extent(&still);
    assert!(rows < cols, "Fox on its feet: {rows} rows, {cols} columns");
    let (rows, cols) = extent(&upright);
    assert!(rows > cols, "Fox upright: {rows} rows, {cols} columns");
}

/// The points of every vertex of `file`'s first skinned mesh as clip `clip` poses it at time `t`,
/// computed here with the `gltf` crate's readers, apart from inbetween's code: the clip's
/// LINEAR or STEP channels sampled (rotations by slerp), each node's world transform, and
/// linear blend skinning, `sum w_k * W_joint_k * IBM_k * p` with the weights scaled to sum 1.
fn skinned_by_gltf_crate(file: &Path, clip: &str, t: f32) -> Vec<glam::Vec3> {
    use glam::{Mat4, Quat, Vec3};
    use gltf::animation::{util::ReadOutputs, Interpolation};
    let (doc, buffers, _) = gltf::import(file).unwrap();
    let nodes: Vec<gltf::Node> = doc.nodes().collect();
    let mut trs: Vec<(Vec3, Quat, Vec3)> = nodes
        .iter()
        .map(|n| {
            let (t, r, s) = n.transform().decomposed();
            (Vec3::from(t), Quat::from_array(r), Vec3::from(s))
        })
        .collect();
    let anim = doc.animations().find(|a| a.name() == Some(clip)).unwrap();
    for ch in anim.channels() {
        let reader = ch.reader(|b| Some(&buffers[b.index()]));
        let times: Vec<f32> = reader.read_inputs().unwrap().collect();
        let interp = ch.sampler().interpolation();
        assert!(matches!(
            interp,
            Interpolation::Linear | Interpolation::Step
        ));
        // Keys k and k + 1 around t, and the fraction between them.
        let k = times.partition_point(|&x| x <= t).clamp(1, times.len()) - 1;
        let k1 = (k + 1).min(times.len() - 1);
        let u = match (interp, k1 > k) {
            (Interpolation::Linear, true) => {
                ((t - times[k]) / (times[k1] - times[k])).clamp(0.0, 1.0)
            }
            _ => 0.0,
        };
        let node = ch.target().node().index();
        match reader.read_outputs().unwrap() {
            ReadOutputs::Translations(v) => {
                let v: Vec<Vec3> = v.map(Vec3::from).collect();
                trs[node].0 = v[k].lerp(v[k1], u);
            }
            ReadOutputs::Rotations(v) => {
                let v: Vec<Quat> = v.into_f32().map(Quat::from_array).collect();
                trs[node].1 = v[k].normalize().slerp(v[k1].normalize(), u);
            }
            ReadOutputs::Scales(v) => {
                let v: Vec<Vec3> = v.map(Vec3::from).collect();
                trs[node].2 = v[k].lerp(v[k1], u);
            }
            ReadOutputs::MorphTargetWeights(_) => {}
        }
    }
    let mut parent = vec![None; nodes.len()];
    for n in &nodes {
        for c in n.children() {
            parent[c.index()] = Some(n.index());
        }
    }
    let world = |mut i: usize| {
        let mut m = Mat4::IDENTITY;
        loop {
            let (t, r, s) = trs[i];
            m = Mat4::from_scale_rotation_translation(s, r, t) * m;
            match parent[i] {
                Some(p) => i = p,
                None => return m,
            }
        }
    };
    let node = nodes.iter().find(|n| n.skin().is_some()).unwrap();
    let skin = node.skin().unwrap();
    let ibms: Vec<Mat4> = skin
        .reader(|b| Some(&buffers[b.index()]))
        .read_inverse_bind_matrices()
        .unwrap()
        .map(|m| Mat4::from_cols_array_2d(&m))
        .collect();
    let joints: Vec<Mat4> = (skin.joints().zip(ibms))
        .map(|(j, ibm)| world(j.index()) * ibm)
        .collect();
    let prim = node.mesh().unwrap().primitives().next().unwrap();
    let r = prim.reader(|b| Some(&buffers[b.index()]));
    let js: Vec<[u16; 4]> = r.read_joints(0).unwrap().into_u16().collect();
    let ws: Vec<[f32; 4]> = r.read_weights(0).unwrap().into_f32().collect();
    r.read_positions()
        .unwrap()
        .enumerate()
        .map(|(v, p)| {
            let sum: f32 = ws[v].iter().sum();
            let m = (0..4).fold(Mat4::ZERO, |m, c| {
                m + joints[js[v][c] as usize] * (ws[v][c] / sum)
            });
            m.transform_point3(Vec3::from(p))
        })
        .collect()
}

/// A character without morph keys plays its clips, a band each, as a glTF viewer plays them:
/// Fox's three clips seen from the side (its look around alone moves in the floor's plane),
/// RobotExpressive's fourteen (its face shapes hold no keys: the clips, unless tween bands are
/// asked for); one clip by `--animation`, its frames different poses, its animation at 30
/// frames a second; every vertex where the `gltf` crate's own reading and skinning puts it;
/// a clip the file lacks refused in one line.
#[test]
fn a_character_s_clips_play_a_band_each_posed_as_gltf_plays_them() {
    let Some(fx) = fixtures() else { return };
    let dir = tempfile::tempdir().unwrap();
    let fox = fx.join("skinned/Fox.glb");
    let robot = fx.join("skinned/RobotExpressive.glb");
    let sheet = dir.path().join("s.png");
    let line = |r: std::process::Output| String::from_utf8_lossy(&r.stderr).to_string();
    let l = line(run_ok(&["preview", s(&fox), "-o", s(&sheet)]));
    assert!(l.contains("3 bands (Survey, Walk, Run) x 12 frames"), "{l}");
    assert!(l.contains("Side view"), "{l}");
    assert!(l.contains("clips that move its nodes as they play"), "{l}");
    let l = line(run_ok(&[
        "preview",
        s(&robot),
        "-o",
        s(&sheet),
        "--frames",
        "4",
    ]));
    assert!(l.contains("14 bands (Dance, Death, Idle"), "{l}");
    let r = inbetween(&["preview", s(&robot), "-o", s(&sheet), "--methods", "spline"]);
    assert_eq!(r.status.code(), Some(2));
    assert!(line(r).contains("no mesh with morph targets"));

    // One clip: its frames differ (the legs move), its animation at 30 frames a second.
    let gif = dir.path().join("walk.gif");
    let args = ["preview", s(&fox), "-o", s(&sheet), "--animation", "Walk"];
    let l = line(run_ok(
        &[&args[..], &["--frames", "6", "--animate", s(&gif)]].concat(),
    ));
    assert!(l.contains("1 band (Walk) x 6 frames"), "{l}");
    let doc = inbetween::gltf::Document::open(&fox).unwrap();
    let walk = (doc.json["animations"].as_array().unwrap().iter())
        .find(|a| a["name"] == "Walk")
        .unwrap();
    // The clip's keys span its samplers' inputs, first to last.
    let (first, last) = (walk["samplers"].as_array().unwrap().iter()).fold(
        (f64::MAX, f64::MIN),
        |(a, b), sampler| {
            let input = &doc.json["accessors"][sampler["input"].as_u64().unwrap() as usize];
            let (min, max) = (
                input["min"][0].as_f64().unwrap(),
                input["max"][0].as_f64().unwrap(),
            );
            (a.min(min), b.max(max))
        },
    );
    let span = last - first;
    let frames = (span * 30.0).round() as usize + 1;
    assert!(
        l.contains(&format!("{frames} frames animated")),
        "{frames}: {l}"
    );
    let (w, h, rgb) = decode_png(&sheet);
    assert_eq!(w, 6 * 160);
    let cell = |c: usize| -> Vec<bool> {
        (0..h)
            .flat_map(|y| (0..160).map(move |x| (x + 160 * c, y)))
            .map(|(x, y)| rgb[3 * (y * w + x)..3 * (y * w + x) + 3] != BACKGROUND)
            .collect()
    };
    let differ = |a: &[bool], b: &[bool]| a.iter().zip(b).filter(|(x, y)| x != y).count();
    for c in 1..5 {
        let d = differ(&cell(0), &cell(c));
        assert!(d > 100, "frame {c} differs from the first by {d} pixels");
    }

    // Every vertex where the gltf crate's reading and skinning puts it, at three times.
    for t in [0.0, 0.3, 0.61] {
        let ours = &inbetween::preview::posed(&doc, "Walk", &[t]).unwrap()[0][0];
        let theirs = skinned_by_gltf_crate(&fox, "Walk", t as f32);
        assert_eq!(ours.len(), theirs.len());
        let (lo, hi) = theirs
            .iter()
            .fold((glam::Vec3::MAX, glam::Vec3::MIN), |(l, h), p| {
                (l.min(*p), h.max(*p))
            });
        let worst = (ours.iter().zip(&theirs))
            .map(|(a, b)| (a.as_vec3() - *b).length())
            .fold(0.0f32, f32::max);
        let size = (hi - lo).length();
        eprintln!("Fox Walk at {t} s: every vertex within {worst:.2e} of the gltf crate's ({size:.1} across)");
        assert!(worst < 1e-4 * size, "t {t}: {worst} off in {size}");
    }

    // A clip the file lacks: one line naming the clips there are, nothing written.
    let none = dir.path().join("none.png");
    let r = inbetween(&["preview", s(&fox), "-o", s(&none), "--animation", "Trot"]);
    assert_eq!(r.status.code(), Some(2));
    let l = line(r);
    assert_eq!(l.trim().lines().count(), 1, "{l}");
    assert!(
        l.contains(r#"no clip "Trot""#) && l.contains(r#""Survey", "Walk", "Run""#),
        "{l}"
    );
    assert!(!none.exists());
}

/// A mesh that several nodes instance is drawn at each of them, as a viewer draws it (it was
/// drawn at its first node only), and a node's `EXT_mesh_gpu_instancing` instances each (as
/// gltfpack `-mi` writes repeated props; drawn once before): a triangle on two nodes 10 apart,
/// the first moved by the clip, then the second drawing it twice, 5 apart.
#[test]
fn a_mesh_on_two_nodes_is_drawn_at_both() {
    let mut json = serde_json::json!({
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"mesh": 0}, {"mesh": 0, "translation": [10.0, 0.0, 0.0]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0]},
            {"bufferView": 1, "componentType": 5126, "count": 2, "type": "SCALAR",
                "min": [0.0], "max": [1.0]},
            {"bufferView": 2, "componentType": 5126, "count": 2, "type": "VEC3"},
            {"bufferView": 3, "componentType": 5126, "count": 2, "type": "VEC3"},
        ],
        "bufferViews": [
            {"buffer": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 8},
            {"buffer": 0, "byteOffset": 44, "byteLength": 24},
            {"buffer": 0, "byteOffset": 68, "byteLength": 24},
        ],
        "buffers": [{"byteLength": 92,
            "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAAAAAAAgD8AAAAAAAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAoEA="}],
        "animations": [{"name": "lift",
            "samplers": [{"input": 1, "output": 2}],
            "channels": [{"sampler": 0, "target": {"node": 0, "path": "translation"}}]}],
    });
    let posed = |json: &serde_json::Value| {
        let bytes = serde_json::to_vec(json).unwrap();
        let path = Path::new("two.gltf");
        let doc = inbetween::gltf::Document::from_bytes(path, &bytes, &Default::default()).unwrap();
        let posed = inbetween::preview::posed(&doc, "lift", &[0.5]).unwrap();
        posed.iter().map(|p| p[0][1]).collect::<Vec<_>>()
    };
    let v = |x: f64, y: f64, z: f64| glam::DVec3::new(x, y, z);
    assert_eq!(posed(&json), [v(1.0, 0.5, 0.0), v(11.0, 0.0, 0.0)]);
    json["nodes"][1]["extensions"] = serde_json::json!(
        {"EXT_mesh_gpu_instancing": {"attributes": {"TRANSLATION": 3}}});
    let three = [v(1.0, 0.5, 0.0), v(11.0, 0.0, 0.0), v(11.0, 0.0, 5.0)];
    assert_eq!(posed(&json), three);
}

/// A BVH capture (no mesh) is drawn as bones, an octahedron a bone, posed at each frame; a
/// capture that walks across the room is followed by the camera, so every cell holds the whole
/// figure at the cell's height (over its 2.5 s the CMU walk travels twice its size: seen from
/// one spot the figure would be a third as tall), under a root bone left at the floor too; a
/// blend of two captures written as BVH is drawn the same way.
#[test]
fn a_capture_is_drawn_as_bones_and_followed_across_the_floor() {
    let Some(fx) = fixtures() else { return };
    let dir = tempfile::tempdir().unwrap();
    let walk = fx.join("bvh/kevinxie4c_walk.bvh");
    let run = fx.join("bvh/kevinxie4c_cmu_run_filtered.bvh");
    let sheet = dir.path().join("walk.png");
    let gif = dir.path().join("walk.gif");
    let r = run_ok(&[
        "preview",
        s(&walk),
        "-o",
        s(&sheet),
        "--frames",
        "8",
        "--animate",
        s(&gif),
    ]);
    let l = String::from_utf8_lossy(&r.stderr);
    // 19 joints and 5 end sites: 23 bones of 8 triangles.
    assert!(
        l.contains("1 band (kevinxie4c_walk) x 8 frames of 184 triangles, Side view"),
        "{l}"
    );
    assert!(
        l.contains("drawn as bones") && l.contains("the camera follows it"),
        "{l}"
    );
    assert!(l.contains("frames animated"), "{l}");
    let (w, h, rgb) = decode_png(&sheet);
    assert_eq!(w, 8 * 160);
    for c in 0..8 {
        let rows = (0..h)
            .filter(|&y| (0..160).any(|x| rgb[3 * (y * w + 160 * c + x)..][..3] != BACKGROUND))
            .count();
        // The label and key bar take 32 of the 185 rows.
        assert!(rows > 110, "cell {c}: the figure spans {rows} rows");
    }
    // The animation is followed as the sheet is: the whole figure in every frame.
    let mut opts = gif::DecodeOptions::new();
    opts.set_color_output(gif::ColorOutput::RGBA);
    let mut d = opts.read_info(std::fs::File::open(&gif).unwrap()).unwrap();
    let mut frames = 0;
    while let Some(f) = d.read_next_frame().unwrap() {
        let w = f.width as usize;
        let rows = (f.buffer.chunks_exact(4 * w))
            .filter(|row| row.chunks_exact(4).any(|c| c[..3] != BACKGROUND))
            .count();
        assert!(
            rows > 110,
            "animation frame {frames}: the figure spans {rows} rows"
        );
        frames += 1;
    }
    assert!(frames > 60, "{frames} frames");
    // Under a root bone that stays at the floor while the hips walk away (Bandai Namco's
    // joint_Root; a capture retargeted onto a game skeleton): the link from it to the hips
    // changes length as the walk goes on, so it is no bone; it stretched across the sheet
    // (24 bones drawn, the figure a fifth of a cell's height).
    let rooted = dir.path().join("rooted.bvh");
    std::fs::write(&rooted, bvh_under_a_still_root(&walk)).unwrap();
    let r = run_ok(&["preview", s(&rooted), "-o", s(&sheet), "--frames", "8"]);
    let l = String::from_utf8_lossy(&r.stderr);
    assert!(l.contains("x 8 frames of 184 triangles"), "{l}");
    let (w, h, rgb) = decode_png(&sheet);
    for c in 0..8 {
        let rows = (0..h)
            .filter(|&y| (0..160).any(|x| rgb[3 * (y * w + 160 * c + x)..][..3] != BACKGROUND))
            .count();
        assert!(rows > 110, "rooted cell {c}: the figure spans {rows} rows");
    }
    let jog = dir.path().join("jog.bvh");
    run_ok(&["blend", s(&walk), s(&run), "-o", s(&jog), "-q"]);
    let r = run_ok(&["preview", s(&jog), "-o", s(&sheet)]);
    let l = String::from_utf8_lossy(&r.stderr);
    assert!(
        l.contains("1 band (jog) x 12 frames of 184 triangles"),
        "{l}"
    );
}

#[test]
fn bad_requests_fail_in_one_line_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let input = sample("tube_bend.glb");
    let missing = dir.path().join("nope.glb");
    for (args, names) in [
        (vec!["preview", s(&input), "-o", "x.jpg"], "x.jpg"),
        (vec!["preview", s(&missing), "-o", "x.png"], "nope.glb"),
        (
            vec!["preview", s(&input), "-o", "x.png", "--methods", "cubic"],
            "cubic",
        ),
        (
            vec!["preview", s(&input), "-o", "x.png", "--size", "10"],
            "--size",
        ),
        (
            vec!["preview", s(&input), "-o", "x.png", "--animate", "x.mp4"],
            "x.mp4",
        ),
    ] {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_inbetween"))
            .args(&args)
            .current_dir(dir.path())
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(err.contains(names), "{err}");
        assert!(
            walk(dir.path()).is_empty(),
            "{args:?} left {:?}",
            walk(dir.path())
        );
    }
}

/// The timing options are tween's: --loop closes the keys into a loop (tube_bend: 31 frames
/// at the default 30 per second, 61 with the loop), --extend-after continues past the last key.
#[test]
fn timing_options_are_those_of_tween() {
    let dir = tempfile::tempdir().unwrap();
    let input = sample("tube_bend.glb");
    let sheet = dir.path().join("s.png");
    for (extra, frames) in [
        (vec![], 31),
        (vec!["--loop"], 61),
        (vec!["--extend-after", "0.5"], 46),
    ] {
        let mut args = vec![
            "preview",
            s(&input),
            "-o",
            s(&sheet),
            "--frames",
            "100",
            "--methods",
            "linear",
        ];
        args.extend(extra.iter().copied());
        let r = run_ok(&args);
        let line = String::from_utf8_lossy(&r.stderr);
        assert!(
            line.contains(&format!("x {frames} frames")),
            "{extra:?}: {line}"
        );
    }
}
