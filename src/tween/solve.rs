//! Solve stage: the sparse least-squares (Poisson) reconstruction of ALGORITHMS.md A.4.
//!
//! The seed minimises `sum_j |X_j V_j^-1 - T_j|^2` over all vertices *and* one fourth vertex per
//! triangle. The fourth vertices appear only in their own triangle's terms, so they are
//! eliminated exactly: with `g` the in-plane gradient operator of a reference triangle
//! ([`super::gradient::gradient_operator`]) the normal equations become
//!
//! ```text
//!   A x = b,   A_ab = sum_j g_ja . g_jb,   b_a = sum_j T_j g_ja
//! ```
//!
//! on the n mesh vertices only: A has the sparsity of the mesh (a cotangent-Laplacian-like
//! matrix) and three right-hand sides (x, y, z) share one factorization. The minimiser is the
//! same as the seed's 3(n+m)-unknown system.
//!
//! `A` is singular: one translation per connected component. Each component's first vertex is
//! pinned to 0 (a Dirichlet row), and the component is translated afterwards onto its centroid
//! path. Vertices that no valid triangle touches are pinned too and placed by the caller.
//! Pins are rows of the fixed pattern, so the symbolic analysis (fill-reducing ordering: faer's
//! AMD, or for large meshes [`super::order`]'s nested dissection; elimination tree, supernodes)
//! is done once per mesh and only the numeric factorization is
//! redone for each reference pose.

use anyhow::{anyhow, Result};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholesky, SymbolicCholeskyRaw,
    SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat, SymbolicSparseColMatRef};
use faer::{Par, Side};
use glam::DVec3;
use rayon::prelude::*;

/// The sparsity pattern of a welded mesh's system, analysed once.
pub struct Pattern {
    pub n: usize,
    col_ptr: Vec<u32>,
    row_idx: Vec<u32>,
    /// For each triangle, the value slots of (a,a), (b,b), (c,c), (a,b), (b,c), (c,a) in the
    /// upper-triangular CSC arrays.
    slots: Vec<[u32; 6]>,
    symbolic: SymbolicCholesky<u32>,
    /// The numeric factorization over the supernodes' tree, independent subtrees side by side
    /// (`None`: a simplicial factor, small meshes; faer's own factorization then).
    plan: Option<super::cholesky::Plan>,
    /// Triangles sharing an edge with each triangle (CSR: `neighbours[start[t]..start[t + 1]]`),
    /// found once per mesh for the spline's branch growth.
    neighbour_start: Vec<u32>,
    neighbours: Vec<u32>,
    /// The value buffer of the last factor dropped (see [`Placement::recycle`]), taken by the
    /// next factorization: its pages are already mapped (at 1M triangles a factor's 279 MB
    /// cost 72k page faults, on the factorization's thread).
    spare: std::sync::Mutex<Vec<f64>>,
}

impl Pattern {
    /// Analyse the pattern of `triangles` over `n` vertices at `positions` (a pose of the
    /// mesh: large meshes are ordered by their geometry, [`super::order`]).
    pub fn new(n: usize, triangles: &[[u32; 3]], positions: &[DVec3]) -> Result<Pattern> {
        // Upper-triangular entries (row <= col), column by column.
        let mut cols: Vec<Vec<u32>> = (0..n as u32).map(|i| vec![i]).collect();
        for t in triangles {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                let (r, c) = if a < b { (a, b) } else { (b, a) };
                cols[c as usize].push(r);
            }
        }
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::new();
        col_ptr.push(0u32);
        for c in &mut cols {
            c.sort_unstable();
            c.dedup();
            row_idx.extend_from_slice(c);
            col_ptr.push(row_idx.len() as u32);
        }
        drop(cols);
        let slot = |r: u32, c: u32| -> u32 {
            let (r, c) = if r <= c { (r, c) } else { (c, r) };
            let s = col_ptr[c as usize] as usize;
            let e = col_ptr[c as usize + 1] as usize;
            s as u32 + row_idx[s..e].binary_search(&r).expect("entry in pattern") as u32
        };
        let slots = triangles
            .par_iter()
            .map(|&[a, b, c]| {
                [
                    slot(a, a),
                    slot(b, b),
                    slot(c, c),
                    slot(a, b),
                    slot(b, c),
                    slot(c, a),
                ]
            })
            .collect();
        let sym =
            SymbolicSparseColMat::<u32>::new_checked(n, n, col_ptr.clone(), None, row_idx.clone());
        // The triangles' adjacency beside the analysis (whose minimum degree ordering is one
        // thread's work).
        let (symbolic, (neighbour_start, neighbours)) = rayon::join(
            || analyse(sym.as_ref(), positions),
            || edge_neighbours(triangles),
        );
        let symbolic = symbolic?;
        let plan = match symbolic.raw() {
            SymbolicCholeskyRaw::Supernodal(s) => {
                let inv = symbolic.perm().map(|p| p.arrays().1);
                super::cholesky::Plan::new(s, inv, &col_ptr, &row_idx)
            }
            SymbolicCholeskyRaw::Simplicial(_) => None,
        };
        Ok(Pattern {
            n,
            col_ptr,
            row_idx,
            slots,
            symbolic,
            plan,
            neighbour_start,
            neighbours,
            spare: Default::default(),
        })
    }

    /// The triangles that share an edge with triangle `t`.
    pub fn neighbours(&self, t: usize) -> &[u32] {
        &self.neighbours[self.neighbour_start[t] as usize..self.neighbour_start[t + 1] as usize]
    }

    fn symbolic_matrix(&self) -> SymbolicSparseColMatRef<'_, u32> {
        // SAFETY: the arrays were checked by `new_checked` when the pattern was built.
        unsafe {
            SymbolicSparseColMatRef::new_unchecked(
                self.n,
                self.n,
                &self.col_ptr,
                None,
                &self.row_idx,
            )
        }
    }
}

/// A's upper-triangular values in the pattern's order, from per-triangle gradient operators
/// (`None` for a triangle left out); a pinned vertex's row and column are those of a Dirichlet
/// row (zero, 1 on the diagonal).
fn assemble(
    pattern: &Pattern,
    grads: impl IntoIterator<Item = Option<[DVec3; 3]>>,
    pinned: &[bool],
) -> Vec<f64> {
    let mut a = vec![0.0f64; pattern.row_idx.len()];
    for (g, s) in grads.into_iter().zip(&pattern.slots) {
        let Some(g) = g else { continue };
        for k in 0..3 {
            a[s[k] as usize] += g[k].length_squared();
        }
        for (k, (i, j)) in [(0usize, 1usize), (1, 2), (2, 0)].into_iter().enumerate() {
            a[s[3 + k] as usize] += g[i].dot(g[j]);
        }
    }
    // Dirichlet rows: zero the row and column of a pinned vertex, 1 on its diagonal.
    for c in 0..pattern.n {
        let range = pattern.col_ptr[c] as usize..pattern.col_ptr[c + 1] as usize;
        for (value, &r) in a[range.clone()].iter_mut().zip(&pattern.row_idx[range]) {
            let r = r as usize;
            if pinned[r] || pinned[c] {
                *value = if r == c { 1.0 } else { 0.0 };
            }
        }
    }
    a
}

/// Above this many entries stored below L's diagonal (the supernodes' explicit zeros included),
/// only the column-oriented copy is kept (8 bytes an entry, packed inside the factorization's
/// own buffer) and the row copy (12 bytes a nonzero) is not built: a factor of 16M entries
/// then takes about 140 MiB instead of 320 MiB, and no second buffer is ever allocated.
pub const TWO_COPIES_MAX_ENTRIES: usize = 16_000_000;

/// Most frames solved in one pass over the factor ([`Placement::place_block`]); 12 right-hand
/// sides of 8 bytes fill a 96-byte row, one and a half cache lines.
pub const MAX_BLOCK: usize = 4;

/// A numeric factorization for one reference pose: `P A P^T = L L^T`, with L kept as its
/// diagonal plus a strictly-lower copy by columns, so a frame's three right-hand sides are
/// solved together in one pass over L per direction.
///
/// The columns keep faer's supernodes: the columns of a block share their rows below the block,
/// so a column's entries are the rows after it inside its block (contiguous) and then the
/// block's rows below, stored once per block instead of a row index per entry (about a
/// quarter less memory than plain CSC: the supernodes' explicit zeros are kept, 10-15% of the
/// entries on the bench's tubes). A simplicial factor is kept as one block per column.
pub struct Factor {
    /// `perm[i]`: the original row placed at position i.
    perm: Vec<u32>,
    diag: Vec<f64>,
    /// Strictly-lower L by columns (for the backward solve, a gather per column of L = row of
    /// L^T)...
    columns: Columns,
    /// ...and by rows (for the forward solve, a gather per row of L), so both passes
    /// accumulate in registers instead of scattering into memory.
    row_ptr: Vec<usize>,
    cols: Vec<u32>,
    row_vals: Vec<f64>,
    /// Vertices held at 0 by a Dirichlet row.
    pub pinned: Vec<bool>,
    /// The columns in independent parts, for the solves on several threads.
    parts: Parts,
}

