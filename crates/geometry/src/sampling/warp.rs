//! Warps from the unit square to directions and points, with their densities.
//!
//! Standard results (Pharr, Jakob & Humphreys, *Physically Based Rendering*,
//! 4th ed., chapter A.5): each `sample_*` maps a uniform `u` in [0, 1)^2 to a
//! point distributed with the density its `*_pdf` twin returns.

use std::f32::consts::{FRAC_1_PI, PI};

use glam::{Vec2, Vec3};

/// Uniform direction on the unit sphere.
pub fn sample_uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Density of [`sample_uniform_sphere`] per steradian: 1 / (4π).
pub fn uniform_sphere_pdf() -> f32 {
    0.25 * FRAC_1_PI
}

/// Uniform direction on the hemisphere around +Z.
pub fn sample_uniform_hemisphere(u: Vec2) -> Vec3 {
    let z = u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Density of [`sample_uniform_hemisphere`] per steradian: 1 / (2π).
pub fn uniform_hemisphere_pdf() -> f32 {
    0.5 * FRAC_1_PI
}

/// Shirley-Chiu concentric map from the square to the unit disc.
pub fn sample_concentric_disk(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o == Vec2::ZERO {
        return Vec2::ZERO;
    }
    let (r, theta) = if o.x.abs() > o.y.abs() {
        (o.x, 0.25 * PI * (o.y / o.x))
    } else {
        (o.y, 0.5 * PI - 0.25 * PI * (o.x / o.y))
    };
    r * Vec2::new(theta.cos(), theta.sin())
}

/// Cosine-weighted direction on the hemisphere around +Z (Malley's method).
pub fn sample_cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = sample_concentric_disk(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

/// Density of [`sample_cosine_hemisphere`] per steradian: cos θ / π.
pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta.max(0.0) * FRAC_1_PI
}

/// Uniform direction in the cone of half-angle `acos(cos_max)` around +Z.
pub fn sample_uniform_cone(u: Vec2, cos_max: f32) -> Vec3 {
    let z = 1.0 - u.x * (1.0 - cos_max);
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Density of [`sample_uniform_cone`] per steradian: 1 / (2π (1 - cos_max)).
pub fn uniform_cone_pdf(cos_max: f32) -> f32 {
    1.0 / (2.0 * PI * (1.0 - cos_max))
}

/// Uniform barycentrics `(b1, b2)` on a triangle (the square-root method,
/// Osada et al. 2002); corner 0 weighs `1 - b1 - b2`.
pub fn sample_triangle_barycentrics(u: Vec2) -> Vec2 {
    let s = u.x.sqrt();
    Vec2::new(1.0 - s, u.y * s)
}

/// Uniform point on the triangle `[a, b, c]`; its density is 1 / area.
pub fn sample_triangle(u: Vec2, [a, b, c]: [Vec3; 3]) -> Vec3 {
    let bary = sample_triangle_barycentrics(u);
    a + bary.x * (b - a) + bary.y * (c - a)
}

/// Uniform point on the parallelogram `origin + s * edge_u + t * edge_v`; its
/// density is 1 / |edge_u × edge_v|.
pub fn sample_parallelogram(u: Vec2, origin: Vec3, edge_u: Vec3, edge_v: Vec3) -> Vec3 {
    origin + u.x * edge_u + u.y * edge_v
}
