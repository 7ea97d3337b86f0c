//! Numeric factorization stage: `P A P^T = L L^T` over faer's supernodes, independent subtrees
//! of the assembly tree on different threads.
//!
//! faer's supernodal factorization is left-looking: supernode s gathers the updates of the
//! supernodes below it (each d whose rows reach into s's columns), then factors its diagonal
//! block and solves the rows below it. It walks the supernodes one after the other, using the
//! threads only inside each one's dense kernels, which at 1M triangles are too small to share:
//! the factorization took 0.85 s a segment on one thread or sixteen. Every update of s comes
//! from a descendant of s, so the subtrees of a node are independent: here they are factored
//! side by side, each node once its children are done (as in multifrontal and supernodal
//! solvers since Liu's assembly trees). The same kernels, with the same operands in the same
//! order, run for each supernode whatever the threads: the factor is the same bits on any
//! number of threads.
//!
//! Measured on the bench's 1M-triangle tube: on 16 cores the two segments' factorizations take
//! 0.54-0.73 s instead of 1.47-2.06 s (end to end 2.41-2.89 s instead of 3.18-3.73). On one
//! thread it costs what faer's does (2 cores, `--threads 1`: 1.17-1.19 s against 1.18-1.19 s
//! end to end; `Factor::new` alone 0.51-0.53 s against 0.55-0.64 s), though an update goes
//! through a product buffer and a scatter where faer's own kernel, not exported, gathers as it
//! multiplies: updates below [`DENSE_UPDATE_MIN`] are summed here, and faer's triangular
//! product skips the upper half of an update's top block. On 2 cores end to end is unchanged
//! within the noise (the factorization runs beside the key gradients).
//!
//! [`Plan`] is made once per mesh from the symbolic factorization: where each entry of A goes
//! in its supernode's block, which supernodes update which, and the tree with its work.

use anyhow::{anyhow, Result};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::{cholesky_in_place, LltRegularization};
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::linalg::cholesky::supernodal::SymbolicSupernodalCholesky;
use faer::{Accum, MatMut, MatRef, Par};
use rayon::prelude::*;

/// Below this many multiply-adds an update is one loop here (a dense product's set-up would
/// cost more than it saves); above, a dense product into a buffer and a scatter.
const DENSE_UPDATE_MIN: usize = 4096;

/// From this many multiply-adds an update's dense product, and from this many columns a
/// diagonal block's factorization and solve, use every thread (the assembly tree's top: the
/// separators of a nested dissection, few and dense, factored after everything below them),
/// where the pool has at least [`PARALLEL_THREADS_MIN`] threads and the machine as many cores:
/// on two, the other thread is busy beside the factorization, and with more threads than cores
/// faer's kernels wait for threads that are not running (2 cores, `--threads 16`, 1M
/// triangles: 3.9 s of numeric factorization against 1.2). 16 cores, 1M triangles: numeric
/// factorization 0.54-0.60 s against 0.65-0.67 s with one thread a node. faer's dense kernels
/// give the same bits on any number of threads (checked by the tests), so this changes the
/// time only.
const PARALLEL_UPDATE_MIN: usize = 1 << 20;
const PARALLEL_COLUMNS_MIN: usize = 128;
const PARALLEL_THREADS_MIN: usize = 4;

/// A subtree of less work than the whole over this many times the threads is factored on one
/// thread, its supernodes in order (more, smaller tasks balance better but cost a hand-over
/// each).
const TASKS_PER_THREAD: usize = 8;

/// What the numeric factorization of one pattern needs besides the values, found once.
pub struct Plan {
    /// A's upper-triangular entries by supernode: `(index in A's values, offset in the
    /// supernode's block)`, for supernode s at `a_ptr[s]..a_ptr[s + 1]`.
    a_ptr: Vec<usize>,
    a_entries: Vec<(u32, u32)>,
    /// The supernodes that update s, ascending, at `by_ptr[s]..by_ptr[s + 1]`.
    by_ptr: Vec<usize>,
    by: Vec<u32>,
    /// The assembly tree: children of s at `child_ptr[s]..child_ptr[s + 1]`, the roots, and
    /// the supernodes in a postorder (`post`; subtree s is `post[at[s] + 1 - size[s]..=at[s]]`).
    child_ptr: Vec<usize>,
    children: Vec<u32>,
    roots: Vec<u32>,
    post: Vec<u32>,
    at: Vec<u32>,
    size: Vec<u32>,
    /// Multiply-adds of each subtree, and of all.
    work: Vec<f64>,
    total: f64,
    /// Largest diagonal block (the dense factorization's scratch).
    widest: usize,
}

