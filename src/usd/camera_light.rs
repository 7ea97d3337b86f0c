//! Cameras and lights: a glTF camera as a UsdGeom `Camera`, a `KHR_lights_punctual` light as a
//! UsdLux light, each a child prim of its node's Xform (so it moves with the node, animated
//! or not). Both look and shine down their node's -Z with +Y up, in glTF as in USD.
//!
//! * Camera: `projection`, `clippingRange` (znear, zfar; an infinite perspective far plane is
//!   [`FAR`]) and the apertures that give glTF's field of view: a perspective camera keeps
//!   USD's default focal length ([`FOCAL_LENGTH`], tenths of a scene unit like the apertures)
//!   and gets the vertical aperture `2 f tan(yfov / 2)`, the horizontal one that times the
//!   aspect ratio (USD's default film back's proportions where glTF leaves it to the
//!   viewport); an orthographic camera's apertures are its extents, `2 xmag` and `2 ymag`, in
//!   tenths of a scene unit.
//! * Lights, `inputs:normalize` on so that the intensity does not depend on the light's size:
//!   directional -> `DistantLight`, its intensity the glTF illuminance (lux, what a normalized
//!   distant light's intensity is); point -> `SphereLight` with `treatAsPoint`, spot -> the
//!   same with `ShapingAPI` (`shaping:cone:angle` the outer cone angle in degrees,
//!   `shaping:cone:softness` the part of it the falloff takes, `1 - inner / outer`). A
//!   normalized sphere of any radius spreads its intensity over its surface, 4 pi r^2, and
//!   shows pi r^2 of it in any direction, so glTF's luminous intensity (candela) is a quarter
//!   of the USD intensity. `color` is the light's colour. A light's `range` has no UsdLux
//!   counterpart: it is named in a warning line.
//!
//! ```text
//! let prims = camera_light::of_node(&doc.json, node, &mut taken, &mut left_out);
//! ```

use super::material::Value;
use super::stage::{identifier, Meta};
use crate::gltf::{arr, quoted_name};
use serde_json::Value as Json;
use std::collections::HashMap;

/// A camera's focal length (tenths of a scene unit): USD's default.
pub const FOCAL_LENGTH: f64 = 50.0;

/// USD's default film back (tenths of a scene unit), whose proportions a camera without an
/// aspect ratio keeps.
const DEFAULT_APERTURE: [f64; 2] = [20.955, 15.2908];

/// The far clipping plane of a perspective camera that glTF leaves infinite (scene units;
/// USD's default far plane).
pub const FAR: f64 = 1e6;

/// (name, type name, value) of an attribute.
pub type Attr = (&'static str, &'static str, Value);

/// A prim of plain attributes: a camera or a light.
#[derive(Clone, Debug, PartialEq)]
pub struct Plain {
    pub name: String,
    /// What it keeps of the glTF camera or light: its name and extras.
    pub meta: Meta,
    /// `Camera`, `DistantLight` or `SphereLight`.
    pub type_name: &'static str,
    /// API schemas applied (`prepend apiSchemas`): `ShapingAPI` for a spot light.
    pub api_schemas: Vec<&'static str>,
    /// Its attributes, in the order written.
    pub attrs: Vec<Attr>,
}

