//! Every WGSL source of the crate, shared modules first (DESIGN.md "Layout":
//! shared WGSL in `src/shaders/common/`, each pass's WGSL beside its module).

/// Colour encoding shared by passes: exposure, clamp and Reinhard operators, sRGB OETF (`src/shaders/common/color.wgsl`).
pub const COLOR_WGSL: &str = include_str!("shaders/common/color.wgsl");

/// The depth pre-pass shader (`src/passes/depth.wgsl`), self-contained.
pub const DEPTH_WGSL: &str = include_str!("passes/depth.wgsl");

/// The tone-map shader: [`COLOR_WGSL`] followed by `src/passes/tonemap.wgsl`.
pub const TONEMAP_WGSL: &str = concat!(
    include_str!("shaders/common/color.wgsl"),
    "\n",
    include_str!("passes/tonemap.wgsl")
);

/// Each WGSL file under `src/` (path relative to `src/`) with the complete
/// module it is validated in: shared modules alone, passes as compiled.
pub const ALL_WGSL: &[(&str, &str)] = &[
    ("shaders/common/color.wgsl", COLOR_WGSL),
    ("passes/depth.wgsl", DEPTH_WGSL),
    ("passes/tonemap.wgsl", TONEMAP_WGSL),
];

#[cfg(test)]
mod tests {
    use std::path::{Path, PathBuf};

    use super::ALL_WGSL;

    /// Parses and validates `src` with naga, naming `path` in the diagnostic.
    fn validate(path: &str, src: &str) {
        let module = naga::front::wgsl::parse_str(src)
            .unwrap_or_else(|e| panic!("{path}: WGSL parse error:\n{}", e.emit_to_string(src)));
        naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::empty(),
        )
        .validate(&module)
        .unwrap_or_else(|e| panic!("{path}: WGSL validation error:\n{}", e.emit_to_string(src)));
    }

    /// Every `.wgsl` file below `dir`, relative to `root`, with `/` separators.
    fn wgsl_files(root: &Path, dir: &Path, out: &mut Vec<String>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path: PathBuf = entry.unwrap().path();
            if path.is_dir() {
                wgsl_files(root, &path, out);
            } else if path.extension().is_some_and(|e| e == "wgsl") {
                let rel = path.strip_prefix(root).unwrap();
                out.push(rel.to_string_lossy().replace('\\', "/"));
            }
        }
    }

    #[test]
    fn every_wgsl_module_parses_and_validates_with_naga() {
        for (path, src) in ALL_WGSL {
            validate(path, src);
        }
    }

    #[test]
    fn every_wgsl_file_is_listed() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
        let mut files = Vec::new();
        wgsl_files(&root, &root, &mut files);
        files.sort();
        let mut listed: Vec<String> = ALL_WGSL.iter().map(|(p, _)| p.to_string()).collect();
        listed.sort();
        assert_eq!(files, listed, "a WGSL file is missing from ALL_WGSL");
    }

    #[test]
    fn shared_wgsl_opens_with_a_notation_table() {
        for (path, src) in ALL_WGSL {
            let head: String = src.lines().take(12).collect::<Vec<_>>().join("\n");
            assert!(head.contains("Notation"), "{path} has no notation table");
        }
    }
}
