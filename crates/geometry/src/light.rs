//! Light sources: power, emission sampling (for particle tracing) and
//! point sampling (for direct lighting).

use std::f32::consts::PI;

use glam::{Vec2, Vec3};

use crate::mesh::{MeshId, triangle_area};
use crate::sampling::{
    Frame, sample_cosine_hemisphere, sample_parallelogram, sample_triangle, sample_uniform_cone,
    sample_uniform_sphere, uniform_cone_pdf, uniform_sphere_pdf,
};
use crate::{GeometryError, Result, Rgb};

/// Isotropic point light.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointLight {
    /// Position.
    pub position: Vec3,
    /// Radiant intensity in W/sr, the same in every direction.
    pub intensity: Rgb,
}

/// Point light with cosine emission `I(θ) = I₀ cos θ` over the hemisphere
/// around `normal`: the far field of a small one-sided area light of radiance
/// `L` and area `A`, with `I₀ = L A`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OrientedPointLight {
    /// Position.
    pub position: Vec3,
    /// Unit direction of peak emission.
    pub normal: Vec3,
    /// Intensity along `normal`, in W/sr.
    pub intensity: Rgb,
}

/// Spot light with Mitsuba 3's fall-off: full intensity inside `beam_width`,
/// falling linearly in angle to zero at `cutoff_angle`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpotLight {
    /// Position.
    pub position: Vec3,
    /// Unit axis of the cone.
    pub direction: Vec3,
    /// Intensity on the axis, in W/sr.
    pub intensity: Rgb,
    /// Half-angle of the cone beyond which nothing is emitted, in radians.
    pub cutoff_angle: f32,
    /// Half-angle of the fully lit inner cone, in radians (`<= cutoff_angle`).
    pub beam_width: f32,
}

impl SpotLight {
    /// The fall-off factor in [0, 1] for a direction at angle `theta` from the axis.
    pub fn falloff(&self, theta: f32) -> f32 {
        if theta <= self.beam_width {
            1.0
        } else if theta >= self.cutoff_angle {
            0.0
        } else {
            (self.cutoff_angle - theta) / (self.cutoff_angle - self.beam_width)
        }
    }
}

/// The emitting shape of an area light.
#[derive(Debug, Clone, PartialEq)]
pub enum AreaShape {
    /// The parallelogram `origin + s edge_u + t edge_v`, `s, t` in [0, 1],
    /// emitting on the side of `edge_u × edge_v`.
    Rectangle {
        /// A corner.
        origin: Vec3,
        /// First edge.
        edge_u: Vec3,
        /// Second edge.
        edge_v: Vec3,
    },
    /// Triangles, each emitting on the side its counter-clockwise winding faces.
    Triangles {
        /// Corner positions.
        triangles: Vec<[Vec3; 3]>,
        /// Cumulative area of the triangles, for choosing one in proportion to its area.
        cumulative_area: Vec<f32>,
    },
}

impl AreaShape {
    /// Triangles as an area light shape (area table built here).
    pub fn triangles(triangles: Vec<[Vec3; 3]>) -> Self {
        let mut total = 0.0;
        let cumulative_area = triangles
            .iter()
            .map(|&t| {
                total += triangle_area(t);
                total
            })
            .collect();
        Self::Triangles {
            triangles,
            cumulative_area,
        }
    }

    /// Total emitting area.
    pub fn area(&self) -> f32 {
        match self {
            Self::Rectangle { edge_u, edge_v, .. } => edge_u.cross(*edge_v).length(),
            Self::Triangles {
                cumulative_area, ..
            } => cumulative_area.last().copied().unwrap_or(0.0),
        }
    }

    /// A uniformly distributed point and the unit normal there.
    pub fn sample_point(&self, u: Vec2) -> (Vec3, Vec3) {
        match self {
            Self::Rectangle {
                origin,
                edge_u,
                edge_v,
            } => (
                sample_parallelogram(u, *origin, *edge_u, *edge_v),
                edge_u.cross(*edge_v).normalize(),
            ),
            Self::Triangles {
                triangles,
                cumulative_area,
            } => {
                let total = self.area();
                let target = u.x * total;
                let i = cumulative_area
                    .partition_point(|&c| c <= target)
                    .min(triangles.len() - 1);
                let lo = if i == 0 { 0.0 } else { cumulative_area[i - 1] };
                let width = cumulative_area[i] - lo;
                let ux = if width > 0.0 {
                    ((target - lo) / width).clamp(0.0, 1.0 - f32::EPSILON)
                } else {
                    0.0
                };
                let t = triangles[i];
                (
                    sample_triangle(Vec2::new(ux, u.y), t),
                    (t[1] - t[0]).cross(t[2] - t[0]).normalize(),
                )
            }
        }
    }

