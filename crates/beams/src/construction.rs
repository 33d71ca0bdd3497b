//! Beam construction (Duvenhage et al. 2010, section 3.1 and 4.3): from each point light through each scatterer triangle, the three vertex rays reflected or refracted into a scattered polygon beam, and a negative shadow beam behind the scatterer; in parallel over (light, scatterer) pairs with rayon.

use glam::Vec3;
use lustre_brdf::scatter_distribution::ScatterDistribution;
use lustre_brdf::{fresnel_conductor, fresnel_dielectric};
use lustre_geometry::Rgb;
use rayon::prelude::*;

use crate::beam::{Beam, BeamKind, GlossyVolume, Scatter, SplitPoint};
use crate::error::Result;
use crate::scatterer::{Emission, PointSource, ScatterMaterial, Scatterer};

/// Options of beam construction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BuildOptions {
    /// Trace negative shadow beams (section 3.1, first-order shadows).
    pub shadow_beams: bool,
    /// The largest volume `P_E` a glossy beam's cut-off may drop: a glossy beam is evaluated within [`glossy_cutoff`] standard deviations σ (as an angle) of its specular beam ([`Beam::support`]), far enough that no planar-facet volume over any domain beyond it exceeds this.
    pub glossy_epsilon: f32,
    /// Triangles with less area than this, relative to the square of their longest edge, are degenerate and skipped.
    pub min_relative_area: f32,
    /// Where glossy beams split the domain outside the flux triangle (section 4.2.2, figure 12).
    pub split_point: SplitPoint,
    /// How glossy beams find their volume `P_E` (section 4.2.2).
    pub glossy_volume: GlossyVolume,
}

impl Default for BuildOptions {
    fn default() -> Self {
        Self {
            shadow_beams: true,
            glossy_epsilon: 1e-3,
            min_relative_area: 1e-7,
            split_point: SplitPoint::Rescattered,
            glossy_volume: GlossyVolume::Facets,
        }
    }
}

/// What beam construction skipped, counted (section 3.1: "only scattering from the front side of a polygon").
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct BuildStats {
    /// (light, scatterer) pairs considered.
    pub pairs: usize,
    /// Scatterers skipped as degenerate (zero area, or collinear corners); counted once each.
    pub degenerate: usize,
    /// Pairs whose light lies in the scatterer's plane or sees no solid angle.
    pub edge_on: usize,
    /// Pairs with a reflector lit from behind: no scattered beam (the shadow
    /// beam stays); and pairs with a closed slab's face lit from inside the
    /// glass ([`Scatterer::slab_face`]): no beam at all, its partner face's
    /// beams carry that light and cast its shadow.
    pub back_facing: usize,
    /// Refracted beams left out because at least one vertex ray is totally internally reflected.
    pub total_internal_reflection: usize,
    /// Beams left out because a ray turns more than about 89° from their mean direction (no flux plane crosses all three rays), e.g. a large scatterer very close to the light.
    pub too_wide: usize,
    /// Scattered beams built.
    pub scattered: usize,
    /// Shadow beams built.
    pub shadow: usize,
}

/// `r = w - 2 (w·n) n`: the mirror direction of the incident unit direction `w` about the unit normal `n` (section 3.1, figure 4).
pub fn reflect(w: Vec3, n: Vec3) -> Vec3 {
    w - 2.0 * w.dot(n) * n
}

/// Snell's law in vector form: the refracted direction of the incident unit direction `w` through an interface with unit normal `n` on the incident side (`w·n < 0`) and `eta` = far index over near index; `None` on total internal reflection (section 3.1: "specular transmissive with a specified refraction index").
pub fn refract(w: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = -w.dot(n);
    let r = 1.0 / eta;
    let sin2_t = r * r * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some((r * w + (r * cos_i - cos_t) * n).normalize())
}

