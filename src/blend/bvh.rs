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
    /// The turn that stood the capture up (see [`upright`]): applied to every joint's offset,
    /// translation and rotation on read, undone on write. The identity for a Y-up file.
    pub(super) turn: DQuat,
}

impl Bvh {
    /// The file's own up axis, as judged on read (`Y`, `Z`, `-X` ...; see [`upright`]).
    pub fn up_axis(&self) -> String {
        let up = self.turn.inverse() * DVec3::Y;
        let sign = if up[up.abs().max_position()] < 0.0 {
            "-"
        } else {
            ""
        };
        format!("{sign}{}", axis_name(up))
    }

    /// Joints with channels, and joints without (End Sites).
    pub fn joint_counts(&self) -> (usize, usize) {
        (self.dofs.len(), self.rig.len() - self.dofs.len())
    }

    /// Values per frame (every joint's channels).
    pub fn channels_per_frame(&self) -> usize {
        self.dofs.iter().map(|(_, l)| l.len()).sum()
    }

    /// The rotation channel orders in the file (`ZXY` ...), each once, in file order.
    pub fn rotation_orders(&self) -> Vec<String> {
        let mut out: Vec<String> = Vec::new();
        for (_, list) in &self.dofs {
            let order: String = (list.iter())
                .filter_map(|d| match d {
                    Dof::Rot(a) => Some(axis_name(*a)),
                    Dof::Pos(_) => None,
                })
                .collect();
            if !order.is_empty() && !out.contains(&order) {
                out.push(order);
            }
        }
        out
    }
}

/// `X`, `Y` or `Z`: the axis along which `v` is longest.
fn axis_name(v: DVec3) -> &'static str {
    ["X", "Y", "Z"][v.abs().max_position()]
}

/// Read a BVH file into a rig (every joint in the skeleton) and its motion.
pub fn read(path: &FsPath) -> Result<(Rig, Clip)> {
    load(path).map(|b| (b.rig, b.clip))
}

/// Read a BVH file with its layout (see [`Bvh`]).
pub fn load(path: &FsPath) -> Result<Bvh> {
    let bytes = std::fs::read(path).map_err(|e| at(path, format!("cannot read: {e}")))?;
    if !crate::gltf::starts_like_bvh(&bytes) {
        if let Some(what) = crate::gltf::other_kind(&bytes) {
            return Err(at(path, what));
        }
    }
    let text = String::from_utf8(bytes).map_err(|e| at(path, format!("cannot read: {e}")))?;
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
    let mut rig = Rig::new(h.names, h.parent, rest).map_err(|e| e.to_string())?;
    let mut clip = clip_from_channels("motion".into(), 0, channels);
    // Every joint's offset, translation and rotation expressed in the upright axes: the posed
    // skeleton turned as one, and its local rotations what a Y-up file of the same skeleton
    // holds (so a Z-up capture blends with a Y-up one).
    let turn = upright(&rig, &clip);
    if turn != DQuat::IDENTITY {
        for r in &mut rig.rest.local {
            r.t = turn * r.t;
        }
        for c in &mut clip.channels {
            for v in c.values.chunks_exact_mut(c.width) {
                match c.path {
                    Path::Translation => {
                        v.copy_from_slice(&(turn * DVec3::from_slice(v)).to_array())
                    }
                    _ => v.copy_from_slice(
                        &(turn * DQuat::from_slice(v) * turn.inverse()).to_array(),
                    ),
                }
            }
        }
    }
    Ok(Bvh {
        rig,
        clip,
        frame_time,
        header: text[..motion_at].to_string(),
        dofs: h.dofs,
        turn,
    })
}

/// A standing skeleton's up-down asymmetry (feet below, one head above) is larger than its
/// front-back one by at least this factor, each measured as how far its joints land from any
/// joint when mirrored across the plane through their mean (fraction of the skeleton's size):
/// 2.7-5.3 on the CMU captures' rest poses, whose left-right mirror is 0.0005-0.009. (Posed,
/// a capture walking across the axes is mirrored by none: 1.3 on start-walk-stop.)
const UP_ASYMMETRY: f64 = 2.0;

/// The root stands at least this much farther above the lowest joint than below the highest
/// (legs longer than the trunk and head above the hips): 1.34-1.75 on the CMU captures.
const ROOT_LOW: f64 = 1.15;

/// Where the rest pose shows no up axis, the motion's must be clear: the posed skeleton at
/// least this many times as tall along it as along any other (summed over three frames, the
/// root bones left out, Bandai Namco's runs and dash stand 1.9-2.3 times as tall as they are
/// wide or long, the walks 2.7-3.5 times).
const POSED_TALL: f64 = 1.5;

