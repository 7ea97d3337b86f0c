//! Write stage for USD point caches: the glTF scene as a USD stage whose animated meshes carry
//! time-sampled `points`, `extent` and `normals`, one sample per output frame.
//!
//! Conventions (the README repeats them):
//! * stage metadata: `defaultPrim` (a root Xform named after the glTF scene, else the file),
//!   `upAxis = "Y"`, `metersPerUnit = 1`, `timeCodesPerSecond = framesPerSecond` = the output
//!   frame rate, start and end time codes covering every frame, `customLayerData` the glTF
//!   asset's copyright, generator and extras ([`layer_data`]);
//! * time code of a frame = its time in seconds times the frame rate; each clip has one place
//!   on the timeline, whichever meshes and nodes it drives, clips following one another one
//!   frame apart (the tween's `timegrid::timeline`); under each node carrying a mesh the
//!   mesh plays the clips that drive that node (none: written still);
//! * each glTF node is an Xform (with `xformOp:transform` when it is not the identity, time
//!   sampled where a clip on the timeline moves the node: [`super::motion`]), each
//!   triangle primitive a Mesh (`subdivisionScheme = "none"`, `faceVertexCounts` of 3,
//!   `faceVertexIndices`), `primvars:st` from TEXCOORD_0 with V flipped (`1 - v`),
//!   `primvars:displayColor` per vertex from COLOR_0 (linear, as glTF stores it; its alpha as
//!   `primvars:displayOpacity`), else one constant from the material's base colour,
//!   `doubleSided` from the material;
//! * primitives with the same attributes and targets (material groups drawing one vertex
//!   buffer) are one Mesh with a `GeomSubset` per primitive bound to its material;
//! * material variants (`KHR_materials_variants`) are a variant set on the root prim
//!   ([`VARIANT_SET`]) whose variants bind the primitives they map ([`Variants`]);
//! * a node's camera or `KHR_lights_punctual` light is a `Camera` or UsdLux light prim below
//!   its Xform ([`super::camera_light`]);
//! * a node drawing its mesh once per instance (`EXT_mesh_gpu_instancing`, as gltfpack `-mi`
//!   writes it) is a PointInstancer (positions, orientations, scales, the mesh as its one
//!   prototype in a `Prototypes` scope);
//! * meshes that are not animated are written once, without time samples, in the pose the
//!   glTF shows (morph targets blended by the node's or the mesh's default weights);
//! * a skinned mesh's points are baked at each of its samples ([`crate::gltf::Skinning`]); one
//!   that is not animated but whose joints a clip on the stage moves is sampled at that clip's
//!   codes;
//! * names are made valid identifiers (`[A-Za-z_][A-Za-z0-9_]*`), unique among siblings by a
//!   `_1`, `_2`, ... suffix, deterministically; a prim keeps its glTF object's name as
//!   `displayName` where its own is another, and the object's `extras` as `customData`
//!   ([`Meta`]).

use super::camera_light::{self, say, Plain};
use super::material::{st_name, Look, LookBuilder};
use super::motion::{ClipOnStage, NodeMotion};
use crate::gltf::{
    self, arr, listed, quoted_name, read_attribute, read_attribute3, read_triangles, read_vec3,
    rest_matrix, Document, Skeleton, Skinning,
};
use anyhow::{bail, Result};
use glam::{DMat4, DVec3};
use serde_json::{json, Value};
use std::cell::RefCell;
use std::collections::{HashMap, HashSet};
use std::sync::Arc;

/// One Mesh prim to write.
pub struct MeshPrim {
    pub name: String,
    /// What it keeps of the glTF mesh: its name and extras ([`Meta`]).
    pub meta: Meta,
    pub points: Vec<[f32; 3]>,
    pub normals: Option<Vec<[f32; 3]>>,
    /// Texture coordinate sets: (`st`, TEXCOORD_0), (`st1`, TEXCOORD_1), ..., V flipped.
    pub st: Vec<(String, Vec<[f32; 2]>)>,
    pub indices: Vec<u32>,
    /// `primvars:displayColor`: COLOR_0 per vertex (linear, as glTF stores it), else the
    /// material's base colour as one constant.
    pub color: Option<DisplayColor>,
    /// `primvars:displayOpacity` per vertex: COLOR_0's alpha, when it has one.
    pub opacity: Option<Vec<f32>>,
    pub double_sided: bool,
    /// The Material prim bound to it (in [`Stage::look`]'s scope).
    pub material: Option<String>,
    /// The Material prims its material variants bind instead (see [`Variants`]).
    pub variants: Variants,
    /// For an animated primitive: where its frames come from and their time codes.
    pub animation: Option<Animation>,
    /// For a skinned primitive: its skin, which each sample's points are baked with.
    pub skin: Option<Skinning>,
    /// For an animated skinned primitive with [`Animation::extra`] samples: its still pose
    /// (targets at their default weights), which those samples skin.
    pub still: Option<Still>,
    /// The faces of each primitive drawing this one's vertex buffer (a material group), bound
    /// to its own material; empty for a Mesh of one primitive.
    pub subsets: Vec<Subset>,
}

/// A primitive's points and normals in the pose the glTF shows when no clip plays it.
pub struct Still {
    pub points: Vec<[f32; 3]>,
    pub normals: Option<Vec<[f32; 3]>>,
}

/// A `GeomSubset` of a Mesh (family `materialBind`): faces `faces` of the Mesh, bound to
/// `material`.
pub struct Subset {
    pub name: String,
    pub faces: Vec<i32>,
    pub material: Option<String>,
    /// As [`MeshPrim::variants`], for this subset's primitive.
    pub variants: Variants,
}

/// The materials of a primitive that `KHR_materials_variants` maps (empty for one it does
/// not): its own Material prim (then not bound on the prim itself, where it would win over
/// every variant: a variant's opinion is weaker than the prim's own) and the one each variant
/// (by index into [`Look::variants`]) binds instead; a variant it does not map binds its own.
/// Written as over prims in the root prim's variant set [`VARIANT_SET`] (see
/// [`variant_overs`]).
#[derive(Default)]
pub struct Variants {
    pub own: Option<String>,
    pub mapped: Vec<(usize, String)>,
}

/// The variant set on the root prim that chooses between a file's material variants; it
/// selects [`Look::default_variant`], every mesh with its own material (glTF's default).
pub const VARIANT_SET: &str = "materialVariant";

