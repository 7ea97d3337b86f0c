//! `inbetween blend` on real characters: foot sliding against the sources and a naive blend,
//! end weights reproducing the sources, cycle periods on motion capture, validity, bad input.

mod common;

use common::*;
use inbetween::blend::{self, CycleMethod};
use inbetween::gltf::Document;
use inbetween::gltf::{self, Container};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// `file` with one more animation: clip `name` started half its duration later (looping).
fn with_shifted_clip(file: &Path, name: &str, dir: &Path) -> (PathBuf, String) {
    let doc = Document::open(file).unwrap();
    let (rig, clips) = blend::load_gltf(&doc).unwrap();
    let clip = clips.iter().find(|c| c.name == name).unwrap();
    let dur = clip.duration();
    let n = (dur * clip.key_rate).round() as usize;
    let times: Vec<f64> = (0..=n).map(|j| j as f64 * dur / n as f64).collect();
    let poses: Vec<blend::Pose> = times
        .iter()
        .map(|t| blend::pose_unwrapped(&rig, clip, true, clip.start + 0.5 * dur + t))
        .collect();
    let shifted = format!("{name}_shifted");
    let out_path = dir.join("shifted.glb");
    let mut out = gltf::begin(&doc, Container::Glb, &out_path).unwrap();
    blend::append_animation(&mut out, &shifted, &times, &poses, &clip.animated());
    gltf::finish(out, Container::Glb, &out_path).unwrap();
    (out_path, shifted)
}

fn blend_report(input: &Path, a: &str, b: &str, w: f64, out: &Path, extra: &[&str]) -> Value {
    let rep = out.with_extension("json");
    let w = w.to_string();
    let mut args = vec![
        "blend",
        input.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--clips",
        a,
        b,
        "--weight",
        &w,
        "--report",
        rep.to_str().unwrap(),
        "-q",
    ];
    args.extend_from_slice(extra);
    run_ok(&args);
    serde_json::from_slice(&std::fs::read(&rep).unwrap()).unwrap()
}

fn sliding(figures: &Value) -> f64 {
    figures["sliding"]["mean"].as_f64().unwrap()
}

#[test]
fn planted_feet_slide_less_than_the_sources_and_a_fifth_of_a_naive_blend() {
    let Some(fx) = fixtures() else { return };
    let dir = tempfile::tempdir().unwrap();
    let python = python();
    for (file, a, b) in [
        ("skinned/Fox.glb", "Walk", "Run"),
        ("skinned/RobotExpressive.glb", "Walking", "Running"),
    ] {
        let input = fx.join(file);
        let (shifted, b_shifted) = with_shifted_clip(&input, b, dir.path());
        for (src, bb) in [(input.clone(), b.to_string()), (shifted.clone(), b_shifted)] {
            for w in [0.25, 0.5, 0.75] {
                let out = dir.path().join(format!("blend_{a}_{bb}_{w}.glb"));
                let r = blend_report(&src, a, &bb, w, &out, &[]);
                let after = sliding(&r["result"]["after_cleanup"]);
                let worse =
                    sliding(&r["clips"][0]["figures"]).max(sliding(&r["clips"][1]["figures"]));
                let naive = sliding(&r["naive"]);
                let planted = r["result"]["after_cleanup"]["sliding"]["count"]
                    .as_u64()
                    .unwrap();
                eprintln!(
                    "{file} {a}+{bb} w={w}: sliding {after:.5} (before clean-up {:.5}; sources worse {worse:.5}; naive {naive:.5}; {planted} planted steps)",
                    sliding(&r["result"]["before_cleanup"])
                );
                assert!(planted > 0, "no planted foot measured on the blend");
                assert!(after <= worse, "{after} > worse source {worse}");
                if r["naive"]["sliding"]["count"].as_u64().unwrap() == 0 {
                    // Robot w=0.75: the run's contacts last under two frames, so the naive
                    // blend has no planted step; the blend must then not slide at all.
                    eprintln!("  the naive blend has no planted step (its figure is 0)");
                }
                // 1e-6 leg: what the analytic IK leaves of a pinned foot's motion.
                assert!(after <= 0.2 * naive + 1e-6, "{after} > 0.2 x naive {naive}");
                assert!(r["result"]["looping"].as_bool().unwrap());
                if w == 0.5 {
                    assert_no_new_issues(&src, &out);
                    if let Some(py) = &python {
                        let schema = root().join("schemas/blend-report.schema.json");
                        let rep = out.with_extension("json");
                        run_tool(
                            py,
                            "check_schema.py",
                            &[schema.as_os_str(), rep.as_os_str()],
                            "the blend report against its schema",
                        );
                    }
                }
            }
        }
    }
}

