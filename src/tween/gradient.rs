//! Per-triangle deformation gradients (ALGORITHMS.md A.1-A.2).
//!
//! For a triangle (v1, v2, v3) the frame is `V = [v2-v1, v3-v1, v4-v1]` with the fourth vertex
//! `v4 = v1 + n / sqrt(|n|)`, `n = (v2-v1) x (v3-v1)` (Sumner & Popovic 2004). The deformation
//! gradient from pose P0 to pose P1 is `T = V1 V0^-1`, split by polar decomposition `T = R S`
//! into a proper rotation R and a symmetric stretch S.
//!
//! Degenerate input never produces NaN: a zero-area reference triangle is reported as invalid
//! (it is left out of the solve); a zero-area target triangle gives a rank-deficient T whose
//! polar factors are still finite; a reflection (det T < 0) keeps R a proper rotation and puts
//! the sign into the smallest principal stretch of S, as an SVD-based polar decomposition does.

use glam::{DMat3, DQuat, DVec3};

/// A triangle is degenerate when twice its area is below this fraction of the sum of its
/// squared edge lengths (unitless; about a 1e-10 radian sliver).
pub const DEGENERATE_RATIO: f64 = 1e-10;

/// The frame matrix `V` of a triangle, or `None` when it is degenerate.
pub fn frame(a: DVec3, b: DVec3, c: DVec3) -> Option<DMat3> {
    frame_above(a, b, c, DEGENERATE_RATIO)
}

/// [`frame`] with the sliver bound `ratio` (twice the area over the sum of squared edges).
pub fn frame_above(a: DVec3, b: DVec3, c: DVec3, ratio: f64) -> Option<DMat3> {
    let e1 = b - a;
    let e2 = c - a;
    let n = e1.cross(e2);
    let len = n.length();
    let scale = e1.length_squared() + e2.length_squared() + (c - b).length_squared();
    if len.is_nan() || len <= ratio * scale {
        return None;
    }
    Some(DMat3::from_cols(e1, e2, n / len.sqrt()))
}

/// The frame of a triangle that may be degenerate (used for the deformed pose only): a
/// collapsed triangle gets a zero normal column, so T loses rank instead of becoming NaN.
#[inline]
pub fn frame_any(a: DVec3, b: DVec3, c: DVec3) -> DMat3 {
    let e1 = b - a;
    let e2 = c - a;
    let n = e1.cross(e2);
    let len = n.length();
    let col = if len > 0.0 {
        n / len.sqrt()
    } else {
        DVec3::ZERO
    };
    DMat3::from_cols(e1, e2, col)
}

/// In-plane gradient operator of a reference triangle: `g[k]` is the gradient of the linear
/// function that is 1 at corner k and 0 at the others. A piecewise-linear map x restricted to
/// the triangle has gradient `sum_k x_k g[k]^T`, and `sum_k g[k] = 0`.
/// Equals the first two rows of `V^-1` (the fourth vertex eliminated).
pub fn gradient_operator(v_inv: &DMat3) -> [DVec3; 3] {
    let t = v_inv.transpose(); // columns of t = rows of V^-1
    let w1 = t.x_axis;
    let w2 = t.y_axis;
    [-(w1 + w2), w1, w2]
}

