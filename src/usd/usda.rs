//! `.usda` writer: the stage as USD text. Every animated attribute's samples are spooled to
//! scratch files beside the output as frames arrive, then copied into the layer, so no frame
//! is held in memory.

use super::camera_light::Plain;
use super::material::{Material, Value, SURFACE};
use super::stage::{
    animated, extent, for_each_sample, for_each_skin_sample, variant_overs, Animation, Data,
    DisplayColor, FrameSource, MeshPrim, Meta, Overs, Prim, Sample, SampleKey, Stage, PROTOTYPES,
    VARIANT_SET,
};
use crate::output::{naming, Outputs};
use anyhow::Result;
use rayon::prelude::*;
use std::collections::HashMap;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Write the stage as USDA text.
fn write_usda(stage: &Stage, out: &mut dyn Write, spool: &Spool) -> Result<()> {
    writeln!(out, "#usda 1.0")?;
    writeln!(out, "(")?;
    writeln!(out, "    defaultPrim = \"{}\"", stage.root)?;
    writeln!(
        out,
        "    doc = \"Written by inbetween {}\"",
        env!("CARGO_PKG_VERSION")
    )?;
    if let Some(Data::Dict(entries)) = &stage.layer_data {
        let text = dict_text(entries).replace('\n', "\n    ");
        writeln!(out, "    customLayerData = {text}")?;
    }
    writeln!(out, "    endTimeCode = {}", stage.end)?;
    writeln!(out, "    framesPerSecond = {}", stage.rate)?;
    writeln!(out, "    metersPerUnit = 1")?;
    writeln!(out, "    startTimeCode = {}", stage.start)?;
    writeln!(out, "    timeCodesPerSecond = {}", stage.rate)?;
    writeln!(out, "    upAxis = \"Y\"")?;
    writeln!(out, ")")?;
    writeln!(out)?;
    let variants = variant_overs(stage);
    let mut meta = meta_lines(&stage.root_meta);
    if !variants.is_empty() {
        let default = &stage.look.default_variant;
        meta.push(format!("prepend variantSets = \"{VARIANT_SET}\""));
        meta.push(format!(
            "variants = {{\n    string {VARIANT_SET} = \"{default}\"\n}}"
        ));
    }
    open_prim(out, "", "def Xform", &stage.root, &meta)?;
    let look = &stage.look;
    let scope = format!("/{}/{}", stage.root, look.scope);
    for c in &stage.children {
        write_prim(c, out, 1, &format!("/{}", stage.root), &scope, spool)?;
    }
    if !look.materials.is_empty() {
        writeln!(out, "    def Scope \"{}\"", look.scope)?;
        writeln!(out, "    {{")?;
        for m in &look.materials {
            write_material(m, out, &format!("{scope}/{}", m.name))?;
        }
        writeln!(out, "    }}")?;
    }
    if !variants.is_empty() {
        writeln!(out, "    variantSet \"{VARIANT_SET}\" = {{")?;
        for (name, overs) in &variants {
            writeln!(out, "        \"{name}\" {{")?;
            for (child, o) in &overs.children {
                write_over(child, o, out, "            ", &scope)?;
            }
            writeln!(out, "        }}")?;
        }
        writeln!(out, "    }}")?;
    }
    writeln!(out, "}}")?;
    Ok(())
}

/// The metadata line of a prim bound to a material.
const BINDING_API: &str = "prepend apiSchemas = [\"MaterialBindingAPI\"]";

/// The metadata of a prim from its glTF object ([`Meta`]): `displayName` where it shows
/// another name than its own, `customData` holding the object's extras.
fn meta_lines(meta: &Meta) -> Vec<String> {
    let mut out = Vec::new();
    if let Some(n) = &meta.display {
        out.push(format!("displayName = {}", string_text(n)));
    }
    if let Some(extras) = &meta.extras {
        let entries = [("extras".to_owned(), extras.clone())];
        out.push(format!("customData = {}", dict_text(&entries)));
    }
    out
}

