//! Developer tools, apart from the product path: nothing under `tween/`, `gltf/`, `usd/` or
//! `blend/` imports them (but one unit test of the solver, which builds a tube).
//! [`synth`] (procedural meshes and keyframe files for the samples, tests and benchmarks) ->
//! [`eval`] (`inbetween eval`: hold-out accuracy per method) and [`bench`] (`inbetween bench`:
//! speed figures); [`fuzz`] holds the fuzzing harnesses.

pub mod bench;
pub mod eval;
pub mod fuzz;
pub mod synth;