impl Factor {
    /// Assemble `A` from per-triangle gradient operators (`None` for a triangle left out) and
    /// factor it. `pinned[v]` marks vertices fixed at 0.
    pub fn new(
        pattern: &Pattern,
        grads: impl IntoIterator<Item = Option<[DVec3; 3]>>,
        pinned: Vec<bool>,
    ) -> Result<Factor> {
        let a = assemble(pattern, grads, &pinned);
        let sym = pattern.symbolic_matrix();
        let mat = SparseColMatRef::new(sym, &a);
        let symbolic = &pattern.symbolic;
        let spare = pattern.spare.lock().map(|mut s| std::mem::take(&mut *s));
        let mut values = match spare {
            Ok(mut v) if v.capacity() > 0 => {
                v.clear();
                v.resize(symbolic.len_val(), 0.0);
                v
            }
            _ => vec![0.0f64; symbolic.len_val()],
        };
        match (symbolic.raw(), &pattern.plan) {
            (SymbolicCholeskyRaw::Supernodal(s), Some(plan)) => plan.factor(s, &a, &mut values)?,
            _ => {
                let mut mem = MemBuffer::try_new(
                    symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
                )
                .map_err(|_| anyhow!("out of memory for the factorization"))?;
                symbolic
                    .factorize_numeric_llt(
                        &mut values,
                        mat,
                        Side::Upper,
                        LltRegularization::default(),
                        Par::Seq,
                        MemStack::new(&mut mem),
                        Default::default(),
                    )
                    .map_err(|e| anyhow!("the system is not positive definite ({e:?})"))?;
            }
        }
        let n = pattern.n;
        let perm: Vec<u32> = match symbolic.perm() {
            Some(p) => p.arrays().0.to_vec(),
            None => (0..n as u32).collect(),
        };
        // Large factors keep only the column copy: decided on the entries L stores below its
        // diagonal, so a large one is never walked entry by entry (80 ms at 1M triangles).
        let large = stored_below(symbolic, n) > TWO_COPIES_MAX_ENTRIES;
        let (mut row_ptr, mut cols, mut row_vals) = (Vec::new(), Vec::new(), Vec::new());
        if !large {
            // Row copy, built straight from the factor: count, then fill (columns come in
            // order, so each row's entries are sorted). Off-diagonal nonzeros only.
            let for_each_entry = |emit: &mut dyn FnMut(usize, usize, f64)| {
                walk_lower(symbolic, n, &mut |j, r, at| {
                    let v = values[at];
                    if r != j && v != 0.0 {
                        emit(j, r, v);
                    }
                })
            };
            row_ptr = vec![0usize; n + 1];
            for_each_entry(&mut |_, r, _| row_ptr[r + 1] += 1);
            for i in 0..n {
                row_ptr[i + 1] += row_ptr[i];
            }
            let mut next = row_ptr.clone();
            cols = vec![0u32; row_ptr[n]];
            row_vals = vec![0.0f64; row_ptr[n]];
            for_each_entry(&mut |j, r, v| {
                cols[next[r]] = j as u32;
                row_vals[next[r]] = v;
                next[r] += 1;
            });
        }
        // Column copy: compacted in place inside the factor's own buffer (entries only move
        // towards the front), so it costs no second allocation of values.
        let (columns, diag) = Columns::pack(symbolic, values, n);
        Ok(Factor {
            row_ptr,
            cols,
            row_vals,
            perm,
            diag,
            columns,
            pinned,
            parts: Parts::default(),
        }
        .checked())
    }

    /// Check, once, what the solves' unchecked accesses rely on: every row copy's pointer
    /// within its arrays and its indices below n, every column's entries within its values
    /// and its rows below n, the order a permutation's worth of indices below n. (Checked at
    /// every solve before: at 100k triangles a pass over 3M indices a frame.)
    fn checked(self) -> Factor {
        let n = self.diag.len();
        self.columns.check();
        assert_eq!(self.columns.block.len(), n);
        assert!(self.perm.len() == n && self.perm.iter().all(|&p| (p as usize) < n));
        if !self.row_ptr.is_empty() {
            assert_eq!(self.row_ptr.len(), n + 1);
            assert!(self.row_ptr.windows(2).all(|w| w[0] <= w[1]));
            assert!(self.row_ptr[n] <= self.cols.len() && self.cols.len() == self.row_vals.len());
            assert!(self.cols.iter().all(|&c| (c as usize) < n));
        }
        Factor {
            parts: Parts::of(&self.columns, rayon::current_num_threads()),
            ..self
        }
    }

    /// Keep only the column-oriented copy of L (half the memory, a slower forward pass):
    /// done for factors over [`TWO_COPIES_MAX_ENTRIES`].
    #[cfg(test)]
    pub fn keep_columns_only(&mut self) {
        self.row_ptr = Vec::new();
        self.cols = Vec::new();
        self.row_vals = Vec::new();
    }

    /// Nonzeros of L kept for the solves (diagonal included).
    pub fn nonzeros(&self) -> usize {
        self.diag.len() + self.columns.vals.len()
    }

    /// Solve `A x = b` in place for three right-hand sides stored as rows `[x, y, z]`.
    pub fn solve(&self, b: &mut [[f64; 3]]) {
        self.solve_block(b);
    }

    /// Solve `A x = b` in place for `M` right-hand sides stored as rows (x, y and z of several
    /// frames side by side): one pass over the factor serves them all, where a solve per frame
    /// streams the whole factor from memory each time. Each column comes out exactly as a
    /// solve of its own would give it (same operations in the same order).
    pub fn solve_block<const M: usize>(&self, b: &mut [[f64; M]]) {
        let mut y: Vec<[f64; M]> = self.perm.iter().map(|&p| b[p as usize]).collect();
        self.solve_permuted(&mut y);
        for (i, &p) in self.perm.iter().enumerate() {
            b[p as usize] = y[i];
        }
    }

    /// The fill-reducing order of the factor: row `i` of [`Factor::solve_permuted`]'s
    /// argument is vertex `order()[i]`.
    pub fn order(&self) -> &[u32] {
        &self.perm
    }

    /// [`Factor::solve_block`] on right-hand sides already in the factor's order (see
    /// [`Factor::order`]), in place: no copy of the block.
    ///
    /// The independent [`Parts`] of the factor are solved on all threads (the forward pass
    /// when the row copy is kept; the backward pass always); each entry of the result comes
    /// from the same operations in the same order as on one thread, so the same bits.
    ///
    /// On an x86-64 processor with AVX2 the same code is compiled for it (vectors of four
    /// instead of two): the same multiplications and additions in the same order (no fused
    /// multiply-add), so the same bits on every machine.
    pub fn solve_permuted<const M: usize>(&self, y: &mut [[f64; M]]) {
        let n = self.diag.len();
        assert_eq!(y.len(), n);
        let rows = Rows(y.as_mut_ptr());
        let parts = &self.parts;
        // SAFETY: every range lies within 0..n (`Parts::of`), and the arrays are as
        // `Factor::checked` asserted; parts run side by side only where `Parts::of` found that
        // each reads and writes its own rows and reads no row another part writes.
        unsafe {
            // Each thread's list of subtrees, one after the other.
            let subtrees = |pass: Pass| {
                parts.bins.par_iter().for_each(|bin| {
                    for r in bin {
                        self.pass(pass, rows, r.clone());
                    }
                })
            };
            // L z = P b
            if self.row_ptr.is_empty() {
                // Only the column copy is kept: scatter each finished value down its column,
                // into rows of other parts too, so on one thread.
                self.pass(Pass::ForwardScatter, rows, 0..n);
            } else {
                subtrees(Pass::Forward);
                for r in &parts.top {
                    self.pass(Pass::Forward, rows, r.clone());
                }
            }
            // L^T w = z
            for r in parts.top.iter().rev() {
                self.pass(Pass::Backward, rows, r.clone());
            }
            subtrees(Pass::Backward);
        }
    }

    /// One pass over the columns `range` of `y` (see [`Pass`]), compiled for AVX2 where the
    /// processor has it.
    ///
    /// # Safety
    /// `range` within `0..n`, `y` holding n rows, and no row this pass reads or writes written
    /// by another thread meanwhile.
    unsafe fn pass<const M: usize>(&self, pass: Pass, y: Rows<M>, range: std::ops::Range<usize>) {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            self.pass_avx2(pass, y, range);
            return;
        }
        self.pass_portable(pass, y, range);
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn pass_avx2<const M: usize>(
        &self,
        pass: Pass,
        y: Rows<M>,
        range: std::ops::Range<usize>,
    ) {
        self.pass_portable(pass, y, range);
    }

