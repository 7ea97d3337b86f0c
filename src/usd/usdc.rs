//! `.usdc` writer: the USD crate binary format, version 0.8.0, written from a [`Stage`].
//!
//! Layout: an 88-byte bootstrap (`PXR-USDC`, version, offset of the table of contents), the
//! values that do not fit in a field ("heap": arrays, matrices, doubles, time samples), then
//! the six structural sections TOKENS, STRINGS, FIELDS, FIELDSETS, PATHS and SPECS, then the
//! table of contents. Structural sections are integer-coded (deltas, a common value and 2-bit
//! width codes) and LZ4-compressed; integer arrays of 16 elements or more are too; float
//! arrays are stored raw. Child lists (`primChildren`, `properties`) are TokenVector values.
//!
//! Every frame's points are written to the file as they are produced: a time-sampled value is
//! laid out as `[offset to times][times][times rep][offset to reps][sample arrays][count][reps]`
//! with every size known beforehand, so nothing is patched but the bootstrap.

use super::camera_light::Plain;
use super::material::{Look, Shader, Value, SURFACE};
use super::stage::{
    animated, extent, for_each_sample, for_each_skin_sample, variant_overs, Animation, Data,
    DisplayColor, FrameSource, MeshPrim, Meta, Overs, Prim, Sample, SampleKey, Stage, PROTOTYPES,
    VARIANT_SET,
};
use anyhow::Result;
use std::collections::HashMap;
use std::io::{Seek, SeekFrom, Write};

const VERSION: [u8; 3] = [0, 8, 0];
const BOOTSTRAP_SIZE: u64 = 88;
/// Pixar's reader treats integer arrays shorter than this as uncompressed.
const MIN_COMPRESSED_ARRAY: usize = 16;

// Value types (crate type enum).
const T_BOOL: u64 = 1;
const T_INT: u64 = 3;
const T_INT64: u64 = 5;
const T_FLOAT: u64 = 8;
const T_DOUBLE: u64 = 9;
const T_STRING: u64 = 10;
const T_TOKEN: u64 = 11;
const T_ASSET_PATH: u64 = 12;
const T_MATRIX4D: u64 = 15;
const T_DICTIONARY: u64 = 31;
const T_QUATH: u64 = 18;
const T_VEC2F: u64 = 20;
const T_VEC3F: u64 = 24;
const T_VEC4F: u64 = 28;
const T_TOKEN_LIST_OP: u64 = 32;
const T_STRING_LIST_OP: u64 = 33;
const T_PATH_LIST_OP: u64 = 34;
const T_TOKEN_VECTOR: u64 = 41;
const T_SPECIFIER: u64 = 42;
const T_VARIABILITY: u64 = 44;
const T_VARIANT_SELECTION_MAP: u64 = 45;
const T_TIME_SAMPLES: u64 = 46;
const T_DOUBLE_VECTOR: u64 = 48;

// Spec types.
const SPEC_ATTRIBUTE: u32 = 1;
const SPEC_PRIM: u32 = 6;
const SPEC_PSEUDO_ROOT: u32 = 7;
const SPEC_RELATIONSHIP: u32 = 8;
const SPEC_VARIANT: u32 = 10;
const SPEC_VARIANT_SET: u32 = 11;

// List-op header bits (SdfListOp in a crate file).
const LIST_EXPLICIT: u8 = 1;
const LIST_HAS_EXPLICIT: u8 = 1 << 1;
const LIST_HAS_PREPENDED: u8 = 1 << 5;

const ARRAY_BIT: u64 = 1 << 63;
const INLINED_BIT: u64 = 1 << 62;
const COMPRESSED_BIT: u64 = 1 << 61;

fn rep_inline(ty: u64, payload: u64) -> u64 {
    (ty << 48) | INLINED_BIT | (payload & ((1 << 48) - 1))
}

fn rep_heap(ty: u64, offset: u64, array: bool) -> u64 {
    (ty << 48) | if array { ARRAY_BIT } else { 0 } | offset
}

