//! One polygon beam: three vertex rays with a flux, its flux plane and flux triangle, the point-in-beam test, and its irradiance at a fragment, specular (Duvenhage et al. 2010, section 3.1, equation 1) or glossy (section 4.2, equation 5, figures 11 and 12).

use glam::{Vec2, Vec3};
use lustre_brdf::scatter_distribution::ScatterDistribution;
use lustre_geometry::{Aabb, Rgb};

/// What made a beam.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum BeamKind {
    /// Reflected off the scatterer (mirror, conductor, or the Fresnel part of a dielectric).
    Reflected,
    /// Refracted through a dielectric interface by Snell's law.
    Refracted,
    /// Straight through a thin slab.
    Transmitted,
    /// The negative shadow beam behind the scatterer (section 3.1, first-order shadows): the light it blocks, subtracted.
    Shadow,
}

/// How a beam's rays left the scatterer, to re-scatter a ray from any point of it (the split point D of section 4.3, figure 12, step 3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Scatter {
    /// Mirror reflection about the interpolated normal.
    Reflect,
    /// Refraction about the interpolated normal, `eta` the far index over the near one.
    Refract {
        /// Far index over near index, seen from the light.
        eta: f32,
    },
    /// Straight on (thin slabs, shadow beams).
    Straight,
}

/// Where the outside case of the glossy volume splits the domain's edge (section 4.2.2, figure 12): the point D whose value stands for the Gaussian's local maximum along the edge nearest the peak.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum SplitPoint {
    /// D on the edge of the 2D domain ABC, where the line from O through the opposite vertex crosses it: exactly continuous across the flux triangle's edges and the cheapest; it stays within about 1 % of [`SplitPoint::Rescattered`]'s `P_E` outside the beams of `tests/glossy.rs` (the straight edge of ABC follows the angle along the scatterer's edge closely).
    Domain,
    /// The paper's construction (figure 12, step 3): `D_F` where the line from F through the opposite flux-triangle vertex crosses the edge, its parameter s taken to the scatterer's edge, `D_W` there, the ray re-scattered from `D_W` giving `φ_d` and `l_d`, and `D = φ_d l_d`. The linear parameter puts `D_W` off the ray through `D_F`, so `P_E` steps at the flux triangle's edges (`tests/glossy.rs` measures it).
    Paper,
    /// As [`SplitPoint::Paper`], with `D_W` the point of the scatterer's edge whose re-scattered ray crosses the flux triangle's edge at `D_F` (bisection): `φ_d` is the true angle at that edge point, and at the flux triangle's edge `D = O`, continuous with the inside case (exactly for beams with one apex, up to the edge's warp otherwise). The default: the paper's construction made consistent.
    #[default]
    Rescattered,
}

/// How a glossy beam's volume `P_E` over the domain ABC is found (section 4.2.2).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum GlossyVolume {
    /// The paper's planar facets through the Gaussian's values at the corners (figures 11 and 12), clamped to one: they widen the beam by about σ at full strength, so the beam's light exceeds its flux.
    #[default]
    Facets,
    /// The Gaussian integrated over ABC ([`ScatterDistribution::triangle_volume_integrated`]): the "better approximation" section 4.2.2 asks for; no split point.
    Integrated,
}

/// The least cosine between a vertex ray and the beam's mean direction; beams wider than this (about 89.4°) are not built.
const MIN_COS: f32 = 0.01;
/// The widest angle from the mean direction a glossy beam's support reaches (85°).
const MAX_SUPPORT_ANGLE: f32 = 85.0 * std::f32::consts::PI / 180.0;