/// A double as the text format reads it back exactly and without a word: the shortest
/// decimal, or in exponent form where that would be long or read as an integer out of range
/// (1e300, 5e-324, 2^64).
fn double_text(x: f64) -> String {
    let plain = x.to_string();
    if plain.len() > 20 || (!plain.contains('.') && x.abs() >= 1e15) {
        format!("{x:e}")
    } else {
        plain
    }
}

/// A dictionary's entries as text, in braces, one a line, indented by four spaces.
fn dict_text(entries: &[(String, Data)]) -> String {
    let mut text = String::from("{");
    for (k, v) in entries {
        text += &format!("\n    {}", data_text(k, v).replace('\n', "\n    "));
    }
    text + "\n}"
}

/// Entry `key` of a dictionary holding `d`, as text: `int lod = 2`, `dictionary x = {...}`
/// (its own lines indented by four spaces under the first).
fn data_text(key: &str, d: &Data) -> String {
    let list = |items: Vec<String>| format!("[{}]", items.join(", "));
    let (ty, value) = match d {
        Data::Bool(b) => ("bool", (*b as u8).to_string()),
        Data::Int(i) => ("int", i.to_string()),
        Data::Int64(i) => ("int64", i.to_string()),
        Data::Double(x) => ("double", double_text(*x)),
        Data::String(s) => ("string", string_text(s)),
        Data::Bools(v) => (
            "bool[]",
            list(v.iter().map(|b| (*b as u8).to_string()).collect()),
        ),
        Data::Ints(v) => ("int[]", list(v.iter().map(i32::to_string).collect())),
        Data::Doubles(v) => (
            "double[]",
            list(v.iter().map(|x| double_text(*x)).collect()),
        ),
        Data::Strings(v) => ("string[]", list(v.iter().map(|s| string_text(s)).collect())),
        Data::Dict(entries) => ("dictionary", dict_text(entries)),
    };
    format!("{ty} {} = {value}", string_text(key))
}

