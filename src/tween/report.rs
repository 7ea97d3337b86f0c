//! `--report FILE.json`: shape-quality figures of every output frame, measured on the welded
//! mesh against the two keys the frame lies between. The file's JSON Schema is
//! `schemas/report.schema.json`.
//!
//! * edge distortion: |length - reference| / reference per edge, where the reference is the
//!   key lengths interpolated linearly at the frame's t (mean and max over edges);
//! * area change: total area relative to the keys' total areas interpolated at t;
//! * volume change: enclosed (signed) volume relative to the keys' volumes interpolated at t, for
//!   closed meshes only (every edge shared by exactly two triangles);
//! * inverted triangles: triangles folded over in the frame but in neither key, where folded
//!   means the triangle's normal points against the (area-weighted) sum of its edge neighbours'
//!   normals. This needs no reference orientation, so a triangle turning 170 degrees between the
//!   keys is not counted at mid-motion.

use glam::DVec3;
use serde::Serialize;
use std::collections::HashMap;

#[derive(Clone, Debug, Serialize)]
pub struct FrameReport {
    pub frame: usize,
    pub time: f64,
    pub key_a: usize,
    pub key_b: usize,
    pub t: f64,
    pub edge_distortion_mean: f64,
    pub edge_distortion_max: f64,
    pub area_change: f64,
    /// None for meshes that are not closed.
    pub volume_change: Option<f64>,
    pub inverted_triangles: usize,
}

#[derive(Clone, Debug, Serialize)]
pub struct MeshReport {
    pub mesh: String,
    pub method: String,
    pub triangles: usize,
    pub closed: bool,
    /// Authored targets given the NORMAL deltas of their shapes (position-only targets in the
    /// glTF rig layout).
    pub targets_given_normals: usize,
    pub frames: Vec<FrameReport>,
}

#[derive(Clone, Debug, Serialize)]
pub struct Report {
    pub input: String,
    pub output: String,
    pub meshes: Vec<MeshReport>,
    /// What `--compact` (or its parts) made of the output; absent for a dense output.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub compact: Option<CompactReport>,
}

/// The compacted output: its size, the tolerance asked for, and each mesh's figures.
#[derive(Clone, Debug, Serialize)]
pub struct CompactReport {
    pub output_bytes: u64,
    pub tolerance: f64,
    pub meshes: Vec<CompactMesh>,
}

#[derive(Clone, Debug, Serialize)]
pub struct CompactMesh {
    pub mesh: String,
    #[serde(flatten)]
    pub figures: super::compact::CompactFigures,
}

/// Per-mesh data the figures need, computed once.
pub struct Shape {
    edges: Vec<[u32; 2]>,
    triangles: Vec<[u32; 3]>,
    /// Edge neighbours of each triangle.
    neighbours: Vec<Vec<u32>>,
    pub closed: bool,
}

impl Shape {
    pub fn new(triangles: &[[u32; 3]]) -> Shape {
        let mut by_edge: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
        for (i, t) in triangles.iter().enumerate() {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                by_edge
                    .entry((a.min(b), a.max(b)))
                    .or_default()
                    .push(i as u32);
            }
        }
        let closed = !by_edge.is_empty() && by_edge.values().all(|v| v.len() == 2);
        let mut neighbours = vec![Vec::new(); triangles.len()];
        for tris in by_edge.values() {
            for &a in tris {
                neighbours[a as usize].extend(tris.iter().copied().filter(|&b| b != a));
            }
        }
        for n in &mut neighbours {
            n.sort_unstable();
        }
        let mut edges: Vec<[u32; 2]> = by_edge.into_keys().map(|(a, b)| [a, b]).collect();
        edges.sort_unstable();
        Shape {
            edges,
            triangles: triangles.to_vec(),
            neighbours,
            closed,
        }
    }

    fn area_volume(&self, x: &[DVec3]) -> (f64, f64) {
        let (mut area, mut volume) = (0.0, 0.0);
        for t in &self.triangles {
            let [a, b, c] = t.map(|i| x[i as usize]);
            area += 0.5 * (b - a).cross(c - a).length();
            volume += a.dot(b.cross(c)) / 6.0;
        }
        (area, volume)
    }

    /// Figures of `frame` between keys `xa` and `xb` at `t`.
    pub fn measure(
        &self,
        frame: &[DVec3],
        xa: &[DVec3],
        xb: &[DVec3],
        t: f64,
    ) -> (f64, f64, f64, Option<f64>, usize) {
        let (mut sum, mut max) = (0.0f64, 0.0f64);
        for e in &self.edges {
            let [i, j] = e.map(|v| v as usize);
            let reference = (1.0 - t) * (xa[i] - xa[j]).length() + t * (xb[i] - xb[j]).length();
            if reference > 0.0 {
                let d = ((frame[i] - frame[j]).length() - reference).abs() / reference;
                sum += d;
                max = max.max(d);
            }
        }
        let mean = sum / self.edges.len().max(1) as f64;
        let (af, vf) = self.area_volume(frame);
        let (aa, va) = self.area_volume(xa);
        let (ab, vb) = self.area_volume(xb);
        let area_ref = (1.0 - t) * aa + t * ab;
        let vol_ref = (1.0 - t) * va + t * vb;
        let area_change = if area_ref > 0.0 {
            af / area_ref - 1.0
        } else {
            0.0
        };
        let volume_change = (self.closed && vol_ref.abs() > 0.0).then(|| vf / vol_ref - 1.0);
        let normal = |x: &[DVec3], tri: &[u32; 3]| {
            let [a, b, c] = tri.map(|i| x[i as usize]);
            (b - a).cross(c - a)
        };
        let folded = |x: &[DVec3], i: usize| -> bool {
            let around: DVec3 = self.neighbours[i]
                .iter()
                .map(|&j| normal(x, &self.triangles[j as usize]))
                .sum();
            normal(x, &self.triangles[i]).dot(around) < 0.0
        };
        let inverted = (0..self.triangles.len())
            .filter(|&i| folded(frame, i) && !folded(xa, i) && !folded(xb, i))
            .count();
        (mean, max, area_change, volume_change, inverted)
    }
}
