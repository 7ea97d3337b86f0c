//! inbetween: tween frames for glTF morph keyframes by the deformation-gradient method, and
//! skeletal clip blending.
//!
//! The product path, one folder per command or format, each opening with its pipeline:
//! [`gltf`] (read and write glTF) -> [`tween`] (keys -> frames -> morph animation) -> [`usd`]
//! (point caches); [`blend`] (skeletal clips); [`inspect`] (what a file holds). Shared rooms: `output` (the one way files are
//! written: staged, then renamed together), `progress` (what the user sees while it runs) and
//! `memory` (peak and available memory, and the allocator kept from unmapping freed blocks).
//! Developer tools apart: [`synth`], [`eval`], [`bench`].

pub mod blend;
mod dev;
pub mod gltf;
pub mod inspect;
mod memory;
mod output;
pub mod preview;
mod progress;
pub mod tween;
pub mod usd;

pub use dev::{bench, eval, fuzz, synth};
pub use memory::keep_freed_memory;
