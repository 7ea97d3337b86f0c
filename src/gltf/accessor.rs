//! Accessor decoding: every accessor (strided, sparse, normalized and quantized integer
//! types) becomes `f64` or `u32` values, so the rest of the pipeline never sees the encoding;
//! and the triangles of a primitive in any of the triangle modes.

use super::read::Document;
use anyhow::{bail, Result};
use glam::DVec3;
use serde_json::Value;

impl Document {
    /// Decode accessor `index` as `f64` values, `count * components` of them, row-major.
    /// Every size is checked against the bytes behind it before anything is allocated, and
    /// every value must be finite.
    pub fn read_f64(&self, index: usize) -> Result<(Vec<f64>, usize)> {
        let (out, ncomp) = self.read_f64_as_stored(index)?;
        if let Some(k) = out.iter().position(|v| !v.is_finite()) {
            bail!(self.err(format!(
                "accessor {index} has a NaN or infinite value at element {}",
                k / ncomp
            )));
        }
        Ok((out, ncomp))
    }

    /// [`Document::read_f64`] with NaN and infinite values kept as stored, for the mends that
    /// write them right (a normal or tangent an exporter divided by a zero length).
    pub fn read_f64_as_stored(&self, index: usize) -> Result<(Vec<f64>, usize)> {
        let acc = self.accessor(index)?;
        let ncomp = acc.ncomp;
        let backing = match acc.view {
            Some(view) => Some(self.view_slice(view, acc.offset, acc.count, acc.elem_size())?),
            None => {
                // Zeros (plus sparse values): as many as the largest accessor the buffers
                // really hold, which is what such an accessor stands beside (a morph target
                // of a mesh).
                if acc.count > self.largest_backed_count() {
                    bail!(self.err(format!(
                        "accessor {index} has no bufferView and claims {} elements, more than any accessor the file holds",
                        acc.count
                    )));
                }
                None
            }
        };
        let total = acc
            .count
            .checked_mul(ncomp)
            .ok_or_else(|| self.err(format!("accessor {index} claims too many elements")))?;
        let mut out = vec![0.0f64; total];
        if let Some((bytes, stride)) = backing {
            for i in 0..acc.count {
                let base = i * stride;
                for c in 0..ncomp {
                    out[i * ncomp + c] = acc.decode(bytes, base + c * acc.comp_size());
                }
            }
        }
        if let Some(sparse) = self.json["accessors"][index].get("sparse") {
            self.apply_sparse(index, &acc, sparse, &mut out)?;
        }
        Ok((out, ncomp))
    }

    /// Overwrite the elements a sparse accessor lists with its values.
    fn apply_sparse(
        &self,
        index: usize,
        acc: &Accessor,
        sparse: &Value,
        out: &mut [f64],
    ) -> Result<()> {
        let ncomp = acc.ncomp;
        let n = sparse["count"].as_u64().unwrap_or(0) as usize;
        if n > acc.count {
            bail!(self.err(format!(
                "accessor {index}: sparse count {n} exceeds its count {}",
                acc.count
            )));
        }
        let indices = self.sparse_indices(index, sparse)?;
        let val = &sparse["values"];
        let vv = val["bufferView"].as_u64().ok_or_else(|| {
            self.err(format!(
                "accessor {index}: sparse values without bufferView"
            ))
        })? as usize;
        let vo = val["byteOffset"].as_u64().unwrap_or(0) as usize;
        let (vbytes, _) = self.view_slice(vv, vo, n, acc.elem_size())?;
        let sparse_acc = Accessor {
            view: None,
            offset: 0,
            ..*acc
        };
        for (k, &target) in indices.iter().enumerate() {
            if target >= acc.count {
                bail!(self.err(format!(
                    "accessor {index}: sparse index {target} is out of range"
                )));
            }
            for c in 0..ncomp {
                out[target * ncomp + c] =
                    sparse_acc.decode(vbytes, k * acc.elem_size() + c * acc.comp_size());
            }
        }
        Ok(())
    }