/// What a primitive drawing another's vertex buffer adds to it: its faces and its look.
struct Faces {
    name: String,
    indices: Vec<u32>,
    /// Its material's base colour (vertex colours are the buffer's, already read).
    color: Option<DisplayColor>,
    material: Option<String>,
    variants: Variants,
    double_sided: bool,
}

impl MeshPrim {
    /// Take in `other`, a primitive drawing the same vertex buffer (the same attributes and
    /// targets, so the same points and frames): its faces appended as a subset of their own
    /// with its material (this one's faces becoming the first subset), its base colour per
    /// face where the two differ, double-sided if either is.
    fn absorb(&mut self, other: Faces) {
        let start = self.indices.len() / 3;
        if self.subsets.is_empty() {
            self.subsets.push(Subset {
                name: self.name.clone(),
                faces: (0..start as i32).collect(),
                material: self.material.take(),
                variants: std::mem::take(&mut self.variants),
            });
        }
        let count = other.indices.len() / 3;
        self.subsets.push(Subset {
            name: other.name,
            faces: (start as i32..(start + count) as i32).collect(),
            material: other.material,
            variants: other.variants,
        });
        // USD's fallback display colour where a primitive has none.
        const GRAY: [f32; 3] = [0.5; 3];
        let per_face = |c: Option<DisplayColor>, n: usize| match c {
            Some(DisplayColor::Constant(c)) => vec![c; n],
            Some(DisplayColor::Face(v)) => v,
            _ => vec![GRAY; n],
        };
        self.color = match (self.color.take(), other.color) {
            // One COLOR_0 for both: the vertex colours stand.
            (Some(DisplayColor::Vertex(v)), _) => Some(DisplayColor::Vertex(v)),
            (Some(DisplayColor::Constant(a)), Some(DisplayColor::Constant(b))) if a == b => {
                Some(DisplayColor::Constant(a))
            }
            (None, None) => None,
            (a, b) => {
                let mut v = per_face(a, start);
                v.extend(per_face(b, count));
                Some(DisplayColor::Face(v))
            }
        };
        self.indices.extend(other.indices);
        self.double_sided |= other.double_sided;
    }
}

/// Where a mesh's display colour comes from.
pub enum DisplayColor {
    Constant([f32; 3]),
    Vertex(Vec<[f32; 3]>),
    /// One colour per face (`uniform`): material groups of one vertex buffer, each its own
    /// material's base colour.
    Face(Vec<[f32; 3]>),
}

/// The frames of an animated primitive: frame f of primitive `primitive` (its position in the
/// mesh's primitive list) of processed mesh `mesh` (its position in the job's list) is at time
/// code `times[f]`.
pub struct Animation {
    pub mesh: usize,
    pub primitive: usize,
    pub times: Vec<f64>,
    /// The frames this prim plays, when not every one (its node is driven by some of the
    /// mesh's tracks only).
    pub played: Option<Vec<usize>>,
    /// Whether the frames carry normals.
    pub normals: bool,
    /// 0, or for a skinned primitive its node + 1: a mesh skinned on two nodes has samples of
    /// its own under each.
    pub instance: usize,
    /// The samples are the skin's alone (a still mesh whose joints move): at `times`, from
    /// the prim's points, not from any processed mesh's frames (`mesh` is then unused).
    pub skin_only: bool,
    /// Time codes where a skinned prim's joints move but it plays no frame (a clip that
    /// tweens another mesh): samples of its still pose ([`MeshPrim::still`]) skinned there,
    /// after the frames' in the sample lists ([`Animation::ordered`]).
    pub extra: Vec<f64>,
}

impl Animation {
    /// Which samples these are.
    pub fn key(&self) -> SampleKey {
        (self.mesh, self.primitive, self.instance)
    }

    /// The frames this prim plays, in order.
    pub fn frames(&self) -> Vec<usize> {
        self.played
            .clone()
            .unwrap_or_else(|| (0..self.times.len()).collect())
    }

    /// The prim's samples in time order, as (time code, value) from `per_sample` (one value
    /// per frame of the mesh, then one per [`Animation::extra`] code): the frames it plays and
    /// its extra samples.
    pub fn ordered<T: Copy>(&self, per_sample: &[T]) -> Vec<(f64, T)> {
        let frames = self.frames().into_iter().map(|f| (self.times[f], f));
        let extra = (self.extra.iter().enumerate()).map(|(k, &c)| (c, self.times.len() + k));
        let mut out: Vec<(f64, T)> = (frames.chain(extra))
            .filter_map(|(c, i)| per_sample.get(i).map(|&v| (c, v)))
            .collect();
        out.sort_by(|a, b| a.0.total_cmp(&b.0));
        // Two tracks of one clip driving the node (a file with two weights channels on it in
        // one animation): one sample a code, the later track's, as a player applies channels.
        out.dedup_by(|later, kept| {
            let same = later.0 == kept.0;
            if same {
                *kept = *later;
            }
            same
        });
        out
    }

    /// `per_frame` (one value per frame of the mesh) at the frames this prim plays.
    pub fn pick<T: Copy>(&self, per_frame: &[T]) -> Vec<T> {
        self.frames()
            .into_iter()
            .filter_map(|f| per_frame.get(f).copied())
            .collect()
    }
}

/// The samples of one animated prim: (processed mesh, primitive, instance), see
/// [`Animation`]'s fields.
pub type SampleKey = (usize, usize, usize);

/// One frame of one primitive: deltas from its base points (and normals), in f32.
pub struct Delta<'a> {
    pub positions: &'a [[f32; 3]],
    pub normals: Option<&'a [[f32; 3]]>,
}

/// Hands every frame of every processed mesh, in order, to the sink it is given:
/// (processed mesh, frame index, per-primitive deltas).
pub type FrameSource<'a> =
    dyn FnMut(&mut dyn FnMut(usize, usize, &[Delta]) -> Result<()>) -> Result<()> + 'a;

/// Base + delta, in f32 as a glTF viewer adds them.
pub fn add(base: &[[f32; 3]], delta: &[[f32; 3]]) -> Vec<[f32; 3]> {
    base.iter()
        .zip(delta)
        .map(|(b, d)| [b[0] + d[0], b[1] + d[1], b[2] + d[2]])
        .collect()
}