/// A string in the text format: in double quotes, a quote, backslash or control character
/// escaped (`\"`, `\\`, `\n`, `\xHH`); any other character as it is (the file is UTF-8).
fn string_text(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if (c as u32) < 0x20 || c == '\u{7f}' => {
                out.push_str(&format!("\\x{:02x}", c as u32))
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// The opening of a prim, indented by `pad`: `def Mesh "name"` (`head` the specifier and
/// type), its metadata `meta` in parentheses when it has any (each entry's lines indented
/// under the prim), and the brace.
fn open_prim(
    out: &mut dyn Write,
    pad: &str,
    head: &str,
    name: &str,
    meta: &[String],
) -> Result<()> {
    if meta.is_empty() {
        writeln!(out, "{pad}{head} \"{name}\"")?;
    } else {
        writeln!(out, "{pad}{head} \"{name}\" (")?;
        for line in meta.iter().flat_map(|m| m.lines()) {
            writeln!(out, "{pad}    {line}")?;
        }
        writeln!(out, "{pad})")?;
    }
    writeln!(out, "{pad}{{")?;
    Ok(())
}

/// An over prim of a material variant (see [`Overs`]), indented by `pad`: the binding it
/// gives, then the over prims below it.
fn write_over(name: &str, o: &Overs, out: &mut dyn Write, pad: &str, scope: &str) -> Result<()> {
    let meta: Vec<String> = o.material.iter().map(|_| BINDING_API.to_owned()).collect();
    open_prim(out, pad, "over", name, &meta)?;
    if let Some(material) = &o.material {
        writeln!(out, "{pad}    rel material:binding = <{scope}/{material}>")?;
    }
    for (child, o) in &o.children {
        write_over(child, o, out, &format!("{pad}    "), scope)?;
    }
    writeln!(out, "{pad}}}")?;
    Ok(())
}

/// A Material prim (in the materials scope) and its shaders; `path` is its own path.
fn write_material(m: &Material, out: &mut dyn Write, path: &str) -> Result<()> {
    open_prim(
        out,
        "        ",
        "def Material",
        &m.name,
        &meta_lines(&m.meta),
    )?;
    writeln!(
        out,
        "            token outputs:surface.connect = <{path}/{SURFACE}.outputs:surface>"
    )?;
    for s in &m.shaders {
        writeln!(out, "            def Shader \"{}\"", s.name)?;
        writeln!(out, "            {{")?;
        let p = "                ";
        writeln!(out, "{p}uniform token info:id = \"{}\"", s.id)?;
        for i in &s.inputs {
            let (ty, name) = (i.type_name, i.name);
            match &i.value {
                Value::Connect { shader, output } => writeln!(
                    out,
                    "{p}{ty} inputs:{name}.connect = <{path}/{shader}.outputs:{output}>"
                )?,
                v => writeln!(out, "{p}{ty} inputs:{name} = {}", value_text(v))?,
            }
        }
        for (name, ty) in &s.outputs {
            writeln!(out, "{p}{ty} outputs:{name}")?;
        }
        writeln!(out, "            }}")?;
    }
    writeln!(out, "        }}")?;
    Ok(())
}

/// A shader input's value as USD text.
fn value_text(v: &Value) -> String {
    let list = |v: &[f32]| {
        let items: Vec<String> = v.iter().map(|x| F(*x).to_string()).collect();
        format!("({})", items.join(", "))
    };
    match v {
        Value::Bool(b) => u8::from(*b).to_string(),
        Value::Float(x) => F(*x).to_string(),
        Value::Vec2(x) => list(x),
        Value::Vec3(x) => list(x),
        Value::Vec4(x) => list(x),
        Value::Token(t) => string_text(t),
        Value::Text(t) => string_text(t),
        // A path with an @ in it (an output named "shot@v2") is delimited by @@@, as USD's
        // text format asks; an @@@ in it escaped.
        Value::Asset(a) if a.contains('@') => format!("@@@{}@@@", a.replace("@@@", "\\@@@")),
        Value::Asset(a) => format!("@{a}@"),
        Value::Connect { .. } => unreachable!("connections are written as .connect"),
    }
}

fn write_prim(
    prim: &Prim,
    out: &mut dyn Write,
    depth: usize,
    path: &str,
    scope: &str,
    spool: &Spool,
) -> Result<()> {
    let pad = "    ".repeat(depth);
    match prim {
        Prim::Xform {
            name,
            meta,
            matrix,
            motion,
            children,
        } => {
            open_prim(out, &pad, "def Xform", name, &meta_lines(meta))?;
            write_transform(out, &pad, matrix, motion)?;
            let path = format!("{path}/{name}");
            for c in children {
                write_prim(c, out, depth + 1, &path, scope, spool)?;
            }
            writeln!(out, "{pad}}}")?;
        }
        Prim::Mesh(m) => write_mesh(m, out, &pad, scope, spool)?,
        Prim::Plain(p) => write_plain(p, out, &pad)?,
        Prim::Instancer(i) => {
            open_prim(
                out,
                &pad,
                "def PointInstancer",
                &i.name,
                &meta_lines(&i.meta),
            )?;
            write_transform(out, &pad, &i.matrix, &i.motion)?;
            let path = format!("{path}/{}", i.name);
            let p = format!("{pad}    ");
            write!(out, "{p}point3f[] positions = ")?;
            write_vec3s(out, &i.instances.positions)?;
            writeln!(out)?;
            // Text order (real, i, j, k), at the half precision the type keeps.
            let quats: Vec<String> = (i.instances.orientations.iter())
                .map(|q| {
                    let [x, y, z, w] = q.map(half_f32);
                    format!("({}, {}, {}, {})", F(w), F(x), F(y), F(z))
                })
                .collect();
            writeln!(out, "{p}quath[] orientations = [{}]", quats.join(", "))?;
            write!(out, "{p}float3[] scales = ")?;
            write_vec3s(out, &i.instances.scales)?;
            writeln!(out)?;
            let zeros = vec!["0"; i.instances.positions.len()];
            writeln!(out, "{p}int[] protoIndices = [{}]", zeros.join(", "))?;
            let proto = match &i.prototype {
                Prim::Xform { name, .. } => name.as_str(),
                _ => unreachable!("a prototype is an Xform"),
            };
            writeln!(out, "{p}rel prototypes = [<{path}/{PROTOTYPES}/{proto}>]")?;
            writeln!(out, "{p}def Scope \"{PROTOTYPES}\"")?;
            writeln!(out, "{p}{{")?;
            let protos = format!("{path}/{PROTOTYPES}");
            write_prim(&i.prototype, out, depth + 2, &protos, scope, spool)?;
            writeln!(out, "{p}}}")?;
            for c in &i.children {
                write_prim(c, out, depth + 1, &path, scope, spool)?;
            }
            writeln!(out, "{pad}}}")?;
        }
    }
    Ok(())
}

/// A camera or light: its type, API schemas and attributes.
fn write_plain(p: &Plain, out: &mut dyn Write, pad: &str) -> Result<()> {
    let mut meta = meta_lines(&p.meta);
    if !p.api_schemas.is_empty() {
        let schemas: Vec<String> = p.api_schemas.iter().map(|s| string_text(s)).collect();
        meta.push(format!("prepend apiSchemas = [{}]", schemas.join(", ")));
    }
    open_prim(out, pad, &format!("def {}", p.type_name), &p.name, &meta)?;
    for (name, ty, v) in &p.attrs {
        writeln!(out, "{pad}    {ty} {name} = {}", value_text(v))?;
    }
    writeln!(out, "{pad}}}")?;
    Ok(())
}

/// An Xformable's `xformOp:transform` (time-sampled when it moves) and `xformOpOrder`.
fn write_transform(
    out: &mut dyn Write,
    pad: &str,
    matrix: &Option<[f64; 16]>,
    motion: &[(f64, [f64; 16])],
) -> Result<()> {
    let text = |m: &[f64; 16]| {
        let rows: Vec<String> = m
            .chunks(4)
            .map(|r| format!("({}, {}, {}, {})", D(r[0]), D(r[1]), D(r[2]), D(r[3])))
            .collect();
        format!("( {} )", rows.join(", "))
    };
    if !motion.is_empty() {
        writeln!(out, "{pad}    matrix4d xformOp:transform.timeSamples = {{")?;
        for (code, m) in motion {
            writeln!(out, "{pad}        {code}: {},", text(m))?;
        }
        writeln!(out, "{pad}    }}")?;
    } else if let Some(m) = matrix {
        writeln!(out, "{pad}    matrix4d xformOp:transform = {}", text(m))?;
    }
    if !motion.is_empty() || matrix.is_some() {
        writeln!(
            out,
            "{pad}    uniform token[] xformOpOrder = [\"xformOp:transform\"]"
        )?;
    }
    Ok(())
}

/// `x` rounded to the nearest half-precision float (USD's `half`, as `quath` stores it).
fn half_f32(x: f32) -> f32 {
    half::f16::from_f32(x).to_f32()
}

/// A double as USD text: Rust's shortest form, with an exponent from 1e15 on (USD reads a
/// longer run of digits as an integer literal, out of range past 2^63).
struct D(f64);

impl std::fmt::Display for D {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.0.abs() >= 1e15 {
            write!(f, "{:e}", self.0)
        } else {
            write!(f, "{}", self.0)
        }
    }
}

/// A float in its shortest round-trip form, in exponent notation below 1e-4 and from 1e7 on
/// (USD parses both back to the same f32).
struct F(f32);

impl std::fmt::Display for F {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let a = self.0.abs();
        if a != 0.0 && !(1e-4..1e7).contains(&a) {
            write!(f, "{:e}", self.0)
        } else {
            write!(f, "{}", self.0)
        }
    }
}