/// One supernode's shape.
struct Node<'s> {
    start: usize,
    ncols: usize,
    /// Rows below the diagonal block, ascending.
    rows: &'s [u32],
    /// Where its column-major block (`ncols + rows.len()` rows) starts in L's values.
    base: usize,
}

impl Node<'_> {
    fn nrows(&self) -> usize {
        self.ncols + self.rows.len()
    }

    fn end(&self) -> usize {
        self.start + self.ncols
    }

    /// The rows of this node's pattern that fall in `columns`: their positions in `rows`.
    fn rows_in(&self, columns: std::ops::Range<usize>) -> std::ops::Range<usize> {
        let from = self.rows.partition_point(|&r| (r as usize) < columns.start);
        let to = from + self.rows[from..].partition_point(|&r| (r as usize) < columns.end);
        from..to
    }
}

/// `items` (group, value) laid out by group: group g's values, in their order in `items`, at
/// `ptr[g]..ptr[g + 1]` of the values returned with `ptr`.
fn grouped<T: Copy + Default>(groups: usize, items: &[(u32, T)]) -> (Vec<usize>, Vec<T>) {
    let mut ptr = vec![0usize; groups + 1];
    for &(g, _) in items {
        ptr[g as usize + 1] += 1;
    }
    for g in 0..groups {
        ptr[g + 1] += ptr[g];
    }
    let mut next = ptr.clone();
    let mut values = vec![T::default(); items.len()];
    for &(g, v) in items {
        values[next[g as usize]] = v;
        next[g as usize] += 1;
    }
    (ptr, values)
}

fn node(s: &SymbolicSupernodalCholesky<u32>, k: usize) -> Node<'_> {
    let start = s.supernode_begin()[k] as usize;
    let rs = s.col_ptr_for_row_idx()[k] as usize;
    Node {
        start,
        ncols: s.supernode_end()[k] as usize - start,
        rows: &s.row_idx()[rs..rs + s.nnz_per_super()[k] as usize],
        base: s.col_ptr_for_val()[k] as usize,
    }
}