    #[inline(always)]
    unsafe fn pass_portable<const M: usize>(
        &self,
        pass: Pass,
        y: Rows<M>,
        range: std::ops::Range<usize>,
    ) {
        match pass {
            Pass::Forward => {
                // Gather along each row of L.
                for i in range {
                    gather_step(y, i, &self.cols, &self.row_vals, &self.row_ptr, &self.diag);
                }
            }
            Pass::ForwardScatter => {
                for j in range {
                    let d = 1.0 / *self.diag.get_unchecked(j);
                    let v = y.get(j);
                    let w: [f64; M] = std::array::from_fn(|c| v[c] * d);
                    y.set(j, w);
                    let (k, inside, below) = self.columns.column(j);
                    let vals = self.columns.vals.get_unchecked(k..);
                    scatter_column(y, vals, inside, below, w);
                }
            }
            Pass::Backward => {
                // Gather along each column of L.
                for j in range.rev() {
                    let (k, inside, below) = self.columns.column(j);
                    let vals = self.columns.vals.get_unchecked(k..);
                    let s = gather_column(y, vals, inside, below);
                    let b = y.get(j);
                    let d = 1.0 / *self.diag.get_unchecked(j);
                    y.set(j, std::array::from_fn(|c| (b[c] - s[c]) * d));
                }
            }
        }
    }
}

/// One pass of the triangular solves over a range of columns: forward (`L z = b`) gathering
/// along L's rows (row copy kept) or scattering down its columns (column copy only, ascending),
/// or backward (`L^T w = z`, gathering along L's columns, descending).
#[derive(Clone, Copy)]
enum Pass {
    Forward,
    ForwardScatter,
    Backward,
}

/// The right-hand sides being solved, rows of `M` values, shared by the threads of a solve
/// (each writing its own rows: see [`Parts`]).
#[derive(Clone, Copy)]
struct Rows<const M: usize>(*mut [f64; M]);

// SAFETY: the threads of a solve write disjoint rows and read no row another writes meanwhile
// ([`Factor::solve_permuted`]).
unsafe impl<const M: usize> Send for Rows<M> {}
unsafe impl<const M: usize> Sync for Rows<M> {}

impl<const M: usize> Rows<M> {
    /// # Safety
    /// `i` within the rows, not written meanwhile by another thread.
    #[inline(always)]
    unsafe fn get(self, i: usize) -> [f64; M] {
        *self.0.add(i)
    }

    /// Row `i` in place, for reading.
    ///
    /// # Safety
    /// As for [`Rows::get`], for as long as the reference is used.
    #[inline(always)]
    unsafe fn row<'a>(self, i: usize) -> &'a [f64; M] {
        &*self.0.add(i)
    }

    /// # Safety
    /// As for [`Rows::get`], and not read meanwhile by another thread.
    #[inline(always)]
    unsafe fn set(self, i: usize, v: [f64; M]) {
        *self.0.add(i) = v;
    }
}

/// The factor's columns split for the solves on several threads: subtrees of the elimination
/// tree of L's blocks (supernodes), each a range of consecutive columns (the order is a
/// postorder) whose entries below the diagonal lie in its own range or in `top`, the columns
/// above them (the separators of a nested dissection). Going forward a row of L gathers only
/// from its subtree, going back a column only from its ancestors: the ranges are solved side
/// by side, `top` alone (after them forward, before them back).
#[derive(Default)]
struct Parts {
    /// The subtrees (ranges of columns) dealt out to the threads, one list a thread (see
    /// [`deal`]).
    bins: Vec<Vec<std::ops::Range<usize>>>,
    /// Every other column, as ascending ranges.
    top: Vec<std::ops::Range<usize>>,
}

/// Fewest entries of L for the solves to be split (below, a solve takes well under 0.1 ms and
/// the threads' hand-over would cost more than it saves).
const PARTS_MIN_ENTRIES: usize = 100_000;

impl Parts {
    /// Split `columns` for `threads` threads: the largest subtree, from the roots down, is
    /// split into its children (its block going to `top`) while it holds more than a thread's
    /// share of the subtrees' entries; the subtrees are then dealt to the threads (see
    /// [`deal`]). No subtree, all columns in `top`, where the factor is
    /// small, one thread runs, or the blocks are not in the order this relies on (checked
    /// entry by entry).
    fn of(columns: &Columns, threads: usize) -> Parts {
        let n = columns.block.len();
        let all = Parts {
            bins: Vec::new(),
            top: std::iter::once(0..n).collect(),
        };
        if threads < 2 || columns.vals.len() < PARTS_MIN_ENTRIES {
            return all;
        }
        let blocks = columns.end.len();
        // Block b's columns are start[b]..end[b], consecutive, blocks in order.
        let start: Vec<usize> = std::iter::once(0)
            .chain(columns.end.iter().map(|&e| e as usize))
            .take(blocks)
            .collect();
        let in_order = (0..n).all(|j| {
            let b = columns.block[j] as usize;
            start[b] <= j && j < columns.end[b] as usize
        });
        if !in_order || blocks == 0 || columns.end[blocks - 1] as usize != n {
            return all;
        }
        const ROOT: usize = usize::MAX;
        let below = |b: usize| &columns.below[columns.below_ptr[b]..columns.below_ptr[b + 1]];
        let parent: Vec<usize> = (0..blocks)
            .map(|b| {
                below(b)
                    .iter()
                    .min()
                    .map_or(ROOT, |&r| columns.block[r as usize] as usize)
            })
            .collect();
        if parent.iter().enumerate().any(|(b, &p)| p != ROOT && p <= b) {
            return all;
        }
        // Each subtree's entries and first block; a postorder numbers a subtree b as
        // first[b]..=b.
        let mut work: Vec<usize> = (0..blocks)
            .map(|b| columns.col_ptr[columns.end[b] as usize] - columns.col_ptr[start[b]])
            .collect();
        let mut first: Vec<usize> = (0..blocks).collect();
        let mut count = vec![1usize; blocks];
        for (b, &p) in parent.iter().enumerate() {
            if p != ROOT {
                work[p] += work[b];
                first[p] = first[p].min(first[b]);
                count[p] += count[b];
            }
        }
        if (0..blocks).any(|b| count[b] != b + 1 - first[b]) {
            return all;
        }
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); blocks];
        let mut roots = Vec::new();
        for (b, &p) in parent.iter().enumerate() {
            match p {
                ROOT => roots.push(b),
                p => children[p].push(b),
            }
        }
        // Split the largest subtree while it outweighs a thread's share.
        let mut heap: std::collections::BinaryHeap<(usize, usize)> =
            roots.iter().map(|&b| (work[b], b)).collect();
        let mut held: usize = heap.iter().map(|&(w, _)| w).sum();
        while let Some(&(w, b)) = heap.peek() {
            if w * threads <= held {
                break;
            }
            heap.pop();
            held -= w;
            for &c in &children[b] {
                heap.push((work[c], c));
                held += work[c];
            }
        }
        let mut ranges: Vec<std::ops::Range<usize>> = heap
            .into_iter()
            .map(|(_, b)| start[first[b]]..columns.end[b] as usize)
            .collect();
        ranges.sort_by_key(|r| r.start);
        if ranges.len() < 2 {
            return all;
        }
        // Label each column with its range (or none: top) and check every entry below the
        // diagonal against it.
        const TOP: u32 = u32::MAX;
        let mut label = vec![TOP; n];
        for (k, r) in ranges.iter().enumerate() {
            label[r.clone()].fill(k as u32);
        }
        let fits = (0..blocks).all(|b| {
            let own = label[start[b]];
            (start[b]..columns.end[b] as usize).all(|j| label[j] == own)
                && below(b)
                    .iter()
                    .all(|&r| label[r as usize] == own || label[r as usize] == TOP)
                && (own != TOP || below(b).iter().all(|&r| label[r as usize] == TOP))
        });
        if !fits {
            return all;
        }
        let mut top: Vec<std::ops::Range<usize>> = Vec::new();
        for j in (0..n).filter(|&j| label[j] == TOP) {
            match top.last_mut() {
                Some(r) if r.end == j => r.end += 1,
                _ => top.push(j..j + 1),
            }
        }
        let work = |r: &std::ops::Range<usize>| columns.col_ptr[r.end] - columns.col_ptr[r.start];
        let bins = deal(&ranges, work, threads);
        Parts { bins, top }
    }
}

