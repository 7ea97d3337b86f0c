//! Look stage: glTF materials as UsdShade materials, for the writers to put under the stage's
//! root in a `Materials` scope and bind to the meshes.
//!
//! Each glTF material becomes a `Material` whose `outputs:surface` is a `UsdPreviewSurface`:
//! * base colour: `diffuseColor` = `baseColorFactor`, or a `UsdUVTexture` (sRGB) of
//!   `baseColorTexture` scaled by the factor; a primitive with `COLOR_0` and no base colour
//!   texture is bound to a variant (`<name>_vertexColor`) whose `diffuseColor` reads the mesh's
//!   `displayColor` primvar (glTF multiplies the factor in too; UsdPreviewSurface cannot, so the
//!   variant keeps the colours and drops a factor that is not white);
//! * `metallic` and `roughness` from the factors, or the B and G channels of
//!   `metallicRoughnessTexture` (raw) scaled by them;
//! * `normal` from `normalTexture` (raw) mapped from [0, 1] to [-1, 1] (a glTF `scale` other
//!   than 1 is left out: usd-core's validator requires the unscaled mapping for 8-bit maps);
//!   `occlusion` from the R channel of `occlusionTexture` with its `strength`;
//! * `emissiveColor` from `emissiveFactor` (times `KHR_materials_emissive_strength`), or
//!   `emissiveTexture` (sRGB) scaled by it;
//! * `opacity` from the base colour's alpha for `BLEND` and `MASK`, with `opacityThreshold` =
//!   `alphaCutoff` (default 0.5) for `MASK`; nothing for `OPAQUE`;
//! * `clearcoat`, `clearcoatRoughness` from `KHR_materials_clearcoat` (factors, or the R and G
//!   channels of its textures scaled by them), `ior` from `KHR_materials_ior`; other material
//!   extensions (sheen, transmission, volume, specular, unlit, ...) are named in
//!   [`Look::left_out`].
//!
//! Every texture reads `primvars:st` (TEXCOORD_0; `st1`, ... for other sets) through a
//! `UsdPrimvarReader_float2`, with the sampler's wrap modes (`repeat`, `mirror`, `clamp`) and
//! `KHR_texture_transform` as a `UsdTransform2d` (in USD's flipped V: see [`transform_2d`]).
//! Image files are carried as they are (PNG, JPEG); WebP images are written as PNG (decoded by
//! `image-webp`, stored losslessly); KTX2 and AVIF cannot be read by USD: those textures are
//! left out and named in [`Look::left_out`].

use super::stage::{identifier, Data, Meta};
use crate::gltf::{arr, Document};
use anyhow::Result;
use serde_json::Value as Json;
use std::collections::{HashMap, HashSet};

/// Every material of a stage and the image files they read.
#[derive(Default)]
pub struct Look {
    /// Name of the scope under the stage's root prim that holds the materials.
    pub scope: String,
    pub materials: Vec<Material>,
    /// Image files, written beside the layer (or packed into a `.usdz`) under these names.
    pub textures: Vec<Texture>,
    /// What could not be carried, one line each (for the summary's warnings).
    pub left_out: Vec<String>,
    /// The material variants (`KHR_materials_variants`) the root prim's variant set chooses
    /// between (see `stage::VARIANT_SET`), by glTF variant index, and the variant it selects,
    /// every primitive with its own material (`default`, unless a glTF variant is so named).
    pub variants: Vec<String>,
    pub default_variant: String,
}

/// One `Material` prim: its shaders, the surface first.
pub struct Material {
    pub name: String,
    /// What it keeps of the glTF material: its name and extras.
    pub meta: Meta,
    pub shaders: Vec<Shader>,
}

/// One `Shader` prim.
pub struct Shader {
    pub name: String,
    /// `info:id`: UsdPreviewSurface, UsdUVTexture, UsdPrimvarReader_float2, ...
    pub id: &'static str,
    pub inputs: Vec<Input>,
    /// Outputs: (name without `outputs:`, type name).
    pub outputs: Vec<(&'static str, &'static str)>,
}

/// One `inputs:` attribute of a shader.
pub struct Input {
    /// Name without `inputs:`.
    pub name: &'static str,
    pub type_name: &'static str,
    pub value: Value,
}