/// A prim of the stage tree.
// One per node: an Xform's matrix inline (the common prim) over a box per Xform is the choice.
#[allow(clippy::large_enum_variant)]
pub enum Prim {
    Xform {
        name: String,
        /// What it keeps of the glTF node: its name and extras ([`Meta`]).
        meta: Meta,
        matrix: Option<[f64; 16]>,
        /// The node's local transform at each time code a clip on the stage moves it (time
        /// order); empty when none does, and then `matrix` stands.
        motion: Vec<(f64, [f64; 16])>,
        children: Vec<Prim>,
    },
    Mesh(Box<MeshPrim>),
    /// A node's camera or light ([`super::camera_light`]).
    Plain(Box<Plain>),
    /// A node drawing its mesh once per instance (`EXT_mesh_gpu_instancing`): a
    /// PointInstancer whose one prototype (`prototype`, an Xform holding the mesh's primitives,
    /// under a `Prototypes` scope) is placed by each instance's transform.
    Instancer(Box<InstancerPrim>),
}

/// A PointInstancer prim: an instancing node, its instances and its mesh as the prototype.
pub struct InstancerPrim {
    pub name: String,
    /// As [`Prim::Xform`]'s.
    pub meta: Meta,
    pub matrix: Option<[f64; 16]>,
    pub motion: Vec<(f64, [f64; 16])>,
    pub instances: Instances,
    pub prototype: Prim,
    pub children: Vec<Prim>,
}

/// The instances of an instancing node, in its own space: translation, rotation (x, y, z,
/// w) and scale of each.
pub struct Instances {
    pub positions: Vec<[f32; 3]>,
    pub orientations: Vec<[f32; 4]>,
    pub scales: Vec<[f32; 3]>,
}

/// The name of the scope under a PointInstancer that holds its prototype.
pub const PROTOTYPES: &str = "Prototypes";

/// The whole stage.
pub struct Stage {
    pub root: String,
    /// What the root keeps of the glTF scene: its name and extras.
    pub root_meta: Meta,
    /// The layer's `customLayerData`: the glTF asset's copyright, generator and extras
    /// (Sketchfab's author, licence and source), see [`layer_data`].
    pub layer_data: Option<Data>,
    pub rate: f64,
    pub start: f64,
    pub end: f64,
    pub children: Vec<Prim>,
    /// The materials the meshes are bound to and the textures they read.
    pub look: Look,
}

/// Make `s` a valid USD identifier.
pub fn identifier(s: &str) -> String {
    let mut out: String = s
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if out.is_empty() || out.starts_with(|c: char| c.is_ascii_digit()) {
        out.insert(0, '_');
    }
    out
}

/// What a prim keeps of the glTF object it was made from besides its content: the name it
/// shows, where its own is another ([`shown`], `displayName`), and the object's `extras`
/// (`customData = { dictionary extras = {...} }`, [`Data`]: Blender's custom properties).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Meta {
    pub display: Option<String>,
    pub extras: Option<Data>,
}

impl Meta {
    /// The metadata of a prim named `written` made from glTF object `gltf`.
    pub fn of(gltf: &Value, written: &str) -> Meta {
        Meta {
            display: shown(gltf, written),
            extras: Data::of(&gltf["extras"]),
        }
    }

    /// Leave entry `key` of the extras out (none left: no extras).
    pub fn leave_out(&mut self, key: &str) {
        if let Some(Data::Dict(entries)) = &mut self.extras {
            entries.retain(|(k, _)| k != key);
            if entries.is_empty() {
                self.extras = None;
            }
        }
    }
}

/// A `customData` value made from JSON: a boolean, a number (`int` where it is a whole number
/// that fits, else `int64`, else `double`), a string, an array of one of those kinds (`bool[]`,
/// `int[]` or `double[]`, `string[]`; an empty one `string[]`), an object a dictionary (keys in
/// order, null entries left out); any other array (mixed, nested) its JSON text as a string;
/// text as [`usd_text`] makes it.
#[derive(Clone, Debug, PartialEq)]
pub enum Data {
    Bool(bool),
    Int(i32),
    Int64(i64),
    Double(f64),
    String(String),
    Bools(Vec<bool>),
    Ints(Vec<i32>),
    Doubles(Vec<f64>),
    Strings(Vec<String>),
    Dict(Vec<(String, Data)>),
}

impl Data {
    /// `v` as a `customData` value; `None` for null or an empty object.
    pub fn of(v: &Value) -> Option<Data> {
        let int = |v: &Value| v.as_i64().and_then(|i| i32::try_from(i).ok());
        Some(match v {
            Value::Null => return None,
            Value::Bool(b) => Data::Bool(*b),
            Value::Number(n) => match (int(v), n.as_i64()) {
                (Some(i), _) => Data::Int(i),
                (None, Some(i)) => Data::Int64(i),
                _ => Data::Double(n.as_f64().unwrap_or(0.0)),
            },
            Value::String(s) => Data::String(usd_text(s)),
            Value::Array(a) if a.iter().all(Value::is_string) => {
                Data::Strings(a.iter().filter_map(|s| s.as_str().map(usd_text)).collect())
            }
            Value::Array(a) if a.iter().all(Value::is_boolean) => {
                Data::Bools(a.iter().filter_map(Value::as_bool).collect())
            }
            Value::Array(a) if a.iter().all(|x| int(x).is_some()) => {
                Data::Ints(a.iter().filter_map(int).collect())
            }
            Value::Array(a) if a.iter().all(Value::is_number) => {
                Data::Doubles(a.iter().filter_map(Value::as_f64).collect())
            }
            Value::Array(_) => Data::String(usd_text(&v.to_string())),
            Value::Object(o) => {
                let mut entries: Vec<(String, Data)> = (o.iter())
                    .filter_map(|(k, v)| Some((usd_text(k), Data::of(v)?)))
                    .collect();
                if entries.is_empty() {
                    return None;
                }
                // USD keeps a dictionary's keys sorted.
                entries.sort_by(|a, b| a.0.cmp(&b.0));
                Data::Dict(entries)
            }
        })
    }
}

/// What the layer keeps of the glTF `asset`: its `copyright`, its `generator` (as
/// `sourceGenerator`: the layer's own is `doc`) and its `extras` (Sketchfab's author, licence,
/// source and title), as a `customLayerData` dictionary; `None` when it has none of them.
pub fn layer_data(asset: &Value) -> Option<Data> {
    Data::of(&json!({
        "copyright": asset["copyright"],
        "extras": asset["extras"],
        "sourceGenerator": asset["generator"],
    }))
}

