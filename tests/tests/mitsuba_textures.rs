//! Diffuse texture maps exported to Mitsuba 3 (`lustre_geometry::mitsuba`): a textured quad facing a point light at the camera renders with the texture the right way up and the radiance `ρ t / π · I cos θ / d²` of its texels.
//!
//! The quad's texture is red over its top half and blue over its bottom half
//! (OBJ's convention, `v` up, as the scene model keeps it). Mitsuba's
//! bitmap puts `(0, 0)` at the image's top-left corner, so an export that
//! got the convention wrong shows the quad upside down.
//!
//! Needs `.mitsuba-venv` at the workspace root (`cargo xtask reference
//! --install-only` creates it). Without it the test prints why and passes,
//! unless the environment variable `CI` is set: then it fails.

use std::path::Path;
use std::process::{Command, Stdio};
use std::sync::Arc;

use glam::{Affine3A, Vec2, Vec3};
use lustre_geometry::light::PointLight;
use lustre_geometry::mitsuba::{self, ExportOptions, ReconstructionFilter};
use lustre_geometry::{Camera, Light, Material, Mesh, Object, Rgb, Scene, Texture};
use lustre_tests::{mitsuba_python, root};

/// Image side in pixels.
const SIZE: u32 = 64;
/// The camera's distance from the quad (the light sits at the camera).
const DISTANCE: f32 = 3.0;
/// The camera's vertical field of view in degrees.
const FOV_Y: f32 = 60.0;
/// The point light's intensity in W/sr.
const INTENSITY: f32 = 10.0;
/// The quad's `Kd`, which the map scales.
const KD: f32 = 0.8;
/// The texels of the top half (rows 0 and 1 of four).
const TOP: Rgb = Rgb::new(0.9, 0.2, 0.1);
/// The texels of the bottom half (rows 2 and 3).
const BOTTOM: Rgb = Rgb::new(0.1, 0.2, 0.9);

/// The quad [-1, 1]² in the plane z = 0 facing +z, UVs `(x + 1)/2, (y + 1)/2` (v up), with a 1 × 4 map: two rows of [`TOP`] over two of [`BOTTOM`]; the camera and an isotropic point light at `(0, 0, DISTANCE)`.
fn textured_quad() -> Scene {
    let positions = [
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(1.0, -1.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(-1.0, 1.0, 0.0),
    ];
    let uvs: Vec<Vec2> = positions
        .iter()
        .map(|p| Vec2::new((p.x + 1.0) / 2.0, (p.y + 1.0) / 2.0))
        .collect();
    let quad = Mesh::flat_with_uvs("quad", &positions, &uvs, &[[0, 1, 2], [2, 3, 0]], 0);
    let texture = Texture::new("red-over-blue", 1, 4, vec![TOP, TOP, BOTTOM, BOTTOM]).unwrap();
    let material = Material::diffuse("quad", Rgb::splat(KD)).with_diffuse_map(Arc::new(texture));
    let eye = Vec3::new(0.0, 0.0, DISTANCE);
    Scene::new(
        "textured-quad",
        vec![quad],
        vec![material],
        vec![Object {
            name: "quad".into(),
            meshes: vec![0],
            transform: Affine3A::IDENTITY,
        }],
        vec![Light::Point(PointLight {
            position: eye,
            intensity: Rgb::splat(INTENSITY),
        })],
        Camera::look_at(eye, Vec3::ZERO, Vec3::Y, FOV_Y),
    )
    .unwrap()
}

/// Reads the first RGB layer of an EXR file: width and pixels, rows top to bottom.
fn read_exr(path: &Path) -> (usize, Vec<[f64; 3]>) {
    let image = exr::prelude::read_first_rgba_layer_from_file(
        path,
        |resolution, _| {
            let (w, h) = (resolution.width(), resolution.height());
            (w, vec![[0.0f64; 3]; w * h])
        },
        |(w, pixels), position, (r, g, b, _a): (f32, f32, f32, f32)| {
            pixels[position.y() * *w + position.x()] = [r as f64, g as f64, b as f64];
        },
    )
    .unwrap_or_else(|e| panic!("reading {}: {e}", path.display()));
    image.layer_data.channel_data.pixels
}

/// The radiance `ρ/π · I cos θ / d²` towards the camera of the quad's point under pixel `(column, row)`'s centre, and that point's height `y`.
fn expected_at(column: usize, row: usize) -> (Rgb, f32) {
    let half = (FOV_Y.to_radians() / 2.0).tan();
    let ndc = |i: usize| 1.0 - 2.0 * (i as f32 + 0.5) / SIZE as f32;
    // The camera looks down −z with +y up; the quad is at distance DISTANCE.
    let (x, y) = (-ndc(column) * half * DISTANCE, ndc(row) * half * DISTANCE);
    let d2 = x * x + y * y + DISTANCE * DISTANCE;
    let cos = DISTANCE / d2.sqrt();
    let texel = if y > 0.0 { TOP } else { BOTTOM };
    (KD * texel / std::f32::consts::PI * INTENSITY * cos / d2, y)
}

#[test]
fn textured_quad_renders_the_right_way_up_in_mitsuba() {
    let Some(python) = mitsuba_python("texture") else {
        return;
    };
    let dir = std::env::temp_dir().join(format!("lustre-mitsuba-textures-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let xml = dir.join("textured-quad.xml");
    let options = ExportOptions {
        width: SIZE,
        height: SIZE,
        spp: 64,
        max_depth: 2,
        filter: ReconstructionFilter::Box,
        ..ExportOptions::default()
    };
    let report = mitsuba::export(&textured_quad(), &xml, &options).unwrap();
    assert!(report.warnings.is_empty(), "{:?}", report.warnings);
    assert_eq!(report.textures.len(), 1);
    let out = dir.join("textured-quad.exr");
    let script = root()
        .join("xtask")
        .join("python")
        .join("mitsuba_render.py");
    let output = Command::new(&python)
        .arg(&script)
        .args(["--variant", "scalar_rgb", "--scene"])
        .arg(&xml)
        .arg("--out")
        .arg(&out)
        .stdin(Stdio::null())
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "Mitsuba failed: {}\n{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
    let (width, pixels) = read_exr(&out);
    let _ = std::fs::remove_dir_all(&dir);
    // Pixels whose quad points lie well inside a half's pure texels (v in [0.625, 0.875] or [0.125, 0.375]).
    let mut checked = 0;
    for row in 0..SIZE as usize {
        for column in [20, 31, 32, 44] {
            let (want, y) = expected_at(column, row);
            let v = (y + 1.0) / 2.0;
            if !((0.65..=0.85).contains(&v) || (0.15..=0.35).contains(&v)) {
                continue;
            }
            let got = pixels[row * width + column];
            for c in 0..3 {
                let w = f64::from(want[c]);
                assert!(
                    (got[c] - w).abs() <= 0.03 * w + 1e-4,
                    "pixel ({column}, {row}) at v = {v:.3}, channel {c}: Mitsuba {:.5}, expected {w:.5} (the {} texel)",
                    got[c],
                    if y > 0.0 { "top" } else { "bottom" }
                );
            }
            checked += 1;
        }
    }
    assert!(checked >= 40, "only {checked} pixels checked");
}