/// What an input holds.
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    Bool(bool),
    Float(f32),
    Vec2([f32; 2]),
    Vec3([f32; 3]),
    Vec4([f32; 4]),
    Token(&'static str),
    Text(String),
    /// An asset path (a texture file, relative to the layer).
    Asset(String),
    /// A connection to output `output` of shader `shader` in the same material.
    Connect {
        shader: String,
        output: &'static str,
    },
}

/// An image file the materials read.
pub struct Texture {
    /// File name, relative to the layer.
    pub file: String,
    pub data: Vec<u8>,
}

/// The surface shader's name in every material.
pub const SURFACE: &str = "PreviewSurface";

/// The names of the material variants of `KHR_materials_variants` (identifiers, unique), in
/// the file's order, where a primitive maps one (none otherwise), and the default variant's.
fn variant_names(json: &Json) -> (Vec<String>, String) {
    let variants = arr(&json["extensions"]["KHR_materials_variants"], "variants");
    let mapped = (arr(json, "meshes").iter())
        .flat_map(|m| arr(m, "primitives"))
        .any(|p| !arr(&p["extensions"]["KHR_materials_variants"], "mappings").is_empty());
    if !mapped {
        return (Vec::new(), String::new());
    }
    let mut taken = HashMap::new();
    let names = (variants.iter().enumerate())
        .map(|(i, v)| {
            let name = v["name"].as_str().filter(|n| !n.is_empty());
            let name = name.map_or_else(|| format!("variant{i}"), identifier);
            super::stage::unique(name, &mut taken)
        })
        .collect();
    (names, super::stage::unique("default".into(), &mut taken))
}

/// Builds the look as primitives ask for materials.
pub struct LookBuilder<'a> {
    doc: &'a Document,
    prefix: String,
    look: Look,
    /// (glTF material, vertex colour) -> material prim name.
    made: HashMap<(usize, bool), String>,
    names: HashSet<String>,
    /// glTF image -> texture file (None: left out).
    files: HashMap<usize, Option<String>>,
}

