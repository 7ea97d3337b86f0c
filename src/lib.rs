//! inbetween: tween frames for glTF morph keyframes by the deformation-gradient method.
//!
//! The pipeline, one module per stage:
//! [`read`] -> [`keyframes`] -> [`weld`] -> [`interpolate`] (with [`gradient`] and [`solve`])
//! -> [`normals`] -> [`write`]; [`tween`] runs it for one mesh and [`job`] from file to file.

pub mod bench;
pub mod blend;
pub mod eval;
pub mod gradient;
pub mod interpolate;
pub mod job;
pub mod keyframes;
pub mod normals;
pub mod progress;
pub mod read;
pub mod report;
pub mod solve;
pub mod spline;
pub mod synth;
pub mod tween;
pub mod usd;
pub mod usdc;
pub mod usdz;
pub mod weld;
pub mod write;
