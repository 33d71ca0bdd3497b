//! Photon emission (section 2.1): photons per light in proportion to its power, and the random numbers of each photon.
//!
//! Every photon has its own random stream, keyed by the seed, its light and
//! its index among that light's photons, so a trace does not depend on how
//! the photons are spread over threads, and photons added later
//! (incremental refinement) continue each light's indices instead of
//! repeating earlier photons. Emission can use quasi-random points instead
//! (Halton or Sobol', Owen-scrambled by the seed), the paper's future work
//! ("Integration of Quasi-Monte Carlo Methods into the particle-tracing
//! phase", section 5): photon `k` of a light takes point `k` of the
//! sequence, dimensions 0-1 for the direction and 2-3 for the position on
//! the light; the bounces after emission use the photon's random stream.

use glam::Vec2;
use lustre_geometry::Rgb;
use lustre_geometry::sampling::{Halton, Pcg32, Sobol};

/// How emission positions and directions are drawn (section 2.1; quasi-random per section 5).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum EmissionSampling {
    /// Independent pseudo-random numbers (PCG32), as in the paper.
    #[default]
    Random,
    /// The Owen-scrambled Halton sequence (bases 2, 3, 5, 7).
    Halton,
    /// The Owen-scrambled Sobol' sequence (32-bit: indices wrap after 2^32 photons per light).
    Sobol,
}

/// SplitMix64's finaliser (Steele, Lea & Flood 2014), used to derive independent keys from a seed.
pub(crate) fn mix64(mut v: u64) -> u64 {
    v = v.wrapping_add(0x9E37_79B9_7F4A_7C15);
    v = (v ^ (v >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    v = (v ^ (v >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    v ^ (v >> 31)
}

/// The key of one light's photons under a seed.
pub(crate) fn light_key(seed: u64, light: u32) -> u64 {
    mix64(seed ^ mix64(u64::from(light) ^ 0x5048_4f54_4f4e))
}

/// The random stream of photon `index` of a light (section 2.1): PCG32 stream `key`, started at a position hashed from `index`.
pub fn photon_stream(seed: u64, light: u32, index: u64) -> Pcg32 {
    let key = light_key(seed, light);
    Pcg32::new(mix64(key ^ mix64(index)), key)
}

/// The four emission numbers `(u_position, u_direction)` of photon `index` of a light (section 2.1; section 5 for the quasi-random options).
pub fn emission_numbers(
    sampling: EmissionSampling,
    seed: u64,
    light: u32,
    index: u64,
    stream: &mut Pcg32,
) -> (Vec2, Vec2) {
    let key = light_key(seed, light);
    match sampling {
        EmissionSampling::Random => {
            let u_direction = stream.next_vec2();
            let u_position = stream.next_vec2();
            (u_position, u_direction)
        }
        EmissionSampling::Halton => {
            let h = Halton::scrambled(key);
            (
                Vec2::new(h.sample(index, 2), h.sample(index, 3)),
                Vec2::new(h.sample(index, 0), h.sample(index, 1)),
            )
        }
        EmissionSampling::Sobol => {
            let s = Sobol::scrambled(key);
            let i = index as u32;
            (
                Vec2::new(s.sample(i, 2), s.sample(i, 3)),
                Vec2::new(s.sample(i, 0), s.sample(i, 1)),
            )
        }
    }
}

/// Splits `photons` among lights in proportion to their power (section 2.1: "each light source i emits a number of photons proportional to its power Φ_i"), by the sum of the RGB channels, with largest remainders so the counts add up exactly.
pub fn allocate_photons(powers: &[Rgb], photons: u64) -> Vec<u64> {
    let weights: Vec<f64> = powers
        .iter()
        .map(|p| {
            let w = f64::from(p.x) + f64::from(p.y) + f64::from(p.z);
            if w.is_finite() && w > 0.0 { w } else { 0.0 }
        })
        .collect();
    let total: f64 = weights.iter().sum();
    if total <= 0.0 || photons == 0 {
        return vec![0; powers.len()];
    }
    let exact: Vec<f64> = weights.iter().map(|w| w / total * photons as f64).collect();
    let mut counts: Vec<u64> = exact.iter().map(|e| e.floor() as u64).collect();
    let assigned: u64 = counts.iter().sum();
    let mut order: Vec<usize> = (0..powers.len()).filter(|&i| weights[i] > 0.0).collect();
    // Largest fractional part first; ties by index, so the split is deterministic.
    order.sort_by(|&a, &b| {
        let (fa, fb) = (exact[a] - exact[a].floor(), exact[b] - exact[b].floor());
        fb.total_cmp(&fa).then(a.cmp(&b))
    });
    for &i in order
        .iter()
        .cycle()
        .take(photons.saturating_sub(assigned) as usize)
    {
        counts[i] += 1;
    }
    counts
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn allocation_is_proportional_and_exact() {
        let powers = [Rgb::splat(1.0), Rgb::splat(3.0), Rgb::ZERO];
        let c = allocate_photons(&powers, 1001);
        assert_eq!(c.iter().sum::<u64>(), 1001);
        assert_eq!(c[2], 0);
        assert!((c[1] as i64 - 751).abs() <= 1, "{c:?}");
        assert_eq!(allocate_photons(&[Rgb::ZERO], 10), vec![0]);
    }

    #[test]
    fn streams_differ_per_photon_and_light() {
        let a = photon_stream(1, 0, 0).next_u32();
        let b = photon_stream(1, 0, 1).next_u32();
        let c = photon_stream(1, 1, 0).next_u32();
        let d = photon_stream(2, 0, 0).next_u32();
        assert!(a != b && a != c && a != d);
        assert_eq!(a, photon_stream(1, 0, 0).next_u32());
    }
}
