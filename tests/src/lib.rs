//! Cross-crate integration tests of Lustre; the tests live in `tests/tests/`.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// The Mitsuba release the references were rendered with (`tests/references/*.json`; `cargo xtask reference` installs it).
pub const MITSUBA_VERSION: &str = "3.9.1";

/// The workspace root.
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .unwrap()
        .to_path_buf()
}

/// The venv's Python when it imports Mitsuba; otherwise `None` with a message naming the `test` that skips (a panic under `CI`).
pub fn mitsuba_python(test: &str) -> Option<PathBuf> {
    let python = root().join(".mitsuba-venv").join("bin").join("python");
    let why = if !python.exists() {
        Some(format!("{} does not exist", python.display()))
    } else {
        let output = Command::new(&python)
            .args(["-c", "import mitsuba, numpy; print(mitsuba.__version__)"])
            .stderr(Stdio::null())
            .output();
        match output {
            Ok(out) if out.status.success() => {
                let version = String::from_utf8_lossy(&out.stdout).trim().to_owned();
                (version != MITSUBA_VERSION).then(|| {
                    format!(
                        "{} has Mitsuba {version}, not the references' {MITSUBA_VERSION}",
                        python.display()
                    )
                })
            }
            _ => Some(format!(
                "{} cannot import mitsuba and numpy",
                python.display()
            )),
        }
    };
    match why {
        None => Some(python),
        Some(why) if std::env::var_os("CI").is_some() => {
            panic!(
                "Mitsuba is required under CI: {why}; run `cargo xtask reference --install-only`"
            )
        }
        Some(why) => {
            eprintln!(
                "skipping the Mitsuba {test} test: {why} (run `cargo xtask reference --install-only`)"
            );
            None
        }
    }
}
