//! The `spline` method: C1 interpolation across all keys in gradient space.
//!
//! For the segment from key a to key b = a + 1, every triangle's deformation gradient from key
//! a to the keys around the segment (see [`WINDOW`]) is split into rotation and stretch (as the
//! seed does for b alone). The rotation logs (relative to key a, whose own log is 0) and the
//! stretches (key a's is I) are interpolated with a cubic Hermite between a and b whose end
//! tangents are those of the C2 cubic spline through the window's keys (non-uniform in time),
//! so the motion is C1 across keys; positions come from the same Poisson solve as the seed's.
//! Against Catmull-Rom's tangents (the neighbours' differences), held-out keys of the
//! morph-keyframe birds (`inbetween eval`) come out 32% / 24% closer on Flamingo at step 2 / 3
//! and 7% closer on Parrot at step 2, 1.2% further at step 3 (four keys per wing beat).
//!
//! Twists: a component that turns past half a turn, or one way on the whole (see
//! [`SPLIT_ABOVE`], [`COHERENT`]), interpolates each triangle's rotation as a bend, a twist
//! about the component's axis (a limb's own length, or on a bent limb its centreline where the
//! triangle lies, see [`local_axes`]) and a swing; its vertices' own turns about that axis
//! (the twist field, see [`Field`]) keep the edges between rings turned far apart on their
//! chords, so a twist comes out right at any tessellation.
//!
//! Paths: every connected component turns about a pivot (the point its mean rotation from key
//! a to the keys next to the segment leaves in place, least squares), which itself follows the
//! spline; its centroid c(u) = p(u) + R(u) (c_a - p), with R(u) the component's area-weighted
//! mean log interpolated like the triangles'. An arm swinging about the shoulder moves on the
//! arc, a rigid motion follows its screw, and the keys' centroids are met exactly. Where a
//! component is split into twists and swings and does not turn as one, its centroid is the sum
//! of its triangles' own screws instead (see [`Screw`]): a limb bending at a joint keeps its
//! upper part still.
//!
//! Ends: the first and last key of a track that does not loop take their chord's slope (the
//! tangent a mirrored neighbour would give). A looping track (last key equal to the first)
//! wraps around. Rotation branches across keys: each further key's log is taken on the branch
//! (angle + 2 pi k about its axis) closest to the linear continuation of the two keys inside
//! it, outward from the segment's own log.

use super::clock::{self, Part};
use super::gradient::{
    aligned, around_axis, deformation, frame, gradient_operator, plane_of, polar_in_plane,
    polar_of_triangle, quat_log, rotation, sin_cos, sym_eigen,
};
use super::solve::{in_order, scatter, Pattern, Placement, MAX_BLOCK};
use super::weld::{bbox_diagonal, rms_rel};
use anyhow::Result;
use glam::{DMat3, DQuat, DVec3, Vec3};
use rayon::prelude::*;
use std::f64::consts::PI;

/// A rotation below this angle (radians) counts as none when its branch is chosen: its axis is
/// the noise of single-precision positions (about 1e-7 relative).
const NO_TURN: f64 = 1e-5;

/// A component more than [`SPLIT_AREA`] of which turns by more than this (radians, from key a
/// to b) interpolates its rotations as a twist about the component's axis (see
/// [`Components::axis`]) after a swing (see [`twist_swing`]); below it, as logs (the same to
/// second order, and measured a little better on the morph-keyframe birds), unless it turns
/// [`COHERENT`]ly.
const SPLIT_ABOVE: f64 = std::f64::consts::PI;

/// Share of a component's area that must turn past [`SPLIT_ABOVE`] for it to split: a few
/// triangles folded at a sharp elbow turn by about 180 degrees either side of it by chance of
/// round-off (the bench's 4M tube: 4e-6 of its area at 3.144 rad, the 1M tube of the same shape
/// at 3.142 below it), and split the component (window 5.9 -> 2.0 s at 4M) where the same shape
/// at another resolution does not. A twisted tube's far end past 180 degrees is a share of its
/// length.
const SPLIT_AREA: f64 = 0.01;

/// A component whose area-weighted mean rotation log to b is longer than this fraction of its
/// largest triangle's, and whose largest turns past [`COHERENT_ABOVE`], is split as one past
/// [`SPLIT_ABOVE`] is: it turns on the whole one way (a twisted limb or tube: its mean is
/// about half its largest turn), so a twist about its axis is defined, and the shear a twist
/// puts on its surface then stays out of the rotation (see [`around_axis`]). Flapping wings
/// turn both ways: the morph-keyframe birds' means are 0.02-0.17 of their largest turns.
const COHERENT: f64 = 0.25;

/// Below this turn (radians, about 17 degrees) a coherent component stays on the logs: the
/// twist's shear is small there (the tested tubes are within 0.005 of the diagonal either way).
const COHERENT_ABOVE: f64 = 0.3;

/// A straight limb (see [`limb_axes`]) is at least this much longer than wide, in the variance
/// of its triangles' centres (about 4.5 times in extent): the tested arm (12 x 1) is 96, a
/// short fat tube (2 x 2) under 1.
const LIMB_ELONGATION: f64 = 20.0;

/// A straight limb's sides face across its length within this on average (|n . axis|, about
/// 1.1 degrees): 0 to round-off on a straight tube, 0.075-0.16 on the tested arm bent 15-30
/// degrees or twisted in key a.
const LIMB_STRAIGHT: f64 = 0.02;

/// A straight limb's length is its twist axis only where its triangles' rotation axes lie
/// within 45 degrees of it (cosine): a limb that twists (the tested arm's rotation axes lean
/// 10-34 degrees towards its bend); one that only bends turns about an axis across it, which
/// stays its axis (taking that bend as the cross-section's swing lost 1.2% of tube_bend's
/// volume in between, against 0.3%).
const TWIST_ALONG_LIMB: f64 = std::f64::consts::FRAC_1_SQRT_2;

/// A split component's triangle whose normal makes less than asin(0.1), about 6 degrees, with
/// the twist axis faces along it (a tube's cap): its rotation is taken by the polar
/// decomposition, as the direction across the axis in its plane is not defined there.
const ALONG_AXIS: f64 = 0.1;

/// Half the width of the cross-section over which a split component's bend is averaged
/// (see [`Build::bends`]), as a fraction of the component's extent along its twist axis: 3% of
/// a limb's length covers one to three rings of the tested arms (30 to 120 rings); 8% measured
/// about the same.
const CROSS_SECTION: f64 = 0.03;

/// Pull of a split triangle's screw pivot (see [`Screw`]) towards its centre (dimensionless,
/// against |I - B|^2 of its bends): a bend under about 0.1 rad moves its centre nearly along
/// the line between the keys' (the arm's and tube_bend's middle frames move by under 1e-3 of
/// the diagonal from 1e-6 to 0.1).
const SCREW_PULL: f64 = 0.01;

/// A triangle's corners' turns about its cross-section's axis line are measured (see
/// [`Build::vertex_twists`]) only where each corner's distance from the line changes by at
/// most this fraction of the farthest corner's at every key: a twist keeps them (0 to
/// round-off on the tested tubes and arms; the skinned elbow's compression moves them by a
/// few percent), a part moving some other way does not (SimpleMorph's one triangle: 0.53 ->
/// 0.97).
const FIELD_RADIAL: f64 = 0.1;

/// Weight each triangle's term by its reference area.
const WEIGHTED: bool = true;

/// Pull of a component's pivot towards its centroid (dimensionless, against |I - R|^2 of its
/// rotations): keeps the system solvable for a component that does not turn; small enough not
/// to move the pivot of a 0.1-degree turn.
const PIVOT_PULL: f64 = 1e-12;

/// A component turns as one when its triangles' rotation logs from key a to b scatter (area-
/// weighted RMS about their mean) by at most this fraction of the mean's angle: its centroid
/// follows the pivot path ...
const RIGID_SPREAD: f64 = 0.05;
/// ... and not at all from this fraction on (a flapping bird's body has no one rotation: its
/// centroid follows the spline through the keys' centroids); smoothly between.
const LOOSE_SPREAD: f64 = 0.25;

/// Keys on each side of a key that set its tangent: the tangent of the C2 cubic spline through
/// the 2 WINDOW + 1 keys centred on it, the window's ends (and the track's) taking their
/// chord's slope. A key's pull on the tangent falls by 2 - sqrt(3) = 0.27 per key between;
/// three keys each side instead of two moved the birds' held-out errors by under 5% (either
/// way) and cost two more polar decompositions per triangle and segment.
const WINDOW: usize = 2;
/// Keys in a segment's window: WINDOW before a, a, b and WINDOW after b.
const MAX_WINDOW: usize = 2 * WINDOW + 2;

/// The keys around a segment and how its end tangents follow from their values.
struct Window {
    /// Keys (indices into the track) and their times, unrolled across a loop's seam.
    keys: Vec<usize>,
    times: Vec<f64>,
    /// Position of key a (key b follows it).
    a: usize,
    /// Coefficients over the window's values of the segment's tangents at a and at b, per unit
    /// of its parameter u (h m, h = t_b - t_a and m the derivative in time).
    tangents: [Vec<f64>; 2],
}

impl Window {
    /// sum_j coef_j value(j).
    fn combine<T>(&self, coef: &[f64], value: impl Fn(usize) -> T) -> T
    where
        T: std::ops::Mul<f64, Output = T> + std::ops::Add<Output = T>,
    {
        let mut terms = coef.iter().enumerate().map(|(j, &c)| value(j) * c);
        let first = terms.next().expect("a window holds keys a and b");
        terms.fold(first, |s, x| s + x)
    }

    /// A quantity known at the window's keys (`value(j)`) as a segment stores it: `[tangent at
    /// a, value at b, tangent at b]` (its value at a is the caller's).
    fn ends<T>(&self, value: impl Fn(usize) -> T) -> [T; 3]
    where
        T: std::ops::Mul<f64, Output = T> + std::ops::Add<Output = T>,
    {
        let [ta, tb] = &self.tangents;
        [
            self.combine(ta, &value),
            value(self.a + 1),
            self.combine(tb, &value),
        ]
    }
}

/// Weights over the values at knots `t` of the derivative at knot `at` of the C2 cubic spline
/// through them: inner knots satisfy h_i m_(i-1) + 2 (h_(i-1) + h_i) m_i + h_(i-1) m_(i+1) =
/// 3 (h_i d_(i-1) + h_(i-1) d_i), h the spans and d the chords' slopes; the end knots take
/// their chord's slope.
fn tangent_weights(t: &[f64], at: usize) -> Vec<f64> {
    let n = t.len();
    let h: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    // Rows of A (tridiagonal, diagonally dominant) and of B, A m = B v.
    let mut a = vec![[0.0f64; 3]; n];
    let mut b = vec![vec![0.0f64; n]; n];
    for i in 0..n {
        if i == 0 || i == n - 1 {
            let s = if i == 0 { 0 } else { n - 2 };
            a[i][1] = 1.0;
            b[i][s] = -1.0 / h[s];
            b[i][s + 1] = 1.0 / h[s];
        } else {
            let (hp, hn) = (h[i - 1], h[i]);
            a[i] = [hn, 2.0 * (hp + hn), hp];
            b[i][i - 1] = -3.0 * hn / hp;
            b[i][i] = 3.0 * (hn / hp - hp / hn);
            b[i][i + 1] = 3.0 * hp / hn;
        }
    }
    // Thomas algorithm on every column of B at once.
    for i in 1..n {
        let f = a[i][0] / a[i - 1][1];
        a[i][1] -= f * a[i - 1][2];
        let above = b[i - 1].clone();
        for (x, y) in b[i].iter_mut().zip(above) {
            *x -= f * y;
        }
    }
    let mut m = vec![vec![0.0f64; n]; n];
    for i in (0..n).rev() {
        let below = if i + 1 < n {
            m[i + 1].clone()
        } else {
            vec![0.0; n]
        };
        for j in 0..n {
            m[i][j] = (b[i][j] - a[i][2] * below[j]) / a[i][1];
        }
    }
    m.swap_remove(at)
}

/// Put the values of a window's keys other than a and b (`v[a]`, `v[a + 1]`) on the branch
/// `nearest` picks closest to the linear continuation of their two inner neighbours, outward
/// from the segment; `t` the keys' times.
fn unroll<T>(v: &mut [T], t: &[f64], a: usize, nearest: impl Fn(T, T) -> T)
where
    T: Copy
        + std::ops::Mul<f64, Output = T>
        + std::ops::Add<Output = T>
        + std::ops::Sub<Output = T>,
{
    for i in a + 2..v.len() {
        let s = (t[i] - t[i - 1]) / (t[i - 1] - t[i - 2]);
        v[i] = nearest(v[i], v[i - 1] + (v[i - 1] - v[i - 2]) * s);
    }
    for i in (0..a).rev() {
        let s = (t[i + 1] - t[i]) / (t[i + 2] - t[i + 1]);
        v[i] = nearest(v[i], v[i + 1] + (v[i + 1] - v[i + 2]) * s);
    }
}

