//! The `spline` method: C1 interpolation across all keys in gradient space.
//!
//! For the segment from key a to key b = a + 1, every triangle's deformation gradient from key
//! a to the neighbouring keys a-1, b and b+1 is split into rotation and stretch (as the seed
//! does for b alone). The rotation logs (relative to key a, whose own log is 0) and the
//! stretches (key a's is I) are interpolated with a non-uniform Catmull-Rom spline (a cubic
//! Hermite whose tangents are the neighbours' differences over their time spans), so the motion
//! is C1 across keys; positions come from the same Poisson solve as the seed's.
//!
//! Paths: every connected component turns about a pivot (the point its mean rotation from key
//! a to the other knots leaves in place, least squares), which itself follows the spline; its
//! centroid c(u) = p(u) + R(u) (c_a - p), with R(u) the component's area-weighted mean log
//! interpolated like the triangles'. An arm swinging about the shoulder moves on the arc, a
//! rigid motion follows its screw, and the keys' centroids are met exactly.
//!
//! Ends: without a looping track, a missing neighbour is mirrored (log -r, stretch 2I - S,
//! pivot 2p_a - p_b), which gives the end key the chord's tangent. A looping track (last
//! key equal to the first) wraps around. Rotation branches across keys: each neighbour's log
//! is taken on the branch (angle + 2 pi k about its axis) closest to the linear continuation
//! of the segment's own log.

use crate::gradient::{deformation, frame, gradient_operator, polar, quat_log};
use crate::interpolate::axis_angle_matrix;
use crate::solve::{scatter, Pattern, Placement};
use anyhow::Result;
use glam::{DMat3, DVec3};
use rayon::prelude::*;
use std::f64::consts::PI;

/// A rotation below this angle (radians) counts as none when its branch is chosen: its axis is
/// the noise of single-precision positions (about 1e-7 relative).
const NO_TURN: f64 = 1e-5;

/// A component some triangle of which turns by more than this (radians, from key a to b)
/// interpolates its rotations as a twist about the component's mean axis after a swing
/// (see [`twist_swing`]); below it, as logs (the same to second order, and measured a little
/// better on the morph-keyframe birds).
const SPLIT_ABOVE: f64 = std::f64::consts::PI;

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

/// All keys of a track (welded positions) and their times.
pub struct SplineTrack<'a> {
    keys: &'a [Vec<DVec3>],
    times: &'a [f64],
    looped: bool,
    pattern: &'a Pattern,
    triangles: &'a [[u32; 3]],
}

/// Per valid triangle of a segment.
struct Tri {
    corners: [u32; 3],
    /// Rotation logs relative to key a of keys prev, b, next.
    r: [DVec3; 3],
    /// Gradient operator at corners 1 and 2 of the reference triangle (corner 0: minus sum).
    g: [DVec3; 2],
    /// S_j g for j = prev, b, next and both gradients.
    sg: [[DVec3; 2]; 3],
    /// Where the component is split (see [`SPLIT_ABOVE`]): the twist angles of prev, b, next
    /// about `axis` (any number of turns), `r` then holding the swings' logs; otherwise `axis`
    /// is zero and `r` the rotations' logs.
    twist: [f64; 3],
    axis: DVec3,
}

struct Path {
    centroid: DVec3,
    pivot: [DVec3; 4],
    log: [DVec3; 3],
    /// Centroids at prev, a, b, next (the path of a component that does not turn as one).
    centroids: [DVec3; 4],
    /// How far the pivot path is followed, 0 to 1 (see [`RIGID_SPREAD`], [`LOOSE_SPREAD`]).
    rigid: f64,
}

pub struct SplineSegment {
    /// Times of prev, a, b, next (prev and next may be mirrored or wrapped).
    t: [f64; 4],
    tris: Vec<Tri>,
    placement: Placement,
    /// Per component: its centroid at key a, its pivots at prev, a, b, next and its mean
    /// rotation logs (relative to key a) at prev, b, next.
    paths: Vec<Path>,
    /// Positions of a and b, for vertices no valid triangle touches.
    x: [Vec<DVec3>; 2],
}