    /// Centroid of the shape (area weighted).
    pub fn centroid(&self) -> Vec3 {
        match self {
            Self::Rectangle {
                origin,
                edge_u,
                edge_v,
            } => *origin + 0.5 * (*edge_u + *edge_v),
            Self::Triangles { triangles, .. } => {
                let (sum, area) = triangles.iter().fold((Vec3::ZERO, 0.0), |(s, a), &t| {
                    let ta = triangle_area(t);
                    (s + ta * (t[0] + t[1] + t[2]) / 3.0, a + ta)
                });
                sum / area
            }
        }
    }

    /// Area-weighted mean unit normal of the shape.
    pub fn mean_normal(&self) -> Vec3 {
        match self {
            Self::Rectangle { edge_u, edge_v, .. } => edge_u.cross(*edge_v).normalize(),
            Self::Triangles { triangles, .. } => triangles
                .iter()
                .map(|t| (t[1] - t[0]).cross(t[2] - t[0]))
                .sum::<Vec3>()
                .normalize_or_zero(),
        }
    }
}

/// A one-sided diffuse area light of constant radiance.
#[derive(Debug, Clone, PartialEq)]
pub struct AreaLight {
    /// The emissive mesh this light was made from, if any.
    pub mesh: Option<MeshId>,
    /// The emitting shape.
    pub shape: AreaShape,
    /// Emitted radiance in W/(m^2 sr).
    pub radiance: Rgb,
}

impl AreaLight {
    /// The cosine point light with the same power and far field: `I₀ = L A`
    /// at the shape's centroid, facing its mean normal (DESIGN.md, point-light techniques).
    pub fn to_oriented_point(&self) -> OrientedPointLight {
        OrientedPointLight {
            position: self.shape.centroid(),
            normal: self.shape.mean_normal(),
            intensity: self.radiance * self.shape.area(),
        }
    }

    /// `k` jittered point lights over the light (Diefenbach & Badler 1997,
    /// section 4.4): cosine point lights of intensity `L A / k` (power `Φ/k`)
    /// along the local normal, at the points of [`hammersley_centred`]
    /// shifted by `rotation` modulo 1 (a Cranley–Patterson rotation, zero for
    /// none) and mapped onto the shape. `k = 1` without rotation is
    /// [`AreaLight::to_oriented_point`], the paper's single point light.
    pub fn jittered_points(&self, k: u32, rotation: Vec2) -> Vec<OrientedPointLight> {
        let k = k.max(1);
        if k == 1 && rotation == Vec2::ZERO {
            return vec![self.to_oriented_point()];
        }
        let intensity = self.radiance * (self.shape.area() / k as f32);
        (0..k)
            .map(|i| {
                let u = (hammersley_centred(i, k) + rotation).fract();
                let (position, normal) = self.shape.sample_point(u);
                OrientedPointLight {
                    position,
                    normal,
                    intensity,
                }
            })
            .collect()
    }
}

/// A light source.
#[derive(Debug, Clone, PartialEq)]
pub enum Light {
    /// Isotropic point light.
    Point(PointLight),
    /// Cosine-emitting point light.
    OrientedPoint(OrientedPointLight),
    /// Spot light.
    Spot(SpotLight),
    /// Diffuse area light.
    Area(AreaLight),
}

/// A photon leaving a light: where, which way, and its weight.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EmissionSample {
    /// Origin on the light.
    pub position: Vec3,
    /// Unit direction of emission.
    pub direction: Vec3,
    /// Unit normal of the light at the origin (the emission axis for point lights).
    pub normal: Vec3,
    /// Density of the position (per m², or 1 for a point light).
    pub pdf_position: f32,
    /// Density of the direction per steradian.
    pub pdf_direction: f32,
    /// Emitted flux over the joint density, `L cos θ / (p_A p_ω)` (or `I / p_ω`):
    /// its expectation is the light's power, so `weight / m` is the power of
    /// one of `m` photons.
    pub weight: Rgb,
}

/// A point on a light seen from a receiver, for direct lighting.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DirectSample {
    /// Point on the light.
    pub position: Vec3,
    /// Unit direction from the receiver to the light.
    pub direction: Vec3,
    /// Distance from the receiver to the light point.
    pub distance: f32,
    /// Incident radiance over the solid-angle density (`I / d²` for point
    /// lights): `f · cos θᵢ · weight` estimates the reflected radiance.
    pub weight: Rgb,
    /// Solid-angle density of the sample (1 for delta lights).
    pub pdf: f32,
    /// Whether the light is a delta (point) light that only this sample can reach.
    pub is_delta: bool,
}