/// Polar decomposition `T = R S`: R a proper rotation (as a unit quaternion), S symmetric.
pub fn polar(t: &DMat3) -> (DQuat, DMat3) {
    let (sigma2, v) = sym_eigen(&(t.transpose() * *t));
    // Make V a proper rotation.
    let v = if v.determinant() < 0.0 {
        DMat3::from_cols(v.x_axis, v.y_axis, -v.z_axis)
    } else {
        v
    };
    let s1 = sigma2[0].max(0.0).sqrt();
    let s2 = sigma2[1].max(0.0).sqrt();
    let scale = s1.max(1e-300);
    // U's columns: T v_i / sigma_i, completed to a right-handed basis.
    let tv1 = *t * v.x_axis;
    let u1 = if s1 > 1e-12 * scale && s1 > 0.0 {
        tv1 / s1
    } else {
        v.x_axis
    };
    let tv2 = *t * v.y_axis;
    let mut u2 = tv2 - u1 * u1.dot(tv2);
    if u2.length() <= 1e-12 * scale || s2 <= 1e-12 * scale {
        u2 = u1.any_orthonormal_vector();
        // Prefer v.y_axis's direction when it is usable, for continuity.
        let alt = v.y_axis - u1 * u1.dot(v.y_axis);
        if alt.length() > 1e-6 {
            u2 = alt.normalize();
        }
    } else {
        u2 = u2.normalize();
    }
    let u1 = u1.normalize();
    let u3 = u1.cross(u2);
    let u = DMat3::from_cols(u1, u2, u3);
    let r = u * v.transpose();
    // S = R^T T, symmetrized against round-off.
    let s = r.transpose() * *t;
    let s = (s + s.transpose()) * 0.5;
    (DQuat::from_mat3(&r).normalize(), s)
}

/// [`polar`] of a triangle's deformation gradient `t` from the reference frame inverse `v_inv`
/// (as [`deformation`] makes it), in closed form: T maps the reference triangle's plane to the
/// deformed one and its normal to the deformed normal, so in orthonormal frames of the two
/// planes it is a 2x2 block and a positive scale, and R is the 2x2 block's nearest rotation
/// (one atan2) between the frames. The same R and S as [`polar`] to round-off, without its
/// Jacobi sweeps; a collapsed deformed triangle goes to [`polar`].
pub fn polar_of_triangle(t: &DMat3, v_inv: &DMat3) -> (DQuat, DMat3) {
    polar_in_plane(t, plane_of(v_inv).as_ref())
}

/// The reference triangle's orthonormal frame `[e0, f0, n0]` that [`polar_of_triangle`] works
/// in, from its frame inverse `v_inv` (`None` where V^-1 has no usable rows): made once per
/// triangle where several keys' gradients from the same reference are decomposed.
pub fn plane_of(v_inv: &DMat3) -> Option<[DVec3; 3]> {
    // Rows of V^-1: the first lies in the reference plane, the third along its normal.
    let rows = v_inv.transpose();
    let (e0, n0) = (rows.x_axis.try_normalize()?, rows.z_axis.try_normalize()?);
    let e0 = (e0 - n0 * n0.dot(e0)).normalize();
    Some([e0, n0.cross(e0), n0])
}

/// [`polar_of_triangle`] given the reference frame [`plane_of`] makes (`None`: [`polar`]); the
/// same bits as it.
pub fn polar_in_plane(t: &DMat3, plane: Option<&[DVec3; 3]>) -> (DQuat, DMat3) {
    let Some(&[e0, f0, n0]) = plane else {
        return polar(t);
    };
    let (te, tf) = (*t * e0, *t * f0);
    let n1 = te.cross(tf);
    let len = n1.length();
    if len.is_nan() || len <= 1e-12 * (te.length_squared() + tf.length_squared()) {
        return polar(t);
    }
    let n1 = n1 / len;
    let e1 = te.normalize();
    let f1 = n1.cross(e1);
    // The 2x2 block in (e1, f1) x (e0, f0): [[|Te|, e1.Tf], [0, f1.Tf]]; its nearest rotation.
    let (sin, cos) = sin_cos((-e1.dot(tf)).atan2(te.length() + f1.dot(tf)));
    let to = DMat3::from_cols(e1 * cos + f1 * sin, f1 * cos - e1 * sin, n1);
    let r = to * DMat3::from_cols(e0, f0, n0).transpose();
    let s = r.transpose() * *t;
    (DQuat::from_mat3(&r).normalize(), (s + s.transpose()) * 0.5)
}

