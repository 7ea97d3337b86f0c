//! The command line: clap's structs, the choices it offers, and their conversion into the
//! library's jobs. Defaults live in the library (`Default` of each option type) and are read
//! from there.

use clap::{Args, Parser, Subcommand, ValueEnum};
use inbetween::blend::{BlendJob, CycleMethod};
use inbetween::gltf::Access;
use inbetween::preview;
use inbetween::tween::{
    typed_rate, Basis, CompactOptions, KeySource, Layout, Method, Timing, TweenJob,
    DEFAULT_TOLERANCE,
};
use std::path::PathBuf;

#[derive(Parser)]
#[command(
    name = "inbetween",
    version,
    about = "Tween frames for glTF morph keyframes by the deformation-gradient method.",
    long_about = "inbetween reads a glTF whose morph targets (or weights animation) are keyframe poses and \
writes the in-between frames, computed per triangle (polar decomposition, rotation slerp, linear stretch) \
and solved for the vertices, instead of by linear vertex blending. Everything else in the file is kept."
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand)]
pub enum Command {
    /// Write tween frames between a mesh's morph keyframes as dense morph animation.
    #[command(
        after_help = "Examples:\n  inbetween tween samples/bar_twist.glb -o bar_tween.glb\n  \
inbetween tween flag.gltf -o flag_30fps.glb --fps 30\n  inbetween tween in.glb -o lerp.glb --method linear --tweens 9"
    )]
    Tween(TweenArgs),
    /// Blend two skeletal clips of a character into a new clip (walk + run = jog): cycles found
    /// and synchronised on foot contacts, the second clip aligned to the first (and made to
    /// travel as it does where one steps in place and the other has root motion), joints
    /// slerped, planted feet cleaned up with two-bone IK. A glTF output is the input plus one
    /// animation per weight; two BVH captures give a BVH file.
    #[command(
        after_help = "Examples:\n  inbetween blend Fox.glb -o fox_trot.glb --clips Walk Run\n  \
inbetween blend robot.glb -o jog.glb --clips Walking Running --weight 0.3 --name Jog --report jog.json\n  \
inbetween blend Fox.glb -o fox_space.glb --clips Walk Run --weight 0,0.25,0.5,0.75,1\n  \
inbetween blend walk.glb run.glb -o jog.glb\n  inbetween blend walk.bvh run.bvh -o jog.bvh"
    )]
    Blend(BlendArgs),
    /// Show what inbetween finds in a file: morph meshes and their targets, animations (keys,
    /// key rate, duration), what `tween` would write with its defaults (frames, new targets,
    /// bytes), the skinned clips `blend` can mix (each with the feet, stride and cycles it finds
    /// in it, or why it refuses it), and the extensions with whether they are decoded; for a BVH
    /// capture, its skeleton, frames, up axis, and the feet, stride and
    /// cycles `blend` finds (or why it refuses the clip).
    #[command(
        after_help = "Examples:\n  inbetween inspect Flamingo.glb\n  inbetween inspect face.glb --json\n  inbetween inspect walk.bvh"
    )]
    Inspect(InspectArgs),
    /// Draw a contact sheet (PNG) of a mesh's frames: one band per method (labelled), frames
    /// across in time order with keys marked, every cell from the same orthographic camera
    /// fitted to the whole animation; for a character without morph keys (a blend output), one
    /// band per skeletal clip as it plays, for a BVH capture its bones; optionally the frames as
    /// an animated GIF or APNG.
    #[command(
        after_help = "Examples:\n  inbetween preview samples/tube_bend.glb -o sheet.png --methods linear,seed,spline\n  \
inbetween preview Flamingo.glb -o fl.png --frames 8 --animate fl.gif\n  inbetween preview tween_out.glb -o out.png\n  \
inbetween blend Fox.glb --clips Walk Run -o jog.glb\n  inbetween preview jog.glb -o jog.png --animation Walk+Run --animate jog.gif"
    )]
    Preview(PreviewArgs),
    /// Hold-out accuracy: keep every K-th key, predict the dropped ones with each method, and
    /// print the RMS vertex error over the bounding-box diagonal (mean and max) per method.
    Eval(EvalArgs),
    /// Print speed figures on generated meshes (set-up, per-frame time, throughput, memory),
    /// side by side with the numpy/scipy peer when python3 with numpy and scipy is available.
    Bench(BenchArgs),
}