/// All keys of a track (welded positions) and their times.
pub struct SplineTrack<'a> {
    keys: &'a [Vec<DVec3>],
    times: &'a [f64],
    looped: bool,
    pattern: &'a Pattern,
    triangles: &'a [[u32; 3]],
    /// Whether the track is a segment's two keys with a pose a short step outside each (see
    /// [`SplineTrack::stepped_ends`]).
    stepped_ends: bool,
}

/// Per valid triangle of a segment. Held in single precision (172 bytes with its `Option`
/// instead of 336: at 4M triangles 0.69 GB instead of 1.34 GB through every frame), as the
/// output's vertices are; computed and used in double precision.
struct Tri {
    corners: [u32; 3],
    /// Rotation logs relative to key a (whose own is zero): the tangent at a, b's log, the
    /// tangent at b (per unit of u, see [`hermite`]).
    r: [Vec3; 3],
    /// Gradient operator at corners 1 and 2 of the reference triangle (corner 0: minus sum).
    g: [Vec3; 2],
    /// S g for both gradients and S the stretch's tangent at a, b's stretch, its tangent at b
    /// (key a's stretch is I; where the rotation is taken across a twist, see [`Build::across`],
    /// S is the U of [`around_axis`] or of [`aligned`], less the twist field's part, see
    /// [`Field`]; I along a limb, whose stretch is then taken after the twist).
    sg: [[Vec3; 2]; 3],
    /// Where the component is split (see [`SPLIT_ABOVE`]): the twist about `axis` (tangent at
    /// a, b's angle with any number of turns, tangent at b), `r` then holding the swings' logs;
    /// otherwise `axis` is zero and `r` the rotations' logs.
    twist: [f32; 3],
    axis: Vec3,
}

impl Tri {
    /// b's rotation log (its swing where the component is split).
    fn log_b(&self) -> DVec3 {
        self.r[1].as_dvec3()
    }

    fn split(&self) -> bool {
        self.axis != Vec3::ZERO
    }
}

/// A component's path; each `[a, tangent at a, b, tangent at b]` (see [`hermite`]).
struct Path {
    centroid: DVec3,
    pivot: [DVec3; 4],
    /// Mean rotation log relative to key a (a's own is zero): `[tangent at a, b, tangent at b]`.
    log: [DVec3; 3],
    /// Centroids (the path of a component that does not turn as one).
    centroids: [DVec3; 4],
    /// How far the pivot path is followed, 0 to 1 (see [`RIGID_SPREAD`], [`LOOSE_SPREAD`]).
    rigid: f64,
    /// Where the component splits: its triangles' screw pivots (see [`Screw`]), summed and
    /// divided by their weight, as `[a, tangent at a, b, tangent at b]`, and that weight; the
    /// path it then follows where its triangles do not turn as one, instead of `centroids`.
    screw: Option<([DVec3; 4], f64)>,
    /// Whether the component twists about its limb's length (see [`limb_axes`]): its screws
    /// then turn with the bend alone.
    limb: bool,
}

pub struct SplineSegment {
    tris: Vec<Option<Tri>>,
    /// Where a component splits, each triangle's bend (see [`Build::bends`]) as a rotation log
    /// applied after its twist: tangent at a, b's, tangent at b (a's is zero); empty elsewhere
    /// (beside the triangles rather than in them: only split components pay for it).
    bends: Vec<[Vec3; 3]>,
    placement: Placement,
    paths: Vec<Path>,
    /// Where a component splits, each triangle's screw offset (see [`Screw`]); empty elsewhere.
    offsets: Vec<Vec3>,
    /// Where a component splits, its twist field (see [`Field`]); empty elsewhere.
    field: Field,
    /// Positions of a and b, for vertices no valid triangle touches.
    x: [Vec<DVec3>; 2],
    /// Whether frames past the ends go on straight (see [`hermite_beyond`]).
    straight_beyond: bool,
}

/// The rotation with log `r` as a twist about `axis` after a swing: R = twist(angle) swing,
/// the swing's axis across `axis`; the twist angle in (-2 pi, 2 pi], the caller choosing its
/// whole turns so that they agree across neighbouring triangles. A part turned by nearly 360
/// degrees, whose own rotation axis the shear of its neighbours tilts anywhere, then keeps a
/// twist near 360 degrees about `axis` and a small swing, so it passes 180 degrees about
/// `axis` half way.
fn twist_swing(r: DVec3, axis: DVec3) -> (f64, DVec3) {
    let q = glam::DQuat::from_scaled_axis(r);
    match twist_of(q, axis) {
        Some(twist) => {
            let along = q.xyz().dot(axis);
            (2.0 * along.atan2(q.w), quat_log(twist.conjugate() * q))
        }
        // A half-turn swing: no twist can be told apart.
        None => (0.0, r),
    }
}

/// The twist about unit `axis` of rotation `q` (the same whichever side of it the swing is
/// taken), `None` for a half-turn swing.
fn twist_of(q: glam::DQuat, axis: DVec3) -> Option<glam::DQuat> {
    let along = q.xyz().dot(axis);
    let norm = (q.w * q.w + along * along).sqrt();
    (norm >= 1e-12)
        .then(|| glam::DQuat::from_xyzw(axis.x * along, axis.y * along, axis.z * along, q.w) / norm)
}

/// The swing of the rotation with log `r` taken after its twist about `axis` (R = swing
/// twist): the swing in the deformed key's frame, as a limb's bend at a joint is.
fn swing_after_twist(r: DVec3, axis: DVec3) -> DVec3 {
    let q = glam::DQuat::from_scaled_axis(r);
    twist_of(q, axis).map_or(DVec3::ZERO, |twist| quat_log(q * twist.conjugate()))
}

/// `angle` plus the whole turns that bring it nearest to `target`.
fn nearest_turn(angle: f64, target: f64) -> f64 {
    angle + 2.0 * PI * ((target - angle) / (2.0 * PI)).round()
}

/// The centroid of the triangle with `corners` at positions `x`.
fn centroid(corners: [u32; 3], x: &[DVec3]) -> DVec3 {
    corners.map(|v| x[v as usize]).iter().sum::<DVec3>() / 3.0
}

/// The number of valid triangles at each vertex.
fn degrees(per: &[Option<Tri>], vertices: usize) -> Vec<u32> {
    let mut deg = vec![0u32; vertices];
    for tri in per.iter().flatten() {
        for v in tri.corners {
            deg[v as usize] += 1;
        }
    }
    deg
}

/// A triangle's corners `p` seen from the line through `centre` along unit `axis` (see
/// [`Field`]): each corner's foot on the line, its offset across the line and that offset
/// turned a quarter about the axis, so that a corner turned by delta about the line is
/// `foot + cos(delta) offset + sin(delta) quarter`.
#[derive(Clone, Copy)]
struct TwistLine {
    foot: [DVec3; 3],
    offset: [DVec3; 3],
    quarter: [DVec3; 3],
}

impl TwistLine {
    fn new(p: [DVec3; 3], centre: DVec3, axis: DVec3) -> TwistLine {
        let offset = p.map(|p| {
            let d = p - centre;
            d - axis * axis.dot(d)
        });
        TwistLine {
            foot: std::array::from_fn(|k| p[k] - offset[k]),
            offset,
            quarter: offset.map(|o| axis.cross(o)),
        }
    }

    /// The deformation gradient (reference frame inverse `v_inv`) taking the triangle to its
    /// corners each turned by `delta` (radians) about the line.
    fn gradient(&self, v_inv: &DMat3, delta: [f64; 3]) -> DMat3 {
        let q: [DVec3; 3] = std::array::from_fn(|k| {
            let (sin, cos) = sin_cos(delta[k]);
            self.foot[k] + self.offset[k] * cos + self.quarter[k] * sin
        });
        deformation(v_inv, q[0], q[1], q[2])
    }
}

/// Cubic Hermite basis at u in [0, 1]: the weights of the value at a, the tangent at a, the
/// value at b and the tangent at b (tangents per unit of u).
pub(super) fn hermite(u: f64) -> [f64; 4] {
    let (u2, u3) = (u * u, u * u * u);
    [
        2.0 * u3 - 3.0 * u2 + 1.0,
        u3 - 2.0 * u2 + u,
        -2.0 * u3 + 3.0 * u2,
        u3 - u2,
    ]
}

/// [`hermite`] at u, or where `straight` past the segment's ends (frames of `--extend-before`
/// and `--extend-after`) the line from the end along its tangent: `[1, u, 0, 0]` before a,
/// `[0, 0, 1, u - 1]` after b. A clip's eases (see `segment::Eases`) set the tangents there,
/// and the cubic past them turns back (an ease's zero tangents: the pose of b at u = -1/2).
pub(super) fn hermite_beyond(u: f64, straight: bool) -> [f64; 4] {
    match straight {
        true if u < 0.0 => [1.0, u, 0.0, 0.0],
        true if u > 1.0 => [0.0, 0.0, 1.0, u - 1.0],
        _ => hermite(u),
    }
}

/// sum_j w_j v_j.
pub(super) fn hermite_point(w: [f64; 4], v: [DVec3; 4]) -> DVec3 {
    v[0] * w[0] + v[1] * w[1] + v[2] * w[2] + v[3] * w[3]
}

/// [`hermite_point`] of a value that is zero at key a (a rotation log or twist relative to
/// it), from its `[tangent at a, value at b, tangent at b]`.
fn hermite_from_a<T>(w: [f64; 4], [ta, b, tb]: [T; 3]) -> T
where
    T: std::ops::Mul<f64, Output = T> + std::ops::Add<Output = T>,
{
    ta * w[1] + b * w[2] + tb * w[3]
}

/// The window of segment a of a track of `count` keys, as positions along the track: WINDOW
/// keys either side of a and a + 1, cut at the track's ends, or continuing past them round a
/// loop (positions below 0 or above `count - 1`, taken modulo the loop's `count - 1` keys).
fn window_span(count: usize, looped: bool, a: usize) -> std::ops::RangeInclusive<isize> {
    let w = WINDOW as isize;
    if looped {
        a as isize - w..=a as isize + 1 + w
    } else {
        (a as isize - w).max(0)..=(a as isize + 1 + w).min(count as isize - 1)
    }
}

/// The keys segment a of a track of `count` keys reads (its window, looped or not, and the
/// first and last keys, which tell whether the track loops): what a caller holding only some
/// of a long track's keys must hold for it.
pub fn keys_read(count: usize, a: usize) -> Vec<usize> {
    let unique = count.saturating_sub(1).max(1) as isize;
    let mut keys: Vec<usize> = window_span(count, false, a)
        .chain(window_span(count, true, a).map(|i| i.rem_euclid(unique)))
        .map(|i| i as usize)
        .chain([0, count.saturating_sub(1)])
        .collect();
    keys.sort_unstable();
    keys.dedup();
    keys
}

/// True when a track's last key repeats its first (RMS difference below 1e-6 of the first key's
/// bounding-box diagonal): a cycle the spline wraps around.
pub fn is_loop(keys: &[Vec<DVec3>]) -> bool {
    keys.len() > 2 && {
        let d = bbox_diagonal(&keys[0]).max(f64::MIN_POSITIVE);
        rms_rel(&keys[0], &keys[keys.len() - 1], d) < 1e-6
    }
}

/// The branch of log `r` (angle + 2 pi k about its axis) closest to `target`.
fn closest_branch(r: DVec3, target: DVec3) -> DVec3 {
    let axis = branch_axis(r, target);
    // |r + 2 pi k axis - target|^2 - |r - target|^2 = 4 pi k (pi k + axis . (r - target)): the
    // log's own branch (k = 0) is nearest by at least 4 pi 1e-6 (rad^2) while the two differ
    // along the axis by less than half a turn less 1e-6 rad, far beyond the sums' rounding; the
    // value is the one the search returns then, bit for bit.
    if axis.dot(r - target).abs() < PI - 1e-6 {
        return r + axis * (2.0 * PI * 0.0);
    }
    nearest_of_branches(r, axis, target)
}

/// The axis whose whole turns give `r`'s branches.
fn branch_axis(r: DVec3, target: DVec3) -> DVec3 {
    let angle = r.length();
    // Below NO_TURN the axis is the noise of single-precision positions: any axis will do.
    if angle > NO_TURN {
        r / angle
    } else {
        target.try_normalize().unwrap_or(DVec3::X)
    }
}

/// The branch `r + 2 pi k axis` (k from -2 to 2, the first of equals) nearest `target`.
fn nearest_of_branches(r: DVec3, axis: DVec3, target: DVec3) -> DVec3 {
    (-2..=2)
        .map(|k| r + axis * (2.0 * PI * k as f64))
        .min_by(|p, q| {
            (*p - target)
                .length_squared()
                .total_cmp(&(*q - target).length_squared())
        })
        .unwrap_or(r)
}

/// A rotation log's angle as the branch growth orders it: in nanoradians, so that angles equal
/// within 1e-9 rad tie.
fn angle_key(r: DVec3) -> u64 {
    (r.length() * 1e9) as u64
}

