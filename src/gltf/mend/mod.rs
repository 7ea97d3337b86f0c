//! Mend stage (on write): data the glTF specification constrains that an input breaks, made
//! right as the input is copied into the output, so that the Khronos validator accepts what we
//! write. Each fix is what every viewer that copes with the broken data does anyway; a line
//! names it where it is more than a codec's rounding.
//!
//! The mends, one a file, in the order `begin` runs them: [`undefined_keys`], [`inverse_binds`],
//! [`weights`] (and joints named twice), [`rotations`], [`key_times`], [`restart_indices`],
//! [`strides`] (with the bounds of the VEC4 data these change) in [`all`]; then [`bounds`],
//! [`normals`], [`tangents`], [`sparse_parts`], [`image_types`], [`image_data_uris`],
//! [`undeclared_extensions`], [`scene_roots`], [`target_extras`], and the animations
//! ([`empty_animations`], [`repeated_channels`], [`negative_times`]: the channels and clips left
//! out, and the clips moved to start at 0 s, when the output is written), and the
//! [`empty_lists`] and meshes with no primitive (left out when the output is written).

mod animations;
mod bounds;
mod data_uris;
mod empty;
mod extensions;
mod images;
mod indices;
mod inverse_binds;
mod key_times;
mod keys;
mod normals;
mod rotations;
mod scenes;
mod sparse;
mod strides;
mod tangents;
mod targets;
mod weights;

pub use animations::{
    drop_empty_animations, drop_repeated_channels, empty_animations, repeated_channels, shadowed,
};
pub use bounds::bounds;
pub use data_uris::image_data_uris;
pub use empty::{drop_empty_lists, empty_lists};
pub use extensions::undeclared_extensions;
pub use images::image_types;
pub use indices::restart_indices;
pub use inverse_binds::inverse_binds;
pub use key_times::{key_times, negative_times, start_at_zero};
pub use keys::undefined_keys;
pub use normals::normals;
pub use rotations::rotations;
pub use scenes::scene_roots;
pub use sparse::sparse_parts;
pub use strides::strides;
pub use tangents::tangents;
pub use targets::target_extras;
pub use weights::weights;

use super::build::BinBuilder;
use super::read::{arr, listed};
use serde_json::Value;

/// Where one accessor's elements (SCALAR, VEC3 or VEC4) lie in the output buffer.
#[derive(Clone, Copy)]
struct Column {
    start: usize,
    stride: usize,
    component: u64,
    /// Bytes of one component.
    size: usize,
}

impl Column {
    /// Attribute `acc` of `json` with its data in `bin` (views placed by `write::begin`), when
    /// it is a plain (not sparse) VEC4 accessor of `count` elements inside the buffer.
    fn of(json: &Value, bin: &BinBuilder, acc: usize, count: usize) -> Option<Column> {
        Column::of_width(json, bin, acc, count, 4)
    }

    /// As [`Column::of`], for a plain accessor of `width` components (SCALAR, VEC3, VEC4).
    fn of_width(
        json: &Value,
        bin: &BinBuilder,
        acc: usize,
        count: usize,
        width: u64,
    ) -> Option<Column> {
        let a = &json["accessors"][acc];
        let component = a["componentType"].as_u64()?;
        let size: u64 = match component {
            5121 => 1,
            5123 => 2,
            5126 => 4,
            _ => return None,
        };
        let ty = match width {
            1 => "SCALAR",
            3 => "VEC3",
            _ => "VEC4",
        };
        if a["type"].as_str() != Some(ty)
            || a.get("sparse").is_some()
            || a["count"].as_u64() != Some(count as u64)
        {
            return None;
        }
        let v = a["bufferView"].as_u64()? as usize;
        let view = bin.views.get(v)?;
        // Checked: a hostile file's counts and offsets must not wrap past the bounds test.
        let start = view["byteOffset"]
            .as_u64()?
            .checked_add(a["byteOffset"].as_u64().unwrap_or(0))?;
        let stride = view["byteStride"].as_u64().unwrap_or(width * size);
        let end = (count as u64)
            .checked_sub(1)?
            .checked_mul(stride)?
            .checked_add(start)?
            .checked_add(width * size)?;
        let view_end = view["byteOffset"]
            .as_u64()?
            .checked_add(view["byteLength"].as_u64()?)?;
        let (start, stride, size) = (start as usize, stride as usize, size as usize);
        (stride >= width as usize * size && end <= view_end && end <= bin.bytes.len() as u64)
            .then_some(Column {
                start,
                stride,
                component,
                size,
            })
    }

    /// A plain float accessor `acc` of `width` components (see [`Column::of_width`]) and its
    /// values as stored, element by element.
    fn floats(
        json: &Value,
        bin: &BinBuilder,
        acc: usize,
        width: u64,
    ) -> Option<(Column, Vec<f32>)> {
        let count = json["accessors"][acc]["count"].as_u64()? as usize;
        let column =
            Column::of_width(json, bin, acc, count, width).filter(|c| c.component == 5126)?;
        let values = (0..count)
            .flat_map(|i| (0..width as usize).map(move |c| (i, c)))
            .map(|(i, c)| column.float(&bin.bytes, i, c))
            .collect();
        Some((column, values))
    }

    fn at(&self, i: usize, c: usize) -> usize {
        self.start + i * self.stride + c * self.size
    }

    fn uint(&self, bytes: &[u8], i: usize, c: usize) -> u32 {
        let p = self.at(i, c);
        match self.component {
            5121 => bytes[p] as u32,
            _ => u16::from_le_bytes([bytes[p], bytes[p + 1]]) as u32,
        }
    }

    fn set_uint(&self, bytes: &mut [u8], i: usize, c: usize, j: u32) {
        let p = self.at(i, c);
        match self.component {
            5121 => bytes[p] = j as u8,
            _ => bytes[p..p + 2].copy_from_slice(&(j as u16).to_le_bytes()),
        }
    }

    fn float(&self, bytes: &[u8], i: usize, c: usize) -> f32 {
        let p = self.at(i, c);
        f32::from_le_bytes(bytes[p..p + 4].try_into().unwrap())
    }

    fn set_float(&self, bytes: &mut [u8], i: usize, c: usize, w: f32) {
        let p = self.at(i, c);
        bytes[p..p + 4].copy_from_slice(&w.to_le_bytes());
    }
}

/// Every mend, in place in `bin` (the views placed by `write::begin`) and, for the bounds of
/// the data they change, `json`; returns the lines.
pub fn all(json: &mut Value, bin: &mut BinBuilder) -> Vec<String> {
    let mut lines = weights(json, bin);
    lines.extend(rotations(json, bin));
    lines.extend(key_times(json, bin));
    lines.extend(restart_indices(json, bin));
    lines.extend(strides(json, bin));
    bounds::rebound_vec4(json, bin);
    lines
}

/// Every primitive's vertex attributes and each of its morph targets', in the file's order.
fn attribute_sets(json: &Value) -> impl Iterator<Item = &Value> {
    (arr(json, "meshes").iter())
        .flat_map(|mesh| arr(mesh, "primitives"))
        .flat_map(|p| std::iter::once(&p["attributes"]).chain(arr(p, "targets")))
}

/// A line about the accessors `which` (none: no line), `say` given their count, the plural's
/// `s`, `its` or `their`, and the list.
pub(super) fn said_of(
    which: &[String],
    say: impl Fn(usize, &str, &str, &str) -> String,
) -> Vec<String> {
    let (s, its) = match which.len() {
        0 => return Vec::new(),
        1 => ("", "its"),
        _ => ("s", "their"),
    };
    vec![say(which.len(), s, its, &listed(which))]
}