/// A polygon beam: rays from the scatterer's corners `A_W, B_W, C_W` along the scattered (or, for shadow beams, the incident) unit directions, carrying the flux `Φ_s` (negative for shadow beams) through every cross-section (section 3.1: "each triplet of vectors is associated with a beam flux that is conserved within the beam"; section 4.3's beam attributes).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Beam {
    /// What made it.
    pub kind: BeamKind,
    /// Index of its light.
    pub light: usize,
    /// Index of its scatterer.
    pub scatterer: usize,
    /// Ray origins: the scatterer's corners.
    pub vertices: [Vec3; 3],
    /// Unit ray directions: the specular scatter directions `S_A, S_B, S_C`.
    pub directions: [Vec3; 3],
    /// The beam flux `Φ_s = I_light Ω_light` times the scatterer's reflectance or transmittance (negative for shadow beams), RGB.
    pub flux: Rgb,
    /// The glossy scatter distribution ρ (section 4.2); `None` for a specular beam.
    pub distribution: Option<ScatterDistribution>,
    /// Unit normal of the generator plane (the scatterer's plane), towards the side the beam goes.
    pub generator_normal: Vec3,
    /// Offset of the generator plane: `generator_normal · x` for x on it.
    pub generator_offset: f32,
    /// The average wavefront normal: the flux plane's normal (section 3.1, figure 5).
    pub wavefront_normal: Vec3,
    /// The rays bounding where a glossy beam is evaluated: the directions turned away from the mean by the cut-off angle (equal to `directions` for specular beams).
    pub support_directions: [Vec3; 3],
    /// Position of the light the beam comes from.
    pub light_position: Vec3,
    /// The scatterer's vertex normals, on the light's side.
    pub normals: [Vec3; 3],
    /// How the rays left the scatterer.
    pub scatter: Scatter,
    /// Which split point the glossy volume uses.
    pub split_point: SplitPoint,
    /// How the glossy volume is found.
    pub volume: GlossyVolume,
}

/// The flux triangle `A_F B_F C_F`: where the three rays cross the flux plane through a fragment, perpendicular to the average wavefront normal (section 3.1, figure 5).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FluxTriangle {
    /// `A_F, B_F, C_F`.
    pub vertices: [Vec3; 3],
    /// Its area `A_⊥`.
    pub area: f32,
    /// The fragment's barycentric coordinates in it (all non-negative inside).
    pub barycentrics: [f32; 3],
}

impl FluxTriangle {
    /// Whether the fragment lies in the flux triangle (section 3.1: "the fragment-in-beam test may be reduced to whether or not the fragment (F) is within the flux triangle").
    pub fn contains_fragment(&self) -> bool {
        self.barycentrics.iter().all(|&b| b >= 0.0)
    }
}

impl Beam {
    /// A beam from its rays; `None` when a ray turns more than about 89° from the mean direction (no flux plane crosses all three) or the flux is zero. `cutoff` is the glossy cut-off in standard deviations ([`crate::glossy_cutoff`]). Its split point is [`SplitPoint::Domain`] until [`Beam::with_scatter`] says how the rays left the scatterer.
    pub fn new(
        kind: BeamKind,
        light: usize,
        scatterer: usize,
        vertices: [Vec3; 3],
        directions: [Vec3; 3],
        flux: Rgb,
        generator_normal: Vec3,
        distribution: Option<ScatterDistribution>,
        cutoff: f32,
    ) -> Option<Self> {
        if flux == Rgb::ZERO || !flux.is_finite() {
            return None;
        }
        let mean = (directions[0] + directions[1] + directions[2]).normalize_or_zero();
        if mean == Vec3::ZERO || directions.iter().any(|d| d.dot(mean) < MIN_COS) {
            return None;
        }
        let centroid = (vertices[0] + vertices[1] + vertices[2]) / 3.0;
        let support_directions = match distribution {
            None => directions,
            Some(d) => widened_beam(
                directions,
                vertices,
                mean,
                (cutoff * d.variance.sqrt()).min(MAX_SUPPORT_ANGLE),
            )
            .unwrap_or_else(|| {
                let widen = cutoff * d.variance.sqrt();
                std::array::from_fn(|i| widened(directions[i], mean, vertices[i] - centroid, widen))
            }),
        };
        Some(Self {
            kind,
            light,
            scatterer,
            vertices,
            directions,
            flux,
            distribution,
            generator_normal,
            generator_offset: generator_normal.dot(vertices[0]),
            wavefront_normal: mean,
            support_directions,
            light_position: Vec3::ZERO,
            normals: [generator_normal; 3],
            scatter: Scatter::Straight,
            split_point: SplitPoint::Domain,
            volume: GlossyVolume::Facets,
        })
    }

    /// This beam with how its rays left the scatterer (light, vertex normals, reflection or refraction) and the split point to use, for [`SplitPoint::Paper`] and [`SplitPoint::Rescattered`].
    pub fn with_scatter(
        mut self,
        light_position: Vec3,
        normals: [Vec3; 3],
        scatter: Scatter,
        split_point: SplitPoint,
    ) -> Self {
        self.light_position = light_position;
        self.normals = normals;
        self.scatter = scatter;
        self.split_point = split_point;
        self
    }

