//! Normals of tween frames.
//!
//! Each frame gets normals recomputed from its own positions (area-weighted face normals),
//! smoothed only across *smoothing groups*: input vertices that sit on the same welded vertex
//! and had the same input normal. A hard edge (split vertices with different normals) stays
//! hard; a UV seam (split vertices with one normal) stays smooth.
//!
//! Authored normals are kept: the output normal of a vertex is its key's authored normal turned
//! by the shortest-arc rotation that takes the key's recomputed normal to the frame's, blended
//! between the segment's two keys by t. Keys therefore come out exactly as authored, and
//! in-betweens follow the surface. Tangents are turned by the same rotation as their normal.

use glam::{DQuat, DVec3};

/// Input normals closer than this (cosine) on one welded vertex share a smoothing group.
pub const SAME_NORMAL_COS: f64 = 0.9999;

pub struct Smoothing {
    /// Group of each input vertex.
    group: Vec<u32>,
    groups: usize,
}

impl Smoothing {
    /// Groups for input vertices with welded ids `welded` and input normals `normals`.
    pub fn new(welded: &[u32], normals: &[DVec3]) -> Smoothing {
        let mut first_of: Vec<Vec<u32>> =
            vec![Vec::new(); welded.iter().map(|&w| w as usize + 1).max().unwrap_or(0)];
        let mut group = Vec::with_capacity(welded.len());
        let mut groups = 0u32;
        let mut group_normal: Vec<DVec3> = Vec::new();
        for (v, &w) in welded.iter().enumerate() {
            let n = normals[v].normalize_or_zero();
            let found = first_of[w as usize]
                .iter()
                .copied()
                .find(|&g| group_normal[g as usize].dot(n) >= SAME_NORMAL_COS);
            let g = found.unwrap_or_else(|| {
                let g = groups;
                groups += 1;
                group_normal.push(n);
                first_of[w as usize].push(g);
                g
            });
            group.push(g);
        }
        Smoothing {
            group,
            groups: groups as usize,
        }
    }

    /// Area-weighted vertex normals of `positions` (input vertices) over `triangles`.
    pub fn normals(&self, positions: &[DVec3], triangles: &[[u32; 3]]) -> Vec<DVec3> {
        let mut acc = vec![DVec3::ZERO; self.groups];
        for t in triangles {
            let [a, b, c] = t.map(|i| i as usize);
            let n = (positions[b] - positions[a]).cross(positions[c] - positions[a]);
            for v in [a, b, c] {
                acc[self.group[v] as usize] += n;
            }
        }
        self.group
            .iter()
            .map(|&g| acc[g as usize].normalize_or_zero())
            .collect()
    }
}

/// Shortest-arc rotation from `from` to `to`; identity when either is zero.
pub fn arc(from: DVec3, to: DVec3) -> DQuat {
    if from == DVec3::ZERO || to == DVec3::ZERO {
        DQuat::IDENTITY
    } else {
        DQuat::from_rotation_arc(from, to)
    }
}

/// Output normal of a frame at `t` between keys a and b: each key's authored normal carried by
/// the rotation of its recomputed normal onto the frame's, blended by `t` (on the sphere where
/// they are far apart).
pub fn carry(
    authored_a: DVec3,
    rec_a: DVec3,
    authored_b: DVec3,
    rec_b: DVec3,
    rec_frame: DVec3,
    t: f64,
) -> DVec3 {
    let na = arc(rec_a, rec_frame) * authored_a;
    if t == 0.0 {
        return na;
    }
    let nb = arc(rec_b, rec_frame) * authored_b;
    if t == 1.0 {
        return nb;
    }
    // Far apart (keys whose blended targets turn a normal each their own way), at a constant
    // rate: the normalized blend would swing most of the way near the middle.
    let cos = na.dot(nb);
    if (-SLERP_FLOOR..SLERP_BELOW).contains(&cos) && na != DVec3::ZERO && nb != DVec3::ZERO {
        return DQuat::IDENTITY.slerp(arc(na, nb), t) * na;
    }
    let n = na * (1.0 - t) + nb * t;
    n.try_normalize().unwrap_or(rec_frame)
}

/// Carried normals farther apart than this (cosine; 30 degrees) are interpolated on the sphere
/// at a constant rate; nearer, their normalized blend is within 0.14 degrees of that.
pub const SLERP_BELOW: f64 = 0.866;

/// ... unless they are nearly opposite (cosine below minus this), where no turn between them
/// is preferred: there the normalized blend, or the frame's own normal where it vanishes.
pub const SLERP_FLOOR: f64 = 0.9999;

/// The TANGENT (xyz) delta of a vertex whose normal turns from `base_normal` to `normal`:
/// its tangent `t` turned by the same shortest arc and made orthogonal to `normal` again, its
/// length kept.
pub fn tangent_delta(base_normal: DVec3, normal: DVec3, t: [f64; 4]) -> DVec3 {
    let t3 = DVec3::new(t[0], t[1], t[2]);
    let rotated = arc(base_normal.normalize_or_zero(), normal) * t3;
    let ortho = (rotated - normal * normal.dot(rotated))
        .try_normalize()
        .unwrap_or(rotated);
    ortho * t3.length() - t3
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Key normals 120 degrees apart, the surface not turning (each key's recomputed normal the
    /// frame's): the frames between turn at a constant rate, 40 degrees a third (the normalized
    /// blend gave 30 and 90 degrees: a 60-degree step in the middle).
    #[test]
    fn far_apart_key_normals_turn_at_a_constant_rate() {
        let (a, b) = (DVec3::X, DVec3::new(-0.5, 0.75f64.sqrt(), 0.0));
        let rec = DVec3::Z;
        for (t, want) in [(1.0 / 3.0, 40.0), (2.0 / 3.0, 80.0), (0.5, 60.0)] {
            let n = carry(a, rec, b, rec, rec, t);
            let got = n.angle_between(a).to_degrees();
            assert!((got - want).abs() < 1e-9, "t {t}: {got} degrees from a");
            assert!((n.length() - 1.0).abs() < 1e-12);
        }
        // Near each other, the normalized blend (outputs unchanged where no key pair is far
        // apart), within 0.14 degrees of the constant rate.
        let c = DVec3::new(0.9, (1.0f64 - 0.81).sqrt(), 0.0);
        let n = carry(a, rec, c, rec, rec, 0.25);
        assert_eq!(n, (a * 0.75 + c * 0.25).normalize());
        assert!(
            (n.angle_between(a) - 0.25 * c.angle_between(a))
                .abs()
                .to_degrees()
                < 0.14
        );
    }
}
