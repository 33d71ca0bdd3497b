//! The input of beam construction: point lights and scatterer triangles with their materials (Duvenhage et al. 2010, sections 3.1 and 4.2), read from a [`Scene`] or given directly.

use glam::Vec3;
use lustre_geometry::light::{OrientedPointLight, SpotLight};
use lustre_geometry::{Light, MaterialModel, Rgb, Scene};

use crate::error::{BeamError, Result};

/// How a point light's intensity depends on direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Emission {
    /// The same intensity every way ([`lustre_geometry::light::PointLight`]).
    Isotropic,
    /// `I(θ) = I₀ cos θ` about `normal`, zero behind ([`OrientedPointLight`]).
    Cosine {
        /// Unit direction of peak emission.
        normal: Vec3,
    },
    /// A spot light's fall-off ([`SpotLight::falloff`]).
    Spot(SpotLight),
}

/// A point light: the apex of every beam (Duvenhage et al. 2010, section 4: light "radiated from a point light source").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointSource {
    /// Position.
    pub position: Vec3,
    /// Radiant intensity `I_light` in W/sr (along the peak direction).
    pub intensity: Rgb,
    /// Its angular profile.
    pub emission: Emission,
}

impl PointSource {
    /// An isotropic point light.
    pub fn isotropic(position: Vec3, intensity: Rgb) -> Self {
        Self {
            position,
            intensity,
            emission: Emission::Isotropic,
        }
    }

    /// `I_light` towards the unit direction `w` (section 4.1: `Φ_s = I_light Ω_light` takes it constant over a scatterer, evaluated towards its centroid).
    pub fn intensity_towards(&self, w: Vec3) -> Rgb {
        match self.emission {
            Emission::Isotropic => self.intensity,
            Emission::Cosine { normal } => self.intensity * normal.dot(w).max(0.0),
            Emission::Spot(s) => {
                let theta = s.direction.dot(w).clamp(-1.0, 1.0).acos();
                self.intensity * s.falloff(theta)
            }
        }
    }

    pub(crate) fn validate(&self, index: usize) -> Result<()> {
        let ok = self.position.is_finite()
            && self.intensity.is_finite()
            && self.intensity.min_element() >= 0.0;
        if ok {
            Ok(())
        } else {
            Err(BeamError::InvalidInput {
                what: format!("light {index}"),
                message: "position must be finite and intensity finite and non-negative".into(),
            })
        }
    }
}

/// What a scatterer does with light, from its material (section 1.2: specular micro-facets; `roughness` 0 is a mirror-like S interaction, more is a glossy G interaction).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ScatterMaterial {
    /// Reflects `reflectance` of the light (`MaterialModel::Mirror`, and `RoughConductor` with its Fresnel at the incidence angle folded in per beam).
    Reflector {
        /// Reflectance (RGB) at the beam's incidence, Fresnel excluded.
        reflectance: Rgb,
        /// Complex index of refraction `(eta, k)` for a conductor's Fresnel, `None` for F = 1.
        conductor: Option<(Rgb, Rgb)>,
        /// Beckmann roughness α; 0 is specular.
        roughness: f32,
    },
    /// A dielectric interface (`MaterialModel::Dielectric`): a reflected beam with Fresnel's F and a refracted beam with `(1 - F)` times `transmittance`.
    Interface {
        /// Index of refraction of the side the geometric normal points away from, over the other side.
        ior: f32,
        /// Transmittance filter.
        transmittance: Rgb,
        /// Beckmann roughness α; 0 is specular.
        roughness: f32,
    },
    /// A thin slab (a window pane: `MaterialModel::Named` with model `thin-dielectric`, parameters `ior` (1.5), `roughness` (0), `transmittance` (1)): light goes straight through with the slab's `T = (1 - F)/(1 + F)` and is reflected with `R = 2F/(1 + F)` (all internal reflections summed).
    ThinSlab {
        /// Index of refraction of the slab.
        ior: f32,
        /// Transmittance filter.
        transmittance: Rgb,
        /// Beckmann roughness α of both faces; 0 is specular.
        roughness: f32,
    },
}

pub use lustre_geometry::material::THIN_DIELECTRIC;

