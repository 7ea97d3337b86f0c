//! `inbetween preview`: a contact sheet (PNG) of a mesh's frames, one band per method, and the
//! frames as an animation (GIF or APNG).
//!
//! The pipeline, one module per stage: frames (the `tween` stages, per method, at the frames
//! picked; for a file without morph keys [`clips`]: its meshes posed by each clip that moves
//! its nodes, or at rest; for a BVH capture [`bones`]) -> the figure followed where it travels
//! ([`follow`]) -> [`camera`] (view axis and fit) -> [`raster`] (shaded triangles, z-buffer) ->
//! [`sheet`] (bands, labels with [`font`], key marks) -> [`encode`] (PNG, APNG, GIF); [`run_preview`]
//! runs it from file to file.

mod bones;
mod camera;
mod clips;
mod encode;
mod font;
mod raster;
mod sheet;

pub use camera::View;
pub use clips::posed;
pub use raster::{Picture, Shading, BACKGROUND};

use crate::gltf::{arr, mesh_nodes, node_parents, rest_matrix, target_names, Access, Document};
use crate::output::Outputs;
use crate::progress::Progress;
use crate::tween::{
    close_loop, find_morph_meshes, frames_at, plan, side_by_side, FrameAt, KeyOptions, KeySource,
    Method, MorphMesh, NoMorphKeys, Timing, TweenOptions,
};
use anyhow::{bail, Result};
use camera::Camera;
use glam::{DMat4, DVec3};
use raster::Drawn;
use rayon::prelude::*;
use serde_json::Value;
use sheet::Band;
use std::path::{Path, PathBuf};

/// What a band shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shown {
    /// Frames computed by a tween method.
    Method(Method),
    /// The file's own keys as a renderer plays them (a tween output's frames).
    File,
}

impl Shown {
    /// The bands `--methods` may name, by their labels.
    pub const NAMED: [Shown; 4] = [
        Shown::Method(Method::Linear),
        Shown::Method(Method::Seed),
        Shown::Method(Method::Spline),
        Shown::File,
    ];

    /// The band `--methods` names `name` (linear, seed, spline or file).
    pub fn parse(name: &str) -> Option<Shown> {
        Shown::NAMED.into_iter().find(|s| s.label() == name)
    }

    fn label(self) -> &'static str {
        match self {
            Shown::Method(Method::Linear) => "linear",
            Shown::Method(Method::Seed) => "seed",
            Shown::Method(Method::Spline) => "spline",
            Shown::File => "file",
        }
    }
}

/// Default cell size in pixels, and most frames across by default.
pub const CELL: (usize, usize) = (160, 160);
pub const DEFAULT_FRAMES: usize = 12;
/// Most frames an animation holds (picked evenly beyond).
pub const MAX_ANIMATION_FRAMES: usize = 240;

/// What `inbetween preview` was asked for.
pub struct PreviewJob {
    pub input: PathBuf,
    pub output: PathBuf,
    /// Bands; empty: `file` for a tween output, else linear and spline.
    pub shown: Vec<Shown>,
    pub frames: usize,
    /// Whole sheet in pixels; `None`: [`CELL`] per frame.
    pub size: Option<(usize, usize)>,
    /// `None`: the view that shows the most motion.
    pub view: Option<View>,
    pub shading: Shading,
    pub animate: Option<PathBuf>,
    pub keys: KeySource,
    pub animation: Option<String>,
    pub timing: Timing,
    /// As `tween`'s --loop / --no-loop (`None`: tracks whose last key equals the first wrap).
    pub looping: Option<bool>,
    /// Seconds the motion continues before the first key and after the last.
    pub extend: [f64; 2],
    pub access: Access,
    pub quiet: bool,
}

/// What was drawn, for the summary line.
pub struct PreviewSummary {
    pub bands: Vec<String>,
    pub frames: usize,
    pub view: View,
    pub size: (usize, usize),
    pub animation_frames: usize,
    pub triangles: usize,
    pub note: Option<String>,
    pub seconds: f64,
    /// Of which drawing the sheet's cells.
    pub draw_seconds: f64,
}