/// The camera and light of glTF node `node` as prims, named uniquely among `taken` (the
/// node's children); what cannot be carried is said in `left_out`.
pub fn of_node(
    json: &Json,
    node: usize,
    taken: &mut HashMap<String, usize>,
    left_out: &mut Vec<String>,
) -> Vec<Plain> {
    let n = &json["nodes"][node];
    let mut out = Vec::new();
    if let Some(c) = n["camera"].as_u64() {
        let cam = &json["cameras"][c as usize];
        match camera(cam) {
            Some((type_name, attrs)) => {
                let name = unique(cam["name"].as_str().unwrap_or("camera"), taken);
                out.push(Plain {
                    meta: Meta::of(cam, &name),
                    name,
                    type_name,
                    api_schemas: Vec::new(),
                    attrs,
                })
            }
            None => say(
                left_out,
                format!(
                    "{} has no valid projection (glTF's camera rules): not written to the USD stage",
                    called("camera", c, cam)
                ),
            ),
        }
    }
    if let Some(l) = n["extensions"]["KHR_lights_punctual"]["light"].as_u64() {
        // A node may name a light the file does not have: said, like one of no known type.
        let lit = &json["extensions"]["KHR_lights_punctual"]["lights"][l as usize];
        let what = || called("light", l, lit);
        match light(lit) {
            Some(mut p) => {
                if let Some(range) = lit["range"].as_f64() {
                    let line = format!(
                        "{}'s range ({range}) is not carried: UsdLux lights have none",
                        what()
                    );
                    say(left_out, line);
                }
                p.name = unique(lit["name"].as_str().unwrap_or("light"), taken);
                p.meta = Meta::of(lit, &p.name);
                out.push(p);
            }
            None => say(
                left_out,
                format!(
                    "{} is not a valid KHR_lights_punctual light: not written to the USD stage",
                    what()
                ),
            ),
        }
    }
    out
}

/// `line` added to `left_out` once (a camera or light several nodes carry is said once).
pub(super) fn say(left_out: &mut Vec<String>, line: String) {
    if !left_out.contains(&line) {
        left_out.push(line);
    }
}

/// `camera "shot"`, or `camera 2` without a name.
fn called(kind: &str, index: u64, v: &Json) -> String {
    match v["name"].as_str() {
        Some(_) => format!("{kind} {}", quoted_name(v, String::new)),
        None => format!("{kind} {index}"),
    }
}

fn unique(name: &str, taken: &mut HashMap<String, usize>) -> String {
    super::stage::unique(identifier(name), taken)
}

/// A positive finite number at `v`.
fn positive(v: &Json) -> Option<f64> {
    v.as_f64().filter(|x| x.is_finite() && *x > 0.0)
}

fn float(x: f64) -> Value {
    Value::Float(x as f32)
}

/// Whether every number of `attrs` is finite as written (f32): an aperture or intensity of
/// 1e38 in the glTF overflows.
fn finite(attrs: &[Attr]) -> bool {
    attrs.iter().all(|(_, _, v)| match v {
        Value::Float(x) => x.is_finite(),
        Value::Vec2(x) => x.iter().all(|x| x.is_finite()),
        Value::Vec3(x) => x.iter().all(|x| x.is_finite()),
        _ => true,
    })
}

/// A glTF camera's type name and attributes (see the module's notes); `None` for one that
/// breaks glTF's rules (no positive field of view or extents, a far plane before the near one).
fn camera(cam: &Json) -> Option<(&'static str, Vec<Attr>)> {
    let (projection, apertures, clipping) = match cam["type"].as_str()? {
        "perspective" => {
            let p = &cam["perspective"];
            let yfov = positive(&p["yfov"]).filter(|f| *f < std::f64::consts::PI)?;
            let near = positive(&p["znear"])?;
            let far = match &p["zfar"] {
                Json::Null => FAR.max(near * 2.0),
                z => positive(z).filter(|f| *f > near)?,
            };
            let vertical = 2.0 * FOCAL_LENGTH * (0.5 * yfov).tan();
            let aspect = match &p["aspectRatio"] {
                Json::Null => DEFAULT_APERTURE[0] / DEFAULT_APERTURE[1],
                a => positive(a)?,
            };
            ("perspective", [vertical * aspect, vertical], [near, far])
        }
        "orthographic" => {
            let o = &cam["orthographic"];
            // Tenths of a scene unit.
            let (x, y) = (positive(&o["xmag"])?, positive(&o["ymag"])?);
            let near = o["znear"].as_f64().filter(|z| z.is_finite() && *z >= 0.0)?;
            let far = positive(&o["zfar"]).filter(|f| *f > near)?;
            ("orthographic", [20.0 * x, 20.0 * y], [near, far])
        }
        _ => return None,
    };
    let attrs = vec![
        ("projection", "token", Value::Token(projection)),
        ("focalLength", "float", float(FOCAL_LENGTH)),
        ("horizontalAperture", "float", float(apertures[0])),
        ("verticalAperture", "float", float(apertures[1])),
        (
            "clippingRange",
            "float2",
            Value::Vec2(clipping.map(|x| x as f32)),
        ),
    ];
    finite(&attrs).then_some(("Camera", attrs))
}