/// `ranges` dealt out to `threads` lists of about equal `work`: the largest first, each to the
/// list that holds least so far (the subtrees are solved each on one thread, so a thread that
/// took the largest one last would leave the other waiting).
fn deal(
    ranges: &[std::ops::Range<usize>],
    work: impl Fn(&std::ops::Range<usize>) -> usize,
    threads: usize,
) -> Vec<Vec<std::ops::Range<usize>>> {
    let mut by_work: Vec<&std::ops::Range<usize>> = ranges.iter().collect();
    by_work.sort_by_key(|r| (std::cmp::Reverse(work(r)), r.start));
    let mut bins: Vec<(usize, Vec<std::ops::Range<usize>>)> =
        vec![(0, Vec::new()); threads.min(ranges.len())];
    for r in by_work {
        let least = (0..bins.len())
            .min_by_key(|&b| (bins[b].0, b))
            .expect("a bin");
        bins[least].0 += work(r);
        bins[least].1.push(r.clone());
    }
    bins.into_iter().map(|(_, bin)| bin).collect()
}

/// L's strictly-lower columns in blocks (see [`Factor`]): column j's values at
/// `col_ptr[j]..col_ptr[j + 1]`, first rows `j + 1..end[b]`, then rows
/// `below[below_ptr[b]..below_ptr[b + 1]]`, with `b = block[j]`.
struct Columns {
    col_ptr: Vec<usize>,
    vals: Vec<f64>,
    block: Vec<u32>,
    end: Vec<u32>,
    below_ptr: Vec<usize>,
    below: Vec<u32>,
}

impl Columns {
    /// Column j of L below the diagonal: where its values start, its rows inside its block,
    /// then its block's rows below.
    ///
    /// # Safety
    /// `j < n` and the columns checked by [`Columns::check`].
    #[inline(always)]
    unsafe fn column(&self, j: usize) -> (usize, std::ops::Range<usize>, &[u32]) {
        let b = *self.block.get_unchecked(j) as usize;
        let end = *self.end.get_unchecked(b) as usize;
        let below = *self.below_ptr.get_unchecked(b)..*self.below_ptr.get_unchecked(b + 1);
        (
            *self.col_ptr.get_unchecked(j),
            j + 1..end,
            self.below.get_unchecked(below),
        )
    }

    /// Check what [`Columns::column`] relies on: every column's entries lie within `vals` and
    /// its rows below `n`.
    fn check(&self) {
        let n = self.block.len();
        assert_eq!(self.col_ptr.len(), n + 1);
        assert_eq!(self.below_ptr.len(), self.end.len() + 1);
        assert!(self.below_ptr.windows(2).all(|w| w[0] <= w[1]));
        assert!(self
            .below_ptr
            .last()
            .is_some_and(|&e| e <= self.below.len()));
        assert!(self.below.iter().all(|&r| (r as usize) < n));
        assert!(self.col_ptr[n] <= self.vals.len());
        for j in 0..n {
            let b = self.block[j] as usize;
            assert!(b < self.end.len());
            let end = self.end[b] as usize;
            assert!(j < end && end <= n);
            let count = end - j - 1 + self.below_ptr[b + 1] - self.below_ptr[b];
            assert_eq!(self.col_ptr[j + 1] - self.col_ptr[j], count);
        }
    }

    /// Pack the strictly-lower entries of the factorization's buffer `values` to its front, in
    /// place (every entry moves only forwards: each column drops at least its diagonal).
    /// Also returns L's diagonal.
    fn pack(
        symbolic: &SymbolicCholesky<u32>,
        mut values: Vec<f64>,
        n: usize,
    ) -> (Columns, Vec<f64>) {
        let mut diag = Vec::with_capacity(n);
        let mut c = Columns {
            col_ptr: Vec::with_capacity(n + 1),
            vals: Vec::new(),
            block: Vec::with_capacity(n),
            end: Vec::new(),
            below_ptr: vec![0],
            below: Vec::new(),
        };
        c.col_ptr.push(0);
        let mut w = 0usize;
        // Column j: its diagonal at `at` (read before any entry moves over it), its entries
        // below the diagonal at `from`.
        let mut keep = |c: &mut Columns, at: usize, from: std::ops::Range<usize>| {
            diag.push(values[at]);
            let len = from.len();
            values.copy_within(from, w);
            w += len;
            c.col_ptr.push(w);
        };
        match symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                let (cp, ri) = (s.col_ptr(), s.row_idx());
                for j in 0..n {
                    let range = cp[j] as usize..cp[j + 1] as usize;
                    // Rows ascend: the diagonal, then the entries below it.
                    let first =
                        range.start + ri[range.clone()].partition_point(|&r| r as usize <= j);
                    c.block.push(c.end.len() as u32);
                    c.end.push(j as u32 + 1);
                    c.below.extend_from_slice(&ri[first..range.end]);
                    c.below_ptr.push(c.below.len());
                    keep(&mut c, first - 1, first..range.end);
                }
            }
            SymbolicCholeskyRaw::Supernodal(s) => {
                for (sn, block) in supernodes(s).enumerate() {
                    let (ncols, nrows) = (block.columns.len(), block.height());
                    c.end.push(block.columns.end as u32);
                    c.below.extend_from_slice(block.rows);
                    c.below_ptr.push(c.below.len());
                    for k in 0..ncols {
                        c.block.push(sn as u32);
                        // Column k of the block is column-major: rows k + 1.. follow its diagonal.
                        let at = block.base + k * nrows;
                        keep(&mut c, at + k, at + k + 1..at + nrows);
                    }
                }
            }
        }
        values.truncate(w);
        values.shrink_to_fit();
        c.below.shrink_to_fit();
        c.vals = values;
        (c, diag)
    }
}

/// Every stored entry of L on or below the diagonal, column by column with rows ascending, as
/// (column, row, position in the factor's value array), for either of faer's layouts: simplicial
/// (plain CSC) or supernodal (per supernode a dense column-major block: the diagonal block's
/// rows, then the supernode's pattern rows).
fn walk_lower(symbolic: &SymbolicCholesky<u32>, n: usize, f: &mut dyn FnMut(usize, usize, usize)) {
    match symbolic.raw() {
        SymbolicCholeskyRaw::Simplicial(s) => {
            let (cp, ri) = (s.col_ptr(), s.row_idx());
            for j in 0..n {
                let range = cp[j] as usize..cp[j + 1] as usize;
                for (k, &r) in range.clone().zip(&ri[range]) {
                    f(j, r as usize, k);
                }
            }
        }
        SymbolicCholeskyRaw::Supernodal(s) => {
            for block in supernodes(s) {
                let (start, ncols, nrows) =
                    (block.columns.start, block.columns.len(), block.height());
                for c in 0..ncols {
                    for r in c..nrows {
                        let row = if r < ncols {
                            start + r
                        } else {
                            block.rows[r - ncols] as usize
                        };
                        f(start + c, row, block.base + c * nrows + r);
                    }
                }
            }
        }
    }
}

/// Entries L stores strictly below its diagonal (what [`Columns::pack`] keeps).
fn stored_below(symbolic: &SymbolicCholesky<u32>, n: usize) -> usize {
    match symbolic.raw() {
        SymbolicCholeskyRaw::Simplicial(s) => s.row_idx().len() - n,
        SymbolicCholeskyRaw::Supernodal(s) => supernodes(s)
            .map(|b| {
                let (ncols, nrows) = (b.columns.len(), b.height());
                ncols * nrows - ncols * (ncols + 1) / 2
            })
            .sum(),
    }
}

/// One supernode of faer's factor: its columns, the rows below its diagonal block, and where
/// its dense column-major block (the diagonal block's rows, then `rows`) starts in the values.
struct Supernode<'s> {
    columns: std::ops::Range<usize>,
    rows: &'s [u32],
    base: usize,
}

impl Supernode<'_> {
    /// Rows of the block: the diagonal block's, then those below.
    fn height(&self) -> usize {
        self.columns.len() + self.rows.len()
    }
}

fn supernodes<'s>(
    s: &'s faer::sparse::linalg::cholesky::supernodal::SymbolicSupernodalCholesky<u32>,
) -> impl Iterator<Item = Supernode<'s>> {
    let (begin, end) = (s.supernode_begin(), s.supernode_end());
    (0..s.n_supernodes()).map(move |sn| Supernode {
        columns: begin[sn] as usize..end[sn] as usize,
        rows: s.supernode(sn).pattern(),
        base: s.col_ptr_for_val()[sn] as usize,
    })
}

