//! BVH motion capture files as a rig and one clip (End Sites become leaf joints named
//! `<parent>_end`, so chains end where the foot or toe does), with what writing the same
//! skeleton back needs ([`Bvh`]: the hierarchy's text and each joint's channels, for
//! [`super::write_bvh`]).

use super::rig::{clip_from_channels, Channel, Clip, Interp, Path, Pose, Rig, Trs};
use crate::gltf::at;
use anyhow::Result;
use glam::{DQuat, DVec3};
use std::path::Path as FsPath;

#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Dof {
    Pos(usize),
    Rot(DVec3),
}

/// A BVH file as read: its rig (every joint in the skeleton), its motion, and its layout.
pub struct Bvh {
    pub rig: Rig,
    pub clip: Clip,
    /// Seconds per frame.
    pub frame_time: f64,
    /// The file's text from the start up to (not including) the word MOTION.
    pub(super) header: String,
    /// Each joint with channels and its channels, in file order.
    pub(super) dofs: Vec<(usize, Vec<Dof>)>,
}

/// Read a BVH file into a rig (every joint in the skeleton) and its motion.
pub fn read(path: &FsPath) -> Result<(Rig, Clip)> {
    load(path).map(|b| (b.rig, b.clip))
}

/// Read a BVH file with its layout (see [`Bvh`]).
pub fn load(path: &FsPath) -> Result<Bvh> {
    let text = std::fs::read_to_string(path).map_err(|e| at(path, format!("cannot read: {e}")))?;
    parse_layout(&text).map_err(|e| at(path, e))
}

/// The whitespace-separated words of a BVH file, each asked for by what it should be, and the
/// file's length in bytes.
struct Words<'a> {
    words: std::str::SplitWhitespace<'a>,
    len: usize,
}

impl<'a> Words<'a> {
    fn next(&mut self, what: &str) -> Result<&'a str, String> {
        self.words
            .next()
            .ok_or_else(|| format!("ends before {what}"))
    }
}

/// The joints of a BVH hierarchy: names, parents, offsets and the channels of each.
#[derive(Default)]
struct Hierarchy {
    names: Vec<String>,
    parent: Vec<Option<usize>>,
    offsets: Vec<DVec3>,
    dofs: Vec<(usize, Vec<Dof>)>,
}

/// Parse the text of a BVH file (errors say what is wrong, without the file name).
pub fn parse(text: &str) -> Result<(Rig, Clip), String> {
    parse_layout(text).map(|b| (b.rig, b.clip))
}

/// Parse the text of a BVH file with its layout.
fn parse_layout(text: &str) -> Result<Bvh, String> {
    let mut words = Words {
        words: text.split_whitespace(),
        len: text.len(),
    };
    if words.next("HIERARCHY")? != "HIERARCHY" {
        return Err("not a BVH file (no HIERARCHY)".into());
    }
    let (h, motion_at) = hierarchy(&mut words, text)?;
    let (channels, frame_time) = motion(&mut words, &h)?;
    let n = h.names.len();
    let rest = Pose {
        local: h
            .offsets
            .iter()
            .map(|&t| Trs { t, ..Trs::IDENTITY })
            .collect(),
        weights: vec![Vec::new(); n],
    };
    let rig = Rig::new(h.names, h.parent, rest).map_err(|e| e.to_string())?;
    Ok(Bvh {
        rig,
        clip: clip_from_channels("motion".into(), 0, channels),
        frame_time,
        header: text[..motion_at].to_string(),
        dofs: h.dofs,
    })
}

