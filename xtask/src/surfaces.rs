//! Which surface each pixel of a built-in scene's image sees, for errors per
//! surface (a speckled glossy reflection hides in the whole-image number).
//!
//! The references are box-filtered, so a pixel averages everything its
//! square sees: a pixel counts for a mesh only when every one of `n × n`
//! stratified camera rays through it hits that mesh first (lustre-geometry's
//! camera and BVH, the scene at its pose at time 0 like a single render).

use anyhow::{Result, bail};
use glam::Vec2;
use lustre_geometry::builtin::builtin;
use lustre_geometry::{Bvh, Camera, MeshId, Scene};
use lustre_image::Image;
use lustre_image::metrics::RELATIVE_MSE_EPSILON;

/// Sub-pixel rays per axis: 4 × 4 per pixel.
pub const RAYS_PER_AXIS: u32 = 4;

/// The mesh each pixel of a `width × height` image sees whole.
#[derive(Debug, Clone)]
pub struct SurfaceMap {
    /// Per pixel, row-major from the top: the mesh all its rays hit, or `None` (an edge, or nothing).
    pub meshes: Vec<Option<MeshId>>,
    /// The scene's mesh names, by mesh id.
    pub names: Vec<String>,
}

impl SurfaceMap {
    /// Casts `n × n` stratified rays through every pixel of `scene`'s camera at aspect `width / height`.
    pub fn of_scene(scene: &Scene, width: u32, height: u32, n: u32) -> Self {
        let camera = scene.camera().with_aspect(width as f32 / height as f32);
        let bvh = Bvh::build(scene);
        let mut meshes = Vec::with_capacity((width * height) as usize);
        for y in 0..height {
            let rays: Vec<_> = (0..width)
                .flat_map(|x| {
                    (0..n * n).map(move |s| {
                        let offset = Vec2::new(
                            ((s % n) as f32 + 0.5) / n as f32,
                            ((s / n) as f32 + 0.5) / n as f32,
                        );
                        camera.primary_ray(Camera::pixel_ndc(x, y, width, height, offset))
                    })
                })
                .collect();
            let hits = bvh.closest_hits(&rays);
            for pixel in hits.chunks_exact((n * n) as usize) {
                let mut seen = pixel
                    .iter()
                    .map(|hit| hit.map(|h| scene.triangle_source(h.triangle).0));
                let first = seen.next().flatten();
                meshes.push(first.filter(|&m| seen.all(|other| other == Some(m))));
            }
        }
        Self {
            meshes,
            names: scene.meshes().iter().map(|m| m.name.clone()).collect(),
        }
    }

    /// The map of a built-in scene.
    pub fn of_builtin(scene: &str, width: u32, height: u32) -> Result<Self> {
        Ok(Self::of_scene(
            &builtin(scene)?,
            width,
            height,
            RAYS_PER_AXIS,
        ))
    }

    /// The id of the mesh named `name`.
    pub fn mesh(&self, name: &str) -> Result<MeshId> {
        match self.names.iter().position(|n| n == name) {
            Some(i) => Ok(i as MeshId),
            None => bail!(
                "no mesh `{name}`; the meshes are: {}",
                self.names.join(", ")
            ),
        }
    }

    /// Indices of the pixels that see only `mesh`.
    pub fn pixels_of(&self, mesh: MeshId) -> Vec<usize> {
        self.meshes
            .iter()
            .enumerate()
            .filter_map(|(i, m)| (*m == Some(mesh)).then_some(i))
            .collect()
    }
}

/// Relative MSE (Rousselle et al. 2011, ε = 0.01) over the given pixels only; `None` when there are none.
pub fn relative_mse_over(test: &Image, reference: &Image, pixels: &[usize]) -> Option<f64> {
    if pixels.is_empty() || test.pixels().len() != reference.pixels().len() {
        return None;
    }
    let sum: f64 = pixels
        .iter()
        .flat_map(|&i| {
            let (t, r) = (test.pixels()[i], reference.pixels()[i]);
            (0..3).map(move |c| {
                let (t, r) = (f64::from(t[c]), f64::from(r[c]));
                (t - r).powi(2) / (r * r + RELATIVE_MSE_EPSILON)
            })
        })
        .sum();
    Some(sum / (3 * pixels.len()) as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn glosbox_pixels_see_the_gold_box_and_the_floor() {
        let map = SurfaceMap::of_builtin("glosbox", 64, 64).unwrap();
        let gold = map.pixels_of(map.mesh("large-box").unwrap());
        let floor = map.pixels_of(map.mesh("floor").unwrap());
        // The large box stands left of centre, the floor fills the bottom.
        assert!(gold.len() > 64 * 64 / 50, "{}", gold.len());
        assert!(floor.len() > 64 * 64 / 20, "{}", floor.len());
        let centre_x = |pixels: &[usize]| {
            pixels.iter().map(|&i| (i % 64) as f64).sum::<f64>() / pixels.len() as f64
        };
        assert!(centre_x(&gold) < 32.0, "{}", centre_x(&gold));
        assert!(
            floor.iter().all(|&i| i / 64 >= 32),
            "the floor is below the horizon"
        );
        // The top-left pixel sees the ceiling and the red wall: an edge, counted for neither.
        assert_eq!(map.meshes[0], None);
        // The back wall between the boxes, below the light.
        let back = map.mesh("back").unwrap();
        assert_eq!(map.meshes[20 * 64 + 32], Some(back));
        assert!(map.mesh("nope").is_err());
    }

    #[test]
    fn relative_mse_over_counts_only_the_chosen_pixels() {
        let reference = Image::filled(2, 1, [1.0; 3]).unwrap();
        let test = Image::new(2, 1, vec![[1.0; 3], [2.0; 3]]).unwrap();
        assert_eq!(relative_mse_over(&test, &reference, &[0]), Some(0.0));
        let got = relative_mse_over(&test, &reference, &[1]).unwrap();
        assert!((got - 1.0 / 1.01).abs() < 1e-12, "{got}");
        assert_eq!(relative_mse_over(&test, &reference, &[]), None);
    }
}
