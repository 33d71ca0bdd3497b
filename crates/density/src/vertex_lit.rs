//! A scene meshed for per-vertex lighting (section 2.9: the estimate is made
//! at mesh vertices and interpolated between them, so surfaces are meshed
//! finely enough for the light's variation).

use lustre_geometry::Scene;
use lustre_geometry::meshing::subdivide;

use crate::error::Result;

/// `scene` with every non-emissive mesh subdivided regularly to edges of at most `edge` (section 2.9); emissive meshes keep their shape, so area lights stay the rectangles they were. Fails on a bad edge length (naming the mesh) or a scene that cannot be rebuilt.
pub fn vertex_lit_scene(scene: &Scene, edge: f32) -> Result<Scene> {
    let meshes = scene
        .meshes()
        .iter()
        .map(|mesh| {
            if scene.materials()[mesh.material as usize].is_emissive() {
                Ok(mesh.clone())
            } else {
                subdivide(mesh, edge)
            }
        })
        .collect::<lustre_geometry::Result<Vec<_>>>()?;
    Ok(scene.with_meshes(meshes)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use lustre_geometry::builtin;

    #[test]
    fn subdivision_keeps_the_light_a_rectangle_and_refines_the_rest() {
        let scene = builtin("cornell").unwrap();
        let fine = vertex_lit_scene(&scene, 0.5).unwrap();
        assert_eq!(fine.lights().len(), scene.lights().len());
        assert_eq!(fine.lights()[0].power(), scene.lights()[0].power());
        assert!(fine.triangle_count() > 10 * scene.triangle_count());
        assert!((fine.bounds().extent() - scene.bounds().extent()).length() < 1e-6);
        assert!(vertex_lit_scene(&scene, 0.0).is_err());
    }
}
