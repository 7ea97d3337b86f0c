//! Fill-reducing ordering of large meshes: geometric nested dissection.
//!
//! A mesh is a surface, so its system matrix is a near-planar graph whose best orderings come
//! from small separators (George's nested dissection). A part is cut at the median of its
//! vertices along x, y and z in turn, and the cut with the fewest separator vertices is kept
//! (the left half's vertices that touch the right half: a mesh's vertex spacing differs by
//! direction, so the longest side of the box is not always the shortest cut); the separator is
//! numbered after the two halves, which are dissected in turn, in parallel, down to leaves of
//! [`LEAF`] vertices. Vertices of more than [`DENSE_DEGREE`] neighbours (a fan's centre closing
//! a cap) are numbered last, as AMD treats dense rows.
//!
//! How good that is depends on the shape, so [`super::solve`] analyses the factor of both this
//! order and faer's approximate minimum degree (AMD) side by side and keeps the one that
//! stores fewer entries. On the bench's 1M-triangle tube (500k vertices) this one wins: 30.1M
//! entries against AMD's 42.2M (METIS: 25.9M, but its ordering alone takes 1.7 s), numeric
//! factorization 1.0 s against 1.6 s, at 4M triangles 5.6 s against 15.2 s. On organic shapes
//! AMD wins and is kept: Flamingo and Parrot subdivided to 0.56M-2.6M triangles, 8-26% more
//! entries by dissection (plane cuts cross wings and body; minimum degree within leaves of 200
//! to 4000 vertices does not change that). Below [`MIN_VERTICES`] only AMD is tried (the outputs
//! of smaller meshes do not change).
//!
//! ```text
//! let perm = order::dissect(&positions, &start, &neighbours);   // perm[new] = old
//! ```

use glam::DVec3;
use std::sync::atomic::{AtomicU32, Ordering::Relaxed};

/// Meshes with fewer welded vertices keep faer's approximate minimum degree ordering.
pub const MIN_VERTICES: usize = 200_000;

/// Largest part left undivided (vertices): it is numbered as it comes.
pub const LEAF: usize = 8;

/// Vertices with more neighbours than this are numbered after everything else.
pub const DENSE_DEGREE: u32 = 32;

/// Parts at least this large (vertices) dissect their two halves on two threads.
const PARALLEL_PART: usize = 20_000;

/// A part of at least [`CHECKED_PART`] vertices whose best cut needs more than this many times
/// the square root of its size as separator is not shaped like a surface in its positions
/// (collapsed or scattered: a base pose at the origin, vertices left in a pile): the caller
/// keeps faer's AMD ordering. A square grid's cut is 1 times the root, a tube's 1.4 times.
pub const BAD_CUT: f64 = 10.0;

/// Smallest part (vertices) whose cut is checked against [`BAD_CUT`].
pub const CHECKED_PART: usize = 10_000;

/// The nested-dissection order of the vertices at `positions` over the symmetric adjacency
/// `neighbours[start[v]..start[v + 1]]`: `perm[new] = old`, each separator after the parts it
/// separates, so the factor's fill stays in the separators' blocks. The same for any number of
/// threads. `None` where the positions do not separate the mesh well ([`BAD_CUT`]).
pub fn dissect(positions: &[DVec3], start: &[u32], neighbours: &[u32]) -> Option<Vec<u32>> {
    let n = positions.len();
    let dense = |v: u32| start[v as usize + 1] - start[v as usize] > DENSE_DEGREE;
    let verts: Vec<u32> = (0..n as u32).filter(|&v| !dense(v)).collect();
    let graph = Graph {
        positions,
        start,
        neighbours,
        tag: (0..n).map(|_| AtomicU32::new(u32::MAX)).collect(),
        next_tag: AtomicU32::new(0),
    };
    let mut out = graph.split(&verts)?;
    out.extend((0..n as u32).filter(|&v| dense(v)));
    Some(out)
}

struct Graph<'a> {
    positions: &'a [DVec3],
    start: &'a [u32],
    neighbours: &'a [u32],
    /// For each vertex, the cut that last put it on its right side: a left vertex finds its
    /// neighbours across the cut in O(degree). Each cut has its own number, so parts dissected
    /// at the same time on other threads never match it.
    tag: Vec<AtomicU32>,
    next_tag: AtomicU32,
}

