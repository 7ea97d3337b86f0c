//! `--report`: the per-frame figures, their JSON Schema, and what they say about the methods.

mod common;

use common::*;
use std::path::Path;

fn report(input: &Path, method: &str) -> serde_json::Value {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.glb");
    let rep = dir.path().join("report.json");
    run_ok(&[
        "tween",
        input.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--method",
        method,
        "--tweens",
        "9",
        "--report",
        rep.to_str().unwrap(),
        "-q",
    ]);
    if let Some(python) = python() {
        check_schema(
            &python,
            "report.schema.json",
            &rep,
            "the report against its schema",
        );
    }
    read_json(&rep)
}

fn frames(r: &serde_json::Value) -> &Vec<serde_json::Value> {
    r["meshes"][0]["frames"].as_array().unwrap()
}

#[test]
fn bent_tube_keeps_its_volume_without_inverted_triangles() {
    let r = report(&sample("tube_bend.glb"), "spline");
    assert_eq!(r["meshes"][0]["closed"], true);
    let f = frames(&r);
    assert_eq!(f.len(), 11);
    for fr in f {
        let v = fr["volume_change"].as_f64().unwrap();
        // 0.29% at most (0.82% before a split component's rotations were taken around its turn).
        assert!(v.abs() <= 0.005, "frame {}: volume change {v}", fr["frame"]);
        assert_eq!(fr["inverted_triangles"], 0, "frame {}", fr["frame"]);
    }
    // Keys are exact: no distortion at t = 0 and 1.
    for fr in [&f[0], &f[10]] {
        assert!(fr["edge_distortion_max"].as_f64().unwrap() < 1e-6);
    }
    // Linear blending loses a large share of the volume at mid-motion.
    let lin = report(&sample("tube_bend.glb"), "linear");
    let worst = frames(&lin)
        .iter()
        .map(|f| f["volume_change"].as_f64().unwrap().abs())
        .fold(0.0, f64::max);
    assert!(worst > 0.2, "linear volume change {worst}");
}

#[test]
fn open_meshes_report_no_volume() {
    let r = report(&sample("flag_wave.glb"), "seed");
    assert_eq!(r["meshes"][0]["closed"], false);
    assert!(frames(&r).iter().all(|f| f["volume_change"].is_null()));
    assert_eq!(frames(&r).len(), 41);
}

#[test]
fn an_unwritable_report_leaves_no_output() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.glb");
    let rep = dir.path().join("missing/report.json");
    let o = inbetween(&[
        "tween",
        sample("bar_twist.glb").to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--report",
        rep.to_str().unwrap(),
        "-q",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(String::from_utf8_lossy(&o.stderr).trim().lines().count(), 1);
    assert!(!out.exists() && !rep.exists());
    if let Some(fx) = fixtures() {
        let o = inbetween(&[
            "blend",
            fx.join("skinned/Fox.glb").to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--clips",
            "Walk",
            "Run",
            "--report",
            rep.to_str().unwrap(),
        ]);
        assert_eq!(o.status.code(), Some(2));
        assert!(!out.exists() && !rep.exists());
    }
}