    /// This beam with its glossy volume found by `volume`.
    pub fn with_volume(mut self, volume: GlossyVolume) -> Self {
        self.volume = volume;
        self
    }

    /// Whether `p` lies strictly on the beam's side of the generator plane (section 4.3: the generator plane's normal and offset are beam attributes).
    pub fn in_front(&self, p: Vec3) -> bool {
        self.generator_normal.dot(p) - self.generator_offset > 0.0
    }

    /// The flux triangle of the beam's rays at the flux plane through `p` (section 3.1, figure 5); `None` where it degenerates (a focus), and where the plane lies upstream of every scatterer vertex (`n · p < n · o_i` for all three: the rays, each moving along the wavefront normal `n`, never reach it, and the triangle extrapolated behind the scatterer shrinks to the beam's apex).
    pub fn flux_triangle(&self, p: Vec3) -> Option<FluxTriangle> {
        flux_triangle(&self.vertices, &self.directions, self.wavefront_normal, p)
    }

    /// Whether `p` is in the beam volume: in front of the generator plane and inside the flux triangle (section 3.1).
    pub fn contains(&self, p: Vec3) -> bool {
        self.in_front(p) && self.flux_triangle(p).is_some_and(|t| t.contains_fragment())
    }

    /// Whether `p` is where the beam is evaluated: the beam volume for a specular beam; for a glossy one the volume whose edges lie [`crate::glossy_cutoff`] σ further out (at most 85° from the mean direction), beyond which its Gaussian is cut off.
    pub fn support(&self, p: Vec3) -> bool {
        if self.distribution.is_none() {
            return self.contains(p);
        }
        self.in_front(p) && self.support_holds(p)
    }

    /// Whether `p` is inside the flux triangle of the support rays (a glossy beam's widened edges).
    fn support_holds(&self, p: Vec3) -> bool {
        flux_triangle(
            &self.vertices,
            &self.support_directions,
            self.wavefront_normal,
            p,
        )
        .is_some_and(|t| t.contains_fragment())
    }

    /// The irradiance the beam gives a fragment at `p` with unit normal `normal`: `E = Φ_s / A_⊥ cos θ` inside a specular beam (equation 1), `E = Φ_s / A_⊥ cos θ min(P_E, 1)` for a glossy one (section 4.2, figures 11 and 12), zero outside the support; negative for shadow beams.
    pub fn irradiance(&self, p: Vec3, normal: Vec3) -> Rgb {
        self.arrival(p, normal).map_or(Rgb::ZERO, |(e, _)| e)
    }

    /// [`Beam::irradiance`] with the unit direction `d` the light travels at `p`, for a receiver's BRDF: `None` where the beam adds nothing. `d` is the vertex directions interpolated with the fragment's barycentrics in the flux triangle (clamped to the triangle outside it, so that glossy beams stay continuous); `cos θ = max(-d · normal, 0)`.
    pub fn arrival(&self, p: Vec3, normal: Vec3) -> Option<(Rgb, Vec3)> {
        if !self.in_front(p) {
            return None;
        }
        let ft = self.flux_triangle(p)?;
        // [`Beam::support`], with a specular beam's flux triangle computed once.
        let held = match self.distribution {
            None => ft.contains_fragment(),
            Some(_) => self.support_holds(p),
        };
        if !held {
            return None;
        }
        let d = self.interpolated_direction(&ft);
        let cos_theta = (-d.dot(normal)).max(0.0);
        if cos_theta <= 0.0 {
            return None;
        }
        let density = self.flux / ft.area * cos_theta;
        let e = match self.distribution {
            None => density,
            Some(dist) => density * self.scatter_volume(&dist, &ft, p).min(1.0),
        };
        Some((e, d))
    }

    /// The vertex directions interpolated with the fragment's barycentrics in the flux triangle, clamped to the triangle outside it, normalised (zero where the barycentrics vanish).
    fn interpolated_direction(&self, ft: &FluxTriangle) -> Vec3 {
        let b = ft.barycentrics.map(|b| b.max(0.0));
        let sum = b[0] + b[1] + b[2];
        if !(sum > 0.0) {
            return Vec3::ZERO;
        }
        (self.directions[0] * b[0] + self.directions[1] * b[1] + self.directions[2] * b[2])
            .normalize_or_zero()
    }