/// The branch growth's regions' first triangles: each region starts from its least-rotated
/// triangle, the regions taken in (angle, index) order, so the next start is the least (key,
/// index) pair of the triangles not yet settled. A scan over the triangles finds it for the first
/// [`Starts::SCANNED`] regions (a connected mesh has one); past them the rest are sorted once.
/// (Key, index) pairs are distinct, so either way the starts come in the order a sort of every
/// triangle's pair would give.
#[derive(Default)]
struct Starts {
    regions: usize,
    /// Past the scanned regions: the unsettled triangles' pairs, greatest first.
    sorted: Vec<(u64, u32)>,
}

impl Starts {
    const SCANNED: usize = 4;

    /// The next region's first triangle, given which are settled and each triangle's key
    /// (`None`: a triangle left out, never a start).
    fn next<K>(&mut self, done: &[bool], key: K) -> Option<u32>
    where
        K: Fn(usize) -> Option<u64> + Sync,
    {
        let unsettled = || {
            (0..done.len())
                .into_par_iter()
                .filter(|&t| !done[t])
                .filter_map(|t| key(t).map(|k| (k, t as u32)))
        };
        self.regions += 1;
        if self.regions <= Self::SCANNED {
            return unsettled().min().map(|(_, t)| t);
        }
        if self.regions == Self::SCANNED + 1 {
            self.sorted = unsettled().collect();
            self.sorted.par_sort_unstable_by(|p, q| q.cmp(p));
        }
        while let Some((_, t)) = self.sorted.pop() {
            if !done[t as usize] {
                return Some(t);
            }
        }
        None
    }
}

impl<'a> SplineTrack<'a> {
    pub fn new(
        keys: &'a [Vec<DVec3>],
        times: &'a [f64],
        looped: bool,
        pattern: &'a Pattern,
        triangles: &'a [[u32; 3]],
    ) -> Result<SplineTrack<'a>> {
        Ok(SplineTrack {
            keys,
            times,
            looped,
            pattern,
            triangles,
            stepped_ends: false,
        })
    }

    /// The track of four keys, a pose a short step before key 1, keys 1 and 2, and a pose a
    /// short step after key 2, whose segment 1 takes as its end tangents the slopes over those
    /// steps (a clip's own motion at its keys, see `segment::Eases`), not the spline's.
    pub fn stepped_ends(self) -> SplineTrack<'a> {
        assert_eq!(self.keys.len(), 4, "two keys and a step outside each");
        SplineTrack {
            stepped_ends: true,
            ..self
        }
    }

    /// Make the rotation logs from key a to key b agree across neighbouring triangles: starting
    /// from the least-rotated triangle of each connected region, every triangle reached over a
    /// shared edge takes the branch of its log (angle + 2 pi k about its axis) closest to the
    /// neighbour it was reached from (Baxter, Barla & Anjyo 2008). A part that turns by 180
    /// degrees or more between two keys then turns the long way everywhere, instead of some
    /// triangles taking the short way and the surface crumpling.
    /// Returns the order the triangles were settled in, each with the one it was reached from
    /// (u32::MAX for a region's first).
    fn consistent_branches(&self, per: &mut [Option<Tri>]) -> Vec<(u32, u32)> {
        let mut order = Vec::with_capacity(per.len());
        // The growth visits the mesh in angle order, all over it: it reads the logs from a
        // compact copy (12 bytes a triangle, not the 172 of its data) and writes them back.
        let mut logs: Vec<Vec3> = per
            .par_iter()
            .map(|t| t.as_ref().map_or(Vec3::ZERO, |t| t.r[1]))
            .collect();
        // A triangle left out is never reached: settled from the start.
        let mut done: Vec<bool> = per.par_iter().map(Option::is_none).collect();
        // Best-first growth: the triangle with the smallest rotation on the frontier is fixed
        // next (from the neighbour that reached it), so triangles near 180 degrees, whose
        // branch is ambiguous, are decided last from settled neighbours.
        use std::cmp::Reverse;
        use std::collections::BinaryHeap;
        // Angles equal within 1e-9 rad tie, and the lower triangle index goes first: when two
        // regions are both unrotated (a part turned by exactly 360 degrees), the region listed
        // first in the file stays fixed.
        // (angle, triangle, the one it was reached from)
        let mut heap: BinaryHeap<Reverse<(u64, u32, u32)>> = BinaryHeap::new();
        let mut starts = Starts::default();
        let start_key = |t: usize| per[t].as_ref().map(|x| angle_key(x.log_b()));
        while let Some(start) = starts.next(&done, start_key) {
            heap.push(Reverse((0, start, u32::MAX)));
            while let Some(Reverse((_, t, from))) = heap.pop() {
                if done[t as usize] {
                    continue;
                }
                done[t as usize] = true;
                order.push((t, from));
                if from != u32::MAX {
                    let target = logs[from as usize].as_dvec3();
                    let own = logs[t as usize].as_dvec3();
                    logs[t as usize] = closest_branch(own, target).as_vec3();
                }
                let r = logs[t as usize].as_dvec3();
                for &nb in self.pattern.neighbours(t as usize) {
                    if !done[nb as usize] {
                        let guess = closest_branch(logs[nb as usize].as_dvec3(), r);
                        heap.push(Reverse((angle_key(guess), nb, t)));
                    }
                }
            }
        }
        per.par_iter_mut().zip(logs).for_each(|(t, log)| {
            if let Some(t) = t {
                t.r[1] = log;
            }
        });
        order
    }

    /// The keys whose values set segment a's end tangents (see [`WINDOW`]).
    fn window(&self, a: usize) -> Window {
        if self.stepped_ends {
            let t = self.times;
            let h = t[2] - t[1];
            let (before, after) = (h / (t[1] - t[0]), h / (t[3] - t[2]));
            return Window {
                keys: vec![0, 1, 2, 3],
                times: t.to_vec(),
                a: 1,
                tangents: [
                    vec![-before, before, 0.0, 0.0],
                    vec![0.0, 0.0, -after, after],
                ],
            };
        }
        let k = self.keys.len();
        let span = window_span(k, self.looped, a);
        // A loop's keys 0..k-1 (the last repeats the first) continue periodically.
        let unique = (k - 1) as isize;
        let period = self.times[k - 1] - self.times[0];
        let (keys, times): (Vec<usize>, Vec<f64>) = span
            .clone()
            .map(|i| {
                let (j, turns) = if self.looped {
                    (i.rem_euclid(unique), i.div_euclid(unique))
                } else {
                    (i, 0)
                };
                (j as usize, self.times[j as usize] + period * turns as f64)
            })
            .unzip();
        let lo = *span.start();
        let ia = (a as isize - lo) as usize;
        // Two keys at one time are a cut (the pose jumps there): the window stops at it, so
        // the spline is C1 on each side and no tangent divides by a gap of zero.
        let first = (0..ia)
            .rev()
            .find(|&i| times[i] >= times[i + 1])
            .map_or(0, |i| i + 1);
        let last = (ia + 1..keys.len() - 1)
            .find(|&i| times[i + 1] <= times[i])
            .unwrap_or(keys.len() - 1);
        let (keys, times) = (keys[first..=last].to_vec(), times[first..=last].to_vec());
        let ia = ia - first;
        let n = keys.len();
        // Tangent at window position c from the keys within WINDOW of it.
        let tangent = |c: usize| {
            let (from, to) = (c.saturating_sub(WINDOW), (c + WINDOW).min(n - 1));
            let mut full = vec![0.0; n];
            full[from..=to].copy_from_slice(&tangent_weights(&times[from..=to], c - from));
            full
        };
        let h = times[ia + 1] - times[ia];
        let tangents = [ia, ia + 1].map(|c| tangent(c).iter().map(|m| h * m).collect());
        Window {
            keys,
            times,
            a: ia,
            tangents,
        }
    }

    /// Prepare segment a (keys a and a + 1).
    pub fn segment(&self, a: usize) -> Result<SplineSegment> {
        let (x0, x1) = (&self.keys[a], &self.keys[a + 1]);
        let build = Build::new(self, a);
        // The system (from key a alone) and key b's triangles side by side: the factorization
        // and the branch growth are each one thread's work.
        let (placement, (mut per, stretch_b, order)) = rayon::join(
            || {
                let t0 = std::time::Instant::now();
                let placement = build.placement();
                clock::add(Part::Numeric, t0);
                placement
            },
            || {
                let t0 = std::time::Instant::now();
                // First key b alone: its branches are made consistent across the surface
                // before the other keys are unrolled from it.
                let (mut per, stretch_b) = build.first_key();
                let order = self.consistent_branches(&mut per);
                clock::add(Part::KeyB, t0);
                (per, stretch_b, order)
            },
        );
        let placement = placement?;
        let t0 = std::time::Instant::now();
        let mut stats = Components::of(&per, &build.areas, &placement);
        // The branch-consistent logs to b, before the split replaces some by swings.
        let full_b: Vec<DVec3> = per
            .iter()
            .map(|t| t.as_ref().map_or(DVec3::ZERO, Tri::log_b))
            .collect();
        let limbs = limb_axes(&per, &build.areas, x0, &placement, &stats);
        let local = local_axes(&per, &build.areas, x0, &placement, &stats, &limbs);
        stats.limb = split_twists(&mut per, &order, &placement, &stats, &limbs, &local);
        // A straight limb that turns about an axis across its length bends (see [`Field`]).
        stats.field = (0..stats.area.len())
            .map(|c| {
                let straight = limbs[c].and_then(Limb::straight);
                stats.splits(c) && (straight.is_none() || stats.limb[c])
            })
            .collect();
        drop(order);
        let slices: Vec<Option<DVec3>> = (limbs.iter())
            .zip(&stats.limb)
            .map(|(l, &limb)| match l {
                // A bent limb is its limb's only through its local axes.
                Some(Limb::Bent(axis)) if limb => Some(*axis),
                _ => None,
            })
            .collect();
        let sections = build.bends(&per, &placement, &slices);
        let WindowSums {
            logs,
            screws,
            offsets,
            parts,
            after,
        } = build.window_pass(
            &mut per,
            (&full_b, &stretch_b),
            &sections,
            &placement,
            &stats,
        );
        // Key b's data and the bends at the window's keys are not held into the frames.
        drop((full_b, stretch_b));
        let bends = build.bend_tangents(&sections.bend);
        drop(sections);
        let paths = self.paths(&build.win, &logs, &stats, &screws, &placement);
        let field = Field { parts, after };
        clock::add(Part::Window, t0);
        Ok(SplineSegment {
            // Kept as they are (a triangle of no area is None): collecting the others into a
            // vector of their own held both, 330 MB each at a million triangles, at the peak.
            tris: per,
            bends,
            placement,
            paths,
            offsets,
            field,
            x: [x0.clone(), x1.clone()],
            straight_beyond: false,
        })
    }

    /// Each component's path (see the module) from its mean rotation `logs` relative to key a
    /// at the window's keys, the scatter of its triangles' logs to b about their mean (see
    /// [`Components::scatter`]) and, where it splits, the sums of its triangles' `screws`.
    fn paths(
        &self,
        win: &Window,
        logs: &[[DVec3; MAX_WINDOW]],
        stats: &Components,
        screws: &[Screw],
        placement: &Placement,
    ) -> Vec<Path> {
        let ia = win.a;
        let centroids: Vec<Vec<DVec3>> = win
            .keys
            .iter()
            .map(|&k| placement.centroids(&self.keys[k]))
            .collect();
        (0..placement.component_count())
            .map(|c| {
                let ca = centroids[ia][c];
                let log = &logs[c];
                let p = pivot(win, log, |j| centroids[j][c], PIVOT_PULL);
                let pivot = |j: usize| centroids[j][c] - rotation(log[j]) * (ca - p);
                let angle = log[ia + 1].length();
                let rigid = if angle > 0.0 {
                    let x = ((LOOSE_SPREAD - stats.scatter(c) / angle)
                        / (LOOSE_SPREAD - RIGID_SPREAD))
                        .clamp(0.0, 1.0);
                    x * x * (3.0 - 2.0 * x)
                } else {
                    0.0
                };
                let path = |f: &dyn Fn(usize) -> DVec3| {
                    let [ta, b, tb] = win.ends(f);
                    [f(ia), ta, b, tb]
                };
                let [_, la, lb, lt] = path(&|j| log[j]);
                let screw = screws.get(c).filter(|s| s.weight > 0.0);
                Path {
                    centroid: ca,
                    pivot: path(&|j| if j == ia { p } else { pivot(j) }),
                    log: [la, lb, lt],
                    centroids: path(&|j| centroids[j][c]),
                    rigid,
                    screw: screw.map(|s| (path(&|j| s.pivots[j] / s.weight), s.weight)),
                    limb: stats.limb[c],
                }
            })
            .collect()
    }
}