impl Light {
    /// Checks that the light's values are finite and its power is positive.
    pub fn validate(&self, name: &str) -> Result<()> {
        let bad = |message: &str| {
            Err(GeometryError::InvalidLight {
                light: name.to_owned(),
                message: message.to_owned(),
            })
        };
        let power = self.power();
        if !power.is_finite() || power.min_element() < 0.0 || power.max_element() <= 0.0 {
            return bad("power must be finite, non-negative and not zero");
        }
        match self {
            Self::Spot(s)
                if !(0.0 <= s.beam_width
                    && s.beam_width <= s.cutoff_angle
                    && s.cutoff_angle <= PI) =>
            {
                bad("spot angles must satisfy 0 <= beam_width <= cutoff_angle <= pi")
            }
            Self::Area(a) if !(a.shape.area() > 0.0) => bad("area light has zero area"),
            _ => Ok(()),
        }
    }

    /// The light as point lights for a point-light renderer: an area light as
    /// its `k` [`AreaLight::jittered_points`] (Diefenbach & Badler 1997,
    /// section 4.4), any other light as itself.
    pub fn as_point_lights(&self, k: u32, rotation: Vec2) -> Vec<Light> {
        match self {
            Self::Area(a) => a
                .jittered_points(k, rotation)
                .into_iter()
                .map(Self::OrientedPoint)
                .collect(),
            other => vec![other.clone()],
        }
    }

    /// Whether the light is a point (delta) light.
    pub fn is_delta(&self) -> bool {
        !matches!(self, Self::Area(_))
    }

    /// Total emitted power in W.
    pub fn power(&self) -> Rgb {
        match self {
            // Φ = ∫ I dω = 4π I.
            Self::Point(p) => 4.0 * PI * p.intensity,
            // Φ = ∫ I₀ cos θ dω over the hemisphere = π I₀.
            Self::OrientedPoint(p) => PI * p.intensity,
            // Φ = 2π I [(1 - cos b) + ((c - b) cos b + sin b - sin c) / (c - b)],
            // integrating the linear fall-off (c - θ)/(c - b) times sin θ from b to c.
            Self::Spot(s) => {
                let (b, c) = (s.beam_width, s.cutoff_angle);
                let transition = if c > b {
                    ((c - b) * b.cos() + b.sin() - c.sin()) / (c - b)
                } else {
                    0.0
                };
                2.0 * PI * s.intensity * ((1.0 - b.cos()) + transition)
            }
            // Φ = ∫∫ L cos θ dω dA = π L A.
            Self::Area(a) => PI * a.radiance * a.shape.area(),
        }
    }

    /// Samples an emitted photon from four uniform numbers.
    pub fn sample_emission(&self, u_position: Vec2, u_direction: Vec2) -> EmissionSample {
        match self {
            Self::Point(p) => {
                let direction = sample_uniform_sphere(u_direction);
                let pdf = uniform_sphere_pdf();
                EmissionSample {
                    position: p.position,
                    direction,
                    normal: direction,
                    pdf_position: 1.0,
                    pdf_direction: pdf,
                    weight: p.intensity / pdf,
                }
            }
            Self::OrientedPoint(p) => {
                let frame = Frame::from_normal(p.normal);
                let local = sample_cosine_hemisphere(u_direction);
                let pdf = local.z / PI;
                EmissionSample {
                    position: p.position,
                    direction: frame.to_world(local),
                    normal: p.normal,
                    pdf_position: 1.0,
                    pdf_direction: pdf,
                    // I₀ cos θ / (cos θ / π) = π I₀, the power.
                    weight: PI * p.intensity,
                }
            }
            Self::Spot(s) => {
                let cos_cutoff = s.cutoff_angle.cos();
                let frame = Frame::from_normal(s.direction);
                let local = sample_uniform_cone(u_direction, cos_cutoff);
                let pdf = uniform_cone_pdf(cos_cutoff);
                let theta = local.z.clamp(-1.0, 1.0).acos();
                EmissionSample {
                    position: s.position,
                    direction: frame.to_world(local),
                    normal: s.direction,
                    pdf_position: 1.0,
                    pdf_direction: pdf,
                    weight: s.intensity * s.falloff(theta) / pdf,
                }
            }
            Self::Area(a) => {
                let (position, normal) = a.shape.sample_point(u_position);
                let local = sample_cosine_hemisphere(u_direction);
                let area = a.shape.area();
                EmissionSample {
                    position,
                    direction: Frame::from_normal(normal).to_world(local),
                    normal,
                    pdf_position: 1.0 / area,
                    pdf_direction: local.z / PI,
                    // L cos θ / ((1/A)(cos θ/π)) = π L A, the power.
                    weight: PI * a.radiance * area,
                }
            }
        }
    }

