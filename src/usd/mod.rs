//! USD point caches of a glTF scene.
//!
//! The pipeline, one module per stage: [`stage`] (the glTF scene as a USD stage model: Xforms,
//! Meshes, which of them are animated and at which time codes; [`material`]: the glTF
//! materials as UsdShade materials and the texture files they read; [`motion`]: the node
//! transforms the clips on the timeline key; [`camera_light`]: cameras and lights; skinned
//! meshes baked by [`crate::gltf::Skinning`]) -> the frames, streamed in as they are computed -> [`usda`] (text,
//! samples spooled) | [`usdc`] (crate file) -> [`usdz`] (package); [`write`] picks the format
//! and stages the file.

mod camera_light;
mod material;
mod motion;
mod stage;
mod usda;
mod usdc;
mod usdz;
mod write;

pub use motion::ClipOnStage;
pub use stage::{
    build_stage, for_each_skin_sample, identifier, Delta, FrameSource, InstancerPrim, MeshPlan,
    Prim, Stage,
};
pub use write::write_file;
