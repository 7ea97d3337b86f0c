//! Compact stage (`--compact`, `--basis`, `--quantize`, `--meshopt`, `--sparse`): the frames of
//! a mesh as few, small morph targets, every frame within a tolerance of the dense frames.
//!
//! * **Basis** (truncated SVD): the frames' deltas (in the rig layout, what is left of them
//!   once the authored targets are blended in, so the authored targets count towards the
//!   basis and the keys stay exact) become K basis targets and K weights per frame. The Gram
//!   matrix of the frames (frames x frames) is built in column chunks from the frames as they
//!   are held (f32), its eigenvectors give the weights and one more pass the basis: the frames
//!   are never copied whole. Where the frames outnumber their values (a small mesh sampled
//!   long), the frames are copied into one matrix instead and their covariance (values x
//!   values) gives the basis directions. K is the smallest whose truncation leaves every frame within
//!   [`TRUNCATION_SHARE`] of the tolerance, then grown until the encoded result is within it.
//! * **Quantized** basis targets: normalized SHORT (or BYTE where the error allows) with each
//!   target's scale carried by its weights (`KHR_mesh_quantization`); NORMAL and TANGENT
//!   deltas alike. Authored targets keep their meaning (a rig drives them at weight 1): they
//!   stay float, and with meshopt go through its EXPONENTIAL filter at the fewest mantissa bits
//!   the tolerance allows.
//! * **Sparse** accessors for targets whose encoded values are zero on enough vertices.
//! * **Meshopt** compression of every view on write (`gltf::encode`).
//!
//! Tolerances (relative to the bounding-box diagonal of the mesh's base): positions within
//! `tolerance` RMS per frame (each primitive on its own) and no vertex farther than
//! [`MAX_FACTOR`] x `tolerance`; normals and tangents (unit vectors, so absolute) within [`NORMAL_FACTOR`] x `tolerance` RMS per frame. The
//! deviation is measured on the values as a reader decodes them.

use super::frames::{MeshFrames, PrimitiveFrames};
use super::keys::MorphMesh;
use crate::gltf::{exp_roundtrip, oct_roundtrip, Storage};
use anyhow::{bail, Result};
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatRef, Par, Side};
use glam::DVec3;
use rayon::prelude::*;
use serde::Serialize;

/// What `--compact` and its parts ask for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CompactOptions {
    /// RMS position deviation per frame allowed, relative to the bounding-box diagonal.
    pub tolerance: f64,
    pub basis: Basis,
    pub quantize: bool,
    pub meshopt: bool,
    pub sparse: bool,
}

/// Default `--tolerance`: 1e-4 of the diagonal (0.1 mm on a 1 m character).
pub const DEFAULT_TOLERANCE: f64 = 1e-4;

/// Normals and tangents are unit vectors: their RMS deviation per frame may be this many times
/// the position tolerance (1e-2 at the default: 0.6 degrees).
pub const NORMAL_FACTOR: f64 = 100.0;

/// No vertex of a frame may deviate more than this many times the tolerance (3e-4 of the
/// diagonal at the default; the issue allowed 10x, but a vertex 1e-3 off shows on a close-up).
pub const MAX_FACTOR: f64 = 3.0;

/// More basis targets a compaction may take to store its authored normals in bytes rather than
/// shorts (see `Plan::byte_normals`).
const BYTE_NORMALS_EXTRA: usize = 3;

/// Share of the tolerance the basis truncation may take ...
pub const TRUNCATION_SHARE: f64 = 0.7;
/// ... and the rounding of the stored values (quantization, the exponential filter); the
/// measured deviation of the decoded frames has the last word.
pub const QUANT_SHARE: f64 = 1.5;

/// Share of the tolerance the rounding of the base (the exponential filter on the primitive's own
/// POSITION, NORMAL and TANGENT, with meshopt) may take at its worst vertex: 2.5e-5 of the
/// diagonal at the default, about 15 bits over the mesh's extent. It adds to every frame's
/// deviation, which is measured with it.
pub const BASE_SHARE: f64 = 0.25;

/// Texture coordinates (with meshopt, through the exponential filter) stay within this many
/// times the tolerance of their values, in texture widths: 1e-4 at the default, 0.4 texel of a
/// 4096 texture (gltfpack's default 12 bits over a unit range: 1.2e-4).
pub const UV_FACTOR: f64 = 1.0;

/// Share of the tolerance the rounding of the weights animation (with meshopt, through the
/// EXPONENTIAL filter, one exponent per target) may take, bounded as if every target's rounding
/// added up at every vertex; the measured deviation includes it.
pub const WEIGHT_SHARE: f64 = 0.25;

/// Most frames a basis is looked for over where the frames have at least as many values (the
/// Gram matrix is frames x frames; with fewer values, their covariance is values x values and
/// any number of frames will do).
pub const MAX_BASIS_FRAMES: usize = 8192;

/// How many basis targets (`--basis`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Basis {
    /// No basis: the layout's own targets, encoded as asked.
    Off,
    /// As few as the tolerance allows.
    Auto,
    /// At most this many.
    Count(usize),
}

impl CompactOptions {
    /// Everything on, at the default tolerance: what `--compact` means.
    pub fn all() -> CompactOptions {
        CompactOptions {
            tolerance: DEFAULT_TOLERANCE,
            basis: Basis::Auto,
            quantize: true,
            meshopt: true,
            sparse: true,
        }
    }
}

/// One attribute of one primitive of a target: the values to store (already divided by the
/// target's scale) and how.
#[derive(Clone, Debug)]
pub struct Stored {
    pub values: Vec<f32>,
    pub storage: Storage,
    /// As a sparse accessor (only the vertices not all zero).
    pub sparse: bool,
}

/// A new target: for each processed primitive, POSITION and the NORMAL and TANGENT deltas the
/// frames carry.
#[derive(Clone, Debug)]
pub struct NewTarget {
    pub position: Vec<Stored>,
    pub normal: Option<Vec<Stored>>,
    pub tangent: Option<Vec<Stored>>,
}

/// Mantissa bits of the exponential filter for a primitive's own (base) attributes; `None`
/// leaves one as it is (not a plain f32 accessor, or no meshopt).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BaseBits {
    pub position: Option<i32>,
    pub normal: Option<i32>,
    pub tangent: Option<i32>,
    /// NORMAL, TANGENT as normalized SHORT through the OCTAHEDRAL filter at those bits (with
    /// `--quantize`, where every vector is a unit one), not floats through the EXPONENTIAL one.
    pub normal_oct: bool,
    pub tangent_oct: bool,
}

/// Which of a primitive's own POSITION, NORMAL and TANGENT the writer can store again (plain
/// f32 accessors).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Restorable {
    pub position: bool,
    pub normal: bool,
    pub tangent: bool,
}

/// The compacted frames of one mesh.
pub struct Compacted {
    /// For each processed primitive, how its own attributes are filtered.
    pub base: Vec<BaseBits>,
    /// The basis targets (scaled for storage).
    pub targets: Vec<NewTarget>,
    /// For each frame, the weights of the basis targets (scales folded in).
    pub weights: Vec<Vec<f32>>,
    /// For each frame, the weights of the authored targets (rig layout; empty rows otherwise):
    /// the keys' own, between keys the least-squares fit of the frame.
    pub authored_weights: Vec<Vec<f64>>,
    /// How the authored targets are stored (rig layout; `None`: as they are in the input).
    pub authored: Option<AuthoredStorage>,
    /// Store sparse accessors where they pay.
    pub sparse: bool,
    /// Mantissa bits of the EXPONENTIAL filter on the weights animation (with meshopt).
    pub weight_bits: Option<i32>,
    pub figures: CompactFigures,
}

/// How the authored targets are stored: their positions, and their normals and tangents.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AuthoredStorage {
    pub position: Storage,
    pub normal: Storage,
}

impl AuthoredStorage {
    /// The storage of attribute `name` (POSITION, NORMAL, TANGENT).
    pub fn of(&self, name: &str) -> Storage {
        self.of_attr(match name {
            "POSITION" => Attr::Position,
            _ => Attr::Normal,
        })
    }