/// A `KHR_lights_punctual` light as a UsdLux prim (unnamed; see the module's notes); `None`
/// for one of no known type or with a negative intensity or cone angles out of order.
fn light(l: &Json) -> Option<Plain> {
    let intensity = match &l["intensity"] {
        Json::Null => 1.0,
        i => i.as_f64().filter(|x| x.is_finite() && *x >= 0.0)?,
    };
    let c = arr(l, "color");
    let color = [0, 1, 2].map(|i| c.get(i).and_then(Json::as_f64).unwrap_or(1.0) as f32);
    let mut attrs = vec![
        ("inputs:color", "color3f", Value::Vec3(color)),
        ("inputs:normalize", "bool", Value::Bool(true)),
    ];
    let mut api_schemas = Vec::new();
    let type_name = match l["type"].as_str()? {
        "directional" => {
            attrs.push(("inputs:intensity", "float", float(intensity)));
            "DistantLight"
        }
        kind @ ("point" | "spot") => {
            attrs.push(("inputs:intensity", "float", float(4.0 * intensity)));
            attrs.push(("treatAsPoint", "bool", Value::Bool(true)));
            if kind == "spot" {
                let s = &l["spot"];
                let quarter = std::f64::consts::FRAC_PI_4;
                let inner = s["innerConeAngle"].as_f64().unwrap_or(0.0);
                let outer = s["outerConeAngle"].as_f64().unwrap_or(quarter);
                let valid = (0.0..outer).contains(&inner) && outer <= 2.0 * quarter;
                if !valid {
                    return None;
                }
                api_schemas.push("ShapingAPI");
                attrs.push((
                    "inputs:shaping:cone:angle",
                    "float",
                    float(outer.to_degrees()),
                ));
                attrs.push((
                    "inputs:shaping:cone:softness",
                    "float",
                    float(1.0 - inner / outer),
                ));
            }
            "SphereLight"
        }
        _ => return None,
    };
    finite(&attrs).then_some(Plain {
        name: String::new(),
        meta: Meta::default(),
        type_name,
        api_schemas,
        attrs,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn attr<'a>(p: &'a Plain, name: &str) -> &'a Value {
        &p.attrs.iter().find(|a| a.0 == name).expect(name).2
    }

    #[test]
    fn a_perspective_camera_keeps_its_field_of_view_and_an_orthographic_one_its_extents() {
        let doc = json!({
            "cameras": [
                {"type": "perspective", "perspective": {"yfov": 0.8, "aspectRatio": 1.5, "znear": 0.1}},
                {"type": "orthographic", "orthographic": {"xmag": 2.0, "ymag": 1.0, "znear": 0.0, "zfar": 50.0}},
                {"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1, "zfar": 0.05}},
            ],
            "nodes": [{"camera": 0}, {"camera": 1}, {"camera": 2}]
        });
        let (mut taken, mut left) = (HashMap::new(), Vec::new());
        let p = of_node(&doc, 0, &mut taken, &mut left).remove(0);
        assert_eq!(p.type_name, "Camera");
        let Value::Float(v) = *attr(&p, "verticalAperture") else {
            panic!()
        };
        let yfov = 2.0 * (0.5 * v as f64 / FOCAL_LENGTH).atan();
        assert!((yfov - 0.8).abs() < 1e-6, "{yfov}");
        let Value::Float(h) = *attr(&p, "horizontalAperture") else {
            panic!()
        };
        assert!((h / v - 1.5).abs() < 1e-6);
        assert_eq!(*attr(&p, "clippingRange"), Value::Vec2([0.1, FAR as f32]));
        let o = of_node(&doc, 1, &mut taken, &mut left).remove(0);
        assert_eq!(*attr(&o, "projection"), Value::Token("orthographic"));
        assert_eq!(*attr(&o, "horizontalAperture"), Value::Float(40.0));
        assert_eq!(*attr(&o, "verticalAperture"), Value::Float(20.0));
        // Two cameras of one name under one parent get distinct names.
        assert_ne!(p.name, o.name);
        // A far plane before the near one breaks glTF's rules, extents of 1e38 overflow the
        // apertures: said, not written.
        assert!(of_node(&doc, 2, &mut taken, &mut left).is_empty());
        let huge = json!({
            "cameras": [{"type": "orthographic",
                "orthographic": {"xmag": 1e38, "ymag": 1.0, "znear": 0.0, "zfar": 1.0}}],
            "nodes": [{"camera": 0}]
        });
        assert!(of_node(&huge, 0, &mut taken, &mut left).is_empty());
        assert_eq!(left.len(), 2, "{left:?}");
    }

    #[test]
    fn lights_keep_their_intensity_colour_and_cone() {
        let doc = json!({
            "extensions": {"KHR_lights_punctual": {"lights": [
                {"name": "sun", "type": "directional", "intensity": 3.0, "color": [1.0, 0.9, 0.8]},
                {"type": "point", "intensity": 10.0, "range": 5.0},
                {"type": "spot", "intensity": 2.0, "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.5}},
            ]}},
            "nodes": [
                {"extensions": {"KHR_lights_punctual": {"light": 0}}},
                {"extensions": {"KHR_lights_punctual": {"light": 1}}},
                {"extensions": {"KHR_lights_punctual": {"light": 2}}},
            ]
        });
        let mut left = Vec::new();
        let mut one = |n: usize| of_node(&doc, n, &mut HashMap::new(), &mut left).remove(0);
        let sun = one(0);
        assert_eq!((sun.type_name, sun.name.as_str()), ("DistantLight", "sun"));
        assert_eq!(*attr(&sun, "inputs:intensity"), Value::Float(3.0));
        assert_eq!(*attr(&sun, "inputs:color"), Value::Vec3([1.0, 0.9, 0.8]));
        let point = one(1);
        assert_eq!(point.type_name, "SphereLight");
        assert_eq!(*attr(&point, "inputs:intensity"), Value::Float(40.0));
        assert_eq!(*attr(&point, "treatAsPoint"), Value::Bool(true));
        assert!(point.api_schemas.is_empty());
        let spot = one(2);
        assert_eq!(spot.api_schemas, ["ShapingAPI"]);
        let Value::Float(angle) = *attr(&spot, "inputs:shaping:cone:angle") else {
            panic!()
        };
        assert!((angle as f64 - 0.5f64.to_degrees()).abs() < 1e-4);
        let Value::Float(soft) = *attr(&spot, "inputs:shaping:cone:softness") else {
            panic!()
        };
        assert!((soft - 0.6).abs() < 1e-6);
        assert_eq!(left.len(), 1, "the point light's range: {left:?}");
        assert!(left[0].contains("range (5)"), "{left:?}");
        // A node naming a light the file does not have (the fuzzer's find: it panicked).
        let missing = json!({"nodes": [{"extensions": {"KHR_lights_punctual": {"light": 7}}}]});
        assert!(of_node(&missing, 0, &mut HashMap::new(), &mut left).is_empty());
        assert!(left[1].starts_with("light 7 is not a valid"), "{left:?}");
    }
}
