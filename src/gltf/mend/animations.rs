//! Empty animations ([`empty_animations`], [`drop_empty_animations`]): an animation must
//! have a channel and a sampler (assimp 5.2's glTF-to-glTF export keeps a morph file's clip
//! with neither, having lost its weights): left out of the output, which plays the same. So
//! is a channel that repeats another's target and sampler ([`repeated_channels`],
//! [`drop_repeated_channels`]): glTF allows one channel a target, and the other plays the
//! same keys. A channel whose target a later channel animates with other keys ([`shadowed`];
//! which keys win is each player's choice: three.js averages them) is left out too, so that
//! the output is valid; every stage reads the later channel's keys, as a player applying
//! channels in order shows them.

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

/// Which channels of `anim` repeat an earlier channel's target and sampler exactly (an
/// animation may target a node's property once; the repeat plays the very same keys): one pass,
/// each channel's target and sampler written once as [`canonical`] text (a clip of 10,000
/// channels compared each with all before it took 16 s).
fn repeats(anim: &Value) -> Vec<bool> {
    let mut seen = std::collections::HashSet::new();
    (arr(anim, "channels").iter())
        .map(|ch| !seen.insert((canonical(&ch["target"]), canonical(&ch["sampler"]))))
        .collect()
}

/// Which channels of `anim` a later channel shadows: one whose target a later channel (not
/// itself a repeat, see [`repeats`]) animates with another sampler. The readers leave them
/// out (the later channel's keys play), as the output does ([`drop_repeated_channels`]).
pub fn shadowed(anim: &Value) -> Vec<bool> {
    let repeat = repeats(anim);
    let targets: Vec<String> = (arr(anim, "channels").iter())
        .map(|c| canonical(&c["target"]))
        .collect();
    let mut later = std::collections::HashSet::new();
    let mut out = vec![false; targets.len()];
    for i in (0..targets.len()).rev() {
        if !repeat[i] && !later.insert(&targets[i]) {
            out[i] = true;
        }
    }
    out
}

/// `v` as text with every object's keys in order: the same text for values JSON holds equal,
/// in whatever order a writer put their keys.
fn canonical(v: &Value) -> String {
    match v {
        Value::Object(o) => {
            let mut kv: Vec<String> = (o.iter())
                .map(|(k, x)| format!("{k:?}:{}", canonical(x)))
                .collect();
            kv.sort_unstable();
            format!("{{{}}}", kv.join(","))
        }
        Value::Array(a) => format!(
            "[{}]",
            a.iter().map(canonical).collect::<Vec<_>>().join(",")
        ),
        x => x.to_string(),
    }
}

/// A line per kind naming the input's animations with channels that repeat another's target
/// and sampler, or that a later channel shadows ([`shadowed`]), which the output leaves out
/// ([`drop_repeated_channels`], when it is written).
pub fn repeated_channels(json: &Value) -> Vec<String> {
    let mut lines = Vec::new();
    for (a, anim) in arr(json, "animations").iter().enumerate() {
        let kinds = [
            (repeats(anim), "repeating another's target and sampler (glTF allows one channel a target): left out, {its} keys played by the other"),
            (shadowed(anim), "whose target a later channel animates with other keys (glTF allows one channel a target; players differ on which wins): left out, the later one playing {its} target"),
        ];
        for (marked, what) in kinds {
            let n = marked.into_iter().filter(|&r| r).count();
            if n > 0 {
                let name = quoted_name(anim, || format!("{a}"));
                let (s, its) = if n == 1 { ("", "its") } else { ("s", "their") };
                let what = what.replace("{its}", its);
                lines.push(format!("animation {name}: {n} channel{s} {what}"));
            }
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
        let keep: Vec<bool> = (repeats(anim).into_iter().zip(shadowed(anim)))
            .map(|(r, s)| !r && !s)
            .collect();
        let sampler_of = |c: &Value| c["sampler"].as_u64().map(|s| s as usize);
        let dropped: Vec<usize> = (arr(anim, "channels").iter().zip(&keep))
            .filter(|(_, k)| !**k)
            .filter_map(|(c, _)| sampler_of(c))
            .collect();
        if let Some(channels) = anim.get_mut("channels").and_then(Value::as_array_mut) {
            let mut k = keep.iter();
            channels.retain(|_| *k.next().unwrap());
        }
        // A sampler only a left-out channel played (a shadowed channel's) goes too, the
        // others renumbered; unused samplers the input has otherwise stay as they are.
        let used: std::collections::HashSet<usize> = arr(anim, "channels")
            .iter()
            .filter_map(sampler_of)
            .collect();
        let freed: std::collections::BTreeSet<usize> =
            dropped.into_iter().filter(|s| !used.contains(s)).collect();
        if freed.is_empty() {
            continue;
        }
        if let Some(samplers) = anim.get_mut("samplers").and_then(Value::as_array_mut) {
            let mut i = 0;
            samplers.retain(|_| {
                i += 1;
                !freed.contains(&(i - 1))
            });
        }
        let shift = |s: usize| s - freed.range(..s).count();
        if let Some(channels) = anim.get_mut("channels").and_then(Value::as_array_mut) {
            for c in channels {
                if let Some(s) = sampler_of(c) {
                    c["sampler"] = shift(s).into();
                }
            }
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
