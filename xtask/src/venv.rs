//! Python virtual environments at the workspace root with one pinned pip
//! package each (`.ray-venv` for Ray, `.bench-venv` for embreex), created
//! with `python3 -m venv` on demand, and a command runner that fails on a
//! non-zero exit.

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{Context, Result, bail, ensure};

/// A venv with one pinned package: where it lives and how to ask its version.
pub struct Venv {
    /// Directory at the workspace root, e.g. `.ray-venv`.
    pub dir: &'static str,
    /// The pip requirement's name, e.g. `ray`.
    pub package: &'static str,
    /// The pinned version.
    pub version: &'static str,
    /// Python that imports the package and prints its version.
    pub probe: &'static str,
    /// What needs it, for messages (`ray`, `bench`).
    pub user: &'static str,
}

impl Venv {
    /// The venv's Python.
    pub fn python(&self, root: &Path) -> PathBuf {
        root.join(self.dir).join("bin").join("python")
    }

    /// The package's version in the venv, or why it cannot be imported.
    fn installed(&self, python: &Path) -> std::result::Result<String, String> {
        let output = Command::new(python)
            .args(["-c", self.probe])
            .output()
            .map_err(|e| format!("cannot run {}: {e}", python.display()))?;
        if !output.status.success() {
            return Err(format!(
                "{} cannot import {}",
                python.display(),
                self.package
            ));
        }
        Ok(String::from_utf8_lossy(&output.stdout).trim().to_owned())
    }

    /// Makes sure the venv imports the pinned package, creating the venv and installing it when missing; its Python.
    pub fn ensure(&self, root: &Path) -> Result<PathBuf> {
        let (venv, python, user) = (root.join(self.dir), self.python(root), self.user);
        let requirement = format!("{}=={}", self.package, self.version);
        if !python.exists() {
            eprintln!("{user}: creating the Python environment {}", venv.display());
            checked(Command::new("python3").args(["-m", "venv"]).arg(&venv)).context(
                "creating the virtual environment (is python3 with the venv module installed? \
                 `apt-get install python3-venv`)",
            )?;
        }
        match self.installed(&python) {
            Ok(version) if version == self.version => return Ok(python),
            Ok(version) => eprintln!(
                "{user}: {} has {} {version}; installing {}",
                venv.display(),
                self.package,
                self.version
            ),
            Err(why) => eprintln!("{user}: {why}; installing {requirement}"),
        }
        checked(Command::new(&python).args(["-m", "pip", "install", "-q", &requirement]))
            .with_context(|| format!("installing {requirement} with pip"))?;
        match self.installed(&python) {
            Ok(version) if version == self.version => Ok(python),
            Ok(version) => bail!(
                "{} has {} {version} after pip install",
                python.display(),
                self.package
            ),
            Err(why) => bail!("{why} after pip install"),
        }
    }
}

/// Runs a command with inherited output and fails on a non-zero exit.
pub fn checked(command: &mut Command) -> Result<()> {
    let status = command
        .status()
        .with_context(|| format!("starting {command:?}"))?;
    ensure!(status.success(), "{command:?} failed ({status})");
    Ok(())
}
