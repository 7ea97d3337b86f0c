//! Everything blend learns from the source clips before it mixes them: whether each loops, the
//! legs, contacts per foot, and the gait cycles.

use super::contacts::{self, Contact};
use super::cycles::{self, CycleMethod, Cycles};
use super::legs::{self, Leg};
use super::measure::{self, Travel};
use super::rig::{Clip, Rig};
use super::track::{self, Track};
use glam::DVec3;

/// A clip travelling over the ground more than this many leg lengths a second heads the way it
/// travels (its root's travel, or against the ground its feet push back in place); one slower
/// (an idle, a T-pose) heads as the clips' feet do together ([`legs::forward`]). Walks and runs
/// travel 1-3 leg lengths a second. Each clip heading its own way, its gait analysis is the
/// same however it is turned; with one direction found from both clips' feet, a pair heading
/// apart cancelled: the CMU run turned half round (through a still root above its hips)
/// blended with the walk to jerk ratios 0.76 / 0.63 / 0.63 against 0.51 / 0.51 / 0.55 as
/// captured.
pub const HEADS: f64 = 0.05;

/// The character as the clips show it.
pub struct Character {
    pub legs: Vec<Leg>,
    /// The first clip's forward direction: the blend's, turned onto it.
    pub forward: DVec3,
    /// Height span of the skeleton in the rest pose.
    pub size: f64,
    /// Leg scale for every tolerance and figure: the longest leg (half the size without legs).
    pub scale: f64,
}

/// One clip, analysed.
pub struct Analysis {
    pub track: Track,
    /// Where each foot touches the floor (same order as `Character::legs`; the contact test's
    /// [`contacts::flags`]): the events the blend's phase is matched on.
    pub touches: Vec<Vec<Contact>>,
    /// Where each foot stands planted: its touches settled ([`contacts::settle`]), where the
    /// clean-up pins it and the figures measure its sliding.
    pub contacts: Vec<Vec<Contact>>,
    pub cycles: Option<Cycles>,
    /// Largest forward-and-back travel of a foot relative to the root, in leg lengths.
    pub stride: f64,
    /// How the clip travels (its heading, [`HEADS`], and how the blend matches the clips'
    /// travel come from it).
    pub travel: Travel,
    /// Judged a loop, the clip is a capture whose ends meet by chance
    /// ([`cycles::meet_by_chance`]): to be analysed again as it is, not looping.
    pub meets_by_chance: bool,
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
    analyze_as(rig, clips, method, &vec![false; clips.len()])
}

/// [`analyze`], the clips marked in `open` taken as they are, not looping, whether or not their
/// ends meet.
pub fn analyze_as(
    rig: &Rig,
    clips: &[&Clip],
    method: CycleMethod,
    open: &[bool],
) -> (Character, Vec<Analysis>) {
    let size = track::character_size(rig, clips);
    let tracks: Vec<Track> = (clips.iter().zip(open))
        .map(|(c, &open)| Track::new(rig, c, !open && track::loops(rig, c, size)))
        .collect();
    let refs: Vec<&Track> = tracks.iter().collect();
    let legs = legs::find(rig, &refs, size);
    let scale = legs
        .iter()
        .map(|l| l.length)
        .fold(0.0, f64::max)
        .max(0.05 * size);
    let together = legs::forward(rig, &legs, &refs);
    // Per clip and leg, the contact test's flags: how the clip travels, its touches and (settled)
    // its contacts.
    let flags: Vec<Vec<Vec<bool>>> = (tracks.iter())
        .map(|t| {
            (legs.iter())
                .map(|l| contacts::flags(t, l, scale))
                .collect()
        })
        .collect();
    let travels: Vec<Travel> = (tracks.iter().zip(&flags))
        .map(|(t, f)| measure::travel(t, rig.body, &legs, f))
        .collect();
    let ends: Vec<usize> = legs.iter().map(Leg::end).collect();
    let forwards: Vec<DVec3> = (travels.iter())
        .map(|travel| {
            let over_ground = travel.root - travel.ground;
            if over_ground.length() > HEADS * scale {
                over_ground.normalize()
            } else {
                together
            }
        })
        .collect();
    // Each frame's way (a turning clip's turns), the sides judged at the first clip's first
    // frame as it heads there: judged along a mean way, a walk turning 225 degrees had its left
    // foot on the right.
    let heads: Vec<Vec<DVec3>> = (tracks.iter().zip(&forwards))
        .map(|(t, &f)| contacts::heads(t, rig.body, scale, f))
        .collect();
    let legs = legs::sided(legs, &tracks[0].pos[0], heads[0][0], size);
    let analyses = tracks
        .into_iter()
        .zip(forwards.iter().zip(travels).zip(flags.iter().zip(&heads)))
        .map(|(track, ((&forward, travel), (flags, heads)))| {
            // The legs' flags in their sided order.
            let (touches, contacts) = legs
                .iter()
                .map(|l| {
                    let k = ends.iter().position(|&e| e == l.end()).expect("a leg");
                    let mut planted = flags[k].clone();
                    contacts::settle(&track, l, scale, &mut planted);
                    (
                        contacts::intervals(&track, &flags[k]),
                        contacts::intervals(&track, &planted),
                    )
                })
                .unzip();
            let stride = legs
                .iter()
                .map(|l| {
                    let along = (track.pos.iter().zip(heads))
                        .map(|(p, h)| (p[l.end()] - p[rig.body]).dot(*h) / scale);
                    let (lo, hi) =
                        along.fold((f64::MAX, f64::MIN), |(lo, hi), x| (lo.min(x), hi.max(x)));
                    (hi - lo).max(0.0)
                })
                .fold(0.0, f64::max);
            let cycles = cycles::detect(method, &track, rig.body, &legs, forward, heads, scale)
                .filter(|_| stride >= cycles::MIN_STRIDE);
            let tolerance = track::LOOP_TOLERANCE * size;
            let meets_by_chance = cycles.as_ref().is_some_and(|c| {
                cycles::meet_by_chance(&track, c, rig.body, &legs, forward, scale, tolerance)
            });
            Analysis {
                track,
                touches,
                contacts,
                cycles,
                stride,
                travel,
                meets_by_chance,
            }
        })
        .collect();
    (
        Character {
            legs,
            forward: forwards[0],
            size,
            scale,
        },
        analyses,
    )
}