/// One step of a gathering triangular solve: `y[i] = (y[i] - sum_k vals[k] y[idx[k]]) / diag[i]`
/// over `k` in `ptr[i]..ptr[i + 1]`.
///
/// # Safety
/// `i + 1 < ptr.len()`, `i < diag.len()`, and as for [`gather_dot`].
#[inline(always)]
unsafe fn gather_step<const M: usize>(
    y: Rows<M>,
    i: usize,
    idx: &[u32],
    vals: &[f64],
    ptr: &[usize],
    diag: &[f64],
) {
    let s = gather_dot(
        y,
        idx,
        vals,
        *ptr.get_unchecked(i),
        *ptr.get_unchecked(i + 1),
    );
    let b = y.get(i);
    let d = 1.0 / *diag.get_unchecked(i);
    y.set(i, std::array::from_fn(|c| (b[c] - s[c]) * d));
}

/// `sum_k vals[k] * y[idx[k]]` over `start..end`, for `M` right-hand sides at once, with two
/// accumulators per component to halve the floating-point add latency chain.
///
/// # Safety
/// `start..end` must lie within `idx` and `vals`, and every `idx[k]` within `y`.
#[inline(always)]
unsafe fn gather_dot<const M: usize>(
    y: Rows<M>,
    idx: &[u32],
    vals: &[f64],
    start: usize,
    end: usize,
) -> [f64; M] {
    let mut sums = [[0.0f64; M]; 2];
    add_pairs(&mut sums, end - start, |k| {
        let k = start + k;
        (
            *vals.get_unchecked(k),
            y.row(*idx.get_unchecked(k) as usize),
        )
    });
    std::array::from_fn(|c| sums[0][c] + sums[1][c])
}

/// Add `count` terms `v * row` (`term(k)` gives the k-th) into two accumulators, alternately:
/// the inner loop of the triangular solves.
#[inline(always)]
fn add_pairs<'y, const M: usize>(
    sums: &mut [[f64; M]; 2],
    count: usize,
    term: impl Fn(usize) -> (f64, &'y [f64; M]),
) {
    let mut k = 0;
    while k + 1 < count {
        let ((v0, t0), (v1, t1)) = (term(k), term(k + 1));
        for c in 0..M {
            sums[0][c] += v0 * t0[c];
            sums[1][c] += v1 * t1[c];
        }
        k += 2;
    }
    if k < count {
        let (v, t) = term(k);
        for c in 0..M {
            sums[0][c] += v * t[c];
        }
    }
}

/// `sum_k vals[k] * y[row_k]` over a column's rows, `inside` (contiguous) then `below`, for
/// `M` right-hand sides at once, with two accumulators per component as in [`gather_dot`].
///
/// # Safety
/// `vals` must hold an entry for every row, and every row must lie within `y`.
#[inline(always)]
unsafe fn gather_column<const M: usize>(
    y: Rows<M>,
    vals: &[f64],
    inside: std::ops::Range<usize>,
    below: &[u32],
) -> [f64; M] {
    let mut sums = [[0.0f64; M]; 2];
    let first = inside.start;
    let count = inside.len();
    add_pairs(&mut sums, count, |k| {
        (*vals.get_unchecked(k), y.row(first + k))
    });
    add_pairs(&mut sums, below.len(), |k| {
        (
            *vals.get_unchecked(count + k),
            y.row(*below.get_unchecked(k) as usize),
        )
    });
    std::array::from_fn(|c| sums[0][c] + sums[1][c])
}

/// `y[row_k] -= vals[k] * w` over a column's rows, `inside` (contiguous) then `below`, for `M`
/// right-hand sides at once: the forward pass's scatter, the twin of [`gather_column`] (two
/// plain loops: one chained iterator over both ran 4% slower at 1M triangles).
///
/// # Safety
/// As for [`gather_column`].
#[inline(always)]
unsafe fn scatter_column<const M: usize>(
    y: Rows<M>,
    vals: &[f64],
    inside: std::ops::Range<usize>,
    below: &[u32],
    w: [f64; M],
) {
    let count = inside.len();
    let subtract = |k: usize, r: usize| {
        let l = *vals.get_unchecked(k);
        let mut t = y.get(r);
        for c in 0..M {
            t[c] -= l * w[c];
        }
        y.set(r, t);
    };
    for (k, r) in inside.enumerate() {
        subtract(k, r);
    }
    for (k, &r) in below.iter().enumerate() {
        subtract(count + k, r as usize);
    }
}

/// Connected components of `triangles` over `n` vertices (union-find); vertices touched by no
/// triangle get `u32::MAX`. Components are numbered in order of their smallest vertex.
pub fn components(n: usize, triangles: &[[u32; 3]]) -> (Vec<u32>, usize) {
    let mut parent: Vec<u32> = (0..n as u32).collect();
    fn find(p: &mut [u32], mut x: u32) -> u32 {
        while p[x as usize] != x {
            p[x as usize] = p[p[x as usize] as usize];
            x = p[x as usize];
        }
        x
    }
    let mut touched = vec![false; n];
    for t in triangles {
        for &v in t {
            touched[v as usize] = true;
        }
        for (a, b) in [(t[0], t[1]), (t[1], t[2])] {
            let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
            if ra != rb {
                let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
                parent[hi as usize] = lo;
            }
        }
    }
    let mut label = vec![u32::MAX; n];
    let mut root_label = vec![u32::MAX; n];
    let mut count = 0usize;
    for v in 0..n {
        if !touched[v] {
            continue;
        }
        let r = find(&mut parent, v as u32) as usize;
        if root_label[r] == u32::MAX {
            root_label[r] = count as u32;
            count += 1;
        }
        label[v] = root_label[r];
    }
    (label, count)
}

/// The solve for one reference pose with its translations fixed: one vertex of every
/// connected component (of the valid triangles) is pinned, and after each solve every
/// component is translated onto the centroid the caller wants; vertices that no valid triangle
/// touches are placed by the caller.
pub struct Placement {
    factor: Factor,
    component: Vec<u32>,
    size: Vec<usize>,
}

impl Placement {
    /// Factor the system of `n` vertices: `grads` per triangle of the pattern (None for one
    /// left out), `valid` the corners of the triangles kept.
    pub fn new(
        pattern: &Pattern,
        n: usize,
        grads: impl IntoIterator<Item = Option<[DVec3; 3]>>,
        valid: &[[u32; 3]],
    ) -> Result<Placement> {
        let (component, count) = components(n, valid);
        let mut pinned = vec![false; n];
        let mut seen = vec![false; count];
        for (pin, &c) in pinned.iter_mut().zip(&component) {
            if c == u32::MAX {
                *pin = true;
            } else if !seen[c as usize] {
                seen[c as usize] = true;
                *pin = true;
            }
        }
        let mut size = vec![0usize; count];
        for &c in component.iter().filter(|&&c| c != u32::MAX) {
            size[c as usize] += 1;
        }
        Ok(Placement {
            factor: Factor::new(pattern, grads, pinned)?,
            component,
            size,
        })
    }

    /// Hand the factor's value buffer to `pattern` for the next factorization.
    pub fn recycle(self, pattern: &Pattern) {
        if let Ok(mut spare) = pattern.spare.lock() {
            *spare = self.factor.columns.vals;
        }
    }

    /// Number of connected components.
    pub fn component_count(&self) -> usize {
        self.size.len()
    }

    /// Component of vertex `v` (None for a vertex no valid triangle touches).
    pub fn component_of(&self, v: usize) -> Option<usize> {
        let c = self.component[v];
        (c != u32::MAX).then_some(c as usize)
    }

    /// Vertex centroid of every component in pose `x`.
    pub fn centroids(&self, x: &[DVec3]) -> Vec<DVec3> {
        let mut sum = vec![DVec3::ZERO; self.size.len()];
        for (p, &c) in x.iter().zip(&self.component) {
            if c != u32::MAX {
                sum[c as usize] += *p;
            }
        }
        sum.iter()
            .zip(&self.size)
            .map(|(s, &m)| *s / m as f64)
            .collect()
    }

    /// Solve for `rhs`, then move component c so its centroid is `centroid[c]`; a vertex no
    /// valid triangle touches goes to `loose(v)`.
    pub fn place(
        &self,
        mut rhs: Vec<[f64; 3]>,
        centroid: &[DVec3],
        loose: impl Fn(usize) -> DVec3,
    ) -> Vec<DVec3> {
        for (b, &p) in rhs.iter_mut().zip(&self.factor.pinned) {
            if p {
                *b = [0.0; 3];
            }
        }
        self.factor.solve(&mut rhs);
        self.centre(
            rhs.iter().map(|b| DVec3::from_array(*b)).collect(),
            centroid,
            loose,
        )
    }