/// The rotation with log `r` as a twist about `axis` after a swing: R = twist(angle) swing,
/// the swing's axis across `axis`; the twist angle in (-2 pi, 2 pi], the caller choosing its
/// whole turns so that they agree across neighbouring triangles. A part turned by nearly 360
/// degrees, whose own rotation axis the shear of its neighbours tilts anywhere, then keeps a
/// twist near 360 degrees about `axis` and a small swing, so it passes 180 degrees about
/// `axis` half way.
fn twist_swing(r: DVec3, axis: DVec3) -> (f64, DVec3) {
    let q = glam::DQuat::from_scaled_axis(r);
    let along = q.xyz().dot(axis);
    let norm = (q.w * q.w + along * along).sqrt();
    if norm < 1e-12 {
        // A half-turn swing: no twist can be told apart.
        return (0.0, r);
    }
    let twist = glam::DQuat::from_xyzw(axis.x * along, axis.y * along, axis.z * along, q.w) / norm;
    let swing = twist.conjugate() * q;
    (2.0 * along.atan2(q.w), quat_log(swing))
}

/// The values of prev and next (`v[0]`, `v[2]`; `v[1]` is b's, key a's is zero) on the branch
/// `nearest` picks closest to the linear continuation of b's over their times, or mirrored
/// (-b, 2b) where the neighbour is missing.
fn around<T>(
    v: &mut [T; 3],
    [prev, next]: [Option<(usize, f64)>; 2],
    [ta, tb]: [f64; 2],
    nearest: impl Fn(T, T) -> T,
) where
    T: Copy + std::ops::Mul<f64, Output = T> + std::ops::Neg<Output = T>,
{
    let b = v[1];
    v[0] = prev.map_or(-b, |(_, tp)| nearest(v[0], b * ((tp - ta) / (tb - ta))));
    v[2] = next.map_or(b * 2.0, |(_, tn)| {
        nearest(v[2], b * ((tn - ta) / (tb - ta)))
    });
}

/// The rotation matrix of log `r` (angle times axis).
fn rotation(r: DVec3) -> DMat3 {
    let angle = r.length();
    if angle > 0.0 {
        axis_angle_matrix(r / angle, angle)
    } else {
        DMat3::IDENTITY
    }
}

/// `angle` plus the whole turns that bring it nearest to `target`.
fn nearest_turn(angle: f64, target: f64) -> f64 {
    angle + 2.0 * PI * ((target - angle) / (2.0 * PI)).round()
}

/// Hermite weights of (prev, a, b, next) at u in [0, 1] for knot times t.
pub fn weights(t: [f64; 4], u: f64) -> [f64; 4] {
    let (u2, u3) = (u * u, u * u * u);
    let h00 = 2.0 * u3 - 3.0 * u2 + 1.0;
    let h10 = u3 - 2.0 * u2 + u;
    let h01 = -2.0 * u3 + 3.0 * u2;
    let h11 = u3 - u2;
    let span = t[2] - t[1];
    let alpha = span / (t[2] - t[0]);
    let beta = span / (t[3] - t[1]);
    [
        -h10 * alpha,
        h00 - h11 * beta,
        h01 + h10 * alpha,
        h11 * beta,
    ]
}

/// True when a track's last key repeats its first (RMS difference below 1e-6 of the first key's
/// bounding-box diagonal): a cycle the spline wraps around.
pub fn is_loop(keys: &[Vec<DVec3>]) -> bool {
    keys.len() > 2 && {
        let d = crate::weld::bbox_diagonal(&keys[0]).max(f64::MIN_POSITIVE);
        crate::weld::rms_rel(&keys[0], &keys[keys.len() - 1], d) < 1e-6
    }
}