impl PreviewSummary {
    pub fn line(&self, job: &PreviewJob) -> String {
        let mut s = format!(
            "{}: {} band{} ({}) x {} frames of {} triangles, {:?} view, {} x {} pixels",
            job.output.display(),
            self.bands.len(),
            if self.bands.len() == 1 { "" } else { "s" },
            self.bands.join(", "),
            self.frames,
            self.triangles,
            self.view,
            self.size.0,
            self.size.1,
        );
        if let Some(a) = &job.animate {
            s += &format!(
                "; {} frames animated in {}",
                self.animation_frames,
                a.display()
            );
        }
        s += &format!(
            "; {:.2} s (drawing {:.2} s)",
            self.seconds, self.draw_seconds
        );
        if let Some(n) = &self.note {
            s += &format!("\nnote: {n}");
        }
        s
    }
}

/// One column of a band: every mesh's world-space points, and whether the column is a key.
struct Column {
    meshes: Vec<Vec<DVec3>>,
    key: bool,
    time: f64,
}

/// The triangles of each mesh drawn (welded), and each band's label and columns.
struct Scene {
    triangles: Vec<Vec<[u32; 3]>>,
    bands: Vec<(String, Vec<Column>)>,
}

/// World matrix of the first node that instances each mesh (identity when none does), every
/// node at rest.
fn mesh_worlds(json: &Value) -> Vec<DMat4> {
    let nodes = arr(json, "nodes");
    let parents = node_parents(json);
    (mesh_nodes(json).iter())
        .map(|carriers| {
            carriers.first().map_or(DMat4::IDENTITY, |&x| {
                clips::world_of(x, &parents, |x| rest_matrix(&nodes[x]))
            })
        })
        .collect()
}

/// `count` indices spread evenly over `0..len`, first and last included.
fn spread(len: usize, count: usize) -> Vec<usize> {
    if len <= count || count < 2 {
        return (0..len.min(count.max(1))).collect();
    }
    (0..count)
        .map(|i| (i * (len - 1) + (count - 1) / 2) / (count - 1))
        .collect()
}

/// The columns of band `shown` for mesh `m` at the frames `picked` of its first track.
fn columns(
    m: &MorphMesh,
    shown: Shown,
    base: &TweenOptions,
    picked: &[usize],
    world: &DMat4,
) -> Result<(Vec<[u32; 3]>, Vec<Column>)> {
    let track = &m.tracks[0];
    let to_world = |v: Vec<DVec3>| {
        v.into_iter()
            .map(|p| world.transform_point3(p))
            .collect::<Vec<_>>()
    };
    match shown {
        Shown::File => {
            let welded = crate::tween::Welded::build(m);
            let cols = picked
                .iter()
                .map(|&k| Column {
                    meshes: vec![to_world(welded.weld(&m.pose(&track.weights[k])))],
                    key: true,
                    time: track.times[k],
                })
                .collect();
            Ok((welded.triangles, cols))
        }
        Shown::Method(method) => {
            let opts = TweenOptions { method, ..*base };
            let all = plan(&track.times, &opts);
            let frames: Vec<FrameAt> = picked.iter().map(|&i| all[i]).collect();
            let (welded, f) = frames_at(m, track, &opts, &frames)?;
            let cols = f
                .into_iter()
                .zip(&frames)
                .map(|(pts, fa)| Column {
                    meshes: vec![to_world(pts)],
                    key: fa.t == 0.0 || fa.t == 1.0,
                    time: fa.time,
                })
                .collect();
            Ok((welded.triangles, cols))
        }
    }
}

/// How many columns a band of `shown` has over the first track of `m`.
fn available(m: &MorphMesh, shown: Shown, base: &TweenOptions) -> usize {
    let track = &m.tracks[0];
    match shown {
        Shown::File => track.times.len(),
        Shown::Method(method) => plan(&track.times, &TweenOptions { method, ..*base }).len(),
    }
}

