//! The seed and linear methods on meshes whose right answer is known.

mod common;

use glam::{DMat3, DQuat, DVec3};
use inbetween::synth::{self, KeyedMesh, KeyframeFile, Surface};
use inbetween::tween::Method;
use inbetween::tween::MorphMesh;
use inbetween::tween::{track_frames_welded, Timing, TweenOptions};

fn write_keys(surface: Surface, keys: Vec<Vec<DVec3>>) -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("keys.glb");
    KeyframeFile {
        meshes: vec![KeyedMesh::new("m", surface, keys)],
        key_times: None,
        key_weights: None,
    }
    .write(&path)
    .unwrap();
    (dir, path)
}

fn frames(mesh: &MorphMesh, method: Method, tweens: usize) -> (Vec<Vec<DVec3>>, Vec<Vec<DVec3>>) {
    let opts = TweenOptions::new(method, Timing::Tweens(tweens));
    let track = &mesh.tracks[0];
    let (welded, f) = track_frames_welded(mesh, track, &opts).unwrap();
    let keys = inbetween::tween::key_poses(mesh, track)
        .iter()
        .map(|k| welded.weld(k))
        .collect();
    (keys, f)
}

fn max_dist(a: &[DVec3], b: &[DVec3]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| (*p - *q).length())
        .fold(0.0, f64::max)
}

#[test]
fn keys_are_reproduced_by_the_solve() {
    for (name, method) in ["bar_twist.glb", "tube_bend.glb", "flag_wave.glb"]
        .into_iter()
        .flat_map(|n| [(n, Method::Seed), (n, Method::Spline)])
    {
        let meshes = common::morph_meshes(&common::sample(name));
        let (keys, f) = frames(&meshes[0], method, 3);
        let d = common::diag(&keys[0]);
        for (k, key) in keys.iter().enumerate() {
            let err = max_dist(&f[k * 4], key);
            assert!(
                err <= 1e-6 * d,
                "{name} key {k}: {err} > 1e-6 of the diagonal {d}"
            );
        }
    }
}

fn centroid(x: &[DVec3]) -> DVec3 {
    x.iter().sum::<DVec3>() / x.len() as f64
}

/// The seed's rigid in-between: the turn about the centroid, which moves on the straight line.
fn centroid_line(k0: &[DVec3], k1: &[DVec3], axis: DVec3, angle: f64, t: f64) -> Vec<DVec3> {
    let (c0, c1) = (centroid(k0), centroid(k1));
    let r = DQuat::from_axis_angle(axis.normalize(), t * angle);
    k0.iter().map(|p| c0.lerp(c1, t) + r * (*p - c0)).collect()
}

/// The screw in-between of the rigid motion from `k0` to `k1` (a turn by `angle` about `axis`):
/// the turn by t angle about the fixed axis line, and t of the slide along it.
fn screw(k0: &[DVec3], k1: &[DVec3], axis: DVec3, angle: f64, t: f64) -> Vec<DVec3> {
    let a = axis.normalize();
    let r = DMat3::from_axis_angle(a, angle);
    let shift = centroid(k1) - r * centroid(k0);
    let along = shift.dot(a);
    // A point q of the axis line: (I - R) q = the shift across the axis, q on the plane.
    let m = DMat3::IDENTITY - r + DMat3::from_cols(a * a.x, a * a.y, a * a.z);
    let q = m.inverse() * (shift - a * along);
    let rt = DMat3::from_axis_angle(a, t * angle);
    k0.iter()
        .map(|p| q + rt * (*p - q) + a * (t * along))
        .collect()
}

#[test]
fn an_arm_swinging_about_its_shoulder_moves_on_the_arc() {
    // Body: a tube left in place; arm: a separate tube hanging from the shoulder (its top end),
    // swung forward 120 degrees about it.
    let body = synth::tube(12, 10, 3.0, 0.6, 0.4);
    let arm = synth::tube(16, 8, 2.0, 0.2, 0.2);
    let shoulder = DVec3::new(1.0, 0.0, 1.0);
    let down = DMat3::from_axis_angle(DVec3::Y, std::f64::consts::FRAC_PI_2);
    let hang: Vec<DVec3> = arm.positions.iter().map(|p| shoulder + down * *p).collect();
    let n = body.positions.len() as u32;
    let mut s = body.clone();
    s.positions.extend(&hang);
    s.triangles
        .extend(arm.triangles.iter().map(|t| t.map(|v| v + n)));
    s.normals = None;
    s.uvs = None;
    let angle = 120f64.to_radians();
    let swing = |t: f64| -> Vec<DVec3> {
        let mut x = body.positions.clone();
        x.extend(synth::rigid(
            &hang,
            DVec3::Y,
            t * angle,
            shoulder,
            DVec3::ZERO,
        ));
        x
    };
    let (_dir, path) = write_keys(s, vec![swing(1.0)]);
    let meshes = common::morph_meshes(&path);
    for method in [Method::Seed, Method::Spline] {
        let (keys, f) = frames(&meshes[0], method, 3);
        let d = common::diag(&keys[0]);
        // On the welded vertices: the arm's are those the key moves.
        let expect = |t: f64| -> Vec<DVec3> {
            keys[0]
                .iter()
                .zip(&keys[1])
                .map(|(p, q)| {
                    if (*p - *q).length() < 1e-9 {
                        *p
                    } else {
                        synth::rigid(&[*p], DVec3::Y, t * angle, shoulder, DVec3::ZERO)[0]
                    }
                })
                .collect()
        };
        let errors: Vec<f64> = (1..4)
            .map(|j| max_dist(&f[j], &expect(j as f64 / 4.0)) / d)
            .collect();
        eprintln!("{method:?}: max error / diagonal at t = 1/4, 1/2, 3/4: {errors:.5?}");
        if method == Method::Spline {
            assert!(errors.iter().all(|&e| e <= 1e-5), "{errors:?}");
        } else {
            // The seed's arm moves on the chord: off the arc by about r (1 - cos 60 deg) / 2.
            assert!(errors[1] > 0.05, "{errors:?}");
        }
    }
}