    /// The element indices `sparse` (the sparse part of accessor `index`) lists, in its order,
    /// as stored.
    pub(super) fn sparse_indices(&self, index: usize, sparse: &Value) -> Result<Vec<usize>> {
        let n = sparse["count"].as_u64().unwrap_or(0) as usize;
        let ind = &sparse["indices"];
        let idx_ty = ind["componentType"].as_u64().unwrap_or(0) as u32;
        let idx_size = match idx_ty {
            5121 | 5123 | 5125 => comp_size(idx_ty).unwrap_or(4),
            _ => bail!(self.err(format!("accessor {index}: bad sparse index type"))),
        };
        let iv = ind["bufferView"].as_u64().ok_or_else(|| {
            self.err(format!(
                "accessor {index}: sparse indices without bufferView"
            ))
        })? as usize;
        let io = ind["byteOffset"].as_u64().unwrap_or(0) as usize;
        let (ibytes, _) = self.view_slice(iv, io, n, idx_size)?;
        Ok((0..n)
            .map(|k| read_uint(ibytes, k * idx_size, idx_ty) as usize)
            .collect())
    }

    /// The largest element count among the accessors whose buffer views hold them.
    fn largest_backed_count(&self) -> usize {
        *self
            .largest_backed
            .get_or_init(|| self.find_largest_backed())
    }

    fn find_largest_backed(&self) -> usize {
        (0..super::read::arr(&self.json, "accessors").len())
            .filter_map(|i| {
                let acc = self.accessor(i).ok()?;
                let view = acc.view?;
                self.view_slice(view, acc.offset, acc.count, acc.elem_size())
                    .ok()
                    .map(|_| acc.count)
            })
            .max()
            .unwrap_or(0)
    }

    /// Decode an index accessor (unsigned integer scalars).
    pub fn read_indices(&self, index: usize) -> Result<Vec<u32>> {
        let (v, ncomp) = self.read_f64(index)?;
        if ncomp != 1 {
            bail!(self.err(format!("accessor {index} used as indices is not SCALAR")));
        }
        Ok(v.into_iter().map(|x| x as u32).collect())
    }

    /// Element count of accessor `index`.
    pub fn accessor_count(&self, index: usize) -> Result<usize> {
        Ok(self.accessor(index)?.count)
    }

    fn accessor(&self, index: usize) -> Result<Accessor> {
        let a = self
            .json
            .get("accessors")
            .and_then(|a| a.get(index))
            .ok_or_else(|| self.err(format!("accessor {index} does not exist")))?;
        let ty = a["componentType"].as_u64().unwrap_or(0) as u32;
        comp_size(ty)
            .ok_or_else(|| self.err(format!("accessor {index} has unknown componentType {ty}")))?;
        let kind = a["type"].as_str().unwrap_or("");
        let Some(ncomp) = components(kind) else {
            bail!(self.err(format!("accessor {index} has unknown type {kind:?}")));
        };
        Ok(Accessor {
            view: a["bufferView"].as_u64().map(|v| v as usize),
            offset: a["byteOffset"].as_u64().unwrap_or(0) as usize,
            count: a["count"].as_u64().unwrap_or(0) as usize,
            ty,
            ncomp,
            normalized: a["normalized"].as_bool().unwrap_or(false),
        })
    }

