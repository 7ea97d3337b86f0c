//! Bones (the scene of a BVH motion capture, which has no mesh): its skeleton drawn as a
//! viewer draws bones, an octahedron from each joint's parent to the joint (its widest
//! [`WIDTH`] of its length, [`WAIST`] of the way along), posed at the frames' times (a Z-up
//! capture stood up as `blend` reads it), one band labelled with the capture's file name.
//!
//! ```text
//! let scene = bones::scene(Path::new("walk.bvh"), 12, false)?;
//! ```

use super::clips::band_times;
use super::{Column, Scene};
use crate::blend::{read_bvh, Rig};
use anyhow::{bail, Result};
use glam::DVec3;
use std::path::Path;

/// A bone's widest cross-section (its half-diagonal), as a share of its length.
pub const WIDTH: f64 = 0.1;

/// Where along the bone (from the parent) it is widest.
pub const WAIST: f64 = 0.2;

/// How much a bone's length may change over the frames drawn (a share of its longest): a
/// capture's links keep theirs to its solver's rounding; a root bone left at the floor while
/// the hips below it walk away (Bandai Namco's joint_Root) is no bone.
pub const STRETCH: f64 = 0.25;

/// The (parent, joint) pairs drawn: every joint with a parent, the two apart in the rest pose
/// (`frames[0]`) and as far apart on every frame, within [`STRETCH`].
fn bones(rig: &Rig, frames: &[Vec<DVec3>]) -> Vec<(usize, usize)> {
    let length = |(p, j): (usize, usize), at: &[DVec3]| at[p].distance(at[j]);
    (0..rig.len())
        .filter_map(|j| rig.parent[j].map(|p| (p, j)))
        .filter(|&bone| length(bone, &frames[0]) > 0.0)
        .filter(|&bone| {
            let (lo, hi) = (frames.iter().map(|at| length(bone, at)))
                .fold((f64::INFINITY, 0.0f64), |(lo, hi), l| {
                    (lo.min(l), hi.max(l))
                });
            hi - lo <= STRETCH * hi
        })
        .collect()
}

/// The six points of the octahedron from `a` to `b`: `a`, a square ring about the waist, `b`.
fn octahedron(a: DVec3, b: DVec3) -> [DVec3; 6] {
    let d = b - a;
    let u = d.normalize_or_zero().any_orthonormal_vector() * (WIDTH * d.length());
    let v = d.normalize_or_zero().cross(u);
    let w = a + d * WAIST;
    [a, w + u, w + v, w - u, w - v, b]
}

/// The eight triangles of an octahedron whose six points start at `o`.
fn faces(o: u32) -> [[u32; 3]; 8] {
    let ring = |i: u32| o + 1 + i % 4;
    std::array::from_fn(|k| {
        let i = (k % 4) as u32;
        match k < 4 {
            true => [o, ring(i), ring(i + 1)],
            false => [o + 5, ring(i + 1), ring(i)],
        }
    })
}

/// The file's name without its extension.
fn stem(path: &Path) -> String {
    path.file_stem()
        .map_or_else(|| "capture".into(), |s| s.to_string_lossy().into_owned())
}

/// The capture at `path` as one band of `count` frames spread from its first frame to its
/// last (`animate`: as a clip's, [`band_times`]).
pub fn scene(path: &Path, count: usize, animate: bool) -> Result<Scene> {
    let (rig, clip) = read_bvh(path)?;
    let (a, b) = (clip.start, clip.end);
    let times = band_times((a, b), count, animate, usize::MAX);
    let joints = |t: f64| -> Vec<DVec3> {
        let world = rig.world(&clip.pose(&rig, t));
        world.iter().map(|m| m.w_axis.truncate()).collect()
    };
    // The bones of the first frame (a joint on its parent there has none) that keep their
    // length over the frames drawn.
    let frames: Vec<Vec<DVec3>> = times.iter().map(|&t| joints(t)).collect();
    let drawn = bones(&rig, &frames);
    if drawn.is_empty() {
        bail!(crate::gltf::at(
            path,
            "has no bone to draw (every joint on its parent)"
        ));
    }
    let triangles: Vec<[u32; 3]> = (0..drawn.len() as u32).flat_map(|k| faces(6 * k)).collect();
    let columns = times
        .iter()
        .zip(&frames)
        .map(|(&time, at)| {
            let points = drawn.iter().flat_map(|&(p, j)| octahedron(at[p], at[j]));
            Column {
                meshes: vec![points.collect()],
                key: false,
                time,
            }
        })
        .collect();
    Ok(Scene {
        triangles: vec![triangles],
        // Labelled as `blend` names a capture: by its file's stem (its motion has no name).
        bands: vec![(stem(path), columns)],
    })
}