/// `T = Q U` with Q the rotation that takes the in-plane unit direction `e` of the reference
/// triangle (unit normal `n`) to the direction of `T e` and `n` to the deformed normal (`T n`'s
/// direction), and `U = Q^T T`: the part of T that Q leaves, shear included (not symmetric).
/// For a rotation T, Q = T and U = I, as the polar decomposition gives them; for a turned
/// surface sheared along `e` (a twisted tube, `e` around it, the shear its helix's slope) Q is
/// the turn and U the shear, which interpolates linearly, where the polar decomposition hands
/// part of the shear to the rotation. `None` where T collapses `e` or `n`.
pub fn aligned(t: &DMat3, e: DVec3, n: DVec3) -> Option<(DQuat, DMat3)> {
    let e2 = (*t * e).try_normalize()?;
    let n2 = (*t * n).try_normalize()?;
    let e2 = (e2 - n2 * n2.dot(e2)).try_normalize()?;
    let from = DMat3::from_cols(e, n.cross(e), n);
    let to = DMat3::from_cols(e2, n2.cross(e2), n2);
    let q = to * from.transpose();
    Some((DQuat::from_mat3(&q).normalize(), q.transpose() * *t))
}

/// Largest relative sideways move `U e` may make off `e` for [`around_axis`] to apply
/// (dimensionless, about 6 degrees): a twisted surface's ring edges stay on their rings (0 up to
/// round-off on the tested tubes, coarse and fat), a rotation left over after the bend and
/// the twist (a part turning its own way inside a component that twists) moves them off.
pub const AROUND_AXIS_RESIDUAL: f64 = 0.1;

/// `T = B W U` with B the rotation `bend`, W the twist about unit `axis` that takes `e` (a unit
/// direction across the axis in the reference triangle's plane) to the direction of
/// `B^-1 T e` seen along the axis, and `U = (B W)^T T`: returns W's angle in (-pi, pi] and U.
/// A twisted tube's surface (any cross-section) is turned ring by ring about its axis and
/// sheared along it, `T = W (I + d f^T)` with f the in-plane direction along the axis and d its
/// shear and tilt, linear in the twist: U is that shear whole, so interpolating W's angle and
/// U linearly follows the twist exactly, where [`aligned`] (which keeps the normal) hands an
/// elliptic tube's tilt to the rotation. `None`
/// where `B^-1 T e` lies along the axis, or where U moves `e` off its line by more than
/// [`AROUND_AXIS_RESIDUAL`] (the triangle turns some other way too: [`aligned`] serves it).
pub fn around_axis(t: &DMat3, e: DVec3, axis: DVec3, bend: DQuat) -> Option<(f64, DMat3)> {
    let turned = bend.conjugate() * (*t * e);
    let to = (turned - axis * axis.dot(turned)).try_normalize()?;
    let from = (e - axis * axis.dot(e)).try_normalize()?;
    let angle = axis.dot(from.cross(to)).atan2(from.dot(to));
    let q = DMat3::from_quat(bend * DQuat::from_axis_angle(axis, angle));
    let u = q.transpose() * *t;
    let ue = u * e;
    let off = (ue - e * e.dot(ue)).length();
    (off <= AROUND_AXIS_RESIDUAL * ue.length()).then_some((angle, u))
}

/// Eigen-decomposition of a symmetric 3x3 matrix by cyclic Jacobi rotations: eigenvalues in
/// descending order and the matching eigenvectors as the columns of the returned matrix.
pub fn sym_eigen(m: &DMat3) -> ([f64; 3], DMat3) {
    let mut a = m.to_cols_array_2d(); // a[col][row]; symmetric so indices commute
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _sweep in 0..32 {
        let off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
        let diag = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
        if off <= 1e-30 * diag || off == 0.0 {
            break;
        }
        for &(p, q) in &[(0usize, 1usize), (0, 2), (1, 2)] {
            let apq = a[p][q];
            if apq == 0.0 {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * apq);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            for col in &mut a {
                let (akp, akq) = (col[p], col[q]);
                col[p] = c * akp - s * akq;
                col[q] = s * akp + c * akq;
            }
            let (ap, aq) = (a[p], a[q]);
            a[p] = std::array::from_fn(|k| c * ap[k] - s * aq[k]);
            a[q] = std::array::from_fn(|k| s * ap[k] + c * aq[k]);
            for row in &mut v {
                let vp = row[p];
                let vq = row[q];
                row[p] = c * vp - s * vq;
                row[q] = s * vp + c * vq;
            }
        }
    }
    // v[row][col]: column j is eigenvector j.
    let mut order = [0usize, 1, 2];
    order.sort_by(|&i, &j| a[j][j].total_cmp(&a[i][i]));
    let vals = order.map(|i| a[i][i]);
    let col = |j: usize| DVec3::new(v[0][j], v[1][j], v[2][j]);
    (
        vals,
        DMat3::from_cols(col(order[0]), col(order[1]), col(order[2])),
    )
}

