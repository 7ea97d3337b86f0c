//! Command-line parsing only; the work is in the library.

use clap::{Parser, Subcommand};
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
        #[arg(long, value_enum, default_value_t = Method::Seed)]
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
        /// No progress bar, no summary.
        #[arg(short, long)]
        quiet: bool,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Tween {
            input,
            output,
            tweens,
            fps,
            method,
            keys,
            animation,
            threads,
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
            };
            match run_tween(&job) {
                Ok(summary) => {
                    if !quiet {
                        eprintln!("{}", summary.line(&job));
                    }
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("inbetween: error: {}", format!("{e:#}").replace('\n', " "));
                    ExitCode::from(2)
                }
            }
        }
    }
}
