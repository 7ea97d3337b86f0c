//! `inbetween blend` from file to file: read, pick the clips and their skeleton, blend (once per
//! weight), append the new animations to the glTF document, or write BVH files with the first
//! capture's skeleton; the files (and the report) are staged and appear together.

use super::align::MatchedTravel;
use super::by_name;
use super::cycles::CycleMethod;
use super::plan::{blend, gait, BlendOptions, Blended, Gait, Report};
use super::rig::{self, Clip, Path, Rig};
use crate::gltf::{self, clip_by, listed, listed_or_none, Access, Container, Document};
use crate::output::{Format, Outputs};
use anyhow::{bail, Result};
use std::collections::BTreeSet;
use std::path::PathBuf;

pub struct BlendJob {
    /// One .gltf/.glb with the character and its clips, or two .bvh captures (a clip each).
    pub inputs: Vec<PathBuf>,
    pub output: PathBuf,
    /// Animation names or indices (glTF input).
    pub clips: Option<[String; 2]>,
    /// Weights of B, one blend each (a blend space when there are several).
    pub weights: Vec<f64>,
    /// Name of the new animation (default "A+B"; `@<weight>` added when there are several).
    pub name: Option<String>,
    pub cycles: CycleMethod,
    pub cleanup: bool,
    pub report: Option<PathBuf>,
    /// Where external references of a `.gltf` input may lead besides its own folder.
    pub access: Access,
}

impl BlendJob {
    /// What tells the blend at weight `w` apart: `@<w>` when the job has several weights.
    fn tag(&self, w: f64) -> String {
        match self.weights.len() {
            1 => String::new(),
            _ => format!("@{w}"),
        }
    }

    /// The new animation's name at weight `w`, the clips being named `clips`.
    fn name_at(&self, w: f64, clips: [&str; 2]) -> String {
        let base = (self.name.clone()).unwrap_or_else(|| format!("{}+{}", clips[0], clips[1]));
        format!("{base}{}", self.tag(w))
    }

    /// The blend options at weight `w`.
    fn options(&self, w: f64) -> BlendOptions {
        BlendOptions {
            cycles: self.cycles,
            cleanup: self.cleanup,
            ..BlendOptions::new(w)
        }
    }
}

/// One blend written: the clip's name, the file it is in, and its figures.
pub struct BlendDone {
    pub name: String,
    pub file: PathBuf,
    pub report: Report,
}

pub struct BlendSummary {
    pub blends: Vec<BlendDone>,
    /// What the output does not carry (a USD point cache's), one line each.
    pub warnings: Vec<String>,
}

impl BlendSummary {
    /// One line per blend, and a warning line for each thing the output does not carry.
    pub fn line(&self) -> String {
        let mut lines: Vec<String> = self.blends.iter().map(BlendDone::line).collect();
        lines.extend(self.warnings.iter().map(|w| format!("warning: {w}")));
        lines.join("\n")
    }
}

impl BlendDone {
    fn line(&self) -> String {
        let r = &self.report;
        format!(
            "{}: \"{}\" = {:.2} x \"{}\" + {:.2} x \"{}\": {} frames, {:.3} s{}; planted-foot sliding {:.4} -> {:.4} leg/frame (sources {:.4}, {:.4}; naive blend {:.4})",
            self.file.display(),
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
        ) + &self.travel_note()
    }

    /// What was done where one clip steps in place and the other travels (empty otherwise).
    fn travel_note(&self) -> String {
        let r = &self.report;
        let Some(m) = r.matched_travel else {
            return String::new();
        };
        let speed = m.velocity().length() / r.leg_scale;
        let [a, b] = [&r.clips[0].name, &r.clips[1].name];
        match m {
            MatchedTravel::Along(_) => format!(
                "; \"{b}\" steps in place and \"{a}\" travels: \"{b}\" moved along at its treadmill's {speed:.2} leg/s"
            ),
            MatchedTravel::OnTheSpot(_) => format!(
                "; \"{b}\" travels and \"{a}\" steps in place: \"{b}\" held on the spot (its {speed:.2} leg/s taken away)"
            ),
        }
    }
}

