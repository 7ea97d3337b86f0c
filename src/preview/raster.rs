//! Raster stage: shaded triangles into a cell with a z-buffer. Orthographic, one fixed light
//! from the upper left in front, two-sided Lambert shading of flat (per triangle) or smooth
//! (area-weighted per vertex) normals; drawn at `SUPERSAMPLE` x the cell's size and averaged
//! down, so edges are smooth. Pure arithmetic in a fixed order: the same bytes every run.

use super::camera::Camera;
use glam::DVec3;

/// Pixels drawn per cell pixel, each way.
pub const SUPERSAMPLE: usize = 2;
/// The background grey and the mesh's colour (sRGB 0-255 and linear 0-1).
pub const BACKGROUND: [u8; 3] = [236, 236, 232];
const ALBEDO: [f64; 3] = [0.62, 0.67, 0.78];
/// Light that reaches every surface, and the directional light's share.
const AMBIENT: f64 = 0.18;

/// How normals are shaded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shading {
    Flat,
    Smooth,
}

/// One mesh of a frame in world space.
pub struct Drawn<'a> {
    pub points: Vec<DVec3>,
    pub triangles: &'a [[u32; 3]],
}

/// An RGB picture.
#[derive(Clone, Debug, PartialEq)]
pub struct Picture {
    pub width: usize,
    pub height: usize,
    pub rgb: Vec<u8>,
}

impl Picture {
    pub fn new(width: usize, height: usize, colour: [u8; 3]) -> Picture {
        Picture {
            width,
            height,
            rgb: colour.repeat(width * height),
        }
    }

    pub fn set(&mut self, x: usize, y: usize, c: [u8; 3]) {
        if x < self.width && y < self.height {
            let i = 3 * (y * self.width + x);
            self.rgb[i..i + 3].copy_from_slice(&c);
        }
    }

    /// Copy `other` with its top-left corner at (`x`, `y`).
    pub fn paste(&mut self, other: &Picture, x: usize, y: usize) {
        for row in 0..other.height.min(self.height.saturating_sub(y)) {
            let w = other.width.min(self.width.saturating_sub(x));
            let src = 3 * row * other.width;
            let dst = 3 * ((y + row) * self.width + x);
            self.rgb[dst..dst + 3 * w].copy_from_slice(&other.rgb[src..src + 3 * w]);
        }
    }

    /// Pixels that differ from `colour`.
    pub fn count_not(&self, colour: [u8; 3]) -> usize {
        self.rgb.chunks_exact(3).filter(|c| *c != colour).count()
    }
}

/// Linear light to an sRGB byte.
fn srgb(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

fn linear(b: u8) -> f64 {
    let x = b as f64 / 255.0;
    if x <= 0.040_45 {
        x / 12.92
    } else {
        ((x + 0.055) / 1.055).powf(2.4)
    }
}

/// Draw `meshes` through `camera` into a `width` x `height` cell.
pub fn draw(
    meshes: &[Drawn],
    camera: &Camera,
    width: usize,
    height: usize,
    shading: Shading,
) -> Picture {
    let (w, h) = (width * SUPERSAMPLE, height * SUPERSAMPLE);
    let cam = camera.scaled(SUPERSAMPLE as f64);
    let toward_viewer = -cam.forward;
    let light = (-0.45 * cam.right + 0.6 * cam.up + 0.66 * toward_viewer).normalize();
    let mut depth = vec![f64::INFINITY; w * h];
    // Linear radiance of each sample, or none (background).
    let mut shade = vec![f64::NAN; w * h];
    for mesh in meshes {
        let projected: Vec<[f64; 3]> = mesh.points.iter().map(|&p| cam.project(p)).collect();
        let face_normal = |t: &[u32; 3]| {
            let [a, b, c] = t.map(|i| mesh.points[i as usize]);
            (b - a).cross(c - a)
        };
        let vertex_normals: Option<Vec<DVec3>> = (shading == Shading::Smooth).then(|| {
            let mut n = vec![DVec3::ZERO; mesh.points.len()];
            for t in mesh.triangles {
                let f = face_normal(t);
                for &i in t {
                    n[i as usize] += f;
                }
            }
            n.iter().map(|v| v.normalize_or_zero()).collect()
        });
        for t in mesh.triangles {
            if t.iter().any(|&i| i as usize >= projected.len()) {
                continue;
            }
            let [a, b, c] = t.map(|i| projected[i as usize]);
            let area = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
            if area.is_nan() || area.abs() <= 1e-12 {
                continue;
            }
            let flat = face_normal(t).normalize_or_zero();
            let x0 = a[0].min(b[0]).min(c[0]).floor().max(0.0) as usize;
            let y0 = a[1].min(b[1]).min(c[1]).floor().max(0.0) as usize;
            let x1 = (a[0].max(b[0]).max(c[0]).ceil().min(w as f64)) as usize;
            let y1 = (a[1].max(b[1]).max(c[1]).ceil().min(h as f64)) as usize;
            for y in y0..y1 {
                let py = y as f64 + 0.5;
                for x in x0..x1 {
                    let px = x as f64 + 0.5;
                    let w0 = ((b[0] - px) * (c[1] - py) - (b[1] - py) * (c[0] - px)) / area;
                    let w1 = ((c[0] - px) * (a[1] - py) - (c[1] - py) * (a[0] - px)) / area;
                    let w2 = 1.0 - w0 - w1;
                    if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                        continue;
                    }
                    let z = w0 * a[2] + w1 * b[2] + w2 * c[2];
                    let i = y * w + x;
                    if z >= depth[i] {
                        continue;
                    }
                    depth[i] = z;
                    let mut n = match &vertex_normals {
                        Some(vn) => {
                            let [na, nb, nc] = t.map(|v| vn[v as usize]);
                            (w0 * na + w1 * nb + w2 * nc).normalize_or_zero()
                        }
                        None => flat,
                    };
                    if n.dot(toward_viewer) < 0.0 {
                        n = -n;
                    }
                    shade[i] = AMBIENT + (1.0 - AMBIENT) * n.dot(light).max(0.0);
                }
            }
        }
    }
    let background = BACKGROUND.map(linear);
    let mut out = Picture::new(width, height, BACKGROUND);
    let samples = (SUPERSAMPLE * SUPERSAMPLE) as f64;
    for y in 0..height {
        for x in 0..width {
            let mut sum = [0.0; 3];
            let mut any = false;
            for sy in 0..SUPERSAMPLE {
                for sx in 0..SUPERSAMPLE {
                    let s = shade[(y * SUPERSAMPLE + sy) * w + x * SUPERSAMPLE + sx];
                    for (c, v) in sum.iter_mut().enumerate() {
                        *v += if s.is_nan() {
                            background[c]
                        } else {
                            any = true;
                            ALBEDO[c] * s
                        };
                    }
                }
            }
            if any {
                out.set(x, y, sum.map(|v| (srgb(v / samples) * 255.0).round() as u8));
            }
        }
    }
    out
}