    fn of_attr(&self, attr: Attr) -> Storage {
        match attr {
            Attr::Position => self.position,
            _ => self.normal,
        }
    }
}

/// What `--report` and the summary say of a compacted mesh.
#[derive(Clone, Debug, Default, Serialize)]
pub struct CompactFigures {
    /// Basis targets.
    pub basis: usize,
    /// Authored targets kept beside them.
    pub authored: usize,
    /// Deviation from the dense frames, relative to the bounding-box diagonal: the worst
    /// RMS of a primitive in a frame, and the worst vertex.
    pub rms_deviation: f64,
    pub max_deviation: f64,
    /// Worst RMS deviation of a primitive's normals in a frame (absolute), when the frames
    /// carry them.
    pub normal_rms_deviation: f64,
    /// Targets stored as SHORT, BYTE, float, and sparse.
    pub short_targets: usize,
    pub byte_targets: usize,
    pub sparse_accessors: usize,
}

/// The three attributes a target may carry.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Attr {
    Position,
    Normal,
    Tangent,
}

/// Vertices a thread measures at a time (3 columns each of the matrix products in
/// [`Plan::measure`]).
const MEASURE_CHUNK: usize = 512;

/// Basis rows made beyond those asked for, at least: the next tries of [`Plan::run`].
const BASIS_AHEAD: usize = 8;

/// One column block of the frames matrix: an attribute of a primitive.
struct Block {
    prim: usize,
    attr: Attr,
    vertices: usize,
    /// Columns scaled by this (normals and tangents weighed against positions).
    weight: f64,
}

/// The frames of a mesh as rows: each frame's deltas less the authored blend (rig layout).
struct Rows<'a> {
    frames: &'a MeshFrames,
    mesh: &'a MorphMesh,
    /// Authored weights of each frame (empty rows in the frames layout).
    authored: Vec<Vec<f64>>,
    /// Frames played by their authored weights alone (keys in the rig layout): the output plays
    /// them as the authored targets blend, so their rows are zero (where the frames' own values
    /// were taken, a key's normalized normals against the authored blend a player normalizes
    /// asked for basis targets no key plays).
    exact: Vec<bool>,
    blocks: Vec<Block>,
}

impl Rows<'_> {
    fn count(&self) -> usize {
        self.authored.len()
    }

    fn frame_values(p: &PrimitiveFrames, attr: Attr, f: usize) -> Option<&[[f32; 3]]> {
        match attr {
            Attr::Position => Some(&p.positions[f]),
            Attr::Normal => p.normals.as_ref().map(|n| &n[f][..]),
            Attr::Tangent => p.tangents.as_ref().map(|t| &t[f][..]),
        }
    }

    fn authored_values(&self, prim: usize, attr: Attr, i: usize) -> Option<&Vec<DVec3>> {
        let p = &self.mesh.primitives[prim];
        match attr {
            Attr::Position => Some(&p.target_pos[i]),
            Attr::Normal => p.target_nrm[i].as_ref(),
            Attr::Tangent => p.target_tan[i].as_ref(),
        }
    }

    /// Visit the matrix in column chunks: `visit(block index, first vertex, chunk)` with the
    /// chunk as a frames x columns matrix, weighted: each frame's values less the authored
    /// targets at its weights, a key of the rig layout zeros. Each chunk is filled on every
    /// thread, a few vertices each, the vertices' authored deltas read once for all frames (a
    /// frame at a time read every target again: 43 GB a pass for a 300-target face rig's 298
    /// frames of 20k vertices, 1.8 s a pass); each value subtracts the targets in their order.
    fn chunks(&self, visit: &mut dyn FnMut(usize, usize, MatRef<f64>)) {
        const VERTICES: usize = 1024;
        /// Vertices a thread fills at a time (their 3 values in every frame).
        const GROUP: usize = 8;
        let frames = self.count();
        let mut buf = Vec::new();
        for (bi, b) in self.blocks.iter().enumerate() {
            let p = &self.frames.primitives[b.prim];
            let targets = self.authored.iter().map(Vec::len).max().unwrap_or(0);
            let authored: Vec<Option<&Vec<DVec3>>> = (0..targets)
                .map(|i| self.authored_values(b.prim, b.attr, i))
                .collect();
            for v0 in (0..b.vertices).step_by(VERTICES) {
                let v1 = (v0 + VERTICES).min(b.vertices);
                let cols = 3 * (v1 - v0);
                buf.clear();
                buf.resize(frames * cols, 0.0);
                // Column-major: GROUP vertices' columns are one run of the buffer.
                buf.par_chunks_mut(frames * 3 * GROUP)
                    .enumerate()
                    .for_each(|(g, out)| {
                        let first = v0 + g * GROUP;
                        let last = (first + GROUP).min(v1);
                        let mut acc = [DVec3::ZERO; GROUP];
                        for f in 0..frames {
                            let acc = &mut acc[..last - first];
                            if self.exact[f] {
                                acc.fill(DVec3::ZERO);
                            } else {
                                let values = Self::frame_values(p, b.attr, f)
                                    .expect("block of a present attribute");
                                for (o, d) in acc.iter_mut().zip(&values[first..last]) {
                                    *o = DVec3::from(d.map(f64::from));
                                }
                                for (&w, d) in self.authored[f].iter().zip(&authored) {
                                    let Some(d) = d.filter(|_| w != 0.0) else {
                                        continue;
                                    };
                                    for (o, x) in acc.iter_mut().zip(&d[first..last]) {
                                        *o -= w * *x;
                                    }
                                }
                                if b.weight != 1.0 {
                                    acc.iter_mut().for_each(|x| *x *= b.weight);
                                }
                            }
                            for (c, x) in acc.iter().flat_map(|x| x.to_array()).enumerate() {
                                out[c * frames + f] = x;
                            }
                        }
                    });
                visit(bi, v0, MatRef::from_column_major_slice(&buf, frames, cols));
            }
        }
    }
}

/// Where the targets come from: the frames' singular directions (`u` F x r, `sigma` the
/// singular values, descending), or the frames themselves (`--basis off`: each listed frame
/// its own target at weight 1).
enum Factors {
    Svd { u: Mat<f64>, sigma: Vec<f64> },
    Own(Vec<usize>),
}

impl Factors {
    /// Targets available.
    fn rank(&self) -> usize {
        match self {
            Factors::Svd { sigma, .. } => sigma.len(),
            Factors::Own(frames) => frames.len(),
        }
    }

    /// Weight of target `k` in frame `f`.
    fn weight(&self, f: usize, k: usize) -> f64 {
        match self {
            Factors::Svd { u, sigma } => u[(f, k)] * sigma[k],
            Factors::Own(frames) => (frames[k] == f) as u8 as f64,
        }
    }
}

/// The frames' singular values (descending) and left singular vectors, from the smaller of
/// their two products: the Gram matrix (frames x frames) or, where the frames have fewer
/// values than there are frames, their covariance (values x values; a 337-vertex mesh at 4,201
/// frames took 9.2 s and 614 MiB by the Gram matrix).
fn factor(rows: &Rows) -> Result<(Factors, Vec<f64>)> {
    let n = rows.count();
    let values = values(&rows.blocks);
    if values < n {
        return factor_by_values(rows, values);
    }
    let mut norms2 = vec![0.0; n];
    // Frames played by their authored weights alone have zero rows: left out of the Gram matrix
    // (faer's eigensolver did not converge on MorphStressTest resampled by gltf-transform, its
    // keys' zero block beside the frames between) and given zero weights.
    let live: Vec<usize> = (0..n).filter(|&f| !rows.exact[f]).collect();
    let mut gram = Mat::<f64>::zeros(live.len(), live.len());
    rows.chunks(&mut |_, _, m| {
        add_row_norms(&mut norms2, m);
        let m = Mat::from_fn(live.len(), m.ncols(), |r, c| m[(live[r], c)]);
        matmul(
            gram.as_mut(),
            Accum::Add,
            m.as_ref(),
            m.transpose(),
            1.0,
            Par::rayon(0),
        );
    });
    let (live_u, sigma) = singular(&gram)?;
    let mut u = Mat::<f64>::zeros(n, sigma.len());
    for (r, &f) in live.iter().enumerate() {
        u.row_mut(f).copy_from(live_u.row(r));
    }
    Ok((Factors::Svd { u, sigma }, norms2))
}

