//! Lewis's physically plausible Phong (Lewis 1994).

use lustre_geometry::Rgb;

use super::modified_phong::ModifiedPhong;
use crate::error::Result;

/// Lewis's plausible Phong BRDF `f = kd/π + ks (n + 2)/(2π) cos^n α` with `kd + ks ≤ 1` (R. R. Lewis, "Making shaders more physically plausible", Computer Graphics Forum 13(2), 1994, section 4, the normalised Phong specular term).
///
/// Lewis derives the same normalisation as Lafortune & Willems (1994) from
/// the energy bound at normal incidence, so the BRDF is the
/// [`ModifiedPhong`] one, reported under the name `lewis`: reciprocal and
/// energy conserving.
pub fn lewis(diffuse: Rgb, specular: Rgb, exponent: f32) -> Result<ModifiedPhong> {
    ModifiedPhong::named("lewis", diffuse, specular, exponent)
}
