//! A clip from a second file of the same character (each animation exported on its own, as
//! Mixamo and most DCC exports give them, the skin often left out): its channels carried onto
//! the first file's nodes by name, once the nodes it moves (and the nodes above them) are found
//! there, hanging from the same parents and resting in the same place wherever the clip does
//! not key them (what a clip leaves unkeyed comes from the first file's rest pose).
//!
//! Example: `inbetween blend walk.glb run.glb -o jog.glb` blends walk.glb's animation with
//! run.glb's on walk.glb's character.

use super::rig::{Clip, Rig, Trs};
use crate::gltf::{arr, listed, Document, Path};
use anyhow::{bail, Result};
use std::collections::{BTreeSet, HashMap};

/// Rest translations of the two files agree within this part of the longer one, plus
/// [`SAME_OFFSET`] of the skeleton's longest rest offset (unitless).
pub const SAME_TRANSLATION: f64 = 1e-3;
/// See [`SAME_TRANSLATION`] (unitless: a node at the origin in one file and 1e-4 of a bone
/// away in the other rests in the same place).
pub const SAME_OFFSET: f64 = 1e-4;
/// Rest rotations agree within this angle (radians; 0.06 degrees, well above a float's
/// rounding of a unit quaternion).
pub const SAME_ANGLE: f64 = 1e-3;
/// Rest scales agree within this part of the larger (unitless).
pub const SAME_SCALE: f64 = 1e-3;

/// Each node's name, None where it has none.
fn names(doc: &Document) -> Vec<Option<&str>> {
    arr(&doc.json, "nodes")
        .iter()
        .map(|n| n.get("name").and_then(|v| v.as_str()))
        .collect()
}

/// A node's name without its namespace (`mixamorig1:Hips` -> `Hips`): exports of one
/// character may differ in it (Mixamo numbers the prefix of a rig uploaded again; Maya
/// references add one), so a name not found whole is looked for by this part.
fn base(name: &str) -> &str {
    name.rsplit(':').next().unwrap_or(name)
}

/// [`base`] without the number Blender appends to a name the scene already holds
/// (`Armature.001`: the second character imported into one scene, exported with its clip):
/// a name found neither whole nor by its base is looked for by this part.
fn stem(name: &str) -> &str {
    let name = base(name);
    match name.rsplit_once('.') {
        Some((stem, n))
            if !stem.is_empty() && n.len() >= 3 && n.bytes().all(|b| b.is_ascii_digit()) =>
        {
            stem
        }
        _ => name,
    }
}

/// How a node is called in a message: its name quoted, else its index.
fn called(names: &[Option<&str>], i: usize) -> String {
    names[i].map_or_else(|| format!("node {i}"), |n| format!("{n:?}"))
}

/// What differs between rest transforms `a` (the character's) and `b` (the clip file's) in
/// the parts the clip does not key (`keyed` tells which), or None; `size` is the skeleton's
/// longest rest offset.
fn rest_differs(a: &Trs, b: &Trs, keyed: impl Fn(Path) -> bool, size: f64) -> Option<String> {
    let (ta, tb) = (a.t, b.t);
    let tol = SAME_TRANSLATION * ta.length().max(tb.length()) + SAME_OFFSET * size;
    if !keyed(Path::Translation) && ta.distance(tb) > tol {
        return Some(format!(
            "translation {:?} against {:?}",
            tb.to_array(),
            ta.to_array()
        ));
    }
    let turn = a.r.inverse() * b.r;
    let angle = 2.0 * turn.xyz().length().atan2(turn.w.abs());
    if !keyed(Path::Rotation) && angle > SAME_ANGLE {
        return Some(format!("rotation {:.3} degrees away", angle.to_degrees()));
    }
    let (sa, sb) = (a.s, b.s);
    if !keyed(Path::Scale) && sa.distance(sb) > SAME_SCALE * sa.length().max(sb.length()) {
        return Some(format!(
            "scale {:?} against {:?}",
            sb.to_array(),
            sa.to_array()
        ));
    }
    None
}