/// The pivot of a motion from key a over the window `win`: the point p with
/// (I - R_j) p = c_j - R_j c_a for the keys next to the segment and b (R_j the rotation with
/// log `log[j]`, c_j = `centre(j)`), least squares with a `pull` towards c_a; along the axis
/// of the turn to b (which leaves it free) it stays level with c_a.
fn pivot(
    win: &Window,
    log: &[DVec3; MAX_WINDOW],
    centre: impl Fn(usize) -> DVec3,
    pull: f64,
) -> DVec3 {
    let (ia, ca) = (win.a, centre(win.a));
    let axis = log[ia + 1].normalize_or_zero();
    let along = DMat3::from_cols(axis * axis.x, axis * axis.y, axis * axis.z);
    let mut lhs = DMat3::IDENTITY * pull + along;
    let mut rhs = ca * pull + along * ca;
    let knots = ia.saturating_sub(1)..(ia + 3).min(win.keys.len());
    for j in knots.filter(|&j| j != ia) {
        let r = rotation(log[j]);
        let k = DMat3::IDENTITY - r;
        lhs += k.transpose() * k;
        rhs += k.transpose() * (centre(j) - r * ca);
    }
    lhs.inverse() * rhs
}

/// Segment a of a track while it is built: its window, and the reference (key a) triangles'
/// areas. Each triangle's residual is weighted by its area (the continuous Poisson energy), in
/// the right-hand side and in the system; components' mean rotations are weighted by it too.
struct Build<'t, 'a> {
    track: &'t SplineTrack<'a>,
    a: usize,
    win: Window,
    areas: Vec<f64>,
}

fn weight(area: f64) -> f64 {
    if WEIGHTED {
        area
    } else {
        1.0
    }
}

impl<'t, 'a> Build<'t, 'a> {
    fn new(track: &'t SplineTrack<'a>, a: usize) -> Build<'t, 'a> {
        let x0 = &track.keys[a];
        let areas: Vec<f64> = track
            .triangles
            .par_iter()
            .map(|&[i, j, k]| {
                let [a, b, c] = [i, j, k].map(|v| x0[v as usize]);
                0.5 * (b - a).cross(c - a).length()
            })
            .collect();
        Build {
            track,
            a,
            win: track.window(a),
            areas,
        }
    }

    /// Rotation log and stretch from key a to `key` of the triangle with frame inverse v_inv.
    fn rs(&self, v_inv: &DMat3, [i, j, k]: [u32; 3], key: usize) -> (DVec3, DMat3) {
        let x = &self.track.keys[key];
        let t = deformation(v_inv, x[i as usize], x[j as usize], x[k as usize]);
        let (q, s) = polar_of_triangle(&t, v_inv);
        (quat_log(q), s)
    }

    /// Inverse frame of a triangle in key a (`None` when it is degenerate there).
    fn inverse(&self, [i, j, k]: [u32; 3]) -> Option<DMat3> {
        let x0 = &self.track.keys[self.a];
        frame(x0[i as usize], x0[j as usize], x0[k as usize]).map(|v| v.inverse())
    }

    /// Every valid triangle with its log to key b, and b's stretch kept aside for the tangents.
    fn first_key(&self) -> (Vec<Option<Tri>>, Vec<DMat3>) {
        let b = self.a + 1;
        self.track
            .triangles
            .par_iter()
            .zip(&self.areas)
            .map(|(&corners, &area)| {
                let Some(v_inv) = self.inverse(corners) else {
                    return (None, DMat3::IDENTITY);
                };
                let g = self.operator(&v_inv, area);
                let (rb, sb) = self.rs(&v_inv, corners, b);
                let tri = Tri {
                    corners,
                    r: [Vec3::ZERO, rb.as_vec3(), Vec3::ZERO],
                    g: g.map(|g| g.as_vec3()),
                    // Set with the tangents in the window pass.
                    sg: [[Vec3::ZERO; 2]; 3],
                    twist: [0.0; 3],
                    axis: Vec3::ZERO,
                };
                (Some(tri), sb)
            })
            .unzip()
    }

    /// A triangle's gradient operator at corners 1 and 2 (`v_inv` its inverse edge matrix at key
    /// a), weighted by its `area`, as [`Tri::g`] holds it.
    fn operator(&self, v_inv: &DMat3, area: f64) -> [DVec3; 2] {
        let g3 = gradient_operator(v_inv);
        let w = weight(area);
        [g3[1] * w, g3[2] * w]
    }

    /// The system A = sum w g g^T over the valid triangles (those key a gives an inverse, as
    /// [`Build::first_key`] keeps them), factored.
    fn placement(&self) -> Result<Placement> {
        let ops: Vec<Option<[DVec3; 2]>> = self
            .track
            .triangles
            .par_iter()
            .zip(&self.areas)
            .map(|(&corners, &area)| Some(self.operator(&self.inverse(corners)?, area)))
            .collect();
        // Pass sqrt(w) g (the operators carry w).
        let grads = ops.iter().zip(&self.areas).map(|(g, &area)| {
            g.map(|g| {
                let s = 1.0 / weight(area).sqrt();
                [-(g[0] + g[1]) * s, g[0] * s, g[1] * s]
            })
        });
        let valid: Vec<[u32; 3]> = (self.track.triangles.iter().zip(&ops))
            .filter(|(_, g)| g.is_some())
            .map(|(&c, _)| c)
            .collect();
        let n = self.track.keys[self.a].len();
        Placement::new(self.track.pattern, n, grads, &valid)
    }

    /// The other keys of the window, unrolled outward from a and b, reduced to each triangle's
    /// tangents at a and b (see [`WindowSums`] for what it returns).
    fn window_pass(
        &self,
        per: &mut [Option<Tri>],
        (full_b, stretch_b): (&[DVec3], &[DMat3]),
        sections: &Sections,
        placement: &Placement,
        stats: &Components,
    ) -> WindowSums {
        // Where a component splits (its cross-sections found), its triangles' screws (see
        // [`Screw`]).
        let split = !sections.bend.is_empty();
        let deg = match split {
            true => degrees(per, self.track.keys[self.a].len()),
            false => Vec::new(),
        };
        let mut offsets = vec![Vec3::ZERO; if split { per.len() } else { 0 }];
        let limb = split && stats.limb.contains(&true);
        let mut after = vec![[glam::Mat3::ZERO; 3]; if limb { per.len() } else { 0 }];
        let fields = stats.field.contains(&true);
        let mut parts = vec![None; if fields { per.len() } else { 0 }];
        let deg = &deg[..];
        // The twist field (see [`Field`]): the vertices' twists, measured from the keys.
        let field = fields.then(|| self.vertex_twists(per, sections, placement, stats));
        let bends = &sections.bend[..];
        let nw = self.win.keys.len();
        // The point of triangle t's axis line: its cross-section's centroid in key a.
        let line = |t: usize| sections.centre[t * nw + self.win.a].as_dvec3();
        let mut logs = vec![[DVec3::ZERO; MAX_WINDOW]; stats.area.len()];
        let mut screws = vec![Screw::default(); stats.area.len()];
        // Fixed chunks: the sums, and so the output, do not depend on the number of threads.
        let chunk = 4096;
        type Sums = std::collections::HashMap<usize, ([DVec3; MAX_WINDOW], Screw)>;
        let sums: Vec<Sums> = per
            .par_chunks_mut(chunk)
            .zip(self.areas.par_chunks(chunk))
            .zip(full_b.par_chunks(chunk))
            .zip(stretch_b.par_chunks(chunk))
            .enumerate()
            .map(|(at, (((tris, areas), full_b), stretch_b))| {
                let mut sums = Sums::new();
                let mut offs = Vec::new();
                let mut found = Vec::new();
                let each = tris.iter_mut().zip(areas).zip(full_b).zip(stretch_b);
                for (k, (((tri, &area), &full_b), &sb)) in each.enumerate() {
                    let Some(tri) = tri.as_mut() else { continue };
                    let t = at * chunk + k;
                    let bend = bends.get(t * nw..(t + 1) * nw);
                    let c = placement.component_of(tri.corners[0] as usize);
                    let along_limb = c.is_some_and(|c| stats.limb[c]);
                    let field = (field.as_ref())
                        .zip(c.filter(|&c| stats.field[c]))
                        .map(|(f, _)| (&f[..], line(t)));
                    let Some(Unrolled { log, screw, field }) =
                        self.tangents(tri, (full_b, sb), bend, deg, along_limb, field)
                    else {
                        continue;
                    };
                    if let Some(field) = field {
                        found.push((t, field));
                    }
                    if screw.weight > 0.0 {
                        offs.push((t, screw.offset.as_vec3()));
                    }
                    if let Some(c) = c {
                        let (sum, sc) = sums
                            .entry(c)
                            .or_insert(([DVec3::ZERO; MAX_WINDOW], Screw::default()));
                        for (s, l) in sum.iter_mut().zip(&log) {
                            *s += *l * area;
                        }
                        sc.weight += screw.weight;
                        for (s, p) in sc.pivots.iter_mut().zip(&screw.pivots) {
                            *s += *p;
                        }
                    }
                }
                (sums, offs, found)
            })
            .collect::<Vec<_>>()
            .into_iter()
            .map(|(sums, offs, found)| {
                for (t, o) in offs {
                    offsets[t] = o;
                }
                for (t, field) in found {
                    parts[t] = Some(field.own);
                    if let Some(a) = field.after {
                        after[t] = a;
                    }
                }
                sums
            })
            .collect();
        for part in sums {
            for (c, (sum, sc)) in part {
                for (l, s) in logs[c].iter_mut().zip(sum) {
                    *l += s;
                }
                screws[c].weight += sc.weight;
                for (s, p) in screws[c].pivots.iter_mut().zip(&sc.pivots) {
                    *s += *p;
                }
            }
        }
        for (l, w) in logs.iter_mut().zip(&stats.area) {
            if *w > 0.0 {
                *l = l.map(|r| r / *w);
            }
        }
        WindowSums {
            logs,
            screws,
            offsets,
            parts,
            after,
        }
    }

    /// Each vertex's twist at the window's keys, where its component takes the field (see
    /// [`Field`]); zero elsewhere, NaN where no triangle measured it. Each triangle at the
    /// vertex measures it: the angle about the triangle's axis from the vertex's offset to its
    /// cross-section's centroid in key a to the same offset at the key, unbent (see
    /// [`Sections`]), b's on the turn nearest the triangle's settled twist and the other keys'
    /// unrolled from a and b (as the triangles' own twists are), where the triangle turns about
    /// that line at every key (see [`FIELD_RADIAL`]); a corner on the line turns with the
    /// others. The measures are averaged, weighted by area. Exact for a twist about the
    /// cross-sections' centroids at any tessellation, where the mean of the triangles' own
    /// twists is not (a tube of 12 unevenly spaced rings twisted 720 degrees in one step:
    /// 0.0035 of the diagonal off half way with that mean, 0.0009 without the field, 0.0000
    /// so), and no decomposition is made again (with the triangles' own twists, which need
    /// them, the 288k-triangle arm's window took 1.8 s, against 1.35 s now and 0.95 s without
    /// the field).
    fn vertex_twists(
        &self,
        per: &[Option<Tri>],
        sections: &Sections,
        placement: &Placement,
        stats: &Components,
    ) -> Vec<[f64; MAX_WINDOW]> {
        let (win, nw) = (&self.win, self.win.keys.len());
        let x0 = &self.track.keys[self.a];
        // Each field triangle's measures of its corners' twists at the window's keys, unrolled
        // outward from b's (on the turn nearest the triangle's settled twist), where it turns
        // about its line at every key.
        let times = &win.times[..nw];
        let measures: Vec<Option<[[f64; MAX_WINDOW]; 3]>> = (per.par_iter().enumerate())
            .map(|(t, tri)| {
                let tri = tri.as_ref().filter(|tri| tri.split())?;
                let c = placement.component_of(tri.corners[0] as usize)?;
                if !stats.field[c] {
                    return None;
                }
                let bend = sections.bend.get(t * nw..(t + 1) * nw);
                let axis = tri.axis.as_dvec3().normalize();
                let across = |v: DVec3| v - axis * axis.dot(v);
                let centre = |w: usize| sections.centre[t * nw + w].as_dvec3();
                let corners = tri.corners.map(|v| x0[v as usize]);
                let from = TwistLine::new(corners, centre(win.a), axis).offset;
                let far = from.iter().map(|f| f.length()).fold(0.0, f64::max);
                let mut out = [[0.0f64; MAX_WINDOW]; 3];
                for (w, &key) in win.keys.iter().enumerate().filter(|&(w, _)| w != win.a) {
                    let unbend = bend.map_or(DQuat::IDENTITY, |b| {
                        DQuat::from_scaled_axis(b[w].as_dvec3()).conjugate()
                    });
                    let x = &self.track.keys[key];
                    let to = tri
                        .corners
                        .map(|v| across(unbend * (x[v as usize] - centre(w))));
                    // A twist keeps every corner's distance from the line (to a share of the
                    // farthest corner's: a corner on the line may be off it by round-off).
                    let turned = from.iter().zip(&to).all(|(from, to)| {
                        (to.length() - from.length()).abs() <= FIELD_RADIAL * far
                    });
                    if !turned {
                        return None;
                    }
                    let angle: [Option<f64>; 3] = std::array::from_fn(|k| {
                        (from[k].length() > 0.0)
                            .then(|| axis.dot(from[k].cross(to[k])).atan2(from[k].dot(to[k])))
                    });
                    // A corner on the line turns with the others (their mean, on one turn).
                    let first = angle.iter().flatten().next().copied().unwrap_or(0.0);
                    let (sum, n) = (angle.iter().flatten()).fold((0.0, 0.0), |(s, n), &a| {
                        (s + nearest_turn(a, first), n + 1.0)
                    });
                    for k in 0..3 {
                        out[k][w] = angle[k].unwrap_or(sum / f64::max(n, 1.0));
                    }
                }
                for twist in out.iter_mut() {
                    twist[win.a + 1] = nearest_turn(twist[win.a + 1], tri.twist[1] as f64);
                    unroll(&mut twist[..nw], times, win.a, nearest_turn);
                }
                // The corners on the first's turns (unrolling can part them at a far key).
                let first = out[0];
                for twist in out.iter_mut().skip(1) {
                    for (t, f) in twist.iter_mut().zip(&first) {
                        *t = nearest_turn(*t, *f);
                    }
                }
                Some(out)
            })
            .collect();
        let mut sum = vec![[0.0f64; MAX_WINDOW]; x0.len()];
        let mut weight = vec![0.0f64; x0.len()];
        // Each vertex's measures on the turns of its first (see [`Build::unfield`]).
        let mut first = vec![[0.0f64; MAX_WINDOW]; x0.len()];
        for ((tri, m), &area) in per.iter().zip(&measures).zip(&self.areas) {
            let (Some(tri), Some(m)) = (tri, m) else {
                continue;
            };
            for (k, &v) in tri.corners.iter().enumerate() {
                let v = v as usize;
                if weight[v] == 0.0 {
                    first[v] = m[k];
                }
                weight[v] += area;
                for ((s, t), f) in sum[v].iter_mut().zip(&m[k]).zip(&first[v]) {
                    *s += nearest_turn(*t, *f) * area;
                }
            }
        }
        // A vertex no triangle measures takes no field (NaN: its triangles keep their own
        // twist, see [`Build::unfield`]).
        for (s, &w) in sum.iter_mut().zip(&weight) {
            *s = s.map(|x| if w > 0.0 { x / w } else { f64::NAN });
        }
        sum
    }