/// The solid angle `Ω_light` of the triangle `abc` seen from `o` (Van Oosterom & Strackee 1983: `tan(Ω/2) = |a·(b×c)| / (abc + (a·b)c + (a·c)b + (b·c)a)` with the corners relative to `o`); section 4.1's `Φ_s = I_light Ω_light`.
pub fn solid_angle(o: Vec3, [a, b, c]: [Vec3; 3]) -> f32 {
    let (a, b, c) = ((a - o).as_dvec3(), (b - o).as_dvec3(), (c - o).as_dvec3());
    let (la, lb, lc) = (a.length(), b.length(), c.length());
    let num = a.dot(b.cross(c)).abs();
    let den = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
    (2.0 * num.atan2(den)) as f32
}

/// The projected solid angle `∫ max(0, n · ω) dω` of triangle `[a, b, c]`
/// seen from `o` about the unit normal `n`: the triangle clipped to the
/// half-space in front of `n`, then Lambert's polygon formula
/// `½ Σ_i γ_i n · (p_i × p_{i+1}) / |p_i × p_{i+1}|` (γ_i the angle each
/// edge subtends). The exact flux a cosine point light of peak intensity I
/// sends through the triangle is `I` times it.
pub fn projected_solid_angle(o: Vec3, n: Vec3, [a, b, c]: [Vec3; 3]) -> f32 {
    let n = n.as_dvec3();
    let corners = [a, b, c].map(|v| (v - o).as_dvec3());
    // Sutherland–Hodgman against n · p >= 0.
    let mut polygon = Vec::with_capacity(4);
    for i in 0..3 {
        let (p, q) = (corners[i], corners[(i + 1) % 3]);
        let (dp, dq) = (n.dot(p), n.dot(q));
        if dp >= 0.0 {
            polygon.push(p);
        }
        if (dp >= 0.0) != (dq >= 0.0) {
            polygon.push(p + (q - p) * (dp / (dp - dq)));
        }
    }
    let mut sum = 0.0;
    for i in 0..polygon.len() {
        let (p, q) = (polygon[i], polygon[(i + 1) % polygon.len()]);
        let cross = p.cross(q);
        let len = cross.length();
        if len > 0.0 {
            sum += len.atan2(p.dot(q)) * n.dot(cross) / len;
        }
    }
    (0.5 * sum.abs()) as f32
}

/// The flux `light` sends through triangle `[a, b, c]` (section 4.1's
/// `Φ_s = I_light Ω_light`): exact for isotropic and cosine lights (the
/// cosine integrated over the triangle, [`projected_solid_angle`]); a spot
/// light's intensity is taken towards the centroid.
pub fn scatterer_flux(light: &PointSource, vertices: [Vec3; 3]) -> Rgb {
    let lp = light.position;
    match light.emission {
        Emission::Cosine { normal } => {
            light.intensity * projected_solid_angle(lp, normal, vertices)
        }
        Emission::Isotropic | Emission::Spot(_) => {
            let centroid = (vertices[0] + vertices[1] + vertices[2]) / 3.0;
            light.intensity_towards((centroid - lp).normalize()) * solid_angle(lp, vertices)
        }
    }
}

/// The cut-off k (in σ) beyond which the planar-facet volume of section 4.2.2 is below `epsilon` over any domain: with every corner at least kσ from the peak each is below `P_O exp(-k²/2)`, and the domain, a triangle with corners at most π from O, is at most `(3√3/4) π²`, so `k = √(2 ln((3√3/4) π² P_O / ε))` (at least 3). The facets overestimate the Gaussian far more when the domain is much wider than σ, so k grows as σ shrinks (about 6 to 7 for σ from 0.3 to 0.003 rad at ε = 1e-3).
pub fn glossy_cutoff(distribution: &ScatterDistribution, epsilon: f32) -> f32 {
    let area = 0.75 * 3f32.sqrt() * std::f32::consts::PI * std::f32::consts::PI;
    let ratio = area * distribution.peak() / epsilon.max(f32::MIN_POSITIVE);
    (2.0 * ratio.max(1.0).ln()).sqrt().max(3.0)
}

/// Everything built from one (light, scatterer) pair, and what was skipped.
struct PairBeams {
    beams: Vec<Beam>,
    stats: BuildStats,
}

