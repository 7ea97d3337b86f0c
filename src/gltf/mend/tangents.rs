//! Tangents ([`tangents`]): a TANGENT is a unit vector and a sign, its w exactly 1 or -1 (the
//! validator's ACCESSOR_VECTOR3_NON_UNIT and ACCESSOR_INVALID_SIGN). Writers break both:
//! UnityGLTF wrote the Meta avatars' w as -0.998 (its issue 121: 13,400 errors), and
//! MikkTSpace leaves a zero tangent on a sliver triangle that glTF-Transform's `tangents`
//! and Blender's exporter have written (glTF-Transform issue 1859, glTF-Blender-Exporter
//! issue 110). A w is written as its sign (0 as 1); a vector off unit length divided by its
//! length; a zero one (a normal map there is undefined, black in three.js) made the tangents
//! of the vertices it shares triangles with, summed, less their part along its normal, or any
//! unit vector across its normal where those cancel. As with normals, a morph primitive's
//! vectors are left as read (its targets carry TANGENT deltas from them), its signs not.

use super::normals::off_unit;
use super::Column;
use crate::gltf::accessor::{read_triangles, read_vec3};
use crate::gltf::build::BinBuilder;
use crate::gltf::read::{arr, quoted_name, Document};
use glam::DVec3;
use serde_json::Value;

/// Make every float TANGENT attribute of the output a unit vector with a sign of 1 or -1 (see
/// the module comment), in place in `bin` (the views placed by `write::begin`), from the values
/// `doc` reads; returns a line for each mesh with such tangents.
pub fn tangents(doc: &Document, json: &mut Value, bin: &mut BinBuilder) -> Vec<String> {
    let mut lines = Vec::new();
    let mut done = std::collections::BTreeSet::new();
    let mut rebound: Vec<(usize, Vec<f32>)> = Vec::new();
    for (m, mesh) in arr(json, "meshes").iter().enumerate() {
        let (mut signs, mut scaled, mut zero) = (0, 0, 0);
        for p in arr(mesh, "primitives") {
            let morph = !arr(p, "targets").is_empty();
            let Some(acc) = p["attributes"]["TANGENT"].as_u64().map(|a| a as usize) else {
                continue;
            };
            let count = json["accessors"][acc]["count"].as_u64().unwrap_or(0) as usize;
            let column = Column::of(json, bin, acc, count).filter(|c| c.component == 5126);
            let Some(column) = column.filter(|_| done.insert(acc)) else {
                continue;
            };
            let Ok((values, 4)) = doc.read_f64_as_stored(acc) else {
                continue;
            };
            let off = |v: &[f64]| !morph && off_unit(DVec3::from_slice(v));
            let unsigned = |v: &[f64]| v[3] != 1.0 && v[3] != -1.0;
            if !values.chunks_exact(4).any(|v| off(v) || unsigned(v)) {
                continue;
            }
            let mut written: Vec<f32> = values.iter().map(|&x| x as f32).collect();
            let mut zeros = Vec::new();
            for (i, v) in values.chunks_exact(4).enumerate() {
                if unsigned(v) {
                    signs += 1;
                    let w = if v[3] < 0.0 { -1.0 } else { 1.0 };
                    column.set_float(&mut bin.bytes, i, 3, w);
                    written[4 * i + 3] = w;
                }
                if !off(v) {
                    continue;
                }
                let t = DVec3::from_slice(v);
                match t.length() {
                    l if l.is_finite() && l > 1e-12 => {
                        scaled += 1;
                        set_xyz(&column, &mut bin.bytes, &mut written, i, t / l);
                    }
                    _ => zeros.push(i),
                }
            }
            if !zeros.is_empty() {
                zero += zeros.len();
                for (i, t) in across_normals(doc, p, &written, &zeros) {
                    set_xyz(&column, &mut bin.bytes, &mut written, i, t);
                }
            }
            rebound.push((acc, written));
        }
        if signs + scaled + zero > 0 {
            let name = quoted_name(mesh, || format!("{m}"));
            lines.push(format!(
                "mesh {name}: {signs} tangent signs were not 1 or -1 and {} tangents not of unit length as glTF requires ({zero} of them zero or not numbers); written as their signs, divided by their lengths, the others along their neighbours' across the normal",
                scaled + zero
            ));
        }
    }
    super::bounds::declared_follow(json, rebound, 4);
    lines
}

/// Write tangent `i`'s vector `t` into `bin` and into `written`, its sign left.
fn set_xyz(column: &Column, bin: &mut [u8], written: &mut [f32], i: usize, t: DVec3) {
    for (c, x) in t.to_array().into_iter().enumerate() {
        column.set_float(bin, i, c, x as f32);
        written[4 * i + c] = x as f32;
    }
}

/// A unit tangent for each vertex of `zeros` (whose tangents in `tangents`, 4 floats a vertex,
/// are zero) of triangle primitive `p`: the sum of the tangents of the vertices it shares a
/// triangle with, less its part along the vertex's normal; where that is zero (or the primitive
/// has no normals or triangles that read), any unit vector across the normal (along x without
/// a normal).
fn across_normals(
    doc: &Document,
    p: &Value,
    tangents: &[f32],
    zeros: &[usize],
) -> Vec<(usize, DVec3)> {
    let count = tangents.len() / 4;
    let normals = (p["attributes"]["NORMAL"].as_u64())
        .and_then(|a| read_vec3(doc, a as usize, "NORMAL").ok())
        .filter(|v| v.len() == count);
    let mut sums = vec![DVec3::ZERO; count];
    let is_zero: std::collections::HashSet<usize> = zeros.iter().copied().collect();
    if let Ok(triangles) = read_triangles(doc, p, count, "primitive") {
        let tangent = |i: usize| {
            DVec3::new(
                tangents[4 * i] as f64,
                tangents[4 * i + 1] as f64,
                tangents[4 * i + 2] as f64,
            )
        };
        for t in triangles.iter().map(|t| t.map(|i| i as usize)) {
            for &a in &t {
                if is_zero.contains(&a) {
                    for &b in t.iter().filter(|&&b| !is_zero.contains(&b)) {
                        sums[a] += tangent(b);
                    }
                }
            }
        }
    }
    (zeros.iter())
        .map(|&i| {
            let n = normals.as_ref().and_then(|n| n[i].try_normalize());
            let t = match n {
                Some(n) => (sums[i] - n * sums[i].dot(n))
                    .try_normalize()
                    .unwrap_or_else(|| n.any_orthonormal_vector()),
                None => sums[i].try_normalize().unwrap_or(DVec3::X),
            };
            (i, t)
        })
        .collect()
}