/// The name a prim shows (its `displayName` metadata): the glTF object's own `name` where
/// the prim's `written` name (made an identifier, unique among its siblings, a primitive's
/// index added) is not it, so that no name the file gives is lost; none for an unnamed object
/// or a name kept as it is. E.g. node "Face.001" is prim `Face_001` showing "Face.001".
pub fn shown(gltf: &Value, written: &str) -> Option<String> {
    (gltf["name"].as_str())
        .filter(|n| *n != written)
        .map(usd_text)
}

/// `s` as a USD string can hold it: a NUL character (which ends a string in the binary
/// format's tables: the tokens after it would shift) as U+FFFD, the replacement character.
pub fn usd_text(s: &str) -> String {
    s.replace('\0', "\u{fffd}")
}

/// Unique names among siblings: the first keeps its name, later ones get `_1`, `_2`, ...
pub(super) fn unique(name: String, taken: &mut HashMap<String, usize>) -> String {
    let mut candidate = name.clone();
    while let Some(n) = taken.get_mut(&candidate) {
        *n += 1;
        candidate = format!("{name}_{n}");
    }
    taken.insert(candidate.clone(), 0);
    candidate
}

/// A processed mesh as the USD writer sees it before any frame is computed: the glTF mesh
/// index and the time code of each of its frames (every track's, in order).
pub struct MeshPlan {
    pub mesh: usize,
    pub codes: Vec<f64>,
    /// The frames each node carrying the mesh plays (those of the tracks that drive it), when
    /// some node does not play them all; a node not listed plays none (its mesh is written
    /// still). `None`: every node plays every frame.
    pub played: Option<HashMap<usize, Vec<usize>>>,
}

/// Build the stage from the glTF document and the processed meshes' frames, at `rate` time
/// codes per second; texture files are named `<texture_prefix><image name>.<png|jpg>`.
pub fn build_stage(
    doc: &Document,
    meshes: &[MeshPlan],
    clips: Vec<ClipOnStage>,
    rate: f64,
    texture_prefix: &str,
) -> Result<Stage> {
    let json = &doc.json;
    // The timeline: every processed mesh's frames and every clip's (a clip that plays no
    // mesh's frames, as a blend's, moves nodes and skinned meshes).
    let clip_codes: Vec<f64> = clips.iter().flat_map(|c| c.codes.iter().copied()).collect();
    let (motion, not_carried) = NodeMotion::new(doc, clips, rate);
    let codes: Vec<Vec<f64>> = meshes.iter().map(|m| m.codes.clone()).collect();
    let scene_index = json["scene"].as_u64().unwrap_or(0) as usize;
    let scene = arr(json, "scenes").get(scene_index);
    let roots: Vec<usize> = match scene {
        Some(s) => arr(s, "nodes")
            .iter()
            .filter_map(Value::as_u64)
            .map(|n| n as usize)
            .collect(),
        None => {
            let mut is_child = vec![false; arr(json, "nodes").len()];
            for n in arr(json, "nodes") {
                for c in arr(n, "children").iter().filter_map(Value::as_u64) {
                    if let Some(x) = is_child.get_mut(c as usize) {
                        *x = true;
                    }
                }
            }
            (0..is_child.len()).filter(|&i| !is_child[i]).collect()
        }
    };
    let root_name = scene
        .and_then(|s| s["name"].as_str())
        .filter(|s| !s.is_empty())
        .map(str::to_owned)
        .unwrap_or_else(|| {
            doc.path
                .file_stem()
                .and_then(|s| s.to_str())
                .unwrap_or("scene")
                .to_owned()
        });
    let ctx = Ctx {
        doc,
        meshes,
        codes: &codes,
        motion: &motion,
        look: RefCell::new(LookBuilder::new(doc, texture_prefix)),
        left_out: RefCell::new(Vec::new()),
    };
    let mut taken = HashMap::new();
    let mut children = Vec::new();
    for n in roots {
        children.push(ctx.node(n, &mut taken, 0)?);
    }
    let look = ctx
        .look
        .into_inner()
        .finish(unique("Materials".into(), &mut taken))?;
    let ctx_left_out = ctx.left_out.into_inner();
    let all: Vec<f64> = codes.iter().flatten().copied().chain(clip_codes).collect();
    let start = all.iter().copied().fold(f64::INFINITY, f64::min);
    let end = all.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let (start, end) = if start.is_finite() {
        (start, end)
    } else {
        (0.0, 0.0)
    };
    let mut stage = Stage {
        root: identifier(&root_name),
        root_meta: scene.map_or_else(Meta::default, |s| Meta::of(s, &identifier(&root_name))),
        layer_data: layer_data(&json["asset"]),
        rate,
        start,
        end,
        children,
        look,
    };
    stage.look.left_out.extend(ctx_left_out);
    stage.look.left_out.extend(not_carried);
    // The stage is the file's scene: a processed mesh no node of it carries has no frames
    // there, which is said (and with none shown, refused) rather than passed over.
    let shown = animated(&stage);
    let missing: Vec<String> = (meshes.iter().enumerate())
        .filter(|(k, _)| !shown.contains_key(k))
        .map(|(_, m)| quoted_name(&json["meshes"][m.mesh], || format!("mesh {}", m.mesh)))
        .collect();
    if !missing.is_empty() {
        let scene = match scene {
            Some(s) => format!(
                "scene {scene_index}{}",
                s["name"]
                    .as_str()
                    .map_or(String::new(), |n| format!(" ({n:?})"))
            ),
            None => "the file's root nodes".to_string(),
        };
        if missing.len() == meshes.len() {
            bail!(doc.err(format!(
                "{scene}, which a USD stage is made of, shows none of the animated meshes ({}); a glTF output keeps them",
                listed(&missing)
            )));
        }
        stage.look.left_out.push(format!(
            "{scene}, which a USD stage is made of, does not show {}: not in the point cache",
            listed(&missing)
        ));
    }
    Ok(stage)
}

struct Ctx<'a> {
    doc: &'a Document,
    meshes: &'a [MeshPlan],
    codes: &'a [Vec<f64>],
    motion: &'a NodeMotion,
    look: RefCell<LookBuilder<'a>>,
    /// What the nodes' cameras and lights do not carry.
    left_out: RefCell<Vec<String>>,
}