/// `--method`.
#[derive(Clone, Copy, ValueEnum)]
pub enum MethodArg {
    /// The seed paper's method: polar decomposition, slerp, linear stretch, Poisson solve.
    Seed,
    /// Vertex lerp between consecutive keys (BlendShape baseline).
    Linear,
    /// C1 spline across all keys in gradient space (rotation logs and stretches by cubic Hermite
    /// with C2-spline tangents, same solve; each component turns about its pivot). The default.
    Spline,
}

impl From<Method> for MethodArg {
    fn from(m: Method) -> MethodArg {
        match m {
            Method::Seed => MethodArg::Seed,
            Method::Linear => MethodArg::Linear,
            Method::Spline => MethodArg::Spline,
        }
    }
}

impl From<MethodArg> for Method {
    fn from(m: MethodArg) -> Method {
        match m {
            MethodArg::Seed => Method::Seed,
            MethodArg::Linear => Method::Linear,
            MethodArg::Spline => Method::Spline,
        }
    }
}

/// `--layout`.
#[derive(Clone, Copy, ValueEnum)]
pub enum LayoutArg {
    /// Authored targets kept; frames between keys added as targets (keys not stored twice).
    Rig,
    /// One target per frame, the authored targets replaced.
    Frames,
}

impl From<Layout> for LayoutArg {
    fn from(l: Layout) -> LayoutArg {
        match l {
            Layout::Rig => LayoutArg::Rig,
            Layout::Frames => LayoutArg::Frames,
        }
    }
}

impl From<LayoutArg> for Layout {
    fn from(l: LayoutArg) -> Layout {
        match l {
            LayoutArg::Rig => Layout::Rig,
            LayoutArg::Frames => Layout::Frames,
        }
    }
}

/// `--keys`.
#[derive(Clone, Copy, ValueEnum)]
pub enum KeysArg {
    /// `animation` for meshes whose weights the file animates (a morph mesh beside them that no
    /// clip animates keeps its pose); `targets` when no clip animates weights or moves a node
    /// (beside a character's skeletal clips, morph targets are blend shapes, not keys).
    Auto,
    /// Key 0 = base mesh, key k = base + target k at weight 1; key times 0, 1, 2, ... s.
    Targets,
    /// The key times of the weights channel that animates the mesh's node.
    Animation,
}

impl From<KeySource> for KeysArg {
    fn from(k: KeySource) -> KeysArg {
        match k {
            KeySource::Auto => KeysArg::Auto,
            KeySource::Targets => KeysArg::Targets,
            KeySource::Animation => KeysArg::Animation,
        }
    }
}

impl From<KeysArg> for KeySource {
    fn from(k: KeysArg) -> KeySource {
        match k {
            KeysArg::Auto => KeySource::Auto,
            KeysArg::Targets => KeySource::Targets,
            KeysArg::Animation => KeySource::Animation,
        }
    }
}

/// `--cycles`.
#[derive(Clone, Copy, ValueEnum)]
pub enum CyclesArg {
    /// From each foot's forward offset and touchdowns: any rig (feet found from the skeleton).
    Legs,
    /// The seed paper's angle between the thighs (bipeds).
    Thigh,
    /// No cycles: each clip whole, on normalised time (for clips that do not walk: the pair is
    /// refused otherwise).
    None,
}

impl From<CycleMethod> for CyclesArg {
    fn from(c: CycleMethod) -> CyclesArg {
        match c {
            CycleMethod::Legs => CyclesArg::Legs,
            CycleMethod::Thigh => CyclesArg::Thigh,
            CycleMethod::None => CyclesArg::None,
        }
    }
}

impl From<CyclesArg> for CycleMethod {
    fn from(c: CyclesArg) -> CycleMethod {
        match c {
            CyclesArg::Legs => CycleMethod::Legs,
            CyclesArg::Thigh => CycleMethod::Thigh,
            CyclesArg::None => CycleMethod::None,
        }
    }
}

