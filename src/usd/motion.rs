//! Node motion on the stage: the translations, rotations and scales that the clips on the
//! stage's timeline (those whose morph frames it plays) key on the scene's nodes, sampled at
//! those clips' time codes as `xformOp:transform` time samples, so a face rig on a moving head
//! or a flag on a swaying pole moves in the point cache as in the glTF. A clip is sampled at
//! every time code its frames have (the glTF sampler evaluated as glTF asks, rotations by
//! slerp), so USD's linear interpolation of the matrices between two frames adds nothing a
//! viewer could see; keys between two frames are not kept. With `--loop` each node channel
//! returns to its first key where the clip's weights close their loop, as in the glTF output.
//! Clips that move nodes but have no frames on the stage are named in a warning.

use crate::gltf::{
    arr, clip_name, close_keys, local_at, node_target, read_channels, rest_trs, Channel, Document,
    Interp, Path,
};
use serde_json::Value;
use std::collections::{BTreeMap, BTreeSet};

/// A clip whose frames the stage plays: animation `animation` at time codes `codes`, code =
/// time x rate + `offset` (each clip has one place on the timeline; they follow one another).
pub struct ClipOnStage {
    pub animation: usize,
    pub codes: Vec<f64>,
    pub offset: f64,
    /// With `--loop`: the time (seconds) the clip's weights close their loop at; each node
    /// channel ending before it returns to its first key there, as the glTF output's do.
    pub loop_end: Option<f64>,
}

/// The keyed node transforms of the clips on the stage, by node.
pub struct NodeMotion {
    rate: f64,
    clips: Vec<ClipOnStage>,
    /// node -> (clip on stage, that clip's transform channels of the node)
    by_node: BTreeMap<usize, Vec<(usize, Vec<Channel>)>>,
}

impl NodeMotion {
    /// The motion of `clips` at `rate` time codes a second, and a line for each thing the stage
    /// will not carry.
    pub fn new(doc: &Document, clips: Vec<ClipOnStage>, rate: f64) -> (Self, Vec<String>) {
        let nodes = arr(&doc.json, "nodes").len();
        let mut warnings = Vec::new();
        let mut by_node: BTreeMap<usize, Vec<(usize, Vec<Channel>)>> = BTreeMap::new();
        for (k, clip) in clips.iter().enumerate() {
            let anim = &doc.json["animations"][clip.animation];
            let name = clip_name(anim, clip.animation);
            let channels = match read_channels(doc, &name, anim, nodes) {
                Ok(c) => c,
                Err(e) => {
                    // The error names the file, as the warning line will.
                    let e = format!("{e:#}");
                    let e = e.trim_start_matches(&format!("{}: ", doc.path.display()));
                    warnings.push(format!(
                        "the node motion of animation {name:?} is not in the stage: {e}"
                    ));
                    continue;
                }
            };
            let mut of_node: BTreeMap<usize, Vec<Channel>> = BTreeMap::new();
            for mut c in channels.into_iter().filter(|c| c.path != Path::Weights) {
                if let Some(end) = clip.loop_end {
                    let cubic = c.interp == Interp::Cubic;
                    close_keys(&mut c.times, &mut c.values, cubic, end);
                }
                of_node.entry(c.node).or_default().push(c);
            }
            for (node, channels) in of_node {
                by_node.entry(node).or_default().push((k, channels));
            }
        }
        let on_stage: BTreeSet<usize> = clips.iter().map(|c| c.animation).collect();
        let left: Vec<String> = (arr(&doc.json, "animations").iter().enumerate())
            .filter(|(a, _)| !on_stage.contains(a))
            .filter(|(_, anim)| {
                arr(anim, "channels").iter().any(|c| {
                    matches!(
                        node_target(&c["target"]),
                        Some((_, "translation" | "rotation" | "scale"))
                    )
                })
            })
            .map(|(a, anim)| format!("{:?}", clip_name(anim, a)))
            .collect();
        if !left.is_empty() {
            let (what, move_, tween, they) = match left.len() {
                1 => ("animation", "moves", "tweens", "it is"),
                _ => ("animations", "move", "tween", "they are"),
            };
            warnings.push(format!(
                "{what} {} {move_} nodes but {tween} no mesh, so {they} not on the point cache's timeline (a glTF output keeps them)",
                crate::gltf::listed(&left)
            ));
        }
        let motion = Self {
            rate,
            clips,
            by_node,
        };
        (motion, warnings)
    }

    /// The local transform of `node` (JSON `json`) at each time code of the clips that move
    /// it, in time order (column-major, as `xformOp:transform` reads it row by row); empty
    /// when no clip on the stage moves it.
    pub fn samples(&self, node: usize, json: &Value) -> Vec<(f64, [f64; 16])> {
        let Some(moved) = self.by_node.get(&node) else {
            return Vec::new();
        };
        let rest = rest_trs(json);
        let mut out: Vec<(f64, [f64; 16])> = Vec::new();
        for (k, channels) in moved {
            let clip = &self.clips[*k];
            for &code in &clip.codes {
                let t = (code - clip.offset) / self.rate;
                out.push((code, local_at(rest, channels, t).to_cols_array()));
            }
        }
        // Clips of different meshes may share codes: the first clip's sample stands.
        out.sort_by(|a, b| a.0.total_cmp(&b.0));
        out.dedup_by(|b, a| a.0 == b.0);
        out
    }
}
