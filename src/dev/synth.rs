//! Procedural test meshes and keyframe files: the inputs in `samples/`, the meshes of the
//! tests and of `inbetween bench`. Everything here is deterministic.

use crate::gltf::{self, Container, Output};
use anyhow::Result;
use glam::{DMat3, DQuat, DVec3};
use serde_json::json;
use std::f64::consts::PI;
use std::path::Path;

/// A triangle mesh with optional normals and texture coordinates.
#[derive(Clone, Debug, Default)]
pub struct Surface {
    pub positions: Vec<DVec3>,
    pub normals: Option<Vec<DVec3>>,
    pub uvs: Option<Vec<[f64; 2]>>,
    pub triangles: Vec<[u32; 3]>,
}

/// A deterministic stream of numbers for randomised tests (a 64-bit linear congruential
/// generator, Knuth's MMIX constants): the same values on every run and machine.
pub struct Lcg(pub u64);

impl Lcg {
    /// The next number, uniform in [0, 1) (53 bits).
    pub fn unit(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A closed tube along +X from 0 to `length`, elliptic cross-section (`ry`, `rz`), with
/// `rings` rings of `segments` vertices and a fan cap at each end (centre vertex).
/// Triangles: `2 * segments * (rings - 1) + 2 * segments`.
pub fn tube(rings: usize, segments: usize, length: f64, ry: f64, rz: f64) -> Surface {
    let mut positions = Vec::with_capacity(rings * segments + 2);
    for i in 0..rings {
        let x = length * i as f64 / (rings - 1) as f64;
        for j in 0..segments {
            let a = 2.0 * PI * j as f64 / segments as f64;
            positions.push(DVec3::new(x, ry * a.cos(), rz * a.sin()));
        }
    }
    let mut triangles = Vec::new();
    let at = |i: usize, j: usize| (i * segments + j % segments) as u32;
    for i in 0..rings - 1 {
        for j in 0..segments {
            // Outward-facing (counter-clockwise seen from outside).
            triangles.push([at(i, j), at(i, j + 1), at(i + 1, j + 1)]);
            triangles.push([at(i, j), at(i + 1, j + 1), at(i + 1, j)]);
        }
    }
    let start = positions.len() as u32;
    positions.push(DVec3::ZERO);
    positions.push(DVec3::new(length, 0.0, 0.0));
    for j in 0..segments {
        triangles.push([start, at(0, j + 1), at(0, j)]);
        triangles.push([start + 1, at(rings - 1, j), at(rings - 1, j + 1)]);
    }
    Surface {
        positions,
        normals: None,
        uvs: None,
        triangles,
    }
}

/// A flat grid in the XY plane, `nx` by `ny` quads over `w` by `h`, facing +Z, with UVs.
pub fn grid(nx: usize, ny: usize, w: f64, h: f64) -> Surface {
    let mut positions = Vec::new();
    let mut uvs = Vec::new();
    for j in 0..=ny {
        for i in 0..=nx {
            let (u, v) = (i as f64 / nx as f64, j as f64 / ny as f64);
            positions.push(DVec3::new(u * w, v * h, 0.0));
            uvs.push([u, 1.0 - v]);
        }
    }
    let at = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    let mut triangles = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            triangles.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            triangles.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    let normals = Some(vec![DVec3::Z; positions.len()]);
    Surface {
        positions,
        normals,
        uvs: Some(uvs),
        triangles,
    }
}

/// Area-weighted vertex normals (smooth everywhere).
pub fn smooth_normals(positions: &[DVec3], triangles: &[[u32; 3]]) -> Vec<DVec3> {
    let mut n = vec![DVec3::ZERO; positions.len()];
    for t in triangles {
        let [a, b, c] = t.map(|i| i as usize);
        let f = (positions[b] - positions[a]).cross(positions[c] - positions[a]);
        n[a] += f;
        n[b] += f;
        n[c] += f;
    }
    n.into_iter().map(|v| v.normalize_or_zero()).collect()
}

/// Twist about the X axis by `angle * x / length` (radians).
pub fn twist(points: &[DVec3], angle: f64, length: f64) -> Vec<DVec3> {
    points
        .iter()
        .map(|p| DQuat::from_rotation_x(angle * p.x / length) * *p)
        .collect()
}

/// Bend a tube along X at `joint` by `angle` about +Z: points past the joint rotate about it,
/// blended smoothly over `blend` either side (like a two-bone skin).
pub fn bend(points: &[DVec3], joint: f64, angle: f64, blend: f64) -> Vec<DVec3> {
    let pivot = DVec3::new(joint, 0.0, 0.0);
    points
        .iter()
        .map(|p| {
            let s = ((p.x - joint + blend) / (2.0 * blend)).clamp(0.0, 1.0);
            let w = s * s * (3.0 - 2.0 * s);
            pivot + DQuat::from_rotation_z(angle * w) * (*p - pivot)
        })
        .collect()
}

/// Rigid motion: rotate by `angle` about `axis` through `center`, then translate.
pub fn rigid(
    points: &[DVec3],
    axis: DVec3,
    angle: f64,
    center: DVec3,
    translate: DVec3,
) -> Vec<DVec3> {
    let r = DMat3::from_axis_angle(axis.normalize(), angle);
    points
        .iter()
        .map(|p| center + r * (*p - center) + translate)
        .collect()
}

/// A mesh of a keyframe file: base surface and absolute key poses (one morph target each).
pub struct KeyedMesh {
    pub name: String,
    pub surface: Surface,
    /// Absolute positions of each morph target (written as deltas from the base).
    pub targets: Vec<Vec<DVec3>>,
    /// Normals of each target, when the base has normals.
    pub target_normals: Vec<Vec<DVec3>>,
    pub color: [f64; 4],
    /// Write the triangles from this index on as a second primitive (with its own copy of the
    /// vertices it uses), to test meshes whose primitives share a border.
    pub split: Option<usize>,
}

impl KeyedMesh {
    pub fn new(name: &str, surface: Surface, targets: Vec<Vec<DVec3>>) -> KeyedMesh {
        KeyedMesh {
            name: name.into(),
            surface,
            targets,
            target_normals: vec![],
            color: [0.8, 0.8, 0.8, 1.0],
            split: None,
        }
    }
}

/// The part of a keyed mesh made of `triangles`, re-indexed over the vertices it uses.
fn sub_mesh(m: &KeyedMesh, triangles: &[[u32; 3]]) -> KeyedMesh {
    let mut map = vec![u32::MAX; m.surface.positions.len()];
    let mut used = Vec::new();
    let tris = triangles
        .iter()
        .map(|t| {
            t.map(|v| {
                if map[v as usize] == u32::MAX {
                    map[v as usize] = used.len() as u32;
                    used.push(v as usize);
                }
                map[v as usize]
            })
        })
        .collect();
    let pick = |v: &Vec<DVec3>| used.iter().map(|&i| v[i]).collect::<Vec<_>>();
    let s = &m.surface;
    KeyedMesh {
        name: m.name.clone(),
        surface: Surface {
            positions: pick(&s.positions),
            normals: s.normals.as_ref().map(pick),
            uvs: s
                .uvs
                .as_ref()
                .map(|uv| used.iter().map(|&i| uv[i]).collect()),
            triangles: tris,
        },
        targets: m.targets.iter().map(pick).collect(),
        target_normals: m.target_normals.iter().map(pick).collect(),
        color: m.color,
        split: None,
    }
}

/// A keyframe file: meshes (each on its own node) and optionally a weights animation for the
/// first mesh at `key_times`: one-hot, stepping through its targets (key k shows target k-1,
/// key 0 the base), or `key_weights` (one weight per target and key: a rig's baked clip).
pub struct KeyframeFile {
    pub meshes: Vec<KeyedMesh>,
    pub key_times: Option<Vec<f64>>,
    pub key_weights: Option<Vec<Vec<f64>>>,
}

impl KeyframeFile {
    pub fn write(&self, path: &Path) -> Result<()> {
        let mut out =
            Output::new(json!({ "asset": { "version": "2.0", "generator": "inbetween synth" } }));
        let mut meshes = Vec::new();
        let mut nodes = Vec::new();
        let mut materials = Vec::new();
        for (mi, whole) in self.meshes.iter().enumerate() {
            let parts: Vec<KeyedMesh> = match whole.split {
                Some(at) => vec![
                    sub_mesh(whole, &whole.surface.triangles[..at]),
                    sub_mesh(whole, &whole.surface.triangles[at..]),
                ],
                None => vec![sub_mesh(whole, &whole.surface.triangles)],
            };
            let mut prims = Vec::new();
            for m in &parts {
                let s = &m.surface;
                let f = |v: &[DVec3]| -> Vec<f32> {
                    v.iter().flat_map(|p| p.as_vec3().to_array()).collect()
                };
                let mut attributes = json!({ "POSITION": out.push_f32(&f(&s.positions), "VEC3", 3, true, Some(34962)) });
                if let Some(n) = &s.normals {
                    attributes["NORMAL"] =
                        json!(out.push_f32(&f(n), "VEC3", 3, false, Some(34962)));
                }
                if let Some(uv) = &s.uvs {
                    let d: Vec<f32> = uv.iter().flat_map(|t| [t[0] as f32, t[1] as f32]).collect();
                    attributes["TEXCOORD_0"] =
                        json!(out.push_f32(&d, "VEC2", 2, false, Some(34962)));
                }
                let idx: Vec<u8> = s
                    .triangles
                    .iter()
                    .flatten()
                    .flat_map(|i| i.to_le_bytes())
                    .collect();
                let view = out.bin.push_view(&idx, Some(34963));
                let indices = out.push_accessor(
                    json!({ "bufferView": view, "componentType": 5125, "count": s.triangles.len() * 3, "type": "SCALAR" }),
                );
                let mut targets = Vec::new();
                for (k, t) in m.targets.iter().enumerate() {
                    let d: Vec<DVec3> = t.iter().zip(&s.positions).map(|(a, b)| *a - *b).collect();
                    let mut target =
                        json!({ "POSITION": out.push_f32(&f(&d), "VEC3", 3, true, Some(34962)) });
                    if let (Some(bn), Some(tn)) = (&s.normals, m.target_normals.get(k)) {
                        let d: Vec<DVec3> = tn.iter().zip(bn).map(|(a, b)| *a - *b).collect();
                        target["NORMAL"] =
                            json!(out.push_f32(&f(&d), "VEC3", 3, false, Some(34962)));
                    }
                    targets.push(target);
                }
                let mut prim =
                    json!({ "attributes": attributes, "indices": indices, "material": mi });
                if !targets.is_empty() {
                    prim["targets"] = json!(targets);
                }
                prims.push(prim);
            }
            materials.push(json!({
                "name": format!("{}_material", whole.name),
                "pbrMetallicRoughness": { "baseColorFactor": whole.color, "metallicFactor": 0.0, "roughnessFactor": 0.6 },
                "doubleSided": true,
            }));
            let mut mesh = json!({ "name": whole.name });
            let targets = whole.targets.len();
            if targets > 0 {
                mesh["weights"] = json!(vec![0.0; targets]);
                let names: Vec<String> = (1..=targets).map(|k| format!("key{k}")).collect();
                mesh["extras"] = json!({ "targetNames": names });
            }
            mesh["primitives"] = json!(prims);
            meshes.push(mesh);
            nodes.push(json!({ "name": whole.name, "mesh": mi }));
        }
        let node_count = nodes.len();
        out.json["meshes"] = json!(meshes);
        out.json["nodes"] = json!(nodes);
        out.json["materials"] = json!(materials);
        out.json["scenes"] =
            json!([{ "name": "samples", "nodes": (0..node_count).collect::<Vec<_>>() }]);
        out.json["scene"] = json!(0);
        if let Some(times) = &self.key_times {
            let n = self.meshes[0].targets.len();
            let t: Vec<f32> = times.iter().map(|&t| t as f32).collect();
            let mut w = Vec::new();
            for k in 0..times.len() {
                match &self.key_weights {
                    Some(kw) => w.extend(kw[k].iter().map(|&x| x as f32)),
                    None => w.extend((0..n).map(|i| if k == i + 1 { 1.0f32 } else { 0.0 })),
                }
            }
            let input = out.push_f32(&t, "SCALAR", 1, true, None);
            let output = out.push_f32(&w, "SCALAR", 1, false, None);
            out.json["animations"] = json!([{
                "name": "keys",
                "samplers": [{ "input": input, "output": output, "interpolation": "LINEAR" }],
                "channels": [{ "sampler": 0, "target": { "node": 0, "path": "weights" } }],
            }]);
        }
        let container = match path.extension().and_then(|e| e.to_str()) {
            Some("gltf") => Container::Gltf,
            _ => Container::Glb,
        };
        gltf::finish(out, container, path)
    }
}

/// A face-rig-like file: a 40 x 40 grid ("face", 2 x 2 units) with `shapes` blend shapes (the
/// first a "jaw" turning the lower third 25 degrees about a horizontal axis, the others round
/// bumps of varied size at varied places, some raising and some sinking) and a weights clip of
/// `seconds` baked at `rate` samples a second, every weight a smooth curve in [0, 1]. Like a
/// capture-driven face: many targets, blended weights, dense keys.
pub fn face_rig(shapes: usize, rate: f64, seconds: f64) -> KeyframeFile {
    face_rig_of(40, shapes, rate, seconds)
}

/// [`face_rig`] on a face of `side` x `side` quads ((side + 1)^2 vertices).
pub fn face_rig_of(side: usize, shapes: usize, rate: f64, seconds: f64) -> KeyframeFile {
    let face = grid(side, side, 2.0, 2.0);
    let mut targets = Vec::new();
    for k in 0..shapes {
        let t: Vec<DVec3> = if k == 0 {
            let jaw = DQuat::from_axis_angle(DVec3::X, 25f64.to_radians());
            face.positions
                .iter()
                .map(|p| {
                    let pivot = DVec3::new(p.x, 0.7, 0.0);
                    let f = ((0.7 - p.y) / 0.2).clamp(0.0, 1.0);
                    let turned = pivot + jaw * (*p - pivot);
                    p.lerp(turned, f * f * (3.0 - 2.0 * f))
                })
                .collect()
        } else {
            let a = k as f64 * 2.399_963; // golden angle: spread over the face
            let centre = DVec3::new(
                1.0 + 0.7 * a.cos() * (k as f64 / shapes as f64).sqrt(),
                1.0 + 0.7 * a.sin() * (k as f64 / shapes as f64).sqrt(),
                0.0,
            );
            let radius = 0.15 + 0.1 * ((k * 7) % 5) as f64 / 4.0;
            let height = if k % 3 == 0 { -0.12 } else { 0.18 };
            face.positions
                .iter()
                .map(|p| {
                    let d2 = (*p - centre).length_squared() / (radius * radius);
                    *p + DVec3::Z * height * (-d2).exp()
                })
                .collect()
        };
        targets.push(t);
    }
    let keys = (seconds * rate).round() as usize + 1;
    let key_times: Vec<f64> = (0..keys).map(|i| i as f64 / rate).collect();
    let key_weights = key_times
        .iter()
        .map(|&t| {
            (0..shapes)
                .map(|k| {
                    let (f, phase) = (0.4 + 0.13 * (k % 7) as f64, k as f64 * 0.9);
                    let x = 0.5 + 0.5 * (2.0 * PI * f * t + phase).sin();
                    x * x
                })
                .collect()
        })
        .collect();
    KeyframeFile {
        meshes: vec![KeyedMesh {
            color: [0.9, 0.75, 0.65, 1.0],
            ..KeyedMesh::new("face", face, targets)
        }],
        key_times: Some(key_times),
        key_weights: Some(key_weights),
    }
}

/// The samples shipped in `samples/`, by file name.
pub fn samples() -> Vec<(&'static str, KeyframeFile)> {
    // A bar of square section, twisted 90 degrees along its length.
    let bar = {
        let s = tube(41, 4, 4.0, 0.5, 0.5);
        let key = twist(&s.positions, PI / 2.0, 4.0);
        KeyedMesh {
            color: [0.8, 0.5, 0.2, 1.0],
            ..KeyedMesh::new("bar", s, vec![key])
        }
    };
    // A round tube bent 150 degrees at a joint in the middle (over 2 units of its length, so the
    // inner side's radius of curvature, 2 / 2.62 - 0.4 = 0.36, stays positive: no fold).
    let tube_bend = {
        let s = tube(61, 24, 6.0, 0.4, 0.4);
        let key = bend(&s.positions, 3.0, 150f64.to_radians(), 1.0);
        KeyedMesh {
            color: [0.3, 0.6, 0.9, 1.0],
            ..KeyedMesh::new("tube", s, vec![key])
        }
    };
    // A flag on a pole, waving through five keys (a weights animation), with normals and UVs.
    let flag = {
        let mut s = grid(24, 16, 3.0, 2.0);
        s.normals = Some(smooth_normals(&s.positions, &s.triangles));
        let keys: Vec<Vec<DVec3>> = (1..=4)
            .map(|k| {
                let phase = k as f64 * PI / 2.0;
                s.positions
                    .iter()
                    .map(|p| {
                        let amp = 0.35 * p.x / 3.0;
                        let a = 2.0 * PI * p.x / 3.0 - phase;
                        // Swing the cloth about the pole: bend, not just lift, so the keys rotate.
                        DVec3::new(
                            p.x - amp * 0.3 * (1.0 - a.cos()),
                            p.y - 0.05 * amp * a.sin(),
                            amp * a.sin(),
                        )
                    })
                    .collect()
            })
            .collect();
        let normals = keys
            .iter()
            .map(|k| smooth_normals(k, &s.triangles))
            .collect();
        KeyedMesh {
            target_normals: normals,
            color: [0.9, 0.1, 0.1, 1.0],
            ..KeyedMesh::new("flag", s, keys)
        }
    };
    let pole = {
        let s = tube(2, 12, 3.0, 0.05, 0.05);
        let positions = s
            .positions
            .iter()
            .map(|p| DVec3::new(p.y - 0.05, p.x - 1.0, p.z))
            .collect();
        let mut s = Surface { positions, ..s };
        s.normals = Some(smooth_normals(&s.positions, &s.triangles));
        KeyedMesh {
            color: [0.6, 0.6, 0.6, 1.0],
            ..KeyedMesh::new("pole", s, vec![])
        }
    };
    vec![
        (
            "bar_twist.glb",
            KeyframeFile {
                meshes: vec![bar],
                key_times: None,
                key_weights: None,
            },
        ),
        (
            "tube_bend.glb",
            KeyframeFile {
                meshes: vec![tube_bend],
                key_times: None,
                key_weights: None,
            },
        ),
        (
            "flag_wave.glb",
            KeyframeFile {
                meshes: vec![flag, pole],
                key_times: Some(vec![0.0, 0.5, 1.0, 1.5, 2.0]),
                key_weights: None,
            },
        ),
    ]
}
