//! Every WGSL source of the crate, shared modules first (DESIGN.md "Layout":
//! shared WGSL in `src/shaders/common/`, each pass's WGSL beside its module).

/// Colour encoding shared by passes: exposure, clamp and Reinhard operators, sRGB OETF (`src/shaders/common/color.wgsl`).
pub const COLOR_WGSL: &str = include_str!("shaders/common/color.wgsl");

/// The view block of group 0 shared by every scene pass (`src/shaders/common/view.wgsl`, [`crate::view`]).
pub const VIEW_WGSL: &str = include_str!("shaders/common/view.wgsl");

/// The depth pre-pass's own WGSL (`src/passes/depth.wgsl`); compiled after [`VIEW_WGSL`].
pub const DEPTH_WGSL: &str = include_str!("passes/depth.wgsl");

/// `source` with its switch `line` (`const NAME: bool = true;`) set to
/// `false`, so the code behind it compiles away: llvmpipe runs a branch no
/// lane takes under an empty mask, so a pass that never needs a feature is
/// compiled without it. Fails naming `file` (the pass's WGSL) and `what`
/// when the source lacks the line.
pub fn switched_off(
    source: String,
    line: &str,
    what: &'static str,
    file: &str,
) -> crate::Result<String> {
    if !source.contains(line) {
        return Err(crate::MprError::InvalidSetting {
            what,
            message: format!("{file} lacks the line `{line}`"),
        });
    }
    Ok(source.replace(line, &line.replace("true", "false")))
}

/// A scene pass's own WGSL after the shared [`VIEW_WGSL`].
pub fn with_view(pass: &str) -> String {
    format!("{VIEW_WGSL}\n{pass}")
}

/// A complete scene-pass module specialised for a device: with `clip_distances`
/// the `enable` directive is prepended and every line marked
/// `//clip_distances: ` is uncommented (see `view.wgsl`); without, the module is
/// unchanged and the projection clips instead ([`crate::view::ClipMethod`]).
///
/// The builtin is a vertex output only, so the fragment stages, which take
/// `in: VertexOutput` by convention, are given `FragmentInput`: the same
/// struct without it.
pub fn specialise(module: &str, clip_distances: bool) -> String {
    if !clip_distances || !module.contains(CLIP_MARKER) {
        return module.to_owned();
    }
    let mut module = module.replace(CLIP_MARKER, "");
    if let Some(start) = module.find("struct VertexOutput {") {
        let end = module[start..]
            .find("\n}\n")
            .map_or(module.len(), |e| start + e + 3);
        let fragment: Vec<&str> = module[start..end]
            .lines()
            .filter(|line| !line.contains("@builtin(clip_distances)"))
            .collect();
        let fragment = fragment
            .join("\n")
            .replace("struct VertexOutput {", "struct FragmentInput {");
        module.insert_str(end, &format!("\n{fragment}\n"));
        module = module.replace("(in: VertexOutput)", "(in: FragmentInput)");
    }
    format!("enable clip_distances;\n{module}")
}

/// The prefix of the lines [`specialise`] uncomments.
const CLIP_MARKER: &str = "//clip_distances: ";

/// The shadow cube-map shader (`src/passes/shadow.wgsl`), self-contained.
pub const SHADOW_WGSL: &str = include_str!("passes/shadow.wgsl");

/// The direct light pass's own WGSL (`src/passes/direct.wgsl`); compiled after [`material_module`] ([`direct_wgsl`]).
pub const DIRECT_WGSL: &str = include_str!("passes/direct.wgsl");

/// The tone-map shader: [`COLOR_WGSL`] followed by `src/passes/tonemap.wgsl`.
pub const TONEMAP_WGSL: &str = concat!(
    include_str!("shaders/common/color.wgsl"),
    "\n",
    include_str!("passes/tonemap.wgsl")
);

/// Materials as weighted lobes (`src/shaders/common/material.wgsl`); needs [`lustre_brdf::shaders::BRDF_WGSL`] before it ([`material_module`]).
pub const MATERIAL_WGSL: &str = include_str!("shaders/common/material.wgsl");

/// The BRDF twins of `lustre-brdf` followed by [`MATERIAL_WGSL`]: the prefix of every pass that evaluates materials.
pub fn material_module() -> String {
    format!("{}\n{MATERIAL_WGSL}", lustre_brdf::shaders::BRDF_WGSL)
}

/// The BRDF of a material in a pass's storage array `materials`, its lobe slots written out (`src/shaders/common/material_storage.wgsl`); after [`material_module`], in a pass that declares `materials`.
pub const MATERIAL_STORAGE_WGSL: &str = include_str!("shaders/common/material_storage.wgsl");

// `material_storage.wgsl` writes out exactly four lobe slots.
const _: () = assert!(crate::material::MAX_LOBES == 4);

/// `pass` (a pass's own WGSL, which declares the storage array `materials: array<GpuMaterial>`) after [`material_module`] and [`MATERIAL_STORAGE_WGSL`].
pub fn with_materials(pass: &str) -> String {
    format!("{}\n{MATERIAL_STORAGE_WGSL}\n{pass}", material_module())
}

/// `pass` (which declares `diffuse_maps` and `diffuse_map_sampler`) after the diffuse map lookups ([`crate::diffuse_map::DIFFUSE_MAP_WGSL`]).
pub fn with_diffuse_maps(pass: &str) -> String {
    format!("{}\n{pass}", crate::diffuse_map::DIFFUSE_MAP_WGSL)
}