/// Each row's squared norm added to `norms2`, summed along the row.
fn add_row_norms(norms2: &mut [f64], m: MatRef<f64>) {
    for (f, r) in norms2.iter_mut().enumerate() {
        *r += m.row(f).iter().map(|x| x * x).sum::<f64>();
    }
}

/// The eigenvectors of `product` (the frames' Gram matrix or covariance) in the order of the
/// frames' singular values, the square roots of its eigenvalues: descending, down to 1e-12 of
/// the largest.
fn singular(product: &Mat<f64>) -> Result<(Mat<f64>, Vec<f64>)> {
    let eig = product
        .self_adjoint_eigen(Side::Lower)
        .map_err(|e| anyhow::anyhow!("the frames' decomposition failed ({e:?})"))?;
    let s = eig.S().column_vector();
    let order: Vec<usize> = (0..product.nrows()).rev().collect();
    let top = s[order[0]].max(0.0);
    let sigma: Vec<f64> = order
        .iter()
        .map(|&i| s[i].max(0.0).sqrt())
        .take_while(|&x| x > 1e-12 * top.sqrt().max(f64::MIN_POSITIVE))
        .collect();
    let vectors = Mat::from_fn(product.nrows(), sigma.len(), |r, c| eig.U()[(r, order[c])]);
    Ok((vectors, sigma))
}

/// How many values a frame has in `blocks` (three a vertex and attribute).
fn values(blocks: &[Block]) -> usize {
    blocks.iter().map(|b| 3 * b.vertices).sum()
}

/// [`factor`] through the covariance of the frames' `values` columns: its eigenvectors are the
/// right singular vectors V, and U = M V / sigma.
fn factor_by_values(rows: &Rows, values: usize) -> Result<(Factors, Vec<f64>)> {
    let n = rows.count();
    let mut m = Mat::<f64>::zeros(n, values);
    let mut at = 0;
    let mut norms2 = vec![0.0; n];
    rows.chunks(&mut |_, _, chunk| {
        add_row_norms(&mut norms2, chunk);
        m.as_mut()
            .submatrix_mut(0, at, n, chunk.ncols())
            .copy_from(chunk);
        at += chunk.ncols();
    });
    let mut cov = Mat::<f64>::zeros(values, values);
    matmul(
        cov.as_mut(),
        Accum::Replace,
        m.transpose(),
        m.as_ref(),
        1.0,
        Par::rayon(0),
    );
    let (v, sigma) = singular(&cov)?;
    let mut u = Mat::<f64>::zeros(n, sigma.len());
    matmul(
        u.as_mut(),
        Accum::Replace,
        m.as_ref(),
        v.as_ref(),
        1.0,
        Par::rayon(0),
    );
    for (c, sv) in sigma.iter().enumerate() {
        for r in 0..n {
            u[(r, c)] /= sv;
        }
    }
    Ok((Factors::Svd { u, sigma }, norms2))
}

/// The smallest K whose truncation leaves every frame's (weighted) residual within `budget`
/// (squared norm per frame), from the Gram diagonal and the weights.
fn smallest_k(f: &Factors, norms2: &[f64], budget2: f64) -> usize {
    let mut resid = norms2.to_vec();
    for k in 0..=f.rank() {
        if resid.iter().all(|r| *r <= budget2) {
            return k;
        }
        if k == f.rank() {
            break;
        }
        for (row, r) in resid.iter_mut().enumerate() {
            let w = f.weight(row, k);
            *r -= w * w;
        }
    }
    f.rank()
}

/// Compact the frames of one mesh (`frames` computed from `mesh`), keeping the authored targets
/// when `authored` gives each frame's authored weights (rig layout); `own` lists the frames
/// that have targets of their own without a basis (the frames between keys in the rig layout);
/// `restorable` says which of each primitive's own attributes the writer can filter.
pub fn compact(
    frames: &MeshFrames,
    mesh: &MorphMesh,
    authored: Vec<Vec<f64>>,
    own: Vec<usize>,
    restorable: &[Restorable],
    opts: &CompactOptions,
) -> Result<Compacted> {
    let rig = authored.iter().any(|w| !w.is_empty());
    // In the rig layout a key plays its authored weights alone: where every frame lies on a
    // key, no basis target would ever play, so none is looked for (a face rig baked at 60 keys
    // a second for 2 minutes: 60 basis targets no frame played, 75 s and 2.1 GB).
    let opts = &CompactOptions {
        basis: match rig && own.is_empty() {
            true => Basis::Off,
            false => opts.basis,
        },
        ..*opts
    };
    let count = authored.len();
    let diag = {
        let all: Vec<DVec3> = mesh
            .primitives
            .iter()
            .flat_map(|p| p.base.iter().copied())
            .collect();
        super::weld::bbox_diagonal(&all).max(f64::MIN_POSITIVE)
    };
    let tol = opts.tolerance * diag;
    let ntol = (NORMAL_FACTOR * opts.tolerance).min(0.5);
    let mut blocks = Vec::new();
    for (pi, p) in frames.primitives.iter().enumerate() {
        let vertices = mesh.primitives[pi].base.len();
        blocks.push(Block {
            prim: pi,
            attr: Attr::Position,
            vertices,
            weight: 1.0,
        });
        if p.normals.is_some() {
            blocks.push(Block {
                prim: pi,
                attr: Attr::Normal,
                vertices,
                weight: tol / ntol,
            });
        }
        if p.tangents.is_some() {
            blocks.push(Block {
                prim: pi,
                attr: Attr::Tangent,
                vertices,
                weight: tol / ntol,
            });
        }
    }
    if opts.basis != Basis::Off && count.min(values(&blocks)) > MAX_BASIS_FRAMES {
        bail!(
            "mesh {:?}: {count} frames are more than a basis is looked for over ({MAX_BASIS_FRAMES}); use fewer frames or --basis off",
            mesh.name
        );
    }
    let vertices: usize = mesh.primitives.iter().map(|p| p.base.len()).sum();
    let (base, base_error) = base_rounding(mesh, &blocks, restorable, opts, (tol, ntol));
    let mut exact = vec![rig; count];
    for &f in &own {
        exact[f] = false;
    }
    let mut rows = Rows {
        frames,
        mesh,
        authored,
        exact,
        blocks,
    };
    // Frames between keys: the authored targets at the weights that come nearest the frame (least
    // squares), so the basis carries only what the rig cannot (keys keep their own weights).
    // Not where the authored targets also move attributes the frames do not solve (TEXCOORD_n,
    // COLOR_n): those play by the authored weights, which then stay blended between the keys.
    let unsolved = mesh.primitives.iter().any(|p| !p.target_other.is_empty());
    if rig && opts.basis != Basis::Off && !unsolved {
        fit_authored(&mut rows, &own)?;
    }
    let plan = Plan {
        rows: &rows,
        opts,
        tol,
        ntol,
        vertices,
        rig,
        base,
        base_error,
        basis_rows: Default::default(),
    };
    plan.run(own)
}

