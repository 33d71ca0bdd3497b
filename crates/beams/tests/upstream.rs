//! No beam lights a point upstream of its whole scatterer (Duvenhage et al.
//! 2010, section 3.1: a beam is the scatterer's rays beyond it). Every ray
//! of a beam, and every support ray of a glossy one, moves along the
//! wavefront normal `n` (at most 85° from it), so no point of the beam
//! volume or the glossy support has `n · p` below the scatterer's smallest
//! `n · o`: the flux plane through such a point meets every ray behind its
//! scatterer vertex, where the triangle the three rays extrapolate to shrinks
//! to the beam's apex and `Φ_s / A_⊥` grows without bound. On glosbox the
//! gold box's side faces reflect the light downwards and sideways, and the
//! green wall's top, in front of their planes but above them, drew
//! isolated pixels of that unbounded light under `--technique beams`.

use glam::Vec3;
use lustre_beams::{BeamSet, BuildOptions, GlossyVolume};
use lustre_geometry::builtin;

#[test]
fn no_beam_lights_a_point_upstream_of_its_scatterer() {
    let scene = builtin("glosbox")
        .unwrap()
        .with_area_lights_as_points()
        .unwrap();
    let options = BuildOptions {
        shadow_beams: false,
        glossy_volume: GlossyVolume::Integrated,
        ..BuildOptions::default()
    };
    let set = BeamSet::from_scene(&scene, &options).unwrap();
    assert!(set.beams().iter().any(|b| b.distribution.is_some()));
    let bounds = scene.bounds();
    let steps = 40;
    let (mut upstream, mut in_front) = (0, 0);
    for beam in set.beams() {
        let n = beam.wavefront_normal;
        let lowest = beam
            .vertices
            .map(|o| o.dot(n))
            .into_iter()
            .fold(f32::MAX, f32::min);
        for i in 0..=steps {
            for j in 0..=steps {
                for k in 0..=steps {
                    let f = Vec3::new(i as f32, j as f32, k as f32) / steps as f32;
                    let p = bounds.min + (bounds.max - bounds.min) * f;
                    if p.dot(n) >= lowest {
                        continue;
                    }
                    upstream += 1;
                    in_front += usize::from(beam.in_front(p));
                    for normal in [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z] {
                        assert!(
                            beam.arrival(p, normal).is_none(),
                            "beam of scatterer {} lights {p} (normal {normal}) upstream of it: {:?}",
                            beam.scatterer,
                            beam.arrival(p, normal)
                        );
                    }
                }
            }
        }
    }
    // The case at stake: points upstream yet in front of a generator plane.
    assert!(
        in_front > 1000,
        "{in_front} of {upstream} upstream points in front"
    );
}