/// The direct light pass as compiled: [`DIRECT_WGSL`] after [`VIEW_WGSL`], [`with_diffuse_maps`] and [`with_materials`].
pub fn direct_wgsl() -> String {
    with_materials(&with_diffuse_maps(&with_view(DIRECT_WGSL)))
}

/// The Gouraud pass as compiled: [`crate::passes::gouraud::GOURAUD_WGSL`] after [`VIEW_WGSL`] and [`with_diffuse_maps`].
pub fn gouraud_wgsl() -> String {
    with_diffuse_maps(&with_view(crate::passes::gouraud::GOURAUD_WGSL))
}

/// Each WGSL file under `src/` (path relative to `src/`) with the complete
/// module it is validated in: shared modules alone, passes as compiled.
pub fn all_wgsl() -> Vec<(&'static str, String)> {
    vec![
        ("shaders/common/color.wgsl", COLOR_WGSL.to_owned()),
        ("shaders/common/material.wgsl", material_module()),
        (
            "shaders/common/material_storage.wgsl",
            format!(
                "{}\n@group(0) @binding(0) var<storage, read> materials: array<GpuMaterial>;\n{MATERIAL_STORAGE_WGSL}",
                material_module()
            ),
        ),
        (
            "shaders/common/diffuse_map.wgsl",
            with_diffuse_maps(
                "@group(0) @binding(0) var diffuse_maps: texture_2d_array<f32>;\n\
                 @group(0) @binding(1) var diffuse_map_sampler: sampler;",
            ),
        ),
        ("shaders/common/view.wgsl", VIEW_WGSL.to_owned()),
        ("passes/depth.wgsl", with_view(DEPTH_WGSL)),
        (
            "passes/accumulate.wgsl",
            crate::passes::accumulate::ACCUMULATE_WGSL.to_owned(),
        ),
        ("passes/splat.wgsl", crate::passes::splat::splat_wgsl()),
        (
            "passes/splat_lowres.wgsl",
            crate::passes::splat_lowres::SPLAT_LOWRES_WGSL.to_owned(),
        ),
        ("passes/tonemap.wgsl", TONEMAP_WGSL.to_owned()),
        (
            "passes/reflector_blend.wgsl",
            crate::passes::reflector_blend::REFLECTOR_BLEND_WGSL.to_owned(),
        ),
        ("passes/beams.wgsl", crate::passes::beams::beams_wgsl()),
        ("passes/shadow.wgsl", SHADOW_WGSL.to_owned()),
        (
            "passes/shadow_volume.wgsl",
            with_view(crate::passes::shadow_volume::SHADOW_VOLUME_WGSL),
        ),
        (
            "passes/emission.wgsl",
            with_view(crate::passes::emission::EMISSION_WGSL),
        ),
        ("passes/direct.wgsl", direct_wgsl()),
        (
            "passes/specular.wgsl",
            with_view(crate::passes::specular::SPECULAR_WGSL),
        ),
        (
            "passes/diffuse_texture.wgsl",
            crate::passes::diffuse_texture::diffuse_texture_wgsl(),
        ),
        ("passes/gouraud.wgsl", gouraud_wgsl()),
        (
            "passes/glossy_image.wgsl",
            with_view(crate::passes::glossy_image::GLOSSY_IMAGE_WGSL),
        ),
        (
            "passes/glossy_reflection.wgsl",
            crate::passes::glossy_reflection::GLOSSY_REFLECTION_WGSL.to_owned(),
        ),
        (
            "passes/radiance_map.wgsl",
            crate::passes::radiance_map::RADIANCE_MAP_WGSL.to_owned(),
        ),
    ]
}

#[cfg(test)]
mod tests {
    use std::path::{Path, PathBuf};

    use super::all_wgsl;

    /// Parses and validates `src` with naga, naming `path` in the diagnostic.
    fn validate(path: &str, src: &str) {
        let module = naga::front::wgsl::parse_str(src)
            .unwrap_or_else(|e| panic!("{path}: WGSL parse error:\n{}", e.emit_to_string(src)));
        naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::CLIP_DISTANCES,
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
        for (path, src) in all_wgsl() {
            validate(path, &src);
            // The variant with user clip distances, where the device has them.
            validate(path, &super::specialise(&src, true));
        }
    }

    #[test]
    fn scene_passes_write_clip_distances_only_when_specialised() {
        for (path, src) in all_wgsl() {
            let active = |module: &str, what: &str| {
                module
                    .lines()
                    .any(|l| l.contains(what) && !l.trim_start().starts_with("//"))
            };
            if src.contains(super::CLIP_MARKER) {
                assert!(!active(&src, "@builtin(clip_distances)"), "{path}");
                let clip = super::specialise(&src, true);
                assert!(active(&clip, "@builtin(clip_distances)"), "{path}");
                assert!(active(&clip, "= view_clip_distance("), "{path}");
            }
        }
    }

    #[test]
    fn every_wgsl_file_is_listed() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
        let mut files = Vec::new();
        wgsl_files(&root, &root, &mut files);
        files.sort();
        let mut listed: Vec<String> = all_wgsl().iter().map(|(p, _)| p.to_string()).collect();
        listed.sort();
        assert_eq!(files, listed, "a WGSL file is missing from all_wgsl()");
    }

    #[test]
    fn shared_wgsl_opens_with_a_notation_table() {
        for (path, src) in all_wgsl() {
            let src = src
                .split_once(lustre_brdf::shaders::BRDF_WGSL)
                .map_or(src.as_str(), |(_, rest)| rest.trim_start());
            let head: String = src.lines().take(12).collect::<Vec<_>>().join("\n");
            assert!(head.contains("Notation"), "{path} has no notation table");
        }
    }
}