/// Replace the authored weights of frames `own` by the least-squares fit of the frames to the
/// authored targets (positions and weighted normals and tangents, as the basis sees them).
fn fit_authored(rows: &mut Rows, own: &[usize]) -> Result<()> {
    let t = rows.mesh.target_count;
    if t == 0 || own.is_empty() {
        return Ok(());
    }
    let mut ata = Mat::<f64>::zeros(t, t);
    let mut atd = Mat::<f64>::zeros(t, own.len());
    for b in &rows.blocks {
        let w2 = b.weight * b.weight;
        let targets: Vec<Option<&Vec<DVec3>>> = (0..t)
            .map(|i| rows.authored_values(b.prim, b.attr, i))
            .collect();
        let p = &rows.frames.primitives[b.prim];
        let frames: Vec<&[[f32; 3]]> = (own.iter())
            .map(|&f| Rows::frame_values(p, b.attr, f).expect("block of a present attribute"))
            .collect();
        // Each target's products with the targets after it (None: one without this attribute)
        // and with the frames, the targets on every thread.
        type Products = (Vec<Option<f64>>, Vec<f64>);
        let products: Vec<Option<Products>> = (0..t)
            .into_par_iter()
            .map(|i| {
                let ai = targets[i]?;
                let later: Vec<&[DVec3]> = targets[i..].iter().flatten().map(|a| &a[..]).collect();
                let mut with = dots(ai, &later, |d| *d).into_iter();
                let later = (targets[i..].iter())
                    .map(|a| a.map(|_| with.next().expect("a product for each target")))
                    .collect();
                Some((later, dots(ai, &frames, |d| DVec3::from(d.map(f64::from)))))
            })
            .collect();
        for (i, products) in products.into_iter().enumerate() {
            let Some((later, frames)) = products else {
                continue;
            };
            for (j, dot) in (i..t).zip(later) {
                if let Some(dot) = dot {
                    ata[(i, j)] += w2 * dot;
                    ata[(j, i)] = ata[(i, j)];
                }
            }
            for (col, dot) in frames.into_iter().enumerate() {
                atd[(i, col)] += w2 * dot;
            }
        }
    }
    // Pseudo-inverse through the eigen-decomposition: targets that coincide share the weight.
    let eig = ata
        .self_adjoint_eigen(Side::Lower)
        .map_err(|e| anyhow::anyhow!("the authored targets' fit failed ({e:?})"))?;
    let s = eig.S().column_vector();
    let top = (0..t).map(|i| s[i]).fold(0.0f64, f64::max);
    let u = eig.U();
    for (col, &f) in own.iter().enumerate() {
        let mut w = vec![0.0; t];
        for k in 0..t {
            if s[k] <= 1e-12 * top {
                continue;
            }
            let proj: f64 = (0..t).map(|i| u[(i, k)] * atd[(i, col)]).sum::<f64>() / s[k];
            for (i, wi) in w.iter_mut().enumerate() {
                *wi += u[(i, k)] * proj;
            }
        }
        rows.authored[f] = w;
    }
    Ok(())
}

/// The dot products of `a` with each of `others` (values `to` makes vectors of), each summed
/// in vertex order from -0.0 as `Iterator::sum` sums them (the same bits), eight at a time so
/// that their sums run side by side: one sum's chain of additions waits on each addition (a
/// 300-target rig's 45,000 products of 20k vertices: 3 s one at a time).
fn dots<T: Sync>(a: &[DVec3], others: &[&[T]], to: impl Fn(&T) -> DVec3) -> Vec<f64> {
    const LANES: usize = 8;
    let mut out = Vec::with_capacity(others.len());
    for group in others.chunks(LANES) {
        let mut sums = [-0.0f64; LANES];
        for (v, x) in a.iter().enumerate() {
            for (s, o) in sums.iter_mut().zip(group) {
                *s += x.dot(to(&o[v]));
            }
        }
        out.extend_from_slice(&sums[..group.len()]);
    }
    out
}

/// A compaction under way: the rows and the tolerances in scene units.
struct Plan<'a> {
    rows: &'a Rows<'a>,
    opts: &'a CompactOptions,
    tol: f64,
    ntol: f64,
    vertices: usize,
    rig: bool,
    /// How each primitive's own attributes are filtered, and what that moves each block by.
    base: Vec<BaseBits>,
    base_error: Vec<Option<Vec<f32>>>,
    /// The basis rows made so far (see [`Plan::encode`]).
    basis_rows: std::sync::Mutex<Vec<Vec<Vec<f32>>>>,
}

