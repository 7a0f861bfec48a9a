//! The `powder` command line: the commands and their dispatch; each command's flags and
//! work live in `cli/`.

use clap::{Parser, Subcommand};
use std::process::ExitCode;

mod cli;
use cli::*;

#[derive(Parser)]
#[command(name = "powder", version, about = "DEM engine for cohesive powders")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a scene headless and print a summary.
    Run(RunArgs),
    /// Collide two spheres head-on and compare with the papers' closed forms.
    Collide(Box<CollideArgs>),
    /// Run a scene on both backends and report their deviations over time.
    Compare(CompareArgs),
    /// Show the GPU adapter the GPU engine would use (POWDER_ADAPTER overrides it).
    Info(InfoArgs),
    /// Measure particle-steps per second and GPU bytes per particle against N.
    Bench(BenchArgs),
    /// Error against run time (work-precision) over the time step, on both backends.
    Accuracy(AccuracyArgs),
    /// Closed forms without a simulation: kp' (paper 000 eq. A.3), Thornton-Ning e_TN and
    /// e_pl (paper 001 eqs. 13-14), the Tabor parameter (paper 002 eq. 1).
    Analytic(analytic::AnalyticArgs),
    /// Every contact law's parameters (or, `params scene`, the scene's other keys): key,
    /// unit, default, valid values and meaning.
    Params(ParamsArgs),
}

fn main() -> ExitCode {
    // A reader that closes the pipe (`powder params | head`) ends the program as it ends
    // other tools, by SIGPIPE, not with a panic at the next print (Rust ignores SIGPIPE).
    #[cfg(unix)]
    // SAFETY: sets a signal's disposition to its default at start-up, before any thread.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Run(a) => run_cmd(a),
        Command::Collide(a) => collide_cmd(a),
        Command::Info(a) => info_cmd(a),
        Command::Bench(a) => bench_cmd(a),
        Command::Accuracy(a) => accuracy_cmd(a),
        Command::Analytic(a) => analytic::analytic_cmd(a),
        Command::Params(a) => params_cmd(a),
        // (as `diff`: 1 where the backends differ beyond a tolerance, 2 where the
        // comparison could not run)
        Command::Compare(a) => match compare_cmd(a) {
            Ok(true) => Ok(()),
            Ok(false) => return ExitCode::from(1),
            Err(e) => {
                eprintln!("error: {e}");
                return ExitCode::from(2);
            }
        },
    };
    match result {
        Ok(()) if INTERRUPTED.load(std::sync::atomic::Ordering::Relaxed) => {
            ExitCode::from(exit_status())
        }
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
