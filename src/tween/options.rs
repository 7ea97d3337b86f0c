//! What a tween is asked to do: the method, where frames go in time, and the other options,
//! each default written once here.

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
#[derive(Clone, Copy, Debug)]
pub enum Timing {
    /// N frames inserted evenly between each pair of consecutive keys.
    Tweens(usize),
    /// Frames at a fixed rate (per second) over the keys' time span.
    Fps(f64),
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
        }
    }
}
