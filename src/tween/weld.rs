//! Weld stage: merge the vertices that glTF duplicates along UV seams, hard normals and
//! primitive boundaries into one vertex for the solve.
//!
//! Two vertices (of any primitives of one mesh) are welded when their base positions are
//! bit-identical and every morph target moves them alike: each target's POSITION deltas agree
//! within [`DELTA_TOLERANCE`] of the mesh's bounding-box diagonal. A seam therefore cannot open,
//! while vertices that merely touch in the base pose but move apart in a key stay separate.

use super::keys::MorphMesh;
use glam::DVec3;
use std::collections::HashMap;

/// Largest difference between two welded vertices' target deltas, relative to the bounding-box
/// diagonal of the base mesh (unitless).
pub const DELTA_TOLERANCE: f64 = 1e-6;

/// The welded mesh the solver works on.
pub struct Welded {
    /// Number of welded vertices.
    pub n: usize,
    /// For each input vertex (all primitives concatenated), its welded vertex.
    pub of_vertex: Vec<u32>,
    /// For each welded vertex, the first input vertex merged into it.
    pub representative: Vec<u32>,
    /// Triangles over welded vertices; triangles that weld onto fewer than three vertices are
    /// left out.
    pub triangles: Vec<[u32; 3]>,
    /// Triangles over input vertices (concatenated indices), every primitive's.
    pub input_triangles: Vec<[u32; 3]>,
}

impl Welded {
    pub fn build(mesh: &MorphMesh) -> Welded {
        let base: Vec<DVec3> = mesh
            .primitives
            .iter()
            .flat_map(|p| p.base.iter().copied())
            .collect();
        let diag = bbox_diagonal(&base);
        let tol = DELTA_TOLERANCE * diag.max(f64::MIN_POSITIVE);
        let deltas_agree = |a: usize, b: usize| -> bool {
            let (pa, ia) = locate(mesh, a);
            let (pb, ib) = locate(mesh, b);
            (0..mesh.target_count).all(|t| {
                let da = mesh.primitives[pa].target_pos[t][ia];
                let db = mesh.primitives[pb].target_pos[t][ib];
                (da - db).abs().max_element() <= tol
            })
        };
        let mut by_position: HashMap<[u64; 3], Vec<u32>> = HashMap::with_capacity(base.len());
        let mut of_vertex = Vec::with_capacity(base.len());
        let mut representative: Vec<u32> = Vec::new();
        for (v, p) in base.iter().enumerate() {
            // +0.0 and -0.0 are the same place.
            let key = [p.x + 0.0, p.y + 0.0, p.z + 0.0].map(f64::to_bits);
            let candidates = by_position.entry(key).or_default();
            let found = candidates
                .iter()
                .copied()
                .find(|&w| deltas_agree(representative[w as usize] as usize, v));
            let w = match found {
                Some(w) => w,
                None => {
                    let w = representative.len() as u32;
                    representative.push(v as u32);
                    candidates.push(w);
                    w
                }
            };
            of_vertex.push(w);
        }
        let mut input_triangles = Vec::new();
        let mut offset = 0u32;
        for p in &mesh.primitives {
            input_triangles.extend(p.triangles.iter().map(|t| t.map(|i| i + offset)));
            offset += p.base.len() as u32;
        }
        let triangles = input_triangles
            .iter()
            .map(|t| t.map(|i| of_vertex[i as usize]))
            .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
            .collect();
        Welded {
            n: representative.len(),
            of_vertex,
            representative,
            triangles,
            input_triangles,
        }
    }

    /// A per-input-vertex array reduced to welded vertices.
    pub fn weld<T: Copy>(&self, per_input: &[T]) -> Vec<T> {
        self.representative
            .iter()
            .map(|&v| per_input[v as usize])
            .collect()
    }
}

/// (primitive, local index) of concatenated vertex `v`.
fn locate(mesh: &MorphMesh, mut v: usize) -> (usize, usize) {
    for (pi, p) in mesh.primitives.iter().enumerate() {
        if v < p.base.len() {
            return (pi, v);
        }
        v -= p.base.len();
    }
    unreachable!("vertex index beyond the mesh")
}

/// Length of the bounding-box diagonal of `points` (0 for no points).
pub fn bbox_diagonal(points: &[DVec3]) -> f64 {
    let Some(first) = points.first() else {
        return 0.0;
    };
    let (lo, hi) = points
        .iter()
        .fold((*first, *first), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
    (hi - lo).length()
}

/// RMS distance between two poses of the same vertices, divided by `diag`.
pub fn rms_rel(a: &[DVec3], b: &[DVec3], diag: f64) -> f64 {
    let s: f64 = a
        .iter()
        .zip(b)
        .map(|(p, q)| (*p - *q).length_squared())
        .sum();
    (s / a.len() as f64).sqrt() / diag
}