impl ScatterMaterial {
    /// The scatter material of a scene material, or `None` for a receiver (diffuse and every other model). Errors on out-of-range `thin-dielectric` parameters.
    pub fn from_model(model: &MaterialModel) -> Result<Option<Self>> {
        Ok(match model {
            MaterialModel::Mirror { reflectance } => Some(Self::Reflector {
                reflectance: *reflectance,
                conductor: None,
                roughness: 0.0,
            }),
            MaterialModel::RoughConductor {
                alpha,
                fresnel,
                specular,
                ..
            } => Some(Self::Reflector {
                reflectance: *specular,
                conductor: match fresnel {
                    lustre_geometry::material::ConductorFresnel::Complex { eta, k } => {
                        Some((*eta, *k))
                    }
                    lustre_geometry::material::ConductorFresnel::None => None,
                },
                roughness: *alpha,
            }),
            MaterialModel::Dielectric { ior, transmittance } => Some(Self::Interface {
                ior: *ior,
                transmittance: *transmittance,
                roughness: 0.0,
            }),
            MaterialModel::Named { model, params } if model == THIN_DIELECTRIC => {
                let scalar = |name: &str, default: f32| -> Result<f32> {
                    match params.get(name).map(Vec::as_slice) {
                        None => Ok(default),
                        Some([v]) => Ok(*v),
                        Some(_) => Err(BeamError::InvalidInput {
                            what: format!("{THIN_DIELECTRIC} parameter `{name}`"),
                            message: "takes one value".into(),
                        }),
                    }
                };
                let transmittance = match params.get("transmittance").map(Vec::as_slice) {
                    None => Rgb::ONE,
                    Some([g]) => Rgb::splat(*g),
                    Some([r, g, b]) => Rgb::new(*r, *g, *b),
                    Some(_) => {
                        return Err(BeamError::InvalidInput {
                            what: format!("{THIN_DIELECTRIC} parameter `transmittance`"),
                            message: "takes one or three values".into(),
                        });
                    }
                };
                let m = Self::ThinSlab {
                    ior: scalar("ior", 1.5)?,
                    transmittance,
                    roughness: scalar("roughness", 0.0)?,
                };
                m.validate("thin-dielectric material")?;
                Some(m)
            }
            _ => None,
        })
    }

    /// The same material with Beckmann roughness `alpha` (0 specular; the paper's glossy variance, figures 13 and 14).
    pub fn with_roughness(self, alpha: f32) -> Self {
        match self {
            Self::Reflector {
                reflectance,
                conductor,
                ..
            } => Self::Reflector {
                reflectance,
                conductor,
                roughness: alpha,
            },
            Self::Interface {
                ior, transmittance, ..
            } => Self::Interface {
                ior,
                transmittance,
                roughness: alpha,
            },
            Self::ThinSlab {
                ior, transmittance, ..
            } => Self::ThinSlab {
                ior,
                transmittance,
                roughness: alpha,
            },
        }
    }

    /// The Beckmann roughness α.
    pub fn roughness(&self) -> f32 {
        match *self {
            Self::Reflector { roughness, .. }
            | Self::Interface { roughness, .. }
            | Self::ThinSlab { roughness, .. } => roughness,
        }
    }

    fn validate(&self, what: &str) -> Result<()> {
        let bad = |message: &str| {
            Err(BeamError::InvalidInput {
                what: what.to_owned(),
                message: message.to_owned(),
            })
        };
        let r = self.roughness();
        if !(r.is_finite() && r >= 0.0) {
            return bad("roughness must be finite and non-negative");
        }
        match *self {
            Self::Reflector {
                reflectance,
                conductor,
                ..
            } => {
                if !(reflectance.is_finite() && reflectance.min_element() >= 0.0) {
                    return bad("reflectance must be finite and non-negative");
                }
                if let Some((eta, k)) = conductor
                    && !(eta.is_finite() && k.is_finite())
                {
                    return bad("conductor eta and k must be finite");
                }
            }
            Self::Interface {
                ior, transmittance, ..
            }
            | Self::ThinSlab {
                ior, transmittance, ..
            } => {
                if !(ior.is_finite() && ior > 0.0) {
                    return bad("ior must be positive and finite");
                }
                if !(transmittance.is_finite() && transmittance.min_element() >= 0.0) {
                    return bad("transmittance must be finite and non-negative");
                }
            }
        }
        Ok(())
    }
}