/// Largest difference between the blended clip at its keys and `source` at the warped times.
fn distance_to_source(out: &Path, input: &Path, source: &str, start: f64) -> f64 {
    let doc_in = Document::open(input).unwrap();
    let (rig, clips) = blend::load_gltf(&doc_in).unwrap();
    let src = clips.iter().find(|c| c.name == source).unwrap();
    let doc_out = Document::open(out).unwrap();
    let (_, out_clips) = blend::load_gltf(&doc_out).unwrap();
    let blended = out_clips.last().unwrap();
    let size = blend::size(&rig, &rig.rest);
    let times = blended.channels[0].times.clone();
    let mut worst: f64 = 0.0;
    for t in times {
        let got = blended.pose(&rig, t);
        let want = blend::pose_unwrapped(&rig, src, true, start + t);
        for (node, path) in src.animated() {
            let (g, w) = (got.local[node], want.local[node]);
            let d = match path {
                blend::Path::Translation => (g.t - w.t).length() / size,
                blend::Path::Rotation => (1.0 - g.r.dot(w.r).abs()).max(0.0).sqrt(),
                blend::Path::Scale => (g.s - w.s).length(),
                blend::Path::Weights => 0.0,
            };
            worst = worst.max(d);
        }
    }
    worst
}

#[test]
fn weights_zero_and_one_give_the_time_warped_sources() {
    let Some(fx) = fixtures() else { return };
    let dir = tempfile::tempdir().unwrap();
    for (file, a, b) in [
        ("skinned/Fox.glb", "Walk", "Run"),
        ("skinned/RobotExpressive.glb", "Walking", "Running"),
    ] {
        let input = fx.join(file);
        for (w, k, name) in [(0.0, 0, a), (1.0, 1, b)] {
            let out = dir.path().join(format!("end_{w}.glb"));
            let r = blend_report(&input, a, b, w, &out, &[]);
            let start = r["clips"][k]["synced_start"].as_f64().unwrap();
            let d = distance_to_source(&out, &input, name, start);
            eprintln!("{file} weight {w}: largest difference to {name} {d:.2e}");
            assert!(d <= 1e-5, "{file} weight {w}: {d}");
        }
    }
}

#[test]
fn clean_up_touches_only_the_legs() {
    let Some(fx) = fixtures() else { return };
    let dir = tempfile::tempdir().unwrap();
    let input = fx.join("skinned/Fox.glb");
    let (with, without) = (dir.path().join("with.glb"), dir.path().join("without.glb"));
    let r = blend_report(&input, "Walk", "Run", 0.5, &with, &[]);
    blend_report(&input, "Walk", "Run", 0.5, &without, &["--no-cleanup"]);
    let legs: Vec<String> = r["legs"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|l| {
            l["chain"]
                .as_array()
                .unwrap()
                .iter()
                .map(|j| j.as_str().unwrap().to_string())
        })
        .collect();
    let load = |p: &Path| {
        let doc = Document::open(p).unwrap();
        let (rig, clips) = blend::load_gltf(&doc).unwrap();
        (rig, clips.last().unwrap().clone())
    };
    let ((rig, a), (_, b)) = (load(&with), load(&without));
    let mut leg_changed = false;
    for t in a.channels[0].times.clone() {
        let (pa, pb) = (a.pose(&rig, t), b.pose(&rig, t));
        for j in 0..rig.len() {
            let moved = (1.0 - pa.local[j].r.dot(pb.local[j].r).abs()) > 1e-9;
            if legs.contains(&rig.names[j]) {
                leg_changed |= moved;
            } else {
                assert!(!moved, "clean-up turned {} at {t}", rig.names[j]);
            }
        }
    }
    assert!(leg_changed, "clean-up changed no leg joint");
}