    /// Where `tri` belongs to a split component and faces across its twist axis: its unit
    /// normal in key a and the in-plane direction across the axis (see [`aligned`]): its
    /// rotation to every key is then taken around the twist, so the shear that a twist puts
    /// on the surface stays in the part interpolated linearly. `None` elsewhere, and for a
    /// triangle facing along the axis (within [`ALONG_AXIS`], like a tube's cap).
    fn across(&self, tri: &Tri) -> Option<(DVec3, DVec3)> {
        if !tri.split() {
            return None;
        }
        let x = &self.track.keys[self.a];
        let [i, j, k] = tri.corners.map(|v| x[v as usize]);
        let n = (j - i).cross(k - i).try_normalize()?;
        let e = tri.axis.as_dvec3().cross(n);
        (e.length() > ALONG_AXIS).then(|| (e.normalize(), n))
    }

    /// [`Build::rs`] by the decomposition aligned `across` the twist where it applies (see
    /// [`Build::across`]), by the polar one elsewhere.
    fn rs_across(
        &self,
        v_inv: &DMat3,
        corners: [u32; 3],
        key: usize,
        across: Option<(DVec3, DVec3)>,
    ) -> (DVec3, DMat3) {
        across
            .and_then(|ac| self.aligned_rs(v_inv, corners, key, ac))
            .unwrap_or_else(|| self.rs(v_inv, corners, key))
    }

    /// [`Build::rs`] by the decomposition aligned `across` the twist (see [`Build::across`]).
    fn aligned_rs(
        &self,
        v_inv: &DMat3,
        [i, j, k]: [u32; 3],
        key: usize,
        (e, n): (DVec3, DVec3),
    ) -> Option<(DVec3, DMat3)> {
        let x = &self.track.keys[key];
        let t = deformation(v_inv, x[i as usize], x[j as usize], x[k as usize]);
        aligned(&t, e, n).map(|(q, u)| (quat_log(q), u))
    }

    /// The bend of each triangle of a split component at every window key (`nw` a triangle,
    /// empty where no component splits): the swing its rotation makes after its twist
    /// ([`swing_after_twist`]), averaged, weighted by area, over the component's triangles whose
    /// centroids in key a lie within [`CROSS_SECTION`] of its own along the twist axis (along a
    /// bent limb's principal direction where its triangles twist about their own axes, see
    /// [`local_axes`]: `slices`, per component). A limb's
    /// bend is shared by its cross-section; the small tilt a twist gives each triangle (a flat
    /// triangle between two rings turned apart) turns with the surface around the axis and
    /// averages out over it. Single precision and running sums: 2 x 12 bytes a triangle and
    /// window key at the peak.
    fn bends(
        &self,
        per: &[Option<Tri>],
        placement: &Placement,
        slices: &[Option<DVec3>],
    ) -> Sections {
        if !per.iter().flatten().any(Tri::split) {
            return Sections::default();
        }
        let (win, x) = (&self.win, &self.track.keys[self.a]);
        let nw = win.keys.len();
        // Each split triangle's component, swings (a's is zero), centres and position along
        // the axis.
        let mut swing = vec![Vec3::ZERO; per.len() * nw];
        let mut centre = vec![Vec3::ZERO; per.len() * nw];
        let mut position = vec![0.0f64; per.len()];
        let each = swing.par_chunks_mut(nw).zip(centre.par_chunks_mut(nw));
        let component: Vec<Option<usize>> = (each.zip(&mut position).zip(per))
            .map(|(((swing, centre), position), tri)| {
                let tri = tri.as_ref().filter(|tri| tri.split())?;
                let c = placement.component_of(tri.corners[0] as usize)?;
                let v_inv = self.inverse(tri.corners)?;
                let (axis, across) = (tri.axis.as_dvec3().normalize(), self.across(tri));
                for (w, &key) in win.keys.iter().enumerate() {
                    let y = &self.track.keys[key];
                    centre[w] = centroid(tri.corners, y).as_vec3();
                    if w != win.a {
                        let (log, _) = self.rs_across(&v_inv, tri.corners, key, across);
                        swing[w] = swing_after_twist(log, axis).as_vec3();
                    }
                }
                *position = centroid(tri.corners, x).dot(slices[c].unwrap_or(axis));
                Some(c)
            })
            .collect();
        // By component, then along the axis (ties by triangle: the same order on any thread).
        let mut order: Vec<u32> = (0..per.len() as u32)
            .filter(|&t| component[t as usize].is_some())
            .collect();
        order.par_sort_unstable_by(|&p, &q| {
            let key = |t: u32| (component[t as usize], position[t as usize]);
            let ((cp, sp), (cq, sq)) = (key(p), key(q));
            cp.cmp(&cq).then(sp.total_cmp(&sq)).then(p.cmp(&q))
        });
        let mut bend = vec![Vec3::ZERO; per.len() * nw];
        let mut section = vec![Vec3::ZERO; per.len() * nw];
        // Running sums of the swings and the centres (weighted by area) at each window key.
        type Sum = [[DVec3; 2]; MAX_WINDOW];
        for run in order.chunk_by(|&p, &q| component[p as usize] == component[q as usize]) {
            let at = |i: usize| position[run[i] as usize];
            let half = CROSS_SECTION * (at(run.len() - 1) - at(0));
            let (mut lo, mut hi, mut area) = (0, 0, 0.0);
            let mut sum: Sum = [[DVec3::ZERO; 2]; MAX_WINDOW];
            let add = |t: u32, sign: f64, sum: &mut Sum, area: &mut f64| {
                let (t, a) = (t as usize, sign * self.areas[t as usize]);
                *area += a;
                for (w, s) in sum.iter_mut().enumerate().take(nw) {
                    s[0] += swing[t * nw + w].as_dvec3() * a;
                    s[1] += centre[t * nw + w].as_dvec3() * a;
                }
            };
            for i in 0..run.len() {
                while hi < run.len() && at(hi) <= at(i) + half {
                    add(run[hi], 1.0, &mut sum, &mut area);
                    hi += 1;
                }
                while at(lo) < at(i) - half {
                    add(run[lo], -1.0, &mut sum, &mut area);
                    lo += 1;
                }
                if area > 0.0 {
                    let t = run[i] as usize;
                    for (w, s) in sum.iter().enumerate().take(nw) {
                        bend[t * nw + w] = (s[0] / area).as_vec3();
                        section[t * nw + w] = (s[1] / area).as_vec3();
                    }
                }
            }
        }
        Sections {
            bend,
            centre: section,
        }
    }

    /// `bends` (see [`Build::bends`]) as each triangle's tangent at a, value at b and tangent at
    /// b, as [`SplineSegment::bends`] keeps them.
    fn bend_tangents(&self, bends: &[Vec3]) -> Vec<[Vec3; 3]> {
        let (win, nw) = (&self.win, self.win.keys.len());
        bends
            .par_chunks(nw)
            .map(|b| win.ends(|w| b[w].as_dvec3()).map(|r| r.as_vec3()))
            .collect()
    }

    /// Set `tri`'s tangents (rotation, twist, stretch) from its values at the window's keys,
    /// given its branch-consistent log `full_b` and stretch `sb` at key b, and in a split
    /// component its `bend` at the window's keys and, once known, the vertices' twists at the
    /// window's keys and the component's centre (see [`Field`]); returns its unrolled logs and
    /// twists at the window's keys (`None` for a triangle degenerate in key a).
    fn tangents(
        &self,
        tri: &mut Tri,
        (full_b, sb): (DVec3, DMat3),
        bend: Option<&[Vec3]>,
        deg: &[u32],
        along_limb: bool,
        field: Option<(&[[f64; MAX_WINDOW]], DVec3)>,
    ) -> Option<Unrolled> {
        let win = &self.win;
        let (ia, nw) = (win.a, win.keys.len());
        // Recomputed rather than kept from the first pass (72 bytes a triangle).
        let v_inv = self.inverse(tri.corners)?;
        let mut log = [DVec3::ZERO; MAX_WINDOW];
        let mut stretch = [DMat3::IDENTITY; MAX_WINDOW];
        (log[ia + 1], stretch[ia + 1]) = (full_b, sb);
        let across = self.across(tri);
        let bend: Option<[DVec3; MAX_WINDOW]> = bend
            .filter(|_| tri.split())
            .map(|bend| std::array::from_fn(|w| bend.get(w).map_or(DVec3::ZERO, |b| b.as_dvec3())));
        let axis = tri.axis.as_dvec3().normalize_or_zero();
        // Key b as the first pass left it unless taken across a twist or after a bend.
        let mut recomputed_b = false;
        // Key a's plane, made once for the keys decomposed in it.
        let plane = std::cell::OnceCell::new();
        for (w, &key) in win.keys.iter().enumerate().filter(|&(w, _)| w != ia) {
            let x = &self.track.keys[key];
            let [i, j, k] = tri.corners.map(|v| x[v as usize]);
            let t = deformation(&v_inv, i, j, k);
            let bend = bend.map(|b| (b[w], DQuat::from_scaled_axis(b[w])));
            // R = bend twist swing: around the twist where the triangle faces across it and
            // turns no other way (no swing); else aligned across it; else polar.
            let around = across
                .zip(bend)
                .and_then(|((e, _), (_, b))| around_axis(&t, e, axis, b));
            let (l, u) = match around {
                Some((angle, u)) => (axis * angle, u),
                None => {
                    let aligned = across.and_then(|(e, n)| aligned(&t, e, n));
                    // b as the first pass left it, but in double precision where the steps
                    // outside a segment set its tangents: its single-precision log, divided by
                    // the step, would put the float's rounding in them.
                    let stepped = self.track.stepped_ends;
                    if w == ia + 1 && aligned.is_none() && bend.is_none() && !stepped {
                        continue;
                    }
                    let (q, u) = aligned.unwrap_or_else(|| {
                        polar_in_plane(&t, plane.get_or_init(|| plane_of(&v_inv)).as_ref())
                    });
                    (quat_log(bend.map_or(q, |(_, b)| b.conjugate() * q)), u)
                }
            };
            (log[w], stretch[w]) = if w == ia + 1 {
                recomputed_b = true;
                // On the branch of b's settled log.
                let unbent = bend.map_or(full_b, |(b, _)| full_b - b);
                (closest_branch(l, unbent), u)
            } else {
                (l, u)
            };
        }
        unroll(&mut log[..nw], &win.times, ia, closest_branch);
        let mut values = log;
        let mut twists = [0.0f64; MAX_WINDOW];
        let mut fielded = None;
        if tri.split() {
            let axis = tri.axis.as_dvec3();
            let mut twist = [0.0; MAX_WINDOW];
            for w in 0..nw {
                (twist[w], values[w]) = if w == ia + 1 {
                    if recomputed_b {
                        // The turn count as b's twist was unwrapped over the surface.
                        let (twist, swing) = twist_swing(log[w], axis);
                        (nearest_turn(twist, tri.twist[1] as f64), swing)
                    } else {
                        (tri.twist[1] as f64, tri.log_b())
                    }
                } else {
                    twist_swing(log[w], axis)
                };
            }
            unroll(&mut twist[..nw], &win.times, ia, nearest_turn);
            twists = twist;
            tri.twist = win.ends(|w| twist[w]).map(|t| t as f32);
            if let Some(field) = field {
                let unfield = (tri.corners, &v_inv, axis.normalize(), &twist, &log);
                fielded = self.unfield(unfield, field, along_limb, &mut stretch);
            }
        }
        tri.r = win.ends(|w| values[w]).map(|r| r.as_vec3());
        let g = tri.g.map(|g| g.as_dvec3());
        tri.sg = win
            .ends(|w| stretch[w])
            .map(|s| [(s * g[0]).as_vec3(), (s * g[1]).as_vec3()]);
        let screw = match bend {
            Some(bend) if !deg.is_empty() => {
                // The cross-section's turn: the bend alone along a limb, else after the twist.
                let turn: [DVec3; MAX_WINDOW] = std::array::from_fn(|w| {
                    if along_limb {
                        bend[w]
                    } else {
                        let twist = DQuat::from_axis_angle(axis, twists[w]);
                        quat_log(DQuat::from_scaled_axis(bend[w]) * twist)
                    }
                });
                self.screw(tri.corners, &turn, deg)
            }
            _ => Screw::default(),
        };
        Some(Unrolled {
            log,
            screw,
            field: fielded,
        })
    }