/// Every band's columns: `count` columns picked evenly over each mesh's first track.
fn scene(
    doc: &Document,
    meshes: &[MorphMesh],
    shown: &[Shown],
    base: &TweenOptions,
    count: usize,
    quiet: bool,
) -> Result<Scene> {
    let worlds = mesh_worlds(&doc.json);
    let progress = Progress::new((shown.len() * meshes.len()) as u64, "preview", quiet);
    let mut triangles = Vec::new();
    let mut bands = Vec::new();
    for (b, &s) in shown.iter().enumerate() {
        let mut cols: Vec<Column> = Vec::new();
        let band = |m: &MorphMesh| {
            let picked = spread(available(m, s, base), count);
            let done = columns(m, s, base, &picked, &worlds[m.mesh]);
            progress.inc();
            done.map_err(|e| doc.err(format!("{e:#}")))
        };
        // Small meshes side by side, as `tween` runs them.
        let mut done = Vec::with_capacity(meshes.len());
        for run in side_by_side(meshes, base) {
            match &meshes[run] {
                [m] => done.push(band(m)),
                run => done.extend(run.par_iter().map(band).collect::<Vec<_>>()),
            }
        }
        for (mi, done) in done.into_iter().enumerate() {
            let (tris, c) = done?;
            if b == 0 {
                triangles.push(tris);
            }
            // One column per picked frame, holding every mesh's points.
            for (i, c) in c.into_iter().enumerate() {
                match cols.get_mut(i) {
                    Some(col) if mi > 0 => col.meshes.extend(c.meshes),
                    _ => cols.push(c),
                }
            }
        }
        bands.push((s.label().to_string(), cols));
    }
    progress.finish();
    Ok(Scene { triangles, bands })
}

/// Draw every column of `scene` in cells of `cell` pixels.
fn draw_bands(scene: &Scene, camera: &Camera, cell: (usize, usize), shading: Shading) -> Vec<Band> {
    scene
        .bands
        .iter()
        .map(|(label, cols)| Band {
            label: label.clone(),
            cells: cols
                .par_iter()
                .map(|c| {
                    let drawn: Vec<Drawn> = c
                        .meshes
                        .iter()
                        .zip(&scene.triangles)
                        .map(|(points, triangles)| Drawn {
                            points: points.clone(),
                            triangles,
                        })
                        .collect();
                    (raster::draw(&drawn, camera, cell.0, cell.1, shading), c.key)
                })
                .collect(),
        })
        .collect()
}

/// Whether the file is a tween output: a mesh has targets named as `tween` names its frames
/// (`f0007_t0.2917`).
fn is_tween_output(doc: &Document) -> bool {
    let frame_name = |n: &String| {
        n.strip_prefix('f')
            .and_then(|n| n.split_once("_t"))
            .is_some_and(|(f, t)| {
                !f.is_empty() && f.bytes().all(|b| b.is_ascii_digit()) && t.parse::<f64>().is_ok()
            })
    };
    arr(&doc.json, "meshes")
        .iter()
        .any(|m| target_names(m).iter().any(frame_name))
}

fn image_kind(path: &Path, allowed: &[&str], what: &str) -> Result<String> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    if !allowed.contains(&ext.as_str()) {
        bail!(
            "{}: {what} must end in {} (got {:?})",
            path.display(),
            allowed
                .iter()
                .map(|e| format!(".{e}"))
                .collect::<Vec<_>>()
                .join(" or "),
            path.extension()
                .map(|e| e.to_string_lossy().to_string())
                .unwrap_or_default()
        );
    }
    Ok(ext)
}

/// The morph meshes of `doc` as `job` asks (keys, animation, loop) and the bands to draw.
fn morph_scene(job: &PreviewJob, doc: &Document) -> Result<(Vec<MorphMesh>, Vec<Shown>)> {
    let keys = KeyOptions {
        source: job.keys,
        animation: job.animation.as_deref(),
    };
    let mut meshes = find_morph_meshes(doc, &keys)?;
    if job.looping == Some(true) {
        meshes
            .iter_mut()
            .flat_map(|m| m.tracks.iter_mut())
            .for_each(close_loop);
    }
    let shown = match (job.shown.is_empty(), is_tween_output(doc)) {
        (false, _) => job.shown.clone(),
        (true, true) => vec![Shown::File],
        (true, false) => vec![Shown::Method(Method::Linear), Shown::Method(Method::Spline)],
    };
    Ok((meshes, shown))
}