/// Elements of an array formatted as one part: larger arrays (a point cache's samples, 23
/// frames of 500k points took 3.9 s of a 7.7 s run on one thread) are formatted in parts of
/// this many on every thread and written in order, the same text.
const TEXT_PART: usize = 16_384;

fn write_vec3s(out: &mut dyn Write, v: &[[f32; 3]]) -> std::io::Result<()> {
    out.write_all(b"[")?;
    if v.len() <= TEXT_PART {
        vec3s_text(out, v, true)?;
    } else {
        let parts: Vec<Vec<u8>> = v
            .par_chunks(TEXT_PART)
            .enumerate()
            .map(|(k, part)| {
                let mut text = Vec::with_capacity(part.len() * 32);
                vec3s_text(&mut text, part, k == 0).map(|()| text)
            })
            .collect::<std::io::Result<_>>()?;
        for text in parts {
            out.write_all(&text)?;
        }
    }
    out.write_all(b"]")
}

/// `v` as `(x, y, z)` separated by commas, one before the first unless it is the `first`.
fn vec3s_text<W: Write + ?Sized>(out: &mut W, v: &[[f32; 3]], first: bool) -> std::io::Result<()> {
    for (i, p) in v.iter().enumerate() {
        if i > 0 || !first {
            out.write_all(b", ")?;
        }
        write!(out, "({}, {}, {})", F(p[0]), F(p[1]), F(p[2]))?;
    }
    Ok(())
}

