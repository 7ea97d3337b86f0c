//! Normals ([`normals`]) must be unit vectors: a float NORMAL attribute's vector farther
//! from unit length than the validator allows ([`UNIT_NORMAL`]) is divided by its length; a
//! zero (or not finite) one, which no division mends, is its vertex's area-weighted face normal
//! in its primitive (Babylon.js 9's export of Fox: 994 zero normals its outputs carried; NaN,
//! a zero divided by its length, as assimp's exporter wrote before its pull request 3214, was
//! carried too, and refused by the USD writer). What
//! a renderer shows there was undefined, black in three.js. Primitives without morph targets
//! only: a morph primitive's targets (and the frames `tween` adds) carry NORMAL deltas from
//! its normals as they were, which a different base would turn.

use super::Column;
use crate::gltf::accessor::{read_triangles, read_vec3};
use crate::gltf::build::BinBuilder;
use crate::gltf::read::{arr, quoted_name, Document};
use serde_json::Value;

/// How far from 1 the validator lets a NORMAL's length be (glTF-Validator 2.0.0-dev.3.10: 1.005
/// passes, 1.0068 and 0.993 fail), with a margin.
const UNIT_NORMAL: f64 = 0.006;

/// Whether vector `v` is farther from unit length than the validator allows (or not finite).
pub(super) fn off_unit(v: glam::DVec3) -> bool {
    let length = v.length();
    !(length.is_finite() && (length - 1.0).abs() <= UNIT_NORMAL)
}

/// Make every float NORMAL attribute of the output a unit vector (see the module comment), in
/// place in `bin` (the views placed by `write::begin`), from the values `doc` reads; returns a
/// line for each mesh with such normals.
pub fn normals(doc: &Document, json: &mut Value, bin: &mut BinBuilder) -> Vec<String> {
    let mut lines = Vec::new();
    let mut done = std::collections::BTreeSet::new();
    // Mended accessors and their values as written, for their declared bounds.
    let mut rebound: Vec<(usize, Vec<f32>)> = Vec::new();
    for (m, mesh) in arr(json, "meshes").iter().enumerate() {
        let (mut scaled, mut zero) = (0, 0);
        for p in arr(mesh, "primitives") {
            // A morph primitive's frames carry NORMAL deltas from the normals as read.
            let targets = !arr(p, "targets").is_empty();
            let acc = p["attributes"]["NORMAL"].as_u64().map(|a| a as usize);
            let Some(acc) = acc.filter(|_| !targets) else {
                continue;
            };
            let count = json["accessors"][acc]["count"].as_u64().unwrap_or(0) as usize;
            let column = Column::of_width(json, bin, acc, count, 3).filter(|c| c.component == 5126);
            let Some(column) = column.filter(|_| done.insert(acc)) else {
                continue;
            };
            let Ok((values, 3)) = doc.read_f64_as_stored(acc) else {
                continue;
            };
            let off = |v: &[f64]| off_unit(glam::DVec3::from_slice(v));
            if !values.chunks_exact(3).any(off) {
                continue;
            }
            let faces = face_normals(doc, p, count);
            let mut written: Vec<f32> = values.iter().map(|&x| x as f32).collect();
            for (i, v) in values.chunks_exact(3).enumerate() {
                if !off(v) {
                    continue;
                }
                let n = glam::DVec3::from_slice(v);
                let unit = match n.length() {
                    l if l.is_finite() && l > 1e-12 => {
                        scaled += 1;
                        n / l
                    }
                    _ => {
                        zero += 1;
                        faces[i].try_normalize().unwrap_or(glam::DVec3::Y)
                    }
                };
                for (c, x) in unit.to_array().into_iter().enumerate() {
                    column.set_float(&mut bin.bytes, i, c, x as f32);
                    written[3 * i + c] = x as f32;
                }
            }
            rebound.push((acc, written));
        }
        if scaled + zero > 0 {
            let name = quoted_name(mesh, || format!("{m}"));
            lines.push(format!(
                "mesh {name}: {} normals were not of unit length as glTF requires ({zero} of them zero or not numbers); written divided by their lengths, the others as the normals of their faces",
                scaled + zero
            ));
        }
    }
    super::bounds::declared_follow(json, rebound, 3);
    lines
}

/// The area-weighted sum of the face normals around each of the `count` vertices of triangle
/// primitive `p` (TRIANGLES, strips or fans; zero where none, or where its positions or
/// triangles do not read).
fn face_normals(doc: &Document, p: &Value, count: usize) -> Vec<glam::DVec3> {
    let mut out = vec![glam::DVec3::ZERO; count];
    let positions = (p["attributes"]["POSITION"].as_u64())
        .and_then(|a| read_vec3(doc, a as usize, "POSITION").ok())
        .filter(|v| v.len() == count);
    let triangles = read_triangles(doc, p, count, "primitive").ok();
    let (Some(at), Some(triangles)) = (positions, triangles) else {
        return out;
    };
    for t in triangles.iter().map(|t| t.map(|i| i as usize)) {
        let n = (at[t[1]] - at[t[0]]).cross(at[t[2]] - at[t[0]]);
        for i in t {
            out[i] += n;
        }
    }
    out
}
