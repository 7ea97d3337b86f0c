//! Legs found from the skeleton alone: chains from a branching joint down to a leaf that comes
//! near the floor. Works for bipeds and quadrupeds and for any joint naming.

use super::rig::{flat, Rig, UP};
use super::track::Track;
use glam::DVec3;
use serde::Serialize;

/// A summed foot velocity or root travel shorter than this (scene units per second, or scene
/// units) gives no forward direction.
const NO_DIRECTION: f64 = 1e-9;

/// A chain end is a foot when its floor (a low percentile of its heights, [`FLOOR_PERCENTILE`])
/// is within this fraction of the character's size of the lowest chain end's floor ...
pub const LOW_FRACTION: f64 = 0.15;
/// ... and the joint it hangs from stands this fraction of the size above it on average (legs
/// span from the pelvis or shoulders down; fingers and foot controls at floor level do not).
/// RobotExpressive's hips stand 0.17-0.19 of its size above its feet in its run (a big head
/// on short legs), which 0.2 refused.
pub const SPAN_FRACTION: f64 = 0.15;
/// ... and its chain is at least this fraction of the longest such chain (fingers of a long
/// arm that brushes the floor are not feet).
pub const LENGTH_FRACTION: f64 = 0.6;
/// Percentile of a joint's heights taken as its floor (robust to a frame through the ground).
pub const FLOOR_PERCENTILE: f64 = 0.02;

/// The floor of a joint from its `heights`: their [`FLOOR_PERCENTILE`] percentile.
pub fn floor(mut heights: Vec<f64>) -> f64 {
    heights.sort_by(f64::total_cmp);
    heights[((heights.len() - 1) as f64 * FLOOR_PERCENTILE) as usize]
}

/// Median of `v` (not empty): its middle value, the upper of the two middle ones for an even
/// count.
pub fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Hips closer than this fraction of the character's size to the body's mid-plane are centred.
pub const SIDE_FRACTION: f64 = 0.02;

#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Side {
    Left,
    Right,
    Center,
}

#[derive(Clone, Debug)]
pub struct Leg {
    /// Joints from the one below the branch (hip) to the leaf (the contact point).
    pub chain: Vec<usize>,
    /// Hip, knee and ankle for two-bone IK: the two adjacent segments of greatest total length.
    pub ik: Option<[usize; 3]>,
    pub side: Side,
    /// Length of the chain (sum of its segments).
    pub length: f64,
    pub name: String,
}

impl Leg {
    pub fn end(&self) -> usize {
        *self.chain.last().unwrap()
    }

    pub fn top(&self) -> usize {
        self.chain[0]
    }
}

/// The legs of the rig's skeleton, judged on the frames of `tracks`, their sides not yet known
/// (see [`sided`]).
pub fn find(rig: &Rig, tracks: &[&Track], size: f64) -> Vec<Leg> {
    let first = &tracks[0].pos[0];
    let mut chains = Vec::new();
    let bones = rig.skeleton_child_counts();
    for leaf in (0..rig.len()).filter(|&j| rig.skeleton[j] && bones[j] == 0) {
        let mut chain = vec![leaf];
        let mut j = leaf;
        while let Some(p) = rig.parent[j].filter(|&p| rig.skeleton[p] && p != rig.root) {
            if bones[p] != 1 {
                break;
            }
            chain.push(p);
            j = p;
        }
        chain.reverse();
        chains.push(chain);
    }
    let floor_of = |j: usize| {
        floor(
            tracks
                .iter()
                .flat_map(|t| t.pos.iter().map(move |p| p[j].y))
                .collect(),
        )
    };
    let floor = chains
        .iter()
        .map(|c| floor_of(*c.last().unwrap()))
        .fold(f64::INFINITY, f64::min);
    let span = |c: &[usize]| {
        let (Some(branch), end) = (rig.parent[c[0]], c[c.len() - 1]) else {
            return 0.0;
        };
        let (mut sum, mut n) = (0.0, 0);
        for t in tracks {
            for p in &t.pos {
                sum += p[branch].y - p[end].y;
                n += 1;
            }
        }
        sum / n.max(1) as f64
    };
    let mut legs: Vec<Leg> = chains
        .into_iter()
        .filter(|c| {
            c.len() >= 2
                && floor_of(*c.last().unwrap()) - floor <= LOW_FRACTION * size
                && span(c) >= SPAN_FRACTION * size
        })
        .map(|chain| {
            let seg: Vec<f64> = chain
                .windows(2)
                .map(|w| (first[w[1]] - first[w[0]]).length())
                .collect();
            let ik = (0..seg.len().saturating_sub(1))
                .max_by(|&a, &b| (seg[a] + seg[a + 1]).total_cmp(&(seg[b] + seg[b + 1])))
                .map(|i| [chain[i], chain[i + 1], chain[i + 2]]);
            Leg {
                name: rig.names[*chain.last().unwrap()].clone(),
                length: seg.iter().sum(),
                ik,
                side: Side::Center,
                chain,
            }
        })
        .collect();
    let longest = legs.iter().map(|l| l.length).fold(0.0, f64::max);
    legs.retain(|l| l.length >= LENGTH_FRACTION * longest);
    legs
}

/// `legs` with their sides, as the body stands in frame `first` heading `forward`, ordered left
/// before right and longer before shorter.
pub fn sided(mut legs: Vec<Leg>, first: &[DVec3], forward: DVec3, size: f64) -> Vec<Leg> {
    let left = UP.cross(forward);
    if !legs.is_empty() {
        let mid = legs
            .iter()
            .map(|l| first[l.ik.map_or(l.top(), |k| k[0])])
            .sum::<DVec3>()
            / legs.len() as f64;
        for leg in &mut legs {
            let hip = leg.ik.map_or(leg.top(), |k| k[0]);
            let d = (first[hip] - mid).dot(left);
            leg.side = if d > SIDE_FRACTION * size {
                Side::Left
            } else if d < -SIDE_FRACTION * size {
                Side::Right
            } else {
                Side::Center
            };
        }
    }
    legs.sort_by(|a, b| {
        (a.side, -a.length, a.end())
            .partial_cmp(&(b.side, -b.length, b.end()))
            .unwrap()
    });
    legs
}

/// Horizontal forward direction of `tracks` together, where a clip's own travel gives none (an
/// idle, a T-pose): feet move backwards relative to the body while they are low (in stance), so
/// forward is against their mean low-phase velocity; failing that, the root's travel; failing
/// that, glTF's +Z.
pub fn forward(rig: &Rig, legs: &[Leg], tracks: &[&Track]) -> DVec3 {
    let mut sum = DVec3::ZERO;
    for t in tracks {
        for leg in legs {
            let e = leg.end();
            let hs: Vec<f64> = t.pos.iter().map(|p| p[e].y).collect();
            let lo = hs.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = hs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            for (i, &h) in hs.iter().enumerate() {
                if h <= lo + 0.3 * (hi - lo) {
                    sum -= flat(t.velocity(i, e) - t.velocity(i, rig.body));
                }
            }
        }
    }
    if sum.length() > NO_DIRECTION {
        return sum.normalize();
    }
    let travel: DVec3 = tracks
        .iter()
        .map(|t| flat(t.pos[t.len() - 1][rig.body] - t.pos[0][rig.body]))
        .sum();
    if travel.length() > NO_DIRECTION {
        travel.normalize()
    } else {
        DVec3::Z
    }
}
