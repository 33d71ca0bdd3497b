//! The jittered lights a view draws: all of them, or inside a glossy image
//! one group of them per sheared view, paired with the image's shear
//! (Diefenbach & Badler 1997, sections 3 and 4.4, accumulated as in
//! Haeberli & Akeley's accumulation buffer, the paper's reference 16).
//!
//! A glossy image averages `N` sheared views (`accbuf(ACCUMULATE)`), and
//! an area light is `L` jittered point lights whose images are summed
//! (section 4.4's "stochastic set of point light sources"). Drawing every
//! light in every sheared view estimates the double average over shears and
//! light points with `N · L` light passes per image; the accumulation
//! buffer's way is to jitter both in the same pass. With
//! [`GlossyLights::Paired`], the sheared view of sample path `p` draws only
//! the lights `i ≡ g(p) (mod G)`, each weighted `G`, with `G = gcd(L, N)`
//! and `g(p) = p·k mod G` (`k` coprime with `N`, about `0.382 N`): over the
//! `N` paths every group is drawn `N / G` times, so the image is the same
//! average with `L / G` light passes per sheared view instead of `L`. What it
//! costs is variance in the reflected penumbrae; the camera's own view
//! still draws every light. Images nested in a glossy image inherit its path
//! ([`crate::passes::specular::nested_shear_index`]), so a whole sample path
//! sees one group.
//!
//! The weight is applied by the direct pass's blend constant (its colour
//! blend is `src · C + dst`), which is exactly 1 for every other view.

use crate::passes::specular::GlossyPath;

/// Which jittered lights the sheared views of a glossy image draw.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum GlossyLights {
    /// Every light in every sheared view (the paper's loop as written).
    All,
    /// One group of `L / gcd(L, N)` lights per sheared view, paired with its
    /// shear and weighted by the group count (module docs).
    #[default]
    Paired,
}

/// The lights `i ≡ index (mod count)` of a view, each weighted `count`
/// (`count = 1`: every light at its own power).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LightGroup {
    /// The group drawn, `0..count`.
    pub index: u32,
    /// How many groups the lights are dealt into.
    pub count: u32,
}

impl Default for LightGroup {
    fn default() -> Self {
        Self::ALL
    }
}

impl LightGroup {
    /// Every light, weight 1.
    pub const ALL: Self = Self { index: 0, count: 1 };

    /// The group a view on glossy sample path `path` draws of `lights`
    /// jittered lights (module docs); [`LightGroup::ALL`] outside glossy
    /// images and under [`GlossyLights::All`].
    pub fn for_path(path: Option<GlossyPath>, lights: usize) -> Self {
        let Some(path) = path else {
            return Self::ALL;
        };
        if path.lights == GlossyLights::All || lights == 0 || path.of <= 1 {
            return Self::ALL;
        }
        let lights = u32::try_from(lights).unwrap_or(u32::MAX);
        let count = gcd(lights, path.of);
        if count <= 1 {
            return Self::ALL;
        }
        let k = coprime_step(path.of, 0.382);
        let index = ((u64::from(path.index % path.of) * u64::from(k)) % u64::from(count)) as u32;
        Self { index, count }
    }

    /// Whether light `i` is drawn.
    pub fn draws(&self, i: usize) -> bool {
        self.count <= 1 || i % self.count as usize == self.index as usize
    }

    /// The weight of each drawn light: the group count.
    pub fn weight(&self) -> f64 {
        f64::from(self.count.max(1))
    }

    /// The blend constant the direct pass draws this group's lights with (`src · C + dst`).
    pub fn blend_constant(&self) -> wgpu::Color {
        crate::passes::redraw::uniform_constant(self.weight())
    }
}

/// The greatest common divisor.
pub(crate) fn gcd(mut a: u32, mut b: u32) -> u32 {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

/// The first integer from `fraction · n` up (at least 1) that is coprime
/// with `n`: a step whose multiples `p · k mod n` permute `0..n` without
/// pairing like with like.
pub(crate) fn coprime_step(n: u32, fraction: f32) -> u32 {
    let n = n.max(1);
    let mut k = ((fraction * n as f32) as u32).max(1);
    while gcd(k, n) != 1 {
        k += 1;
    }
    k
}

#[cfg(test)]
mod tests {
    use super::*;

    fn path(index: u32, of: u32) -> Option<GlossyPath> {
        Some(GlossyPath {
            index,
            of,
            lights: GlossyLights::Paired,
        })
    }

    #[test]
    fn every_light_is_drawn_equally_often_over_the_paths() {
        for (lights, n) in [
            (16usize, 16u32),
            (16, 8),
            (4, 16),
            (80, 16),
            (17, 16),
            (12, 18),
        ] {
            let mut drawn = vec![0.0f64; lights];
            for p in 0..n {
                let group = LightGroup::for_path(path(p, n), lights);
                for (i, d) in drawn.iter_mut().enumerate() {
                    if group.draws(i) {
                        *d += group.weight();
                    }
                }
            }
            // Each light's total weight over the N paths is N: the average
            // over paths gives every light its own power, as drawing all.
            for (i, d) in drawn.iter().enumerate() {
                assert_eq!(*d, f64::from(n), "light {i} of {lights}, N = {n}");
            }
        }
    }

    #[test]
    fn groups_divide_the_lights_and_the_paths() {
        assert_eq!(LightGroup::for_path(path(3, 16), 16).count, 16);
        assert_eq!(LightGroup::for_path(path(3, 16), 4).count, 4);
        assert_eq!(LightGroup::for_path(path(3, 16), 17), LightGroup::ALL);
        assert_eq!(LightGroup::for_path(None, 16), LightGroup::ALL);
        let all = Some(GlossyPath {
            index: 3,
            of: 16,
            lights: GlossyLights::All,
        });
        assert_eq!(LightGroup::for_path(all, 16), LightGroup::ALL);
        // The paths of one glossy image draw distinct single lights.
        let mut seen: Vec<u32> = (0..16)
            .map(|p| LightGroup::for_path(path(p, 16), 16).index)
            .collect();
        seen.sort_unstable();
        assert_eq!(seen, (0..16).collect::<Vec<_>>());
    }

    #[test]
    fn the_step_is_coprime() {
        for n in 1..64 {
            for f in [0.382, 0.618] {
                assert_eq!(gcd(coprime_step(n, f), n.max(1)), 1);
            }
        }
    }
}
