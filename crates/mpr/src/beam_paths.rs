//! Which photon hits the beams stand for (Duvenhage et al. 2010, section 3.1: beams model the light-to-specular-to-diffuse paths, L(S|G)DE): a photon's second hit when its first was on a scatterer (a mirror, a rough conductor, a dielectric interface or a thin slab). A frame that draws the beam pass leaves those hits out of its splats and diffuse textures so that the light is added once; later hits of the same photon (the caustic's own diffuse inter-reflection) stay.

use lustre_beams::ScatterMaterial;
use lustre_geometry::Scene;
use lustre_photon::HitRecord;

use crate::{MprError, Result};

/// Per surface of `scene`, whether its material scatters beams ([`ScatterMaterial::from_model`]).
pub fn scatterer_surfaces(scene: &Scene) -> Result<Vec<bool>> {
    let materials = scene
        .materials()
        .iter()
        .map(|m| {
            ScatterMaterial::from_model(&m.model)
                .map(|s| s.is_some())
                .map_err(|e| MprError::UnsupportedMaterial {
                    material: m.name.clone(),
                    message: e.to_string(),
                })
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(scene
        .surfaces()
        .iter()
        .map(|s| materials[s.material as usize])
        .collect())
}

/// Per record, whether the beams draw its light: bounce 2 right after a bounce-1 record of the same photon on a scatterer surface (`scatterer[surface]`). Records must hold whole photon paths in order, as the tracer writes them.
pub fn drawn_by_beams(records: &[HitRecord], scatterer: &[bool]) -> Vec<bool> {
    let mut previous: Option<&HitRecord> = None;
    records
        .iter()
        .map(|r| {
            let drawn = r.bounce == 2
                && previous.is_some_and(|p| {
                    p.bounce == 1 && scatterer.get(p.surface as usize).copied().unwrap_or(false)
                });
            previous = Some(r);
            drawn
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Vec2, Vec3};
    use lustre_geometry::Rgb;

    fn hit(surface: u32, bounce: u8) -> HitRecord {
        HitRecord {
            surface,
            triangle: 0,
            position: Vec2::ZERO,
            direction: Vec3::Y,
            light: 0,
            bounce,
            rho: Rgb::ONE,
        }
    }

    #[test]
    fn only_the_hit_after_a_first_scatter_is_drawn() {
        // Surface 1 scatters; 0 and 2 receive.
        let scatterer = [false, true, false];
        let records = [
            hit(1, 1), // light -> mirror
            hit(0, 2), // -> floor: the beam's
            hit(2, 3), // -> wall: stays
            hit(0, 1), // direct on the floor
            hit(1, 2), // -> mirror second: not a first scatter
            hit(2, 3), // stays
            hit(1, 1), // a new photon on the mirror
            hit(1, 2), // -> mirror again (L S S): the beam lights nothing there
        ];
        assert_eq!(
            drawn_by_beams(&records, &scatterer),
            [false, true, false, false, false, false, false, true]
        );
    }

    #[test]
    fn scatterers_of_the_caustic_scenes_are_their_specular_surfaces() {
        let scene = lustre_geometry::builtin::cardioid();
        let s = scatterer_surfaces(&scene).unwrap();
        assert_eq!(s.len(), scene.surfaces().len());
        for (surface, &is) in scene.surfaces().iter().zip(&s) {
            let mirror = matches!(
                scene.materials()[surface.material as usize].model,
                lustre_geometry::MaterialModel::Mirror { .. }
            );
            assert_eq!(is, mirror);
        }
        assert!(s.iter().any(|&x| x) && s.iter().any(|&x| !x));
    }
}
