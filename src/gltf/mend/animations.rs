//! Empty animations ([`empty_animations`], [`drop_empty_animations`]): an animation must
//! have a channel and a sampler (assimp 5.2's glTF-to-glTF export keeps a morph file's clip
//! with neither, having lost its weights): left out of the output, which plays the same. So
//! is a channel that repeats another's target and sampler ([`repeated_channels`],
//! [`drop_repeated_channels`]): glTF allows one channel a target, and the other plays the
//! same keys. Repeats on other samplers (which keys win is each player's choice) are left.

use crate::gltf::read::{arr, listed, quoted_name};
use serde_json::Value;

/// Whether animation `anim` has what the specification asks of one: a channel and a sampler.
fn playable(anim: &Value) -> bool {
    !arr(anim, "channels").is_empty() && !arr(anim, "samplers").is_empty()
}

/// A line naming the input's animations that have no channel or no sampler, which the output
/// leaves out ([`drop_empty_animations`], when it is written: until then the other stages
/// address the animations by their index in the input).
pub fn empty_animations(json: &Value) -> Vec<String> {
    let empty: Vec<String> = (arr(json, "animations").iter().enumerate())
        .filter(|(_, a)| !playable(a))
        .map(|(i, a)| quoted_name(a, || format!("{i}")))
        .collect();
    let (what, has) = match empty.len() {
        0 => return Vec::new(),
        1 => ("animation", "has"),
        _ => ("animations", "have"),
    };
    vec![format!(
        "{what} {} {has} no channel or no sampler (nothing to play): left out",
        listed(&empty)
    )]
}

/// Channel `c` of `anim` when it repeats an earlier channel's target and sampler exactly (an
/// animation may target a node's property once; the repeat plays the very same keys).
fn repeats(anim: &Value, c: usize) -> bool {
    let channels = arr(anim, "channels");
    let key = |ch: &Value| (ch["target"].clone(), ch["sampler"].clone());
    channels[..c].iter().any(|e| key(e) == key(&channels[c]))
}

/// A line naming the input's animations with channels that repeat another's target and
/// sampler, which the output leaves out ([`drop_repeated_channels`], when it is written).
pub fn repeated_channels(json: &Value) -> Vec<String> {
    let mut lines = Vec::new();
    for (a, anim) in arr(json, "animations").iter().enumerate() {
        let n = (0..arr(anim, "channels").len())
            .filter(|&c| repeats(anim, c))
            .count();
        if n > 0 {
            let name = quoted_name(anim, || format!("{a}"));
            let (s, its) = if n == 1 { ("", "its") } else { ("s", "their") };
            lines.push(format!(
                "animation {name}: {n} channel{s} repeating another's target and sampler (glTF allows one channel a target): left out, {its} keys played by the other"
            ));
        }
    }
    lines
}

/// Remove every channel that repeats an earlier one of its animation exactly; see
/// [`repeated_channels`].
pub fn drop_repeated_channels(json: &mut Value) {
    let Some(anims) = json.get_mut("animations").and_then(Value::as_array_mut) else {
        return;
    };
    for anim in anims {
        let keep: Vec<bool> = (0..arr(anim, "channels").len())
            .map(|c| !repeats(anim, c))
            .collect();
        if let Some(channels) = anim.get_mut("channels").and_then(Value::as_array_mut) {
            let mut k = keep.iter();
            channels.retain(|_| *k.next().unwrap());
        }
    }
}

/// Remove the animations that have no channel or no sampler (and `animations`, if none is
/// left); see [`empty_animations`].
pub fn drop_empty_animations(json: &mut Value) {
    let Some(anims) = json.get_mut("animations").and_then(Value::as_array_mut) else {
        return;
    };
    anims.retain(playable);
    if anims.is_empty() {
        json.as_object_mut().map(|o| o.remove("animations"));
    }
}