impl Plan {
    /// The plan for A's upper-triangular pattern (`col_ptr`, `row_idx`, original numbering)
    /// under the symbolic factorization `s` with permutation `inv` (`inv[v]`: v's position).
    /// `None` where a block is too large for the offsets or the structure is not a tree below
    /// its supernodes (faer's own sequential factorization is used then).
    pub fn new(
        s: &SymbolicSupernodalCholesky<u32>,
        inv: Option<&[u32]>,
        col_ptr: &[u32],
        row_idx: &[u32],
    ) -> Option<Plan> {
        let n = s.nrows();
        let count = s.n_supernodes();
        let nodes: Vec<Node> = (0..count).map(|k| node(s, k)).collect();
        if nodes.iter().any(|b| {
            b.nrows()
                .checked_mul(b.ncols)
                .is_none_or(|x| x > u32::MAX as usize)
        }) {
            return None;
        }
        let mut owner = vec![0u32; n];
        for (k, b) in nodes.iter().enumerate() {
            owner[b.start..b.end()].fill(k as u32);
        }
        // A's entries: (i, j) upper with i <= j lands at (max, min) of their positions.
        let at = |v: u32| inv.map_or(v, |p| p[v as usize]) as usize;
        let mut placed = Vec::with_capacity(row_idx.len());
        for c in 0..n {
            let entries = col_ptr[c] as usize..col_ptr[c + 1] as usize;
            for (e, &i) in entries.clone().zip(&row_idx[entries]) {
                let (x, y) = (at(i), at(c as u32));
                let (row, col) = (x.max(y), x.min(y));
                let k = owner[col] as usize;
                let b = &nodes[k];
                let r = if row < b.end() {
                    row - b.start
                } else {
                    b.ncols + b.rows.binary_search(&(row as u32)).ok()?
                };
                placed.push((
                    k as u32,
                    (e as u32, ((col - b.start) * b.nrows() + r) as u32),
                ));
            }
        }
        let (a_ptr, a_entries) = grouped(count, &placed);
        drop(placed);
        // Which supernodes each supernode updates: those owning its rows below (ascending d
        // for each s, as the loop over d is ascending).
        let mut updates = Vec::new();
        let mut own = vec![0.0f64; count];
        for (d, b) in nodes.iter().enumerate() {
            let mut last = u32::MAX;
            for &row in b.rows {
                let k = owner[row as usize];
                if k == last {
                    continue;
                }
                last = k;
                updates.push((k, d as u32));
                let t = &nodes[k as usize];
                let r = b.rows_in(t.start..t.end());
                let m = b.rows.len() - r.start;
                own[k as usize] += (m * r.len() * b.ncols) as f64;
            }
        }
        let (by_ptr, by) = grouped(count, &updates);
        drop(updates);
        // The tree: a supernode's parent owns its first row below.
        let parent: Vec<Option<usize>> = nodes
            .iter()
            .map(|b| b.rows.first().map(|&r| owner[r as usize] as usize))
            .collect();
        let mut size = vec![1u32; count];
        let mut work = own;
        for (k, b) in nodes.iter().enumerate() {
            let (c, h) = (b.ncols as f64, b.nrows() as f64);
            work[k] += c * c * c / 3.0 + (h - c) * c * c + h * c;
        }
        let mut parent_of = Vec::with_capacity(count);
        let mut roots = Vec::new();
        for k in 0..count {
            match parent[k] {
                Some(p) if p > k => {
                    size[p] += size[k];
                    work[p] += work[k];
                    parent_of.push((p as u32, k as u32));
                }
                Some(_) => return None,
                None => roots.push(k as u32),
            }
        }
        let (child_ptr, children) = grouped(count, &parent_of);
        // A postorder: each node after its subtree, the subtrees one after the other.
        let mut post = Vec::with_capacity(count);
        let mut at = vec![0u32; count];
        let mut stack: Vec<(u32, bool)> = roots.iter().rev().map(|&r| (r, false)).collect();
        while let Some((k, expanded)) = stack.pop() {
            let k = k as usize;
            if expanded {
                at[k] = post.len() as u32;
                post.push(k as u32);
            } else {
                stack.push((k as u32, true));
                let kids = &children[child_ptr[k]..child_ptr[k + 1]];
                stack.extend(kids.iter().rev().map(|&c| (c, false)));
            }
        }
        // What the tasks' sharing of L rests on (see `Run::block`): every supernode that
        // updates s lies in s's subtree, so its task has ended before s's starts.
        let below = |d: usize, k: usize| {
            let (pd, pk) = (at[d] as usize, at[k] as usize);
            pd < pk && pd + size[k] as usize > pk
        };
        if (0..count).any(|k| {
            let kids = &by[by_ptr[k]..by_ptr[k + 1]];
            kids.iter().any(|&d| !below(d as usize, k))
        }) {
            return None;
        }
        let total = roots.iter().map(|&r| work[r as usize]).sum();
        let widest = nodes.iter().map(|b| b.ncols).max().unwrap_or(0);
        Some(Plan {
            a_ptr,
            a_entries,
            by_ptr,
            by,
            child_ptr,
            children,
            roots,
            post,
            at,
            size,
            work,
            total,
            widest,
        })
    }

    fn children(&self, k: usize) -> &[u32] {
        &self.children[self.child_ptr[k]..self.child_ptr[k + 1]]
    }

    /// Factor: `a` holds A's upper-triangular values in the pattern's order, `values` (of
    /// `s.len_val()`) receives L in faer's supernodal layout. On the threads of the current
    /// rayon pool; the same bits on any number.
    pub fn factor(
        &self,
        s: &SymbolicSupernodalCholesky<u32>,
        a: &[f64],
        values: &mut [f64],
    ) -> Result<()> {
        let cores = std::thread::available_parallelism().map_or(1, usize::from);
        let parallel = (rayon::current_num_threads().min(cores) >= PARALLEL_THREADS_MIN)
            .then_some((PARALLEL_COLUMNS_MIN, PARALLEL_UPDATE_MIN));
        self.factor_with(s, a, values, parallel)
    }

    /// [`Plan::factor`], the dense kernels on every thread from `parallel`'s (columns,
    /// multiply-adds) on (`None`: on one thread each).
    pub(super) fn factor_with(
        &self,
        s: &SymbolicSupernodalCholesky<u32>,
        a: &[f64],
        values: &mut [f64],
        parallel: Option<(usize, usize)>,
    ) -> Result<()> {
        assert_eq!(values.len(), s.len_val());
        assert_eq!(self.a_ptr.len(), s.n_supernodes() + 1);
        let threads = rayon::current_num_threads();
        let (wide, large) = parallel.unwrap_or((usize::MAX, usize::MAX));
        let run = Run {
            wide,
            large,
            plan: self,
            s,
            a,
            values: Shared(values.as_mut_ptr()),
            len: values.len(),
            grain: self.total / (threads * TASKS_PER_THREAD) as f64,
            spare: Default::default(),
            failed: std::sync::atomic::AtomicUsize::new(usize::MAX),
        };
        match threads {
            1 => run.in_order(&(0..s.n_supernodes() as u32).collect::<Vec<_>>()),
            _ => self.roots.par_iter().for_each(|&r| run.subtree(r as usize)),
        }
        match run.failed.into_inner() {
            usize::MAX => Ok(()),
            index => Err(anyhow!(
                "the system is not positive definite (pivot {index} not positive)"
            )),
        }
    }
}