fn write_mesh(
    m: &MeshPrim,
    out: &mut dyn Write,
    pad: &str,
    scope: &str,
    spool: &Spool,
) -> Result<()> {
    let mut meta = meta_lines(&m.meta);
    meta.extend(m.material.iter().map(|_| BINDING_API.to_owned()));
    open_prim(out, pad, "def Mesh", &m.name, &meta)?;
    let p = format!("{pad}    ");
    if let Some(material) = &m.material {
        writeln!(out, "{p}rel material:binding = <{scope}/{material}>")?;
    }
    if m.double_sided {
        writeln!(out, "{p}uniform bool doubleSided = 1")?;
    }
    match &m.animation {
        None => {
            let e = extent(&m.points);
            write!(out, "{p}float3[] extent = ")?;
            write_vec3s(out, &e)?;
            writeln!(out)?;
        }
        Some(a) => {
            writeln!(out, "{p}float3[] extent.timeSamples = {{")?;
            spool.copy(a, Attr::Extent, out)?;
            writeln!(out, "{p}}}")?;
        }
    }
    write!(out, "{p}int[] faceVertexCounts = [")?;
    for i in 0..m.indices.len() / 3 {
        out.write_all(if i == 0 { b"3" } else { b", 3" })?;
    }
    writeln!(out, "]")?;
    write!(out, "{p}int[] faceVertexIndices = [")?;
    for (i, v) in m.indices.iter().enumerate() {
        if i > 0 {
            out.write_all(b", ")?;
        }
        write!(out, "{v}")?;
    }
    writeln!(out, "]")?;
    if let Some(n) = &m.normals {
        match &m.animation {
            Some(a) if a.normals => {
                writeln!(out, "{p}normal3f[] normals (")?;
                writeln!(out, "{p}    interpolation = \"vertex\"")?;
                writeln!(out, "{p})")?;
                writeln!(out, "{p}normal3f[] normals.timeSamples = {{")?;
                spool.copy(a, Attr::Normals, out)?;
                writeln!(out, "{p}}}")?;
            }
            _ => {
                write!(out, "{p}normal3f[] normals = ")?;
                write_vec3s(out, n)?;
                writeln!(out, " (")?;
                writeln!(out, "{p}    interpolation = \"vertex\"")?;
                writeln!(out, "{p})")?;
            }
        }
    }
    match &m.animation {
        None => {
            write!(out, "{p}point3f[] points = ")?;
            write_vec3s(out, &m.points)?;
            writeln!(out)?;
        }
        Some(a) => {
            writeln!(out, "{p}point3f[] points.timeSamples = {{")?;
            spool.copy(a, Attr::Points, out)?;
            writeln!(out, "{p}}}")?;
        }
    }
    write_primvars(m, out, &p)?;
    if !m.subsets.is_empty() {
        writeln!(
            out,
            "{p}uniform token subsetFamily:materialBind:familyType = \"partition\""
        )?;
    }
    writeln!(out, "{p}uniform token subdivisionScheme = \"none\"")?;
    for sub in &m.subsets {
        let meta: Vec<String> = sub
            .material
            .iter()
            .map(|_| BINDING_API.to_owned())
            .collect();
        open_prim(out, &p, "def GeomSubset", &sub.name, &meta)?;
        writeln!(out, "{p}    uniform token elementType = \"face\"")?;
        writeln!(out, "{p}    uniform token familyName = \"materialBind\"")?;
        let faces: Vec<String> = sub.faces.iter().map(i32::to_string).collect();
        writeln!(out, "{p}    int[] indices = [{}]", faces.join(", "))?;
        if let Some(material) = &sub.material {
            writeln!(out, "{p}    rel material:binding = <{scope}/{material}>")?;
        }
        writeln!(out, "{p}}}")?;
    }
    writeln!(out, "{pad}}}")?;
    Ok(())
}