/// The view of `--view auto`: the most motion among the views whose pictures fill the cell
/// well ([`probe_coverage`]), over the first band's columns (the bands of a morph mesh are one
/// motion by several methods) or with `every_band` over all of them (a band per clip: a fox's
/// look around alone moves in the floor's plane, its walk and run in the body's), or for a
/// still the widest picture.
fn auto_view(scene: &Scene, cell: (usize, usize), every_band: bool) -> View {
    let bands = if every_band {
        &scene.bands[..]
    } else {
        &scene.bands[..1]
    };
    let frames: Vec<Vec<DVec3>> = (bands.iter().flat_map(|(_, c)| c))
        .map(|c| c.meshes.concat())
        .collect();
    match frames.len() {
        0 => return View::Front,
        1 => return View::widest(&frames[0]),
        _ => {}
    }
    let coverage = [View::Front, View::Side, View::Top].map(|v| probe_coverage(scene, v, cell));
    View::most_motion(&frames, coverage)
}

/// Width in pixels of the small cells [`probe_coverage`] draws.
const PROBE_WIDTH: usize = 64;

/// Most triangles of a mesh [`probe_coverage`] draws (every k-th beyond).
const PROBE_TRIANGLES: usize = 20_000;

/// The share of a cell that the first band's first, middle and last columns cover seen by
/// `view` (the camera fitted to every column), drawn small: how much of the surface the view
/// shows, not how much area projects onto it (a flag seen along its plane is a line; a tube's
/// walls seen down its axis overlap).
fn probe_coverage(scene: &Scene, view: View, cell: (usize, usize)) -> f64 {
    let columns = &scene.bands[0].1;
    let (w, h) = (PROBE_WIDTH, (PROBE_WIDTH * cell.1 / cell.0.max(1)).max(1));
    let points = columns.iter().flat_map(|c| c.meshes.iter()).flatten();
    let camera = Camera::fit(view, points, w, h);
    let sampled: Vec<Vec<[u32; 3]>> = scene
        .triangles
        .iter()
        .map(|t| {
            let step = (t.len() / PROBE_TRIANGLES).max(1);
            t.iter().step_by(step).copied().collect()
        })
        .collect();
    let mut picked = vec![0, columns.len() / 2, columns.len() - 1];
    picked.dedup();
    let covered: usize = picked
        .par_iter()
        .map(|&i| {
            let drawn: Vec<Drawn> = columns[i]
                .meshes
                .iter()
                .zip(&sampled)
                .map(|(points, triangles)| Drawn {
                    points: points.clone(),
                    triangles,
                })
                .collect();
            raster::draw(&drawn, &camera, w, h, Shading::Flat).count_not(BACKGROUND)
        })
        .sum();
    covered as f64 / (picked.len() * w * h) as f64
}

/// The animation's frames: each the bands stacked (one cell each), shown for its own time; as
/// many frames as the longest band has, a shorter band (a shorter clip) starting over.
fn animation(
    anim: &Scene,
    camera: &Camera,
    cell: (usize, usize),
    shading: Shading,
) -> Vec<(Picture, f64)> {
    let drawn = draw_bands(anim, camera, cell, shading);
    let Some(longest) = (0..drawn.len()).max_by_key(|&b| (drawn[b].cells.len(), usize::MAX - b))
    else {
        return Vec::new();
    };
    let n = drawn[longest].cells.len();
    let times: Vec<f64> = anim.bands[longest].1.iter().map(|c| c.time).collect();
    (0..n)
        .map(|i| {
            let one: Vec<Band> = drawn
                .iter()
                .filter(|b| !b.cells.is_empty())
                .map(|b| Band {
                    label: b.label.clone(),
                    cells: vec![b.cells[i % b.cells.len()].clone()],
                })
                .collect();
            let delay = if i + 1 < n {
                times[i + 1] - times[i]
            } else {
                1.0 / 30.0
            };
            (sheet::compose(&one, cell, 1), delay.max(0.02))
        })
        .collect()
}