impl Ctx<'_> {
    fn node(&self, index: usize, taken: &mut HashMap<String, usize>, depth: usize) -> Result<Prim> {
        let json = &self.doc.json;
        let node = &json["nodes"][index];
        if depth > 256 {
            bail!(self
                .doc
                .err("the node hierarchy is deeper than 256 levels (a cycle?)"));
        }
        let name = unique(
            identifier(node["name"].as_str().unwrap_or(&format!("node{index}"))),
            taken,
        );
        let matrix = node_matrix(node);
        let motion = self.motion.samples(index, node);
        let mut kids = HashMap::new();
        let mut children = Vec::new();
        let instances = self.instances(index)?;
        let mut mesh = Vec::new();
        if let Some(mi) = node["mesh"].as_u64() {
            let mut taken = HashMap::new();
            let names = if instances.is_some() {
                &mut taken
            } else {
                &mut kids
            };
            if instances.is_some() && node["skin"].is_u64() {
                self.left_out.borrow_mut().push(format!(
                    "node {} draws a skinned mesh once per instance (EXT_mesh_gpu_instancing), which glTF does not skin: its instances are written unskinned",
                    quoted_name(node, || index.to_string())
                ));
            }
            mesh = self.mesh(index, mi as usize, names, instances.is_none())?;
        }
        if instances.is_none() {
            children.append(&mut mesh);
        } else {
            // The prototype's name is unique among the node's prims too.
            kids.insert(PROTOTYPES.to_string(), 0);
        }
        let plain = camera_light::of_node(json, index, &mut kids, &mut self.left_out.borrow_mut());
        children.extend(plain.into_iter().map(|p| Prim::Plain(Box::new(p))));
        for c in arr(node, "children").iter().filter_map(Value::as_u64) {
            children.push(self.node(c as usize, &mut kids, depth + 1)?);
        }
        Ok(match instances {
            Some(instances) => {
                let mi = node["mesh"].as_u64().unwrap_or(0) as usize;
                let mesh_name = self.doc.json["meshes"][mi]["name"].as_str();
                let prototype_name = identifier(mesh_name.unwrap_or(&format!("mesh{mi}")));
                let prototype = Prim::Xform {
                    // The mesh's extras are its Mesh prims'.
                    meta: Meta {
                        display: shown(&self.doc.json["meshes"][mi], &prototype_name),
                        extras: None,
                    },
                    name: prototype_name,
                    matrix: None,
                    motion: Vec::new(),
                    children: mesh,
                };
                Prim::Instancer(Box::new(InstancerPrim {
                    meta: Meta::of(node, &name),
                    name,
                    matrix,
                    motion,
                    instances,
                    prototype,
                    children,
                }))
            }
            None => Prim::Xform {
                meta: Meta::of(node, &name),
                name,
                matrix,
                motion,
                children,
            },
        })
    }

    /// The points and normals of primitive `p` of mesh `mi` as node `node` shows it when no
    /// clip plays: its targets blended by the node's `weights`, else the mesh's (a face held
    /// in an expression, a prop squashed by a blend shape); normals renormalised.
    fn posed(
        &self,
        node: usize,
        mi: usize,
        p: &Value,
        mut points: Vec<DVec3>,
        mut normals: Option<Vec<DVec3>>,
        what: &str,
    ) -> Result<(Vec<DVec3>, Option<Vec<DVec3>>)> {
        let json = &self.doc.json;
        let weights = match json["nodes"][node]["weights"].as_array() {
            Some(w) => w,
            None => arr(&json["meshes"][mi], "weights"),
        };
        let targets = arr(p, "targets");
        let mut moved = false;
        for (i, w) in weights.iter().enumerate() {
            let (Some(w), Some(t)) = (w.as_f64(), targets.get(i)) else {
                continue;
            };
            if w == 0.0 {
                continue;
            }
            if let Some(acc) = t["POSITION"].as_u64() {
                let d = read_vec3(
                    self.doc,
                    acc as usize,
                    &format!("{what} target {i} POSITION"),
                )?;
                points.iter_mut().zip(&d).for_each(|(p, d)| *p += w * *d);
            }
            if let (Some(n), Some(acc)) = (normals.as_mut(), t["NORMAL"].as_u64()) {
                let d = read_vec3(self.doc, acc as usize, &format!("{what} target {i} NORMAL"))?;
                n.iter_mut().zip(&d).for_each(|(n, d)| *n += w * *d);
                moved = true;
            }
        }
        if moved {
            normals
                .iter_mut()
                .flatten()
                .for_each(|n| *n = n.normalize_or_zero());
        }
        Ok((points, normals))
    }

    /// Node `node`'s skeleton, for its mesh `mesh_name` (whose frames are at `frames`), and
    /// the time codes its joints move at; `None` where the node has no skin, or (with a line
    /// saying so) where its world transform cannot be inverted at one of its time codes.
    fn skeleton(
        &self,
        node: usize,
        mesh_name: &str,
        frames: &[f64],
    ) -> Result<Option<(Arc<Skeleton>, Vec<f64>)>> {
        let json = &self.doc.json;
        let samples_of = |x: usize| self.motion.samples(x, &json["nodes"][x]);
        let Some(skeleton) = Skeleton::read(self.doc, node, &samples_of)? else {
            return Ok(None);
        };
        let moves = skeleton.codes();
        let mut codes = [&moves[..], frames].concat();
        if codes.is_empty() {
            codes.push(0.0);
        }
        if !skeleton.works_at(&codes) {
            let node_name = quoted_name(&json["nodes"][node], || node.to_string());
            say(&mut self.left_out.borrow_mut(), format!(
                "node {node_name} is scaled to nothing, so mesh {mesh_name:?}'s skin cannot be placed in it: written unskinned"
            ));
            return Ok(None);
        }
        Ok(Some((skeleton, moves)))
    }

    /// Primitive `p`'s look: its material's base colour (white for a material without one;
    /// None without a material), whether it is double-sided, and the material's prim (made on
    /// first use; `vertex_colors`: the primitive has COLOR_0, which the material multiplies).
    fn look_of(
        &self,
        p: &Value,
        vertex_colors: bool,
    ) -> Result<(Option<[f32; 3]>, bool, Option<String>)> {
        let index = p["material"].as_u64();
        let material = index.map(|m| &self.doc.json["materials"][m as usize]);
        let color = material.map(|m| {
            let c = arr(&m["pbrMetallicRoughness"], "baseColorFactor");
            [0, 1, 2].map(|i| c.get(i).and_then(Value::as_f64).unwrap_or(1.0) as f32)
        });
        let double_sided = material.is_some_and(|m| m["doubleSided"].as_bool() == Some(true));
        let prim = match index {
            Some(m) => (self.look.borrow_mut()).material(m as usize, vertex_colors)?,
            None => None,
        };
        Ok((color, double_sided, prim))
    }

    /// The binding of primitive `p` whose own Material prim is `material`: on the prim, or
    /// with its variants where it has some (see [`Variants`]).
    fn variants(
        &self,
        material: Option<String>,
        p: &Value,
        vertex_colors: bool,
    ) -> Result<(Option<String>, Variants)> {
        let mapped = self.variant_looks(p, vertex_colors)?;
        Ok(match mapped.is_empty() {
            true => (material, Variants::default()),
            false => (
                None,
                Variants {
                    own: material,
                    mapped,
                },
            ),
        })
    }

    /// Primitive `p`'s material variants: the Material prim of each variant its
    /// `KHR_materials_variants` mappings name (made on first use, as [`Ctx::look_of`]'s), in
    /// variant order; a variant mapped twice takes its first mapping, one the file does not
    /// declare is passed over.
    fn variant_looks(&self, p: &Value, vertex_colors: bool) -> Result<Vec<(usize, String)>> {
        let declared = arr(
            &self.doc.json["extensions"]["KHR_materials_variants"],
            "variants",
        );
        let mut out = Vec::new();
        for mapping in arr(&p["extensions"]["KHR_materials_variants"], "mappings") {
            let Some(m) = mapping["material"].as_u64() else {
                continue;
            };
            let Some(prim) = (self.look.borrow_mut()).material(m as usize, vertex_colors)? else {
                continue;
            };
            for v in arr(mapping, "variants").iter().filter_map(Value::as_u64) {
                let v = v as usize;
                if v < declared.len() && !out.iter().any(|(x, _)| *x == v) {
                    out.push((v, prim.clone()));
                }
            }
        }
        out.sort();
        Ok(out)
    }

    /// The instances of a node with a mesh and `EXT_mesh_gpu_instancing` ([`gltf::instances`]),
    /// in single precision, or `None`.
    fn instances(&self, index: usize) -> Result<Option<Instances>> {
        let Some(inst) = gltf::instances(self.doc, index)? else {
            return Ok(None);
        };
        let f32s = |v: &[DVec3]| v.iter().map(|v| v.as_vec3().to_array()).collect();
        Ok(Some(Instances {
            positions: f32s(&inst.translations),
            orientations: (inst.rotations.iter())
                .map(|q| q.as_quat().to_array())
                .collect(),
            scales: f32s(&inst.scales),
        }))
    }

    /// The Mesh prims of mesh `mi` drawn by node `node`, skinned by the node's skin when
    /// `skinned` (a node drawing instances is not).
    fn mesh(
        &self,
        node: usize,
        mi: usize,
        taken: &mut HashMap<String, usize>,
        skinned: bool,
    ) -> Result<Vec<Prim>> {
        let doc = self.doc;
        let mesh = &doc.json["meshes"][mi];
        let mesh_name = mesh["name"]
            .as_str()
            .map(str::to_owned)
            .unwrap_or_else(|| format!("mesh{mi}"));
        let processed = self.meshes.iter().position(|m| m.mesh == mi);
        let prims = arr(mesh, "primitives");
        // The node's skeleton and where its joints move: read at the first primitive that is
        // skinned, once for them all.
        let frames = processed.map_or(&[][..], |k| &self.codes[k][..]);
        let mut skeleton: Option<Option<(Arc<Skeleton>, Vec<f64>)>> = None;
        // Primitives with the same attributes and targets draw one vertex buffer (three.js'
        // and Babylon.js' material groups): one Mesh with a subset per primitive.
        let mut groups: Vec<(Value, MeshPrim)> = Vec::new();
        for (pi, p) in prims.iter().enumerate() {
            if !matches!(p["mode"].as_u64().unwrap_or(4), 4..=6) {
                continue; // points and lines have no Mesh form
            }
            let what = format!("mesh {mesh_name:?} primitive {pi}");
            let Some(pos) = p["attributes"]["POSITION"].as_u64() else {
                continue;
            };
            let base_name = if prims.len() == 1 {
                identifier(&mesh_name)
            } else {
                identifier(&format!("{mesh_name}_{pi}"))
            };
            let vertices = json!([p["attributes"], p["targets"]]);
            if let Some((_, first)) = groups.iter_mut().find(|(v, _)| *v == vertices) {
                // A material group of a vertex buffer already read: its faces and look only.
                let indices = triangle_indices(doc, p, first.points.len(), &what)?;
                let vertex_colors = p["attributes"]["COLOR_0"].is_u64();
                let (color, double_sided, material) = self.look_of(p, vertex_colors)?;
                let (material, variants) = self.variants(material, p, vertex_colors)?;
                first.absorb(Faces {
                    name: base_name,
                    indices,
                    color: color.map(DisplayColor::Constant),
                    material,
                    variants,
                    double_sided,
                });
                continue;
            }
            let points = read_vec3(doc, pos as usize, &format!("{what} POSITION"))?;
            let n = points.len();
            let normals = read_attribute3(doc, p, "NORMAL", n, &what)?;
            let mut st = Vec::new();
            for set in 0..8 {
                let key = format!("TEXCOORD_{set}");
                if let Some(v) = read_attribute(doc, p, &key, 2, n, &what)? {
                    let v = v.chunks_exact(2);
                    let v = v.map(|t| [t[0] as f32, 1.0 - t[1] as f32]).collect();
                    st.push((st_name(set), v));
                }
            }
            let indices = triangle_indices(doc, p, n, &what)?;
            // COLOR_0 (float or normalized, RGB or RGBA) wins over the material's constant.
            let rgba = match p["attributes"]["COLOR_0"].as_u64() {
                Some(a) => {
                    let comps = if doc.json["accessors"][a as usize]["type"] == "VEC4" {
                        4
                    } else {
                        3
                    };
                    read_attribute(doc, p, "COLOR_0", comps, n, &what)?.map(|v| (v, comps))
                }
                None => None,
            };
            let (color, double_sided, material) = self.look_of(p, rgba.is_some())?;
            let (material, variants) = self.variants(material, p, rgba.is_some())?;
            let (color, opacity) = match rgba {
                Some((v, comps)) => {
                    let c = |x: f64| x.clamp(0.0, 1.0) as f32;
                    let rgb = v
                        .chunks_exact(comps)
                        .map(|x| [c(x[0]), c(x[1]), c(x[2])])
                        .collect();
                    let alpha = (comps == 4).then(|| v.chunks_exact(4).map(|x| c(x[3])).collect());
                    (Some(DisplayColor::Vertex(rgb)), alpha)
                }
                None => (color.map(DisplayColor::Constant), None),
            };
            // Processed meshes keep every primitive (a non-triangle one is an error there).
            let played = processed.map(|k| {
                (self.meshes[k].played.as_ref()).map(|p| p.get(&node).cloned().unwrap_or_default())
            });
            let animation = processed
                .filter(|_| {
                    !played
                        .as_ref()
                        .is_some_and(|p| p.as_ref().is_some_and(Vec::is_empty))
                })
                .map(|k| Animation {
                    mesh: k,
                    primitive: pi,
                    times: self.codes[k].clone(),
                    played: played.clone().flatten(),
                    normals: normals.is_some()
                        && prims.iter().all(|q| q["attributes"]["NORMAL"].is_u64()),
                    instance: 0,
                    skin_only: false,
                    extra: Vec::new(),
                });
            if skinned && skeleton.is_none() {
                skeleton = Some(self.skeleton(node, &mesh_name, frames)?);
            }
            let read = skeleton.as_ref().and_then(Option::as_ref);
            let skin = match read {
                Some((skeleton, _)) => Skinning::read(doc, skeleton, p, n, &what)?,
                None => None,
            };
            let moves: &[f64] = read.map_or(&[], |(_, codes)| codes);
            // Where a skinned prim's joints move and it plays no frame, its still pose.
            let extra: Vec<f64> = match (&animation, &skin) {
                (Some(a), Some(_)) => {
                    let played: Vec<f64> = a.pick(&a.times);
                    (moves.iter())
                        .filter(|c| !played.contains(c))
                        .copied()
                        .collect()
                }
                _ => Vec::new(),
            };
            let still = match extra.is_empty() {
                true => None,
                false => Some(self.posed(node, mi, p, points.clone(), normals.clone(), &what)?),
            };
            // Written still: the pose the glTF shows, its default weights applied.
            let (points, normals) = match animation {
                Some(_) => (points, normals),
                None => self.posed(node, mi, p, points, normals, &what)?,
            };
            // A skinned prim has samples of its own (see [`Animation::instance`]); a still one
            // whose joints move is animated by its skin alone.
            let animation = match (animation, &skin) {
                (Some(a), Some(_)) => Some(Animation {
                    instance: node + 1,
                    extra,
                    ..a
                }),
                (None, Some(_)) if !moves.is_empty() => Some(Animation {
                    mesh: usize::MAX,
                    primitive: pi,
                    times: moves.to_vec(),
                    played: None,
                    normals: normals.is_some(),
                    instance: node + 1,
                    skin_only: true,
                    extra: Vec::new(),
                }),
                (a, _) => a,
            };
            let f32s = |v: Vec<DVec3>| -> Vec<[f32; 3]> {
                v.into_iter().map(|p| p.as_vec3().to_array()).collect()
            };
            let still = still.map(|(p, n)| Still {
                points: f32s(p),
                normals: n.map(f32s),
            });
            let mut prim = MeshPrim {
                name: base_name,
                meta: Meta::default(),
                still,
                points: f32s(points),
                normals: normals.map(f32s),
                st,
                indices,
                color,
                opacity,
                double_sided,
                material,
                variants,
                animation,
                skin,
                subsets: Vec::new(),
            };
            // Frames without normals (another primitive of the mesh has none): a skinned
            // prim's stored normals would not turn with it, so USD computes them.
            if prim.skin.is_some() && prim.animation.as_ref().is_some_and(|a| !a.normals) {
                prim.normals = None;
            }
            // Skinned and still: baked once, in the pose its joints rest in.
            if prim.animation.is_none() {
                if let Some(skin) = prim.skin.take() {
                    skin.apply(0.0, &mut prim.points, prim.normals.as_deref_mut());
                }
            }
            groups.push((vertices, prim));
        }
        let whole = groups.len() == 1 && !groups[0].1.subsets.is_empty();
        Ok(groups
            .into_iter()
            .map(|(_, mut m)| {
                if whole {
                    m.name = identifier(&mesh_name);
                }
                m.name = unique(std::mem::take(&mut m.name), taken);
                m.meta = Meta::of(mesh, &m.name);
                // The morph targets' names: a point cache has no targets.
                m.meta.leave_out("targetNames");
                Prim::Mesh(Box::new(m))
            })
            .collect())
    }
}