    /// The stretches at the window's keys of a split triangle (`corners`, frame inverse `v_inv`
    /// in key a, its unit `axis`, its `twist` and unrolled `log` at the window's keys) with the
    /// twist field's part taken out (see [`Field`]), given the vertices' twists at the window's
    /// keys and the point of its axis line; along a limb all of them I. Returns its corners'
    /// turns relative to its own twist and along a limb its stretches after the twist (`None`
    /// where a corner was not measured: no field).
    fn unfield(
        &self,
        (corners, v_inv, axis, twist, log): Unfield,
        (vertex, centre): (&[[f64; MAX_WINDOW]], DVec3),
        along_limb: bool,
        stretch: &mut [DMat3; MAX_WINDOW],
    ) -> Option<FieldOf> {
        let win = &self.win;
        // A corner no triangle measured (see [`Build::vertex_twists`]): no field.
        if corners
            .iter()
            .any(|&v| vertex[v as usize].iter().any(|t| t.is_nan()))
        {
            return None;
        }
        let x = &self.track.keys[self.a];
        let line = TwistLine::new(corners.map(|v| x[v as usize]), centre, axis);
        let mut after = [DMat3::IDENTITY; MAX_WINDOW];
        let mut deltas = [[0.0f64; MAX_WINDOW]; 3];
        for w in (0..win.keys.len()).filter(|&w| w != win.a) {
            // A corner's turn relative to the triangle's, on the nearest turn (the vertex and
            // the triangle may have unrolled a far key onto different turns).
            let delta = corners.map(|v| nearest_turn(vertex[v as usize][w] - twist[w], 0.0));
            for (k, d) in delta.iter().enumerate() {
                deltas[k][w] = *d;
            }
            let d = line.gradient(v_inv, delta);
            // A field that collapses the triangle (turns apart by half a turn) takes nothing.
            let d_inv = if d.determinant().abs() > 1e-12 {
                d.inverse()
            } else {
                DMat3::IDENTITY
            };
            if along_limb {
                // T = B (W X) U = B S (W X) D: S = (W X) U D^-1 (W X)^T.
                let q = rotation(log[w]);
                after[w] = q * stretch[w] * d_inv * q.transpose();
                stretch[w] = DMat3::IDENTITY;
            } else {
                stretch[w] = d_inv * stretch[w];
            }
        }
        Some(FieldOf {
            own: FieldPart {
                deltas: deltas.map(|d| win.ends(|w| d[w]).map(|x| x as f32)),
                line: centre.as_vec3(),
            },
            after: along_limb.then(|| win.ends(|w| after[w]).map(|m| m.as_mat3())),
        })
    }

    /// The screw (see [`Screw`]) of the triangle with `corners` from its `bend` logs at the
    /// window's keys (`deg`: the number of triangles at each vertex).
    fn screw(&self, corners: [u32; 3], bend: &[DVec3; MAX_WINDOW], deg: &[u32]) -> Screw {
        let win = &self.win;
        let (ia, nw) = (win.a, win.keys.len());
        let omega = corners.map(|v| 1.0 / deg[v as usize].max(1) as f64);
        let weight: f64 = omega.iter().sum();
        let centre = |key: usize| {
            let x = &self.track.keys[key];
            (0..3)
                .map(|k| x[corners[k] as usize] * omega[k])
                .sum::<DVec3>()
                / weight
        };
        let cs: [DVec3; MAX_WINDOW] = std::array::from_fn(|w| {
            if w < nw {
                centre(win.keys[w])
            } else {
                DVec3::ZERO
            }
        });
        let ca = cs[ia];
        let p = pivot(win, bend, |j| cs[j], SCREW_PULL);
        let mut pivots = [DVec3::ZERO; MAX_WINDOW];
        for w in 0..nw {
            pivots[w] = if w == ia {
                p
            } else {
                cs[w] - rotation(bend[w]) * (ca - p)
            } * weight;
        }
        Screw {
            weight,
            pivots,
            offset: (ca - p) * weight,
        }
    }
}

/// The cross-sections of a segment's split triangles (see [`Build::bends`]), `nw` values a
/// triangle (empty where no component splits).
#[derive(Default)]
struct Sections {
    /// The bend each shares with its cross-section at each window key.
    bend: Vec<Vec3>,
    /// Its cross-section's centroid at each window key: a point of the twist axis line there.
    centre: Vec<Vec3>,
}

/// What [`Build::window_pass`] finds besides the triangles' tangents: the components'
/// area-weighted mean logs at every window key, and where a component splits, the sums of its
/// triangles' screws, each triangle's screw offset (see [`Screw`]), each triangle's part of the
/// twist field and along a limb its stretch after its twist (see [`Field`]; all four empty
/// where none splits).
struct WindowSums {
    logs: Vec<[DVec3; MAX_WINDOW]>,
    screws: Vec<Screw>,
    offsets: Vec<Vec3>,
    parts: Vec<Option<FieldPart>>,
    after: Vec<[glam::Mat3; 3]>,
}

/// A split triangle as [`Build::unfield`] takes it.
type Unfield<'x> = (
    [u32; 3],
    &'x DMat3,
    DVec3,
    &'x [f64; MAX_WINDOW],
    &'x [DVec3; MAX_WINDOW],
);

/// What [`Build::tangents`] finds besides the tangents it sets.
struct Unrolled {
    /// The triangle's logs at the window's keys, unrolled.
    log: [DVec3; MAX_WINDOW],
    screw: Screw,
    /// Where it takes the twist field, its part of it.
    field: Option<FieldOf>,
}

/// A triangle's part of the twist field (see [`Field`]), as [`Build::unfield`] finds it.
struct FieldOf {
    own: FieldPart,
    /// Along a limb, its stretch after the twist (see [`Field::after`]).
    after: Option<[glam::Mat3; 3]>,
}

/// A triangle's part of the twist field as a segment keeps it (see [`Field`]).
#[derive(Clone, Copy)]
struct FieldPart {
    /// Each corner's turn relative to the triangle's own twist: tangent at a, b's, tangent at b.
    deltas: [[f32; 3]; 3],
    /// The point of its axis line: its cross-section's centroid in key a.
    line: Vec3,
}

/// A split triangle's path as a screw: its weighted centre (corners weighted by one over the
/// number of triangles at each, so that the sum over a component is the sum of its vertices)
/// turns with its cross-section (its bend, see [`Build::bends`], after its twist) about a pivot
/// that follows the window's keys (least squares, as a component's, see [`Build::paths`]).
/// Where the component twists about its limb's length (see [`limb_axes`]) the bend alone: the
/// twist turns the centre about the limb's axis, around its cross-section's centre, and with a
/// twist near whole turns the pivot is ill-conditioned (the tested arm twisting as it bends:
/// 0.0751 -> 0.1347 of the diagonal with the twist in). Summed over a split component whose
/// triangles do not turn as one, the component's centroid: a limb bending at a joint keeps its
/// upper part still and swings the lower on the arc (an arm bent 90 degrees in one key step:
/// 0.037 of the diagonal off the skinned bend at the middle frame along the line between the
/// keys' centroids, 0.0015 so).
#[derive(Clone, Copy, Default)]
struct Screw {
    weight: f64,
    /// weight x pivot at each window key.
    pivots: [DVec3; MAX_WINDOW],
    /// weight x (centre in key a - pivot).
    offset: DVec3,
}

/// The twist field of a segment's split components: each vertex turned by its own twist
/// (measured from the keys' positions, see [`Build::vertex_twists`]) about the axis LINE of
/// its triangle's cross-section (the triangle's twist axis through the centroid of its
/// cross-section in key a, see [`Sections`]). A triangle whose corners turn apart (a tube's
/// rings a twist turns by different angles) has its edges between them on the chords of the
/// turned corners at every frame: each split triangle's gradient is B W X D S with D the
/// gradient of that field relative to the triangle's own twist W (exact for any twist about
/// the cross-sections' centroids at any resolution) and S what the field leaves, interpolated
/// linearly. Without D a triangle's edge between two rings turned delta apart followed the
/// key's chord half way: r cos(delta / 2) from the axis instead of r (10 x 16 tube, radii 1 /
/// 0.6, length 2, twisted 720 degrees in one key step: 0.0251 of the diagonal off at the
/// middle frame; 0.0001 with the field). Along a limb twisting about its length (see
/// [`limb_axes`], [`local_axes`]) S is taken after the twist, B S W X D: what is left there is
/// a bend's (its compression at a joint lies in the bent limb's frame, which the twist turns as
/// it goes; the arm bent 90 degrees and twisted 720 in one key step: 0.0093 -> 0.0025). A
/// straight limb turning about an axis across its length bends rather than twists and takes no
/// field: its triangles' turns about that axis carry each one's shear from the bend, not its
/// corners' turns (tube_bend: up to 0.33 rad past its rings' turn; with a field from those
/// turns it lost 1.7% of its volume in between, against 0.24% gained without).
#[derive(Default)]
struct Field {
    /// Each triangle's part, where it takes the field.
    parts: Vec<Option<FieldPart>>,
    /// Along a limb, each triangle's stretch after its twist: tangent at a, b's, tangent at b
    /// (a's is I); empty where no split component is a limb's.
    after: Vec<[glam::Mat3; 3]>,
}

/// A triangle's two right-hand-side terms for one frame, and its screw offset turned with its
/// component's cross-section (the component and the offset).
type Terms = ([DVec3; 2], Option<(usize, DVec3)>);

/// A split triangle's part of the [`Field`], in double precision for a block of frames.
#[derive(Clone, Copy)]
struct FieldTri {
    deltas: [[f64; 3]; 3],
    line: TwistLine,
    v_inv: DMat3,
    after: Option<[DMat3; 3]>,
}

impl FieldTri {
    /// At Hermite weights `w`: the field's gradient D relative to the triangle's twist, and
    /// along a limb the stretch after the twist.
    fn at(&self, w: [f64; 4]) -> (DMat3, Option<DMat3>) {
        let delta = self.deltas.map(|t| hermite_from_a(w, t));
        let d = self.line.gradient(&self.v_inv, delta);
        let after = self
            .after
            .map(|after| DMat3::IDENTITY * w[0] + hermite_from_a(w, after));
        (d, after)
    }
}

/// Per component of a segment: area, area-weighted mean log to b, the scatter of its
/// triangles' logs about it (area-weighted sum of squares), largest turn.
struct Components {
    area: Vec<f64>,
    mean_b: Vec<DVec3>,
    spread: Vec<f64>,
    turn: Vec<f64>,
    /// Area-weighted sum of the outer products of the logs' unit directions.
    directions: Vec<DMat3>,
    /// Area of the triangles that turn past [`SPLIT_ABOVE`].
    past: Vec<f64>,
    /// Where the component splits about its limb's length (see [`limb_axes`]), set by
    /// [`split_twists`].
    limb: Vec<bool>,
    /// Where the component splits and takes the twist field (see [`Field`]).
    field: Vec<bool>,
}

impl Components {
    fn of(per: &[Option<Tri>], areas: &[f64], placement: &Placement) -> Components {
        let components = placement.component_count();
        let mut area_of = vec![0.0; components];
        let mut mean_b = vec![DVec3::ZERO; components];
        let mut turn = vec![0.0f64; components];
        let mut directions = vec![DMat3::ZERO; components];
        let mut past = vec![0.0f64; components];
        let members = || {
            per.iter().zip(areas).filter_map(|(tri, &area)| {
                let tri = tri.as_ref()?;
                Some((tri, placement.component_of(tri.corners[0] as usize)?, area))
            })
        };
        for (tri, c, area) in members() {
            area_of[c] += area;
            mean_b[c] += tri.log_b() * area;
            turn[c] = turn[c].max(tri.log_b().length());
            if tri.log_b().length() > SPLIT_ABOVE {
                past[c] += area;
            }
            let d = tri.log_b().normalize_or_zero() * area.sqrt();
            directions[c] += DMat3::from_cols(d * d.x, d * d.y, d * d.z);
        }
        for (m, w) in mean_b.iter_mut().zip(&area_of) {
            if *w > 0.0 {
                *m /= *w;
            }
        }
        let mut spread = vec![0.0; components];
        for (tri, c, area) in members() {
            spread[c] += area * (tri.log_b() - mean_b[c]).length_squared();
        }
        Components {
            area: area_of,
            mean_b,
            spread,
            turn,
            directions,
            past,
            limb: vec![false; components],
            field: vec![false; components],
        }
    }