/// Skeletons of more joints than this are taken as read (Y-up): the judgement compares every
/// joint with every other (a hostile file of a million joints would take hours); motion
/// captures have tens to a few hundred.
const MOST_JUDGED: usize = 4096;

/// The turn that stands the capture up in +Y, the world up of the later stages: BVH is Y-up by
/// convention, but Blender's BVH export (and 3ds Max's) writes its own Z-up world, where the
/// CMU walk's legs were not found. Judged from the rest pose (where a skeleton stands
/// symmetric): the up axis is the one whose mirror moves the joints farthest (see
/// [`UP_ASYMMETRY`]), up the side the root is nearer to (see [`ROOT_LOW`]); kept only where
/// the motion stands along it too (the posed skeleton, at the first, middle and last frames,
/// is tallest along it: a rest pose lying down that the root's rotation stands up is not
/// turned). Where any of it is not clear, or up is +Y, the identity.
fn upright(rig: &Rig, clip: &Clip) -> DQuat {
    let (n, root) = (rig.len(), rig.root);
    if !(4..=MOST_JUDGED).contains(&n) {
        return DQuat::IDENTITY;
    }
    let bounds = |pos: &[DVec3]| {
        let lo = pos.iter().fold(DVec3::INFINITY, |a, &p| a.min(p));
        let hi = pos.iter().fold(DVec3::NEG_INFINITY, |a, &p| a.max(p));
        (lo, hi)
    };
    // The body: the first joint that branches (the hips), below any root bones that hang it
    // (Bandai Namco's captures keep a joint_Root at the floor above the Hips, which carry the
    // travel): those stay behind while the body walks away, so they mark neither where the
    // root stands nor how tall the posed skeleton is.
    let children = rig.children();
    let mut body = root;
    let mut above = vec![false; n];
    while let [only] = children[body][..] {
        above[body] = true;
        body = only;
    }
    if children[body].is_empty() {
        // One chain (a tail, a rope): no body below root bones; every joint counts.
        (body, above) = (root, vec![false; n]);
    }
    let pos = rig.positions(&rig.rest);
    let (lo, hi) = bounds(&pos);
    let size = (hi - lo).max_element();
    if !size.is_finite() || size <= 0.0 {
        return DQuat::IDENTITY;
    }
    let mean = pos.iter().sum::<DVec3>() / n as f64;
    let mirror_error = |a: usize| {
        let moved: f64 = (pos.iter())
            .map(|&p| {
                let mut m = p;
                m[a] = 2.0 * mean[a] - p[a];
                pos.iter()
                    .map(|q| q.distance_squared(m))
                    .fold(f64::INFINITY, f64::min)
                    .sqrt()
            })
            .sum();
        moved / (n as f64 * size)
    };
    let errors = [mirror_error(0), mirror_error(1), mirror_error(2)];
    // The posed skeleton (root bones left out) at the first, middle and last frames: its
    // extent per axis, summed, and how far the body stands above its lowest joints and below
    // its highest, per axis, summed.
    let (mut posed, mut below, mut over) = (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO);
    for t in [clip.start, 0.5 * (clip.start + clip.end), clip.end] {
        let pos = rig.positions(&clip.pose(rig, t));
        let carried: Vec<DVec3> = (0..n).filter(|&j| !above[j]).map(|j| pos[j]).collect();
        let (lo, hi) = bounds(&carried);
        posed += hi - lo;
        below += pos[body] - lo;
        over += hi - pos[body];
    }
    let side = |below: f64, over: f64| {
        if below > ROOT_LOW * over {
            Some(1.0)
        } else if over > ROOT_LOW * below {
            Some(-1.0)
        } else {
            None
        }
    };
    let turned = |u: usize, sign: f64| {
        let mut up = DVec3::ZERO;
        up[u] = sign;
        DQuat::from_rotation_arc(up, DVec3::Y)
    };
    let mut axes = [0, 1, 2];
    axes.sort_by(|&a, &b| errors[b].total_cmp(&errors[a]));
    let u = axes[0];
    let rest = (errors[u] >= UP_ASYMMETRY * errors[axes[1]])
        .then(|| side(pos[body][u] - lo[u], hi[u] - pos[body][u]))
        .flatten();
    let Some(sign) = rest else {
        // The rest pose shows no up (offsets laid along each joint's own axis, as Bandai
        // Namco's are, and Blender's Z-up export of them): up is the axis the motion stands
        // tallest along, by [`POSED_TALL`] over the next, the body low on it.
        let mut tall = [0, 1, 2];
        tall.sort_by(|&a, &b| posed[b].total_cmp(&posed[a]));
        let u = tall[0];
        if posed[u] < POSED_TALL * posed[tall[1]] {
            return DQuat::IDENTITY;
        }
        return side(below[u], over[u]).map_or(DQuat::IDENTITY, |sign| turned(u, sign));
    };
    let turn = turned(u, sign);
    // Kept only where the motion stands along it too.
    match turn == DQuat::IDENTITY || (0..3).all(|a| a == u || posed[a] < posed[u]) {
        true => turn,
        false => DQuat::IDENTITY,
    }
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
    let written = words.next("a frame time")?;
    // As written to six places, 1/120 s is 120.0048 a second: read as the rate it stands for.
    let dt = crate::tween::written_frame_time(written)
        .ok_or_else(|| format!("{written:?} is not a number"))?;
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
    for f in 0..frames {
        let mut read = 0;
        for (j, list) in &h.dofs {
            let mut t = h.offsets[*j];
            let mut r = DQuat::IDENTITY;
            let mut moved = false;
            for d in list {
                // A capture cut short (the recording stopped, the header kept): said as such.
                let word = words.next("").map_err(|_| {
                    format!(
                        "declares {frames} frames but ends after {f} (frame {} has {read} of its {per_frame} values)",
                        f + 1
                    )
                })?;
                let v = num(word)?;
                read += 1;
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A stick figure in a T-pose (hips, two legs with knees and feet, a spine to the head,
    /// two arms out), each offset given Y-up and written through `axes`; one frame, the root
    /// turned `root_x` degrees about X.
    fn figure(axes: impl Fn(DVec3) -> DVec3, root_x: f64) -> String {
        let o = |x: f64, y: f64, z: f64| {
            let v = axes(DVec3::new(x, y, z));
            format!("OFFSET {} {} {}", v.x, v.y, v.z)
        };
        let leg = |side: &str, x: f64| {
            format!(
                "JOINT {side}Hip {{ {} JOINT {side}Knee {{ {} JOINT {side}Foot {{ {} End Site {{ {} }} }} }} }}",
                o(x, -0.05, 0.0),
                o(0.0, -0.45, 0.0),
                o(0.0, -0.45, 0.0),
                o(0.0, -0.05, 0.15)
            )
        };
        let arm = |side: &str, x: f64| {
            format!(
                "JOINT {side}Arm {{ {} JOINT {side}Hand {{ {} End Site {{ {} }} }} }}",
                o(x * 0.2, 0.0, 0.0),
                o(x * 0.5, 0.0, 0.0),
                o(x * 0.15, 0.0, 0.0)
            )
        };
        format!(
            "HIERARCHY\nROOT Hips {{ {} CHANNELS 6 Xposition Yposition Zposition Xrotation Yrotation Zrotation {} {} JOINT Chest {{ {} {} {} JOINT Head {{ {} End Site {{ {} }} }} }} }}\nMOTION\nFrames: 1\nFrame Time: 0.0333\n0 0 0 {root_x} 0 0\n",
            o(0.0, 0.0, 0.0),
            leg("L", 0.1),
            leg("R", -0.1),
            o(0.0, 0.45, 0.0),
            arm("L", 1.0),
            arm("R", -1.0),
            o(0.0, 0.15, 0.0),
            o(0.0, 0.12, 0.0)
        )
    }

    #[test]
    fn a_z_up_capture_is_stood_up_and_a_y_up_one_is_left() {
        let y_up = parse_layout(&figure(|v| v, 0.0)).unwrap();
        assert_eq!(y_up.turn, DQuat::IDENTITY);
        // Z-up, as Blender writes: (x, y, z) -> (x, -z, y).
        let z_up = parse_layout(&figure(|v| DVec3::new(v.x, -v.z, v.y), 0.0)).unwrap();
        assert!(z_up
            .turn
            .abs_diff_eq(DQuat::from_rotation_arc(DVec3::Z, DVec3::Y), 1e-12));
        // Stood up, its joints are where the Y-up file has them.
        let at = |b: &Bvh| b.rig.positions(&b.clip.pose(&b.rig, 0.0));
        for (p, q) in at(&y_up).iter().zip(at(&z_up)) {
            assert!(p.distance(q) < 1e-12, "{p} against {q}");
        }
        // A Z-up rest pose that its root's rotation stands up in the motion is left as read.
        let stood = parse_layout(&figure(|v| DVec3::new(v.x, -v.z, v.y), -90.0)).unwrap();
        assert_eq!(stood.turn, DQuat::IDENTITY);
    }

    /// A capture whose root bone stays at the floor while the hips below it carry the travel
    /// (Bandai Namco's joint_Root), its rest pose lying along Z (bones along their joints' own
    /// axes) and the hips' rotation standing it up in Y: up is Y. The posed skeleton's height
    /// was measured with the root bone left behind, so a walk along Z was taken as Z-up and
    /// turned over (the legs then not found).
    #[test]
    fn a_root_bone_left_behind_does_not_turn_a_capture_over() {
        let text = figure(|v| DVec3::new(v.x, -v.z, v.y), 0.0);
        let (head, _) = text.split_once("MOTION").unwrap();
        let body = head.replacen("ROOT Hips", "JOINT Hips", 1);
        let body = body.trim_start_matches("HIERARCHY\n");
        let walked: String = (0..3)
            .map(|k| format!("0 0 0 0 0 0 0 0.95 {} -90 0 0\n", 4.0 * k as f64))
            .collect();
        let text = format!(
            "HIERARCHY\nROOT joint_Root {{ OFFSET 0 0 0 CHANNELS 6 Xposition Yposition Zposition Xrotation Yrotation Zrotation\n{body} }}\nMOTION\nFrames: 3\nFrame Time: 0.0333\n{walked}"
        );
        let read = parse_layout(&text).unwrap();
        assert_eq!(read.turn, DQuat::IDENTITY, "up {}", read.up_axis());
    }

    /// Offsets laid along each joint's own axis (Bandai Namco's captures: the rest pose a line
    /// 2.2 across here, 457 cm there) say nothing of the character's size nor of its up axis;
    /// its first frame, where the joints' rotations stand it up 1.7 tall, does.
    #[test]
    fn a_rest_pose_laid_along_the_joints_axes_is_sized_as_it_stands() {
        let rot = "CHANNELS 3 Zrotation Xrotation Yrotation";
        let chain = |name: &str, sign: f64, lengths: &[f64]| {
            let mut text = String::new();
            for (k, l) in lengths.iter().enumerate() {
                let channels = if k == 0 { rot } else { "" };
                text += &format!("JOINT {name}{k} {{ OFFSET {} 0 0 {channels} ", sign * l);
            }
            text += &format!("End Site {{ OFFSET {} 0 0 }} ", sign * 0.1);
            text + &"} ".repeat(lengths.len())
        };
        let text = format!(
            "HIERARCHY\nROOT Hips {{ OFFSET 0 0 0 CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation {} {} {} }}\nMOTION\nFrames: 1\nFrame Time: 0.0333\n0 1 0 0 0 0 -90 0 0 90 0 0 90 0 0\n",
            chain("L", 1.0, &[0.1, 0.45, 0.45]),
            chain("R", -1.0, &[0.1, 0.45, 0.45]),
            chain("C", 1.0, &[0.05, 0.45, 0.15]),
        );
        let read = parse_layout(&text).unwrap();
        let rest = super::super::track::size(&read.rig, &read.rig.rest);
        let size = super::super::track::character_size(&read.rig, &[&read.clip]);
        assert!((rest - 2.2).abs() < 1e-9, "rest {rest}");
        assert!((size - 1.7).abs() < 1e-9, "size {size}");
        assert_eq!(read.up_axis(), "Y");
        // The same figure standing along Z in its motion (Blender's Z-up export of such a
        // capture): the rest pose shows no up, the motion does; it was read as Y-up.
        let z_up = text.replace(
            "0 1 0 0 0 0 -90 0 0 90 0 0 90 0 0",
            "0 0 1 0 0 0 0 0 90 0 0 -90 0 0 -90",
        );
        let read = parse_layout(&z_up).unwrap();
        assert_eq!(read.up_axis(), "Z");
        let size = super::super::track::character_size(&read.rig, &[&read.clip]);
        assert!((size - 1.7).abs() < 1e-9, "size {size}");
    }

    /// A capture cut short (the recording stopped, its header kept) is refused saying how many
    /// frames it declares, how many it holds and how much of the next.
    #[test]
    fn a_capture_cut_short_says_where() {
        let whole = figure(|v| v, 0.0).replace("Frames: 1", "Frames: 3");
        let text = format!("{whole}0 0 0 5 0 0\n0 0 0\n");
        let err = parse(&text).err().unwrap();
        assert_eq!(
            err,
            "declares 3 frames but ends after 2 (frame 3 has 3 of its 6 values)"
        );
    }
}