/// A scatterer triangle (section 3.1: a polygon the beam is traced to, its three vertex rays scattered with the vertex normals, so that the beam is a warped volume decoupled from the flat triangle).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scatterer {
    /// Corner positions `A_W, B_W, C_W`; the counter-clockwise winding's normal is the front.
    pub vertices: [Vec3; 3],
    /// Corner shading normals (unit, on the front side).
    pub normals: [Vec3; 3],
    /// What it does with light.
    pub material: ScatterMaterial,
    /// One face of a closed glass slab ([`lustre_geometry::slab`]; its
    /// material a [`ScatterMaterial::ThinSlab`]): it scatters only light
    /// arriving on the front of its winding, from outside the glass. Light
    /// that reaches its back has come in through the slab's other face, whose
    /// beams already carry it straight through (Diefenbach & Badler 1997,
    /// section 2's in-out refraction).
    pub slab_face: bool,
}

impl Scatterer {
    /// A flat triangle: every vertex normal is the geometric normal.
    pub fn flat(vertices: [Vec3; 3], material: ScatterMaterial) -> Self {
        let n = (vertices[1] - vertices[0])
            .cross(vertices[2] - vertices[0])
            .normalize_or_zero();
        Self {
            vertices,
            normals: [n; 3],
            material,
            slab_face: false,
        }
    }

    pub(crate) fn validate(&self, index: usize) -> Result<()> {
        let what = format!("scatterer {index}");
        if !(self.vertices.iter().all(|v| v.is_finite())
            && self.normals.iter().all(|n| n.is_finite()))
        {
            return Err(BeamError::InvalidInput {
                what,
                message: "vertices and normals must be finite".into(),
            });
        }
        self.material.validate(&what)
    }
}

/// Point lights and scatterers read from a scene.
#[derive(Debug, Clone, PartialEq)]
pub struct BeamInput {
    /// The point lights (point, oriented point and spot lights).
    pub lights: Vec<PointSource>,
    /// Area lights left out: beams need a point apex; call [`Scene::with_area_lights_as_points`] first to trace them from cosine point lights of equal power.
    pub area_lights_ignored: usize,
    /// Every triangle whose material scatters ([`ScatterMaterial::from_model`]);
    /// the faces of a closed glass slab ([`lustre_geometry::slab::slab_faces`])
    /// as [`Scatterer::slab_face`]s of a [`ScatterMaterial::ThinSlab`] with
    /// the dielectric's index and its transmittance squared (two refractions),
    /// so that light through the slab makes one beam, not one per face.
    pub scatterers: Vec<Scatterer>,
}

impl BeamInput {
    /// The point lights and scatterer triangles of `scene` (in scene-wide triangle order). Errors when the scene has no point light or a `thin-dielectric` material is out of range.
    pub fn from_scene(scene: &Scene) -> Result<Self> {
        let mut lights = Vec::new();
        let mut area_lights_ignored = 0;
        for light in scene.lights() {
            match *light {
                Light::Point(p) => lights.push(PointSource::isotropic(p.position, p.intensity)),
                Light::OrientedPoint(OrientedPointLight {
                    position,
                    normal,
                    intensity,
                }) => lights.push(PointSource {
                    position,
                    intensity,
                    emission: Emission::Cosine { normal },
                }),
                Light::Spot(s) => lights.push(PointSource {
                    position: s.position,
                    intensity: s.intensity,
                    emission: Emission::Spot(s),
                }),
                Light::Area(_) => area_lights_ignored += 1,
            }
        }
        if lights.is_empty() {
            return Err(BeamError::NoPointLight {
                lights: area_lights_ignored,
            });
        }
        let materials = scene
            .materials()
            .iter()
            .map(|m| ScatterMaterial::from_model(&m.model))
            .collect::<Result<Vec<_>>>()?;
        let slabs = lustre_geometry::slab::slab_faces(scene);
        let scatterers = scene
            .world_triangles()
            .into_iter()
            .filter_map(|t| {
                let slab_face = slabs[t.surface as usize].is_some();
                let material = match materials[t.material as usize]? {
                    ScatterMaterial::Interface {
                        ior,
                        transmittance,
                        roughness,
                    } if slab_face => ScatterMaterial::ThinSlab {
                        ior,
                        transmittance: transmittance * transmittance,
                        roughness,
                    },
                    m => m,
                };
                let n = (t.positions[1] - t.positions[0]).cross(t.positions[2] - t.positions[0]);
                // Shading normals on the front side of the winding.
                let normals = t.normals.map(|s| if s.dot(n) < 0.0 { -s } else { s });
                Some(Scatterer {
                    vertices: t.positions,
                    normals,
                    material,
                    slab_face,
                })
            })
            .collect();
        Ok(Self {
            lights,
            area_lights_ignored,
            scatterers,
        })
    }
}
