//! Interpolate stage: tween frames between two key poses of a welded mesh.
//!
//! * [`Method::Seed`] is ALGORITHMS.md part A as published: per triangle `T = R S`,
//!   `R(t) = exp(t log R)` (slerp from identity, shortest arc), `S(t) = (1-t) I + t S`,
//!   `T(t) = R(t) S(t)`, the vertices from the least-squares solve, and every connected
//!   component translated so its vertex centroid follows the straight line between the keys'.
//! * [`Method::Linear`] is vertex lerp (the BlendShape baseline).

use crate::gradient::{deformation, frame, gradient_operator, polar, quat_log, rotvec_matrix};
use crate::solve::{components, Factor, Pattern};
use anyhow::Result;
use glam::{DMat3, DVec3};
use rayon::prelude::*;

/// Interpolation method (`--method`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Method {
    /// The seed paper's method: polar decomposition, slerp, linear stretch, Poisson solve.
    Seed,
    /// Vertex lerp between consecutive keys (BlendShape baseline).
    Linear,
}

impl Method {
    pub fn name(self) -> &'static str {
        match self {
            Method::Seed => "seed",
            Method::Linear => "linear",
        }
    }
}

/// What a seed segment keeps per valid triangle to assemble a frame's right-hand side.
struct TriangleTween {
    corners: [u32; 3],
    /// log of the rotation factor R (axis times angle, angle in [0, pi]).
    rotation: DVec3,
    /// Gradient operator of the reference triangle.
    g: [DVec3; 3],
    /// S applied to each g.
    sg: [DVec3; 3],
}

/// The tween of one pair of keys, ready to produce frames.
pub enum Segment<'p> {
    Linear { x0: Vec<DVec3>, x1: Vec<DVec3> },
    Seed(Box<SeedSegment<'p>>),
}

pub struct SeedSegment<'p> {
    x0: Vec<DVec3>,
    x1: Vec<DVec3>,
    triangles: Vec<TriangleTween>,
    factor: Factor<'p>,
    component: Vec<u32>,
    centroid0: Vec<DVec3>,
    centroid1: Vec<DVec3>,
    component_size: Vec<usize>,
}

impl<'p> Segment<'p> {
    /// Prepare the tween from `x0` to `x1` (welded positions). `pattern` is the mesh's
    /// analysed system and `triangles` its welded triangles (same order as the pattern's).
    pub fn new(
        method: Method,
        x0: Vec<DVec3>,
        x1: Vec<DVec3>,
        pattern: Option<&'p Pattern>,
        triangles: &[[u32; 3]],
    ) -> Result<Segment<'p>> {
        match method {
            Method::Linear => Ok(Segment::Linear { x0, x1 }),
            Method::Seed => {
                let pattern = pattern.expect("the seed method needs the mesh's pattern");
                Ok(Segment::Seed(Box::new(SeedSegment::new(
                    x0, x1, pattern, triangles,
                )?)))
            }
        }
    }

    /// The frame at `t` in [0, 1] (or beyond, to extrapolate).
    pub fn frame(&self, t: f64) -> Vec<DVec3> {
        match self {
            Segment::Linear { x0, x1 } => x0.iter().zip(x1).map(|(a, b)| a.lerp(*b, t)).collect(),
            Segment::Seed(s) => s.frame(t),
        }
    }
}

impl<'p> SeedSegment<'p> {
    fn new(
        x0: Vec<DVec3>,
        x1: Vec<DVec3>,
        pattern: &'p Pattern,
        triangles: &[[u32; 3]],
    ) -> Result<Self> {
        let n = x0.len();
        let per_triangle: Vec<Option<TriangleTween>> = triangles
            .par_iter()
            .map(|&[a, b, c]| {
                let (pa, pb, pc) = (x0[a as usize], x0[b as usize], x0[c as usize]);
                let v = frame(pa, pb, pc)?;
                let v_inv = v.inverse();
                let g = gradient_operator(&v_inv);
                let t = deformation(&v_inv, x1[a as usize], x1[b as usize], x1[c as usize]);
                let (q, s) = polar(&t);
                Some(TriangleTween {
                    corners: [a, b, c],
                    rotation: quat_log(q),
                    g,
                    sg: g.map(|gk| s * gk),
                })
            })
            .collect();
        let grads: Vec<Option<[DVec3; 3]>> = per_triangle
            .iter()
            .map(|t| t.as_ref().map(|t| t.g))
            .collect();
        let valid: Vec<[u32; 3]> = per_triangle.iter().flatten().map(|t| t.corners).collect();
        let (component, count) = components(n, &valid);
        // Pin the first vertex of every component, and every vertex no valid triangle touches.
        let mut pinned = vec![false; n];
        let mut seen = vec![false; count];
        for v in 0..n {
            match component[v] {
                u32::MAX => pinned[v] = true,
                c if !seen[c as usize] => {
                    seen[c as usize] = true;
                    pinned[v] = true;
                }
                _ => {}
            }
        }
        let factor = Factor::new(pattern, &grads, pinned)?;
        let mut centroid0 = vec![DVec3::ZERO; count];
        let mut centroid1 = vec![DVec3::ZERO; count];
        let mut component_size = vec![0usize; count];
        for v in 0..n {
            if let Some(c) = label(&component, v) {
                centroid0[c] += x0[v];
                centroid1[c] += x1[v];
                component_size[c] += 1;
            }
        }
        for c in 0..count {
            centroid0[c] /= component_size[c] as f64;
            centroid1[c] /= component_size[c] as f64;
        }
        Ok(SeedSegment {
            x0,
            x1,
            triangles: per_triangle.into_iter().flatten().collect(),
            factor,
            component,
            centroid0,
            centroid1,
            component_size,
        })
    }

    fn frame(&self, t: f64) -> Vec<DVec3> {
        let n = self.x0.len();
        let mut rhs = vec![0.0f64; 3 * n];
        for tri in &self.triangles {
            let r: DMat3 = rotvec_matrix(tri.rotation * t);
            for k in 0..3 {
                // T(t) g = R(t) ((1-t) g + t S g)
                let v = r * (tri.g[k] * (1.0 - t) + tri.sg[k] * t);
                let i = tri.corners[k] as usize;
                rhs[i] += v.x;
                rhs[n + i] += v.y;
                rhs[2 * n + i] += v.z;
            }
        }
        for (v, &p) in self.factor.pinned.iter().enumerate() {
            if p {
                rhs[v] = 0.0;
                rhs[n + v] = 0.0;
                rhs[2 * n + v] = 0.0;
            }
        }
        self.factor.solve(&mut rhs);
        let mut out: Vec<DVec3> = (0..n)
            .map(|i| DVec3::new(rhs[i], rhs[n + i], rhs[2 * n + i]))
            .collect();
        // Centroid path per component; untouched vertices follow the straight line.
        let mut sum = vec![DVec3::ZERO; self.centroid0.len()];
        for (v, p) in out.iter().enumerate() {
            if let Some(c) = label(&self.component, v) {
                sum[c] += *p;
            }
        }
        let shift: Vec<DVec3> = (0..sum.len())
            .map(|c| {
                self.centroid0[c].lerp(self.centroid1[c], t)
                    - sum[c] / self.component_size[c] as f64
            })
            .collect();
        for (v, p) in out.iter_mut().enumerate() {
            match label(&self.component, v) {
                Some(c) => *p += shift[c],
                None => *p = self.x0[v].lerp(self.x1[v], t),
            }
        }
        out
    }
}

fn label(component: &[u32], v: usize) -> Option<usize> {
    match component[v] {
        u32::MAX => None,
        c => Some(c as usize),
    }
}