impl<'a> LookBuilder<'a> {
    /// A builder whose texture files are named `<prefix><image name>.<png|jpg>`.
    pub fn new(doc: &'a Document, prefix: &str) -> LookBuilder<'a> {
        LookBuilder {
            doc,
            prefix: prefix.to_owned(),
            look: Look::default(),
            made: HashMap::new(),
            names: HashSet::new(),
            files: HashMap::new(),
        }
    }

    /// The Material prim name for glTF material `m` on a primitive with (`vertex_color`) or
    /// without COLOR_0; `None` when the file has no such material.
    pub fn material(&mut self, m: usize, vertex_color: bool) -> Result<Option<String>> {
        let Some(mat) = arr(&self.doc.json, "materials").get(m) else {
            return Ok(None);
        };
        let has_texture = mat["pbrMetallicRoughness"]["baseColorTexture"].is_object();
        let vertex_color = vertex_color && !has_texture;
        if let Some(name) = self.made.get(&(m, vertex_color)) {
            return Ok(Some(name.clone()));
        }
        let base = identifier(mat["name"].as_str().unwrap_or(&format!("material{m}")));
        let base = if vertex_color {
            format!("{base}_vertexColor")
        } else {
            base
        };
        let mut name = base.clone();
        let mut k = 0;
        while !self.names.insert(name.clone()) {
            k += 1;
            name = format!("{base}_{k}");
        }
        let shaders = self.shaders(m, mat, vertex_color)?;
        // The vertex-colour copy shows the glTF name with the suffix its prim name has.
        let display = (mat["name"].as_str())
            .map(|n| match vertex_color {
                true => format!("{n}_vertexColor"),
                false => n.to_owned(),
            })
            .filter(|n| *n != name);
        self.look.materials.push(Material {
            name: name.clone(),
            meta: Meta {
                display,
                extras: Data::of(&mat["extras"]),
            },
            shaders,
        });
        self.made.insert((m, vertex_color), name.clone());
        Ok(Some(name))
    }

    /// The look, its materials in the scope named `scope`; materials no primitive asked for
    /// are added too (unbound), so that none of the file's is lost.
    pub fn finish(mut self, scope: String) -> Result<Look> {
        for m in 0..arr(&self.doc.json, "materials").len() {
            if !self.made.keys().any(|&(k, _)| k == m) {
                self.material(m, false)?;
            }
        }
        (self.look.variants, self.look.default_variant) = variant_names(&self.doc.json);
        Ok(Look { scope, ..self.look })
    }

    /// The shaders of glTF material `m` (`mat`), the surface first.
    fn shaders(&mut self, m: usize, mat: &Json, vertex_color: bool) -> Result<Vec<Shader>> {
        let mut parts = Parts::default();
        self.base_color(m, mat, vertex_color, &mut parts)?;
        self.maps(m, mat, &mut parts)?;
        self.extensions(m, mat, &mut parts)?;
        let surface = Shader {
            name: SURFACE.into(),
            id: "UsdPreviewSurface",
            inputs: parts.inputs,
            outputs: vec![("surface", "token")],
        };
        let mut shaders = vec![surface];
        shaders.extend(parts.more);
        Ok(shaders)
    }

    /// Base colour, opacity and alpha cut-off of glTF material `m` (`mat`).
    fn base_color(
        &mut self,
        m: usize,
        mat: &Json,
        vertex_color: bool,
        parts: &mut Parts,
    ) -> Result<()> {
        let pbr = &mat["pbrMetallicRoughness"];
        let factor = floats::<4>(&pbr["baseColorFactor"], [1.0; 4]);
        let rgb = [factor[0], factor[1], factor[2]];
        let alpha_mode = mat["alphaMode"].as_str().unwrap_or("OPAQUE");
        let opacity = alpha_mode != "OPAQUE";
        let slot = Slot {
            key: "baseColorTexture",
            shader: "BaseColor",
            srgb: true,
            scale: factor,
            bias: [0.0; 4],
        };
        match self.texture(&pbr["baseColorTexture"], slot, m, &mut parts.more)? {
            Some(tex) => {
                parts.set("diffuseColor", "color3f", connect(&tex, "rgb"));
                if opacity {
                    parts.set("opacity", "float", connect(&tex, "a"));
                }
            }
            None if vertex_color => {
                parts.more.push(Shader {
                    name: "VertexColor".into(),
                    id: "UsdPrimvarReader_float3",
                    inputs: vec![
                        input("varname", "string", Value::Text("displayColor".into())),
                        input("fallback", "float3", Value::Vec3(rgb)),
                    ],
                    outputs: vec![("result", "float3")],
                });
                parts.set("diffuseColor", "color3f", connect("VertexColor", "result"));
                if rgb != [1.0; 3] {
                    self.look.left_out.push(format!(
                        "material {m} baseColorFactor {rgb:?} left out where COLOR_0 colours the mesh (UsdPreviewSurface cannot multiply them)"
                    ));
                }
            }
            None => parts.set("diffuseColor", "color3f", Value::Vec3(rgb)),
        }
        if opacity && parts.get("opacity").is_none() {
            parts.set("opacity", "float", Value::Float(factor[3]));
        }
        if alpha_mode == "MASK" {
            let cutoff = mat["alphaCutoff"].as_f64().unwrap_or(0.5) as f32;
            parts.set("opacityThreshold", "float", Value::Float(cutoff));
        }
        Ok(())
    }

    /// Metallic, roughness, normal, occlusion and emissive of glTF material `m` (`mat`).
    fn maps(&mut self, m: usize, mat: &Json, parts: &mut Parts) -> Result<()> {
        let pbr = &mat["pbrMetallicRoughness"];
        let metallic = pbr["metallicFactor"].as_f64().unwrap_or(1.0) as f32;
        let roughness = pbr["roughnessFactor"].as_f64().unwrap_or(1.0) as f32;
        // glTF keeps roughness in G and metallic in B.
        let slot = Slot {
            key: "metallicRoughnessTexture",
            shader: "MetallicRoughness",
            srgb: false,
            scale: [1.0, roughness, metallic, 1.0],
            bias: [0.0; 4],
        };
        match self.texture(&pbr["metallicRoughnessTexture"], slot, m, &mut parts.more)? {
            Some(tex) => {
                parts.set("metallic", "float", connect(&tex, "b"));
                parts.set("roughness", "float", connect(&tex, "g"));
            }
            None => {
                parts.set("metallic", "float", Value::Float(metallic));
                parts.set("roughness", "float", Value::Float(roughness));
            }
        }
        // Normal map: [0, 1] to [-1, 1]. usd-core's validator requires exactly this scale and
        // bias for 8-bit maps, so a glTF `scale` other than 1 cannot be carried: said so.
        let normal = &mat["normalTexture"];
        let slot = Slot {
            key: "normalTexture",
            shader: "Normal",
            srgb: false,
            scale: [2.0, 2.0, 2.0, 1.0],
            bias: [-1.0, -1.0, -1.0, 0.0],
        };
        if let Some(tex) = self.texture(normal, slot, m, &mut parts.more)? {
            parts.set("normal", "normal3f", connect(&tex, "rgb"));
            let s = normal["scale"].as_f64().unwrap_or(1.0);
            if s != 1.0 {
                self.look.left_out.push(format!(
                    "material {m} normalTexture: scale {s} left out (UsdPreviewSurface normal maps are unscaled)"
                ));
            }
        }
        // Occlusion: 1 + strength * (ao - 1).
        let k = mat["occlusionTexture"]["strength"].as_f64().unwrap_or(1.0) as f32;
        let slot = Slot {
            key: "occlusionTexture",
            shader: "Occlusion",
            srgb: false,
            scale: [k, k, k, 1.0],
            bias: [1.0 - k, 1.0 - k, 1.0 - k, 0.0],
        };
        if let Some(tex) = self.texture(&mat["occlusionTexture"], slot, m, &mut parts.more)? {
            parts.set("occlusion", "float", connect(&tex, "r"));
        }
        let strength = mat["extensions"]["KHR_materials_emissive_strength"]["emissiveStrength"]
            .as_f64()
            .unwrap_or(1.0) as f32;
        let emissive = floats::<3>(&mat["emissiveFactor"], [0.0; 3]).map(|c| c * strength);
        let slot = Slot {
            key: "emissiveTexture",
            shader: "Emissive",
            srgb: true,
            scale: [emissive[0], emissive[1], emissive[2], 1.0],
            bias: [0.0; 4],
        };
        match self.texture(&mat["emissiveTexture"], slot, m, &mut parts.more)? {
            Some(tex) => parts.set("emissiveColor", "color3f", connect(&tex, "rgb")),
            None if emissive != [0.0; 3] => {
                parts.set("emissiveColor", "color3f", Value::Vec3(emissive))
            }
            None => {}
        }
        Ok(())
    }

    /// The material extensions UsdPreviewSurface has inputs for: `KHR_materials_clearcoat`
    /// (`clearcoat`, `clearcoatRoughness`: factors, or the R and G channels of their textures
    /// scaled by them) and `KHR_materials_ior` (`ior`). Any other material extension (sheen,
    /// transmission, volume, specular, unlit, ...) and the clearcoat normal map are left out,
    /// named in `left_out`.
    fn extensions(&mut self, m: usize, mat: &Json, parts: &mut Parts) -> Result<()> {
        let ext = &mat["extensions"];
        let coat = &ext["KHR_materials_clearcoat"];
        if coat.is_object() {
            for (key, factor_key, input, channel) in [
                ("clearcoatTexture", "clearcoatFactor", "clearcoat", "r"),
                (
                    "clearcoatRoughnessTexture",
                    "clearcoatRoughnessFactor",
                    "clearcoatRoughness",
                    "g",
                ),
            ] {
                let f = coat[factor_key].as_f64().unwrap_or(0.0) as f32;
                let slot = Slot {
                    key,
                    shader: if input == "clearcoat" {
                        "Clearcoat"
                    } else {
                        "ClearcoatRoughness"
                    },
                    srgb: false,
                    scale: [f, f, f, 1.0],
                    bias: [0.0; 4],
                };
                match self.texture(&coat[key], slot, m, &mut parts.more)? {
                    Some(tex) => parts.set(input, "float", connect(&tex, channel)),
                    None => parts.set(input, "float", Value::Float(f)),
                }
            }
            if coat["clearcoatNormalTexture"].is_object() {
                self.look.left_out.push(format!(
                    "material {m} clearcoatNormalTexture left out (UsdPreviewSurface has one normal input)"
                ));
            }
        }
        if let Some(ior) = ext["KHR_materials_ior"]["ior"].as_f64() {
            parts.set("ior", "float", Value::Float(ior as f32));
        } else if ext["KHR_materials_ior"].is_object() {
            parts.set("ior", "float", Value::Float(1.5));
        }
        let carried = [
            "KHR_materials_clearcoat",
            "KHR_materials_ior",
            "KHR_materials_emissive_strength",
        ];
        let left: Vec<&str> = (ext.as_object().into_iter().flatten())
            .map(|(k, _)| k.as_str())
            .filter(|k| k.starts_with("KHR_materials_") && !carried.contains(k))
            .collect();
        if !left.is_empty() {
            self.look.left_out.push(format!(
                "material {m} {} left out (UsdPreviewSurface has no inputs for {})",
                left.join(", "),
                if left.len() == 1 { "it" } else { "them" }
            ));
        }
        Ok(())
    }

    /// A `UsdUVTexture` (with its primvar reader and transform) for texture reference `info`
    /// of glTF material `m`, pushed to `out`; returns its name, or `None` when there is no
    /// reference or its image is left out.
    fn texture(
        &mut self,
        info: &Json,
        slot: Slot,
        m: usize,
        out: &mut Vec<Shader>,
    ) -> Result<Option<String>> {
        let Slot {
            key,
            shader: name,
            srgb,
            scale,
            bias,
        } = slot;
        let what = &format!("material {m} {key}");
        let Some(t) = info["index"].as_u64() else {
            return Ok(None);
        };
        let json = &self.doc.json;
        let texture = &json["textures"][t as usize];
        let Some(file) = self.image_file(texture, what)? else {
            return Ok(None);
        };
        let st = coordinates(info, name, out);
        let sampler = texture["sampler"]
            .as_u64()
            .map(|s| &json["samplers"][s as usize]);
        let wrap = |key: &str| match sampler.and_then(|s| s[key].as_u64()) {
            Some(33071) => "clamp",
            Some(33648) => "mirror",
            _ => "repeat",
        };
        let mut inputs = vec![
            input("file", "asset", Value::Asset(format!("./{file}"))),
            input("st", "float2", st),
            input("wrapS", "token", Value::Token(wrap("wrapS"))),
            input("wrapT", "token", Value::Token(wrap("wrapT"))),
            input(
                "sourceColorSpace",
                "token",
                Value::Token(if srgb { "sRGB" } else { "raw" }),
            ),
        ];
        if scale != [1.0; 4] {
            inputs.push(input("scale", "float4", Value::Vec4(scale)));
        }
        if bias != [0.0; 4] {
            inputs.push(input("bias", "float4", Value::Vec4(bias)));
        }
        out.push(Shader {
            name: name.to_owned(),
            id: "UsdUVTexture",
            inputs,
            outputs: vec![
                ("rgb", "float3"),
                ("r", "float"),
                ("g", "float"),
                ("b", "float"),
                ("a", "float"),
            ],
        });
        Ok(Some(name.to_owned()))
    }

    /// The file name of the image texture `texture` shows (its PNG or JPEG source, or its
    /// EXT_texture_webp source as PNG; KHR_texture_basisu and EXT_texture_avif sources are left
    /// out, with a line in `left_out`).
    fn image_file(&mut self, texture: &Json, what: &str) -> Result<Option<String>> {
        // WebP first: of the three, the one we can write for USD.
        let extension_source = ["EXT_texture_webp", "KHR_texture_basisu", "EXT_texture_avif"]
            .iter()
            .find_map(|e| texture["extensions"][*e]["source"].as_u64());
        let Some(i) = texture["source"].as_u64().or(extension_source) else {
            self.look
                .left_out
                .push(format!("{what}: the texture has no image"));
            return Ok(None);
        };
        let i = i as usize;
        if let Some(file) = self.files.get(&i) {
            return Ok(file.clone());
        }
        // An image file that cannot be read (a texture missing beside a downloaded .gltf) is
        // left out, said; one leading outside the allowed folders is still refused.
        let uri = self.doc.json["images"][i]["uri"].as_str();
        let (data, mime) = match uri.filter(|u| !u.starts_with("data:")) {
            Some(uri) => match self.doc.read_image_or_why(i, uri)? {
                Ok((data, mime)) => (data, Some(mime)),
                Err(why) => {
                    (self.look.left_out).push(format!("{what}: image {i} {uri:?} {why}, left out"));
                    self.files.insert(i, None);
                    return Ok(None);
                }
            },
            None => self.doc.image(i)?,
        };
        let img = &self.doc.json["images"][i];
        let label = img["name"]
            .as_str()
            .map(str::to_owned)
            .or_else(|| {
                let uri = img["uri"].as_str().filter(|u| !u.starts_with("data:"))?;
                let stem = std::path::Path::new(uri).file_stem()?.to_str()?;
                Some(stem.to_owned())
            })
            .unwrap_or_else(|| format!("image{i}"));
        // An image named after its file: "uv_texture.jpg" gives uv_texture.
        let label = match label.rsplit_once('.') {
            Some((stem, ext))
                if ["png", "jpg", "jpeg", "webp"].contains(&ext.to_ascii_lowercase().as_str()) =>
            {
                stem.to_owned()
            }
            _ => label,
        };
        // WebP (EXT_texture_webp, what `gltf-transform webp` writes) as PNG, which USD reads.
        let (data, mime) = match mime {
            Some("image/webp") => match webp_to_png(&data) {
                Ok(png) => (png, Some("image/png")),
                Err(why) => {
                    self.look.left_out.push(format!(
                        "{what}: image {i} {label:?} is a WebP image that cannot be read ({why}), left out"
                    ));
                    self.files.insert(i, None);
                    return Ok(None);
                }
            },
            _ => (data, mime),
        };
        let file = match mime {
            Some("image/png") | Some("image/jpeg") => {
                let ext = if mime == Some("image/png") {
                    "png"
                } else {
                    "jpg"
                };
                let stem = format!("{}{}", self.prefix, identifier(&label));
                let mut file = format!("{stem}.{ext}");
                let mut k = 0;
                while self.look.textures.iter().any(|t| t.file == file) {
                    k += 1;
                    file = format!("{stem}_{k}.{ext}");
                }
                self.look.textures.push(Texture {
                    file: file.clone(),
                    data,
                });
                Some(file)
            }
            other => {
                let kind = other.map_or("an unknown format", |m| m.trim_start_matches("image/"));
                self.look.left_out.push(format!(
                    "{what}: image {i} {label:?} is {} (USD reads PNG and JPEG, and WebP is written as PNG), left out",
                    kind.to_uppercase()
                ));
                None
            }
        };
        self.files.insert(i, file.clone());
        Ok(file)
    }
}

/// Most bytes a WebP image may decode to for [`webp_to_png`] (a 16,384-pixel square RGBA
/// texture): a header asking for more is refused rather than allocated.
const MAX_WEBP_BYTES: usize = 1 << 30;

/// A WebP image as a PNG file: decoded (the first frame of an animated one) and stored
/// losslessly, RGB or RGBA as the image has alpha; `Err` says why it cannot be read.
fn webp_to_png(data: &[u8]) -> Result<Vec<u8>, String> {
    let mut decoder =
        image_webp::WebPDecoder::new(std::io::Cursor::new(data)).map_err(|e| e.to_string())?;
    let (width, height) = decoder.dimensions();
    let size = (decoder.output_buffer_size())
        .filter(|&n| n <= MAX_WEBP_BYTES)
        .ok_or_else(|| format!("{width} x {height} pixels"))?;
    decoder.set_memory_limit(MAX_WEBP_BYTES);
    let mut pixels = vec![0u8; size];
    decoder.read_image(&mut pixels).map_err(|e| e.to_string())?;
    let mut out = Vec::new();
    let mut png = png::Encoder::new(&mut out, width, height);
    png.set_color(if decoder.has_alpha() {
        png::ColorType::Rgba
    } else {
        png::ColorType::Rgb
    });
    png.set_depth(png::BitDepth::Eight);
    let mut writer = png.write_header().map_err(|e| e.to_string())?;
    writer
        .write_image_data(&pixels)
        .map_err(|e| e.to_string())?;
    writer.finish().map_err(|e| e.to_string())?;
    Ok(out)
}

/// A material's surface inputs and the shaders they read, as they are built.
#[derive(Default)]
struct Parts {
    inputs: Vec<Input>,
    more: Vec<Shader>,
}

impl Parts {
    fn set(&mut self, name: &'static str, type_name: &'static str, value: Value) {
        self.inputs.push(Input {
            name,
            type_name,
            value,
        });
    }