/// The triangles of primitive `p` (of `n` vertices) as a flat index list.
fn triangle_indices(doc: &Document, p: &Value, n: usize, what: &str) -> Result<Vec<u32>> {
    Ok(read_triangles(doc, p, n, what)?
        .into_iter()
        .flatten()
        .collect())
}

/// Local transform of a glTF node as a column-major 4x4 (USD's row-vector matrix4d reads the
/// same 16 numbers row by row); `None` for the identity.
fn node_matrix(node: &Value) -> Option<[f64; 16]> {
    let m = rest_matrix(node);
    (m != DMat4::IDENTITY).then(|| m.to_cols_array())
}

/// Minimum and maximum corner of `points`.
pub fn extent(points: &[[f32; 3]]) -> [[f32; 3]; 2] {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for p in points {
        for c in 0..3 {
            lo[c] = lo[c].min(p[c]);
            hi[c] = hi[c].max(p[c]);
        }
    }
    if points.is_empty() {
        return [[0.0; 3]; 2];
    }
    [lo, hi]
}

/// The animated primitives of a stage by processed mesh, each mesh's in stage order: one entry
/// per (processed mesh, primitive), with the base points and normals its frames' deltas apply
/// to (instances share the entry). Grouped so that a frame finds its own mesh's primitives
/// (scanning all of them for each frame, 8,000 animated meshes took 13.5 s to write).
pub fn animated(stage: &Stage) -> HashMap<usize, Vec<&MeshPrim>> {
    let (mut seen, mut out) = (HashSet::new(), HashMap::<usize, Vec<&MeshPrim>>::new());
    for m in prims_of(stage) {
        if let Some(a) = m.animation.as_ref().filter(|a| !a.skin_only) {
            if seen.insert(a.key()) {
                out.entry(a.mesh).or_default().push(m);
            }
        }
    }
    out
}