/// The hierarchy, up to and including the word MOTION, and where that word starts in `text`.
fn hierarchy(words: &mut Words, text: &str) -> Result<(Hierarchy, usize), String> {
    let mut h = Hierarchy::default();
    let mut stack: Vec<usize> = Vec::new();
    let mut last: Option<usize> = None;
    loop {
        let tok = words.next("MOTION")?;
        match tok {
            "ROOT" | "JOINT" | "End" => {
                let name = words.next("a joint name")?.to_string();
                let name = if tok == "End" {
                    format!("{}_end", last.map_or("", |l| h.names[l].as_str()))
                } else {
                    name
                };
                h.names.push(name);
                h.parent.push(stack.last().copied());
                h.offsets.push(DVec3::ZERO);
                last = Some(h.names.len() - 1);
            }
            "{" => stack.push(last.ok_or("a brace before any joint")?),
            "}" => {
                stack.pop().ok_or("unbalanced braces")?;
                last = stack.last().copied();
            }
            "OFFSET" => {
                let j = last.ok_or("OFFSET outside a joint")?;
                let mut v = [0.0; 3];
                for x in &mut v {
                    *x = num(words.next("an offset")?)?;
                }
                h.offsets[j] = DVec3::from_array(v);
            }
            "CHANNELS" => {
                let j = last.ok_or("CHANNELS outside a joint")?;
                h.dofs.push((j, channel_list(words)?));
            }
            "MOTION" => return Ok((h, tok.as_ptr() as usize - text.as_ptr() as usize)),
            other => return Err(format!("unexpected {other:?} in the hierarchy")),
        }
    }
}

/// A CHANNELS line after its keyword: the count and the channel names.
fn channel_list(words: &mut Words) -> Result<Vec<Dof>, String> {
    let n: usize = words
        .next("a channel count")?
        .parse()
        .map_err(|_| "bad channel count")?;
    let mut list = Vec::with_capacity(n.min(6));
    for _ in 0..n {
        list.push(
            match words.next("a channel name")?.to_ascii_lowercase().as_str() {
                "xposition" => Dof::Pos(0),
                "yposition" => Dof::Pos(1),
                "zposition" => Dof::Pos(2),
                "xrotation" => Dof::Rot(DVec3::X),
                "yrotation" => Dof::Rot(DVec3::Y),
                "zrotation" => Dof::Rot(DVec3::Z),
                other => return Err(format!("unknown channel {other:?}")),
            },
        );
    }
    Ok(list)
}

/// The MOTION section: one channel per moved property of each joint, keyed every frame, and
/// the frame time.
fn motion(words: &mut Words, h: &Hierarchy) -> Result<(Vec<Channel>, f64), String> {
    if words.next("Frames:")? != "Frames:" {
        return Err("no \"Frames:\" line".into());
    }
    let frames: usize = words
        .next("a frame count")?
        .parse()
        .map_err(|_| "bad frame count")?;
    if words.next("Frame Time:")? != "Frame" || words.next("Frame Time:")? != "Time:" {
        return Err("no \"Frame Time:\" line".into());
    }
    let dt = num(words.next("a frame time")?)?;
    if dt <= 0.0 || frames == 0 {
        return Err("no frames".into());
    }
    // Each value takes at least two characters: a frame count beyond the text is refused
    // before anything is allocated for it.
    let per_frame: usize = h.dofs.iter().map(|(_, l)| l.len()).sum();
    if frames.saturating_mul(per_frame.max(1)) > words.len / 2 {
        return Err(format!("claims {frames} frames, more than the file holds"));
    }
    let n = h.names.len();
    let times: Vec<f64> = (0..frames).map(|f| f as f64 * dt).collect();
    let mut trans: Vec<Vec<f64>> = vec![Vec::new(); n];
    let mut rots: Vec<Vec<f64>> = vec![Vec::new(); n];
    for _ in 0..frames {
        for (j, list) in &h.dofs {
            let mut t = h.offsets[*j];
            let mut r = DQuat::IDENTITY;
            let mut moved = false;
            for d in list {
                let v = num(words.next("frame values")?)?;
                match *d {
                    Dof::Pos(c) => {
                        t[c] = v;
                        moved = true;
                    }
                    Dof::Rot(axis) => r *= DQuat::from_axis_angle(axis, v.to_radians()),
                }
            }
            if moved {
                trans[*j].extend(t.to_array());
            }
            rots[*j].extend(r.normalize().to_array());
        }
    }
    let mut channels = Vec::new();
    for j in 0..n {
        for (path, values, width) in [
            (Path::Translation, std::mem::take(&mut trans[j]), 3),
            (Path::Rotation, std::mem::take(&mut rots[j]), 4),
        ] {
            if !values.is_empty() {
                channels.push(Channel {
                    node: j,
                    path,
                    interp: Interp::Linear,
                    times: times.clone(),
                    values,
                    width,
                });
            }
        }
    }
    Ok((channels, dt))
}

fn num(s: &str) -> Result<f64, String> {
    s.parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| format!("{s:?} is not a number"))
}