/// Where frames lie in time (`tween` and `preview`).
#[derive(Args)]
pub struct TimingArgs {
    /// Frames per second between keys [default: 30]: every key is kept as it is, the gap
    /// between two keys gets round(gap x RATE) - 1 evenly spaced frames, and keys already
    /// closer than 1/RATE s get none (a clip baked at 30 or 60 samples a second stays as it
    /// is). Keys on a 1/10, 1/15 or 1/30 s grid give frames exactly on the 30 per second grid.
    /// A rate is a number or a fraction (24000/1001; 23.976, 29.97 and 59.94 are read as the
    /// NTSC rates they stand for).
    #[arg(long, value_name = "RATE", conflicts_with_all = ["tweens", "fps"], allow_negative_numbers = true, value_parser = per_second)]
    rate: Option<f64>,
    /// Instead: exactly N frames inserted evenly between each pair of consecutive keys.
    #[arg(
        long,
        value_name = "N",
        conflicts_with = "fps",
        allow_negative_numbers = true
    )]
    tweens: Option<usize>,
    /// Instead: frames at this fixed rate (per second) from the first key over the keys' time
    /// span; the first and the last key are always frames, keys between them only where the
    /// grid meets them. A number or a fraction, as --rate.
    #[arg(long, value_name = "FPS", allow_negative_numbers = true, value_parser = per_second)]
    fps: Option<f64>,
    /// Close every key sequence into a loop (append its first key after the last) and let
    /// `spline` wrap around it. Without it, tracks whose last key equals the first wrap.
    #[arg(long = "loop", conflicts_with = "no_loop")]
    looping: bool,
    /// Never wrap `spline` around the ends, even when the last key equals the first.
    #[arg(long)]
    no_loop: bool,
    /// Seconds to continue the motion before the first key (the seed paper's exaggeration).
    #[arg(
        long,
        value_name = "SECONDS",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    extend_before: f64,
    /// Seconds to continue the motion after the last key.
    #[arg(
        long,
        value_name = "SECONDS",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    extend_after: f64,
}

/// A rate given as a number (`30`; `29.97`, `23.976` and `59.94` read as the NTSC rates they
/// stand for) or as a fraction of two (`30000/1001`): its value, whatever its sign (the
/// timing's own check refuses what a run cannot use, in the words it uses for both forms).
fn per_second(text: &str) -> Result<f64, String> {
    let number = |t: &str| {
        t.trim().parse::<f64>().map_err(|e| {
            format!("{e} (a rate is a number such as 30 or a fraction such as 30000/1001)")
        })
    };
    match text.split_once('/') {
        Some((n, d)) => Ok(number(n)? / number(d)?),
        None => Ok(typed_rate(number(text)?)),
    }
}

impl TimingArgs {
    /// `Some(true)`: --loop; `Some(false)`: --no-loop; `None`: tracks whose last key equals the
    /// first wrap.
    fn looping(&self) -> Option<bool> {
        match (self.looping, self.no_loop) {
            (true, _) => Some(true),
            (_, true) => Some(false),
            _ => None,
        }
    }

    fn timing(&self) -> Timing {
        match (self.fps, self.tweens, self.rate) {
            (Some(f), _, _) => Timing::Fps(f),
            (_, Some(n), _) => Timing::Tweens(n),
            (_, _, Some(r)) => Timing::Rate(r),
            _ => Timing::default(),
        }
    }
}