impl Plan<'_> {
    fn run(&self, own: Vec<usize>) -> Result<Compacted> {
        let rows = self.rows;
        // The frames' squared norms come with the factors, from the same pass over the frames.
        let (factors, norms2) = match self.opts.basis {
            Basis::Off => (Some(Factors::Own(own)), Vec::new()),
            _ => {
                let (f, norms2) = factor(rows)?;
                (Some(f), norms2)
            }
        };
        let mut k = match (&factors, self.opts.basis) {
            (Some(f), Basis::Off) => f.rank(),
            (Some(f), Basis::Auto) => {
                let blocks = rows.blocks.len() as f64 / rows.frames.primitives.len().max(1) as f64;
                let budget = TRUNCATION_SHARE * self.tol;
                smallest_k(f, &norms2, budget * budget * self.vertices as f64 * blocks)
            }
            (Some(f), Basis::Count(k)) => k.min(f.rank()),
            _ => 0,
        };
        let exp_bits = self.opts.meshopt.then_some(0);
        let mut quantize = self.opts.quantize;
        loop {
            let out = self.encode(factors.as_ref(), k, quantize, exp_bits, false)?;
            let fits = self.fits(&out.figures);
            let more = factors.as_ref().is_some_and(|fs| {
                k < fs.rank() && !matches!(self.opts.basis, Basis::Count(c) if k >= c)
            });
            if fits {
                return self.byte_normals(factors.as_ref(), k, exp_bits, out);
            }
            if !more && !quantize {
                return Ok(out);
            }
            if more {
                k += 1;
            } else {
                quantize = false;
            }
        }
    }

    /// The compaction `fitted` (`k` basis targets, within the tolerances), or one whose authored
    /// normals and tangents are normalized bytes where the bound gave them shorts, when that
    /// still fits with at most [`BYTE_NORMALS_EXTRA`] more basis targets: the bound takes every
    /// target at full weight at once, and authored normals are as many values as their
    /// positions (a face rig of 52 position-only targets given the normals of their shapes:
    /// 343 KB with shorts, 254 KB with bytes and two more basis targets).
    fn byte_normals(
        &self,
        factors: Option<&Factors>,
        k: usize,
        exp_bits: Option<i32>,
        fitted: Compacted,
    ) -> Result<Compacted> {
        let shorts = fitted.authored.is_some_and(|a| a.normal == Storage::Short);
        if !shorts {
            return Ok(fitted);
        }
        let rank = factors.map_or(k, Factors::rank);
        let cap = match self.opts.basis {
            Basis::Count(c) => c.min(rank),
            Basis::Off => k,
            Basis::Auto => rank,
        };
        for k in k..=(k + BYTE_NORMALS_EXTRA).min(cap) {
            let out = self.encode(factors, k, true, exp_bits, true)?;
            if self.fits(&out.figures) {
                return Ok(out);
            }
        }
        Ok(fitted)
    }

    /// Whether figures are within the tolerances.
    fn fits(&self, f: &CompactFigures) -> bool {
        f.rms_deviation <= self.opts.tolerance
            && f.max_deviation <= MAX_FACTOR * self.opts.tolerance
            && f.normal_rms_deviation <= self.ntol
    }

    /// How the authored targets are stored, their positions and (apart) their normals and
    /// tangents: normalized BYTE or SHORT when `quantize` and every component lies in [-1, 1] (a
    /// unit vector's change mostly does, and a character's shapes in metres; the target keeps
    /// its meaning at weight 1, no scale needed) and the integer step at the largest authored
    /// weight is within the step (`q_pos`, `q_nrm`); else floats through the exponential filter
    /// at the fewest mantissa bits whose rounding at that weight is within it.
    fn authored_storage(
        &self,
        q_pos: f64,
        q_nrm: f64,
        quantize: bool,
        byte_normals: bool,
    ) -> AuthoredStorage {
        let rows = self.rows;
        let weight = rows
            .authored
            .iter()
            .flatten()
            .fold(1.0f64, |m, w| m.max(w.abs()));
        // The largest component of the listed deltas (`None`: there are none).
        let largest = |list: Vec<&Vec<DVec3>>| {
            list.iter()
                .flat_map(|v| v.iter())
                .map(|d| d.abs().max_element())
                .reduce(f64::max)
        };
        let mesh = rows.mesh;
        let lp = largest(
            mesh.primitives
                .iter()
                .flat_map(|p| p.target_pos.iter())
                .collect(),
        );
        let ln = largest(
            mesh.primitives
                .iter()
                .flat_map(|p| p.target_nrm.iter().chain(&p.target_tan).flatten())
                .collect(),
        );
        let store = |largest: Option<f64>, step: f64| {
            let integer = [(Storage::Byte, 127.0), (Storage::Short, 32767.0)]
                .into_iter()
                .find(|(_, steps)| weight / steps <= step)
                .map(|(s, _)| s)
                .filter(|_| quantize && largest.is_some_and(|l| l <= 1.0));
            let l = largest.unwrap_or(0.0);
            let bits = ((l * weight / step).log2().ceil() as i32 + 1).clamp(4, 24);
            integer.unwrap_or(Storage::Float {
                exp_bits: Some(bits),
            })
        };
        AuthoredStorage {
            position: store(lp, q_pos),
            normal: match byte_normals && quantize && ln.is_some_and(|l| l <= 1.0) {
                true => Storage::Byte,
                false => store(ln, q_nrm),
            },
        }
    }

    /// The basis of the first `k` directions, encoded, and its measured deviation.
    fn encode(
        &self,
        factors: Option<&Factors>,
        k: usize,
        quantize: bool,
        exp_bits: Option<i32>,
        byte_normals: bool,
    ) -> Result<Compacted> {
        let rows = self.rows;
        let n = rows.count();
        // Basis rows: (1 / sigma) U^T R, per block, unweighted (normals back in their units).
        // The frames' own (`--basis off`) here; the singular directions' kept in `basis_rows`.
        let mut basis: Vec<Vec<Vec<f32>>> = Vec::new();
        if let (Some(Factors::Own(frames)), true) = (factors, k > 0) {
            basis = vec![
                rows.blocks
                    .iter()
                    .map(|b| vec![0.0f32; 3 * b.vertices])
                    .collect();
                k
            ];
            // The frames' rows as the residuals' passes fill them (each frame alone read every
            // authored target again, on one thread).
            rows.chunks(&mut |bi, v0, m| {
                let w = rows.blocks[bi].weight;
                for (target, &f) in basis.iter_mut().zip(frames) {
                    let out = &mut target[bi][3 * v0..3 * v0 + m.ncols()];
                    for (j, o) in out.iter_mut().enumerate() {
                        *o = (m[(f, j)] / w) as f32;
                    }
                }
            });
        }
        let mut cache = self.basis_rows.lock().expect("one encode at a time");
        if let (Some(Factors::Svd { u, sigma }), true) = (factors, k > 0) {
            if cache.len() < k {
                // Row c is the same for every k: rows past k made in the same pass (its cost
                // is in filling the residuals, not in the rows), for the next k tried.
                let from = cache.len();
                let to = (k + (k / 8).max(BASIS_AHEAD)).min(sigma.len());
                let mut uk = Mat::<f64>::zeros(to - from, n);
                for c in from..to {
                    for r in 0..n {
                        uk[(c - from, r)] = u[(r, c)] / sigma[c];
                    }
                }
                let mut fresh: Vec<Vec<Vec<f32>>> = vec![
                    rows.blocks
                        .iter()
                        .map(|b| vec![0.0f32; 3 * b.vertices])
                        .collect();
                    to - from
                ];
                rows.chunks(&mut |bi, v0, m| {
                    let mut part = Mat::<f64>::zeros(to - from, m.ncols());
                    matmul(
                        part.as_mut(),
                        Accum::Replace,
                        uk.as_ref(),
                        m.as_ref(),
                        1.0,
                        Par::Seq,
                    );
                    let w = rows.blocks[bi].weight;
                    for (c, target) in fresh.iter_mut().enumerate() {
                        for j in 0..m.ncols() {
                            target[bi][3 * v0 + j] = (part[(c, j)] / w) as f32;
                        }
                    }
                });
                cache.extend(fresh);
            }
        }
        let basis = match basis.is_empty() {
            true => &cache[..k.min(cache.len())],
            false => &basis[..],
        };
        // Weights W = U sigma; keys of the rig (no residual) exactly zero.
        let mut weights: Vec<Vec<f64>> = (0..n)
            .map(|r| {
                (0..k)
                    .map(|c| factors.map_or(0.0, |fs| fs.weight(r, c)))
                    .collect()
            })
            .collect();
        // Each target scaled to its largest value, quantized or filtered.
        let mut targets = Vec::with_capacity(k);
        let mut figures = CompactFigures {
            basis: k,
            authored: if self.rig { rows.mesh.target_count } else { 0 },
            ..Default::default()
        };
        // Each target rounded to the step its largest weight allows: the roundings of all the
        // targets together stay within QUANT_SHARE of the tolerance (RMS per frame).
        let total = (k + figures.authored).max(1) as f64;
        let q_pos = 2.0 * QUANT_SHARE * self.tol / total.sqrt();
        let q_nrm = 2.0 * QUANT_SHARE * self.ntol / total.sqrt();
        for (c, t) in basis.iter().enumerate() {
            let largest_weight = weights.iter().map(|w| w[c].abs()).fold(0.0, f64::max);
            let (step_p, step_n) = (
                q_pos / largest_weight.max(f64::MIN_POSITIVE),
                q_nrm / largest_weight.max(f64::MIN_POSITIVE),
            );
            let (target, scale) = self.target(
                t,
                step_p,
                step_n,
                quantize,
                exp_bits.is_some(),
                &mut figures,
            );
            for w in &mut weights {
                w[c] *= scale;
            }
            targets.push(target);
        }
        let authored = exp_bits
            .filter(|_| self.rig)
            .map(|_| self.authored_storage(q_pos, q_nrm, quantize, byte_normals));
        let weights: Vec<Vec<f32>> = weights
            .iter()
            .map(|w| w.iter().map(|&x| x as f32).collect())
            .collect();
        let weight_bits = self.measure(&targets, &weights, authored, &mut figures);
        Ok(Compacted {
            base: self.base.clone(),
            targets,
            weights,
            authored_weights: rows.authored.clone(),
            authored,
            sparse: self.opts.sparse,
            weight_bits,
            figures,
        })
    }

    /// One basis target from its blocks' values: positions rounded to `step_p` (normals and
    /// tangents to `step_n`) as normalized integers when `quantize` (the target's scale, which
    /// its weights carry, is returned), else floats (through the exponential filter at the
    /// bits the steps allow when `filter`).
    fn target(
        &self,
        blocks: &[Vec<f32>],
        step_p: f64,
        step_n: f64,
        quantize: bool,
        filter: bool,
        figures: &mut CompactFigures,
    ) -> (NewTarget, f64) {
        let largest = |attr: Attr| -> f64 {
            self.rows
                .blocks
                .iter()
                .zip(blocks)
                .filter(|(b, _)| (b.attr == Attr::Position) == (attr == Attr::Position))
                .flat_map(|(_, v)| v.iter())
                .fold(0.0f64, |m, x| m.max(x.abs() as f64))
        };
        let (lp, ln) = (largest(Attr::Position), largest(Attr::Normal));
        let bits = |l: f64, step: f64| ((l / step).log2().ceil() as i32 + 1).clamp(4, 24);
        // Positions set the integer step; the scale turns it into normalized values.
        let (pos_storage, scale) = if !quantize {
            (
                Storage::Float {
                    exp_bits: filter.then(|| bits(lp, step_p)),
                },
                1.0,
            )
        } else if lp / step_p <= 127.0 {
            (Storage::Byte, step_p * 127.0)
        } else if lp / step_p <= 32767.0 {
            (Storage::Short, step_p * 32767.0)
        } else {
            (Storage::Short, lp.max(f64::MIN_POSITIVE))
        };
        let scale = scale.max(f64::MIN_POSITIVE);
        // Normals and tangents share the weight: an integer whose step is fine enough, else
        // floats.
        let nrm_storage = if !quantize {
            Storage::Float {
                exp_bits: filter.then(|| bits(ln, step_n)),
            }
        } else if scale / 127.0 <= step_n && ln <= scale {
            Storage::Byte
        } else if scale / 32767.0 <= step_n && ln <= scale {
            Storage::Short
        } else {
            Storage::Float {
                exp_bits: filter.then(|| bits(ln / scale, step_n / scale)),
            }
        };
        match pos_storage {
            Storage::Byte => figures.byte_targets += 1,
            Storage::Short => figures.short_targets += 1,
            Storage::Float { .. } => {}
        }
        let prims = self.rows.frames.primitives.len();
        let mut position = Vec::with_capacity(prims);
        let mut normal: Option<Vec<Stored>> = None;
        let mut tangent: Option<Vec<Stored>> = None;
        for (b, values) in self.rows.blocks.iter().zip(blocks) {
            let storage = if b.attr == Attr::Position {
                pos_storage
            } else {
                nrm_storage
            };
            let values: Vec<f32> = values.iter().map(|x| (*x as f64 / scale) as f32).collect();
            let sparse = self.opts.sparse && sparse_pays(&values, storage, self.opts.meshopt);
            figures.sparse_accessors += sparse as usize;
            let s = Stored {
                values,
                storage,
                sparse,
            };
            match b.attr {
                Attr::Position => position.push(s),
                Attr::Normal => normal.get_or_insert_with(Vec::new).push(s),
                Attr::Tangent => tangent.get_or_insert_with(Vec::new).push(s),
            }
        }
        (
            NewTarget {
                position,
                normal,
                tangent,
            },
            scale,
        )
    }

    /// The deviation of the frames as a reader decodes them from the dense frames; with meshopt
    /// the weights go through the EXPONENTIAL filter first, at the bits returned.
    fn measure(
        &self,
        targets: &[NewTarget],
        weights: &[Vec<f32>],
        authored: Option<AuthoredStorage>,
        figures: &mut CompactFigures,
    ) -> Option<i32> {
        let rows = self.rows;
        let decoded: Vec<Vec<Vec<f32>>> = targets
            .iter()
            .map(|t| {
                rows.blocks
                    .iter()
                    .enumerate()
                    .map(|(bi, b)| {
                        let list = match b.attr {
                            Attr::Position => &t.position,
                            Attr::Normal => t.normal.as_ref().expect("normals"),
                            Attr::Tangent => t.tangent.as_ref().expect("tangents"),
                        };
                        let prim_index = rows.blocks[..bi]
                            .iter()
                            .filter(|x| x.attr == b.attr)
                            .count();
                        decode(&list[prim_index])
                    })
                    .collect()
            })
            .collect();
        let authored_decoded = self.authored_decoded(authored);
        // The weights as a reader decodes them: (authored, basis) of each frame.
        let (weight_bits, authored_w, weights) = match self.opts.meshopt {
            true => self.filtered_weights(&decoded, authored_decoded.as_ref(), weights),
            false => (None, rows.authored.clone(), weights.to_vec()),
        };
        // Squared deviations per primitive and frame: a small primitive (an eye) must not hide
        // in a large one's average.
        let prims = rows.frames.primitives.len();
        let n = rows.count();
        let mut pos2 = vec![vec![0.0f64; n]; prims];
        let mut nrm2 = vec![vec![0.0f64; n]; prims];
        let mut pos_n = vec![0usize; prims];
        let mut nrm_n = vec![0usize; prims];
        let mut worst = 0.0f64;
        // A frame as a reader plays it: the basis at its weights and the authored targets (as
        // decoded) at theirs, against the dense frame; a key the authored weights alone play
        // (rig layout), against the authored targets exact at the exact weights. Per block, in
        // chunks of vertices, those sums as matrix products (the targets by the frames).
        let a = rows.authored.iter().map(Vec::len).max().unwrap_or(0);
        let k = decoded.len();
        let played = Mat::<f64>::from_fn(k + a, n, |c, f| match c < k {
            true => weights[f][c] as f64,
            false => authored_w[f].get(c - k).copied().unwrap_or(0.0),
        });
        let exact: Vec<usize> = (0..n).filter(|&f| rows.exact[f]).collect();
        let keys = Mat::<f64>::from_fn(a, exact.len(), |i, r| {
            rows.authored[exact[r]].get(i).copied().unwrap_or(0.0)
        });
        for (bi, b) in rows.blocks.iter().enumerate() {
            if b.attr == Attr::Position {
                pos_n[b.prim] += b.vertices;
            } else {
                nrm_n[b.prim] += b.vertices;
            }
            let frames = &rows.frames.primitives[b.prim];
            let exact_values: Vec<Option<&Vec<DVec3>>> = (0..a)
                .map(|i| rows.authored_values(b.prim, b.attr, i))
                .collect();
            let dec = authored_decoded.as_ref().map(|ad| &ad[bi]);
            let chunk = |v0: usize| -> Vec<(f64, f64)> {
                let v1 = (v0 + MEASURE_CHUNK).min(b.vertices);
                let cols = 3 * (v1 - v0);
                // Each target a column over the chunk's values.
                let exact_col = |i: usize, m: &mut [f64]| {
                    if let Some(x) = exact_values[i] {
                        for (o, d) in m.chunks_exact_mut(3).zip(&x[v0..v1]) {
                            o.copy_from_slice(&d.to_array());
                        }
                    }
                };
                let mut targets = Mat::<f64>::zeros(cols, k + a);
                for c in 0..k + a {
                    let m = targets.col_as_slice_mut(c);
                    if c < k {
                        let t = &decoded[c][bi][3 * v0..3 * v1];
                        m.iter_mut().zip(t).for_each(|(o, x)| *o = *x as f64);
                    } else if let Some(d) = dec.and_then(|d| d[c - k].as_ref()) {
                        let t = &d[3 * v0..3 * v1];
                        m.iter_mut().zip(t).for_each(|(o, x)| *o = *x as f64);
                    } else {
                        exact_col(c - k, m);
                    }
                }
                let mut e = Mat::<f64>::zeros(cols, n);
                if !exact.is_empty() && a > 0 {
                    let mut x = Mat::<f64>::zeros(cols, a);
                    (0..a).for_each(|i| exact_col(i, x.col_as_slice_mut(i)));
                    let mut blend = Mat::<f64>::zeros(cols, exact.len());
                    let (x, keys) = (x.as_ref(), keys.as_ref());
                    matmul(blend.as_mut(), Accum::Replace, x, keys, 1.0, Par::Seq);
                    for (r, &f) in exact.iter().enumerate() {
                        e.col_as_slice_mut(f).copy_from_slice(blend.col_as_slice(r));
                    }
                }
                for f in (0..n).filter(|&f| !rows.exact[f]) {
                    let values = Rows::frame_values(frames, b.attr, f).expect("present");
                    let m = e.col_as_slice_mut(f);
                    for (o, d) in m.chunks_exact_mut(3).zip(&values[v0..v1]) {
                        o.copy_from_slice(&d.map(f64::from));
                    }
                }
                let (t, p) = (targets.as_ref(), played.as_ref());
                matmul(e.as_mut(), Accum::Add, t, p, -1.0, Par::Seq);
                let be = self.base_error[bi].as_ref().map(|be| &be[3 * v0..3 * v1]);
                (0..n)
                    .map(|f| {
                        let (mut sum, mut most) = (0.0f64, 0.0f64);
                        for (v, r) in e.col_as_slice(f).chunks_exact(3).enumerate() {
                            let mut d2 = 0.0;
                            for i in 0..3 {
                                let x = r[i] - be.map_or(0.0, |be| be[3 * v + i] as f64);
                                d2 += x * x;
                            }
                            sum += d2;
                            most = most.max(d2);
                        }
                        (sum, most)
                    })
                    .collect()
            };
            // Chunks of a fixed size, summed in order: the same figures on any number of
            // threads.
            let parts: Vec<Vec<(f64, f64)>> = (0..b.vertices)
                .step_by(MEASURE_CHUNK)
                .collect::<Vec<_>>()
                .into_par_iter()
                .map(chunk)
                .collect();
            // Normals and tangents share a sum.
            let sums = match b.attr {
                Attr::Position => &mut pos2[b.prim],
                _ => &mut nrm2[b.prim],
            };
            for part in parts {
                for (f, (sum, most)) in part.into_iter().enumerate() {
                    sums[f] += sum;
                    if b.attr == Attr::Position {
                        worst = worst.max(most);
                    }
                }
            }
        }
        let worst_rms = |sums: &[Vec<f64>], n: &[usize]| {
            sums.iter()
                .zip(n)
                .flat_map(|(s, &n)| s.iter().map(move |x| (x / n.max(1) as f64).sqrt()))
                .fold(0.0, f64::max)
        };
        figures.rms_deviation = worst_rms(&pos2, &pos_n) / (self.tol / self.opts.tolerance);
        figures.max_deviation = worst.sqrt() / (self.tol / self.opts.tolerance);
        figures.normal_rms_deviation = worst_rms(&nrm2, &nrm_n);
        weight_bits
    }

    /// The fewest mantissa bits of the EXPONENTIAL filter on the weights animation (the view of
    /// every track's rows `[authored, basis]`, as the writer lays it out) whose rounding, added
    /// up over the targets as if it never cancelled, stays within [`WEIGHT_SHARE`] of the
    /// tolerances; and the weights (authored, basis) a reader then decodes. `decoded` holds the
    /// basis targets per block, `authored` the authored ones where they are filtered.
    #[allow(clippy::type_complexity)]
    fn filtered_weights(
        &self,
        decoded: &[Vec<Vec<f32>>],
        authored: Option<&Vec<Vec<Option<Vec<f32>>>>>,
        weights: &[Vec<f32>],
    ) -> (Option<i32>, Vec<Vec<f64>>, Vec<Vec<f32>>) {
        let rows = self.rows;
        let a = if self.rig { rows.mesh.target_count } else { 0 };
        let width = a + decoded.len();
        let exact = || (None, rows.authored.clone(), weights.to_vec());
        if width == 0 || weights.is_empty() {
            return exact();
        }
        // Each column's target: per primitive RMS and worst length of its positions, and the
        // RMS of its normals and tangents.
        let mut pos_rms = vec![0.0f64; width];
        let mut pos_max = vec![0.0f64; width];
        let mut nrm_rms = vec![0.0f64; width];
        for (bi, b) in rows.blocks.iter().enumerate() {
            for c in 0..width {
                let flat: Option<Vec<f32>> = if c < a {
                    let dec = authored.and_then(|ad| ad[bi][c].clone());
                    dec.or_else(|| {
                        let v = rows.authored_values(b.prim, b.attr, c)?;
                        Some(v.iter().flat_map(|d| d.as_vec3().to_array()).collect())
                    })
                } else {
                    Some(decoded[c - a][bi].clone())
                };
                let Some(flat) = flat else { continue };
                let (mut sum2, mut worst) = (0.0f64, 0.0f64);
                for d in flat.chunks_exact(3) {
                    let l2: f64 = d.iter().map(|&x| (x as f64) * (x as f64)).sum();
                    sum2 += l2;
                    worst = worst.max(l2);
                }
                let rms = (sum2 / b.vertices.max(1) as f64).sqrt();
                if b.attr == Attr::Position {
                    pos_rms[c] = pos_rms[c].max(rms);
                    pos_max[c] = pos_max[c].max(worst.sqrt());
                } else {
                    nrm_rms[c] = nrm_rms[c].max(rms);
                }
            }
        }
        // The rows as written: every track of the mesh in one view.
        let n = rows.count();
        let written: Vec<f32> = (0..n)
            .flat_map(|f| {
                let authored = rows.authored[f].iter().map(|&x| x as f32);
                authored
                    .chain(weights[f].iter().copied())
                    .collect::<Vec<f32>>()
            })
            .collect();
        let comps = crate::gltf::row_components(width);
        let roundtrip = |bits: i32| exp_roundtrip(&written, comps, bits);
        let fits = |decoded: &[f32]| {
            let mut worst = vec![0.0f64; width];
            for (i, (x, d)) in written.iter().zip(decoded).enumerate() {
                let c = i % width;
                worst[c] = worst[c].max((*x as f64 - *d as f64).abs());
            }
            let sum = |norms: &[f64]| worst.iter().zip(norms).map(|(d, t)| d * t).sum::<f64>();
            sum(&pos_rms) <= WEIGHT_SHARE * self.tol
                && sum(&pos_max) <= WEIGHT_SHARE * MAX_FACTOR * self.tol
                && sum(&nrm_rms) <= WEIGHT_SHARE * self.ntol
        };
        let Some((bits, decoded)) = (1..=24).map(|b| (b, roundtrip(b))).find(|(_, d)| fits(d))
        else {
            return exact();
        };
        let authored_w = (0..n)
            .map(|f| (0..a).map(|i| decoded[f * width + i] as f64).collect())
            .collect();
        let basis_w = (0..n)
            .map(|f| decoded[f * width + a..(f + 1) * width].to_vec())
            .collect();
        (Some(bits), authored_w, basis_w)
    }

    /// The authored targets as a reader decodes them after the EXPONENTIAL filter, per block
    /// and target (`None` when they are stored exactly).
    fn authored_decoded(
        &self,
        authored: Option<AuthoredStorage>,
    ) -> Option<Vec<Vec<Option<Vec<f32>>>>> {
        let authored = authored?;
        let rows = self.rows;
        // As the writer stores them: the dense targets of a block share one filtered view (one
        // exponent per component), a sparse target's values are a view of their own.
        Some(
            rows.blocks
                .iter()
                .map(|b| {
                    let mut out: Vec<Option<Vec<f32>>> = vec![None; rows.mesh.target_count];
                    let storage = authored.of_attr(b.attr);
                    let bits = match storage {
                        Storage::Float {
                            exp_bits: Some(bits),
                        } => bits,
                        Storage::Float { exp_bits: None } => return out,
                        // Integers: each value on its own.
                        _ => {
                            for (i, slot) in out.iter_mut().enumerate() {
                                *slot = rows.authored_values(b.prim, b.attr, i).map(|a| {
                                    let flat = a.iter().flat_map(|d| d.as_vec3().to_array());
                                    flat.map(|x| storage.stored(x)).collect()
                                });
                            }
                            return out;
                        }
                    };
                    let flat = |i: usize| -> Option<Vec<f32>> {
                        let a = rows.authored_values(b.prim, b.attr, i)?;
                        Some(a.iter().flat_map(|d| d.as_vec3().to_array()).collect())
                    };
                    let mut dense = Vec::new();
                    for (i, slot) in out.iter_mut().enumerate() {
                        let Some(values) = flat(i) else { continue };
                        if self.opts.sparse && sparse_pays(&values, storage, self.opts.meshopt) {
                            let moving: Vec<usize> = (0..b.vertices)
                                .filter(|&v| values[3 * v..3 * v + 3].iter().any(|&x| x != 0.0))
                                .collect();
                            let picked: Vec<f32> = moving
                                .iter()
                                .flat_map(|&v| values[3 * v..3 * v + 3].to_vec())
                                .collect();
                            let mut decoded = vec![0.0f32; values.len()];
                            for (&v, d) in moving
                                .iter()
                                .zip(exp_roundtrip(&picked, 3, bits).chunks_exact(3))
                            {
                                decoded[3 * v..3 * v + 3].copy_from_slice(d);
                            }
                            *slot = Some(decoded);
                        } else {
                            dense.push((i, values));
                        }
                    }
                    let all: Vec<f32> = dense.iter().flat_map(|(_, v)| v.iter().copied()).collect();
                    let decoded = exp_roundtrip(&all, 3, bits);
                    for (chunk, (i, _)) in decoded.chunks(3 * b.vertices).zip(&dense) {
                        out[*i] = Some(chunk.to_vec());
                    }
                    out
                })
                .collect(),
        )
    }
}