/// The branch of log `r` (angle + 2 pi k about its axis) closest to `target`.
fn closest_branch(r: DVec3, target: DVec3) -> DVec3 {
    let angle = r.length();
    // Below NO_TURN the axis is the noise of single-precision positions: any axis will do.
    let axis = if angle > NO_TURN {
        r / angle
    } else {
        target.try_normalize().unwrap_or(DVec3::X)
    };
    (-2..=2)
        .map(|k| r + axis * (2.0 * PI * k as f64))
        .min_by(|p, q| {
            (*p - target)
                .length_squared()
                .total_cmp(&(*q - target).length_squared())
        })
        .unwrap_or(r)
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
        })
    }

    /// Neighbour key of segment a on side `before` (key a-1) or after (key a+2): its index
    /// and time, or None when it must be mirrored.
    fn neighbour(&self, a: usize, before: bool) -> Option<(usize, f64)> {
        let k = self.keys.len();
        let period = self.times[k - 1] - self.times[0];
        if before {
            if a > 0 {
                Some((a - 1, self.times[a - 1]))
            } else if self.looped {
                Some((k - 2, self.times[k - 2] - period))
            } else {
                None
            }
        } else if a + 2 < k {
            Some((a + 2, self.times[a + 2]))
        } else if self.looped {
            let j = a + 2 - (k - 1);
            Some((j, self.times[j] + period))
        } else {
            None
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
        let m = per.len();
        let mut edges: std::collections::HashMap<(u32, u32), Vec<u32>> =
            std::collections::HashMap::with_capacity(3 * m / 2);
        for (t, tri) in per.iter().enumerate() {
            if let Some(tri) = tri {
                let [a, b, c] = tri.corners;
                for (u, v) in [(a, b), (b, c), (c, a)] {
                    edges
                        .entry((u.min(v), u.max(v)))
                        .or_default()
                        .push(t as u32);
                }
            }
        }
        // Best-first growth: the triangle with the smallest rotation on the frontier is fixed
        // next (from the neighbour that reached it), so triangles near 180 degrees, whose
        // branch is ambiguous, are decided last from settled neighbours.
        use std::cmp::Reverse;
        use std::collections::BinaryHeap;
        // Angles equal within 1e-9 rad tie, and the lower triangle index goes first: when two
        // regions are both unrotated (a part turned by exactly 360 degrees), the region listed
        // first in the file stays fixed.
        let key = |r: DVec3| (r.length() * 1e9) as u64;
        let mut done = vec![false; m];
        let mut heap: BinaryHeap<Reverse<(u64, u32, u32)>> = BinaryHeap::new(); // (angle, tri, from)
        let mut starts: Vec<u32> = (0..m as u32)
            .filter(|&t| per[t as usize].is_some())
            .collect();
        starts.sort_by_key(|&t| {
            (
                key(per[t as usize].as_ref().map_or(DVec3::ZERO, |x| x.r[1])),
                t,
            )
        });
        for &start in &starts {
            if done[start as usize] {
                continue;
            }
            heap.push(Reverse((0, start, u32::MAX)));
            while let Some(Reverse((_, t, from))) = heap.pop() {
                if done[t as usize] {
                    continue;
                }
                done[t as usize] = true;
                order.push((t, from));
                if from != u32::MAX {
                    let target = per[from as usize].as_ref().map_or(DVec3::ZERO, |x| x.r[1]);
                    if let Some(tri) = per[t as usize].as_mut() {
                        tri.r[1] = closest_branch(tri.r[1], target);
                    }
                }
                let Some(tri) = per[t as usize].as_ref() else {
                    continue;
                };
                let (corners, r) = (tri.corners, tri.r[1]);
                let [a, b, c] = corners;
                for (u, v) in [(a, b), (b, c), (c, a)] {
                    for &nb in &edges[&(u.min(v), u.max(v))] {
                        if !done[nb as usize] {
                            if let Some(n) = per[nb as usize].as_ref() {
                                let guess = closest_branch(n.r[1], r);
                                heap.push(Reverse((key(guess), nb, t)));
                            }
                        }
                    }
                }
            }
        }
        order
    }

    /// Prepare segment a (keys a and a + 1).
    pub fn segment(&self, a: usize) -> Result<SplineSegment> {
        let b = a + 1;
        let (x0, x1) = (&self.keys[a], &self.keys[b]);
        let prev = self.neighbour(a, true);
        let next = self.neighbour(a, false);
        let (ta, tb) = (self.times[a], self.times[b]);
        let t = [
            prev.map_or(2.0 * ta - tb, |p| p.1),
            ta,
            tb,
            next.map_or(2.0 * tb - ta, |p| p.1),
        ];
        // Reference areas: each triangle's residual is weighted by its area (the continuous
        // Poisson energy), in the right-hand side and in A below; components' mean rotations
        // are weighted by it too.
        let areas: Vec<f64> = self
            .triangles
            .par_iter()
            .map(|&[i, j, k]| {
                let [a, b, c] = [i, j, k].map(|v| x0[v as usize]);
                0.5 * (b - a).cross(c - a).length()
            })
            .collect();
        let weight = |area: f64| if WEIGHTED { area } else { 1.0 };
        let per: Vec<Option<Tri>> = self
            .triangles
            .par_iter()
            .zip(&areas)
            .map(|(&[i, j, k], &area)| {
                let v = frame(x0[i as usize], x0[j as usize], x0[k as usize])?;
                let v_inv = v.inverse();
                let g3 = gradient_operator(&v_inv);
                let w = weight(area);
                let g = [g3[1] * w, g3[2] * w];
                let rs = |key: usize| -> (DVec3, DMat3) {
                    let x = &self.keys[key];
                    let (q, s) = polar(&deformation(
                        &v_inv,
                        x[i as usize],
                        x[j as usize],
                        x[k as usize],
                    ));
                    (quat_log(q), s)
                };
                // Shortest-arc logs for now; branches are made consistent below.
                let (rb, sb) = rs(b);
                let (rp, sp) = match prev {
                    Some((p, _)) => rs(p),
                    None => (DVec3::ZERO, DMat3::IDENTITY * 2.0 - sb),
                };
                let (rn, sn) = match next {
                    Some((n, _)) => rs(n),
                    None => (DVec3::ZERO, sb * 2.0 - DMat3::IDENTITY),
                };
                Some(Tri {
                    corners: [i, j, k],
                    r: [rp, rb, rn],
                    g,
                    sg: [
                        [sp * g[0], sp * g[1]],
                        [sb * g[0], sb * g[1]],
                        [sn * g[0], sn * g[1]],
                    ],
                    twist: [0.0; 3],
                    axis: DVec3::X,
                })
            })
            .collect();
        let mut per = per;
        let order = self.consistent_branches(&mut per);
        for tri in per.iter_mut().flatten() {
            around(&mut tri.r, [prev, next], [ta, tb], closest_branch);
        }
        let n = x0.len();
        // A = sum w g g^T: pass sqrt(w) g (the stored g carry w).
        let grads = per.iter().zip(&areas).map(|(t, &area)| {
            t.as_ref().map(|t| {
                let s = 1.0 / weight(area).sqrt();
                [-(t.g[0] + t.g[1]) * s, t.g[0] * s, t.g[1] * s]
            })
        });
        let valid: Vec<[u32; 3]> = per.iter().flatten().map(|t| t.corners).collect();
        let placement = Placement::new(self.pattern, n, grads, &valid)?;
        let paths = self.paths(
            &per,
            &areas,
            &placement,
            x0,
            x1,
            [prev.map(|(k, _)| k), next.map(|(k, _)| k)],
        );
        // Twist and swing per triangle about its component's axis; the twist angles (one
        // number each) are unwrapped over the same settling order as the logs' branches.
        let mut turn = vec![0.0f64; placement.component_count()];
        for tri in per.iter().flatten() {
            if let Some(c) = placement.component_of(tri.corners[0] as usize) {
                turn[c] = turn[c].max(tri.r[1].length());
            }
        }
        per.par_iter_mut().flatten().for_each(|tri| {
            let c = placement.component_of(tri.corners[0] as usize);
            if c.is_none_or(|c| turn[c] <= SPLIT_ABOVE) {
                // Logs as they are (axis zero: see `frame`).
                tri.axis = DVec3::ZERO;
                return;
            }
            let axis = c
                .map(|c| paths[c].log[1].normalize_or_zero())
                .filter(|a| *a != DVec3::ZERO)
                .unwrap_or(DVec3::X);
            tri.axis = axis;
            for j in 0..3 {
                let (t, s) = twist_swing(tri.r[j], axis);
                tri.twist[j] = t;
                tri.r[j] = s;
            }
        });
        for &(t, from) in &order {
            let target = if from == u32::MAX {
                0.0
            } else {
                per[from as usize].as_ref().map_or(0.0, |x| x.twist[1])
            };
            if let Some(tri) = per[t as usize].as_mut().filter(|x| x.axis != DVec3::ZERO) {
                tri.twist[1] = nearest_turn(tri.twist[1], target);
            }
        }
        for tri in per.iter_mut().flatten().filter(|x| x.axis != DVec3::ZERO) {
            around(&mut tri.twist, [prev, next], [ta, tb], nearest_turn);
            if prev.is_none() {
                tri.r[0] = -tri.r[1];
            }
            if next.is_none() {
                tri.r[2] = 2.0 * tri.r[1];
            }
        }
        let tris: Vec<Tri> = per.into_iter().flatten().collect();
        Ok(SplineSegment {
            t,
            tris,
            placement,
            paths,
            x: [x0.clone(), x1.clone()],
        })
    }

    /// Each component's path (see the module): mean logs of its triangles (weighted by their
    /// `areas`, indexed like `per`) and pivots at the knots; `around` are the keys of prev and
    /// next where they exist.
    fn paths(
        &self,
        per: &[Option<Tri>],
        areas: &[f64],
        placement: &Placement,
        x0: &[DVec3],
        x1: &[DVec3],
        around: [Option<usize>; 2],
    ) -> Vec<Path> {
        let m = placement.component_count();
        // Each triangle with its component and reference area.
        let members: Vec<(&Tri, usize, f64)> = per
            .iter()
            .zip(areas)
            .filter_map(|(tri, &area)| {
                let tri = tri.as_ref()?;
                Some((tri, placement.component_of(tri.corners[0] as usize)?, area))
            })
            .collect();
        let mut logs = vec![[DVec3::ZERO; 3]; m];
        let mut weight = vec![0.0; m];
        for &(tri, c, area) in &members {
            for (l, r) in logs[c].iter_mut().zip(tri.r) {
                *l += r * area;
            }
            weight[c] += area;
        }
        for (l, w) in logs.iter_mut().zip(&weight) {
            if *w > 0.0 {
                *l = l.map(|r| r / *w);
            }
        }
        let mut spread = vec![0.0; m];
        for &(tri, c, area) in &members {
            spread[c] += area * (tri.r[1] - logs[c][1]).length_squared();
        }
        let ca = placement.centroids(x0);
        let cb = placement.centroids(x1);
        let cp = around[0].map(|k| placement.centroids(&self.keys[k]));
        let cn = around[1].map(|k| placement.centroids(&self.keys[k]));
        (0..m)
            .map(|c| {
                // Knots that exist: (rotation from key a, centroid).
                let mut knots = vec![(rotation(logs[c][1]), cb[c])];
                knots.extend(cp.as_ref().map(|p| (rotation(logs[c][0]), p[c])));
                knots.extend(cn.as_ref().map(|n| (rotation(logs[c][2]), n[c])));
                // Pivot: (I - R_j) p = c_j - R_j c_a for every knot j, least squares; along the
                // segment's axis (where the turn to b leaves it free) it stays level with c_a.
                let axis = logs[c][1].normalize_or_zero();
                let along = DMat3::from_cols(axis * axis.x, axis * axis.y, axis * axis.z);
                let mut lhs = DMat3::IDENTITY * PIVOT_PULL + along;
                let mut rhs = ca[c] * PIVOT_PULL + along * ca[c];
                for (r, cj) in &knots {
                    let k = DMat3::IDENTITY - *r;
                    lhs += k.transpose() * k;
                    rhs += k.transpose() * (*cj - *r * ca[c]);
                }
                let p = lhs.inverse() * rhs;
                let at = |r: DVec3, cj: DVec3| cj - rotation(r) * (ca[c] - p);
                let pb = at(logs[c][1], cb[c]);
                let pp = match &cp {
                    Some(cp) => at(logs[c][0], cp[c]),
                    _ => 2.0 * p - pb,
                };
                let pn = match &cn {
                    Some(cn) => at(logs[c][2], cn[c]),
                    _ => 2.0 * pb - p,
                };
                let scatter = (spread[c] / weight[c].max(f64::MIN_POSITIVE)).sqrt();
                let angle = logs[c][1].length();
                let rigid = if angle > 0.0 {
                    let x = ((LOOSE_SPREAD - scatter / angle) / (LOOSE_SPREAD - RIGID_SPREAD))
                        .clamp(0.0, 1.0);
                    x * x * (3.0 - 2.0 * x)
                } else {
                    0.0
                };
                let cpc = match &cp {
                    Some(cp) => cp[c],
                    _ => 2.0 * ca[c] - cb[c],
                };
                let cnc = match &cn {
                    Some(cn) => cn[c],
                    _ => 2.0 * cb[c] - ca[c],
                };
                Path {
                    centroid: ca[c],
                    pivot: [pp, p, pb, pn],
                    log: logs[c],
                    centroids: [cpc, ca[c], cb[c], cnc],
                    rigid,
                }
            })
            .collect()
    }

    /// The frame at u in [0, 1] of segment a (built anew: use [`SplineSegment`] for several).
    pub fn frame(&self, a: usize, u: f64) -> Vec<DVec3> {
        self.segment(a)
            .map(|s| s.frame(u))
            .unwrap_or_else(|_| self.keys[a].clone())
    }
}