    /// [`Placement::place`] for several frames (`rhs`, `centroids` and `loose` per frame), up to
    /// [`MAX_BLOCK`] solved in one pass over the factor; the same positions, bit for bit.
    pub fn place_block(
        &self,
        rhs: Vec<Vec<[f64; 3]>>,
        centroids: &[Vec<DVec3>],
        loose: impl Fn(usize, usize) -> DVec3,
    ) -> Vec<Vec<DVec3>> {
        let mut solved = Vec::with_capacity(rhs.len());
        let mut rest = rhs.into_iter().peekable();
        while rest.peek().is_some() {
            let part: Vec<Vec<[f64; 3]>> = rest.by_ref().take(MAX_BLOCK).collect();
            solved.extend(match part.len() {
                1 => self.solve_packed::<3>(part),
                2 => self.solve_packed::<6>(part),
                3 => self.solve_packed::<9>(part),
                _ => self.solve_packed::<12>(part),
            });
        }
        solved
            .into_iter()
            .zip(centroids)
            .enumerate()
            .map(|(f, (x, c))| self.centre(x, c, |v| loose(f, v)))
            .collect()
    }

    /// Solve the frames of `rhs` (M / 3 of them) side by side; pinned rows are zero. `rhs` is
    /// dropped once packed.
    fn solve_packed<const M: usize>(&self, rhs: Vec<Vec<[f64; 3]>>) -> Vec<Vec<DVec3>> {
        let frames = M / 3;
        debug_assert_eq!(rhs.len(), frames);
        let order = self.factor.order();
        // Packed straight in the factor's order, solved in place.
        let mut y: Vec<[f64; M]> = order
            .iter()
            .map(|&v| {
                let v = v as usize;
                let mut row = [0.0; M];
                if !self.factor.pinned[v] {
                    for (f, r) in rhs.iter().enumerate() {
                        row[3 * f..3 * f + 3].copy_from_slice(&r[v]);
                    }
                }
                row
            })
            .collect();
        drop(rhs);
        self.factor.solve_permuted(&mut y);
        (0..frames)
            .map(|f| {
                let mut out = vec![DVec3::ZERO; y.len()];
                for (row, &v) in y.iter().zip(order) {
                    out[v as usize] = DVec3::new(row[3 * f], row[3 * f + 1], row[3 * f + 2]);
                }
                out
            })
            .collect()
    }

    /// Move component c of the solved positions `out` so its centroid is `centroid[c]`; a vertex
    /// no valid triangle touches goes to `loose(v)`.
    fn centre(
        &self,
        mut out: Vec<DVec3>,
        centroid: &[DVec3],
        loose: impl Fn(usize) -> DVec3,
    ) -> Vec<DVec3> {
        let shift: Vec<DVec3> = self
            .centroids(&out)
            .iter()
            .zip(centroid)
            .map(|(now, want)| *want - *now)
            .collect();
        for (v, p) in out.iter_mut().enumerate() {
            match self.component[v] {
                u32::MAX => *p = loose(v),
                c => *p += shift[c as usize],
            }
        }
        out
    }

    pub fn factor_nonzeros(&self) -> usize {
        self.factor.nonzeros()
    }
}

/// Triangles taken per parallel pass of [`in_order`] (a pass's terms, up to about 400 bytes a
/// triangle for a block of four spline frames, stay in cache while they are added).
const TERMS_CHUNK: usize = 4096;

/// `each(t)` for every `t` in `0..count`, computed on all threads [`TERMS_CHUNK`] at a time,
/// and given to `add` in order of `t` on one thread (beside the next chunk's computation):
/// sums built by `add` are the same, bit for bit, on any number of threads as on one. (On one
/// thread the terms pass through the chunk too; a frame there costs what it did with a loop
/// adding each term as it is made, within 3% over five alternating bench runs, and a path of
/// its own for one thread slowed the spline's terms on two threads by 15%.)
///
/// A frame's right-hand side is built this way: the triangles' terms (rotations, their
/// sines and cosines, the products with the gradients) in parallel, their sums per vertex
/// ([`scatter`]) in triangle order.
pub fn in_order<T: Send>(
    count: usize,
    each: impl Fn(usize) -> T + Sync,
    mut add: impl FnMut(usize, T) + Send,
) {
    let compute = |start: usize| -> Vec<T> {
        (start..(start + TERMS_CHUNK).min(count))
            .into_par_iter()
            .with_min_len(256)
            .map(&each)
            .collect()
    };
    let mut starts = (0..count).step_by(TERMS_CHUNK);
    let Some(first) = starts.next() else { return };
    let mut ready = (first, compute(first));
    for next in starts {
        let (start, terms) = ready;
        let add = &mut add;
        let ((), computed) = rayon::join(
            || {
                for (k, term) in terms.into_iter().enumerate() {
                    add(start + k, term);
                }
            },
            || compute(next),
        );
        ready = (next, computed);
    }
    let (start, terms) = ready;
    for (k, term) in terms.into_iter().enumerate() {
        add(start + k, term);
    }
}

/// Add a triangle's right-hand-side terms `T g` for corners 1 and 2 (corner 0 gets minus
/// their sum, since the gradient operators sum to zero).
#[inline]
pub fn scatter(rhs: &mut [[f64; 3]], corners: [u32; 3], v1: DVec3, v2: DVec3) {
    for (k, v) in [(0, -(v1 + v2)), (1, v1), (2, v2)] {
        let b = &mut rhs[corners[k] as usize];
        b[0] += v.x;
        b[1] += v.y;
        b[2] += v.z;
    }
}

/// A factor whose factorization takes more than this many multiply-adds per stored entry (its
/// columns long enough to share rows in dense blocks) is analysed as supernodes, and factored
/// by [`super::cholesky::Plan`]; below it, column by column by faer's simplicial factorization.
/// faer's own choice (40) was made for its supernodal factorization. Ours, measured against its
/// simplicial one on square grids of 500 to 20,000 vertices (40 keys, `tween`'s numeric
/// factorization figure): 0.6-0.8x the time from 28 a entry (8,000 vertices 0.209 -> 0.161 s,
/// 20,000 vertices 0.74 -> 0.47 s), 1.05-1.15x at 17-20 (2,000-3,000 vertices), 0.65x at 10
/// (500 vertices, well under a millisecond a factorization). The bench's tubes are above 40.
const SUPERNODAL_ABOVE: f64 = 20.0;

/// The symbolic Cholesky analysis of `sym` (upper triangle) by faer's AMD ordering; for a
/// large mesh ([`super::order::MIN_VERTICES`]) also by nested dissection of its `positions`,
/// the two side by side, keeping the one whose factor stores fewer entries (dissection wins on
/// regular surfaces such as the bench's tubes, AMD on organic shapes: see [`super::order`]).
fn analyse(
    sym: SymbolicSparseColMatRef<'_, u32>,
    positions: &[DVec3],
) -> Result<SymbolicCholesky<u32>> {
    let n = sym.nrows();
    let by = |ordering: SymmetricOrdering<'_, u32>| {
        let params = CholeskySymbolicParams {
            // faer compares against 40 times the threshold.
            supernodal_flop_ratio_threshold: SupernodalThreshold(SUPERNODAL_ABOVE / 40.0),
            ..Default::default()
        };
        factorize_symbolic_cholesky(sym, Side::Upper, ordering, params)
            .map_err(|e| anyhow!("symbolic factorization failed: {e:?}"))
    };
    if n < super::order::MIN_VERTICES || positions.len() != n {
        return by(SymmetricOrdering::Amd);
    }
    let dissected = || {
        let (start, neighbours) = symmetric_adjacency(n, sym.col_ptr(), sym.row_idx());
        let fwd = super::order::dissect(positions, &start, &neighbours)?;
        let mut inv = vec![0u32; n];
        for (new, &old) in fwd.iter().enumerate() {
            inv[old as usize] = new as u32;
        }
        Some(by(SymmetricOrdering::Custom(PermRef::new_checked(
            &fwd, &inv, n,
        ))))
    };
    // A failed analysis by dissection only leaves AMD's (whose failure is the error).
    let (amd, nd) = rayon::join(|| by(SymmetricOrdering::Amd), dissected);
    match (amd, nd) {
        (Ok(amd), Some(Ok(nd))) if nd.len_val() < amd.len_val() => Ok(nd),
        (Err(_), Some(Ok(nd))) => Ok(nd),
        (amd, _) => amd,
    }
}

