//! Weld stage: merge the vertices that glTF duplicates along UV seams, hard normals and
//! primitive boundaries into one vertex for the solve.
//!
//! Two vertices (of any primitives of one mesh) are welded when their base positions are
//! bit-identical and every morph target moves them alike: each target's POSITION deltas agree
//! within [`DELTA_TOLERANCE`] of the mesh's bounding-box diagonal. A seam therefore cannot open,
//! while vertices that merely touch in the base pose but move apart in a key stay separate.

use super::keys::MorphMesh;
use glam::DVec3;
use rayon::prelude::*;

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
        // Vertices sorted by position (bit patterns; +0.0 and -0.0 are the same place), then
        // by index: each run of one position is welded on its own, in parallel.
        let keys: Vec<[u64; 3]> = base
            .par_iter()
            .map(|p| [p.x + 0.0, p.y + 0.0, p.z + 0.0].map(f64::to_bits))
            .collect();
        let mut order: Vec<u32> = (0..base.len() as u32).collect();
        order.par_sort_unstable_by_key(|&v| (keys[v as usize], v));
        // Per vertex (in `order`): the vertex it welds onto, the first of its run whose deltas
        // agree with it (itself where none does), as taking the vertices in input order would.
        let mut onto_sorted: Vec<(u32, u32)> = order.iter().map(|&v| (v, v)).collect();
        onto_sorted
            .par_chunk_by_mut(|p, q| keys[p.0 as usize] == keys[q.0 as usize])
            .for_each(|run| {
                for i in 1..run.len() {
                    let v = run[i].0 as usize;
                    if let Some(&(first, _)) = run[..i]
                        .iter()
                        .find(|(w, onto)| w == onto && deltas_agree(*w as usize, v))
                    {
                        run[i].1 = first;
                    }
                }
            });
        let mut onto = vec![0u32; base.len()];
        for &(v, w) in &onto_sorted {
            onto[v as usize] = w;
        }
        // Welded vertices numbered in the order of their first input vertex.
        let mut number = vec![u32::MAX; base.len()];
        let mut representative: Vec<u32> = Vec::new();
        for (v, &w) in onto.iter().enumerate() {
            if w as usize == v {
                number[v] = representative.len() as u32;
                representative.push(v as u32);
            }
        }
        let of_vertex: Vec<u32> = onto.iter().map(|&w| number[w as usize]).collect();
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tween::keys::Primitive;

    /// The weld as a scan in input order: each vertex joins the first earlier welded vertex
    /// at its position whose deltas agree, else starts one.
    fn welded_in_order(mesh: &MorphMesh, tol: f64) -> Vec<u32> {
        let all: Vec<(DVec3, Vec<DVec3>)> = mesh
            .primitives
            .iter()
            .flat_map(|p| {
                (0..p.base.len()).map(|i| (p.base[i], p.target_pos.iter().map(|t| t[i]).collect()))
            })
            .collect();
        let mut firsts: Vec<usize> = Vec::new();
        all.iter()
            .enumerate()
            .map(|(v, (p, d))| {
                let same = |w: &usize| {
                    let (q, e) = &all[*w];
                    *q == *p
                        && d.iter()
                            .zip(e)
                            .all(|(a, b)| (*a - *b).abs().max_element() <= tol)
                };
                match firsts.iter().position(same) {
                    Some(k) => k as u32,
                    None => {
                        firsts.push(v);
                        (firsts.len() - 1) as u32
                    }
                }
            })
            .collect()
    }

    #[test]
    fn welds_as_a_scan_in_input_order_would() {
        // Two primitives over a few positions (+0.0 and -0.0 among them), two targets whose
        // deltas agree on some duplicates and not on others.
        let mut lcg = crate::dev::synth::Lcg(0x9e37_79b9_7f4a_7c15);
        let mut next = |n: u64| (lcg.unit() * n as f64) as u64;
        let spots = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(-0.0, 0.0, -0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(1.0, 1.0, 2.0),
        ];
        let moves = [DVec3::ZERO, DVec3::X, DVec3::new(0.0, 1e-9, 0.0)];
        let primitive = |index: usize, count: usize, next: &mut dyn FnMut(u64) -> u64| {
            let base: Vec<DVec3> = (0..count).map(|_| spots[next(5) as usize]).collect();
            let target_pos = (0..2)
                .map(|_| (0..count).map(|_| moves[next(3) as usize]).collect())
                .collect();
            Primitive {
                index,
                base,
                normals: None,
                tangents: None,
                target_pos,
                target_nrm: vec![None, None],
                target_tan: vec![None, None],
                target_other: Vec::new(),
                triangles: (0..count as u32 / 3)
                    .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
                    .collect(),
            }
        };
        let primitives = vec![primitive(0, 300, &mut next), primitive(1, 240, &mut next)];
        let mesh = MorphMesh {
            mesh: 0,
            name: "m".into(),
            primitives,
            target_count: 2,
            tracks: Vec::new(),
            dropped_channels: Vec::new(),
            normals_given: 0,
        };
        let welded = Welded::build(&mesh);
        let diag = bbox_diagonal(&mesh.pose(&[0.0, 0.0]));
        let want = welded_in_order(&mesh, DELTA_TOLERANCE * diag);
        assert_eq!(welded.of_vertex, want);
        assert_eq!(welded.n, *want.iter().max().unwrap() as usize + 1);
        // Every position and delta pair appears, so some duplicates weld and some do not.
        assert!(welded.n > 5 && welded.n < 540, "{}", welded.n);
        for (w, &v) in welded.representative.iter().enumerate() {
            assert_eq!(welded.of_vertex[v as usize], w as u32);
        }
    }
}