/// Builds the scattered and shadow beams of every (light, scatterer) pair in parallel; degenerate scatterers are skipped and counted (section 4.3: "traces rays from the light source through the vertices of each scatterer to generate the reflected, refracted and shadow rays").
pub fn build_beams(
    lights: &[PointSource],
    scatterers: &[Scatterer],
    options: &BuildOptions,
) -> Result<(Vec<Beam>, BuildStats)> {
    for (i, l) in lights.iter().enumerate() {
        l.validate(i)?;
    }
    for (i, s) in scatterers.iter().enumerate() {
        s.validate(i)?;
    }
    let degenerate: Vec<bool> = scatterers
        .iter()
        .map(|s| is_degenerate(s, options.min_relative_area))
        .collect();
    let pairs: Vec<(usize, usize)> = (0..lights.len())
        .flat_map(|l| (0..scatterers.len()).map(move |s| (l, s)))
        .filter(|&(_, s)| !degenerate[s])
        .collect();
    let built: Vec<PairBeams> = pairs
        .par_iter()
        .map(|&(l, s)| pair_beams(l, &lights[l], s, &scatterers[s], options))
        .collect::<Result<_>>()?;
    let mut stats = BuildStats {
        degenerate: degenerate.iter().filter(|&&d| d).count(),
        ..BuildStats::default()
    };
    let mut beams = Vec::new();
    for b in built {
        stats.pairs += b.stats.pairs;
        stats.edge_on += b.stats.edge_on;
        stats.back_facing += b.stats.back_facing;
        stats.total_internal_reflection += b.stats.total_internal_reflection;
        stats.too_wide += b.stats.too_wide;
        stats.scattered += b.stats.scattered;
        stats.shadow += b.stats.shadow;
        beams.extend(b.beams);
    }
    Ok((beams, stats))
}

fn is_degenerate(s: &Scatterer, min_relative_area: f32) -> bool {
    let [a, b, c] = s.vertices;
    let twice_area = (b - a).cross(c - a).length();
    let longest = (b - a)
        .length_squared()
        .max((c - b).length_squared())
        .max((a - c).length_squared());
    !(twice_area > 2.0 * min_relative_area * longest) || s.normals.iter().any(|n| n.length() < 0.5)
}