    /// The volume `P_E` under the 2D Gaussian over the triangular domain ABC (section 4.2.1: `A = φ_a l_a` with φ_a the angle between `A_W F` and the specular direction at `A_W`, and `l_a` the unit direction from F to `A_F` in the flux plane; section 4.2.2 via [`ScatterDistribution::triangle_volume_split`], clamped to one there), with the beam's [`SplitPoint`].
    pub fn scatter_volume(&self, dist: &ScatterDistribution, ft: &FluxTriangle, p: Vec3) -> f32 {
        let (u, v) = self.wavefront_normal.any_orthonormal_pair();
        let to_domain = |origin: Vec3, d: Vec3, towards: Vec3| -> Vec2 {
            let to_f = p - origin;
            let phi = to_f.cross(d).length().atan2(to_f.dot(d));
            let l = towards - p;
            Vec2::new(l.dot(u), l.dot(v)).normalize_or_zero() * phi
        };
        let corner = |i: usize| to_domain(self.vertices[i], self.directions[i], ft.vertices[i]);
        if self.volume == GlossyVolume::Integrated {
            return dist.triangle_volume_integrated(corner(0), corner(1), corner(2));
        }
        let split = |k: usize, _s: f32, d: Vec2| -> Vec2 {
            match self.split_point {
                SplitPoint::Domain => d,
                SplitPoint::Paper | SplitPoint::Rescattered => self
                    .rescattered_split(k, ft, p, self.split_point == SplitPoint::Rescattered)
                    .map_or(d, |(origin, dir, at)| to_domain(origin, dir, at)),
            }
        };
        dist.triangle_volume_split(corner(0), corner(1), corner(2), split)
    }