/// Both triangles of an upper-triangular pattern as adjacency lists (CSR, diagonal left out).
fn symmetric_adjacency(n: usize, col_ptr: &[u32], row_idx: &[u32]) -> (Vec<u32>, Vec<u32>) {
    let mut start = vec![0u32; n + 1];
    for c in 0..n {
        for &r in &row_idx[col_ptr[c] as usize..col_ptr[c + 1] as usize] {
            if r as usize != c {
                start[r as usize + 1] += 1;
                start[c + 1] += 1;
            }
        }
    }
    for v in 0..n {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut neighbours = vec![0u32; start[n] as usize];
    for c in 0..n {
        for &r in &row_idx[col_ptr[c] as usize..col_ptr[c + 1] as usize] {
            if r as usize != c {
                neighbours[fill[r as usize] as usize] = c as u32;
                fill[r as usize] += 1;
                neighbours[fill[c] as usize] = r;
                fill[c] += 1;
            }
        }
    }
    (start, neighbours)
}

/// Triangles sharing one edge are all each other's neighbours up to this many; an edge shared
/// by more (a fan of coincident or stacked faces, which only a broken or hostile file has:
/// 2,000 copies of one triangle made 12M neighbour pairs and a growth of 4M steps) links
/// them in a ring instead, each to the next in index order, which keeps them connected with
/// two neighbours each instead of all.
const ALL_PAIRS_FAN: usize = 8;

/// For each triangle, the triangles sharing one of its edges (each once per shared edge), as
/// CSR arrays: edges sorted by their vertex pair (in parallel), then runs paired up (in a ring
/// beyond [`ALL_PAIRS_FAN`]).
fn edge_neighbours(triangles: &[[u32; 3]]) -> (Vec<u32>, Vec<u32>) {
    let mut edges: Vec<(u64, u32)> = triangles
        .par_iter()
        .enumerate()
        .flat_map_iter(|(t, &[a, b, c])| {
            [(a, b), (b, c), (c, a)]
                .into_iter()
                .map(move |(u, v)| (((u.min(v) as u64) << 32) | u.max(v) as u64, t as u32))
        })
        .collect();
    edges.par_sort_unstable();
    let mut pairs: Vec<(u32, u32)> = Vec::with_capacity(edges.len());
    let mut i = 0;
    while i < edges.len() {
        let j = i + edges[i..].iter().take_while(|e| e.0 == edges[i].0).count();
        let fan = &edges[i..j];
        if fan.len() <= ALL_PAIRS_FAN {
            for x in fan {
                for y in fan {
                    if x.1 != y.1 {
                        pairs.push((x.1, y.1));
                    }
                }
            }
        } else {
            for (k, x) in fan.iter().enumerate() {
                let next = fan[(k + 1) % fan.len()].1;
                if next != x.1 {
                    pairs.extend([(x.1, next), (next, x.1)]);
                }
            }
        }
        i = j;
    }
    pairs.par_sort_unstable();
    let mut start = vec![0u32; triangles.len() + 1];
    for &(t, _) in &pairs {
        start[t as usize + 1] += 1;
    }
    for t in 0..triangles.len() {
        start[t + 1] += start[t];
    }
    (start, pairs.into_iter().map(|p| p.1).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tween::gradient::{frame, gradient_operator};

    #[test]
    fn a_fan_of_many_faces_on_one_edge_is_a_ring() {
        // Two triangles on an edge are each other's neighbour, as are up to eight.
        let (start, nb) = edge_neighbours(&[[0, 1, 2], [1, 0, 3]]);
        assert_eq!((start, nb), (vec![0, 1, 2], vec![1, 0]));
        let eight = vec![[0u32, 1, 2]; ALL_PAIRS_FAN];
        let (start, _) = edge_neighbours(&eight);
        assert!(start
            .windows(2)
            .all(|w| w[1] - w[0] == 3 * (ALL_PAIRS_FAN as u32 - 1)));
        // 2,000 copies of one triangle: two neighbours per edge, all still connected.
        let n = 2000;
        let (start, nb) = edge_neighbours(&vec![[0u32, 1, 2]; n]);
        assert!(start.windows(2).all(|w| w[1] - w[0] == 6));
        let mut seen = vec![false; n];
        let mut stack = vec![0usize];
        while let Some(t) = stack.pop() {
            if !std::mem::replace(&mut seen[t], true) {
                let (a, b) = (start[t] as usize, start[t + 1] as usize);
                stack.extend(nb[a..b].iter().map(|&x| x as usize));
            }
        }
        assert!(seen.iter().all(|&x| x));
    }

    /// Each triangle's gradient operator in the rest pose (`None` for a degenerate one).
    fn rest_gradients(s: &crate::dev::synth::Surface) -> Vec<Option<[DVec3; 3]>> {
        (s.triangles.iter())
            .map(|t| {
                let [a, b, c] = t.map(|v| s.positions[v as usize]);
                frame(a, b, c).map(|v| gradient_operator(&v.inverse()))
            })
            .collect()
    }

    /// The factor of a small tube's system (vertex 0 pinned), and the tube.
    fn tube_factor() -> (Factor, crate::dev::synth::Surface) {
        tube_factor_of(12, 9)
    }

    fn tube_factor_of(rings: usize, segments: usize) -> (Factor, crate::dev::synth::Surface) {
        let s = crate::dev::synth::tube(rings, segments, 3.0, 0.5, 0.4);
        let pattern = Pattern::new(s.positions.len(), &s.triangles, &s.positions).unwrap();
        let grads = rest_gradients(&s);
        let mut pinned = vec![false; s.positions.len()];
        pinned[0] = true;
        (Factor::new(&pattern, grads, pinned).unwrap(), s)
    }

    /// The factorization over the assembly tree ([`super::super::cholesky`]) gives the same
    /// bits on 1, 2, 3 or 8 threads, and the factor faer's own sequential factorization gives,
    /// to rounding; a mesh of two pieces (two roots) too.
    #[test]
    fn the_tree_s_factorization_is_the_same_bits_on_any_threads_and_matches_faer_s() {
        let mut s = crate::dev::synth::tube(300, 120, 3.0, 0.5, 0.4);
        let mut other = crate::dev::synth::tube(40, 30, 1.0, 0.2, 0.2);
        let base = s.positions.len() as u32;
        s.positions.append(&mut other.positions);
        s.triangles
            .extend(other.triangles.iter().map(|t| t.map(|v| v + base)));
        let n = s.positions.len();
        let mut pattern = Pattern::new(n, &s.triangles, &s.positions).unwrap();
        assert!(pattern.plan.is_some());
        let grads = rest_gradients(&s);
        let mut pinned = vec![false; n];
        pinned[0] = true;
        pinned[base as usize] = true;
        let bits = |f: &Factor| -> Vec<u64> {
            (f.columns.vals.iter().chain(&f.diag))
                .map(|x| x.to_bits())
                .collect()
        };
        let on = |threads: usize, pattern: &Pattern| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| Factor::new(pattern, grads.clone(), pinned.clone()).unwrap())
        };
        let one = on(1, &pattern);
        for threads in [2, 3, 8] {
            assert!(
                bits(&one) == bits(&on(threads, &pattern)),
                "{threads} threads"
            );
        }
        // faer's dense kernels on every thread for every node and update: the same bits.
        let symbolic = match pattern.symbolic.raw() {
            SymbolicCholeskyRaw::Supernodal(s) => s,
            SymbolicCholeskyRaw::Simplicial(_) => panic!("a supernodal factor"),
        };
        let plan = pattern.plan.as_ref().unwrap();
        let a = assemble(&pattern, grads.clone(), &pinned);
        let values = |threads: usize, parallel| {
            let mut v = vec![0.0; symbolic.len_val()];
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| plan.factor_with(symbolic, &a, &mut v, parallel))
                .unwrap();
            v.iter().map(|x| x.to_bits()).collect::<Vec<u64>>()
        };
        let alone = values(1, None);
        for threads in [2, 5, 8] {
            assert!(alone == values(threads, Some((0, 0))), "{threads} threads");
        }
        pattern.plan = None;
        let faer = on(1, &pattern);
        let (ours, theirs) = (
            one.columns.vals.iter().chain(&one.diag),
            faer.columns.vals.iter().chain(&faer.diag),
        );
        let scale = faer.diag.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let worst = ours
            .zip(theirs)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(worst <= 1e-12 * scale, "{worst} against {scale}");
        assert!(one.diag.iter().all(|&d| d > 0.0));
    }

    /// A reused value buffer (left over from an earlier factor: any length, any contents)
    /// factors bit for bit as a fresh one, and the packed column copy keeps exactly the entries
    /// `stored_below` counts, in both of faer's layouts.
    #[test]
    fn a_reused_buffer_factors_bit_for_bit_and_packing_keeps_what_is_stored() {
        let mut layouts = Vec::new();
        for (rings, segments) in [(12, 9), (200, 100)] {
            let s = crate::dev::synth::tube(rings, segments, 3.0, 0.5, 0.4);
            let n = s.positions.len();
            let pattern = Pattern::new(n, &s.triangles, &s.positions).unwrap();
            let grads = rest_gradients(&s);
            let mut pinned = vec![false; n];
            pinned[0] = true;
            let fresh = Factor::new(&pattern, grads.clone(), pinned.clone()).unwrap();
            layouts.push(matches!(
                pattern.symbolic.raw(),
                SymbolicCholeskyRaw::Supernodal(_)
            ));
            assert_eq!(fresh.columns.vals.len(), stored_below(&pattern.symbolic, n));
            assert_eq!(fresh.diag.len(), n);
            let len = pattern.symbolic.len_val();
            for spare in [vec![f64::NAN; 3], vec![f64::NAN; 2 * len]] {
                *pattern.spare.lock().unwrap() = spare;
                let again = Factor::new(&pattern, grads.clone(), pinned.clone()).unwrap();
                let bits = |f: &Factor| -> Vec<u64> {
                    (f.columns.vals.iter().chain(&f.diag).chain(&f.row_vals))
                        .map(|x| x.to_bits())
                        .collect()
                };
                assert_eq!(bits(&fresh), bits(&again));
            }
        }
        assert_eq!(
            layouts,
            [false, true],
            "one simplicial and one supernodal factor"
        );
    }

    /// Which factorization a mesh gets follows [`SUPERNODAL_ABOVE`]: a flat grid of 91 x 91
    /// vertices (about 28 multiply-adds per entry of its factor) is factored by supernodes,
    /// where faer's own threshold would keep it simplicial; one of 21 x 21 (about 10) stays
    /// simplicial.
    #[test]
    fn mid_sized_meshes_are_factored_by_supernodes() {
        for (side, supernodal) in [(90, true), (20, false)] {
            let s = crate::dev::synth::grid(side, side, 1.0, 1.0);
            let n = s.positions.len();
            let pattern = Pattern::new(n, &s.triangles, &s.positions).unwrap();
            let raw = pattern.symbolic.raw();
            assert_eq!(
                matches!(raw, SymbolicCholeskyRaw::Supernodal(_)),
                supernodal,
                "{n} vertices"
            );
            assert_eq!(pattern.plan.is_some(), supernodal);
        }
    }

    #[test]
    fn a_block_of_frames_solves_exactly_as_each_frame_alone() {
        let (mut factor, s) = tube_factor();
        let n = s.positions.len();
        let frames: Vec<Vec<[f64; 3]>> = (0..4)
            .map(|f| {
                (0..n)
                    .map(|i| {
                        [
                            (i * (f + 3) % 7) as f64 - 3.0,
                            f as f64 + 0.25,
                            (i % 5) as f64,
                        ]
                    })
                    .collect()
            })
            .collect();
        // Both copies of L (gathering forward pass), then the column copy only (scattering).
        for columns_only in [false, true] {
            if columns_only {
                factor.keep_columns_only();
            }
            let mut block: Vec<[f64; 12]> = (0..n)
                .map(|i| std::array::from_fn(|c| frames[c / 3][i][c % 3]))
                .collect();
            factor.solve_block(&mut block);
            for (f, rhs) in frames.iter().enumerate() {
                let mut alone = rhs.clone();
                factor.solve(&mut alone);
                for (i, x) in alone.iter().enumerate() {
                    for c in 0..3 {
                        let y = block[i][3 * f + c];
                        assert_eq!(x[c].to_bits(), y.to_bits(), "frame {f}, {columns_only}");
                    }
                }
            }
        }
    }

    /// Split into parts for four threads, the solves give the same bits as on one thread
    /// (both passes, a frame and a block of four, both copies of L and the column copy only),
    /// and each part's columns reach only their own part and the top.
    #[test]
    fn solves_split_into_parts_give_the_same_bits_as_one_thread() {
        let (mut factor, s) = tube_factor_of(200, 100);
        let n = s.positions.len();
        let serial = Parts::of(&factor.columns, 1);
        assert!(serial.bins.is_empty() && serial.top.len() == 1 && serial.top[0] == (0..n));
        let parts = Parts::of(&factor.columns, 4);
        let ranges = parts.bins.concat();
        assert!(
            parts.bins.len() == 4 && ranges.len() >= 4,
            "{:?}",
            parts.bins
        );
        let top: usize = parts.top.iter().map(|r| r.len()).sum();
        let inside: usize = ranges.iter().map(|r| r.len()).sum();
        assert_eq!(top + inside, n);
        assert!(top < n / 4, "{top} of {n} columns on one thread");
        let part_of = |r: usize| ranges.iter().position(|p| p.contains(&r));
        for j in 0..n {
            // SAFETY: j < n, the factor checked when made.
            let (_, inside, below) = unsafe { factor.columns.column(j) };
            for row in inside.chain(below.iter().map(|&r| r as usize)) {
                let (own, other) = (part_of(j), part_of(row));
                assert!(other.is_none() || other == own, "column {j}, row {row}");
            }
        }
        let rhs: Vec<[f64; 12]> = (0..n)
            .map(|i| std::array::from_fn(|c| ((i * (c + 3)) % 11) as f64 - 5.0))
            .collect();
        for columns_only in [false, true] {
            if columns_only {
                factor.keep_columns_only();
            }
            let mut solved = Vec::new();
            for p in [Parts::of(&factor.columns, 1), Parts::of(&factor.columns, 4)] {
                factor.parts = p;
                let mut block = rhs.clone();
                factor.solve_permuted(&mut block);
                let mut one: Vec<[f64; 3]> = rhs.iter().map(|r| [r[0], r[1], r[2]]).collect();
                factor.solve_permuted(&mut one);
                solved.push((block, one));
            }
            let bits = |x: &[[f64; 12]], y: &[[f64; 3]]| -> Vec<u64> {
                x.iter()
                    .flatten()
                    .chain(y.iter().flatten())
                    .map(|v| v.to_bits())
                    .collect()
            };
            let (a, b) = (&solved[0], &solved[1]);
            assert_eq!(
                bits(&a.0, &a.1),
                bits(&b.0, &b.1),
                "columns only: {columns_only}"
            );
            assert!(a.1.iter().flatten().any(|v| v.abs() > 1e-3));
        }
    }

    /// The subtrees of the 16k and 100k bench tubes' factors (their entries as `work`) dealt
    /// to two threads: the largest first, each to the lighter list, so neither thread waits
    /// long for the other.
    #[test]
    fn subtrees_are_dealt_largest_first_to_the_lighter_thread() {
        let ranges_of = |works: &[usize]| -> Vec<std::ops::Range<usize>> {
            let mut at = 0;
            works
                .iter()
                .map(|&w| {
                    at += w;
                    at - w..at
                })
                .collect()
        };
        let work = |r: &std::ops::Range<usize>| r.len();
        let loads = |bins: &[Vec<std::ops::Range<usize>>]| -> Vec<usize> {
            bins.iter().map(|b| b.iter().map(work).sum()).collect()
        };
        let small = ranges_of(&[28_000, 44_248, 58_429, 129_264]);
        let bins = deal(&small, work, 2);
        assert_eq!(bins[0], vec![small[3].clone()]);
        assert_eq!(loads(&bins), vec![129_264, 130_677]);
        let large = ranges_of(&[448_162, 138_990, 433_412, 349_353, 1_097_045]);
        assert_eq!(loads(&deal(&large, work, 2)), vec![1_236_035, 1_230_927]);
        // More threads than subtrees: one list a subtree; every subtree dealt once.
        let bins = deal(&small, work, 8);
        assert_eq!(bins.len(), 4);
        let mut all = bins.concat();
        all.sort_by_key(|r| r.start);
        assert_eq!(all, small);
    }

    /// Terms computed on all threads chunk by chunk come to `add` in order: an order-sensitive
    /// floating-point sum over three chunks and a part is the one loop's, bit for bit.
    #[test]
    fn terms_come_in_order() {
        let count = 3 * TERMS_CHUNK + 17;
        let term = |t: usize| ((t * 7919) % 1000) as f64 * 1e-3 + 1e10 * (t % 3) as f64;
        let (mut sum, mut seen) = (0.0f64, Vec::new());
        in_order(count, term, |t, x| {
            seen.push(t);
            sum += x;
        });
        let one: f64 = (0..count).map(term).fold(0.0, |a, x| a + x);
        assert_eq!(sum.to_bits(), one.to_bits());
        assert!(seen.iter().copied().eq(0..count));
    }

    #[test]
    fn column_only_solve_matches_two_copy_solve() {
        let (mut factor, s) = tube_factor();
        let rhs: Vec<[f64; 3]> = (0..s.positions.len())
            .map(|i| [i as f64 % 3.0 - 1.0, (i * 7 % 5) as f64, 0.5])
            .collect();
        let mut a = rhs.clone();
        factor.solve(&mut a);
        factor.keep_columns_only();
        let mut b = rhs;
        factor.solve(&mut b);
        let worst = a
            .iter()
            .zip(&b)
            .flat_map(|(p, q)| (0..3).map(move |c| (p[c] - q[c]).abs()))
            .fold(0.0, f64::max);
        assert!(worst < 1e-12, "{worst}");
        assert!(
            a.iter().flatten().any(|v| v.abs() > 1e-3),
            "a non-trivial solution"
        );
    }
}