#[derive(Args)]
pub struct TweenArgs {
    /// Input .gltf (embedded or external buffers) or .glb (.vrm too: a GLB).
    input: PathBuf,
    /// Output file; the format follows the extension (.glb or .vrm, .gltf, .usda, .usdc or
    /// .usdz). A USD output carries the materials as UsdPreviewSurface, their PNG and JPEG
    /// textures written beside a .usda/.usdc as <stem>_<image>.png|jpg or packed inside a .usdz.
    #[arg(short, long)]
    output: PathBuf,
    #[command(flatten)]
    timing: TimingArgs,
    /// How a glTF output carries the frames. `rig`: the authored morph targets stay (names,
    /// other animations driving them); keys are played by the authored weights and only the
    /// frames between keys get targets of their own (a target that moves positions without
    /// NORMAL deltas is given those of its shape, so keys shade as the frames between them).
    /// `frames`: one target per frame, keys included, replacing the authored targets.
    #[arg(long, value_enum, default_value_t = Layout::default().into())]
    layout: LayoutArg,
    /// Write the smallest glTF whose every frame is within --tolerance of the dense frames: a
    /// basis of few targets (truncated SVD; authored targets kept in the rig layout count
    /// towards it), quantized deltas with their scale in the weights (KHR_mesh_quantization),
    /// sparse accessors where they pay, and EXT_meshopt_compression of every view. Each part
    /// alone: --basis, --quantize, --sparse, --meshopt. A USD output is already written in
    /// the smallest encoding usd-core reads (a .usdc crate file the size usd-core writes):
    /// --compact changes nothing there.
    #[arg(long)]
    compact: bool,
    /// With --compact or its parts: RMS deviation per frame (and primitive) allowed, relative
    /// to the bounding-box diagonal (no vertex more than 3x it; normals within 100x it; with
    /// meshopt, texture coordinates within 1x it of their values) [default: 1e-4].
    #[arg(long, value_name = "T", allow_negative_numbers = true)]
    tolerance: Option<f64>,
    /// Basis targets: `auto` (as few as the tolerance allows; the default of --compact), a
    /// number (at most that many: engines that blend few targets at a time), or `off`.
    #[arg(long, value_name = "K|auto|off")]
    basis: Option<String>,
    /// Store new targets as normalized SHORT/BYTE with their scale in the weights (with
    /// --meshopt too: authored targets whose values lie in [-1, 1] where the step fits, and
    /// the processed meshes' own normals and tangents through the octahedral filter).
    #[arg(long)]
    quantize: bool,
    /// Store targets that move part of the mesh as sparse accessors.
    #[arg(long)]
    sparse: bool,
    /// Compress vertex, index, target and animation data with EXT_meshopt_compression: the
    /// processed primitives' vertices renumbered in the order their triangles use them and
    /// the triangles in vertex-cache order (alpha-blended ones keep their order), as gltfpack
    /// does; float targets, the weights animation and the meshes' own positions, normals,
    /// tangents and texture coordinates through its exponential filter, within the tolerance.
    /// Readers need the extension (three.js and Babylon.js with their meshopt decoders,
    /// gltfpack, glTF-Transform); Blender's importer, assimp and tinygltf refuse it: for them,
    /// --basis auto --quantize.
    #[arg(long)]
    meshopt: bool,
    /// Interpolation method.
    #[arg(long, value_enum, default_value_t = Method::default().into())]
    method: MethodArg,
    /// Where the keys come from.
    #[arg(long, value_enum, default_value_t = KeySource::default().into())]
    keys: KeysArg,
    /// The animation (name or index) whose weights channel supplies the keys.
    #[arg(long, value_name = "NAME|INDEX")]
    animation: Option<String>,
    /// Worker threads for frames (default: all cores). Output is identical for any value.
    #[arg(long, allow_negative_numbers = true)]
    pub threads: Option<usize>,
    /// Also write per-frame shape figures (edge distortion, area and volume change,
    /// inverted triangles) to this JSON file (schema: schemas/report.schema.json).
    #[arg(long, value_name = "FILE.json")]
    report: Option<PathBuf>,
    /// Also read external buffers and images of a .gltf input under this folder (repeatable).
    /// Without it a .gltf may only refer to files inside its own folder.
    #[arg(long, value_name = "FOLDER")]
    allow_external: Vec<PathBuf>,
    /// No progress bar, no summary.
    #[arg(short, long)]
    pub quiet: bool,
}

