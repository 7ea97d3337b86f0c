//! `inbetween tween`: in-between frames of a mesh's morph keyframes.
//!
//! The pipeline, one module per stage: [`keys`] (morph meshes and their key tracks from the
//! glTF; for the glTF rig layout, [`target_normals`] for position-only targets) -> [`weld`]
//! (seams merged for the solve) -> [`schedule`] (where frames lie in time) ->
//! [`segment`] per pair of keys: [`seed`] or [`spline`] (with [`gradient`]: deformation
//! gradients, polar decomposition, rotation logs; and [`solve`]: the sparse Poisson system,
//! large meshes ordered by [`order`], factored subtree by subtree by [`cholesky`]) ->
//! [`normals`] -> [`report`] (shape figures) -> [`frames`] (a mesh's frames, streamed) ->
//! [`morph_targets`] (glTF morph animation; with `--compact`, [`compact`] and [`base`]) or the
//! USD writer; [`job`] runs it from file to file, with [`options`] holding what the user asked
//! for.

mod base;
mod cholesky;
mod clock;
mod compact;
mod frames;
mod gradient;
mod job;
mod keys;
mod morph_targets;
mod normals;
mod options;
mod order;
mod report;
mod schedule;
mod seed;
mod segment;
mod solve;
mod spline;
mod target_normals;
mod timegrid;
mod weld;

pub use compact::{Basis, CompactFigures, CompactOptions, DEFAULT_TOLERANCE};
pub use frames::{frames_at, key_poses, track_frames_welded};
pub use job::{run_tween, side_by_side, Summary, TweenJob};
pub use keys::{
    find_morph_meshes, mesh_geometry, skeletal_clips, KeyOptions, KeySource, MorphMesh,
    NoMorphKeys, Track, TrackOrigin,
};
pub use options::{Layout, Method, Timing, TweenOptions, DEFAULT_RATE};
pub use schedule::{close_loop, plan, schedule, FrameAt};
pub use target_normals::{derive as derive_target_normals, wanted as targets_given_normals};
pub use timegrid::{grid_of, rate_text, typed_rate, written_frame_time, Grid};
pub use weld::bbox_diagonal;

pub(crate) use segment::{KeyTrack, Segment};
pub(crate) use solve::{Pattern, MAX_BLOCK};
pub(crate) use spline::is_loop;
pub(crate) use weld::{rms_rel, Welded};