    /// Figure 12, step 3: `D_F` where the line from F through the flux triangle's vertex `k` crosses the opposite edge, its parameter s on that edge, `D_W` on the scatterer's edge, the direction `S_D` re-scattered there from the light with the interpolated normal, and `D_T` where that ray crosses the flux plane; returns `(D_W, S_D, D_T)`. With `matched`, `D_W` is the edge point whose ray crosses the flux triangle's edge at `D_F` (found by bisection) instead of the point at the same parameter s.
    fn rescattered_split(
        &self,
        k: usize,
        ft: &FluxTriangle,
        p: Vec3,
        matched: bool,
    ) -> Option<(Vec3, Vec3, Vec3)> {
        let n = self.wavefront_normal;
        let (i, j) = ((k + 1) % 3, (k + 2) % 3);
        let (xk, xi, xj) = (ft.vertices[k], ft.vertices[i], ft.vertices[j]);
        let (towards, edge) = (xk - p, xj - xi);
        let denom = edge.cross(towards).dot(n);
        if denom == 0.0 {
            return None;
        }
        let s = ((p - xi).cross(towards).dot(n) / denom).clamp(0.0, 1.0);
        // The ray scattered at parameter t of the scatterer's edge, and where it crosses the flux plane.
        let ray = |t: f32| -> Option<(Vec3, Vec3, Vec3)> {
            let dw = self.vertices[i].lerp(self.vertices[j], t);
            let normal = self.normals[i].lerp(self.normals[j], t).normalize_or_zero();
            let w = (dw - self.light_position).normalize_or_zero();
            let sd = match self.scatter {
                Scatter::Reflect => crate::construction::reflect(w, normal),
                Scatter::Refract { eta } => crate::construction::refract(w, normal, eta)?,
                Scatter::Straight => w,
            };
            let den = sd.dot(n);
            if !(den > 0.0) {
                return None;
            }
            Some((dw, sd, dw + sd * ((p - dw).dot(n) / den)))
        };
        if !matched {
            return ray(s);
        }
        // The edge's rays cross the flux plane along a curve from X_i (t = 0)
        // to X_j (t = 1); find where its projection on the edge is at s.
        let along = |t: f32| ray(t).map(|(_, _, dt)| (dt - xi).dot(edge) / edge.length_squared());
        let (mut lo, mut hi) = (0.0f32, 1.0f32);
        for _ in 0..24 {
            let mid = 0.5 * (lo + hi);
            if along(mid)? < s {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        ray(0.5 * (lo + hi))
    }

    /// Boxes whose union holds every point of `within` where [`Beam::support`] holds (so every point the beam lights there), one per slab of equal slabs along the mean direction (about as long as the beam is wide, at most `pieces`): the three support rays, each over the range of ray parameters at which flux planes through the part of `within` in front of the generator plane cross it, clipped to that part's box (an infinite beam bounded by the scene, for [`crate::BeamHierarchy`]). Empty boxes where the beam misses `within`. Each box comes with its slab's range of flux-plane offsets `n · p` (n the wavefront normal): the first slab's range open below, the last's open above, each half-open `[lo, hi)`, so that every point lies in exactly one slab's range and a traversal that counts a beam only in the box whose range holds `n · p` counts it once (the GPU pass's rule, `passes::beams` in lustre-mpr).
    pub fn slabs_within(&self, within: Aabb, pieces: usize) -> Vec<BeamSlab> {
        // The corners of `within` cut by the generator plane: the box's
        // corners in front of it and where its edges cross it.
        let corners: [Vec3; 8] = std::array::from_fn(|k| {
            Vec3::new(
                if k & 1 == 0 {
                    within.min.x
                } else {
                    within.max.x
                },
                if k & 2 == 0 {
                    within.min.y
                } else {
                    within.max.y
                },
                if k & 4 == 0 {
                    within.min.z
                } else {
                    within.max.z
                },
            )
        });
        let height = |p: Vec3| self.generator_normal.dot(p) - self.generator_offset;
        let mut region: Vec<Vec3> = corners
            .iter()
            .copied()
            .filter(|&c| height(c) >= 0.0)
            .collect();
        for a in 0..8 {
            for bit in [1, 2, 4] {
                let b = a | bit;
                if b == a {
                    continue;
                }
                let (ha, hb) = (height(corners[a]), height(corners[b]));
                if (ha < 0.0) != (hb < 0.0) {
                    let t = ha / (ha - hb);
                    region.push(corners[a] + (corners[b] - corners[a]) * t);
                }
            }
        }
        if region.is_empty() {
            return Vec::new();
        }
        let n = self.wavefront_normal;
        let (s0, s1) = region
            .iter()
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), c| {
                (a.min(c.dot(n)), b.max(c.dot(n)))
            });
        let region = Aabb::from_points(region);
        // As many slabs as make each about as long as the beam is wide
        // (more for long, thin beams), at most `pieces`.
        let width = |s: f32| {
            let x: [Vec3; 3] = std::array::from_fn(|i| {
                let (o, d) = (self.vertices[i], self.support_directions[i]);
                o + (s - o.dot(n)) / d.dot(n) * d
            });
            (x[0] - x[1])
                .length()
                .max((x[1] - x[2]).length())
                .max((x[2] - x[0]).length())
        };
        let widest = width(s0).max(width(s1));
        let pieces = if widest > 0.0 {
            ((s1 - s0) / widest).ceil().clamp(1.0, pieces.max(1) as f32) as usize
        } else {
            pieces.max(1)
        };
        (0..pieces)
            .map(|k| {
                // Flux planes n·F = s for s in this slab cross ray i at
                // t = (s - n·o) / (n·d): a segment of it.
                let (sa, sb) = (
                    s0 + (s1 - s0) * k as f32 / pieces as f32,
                    s0 + (s1 - s0) * (k + 1) as f32 / pieces as f32,
                );
                let along = [
                    if k == 0 { f32::NEG_INFINITY } else { sa },
                    if k + 1 == pieces { f32::INFINITY } else { sb },
                ];
                let mut hull = Aabb::EMPTY;
                for i in 0..3 {
                    let (o, d) = (self.vertices[i], self.support_directions[i]);
                    let den = d.dot(n);
                    let on = o.dot(n);
                    hull = hull
                        .grow(o + (sa - on) / den * d)
                        .grow(o + (sb - on) / den * d);
                }
                let clipped = Aabb {
                    min: hull.min.max(region.min),
                    max: hull.max.min(region.max),
                };
                let bounds =
                    if clipped.is_empty() || !clipped.min.is_finite() || !clipped.max.is_finite() {
                        Aabb::EMPTY
                    } else {
                        clipped
                    };
                BeamSlab { bounds, along }
            })
            .collect()
    }
}

/// One slab of a beam's volume within a region ([`Beam::slabs_within`]): a box holding the part of the beam's support whose flux-plane offset `n · p` is in `along`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BeamSlab {
    /// The box (empty where the beam misses the region there).
    pub bounds: Aabb,
    /// `[lo, hi)` of `n · p`, infinite at the ends of the beam.
    pub along: [f32; 2],
}

