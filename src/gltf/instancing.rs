//! `EXT_mesh_gpu_instancing`: a node that draws its mesh once per instance, each placed by its
//! TRANSLATION, ROTATION and SCALE (in the node's frame, before the node's own transform), as
//! gltfpack `-mi` and glTF-Transform `instance` write repeated props.
//!
//! ```text
//! if let Some(inst) = gltf::instances(&doc, node)? { for k in 0..inst.len() { inst.matrix(k) } }
//! ```

use super::{read::Document, MIN_QUATERNION};
use anyhow::{bail, Result};
use glam::{DMat4, DQuat, DVec3};

/// The instances of one node (the three lists of equal length; a missing attribute is the
/// identity: no translation, no rotation, unit scale).
pub struct Instances {
    pub translations: Vec<DVec3>,
    /// Unit quaternions.
    pub rotations: Vec<DQuat>,
    pub scales: Vec<DVec3>,
}

impl Instances {
    pub fn len(&self) -> usize {
        self.translations.len()
    }

    pub fn is_empty(&self) -> bool {
        self.translations.is_empty()
    }

    /// Instance `k`'s transform in its node's frame.
    pub fn matrix(&self, k: usize) -> DMat4 {
        DMat4::from_scale_rotation_translation(
            self.scales[k],
            self.rotations[k],
            self.translations[k],
        )
    }
}

/// The instances of node `index` of `doc` when it has a mesh and `EXT_mesh_gpu_instancing`
/// (floats, or normalized integers for rotations), else `None`; an error says what breaks the
/// extension's rules (a wrong width, counts that differ, a zero quaternion).
pub fn instances(doc: &Document, index: usize) -> Result<Option<Instances>> {
    let node = &doc.json["nodes"][index];
    let attributes = &node["extensions"]["EXT_mesh_gpu_instancing"]["attributes"];
    if !node["mesh"].is_u64() || !attributes.is_object() {
        return Ok(None);
    }
    let read = |name: &str, width: usize| -> Result<Option<Vec<f64>>> {
        let Some(a) = attributes[name].as_u64() else {
            return Ok(None);
        };
        let (values, n) = doc.read_f64(a as usize)?;
        if n != width {
            bail!(doc.err(format!(
                "node {index}'s EXT_mesh_gpu_instancing {name} (accessor {a}) has {n} components, not {width}"
            )));
        }
        Ok(Some(values))
    };
    let (t, r, s) = (
        read("TRANSLATION", 3)?,
        read("ROTATION", 4)?,
        read("SCALE", 3)?,
    );
    let counts: Vec<usize> = [(&t, 3), (&r, 4), (&s, 3)]
        .iter()
        .filter_map(|(v, w)| v.as_ref().map(|v| v.len() / w))
        .collect();
    let Some(&count) = counts.first() else {
        return Ok(None);
    };
    if counts.iter().any(|&c| c != count) {
        bail!(doc.err(format!(
            "node {index}'s EXT_mesh_gpu_instancing attributes hold different instance counts"
        )));
    }
    let vec3s = |v: Option<Vec<f64>>, default: DVec3| -> Vec<DVec3> {
        match v {
            Some(v) => v.chunks_exact(3).map(DVec3::from_slice).collect(),
            None => vec![default; count],
        }
    };
    let rotations = match r {
        Some(r) => (r.chunks_exact(4).enumerate())
            .map(|(k, q)| {
                let q = DQuat::from_slice(q);
                if q.length() < MIN_QUATERNION {
                    bail!(doc.err(format!(
                        "node {index}'s EXT_mesh_gpu_instancing ROTATION of instance {k} is not a rotation (a zero quaternion)"
                    )));
                }
                Ok(q.normalize())
            })
            .collect::<Result<_>>()?,
        None => vec![DQuat::IDENTITY; count],
    };
    Ok(Some(Instances {
        translations: vec3s(t, DVec3::ZERO),
        rotations,
        scales: vec3s(s, DVec3::ONE),
    }))
}
