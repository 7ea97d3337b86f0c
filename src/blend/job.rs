//! `inbetween blend` from file to file: read, pick the clips and their skeleton, blend, append
//! the new animation, write the document (atomically) and the report.

use super::cycles::CycleMethod;
use super::plan::{blend, BlendOptions, Blended, Report};
use super::rig::{self, Clip, Path, Rig};
use crate::gltf::{self, Access, Container, Document};
use crate::output::{Format, Outputs};
use anyhow::{bail, Result};
use std::collections::BTreeSet;
use std::path::PathBuf;

pub struct BlendJob {
    pub input: PathBuf,
    pub output: PathBuf,
    /// Animation names or indices.
    pub clips: [String; 2],
    pub weight: f64,
    /// Name of the new animation (default "A+B").
    pub name: Option<String>,
    pub cycles: CycleMethod,
    pub cleanup: bool,
    pub report: Option<PathBuf>,
    /// Where external references of a `.gltf` input may lead besides its own folder.
    pub access: Access,
}

pub struct BlendSummary {
    pub name: String,
    pub report: Report,
}

impl BlendSummary {
    pub fn line(&self, job: &BlendJob) -> String {
        let r = &self.report;
        format!(
            "{}: \"{}\" = {:.2} x \"{}\" + {:.2} x \"{}\": {} frames, {:.3} s{}; planted-foot sliding {:.4} -> {:.4} leg/frame (sources {:.4}, {:.4}; naive blend {:.4})",
            job.output.display(),
            self.name,
            1.0 - r.weight,
            r.clips[0].name,
            r.weight,
            r.clips[1].name,
            r.result.frames,
            r.result.duration,
            if r.result.looping { ", loops" } else { "" },
            r.result.before_cleanup.sliding.mean,
            r.result.after_cleanup.sliding.mean,
            r.clips[0].figures.sliding.mean,
            r.clips[1].figures.sliding.mean,
            r.naive.sliding.mean,
        )
    }
}

fn find_clip<'a>(doc: &Document, clips: &'a [Clip], key: &str) -> Result<&'a Clip> {
    if let Some(c) = clips.iter().find(|c| c.name == key) {
        return Ok(c);
    }
    if let Some(c) = key.parse::<usize>().ok().and_then(|i| clips.get(i)) {
        return Ok(c);
    }
    let names: Vec<String> = clips.iter().map(|c| format!("{:?}", c.name)).collect();
    bail!(doc.err(format!(
        "no animation named {key:?} (it has {})",
        if names.is_empty() {
            "none".to_string()
        } else {
            names.join(", ")
        }
    )))
}

/// Most samples of a clip that blend analyses (at its key rate, at least
/// [`MIN_RATE`](super::track::MIN_RATE)): 2.3 hours of capture at 120 per second.
const MAX_SAMPLES: f64 = 1e6;

/// Refuse a clip whose duration and key rate would need more than [`MAX_SAMPLES`] samples.
fn check_size(doc: &Document, clip: &Clip) -> Result<()> {
    let rate = clip.key_rate.max(super::track::MIN_RATE);
    let samples = clip.duration() * rate;
    if samples > MAX_SAMPLES {
        bail!(doc.err(format!(
            "animation {:?} lasts {:.6} s at {:.1} keys per second: more than {MAX_SAMPLES} samples to analyse",
            clip.name,
            clip.duration(),
            rate
        )));
    }
    Ok(())
}

fn skeleton_nodes(clip: &Clip) -> BTreeSet<usize> {
    clip.channels
        .iter()
        .filter(|c| c.path != Path::Weights)
        .map(|c| c.node)
        .collect()
}

/// Two clips of a document's character, blended: the rig (skeleton of their skin marked), the
/// blended clip, and every (node, property) either source animates.
pub struct BlendedClips {
    pub rig: Rig,
    pub blended: Blended,
    pub animated: BTreeSet<(usize, Path)>,
    /// The clips' names.
    pub names: [String; 2],
}

/// Blend clips `clips` (names or indices) of `doc`'s character with `opts`: the skeleton they
/// share found from the skins, everything checked first.
pub fn blend_clips(
    doc: &Document,
    clips: &[String; 2],
    opts: &BlendOptions,
) -> Result<BlendedClips> {
    let (mut rig, all) = rig::load_gltf(doc)?;
    let skins = rig::skins(doc);
    if skins.is_empty() {
        bail!(doc.err("has no skin: blend needs a skinned character"));
    }
    let a = find_clip(doc, &all, &clips[0])?;
    let b = find_clip(doc, &all, &clips[1])?;
    for clip in [a, b] {
        check_size(doc, clip)?;
    }
    let (na, nb) = (skeleton_nodes(a), skeleton_nodes(b));
    let best = |nodes: &BTreeSet<usize>| {
        (0..skins.len())
            .map(|s| (skins[s].intersection(nodes).count(), usize::MAX - s))
            .max()
            .filter(|&(n, _)| n > 0)
            .map(|(_, s)| usize::MAX - s)
    };
    let Some(skin) = best(&na) else {
        bail!(doc.err(format!(
            "animation {:?} animates no joint of a skin",
            a.name
        )));
    };
    if skins[skin].intersection(&nb).next().is_none() {
        match best(&nb) {
            Some(other) => bail!(doc.err(format!(
                "animations {:?} and {:?} animate different skeletons (skins {skin} and {other})",
                a.name, b.name
            ))),
            None => bail!(doc.err(format!(
                "animation {:?} animates no joint of a skin",
                b.name
            ))),
        }
    }
    rig::use_skin(doc, &mut rig, skin);
    let blended = blend(&rig, a, b, opts).map_err(|e| doc.err(e))?;
    Ok(BlendedClips {
        animated: a.animated().union(&b.animated()).copied().collect(),
        names: [a.name.clone(), b.name.clone()],
        rig,
        blended,
    })
}

pub fn run_blend(job: &BlendJob) -> Result<BlendSummary> {
    let Some(container) = Container::of(Format::of(&job.output)?) else {
        bail!(
            "{}: blend writes .gltf or .glb (a skeletal clip has no USD point-cache form here)",
            job.output.display()
        );
    };
    if !(0.0..=1.0).contains(&job.weight) {
        bail!("--weight {} is outside [0, 1]", job.weight);
    }
    let doc = Document::open_with(&job.input, &job.access)?;
    let opts = BlendOptions {
        cycles: job.cycles,
        cleanup: job.cleanup,
        ..BlendOptions::new(job.weight)
    };
    let BlendedClips {
        rig,
        blended,
        animated,
        names,
    } = blend_clips(&doc, &job.clips, &opts)?;
    let name = job
        .name
        .clone()
        .unwrap_or_else(|| format!("{}+{}", names[0], names[1]));
    let channels = super::write::channels(&rig, &blended.poses, &animated);
    let mut out = gltf::begin(&doc, container, &job.output)?;
    super::write::append_animation(&mut out, &name, &blended.times, &blended.poses, &channels);
    let mut files = Outputs::new();
    gltf::stage(out, container, &job.output, &mut files)?;
    if let Some(path) = &job.report {
        files.write(path, &serde_json::to_vec_pretty(&blended.report)?)?;
    }
    files.commit()?;
    Ok(BlendSummary {
        name,
        report: blended.report,
    })
}