/// Every Mesh prim of the stage, in stage order (a prototype's once).
fn prims_of(stage: &Stage) -> Vec<&MeshPrim> {
    fn walk<'a>(p: &'a Prim, out: &mut Vec<&'a MeshPrim>) {
        match p {
            Prim::Xform { children, .. } => children.iter().for_each(|c| walk(c, out)),
            Prim::Instancer(i) => {
                walk(&i.prototype, out);
                i.children.iter().for_each(|c| walk(c, out));
            }
            Prim::Mesh(m) => out.push(m),
            Prim::Plain(_) => {}
        }
    }
    let mut out = Vec::new();
    stage.children.iter().for_each(|c| walk(c, &mut out));
    out
}

/// The over prims below the root prim that one material variant holds: a path of prim names
/// down to each Mesh or GeomSubset it binds, and the Material prim it binds there.
#[derive(Default)]
pub struct Overs {
    pub children: Vec<(String, Overs)>,
    pub material: Option<String>,
}

impl Overs {
    fn insert(&mut self, path: &[String], material: &str) {
        let Some((first, rest)) = path.split_first() else {
            self.material = Some(material.to_owned());
            return;
        };
        let at = match self.children.iter().position(|(n, _)| n == first) {
            Some(at) => at,
            None => {
                self.children.push((first.clone(), Overs::default()));
                self.children.len() - 1
            }
        };
        self.children[at].1.insert(rest, material);
    }
}

