//! Command-line parsing only; the work is in the library.

use clap::{Parser, Subcommand};
use inbetween::bench::{self, BenchOptions};
use inbetween::interpolate::Method;
use inbetween::job::{run_tween, TweenJob};
use inbetween::keyframes::KeySource;
use inbetween::tween::Timing;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "inbetween",
    version,
    about = "Tween frames for glTF morph keyframes by the deformation-gradient method.",
    long_about = "inbetween reads a glTF whose morph targets (or weights animation) are keyframe poses and \
writes the in-between frames, computed per triangle (polar decomposition, rotation slerp, linear stretch) \
and solved for the vertices, instead of by linear vertex blending. Everything else in the file is kept."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Write tween frames between a mesh's morph keyframes as dense morph animation.
    #[command(
        after_help = "Examples:\n  inbetween tween samples/bar_twist.glb -o bar_tween.glb\n  \
inbetween tween flag.gltf -o flag_30fps.glb --fps 30\n  inbetween tween in.glb -o lerp.glb --method linear --tweens 9"
    )]
    Tween {
        /// Input .gltf (embedded or external buffers) or .glb.
        input: PathBuf,
        /// Output file; the format follows the extension (.glb or .gltf).
        #[arg(short, long)]
        output: PathBuf,
        /// Frames inserted evenly between each pair of consecutive keys.
        #[arg(long, default_value_t = 4, conflicts_with = "fps")]
        tweens: usize,
        /// Instead of --tweens: frames at this fixed rate (per second) over the keys' time span.
        #[arg(long)]
        fps: Option<f64>,
        /// Interpolation method.
        #[arg(long, value_enum, default_value_t = Method::Spline)]
        method: Method,
        /// Where the keys come from.
        #[arg(long, value_enum, default_value_t = KeySource::Auto)]
        keys: KeySource,
        /// The animation (name or index) whose weights channel supplies the keys.
        #[arg(long, value_name = "NAME|INDEX")]
        animation: Option<String>,
        /// Worker threads for frames (default: all cores). Output is identical for any value.
        #[arg(long)]
        threads: Option<usize>,
        /// Close every key sequence into a loop (append its first key after the last) and let
        /// `spline` wrap around it. Without it, tracks whose last key equals the first wrap.
        #[arg(long = "loop", conflicts_with = "no_loop")]
        looping: bool,
        /// Never wrap `spline` around the ends, even when the last key equals the first.
        #[arg(long)]
        no_loop: bool,
        /// Seconds to continue the motion before the first key (the seed paper's exaggeration).
        #[arg(long, value_name = "SECONDS", default_value_t = 0.0)]
        extend_before: f64,
        /// Seconds to continue the motion after the last key.
        #[arg(long, value_name = "SECONDS", default_value_t = 0.0)]
        extend_after: f64,
        /// Also write per-frame shape figures (edge distortion, area and volume change,
        /// inverted triangles) to this JSON file (schema: schemas/report.schema.json).
        #[arg(long, value_name = "FILE.json")]
        report: Option<PathBuf>,
        /// No progress bar, no summary.
        #[arg(short, long)]
        quiet: bool,
    },
    /// Blend two skeletal clips of a character into a new clip (walk + run = jog): cycles found
    /// and synchronised on foot contacts, the second clip aligned to the first, joints slerped,
    /// planted feet cleaned up with two-bone IK. The output is the input plus one animation.
    #[command(
        after_help = "Examples:\n  inbetween blend Fox.glb -o fox_trot.glb --clips Walk Run\n  \
inbetween blend robot.glb -o jog.glb --clips Walking Running --weight 0.3 --name Jog --report jog.json"
    )]
    Blend {
        /// Input .gltf or .glb with a skinned character and its animations.
        input: PathBuf,
        /// Output .gltf or .glb.
        #[arg(short, long)]
        output: PathBuf,
        /// The two animations to blend (names or indices).
        #[arg(long, num_args = 2, value_names = ["A", "B"], required = true)]
        clips: Vec<String>,
        /// Weight of B: 0 gives A, 1 gives B.
        #[arg(long, default_value_t = 0.5)]
        weight: f64,
        /// Name of the new animation (default "A+B").
        #[arg(long)]
        name: Option<String>,
        /// How gait cycles are found: `legs` works for any rig (feet found from the skeleton);
        /// `thigh` is the seed paper's angle between the thighs (bipeds).
        #[arg(long, value_enum, default_value_t = inbetween::blend::cycles::CycleMethod::Legs)]
        cycles: inbetween::blend::cycles::CycleMethod,
        /// Leave planted feet as the blend puts them (no IK clean-up).
        #[arg(long)]
        no_cleanup: bool,
        /// Also write cycles, contacts, foot sliding, root speed and smoothness figures to this
        /// JSON file (schema: schemas/blend-report.schema.json).
        #[arg(long, value_name = "FILE.json")]
        report: Option<PathBuf>,
        /// No summary line.
        #[arg(short, long)]
        quiet: bool,
    },
    /// Hold-out accuracy: keep every K-th key, predict the dropped ones with each method, and
    /// print the RMS vertex error over the bounding-box diagonal (mean and max) per method.
    Eval {
        /// Input .gltf or .glb with morph keyframes.
        input: PathBuf,
        /// Keep every K-th key.
        #[arg(long, default_value_t = 2)]
        step: usize,
        /// Methods to compare (linear, poscr, seed, spline).
        #[arg(long, value_delimiter = ',', default_values_t = ["linear", "poscr", "seed", "spline"].map(String::from))]
        methods: Vec<String>,
        /// Where the keys come from.
        #[arg(long, value_enum, default_value_t = KeySource::Auto)]
        keys: KeySource,
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Print speed figures on generated meshes (set-up, per-frame time, throughput, memory),
    /// side by side with the numpy/scipy peer when python3 with numpy and scipy is available.
    Bench {
        /// Triangle counts to generate (comma-separated).
        #[arg(long, value_delimiter = ',', default_values_t = vec![16020, 100_000, 1_000_000])]
        sizes: Vec<usize>,
        /// Frames timed per method and size (the median is reported).
        #[arg(long, default_value_t = 20)]
        frames: usize,
        /// Python with numpy and scipy for the peer (default: .venv/bin/python, else python3).
        #[arg(long)]
        python: Option<PathBuf>,
        /// Folder holding ref_tween.py.
        #[arg(long, default_value = "../shared/peers")]
        peers: PathBuf,
        /// Skip the peer above this many triangles (its set-up takes minutes at 1M).
        #[arg(long, default_value_t = 100_000)]
        peer_max_triangles: usize,
        /// Worker threads for the all-threads figure (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
        /// Print the rows as JSON lines instead of a table.
        #[arg(long)]
        json: bool,
        /// Instead: write a 3-key tube of this many triangles and time `inbetween tween
        /// --tweens 10` on it end to end, in a child process (e.g. 1000000).
        #[arg(long, value_name = "TRIANGLES")]
        end_to_end: Option<usize>,
        /// With --end-to-end: frames inserted between keys.
        #[arg(long, default_value_t = 10)]
        e2e_tweens: usize,
        /// With --end-to-end: output format (glb, gltf, usda, usdc, usdz).
        #[arg(long, default_value = "glb")]
        e2e_format: String,
    },
}