/// The flux triangle of rays `origins + t directions` at the plane through `p` with normal `n` (section 3.1, figure 5).
fn flux_triangle(
    origins: &[Vec3; 3],
    directions: &[Vec3; 3],
    n: Vec3,
    p: Vec3,
) -> Option<FluxTriangle> {
    let t: [f32; 3] = std::array::from_fn(|i| (p - origins[i]).dot(n) / directions[i].dot(n));
    // Upstream of every vertex no ray of the beam reaches the plane (each
    // moves along n); the extrapolated triangle shrinks to the apex there.
    if !t.iter().any(|&t| t > 0.0) {
        return None;
    }
    let x: [Vec3; 3] = std::array::from_fn(|i| origins[i] + t[i] * directions[i]);
    let total = (x[1] - x[0]).cross(x[2] - x[0]).dot(n);
    if total == 0.0 || !total.is_finite() {
        return None;
    }
    let b = [
        (x[1] - p).cross(x[2] - p).dot(n) / total,
        (x[2] - p).cross(x[0] - p).dot(n) / total,
        (x[0] - p).cross(x[1] - p).dot(n) / total,
    ];
    Some(FluxTriangle {
        vertices: x,
        area: 0.5 * total.abs(),
        barycentrics: b,
    })
}

/// The directions of a beam whose edges lie `angle` further out than the beam's, seen along `mean`: in the plane one unit along `mean` each direction's point moves by `tan(angle)` along the miter of its two edges' outward normals (at most 8 times as far, for slivers), so that each edge moves out by `tan(angle)`; then at most [`MAX_SUPPORT_ANGLE`] from `mean`. The edges are oriented by the directions' triangle, or the scatterer's when that one is degenerate; `None` when both are.
fn widened_beam(
    directions: [Vec3; 3],
    vertices: [Vec3; 3],
    mean: Vec3,
    angle: f32,
) -> Option<[Vec3; 3]> {
    let (u, v) = mean.any_orthonormal_pair();
    let flat = |x: Vec3| Vec2::new(x.dot(u), x.dot(v));
    let g: [Vec2; 3] = std::array::from_fn(|i| flat(directions[i]) / directions[i].dot(mean));
    let area = |t: &[Vec2; 3]| (t[1] - t[0]).perp_dot(t[2] - t[0]);
    let centroid = (vertices[0] + vertices[1] + vertices[2]) / 3.0;
    let shape = if area(&g).abs() > 1e-10 {
        g
    } else {
        std::array::from_fn(|i| flat(vertices[i] - centroid))
    };
    let orient = area(&shape);
    if orient == 0.0 || !orient.is_finite() {
        return None;
    }
    // Outward unit normal of the edge from vertex k to k + 1.
    let normal: [Vec2; 3] = std::array::from_fn(|k| {
        let e = shape[(k + 1) % 3] - shape[k];
        (Vec2::new(e.y, -e.x) * orient.signum()).normalize_or_zero()
    });
    let offset = angle.tan();
    Some(std::array::from_fn(|i| {
        let (a, b) = (normal[(i + 2) % 3], normal[i]);
        let miter = (a + b) / (1.0 + a.dot(b)).max(1.0 / 64.0);
        let miter = miter.clamp_length_max(8.0);
        let p = g[i] + miter * offset;
        let d = (mean + u * p.x + v * p.y).normalize();
        let current = d.dot(mean).clamp(-1.0, 1.0).acos();
        if current <= MAX_SUPPORT_ANGLE {
            d
        } else {
            let perp = (d - d.dot(mean) * mean).normalize_or_zero();
            mean * MAX_SUPPORT_ANGLE.cos() + perp * MAX_SUPPORT_ANGLE.sin()
        }
    }))
}

/// `d` turned by `angle` away from `mean` (in their common plane; along `outward`, made perpendicular to `mean`, when `d` is parallel to it), at most [`MAX_SUPPORT_ANGLE`] from `mean`.
fn widened(d: Vec3, mean: Vec3, outward: Vec3, angle: f32) -> Vec3 {
    let mut perp = d - d.dot(mean) * mean;
    if perp.length_squared() < 1e-12 {
        perp = outward - outward.dot(mean) * mean;
    }
    let perp = perp.normalize_or_zero();
    if perp == Vec3::ZERO {
        return d;
    }
    let current = d.dot(mean).clamp(-1.0, 1.0).acos();
    let target = (current + angle).min(MAX_SUPPORT_ANGLE.max(current));
    mean * target.cos() + perp * target.sin()
}