/// How far (as a share of the figure's size) a figure may travel across the floor before the
/// camera follows it.
pub const FOLLOW_TRAVEL: f64 = 0.5;

/// Each column's bounding box, band after band.
fn boxes(scene: &Scene) -> Vec<(DVec3, DVec3)> {
    let columns = scene.bands.iter().flat_map(|(_, c)| c);
    columns
        .map(|c| camera::bounds(c.meshes.iter().flatten()))
        .collect()
}

/// A bounding box's centre on the floor (x and z).
fn floor_centre((lo, hi): (DVec3, DVec3)) -> DVec3 {
    (lo + hi) * 0.5 * DVec3::new(1.0, 0.0, 1.0)
}

/// How far the figure travels across the floor over the columns whose bounding boxes are
/// `boxes` (the farthest a box's centre gets from the first's), as a multiple of the figure's
/// largest size: a capture walking across the room travels several times its size, a clip
/// played in place a fraction.
fn travel(boxes: &[(DVec3, DVec3)]) -> f64 {
    let Some(&first) = boxes.first() else {
        return 0.0;
    };
    let first = floor_centre(first);
    let size = (boxes.iter())
        .map(|(lo, hi)| (*hi - *lo).length())
        .fold(0.0, f64::max);
    let far = (boxes.iter())
        .map(|&b| floor_centre(b).distance(first))
        .fold(0.0, f64::max);
    if size > 0.0 {
        far / size
    } else {
        0.0
    }
}

/// Follow the figure: each column of `scene` (its bounding boxes `boxes`) moved across the
/// floor so that its box's centre stays where the first column's is.
fn follow(scene: &mut Scene, boxes: &[(DVec3, DVec3)]) {
    let Some(&first) = boxes.first() else {
        return;
    };
    let columns = scene.bands.iter_mut().flat_map(|(_, c)| c);
    for (c, &b) in columns.zip(boxes) {
        let shift = floor_centre(first) - floor_centre(b);
        c.meshes.iter_mut().flatten().for_each(|p| *p += shift);
    }
}

/// What a sheet draws.
enum Source {
    /// A morph mesh's frames, a band per tween method (or the file's own).
    Morph(Document, Vec<MorphMesh>, Vec<Shown>),
    /// A file without morph keys: a band per clip that moves its nodes.
    Clips(Document),
    /// A file without morph keys or such clips: its meshes at rest.
    Still,
    /// A BVH motion capture: its bones.
    Capture,
}

/// What `job` draws, the sheet's scene of it, and a note for the summary.
fn source(job: &PreviewJob, base: &TweenOptions) -> Result<(Source, Scene, Option<String>)> {
    if crate::blend::is_capture(&job.input) {
        let scene = bones::scene(&job.input, job.frames, false)?;
        let note = "a BVH motion capture: its skeleton drawn as bones";
        return Ok((Source::Capture, scene, Some(note.into())));
    }
    let doc = Document::open_with(&job.input, &job.access)?;
    let has_targets = arr(&doc.json, "meshes").iter().any(|m| {
        arr(m, "primitives")
            .iter()
            .any(|p| !arr(p, "targets").is_empty())
    });
    // A file whose morph targets hold no keys (a character's face shapes beside its skeletal
    // clips) is drawn as one without targets, unless bands of tween methods were asked for.
    if has_targets {
        match morph_scene(job, &doc) {
            Err(e) if e.is::<NoMorphKeys>() && job.shown.is_empty() => {}
            found => {
                let (meshes, shown) = found?;
                let scene = scene(&doc, &meshes, &shown, base, job.frames, job.quiet)?;
                return Ok((Source::Morph(doc, meshes, shown), scene, None));
            }
        }
    }
    if let Some((played, left, instances_left)) =
        clips::scene(&doc, job.animation.as_deref(), job.frames, false, job.quiet)?
    {
        let note = format!(
            "no morph keys: the file's clips that move its nodes as they play, a band each{}{}",
            match (played.bands.len(), left) {
                (1, _) => String::new(),
                (_, 0) => " (--animation NAME draws one)".into(),
                (n, left) => format!(" (the first {n}; {left} more: --animation NAME draws any)"),
            },
            instances_left_out(instances_left)
        );
        return Ok((Source::Clips(doc), played, Some(note)));
    }
    let (still, instances_left) = clips::still(&doc)?;
    let note = format!("no morph keys and no clip that moves a node: the meshes as the file shows them (a skinned one in the pose its joints rest in){}", instances_left_out(instances_left));
    Ok((Source::Still, still, Some(note)))
}