/// The scattered and shadow beams of one light and one scatterer.
fn pair_beams(
    light_index: usize,
    light: &PointSource,
    scatterer_index: usize,
    s: &Scatterer,
    options: &BuildOptions,
) -> Result<PairBeams> {
    let mut stats = BuildStats {
        pairs: 1,
        ..BuildStats::default()
    };
    let mut beams = Vec::new();
    let [a, b, c] = s.vertices;
    let face = (b - a).cross(c - a).normalize();
    let lp = light.position;
    let height = face.dot(lp - a);
    let omega = solid_angle(lp, s.vertices);
    if height == 0.0 || !(omega > 0.0) {
        stats.edge_on = 1;
        return Ok(PairBeams { beams, stats });
    }
    // Orient the face and the vertex normals towards the light.
    let side = height.signum();
    if s.slab_face && side < 0.0 {
        stats.back_facing = 1;
        return Ok(PairBeams { beams, stats });
    }
    let n_light = face * side;
    let normals = s.normals.map(|n| (n * side).normalize());
    let centroid = (a + b + c) / 3.0;
    let w_centroid = (centroid - lp).normalize();
    let flux = scatterer_flux(light, s.vertices);
    let incident = s.vertices.map(|v| (v - lp).normalize());
    let cos_centroid = (-w_centroid.dot(n_light)).clamp(0.0, 1.0);
    let roughness = s.material.roughness();
    let glossy =
        |d: lustre_brdf::Result<ScatterDistribution>| -> Result<Option<ScatterDistribution>> {
            if roughness > 0.0 {
                Ok(Some(d?))
            } else {
                Ok(None)
            }
        };
    let too_wide = std::cell::Cell::new(0);
    let make = |kind: BeamKind,
                directions: [Vec3; 3],
                flux: Rgb,
                generator_normal: Vec3,
                distribution: Option<ScatterDistribution>,
                scatter: Scatter| {
        let beam = Beam::new(
            kind,
            light_index,
            scatterer_index,
            s.vertices,
            directions,
            flux,
            generator_normal,
            distribution,
            distribution.map_or(0.0, |d| glossy_cutoff(&d, options.glossy_epsilon)),
        );
        if beam.is_none() && flux != Rgb::ZERO {
            too_wide.set(too_wide.get() + 1);
        }
        beam.map(|b| {
            b.with_scatter(lp, normals, scatter, options.split_point)
                .with_volume(options.glossy_volume)
        })
    };
    let reflected = || incident_map(incident, normals, reflect);
    match s.material {
        ScatterMaterial::Reflector {
            reflectance,
            conductor,
            ..
        } => {
            if side < 0.0 {
                stats.back_facing = 1;
            } else {
                let fresnel = match conductor {
                    Some((eta, k)) => fresnel_conductor(cos_centroid, eta, k),
                    None => Rgb::ONE,
                };
                let dist = glossy(ScatterDistribution::from_beckmann_alpha(roughness))?;
                beams.extend(make(
                    BeamKind::Reflected,
                    reflected(),
                    flux * reflectance * fresnel,
                    n_light,
                    dist,
                    Scatter::Reflect,
                ));
            }
        }
        ScatterMaterial::Interface {
            ior, transmittance, ..
        } => {
            // Far index over near index, as seen from the light's side.
            let eta = if side > 0.0 { ior } else { 1.0 / ior };
            let f = fresnel_dielectric(cos_centroid, eta);
            let dist = glossy(ScatterDistribution::from_beckmann_alpha(roughness))?;
            beams.extend(make(
                BeamKind::Reflected,
                reflected(),
                flux * f,
                n_light,
                dist,
                Scatter::Reflect,
            ));
            let refracted: Option<Vec<Vec3>> = incident
                .iter()
                .zip(&normals)
                .map(|(&w, &n)| refract(w, n, eta))
                .collect();
            match refracted {
                Some(r) if f < 1.0 => {
                    let dist = if (eta - 1.0).abs() > 0.0 {
                        glossy(ScatterDistribution::from_beckmann_alpha_refracted(
                            roughness, eta,
                        ))?
                    } else {
                        None
                    };
                    beams.extend(make(
                        BeamKind::Refracted,
                        [r[0], r[1], r[2]],
                        flux * (1.0 - f) * transmittance,
                        -n_light,
                        dist,
                        Scatter::Refract { eta },
                    ));
                }
                _ => stats.total_internal_reflection = 1,
            }
        }
        ScatterMaterial::ThinSlab {
            ior, transmittance, ..
        } => {
            let f = fresnel_dielectric(cos_centroid, ior);
            let (r, t) = (2.0 * f / (1.0 + f), (1.0 - f) / (1.0 + f));
            let dist = glossy(ScatterDistribution::from_beckmann_alpha(roughness))?;
            beams.extend(make(
                BeamKind::Reflected,
                reflected(),
                flux * r,
                n_light,
                dist,
                Scatter::Reflect,
            ));
            let dist = if (ior - 1.0).abs() > 0.0 {
                glossy(ScatterDistribution::from_beckmann_alpha_thin_slab(
                    roughness, ior,
                ))?
            } else {
                None
            };
            beams.extend(make(
                BeamKind::Transmitted,
                incident,
                flux * t * transmittance,
                -n_light,
                dist,
                Scatter::Straight,
            ));
        }
    }
    stats.scattered = beams.len();
    if options.shadow_beams {
        let before = beams.len();
        beams.extend(make(
            BeamKind::Shadow,
            incident,
            -flux,
            -n_light,
            None,
            Scatter::Straight,
        ));
        stats.shadow = beams.len() - before;
    }
    stats.too_wide = too_wide.get();
    Ok(PairBeams { beams, stats })
}

fn incident_map(w: [Vec3; 3], n: [Vec3; 3], f: impl Fn(Vec3, Vec3) -> Vec3) -> [Vec3; 3] {
    [f(w[0], n[0]), f(w[1], n[1]), f(w[2], n[2])]
}