    /// Samples a point on the light as seen from `receiver`; `None` when the
    /// light emits nothing toward it.
    pub fn sample_direct(&self, receiver: Vec3, u: Vec2) -> Option<DirectSample> {
        let toward = |position: Vec3| {
            let d = position - receiver;
            let distance = d.length();
            (distance > 0.0).then(|| (d / distance, distance))
        };
        let delta = |position: Vec3, intensity: Rgb| {
            let (direction, distance) = toward(position)?;
            Some(DirectSample {
                position,
                direction,
                distance,
                weight: intensity / (distance * distance),
                pdf: 1.0,
                is_delta: true,
            })
        };
        match self {
            Self::Point(p) => delta(p.position, p.intensity),
            Self::OrientedPoint(p) => {
                let (direction, _) = toward(p.position)?;
                let cos = (-direction).dot(p.normal);
                (cos > 0.0).then_some(())?;
                delta(p.position, p.intensity * cos)
            }
            Self::Spot(s) => {
                let (direction, _) = toward(s.position)?;
                let theta = (-direction).dot(s.direction).clamp(-1.0, 1.0).acos();
                let f = s.falloff(theta);
                (f > 0.0).then_some(())?;
                delta(s.position, s.intensity * f)
            }
            Self::Area(a) => {
                let (position, normal) = a.shape.sample_point(u);
                let (direction, distance) = toward(position)?;
                let cos_light = (-direction).dot(normal);
                if cos_light <= 0.0 {
                    return None;
                }
                // Area density 1/A converted to solid angle: d² / (A cos θ_light).
                let pdf = distance * distance / (a.shape.area() * cos_light);
                Some(DirectSample {
                    position,
                    direction,
                    distance,
                    weight: a.radiance / pdf,
                    pdf,
                    is_delta: false,
                })
            }
        }
    }
}

/// Every light of `lights` as point lights, each area light as its `k`
/// [`AreaLight::jittered_points`] (Diefenbach & Badler 1997, section 4.4).
pub fn jittered_point_lights(lights: &[Light], k: u32, rotation: Vec2) -> Vec<Light> {
    lights
        .iter()
        .flat_map(|l| l.as_point_lights(k, rotation))
        .collect()
}

/// The lights shadow volumes are built from, one per light of
/// [`jittered_point_lights`]`(lights, k, _)` in its order: each of an area
/// light's `k` jittered lights gets the point light at its centre, so moving
/// to the jittered position moves only the volume's far vertices (Diefenbach
/// & Badler 1997, section 4.4, the pivot approximation); point lights stay
/// themselves.
pub fn pivot_point_lights(lights: &[Light], k: u32) -> Vec<Light> {
    lights
        .iter()
        .flat_map(|l| {
            let centre = l.as_point_lights(1, Vec2::ZERO);
            let copies = if l.is_delta() { 1 } else { k as usize };
            std::iter::repeat_n(centre, copies).flatten()
        })
        .collect()
}

/// The `i`-th of `n` offsets in [0, 1)²: the Hammersley set
/// `((i + ½)/n, φ₂(i) + ½/2^⌈log₂ n⌉)`, stratified in x for every `n` and in y
/// when `n` is a power of two; `n = 1` is the centre (0.5, 0.5). The jitter pattern
/// of accumulation antialiasing (Diefenbach & Badler 1997, section 7) and of
/// jittered point lights (section 4.4).
pub fn hammersley_centred(i: u32, n: u32) -> Vec2 {
    let n = n.max(1);
    let strata = n.next_power_of_two() as f32;
    let phi = i.reverse_bits() as f32 * (1.0 / 4_294_967_296.0);
    Vec2::new((i as f32 + 0.5) / n as f32, phi + 0.5 / strata)
}

/// The rotation of a `k`-point [`hammersley_centred`] light pattern for
/// accumulation sample `s` of `n`: `(hammersley_centred(s, n) − ½) / (k,
/// 2^⌈log₂ k⌉)`, which moves every light within its own stratum so that the
/// `n k` positions of all samples are stratified together (`n = 1`: none).
/// Diefenbach & Badler 1997, section 4.4: a different set of jittered light
/// positions for each accumulated frame.
pub fn paired_rotation(s: u32, n: u32, k: u32) -> Vec2 {
    let k = k.max(1);
    (hammersley_centred(s, n) - Vec2::splat(0.5))
        / Vec2::new(k as f32, k.next_power_of_two() as f32)
}
