//! Atomic file writes (DESIGN.md, "Conventions"): every file is written to a
//! temporary name in its own directory and renamed over the target, so a
//! failed run never leaves a half-written image or sidecar.

use std::fs::{self, File};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::ImageError;

/// Distinguishes the temporary files of concurrent writes within one process.
static NEXT_TEMPORARY: AtomicU64 = AtomicU64::new(0);

/// The temporary name beside `path`: `.<name>.tmp-<pid>-<n>`, hidden and unique to this write.
fn temporary_path(path: &Path) -> Result<PathBuf, ImageError> {
    let name = path.file_name().ok_or_else(|| ImageError::Write {
        path: path.to_path_buf(),
        source: std::io::Error::new(std::io::ErrorKind::InvalidInput, "the path names no file"),
    })?;
    let n = NEXT_TEMPORARY.fetch_add(1, Ordering::Relaxed);
    Ok(path.with_file_name(format!(
        ".{}.tmp-{}-{n}",
        name.to_string_lossy(),
        std::process::id()
    )))
}

/// An I/O error while writing `path`.
pub(crate) fn write_error(path: &Path) -> impl Fn(std::io::Error) -> ImageError + '_ {
    move |source| ImageError::Write {
        path: path.to_path_buf(),
        source,
    }
}

/// Writes `path` atomically: `write` fills a new temporary file beside it,
/// which is flushed, synced and renamed to `path`; on any error the
/// temporary file is removed and `path` is left as it was.
pub(crate) fn write_atomic(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> Result<(), ImageError>,
) -> Result<(), ImageError> {
    let temporary = temporary_path(path)?;
    let result = (|| {
        let file = File::create_new(&temporary).map_err(write_error(path))?;
        let mut writer = BufWriter::new(file);
        write(&mut writer)?;
        let file = writer
            .into_inner()
            .map_err(|e| write_error(path)(e.into_error()))?;
        file.sync_all().map_err(write_error(path))?;
        fs::rename(&temporary, path).map_err(write_error(path))
    })();
    if result.is_err() {
        let _ = fs::remove_file(&temporary);
    }
    result
}

/// Writes `bytes` to `path` atomically (temporary file + rename).
pub fn write_bytes_atomic(path: impl AsRef<Path>, bytes: &[u8]) -> Result<(), ImageError> {
    let path = path.as_ref();
    write_atomic(path, |w| w.write_all(bytes).map_err(write_error(path)))
}

/// Writes `value` as pretty-printed JSON with a final newline to `path`
/// atomically, e.g. the sidecar of a render.
pub fn write_json_atomic(
    path: impl AsRef<Path>,
    value: &serde_json::Value,
) -> Result<(), ImageError> {
    let path = path.as_ref();
    let mut text =
        serde_json::to_string_pretty(value).map_err(|source| ImageError::EncodeJson {
            path: path.to_path_buf(),
            source,
        })?;
    text.push('\n');
    write_bytes_atomic(path, text.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::Scratch;

    #[test]
    fn success_leaves_only_the_target() {
        let dir = Scratch::new("atomic-success");
        let path = dir.path().join("a.json");
        write_json_atomic(&path, &serde_json::json!({"photons": 3})).unwrap();
        let text = fs::read_to_string(&path).unwrap();
        assert_eq!(
            serde_json::from_str::<serde_json::Value>(&text).unwrap()["photons"],
            3
        );
        assert!(text.ends_with('\n'));
        assert_eq!(dir.entries(), vec!["a.json".to_owned()]);
    }

    #[test]
    fn overwrites_an_existing_file() {
        let dir = Scratch::new("atomic-overwrite");
        let path = dir.path().join("b.txt");
        write_bytes_atomic(&path, b"old").unwrap();
        write_bytes_atomic(&path, b"new").unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"new");
        assert_eq!(dir.entries(), vec!["b.txt".to_owned()]);
    }

    #[test]
    fn missing_directory_creates_nothing() {
        let dir = Scratch::new("atomic-missing-dir");
        let path = dir.path().join("no-such-dir").join("c.json");
        let error = write_bytes_atomic(&path, b"x").unwrap_err();
        assert!(matches!(error, ImageError::Write { .. }));
        assert!(error.to_string().contains("c.json"), "{error}");
        assert!(!path.exists());
        assert!(dir.entries().is_empty());
    }

    #[test]
    fn failed_rename_removes_the_temporary() {
        // The target is a non-empty directory, so the final rename fails
        // after the temporary file was fully written.
        let dir = Scratch::new("atomic-failed-rename");
        let path = dir.path().join("d.json");
        fs::create_dir(&path).unwrap();
        fs::write(path.join("keep"), b"k").unwrap();
        assert!(write_bytes_atomic(&path, b"x").is_err());
        assert_eq!(dir.entries(), vec!["d.json".to_owned()]);
        assert!(path.join("keep").exists());
    }

    #[test]
    fn failed_encode_removes_the_temporary() {
        let dir = Scratch::new("atomic-failed-encode");
        let path = dir.path().join("e.bin");
        let result = write_atomic(&path, |w| {
            w.write_all(b"half").map_err(write_error(&path))?;
            Err(write_error(&path)(std::io::Error::other("encoder gave up")))
        });
        assert!(result.is_err());
        assert!(dir.entries().is_empty());
    }
}