#[test]
fn rigid_rotation_tweens_to_the_exact_rotation() {
    let s = synth::tube(12, 10, 3.0, 0.6, 0.3);
    let axes = [
        DVec3::X,
        DVec3::Y,
        DVec3::Z,
        DVec3::new(1.0, 2.0, 3.0),
        DVec3::new(-0.3, 0.1, 0.9),
    ];
    for (i, axis) in axes.iter().enumerate() {
        for degrees in [10.0, 90.0, 135.0, 170.0] {
            let angle = f64::to_radians(degrees);
            let shift = DVec3::new(1.0, -2.0, 0.5) * i as f64;
            let key = synth::rigid(&s.positions, *axis, angle, DVec3::new(0.3, 0.2, 0.1), shift);
            let (_dir, path) = write_keys(s.clone(), vec![key]);
            let meshes = common::morph_meshes(&path);
            for method in [Method::Seed, Method::Spline] {
                let (keys, f) = frames(&meshes[0], method, 7);
                let d = common::diag(&keys[0]);
                for (j, frame) in f.iter().enumerate() {
                    let t = j as f64 / 8.0;
                    let expect = if method == Method::Seed {
                        centroid_line(&keys[0], &keys[1], *axis, angle, t)
                    } else {
                        screw(&keys[0], &keys[1], *axis, angle, t)
                    };
                    let err = max_dist(frame, &expect);
                    assert!(
                        err <= 1e-5 * d,
                        "{method:?} axis {axis} {degrees} deg t={t}: error {err} > 1e-5 of {d}"
                    );
                }
            }
        }
    }
}

#[test]
fn linear_is_vertex_lerp() {
    let meshes = common::morph_meshes(&common::sample("flag_wave.glb"));
    let (keys, f) = frames(&meshes[0], Method::Linear, 4);
    for (j, frame) in f.iter().enumerate() {
        let (k, t) = (
            (j / 5).min(keys.len() - 2),
            (j as f64 / 5.0) - (j / 5).min(keys.len() - 2) as f64,
        );
        let expect: Vec<DVec3> = keys[k]
            .iter()
            .zip(&keys[k + 1])
            .map(|(a, b)| a.lerp(*b, t))
            .collect();
        assert!(max_dist(frame, &expect) < 1e-12, "frame {j}");
    }
}

#[test]
fn twist_does_not_shrink_like_linear() {
    // Middle frame of the 90-degree twist: the seed keeps the cross-section, lerp shrinks it.
    let meshes = common::morph_meshes(&common::sample("bar_twist.glb"));
    let far: Vec<usize> = (0..meshes[0].vertex_count())
        .filter(|&v| meshes[0].primitives[0].base[v].x > 3.99)
        .collect();
    let radius = |f: &[DVec3]| {
        far.iter()
            .map(|&v| (f[v].y * f[v].y + f[v].z * f[v].z).sqrt())
            .fold(0.0, f64::max)
    };
    let (keys, seed) = frames(&meshes[0], Method::Seed, 1);
    let (_, lin) = frames(&meshes[0], Method::Linear, 1);
    let r0 = radius(&keys[0]);
    // The far end corners turn 45 degrees at the middle frame: lerp pulls them in to cos(45).
    assert!(
        (radius(&seed[1]) / r0 - 1.0).abs() < 0.03,
        "seed radius {}",
        radius(&seed[1]) / r0
    );
    assert!(
        radius(&lin[1]) / r0 < 0.75,
        "linear radius {}",
        radius(&lin[1]) / r0
    );
}

#[test]
fn degenerate_triangles_and_reflections_give_no_nan() {
    // A strip with a zero-area sliver and a lone vertex only in it, keyed to a mirror image.
    let mut s = synth::grid(4, 2, 2.0, 1.0);
    let n = s.positions.len() as u32;
    s.positions.push(s.positions[0]); // duplicate position, its own vertex
    s.positions.push((s.positions[0] + s.positions[1]) * 0.5); // on edge 0-1: zero area
    s.normals = None;
    s.uvs = None;
    s.triangles.push([0, 1, n + 1]);
    let mirrored: Vec<DVec3> = s
        .positions
        .iter()
        .map(|p| DVec3::new(-p.x, p.y, p.z + 0.1))
        .collect();
    let flat: Vec<DVec3> = s
        .positions
        .iter()
        .map(|p| DVec3::new(p.x, 0.0, 0.0))
        .collect();
    for key in [mirrored, flat] {
        let (_dir, path) = write_keys(s.clone(), vec![key]);
        let meshes = common::morph_meshes(&path);
        let (keys, f) = frames(&meshes[0], Method::Seed, 5);
        for frame in &f {
            assert!(frame.iter().all(|p| p.is_finite()), "NaN in a frame");
        }
        let d = common::diag(&keys[0]);
        assert!(max_dist(&f[6], &keys[1]) <= 1e-6 * d.max(1.0), "end key");
    }
}