    /// The area-weighted RMS of component `c`'s triangles' logs to b about their mean (radians).
    fn scatter(&self, c: usize) -> f64 {
        (self.spread[c] / self.area[c].max(f64::MIN_POSITIVE)).sqrt()
    }

    /// Whether component `c` is split into twist and swing (see [`SPLIT_ABOVE`], [`COHERENT`]).
    fn splits(&self, c: usize) -> bool {
        let turn = self.turn[c];
        let past = self.past[c] > SPLIT_AREA * self.area[c];
        past || (turn > COHERENT_ABOVE && self.mean_b[c].length() > COHERENT * turn)
    }

    /// Component `c`'s twist axis: the principal direction of its triangles' rotation axes
    /// (area-weighted, whatever their angles and branches), turned to its mean log's side. The
    /// mean log itself tilts where the branches a twist's triangles settle on differ around
    /// the tube (the off-axis part of a log grows with its whole turns): 1 degree off on a fat
    /// tube twisted 405 degrees, 0.013 of the diagonal at the middle frame (0.0005 on the axis).
    fn axis(&self, c: usize) -> DVec3 {
        let mean = self.mean_b[c].try_normalize().unwrap_or(DVec3::X);
        let (_, v) = sym_eigen(&self.directions[c]);
        match v.x_axis.try_normalize() {
            Some(p) if p.dot(mean) < 0.0 => -p,
            Some(p) => p,
            None => mean,
        }
    }
}

/// Each component's limb, where it splits (see [`Components::splits`]) and is a limb in key
/// a: its triangles turn by different amounts (not as one, see [`RIGID_SPREAD`]) and its
/// length along the principal direction of its triangles' centres is [`LIMB_ELONGATION`]
/// times any other (in variance). Straight where its sides (triangles facing less than 60
/// degrees from across that direction) face across it within [`LIMB_STRAIGHT`] on average,
/// bent otherwise (see [`local_axes`]). A twist turns a limb about its own length; the
/// direction of its triangles' rotation axes (see [`Components::axis`]) leans towards a bend
/// it makes at the same time. `None` elsewhere (its rotation axes serve).
fn limb_axes(
    per: &[Option<Tri>],
    areas: &[f64],
    x0: &[DVec3],
    placement: &Placement,
    stats: &Components,
) -> Vec<Option<Limb>> {
    let components = placement.component_count();
    let candidate: Vec<bool> = (0..components)
        .map(|c| {
            let angle = stats.mean_b[c].length();
            stats.splits(c) && angle > 0.0 && stats.scatter(c) / angle > RIGID_SPREAD
        })
        .collect();
    if !candidate.contains(&true) {
        return vec![None; components];
    }
    let members = || {
        per.iter().zip(areas).filter_map(|(tri, &area)| {
            let tri = tri.as_ref()?;
            let c = placement.component_of(tri.corners[0] as usize)?;
            candidate[c].then(|| (tri.corners.map(|v| x0[v as usize]), c, area))
        })
    };
    // Area-weighted moments of the triangles' centres, about the component's vertices' centroid
    // (no cancellation far from the origin).
    let origin = placement.centroids(x0);
    let mut moments = vec![(0.0f64, DVec3::ZERO, DMat3::ZERO); components];
    for (p, c, area) in members() {
        let m = (p[0] + p[1] + p[2]) / 3.0 - origin[c];
        let (w, sum, outer) = &mut moments[c];
        *w += area;
        *sum += m * area;
        *outer += DMat3::from_cols(m * m.x, m * m.y, m * m.z) * area;
    }
    let length: Vec<Option<DVec3>> = moments
        .iter()
        .map(|&(w, sum, outer)| {
            let mean = (w > 0.0).then(|| sum / w)?;
            let covariance =
                outer * (1.0 / w) - DMat3::from_cols(mean * mean.x, mean * mean.y, mean * mean.z);
            let (ev, v) = sym_eigen(&covariance);
            (ev[0] > LIMB_ELONGATION * ev[1])
                .then(|| v.x_axis.try_normalize())
                .flatten()
        })
        .collect();
    let mut sides = vec![(0.0f64, 0.0f64); components];
    for (p, c, area) in members() {
        let (Some(axis), Some(n)) = (length[c], (p[1] - p[0]).cross(p[2] - p[0]).try_normalize())
        else {
            continue;
        };
        let along = n.dot(axis).abs();
        if along < 0.5 {
            sides[c].0 += area;
            sides[c].1 += area * along;
        }
    }
    length
        .iter()
        .zip(&sides)
        .map(|(axis, &(area, along))| {
            let straight = area > 0.0 && along < LIMB_STRAIGHT * area;
            axis.map(|axis| {
                if straight {
                    Limb::Straight(axis)
                } else {
                    Limb::Bent(axis)
                }
            })
        })
        .collect()
}

/// A component's shape in key a where it may be a limb (see [`limb_axes`]).
#[derive(Clone, Copy, Debug)]
enum Limb {
    /// A straight limb along this direction.
    Straight(DVec3),
    /// A limb ([`LIMB_ELONGATION`] times longer than wide) that is not straight (bent or
    /// twisted in key a), with its principal direction.
    Bent(DVec3),
}

impl Limb {
    fn straight(self) -> Option<DVec3> {
        match self {
            Limb::Straight(axis) => Some(axis),
            Limb::Bent(_) => None,
        }
    }
}

/// Share of a bent limb's length each side of a triangle over which its centreline's direction
/// is taken (see [`local_axes`]): a tenth covers the tested arm's elbow (1.5 units each side
/// of 12) without reaching far past it.
const LOCAL_SPAN: f64 = 0.1;

/// A bent limb's centreline whose direction stays within this of its principal direction
/// everywhere (radians, 5 degrees) is straight (see [`local_axes`]).
const LOCAL_BENT: f64 = 0.087;

/// Where a split component is a bent limb (see [`Limb::Bent`]) twisting about its length (its
/// rotations' axis within 45 degrees of its principal direction): each triangle's own twist
/// axis, the direction of the limb's centreline at it (from the centroid of its triangles
/// within [`LOCAL_SPAN`] of its length behind it, along the principal direction, to that of
/// those ahead), or the principal direction wherever the centreline stays within
/// [`LOCAL_BENT`] of it (a straight limb twisted in key a: the local directions of a twisted
/// ribbon wobble, 0.0002 -> 0.0014 of the diagonal half way with them). One axis for the whole limb
/// suits neither side of a bent joint: an arm bent 30 degrees in key a, bending 30 more and
/// twisting 240 degrees to key b, was 0.0146 of the diagonal off the analytic pose half way,
/// mostly its forearm swung 2.2 degrees out of the bend's plane; 0.0020 with the local axes.
/// A straight limb keeps its one length (see [`limb_axes`]). Empty where no component is such
/// a limb.
fn local_axes(
    per: &[Option<Tri>],
    areas: &[f64],
    x0: &[DVec3],
    placement: &Placement,
    stats: &Components,
    limbs: &[Option<Limb>],
) -> Vec<Option<DVec3>> {
    let bent: Vec<Option<DVec3>> = (0..stats.area.len())
        .map(|c| match limbs[c] {
            Some(Limb::Bent(l))
                if stats.splits(c) && l.dot(stats.axis(c)).abs() > TWIST_ALONG_LIMB =>
            {
                Some(if l.dot(stats.axis(c)) < 0.0 { -l } else { l })
            }
            _ => None,
        })
        .collect();
    if bent.iter().all(Option::is_none) {
        return Vec::new();
    }
    // Each such limb's triangles: component, position along its direction, centre, area, index.
    struct Member {
        c: usize,
        s: f64,
        centre: DVec3,
        area: f64,
        t: usize,
    }
    let mut members: Vec<Member> = (per.iter().zip(areas).enumerate())
        .filter_map(|(t, (tri, &area))| {
            let tri = tri.as_ref()?;
            let c = placement.component_of(tri.corners[0] as usize)?;
            let centre = centroid(tri.corners, x0);
            Some(Member {
                c,
                s: centre.dot(bent[c]?),
                centre,
                area,
                t,
            })
        })
        .collect();
    members.sort_unstable_by(|p, q| {
        (p.c.cmp(&q.c))
            .then(p.s.total_cmp(&q.s))
            .then(p.t.cmp(&q.t))
    });
    let mut out = vec![None; per.len()];
    for run in members.chunk_by(|p, q| p.c == q.c) {
        // Prefix sums of area and area x centre along the limb.
        let mut area = vec![0.0f64; run.len() + 1];
        let mut moment = vec![DVec3::ZERO; run.len() + 1];
        for (i, m) in run.iter().enumerate() {
            area[i + 1] = area[i] + m.area;
            moment[i + 1] = moment[i] + m.centre * m.area;
        }
        // The centroid of the triangles positioned in [a, b] (at least one).
        let centroid = |a: f64, b: f64| {
            let i = run.partition_point(|m| m.s < a).min(run.len() - 1);
            let j = run.partition_point(|m| m.s <= b).max(i + 1);
            (moment[j] - moment[i]) / (area[j] - area[i]).max(f64::MIN_POSITIVE)
        };
        let (lo, hi) = (run[0].s, run[run.len() - 1].s);
        let span = LOCAL_SPAN * (hi - lo);
        let l = bent[run[0].c].expect("a bent limb");
        let dirs: Vec<DVec3> = run
            .iter()
            .map(|m| {
                let (a, b) = ((m.s - span).max(lo), (m.s + span).min(hi));
                let mid = 0.5 * (a + b);
                let dir = (centroid(mid, b) - centroid(a, mid))
                    .try_normalize()
                    .unwrap_or(l);
                if dir.dot(l) < 0.0 {
                    -dir
                } else {
                    dir
                }
            })
            .collect();
        // A centreline that stays within LOCAL_BENT of its principal direction is straight
        // (a limb twisted in key a): one axis serves it.
        let straight = dirs.iter().all(|d| d.dot(l) > LOCAL_BENT.cos());
        for (m, dir) in run.iter().zip(dirs) {
            out[m.t] = Some(if straight { l } else { dir });
        }
    }
    out
}

/// Components more than [`SPLIT_AREA`] of which turns past [`SPLIT_ABOVE`], or that turn
/// [`COHERENT`]ly: each rotation to b becomes a twist about the component's axis and a swing,
/// b's twists unwrapped over the settling `order` of the branches.
fn split_twists(
    per: &mut [Option<Tri>],
    order: &[(u32, u32)],
    placement: &Placement,
    stats: &Components,
    limbs: &[Option<Limb>],
    local: &[Option<DVec3>],
) -> Vec<bool> {
    // Each split component's axis (zero where it does not split), and whether it is its limb's.
    let (axis, mut limb): (Vec<DVec3>, Vec<bool>) = (0..stats.area.len())
        .map(|c| {
            if !stats.splits(c) {
                return (DVec3::ZERO, false);
            }
            let a = stats.axis(c);
            let straight = limbs[c].and_then(Limb::straight);
            match straight.filter(|limb| limb.dot(a).abs() > TWIST_ALONG_LIMB) {
                Some(limb) => (if limb.dot(a) < 0.0 { -limb } else { limb }, true),
                None => (a, false),
            }
        })
        .unzip();
    // A bent limb twisting about its length: each triangle about its own (see [`local_axes`]).
    for (tri, l) in per.iter().zip(local) {
        if let (Some(tri), Some(_)) = (tri, l) {
            if let Some(c) = placement.component_of(tri.corners[0] as usize) {
                limb[c] = true;
            }
        }
    }
    per.par_iter_mut().enumerate().for_each(|(t, tri)| {
        let Some(tri) = tri else { return };
        if let Some(c) = placement.component_of(tri.corners[0] as usize) {
            let own = match local.get(t).copied().flatten() {
                Some(own) if axis[c] != DVec3::ZERO => own,
                _ => axis[c],
            };
            tri.axis = own.as_vec3();
            if tri.split() {
                let (twist, swing) = twist_swing(tri.log_b(), own);
                tri.twist[1] = twist as f32;
                tri.r[1] = swing.as_vec3();
            }
        }
    });
    for &(t, from) in order {
        let target = if from == u32::MAX {
            0.0
        } else {
            per[from as usize]
                .as_ref()
                .map_or(0.0, |x| x.twist[1] as f64)
        };
        if let Some(tri) = per[t as usize].as_mut().filter(|x| x.split()) {
            tri.twist[1] = nearest_turn(tri.twist[1] as f64, target) as f32;
        }
    }
    limb
}