/// The fewest mantissa bits of the exponential filter (as the writer applies it to a view of
/// these values alone) that keep every element of `values` (`components` each) within `within`
/// (Euclidean), with the values as a reader decodes them at those bits; `None` when even 24
/// bits do not.
pub fn fewest_bits(values: &[f32], components: usize, within: f64) -> Option<(i32, Vec<f32>)> {
    let fits = |bits: i32| {
        let decoded = exp_roundtrip(values, components, bits);
        let ok = values
            .chunks_exact(components)
            .zip(decoded.chunks_exact(components))
            .all(|(a, b)| {
                let d2: f64 = a
                    .iter()
                    .zip(b)
                    .map(|(x, y)| (*x as f64 - *y as f64).powi(2))
                    .sum();
                d2 <= within * within
            });
        ok.then_some(decoded)
    };
    // The rounding step halves with every bit: the first that fits, by bisection.
    let (mut lo, mut hi) = (1, 24);
    let mut best = fits(hi)?;
    while lo < hi {
        let mid = (lo + hi) / 2;
        match fits(mid) {
            Some(decoded) => (hi, best) = (mid, decoded),
            None => lo = mid + 1,
        }
    }
    Some((hi, best))
}

/// A primitive's own attribute as f32, `N` components per vertex.
fn flat<const N: usize>(values: impl Iterator<Item = [f64; N]>) -> Vec<f32> {
    values.flatten().map(|x| x as f32).collect()
}

