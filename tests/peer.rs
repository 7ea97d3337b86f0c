//! Cross-check against the numpy/scipy peer (../shared/peers/ref_tween.py) on real files.

mod common;

use inbetween::tween::Method;
use inbetween::tween::{key_poses, schedule, track_frames_welded, Timing, TweenOptions};
use serde_json::json;

#[test]
fn seed_frames_agree_with_the_scipy_peer_on_flamingo_and_parrot() {
    let Some(fx) = common::fixtures() else { return };
    let Some(python) = common::python() else {
        return;
    };
    let peers = fx.join("../peers");
    for name in ["Flamingo.glb", "Parrot.glb"] {
        let meshes = common::morph_meshes(&fx.join("morph-keyframes").join(name));
        let mesh = &meshes[0];
        let track = &mesh.tracks[0];
        let opts = TweenOptions::new(Method::Seed, Timing::Tweens(3));
        let (welded, frames) = track_frames_welded(mesh, track, &opts).unwrap();
        let keys: Vec<Vec<[f64; 3]>> = key_poses(mesh, track)
            .iter()
            .map(|k| welded.weld(k).iter().map(|p| p.to_array()).collect())
            .collect();
        let at = schedule(&track.times, opts.timing);
        let job = json!({
            "tris": welded.triangles,
            "keys": keys,
            "frames": at.iter().zip(&frames).map(|(f, x)| json!({
                "a": f.key_a, "t": f.t, "x": x.iter().map(|p| p.to_array()).collect::<Vec<_>>()
            })).collect::<Vec<_>>(),
        });
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("job.json");
        std::fs::write(&path, job.to_string()).unwrap();
        let stdout = common::run_tool(
            &python,
            "crosscheck_peer.py",
            &[path.as_os_str(), peers.as_os_str()],
            name,
        );
        let r: serde_json::Value = serde_json::from_slice(&stdout).unwrap();
        let worst = r["max_rel"].as_f64().unwrap();
        eprintln!(
            "{name}: {} frames, max |inbetween - peer| = {worst:.2e} of the diagonal",
            r["frames"]
        );
        assert!(worst <= 1e-4, "{name}: {worst}");
    }
}
