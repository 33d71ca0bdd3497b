//! `lustre render --technique composed`: `L = direct + k_d D + k_s (M * K) R
//! + caustics` in one frame, and its terms written one by one.

mod support;

use std::path::Path;

use support::{render_or_skip, scratch, sidecar};

/// The five terms `--term-images` writes, in its order.
const TERMS: [&str; 5] = ["emission", "direct", "diffuse", "glossy", "caustics"];

/// Renders `glosbox` composed at 48 × 36 with `extra` arguments and
/// `--term-images` into `dir`; the sidecar, or `None` when skipped.
fn render_terms(test: &str, dir: &Path, extra: &[&str]) -> Option<serde_json::Value> {
    let out = dir.join("c.exr");
    let mut args = vec![
        "render",
        "glosbox",
        "--technique",
        "composed",
        "--photons",
        "20000",
        "--seed",
        "2",
        "--size",
        "48x36",
        "--aa",
        "2",
        "--term-images",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let result = render_or_skip(test, &args)?;
    assert!(
        result.status.success(),
        "{}",
        String::from_utf8_lossy(&result.stderr)
    );
    Some(sidecar(&out))
}

/// Asserts that each term image in `dir` is finite and not negative, that
/// those but `dark` carry light, and that they sum to the frame `c.exr`:
/// every term is in the frame once, none is missing or drawn twice.
fn assert_terms_add_up(dir: &Path, info: &serde_json::Value, dark: &[&str]) {
    let frame = lustre_image::read_exr(dir.join("c.exr")).unwrap();
    let mut sum = vec![[0.0f32; 3]; (frame.width() * frame.height()) as usize];
    for term in TERMS {
        let path = dir.join(format!("c-{term}.exr"));
        assert_eq!(
            info["term_images"][term],
            path.to_str().unwrap(),
            "{term}: {info}"
        );
        let image = lustre_image::read_exr(&path).unwrap();
        let mean = lustre_image::metrics::mean(&image);
        assert!(
            mean.iter().all(|&m| m >= 0.0 && m.is_finite()),
            "{term}: {mean:?}"
        );
        assert!(
            dark.contains(&term) || mean.iter().all(|&m| m > 0.0),
            "{term} carries no light: {mean:?}"
        );
        for (s, p) in sum.iter_mut().zip(image.pixels()) {
            for c in 0..3 {
                s[c] += p[c];
            }
        }
    }
    let mut worst = 0.0f32;
    for (s, f) in sum.iter().zip(frame.pixels()) {
        for c in 0..3 {
            // Half-float targets round each pass's sum to 11 bits.
            let err = (s[c] - f[c]).abs() / (f[c].abs() + 1e-2);
            worst = worst.max(err);
        }
    }
    assert!(worst < 5e-3, "the terms' sum is {worst} off the frame");
}

/// The default composition of `glosbox`: direct light under shadow volumes,
/// the Lambertian lobes from diffuse textures, the floor and the gold box's
/// faces as glossy images, the gold box's glossy beams, splats elsewhere.
/// The glossy images draw the reflected scene with the frame's own terms,
/// so what the imaged faces reflect lands in those (direct, diffuse, ...)
/// and the glossy term holds only the splats of glossy surfaces that are
/// not imaged: none in `glosbox` at this size.
#[test]
fn the_composed_frames_terms_add_up_to_the_frame() {
    let test = "the_composed_frames_terms_add_up_to_the_frame";
    let dir = scratch("composed-terms");
    let Some(info) = render_terms(test, &dir, &[]) else {
        return;
    };
    assert_eq!(info["technique"], "composed", "{info}");
    assert_eq!(info["composed"]["reflectors"], "images", "{info}");
    assert_eq!(info["composed"]["caustics"], "beams", "{info}");
    assert!(
        info["glossy_images"]["imaged_surfaces"]
            .as_u64()
            .is_some_and(|n| n > 0),
        "{info}"
    );
    assert!(
        info["beams"]["scattered"].as_u64().is_some_and(|n| n > 0),
        "{info}"
    );
    assert_terms_add_up(&dir, &info, &["glossy"]);
}

/// The same with the reflectors from radiance maps (Bastos et al. 1999),
/// their reflected images at the frame's resolution, whose M does not
/// depend on the frame before.
#[test]
fn the_terms_add_up_with_radiance_maps() {
    let test = "the_terms_add_up_with_radiance_maps";
    let dir = scratch("composed-terms-maps");
    let extra = [
        "--reflectors",
        "maps",
        "--ibr-arc-step",
        "60",
        "--ibr-map-size",
        "16",
        "--ibr-resolution",
        "frame",
    ];
    let Some(info) = render_terms(test, &dir, &extra) else {
        return;
    };
    assert_eq!(info["composed"]["reflectors"], "maps", "{info}");
    assert!(info["radiance_maps"]["reflectors"].is_array(), "{info}");
    assert!(info["glossy_images"].is_null(), "{info}");
    assert_terms_add_up(&dir, &info, &[]);
}