impl Graph<'_> {
    fn neighbours(&self, v: u32) -> &[u32] {
        &self.neighbours[self.start[v as usize] as usize..self.start[v as usize + 1] as usize]
    }

    /// The order of `verts`: left part, right part, then the separator between them.
    fn split(&self, verts: &[u32]) -> Option<Vec<u32>> {
        if verts.len() <= LEAF {
            return Some(verts.to_vec());
        }
        let mid = verts.len() / 2;
        // The best cut so far: its vertices (left half, then right from `mid`), the left half
        // without the separator, and the separator.
        let mut best: Option<(Vec<u32>, Vec<u32>, Vec<u32>)> = None;
        for axis in 0..3 {
            let mut cut = verts.to_vec();
            cut.select_nth_unstable_by(mid, |a, b| {
                let (pa, pb) = (self.positions[*a as usize], self.positions[*b as usize]);
                pa[axis].total_cmp(&pb[axis]).then(a.cmp(b))
            });
            let t = self.next_tag.fetch_add(1, Relaxed);
            for &v in &cut[mid..] {
                self.tag[v as usize].store(t, Relaxed);
            }
            let (inner, separator): (Vec<u32>, Vec<u32>) = cut[..mid].iter().partition(|&&v| {
                !self
                    .neighbours(v)
                    .iter()
                    .any(|&u| self.tag[u as usize].load(Relaxed) == t)
            });
            if best.as_ref().is_none_or(|b| separator.len() < b.2.len()) {
                best = Some((cut, inner, separator));
            }
        }
        let (cut, inner, separator) = best.expect("three cuts");
        if verts.len() >= CHECKED_PART
            && separator.len() as f64 > BAD_CUT * (verts.len() as f64).sqrt()
        {
            return None;
        }
        let right = &cut[mid..];
        let (a, b) = if inner.len() + right.len() >= PARALLEL_PART {
            rayon::join(|| self.split(&inner), || self.split(right))
        } else {
            (self.split(&inner), self.split(right))
        };
        let mut a = a?;
        a.extend_from_slice(&b?);
        a.extend_from_slice(&separator);
        Some(a)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `w` x `h` grid of vertices at `positions` (4-neighbour adjacency).
    fn grid(w: usize, h: usize) -> (Vec<u32>, Vec<u32>) {
        let mut start = vec![0u32];
        let mut neighbours = Vec::new();
        for i in 0..w * h {
            let (x, y) = (i % w, i / w);
            if x > 0 {
                neighbours.push((i - 1) as u32);
            }
            if x + 1 < w {
                neighbours.push((i + 1) as u32);
            }
            if y > 0 {
                neighbours.push((i - w) as u32);
            }
            if y + 1 < h {
                neighbours.push((i + w) as u32);
            }
            start.push(neighbours.len() as u32);
        }
        (start, neighbours)
    }

    /// A grid's order is a permutation with the middle column last.
    #[test]
    fn a_grid_is_split_by_its_middle_column() {
        let (w, h) = (40usize, 10usize);
        let positions: Vec<DVec3> = (0..w * h)
            .map(|i| DVec3::new((i % w) as f64, (i / w) as f64, 0.0))
            .collect();
        let (start, neighbours) = grid(w, h);
        let perm = dissect(&positions, &start, &neighbours).unwrap();
        let mut seen = perm.clone();
        seen.sort_unstable();
        assert_eq!(seen, (0..(w * h) as u32).collect::<Vec<_>>());
        let last: Vec<usize> = perm[w * h - h..].iter().map(|&v| v as usize % w).collect();
        assert!(last.iter().all(|&x| x == w / 2 - 1), "{last:?}");
    }

    /// Positions that do not follow the mesh (scattered) are refused, so AMD is used.
    #[test]
    fn scattered_positions_are_refused() {
        let (w, h) = (200usize, 200usize);
        let (start, neighbours) = grid(w, h);
        let mut lcg = crate::dev::synth::Lcg(12345);
        let positions: Vec<DVec3> = (0..w * h)
            .map(|_| DVec3::new(lcg.unit(), lcg.unit(), lcg.unit()))
            .collect();
        assert!(dissect(&positions, &start, &neighbours).is_none());
        let laid_out: Vec<DVec3> = (0..w * h)
            .map(|i| DVec3::new((i % w) as f64, (i / w) as f64, 0.0))
            .collect();
        assert!(dissect(&laid_out, &start, &neighbours).is_some());
    }
}