#[test]
fn a_blink_closed_onto_its_lower_lid_is_solved_by_every_method() {
    // A sheet whose second key closes a row of cells onto the next row: the upper row moves
    // to the lower one's positions up to float32 rounding, as an eyelid closed onto its lower
    // lid, leaving slivers a float32 step high. Their 1/height^2 terms left the seed's system
    // numerically indefinite: "the system is not positive definite" on a plain blink key.
    let s = synth::grid(12, 6, 3.0, 1.5);
    let (rows, cols) = (7, 13);
    let closed: Vec<DVec3> = s
        .positions
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let (r, c) = (i / cols, i % cols);
            match r {
                3 => {
                    let below = s.positions[(r + 1) * cols + c];
                    // Stored in float32 as glTF does, a step off where rounding lands.
                    DVec3::new(below.x, below.y + 1e-7, below.z)
                }
                _ => *p,
            }
        })
        .collect();
    assert_eq!(s.positions.len(), rows * cols);
    let (_dir, path) = write_keys(s.clone(), vec![closed.clone(), s.positions.clone()]);
    let meshes = common::morph_meshes(&path);
    for method in [Method::Seed, Method::Spline, Method::Linear] {
        let (keys, f) = frames(&meshes[0], method, 3);
        assert!(
            f.iter().flatten().all(|p| p.is_finite()),
            "{method:?}: finite"
        );
        let d = common::diag(&keys[0]);
        for (k, key) in keys.iter().enumerate() {
            let err = max_dist(&f[k * 4], key);
            assert!(err <= 1e-6 * d, "{method:?} key {k}: {err}");
        }
        // Between keys the sheet stays within the keys' span (no vertex thrown off).
        for frame in &f {
            assert!(
                frame
                    .iter()
                    .all(|p| p.x.abs() <= 3.5 && p.y.abs() <= 2.0 && p.z.abs() <= 0.5),
                "{method:?}"
            );
        }
    }
}

#[test]
fn seams_and_primitive_borders_stay_closed() {
    // Tube with its seam column duplicated (as a UV seam exports it) and split into two
    // primitives at the middle ring; bend it and check duplicates agree in every frame.
    let path = common::sample("tube_bend.glb");
    let meshes = common::morph_meshes(&path);
    let mesh = &meshes[0];
    let opts = TweenOptions::new(Method::Seed, Timing::Tweens(5));
    let (welded, f) = track_frames_welded(mesh, &mesh.tracks[0], &opts).unwrap();
    assert_eq!(
        welded.n,
        mesh.vertex_count(),
        "the generated tube has no duplicates"
    );

    // Build the same tube with every vertex of ring column 0 duplicated.
    let s = synth::tube(61, 24, 6.0, 0.4, 0.4);
    let mut dup = s.clone();
    let mut copy_of = Vec::new();
    for (v, p) in s.positions.iter().enumerate() {
        if v < 61 * 24 && v % 24 == 0 {
            copy_of.push((v, dup.positions.len()));
            dup.positions.push(*p);
        }
    }
    // Triangles on the 23->0 wrap use the copies.
    for t in dup.triangles.iter_mut().take(2 * 24 * 60) {
        let wraps = t.iter().any(|&i| (i as usize) < 61 * 24 && i % 24 == 23);
        if wraps {
            for i in t.iter_mut() {
                if let Some(&(_, c)) = copy_of.iter().find(|(v, _)| *v == *i as usize) {
                    *i = c as u32;
                }
            }
        }
    }
    let key = synth::bend(&dup.positions, 3.0, 150f64.to_radians(), 1.0);
    let (_dir, p2) = write_keys(dup, vec![key]);
    let meshes2 = common::morph_meshes(&p2);
    let (welded2, f2) = track_frames_welded(&meshes2[0], &meshes2[0].tracks[0], &opts).unwrap();
    assert_eq!(welded2.n, welded.n, "duplicates weld");
    // Same frames as the tube without duplicates.
    for (a, b) in f.iter().zip(&f2) {
        assert!(max_dist(a, b) < 1e-9);
    }
}

#[test]
fn eval_spline_beats_linear_and_positional_catmull_rom() {
    let Some(fx) = common::fixtures() else { return };
    for (file, step) in [
        ("Flamingo.glb", 2),
        ("Flamingo.glb", 3),
        ("Parrot.glb", 2),
        ("Parrot.glb", 3),
    ] {
        let meshes = common::morph_meshes(&fx.join("morph-keyframes").join(file));
        let r = inbetween::eval::evaluate(&meshes[0], step, inbetween::eval::METHODS).unwrap();
        let score = |m: &str| r.scores.iter().find(|s| s.method == m).unwrap().mean;
        let (lin, poscr, spline) = (score("linear"), score("poscr"), score("spline"));
        eprintln!("{file} step {step}: linear {lin:.5} poscr {poscr:.5} seed {:.5} spline {spline:.5} (spline/linear {:.2}, spline/poscr {:.2})", score("seed"), spline / lin, spline / poscr);
        assert!(
            spline <= 0.75 * lin,
            "{file} step {step}: spline {spline} vs linear {lin}"
        );
        assert!(
            spline < poscr,
            "{file} step {step}: spline {spline} vs poscr {poscr}"
        );
        // Issue 5's goal (20% below poscr) holds except on Parrot at step 3, where four keys
        // per wing beat leave every interpolant tried near poscr (see README, "Methods").
        if (file, step) != ("Parrot.glb", 3) {
            assert!(
                spline <= 0.8 * poscr,
                "{file} step {step}: spline {spline} vs poscr {poscr}"
            );
        }
    }
}

/// Length of the twisted tube (radii 0.5 and 0.25): with it, linear and seed give the baseline
/// errors issue 5 quotes (RMS 0.058 and 0.070 at 270 degrees).
const LEN: f64 = 6.0;

/// Middle frame of an elliptic tube twisted by `degrees` between two keys, against the analytic
/// half twist: (RMS, max) vertex error over the bounding-box diagonal.
fn twist_error(method: Method, degrees: f64) -> (f64, f64) {
    let s = synth::tube(121, 24, LEN, 0.5, 0.25);
    let key = synth::twist(&s.positions, degrees.to_radians(), LEN);
    let (_dir, path) = write_keys(s.clone(), vec![key]);
    let meshes = common::morph_meshes(&path);
    let (keys, f) = frames(&meshes[0], method, 1);
    let half = synth::twist(&keys[0], (degrees / 2.0).to_radians(), LEN);
    let d = common::diag(&keys[0]);
    let rms = (f[1]
        .iter()
        .zip(&half)
        .map(|(p, q)| (*p - *q).length_squared())
        .sum::<f64>()
        / half.len() as f64)
        .sqrt();
    (rms / d, max_dist(&f[1], &half) / d)
}

