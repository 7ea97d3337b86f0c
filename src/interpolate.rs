//! Interpolate stage: tween frames between two key poses of a welded mesh.
//!
//! * [`Method::Seed`] is ALGORITHMS.md part A as published: per triangle `T = R S`,
//!   `R(t) = exp(t log R)` (slerp from identity, shortest arc), `S(t) = (1-t) I + t S`,
//!   `T(t) = R(t) S(t)`, the vertices from the least-squares solve, and every connected
//!   component translated so its vertex centroid follows the straight line between the keys'.
//! * [`Method::Linear`] is vertex lerp (the BlendShape baseline).

use crate::gradient::{deformation, frame, gradient_operator, polar, quat_log};
use crate::solve::{scatter, Pattern, Placement};
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
    /// C1 spline across all keys in gradient space (rotation logs and stretches by cubic Hermite
    /// with C2-spline tangents, same solve; each component turns about its pivot). The default.
    Spline,
}

impl Method {
    pub fn name(self) -> &'static str {
        match self {
            Method::Seed => "seed",
            Method::Linear => "linear",
            Method::Spline => "spline",
        }
    }
}

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

/// The tween of one pair of keys, ready to produce frames.
pub enum Segment {
    Linear { x0: Vec<DVec3>, x1: Vec<DVec3> },
    Seed(Box<SeedSegment>),
    Spline(Box<crate::spline::SplineSegment>),
}

pub struct SeedSegment {
    x0: Vec<DVec3>,
    x1: Vec<DVec3>,
    triangles: Vec<TriangleTween>,
    placement: Placement,
    centroid0: Vec<DVec3>,
    centroid1: Vec<DVec3>,
}

impl Segment {
    /// Prepare the tween from `x0` to `x1` (welded positions). `pattern` is the mesh's
    /// analysed system and `triangles` its welded triangles (same order as the pattern's).
    pub fn new(
        method: Method,
        x0: Vec<DVec3>,
        x1: Vec<DVec3>,
        pattern: Option<&Pattern>,
        triangles: &[[u32; 3]],
    ) -> Result<Segment> {
        match method {
            Method::Linear => Ok(Segment::Linear { x0, x1 }),
            Method::Seed | Method::Spline => {
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
            Segment::Spline(s) => s.frame(t),
        }
    }

    /// The segment from key a to key b = a + 1 of a track (welded `keys` at `times`), for
    /// `opts.method`. `pattern` is required by `seed` and `spline`.
    pub fn for_key_pair(
        opts: &crate::tween::TweenOptions,
        keys: &[Vec<DVec3>],
        times: &[f64],
        a: usize,
        b: usize,
        pattern: Option<&Pattern>,
        triangles: &[[u32; 3]],
    ) -> Result<Segment> {
        match opts.method {
            Method::Spline if b == a + 1 => {
                let pattern = pattern.expect("the spline method needs the mesh's pattern");
                let looped = opts.wrap && crate::spline::is_loop(keys);
                let track =
                    crate::spline::SplineTrack::new(keys, times, looped, pattern, triangles)?;
                Ok(Segment::Spline(Box::new(track.segment(a)?)))
            }
            Method::Spline => Segment::new(
                Method::Seed,
                keys[a].clone(),
                keys[b].clone(),
                pattern,
                triangles,
            ),
            m => Segment::new(m, keys[a].clone(), keys[b].clone(), pattern, triangles),
        }
    }

    /// Nonzeros of the Cholesky factor used by the solves (0 for `linear`).
    pub fn factor_nonzeros(&self) -> usize {
        match self {
            Segment::Linear { .. } => 0,
            Segment::Seed(s) => s.placement.factor_nonzeros(),
            Segment::Spline(s) => s.factor_nonzeros(),
        }
    }
}

impl SeedSegment {
    fn new(
        x0: Vec<DVec3>,
        x1: Vec<DVec3>,
        pattern: &Pattern,
        triangles: &[[u32; 3]],
    ) -> Result<Self> {
        let n = x0.len();
        let per_triangle: Vec<Option<TriangleTween>> = triangles
            .par_iter()
            .map(|&[a, b, c]| {
                let v = frame(x0[a as usize], x0[b as usize], x0[c as usize])?;
                let v_inv = v.inverse();
                let g = gradient_operator(&v_inv);
                let t = deformation(&v_inv, x1[a as usize], x1[b as usize], x1[c as usize]);
                let (q, s) = polar(&t);
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
        })
    }