/// Rotation vector (axis times angle, angle in [0, pi]) of a unit quaternion.
pub fn quat_log(q: DQuat) -> DVec3 {
    let q = if q.w < 0.0 { -q } else { q };
    let xyz = DVec3::new(q.x, q.y, q.z);
    let s = xyz.length();
    if s < 1e-300 {
        return DVec3::ZERO;
    }
    let angle = 2.0 * s.atan2(q.w);
    xyz * (angle / s)
}

/// Deformation gradient of a triangle from a reference frame inverse to a deformed triangle.
#[inline]
pub fn deformation(v_inv: &DMat3, a: DVec3, b: DVec3, c: DVec3) -> DMat3 {
    frame_any(a, b, c) * *v_inv
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

/// The rotation matrix of log `r` (angle times axis).
pub fn rotation(r: DVec3) -> DMat3 {
    let angle = r.length();
    if angle > 0.0 {
        axis_angle_matrix(r / angle, angle)
    } else {
        DMat3::IDENTITY
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: &DMat3, b: &DMat3, tol: f64) -> bool {
        a.to_cols_array()
            .iter()
            .zip(b.to_cols_array())
            .all(|(x, y)| (x - y).abs() <= tol)
    }

    #[test]
    fn polar_recovers_rotation_and_stretch() {
        let r = DMat3::from_axis_angle(DVec3::new(1.0, 2.0, -0.5).normalize(), 2.7);
        let s = DMat3::from_cols(
            DVec3::new(1.5, 0.2, 0.0),
            DVec3::new(0.2, 0.7, 0.1),
            DVec3::new(0.0, 0.1, 1.1),
        );
        let (q, s2) = polar(&(r * s));
        assert!(close(&DMat3::from_quat(q), &r, 1e-10));
        assert!(close(&s2, &s, 1e-10));
    }

    #[test]
    fn polar_of_triangle_matches_polar() {
        let mut lcg = crate::dev::synth::Lcg(7);
        let mut rnd = || lcg.unit() * 2.0 - 1.0;
        let mut worst = 0.0f64;
        for case in 0..2000 {
            let p: [DVec3; 3] = std::array::from_fn(|_| DVec3::new(rnd(), rnd(), rnd()));
            let Some(v) = frame(p[0], p[1], p[2]) else {
                continue;
            };
            let v_inv = v.inverse();
            let axis = DVec3::new(rnd(), rnd(), rnd()).normalize();
            let turn = DMat3::from_axis_angle(axis, 3.0 * rnd());
            // Stretched, sheared, flattened (every 10th nearly to a line) and turned.
            let flat = if case % 10 == 0 {
                1e-6
            } else {
                1.0 + rnd() * 0.9
            };
            let stretch = DMat3::from_cols(
                DVec3::new(1.0 + 0.5 * rnd(), 0.3 * rnd(), 0.0),
                DVec3::new(0.3 * rnd(), flat, 0.2 * rnd()),
                DVec3::new(0.0, 0.1 * rnd(), 1.0 + 0.5 * rnd()),
            );
            let q: [DVec3; 3] = p.map(|x| turn * stretch * x);
            let t = deformation(&v_inv, q[0], q[1], q[2]);
            let (r1, s1) = polar(&t);
            let (r2, s2) = polar_of_triangle(&t, &v_inv);
            let dr = (DMat3::from_quat(r1) - DMat3::from_quat(r2))
                .abs()
                .to_cols_array();
            let ds = (s1 - s2).abs().to_cols_array();
            let scale = t
                .abs()
                .to_cols_array()
                .iter()
                .fold(1.0f64, |m, x| m.max(*x));
            let d = dr.iter().chain(&ds).fold(0.0f64, |m, x| m.max(*x)) / scale;
            if case % 10 != 0 {
                worst = worst.max(d);
            }
            // Nearly flattened: both finite and T = R S.
            assert!(
                close(&(DMat3::from_quat(r2) * s2), &t, 1e-9 * scale),
                "{case}"
            );
        }
        assert!(worst < 1e-10, "{worst}");
    }

    #[test]
    fn aligned_keeps_rotations_and_leaves_a_twist_s_shear_to_u() {
        let (e, n) = (DVec3::Y, DVec3::Z);
        let r = DMat3::from_quat(DQuat::from_axis_angle(
            DVec3::new(1.0, 2.0, -0.5).normalize(),
            2.5,
        ));
        let (q, u) = aligned(&r, e, n).unwrap();
        assert!(close(&DMat3::from_quat(q), &r, 1e-12) && close(&u, &DMat3::IDENTITY, 1e-12));
        // A surface along x sheared around it (a helix's slope, 1.5) and turned about x: the
        // turn comes out whole, the shear stays in U; the polar decomposition mixes them.
        let shear = DMat3::from_cols(DVec3::new(1.0, 1.5, 0.0), DVec3::Y, DVec3::Z);
        let turn = DMat3::from_rotation_x(2.0);
        let (q, u) = aligned(&(turn * shear), e, n).unwrap();
        assert!(close(&DMat3::from_quat(q), &turn, 1e-12) && close(&u, &shear, 1e-12));
        let (p, _) = polar(&(turn * shear));
        assert!(!close(&DMat3::from_quat(p), &turn, 0.1));
    }

    #[test]
    fn around_axis_leaves_a_twist_s_shear_and_tilt_to_u() {
        // A triangle facing y on a surface along x: e across the axis (z), f = n x e along it.
        let (axis, e, n) = (DVec3::X, DVec3::Z, DVec3::Y);
        let f = n.cross(e);
        // An elliptic tube's twist: the ring edge e kept, f sheared around the ring and
        // tilted out of the plane (slope 4), turned 2.5 rad about the axis after a bend.
        let sf = f + e * 4.0 + n * 1.5;
        let basis = DMat3::from_cols(e, f, n);
        let shear = DMat3::from_cols(e, sf, e.cross(sf).normalize()) * basis.transpose();
        let bend = DQuat::from_rotation_z(0.4);
        let twist = DMat3::from_axis_angle(axis, 2.5);
        let t = DMat3::from_quat(bend) * twist * shear;
        let (angle, u) = around_axis(&t, e, axis, bend).unwrap();
        assert!((angle - 2.5).abs() < 1e-12 && close(&u, &shear, 1e-12));
        // The polar and aligned decompositions both turn part of the tilt into rotation.
        let (q, _) = aligned(&(twist * shear), e, n).unwrap();
        assert!(!close(&DMat3::from_quat(q), &twist, 0.1));
        // A triangle turning about its own normal as well: refused.
        let own = DMat3::from_axis_angle(n, 0.3);
        assert!(around_axis(&(twist * own), e, axis, DQuat::IDENTITY).is_none());
    }

    #[test]
    fn polar_of_reflection_and_collapse_is_finite() {
        let refl = DMat3::from_diagonal(DVec3::new(1.0, 1.0, -1.0));
        let (q, s) = polar(&refl);
        assert!(q.is_finite() && s.is_finite());
        assert!(close(&(DMat3::from_quat(q) * s), &refl, 1e-12));
        let flat = DMat3::from_cols(DVec3::X, DVec3::ZERO, DVec3::ZERO);
        let (q, s) = polar(&flat);
        assert!(q.is_finite() && s.is_finite());
        assert!(close(&(DMat3::from_quat(q) * s), &flat, 1e-12));
        let (q, s) = polar(&DMat3::ZERO);
        assert!(q.is_finite() && s.is_finite());
    }

    #[test]
    fn log_and_exp_invert() {
        let r = DVec3::new(0.3, -1.2, 2.0);
        let q = DQuat::from_axis_angle(r.normalize(), r.length());
        assert!((quat_log(q) - r).length() < 1e-12);
    }

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