/// L's values, written by one supernode's task each and read by its ancestors' after it.
#[derive(Clone, Copy)]
struct Shared(*mut f64);
// SAFETY: see `Run::block`: a block is written by its own supernode's task alone, and read
// only by the tasks of its ancestors, which start after that task has ended.
unsafe impl Send for Shared {}
unsafe impl Sync for Shared {}

struct Run<'p> {
    /// Diagonal blocks from this many columns, and updates from this many multiply-adds, on
    /// every thread.
    wide: usize,
    large: usize,
    plan: &'p Plan,
    s: &'p SymbolicSupernodalCholesky<u32>,
    a: &'p [f64],
    values: Shared,
    len: usize,
    grain: f64,
    /// Scratch of tasks that ended, for the next ones.
    spare: std::sync::Mutex<Vec<Scratch>>,
    /// Smallest pivot found not positive.
    failed: std::sync::atomic::AtomicUsize,
}

#[derive(Default)]
struct Scratch {
    /// A row's position in the current supernode's block (rows below its diagonal block).
    local: Vec<u32>,
    /// An update's rows in the current block.
    rows: Vec<u32>,
    product: Vec<f64>,
    dense: Option<MemBuffer>,
}

impl Run<'_> {
    /// Subtree k: its children's subtrees side by side, then k. A chain of single children is
    /// followed down first (no recursion a level per node), and a subtree of less than a
    /// task's work is one thread's, in order.
    fn subtree(&self, k: usize) {
        let plan = self.plan;
        if plan.work[k] < self.grain {
            let last = plan.at[k] as usize;
            let mut nodes = plan.post[last + 1 - plan.size[k] as usize..=last].to_vec();
            nodes.sort_unstable();
            return self.in_order(&nodes);
        }
        let mut chain = vec![k];
        let mut x = k;
        while let [only] = plan.children(x) {
            if plan.work[*only as usize] < self.grain {
                break;
            }
            x = *only as usize;
            chain.push(x);
        }
        plan.children(x)
            .par_iter()
            .for_each(|&c| self.subtree(c as usize));
        let mut scratch = self.scratch();
        for &y in chain.iter().rev() {
            self.supernode(y, &mut scratch);
        }
        self.give_back(scratch);
    }

    fn in_order(&self, supernodes: &[u32]) {
        let mut scratch = self.scratch();
        for &k in supernodes {
            self.supernode(k as usize, &mut scratch);
        }
        self.give_back(scratch);
    }

    fn scratch(&self) -> Scratch {
        let mut spare = self.spare.lock().unwrap_or_else(|e| e.into_inner());
        spare.pop().unwrap_or_default()
    }

    fn give_back(&self, scratch: Scratch) {
        let mut spare = self.spare.lock().unwrap_or_else(|e| e.into_inner());
        spare.push(scratch);
    }

    /// Supernode k's block.
    ///
    /// # Safety
    /// The block lies within the values (checked); the caller holds the only reference to it:
    /// k's own task writes it, after its descendants' tasks and before its ancestors'.
    #[allow(clippy::mut_from_ref)]
    unsafe fn block(&self, b: &Node) -> &mut [f64] {
        let len = b.nrows() * b.ncols;
        assert!(b.base + len <= self.len);
        std::slice::from_raw_parts_mut(self.values.0.add(b.base), len)
    }

    /// Supernode d's finished block, for reading.
    fn done(&self, d: &Node) -> &[f64] {
        let len = d.nrows() * d.ncols;
        assert!(d.base + len <= self.len);
        // SAFETY: within the values; d is a descendant of the supernode being factored, so
        // its task has ended and nothing writes its block any more.
        unsafe { std::slice::from_raw_parts(self.values.0.add(d.base), len) }
    }

    /// Factor supernode k: A's entries, every descendant's update, the diagonal block's
    /// Cholesky factor, the rows below solved against it.
    fn supernode(&self, k: usize, scratch: &mut Scratch) {
        use std::sync::atomic::Ordering::Relaxed;
        if self.failed.load(Relaxed) != usize::MAX {
            return;
        }
        let (plan, s) = (self.plan, self.s);
        let b = node(s, k);
        let h = b.nrows();
        // SAFETY: see `block`: this task is k's.
        let block = unsafe { self.block(&b) };
        block.fill(0.0);
        for &(e, off) in &plan.a_entries[plan.a_ptr[k]..plan.a_ptr[k + 1]] {
            block[off as usize] += self.a[e as usize];
        }
        if scratch.local.len() < s.nrows() {
            scratch.local.resize(s.nrows(), 0);
        }
        for (i, &r) in b.rows.iter().enumerate() {
            scratch.local[r as usize] = (b.ncols + i) as u32;
        }
        for &d in &plan.by[plan.by_ptr[k]..plan.by_ptr[k + 1]] {
            let d = node(s, d as usize);
            let mid = d.rows_in(b.start..b.end());
            update(block, &b, self.done(&d), &d, mid, self.large, scratch);
        }
        let (mut top, mut bottom) =
            MatMut::from_column_major_slice_mut(block, h, b.ncols).split_at_row_mut(b.ncols);
        let dense = scratch.dense.get_or_insert_with(|| {
            MemBuffer::new(
                faer::linalg::cholesky::llt::factor::cholesky_in_place_scratch::<f64>(
                    plan.widest,
                    Par::Seq,
                    Default::default(),
                ),
            )
        });
        let par = match b.ncols >= self.wide {
            true => Par::rayon(0),
            false => Par::Seq,
        };
        match cholesky_in_place(
            top.rb_mut(),
            LltRegularization::default(),
            par,
            MemStack::new(dense),
            Default::default(),
        ) {
            Ok(_) => faer::linalg::triangular_solve::solve_lower_triangular_in_place(
                top.rb(),
                bottom.rb_mut().transpose_mut(),
                par,
            ),
            Err(faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot { index }) => {
                self.failed.fetch_min(b.start + index, Relaxed);
            }
        }
    }
}

