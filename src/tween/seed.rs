//! The seed method (ALGORITHMS.md part A as published) between two key poses of a welded mesh:
//! per triangle `T = R S`, `R(t) = exp(t log R)` (slerp from identity, shortest arc),
//! `S(t) = (1-t) I + t S`, `T(t) = R(t) S(t)`, the vertices from the least-squares solve, and
//! every connected component translated so its vertex centroid follows the straight line
//! between the keys'.

use super::gradient::{
    axis_angle_matrix, deformation, frame_above, gradient_operator, polar_of_triangle, quat_log,
};
use super::solve::{in_order, scatter, Pattern, Placement};
use super::spline::hermite_beyond;
use anyhow::Result;
use glam::DVec3;
use rayon::prelude::*;

/// Reference triangles thinner than this are left out of the seed's solve (twice the area over
/// the sum of squared edges, unitless, as [`super::gradient::DEGENERATE_RATIO`]: a height below
/// about 2e-6 of the triangle's size). Such slivers (an eyelid closed onto its lower lid in a
/// blink key, its corners float32 steps apart) weigh 1/height^2 in the unweighted system and
/// left it indefinite or ill-conditioned: "the system is not positive definite", or keys 0.04
/// off on a 3-unit sheet. The spline weighs each term by its area and keeps the bound of
/// [`super::gradient::frame`].
const SLIVER_RATIO: f64 = 1e-6;

/// What a seed segment keeps per valid triangle to assemble a frame's right-hand side.
struct TriangleTween {
    corners: [u32; 3],
    /// Unit rotation axis of R and its angle in [0, pi] (shortest arc, as the seed's slerp).
    axis: DVec3,
    angle: f64,
    /// Gradient operator of the reference triangle at corners 1 and 2 (corner 0's is minus
    /// their sum).
    g: [DVec3; 2],
    /// S applied to each of them.
    sg: [DVec3; 2],
}

impl TriangleTween {
    fn gradients(&self) -> [DVec3; 3] {
        [-(self.g[0] + self.g[1]), self.g[0], self.g[1]]
    }
}

pub struct SeedSegment {
    x0: Vec<DVec3>,
    x1: Vec<DVec3>,
    triangles: Vec<TriangleTween>,
    placement: Placement,
    centroid0: Vec<DVec3>,
    centroid1: Vec<DVec3>,
    /// A clip's pace between the keys (see [`SeedSegment::paced`]), or none: its own.
    pace: Option<[f64; 2]>,
}

impl SeedSegment {
    pub fn new(
        x0: Vec<DVec3>,
        x1: Vec<DVec3>,
        pattern: &Pattern,
        triangles: &[[u32; 3]],
    ) -> Result<Self> {
        let n = x0.len();
        let per_triangle: Vec<Option<TriangleTween>> = triangles
            .par_iter()
            .map(|&[a, b, c]| {
                let v = frame_above(x0[a as usize], x0[b as usize], x0[c as usize], SLIVER_RATIO)?;
                let v_inv = v.inverse();
                let g = gradient_operator(&v_inv);
                let t = deformation(&v_inv, x1[a as usize], x1[b as usize], x1[c as usize]);
                let (q, s) = polar_of_triangle(&t, &v_inv);
                let r = quat_log(q);
                let angle = r.length();
                let axis = if angle > 0.0 { r / angle } else { DVec3::X };
                Some(TriangleTween {
                    corners: [a, b, c],
                    axis,
                    angle,
                    g: [g[1], g[2]],
                    sg: [s * g[1], s * g[2]],
                })
            })
            .collect();
        let valid: Vec<[u32; 3]> = per_triangle.iter().flatten().map(|t| t.corners).collect();
        let placement = Placement::new(
            pattern,
            n,
            per_triangle
                .iter()
                .map(|t| t.as_ref().map(TriangleTween::gradients)),
            &valid,
        )?;
        let (centroid0, centroid1) = (placement.centroids(&x0), placement.centroids(&x1));
        Ok(SeedSegment {
            x0,
            x1,
            triangles: per_triangle.into_iter().flatten().collect(),
            placement,
            centroid0,
            centroid1,
            pace: None,
        })
    }

    /// The segment taken at a clip's pace: the frame at `t` is the seed's at `s(t)`, the cubic
    /// Hermite from 0 to 1 with `slopes` (per unit of t) at its ends, and past them the line
    /// along the end's slope (see [`hermite_beyond`]). For an eased segment these are the
    /// slopes of the clip's blend along the keys' chord (see `segment::Eases`): zero tangents
    /// give an ease out and in (`s = 3t^2 - 2t^3`), the chord's slopes the seed's own pace.
    pub fn paced(self, slopes: [f64; 2]) -> SeedSegment {
        SeedSegment {
            pace: Some(slopes),
            ..self
        }
    }

    /// Where on the seed's path from key a to b the frame at `t` lies.
    fn at(&self, t: f64) -> f64 {
        match self.pace {
            Some([ma, mb]) => {
                let w = hermite_beyond(t, true);
                w[1] * ma + w[2] + w[3] * mb
            }
            None => t,
        }
    }

    pub fn factor_nonzeros(&self) -> usize {
        self.placement.factor_nonzeros()
    }

    /// The segment's solve, once its frames are done (see [`Placement::recycle`]).
    pub fn into_placement(self) -> Placement {
        self.placement
    }

    pub fn frame(&self, t: f64) -> Vec<DVec3> {
        let t = self.at(t);
        let (rhs, centroids) = self.system(t);
        self.placement
            .place(rhs, &centroids, |v| self.x0[v].lerp(self.x1[v], t))
    }

    /// The frames at `ts`, their solves sharing passes over the factor (see
    /// [`Placement::place_block`]): the same positions as [`SeedSegment::frame`] at each.
    pub fn frames(&self, ts: &[f64]) -> Vec<Vec<DVec3>> {
        let ts: Vec<f64> = ts.iter().map(|&t| self.at(t)).collect();
        let (rhs, centroids): (Vec<_>, Vec<_>) = ts.iter().map(|&t| self.system(t)).unzip();
        self.placement
            .place_block(rhs, &centroids, |f, v| self.x0[v].lerp(self.x1[v], ts[f]))
    }

    /// The right-hand side of frame `t` and its components' centroids.
    fn system(&self, t: f64) -> (Vec<[f64; 3]>, Vec<DVec3>) {
        let mut rhs = vec![[0.0f64; 3]; self.x0.len()];
        in_order(
            self.triangles.len(),
            |k| {
                let tri = &self.triangles[k];
                let r = axis_angle_matrix(tri.axis, tri.angle * t);
                // T(t) g = R(t) ((1-t) g + t S g)
                let v1 = r * (tri.g[0] * (1.0 - t) + tri.sg[0] * t);
                let v2 = r * (tri.g[1] * (1.0 - t) + tri.sg[1] * t);
                (v1, v2)
            },
            |k, (v1, v2)| scatter(&mut rhs, self.triangles[k].corners, v1, v2),
        );
        // Centroid path per component; untouched vertices follow the straight line.
        let centroids: Vec<DVec3> = self
            .centroid0
            .iter()
            .zip(&self.centroid1)
            .map(|(a, b)| a.lerp(*b, t))
            .collect();
        (rhs, centroids)
    }
}
