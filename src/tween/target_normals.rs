//! NORMAL (and TANGENT) deltas for authored targets that move positions without them.
//!
//! In the glTF rig layout a key plays its authored weights, so a key of position-only targets
//! shows the base normals, while the frames between keys take normals that follow the surface
//! ([`super::normals`]): the shading would jump at every key (a face rig keyed at 10 a second:
//! 18-24 degrees on average into and out of each key). Each such target is given the deltas of
//! its own shape instead, as Blender's exporter writes shape-key normals: at each vertex the
//! base normal turned by the shortest arc from the base's recomputed normal to the target
//! pose's, less the base normal (and the tangent turned with it); zero where the target moves
//! nothing around the vertex or turns its normal by less than [`LEAST_CHANGE`]. A key on one
//! target then shows what a frame on it shows; a key blending several shows their normals
//! blended, as every glTF renderer blends them, and the frames next to it carry from there. The
//! targets' positions stay exactly as authored. Only for meshes with frames between keys (a
//! rig baked at the output's rate goes out as it came in).
//!
//! ```text
//! a mesh whose base has NORMAL, target 3 moves POSITION only
//!   -> target 3: NORMAL = arc(rec(base), rec(base + target 3)) * n - n
//! ```

use super::keys::MorphMesh;
use super::normals::{arc, tangent_delta, Smoothing};
use super::weld::Welded;
use glam::DVec3;
use rayon::prelude::*;

/// A normal's change smaller than this (a unit vector's; 0.06 degrees) is left out: the far
/// tail of a smooth shape, which would otherwise make every vertex the shape touches a stored
/// one (a face rig's 52 shapes: 52% of the rows, 26% above this).
pub const LEAST_CHANGE: f64 = 1e-3;

/// The targets of `mesh` that [`derive`] gives normals: those that move positions but carry no
/// NORMAL deltas (in some primitive), where every primitive has normals.
pub fn wanted(mesh: &MorphMesh) -> Vec<usize> {
    if mesh.primitives.iter().any(|p| p.normals.is_none()) {
        return Vec::new();
    }
    (0..mesh.target_count)
        .filter(|&i| {
            let lacks = mesh.primitives.iter().any(|p| p.target_nrm[i].is_none());
            let moves =
                (mesh.primitives.iter()).any(|p| p.target_pos[i].iter().any(|d| *d != DVec3::ZERO));
            lacks && moves
        })
        .collect()
}

/// Give every target of `mesh` that moves positions but carries no NORMAL deltas (in some
/// primitive) the deltas of its shape, and TANGENT deltas where the base has tangents and the
/// target none, counting them in `mesh.normals_given`. Nothing where a primitive has no
/// normals.
pub fn derive(mesh: &mut MorphMesh) {
    let wanted = wanted(mesh);
    if wanted.is_empty() {
        return;
    }
    let welded = Welded::build(mesh);
    let raw: Vec<DVec3> = (mesh.primitives.iter())
        .flat_map(|p| p.normals.iter().flatten().copied())
        .collect();
    let unit: Vec<DVec3> = raw.iter().map(|n| n.normalize_or_zero()).collect();
    let smoothing = Smoothing::new(&welded.of_vertex, &unit);
    let base = mesh.pose(&[]);
    let rec_base = smoothing.normals(&base, &welded.input_triangles);
    let derived: Vec<Vec<DVec3>> = wanted
        .par_iter()
        .map(|&i| {
            let mut w = vec![0.0; mesh.target_count];
            w[i] = 1.0;
            let rec = smoothing.normals(&mesh.pose(&w), &welded.input_triangles);
            (rec_base.iter().zip(&rec).zip(unit.iter().zip(&raw)))
                .map(|((rb, r), (n, raw))| {
                    let d = arc(*rb, *r) * *n - *raw;
                    match rb == r || d.length() < LEAST_CHANGE {
                        true => DVec3::ZERO,
                        false => d,
                    }
                })
                .collect()
        })
        .collect();
    for (&i, d) in wanted.iter().zip(derived) {
        let mut offset = 0;
        let mut any = false;
        for p in &mut mesh.primitives {
            let range = offset..offset + p.base.len();
            offset += p.base.len();
            let d = &d[range];
            if p.target_nrm[i].is_some() || d.iter().all(|x| *x == DVec3::ZERO) {
                continue;
            }
            any = true;
            let normals = p.normals.as_ref().expect("normals present");
            if let (Some(tangents), None) = (&p.tangents, &p.target_tan[i]) {
                p.target_tan[i] = Some(
                    (normals.iter().zip(d).zip(tangents))
                        .map(|((n, d), t)| match *d == DVec3::ZERO {
                            true => DVec3::ZERO,
                            false => tangent_delta(*n, *n + *d, *t),
                        })
                        .collect(),
                );
            }
            p.target_nrm[i] = Some(d.to_vec());
        }
        mesh.normals_given += any as usize;
    }
}