/// A mesh's primvars (display colour and opacity, texture coordinates), indented by `p`.
fn write_primvars(m: &MeshPrim, out: &mut dyn Write, p: &str) -> Result<()> {
    match &m.color {
        Some(DisplayColor::Constant(c)) => {
            writeln!(
                out,
                "{p}color3f[] primvars:displayColor = [({}, {}, {})] (",
                F(c[0]),
                F(c[1]),
                F(c[2])
            )?;
            writeln!(out, "{p}    interpolation = \"constant\"")?;
            writeln!(out, "{p})")?;
        }
        Some(DisplayColor::Vertex(colors) | DisplayColor::Face(colors)) => {
            write!(out, "{p}color3f[] primvars:displayColor = [")?;
            for (i, c) in colors.iter().enumerate() {
                if i > 0 {
                    write!(out, ", ")?;
                }
                write!(out, "({}, {}, {})", F(c[0]), F(c[1]), F(c[2]))?;
            }
            writeln!(out, "] (")?;
            let interpolation = match m.color {
                Some(DisplayColor::Face(_)) => "uniform",
                _ => "vertex",
            };
            writeln!(out, "{p}    interpolation = \"{interpolation}\"")?;
            writeln!(out, "{p})")?;
        }
        None => {}
    }
    if let Some(alpha) = &m.opacity {
        write!(out, "{p}float[] primvars:displayOpacity = [")?;
        for (i, a) in alpha.iter().enumerate() {
            if i > 0 {
                write!(out, ", ")?;
            }
            write!(out, "{}", F(*a))?;
        }
        writeln!(out, "] (")?;
        writeln!(out, "{p}    interpolation = \"vertex\"")?;
        writeln!(out, "{p})")?;
    }
    for (name, st) in &m.st {
        write!(out, "{p}texCoord2f[] primvars:{name} = [")?;
        for (i, t) in st.iter().enumerate() {
            if i > 0 {
                out.write_all(b", ")?;
            }
            write!(out, "({}, {})", F(t[0]), F(t[1]))?;
        }
        writeln!(out, "] (")?;
        writeln!(out, "{p}    interpolation = \"vertex\"")?;
        writeln!(out, "{p})")?;
    }
    Ok(())
}

/// Time-sampled attributes written per frame.
#[derive(Clone, Copy)]
pub enum Attr {
    Extent,
    Normals,
    Points,
}