/// Strides of the foot `end` from its contacts: (touchdown, next touchdown). Written apart from
/// `blend::touchdowns` for captures that move over the floor (no ground velocity, no check of
/// the other legs): a stance is where the foot's horizontal speed in the world is below 10% of
/// its 98th percentile (until it passes 50% again), its touchdown the frame from which the foot
/// stays within 5% of a leg of its median stance position. (The toe settles over about 0.1 s:
/// within 3% of the mid-stance position and a 20% speed gives strides up to 2.6% shorter.)
fn contact_strides(track: &blend::Track, end: usize, leg: f64) -> Vec<(f64, f64)> {
    let flat = |i: usize| {
        let p = track.pos[i][end];
        (p.x, p.z)
    };
    let speed: Vec<f64> = (0..track.len())
        .map(|i| {
            let v = track.velocity(i, end);
            v.x.hypot(v.z)
        })
        .collect();
    let mut s = speed.clone();
    s.sort_by(f64::total_cmp);
    let fast = s[s.len() * 98 / 100];
    let mut stances = Vec::new();
    let mut from = None;
    for (i, &v) in speed.iter().enumerate() {
        match from {
            None if v <= 0.1 * fast => from = Some(i),
            Some(f) if v > 0.5 * fast => {
                stances.push((f, i));
                from = None;
            }
            _ => {}
        }
    }
    let downs: Vec<f64> = stances
        .iter()
        .skip(1)
        .map(|&(f, e)| {
            let median = |mut v: Vec<f64>| {
                v.sort_by(f64::total_cmp);
                v[v.len() / 2]
            };
            let mid = (
                median((f..e).map(|i| flat(i).0).collect()),
                median((f..e).map(|i| flat(i).1).collect()),
            );
            let mut k = f;
            while k > 0 {
                let p = flat(k - 1);
                if (p.0 - mid.0).hypot(p.1 - mid.1) >= 0.05 * leg {
                    break;
                }
                k -= 1;
            }
            track.time(k)
        })
        .collect();
    downs
        .windows(2)
        .map(|w| (w[0], w[1]))
        .filter(|(a, b)| (0.25..=2.5).contains(&(b - a)))
        .collect()
}

#[test]
fn stride_periods_of_motion_capture_match_foot_contacts() {
    let Some(fx) = fixtures() else { return };
    for file in [
        "bvh/kevinxie4c_walk.bvh",
        "bvh/bvh11_131_01_start_walk_stop.bvh",
        // kevinxie4c_cmu_run_filtered (a run, not a walk) has one touchdown per foot after its
        // first stance: no contact stride to compare with (its cycle, from the feet's forward
        // offsets, is 0.771 s).
    ] {
        let (rig, clip) = blend::read_bvh(&fx.join(file)).unwrap();
        let (ch, an) = blend::analyze(&rig, &[&clip], CycleMethod::Legs);
        let spans = &an[0].cycles.as_ref().expect("cycles found").spans;
        // A cycle starts as the first leg steps: its contact stride starting nearest the cycle.
        let strides = contact_strides(&an[0].track, ch.legs[0].end(), ch.scale);
        for &(start, period) in spans {
            let (t0, t1) = *strides
                .iter()
                .min_by(|a, b| (a.0 - start).abs().total_cmp(&(b.0 - start).abs()))
                .unwrap_or_else(|| panic!("{file}: no contact stride"));
            assert!(
                (t0 - start).abs() <= 0.25 * period,
                "{file}: cycle at {start:.3} s, nearest contact stride at {t0:.3} s"
            );
            let err = (period - (t1 - t0)).abs() / (t1 - t0);
            eprintln!(
                "{file}: cycle {start:.3} s + {period:.4} s, contact stride {t0:.3} s + {:.4} s ({:.2}%)",
                t1 - t0,
                100.0 * err
            );
            assert!(err <= 0.02, "{file}: period error {err}");
        }
    }
}