/// What the note says of `left` mesh instances left out (more points than a preview poses).
fn instances_left_out(left: usize) -> String {
    match left {
        0 => String::new(),
        n => format!(
            "; {n} mesh instance{} left out: more than {} points to pose",
            if n == 1 { "" } else { "s" },
            clips::MAX_POINTS / 2
        ),
    }
}

/// Run the preview job. Nothing is written unless every step succeeds.
pub fn run_preview(job: &PreviewJob) -> Result<PreviewSummary> {
    let started = std::time::Instant::now();
    crate::output::not_a_folder(&job.output, &job.input, ".png")?;
    image_kind(&job.output, &["png"], "the sheet")?;
    let anim_kind = job
        .animate
        .as_deref()
        .map(|a| {
            crate::output::not_a_folder(a, &job.input, ".gif")?;
            image_kind(a, &["gif", "png", "apng"], "--animate")
        })
        .transpose()?;
    if job.frames == 0 {
        bail!("--frames must be at least 1");
    }
    job.timing.check(job.extend)?;
    if let Some((w, h)) = job.size {
        if w < 16 || h < 16 || w > 16_384 || h > 16_384 {
            bail!("--size must be between 16x16 and 16384x16384 pixels (got {w}x{h})");
        }
    }
    // The tween options every band starts from (its method set per band).
    let base = TweenOptions {
        wrap: job.looping != Some(false),
        extend: job.extend,
        ..TweenOptions::new(Method::default(), job.timing)
    };
    let (source, mut scene, mut note) = source(job, &base)?;
    // A character or capture that travels across the floor is followed (its frames are seen
    // in the cells' middle, not as specks along its path); a morph mesh's motion is its own.
    let sheet_boxes = boxes(&scene);
    let travels = travel(&sheet_boxes);
    let follows = !matches!(source, Source::Morph(..)) && travels > FOLLOW_TRAVEL;
    if follows {
        follow(&mut scene, &sheet_boxes);
        let line = format!(
            "the camera follows it across the floor (it travels {travels:.1} times its size)"
        );
        note = Some(match note {
            Some(n) => format!("{n}; {line}"),
            None => line,
        });
    }
    let columns = scene
        .bands
        .iter()
        .map(|(_, c)| c.len())
        .max()
        .unwrap_or(1)
        .max(1);
    let bands = scene.bands.len().max(1);
    let cell = match job.size {
        Some((w, h)) => (
            (w / columns).max(8),
            (h.saturating_sub(bands * (sheet::LABEL + sheet::KEY_BAR)) / bands).max(8),
        ),
        None => CELL,
    };
    let all_points = || {
        scene
            .bands
            .iter()
            .flat_map(|(_, c)| c.iter())
            .flat_map(|c| c.meshes.iter())
            .flatten()
    };
    let every_band = !matches!(source, Source::Morph(..));
    let view = job
        .view
        .unwrap_or_else(|| auto_view(&scene, cell, every_band));
    let camera = Camera::fit(view, all_points(), cell.0, cell.1);
    let draw_start = std::time::Instant::now();
    let drawn = draw_bands(&scene, &camera, cell, job.shading);
    let draw_seconds = draw_start.elapsed().as_secs_f64();
    let mut picture = sheet::compose(&drawn, cell, columns);
    if let Some((w, h)) = job.size {
        let mut exact = Picture::new(w, h, BACKGROUND);
        exact.paste(&picture, 0, 0);
        picture = exact;
    }
    let mut files = Outputs::new();
    files.write(&job.output, &encode::png(&picture)?)?;
    let mut animation_frames = 0;
    let animated = match (&job.animate, &source) {
        (None, _) | (_, Source::Still) => None,
        (Some(_), Source::Morph(doc, meshes, shown)) => {
            Some(scene_all(doc, meshes, shown, &base, job.quiet)?)
        }
        (Some(_), Source::Clips(doc)) => {
            clips::scene(doc, job.animation.as_deref(), 0, true, job.quiet)?.map(|s| s.0)
        }
        (Some(_), Source::Capture) => Some(bones::scene(&job.input, 0, true)?),
    };
    // Followed as the sheet is (the camera was fitted to the followed figure).
    let animated = animated.map(|mut a| {
        if follows {
            let b = boxes(&a);
            follow(&mut a, &b);
        }
        a
    });
    if let (Some(path), Some(kind), Some(animated)) = (&job.animate, &anim_kind, &animated) {
        let frames = animation(animated, &camera, cell, job.shading);
        animation_frames = frames.len();
        let bytes = match kind.as_str() {
            "gif" => encode::gif(&frames)?,
            _ => encode::apng(&frames)?,
        };
        files.write(path, &bytes)?;
    } else if job.animate.is_some() {
        note = Some(note.unwrap_or_default() + "; nothing to animate");
    }
    files.commit()?;
    Ok(PreviewSummary {
        bands: scene.bands.iter().map(|(label, _)| label.clone()).collect(),
        frames: columns,
        view,
        size: (picture.width, picture.height),
        animation_frames,
        triangles: scene.triangles.iter().map(Vec::len).sum(),
        note,
        seconds: started.elapsed().as_secs_f64(),
        draw_seconds,
    })
}