/// A field value before it is written.
enum Val<'a> {
    Token(&'a str),
    String(&'a str),
    Double(f64),
    Bool(bool),
    Specifier,
    /// The `over` specifier (a prim spec that only adds opinions).
    Over,
    Uniform,
    TokenVector(Vec<String>),
    Tokens(Vec<&'a str>),
    Matrix([f64; 16]),
    Ints(Vec<i32>),
    Vec3fs(&'a [[f32; 3]]),
    /// Quaternions (x, y, z, w) stored as `quath` (half floats, imaginary part first).
    Quaths(&'a [[f32; 4]]),
    Vec2fs(&'a [[f32; 2]]),
    Floats(&'a [f32]),
    Float(f32),
    Vec2(&'a [f32; 2]),
    Vec3(&'a [f32; 3]),
    Vec4(&'a [f32; 4]),
    Asset(&'a str),
    /// An explicit list of paths (connections, relationship targets), as path indices.
    Paths(Vec<usize>),
    /// Tokens prepended to a list (`prepend apiSchemas = [...]`).
    PrependTokens(Vec<&'a str>),
    /// Strings prepended to a list (`prepend variantSets = [...]`).
    PrependStrings(Vec<&'a str>),
    /// A prim's variant selections: (variant set, variant).
    Selections(Vec<(&'a str, &'a str)>),
}

/// A path in the spec tree: its parent's index and its element (prim name or property name).
struct PathNode {
    parent: Option<usize>,
    name: String,
    property: bool,
    children: Vec<usize>,
}

struct Writer<W: Write + Seek> {
    out: W,
    pos: u64,
    tokens: Vec<String>,
    token_index: HashMap<String, u32>,
    strings: Vec<u32>,
    fields: Vec<(u32, u64)>,
    field_index: HashMap<(u32, u64), u32>,
    fieldsets: Vec<u32>,
    paths: Vec<PathNode>,
    /// (path index, fieldset index, spec type)
    specs: Vec<(u32, u32, u32)>,
    /// The path of the materials scope, when the stage has materials.
    scope: Option<usize>,
}

impl<W: Write + Seek> Writer<W> {
    fn bytes(&mut self, b: &[u8]) -> Result<()> {
        self.out.write_all(b)?;
        self.pos += b.len() as u64;
        Ok(())
    }

    fn u64(&mut self, v: u64) -> Result<()> {
        self.bytes(&v.to_le_bytes())
    }

    fn token(&mut self, s: &str) -> u32 {
        if let Some(&i) = self.token_index.get(s) {
            return i;
        }
        let i = self.tokens.len() as u32;
        self.tokens.push(s.to_owned());
        self.token_index.insert(s.to_owned(), i);
        i
    }

    fn field(&mut self, name: &str, value: Val) -> Result<u32> {
        let rep = self.value(value)?;
        let key = (self.token(name), rep);
        if let Some(&i) = self.field_index.get(&key) {
            return Ok(i);
        }
        let i = self.fields.len() as u32;
        self.fields.push(key);
        self.field_index.insert(key, i);
        Ok(i)
    }

    /// Write (or inline) a value and return its ValueRep.
    fn value(&mut self, v: Val) -> Result<u64> {
        Ok(match v {
            Val::Token(t) => rep_inline(T_TOKEN, self.token(t) as u64),
            Val::String(s) => rep_inline(T_STRING, self.string(s) as u64),
            Val::Bool(b) => rep_inline(T_BOOL, b as u64),
            Val::Specifier => rep_inline(T_SPECIFIER, 0), // def
            Val::Over => rep_inline(T_SPECIFIER, 1),
            Val::Uniform => rep_inline(T_VARIABILITY, 1),
            Val::Double(d) => {
                let at = self.pos;
                self.bytes(&d.to_le_bytes())?;
                rep_heap(T_DOUBLE, at, false)
            }
            // Same bytes, different types: child lists must be a TokenVector (usd-core
            // rejects a token array there), attribute values a token array.
            Val::TokenVector(names) => rep_heap(T_TOKEN_VECTOR, self.token_list(&names)?, false),
            Val::Tokens(names) => rep_heap(T_TOKEN, self.token_list(&names)?, true),
            Val::Matrix(m) => {
                let at = self.pos;
                for x in m {
                    self.bytes(&x.to_le_bytes())?;
                }
                rep_heap(T_MATRIX4D, at, false)
            }
            Val::Ints(v) => {
                let at = self.pos;
                self.u64(v.len() as u64)?;
                if v.len() >= MIN_COMPRESSED_ARRAY {
                    let encoded = encode_ints(&v);
                    self.lz4(&encoded)?;
                    rep_heap(T_INT, at, true) | COMPRESSED_BIT
                } else {
                    for x in v {
                        self.bytes(&x.to_le_bytes())?;
                    }
                    rep_heap(T_INT, at, true)
                }
            }
            Val::Vec3fs(v) => self.vec3f_array(v)?,
            Val::Quaths(v) => {
                let raw: Vec<u8> = (v.iter().flatten())
                    .flat_map(|&x| half::f16::from_f32(x).to_le_bytes())
                    .collect();
                self.array(T_QUATH, v.len(), &raw)?
            }
            Val::Vec2fs(v) => {
                let raw: Vec<u8> = v.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
                self.array(T_VEC2F, v.len(), &raw)?
            }
            Val::Floats(v) => {
                let raw: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
                self.array(T_FLOAT, v.len(), &raw)?
            }
            Val::Float(x) => rep_inline(T_FLOAT, x.to_bits() as u64),
            Val::Vec2(v) => self.floats_value(T_VEC2F, v)?,
            Val::Vec3(v) => self.floats_value(T_VEC3F, v)?,
            Val::Vec4(v) => self.floats_value(T_VEC4F, v)?,
            Val::Asset(a) => rep_inline(T_ASSET_PATH, self.token(a) as u64),
            Val::Paths(paths) => {
                let at = self.pos;
                self.bytes(&[LIST_EXPLICIT | LIST_HAS_EXPLICIT])?;
                self.u64(paths.len() as u64)?;
                for p in paths {
                    self.bytes(&(p as u32).to_le_bytes())?;
                }
                rep_heap(T_PATH_LIST_OP, at, false)
            }
            Val::PrependTokens(names) => {
                let idx: Vec<u32> = names.iter().map(|n| self.token(n)).collect();
                self.prepended(T_TOKEN_LIST_OP, &idx)?
            }
            Val::PrependStrings(items) => {
                let idx: Vec<u32> = items.iter().map(|s| self.string(s)).collect();
                self.prepended(T_STRING_LIST_OP, &idx)?
            }
            Val::Selections(pairs) => {
                let idx: Vec<[u32; 2]> = (pairs.iter())
                    .map(|(set, v)| [self.string(set), self.string(v)])
                    .collect();
                let at = self.pos;
                self.u64(idx.len() as u64)?;
                for i in idx.iter().flatten() {
                    self.bytes(&i.to_le_bytes())?;
                }
                rep_heap(T_VARIANT_SELECTION_MAP, at, false)
            }
        })
    }

    /// A list op of type `ty` holding only prepended items (token or string indices `idx`).
    fn prepended(&mut self, ty: u64, idx: &[u32]) -> Result<u64> {
        let at = self.pos;
        self.bytes(&[LIST_HAS_PREPENDED])?;
        self.u64(idx.len() as u64)?;
        for i in idx {
            self.bytes(&i.to_le_bytes())?;
        }
        Ok(rep_heap(ty, at, false))
    }

    /// The index of string `s` in the STRINGS section (added unless it is there).
    fn string(&mut self, s: &str) -> u32 {
        let t = self.token(s);
        match self.strings.iter().position(|&x| x == t) {
            Some(i) => i as u32,
            None => {
                self.strings.push(t);
                self.strings.len() as u32 - 1
            }
        }
    }

    /// A single vector value (not an array) of type `ty`, in the heap.
    fn floats_value(&mut self, ty: u64, v: &[f32]) -> Result<u64> {
        let at = self.pos;
        for x in v {
            self.bytes(&x.to_le_bytes())?;
        }
        Ok(rep_heap(ty, at, false))
    }

    /// Write a u64 count and the token indices of `names`; returns where they start.
    fn token_list<S: AsRef<str>>(&mut self, names: &[S]) -> Result<u64> {
        let at = self.pos;
        let idx: Vec<u32> = names.iter().map(|n| self.token(n.as_ref())).collect();
        self.u64(idx.len() as u64)?;
        for i in idx {
            self.bytes(&i.to_le_bytes())?;
        }
        Ok(at)
    }

    fn vec3f_array(&mut self, v: &[[f32; 3]]) -> Result<u64> {
        let raw: Vec<u8> = v.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
        self.array(T_VEC3F, v.len(), &raw)
    }

    /// An uncompressed array of `len` elements of type `ty` whose bytes are `raw`: its count,
    /// then the elements as they are.
    fn array(&mut self, ty: u64, len: usize, raw: &[u8]) -> Result<u64> {
        let at = self.pos;
        self.u64(len as u64)?;
        self.bytes(raw)?;
        Ok(rep_heap(ty, at, true))
    }

    /// A TimeSamples value over arrays already in the file (`reps[f]` at `times[f]`):
    /// `[i64 to times rep][times: u64 count + doubles][times rep][i64 to values][count][reps]`.
    /// The time samples of an animated prim's attribute, `reps` its samples' values (see
    /// [`Animation::ordered`]), in time order.
    fn sampled(&mut self, a: &Animation, reps: &[u64]) -> Result<u64> {
        let (times, reps): (Vec<f64>, Vec<u64>) = a.ordered(reps).into_iter().unzip();
        self.time_samples(&times, &reps)
    }

    fn time_samples(&mut self, times: &[f64], reps: &[u64]) -> Result<u64> {
        anyhow::ensure!(
            times.len() == reps.len(),
            "{} time samples for {} times",
            reps.len(),
            times.len()
        );
        let at = self.pos;
        let n = times.len() as u64;
        let times_size = 8 + 8 * n;
        self.bytes(&((8 + times_size) as i64).to_le_bytes())?;
        let times_at = self.pos;
        self.u64(n)?;
        for t in times {
            self.bytes(&t.to_le_bytes())?;
        }
        self.u64(rep_heap(T_DOUBLE_VECTOR, times_at, false))?;
        self.bytes(&8i64.to_le_bytes())?;
        self.u64(n)?;
        for &r in reps {
            self.u64(r)?;
        }
        Ok(rep_heap(T_TIME_SAMPLES, at, false))
    }

    /// LZ4 block in TfFastCompression framing: u64 compressed size, a 0 chunk-count byte, the block.
    fn lz4(&mut self, data: &[u8]) -> Result<()> {
        let block = lz4_flex::block::compress(data);
        self.u64(block.len() as u64 + 1)?;
        self.bytes(&[0])?;
        self.bytes(&block)
    }

    /// The path `name` under `parent` (a property or a prim), added unless it is there.
    fn path(&mut self, parent: Option<usize>, name: &str, property: bool) -> usize {
        if let Some(p) = parent {
            let found = self.paths[p]
                .children
                .iter()
                .copied()
                .find(|&c| self.paths[c].name == name && self.paths[c].property == property);
            if let Some(c) = found {
                return c;
            }
        }
        let i = self.paths.len();
        self.paths.push(PathNode {
            parent,
            name: name.to_owned(),
            property,
            children: Vec::new(),
        });
        if let Some(p) = parent {
            self.paths[p].children.push(i);
        }
        i
    }

    fn spec(&mut self, path: usize, fields: Vec<u32>, ty: u32) {
        let fs = self.fieldsets.len() as u32;
        self.fieldsets.extend(fields);
        self.fieldsets.push(u32::MAX);
        self.specs.push((path as u32, fs, ty));
    }

    /// An attribute spec under `prim` with the given fields.
    fn attribute(
        &mut self,
        prim: usize,
        name: &str,
        type_name: &str,
        extra: Vec<u32>,
    ) -> Result<()> {
        let p = self.path(Some(prim), name, true);
        let mut fields = vec![self.field("typeName", Val::Token(type_name))?];
        fields.extend(extra);
        self.spec(p, fields, SPEC_ATTRIBUTE);
        Ok(())
    }

    fn prim(&mut self, prim: &Prim, parent: usize, frames: &FrameReps) -> Result<()> {
        match prim {
            Prim::Xform {
                name,
                meta,
                matrix,
                motion,
                children,
            } => {
                let me = self.path(Some(parent), name, false);
                let props = self.transform(me, matrix, motion)?;
                for c in children {
                    self.prim(c, me, frames)?;
                }
                let kids = children.iter().map(prim_name).collect();
                let extra = self.meta(meta)?;
                self.prim_spec_with(me, "Xform", props, kids, extra)
            }
            Prim::Mesh(m) => self.mesh(m, parent, frames),
            Prim::Plain(p) => self.plain(p, parent),
            Prim::Instancer(i) => {
                let me = self.path(Some(parent), &i.name, false);
                let mut props = self.transform(me, &i.matrix, &i.motion)?;
                let v = self.field("default", Val::Vec3fs(&i.instances.positions))?;
                self.attribute(me, "positions", "point3f[]", vec![v])?;
                let v = self.field("default", Val::Quaths(&i.instances.orientations))?;
                self.attribute(me, "orientations", "quath[]", vec![v])?;
                let v = self.field("default", Val::Vec3fs(&i.instances.scales))?;
                self.attribute(me, "scales", "float3[]", vec![v])?;
                let zeros = vec![0; i.instances.positions.len()];
                let v = self.field("default", Val::Ints(zeros))?;
                self.attribute(me, "protoIndices", "int[]", vec![v])?;
                let protos = self.path(Some(me), PROTOTYPES, false);
                self.prim(&i.prototype, protos, frames)?;
                let target = self.path(Some(protos), &prim_name(&i.prototype), false);
                let rel = self.path(Some(me), "prototypes", true);
                let uniform = self.field("variability", Val::Uniform)?;
                let targets = self.field("targetPaths", Val::Paths(vec![target]))?;
                self.spec(rel, vec![uniform, targets], SPEC_RELATIONSHIP);
                props.extend(
                    [
                        "positions",
                        "orientations",
                        "scales",
                        "protoIndices",
                        "prototypes",
                    ]
                    .map(String::from),
                );
                self.prim_spec(protos, "Scope", vec![], vec![prim_name(&i.prototype)])?;
                for c in &i.children {
                    self.prim(c, me, frames)?;
                }
                let kids = std::iter::once(PROTOTYPES.to_string())
                    .chain(i.children.iter().map(prim_name))
                    .collect();
                let extra = self.meta(&i.meta)?;
                self.prim_spec_with(me, "PointInstancer", props, kids, extra)
            }
        }
    }

    /// An Xformable's `xformOp:transform` (time-sampled when it moves) and `xformOpOrder`;
    /// returns the property names written.
    fn transform(
        &mut self,
        me: usize,
        matrix: &Option<[f64; 16]>,
        motion: &[(f64, [f64; 16])],
    ) -> Result<Vec<String>> {
        let value = match (motion.is_empty(), matrix) {
            (false, _) => {
                let times: Vec<f64> = motion.iter().map(|(c, _)| *c).collect();
                let reps = (motion.iter())
                    .map(|(_, m)| self.value(Val::Matrix(*m)))
                    .collect::<Result<Vec<u64>>>()?;
                let rep = self.time_samples(&times, &reps)?;
                Some(self.raw_field("timeSamples", rep))
            }
            (true, Some(m)) => Some(self.field("default", Val::Matrix(*m))?),
            (true, None) => None,
        };
        let Some(v) = value else {
            return Ok(Vec::new());
        };
        self.attribute(me, "xformOp:transform", "matrix4d", vec![v])?;
        let u = self.field("variability", Val::Uniform)?;
        let v = self.field("default", Val::Tokens(vec!["xformOp:transform"]))?;
        self.attribute(me, "xformOpOrder", "token[]", vec![u, v])?;
        Ok(vec![
            "xformOp:transform".to_owned(),
            "xformOpOrder".to_owned(),
        ])
    }

    /// The metadata fields of a prim from its glTF object ([`Meta`]): `displayName` where it
    /// shows another name than its own, `customData` holding the object's extras.
    fn meta(&mut self, meta: &Meta) -> Result<Vec<u32>> {
        let mut out = Vec::new();
        if let Some(n) = &meta.display {
            out.push(self.field("displayName", Val::String(n))?);
        }
        if let Some(extras) = &meta.extras {
            let dict = Data::Dict(vec![("extras".to_owned(), extras.clone())]);
            let rep = self.data(&dict)?;
            out.push(self.raw_field("customData", rep));
        }
        Ok(out)
    }

    /// Write (or inline) a `customData` value and return its ValueRep. A dictionary is its
    /// entry count, then per entry the key's string index, a forward offset to the value's
    /// rep (8: right after it; the values are written before the dictionary) and the rep.
    fn data(&mut self, d: &Data) -> Result<u64> {
        Ok(match d {
            Data::Bool(b) => self.value(Val::Bool(*b))?,
            Data::Int(i) => rep_inline(T_INT, *i as u32 as u64),
            Data::Int64(i) => {
                let at = self.pos;
                self.bytes(&i.to_le_bytes())?;
                rep_heap(T_INT64, at, false)
            }
            Data::Double(x) => self.value(Val::Double(*x))?,
            Data::String(s) => self.value(Val::String(s))?,
            Data::Bools(v) => {
                let raw: Vec<u8> = v.iter().map(|&b| b as u8).collect();
                self.array(T_BOOL, v.len(), &raw)?
            }
            Data::Ints(v) => self.value(Val::Ints(v.clone()))?,
            Data::Doubles(v) => {
                let raw: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
                self.array(T_DOUBLE, v.len(), &raw)?
            }
            Data::Strings(v) => {
                let raw: Vec<u8> = (v.iter())
                    .flat_map(|s| self.string(s).to_le_bytes())
                    .collect();
                self.array(T_STRING, v.len(), &raw)?
            }
            Data::Dict(entries) => {
                let mut body = Vec::with_capacity(entries.len());
                for (k, v) in entries {
                    body.push((self.string(k), self.data(v)?));
                }
                let at = self.pos;
                self.u64(body.len() as u64)?;
                for (key, rep) in body {
                    self.bytes(&key.to_le_bytes())?;
                    self.bytes(&8i64.to_le_bytes())?;
                    self.u64(rep)?;
                }
                rep_heap(T_DICTIONARY, at, false)
            }
        })
    }

    fn prim_spec(
        &mut self,
        path: usize,
        type_name: &str,
        props: Vec<String>,
        children: Vec<String>,
    ) -> Result<()> {
        self.prim_spec_with(path, type_name, props, children, Vec::new())
    }

    /// A prim spec with fields `extra` besides its type, properties and children.
    fn prim_spec_with(
        &mut self,
        path: usize,
        type_name: &str,
        props: Vec<String>,
        children: Vec<String>,
        extra: Vec<u32>,
    ) -> Result<()> {
        let mut fields = vec![
            self.field("specifier", Val::Specifier)?,
            self.field("typeName", Val::Token(type_name))?,
        ];
        fields.extend(extra);
        if !props.is_empty() {
            fields.push(self.field("properties", Val::TokenVector(props))?);
        }
        if !children.is_empty() {
            fields.push(self.field("primChildren", Val::TokenVector(children))?);
        }
        self.spec(path, fields, SPEC_PRIM);
        Ok(())
    }

    fn mesh(&mut self, m: &MeshPrim, parent: usize, frames: &FrameReps) -> Result<()> {
        let reps = m.animation.as_ref().and_then(|a| frames.get(&a.key()));
        let me = self.path(Some(parent), &m.name, false);
        let mut props: Vec<String> = Vec::new();
        let uniform = self.field("variability", Val::Uniform)?;
        let vertex = self.field("interpolation", Val::Token("vertex"))?;
        if m.double_sided {
            let v = self.field("default", Val::Bool(true))?;
            self.attribute(me, "doubleSided", "bool", vec![uniform, v])?;
            props.push("doubleSided".into());
        }
        match (&m.animation, reps) {
            (Some(a), Some(r)) => {
                let rep = self.sampled(a, &r.extent)?;
                let v = self.raw_field("timeSamples", rep);
                self.attribute(me, "extent", "float3[]", vec![v])?;
            }
            _ => {
                let e = extent(&m.points);
                let v = self.field("default", Val::Vec3fs(&e))?;
                self.attribute(me, "extent", "float3[]", vec![v])?;
            }
        }
        props.push("extent".into());
        let counts = self.field("default", Val::Ints(vec![3; m.indices.len() / 3]))?;
        self.attribute(me, "faceVertexCounts", "int[]", vec![counts])?;
        let indices = self.field(
            "default",
            Val::Ints(m.indices.iter().map(|&i| i as i32).collect()),
        )?;
        self.attribute(me, "faceVertexIndices", "int[]", vec![indices])?;
        props.extend(["faceVertexCounts".into(), "faceVertexIndices".into()]);
        if let Some(normals) = &m.normals {
            let v = match (&m.animation, reps) {
                (Some(a), Some(r)) if a.normals => {
                    let rep = self.sampled(a, &r.normals)?;
                    self.raw_field("timeSamples", rep)
                }
                _ => self.field("default", Val::Vec3fs(normals))?,
            };
            self.attribute(me, "normals", "normal3f[]", vec![vertex, v])?;
            props.push("normals".into());
        }
        let v = match (&m.animation, reps) {
            (Some(a), Some(r)) => {
                let rep = self.sampled(a, &r.points)?;
                self.raw_field("timeSamples", rep)
            }
            _ => self.field("default", Val::Vec3fs(&m.points))?,
        };
        self.attribute(me, "points", "point3f[]", vec![v])?;
        props.push("points".into());
        if let Some(color) = &m.color {
            let (interpolation, v) = match color {
                DisplayColor::Constant(c) => {
                    ("constant", self.field("default", Val::Vec3fs(&[*c]))?)
                }
                DisplayColor::Vertex(c) => ("vertex", self.field("default", Val::Vec3fs(c))?),
                DisplayColor::Face(c) => ("uniform", self.field("default", Val::Vec3fs(c))?),
            };
            let interpolation = self.field("interpolation", Val::Token(interpolation))?;
            self.attribute(
                me,
                "primvars:displayColor",
                "color3f[]",
                vec![interpolation, v],
            )?;
            props.push("primvars:displayColor".into());
        }
        if let Some(alpha) = &m.opacity {
            let v = self.field("default", Val::Floats(alpha))?;
            self.attribute(me, "primvars:displayOpacity", "float[]", vec![vertex, v])?;
            props.push("primvars:displayOpacity".into());
        }
        for (name, st) in &m.st {
            let v = self.field("default", Val::Vec2fs(st))?;
            let name = format!("primvars:{name}");
            self.attribute(me, &name, "texCoord2f[]", vec![vertex, v])?;
            props.push(name);
        }
        if !m.subsets.is_empty() {
            let v = self.field("default", Val::Token("partition"))?;
            let family = "subsetFamily:materialBind:familyType";
            self.attribute(me, family, "token", vec![uniform, v])?;
            props.push(family.into());
        }
        let v = self.field("default", Val::Token("none"))?;
        self.attribute(me, "subdivisionScheme", "token", vec![uniform, v])?;
        props.push("subdivisionScheme".into());
        let mut extra = self.meta(&m.meta)?;
        extra.extend(self.bind(me, &m.material, &mut props)?);
        for sub in &m.subsets {
            let at = self.path(Some(me), &sub.name, false);
            let mut props = Vec::new();
            for (name, value) in [("elementType", "face"), ("familyName", "materialBind")] {
                let v = self.field("default", Val::Token(value))?;
                self.attribute(at, name, "token", vec![uniform, v])?;
                props.push(name.to_string());
            }
            let v = self.field("default", Val::Ints(sub.faces.clone()))?;
            self.attribute(at, "indices", "int[]", vec![v])?;
            props.push("indices".into());
            let extra = self.bind(at, &sub.material, &mut props)?;
            self.prim_spec_with(at, "GeomSubset", props, vec![], extra)?;
        }
        let subsets = m.subsets.iter().map(|s| s.name.clone()).collect();
        self.prim_spec_with(me, "Mesh", props, subsets, extra)
    }

    /// Bind prim `at` to `material` (in the materials scope), when it has one: the
    /// relationship (its name pushed to `props`), and the prim's `apiSchemas` field returned.
    fn bind(
        &mut self,
        at: usize,
        material: &Option<String>,
        props: &mut Vec<String>,
    ) -> Result<Vec<u32>> {
        let (Some(material), Some(scope)) = (material, self.scope) else {
            return Ok(Vec::new());
        };
        let uniform = self.field("variability", Val::Uniform)?;
        let target = self.path(Some(scope), material, false);
        let rel = self.path(Some(at), "material:binding", true);
        let targets = self.field("targetPaths", Val::Paths(vec![target]))?;
        self.spec(rel, vec![uniform, targets], SPEC_RELATIONSHIP);
        props.push("material:binding".into());
        Ok(vec![self.field(
            "apiSchemas",
            Val::PrependTokens(vec!["MaterialBindingAPI"]),
        )?])
    }

    /// The materials scope (at path `scope`) with its materials and their shaders.
    fn look(&mut self, look: &Look, scope: usize) -> Result<()> {
        for m in &look.materials {
            let mp = self.path(Some(scope), &m.name, false);
            let surface = self.path(Some(mp), SURFACE, false);
            let out = self.path(Some(surface), "outputs:surface", true);
            let c = self.field("connectionPaths", Val::Paths(vec![out]))?;
            self.attribute(mp, "outputs:surface", "token", vec![c])?;
            for s in &m.shaders {
                self.shader(s, mp)?;
            }
            let children = m.shaders.iter().map(|s| s.name.clone()).collect();
            let props = vec!["outputs:surface".into()];
            let extra = self.meta(&m.meta)?;
            self.prim_spec_with(mp, "Material", props, children, extra)?;
        }
        let names = look.materials.iter().map(|m| m.name.clone()).collect();
        self.prim_spec(scope, "Scope", vec![], names)
    }

    /// The `default` field of an attribute holding `v` (not a connection).
    fn default_field(&mut self, v: &Value) -> Result<u32> {
        let v = match v {
            Value::Bool(b) => Val::Bool(*b),
            Value::Float(x) => Val::Float(*x),
            Value::Vec2(x) => Val::Vec2(x),
            Value::Vec3(x) => Val::Vec3(x),
            Value::Vec4(x) => Val::Vec4(x),
            Value::Token(t) => Val::Token(t),
            Value::Text(t) => Val::String(t),
            Value::Asset(a) => Val::Asset(a),
            Value::Connect { .. } => unreachable!("connections are written as connectionPaths"),
        };
        self.field("default", v)
    }

    /// A camera or light: its type, API schemas and attributes.
    fn plain(&mut self, p: &Plain, parent: usize) -> Result<()> {
        let me = self.path(Some(parent), &p.name, false);
        let mut props = Vec::new();
        for (name, ty, v) in &p.attrs {
            let f = self.default_field(v)?;
            self.attribute(me, name, ty, vec![f])?;
            props.push(name.to_string());
        }
        let mut extra = self.meta(&p.meta)?;
        if !p.api_schemas.is_empty() {
            let schemas = Val::PrependTokens(p.api_schemas.clone());
            extra.push(self.field("apiSchemas", schemas)?);
        }
        self.prim_spec_with(me, p.type_name, props, vec![], extra)
    }

    /// One shader of the material at path `material`.
    fn shader(&mut self, s: &Shader, material: usize) -> Result<()> {
        let me = self.path(Some(material), &s.name, false);
        let uniform = self.field("variability", Val::Uniform)?;
        let id = self.field("default", Val::Token(s.id))?;
        self.attribute(me, "info:id", "token", vec![uniform, id])?;
        let mut props = vec!["info:id".to_owned()];
        for i in &s.inputs {
            let name = format!("inputs:{}", i.name);
            let v = match &i.value {
                Value::Connect { shader, output } => {
                    let from = self.path(Some(material), shader, false);
                    let out = self.path(Some(from), &format!("outputs:{output}"), true);
                    self.field("connectionPaths", Val::Paths(vec![out]))?
                }
                v => self.default_field(v)?,
            };
            self.attribute(me, &name, i.type_name, vec![v])?;
            props.push(name);
        }
        for (name, ty) in &s.outputs {
            let name = format!("outputs:{name}");
            self.attribute(me, &name, ty, vec![])?;
            props.push(name);
        }
        self.prim_spec(me, "Shader", props, vec![])
    }

    /// The root prim's variant set of material variants (see [`variant_overs`]), with the
    /// over prims each variant holds; returns the root prim's fields that name and select it
    /// (none where the stage has no variants).
    fn variant_set(&mut self, stage: &Stage, top: usize) -> Result<Vec<u32>> {
        let variants = variant_overs(stage);
        if variants.is_empty() {
            return Ok(Vec::new());
        }
        let set = self.path(Some(top), &format!("{{{VARIANT_SET}=}}"), false);
        let names = variants.iter().map(|(n, _)| n.clone()).collect();
        let children = self.field("variantChildren", Val::TokenVector(names))?;
        self.spec(set, vec![children], SPEC_VARIANT_SET);
        for (name, overs) in &variants {
            let v = self.path(Some(top), &format!("{{{VARIANT_SET}={name}}}"), false);
            let mut fields = Vec::new();
            if !overs.children.is_empty() {
                let kids = overs.children.iter().map(|(n, _)| n.clone()).collect();
                fields.push(self.field("primChildren", Val::TokenVector(kids))?);
            }
            self.spec(v, fields, SPEC_VARIANT);
            for (child, o) in &overs.children {
                self.over(v, child, o)?;
            }
        }
        let default = stage.look.default_variant.as_str();
        Ok(vec![
            self.field("variantSetNames", Val::PrependStrings(vec![VARIANT_SET]))?,
            self.field(
                "variantSelection",
                Val::Selections(vec![(VARIANT_SET, default)]),
            )?,
            self.field(
                "variantSetChildren",
                Val::TokenVector(vec![VARIANT_SET.into()]),
            )?,
        ])
    }

    /// An over prim `name` under `parent` in a variant (see [`Overs`]): the binding it gives
    /// and the over prims below it.
    fn over(&mut self, parent: usize, name: &str, o: &Overs) -> Result<()> {
        let me = self.path(Some(parent), name, false);
        let mut props = Vec::new();
        let mut fields = vec![self.field("specifier", Val::Over)?];
        fields.extend(self.bind(me, &o.material, &mut props)?);
        for (child, c) in &o.children {
            self.over(me, child, c)?;
        }
        if !props.is_empty() {
            fields.push(self.field("properties", Val::TokenVector(props))?);
        }
        if !o.children.is_empty() {
            let kids = o.children.iter().map(|(n, _)| n.clone()).collect();
            fields.push(self.field("primChildren", Val::TokenVector(kids))?);
        }
        self.spec(me, fields, SPEC_PRIM);
        Ok(())
    }

    fn raw_field(&mut self, name: &str, rep: u64) -> u32 {
        let key = (self.token(name), rep);
        let i = self.fields.len() as u32;
        self.fields.push(key);
        self.field_index.insert(key, i);
        i
    }

    /// Depth-first path table: (path index, element token, jump) per node.
    fn path_table(&mut self) -> (Vec<u32>, Vec<i32>, Vec<i32>) {
        let mut order = Vec::with_capacity(self.paths.len());
        let mut stack = vec![0usize];
        while let Some(p) = stack.pop() {
            order.push(p);
            stack.extend(self.paths[p].children.iter().rev());
        }
        // Position of each node in the depth-first order.
        let mut at = vec![0usize; self.paths.len()];
        for (i, &p) in order.iter().enumerate() {
            at[p] = i;
        }
        let mut tokens = Vec::with_capacity(order.len());
        let mut jumps = Vec::with_capacity(order.len());
        for &p in &order {
            let node = &self.paths[p];
            let name = node.name.clone();
            let property = node.property;
            let has_child = !node.children.is_empty();
            let next_sibling = node.parent.and_then(|q| {
                let sibs = &self.paths[q].children;
                let k = sibs.iter().position(|&s| s == p).unwrap();
                sibs.get(k + 1).copied()
            });
            let t = if p == 0 { 0 } else { self.token(&name) as i32 };
            tokens.push(if property { -t } else { t });
            jumps.push(match (has_child, next_sibling) {
                (true, Some(s)) => (at[s] - at[p]) as i32,
                (true, None) => -1,
                (false, Some(_)) => 0,
                (false, None) => -2,
            });
        }
        (order.iter().map(|&p| p as u32).collect(), tokens, jumps)
    }

    fn finish(mut self) -> Result<W> {
        let (path_ids, element_tokens, jumps) = self.path_table();
        let mut sections: Vec<(&str, u64, u64)> = Vec::new();
        // TOKENS
        let start = self.pos;
        let mut buf = Vec::new();
        for t in &self.tokens {
            buf.extend_from_slice(t.as_bytes());
            buf.push(0);
        }
        self.u64(self.tokens.len() as u64)?;
        self.u64(buf.len() as u64)?;
        self.lz4(&buf)?;
        sections.push(("TOKENS", start, self.pos - start));
        // STRINGS
        let start = self.pos;
        self.u64(self.strings.len() as u64)?;
        for s in self.strings.clone() {
            self.bytes(&s.to_le_bytes())?;
        }
        sections.push(("STRINGS", start, self.pos - start));
        // FIELDS
        let start = self.pos;
        self.u64(self.fields.len() as u64)?;
        let names: Vec<u32> = self.fields.iter().map(|f| f.0).collect();
        self.lz4(&encode_ints(&names))?;
        let reps: Vec<u8> = self.fields.iter().flat_map(|f| f.1.to_le_bytes()).collect();
        self.lz4(&reps)?;
        sections.push(("FIELDS", start, self.pos - start));
        // FIELDSETS
        let start = self.pos;
        self.u64(self.fieldsets.len() as u64)?;
        let sets = encode_ints(&self.fieldsets);
        self.lz4(&sets)?;
        sections.push(("FIELDSETS", start, self.pos - start));
        // PATHS
        let start = self.pos;
        self.u64(self.paths.len() as u64)?;
        self.u64(path_ids.len() as u64)?;
        self.lz4(&encode_ints(&path_ids))?;
        self.lz4(&encode_ints(&element_tokens))?;
        self.lz4(&encode_ints(&jumps))?;
        sections.push(("PATHS", start, self.pos - start));
        // SPECS
        let start = self.pos;
        self.u64(self.specs.len() as u64)?;
        let (a, b, c): (Vec<u32>, Vec<u32>, Vec<u32>) = (
            self.specs.iter().map(|s| s.0).collect(),
            self.specs.iter().map(|s| s.1).collect(),
            self.specs.iter().map(|s| s.2).collect(),
        );
        self.lz4(&encode_ints(&a))?;
        self.lz4(&encode_ints(&b))?;
        self.lz4(&encode_ints(&c))?;
        sections.push(("SPECS", start, self.pos - start));
        // Table of contents.
        let toc = self.pos;
        self.u64(sections.len() as u64)?;
        for (name, start, size) in sections {
            let mut n = [0u8; 16];
            n[..name.len()].copy_from_slice(name.as_bytes());
            self.bytes(&n)?;
            self.u64(start)?;
            self.u64(size)?;
        }
        // Bootstrap.
        self.out.seek(SeekFrom::Start(0))?;
        let mut boot = [0u8; BOOTSTRAP_SIZE as usize];
        boot[..8].copy_from_slice(b"PXR-USDC");
        boot[8..11].copy_from_slice(&VERSION);
        boot[16..24].copy_from_slice(&toc.to_le_bytes());
        self.out.write_all(&boot)?;
        self.out.flush()?;
        Ok(self.out)
    }
}

fn prim_name(p: &Prim) -> String {
    match p {
        Prim::Xform { name, .. } => name.clone(),
        Prim::Instancer(i) => i.name.clone(),
        Prim::Mesh(m) => m.name.clone(),
        Prim::Plain(p) => p.name.clone(),
    }
}

/// Offsets (ValueReps) of each animated primitive's per-frame arrays.
#[derive(Default)]
struct SampleReps {
    extent: Vec<u64>,
    normals: Vec<u64>,
    points: Vec<u64>,
}

type FrameReps = HashMap<SampleKey, SampleReps>;

/// Write `stage` as a crate file to `out` (which must start empty, at position 0), taking the
/// animated primitives' frames from `source`: each frame's arrays go to the file as it arrives.
pub fn write_usdc<W: Write + Seek>(stage: &Stage, out: W, source: &mut FrameSource) -> Result<W> {
    let mut w = Writer {
        out,
        pos: 0,
        tokens: Vec::new(),
        token_index: HashMap::new(),
        strings: Vec::new(),
        fields: Vec::new(),
        field_index: HashMap::new(),
        fieldsets: Vec::new(),
        paths: Vec::new(),
        specs: Vec::new(),
        scope: None,
    };
    w.bytes(&[0u8; BOOTSTRAP_SIZE as usize])?;
    let prims = animated(stage);
    let mut frames: FrameReps = HashMap::new();
    let mut put = |a: &Animation, _code: f64, sample: Sample| -> Result<()> {
        let e = w.vec3f_array(&sample.extent)?;
        let p = w.vec3f_array(&sample.points)?;
        let n = sample
            .normals
            .as_ref()
            .map(|n| w.vec3f_array(n))
            .transpose()?;
        let r = frames.entry(a.key()).or_default();
        r.extent.push(e);
        r.points.push(p);
        r.normals.extend(n);
        Ok(())
    };
    source(&mut |k, f, deltas| {
        for_each_sample(&prims, k, f, deltas, &mut |a, s| put(a, a.times[f], s))
    })?;
    for_each_skin_sample(stage, &mut put)?;
    // Token 0 is a prim name, so no property path ever needs the (unnegatable) index 0.
    w.token(&stage.root);
    let root = w.path(None, "", false);
    let top = w.path(Some(root), &stage.root, false);
    let mut children: Vec<String> = stage.children.iter().map(prim_name).collect();
    if !stage.look.materials.is_empty() {
        w.scope = Some(w.path(Some(top), &stage.look.scope, false));
        children.push(stage.look.scope.clone());
    }
    for c in &stage.children {
        w.prim(c, top, &frames)?;
    }
    if let Some(scope) = w.scope {
        w.look(&stage.look, scope)?;
    }
    let mut extra = w.meta(&stage.root_meta)?;
    extra.extend(w.variant_set(stage, top)?);
    w.prim_spec_with(top, "Xform", vec![], children, extra)?;
    let doc = format!("Written by inbetween {}", env!("CARGO_PKG_VERSION"));
    let layer_data = match &stage.layer_data {
        Some(d) => {
            let rep = w.data(d)?;
            Some(w.raw_field("customLayerData", rep))
        }
        None => None,
    };
    let mut fields = vec![
        w.field("defaultPrim", Val::Token(&stage.root))?,
        w.field("documentation", Val::String(&doc))?,
        w.field("endTimeCode", Val::Double(stage.end))?,
        w.field("framesPerSecond", Val::Double(stage.rate))?,
        w.field("metersPerUnit", Val::Double(1.0))?,
        w.field("startTimeCode", Val::Double(stage.start))?,
        w.field("timeCodesPerSecond", Val::Double(stage.rate))?,
        w.field("upAxis", Val::Token("Y"))?,
        w.field("primChildren", Val::TokenVector(vec![stage.root.clone()]))?,
    ];
    fields.extend(layer_data);
    w.spec(root, fields, SPEC_PSEUDO_ROOT);
    w.finish()
}

/// USD integer coding: deltas from the previous value, the most common delta stored once,
/// 2-bit codes per value (common / 8 / 16 / 32 bits for 32-bit integers), then the
/// non-common deltas.
pub fn encode_ints<T: Copy + Into<i64>>(values: &[T]) -> Vec<u8> {
    if values.is_empty() {
        return Vec::new();
    }
    let mut prev = 0i64;
    let deltas: Vec<i64> = values
        .iter()
        .map(|v| {
            let v: i64 = (*v).into();
            // Values are 32-bit: deltas wrap like the reader's 32-bit sums.
            let d = (v as i32).wrapping_sub(prev as i32) as i64;
            prev = v;
            d
        })
        .collect();
    let mut counts: HashMap<i64, usize> = HashMap::new();
    for &d in &deltas {
        *counts.entry(d).or_default() += 1;
    }
    let common = counts
        .iter()
        .max_by(|a, b| a.1.cmp(b.1).then(b.0.cmp(a.0)))
        .map(|(v, _)| *v)
        .unwrap_or(0);
    let mut out = Vec::new();
    out.extend_from_slice(&(common as i32).to_le_bytes());
    let mut codes = vec![0u8; (deltas.len() * 2).div_ceil(8)];
    let mut tail = Vec::new();
    for (i, &d) in deltas.iter().enumerate() {
        let code = if d == common {
            0
        } else if i8::try_from(d).is_ok() {
            tail.push(d as i8 as u8);
            1
        } else if i16::try_from(d).is_ok() {
            tail.extend_from_slice(&(d as i16).to_le_bytes());
            2
        } else {
            tail.extend_from_slice(&(d as i32).to_le_bytes());
            3
        };
        codes[i / 4] |= code << (2 * (i % 4));
    }
    out.extend_from_slice(&codes);
    out.extend_from_slice(&tail);
    out
}