/// Subtract descendant d's update from block `to` (of node `b`): `mid` are d's rows that fall
/// in b's columns; d's rows from `mid.start` on, times those rows, lower part.
fn update(
    to: &mut [f64],
    b: &Node,
    from: &[f64],
    d: &Node,
    mid: std::ops::Range<usize>,
    large: usize,
    scratch: &mut Scratch,
) {
    let (h, dh) = (b.nrows(), d.nrows());
    let (m, p, depth) = (d.rows.len() - mid.start, mid.len(), d.ncols);
    // Each row's position in b's block; the first p are b's own columns.
    scratch.rows.clear();
    scratch
        .rows
        .extend(d.rows[mid.start..].iter().enumerate().map(|(i, &r)| {
            if i < p {
                (r as usize - b.start) as u32
            } else {
                scratch.local[r as usize]
            }
        }));
    let rows = &scratch.rows;
    // d's rows from mid.start on start at `off` in each of its columns.
    let off = d.ncols + mid.start;
    if m * p * depth < DENSE_UPDATE_MIN {
        // Column j of the product, rows j.. (the lower part), summed over d's columns in
        // order, then subtracted.
        let sum = &mut scratch.product;
        for j in 0..p {
            sum.clear();
            sum.resize(m - j, 0.0);
            for c in 0..depth {
                let column = &from[c * dh + off..c * dh + off + m];
                let factor = column[j];
                for (s, x) in sum.iter_mut().zip(&column[j..]) {
                    *s += x * factor;
                }
            }
            let col = rows[j] as usize * h;
            for (s, &r) in sum.iter().zip(&rows[j..]) {
                to[col + r as usize] -= s;
            }
        }
        return;
    }
    let below = MatRef::from_column_major_slice_with_stride(&from[off..], m, depth, dh);
    if scratch.product.len() < m * p {
        scratch.product.resize(m * p, 0.0);
    }
    let mut product = MatMut::from_column_major_slice_mut(&mut scratch.product[..m * p], m, p);
    let par = match m * p * depth >= large {
        true => Par::rayon(0),
        false => Par::Seq,
    };
    // The product's lower part only: its top p x p block is lower triangular.
    let (top, bottom) = below.split_at_row(p);
    let (mut upper, lower) = product.rb_mut().split_at_row_mut(p);
    faer::linalg::matmul::triangular::matmul(
        upper.rb_mut(),
        faer::linalg::matmul::triangular::BlockStructure::TriangularLower,
        Accum::Replace,
        top,
        faer::linalg::matmul::triangular::BlockStructure::Rectangular,
        top.transpose(),
        faer::linalg::matmul::triangular::BlockStructure::Rectangular,
        1.0,
        par,
    );
    faer::linalg::matmul::matmul(lower, Accum::Replace, bottom, top.transpose(), 1.0, par);
    for j in 0..p {
        let col = rows[j] as usize * h;
        for i in j..m {
            to[col + rows[i] as usize] -= product[(i, j)];
        }
    }
}
