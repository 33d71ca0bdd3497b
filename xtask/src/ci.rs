//! `cargo xtask ci`: the checks CI runs, in the order a developer should run them.

use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};

use anyhow::{Context, bail};

/// Runs one cargo command from the workspace root, failing on a non-zero exit.
pub fn cargo(args: &[&str]) -> anyhow::Result<()> {
    println!("xtask: cargo {}", args.join(" "));
    let status = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
        .args(args)
        .current_dir(crate::workspace_root())
        .status()
        .with_context(|| format!("cannot run cargo {}", args.join(" ")))?;
    if !status.success() {
        bail!("cargo {} failed ({status})", args.join(" "));
    }
    Ok(())
}

/// Format check, clippy with warnings denied, every test of the workspace
/// (closing with one line that sums the test binaries' results), then the
/// golden images and the reference checks (each closing with its own summary
/// line), then the Ray driver's check (`cargo xtask ray`).
pub fn run() -> anyhow::Result<()> {
    cargo(&["fmt", "--all", "--", "--check"])?;
    cargo(&[
        "clippy",
        "--workspace",
        "--all-targets",
        "--",
        "-D",
        "warnings",
    ])?;
    test_workspace()?;
    // Every check runs before any failure is reported.
    let golden = crate::golden::run(None);
    let reference = crate::reference_check::run(crate::reference_check::Args::all());
    let ray = crate::ray::run(crate::ray::Args {
        install_only: false,
    });
    golden.and(reference).and(ray)
}

/// Runs `cargo test --workspace`, echoing its output, and prints the totals
/// of its `test result:` lines as `tests: N passed, N failed, N skipped`.
fn test_workspace() -> anyhow::Result<()> {
    println!("xtask: cargo test --workspace");
    let mut child = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
        .args(["test", "--workspace"])
        .current_dir(crate::workspace_root())
        .stdout(Stdio::piped())
        .spawn()
        .context("cannot run cargo test")?;
    let (mut passed, mut failed, mut ignored) = (0u64, 0u64, 0u64);
    let stdout = child.stdout.take().context("cargo test has no stdout")?;
    for line in BufReader::new(stdout).lines() {
        let line = line.context("cannot read cargo test's output")?;
        println!("{line}");
        if let Some(rest) = line.strip_prefix("test result: ") {
            for part in rest.split(';') {
                let mut words = part.split_whitespace().rev();
                let (Some(what), Some(n)) = (words.next(), words.next()) else {
                    continue;
                };
                let n: u64 = n.parse().unwrap_or(0);
                match what {
                    "passed" => passed += n,
                    "failed" => failed += n,
                    "ignored" => ignored += n,
                    _ => {}
                }
            }
        }
    }
    let status = child.wait().context("cargo test did not finish")?;
    println!("tests: {passed} passed, {failed} failed, {ignored} skipped");
    if !status.success() {
        bail!("cargo test --workspace failed ({status})");
    }
    Ok(())
}