    fn get(&self, name: &str) -> Option<&Value> {
        self.inputs
            .iter()
            .find(|i| i.name == name)
            .map(|i| &i.value)
    }
}

/// How one glTF texture slot is read: its key in the material (for messages), the shader's
/// name, whether its colours are sRGB, and the scale and bias applied to what it reads.
struct Slot {
    key: &'static str,
    shader: &'static str,
    srgb: bool,
    scale: [f32; 4],
    bias: [f32; 4],
}

/// The texture coordinates texture reference `info` reads (for shader `name`): a
/// `UsdPrimvarReader_float2` of its set (shared by the material's textures), through a
/// `UsdTransform2d` when it has `KHR_texture_transform`; shaders pushed to `out`.
fn coordinates(info: &Json, name: &str, out: &mut Vec<Shader>) -> Value {
    let transform = &info["extensions"]["KHR_texture_transform"];
    let set = transform["texCoord"]
        .as_u64()
        .or(info["texCoord"].as_u64())
        .unwrap_or(0);
    let reader = format!("TexCoord{set}");
    if !out.iter().any(|s| s.name == reader) {
        out.push(Shader {
            name: reader.clone(),
            id: "UsdPrimvarReader_float2",
            inputs: vec![input(
                "varname",
                "string",
                Value::Text(st_name(set as usize)),
            )],
            outputs: vec![("result", "float2")],
        });
    }
    let mut st = connect(&reader, "result");
    if transform.is_object() {
        let (rotation, scale, translation) = transform_2d(
            floats::<2>(&transform["offset"], [0.0; 2]),
            transform["rotation"].as_f64().unwrap_or(0.0),
            floats::<2>(&transform["scale"], [1.0; 2]),
        );
        let tname = format!("{name}Transform");
        out.push(Shader {
            name: tname.clone(),
            id: "UsdTransform2d",
            inputs: vec![
                input("in", "float2", st),
                input("rotation", "float", Value::Float(rotation)),
                input("scale", "float2", Value::Vec2(scale)),
                input("translation", "float2", Value::Vec2(translation)),
            ],
            outputs: vec![("result", "float2")],
        });
        st = connect(&tname, "result");
    }
    st
}

/// The primvar a glTF texture coordinate set becomes: `st`, `st1`, `st2`, ...
pub fn st_name(set: usize) -> String {
    match set {
        0 => "st".into(),
        n => format!("st{n}"),
    }
}

fn input(name: &'static str, type_name: &'static str, value: Value) -> Input {
    Input {
        name,
        type_name,
        value,
    }
}

fn connect(shader: &str, output: &'static str) -> Value {
    Value::Connect {
        shader: shader.to_owned(),
        output,
    }
}

/// `N` numbers of a JSON array, `default` where it has none.
fn floats<const N: usize>(v: &Json, default: [f32; N]) -> [f32; N] {
    let mut out = default;
    if let Some(a) = v.as_array().filter(|a| a.len() == N) {
        for (o, x) in out.iter_mut().zip(a) {
            *o = x.as_f64().map_or(*o, |x| x as f32);
        }
    }
    out
}

/// `KHR_texture_transform` (offset, rotation in radians, scale; in glTF's UV space, V down) as
/// `UsdTransform2d` inputs (rotation in degrees, scale, translation; in USD's st space, where
/// t = 1 - v): glTF maps uv to T(offset) R(rotation) S(scale) uv with R = [[cos, sin],
/// [-sin, cos]]; flipping V on both sides makes R the counter-clockwise rotation USD applies
/// after the scale, and moves the translation to (ox + sy sin r, 1 - oy - sy cos r).
pub fn transform_2d(offset: [f32; 2], rotation: f64, scale: [f32; 2]) -> (f32, [f32; 2], [f32; 2]) {
    let (s, c) = rotation.sin_cos();
    let (sy, ox, oy) = (scale[1] as f64, offset[0] as f64, offset[1] as f64);
    let translation = [(ox + sy * s) as f32, (1.0 - oy - sy * c) as f32];
    (rotation.to_degrees() as f32, scale, translation)
}
