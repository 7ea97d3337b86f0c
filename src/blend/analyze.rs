//! Everything blend learns from the source clips before it mixes them: whether each loops, the
//! legs, contacts per foot, and the gait cycles.

use super::contacts::{self, Contact};
use super::cycles::{self, CycleMethod, Cycles};
use super::legs::{self, Leg};
use super::rig::{Clip, Rig};
use super::track::{self, Track};
use glam::DVec3;

/// The character as the clips show it.
pub struct Character {
    pub legs: Vec<Leg>,
    pub forward: DVec3,
    /// Height span of the skeleton in the rest pose.
    pub size: f64,
    /// Leg scale for every tolerance and figure: the longest leg (half the size without legs).
    pub scale: f64,
}

/// One clip, analysed.
pub struct Analysis {
    pub track: Track,
    /// Contacts per leg (same order as `Character::legs`).
    pub contacts: Vec<Vec<Contact>>,
    pub cycles: Option<Cycles>,
    /// Largest forward-and-back travel of a foot relative to the root, in leg lengths.
    pub stride: f64,
}

impl Analysis {
    pub fn looping(&self) -> bool {
        self.track.looping
    }

    /// Whether leg `leg` is planted within `half` seconds of time `t` of the clip.
    pub fn planted(&self, leg: usize, t: f64, half: f64) -> bool {
        let period = self
            .track
            .looping
            .then(|| (self.track.start, self.track.duration()));
        contacts::planted(&self.contacts[leg], t, half, period)
    }
}

pub fn analyze(rig: &Rig, clips: &[&Clip], method: CycleMethod) -> (Character, Vec<Analysis>) {
    let size = track::character_size(rig, clips);
    let tracks: Vec<Track> = clips
        .iter()
        .map(|c| Track::new(rig, c, track::loops(rig, c, size)))
        .collect();
    let refs: Vec<&Track> = tracks.iter().collect();
    let (legs, forward) = legs::find(rig, &refs, size);
    let scale = legs
        .iter()
        .map(|l| l.length)
        .fold(0.0, f64::max)
        .max(0.05 * size);
    let analyses = tracks
        .into_iter()
        .map(|track| {
            let contacts = legs
                .iter()
                .map(|l| contacts::intervals(&track, &contacts::flags(&track, l, scale)))
                .collect();
            let stride = legs
                .iter()
                .map(|l| {
                    let along = track
                        .pos
                        .iter()
                        .map(|p| (p[l.end()] - p[rig.body]).dot(forward) / scale);
                    let (lo, hi) =
                        along.fold((f64::MAX, f64::MIN), |(lo, hi), x| (lo.min(x), hi.max(x)));
                    (hi - lo).max(0.0)
                })
                .fold(0.0, f64::max);
            let cycles = cycles::detect(method, &track, rig.body, &legs, forward, scale)
                .filter(|_| stride >= cycles::MIN_STRIDE);
            Analysis {
                track,
                contacts,
                cycles,
                stride,
            }
        })
        .collect();
    (
        Character {
            legs,
            forward,
            size,
            scale,
        },
        analyses,
    )
}