/// `Fox.glb` with one more clip, `name`, that turns only node 0 (not a joint of its skin),
/// written to `dir/file`; with `extra_skin`, node 0 is the joint of a second skin.
fn fox_with_node0_clip(
    fox: &Path,
    dir: &Path,
    file: &str,
    name: &str,
    extra_skin: bool,
) -> PathBuf {
    let doc = Document::open(fox).unwrap();
    let path = dir.join(file);
    let mut out = gltf::begin(&doc, Container::Glb, &path).unwrap();
    let j = &mut out.json;
    let walk = &j["animations"][1];
    let rot = walk["channels"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["target"]["path"] == "rotation")
        .unwrap()["sampler"]
        .as_u64()
        .unwrap() as usize;
    let sampler = walk["samplers"][rot].clone();
    if extra_skin {
        j["skins"]
            .as_array_mut()
            .unwrap()
            .push(serde_json::json!({"joints": [0]}));
    }
    j["animations"]
        .as_array_mut()
        .unwrap()
        .push(serde_json::json!({
            "name": name,
            "samplers": [sampler],
            "channels": [{"sampler": 0, "target": {"node": 0, "path": "rotation"}}]
        }));
    gltf::finish(out, Container::Glb, &path).unwrap();
    path
}

#[test]
fn bad_input_gives_one_line_exit_2_and_no_file() {
    let Some(fx) = fixtures() else { return };
    let dir = tempfile::tempdir().unwrap();
    let fox = fx.join("skinned/Fox.glb");
    let robot = fx.join("skinned/RobotExpressive.glb");
    let other_skin = fox_with_node0_clip(&fox, dir.path(), "other_skin.glb", "OtherSkeleton", true);
    let no_joint = fox_with_node0_clip(&fox, dir.path(), "no_joint.glb", "NotJoints", false);
    let cases: Vec<(PathBuf, Vec<&str>, &str)> = vec![
        (
            fox.clone(),
            vec!["Walk", "Trot"],
            "no animation named \"Trot\"",
        ),
        (sample("bar_twist.glb"), vec!["0", "0"], "no skin"),
        (
            other_skin,
            vec!["Walk", "OtherSkeleton"],
            "different skeletons",
        ),
        (no_joint, vec!["Walk", "NotJoints"], "animates no joint"),
        // Clips that do not walk (issue 17): an idle, a standing pose, a dance.
        (
            fox.clone(),
            vec!["Survey", "Walk"],
            "clip \"Survey\" has no stride cycle: its feet travel 0.000 leg lengths",
        ),
        (
            robot.clone(),
            vec!["Walking", "Idle"],
            "clip \"Idle\" has no stride cycle",
        ),
        (
            robot.clone(),
            vec!["Standing", "Running"],
            "clip \"Standing\" has no stride cycle",
        ),
        (
            robot.clone(),
            vec!["Walking", "Dance"],
            "clip \"Dance\" has no stride cycle",
        ),
        (fox.clone(), vec!["Walk", "Run"], ""),
    ];
    for (input, clips, needle) in cases {
        let out = dir.path().join("bad_out.glb");
        let _ = std::fs::remove_file(&out);
        let o = inbetween(&[
            "blend",
            input.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--clips",
            clips[0],
            clips[1],
            "-q",
        ]);
        if needle.is_empty() {
            assert!(o.status.success());
            continue;
        }
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(err.contains(needle), "{err}");
        assert!(
            err.contains(input.file_name().unwrap().to_str().unwrap()),
            "{err}"
        );
        assert!(!out.exists());
    }
}

/// `--cycles none` blends clips that do not walk anyway, whole, on normalised time; the report
/// says so.
#[test]
fn cycles_none_blends_what_does_not_walk() {
    let Some(fx) = fixtures() else { return };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("idle.glb");
    let rep = dir.path().join("idle.json");
    let robot = fx.join("skinned/RobotExpressive.glb");
    let args = [
        "blend",
        robot.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--clips",
        "Walking",
        "Idle",
    ];
    let mut with = args.to_vec();
    with.extend(["--cycles", "none", "--report", rep.to_str().unwrap(), "-q"]);
    run_ok(&with);
    let r: serde_json::Value = serde_json::from_slice(&std::fs::read(&rep).unwrap()).unwrap();
    assert_eq!(r["cycle_method"], "none");
    assert!(r["clips"]
        .as_array()
        .unwrap()
        .iter()
        .all(|c| c["cycles"].as_array().unwrap().is_empty()));
    let (_, clips) = blend::load_gltf(&Document::open(&out).unwrap()).unwrap();
    assert_eq!(clips.last().unwrap().name, "Walking+Idle");
}
