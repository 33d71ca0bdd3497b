//! `--ibr-cache`: the key under which `--technique ibr`'s radiance maps are
//! stored in a [`lustre_ibr::cache`] file, so the capture (Bastos et al.
//! 1999, section 6's preprocessing) runs once per scene, lighting and
//! sampling.
//!
//! The key is a 64-bit FNV-1a hash (the `fnv` crate: a fixed algorithm, so
//! a key written by one run is the key of the next) of this build's
//! version, the scene as loaded (its `Debug` form: every triangle, material,
//! light and the camera) and every render option except those that cannot
//! change what the maps hold: the image size, output path, exposure,
//! antialiasing, adapter choice, frame counts and camera path, the terms
//! drawn and their images, and the cache path itself, and with one capture pass (`--ibr-bounces 1`) the per-frame
//! options (maps per hemisphere, selection, kernel, modulation, resolution),
//! which only later passes draw into the maps. A photon file enters by its path, length and modification
//! time. An option added later enters the key unless it is listed here, so
//! a new option can cost a recapture but never reuses stale maps. The maps
//! also depend on the renderer's code: a cache written by another version of
//! Lustre is a miss, one written by a changed build of the same version is
//! not, so delete it after changing the renderer.

use std::fmt::Write as _;
use std::hash::Hasher;
use std::path::PathBuf;

use fnv::FnvHasher;
use lustre_geometry::Scene;

use crate::render::{
    IbrKernelArg, IbrModulationArg, IbrResolutionArg, IbrSelectionArg, RenderArgs,
};

/// A [`std::fmt::Write`] that feeds the hasher instead of building a string (the house's `Debug` form is tens of megabytes).
struct HashWriter(FnvHasher);

impl std::fmt::Write for HashWriter {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        self.0.write(s.as_bytes());
        Ok(())
    }
}

/// The cache key of the maps `args` capture of `scene` (module documentation).
pub fn key(args: &RenderArgs, scene: &Scene) -> u64 {
    let mut neutral = args.clone();
    neutral.scene = String::new();
    neutral.size = (0, 0);
    neutral.out = PathBuf::new();
    neutral.exposure = 0.0;
    neutral.aa = 0;
    neutral.software = false;
    neutral.frames = None;
    neutral.timing_only = false;
    neutral.camera_path = None;
    neutral.path_frames = None;
    neutral.ibr_cache = None;
    // The maps are captured with every term; `--terms` only leaves terms out of the frames drawn.
    neutral.terms = None;
    neutral.term_images = false;
    if args.ibr_bounces == 1 {
        // One capture pass draws no reflector's term into the maps: how the
        // maps are selected, convolved and modulated per frame is not in them.
        neutral.ibr_maps = 0;
        neutral.ibr_selection = IbrSelectionArg::Angle;
        neutral.ibr_kernel = IbrKernelArg::Invariant;
        neutral.ibr_modulation = IbrModulationArg::Albedo;
        neutral.ibr_resolution = IbrResolutionArg::Glossiness;
    }
    let photons_file = args.photons_file.as_ref().map(|path| {
        std::fs::metadata(path)
            .ok()
            .map(|m| (m.len(), m.modified().ok()))
    });
    let mut w = HashWriter(FnvHasher::default());
    // Writing to a HashWriter cannot fail.
    let _ = write!(
        w,
        "lustre {} | {neutral:?} | {photons_file:?} | {scene:?}",
        env!("CARGO_PKG_VERSION")
    );
    w.0.finish()
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: RenderArgs,
    }

    fn args(extra: &[&str]) -> RenderArgs {
        let mut argv = vec!["lustre", "glosbox", "--technique", "ibr"];
        argv.extend_from_slice(extra);
        Cli::parse_from(argv).args
    }

    #[test]
    fn the_key_ignores_the_view_and_follows_the_lighting_and_sampling() {
        let scene = lustre_geometry::builtin::glosbox();
        let base = key(&args(&[]), &scene);
        assert_eq!(base, key(&args(&[]), &scene), "the key is deterministic");
        for same in [
            &["--size", "64x48"][..],
            &["--out", "elsewhere.png"],
            &["--exposure", "2"],
            &["--aa", "1"],
            &["--ibr-cache", "maps.ibr"],
        ] {
            assert_eq!(base, key(&args(same), &scene), "{same:?} changed the key");
        }
        // The second pass draws the reflectors as a frame does; the first does not.
        assert_ne!(base, key(&args(&["--ibr-maps", "4"]), &scene));
        let one = key(&args(&["--ibr-bounces", "1"]), &scene);
        assert_eq!(
            one,
            key(&args(&["--ibr-bounces", "1", "--ibr-maps", "4"]), &scene)
        );
        for other in [
            &["--photons", "1000"][..],
            &["--seed", "7"],
            &["--ibr-map-size", "32"],
            &["--ibr-arc-step", "45"],
            &["--ibr-bounces", "1"],
        ] {
            assert_ne!(base, key(&args(other), &scene), "{other:?} kept the key");
        }
        let mut moved = scene.clone();
        moved.name.push('2');
        assert_ne!(base, key(&args(&[]), &moved), "the scene enters the key");
    }
}
