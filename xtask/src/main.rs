//! `cargo xtask`: Lustre's project tasks, one module per subcommand
//! (DESIGN.md, "Layout": golden, bless, reference, bench, ci).

mod bench;
mod ci;
mod converge;
mod density_errors;
mod embree;
mod golden;
mod path_tracer;
mod ray;
mod reference;
mod reference_check;
mod render;
mod surfaces;
mod venv;
mod walkthrough;

pub use reference::workspace_root;

use std::process::ExitCode;

/// The cases of a registry to run: all, or the one named (`kind` names the registry in the error, which lists the cases).
pub(crate) fn select_case<'a, C>(
    cases: &'a [C],
    name: Option<&str>,
    name_of: impl Fn(&C) -> &str,
    kind: &str,
) -> anyhow::Result<Vec<&'a C>> {
    match name {
        None => Ok(cases.iter().collect()),
        Some(name) => match cases.iter().find(|c| name_of(c) == name) {
            Some(case) => Ok(vec![case]),
            None => anyhow::bail!(
                "no {kind} case `{name}`; the cases are: {}",
                cases.iter().map(&name_of).collect::<Vec<_>>().join(", ")
            ),
        },
    }
}

use clap::{Parser, Subcommand};

/// Lustre's project tasks.
#[derive(Debug, Parser)]
#[command(name = "cargo xtask", version, about)]
struct Cli {
    /// The task to run.
    #[command(subcommand)]
    command: Command,
}

/// The subcommands; each lives in its own module.
#[derive(Debug, Subcommand)]
enum Command {
    /// Render path-traced references of the built-in scenes with Mitsuba 3.
    Reference(reference::Args),
    /// Render every technique on every scene with a reference and hold relMSE, FLIP (mean, p99) and the mean luminance to per-case bounds.
    ReferenceCheck(reference_check::Args),
    /// Run the criterion benches and our BVH against Embree (`embree`; creates .bench-venv) and write BENCHMARKS.md from their medians.
    Bench {
        /// Only the bench targets whose name contains this (`embree` for the Embree comparison alone).
        filter: Option<String>,
    },
    /// Render the golden-image cases with `lustre render` and compare them with tests/goldens by FLIP.
    Golden {
        /// Only the case with this name.
        #[arg(long)]
        case: Option<String>,
    },
    /// Render the golden-image cases and write them as the new goldens, on purpose.
    Bless {
        /// Only the case with this name.
        #[arg(long)]
        case: Option<String>,
    },
    /// Measure relative MSE and FLIP against the references per technique and photon count, into BENCHMARKS.md.
    Converge(converge::Args),
    /// Error (noise, bias, total) and per-frame times of the quasi-static estimators, into BENCHMARKS.md (García et al. tables 2.1, 2.6-2.8).
    DensityErrors(density_errors::Args),
    /// The walkthrough benchmark: a camera path rendered once with `--camera-path`, every frame against a path-traced reference and beside the path tracer's time for the same error, into BENCHMARKS.md.
    Walkthrough(walkthrough::Args),
    /// Check the Ray driver (tools/ray) on a local Ray instance against a single-process trace; creates .ray-venv.
    Ray(ray::Args),
    /// The README's test command: format check, clippy with warnings denied, all tests, golden images, reference checks, the Ray driver.
    Ci,
}

fn main() -> ExitCode {
    let result = match Cli::parse().command {
        Command::Reference(args) => reference::run(args),
        Command::ReferenceCheck(args) => reference_check::run(args),
        Command::Bench { filter } => bench::run(filter.as_deref()),
        Command::Golden { case } => golden::run(case.as_deref()),
        Command::Bless { case } => golden::bless(case.as_deref()),
        Command::Converge(args) => converge::run(args),
        Command::DensityErrors(args) => density_errors::run(args),
        Command::Ray(args) => ray::run(args),
        Command::Walkthrough(args) => walkthrough::run(args),
        Command::Ci => ci::run(),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            // The whole context chain on one line, without a backtrace.
            eprintln!("error: {error:#}");
            ExitCode::FAILURE
        }
    }
}