impl TweenArgs {
    /// What --compact and its parts ask for (None: a dense output).
    fn compact(&self) -> Result<Option<CompactOptions>, String> {
        let basis = match self.basis.as_deref() {
            None => None,
            Some("auto") => Some(Basis::Auto),
            Some("off") => Some(Basis::Off),
            Some(k) => Some(Basis::Count(k.parse().map_err(|_| {
                format!("--basis takes a number, auto or off (got {k:?})")
            })?)),
        };
        if !(self.compact || basis.is_some() || self.quantize || self.sparse || self.meshopt) {
            return Ok(None);
        }
        let tolerance = self.tolerance.unwrap_or(DEFAULT_TOLERANCE);
        if !(tolerance.is_finite() && tolerance > 0.0) {
            return Err(format!(
                "--tolerance must be a positive number (got {tolerance})"
            ));
        }
        let all = self.compact;
        Ok(Some(CompactOptions {
            tolerance,
            basis: basis.unwrap_or(if all { Basis::Auto } else { Basis::Off }),
            quantize: all || self.quantize,
            sparse: all || self.sparse,
            meshopt: all || self.meshopt,
        }))
    }

    pub fn job(self) -> Result<TweenJob, String> {
        let compact = self.compact()?;
        Ok(TweenJob {
            input: self.input,
            output: self.output,
            method: self.method.into(),
            keys: self.keys.into(),
            animation: self.animation,
            timing: self.timing.timing(),
            layout: self.layout.into(),
            compact,
            quiet: self.quiet,
            looping: self.timing.looping(),
            extend: [self.timing.extend_before, self.timing.extend_after],
            report: self.report,
            access: Access {
                roots: self.allow_external,
            },
        })
    }
}

#[derive(Args)]
pub struct PreviewArgs {
    /// Input .gltf or .glb: morph keys (tweened by each method), a tween output (its own
    /// frames: band `file`), or a file without morph keys (a band per clip that moves its
    /// nodes, skins included, as a viewer plays it; with no such clip, its meshes at rest);
    /// or a .bvh motion capture (its skeleton as bones). A character or capture that travels
    /// across the floor is followed by the camera.
    input: PathBuf,
    /// The contact sheet (.png).
    #[arg(short, long)]
    output: PathBuf,
    /// Bands, comma-separated: linear, seed, spline, file (the file's keys as a renderer plays
    /// them). Default: file for a tween output, else linear,spline.
    #[arg(long, value_delimiter = ',', value_name = "LIST")]
    methods: Vec<String>,
    /// Frames across, picked evenly over the frames the timing options give (first and last
    /// always).
    #[arg(long, default_value_t = preview::DEFAULT_FRAMES, allow_negative_numbers = true)]
    frames: usize,
    /// Size of the whole sheet in pixels, WxH (default: 160 x 160 per cell).
    #[arg(long, value_name = "WxH")]
    size: Option<String>,
    /// Camera: front (along -Z), side (along -X), top (down -Y), or auto (the axis along which
    /// the mesh moves least, so the motion lies in the picture).
    #[arg(long, default_value = "auto")]
    view: String,
    /// Normals shaded per triangle (flat) or interpolated (smooth).
    #[arg(long, default_value = "flat")]
    shading: String,
    /// Also write every frame (up to 240) as an animation: .gif, or .png/.apng (APNG).
    #[arg(long, value_name = "FILE")]
    animate: Option<PathBuf>,
    #[command(flatten)]
    timing: TimingArgs,
    /// Where the keys come from.
    #[arg(long, value_enum, default_value_t = KeySource::default().into())]
    keys: KeysArg,
    /// The animation (name or index) whose weights channel supplies the keys; in a file
    /// without morph keys, the one clip drawn.
    #[arg(long, value_name = "NAME|INDEX")]
    animation: Option<String>,
    /// Also read external buffers and images of a .gltf input under this folder (repeatable).
    #[arg(long, value_name = "FOLDER")]
    allow_external: Vec<PathBuf>,
    /// Worker threads (default: all cores). The picture is identical for any value.
    #[arg(long, allow_negative_numbers = true)]
    pub threads: Option<usize>,
    /// No progress bar, no summary.
    #[arg(short, long)]
    pub quiet: bool,
}