    /// The bytes of `count` elements of `elem` bytes starting `offset` bytes into buffer view
    /// `view`, and the stride between elements; an error unless the view holds them all.
    fn view_slice(
        &self,
        view: usize,
        offset: usize,
        count: usize,
        elem: usize,
    ) -> Result<(&[u8], usize)> {
        let bv = self
            .json
            .get("bufferViews")
            .and_then(|v| v.get(view))
            .ok_or_else(|| self.err(format!("bufferView {view} does not exist")))?;
        let buffer = bv["buffer"].as_u64().unwrap_or(u64::MAX) as usize;
        let data = self
            .buffers
            .get(buffer)
            .ok_or_else(|| self.err(format!("bufferView {view} names missing buffer {buffer}")))?;
        let start = bv["byteOffset"].as_u64().unwrap_or(0) as usize;
        let len = bv["byteLength"].as_u64().unwrap_or(0) as usize;
        let stride = bv["byteStride"]
            .as_u64()
            .map(|s| s as usize)
            .unwrap_or(elem);
        if stride < elem {
            bail!(self.err(format!(
                "bufferView {view} has a byteStride of {stride}, less than the {elem}-byte elements read from it"
            )));
        }
        let end = start
            .checked_add(len)
            .filter(|&e| e <= data.len())
            .ok_or_else(|| {
                self.err(format!(
                    "bufferView {view} reaches past the end of buffer {buffer}"
                ))
            })?;
        let need = match count {
            0 => Some(offset),
            _ => (count - 1)
                .checked_mul(stride)
                .and_then(|x| x.checked_add(offset))
                .and_then(|x| x.checked_add(elem)),
        };
        if need.is_none_or(|n| n > len) {
            bail!(self.err(format!(
                "an accessor reads past the end of bufferView {view}"
            )));
        }
        Ok((&data[start + offset..end], stride))
    }
}

#[derive(Clone, Copy)]
struct Accessor {
    view: Option<usize>,
    offset: usize,
    count: usize,
    ty: u32,
    ncomp: usize,
    normalized: bool,
}

impl Accessor {
    fn comp_size(&self) -> usize {
        comp_size(self.ty).unwrap_or(4)
    }
    fn elem_size(&self) -> usize {
        self.comp_size() * self.ncomp
    }
    fn decode(&self, b: &[u8], at: usize) -> f64 {
        let raw = raw_component(b, at, self.ty);
        if !self.normalized {
            return raw;
        }
        // glTF 2.0 normalization rules (section 3.11).
        match self.ty {
            5120 => (raw / 127.0).max(-1.0),
            5121 => raw / 255.0,
            5122 => (raw / 32767.0).max(-1.0),
            5123 => raw / 65535.0,
            5125 => raw / 4294967295.0,
            _ => raw,
        }
    }
}

pub(super) fn comp_size(ty: u32) -> Option<usize> {
    match ty {
        5120 | 5121 => Some(1),
        5122 | 5123 => Some(2),
        5125 | 5126 => Some(4),
        _ => None,
    }
}

/// The component of type `ty` at `at` in `b` as stored (little-endian): a float's value, a
/// normalized integer's raw integer (what min and max state).
pub(super) fn raw_component(b: &[u8], at: usize, ty: u32) -> f64 {
    match ty {
        5126 => f32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]]) as f64,
        5120 => b[at] as i8 as f64,
        5122 => i16::from_le_bytes([b[at], b[at + 1]]) as f64,
        _ => read_uint(b, at, ty) as f64,
    }
}

pub(super) fn read_uint(b: &[u8], at: usize, ty: u32) -> u64 {
    match ty {
        5121 | 5120 => b[at] as u64,
        5123 | 5122 => u16::from_le_bytes([b[at], b[at + 1]]) as u64,
        _ => u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]]) as u64,
    }
}

/// Accessor `acc` as 3-vectors, refused (naming `what`) when it is not VEC3 or holds a NaN or
/// infinite value.
pub fn read_vec3(doc: &Document, acc: usize, what: &str) -> Result<Vec<DVec3>> {
    let (v, n) = doc.read_f64(acc)?;
    if n != 3 {
        bail!(doc.err(format!("{what} (accessor {acc}) is not VEC3")));
    }
    let out: Vec<DVec3> = v
        .chunks_exact(3)
        .map(|c| DVec3::new(c[0], c[1], c[2]))
        .collect();
    if let Some(i) = out.iter().position(|p| !p.is_finite()) {
        bail!(doc.err(format!(
            "{what} (accessor {acc}) has a NaN or infinite value at element {i}"
        )));
    }
    Ok(out)
}

