//! The blended clip as a BVH file with the first input's skeleton: its HIERARCHY text as it
//! was (joint names, offsets, channel lists and their order), then MOTION at the input's frame
//! time, the blend resampled on that grid (translations linear, rotations slerped).
//!
//! Each joint's rotation channels (three distinct axes, in any order) get the Euler angles of
//! its local rotation in that order, in degrees (R = R(c1) R(c2) R(c3), as the reader composes
//! them), unwrapped from frame to frame so that no curve jumps by 360; position channels get
//! the local translation's components.

use super::bvh::{Bvh, Dof};
use super::rig::{clip_from_channels, Channel, Interp, Path, Pose};
use anyhow::{bail, Result};
use glam::{DQuat, DVec3, EulerRot};
use std::io::Write;

/// Decimal places of every value written (a thousandth of a millimetre in centimetre units).
const DIGITS: usize = 6;

/// The poses at `times` (seconds from 0, LINEAR between them) sampled every `dt` from 0 to the
/// last time (the last sample at or before it).
pub fn resample(bvh: &Bvh, times: &[f64], poses: &[Pose], dt: f64) -> Vec<Pose> {
    let rig = &bvh.rig;
    let mut channels = Vec::new();
    for j in 0..rig.len() {
        let t: Vec<f64> = poses.iter().flat_map(|p| p.local[j].t.to_array()).collect();
        let r: Vec<f64> = poses.iter().flat_map(|p| p.local[j].r.to_array()).collect();
        for (path, values, width) in [(Path::Translation, t, 3), (Path::Rotation, r, 4)] {
            channels.push(Channel {
                node: j,
                path,
                interp: Interp::Linear,
                times: times.to_vec(),
                values,
                width,
            });
        }
    }
    let clip = clip_from_channels(String::new(), 0, channels);
    let end = times.last().copied().unwrap_or(0.0);
    let count = (end / dt + 1e-6).floor() as usize + 1;
    (0..count).map(|k| clip.pose(rig, k as f64 * dt)).collect()
}

/// The Euler order of every joint with channels of `bvh`, or why its skeleton cannot be
/// written back (checked before any work).
pub fn orders(bvh: &Bvh) -> Result<Vec<Option<EulerRot>>> {
    bvh.dofs
        .iter()
        .map(|(j, list)| euler_order(list, &bvh.rig.names[*j]))
        .collect()
}

/// Write `poses` (one every `bvh.frame_time`) as BVH text with `bvh`'s skeleton and channels.
pub fn write(bvh: &Bvh, poses: &[Pose], out: &mut dyn Write) -> Result<()> {
    let orders = orders(bvh)?;
    let eol = if bvh.header.contains("\r\n") {
        "\r\n"
    } else {
        "\n"
    };
    out.write_all(bvh.header.as_bytes())?;
    write!(out, "MOTION{eol}Frames: {}{eol}", poses.len())?;
    write!(out, "Frame Time: {:.8}{eol}", bvh.frame_time)?;
    let mut previous: Vec<[f64; 3]> = vec![[0.0; 3]; bvh.dofs.len()];
    let mut line = String::new();
    // A capture turned upright on read goes back to the file's own up.
    let back = bvh.turn.inverse();
    for (f, pose) in poses.iter().enumerate() {
        line.clear();
        for (k, (j, list)) in bvh.dofs.iter().enumerate() {
            let mut local = pose.local[*j];
            (local.t, local.r) = (back * local.t, back * local.r * bvh.turn);
            let mut angles = match orders[k] {
                Some(order) => euler(local.r, order),
                None => [0.0; 3],
            };
            for (a, p) in angles.iter_mut().zip(&previous[k]) {
                if f > 0 {
                    *a += 360.0 * ((p - *a) / 360.0).round();
                }
            }
            previous[k] = angles;
            let mut rot = 0;
            for d in list {
                let v = match *d {
                    Dof::Pos(c) => local.t[c],
                    Dof::Rot(_) => {
                        rot += 1;
                        angles[rot - 1]
                    }
                };
                if !line.is_empty() {
                    line.push(' ');
                }
                line += &format!("{v:.DIGITS$}");
            }
        }
        write!(out, "{line}{eol}")?;
    }
    Ok(())
}

/// The Euler order of a joint's rotation channels: `None` without any; three distinct axes
/// otherwise (other layouts are refused, naming the joint).
fn euler_order(list: &[Dof], joint: &str) -> Result<Option<EulerRot>> {
    let axes: Vec<usize> = list
        .iter()
        .filter_map(|d| match d {
            Dof::Rot(a) => Some(if *a == DVec3::X {
                0
            } else if *a == DVec3::Y {
                1
            } else {
                2
            }),
            Dof::Pos(_) => None,
        })
        .collect();
    Ok(Some(match axes[..] {
        [] => return Ok(None),
        [2, 0, 1] => EulerRot::ZXY,
        [2, 1, 0] => EulerRot::ZYX,
        [1, 0, 2] => EulerRot::YXZ,
        [1, 2, 0] => EulerRot::YZX,
        [0, 1, 2] => EulerRot::XYZ,
        [0, 2, 1] => EulerRot::XZY,
        _ => bail!("joint {joint:?} has rotation channels BVH output cannot write (three distinct axes are needed)"),
    }))
}

/// Angles (degrees) of `q` in the intrinsic order `order`.
fn euler(q: DQuat, order: EulerRot) -> [f64; 3] {
    let (a, b, c) = q.to_euler(order);
    [a.to_degrees(), b.to_degrees(), c.to_degrees()]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// glam's intrinsic orders compose as the reader does: R = R(c1) R(c2) R(c3).
    #[test]
    fn euler_angles_rebuild_the_rotation_in_channel_order() {
        let q = DQuat::from_euler(EulerRot::XYZ, 0.3, -1.1, 2.0).normalize();
        let axis = [DVec3::X, DVec3::Y, DVec3::Z];
        for order in [
            [2, 0, 1],
            [2, 1, 0],
            [1, 0, 2],
            [1, 2, 0],
            [0, 1, 2],
            [0, 2, 1],
        ] {
            let list: Vec<Dof> = order.iter().map(|&i| Dof::Rot(axis[i])).collect();
            let e = euler_order(&list, "j").unwrap().unwrap();
            let a = euler(q, e);
            let r = (0..3).fold(DQuat::IDENTITY, |r, k| {
                r * DQuat::from_axis_angle(axis[order[k]], a[k].to_radians())
            });
            assert!(r.dot(q).abs() > 1.0 - 1e-12, "{order:?}: {r} vs {q}");
        }
    }
}