/// Each material variant of the stage with the over prims it binds: the default one
/// ([`Look::default_variant`], every primitive's own material), then the file's
/// ([`Look::variants`]); none where the file has none.
pub fn variant_overs(stage: &Stage) -> Vec<(String, Overs)> {
    // The default variant first, then the file's.
    fn bind(out: &mut [(String, Overs)], path: &[String], variants: &Variants) {
        if variants.mapped.is_empty() {
            return;
        }
        for (v, (_, overs)) in out.iter_mut().enumerate() {
            let mapped = v.checked_sub(1).and_then(|v| {
                let at = variants.mapped.iter().find(|(x, _)| *x == v);
                at.map(|(_, m)| m)
            });
            if let Some(material) = mapped.or(variants.own.as_ref()) {
                overs.insert(path, material);
            }
        }
    }
    fn walk(p: &Prim, path: &mut Vec<String>, out: &mut [(String, Overs)]) {
        match p {
            Prim::Xform { name, children, .. } => {
                path.push(name.clone());
                children.iter().for_each(|c| walk(c, path, out));
                path.pop();
            }
            Prim::Instancer(i) => {
                path.push(i.name.clone());
                path.push(PROTOTYPES.into());
                walk(&i.prototype, path, out);
                path.pop();
                i.children.iter().for_each(|c| walk(c, path, out));
                path.pop();
            }
            Prim::Mesh(m) => {
                path.push(m.name.clone());
                bind(out, path, &m.variants);
                for sub in &m.subsets {
                    path.push(sub.name.clone());
                    bind(out, path, &sub.variants);
                    path.pop();
                }
                path.pop();
            }
            Prim::Plain(_) => {}
        }
    }
    let look = &stage.look;
    if look.variants.is_empty() {
        return Vec::new();
    }
    let mut out: Vec<(String, Overs)> = (std::iter::once(&look.default_variant))
        .chain(&look.variants)
        .map(|v| (v.clone(), Overs::default()))
        .collect();
    let mut path = Vec::new();
    stage
        .children
        .iter()
        .for_each(|c| walk(c, &mut path, &mut out));
    out
}

/// The time-sampled arrays of one animated primitive at one frame.
pub struct Sample {
    pub extent: [[f32; 3]; 2],
    pub points: Vec<[f32; 3]>,
    /// Present when the primitive's frames carry normals.
    pub normals: Option<Vec<[f32; 3]>>,
}

/// Call `f` with the sample of every animated primitive of processed mesh `k` in `prims` (from
/// [`animated`]), given that mesh's per-primitive deltas for one frame.
pub fn for_each_sample(
    prims: &HashMap<usize, Vec<&MeshPrim>>,
    k: usize,
    frame: usize,
    deltas: &[Delta],
    f: &mut dyn FnMut(&Animation, Sample) -> Result<()>,
) -> Result<()> {
    for m in prims.get(&k).into_iter().flatten() {
        let Some(a) = m.animation.as_ref() else {
            continue;
        };
        let d = &deltas[a.primitive];
        let points = add(&m.points, d.positions);
        let normals = match (a.normals, &m.normals, d.normals) {
            (true, Some(base), Some(n)) => Some(add(base, n)),
            _ => None,
        };
        f(a, sample(m, a.times[frame], points, normals))?;
    }
    Ok(())
}

/// Call `f` with every sample (and its time code) that a prim's skin alone makes: every
/// sample of a prim whose samples are all its skin's ([`Animation::skin_only`]), and the
/// [`Animation::extra`] samples of the others, in that order for each prim.
pub fn for_each_skin_sample(
    stage: &Stage,
    f: &mut dyn FnMut(&Animation, f64, Sample) -> Result<()>,
) -> Result<()> {
    for m in prims_of(stage) {
        let Some(a) = m.animation.as_ref() else {
            continue;
        };
        let (codes, points, normals) = match (a.skin_only, &m.still) {
            (true, _) => (&a.times, &m.points, &m.normals),
            (false, Some(still)) => (&a.extra, &still.points, &still.normals),
            (false, None) => continue,
        };
        for &code in codes {
            let normals = normals.clone().filter(|_| a.normals);
            f(a, code, sample(m, code, points.clone(), normals))?;
        }
    }
    Ok(())
}

/// The sample of prim `m` at time code `code` from its points and normals there, skinned
/// when it has a skin.
fn sample(
    m: &MeshPrim,
    code: f64,
    mut points: Vec<[f32; 3]>,
    mut normals: Option<Vec<[f32; 3]>>,
) -> Sample {
    if let Some(skin) = &m.skin {
        skin.apply(code, &mut points, normals.as_deref_mut());
    }
    Sample {
        extent: extent(&points),
        points,
        normals,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_prim_has_one_sample_a_time_code() {
        // Two tracks of one clip on one node (frames 0-2 and 3-5 at the same codes), and an
        // extra sample between: one sample a code, the later track's.
        let a = Animation {
            mesh: 0,
            primitive: 0,
            times: vec![0.0, 1.0, 2.0, 0.0, 1.0, 2.0],
            played: None,
            normals: false,
            instance: 0,
            skin_only: false,
            extra: vec![1.5],
        };
        let per_sample = ['a', 'b', 'c', 'd', 'e', 'f', 'x'];
        let want = [(0.0, 'd'), (1.0, 'e'), (1.5, 'x'), (2.0, 'f')];
        assert_eq!(a.ordered(&per_sample), want);
    }
}