fn find_clip<'a>(doc: &Document, clips: &'a [Clip], key: &str) -> Result<&'a Clip> {
    let named = clips.iter().map(|c| (c.index, c.name.as_str()));
    if let Some(i) = clip_by(key, named).map_err(|e| doc.err(e))? {
        if let Some(c) = clips.iter().find(|c| c.index == i) {
            return Ok(c);
        }
    }
    let names: Vec<String> = clips.iter().map(|c| format!("{:?}", c.name)).collect();
    bail!(doc.err(format!(
        "no animation named {key:?} (it has {})",
        listed_or_none(&names)
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
    let (rig, all) = rig::load_gltf(doc)?;
    let skins = skins_of(doc)?;
    let a = find_clip(doc, &all, &clips[0])?;
    let b = find_clip(doc, &all, &clips[1])?;
    blend_on(doc, rig, &skins, [(doc, a), (doc, b)], opts)
}

/// Clip `key` of `doc` (a name or an index), or its only animation when `key` is None.
fn pick_clip<'a>(doc: &Document, clips: &'a [Clip], key: Option<&String>) -> Result<&'a Clip> {
    match (key, clips) {
        (Some(key), _) => find_clip(doc, clips, key),
        (None, [one]) => Ok(one),
        (None, _) => {
            let names: Vec<String> = clips.iter().map(|c| format!("{:?}", c.name)).collect();
            bail!(doc.err(match names.is_empty() {
                true => "has no animation to blend".to_string(),
                false => format!(
                    "has {} animations ({}): name the one to blend with --clips A B",
                    names.len(),
                    listed(&names)
                ),
            }))
        }
    }
}

/// The animation of `doc_a` (its character) blended with that of `doc_b` (the same character's
/// file, or an export of the animation alone), `clips` naming them where a file has several;
/// `doc_b`'s clip carried onto `doc_a`'s nodes by name ([`by_name::carry`]). Clips of the
/// same name (Mixamo calls every one "mixamo.com") are called by their files' stems.
pub fn blend_files(
    [doc_a, doc_b]: [&Document; 2],
    clips: Option<&[String; 2]>,
    opts: &BlendOptions,
) -> Result<BlendedClips> {
    let (rig, all_a) = rig::load_gltf(doc_a)?;
    let skins = skins_of(doc_a)?;
    let (rig_b, all_b) = rig::load_gltf(doc_b)?;
    let mut a = pick_clip(doc_a, &all_a, clips.map(|c| &c[0]))?.clone();
    let b = pick_clip(doc_b, &all_b, clips.map(|c| &c[1]))?;
    let mut b = by_name::carry(doc_a, &rig, doc_b, &rig_b, b)?;
    if a.name == b.name {
        let stem = |d: &Document| d.path.file_stem().map(|s| s.to_string_lossy().into_owned());
        if let (Some(sa), Some(sb)) = (stem(doc_a), stem(doc_b)) {
            (a.name, b.name) = (sa, sb);
        }
    }
    blend_on(doc_a, rig, &skins, [(doc_a, &a), (doc_b, &b)], opts)
}

/// The skins of `doc` (each a set of joints), refused when there is none.
fn skins_of(doc: &Document) -> Result<Vec<BTreeSet<usize>>> {
    let skins = rig::skins(doc);
    if skins.is_empty() {
        bail!(doc.err("has no skin: blend needs a skinned character"));
    }
    Ok(skins)
}

/// The skin (index in `skins`) whose joints `clip` animates most, the first of as many.
fn skin_of(skins: &[BTreeSet<usize>], clip: &Clip) -> Option<usize> {
    let nodes = skeleton_nodes(clip);
    (0..skins.len())
        .map(|s| (skins[s].intersection(&nodes).count(), usize::MAX - s))
        .max()
        .filter(|&(n, _)| n > 0)
        .map(|(_, s)| usize::MAX - s)
}

/// What `blend` finds in each of `doc`'s clips that animate a skin, alone (for `inspect`):
/// (the animation's index, its [`Gait`] on the skeleton of that skin). Empty for a file
/// without a skin.
pub fn clip_gaits(doc: &Document) -> Result<Vec<(usize, Gait)>> {
    let (rig, clips) = rig::load_gltf(doc)?;
    let skins = rig::skins(doc);
    let mut out = Vec::new();
    for clip in &clips {
        // A clip too long to analyse is left out (blend refuses it, saying so).
        let Some(skin) = skin_of(&skins, clip).filter(|_| check_size(doc, clip).is_ok()) else {
            continue;
        };
        let mut rig = rig.clone();
        rig::use_skin(doc, &mut rig, skin);
        out.push((clip.index, gait(&rig, clip)));
    }
    Ok(out)
}

