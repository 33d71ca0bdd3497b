//! What the `lustre` command-line tests share: running the binary, scratch directories, GPU skips.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs the `lustre` binary with `args`.
pub fn lustre(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lustre"))
        .args(args)
        .output()
        .expect("the lustre binary runs")
}

/// A fresh directory under the system's temporary directory, unique to this process and `name`.
pub fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("lustre-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `lustre` with `args`, or `None` when the binary says no adapter exists (exit 77) and the environment allows skipping.
pub fn render_or_skip(test: &str, args: &[&str]) -> Option<Output> {
    let out = lustre(args);
    if out.status.code() == Some(77) {
        assert!(
            std::env::var_os("LUSTRE_REQUIRE_GPU").is_none(),
            "{test}: LUSTRE_REQUIRE_GPU is set but: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        eprintln!("SKIPPED {test}: no Vulkan adapter");
        return None;
    }
    Some(out)
}

/// The JSON sidecar written beside the render `path`.
pub fn sidecar(path: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(path.with_extension("json")).unwrap()).unwrap()
}