impl PreviewArgs {
    pub fn job(self) -> Result<preview::PreviewJob, String> {
        let shown = self
            .methods
            .iter()
            .map(|m| {
                preview::Shown::parse(m.trim()).ok_or_else(|| {
                    format!(
                        "--methods takes linear, seed, spline and file (got {:?})",
                        m.trim()
                    )
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        let size = match &self.size {
            None => None,
            Some(s) => {
                let bad =
                    || format!("--size takes WIDTHxHEIGHT in pixels, e.g. 1600x400 (got {s:?})");
                let (w, h) = s.split_once(['x', 'X']).ok_or_else(bad)?;
                Some((
                    w.trim().parse().map_err(|_| bad())?,
                    h.trim().parse().map_err(|_| bad())?,
                ))
            }
        };
        let view = match self.view.as_str() {
            "auto" => None,
            "front" => Some(preview::View::Front),
            "side" => Some(preview::View::Side),
            "top" => Some(preview::View::Top),
            v => return Err(format!("--view takes auto, front, side or top (got {v:?})")),
        };
        let shading = match self.shading.as_str() {
            "flat" => preview::Shading::Flat,
            "smooth" => preview::Shading::Smooth,
            v => return Err(format!("--shading takes flat or smooth (got {v:?})")),
        };
        Ok(preview::PreviewJob {
            input: self.input,
            output: self.output,
            shown,
            frames: self.frames,
            size,
            view,
            shading,
            animate: self.animate,
            keys: self.keys.into(),
            animation: self.animation,
            timing: self.timing.timing(),
            looping: self.timing.looping(),
            extend: [self.timing.extend_before, self.timing.extend_after],
            access: Access {
                roots: self.allow_external,
            },
            quiet: self.quiet,
        })
    }
}

#[derive(Args)]
pub struct BlendArgs {
    /// Input: a .gltf or .glb with a skinned character and its animations (name two of them
    /// with --clips); or two of them, a clip each (the character is the first file's; the
    /// second may hold the animation alone, its nodes matched by name); or two .bvh captures
    /// of one skeleton (a clip each).
    #[arg(required = true, num_args = 1..=2, value_name = "INPUT")]
    inputs: Vec<PathBuf>,
    /// Output .gltf or .glb (the blend added as a new animation), or .usda, .usdc or .usdz (a
    /// USD point cache of the blend: skinned meshes baked at each frame); .bvh for .bvh inputs
    /// (the first capture's skeleton and channel order, at its frame time).
    #[arg(short, long)]
    output: PathBuf,
    /// The two animations to blend (names or indices): of a glTF input, or one of each of two
    /// glTF inputs (needed only where a file has several).
    #[arg(long, num_args = 2, value_names = ["A", "B"])]
    clips: Vec<String>,
    /// Weight of B: 0 gives A, 1 gives B. A list (0,0.25,0.5,0.75,1) writes one blend per
    /// weight on the same synchronised cycle, named "A+B@<weight>" (a 1-D blend space); BVH
    /// outputs then go to <output stem>@<weight>.bvh.
    #[arg(
        long,
        default_value = "0.5",
        value_delimiter = ',',
        allow_negative_numbers = true
    )]
    weight: Vec<f64>,
    /// Name of the new animation (default "A+B"; "@<weight>" added for a list of weights).
    #[arg(long)]
    name: Option<String>,
    /// How gait cycles are found.
    #[arg(long, value_enum, default_value_t = CycleMethod::default().into())]
    cycles: CyclesArg,
    /// Leave planted feet as the blend puts them (no IK clean-up).
    #[arg(long)]
    no_cleanup: bool,
    /// Also write cycles, contacts, foot sliding, root speed and smoothness figures to this
    /// JSON file (schema: schemas/blend-report.schema.json).
    #[arg(long, value_name = "FILE.json")]
    report: Option<PathBuf>,
    /// Also read external buffers and images of a .gltf input under this folder (repeatable).
    /// Without it a .gltf may only refer to files inside its own folder.
    #[arg(long, value_name = "FOLDER")]
    allow_external: Vec<PathBuf>,
    /// No summary line.
    #[arg(short, long)]
    pub quiet: bool,
}

impl BlendArgs {
    pub fn job(self) -> BlendJob {
        BlendJob {
            inputs: self.inputs,
            output: self.output,
            clips: (self.clips.len() == 2).then(|| [self.clips[0].clone(), self.clips[1].clone()]),
            weights: self.weight,
            name: self.name,
            cycles: self.cycles.into(),
            cleanup: !self.no_cleanup,
            report: self.report,
            access: Access {
                roots: self.allow_external,
            },
        }
    }
}

#[derive(Args)]
pub struct InspectArgs {
    /// Input .gltf, .glb or .bvh.
    pub input: PathBuf,
    /// Print JSON (schema: schemas/inspect.schema.json) instead of text.
    #[arg(long)]
    pub json: bool,
    /// Also read external buffers and images under this folder (repeatable).
    #[arg(long, value_name = "FOLDER")]
    allow_external: Vec<PathBuf>,
}

impl InspectArgs {
    pub fn access(&self) -> Access {
        Access {
            roots: self.allow_external.clone(),
        }
    }
}

#[derive(Args)]
pub struct EvalArgs {
    /// Input .gltf or .glb with morph keyframes.
    pub input: PathBuf,
    /// Keep every K-th key.
    #[arg(long, default_value_t = 2)]
    pub step: usize,
    /// Methods to compare (linear, poscr, seed, spline).
    #[arg(long, value_delimiter = ',', default_values_t = inbetween::eval::METHODS.iter().map(|m| m.to_string()))]
    pub methods: Vec<String>,
    /// Where the keys come from.
    #[arg(long, value_enum, default_value_t = KeySource::default().into())]
    keys: KeysArg,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

impl EvalArgs {
    pub fn keys(&self) -> KeySource {
        self.keys.into()
    }
}

#[derive(Args)]
pub struct BenchArgs {
    /// Triangle counts to generate (comma-separated).
    #[arg(long, value_delimiter = ',', default_values_t = vec![16020, 100_000, 1_000_000])]
    pub sizes: Vec<usize>,
    /// Frames timed per method and size (the median is reported).
    #[arg(long, default_value_t = 20)]
    pub frames: usize,
    /// Python with numpy and scipy for the peer (default: .venv/bin/python, else python3).
    #[arg(long)]
    pub python: Option<PathBuf>,
    /// Folder holding ref_tween.py.
    #[arg(long, default_value = "../shared/peers")]
    pub peers: PathBuf,
    /// Skip the peer above this many triangles (its set-up takes minutes at 1M).
    #[arg(long, default_value_t = 100_000)]
    pub peer_max_triangles: usize,
    /// Worker threads for the all-threads figure (default: all cores).
    #[arg(long, allow_negative_numbers = true)]
    pub threads: Option<usize>,
    /// Print the rows as JSON lines instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Instead: write a 3-key tube of this many triangles and time `inbetween tween
    /// --tweens 10` on it end to end, in a child process (e.g. 1000000).
    #[arg(long, value_name = "TRIANGLES")]
    pub end_to_end: Option<usize>,
    /// With --end-to-end: frames inserted between keys.
    #[arg(long, default_value_t = 10)]
    pub e2e_tweens: usize,
    /// With --end-to-end: output format (glb, gltf, usda, usdc, usdz).
    #[arg(long, default_value = "glb")]
    pub e2e_format: String,
    /// Instead: time `inbetween preview` (12 frames) on a bent tube of this many triangles.
    #[arg(long, value_name = "TRIANGLES")]
    pub preview: Option<usize>,
    /// With --preview: the bands (comma-separated methods).
    #[arg(long, default_value = "linear")]
    pub preview_methods: String,
    /// Instead: write a scene of this many small morph meshes (a node each) and time `tween`
    /// (.glb, --meshopt, .usdc) and `preview` on it, each in a child process (e.g. 30000).
    #[arg(long, value_name = "MESHES")]
    pub scene: Option<usize>,
    /// Instead: write a face rig of this many blend shapes (about 20,000 vertices, 101 keys of
    /// a weights animation) and time `tween` (.glb, --meshopt, --compact, .usdc) on it, each
    /// in a child process (e.g. 300).
    #[arg(long, value_name = "SHAPES")]
    pub rig: Option<usize>,
    /// With --end-to-end: more `tween` options for the timed run (e.g. --e2e-arg=--compact).
    #[arg(long = "e2e-arg", value_name = "ARG", allow_hyphen_values = true)]
    pub e2e_args: Vec<String>,
}
