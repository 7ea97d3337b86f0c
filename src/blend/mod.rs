//! `inbetween blend`: mix two skeletal clips of one character into a new clip.
//!
//! The pipeline, one module per stage: [`rig`] (read the character and its clips; [`bvh`] for
//! capture files; [`by_name`] for a clip in a second file) -> [`track`] (sample for analysis)
//! -> [`legs`] -> [`contacts`] -> [`cycles`] ([`analyze`] runs these, each clip heading the
//! way [`measure`] finds it travels) -> [`timewarp`] -> [`align`] -> [`mix`] -> [`cleanup`] ->
//! [`measure`] -> [`write`] (glTF) | [`write_bvh`] (BVH) | [`write_usd`] (USD point cache, from
//! the glTF); [`plan`] runs the middle from clips to frames, [`job`] from file to file.

mod align;
mod analyze;
mod bvh;
mod by_name;
mod cleanup;
mod contacts;
mod cycles;
mod job;
mod legs;
mod measure;
mod mix;
mod plan;
mod rig;
mod timewarp;
mod track;
mod write;
mod write_bvh;
mod write_usd;

pub use analyze::{analyze, Analysis, Character};
pub use bvh::{load as load_bvh, parse as parse_bvh, read as read_bvh, Bvh};
pub use cycles::{touchdowns, CycleMethod};
pub use job::{
    blend_clips, blend_files, clip_gaits, is_bvh, is_capture, run_blend, BlendDone, BlendJob,
    BlendSummary, BlendedClips,
};
pub use plan::{blend, gait, BlendOptions, Blended, Gait};
pub use rig::{load_gltf, slerp, Clip, Path, Pose, Rig};
pub use track::{pose_unwrapped, size, Track};
pub use write::append_animation;