#[test]
fn large_twists_between_two_keys_stay_consistent() {
    // 1.6e-9, 3.6e-9 and 4.3e-9 with the twist field (5e-8, 6e-7 and 1.2e-6 before it; at 270
    // and 360 degrees 0.0007 and 0.0013 with the rotation that
    // kept each triangle's normal, 0.0025 and 0.0045 with the polar decomposition; at 90
    // degrees, before a component turning coherently one way split, 0.0003).
    for (degrees, tol) in [(90.0, 1e-4), (270.0, 1e-4), (360.0, 1e-4)] {
        let lin = twist_error(Method::Linear, degrees);
        let seed = twist_error(Method::Seed, degrees);
        let spline = twist_error(Method::Spline, degrees);
        eprintln!(
            "twist {degrees} deg, middle frame, RMS (max) error / diagonal: linear {:.4} ({:.4}), seed {:.4} ({:.4}), spline {:.1e} ({:.1e})",
            lin.0, lin.1, seed.0, seed.1, spline.0, spline.1
        );
        assert!(
            spline.0 <= tol,
            "spline {degrees} deg: RMS {} > {tol}",
            spline.0
        );
    }
}

#[test]
fn a_720_degree_twist_in_eight_keys_stays_smooth() {
    // Keys every 90 degrees; every frame against the analytic twist at its time.
    let s = synth::tube(61, 16, LEN, 0.5, 0.25);
    let keys: Vec<Vec<DVec3>> = (1..=8)
        .map(|k| synth::twist(&s.positions, (90.0 * k as f64).to_radians(), LEN))
        .collect();
    let (_dir, path) = write_keys(s.clone(), keys);
    let meshes = common::morph_meshes(&path);
    // Spline 1.2e-8 (1.4e-6 before the twist field, 2.4e-4 before its rotations were taken
    // around the twist after the bend),
    // seed 3.9e-4.
    for (method, tol) in [(Method::Seed, 0.005), (Method::Spline, 1e-4)] {
        let (keys, f) = frames(&meshes[0], method, 3);
        assert_eq!(f.len(), 8 * 4 + 1);
        let d = common::diag(&keys[0]);
        let worst = f
            .iter()
            .enumerate()
            .map(|(j, frame)| {
                let want = synth::twist(&keys[0], (720.0 * j as f64 / 32.0).to_radians(), LEN);
                rms(frame, &want) / d
            })
            .fold(0.0, f64::max);
        eprintln!("{method:?}: 720-degree twist in 8 keys, worst frame RMS / diagonal {worst:.1e}");
        assert!(worst <= tol, "{method:?}: {worst}");
    }
}

#[test]
fn extension_continues_a_rigid_rotation_exactly() {
    let s = synth::tube(12, 10, 3.0, 0.6, 0.3);
    let axis = DVec3::new(0.2, 1.0, -0.4).normalize();
    let angle = 100f64.to_radians();
    let key = synth::rigid(
        &s.positions,
        axis,
        angle,
        DVec3::ZERO,
        DVec3::new(0.5, 0.0, 0.0),
    );
    let (_dir, path) = write_keys(s.clone(), vec![key]);
    let meshes = common::morph_meshes(&path);
    for method in [Method::Seed, Method::Spline] {
        let mut opts = TweenOptions::new(method, Timing::Tweens(3));
        opts.extend = [0.5, 0.5];
        let (_, frames) = track_frames_welded(&meshes[0], &meshes[0].tracks[0], &opts).unwrap();
        let plan = inbetween::tween::plan(&meshes[0].tracks[0].times, &opts);
        assert_eq!(frames.len(), 5 + 2 + 2);
        assert!((plan[0].t + 0.5).abs() < 1e-12 && (plan[8].t - 1.5).abs() < 1e-12);
        let (keys, _) = self::frames(&meshes[0], method, 1);
        let d = common::diag(&keys[0]);
        for (f, at) in frames.iter().zip(&plan) {
            let expect = if method == Method::Seed {
                centroid_line(&keys[0], &keys[1], axis, angle, at.t)
            } else {
                screw(&keys[0], &keys[1], axis, angle, at.t)
            };
            assert!(max_dist(f, &expect) <= 1e-5 * d, "{method:?} t={}", at.t);
        }
    }
}

/// RMS error over the diagonal of the middle frame of a clip whose keys are `pose(angle
/// share)` at shares 1/keys .. 1 of a tube (`rings` x `segments`, radii `ry`, `rz`, length
/// `len`), against `pose(1/2)`: one frame between keys, so with an odd number of key steps the
/// middle of the clip is a tween.
fn sweep_case(
    (rings, segments, ry, rz, len): (usize, usize, f64, f64, f64),
    keys: usize,
    pose: &dyn Fn(&[DVec3], f64) -> Vec<DVec3>,
) -> f64 {
    middle_error(synth::tube(rings, segments, len, ry, rz), keys, pose)
}

/// [`sweep_case`] for any surface `s`.
fn middle_error(s: Surface, keys: usize, pose: &dyn Fn(&[DVec3], f64) -> Vec<DVec3>) -> f64 {
    let poses: Vec<Vec<DVec3>> = (1..=keys)
        .map(|k| pose(&s.positions, k as f64 / keys as f64))
        .collect();
    let (_dir, path) = write_keys(s.clone(), poses);
    let meshes = common::morph_meshes(&path);
    let (k, f) = frames(&meshes[0], Method::default(), 1);
    let middle = f.len() / 2;
    let want = pose(&k[0], middle as f64 / (f.len() - 1) as f64);
    rms(&f[middle], &want) / common::diag(&k[0])
}

