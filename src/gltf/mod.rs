//! glTF in and out.
//!
//! The pipeline, one module per stage: [`read`] (a `.gltf`/`.glb` file into a [`Document`]:
//! [`container`]: a `.glb`'s chunks, read as they say where its header's length is wrong; buffers;
//! [`uri`] says what external files it may read; [`spelling`]: a byte-order mark read past, whole
//! decimals read as the integers glTF asks, signed indices as unsigned) -> [`decode`] (meshopt and
//! Draco compression undone; [`targets`]: a mesh's primitives given the same number of morph
//! targets) -> [`accessor`] (accessors decoded to `f64`/`u32`, triangles; [`channel`]: animation
//! channels read and evaluated, nodes' rest transforms; [`skin`]: skinned points at any pose;
//! [`instancing`]: a node's mesh instances) ... the command's own work ... -> [`build`] (new
//! accessors and buffer views on an [`Output`]; [`mend`]: what the input breaks of glTF's rules,
//! one mend a file, made right as it is copied: undefined keys, inverse bind matrices, skin
//! weights, rotation keys, key times, indices, strides, bounds, normals, tangents, sparse parts,
//! image types, image data URIs, undeclared extensions, scene roots, repeated channels, empty clips
//! and empty lists) -> [`mod@reorder`] (with meshopt: triangles and vertices in mesh order) ->
//! [`compact`] (channels and accessors nothing uses any more dropped) -> [`encode`] (meshopt
//! compression, when asked for) -> [`write`] (`.glb` or `.gltf` with its `.bin` and images, staged
//! as one all-or-nothing set of files).

mod accessor;
mod build;
mod channel;
mod compact;
mod container;
mod decode;
mod encode;
mod instancing;
mod mend;
mod read;
mod reorder;
mod skin;
mod spelling;
mod targets;
mod uri;
mod write;

pub use accessor::{read_attribute, read_attribute3, read_triangles, read_vec3};
pub use build::{set_bounds, BinBuilder, Output, Storage};
pub use channel::{
    clip_by, clip_name, close_keys, defined_keys, defined_only, local_at, node_parents, push_key,
    read_channels, rest_matrix, rest_trs, slerp, Channel, Interp, Path, MIN_QUATERNION,
};
pub(crate) use compact::{compact, drop_channels, AccessorRefs, PASSED_THROUGH};
pub use encode::{
    exp_roundtrip, oct_roundtrip, row_components, ELEMENT_MARK, FILTER_GROUP, FILTER_MARK, OCT_MARK,
};
pub use instancing::{instances, Instances};
pub use mend::shadowed;
pub use read::{
    arr, at, listed, listed_or_none, mesh_nodes, node_target, other_kind, quoted_name,
    starts_like_bvh, target_names, weights_target, Document, WeightsTarget,
};
pub use reorder::reorder;
pub use skin::{Skeleton, Skinning};
pub use uri::Access;
pub use write::{begin, finish, glb_bytes, stage, Container};
