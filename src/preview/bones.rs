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

/// The (parent, joint) pairs drawn: every joint with a parent, the two apart.
fn bones(rig: &Rig, world: &[DVec3]) -> Vec<(usize, usize)> {
    (0..rig.len())
        .filter_map(|j| rig.parent[j].map(|p| (p, j)))
        .filter(|&(p, j)| world[p].distance(world[j]) > 0.0)
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
    // The bones of the rest pose (a joint on its parent there has none).
    let drawn = bones(&rig, &joints(a));
    if drawn.is_empty() {
        bail!(crate::gltf::at(
            path,
            "has no bone to draw (every joint on its parent)"
        ));
    }
    let triangles: Vec<[u32; 3]> = (0..drawn.len() as u32).flat_map(|k| faces(6 * k)).collect();
    let columns = times
        .iter()
        .map(|&time| {
            let at = joints(time);
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