impl SplineSegment {
    /// The segment with its frames past its ends on straight lines (see [`hermite_beyond`]).
    pub fn straight_beyond(self) -> SplineSegment {
        SplineSegment {
            straight_beyond: true,
            ..self
        }
    }

    pub fn factor_nonzeros(&self) -> usize {
        self.placement.factor_nonzeros()
    }

    /// The segment's solve, once its frames are done (see [`Placement::recycle`]).
    pub fn into_placement(self) -> Placement {
        self.placement
    }

    pub fn frame(&self, u: f64) -> Vec<DVec3> {
        let (rhs, centroids) = self.systems(&[u]).pop().expect("one frame");
        self.placement
            .place(rhs, &centroids, |v| self.x[0][v].lerp(self.x[1][v], u))
    }

    /// The frames at `us`, their solves sharing passes over the factor (see
    /// [`Placement::place_block`]): the same positions as [`SplineSegment::frame`] at each.
    pub fn frames(&self, us: &[f64]) -> Vec<Vec<DVec3>> {
        let (rhs, centroids): (Vec<_>, Vec<_>) = self.systems(us).into_iter().unzip();
        self.placement.place_block(rhs, &centroids, |f, v| {
            self.x[0][v].lerp(self.x[1][v], us[f])
        })
    }

    /// The right-hand side of each frame of `us` and its components' centroids, in one pass
    /// over the triangles' data for up to [`MAX_BLOCK`] frames (read once for the frames of a
    /// block, not once a frame).
    fn systems(&self, us: &[f64]) -> Vec<(Vec<[f64; 3]>, Vec<DVec3>)> {
        let mut out = Vec::with_capacity(us.len());
        for part in us.chunks(MAX_BLOCK) {
            match part.len() {
                1 => out.extend(self.systems_of::<1>(part)),
                2 => out.extend(self.systems_of::<2>(part)),
                3 => out.extend(self.systems_of::<3>(part)),
                _ => out.extend(self.systems_of::<MAX_BLOCK>(part)),
            }
        }
        out
    }

    /// [`SplineSegment::systems`] for `N` frames (a frame count known to the compiler: one
    /// frame alone costs what it did before frames shared the pass).
    fn systems_of<const N: usize>(&self, us: &[f64]) -> [(Vec<[f64; 3]>, Vec<DVec3>); N] {
        let ws: [[f64; 4]; N] =
            std::array::from_fn(|f| hermite_beyond(us[f], self.straight_beyond));
        let mut rhs: [Vec<[f64; 3]>; N] =
            std::array::from_fn(|_| vec![[0.0f64; 3]; self.x[0].len()]);
        // Each split component's screw offsets turned with their cross-sections (see [`Screw`]).
        let mut turned: [Vec<DVec3>; N] =
            std::array::from_fn(|_| vec![DVec3::ZERO; self.paths.len()]);
        let each = |t: usize| self.terms(t, &ws);
        in_order(self.tris.len(), each, |t, terms| {
            let (Some(terms), Some(tri)) = (terms, &self.tris[t]) else {
                return;
            };
            for (f, (v, turn)) in terms.into_iter().enumerate() {
                scatter(&mut rhs[f], tri.corners, v[0], v[1]);
                if let Some((c, turn)) = turn {
                    turned[f][c] += turn;
                }
            }
        });
        let mut rhs = rhs.into_iter();
        std::array::from_fn(|f| {
            let rhs = rhs.next().expect("N right-hand sides");
            (rhs, self.centroids(ws[f], &turned[f]))
        })
    }

    /// Triangle `t`'s two terms at each of the Hermite weights `ws` and, where its component
    /// turns its screw offset, that offset turned (see [`SplineSegment::systems_of`]); `None`
    /// for a triangle left out.
    #[inline(always)]
    fn terms<const N: usize>(&self, t: usize, ws: &[[f64; 4]; N]) -> Option<[Terms; N]> {
        let tri = self.tris[t].as_ref()?;
        let r = tri.r.map(|r| r.as_dvec3());
        let g = tri.g.map(|g| g.as_dvec3());
        let sg = tri.sg.map(|s| s.map(|s| s.as_dvec3()));
        // The rotation's stretched gradients, at Hermite weights `w`.
        let turned = |w: &[f64; 4], rot: DMat3| -> [DVec3; 2] {
            std::array::from_fn(|k| {
                rot * (g[k] * w[0] + sg[0][k] * w[1] + sg[1][k] * w[2] + sg[2][k] * w[3])
            })
        };
        if !tri.split() {
            return Some(std::array::from_fn(|f| {
                let w = &ws[f];
                (turned(w, rotation(hermite_from_a(*w, r))), None)
            }));
        }
        // A split triangle's twist, axis, bend and screw offset (with its component and
        // whether that twists about its limb) and its part of the field: the same for every
        // frame. (Held apart, not gathered in one value: the field's part, about 600 bytes,
        // was then copied into it and again for each frame, 4-6% of a spline frame's time at
        // 16k triangles by perf.)
        let twist = tri.twist.map(f64::from);
        let axis = tri.axis.as_dvec3().normalize();
        let bend = self.bends.get(t).map(|b| b.map(|b| b.as_dvec3()));
        let c = self.placement.component_of(tri.corners[0] as usize);
        let screw = c
            .zip(self.offsets.get(t))
            .map(|(c, o)| (c, self.paths[c].limb, o.as_dvec3()));
        let field = self.field_of(t, tri);
        Some(std::array::from_fn(|f| {
            let w = &ws[f];
            let r = hermite_from_a(*w, r);
            let twist = hermite_from_a(*w, twist);
            let bend = bend.map_or(DVec3::ZERO, |b| hermite_from_a(*w, b));
            let bend_q = glam::DQuat::from_scaled_axis(bend);
            let twist_q = glam::DQuat::from_axis_angle(axis, twist);
            let turn = screw.map(|(c, limb, o)| {
                let section = DMat3::from_quat(if limb { bend_q } else { bend_q * twist_q });
                (c, section * o)
            });
            // B W X D, or B S W X D along a limb (see [`Field`]).
            let swing = glam::DQuat::from_scaled_axis(r);
            let rot = || DMat3::from_quat(bend_q * twist_q * swing);
            let rot = match field.as_ref().map(|f| f.at(*w)) {
                Some((d, Some(s))) => {
                    DMat3::from_quat(bend_q) * s * DMat3::from_quat(twist_q * swing) * d
                }
                Some((d, None)) => rot() * d,
                None => rot(),
            };
            (turned(w, rot), turn)
        }))
    }

    /// Split triangle `t`'s part of the twist field (see [`Field`]).
    fn field_of(&self, t: usize, tri: &Tri) -> Option<FieldTri> {
        let field = &self.field;
        let part = field.parts.get(t).copied().flatten()?;
        let corners = tri.corners.map(|v| self.x[0][v as usize]);
        let v_inv = frame(corners[0], corners[1], corners[2])?.inverse();
        let c = self.placement.component_of(tri.corners[0] as usize)?;
        let axis = tri.axis.as_dvec3().normalize();
        Some(FieldTri {
            deltas: part.deltas.map(|d| d.map(f64::from)),
            line: TwistLine::new(corners, part.line.as_dvec3(), axis),
            v_inv,
            after: (self.paths[c].limb).then(|| field.after[t].map(|m| m.as_dmat3())),
        })
    }

    /// The components' centroids at Hermite weights `w`, `turned` their screw offsets.
    fn centroids(&self, w: [f64; 4], turned: &[DVec3]) -> Vec<DVec3> {
        self.paths
            .iter()
            .enumerate()
            .map(|(c, path)| {
                // The pivot now; the centroid keeps its offset from the pivot, turned.
                let p = hermite_point(w, path.pivot);
                let [la, lb, lt] = path.log;
                let rot = rotation(hermite_from_a(w, [la, lb, lt]));
                let spline = match path.screw {
                    Some((pivots, weight)) => hermite_point(w, pivots) + turned[c] / weight,
                    None => hermite_point(w, path.centroids),
                };
                spline.lerp(p + rot * (path.centroid - path.pivot[0]), path.rigid)
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The starts scanned and then sorted come in the order of one sort of every triangle's
    /// (key, index) pair, skipping the settled: many regions, tied keys, triangles left out.
    #[test]
    fn region_starts_come_in_key_then_index_order() {
        let mut rng = crate::dev::synth::Lcg(7);
        let n = 2000;
        let keys: Vec<Option<u64>> = (0..n)
            .map(|_| (rng.unit() > 0.05).then(|| (rng.unit() * 50.0) as u64))
            .collect();
        let mut sorted: Vec<(u64, u32)> = (0..n)
            .filter_map(|t| keys[t].map(|k| (k, t as u32)))
            .collect();
        sorted.sort_unstable();
        let mut done: Vec<bool> = keys.iter().map(Option::is_none).collect();
        let mut starts = Starts::default();
        let mut count = 0;
        while let Some(t) = starts.next(&done, |t| keys[t]) {
            let want = sorted.iter().find(|&&(_, s)| !done[s as usize]);
            assert_eq!(Some(t), want.map(|&(_, s)| s), "region {count}");
            // The region grown from it: the start and a few dozen others.
            done[t as usize] = true;
            for _ in 0..(rng.unit() * 60.0) as usize {
                done[(rng.unit() * n as f64) as usize % n] = true;
            }
            count += 1;
        }
        assert!(count > Starts::SCANNED + 10, "{count} regions");
        assert!(done.iter().all(|&d| d));
    }

    /// The shortcut for a log's own branch gives the search's value bit for bit, near half a
    /// turn apart too, and the search still decides past it.
    #[test]
    fn the_nearest_branch_is_the_search_s_bit_for_bit() {
        let search = |r, target| nearest_of_branches(r, branch_axis(r, target), target);
        let mut rng = crate::dev::synth::Lcg(11);
        let mut v =
            |scale: f64| DVec3::new(rng.unit() - 0.5, rng.unit() - 0.5, rng.unit() - 0.5) * scale;
        let (mut own, mut other) = (0, 0);
        for i in 0..200_000 {
            let r = v([1e-7, 1.0, 4.0, 12.0][i % 4]);
            // Targets near r, near half a turn along its axis from it, and anywhere.
            let target = match i % 3 {
                0 => r + v(0.5),
                1 => r - r.normalize_or_zero() * (PI + v(1e-5).x) + v(1e-7),
                _ => v(20.0),
            };
            let got = closest_branch(r, target);
            let want = search(r, target);
            assert_eq!(
                got.to_array().map(f64::to_bits),
                want.to_array().map(f64::to_bits)
            );
            if got == r {
                own += 1
            } else {
                other += 1
            }
        }
        assert!(own > 50_000 && other > 20_000, "{own} own, {other} other");
    }

    #[test]
    fn a_triangle_s_data_takes_172_bytes() {
        // What the memory figures of a segment (and the 4M-triangle peak) rest on.
        assert_eq!(std::mem::size_of::<Option<Tri>>(), 172);
    }

    #[test]
    fn c2_tangents_reproduce_lines_and_match_hand_values() {
        // Three uniform knots: the chord ends give m0 + 4 m1 + m2 = 3 (v2 - v0) with
        // m0 = v1 - v0, m2 = v2 - v1, so m1 = (v2 - v0) / 2, Catmull-Rom's tangent.
        let w = tangent_weights(&[0.0, 1.0, 2.0], 1);
        for (x, y) in w.iter().zip([-0.5, 0.0, 0.5]) {
            assert!((x - y).abs() < 1e-12, "{w:?}");
        }
        // Any knots, any position: a straight line's slope exactly.
        let t = [-1.5, -0.2, 0.0, 1.0, 1.3, 4.0];
        for at in 0..t.len() {
            let w = tangent_weights(&t, at);
            let slope: f64 = w.iter().zip(&t).map(|(w, t)| w * (3.0 * t - 1.0)).sum();
            assert!((slope - 3.0).abs() < 1e-12, "at {at}: {slope}");
        }
        // Five uniform knots, v = (0, 0, 0, 0, 1): m0 = 0, m4 = 1, 4 m1 + m2 = 0,
        // m1 + 4 m2 + m3 = 0, m2 + 4 m3 = 3 - 1, so m2 = -1/7: the last key's weight.
        let w = tangent_weights(&[0.0, 1.0, 2.0, 3.0, 4.0], 2);
        assert!((w[4] + 1.0 / 7.0).abs() < 1e-12, "{w:?}");
    }

    #[test]
    fn hermite_basis_interpolates_the_keys_and_its_value_weights_sum_to_one() {
        for u in [0.0, 0.3, 0.7, 1.0] {
            let w = hermite(u);
            assert!((w[0] + w[2] - 1.0).abs() < 1e-12);
        }
        assert_eq!(hermite(0.0), [1.0, 0.0, 0.0, 0.0]);
        let w1 = hermite(1.0);
        assert!(
            w1[0].abs() < 1e-15
                && w1[1].abs() < 1e-15
                && (w1[2] - 1.0).abs() < 1e-15
                && w1[3].abs() < 1e-15
        );
    }
}
