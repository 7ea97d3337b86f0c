//! Camera stage: an orthographic view along one axis (`--view`, or the axis along which the
//! animation moves least, so that its motion lies in the picture), fitted to the bounds of every
//! frame of every band, the same for all cells.

use glam::DVec3;

/// How well a view's picture must fill its cell, as a share of the best-filled view's, for
/// `--view auto` to choose it: a sheet seen along its plane (a line) or a long bar seen from
/// its side against its end (a square) fall below.
pub const FILLED: f64 = 0.25;

/// Which way the camera looks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum View {
    /// Along -Z, +Y up (glTF's front).
    Front,
    /// Along -X, +Y up.
    Side,
    /// Down -Y, -Z up.
    Top,
}

impl View {
    /// (right, up, forward) unit vectors; forward points into the picture.
    pub fn axes(self) -> (DVec3, DVec3, DVec3) {
        match self {
            View::Front => (DVec3::X, DVec3::Y, DVec3::NEG_Z),
            View::Side => (DVec3::NEG_Z, DVec3::Y, DVec3::NEG_X),
            View::Top => (DVec3::X, DVec3::NEG_Z, DVec3::NEG_Y),
        }
    }

    /// The view whose picture shows the most of the motion: the one looking along the axis in
    /// which the vertices move least over `frames` (each frame: the same vertices in order),
    /// among the views whose pictures fill their cells at least [`FILLED`] as well as the
    /// best one's (`coverage`, front, side, top: a waving flag moves most across its own
    /// plane, and seen along it would be a line). Ties keep the order front, side, top.
    pub fn most_motion(frames: &[Vec<DVec3>], coverage: [f64; 3]) -> View {
        let Some(first) = frames.first() else {
            return View::Front;
        };
        // At most about 20,000 vertices looked at.
        let step = (first.len() / 20_000).max(1);
        let mut spread = DVec3::ZERO;
        for v in (0..first.len()).step_by(step) {
            let n = frames.len() as f64;
            let mean = frames.iter().map(|f| f[v]).sum::<DVec3>() / n;
            spread += frames
                .iter()
                .map(|f| (f[v] - mean) * (f[v] - mean))
                .sum::<DVec3>();
        }
        let candidates = [
            (View::Front, spread.z, coverage[0]),
            (View::Side, spread.x, coverage[1]),
            (View::Top, spread.y, coverage[2]),
        ];
        let best = coverage.iter().copied().fold(0.0, f64::max);
        candidates
            .iter()
            .filter(|c| c.2 >= FILLED * best)
            .fold(None, |best: Option<(View, f64, f64)>, &c| match best {
                Some(b) if c.1 >= b.1 * (1.0 - 1e-9) => Some(b),
                _ => Some(c),
            })
            .map_or(View::Front, |c| c.0)
    }
}

/// The least and greatest corners of `points`' bounding box (MAX and MIN for none).
pub fn bounds<'a>(points: impl IntoIterator<Item = &'a DVec3>) -> (DVec3, DVec3) {
    (points.into_iter()).fold((DVec3::MAX, DVec3::MIN), |(l, h), p| (l.min(*p), h.max(*p)))
}

impl View {
    /// The view whose picture of `points` covers the largest bounding rectangle (a still: a
    /// character seen from the side rather than head-on). Ties keep the order front, side, top.
    pub fn widest(points: &[DVec3]) -> View {
        let (lo, hi) = bounds(points);
        let e = (hi - lo).max(DVec3::ZERO);
        let candidates = [
            (View::Front, e.x * e.y),
            (View::Side, e.z * e.y),
            (View::Top, e.x * e.z),
        ];
        candidates
            .iter()
            .fold(candidates[0], |best, &c| {
                if c.1 > best.1 * (1.0 + 1e-9) {
                    c
                } else {
                    best
                }
            })
            .0
    }
}

/// Orthographic camera: world point -> (x, y) pixels in a cell and depth (larger is farther).
#[derive(Clone, Copy, Debug)]
pub struct Camera {
    pub right: DVec3,
    pub up: DVec3,
    pub forward: DVec3,
    /// World units to pixels.
    scale: f64,
    /// Picture-plane point at the cell's centre.
    centre: (f64, f64),
    size: (f64, f64),
}

/// Share of a cell left empty around the fitted bounds, each side.
pub const MARGIN: f64 = 0.06;

impl Camera {
    /// Fit `view` to every point of `points` in a cell of `width` x `height` pixels.
    pub fn fit<'a>(
        view: View,
        points: impl Iterator<Item = &'a DVec3>,
        width: usize,
        height: usize,
    ) -> Camera {
        let (right, up, forward) = view.axes();
        let (mut lo, mut hi) = ((f64::MAX, f64::MAX), (f64::MIN, f64::MIN));
        for p in points {
            let (x, y) = (p.dot(right), p.dot(up));
            lo = (lo.0.min(x), lo.1.min(y));
            hi = (hi.0.max(x), hi.1.max(y));
        }
        if lo.0 > hi.0 {
            (lo, hi) = ((-1.0, -1.0), (1.0, 1.0));
        }
        let (w, h) = (width as f64, height as f64);
        let span = ((hi.0 - lo.0) / w).max((hi.1 - lo.1) / h).max(1e-12);
        Camera {
            right,
            up,
            forward,
            scale: (1.0 - 2.0 * MARGIN) / span,
            centre: ((lo.0 + hi.0) / 2.0, (lo.1 + hi.1) / 2.0),
            size: (w, h),
        }
    }

    /// Pixel coordinates (x right, y down) and depth of `p`.
    pub fn project(&self, p: DVec3) -> [f64; 3] {
        [
            self.size.0 / 2.0 + (p.dot(self.right) - self.centre.0) * self.scale,
            self.size.1 / 2.0 - (p.dot(self.up) - self.centre.1) * self.scale,
            p.dot(self.forward),
        ]
    }

    /// The same camera drawing into a cell `factor` times larger (supersampling).
    pub fn scaled(&self, factor: f64) -> Camera {
        Camera {
            scale: self.scale * factor,
            size: (self.size.0 * factor, self.size.1 * factor),
            ..*self
        }
    }
}