/// `clip` of `doc_b` (read into `rig_b`) carried onto `rig_a`, the character of `doc_a`:
/// every node it moves, and every node above one, matched by name (else by name without its
/// namespace, [`base`], or without Blender's number too, [`stem`]; where nodes of `doc_a`
/// share a name, the one under the parent's match), with the same parent and, where the clip
/// does not key it, the same rest transform; its morph weights channels kept where `doc_a`
/// has a node of that name with as many weights, dropped otherwise. Errors name `doc_b` and
/// what differs.
pub fn carry(
    doc_a: &Document,
    rig_a: &Rig,
    doc_b: &Document,
    rig_b: &Rig,
    clip: &Clip,
) -> Result<Clip> {
    let (names_a, names_b) = (names(doc_a), names(doc_b));
    let (mut by_name, mut by_base, mut by_stem) = (HashMap::new(), HashMap::new(), HashMap::new());
    for (i, name) in names_a.iter().enumerate() {
        if let Some(name) = name {
            by_name.entry(*name).or_insert_with(Vec::new).push(i);
            by_base.entry(base(name)).or_insert_with(Vec::new).push(i);
            by_stem.entry(stem(name)).or_insert_with(Vec::new).push(i);
        }
    }
    let named = |n: &str| {
        (by_name.get(n))
            .or_else(|| by_base.get(base(n)))
            .or_else(|| by_stem.get(stem(n)))
    };
    // Parents first: of the nodes of the same name (Blender names a bone's mesh after it), the
    // one under the node matched to the parent, else the only one.
    let mut map: Vec<Option<usize>> = vec![None; rig_b.len()];
    for &b in &rig_b.order {
        let found = names_b[b].and_then(named);
        let Some(candidates) = found else {
            continue;
        };
        let parent = rig_b.parent[b].map(|p| map[p]);
        let under = |a: &&usize| match parent {
            None => rig_a.parent[**a].is_none(),
            Some(p) => p.is_some() && rig_a.parent[**a] == p,
        };
        let same_parent: Vec<usize> = candidates.iter().filter(under).copied().collect();
        map[b] = match (&same_parent[..], &candidates[..]) {
            ([one], _) | ([], [one]) => Some(*one),
            _ => None,
        };
    }
    let mut needed = BTreeSet::new();
    for c in clip.channels.iter().filter(|c| c.path != Path::Weights) {
        let mut node = Some(c.node);
        while let Some(b) = node.filter(|&b| needed.insert(b)) {
            node = rig_b.parent[b];
        }
    }
    let other = doc_a.path.display();
    let missing: Vec<String> = (needed.iter())
        .filter(|&&b| map[b].is_none())
        .map(|&b| match names_b[b].and_then(named) {
            Some(list) => format!(
                "{} ({} nodes of that name there)",
                called(&names_b, b),
                list.len()
            ),
            None => called(&names_b, b),
        })
        .collect();
    if !missing.is_empty() {
        bail!(doc_b.err(format!(
            "animation {:?} moves nodes that {other} lacks (matched by name): {}",
            clip.name,
            listed(&missing)
        )));
    }
    let find = |b: usize| map[b];
    let size = (needed.iter())
        .map(|&b| rig_b.rest.local[b].t.length())
        .fold(0.0, f64::max);
    let keyed = clip.animated();
    for &b in &needed {
        let a = find(b).expect("every needed node was found");
        let (parent_a, parent_b) = (rig_a.parent[a], rig_b.parent[b]);
        if parent_a != parent_b.and_then(find) {
            let here = parent_b.map_or("the scene".to_string(), |p| called(&names_b, p));
            let there = parent_a.map_or("the scene".to_string(), |p| called(&names_a, p));
            bail!(doc_b.err(format!(
                "node {} hangs from {here} here but from {there} in {other}: not the same skeleton",
                called(&names_b, b)
            )));
        }
        let keys = |p: Path| keyed.contains(&(b, p));
        if let Some(what) = rest_differs(&rig_a.rest.local[a], &rig_b.rest.local[b], keys, size) {
            bail!(doc_b.err(format!(
                "node {} rests elsewhere than in {other} and animation {:?} does not key it there ({what}): not the same character",
                called(&names_b, b),
                clip.name
            )));
        }
    }
    let channels = (clip.channels.iter())
        .filter_map(|c| {
            let a = find(c.node)?;
            let fits = c.path != Path::Weights || rig_a.rest.weights[a].len() == c.width;
            fits.then(|| super::rig::Channel {
                node: a,
                ..c.clone()
            })
        })
        .collect();
    Ok(Clip {
        channels,
        ..clip.clone()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_match_without_namespace_and_blender_s_number() {
        assert_eq!(base("mixamorig1:Hips"), "Hips");
        assert_eq!(stem("mixamorig1:Hips"), "Hips");
        assert_eq!(stem("Armature.001"), "Armature");
        assert_eq!(stem("Armature.1000"), "Armature");
        // Not Blender's number: kept whole.
        assert_eq!(stem("Finger.01"), "Finger.01");
        assert_eq!(stem("Bone.L"), "Bone.L");
        assert_eq!(stem(".001"), ".001");
        assert_eq!(stem("v.00a"), "v.00a");
    }
}