/// How the base of each primitive is filtered (with meshopt: each attribute the writer can
/// store again, at the fewest bits within [`BASE_SHARE`] of the tolerance), and what that
/// does to each block of the frames matrix (decoded less exact, 3 per vertex, unweighted).
fn base_rounding(
    mesh: &MorphMesh,
    blocks: &[Block],
    restorable: &[Restorable],
    opts: &CompactOptions,
    (tol, ntol): (f64, f64),
) -> (Vec<BaseBits>, Vec<Option<Vec<f32>>>) {
    let mut bits = vec![BaseBits::default(); mesh.primitives.len()];
    let mut errors = vec![None; blocks.len()];
    if !opts.meshopt {
        return (bits, errors);
    }
    let rounded = |values: Vec<f32>, n: usize, within: f64| -> Option<(i32, Vec<f32>)> {
        let (b, decoded) = fewest_bits(&values, n, within)?;
        let error = values
            .chunks_exact(n)
            .zip(decoded.chunks_exact(n))
            .flat_map(|(x, y)| (0..3).map(move |i| y[i] - x[i]))
            .collect();
        Some((b, error))
    };
    // Unit vectors (and a tangent's sign) through the octahedral filter, error on x, y, z.
    let octahedral = |values: Vec<[f64; 4]>, within: f64| -> Option<(i32, Vec<f32>)> {
        let ints: Vec<i16> = values.iter().flatten().map(|&x| snorm16(x)).collect();
        (2..=16).find_map(|b| {
            let decoded = oct_roundtrip(&ints, b);
            let error: Vec<f32> = values
                .iter()
                .zip(decoded.chunks_exact(4))
                .flat_map(|(x, d)| (0..3).map(move |i| (unsnorm16(d[i]) - x[i]) as f32))
                .collect();
            let worst = error
                .chunks_exact(3)
                .map(|e| e.iter().map(|&x| (x as f64) * (x as f64)).sum::<f64>())
                .fold(0.0f64, f64::max);
            (worst.sqrt() <= within).then_some((b, error))
        })
    };
    for (bi, block) in blocks.iter().enumerate() {
        let p = &mesh.primitives[block.prim];
        let r = restorable.get(block.prim).copied().unwrap_or_default();
        let base = &mut bits[block.prim];
        let within = BASE_SHARE * ntol;
        let done = match block.attr {
            Attr::Position if r.position => {
                let done = rounded(
                    flat(p.base.iter().map(|v| v.to_array())),
                    3,
                    BASE_SHARE * tol,
                );
                base.position = done.as_ref().map(|d| d.0);
                done
            }
            Attr::Normal | Attr::Tangent => {
                let normal = block.attr == Attr::Normal;
                let vectors: Option<Vec<[f64; 4]>> = match normal {
                    true => p
                        .normals
                        .as_ref()
                        .filter(|_| r.normal)
                        .map(|n| n.iter().map(|v| [v.x, v.y, v.z, 0.0]).collect()),
                    false => p.tangents.clone().filter(|_| r.tangent),
                };
                let Some(vectors) = vectors else { continue };
                // Octahedral where every vector is a unit one, else the exponential filter.
                let oct = opts
                    .quantize
                    .then(|| octahedral(vectors.clone(), within))
                    .flatten();
                let is_oct = oct.is_some();
                let done = oct.or_else(|| match normal {
                    true => rounded(flat(vectors.iter().map(|v| [v[0], v[1], v[2]])), 3, within),
                    false => rounded(flat(vectors.iter().copied()), 4, within),
                });
                let bits = done.as_ref().map(|d| d.0);
                if normal {
                    (base.normal, base.normal_oct) = (bits, is_oct);
                } else {
                    (base.tangent, base.tangent_oct) = (bits, is_oct);
                }
                done
            }
            _ => continue,
        };
        if let Some((_, error)) = done {
            errors[bi] = Some(error);
        }
    }
    (bits, errors)
}