/// The animation's scene: every frame of each band (evenly picked down to
/// [`MAX_ANIMATION_FRAMES`]).
fn scene_all(
    doc: &Document,
    meshes: &[MorphMesh],
    shown: &[Shown],
    base: &TweenOptions,
    quiet: bool,
) -> Result<Scene> {
    let most = meshes
        .iter()
        .flat_map(|m| shown.iter().map(move |&s| available(m, s, base)))
        .max()
        .unwrap_or(1);
    scene(
        doc,
        meshes,
        shown,
        base,
        most.min(MAX_ANIMATION_FRAMES),
        quiet,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_keeps_the_ends_and_order() {
        assert_eq!(spread(5, 12), vec![0, 1, 2, 3, 4]);
        let s = spread(100, 12);
        assert_eq!((s[0], s[11], s.len()), (0, 99, 12));
        assert!(s.windows(2).all(|w| w[0] < w[1]));
    }

    #[test]
    fn a_triangle_is_drawn_and_the_rest_is_background() {
        let tris = [[0u32, 1, 2]];
        let points = vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
        ];
        let cam = Camera::fit(View::Front, points.iter(), 32, 32);
        let p = raster::draw(
            &[Drawn {
                points: points.clone(),
                triangles: &tris,
            }],
            &cam,
            32,
            32,
            Shading::Flat,
        );
        let ink = p.count_not(BACKGROUND);
        // About half of the fitted square (less the margins).
        assert!((300..=600).contains(&ink), "{ink}");
        // Seen edge-on from the side it vanishes.
        let side = Camera::fit(View::Side, points.iter(), 32, 32);
        let q = raster::draw(
            &[Drawn {
                points,
                triangles: &tris,
            }],
            &side,
            32,
            32,
            Shading::Flat,
        );
        assert!(q.count_not(BACKGROUND) < 40);
    }
}
