//! Where the set-up time goes, for the summary: process-wide accumulators that the stages add
//! their wall time to (one job runs per process; figures only, nothing depends on them).
//! A segment's key gradients and its numeric factorization run side by side, so the parts can
//! add up to more than the set-up's wall time.

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

/// The parts of a segment's set-up.
#[derive(Clone, Copy)]
pub enum Part {
    /// The system's pattern and its symbolic Cholesky analysis (once per mesh).
    Symbolic = 0,
    /// Gradients and polar decompositions to the segment's end key, and their whole turns made
    /// consistent over the surface.
    KeyB = 1,
    /// The numeric Cholesky factorization.
    Numeric = 2,
    /// The other keys of the spline window: their gradients, polar decompositions and tangents.
    Window = 3,
}

/// Names of the parts, in order.
pub const NAMES: [&str; 4] = [
    "symbolic",
    "key gradients and turns",
    "numeric factorization (beside them)",
    "spline window",
];

static NANOS: [AtomicU64; 4] = [
    AtomicU64::new(0),
    AtomicU64::new(0),
    AtomicU64::new(0),
    AtomicU64::new(0),
];

/// Add the time since `since` to `part`.
pub fn add(part: Part, since: Instant) {
    NANOS[part as usize].fetch_add(since.elapsed().as_nanos() as u64, Ordering::Relaxed);
}

/// Seconds spent in each part so far.
pub fn seconds() -> [f64; 4] {
    std::array::from_fn(|i| NANOS[i].load(Ordering::Relaxed) as f64 * 1e-9)
}