/// RMS distance between corresponding points.
fn rms(a: &[DVec3], b: &[DVec3]) -> f64 {
    (a.iter()
        .zip(b)
        .map(|(p, q)| (*p - *q).length_squared())
        .sum::<f64>()
        / b.len().max(1) as f64)
        .sqrt()
}

/// Whole turns at any resolution (issue 16): tubes coarse and fine, round and elliptic, thin and
/// fat, short and long, twisted 22.5 to 720 degrees in 22.5-degree steps, in one, three and
/// five key steps (odd, so that the clip's middle frame is a tween; the resolutions and angles
/// where the turn count was once chosen wrong are in). Against the analytic twist:
/// - every case within 0.002 of the diagonal (worst 0.0001; the 10 x 16 fat tube twisted 720
///   degrees in one key step has 72 degrees between rings);
/// - no wrong turn count: no step of 22.5 degrees changes the error by more than 0.005 (a
///   wrong count costs 0.13), and the resolutions of a shape agree within 0.005, at any slope
///   of the helix (r x angle / length, up to 6.3 here).
///
/// Before the rotations of a split component were taken around its twist after the bend (the
/// shear and an elliptic tube's tilt in U, see `gradient::around_axis`), with its axis from its
/// triangles' rotation axes, 78 cases were over 0.01, up to 0.354; before the twist field
/// (`spline::Field`: edges between rings turned far apart on the chords of the turned rings,
/// not on the key's chord interpolated) 10, up to 0.0251.
#[test]
fn whole_turns_at_any_resolution() {
    // (rings, segments around, ry, rz, length); shapes that differ only in resolution in a row.
    type Tube = (usize, usize, f64, f64, f64);
    let shapes: &[&[Tube]] = &[
        &[
            (60, 24, 0.5, 0.25, 6.0),
            (40, 16, 0.5, 0.25, 6.0),
            (80, 32, 0.5, 0.25, 6.0),
            (12, 8, 0.5, 0.25, 6.0),
            (61, 16, 0.5, 0.25, 6.0),
        ],
        &[(20, 6, 0.4, 0.4, 3.0), (40, 12, 0.4, 0.4, 3.0)],
        &[(100, 12, 0.3, 0.1, 12.0), (25, 24, 0.3, 0.1, 12.0)],
        &[(30, 48, 1.0, 0.6, 2.0), (10, 16, 1.0, 0.6, 2.0)],
        &[(16, 16, 0.2, 0.2, 8.0)],
    ];
    let (mut failures, mut cases, mut worst) = (Vec::new(), 0, (0.0, String::new()));
    let mut over = 0;
    for family in shapes {
        for keys in [1, 3, 5] {
            let mut previous: Vec<f64> = vec![0.0; family.len()];
            for step in 1..=32 {
                let degrees = 22.5 * step as f64;
                let errors: Vec<f64> = family
                    .iter()
                    .map(|&shape| {
                        let len = shape.4;
                        sweep_case(shape, keys, &|p, share| {
                            synth::twist(p, (degrees * share).to_radians(), len)
                        })
                    })
                    .collect();
                for (&(rings, segments, ry, rz, len), (&e, &before)) in
                    family.iter().zip(errors.iter().zip(&previous))
                {
                    cases += 1;
                    over += usize::from(e > 0.01);
                    let what = format!("{rings} rings x {segments} around, radii {ry}/{rz}, length {len}, {degrees} deg in {keys} key step(s): {e:.4}");
                    if e > worst.0 {
                        worst = (e, what.clone());
                    }
                    let between_rings = degrees / keys as f64 / rings as f64;
                    if e > 0.002 {
                        failures.push(format!("{what} ({between_rings} deg between rings)"));
                    }
                    if step > 1 && (e - before).abs() > 0.005 {
                        failures.push(format!("{what}: jumped from {before:.4}"));
                    }
                }
                let (lo, hi) = errors
                    .iter()
                    .fold((f64::MAX, 0.0f64), |(l, h), &e| (l.min(e), h.max(e)));
                if hi - lo > 0.005 {
                    failures.push(format!(
                        "{:?} at {degrees} deg in {keys}: resolutions disagree {errors:?}",
                        family[0]
                    ));
                }
                previous = errors;
            }
        }
    }
    eprintln!(
        "whole turns: {cases} cases, {over} over 0.01 of the diagonal, worst {}",
        worst.1
    );
    assert!(
        failures.is_empty(),
        "{} of {cases} cases:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

/// A limb bending at a joint in one key step (45 and 90 degrees, skinned over 1.5 units either
/// side of the elbow): the middle frame within 0.002 of the diagonal of the half bend (0.00037
/// and 0.00145), and the upper arm, still in both keys, still in between (within 0.002 of the
/// diagonal: 0.00043 and 0.00125). Its triangles turn by different amounts, so the arm's
/// centroid used to follow the line between the keys' centroids: 0.0095 and 0.037 off, the
/// whole arm sliding.
#[test]
fn a_limb_bending_at_a_joint_keeps_its_upper_part_still() {
    for bend in [45.0f64, 90.0] {
        let pose = |p: &[DVec3], share: f64| synth::bend(p, 6.0, (bend * share).to_radians(), 1.5);
        let s = synth::tube(60, 24, 12.0, 0.5, 0.4);
        let (_dir, path) = write_keys(s.clone(), vec![pose(&s.positions, 1.0)]);
        let meshes = common::morph_meshes(&path);
        let (k, f) = frames(&meshes[0], Method::default(), 1);
        let d = common::diag(&k[0]);
        let middle = &f[f.len() / 2];
        let off = rms(middle, &pose(&k[0], 0.5)) / d;
        let upper = k[0]
            .iter()
            .zip(middle)
            .filter(|(p, _)| p.x < 4.0)
            .map(|(p, q)| (*p - *q).length())
            .fold(0.0, f64::max)
            / d;
        eprintln!("bend {bend} in one key step: middle frame {off:.5}, upper arm moved {upper:.5}");
        assert!(off <= 2e-3 && upper <= 2e-3, "bend {bend}: {off} {upper}");
    }
}

/// A bent and twisted arm (a twist about an axis that moves with the bend): an arm of 12 units
/// bent at its middle by 45 or 90 degrees while twisting 90 to 720 degrees, in one and three key
/// steps, at three resolutions, against the analytic pose (half the twist, then half the bend)
/// at the middle frame:
/// - within 0.003 of the diagonal at every twist, in one key step (0.0003-0.0025) as in three
///   (0.0005-0.0020);
/// - the three resolutions agree within 0.005 (0.0009 at most: the turn is counted the same
///   at every tessellation).
///
/// Before (issue 16) one key step was off by 0.02 to 0.38 and the resolutions by 0.26: the
/// twist axis came from the rotations alone, which lean towards the forearm's bend (now a
/// straight limb's own length, see `spline::limb_axes`), and the arm moved along the line
/// between the keys' centroids (now its split triangles' screws, see `spline::Screw`). Before
/// the twist field (see `spline::Field`) one key step was off by up to 0.0107; before each
/// triangle of a bent limb twisted about its own axis (see `spline::local_axes`) three steps
/// were off by up to 0.0147 (the middle segment starts bent 30 degrees).
#[test]
fn a_bent_and_twisted_arm_counts_its_turns_at_every_resolution() {
    let mut failures = Vec::new();
    let mut worst = 0.0f64;
    for bend in [45.0f64, 90.0] {
        for keys in [1, 3] {
            for step in 1..=8 {
                let twist = 90.0 * step as f64;
                let pose = |p: &[DVec3], share: f64| {
                    let t = synth::twist(p, (twist * share).to_radians(), 12.0);
                    synth::bend(&t, 6.0, (bend * share).to_radians(), 1.5)
                };
                let errors: Vec<f64> = [
                    (60, 24, 0.5, 0.4, 12.0),
                    (30, 12, 0.5, 0.4, 12.0),
                    (120, 16, 0.5, 0.4, 12.0),
                ]
                .into_iter()
                .map(|shape| sweep_case(shape, keys, &pose))
                .collect();
                let what =
                    format!("bend {bend}, twist {twist} in {keys} key step(s): {errors:.4?}");
                eprintln!("bent and twisted arm, middle frame against the analytic pose: {what}");
                let (lo, hi) = errors
                    .iter()
                    .fold((f64::MAX, 0.0f64), |(l, h), &e| (l.min(e), h.max(e)));
                worst = worst.max(hi - lo);
                if hi > 0.003 {
                    failures.push(format!("{what}: off the analytic pose"));
                }
                if hi - lo > 0.005 {
                    failures.push(format!("{what}: resolutions disagree"));
                }
            }
        }
    }
    eprintln!("bent and twisted arm: resolutions differ by up to {worst:.4} of the diagonal");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Twists of shapes the sweep above does not have, against the analytic pose at the middle
/// frame: a flat ribbon (48 x 4 quads, 12 x 1) twisted about its length, a tube of 12 rings
/// spaced unevenly along it and each turned by its own phase (no ring edge lines up with the
/// next), and an arm bent 60 degrees at an elbow a third of the way along while twisting, 180
/// to 720 degrees in one, three and five key steps. Every case within 0.002 of the diagonal
/// (0.0000-0.0012). With the vertices' twists the mean of their triangles' (not measured from
/// their positions) the uneven tube was 0.0035 off (its rings from an earlier sequence of the
/// same spread); with a local axis wherever a limb's key a is not straight, the ribbon twisted
/// in key a 0.0014; with one twist axis for the bent arm (the code before issue 16's twist
/// field) the arm 0.0134.
#[test]
fn twists_of_other_shapes_stay_on_the_analytic_pose() {
    let mut ribbon = synth::grid(48, 4, 12.0, 1.0);
    for p in ribbon.positions.iter_mut() {
        p.y -= 0.5;
    }
    // Rings moved along the tube by up to a quarter of their spacing and turned by up to 0.3
    // rad each (a fixed sequence), the end rings moved only in turn.
    let rings = 12;
    let mut uneven = synth::tube(rings, 16, 6.0, 0.5, 0.3);
    let mut lcg = synth::Lcg(12345);
    let mut next = || lcg.unit() - 0.5;
    let spacing = 6.0 / (rings - 1) as f64;
    let moves: Vec<(f64, f64)> = (0..rings)
        .map(|_| (next() * 0.5 * spacing, next() * 0.6))
        .collect();
    for (v, p) in uneven.positions.iter_mut().enumerate().take(rings * 16) {
        let ring = v / 16;
        let (along, turn) = moves[ring];
        let q = DQuat::from_rotation_x(turn) * DVec3::new(0.0, p.y, p.z);
        let end = ring == 0 || ring == rings - 1;
        *p = DVec3::new(p.x + if end { 0.0 } else { along }, q.y, q.z);
    }
    let mut failures = Vec::new();
    for degrees in [180.0f64, 360.0, 540.0, 720.0] {
        for keys in [1, 3, 5] {
            let twist = |len: f64| {
                move |p: &[DVec3], share: f64| synth::twist(p, (degrees * share).to_radians(), len)
            };
            let arm = |p: &[DVec3], share: f64| {
                let t = synth::twist(p, (degrees * share).to_radians(), 12.0);
                synth::bend(&t, 4.0, (60.0 * share).to_radians(), 1.0)
            };
            let cases: [(&str, f64); 3] = [
                ("ribbon", middle_error(ribbon.clone(), keys, &twist(12.0))),
                (
                    "uneven tube",
                    middle_error(uneven.clone(), keys, &twist(6.0)),
                ),
                (
                    "arm",
                    middle_error(synth::tube(60, 20, 12.0, 0.5, 0.5), keys, &arm),
                ),
            ];
            for (what, e) in cases {
                eprintln!("{what}, twist {degrees} in {keys} key step(s): {e:.4}");
                if e > 0.002 {
                    failures.push(format!("{what}, twist {degrees} in {keys}: {e:.4}"));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The weights a CUBICSPLINE clip (`track`, its eases given) plays at frame `f`: each
/// weight's cubic Hermite through its keys' values and slopes (tangents per second times the
/// span), as glTF defines it.
fn clip_weights(track: &inbetween::tween::Track, f: &inbetween::tween::FrameAt) -> Vec<f64> {
    let (a, b, u) = (f.key_a, f.key_b, f.t);
    let (w, eases) = (&track.weights, track.eases.as_ref().expect("eases"));
    let h = track.times[b] - track.times[a];
    let (u2, u3) = (u * u, u * u * u);
    let c = [
        2.0 * u3 - 3.0 * u2 + 1.0,
        u3 - 2.0 * u2 + u,
        3.0 * u2 - 2.0 * u3,
        u3 - u2,
    ];
    (0..w[a].len())
        .map(|i| {
            c[0] * w[a][i] + c[1] * h * eases[a][1][i] + c[2] * w[b][i] + c[3] * h * eases[b][0][i]
        })
        .collect()
}

/// A clip's CUBICSPLINE eases (`Track::eases`) are followed between its keys: by `linear`
/// exactly, its frames the blends the clip plays at their times (with every tangent zero, an
/// ease out of and into each key; with each segment's chord slope, the frames of the same keys
/// played LINEAR); by `spline` from the clip's own motion at the keys: with every tangent zero
/// the frames a quarter of a segment from its keys lie about the cubic's 0.156 of the way.
/// Past the ends `linear`, `spline` and `seed` (at the eases' pace) go on along the end's
/// tangent.
#[test]
fn eased_keys_are_followed_between_them() {
    use inbetween::tween::{plan, Track};
    let meshes = common::morph_meshes(&common::sample("flag_wave.glb"));
    let mesh = &meshes[0];
    let plain = &mesh.tracks[0];
    let (times, weights) = (&plain.times, &plain.weights);
    let k = times.len();
    assert!(k >= 3, "{k} keys");
    let with = |eases: Option<Vec<[Vec<f64>; 2]>>| Track {
        origin: plain.origin.clone(),
        times: times.clone(),
        weights: weights.clone(),
        eases,
    };
    let zero = vec![0.0; mesh.target_count];
    let flat = with(Some(vec![[zero.clone(), zero.clone()]; k]));
    let chord = |a: usize| -> Vec<f64> {
        let h = times[a + 1] - times[a];
        (weights[a].iter().zip(&weights[a + 1]))
            .map(|(x, y)| (y - x) / h)
            .collect()
    };
    let chords = with(Some(
        (0..k)
            .map(|i| {
                let into = if i > 0 { chord(i - 1) } else { zero.clone() };
                let out = if i + 1 < k { chord(i) } else { zero.clone() };
                [into, out]
            })
            .collect(),
    ));
    let opts = |method| TweenOptions::new(method, Timing::Tweens(3));
    let d = common::diag(&mesh.primitives[0].base);
    // The clip's blend at each frame's time.
    let played = |track: &Track| -> Vec<Vec<DVec3>> {
        let (welded, _) = track_frames_welded(mesh, track, &opts(Method::Linear)).unwrap();
        plan(times, &opts(Method::Linear))
            .iter()
            .map(|f| {
                let w = clip_weights(track, f);
                welded.weld(&mesh.pose(&w))
            })
            .collect()
    };
    let frames_of =
        |track: &Track, method| track_frames_welded(mesh, track, &opts(method)).unwrap().1;
    for (what, track) in [("flat", &flat), ("chords", &chords)] {
        let got = frames_of(track, Method::Linear);
        for (f, (g, want)) in got.iter().zip(played(track)).enumerate() {
            assert!(max_dist(g, &want) <= 1e-9 * d, "{what} frame {f}");
        }
    }
    let (lerped, by_chords) = (
        frames_of(plain, Method::Linear),
        frames_of(&chords, Method::Linear),
    );
    for (f, (a, b)) in lerped.iter().zip(&by_chords).enumerate() {
        assert!(max_dist(a, b) <= 1e-9 * d, "frame {f}");
    }
    // Past the ends (`--extend-before`, `--extend-after`) the motion goes on along the clip's
    // tangent there: with eases, a stop, so the end keys' poses (where the cubic turns back).
    let (first, last) = (&lerped[0], &lerped[lerped.len() - 1]);
    // (The solves give the key back to about single precision: `spline`'s per-triangle data.)
    for (method, within) in [
        (Method::Linear, 1e-9),
        (Method::Seed, 1e-7),
        (Method::Spline, 1e-7),
    ] {
        let mut o = opts(method);
        o.extend = [0.5, 0.5];
        let frames = track_frames_welded(mesh, &flat, &o).unwrap().1;
        let (t, n) = (plan(times, &o), frames.len());
        let before = t.iter().take_while(|f| f.time < times[0]).count();
        let after = t.iter().filter(|f| f.time > times[k - 1]).count();
        assert!(before > 0 && after > 0, "{method:?}");
        for (f, end) in (0..before)
            .map(|f| (f, first))
            .chain((n - after..n).map(|f| (f, last)))
        {
            let off = max_dist(&frames[f], end);
            assert!(off <= within * d, "{method:?} frame {f}: {off} of {d}");
        }
    }
    // Out of and into each key at the cubic's pace: 0.156 of the way a quarter of the span
    // from it (gradient space is not position space: 0.10-0.22 allowed).
    let eased = frames_of(&flat, Method::Spline);
    for a in 0..k - 1 {
        let (key, next) = (4 * a, 4 * a + 4);
        let span = max_dist(&eased[next], &eased[key]);
        for (frame, end) in [(key + 1, key), (next - 1, next)] {
            let r = max_dist(&eased[frame], &eased[end]) / span;
            assert!((0.10..0.22).contains(&r), "segment {a} frame {frame}: {r}");
        }
    }
}

/// Where the clip's motion turns nothing (two targets that stretch a sheet along x and along
/// y: each triangle's stretch is affine in the weights, and a cubic of its keys' stretches and
/// slopes is the clip's own), `spline` following the eases gives the clip's poses at every
/// frame, for tangents of any size and sign: the eases' slopes at the keys are taken whole.
/// With one target (the clip moving along each segment's chord) `seed` at the eases' pace
/// does too.
#[test]
fn eased_stretches_are_the_clip_s_own() {
    use inbetween::tween::{plan, Track};
    let s = synth::grid(12, 6, 2.0, 1.0);
    let along = |sx: f64, sy: f64| -> Vec<DVec3> {
        (s.positions.iter())
            .map(|p| DVec3::new(p.x * sx, p.y * sy, p.z))
            .collect()
    };
    let (_dir, path) = write_keys(s.clone(), vec![along(1.6, 1.0), along(1.0, 0.6)]);
    let meshes = common::morph_meshes(&path);
    let mesh = &meshes[0];
    let times = vec![0.0, 0.4, 1.0, 1.3];
    let weights = vec![
        vec![0.0, 0.0],
        vec![1.0, 0.2],
        vec![0.3, 1.0],
        vec![0.0, 0.0],
    ];
    let eases = vec![
        [vec![0.0, 0.0], vec![2.0, -1.0]],
        [vec![0.5, 1.5], vec![-0.4, 3.0]],
        [vec![-1.2, 0.0], vec![-2.5, -0.7]],
        [vec![0.3, 0.2], vec![0.0, 0.0]],
    ];
    let track = Track {
        origin: mesh.tracks[0].origin.clone(),
        times: times.clone(),
        weights: weights.clone(),
        eases: Some(eases.clone()),
    };
    // Every frame of `track` by each of `methods` is the clip's pose at its time.
    let plays_the_clip = |mesh: &MorphMesh, track: &Track, methods: &[Method], what: &str| {
        let d = common::diag(&mesh.primitives[0].base);
        for &method in methods {
            let opts = TweenOptions::new(method, Timing::Tweens(5));
            let (welded, frames) = track_frames_welded(mesh, track, &opts).unwrap();
            for (f, at) in plan(&times, &opts).iter().enumerate() {
                let w = clip_weights(track, at);
                let want = welded.weld(&mesh.pose(&w));
                let off = max_dist(&frames[f], &want);
                assert!(
                    off <= 1e-6 * d,
                    "{what}, {method:?} frame {f}: {off} of {d}"
                );
            }
        }
    };
    plays_the_clip(
        mesh,
        &track,
        &[Method::Linear, Method::Spline],
        "two targets",
    );
    // One target: the clip moves along the chord between its keys, so `seed`, taking its path
    // at the eases' pace, gives the clip's poses too.
    let (_dir, path) = write_keys(s.clone(), vec![along(1.6, 0.6)]);
    let meshes = common::morph_meshes(&path);
    let mesh = &meshes[0];
    let track = Track {
        origin: mesh.tracks[0].origin.clone(),
        times: times.clone(),
        weights: weights.iter().map(|w| vec![w[0]]).collect(),
        eases: Some(
            eases
                .iter()
                .map(|e| e.clone().map(|m| vec![m[0]]))
                .collect(),
        ),
    };
    let every = [Method::Seed, Method::Linear, Method::Spline];
    plays_the_clip(mesh, &track, &every, "one target");
}

/// The Flamingo's CUBICSPLINE conversion (every tangent zero: a stop at every key), its frames
/// by each method against the clip's own blend at their times: `seed` at the eases' pace
/// leaves and reaches each key as the clip does, where at its own pace it was as far off as
/// `linear` not following them.
#[test]
fn the_seed_takes_its_path_at_the_eases_pace() {
    use inbetween::tween::{plan, Track};
    let Some(fx) = common::fixtures() else { return };
    let path = fx.join("morph-keyframes/Flamingo_cubicspline_unindexed.glb");
    let meshes = common::morph_meshes(&path);
    let mesh = &meshes[0];
    let eased = &mesh.tracks[0];
    assert!(eased.eases.is_some());
    let unpaced = Track {
        eases: None,
        ..eased.clone()
    };
    let d = common::diag(&mesh.primitives[0].base);
    let off = |track: &Track, method| -> (f64, f64) {
        let opts = TweenOptions::new(method, Timing::Tweens(3));
        let (welded, frames) = track_frames_welded(mesh, track, &opts).unwrap();
        let at = plan(&eased.times, &opts);
        let (mut worst, mut sum) = (0.0f64, 0.0);
        for (f, at) in at.iter().enumerate() {
            let want = welded.weld(&mesh.pose(&clip_weights(eased, at)));
            worst = worst.max(max_dist(&frames[f], &want) / d);
            sum += rms(&frames[f], &want) / d;
        }
        (worst, sum / at.len() as f64)
    };
    for method in [Method::Seed, Method::Linear, Method::Spline] {
        let (w0, m0) = off(&unpaced, method);
        let (w1, m1) = off(eased, method);
        println!("{method:?}: worst {w0:.4} -> {w1:.4}, mean rms {m0:.4} -> {m1:.4}");
        // (Measured: seed 0.0351 -> 0.0295 and 0.0041 -> 0.0021; spline 0.0366 -> 0.0293 and
        // 0.0048 -> 0.0021; linear to 0: the rest is the wings' turns, which a blend shrinks.)
        assert!(w1 < 0.9 * w0 && m1 < 0.6 * m0, "{method:?}");
    }
}
