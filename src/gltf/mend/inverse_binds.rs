//! Inverse bind matrices ([`inverse_binds`]): a skin's `inverseBindMatrices` must hold a
//! matrix for each of its joints (the validator's INVALID_IBM_ACCESSOR_COUNT). Writers have left
//! out the last joints' (glTF-Blender-IO issue 2532: a Fox with 51 for 64 joints, which
//! Blender imports; three.js reads past the end and poses nothing); the skin stages read the
//! missing ones as the rest pose binds them ([`crate::gltf::skin::inverse_binds as rebuilt`]), and
//! the output is written with them: a new accessor holding the file's matrices and those.

use crate::gltf::build::Output;
use crate::gltf::read::{arr, quoted_name, Document};
use crate::gltf::skin;
use glam::DMat4;

/// Give every skin of `out` whose inverse bind matrices are fewer than its joints the missing
/// ones (see the module comment; the file's read from `doc`); a line for each.
pub fn inverse_binds(doc: &Document, out: &mut Output) -> Vec<String> {
    let mut said = Vec::new();
    for s in 0..arr(&out.json, "skins").len() {
        let skin = &out.json["skins"][s];
        let joints = arr(skin, "joints").len();
        let Some(acc) = skin["inverseBindMatrices"].as_u64().map(|a| a as usize) else {
            continue;
        };
        let a = &out.json["accessors"][acc];
        let Some(held) = a["count"].as_u64().map(|c| c as usize) else {
            continue;
        };
        if held >= joints || a["type"] != "MAT4" {
            continue;
        }
        // A skin no node uses binds as the scene's origin does.
        let mesh_node = (arr(&out.json, "nodes").iter())
            .position(|n| n["skin"].as_u64() == Some(s as u64))
            .unwrap_or(usize::MAX);
        let Ok((stored, _)) = doc.read_f64(acc) else {
            continue;
        };
        let stored: Vec<DMat4> = stored
            .chunks_exact(16)
            .map(DMat4::from_cols_slice)
            .collect();
        let data: Vec<f32> = (skin::inverse_binds(&out.json, s, mesh_node, &stored).iter())
            .flat_map(DMat4::to_cols_array)
            .map(|x| x as f32)
            .collect();
        let new = out.push_f32(&data, "MAT4", 16, false, None);
        out.json["skins"][s]["inverseBindMatrices"] = new.into();
        let name = quoted_name(&out.json["skins"][s], || s.to_string());
        said.push(format!(
            "skin {name}'s inverseBindMatrices hold {held} matrices for {joints} joints (glTF asks one each): the other {} written as the rest pose binds them",
            joints - held
        ));
    }
    said
}