/// Clips `a` and `b` (each with the document it came from, for messages) blended on `doc`'s
/// character `rig`, its skeleton the one of `skins` whose joints they animate.
fn blend_on(
    doc: &Document,
    mut rig: Rig,
    skins: &[BTreeSet<usize>],
    [(doc_a, a), (doc_b, b)]: [(&Document, &Clip); 2],
    opts: &BlendOptions,
) -> Result<BlendedClips> {
    check_size(doc_a, a)?;
    check_size(doc_b, b)?;
    let nb = skeleton_nodes(b);
    let Some(skin) = skin_of(skins, a) else {
        bail!(doc.err(format!(
            "animation {:?} animates no joint of a skin",
            a.name
        )));
    };
    if skins[skin].intersection(&nb).next().is_none() {
        match skin_of(skins, b) {
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

/// Whether `p` names a BVH file (by its extension, any case): what an output is written as.
pub fn is_bvh(p: &std::path::Path) -> bool {
    p.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("bvh"))
}

/// Whether the input at `p` is a BVH capture: by its extension, or by its first word
/// (HIERARCHY) whatever it is named (`walk.txt`, a download without its extension), so that
/// every command reads a capture as one.
pub fn is_capture(p: &std::path::Path) -> bool {
    if is_bvh(p) {
        return true;
    }
    let mut start = [0u8; 64];
    let read = std::fs::File::open(p)
        .and_then(|mut f| std::io::Read::read(&mut f, &mut start))
        .unwrap_or(0);
    crate::gltf::starts_like_bvh(&start[..read])
}

/// The report file: one blend's report, or the list of them for several weights.
fn stage_report(job: &BlendJob, blends: &[BlendDone], files: &mut Outputs) -> Result<()> {
    let Some(path) = &job.report else {
        return Ok(());
    };
    let json = match blends {
        [one] => serde_json::to_vec_pretty(&one.report)?,
        many => serde_json::to_vec_pretty(&many.iter().map(|b| &b.report).collect::<Vec<_>>())?,
    };
    files.write(path, &json)?;
    Ok(())
}

pub fn run_blend(job: &BlendJob) -> Result<BlendSummary> {
    if job.weights.is_empty() {
        bail!("--weight needs at least one weight");
    }
    if job.name.as_deref().is_some_and(|n| n.trim().is_empty()) {
        bail!(
            "--name names the new animation (got {:?})",
            job.name.as_deref().unwrap_or("")
        );
    }
    if let Some(w) = job.weights.iter().find(|w| !(0.0..=1.0).contains(*w)) {
        bail!("--weight {w} is outside [0, 1]");
    }
    if let Some((i, w)) =
        (job.weights.iter().enumerate()).find(|(i, w)| job.weights[..*i].contains(w))
    {
        bail!(
            "--weight lists {w} twice (at places {} and {})",
            job.weights.iter().position(|x| x == w).unwrap_or(0) + 1,
            i + 1
        );
    }
    let captures: Vec<bool> = job.inputs.iter().map(|p| is_capture(p)).collect();
    if let Some(first) = job.inputs.first() {
        let suffix = if captures[0] {
            "_blend.bvh"
        } else {
            "_blend.glb"
        };
        crate::output::not_a_folder(&job.output, first, suffix)?;
    }
    match (&job.inputs[..], &captures[..]) {
        ([a, b], [true, true]) => run_bvh(job, [a, b]),
        ([input], [false]) => run_gltf(job, &[input]),
        ([a, b], [false, false]) => run_gltf(job, &[a, b]),
        ([a, b], [first, _]) => {
            let (capture, character) = if *first { (a, b) } else { (b, a) };
            bail!(
                "{}: a BVH capture is not blended with a glTF character ({}): blend two .bvh captures, or two .gltf/.glb files of one character",
                capture.display(),
                character.display()
            )
        }
        _ => bail!(
            "{}: blend takes one .gltf or .glb with --clips A B, two of them (a clip each), or two .bvh captures (got {} input{})",
            job.inputs[0].display(),
            job.inputs.len(),
            if job.inputs.len() == 1 { "" } else { "s" }
        ),
    }
}

/// The names of `doc`'s animations (an unnamed one as `animation <index>`).
fn clip_names(doc: &Document) -> Vec<String> {
    let anims = gltf::arr(&doc.json, "animations");
    (anims.iter().enumerate())
        .map(|(a, anim)| gltf::clip_name(anim, a))
        .collect()
}

/// A glTF character's two clips blended at every weight, appended as new animations: two
/// clips of one file, or one clip of each of two files (the first file's character).
fn run_gltf(job: &BlendJob, inputs: &[&PathBuf]) -> Result<BlendSummary> {
    // A folder that is not there is told as such, whatever the extension.
    crate::output::folder_exists(&job.output)?;
    let format = Format::of(&job.output).ok();
    let usd = format.filter(|f| matches!(f, Format::Usda | Format::Usdc | Format::Usdz));
    // A USD output is staged from the glTF the blends make, held as a .glb.
    let Some(container) = format
        .and_then(Container::of)
        .or(usd.map(|_| Container::Glb))
    else {
        bail!(
            "{}: blend writes a glTF character's clips to .gltf or .glb, or a USD point cache (.usda, .usdc, .usdz); .bvh from two .bvh captures",
            job.output.display()
        );
    };
    if inputs.len() == 1 && job.clips.is_none() {
        bail!(
            "{}: --clips A B names the two animations to blend",
            inputs[0].display()
        );
    }
    let docs = (inputs.iter())
        .map(|p| Document::open_with(p, &job.access))
        .collect::<Result<Vec<_>>>()?;
    let mut out = gltf::begin(&docs[0], container, &job.output)?;
    let input = inputs[0].display();
    // A USD output says its own unread images (left out of its materials).
    let unread = out.unread_images.iter().filter(|_| usd.is_none());
    let mut warnings: Vec<String> = (unread.chain(&out.mended))
        .map(|what| format!("{input}: {what}"))
        .collect();
    let mut blends = Vec::new();
    // (animation, times) of each blend.
    let mut appended = Vec::new();
    let taken = clip_names(&docs[0]);
    for &w in &job.weights {
        let opts = job.options(w);
        let BlendedClips {
            rig,
            blended,
            animated,
            names,
        } = match (&docs[..], &job.clips) {
            ([doc], Some(clips)) => blend_clips(doc, clips, &opts)?,
            ([a, b], clips) => blend_files([a, b], clips.as_ref(), &opts)?,
            _ => unreachable!("one input comes with --clips, checked above"),
        };
        let name = job.name_at(w, [&names[0], &names[1]]);
        // In a glTF output the blend sits beside the file's animations, which engines find by
        // name: one of the same name (a blend made before, or --name naming a clip) is not
        // shadowed.
        if usd.is_none() && taken.contains(&name) {
            let hint = match job.name {
                Some(_) => "(--name names the blend: one the file does not use)",
                None => "(a blend made before?): --name NAME names this one otherwise",
            };
            bail!("{input}: already has an animation named {name:?} {hint}");
        }
        let channels = super::write::channels(&rig, &blended.poses, &animated);
        let animation = super::write::append_animation(
            &mut out,
            &name,
            &blended.times,
            &blended.poses,
            &channels,
        );
        appended.push((animation, blended.times.clone()));
        blends.push(BlendDone {
            name,
            file: job.output.clone(),
            report: blended.report,
        });
    }
    let mut files = Outputs::new();
    match usd {
        Some(format) => {
            let left_out = super::write_usd::write(
                out,
                &appended,
                inputs[0],
                &job.output,
                format,
                &job.access,
                &mut files,
            )?;
            warnings.extend(left_out.iter().map(|what| format!("{input}: {what}")));
        }
        None => {
            gltf::stage(out, container, &job.output, &mut files)?;
        }
    }
    stage_report(job, &blends, &mut files)?;
    files.commit()?;
    Ok(BlendSummary { blends, warnings })
}

/// Two captures of one skeleton blended at every weight, each written as BVH with the first
/// capture's hierarchy and channels: to the output, or with several weights to
/// `<output stem>@<weight>.bvh` beside it.
fn run_bvh(job: &BlendJob, inputs: [&PathBuf; 2]) -> Result<BlendSummary> {
    if !is_bvh(&job.output) {
        bail!(
            "{}: two BVH captures are blended into a .bvh output",
            job.output.display()
        );
    }
    if job.clips.is_some() {
        bail!(
            "{}: --clips names animations of a glTF input; each .bvh input is one clip",
            inputs[0].display()
        );
    }
    let mut loaded = Vec::new();
    for p in inputs {
        let mut bvh = super::bvh::load(p)?;
        bvh.clip.name = (p.file_stem().and_then(|s| s.to_str()))
            .unwrap_or("capture")
            .to_owned();
        loaded.push(bvh);
    }
    let (a, b) = (&loaded[0], &loaded[1]);
    if a.rig.parent != b.rig.parent {
        bail!(
            "{} and {} have different skeletons ({} and {} joints, End Sites included): blend needs one skeleton",
            inputs[0].display(),
            inputs[1].display(),
            a.rig.len(),
            b.rig.len()
        );
    }
    super::write_bvh::orders(a).map_err(|e| gltf::at(inputs[0], e))?;
    let mut files = Outputs::new();
    let mut blends = Vec::new();
    for &w in &job.weights {
        let opts = job.options(w);
        let blended = blend(&a.rig, &a.clip, &b.clip, &opts).map_err(|e| gltf::at(inputs[0], e))?;
        let poses = super::write_bvh::resample(a, &blended.times, &blended.poses, a.frame_time);
        let file = match job.tag(w) {
            tag if tag.is_empty() => job.output.clone(),
            tag => {
                let stem = job.output.file_stem().and_then(|s| s.to_str());
                job.output
                    .with_file_name(format!("{}{tag}.bvh", stem.unwrap_or("blend")))
            }
        };
        files.write_with(&file, |out| super::write_bvh::write(a, &poses, out))?;
        blends.push(BlendDone {
            name: job.name_at(w, [&a.clip.name, &b.clip.name]),
            file,
            report: blended.report,
        });
    }
    stage_report(job, &blends, &mut files)?;
    files.commit()?;
    Ok(BlendSummary {
        blends,
        warnings: Vec::new(),
    })
}