    fn frame(&self, t: f64) -> Vec<DVec3> {
        let mut rhs = vec![[0.0f64; 3]; self.x0.len()];
        for tri in &self.triangles {
            let r = axis_angle_matrix(tri.axis, tri.angle * t);
            // T(t) g = R(t) ((1-t) g + t S g)
            let v1 = r * (tri.g[0] * (1.0 - t) + tri.sg[0] * t);
            let v2 = r * (tri.g[1] * (1.0 - t) + tri.sg[1] * t);
            scatter(&mut rhs, tri.corners, v1, v2);
        }
        // Centroid path per component; untouched vertices follow the straight line.
        let centroids: Vec<DVec3> = self
            .centroid0
            .iter()
            .zip(&self.centroid1)
            .map(|(a, b)| a.lerp(*b, t))
            .collect();
        self.placement
            .place(rhs, &centroids, |v| self.x0[v].lerp(self.x1[v], t))
    }
}

/// Rotation matrix about a unit axis by an angle, through the half-angle quaternion.
#[inline(always)]
pub fn axis_angle_matrix(axis: DVec3, angle: f64) -> DMat3 {
    let (s, c) = sin_cos(0.5 * angle);
    let (x, y, z, w) = (axis.x * s, axis.y * s, axis.z * s, c);
    let (x2, y2, z2) = (x + x, y + y, z + z);
    let (xx, yy, zz) = (x * x2, y * y2, z * z2);
    let (xy, xz, yz) = (x * y2, x * z2, y * z2);
    let (wx, wy, wz) = (w * x2, w * y2, w * z2);
    DMat3::from_cols(
        DVec3::new(1.0 - (yy + zz), xy + wz, xz - wy),
        DVec3::new(xy - wz, 1.0 - (xx + zz), yz + wx),
        DVec3::new(xz + wy, yz - wx, 1.0 - (xx + yy)),
    )
}

/// sin and cos together, inlined: Cody-Waite reduction by pi/2 and the fdlibm kernel
/// polynomials on [-pi/4, pi/4] (error about 1 ulp for |x| < 1e5).
#[inline(always)]
pub fn sin_cos(x: f64) -> (f64, f64) {
    const PIO2_HI: f64 = 1.570_796_326_734_125_6;
    const PIO2_LO: f64 = 6.077_100_506_506_192e-11;
    // Round to nearest by the 1.5 * 2^52 trick (|x| < 2^50): no libm call.
    const ROUND: f64 = 6_755_399_441_055_744.0;
    let k = (x * std::f64::consts::FRAC_2_PI + ROUND) - ROUND;
    let r = (x - k * PIO2_HI) - k * PIO2_LO;
    let z = r * r;
    let s = r + r
        * z
        * (-1.666_666_666_666_663_2e-1
            + z * (8.333_333_333_322_49e-3
                + z * (-1.984_126_982_985_795e-4
                    + z * (2.755_731_370_707_006_8e-6
                        + z * (-2.505_076_025_340_686_3e-8 + z * 1.589_690_995_211_55e-10)))));
    let c = 1.0 - 0.5 * z
        + z * z
            * (4.166_666_666_666_66e-2
                + z * (-1.388_888_888_887_411e-3
                    + z * (2.480_158_728_947_673e-5
                        + z * (-2.755_731_435_139_066_3e-7
                            + z * (2.087_572_321_298_175e-9 + z * -1.135_964_755_778_819_5e-11)))));
    match (k as i64).rem_euclid(4) {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sin_cos_matches_libm() {
        let mut worst = 0.0f64;
        for i in -20000..=20000 {
            let x = i as f64 * 1.7e-3;
            let (s, c) = sin_cos(x);
            worst = worst.max((s - x.sin()).abs()).max((c - x.cos()).abs());
        }
        assert!(worst < 4e-16, "{worst}");
    }

    #[test]
    fn axis_angle_matrix_matches_glam() {
        let axis = DVec3::new(0.3, -0.5, 0.8).normalize();
        for angle in [0.0, 0.4, 2.0, 3.1, -1.0, 7.5] {
            let a = axis_angle_matrix(axis, angle);
            let b = DMat3::from_axis_angle(axis, angle);
            assert!(a.abs_diff_eq(b, 1e-15), "{angle}");
        }
    }
}