/// Triangles of a primitive with `n` vertices (TRIANGLES, TRIANGLE_STRIP and TRIANGLE_FAN;
/// other modes are an error naming `what`).
pub fn read_triangles(doc: &Document, p: &Value, n: usize, what: &str) -> Result<Vec<[u32; 3]>> {
    let what = what.trim_end();
    let mode = p["mode"].as_u64().unwrap_or(4);
    let indices: Vec<u32> = match p["indices"].as_u64() {
        Some(a) => doc.read_indices(a as usize)?,
        None => (0..n as u32).collect(),
    };
    if let Some(&bad) = indices.iter().find(|&&i| i as usize >= n) {
        bail!(doc.err(format!("{what} has index {bad} but only {n} vertices")));
    }
    Ok(match mode {
        4 => {
            if !indices.len().is_multiple_of(3) {
                bail!(doc.err(format!(
                    "{what} has a TRIANGLES index count that is not a multiple of 3"
                )));
            }
            indices
                .chunks_exact(3)
                .map(|c| [c[0], c[1], c[2]])
                .collect()
        }
        5 => (2..indices.len())
            .map(|i| {
                if i % 2 == 0 {
                    [indices[i - 2], indices[i - 1], indices[i]]
                } else {
                    [indices[i - 1], indices[i - 2], indices[i]]
                }
            })
            .collect(),
        6 => (2..indices.len())
            .map(|i| [indices[0], indices[i - 1], indices[i]])
            .collect(),
        m => {
            let kind = ["POINTS", "LINES", "LINE_LOOP", "LINE_STRIP"]
                .get(m as usize)
                .copied()
                .unwrap_or("unknown");
            bail!(doc.err(format!(
                "{what} is not made of triangles (mode {m}, {kind}); morph tweening needs a triangle mesh"
            )))
        }
    })
}

/// Attribute `name` of primitive `p` (None when it has none): `ncomp` components per element
/// and one element per vertex of the primitive's `n`, or an error naming `what`.
pub fn read_attribute(
    doc: &Document,
    p: &Value,
    name: &str,
    ncomp: usize,
    n: usize,
    what: &str,
) -> Result<Option<Vec<f64>>> {
    let Some(acc) = p["attributes"][name].as_u64() else {
        return Ok(None);
    };
    let (v, c) = doc.read_f64(acc as usize)?;
    if c != ncomp {
        bail!(doc.err(format!(
            "{what} {name} (accessor {acc}) has {c} components, not {ncomp}"
        )));
    }
    if v.len() != n * ncomp {
        bail!(doc.err(format!(
            "{what} {name} (accessor {acc}) has {} elements but POSITION has {n}",
            v.len() / ncomp
        )));
    }
    Ok(Some(v))
}

/// [`read_attribute`] of a VEC3 attribute as vectors.
pub fn read_attribute3(
    doc: &Document,
    p: &Value,
    name: &str,
    n: usize,
    what: &str,
) -> Result<Option<Vec<DVec3>>> {
    Ok(read_attribute(doc, p, name, 3, n, what)?.map(|v| {
        v.chunks_exact(3)
            .map(|c| DVec3::new(c[0], c[1], c[2]))
            .collect()
    }))
}

/// Components of an accessor `type` (`SCALAR` 1 ... `MAT4` 16).
pub(crate) fn components(ty: &str) -> Option<usize> {
    Some(match ty {
        "SCALAR" => 1,
        "VEC2" => 2,
        "VEC3" => 3,
        "VEC4" | "MAT2" => 4,
        "MAT3" => 9,
        "MAT4" => 16,
        _ => return None,
    })
}