fn set_threads(threads: Option<usize>) {
    if let Some(n) = threads {
        let _ = rayon::ThreadPoolBuilder::new()
            .num_threads(n.max(1))
            .build_global();
    }
}

fn fail(e: anyhow::Error) -> ExitCode {
    eprintln!("inbetween: error: {}", format!("{e:#}").replace('\n', " "));
    ExitCode::from(2)
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Eval {
            input,
            step,
            methods,
            keys,
            json,
        } => {
            let run = || -> anyhow::Result<Vec<inbetween::eval::MeshScore>> {
                let doc = inbetween::read::Document::open(&input)?;
                let meshes = inbetween::keyframes::find_morph_meshes(
                    &doc,
                    &inbetween::keyframes::KeyOptions {
                        source: keys,
                        animation: None,
                    },
                )?;
                let methods: Vec<&str> = methods.iter().map(String::as_str).collect();
                meshes
                    .iter()
                    .map(|m| inbetween::eval::evaluate(m, step, &methods))
                    .collect()
            };
            match run() {
                Ok(scores) => {
                    if json {
                        println!(
                            "{}",
                            serde_json::to_string_pretty(&scores).unwrap_or_default()
                        );
                    } else {
                        print!("{}", inbetween::eval::table(&scores));
                    }
                    ExitCode::SUCCESS
                }
                Err(e) => fail(e),
            }
        }
        Command::Blend {
            input,
            output,
            clips,
            weight,
            name,
            cycles,
            no_cleanup,
            report,
            quiet,
        } => {
            let job = inbetween::blend::job::BlendJob {
                input,
                output,
                clips: [clips[0].clone(), clips[1].clone()],
                weight,
                name,
                cycles,
                cleanup: !no_cleanup,
                report,
            };
            match inbetween::blend::job::run_blend(&job) {
                Ok(summary) => {
                    if !quiet {
                        eprintln!("{}", summary.line(&job));
                    }
                    ExitCode::SUCCESS
                }
                Err(e) => fail(e),
            }
        }
        Command::Bench {
            sizes,
            frames,
            python,
            peers,
            peer_max_triangles,
            threads,
            json,
            end_to_end,
            e2e_tweens,
            e2e_format,
        } => {
            set_threads(threads);
            if let Some(triangles) = end_to_end {
                return match bench::end_to_end(triangles, e2e_tweens, &e2e_format) {
                    Ok(r) => {
                        println!("{}", serde_json::to_string_pretty(&r).unwrap_or_default());
                        ExitCode::SUCCESS
                    }
                    Err(e) => fail(e),
                };
            }
            let python = python.or_else(|| {
                let venv = PathBuf::from(".venv/bin/python");
                Some(if venv.exists() {
                    venv
                } else {
                    PathBuf::from("python3")
                })
            });
            let peer = python.filter(|p| {
                peers.join("ref_tween.py").exists()
                    && std::process::Command::new(p)
                        .args(["-c", "import numpy, scipy"])
                        .output()
                        .is_ok_and(|o| o.status.success())
            });
            if peer.is_none() {
                eprintln!(
                    "bench: no python with numpy+scipy or no {}: peer columns left empty",
                    peers.display()
                );
            }
            let opts = BenchOptions {
                sizes,
                frames: frames.max(1),
                peer: peer.map(|p| (p, peers)),
                peer_max_triangles,
            };
            let result = bench::run(&opts, &mut |row| {
                if json {
                    println!("{}", serde_json::to_string(row).unwrap_or_default());
                } else {
                    eprintln!("bench: {} triangles done", row.triangles);
                }
            });
            match result {
                Ok(rows) => {
                    if !json {
                        print!("{}", bench::table(&rows));
                        if let Some(x) = bench::fitted_exponent(&rows) {
                            println!("\nper-frame seed time grows as triangles^{x:.2} (least-squares fit over these sizes)");
                        }
                    }
                    ExitCode::SUCCESS
                }
                Err(e) => fail(e),
            }
        }
        Command::Tween {
            input,
            output,
            tweens,
            fps,
            method,
            keys,
            animation,
            threads,
            looping,
            no_loop,
            extend_before,
            extend_after,
            report,
            quiet,
        } => {
            if let Some(n) = threads {
                let _ = rayon::ThreadPoolBuilder::new()
                    .num_threads(n.max(1))
                    .build_global();
            }
            let job = TweenJob {
                input,
                output,
                method,
                keys,
                animation,
                timing: fps.map(Timing::Fps).unwrap_or(Timing::Tweens(tweens)),
                quiet,
                looping: if looping {
                    Some(true)
                } else if no_loop {
                    Some(false)
                } else {
                    None
                },
                extend: [extend_before, extend_after],
                report,
            };
            match run_tween(&job) {
                Ok(summary) => {
                    if !quiet {
                        eprintln!("{}", summary.line(&job));
                    }
                    ExitCode::SUCCESS
                }
                Err(e) => fail(e),
            }
        }
    }
}
