//! Command-line parsing and dispatch only; the work is in the library.

mod cli;

use clap::Parser;
use cli::{BenchArgs, Cli, Command, EvalArgs};
use inbetween::{bench, blend, eval, inspect, preview, tween};
use std::process::ExitCode;

/// `print!` to stdout, a reader that stopped reading (`inspect file | head`) no error: the
/// standard macro panicked on the closed pipe.
macro_rules! out {
    ($($arg:tt)*) => {{
        use std::io::Write;
        let _ = write!(std::io::stdout().lock(), $($arg)*);
    }};
}

/// [`out!`] with a line end, as `println!`.
macro_rules! outln {
    ($($arg:tt)*) => {{
        use std::io::Write;
        let _ = writeln!(std::io::stdout().lock(), $($arg)*);
    }};
}

/// [`outln!`] to stderr (the summary, its warnings and errors), as `eprintln!`.
macro_rules! errln {
    ($($arg:tt)*) => {{
        use std::io::Write;
        let _ = writeln!(std::io::stderr().lock(), $($arg)*);
    }};
}

fn main() -> ExitCode {
    inbetween::keep_freed_memory();
    match Cli::parse().command {
        Command::Tween(args) => {
            set_threads(args.threads);
            let quiet = args.quiet;
            run_job(args.job(), tween::run_tween, |s, job| {
                summary(quiet, s.line(job))
            })
        }
        Command::Blend(args) => {
            let quiet = args.quiet;
            let job = args.job();
            finish(blend::run_blend(&job), |s| summary(quiet, s.line()))
        }
        Command::Inspect(args) => {
            let found = inspect::inspect(&args.input, &args.access());
            finish(found, |i| match args.json {
                true => outln!("{}", serde_json::to_string_pretty(&i).unwrap_or_default()),
                false => out!("{}", inspect::text(&i)),
            })
        }
        Command::Preview(args) => {
            set_threads(args.threads);
            let quiet = args.quiet;
            run_job(args.job(), preview::run_preview, |s, job| {
                summary(quiet, s.line(job))
            })
        }
        Command::Eval(args) => run_eval(&args),
        Command::Bench(args) => run_bench(args),
    }
}

/// Exit 0 after `done` on success; on failure one line on stderr and exit code 2.
fn finish<T>(result: anyhow::Result<T>, done: impl FnOnce(T)) -> ExitCode {
    match result {
        Ok(value) => {
            done(value);
            ExitCode::SUCCESS
        }
        Err(e) => {
            errln!("inbetween: error: {}", format!("{e:#}").replace('\n', " "));
            ExitCode::from(2)
        }
    }
}

/// Run `job` (or report why the arguments do not make one) with `run`, then `done`.
fn run_job<J, T>(
    job: Result<J, String>,
    run: impl FnOnce(&J) -> anyhow::Result<T>,
    done: impl FnOnce(T, &J),
) -> ExitCode {
    match job {
        Ok(job) => finish(run(&job), |s| done(s, &job)),
        Err(e) => finish::<()>(Err(anyhow::anyhow!(e)), |_| {}),
    }
}

fn summary(quiet: bool, line: String) {
    if !quiet {
        errln!("{line}");
    }
}

fn set_threads(threads: Option<usize>) {
    if let Some(n) = threads {
        let _ = rayon::ThreadPoolBuilder::new()
            .num_threads(n.max(1))
            .build_global();
    }
}

fn run_eval(args: &EvalArgs) -> ExitCode {
    let scores = eval::run_eval(&args.input, args.step, &args.methods, args.keys());
    finish(scores, |scores| {
        if args.json {
            outln!(
                "{}",
                serde_json::to_string_pretty(&scores).unwrap_or_default()
            );
        } else {
            out!("{}", eval::table(&scores));
        }
    })
}

/// What `result` holds, as JSON on stdout (see [`finish`]).
fn pretty<T: serde::Serialize>(result: anyhow::Result<T>) -> ExitCode {
    finish(result, |r| {
        outln!("{}", serde_json::to_string_pretty(&r).unwrap_or_default())
    })
}

fn run_bench(args: BenchArgs) -> ExitCode {
    set_threads(args.threads);
    if let Some(triangles) = args.preview {
        return pretty(bench::preview(triangles, &args.preview_methods));
    }
    if let Some(meshes) = args.scene {
        return pretty(bench::scene(meshes));
    }
    if let Some(shapes) = args.rig {
        return pretty(bench::rig(shapes));
    }
    if let Some(triangles) = args.end_to_end {
        let r = bench::end_to_end(triangles, args.e2e_tweens, &args.e2e_format, &args.e2e_args);
        return pretty(r);
    }
    let opts = bench::BenchOptions {
        sizes: args.sizes,
        frames: args.frames.max(1),
        peer: bench::find_peer(args.python, args.peers),
        peer_max_triangles: args.peer_max_triangles,
    };
    let json = args.json;
    let rows = bench::run(&opts, &mut |row| {
        if json {
            outln!("{}", serde_json::to_string(row).unwrap_or_default());
        } else {
            errln!("bench: {} triangles done", row.triangles);
        }
    });
    finish(rows, |rows| {
        if !json {
            out!("{}", bench::table(&rows));
            if let Some(x) = bench::fitted_exponent(&rows) {
                outln!("\nper-frame seed time grows as triangles^{x:.2} (least-squares fit over these sizes)");
            }
        }
    })
}
