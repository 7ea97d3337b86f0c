//! What a tween is asked to do: the method, where frames go in time, and the other options,
//! each default written once here.

use super::compact::CompactOptions;

/// Interpolation method (`--method`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Method {
    /// The seed paper's method: polar decomposition, slerp, linear stretch, Poisson solve.
    Seed,
    /// Vertex lerp between consecutive keys (BlendShape baseline).
    Linear,
    /// C1 spline across all keys in gradient space (rotation logs and stretches by cubic Hermite
    /// with C2-spline tangents, same solve; each component turns about its pivot). The default.
    #[default]
    Spline,
}

impl Method {
    pub fn name(self) -> &'static str {
        match self {
            Method::Seed => "seed",
            Method::Linear => "linear",
            Method::Spline => "spline",
        }
    }
}

/// How output frames are placed in time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Timing {
    /// Every key kept; between two keys, frames evenly spaced at about this many per second
    /// (round(gap x rate) - 1 of them), none between keys closer than that. The default, at
    /// [`DEFAULT_RATE`]: on keys that lie on a grid of 1/30 s (or 1/10, 1/15 ...), frames land
    /// exactly on the 30 per second grid.
    Rate(f64),
    /// N frames inserted evenly between each pair of consecutive keys.
    Tweens(usize),
    /// Frames at a fixed rate (per second) over the keys' time span; the first and the last key
    /// are always frames.
    Fps(f64),
}

impl Timing {
    /// An error unless the timing and the seconds the motion continues before the first key
    /// and after the last (`--extend-before`, `--extend-after`) are numbers a run can use:
    /// --fps and --rate positive, the extensions zero or positive (`tween` and `preview` ask).
    pub fn check(self, extend: [f64; 2]) -> anyhow::Result<()> {
        if let Timing::Fps(f) | Timing::Rate(f) = self {
            anyhow::ensure!(
                f.is_finite() && f > 0.0,
                "--fps and --rate must be positive numbers (got {f})"
            );
        }
        for (e, name) in extend.iter().zip(["--extend-before", "--extend-after"]) {
            anyhow::ensure!(
                e.is_finite() && *e >= 0.0,
                "{name} takes seconds, zero or more (got {e})"
            );
        }
        Ok(())
    }
}

/// Frames per second of the default timing: what game and web pipelines play at.
pub const DEFAULT_RATE: f64 = 30.0;

impl Default for Timing {
    fn default() -> Timing {
        Timing::Rate(DEFAULT_RATE)
    }
}

/// How the frames become morph targets in a glTF output.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Layout {
    /// The authored morph targets stay (names, order, their other animations); the keys are
    /// played by the authored weights at their times, and only the frames between keys get
    /// targets of their own. The default.
    #[default]
    Rig,
    /// One target per frame, keys included; the authored targets are replaced.
    Frames,
}

/// Options of the tween job.
#[derive(Clone, Copy, Debug)]
pub struct TweenOptions {
    pub method: Method,
    pub timing: Timing,
    /// Measure every frame for `--report`.
    pub report: bool,
    /// Let `spline` wrap around tracks whose last key equals the first (`--no-loop` clears it).
    pub wrap: bool,
    /// Seconds of motion continued before the first key and after the last
    /// (`--extend-before`, `--extend-after`).
    pub extend: [f64; 2],
    /// How a glTF output carries the frames.
    pub layout: Layout,
    /// Compact a glTF output (`--compact` or its parts).
    pub compact: Option<CompactOptions>,
}

impl Default for TweenOptions {
    /// What `inbetween tween` does without options.
    fn default() -> TweenOptions {
        TweenOptions::new(Method::default(), Timing::default())
    }
}

impl TweenOptions {
    /// Options with every default: no report, wrapping on, no extension.
    pub fn new(method: Method, timing: Timing) -> TweenOptions {
        TweenOptions {
            method,
            timing,
            report: false,
            wrap: true,
            extend: [0.0, 0.0],
            layout: Layout::default(),
            compact: None,
        }
    }

    /// Whether a glTF output reads the frames that lie on keys: not in the rig layout
    /// uncompacted, where a key plays its authored weights alone (no target of its own).
    pub fn gltf_reads_keys(&self) -> bool {
        self.layout == Layout::Frames || self.compact.is_some()
    }
}