/// Sample text of every animated attribute, spooled to one scratch file beside the output as
/// frames arrive, then copied into the .usda (so no frame is held in memory): each attribute's
/// samples are chunks of that file, in frame order. (One file per attribute kept a file open
/// for each: a stage of 600 animated meshes failed with "Too many open files" under the
/// usual limit of 1,024.)
pub struct Spool {
    file: Option<PathBuf>,
    /// ((mesh, primitive, instance), attribute) -> its samples' (offset, length) in the file.
    chunks: HashMap<(SampleKey, u8), Vec<(u64, u64)>>,
}

impl Spool {
    fn copy(&self, a: &Animation, attr: Attr, out: &mut dyn Write) -> Result<()> {
        use std::io::Read;
        let key = (a.key(), attr as u8);
        let (Some(file), Some(chunks)) = (&self.file, self.chunks.get(&key)) else {
            return Ok(());
        };
        let mut f = std::io::BufReader::with_capacity(1 << 16, std::fs::File::open(file)?);
        let (mut at, mut buf) = (0u64, Vec::new());
        for (_, (offset, len)) in a.ordered(chunks) {
            f.seek_relative(offset as i64 - at as i64)?;
            buf.resize(len as usize, 0);
            f.read_exact(&mut buf)?;
            out.write_all(&buf)?;
            at = offset + len;
        }
        Ok(())
    }
}

/// Stage `stage` as a `.usda` at `path` in `files`, its frames taken from `source`.
pub fn write(
    stage: &Stage,
    path: &Path,
    source: &mut FrameSource,
    files: &mut Outputs,
) -> Result<u64> {
    let spool = spool_frames(stage, path, source, files)?;
    files.write_with(path, |w| write_usda(stage, w, &spool))
}

/// Run the frame source, writing each animated primitive's sample lines to spool files.
fn spool_frames(
    stage: &Stage,
    path: &Path,
    source: &mut FrameSource,
    files: &mut Outputs,
) -> Result<Spool> {
    let prims = animated(stage);
    let mut spool = Spool {
        file: None,
        chunks: HashMap::new(),
    };
    let file = files.scratch(path, ".samples");
    let f = std::fs::File::create(&file)
        .map_err(|e| anyhow::anyhow!("{}: cannot write: {e}", path.display()))?;
    spool.file = Some(file);
    let mut w = std::io::BufWriter::with_capacity(1 << 20, f);
    let (mut at, mut line) = (0u64, Vec::new());
    let pad = "            ";
    let chunks = &mut spool.chunks;
    let mut put = |a: &Animation, t: f64, s: Sample| -> Result<()> {
        let arrays = [
            (Attr::Extent, Some(&s.extent[..])),
            (Attr::Normals, s.normals.as_deref()),
            (Attr::Points, Some(&s.points[..])),
        ];
        for (attr, values) in arrays {
            if let Some(values) = values {
                line.clear();
                write!(line, "{pad}{t}: ")?;
                write_vec3s(&mut line, values)?;
                writeln!(line, ",")?;
                w.write_all(&line)?;
                let len = line.len() as u64;
                chunks
                    .entry((a.key(), attr as u8))
                    .or_default()
                    .push((at, len));
                at += len;
            }
        }
        Ok(())
    };
    source(&mut |k, f, deltas| {
        for_each_sample(&prims, k, f, deltas, &mut |a, s| put(a, a.times[f], s))
    })
    .map_err(|e| naming(path, e))?;
    for_each_skin_sample(stage, &mut put).map_err(|e| naming(path, e))?;
    w.flush().map_err(|e| naming(path, e.into()))?;
    Ok(spool)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn doubles_usd_would_read_as_integers_get_an_exponent() {
        assert_eq!(D(1e39).to_string(), "1e39");
        assert_eq!(D(-2.5e15).to_string(), "-2.5e15");
        assert_eq!(D(123456.75).to_string(), "123456.75");
        assert_eq!(
            D(6.123233995736766e-17).to_string(),
            "0.00000000000000006123233995736766"
        );
        assert_eq!(half_f32(0.70710677), 0.70703125);
    }
}