impl SplineSegment {
    pub fn factor_nonzeros(&self) -> usize {
        self.placement.factor_nonzeros()
    }

    pub fn frame(&self, u: f64) -> Vec<DVec3> {
        let w = weights(self.t, u);
        let mut rhs = vec![[0.0f64; 3]; self.x[0].len()];
        for tri in &self.tris {
            let r = tri.r[0] * w[0] + tri.r[1] * w[2] + tri.r[2] * w[3];
            let rot = if tri.axis == DVec3::ZERO {
                rotation(r)
            } else {
                let twist = tri.twist[0] * w[0] + tri.twist[1] * w[2] + tri.twist[2] * w[3];
                let q = glam::DQuat::from_axis_angle(tri.axis, twist)
                    * glam::DQuat::from_scaled_axis(r);
                DMat3::from_quat(q)
            };
            let v: [DVec3; 2] = std::array::from_fn(|k| {
                rot * (tri.sg[0][k] * w[0]
                    + tri.g[k] * w[1]
                    + tri.sg[1][k] * w[2]
                    + tri.sg[2][k] * w[3])
            });
            scatter(&mut rhs, tri.corners, v[0], v[1]);
        }
        let centroids: Vec<DVec3> = self
            .paths
            .iter()
            .map(|path| {
                let k = path.pivot;
                // The pivot now; the centroid keeps its offset from the pivot, turned.
                let p = k[0] * w[0] + k[1] * w[1] + k[2] * w[2] + k[3] * w[3];
                let rot = rotation(path.log[0] * w[0] + path.log[1] * w[2] + path.log[2] * w[3]);
                let c = path.centroids;
                let spline = c[0] * w[0] + c[1] * w[1] + c[2] * w[2] + c[3] * w[3];
                spline.lerp(p + rot * (path.centroid - k[1]), path.rigid)
            })
            .collect();
        self.placement
            .place(rhs, &centroids, |v| self.x[0][v].lerp(self.x[1][v], u))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hermite_weights_interpolate_the_keys_and_sum_to_one() {
        let t = [-1.0, 0.0, 1.0, 2.5];
        for u in [0.0, 0.3, 0.7, 1.0] {
            let w = weights(t, u);
            assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        }
        assert_eq!(weights(t, 0.0), [0.0, 1.0, 0.0, 0.0]);
        let w1 = weights(t, 1.0);
        assert!(
            w1[0].abs() < 1e-15
                && w1[1].abs() < 1e-15
                && (w1[2] - 1.0).abs() < 1e-15
                && w1[3].abs() < 1e-15
        );
    }
}
