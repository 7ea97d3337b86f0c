//! `inbetween inspect capture.bvh`: what `blend` finds in a BVH motion capture before it runs:
//! the skeleton (joints, End Sites, the root, channel orders), the motion (frames, frame time,
//! duration), the file's up axis (a Z-up capture is stood up on read), and the clip alone as
//! `blend` analyses it (feet, stride, cycles, or why it would refuse the clip).

use super::{gait_line, GaitInfo};
use crate::blend::{gait, load_bvh};
use anyhow::Result;
use serde::Serialize;
use std::path::Path;

#[derive(Serialize)]
pub struct BvhInspection {
    pub file: String,
    pub bytes: u64,
    /// Always `bvh` (a glTF inspection has no `format`).
    pub format: &'static str,
    /// Joints with channels.
    pub joints: usize,
    /// End Sites (joints without channels).
    pub end_sites: usize,
    pub root: String,
    /// Values per frame.
    pub channels: usize,
    /// Rotation channel orders (`ZXY` ...), each once.
    pub rotation_orders: Vec<String>,
    pub frames: usize,
    pub frame_time: f64,
    pub duration: f64,
    /// The file's up axis (`Y` by the format's convention; `Z` as Blender and 3ds Max write).
    pub up: String,
    /// What `blend` finds in the clip alone.
    pub blend: GaitInfo,
}

/// Inspect the BVH file at `path`.
pub fn inspect(path: &Path) -> Result<BvhInspection> {
    let bvh = load_bvh(path)?;
    let (joints, end_sites) = bvh.joint_counts();
    let frames = bvh.clip.channels.first().map_or(0, |c| c.times.len());
    let blend = GaitInfo::of(gait(&bvh.rig, &bvh.clip));
    Ok(BvhInspection {
        file: path.display().to_string(),
        bytes: std::fs::metadata(path).map_or(0, |m| m.len()),
        format: "bvh",
        joints,
        end_sites,
        root: bvh.rig.names[bvh.rig.root].clone(),
        channels: bvh.channels_per_frame(),
        rotation_orders: bvh.rotation_orders(),
        frames,
        frame_time: bvh.frame_time,
        duration: bvh.clip.duration(),
        up: bvh.up_axis(),
        blend,
    })
}

/// The rate of frames `frame_time` apart as inspect shows it: a whole or NTSC rate exactly
/// ("120", "30000/1001"), another to two places.
fn rate_shown(frame_time: f64) -> String {
    let rate = crate::tween::typed_rate(1.0 / frame_time);
    match crate::tween::rate_text(rate) {
        ntsc if ntsc.contains('/') => ntsc,
        _ if (rate - rate.round()).abs() < 1e-9 => format!("{}", rate.round()),
        _ => format!("{rate:.2}"),
    }
}

/// The inspection as text for a person.
pub fn text(i: &BvhInspection) -> String {
    let mut s = format!("{}: {} bytes, a BVH motion capture\n", i.file, i.bytes);
    s += &format!(
        "skeleton: {} joints and {} End Sites from root {:?}, {} channels a frame, rotations in {} order\n",
        i.joints,
        i.end_sites,
        i.root,
        i.channels,
        i.rotation_orders.join(", ")
    );
    s += &format!(
        "motion: {} frames every {:.6} s ({} a second), {:.3} s\n",
        i.frames,
        i.frame_time,
        rate_shown(i.frame_time),
        i.duration
    );
    s += &match i.up.as_str() {
        "Y" => "up: Y, as BVH is by convention\n".to_string(),
        up => format!("up: {up} (as Blender and 3ds Max write BVH): stood up to Y on read, written back in {up}\n"),
    };
    s += &format!("blend: {}\n", gait_line(&i.blend));
    s
}