/// A value in [-1, 1] as a normalized i16 (as meshopt quantizes it) ...
pub fn snorm16(x: f64) -> i16 {
    (x.clamp(-1.0, 1.0) * 32767.0).round() as i16
}

/// ... and back, as a reader decodes it.
fn unsnorm16(i: i16) -> f64 {
    (i as f64 / 32767.0).max(-1.0)
}

/// What a sparse accessor adds to the JSON beside a dense one, in bytes: its indices' view and
/// the `sparse` object; with meshopt also its values' view (a dense target's values join its
/// neighbours' compressed view), whose extension object is most of it.
const SPARSE_JSON: usize = 150;
const SPARSE_JSON_MESHOPT: usize = 340;

/// Whether a sparse accessor stores `values` (x, y, z per vertex) in fewer bytes than a dense
/// one, counting the vertices whose stored value is not zero and the JSON it adds (a target that
/// moves nothing needs no data at all).
pub fn sparse_pays(values: &[f32], storage: Storage, meshopt: bool) -> bool {
    let elem = match storage {
        Storage::Float { .. } => 12,
        Storage::Short => 8,
        Storage::Byte => 4,
    };
    let nonzero = values
        .chunks_exact(3)
        .filter(|v| v.iter().any(|x| storage.stored(*x) != 0.0))
        .count();
    let n = values.len() / 3;
    let index = if n <= 65_536 { 2 } else { 4 };
    if nonzero == 0 {
        // No data at all: an accessor of zeros without a view.
        true
    } else if meshopt {
        // meshopt's attribute codec stores a run of zero deltas in about 2 bits per byte
        // column: a dense accessor costs its moving vertices plus about a quarter byte for
        // each still one, while the sparse indices go uncompressed.
        nonzero * index + SPARSE_JSON_MESHOPT < (n - nonzero) / 4
    } else {
        nonzero * (index + elem) + SPARSE_JSON < n * elem
    }
}

/// The values of `s` as a reader decodes them.
fn decode(s: &Stored) -> Vec<f32> {
    match s.storage {
        Storage::Float {
            exp_bits: Some(bits),
        } => exp_roundtrip(&s.values, 3, bits),
        storage => s.values.iter().map(|&x| storage.stored(x)).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fewest_bits_keep_every_element_within_and_one_less_does_not() {
        // UV-like values over [0, 1] and positions far from the origin.
        let uv: Vec<f32> = (0..1000)
            .map(|i| ((i * 37) % 1000) as f32 / 999.0)
            .collect();
        let far: Vec<f32> = (0..999)
            .map(|i| 100.0 + ((i * 7919) % 997) as f32 * 1e-3)
            .collect();
        for (values, n, within) in [(&uv, 2, 1e-4), (&far, 3, 1e-3), (&uv, 2, 0.2)] {
            let (bits, decoded) = fewest_bits(values, n, within).expect("24 bits are enough");
            assert_eq!(decoded, exp_roundtrip(values, n, bits));
            let err = |b: i32| {
                values
                    .chunks_exact(n)
                    .zip(exp_roundtrip(values, n, b).chunks_exact(n))
                    .map(|(a, d)| {
                        a.iter()
                            .zip(d)
                            .map(|(x, y)| (*x as f64 - *y as f64).powi(2))
                            .sum::<f64>()
                            .sqrt()
                    })
                    .fold(0.0, f64::max)
            };
            assert!(err(bits) <= within, "{bits} bits: {} > {within}", err(bits));
            assert!(
                bits == 1 || err(bits - 1) > within,
                "{bits} bits are not the fewest"
            );
        }
        // Positions near 100 need about 17 bits for 1e-3 (100 / 2^17 = 7.6e-4).
        assert!((16..=18).contains(&fewest_bits(&far, 3, 1e-3).unwrap().0));
        assert_eq!(fewest_bits(&far, 3, 1e-9), None);
    }
}
