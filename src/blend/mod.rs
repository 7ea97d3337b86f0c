//! `inbetween blend`: mix two skeletal clips of one character into a new clip.
//!
//! The pipeline, one module per stage: [`rig`] (read the character and its clips; [`bvh`] for
//! capture files) -> [`track`] (sample for analysis) -> [`legs`] -> [`contacts`] -> [`cycles`]
//! ([`analyze`] runs these) -> [`timewarp`] -> [`align`] -> [`mix`] -> [`cleanup`] ->
//! [`measure`] -> [`write`]; [`plan`] runs the middle from clips to frames, [`job`] from file to
//! file.

pub mod align;
pub mod analyze;
pub mod bvh;
pub mod cleanup;
pub mod contacts;
pub mod cycles;
pub mod job;
pub mod legs;
pub mod measure;
pub mod mix;
pub mod plan;
pub mod rig;
pub mod timewarp;
pub mod track;
pub mod write;
