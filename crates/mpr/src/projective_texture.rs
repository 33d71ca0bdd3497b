//! Specular projection (Diefenbach & Badler 1997, section 4.5): light
//! passing a planar face of non-uniform transmittance, a stained-glass
//! window of coplanar panes, as one light volume modulated by a projective
//! texture of the window, instead of one light volume per uniform face.
//!
//! A [`Window`] is the paper's *texture plane*: smooth `thin-dielectric`
//! panes (straight transmission, `T = (1 − F)/(1 + F)` times their
//! `transmittance`) on one plane with one index of refraction, their
//! bounding rectangle `origin + s·u + t·v` (`s, t ∈ [0, 1]`) and a texture
//! of each pane's transmittance baked over it
//! ([`TransmittanceTexture`]). Light from a point light at `L` that crosses
//! the window at `X` carries the texel at `X`'s `(s, t)`.
//!
//! The texture is projected from the light as a slide projector: a point
//! `P` is taken to the light's image plane by the light's view and
//! projection `P_L`, and from there to texture coordinates by `M₃₃⁻¹`, the
//! inverse of the 2-D projective map of the unit square onto the
//! quadrilateral that the window's rectangle makes in the light's image
//! (figure 8(b): the texture plane is not aligned with the light's view; the
//! rectangle-to-quadrilateral map of Heckbert 1989, section 2.2.3, the
//! paper's reference \[18\]). Every point on the line from `L` through `X`
//! gets `X`'s coordinates, so the texture lands on every receiver as the
//! light through the window does ([`Projector`]).
//!
//! Written here rather than taken from a crate: the square-to-quadrilateral
//! solve is eight lines of closed form, and glam has no homography type.

use glam::{Mat3, Mat4, Vec2, Vec3, Vec4};
use lustre_beams::ScatterMaterial;
use lustre_geometry::{Plane, Rgb, Scene, SurfaceKind};

use crate::view::face_frame;
use crate::{MprError, Result};

/// How light through thin-dielectric panes reaches the receivers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PaneLight {
    /// Not drawn by virtual lights (left to the photon splats).
    Off,
    /// One light volume per pane surface, each a window of its own with a
    /// one-texel texture: the uniform faces of section 4.2.
    PerPane,
    /// Coplanar panes grouped into one window whose light volume is
    /// modulated by a projective texture of `size` × `size` texels over its
    /// bounding rectangle (section 4.5).
    Projective {
        /// Texels along each side of the window's rectangle.
        size: u32,
    },
}

impl Default for PaneLight {
    fn default() -> Self {
        Self::Projective {
            size: DEFAULT_TEXTURE_SIZE,
        }
    }
}

/// Texels along each side of a window's texture by default.
pub const DEFAULT_TEXTURE_SIZE: u32 = 256;

/// The largest texture side accepted.
pub const MAX_TEXTURE_SIZE: u32 = 4096;

/// One pane triangle of a window and what it passes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pane {
    /// World corners.
    pub corners: [Vec3; 3],
    /// The pane's transmittance filter.
    pub transmittance: Rgb,
}

/// The transmittance filters of a window baked over its rectangle, row by
/// row from `t = 0`; each texel is the mean over 4 × 4 points of the
/// panes' filters (0 where no pane covers), alpha the covered fraction.
#[derive(Debug, Clone, PartialEq)]
pub struct TransmittanceTexture {
    /// Texels along `u`.
    pub width: u32,
    /// Texels along `v`.
    pub height: u32,
    /// RGBA, `width × height`.
    pub texels: Vec<[f32; 4]>,
}

/// A texture plane (section 4.5): coplanar smooth thin-dielectric panes of
/// one index of refraction and their baked transmittance.
#[derive(Debug, Clone, PartialEq)]
pub struct Window {
    /// The panes' plane, its normal as the first pane's geometric normal.
    pub plane: Plane,
    /// The bounding rectangle's corner `s = t = 0`.
    pub origin: Vec3,
    /// Its edge along `s`.
    pub u: Vec3,
    /// Its edge along `t`.
    pub v: Vec3,
    /// The panes' index of refraction.
    pub ior: f32,
    /// The `SurfaceId`s of its panes.
    pub surfaces: Vec<u32>,
    /// Its pane triangles.
    pub panes: Vec<Pane>,
    /// The baked filters.
    pub texture: TransmittanceTexture,
}

impl Window {
    /// The point at texture coordinates `(s, t)`.
    pub fn point(&self, st: Vec2) -> Vec3 {
        self.origin + st.x * self.u + st.y * self.v
    }

    /// The rectangle's corners at `(0,0), (1,0), (1,1), (0,1)`.
    pub fn rectangle(&self) -> [Vec3; 4] {
        [
            self.origin,
            self.origin + self.u,
            self.origin + self.u + self.v,
            self.origin + self.v,
        ]
    }

    /// The corners of its pane triangles, three per triangle.
    pub fn corners(&self) -> Vec<Vec3> {
        self.panes.iter().flat_map(|p| p.corners).collect()
    }

    /// The pane whose triangle holds `x` (a point on the plane), if any.
    pub fn pane_at(&self, x: Vec3) -> Option<&Pane> {
        let n = self.plane.normal;
        self.panes.iter().find(|p| {
            let [a, b, c] = p.corners;
            let side = |p: Vec3, q: Vec3| (q - p).cross(x - p).dot(n);
            let (d0, d1, d2) = (side(a, b), side(b, c), side(c, a));
            (d0 >= 0.0 && d1 >= 0.0 && d2 >= 0.0) || (d0 <= 0.0 && d1 <= 0.0 && d2 <= 0.0)
        })
    }

    /// The thin slab's transmittance `T = (1 − F)/(1 + F)` for light
    /// crossing at `|cos θ|` (lustre-brdf's `ThinDielectric`), times the
    /// filter of the pane at `x`; zero off the panes.
    pub fn transmission_at(&self, x: Vec3, cos: f32) -> Vec3 {
        let Some(pane) = self.pane_at(x) else {
            return Vec3::ZERO;
        };
        let f = lustre_brdf::fresnel::fresnel_dielectric(cos.abs(), self.ior);
        let t = (1.0 - f) / (1.0 + f);
        t * Vec3::new(
            pane.transmittance.x,
            pane.transmittance.y,
            pane.transmittance.z,
        )
    }
}

/// The windows of `scene` under `light` (none for [`PaneLight::Off`]):
/// planar surfaces of smooth `thin-dielectric` material, grouped by plane
/// and index of refraction ([`PaneLight::Projective`]) or one per surface
/// ([`PaneLight::PerPane`]). Rough panes are left out (their light spreads:
/// the splats and beams draw it).
pub fn windows(scene: &Scene, light: PaneLight) -> Result<Vec<Window>> {
    let size = match light {
        PaneLight::Off => return Ok(Vec::new()),
        PaneLight::PerPane => 1,
        PaneLight::Projective { size } => {
            if size == 0 || size > MAX_TEXTURE_SIZE {
                return Err(MprError::InvalidSetting {
                    what: "projective texture size",
                    message: format!("{size} texels; expected 1 to {MAX_TEXTURE_SIZE}"),
                });
            }
            size
        }
    };
    let extent = scene.bounds().extent().max_element().max(1e-6);
    let tolerance = 1e-4 * extent;
    // Per group: plane, ior, surfaces and panes.
    let mut groups: Vec<(Plane, f32, Vec<u32>, Vec<Pane>)> = Vec::new();
    for (id, surface) in scene.surfaces().iter().enumerate() {
        let SurfaceKind::Planar(plane) = surface.kind else {
            continue;
        };
        let material = &scene.materials()[surface.material as usize];
        let Some(ScatterMaterial::ThinSlab {
            ior,
            transmittance,
            roughness,
        }) =
            ScatterMaterial::from_model(&material.model).map_err(|e| MprError::InvalidSetting {
                what: "window pane material",
                message: format!("material `{}`: {e}", material.name),
            })?
        else {
            continue;
        };
        if roughness > 0.0 {
            continue;
        }
        let positions = scene.world_positions(surface.mesh);
        let mesh = &scene.meshes()[surface.mesh as usize];
        let panes: Vec<Pane> = surface
            .triangles
            .iter()
            .map(|&t| Pane {
                corners: mesh.indices[t as usize].map(|i| positions[i as usize]),
                transmittance,
            })
            .collect();
        let same = |p: &Plane, i: f32| {
            let d = p.normal.dot(plane.normal);
            i == ior
                && d.abs() > 1.0 - 1e-5
                && (p.offset - d.signum() * plane.offset).abs() <= tolerance
        };
        match groups.iter_mut().find(|g| same(&g.0, g.1)) {
            Some(group) if size > 1 => {
                group.2.push(id as u32);
                group.3.extend(panes);
            }
            _ => groups.push((plane, ior, vec![id as u32], panes)),
        }
    }
    Ok(groups
        .into_iter()
        .map(|(plane, ior, surfaces, panes)| window(plane, ior, surfaces, panes, size))
        .collect())
}

/// One window: its bounding rectangle in the plane's frame and its texture.
fn window(plane: Plane, ior: f32, surfaces: Vec<u32>, panes: Vec<Pane>, size: u32) -> Window {
    let (a, b) = face_frame(&plane);
    let (mut lo, mut hi) = (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY));
    for p in panes.iter().flat_map(|p| p.corners) {
        let q = Vec2::new(p.dot(a), p.dot(b));
        lo = lo.min(q);
        hi = hi.max(q);
    }
    let span = (hi - lo).max(Vec2::splat(1e-9));
    // Square in texels whatever the rectangle's shape, so that every
    // window is a layer of one array texture.
    let (width, height) = (size, size);
    let mut out = Window {
        origin: plane.normal * plane.offset + a * lo.x + b * lo.y,
        u: a * span.x,
        v: b * span.y,
        plane,
        ior,
        surfaces,
        panes,
        texture: TransmittanceTexture {
            width,
            height,
            texels: Vec::new(),
        },
    };
    const SUB: u32 = 4;
    let mut texels = Vec::with_capacity((width * height) as usize);
    for j in 0..height {
        for i in 0..width {
            let mut sum = Vec3::ZERO;
            let mut covered = 0.0;
            for sj in 0..SUB {
                for si in 0..SUB {
                    let st = Vec2::new(
                        (i as f32 + (si as f32 + 0.5) / SUB as f32) / width as f32,
                        (j as f32 + (sj as f32 + 0.5) / SUB as f32) / height as f32,
                    );
                    if let Some(p) = out.pane_at(out.point(st)) {
                        sum += Vec3::new(p.transmittance.x, p.transmittance.y, p.transmittance.z);
                        covered += 1.0;
                    }
                }
            }
            let n = (SUB * SUB) as f32;
            texels.push([sum.x / n, sum.y / n, sum.z / n, covered / n]);
        }
    }
    out.texture.texels = texels;
    out
}

/// Heckbert's square-to-quadrilateral map (1989, section 2.2.3): the
/// projective `M₃₃` taking `(0,0), (1,0), (1,1), (0,1)` to `q[0..4]` in
/// homogeneous coordinates, `(x w, y w, w) = M₃₃ (s, t, 1)`.
pub fn square_to_quad(q: [Vec2; 4]) -> Mat3 {
    let sigma = q[0] - q[1] + q[2] - q[3];
    let d1 = q[1] - q[2];
    let d2 = q[3] - q[2];
    let det = |a: Vec2, b: Vec2| a.x * b.y - a.y * b.x;
    let den = det(d1, d2);
    let (g, h) = if den == 0.0 {
        (0.0, 0.0)
    } else {
        (det(sigma, d2) / den, det(d1, sigma) / den)
    };
    // Columns: the s, t and constant terms.
    Mat3::from_cols(
        Vec3::new(
            q[1].x - q[0].x + g * q[1].x,
            q[1].y - q[0].y + g * q[1].y,
            g,
        ),
        Vec3::new(
            q[3].x - q[0].x + h * q[3].x,
            q[3].y - q[0].y + h * q[3].y,
            h,
        ),
        Vec3::new(q[0].x, q[0].y, 1.0),
    )
}

/// The slide projector of a window from a light (section 4.5): world
/// points to homogeneous texture coordinates, `(s q, t q, ·, q) = M p`,
/// with `q > 0` on the light's side of the projection's centre.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Projector {
    /// `M = M₃₃⁻¹ · P_L` (the rows `x, y, w` of the light's projection), as a
    /// 4 × 4 whose third row is zero.
    pub matrix: Mat4,
}

impl Projector {
    /// The projector of `window` from a point light at `light`; `None` when
    /// the light lies in the window's plane (no projection).
    pub fn new(window: &Window, light: Vec3) -> Option<Self> {
        let centre = window.origin + 0.5 * (window.u + window.v);
        let axis = centre - light;
        if window.plane.signed_distance(light).abs() <= 1e-6 * axis.length().max(1e-6) {
            return None;
        }
        let up = if axis.cross(Vec3::Y).length_squared() > 1e-8 * axis.length_squared() {
            Vec3::Y
        } else {
            Vec3::X
        };
        // The light's view with a unit focal length: image coordinates
        // (x/w, y/w) of the paper's light projection P_L (M₃₃ absorbs any
        // field of view). Rows x, y and w as 4-vectors on (p, 1).
        let forward = axis.normalize();
        let right = forward.cross(up).normalize();
        let up = right.cross(forward);
        let row = |d: Vec3| d.extend(-d.dot(light));
        let (x, y, w) = (row(right), row(up), row(forward));
        let image = |p: Vec3| {
            let c = p.extend(1.0);
            Vec2::new(x.dot(c) / w.dot(c), y.dot(c) / w.dot(c))
        };
        let quad = window.rectangle().map(image);
        let inverse = square_to_quad(quad).inverse();
        if !inverse.is_finite() {
            return None;
        }
        let row = |r: Vec3| x * r.x + y * r.y + w * r.z;
        // Rows of M₃₃⁻¹ applied to (x, y, w).
        let (r0, r1, r2) = (inverse.row(0), inverse.row(1), inverse.row(2));
        let (mut s, mut t, mut q) = (row(r0), row(r1), row(r2));
        // The homogeneous scale is free: make q positive at the window's centre.
        if q.dot(centre.extend(1.0)) < 0.0 {
            (s, t, q) = (-s, -t, -q);
        }
        Some(Self {
            matrix: Mat4::from_cols(s, t, Vec4::ZERO, q).transpose(),
        })
    }

    /// Texture coordinates of `p`, `None` behind the projection's centre.
    pub fn coordinates(&self, p: Vec3) -> Option<Vec2> {
        let h = self.matrix * p.extend(1.0);
        (h.w > 0.0).then(|| Vec2::new(h.x / h.w, h.y / h.w))
    }
}

/// Uploads equal-sized RGBA layers (row 0 at `t = 0`) as one RGBA16F
/// 2-D array texture and returns its array view.
pub fn upload_layers(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    width: u32,
    height: u32,
    layers: &[Vec<[f32; 4]>],
) -> wgpu::TextureView {
    let count = layers.len().max(1) as u32;
    let texture = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("window-transmittance"),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: count,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba16Float,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    for (layer, texels) in layers.iter().enumerate() {
        let data: Vec<half::f16> = texels
            .iter()
            .flat_map(|t| t.map(half::f16::from_f32))
            .collect();
        queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &texture,
                mip_level: 0,
                origin: wgpu::Origin3d {
                    x: 0,
                    y: 0,
                    z: layer as u32,
                },
                aspect: wgpu::TextureAspect::All,
            },
            bytemuck::cast_slice(&data),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(width * 8),
                rows_per_image: Some(height),
            },
            wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
        );
    }
    texture.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    })
}

/// The windows' textures' total texel bytes as RGBA16F.
pub fn texture_bytes(windows: &[Window]) -> usize {
    windows
        .iter()
        .map(|w| (w.texture.width * w.texture.height) as usize * 8)
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A window `origin + s u + t v` of two rectangular panes split at
    /// `s = 0.3`: red below, blue above.
    fn square_window(origin: Vec3, u: Vec3, v: Vec3) -> Window {
        let plane = Plane::from_point_normal(origin, u.cross(v));
        let rect = |a: Vec3, b: Vec3, transmittance: Rgb| {
            let [p0, p1, p2, p3] = [a, a + b, a + b + v, a + v];
            [
                Pane {
                    corners: [p0, p1, p2],
                    transmittance,
                },
                Pane {
                    corners: [p0, p2, p3],
                    transmittance,
                },
            ]
        };
        let mut panes = rect(origin, 0.3 * u, Rgb::new(1.0, 0.0, 0.0)).to_vec();
        panes.extend(rect(origin + 0.3 * u, 0.7 * u, Rgb::new(0.0, 0.0, 1.0)));
        window(plane, 1.5, vec![0], panes, 8)
    }

    #[test]
    fn square_to_quad_maps_the_corners() {
        let q = [
            Vec2::new(0.1, 0.2),
            Vec2::new(1.3, -0.1),
            Vec2::new(1.1, 0.9),
            Vec2::new(-0.2, 0.7),
        ];
        let m = square_to_quad(q);
        for (st, want) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
            .into_iter()
            .zip(q)
        {
            let h = m * Vec3::new(st.0, st.1, 1.0);
            let got = Vec2::new(h.x / h.z, h.y / h.z);
            assert!((got - want).length() < 1e-5, "{st:?}: {got} vs {want}");
        }
        // A parallelogram: affine, g = h = 0.
        let p = [
            Vec2::ZERO,
            Vec2::new(2.0, 0.0),
            Vec2::new(3.0, 1.0),
            Vec2::new(1.0, 1.0),
        ];
        let m = square_to_quad(p);
        assert_eq!(m.row(2), Vec3::new(0.0, 0.0, 1.0));
    }

    #[test]
    fn the_projector_gives_where_the_line_from_the_light_crosses_the_window() {
        let w = square_window(
            Vec3::new(-0.6, 1.0, 0.0),
            Vec3::new(1.2, 0.0, 0.0),
            Vec3::new(0.0, 1.2, 0.3),
        );
        let mut rng = 0x2545_f491_u32;
        let mut next = move || {
            rng ^= rng << 13;
            rng ^= rng >> 17;
            rng ^= rng << 5;
            rng as f32 / u32::MAX as f32
        };
        for light in [
            Vec3::new(0.2, 3.4, -2.0),
            Vec3::new(-3.0, 0.5, -1.0),
            Vec3::new(0.0, 1.6, -0.2),
        ] {
            let projector = Projector::new(&w, light).expect("light off the plane");
            for _ in 0..200 {
                let st = Vec2::new(next(), next());
                let x = w.point(st);
                // Any receiver on the line from the light through X, beyond the window.
                let p = light + (x - light) * (1.0 + 3.0 * next());
                let got = projector.coordinates(p).expect("in front of the light");
                assert!((got - st).length() < 2e-4, "light {light}: {got} vs {st}");
            }
        }
        // A light in the window's plane projects nothing.
        assert!(Projector::new(&w, w.origin + 2.0 * w.u).is_none());
    }

    #[test]
    fn the_texture_holds_each_panes_filter_and_the_coverage() {
        let w = square_window(Vec3::ZERO, Vec3::X, Vec3::Y);
        assert_eq!((w.texture.width, w.texture.height), (8, 8));
        // Texels wholly at x < 0.3 are red, at x > 0.3 blue; those the
        // split crosses mix both, fully covered.
        let (mut red, mut blue) = (0, 0);
        for j in 0..8u32 {
            for i in 0..8u32 {
                let texel = w.texture.texels[(j * 8 + i) as usize];
                assert_eq!(texel[3], 1.0);
                let xs = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)].map(|(a, b)| {
                    w.point(Vec2::new((i as f32 + a) / 8.0, (j as f32 + b) / 8.0))
                        .x
                });
                if xs.iter().all(|&x| x < 0.3) {
                    assert_eq!(texel, [1.0, 0.0, 0.0, 1.0]);
                    red += 1;
                } else if xs.iter().all(|&x| x > 0.3) {
                    assert_eq!(texel, [0.0, 0.0, 1.0, 1.0]);
                    blue += 1;
                } else {
                    assert!((texel[0] + texel[2] - 1.0).abs() < 1e-6, "{texel:?}");
                }
            }
        }
        // Two columns red, five blue, one mixed (whichever axis s runs along x).
        assert_eq!((red, blue), (16, 40));
        // 10 of the 32 sample columns (4 per texel) lie at x < 0.3.
        let (sum, covered) = w
            .texture
            .texels
            .iter()
            .fold((Vec3::ZERO, 0.0f32), |(s, c), t| {
                (s + Vec3::new(t[0], t[1], t[2]), c + t[3])
            });
        let mean = sum / covered;
        assert!(
            (mean - Vec3::new(10.0 / 32.0, 0.0, 22.0 / 32.0)).length() < 1e-6,
            "{mean}"
        );
    }

    #[test]
    fn stained_glass_is_one_window_or_sixteen_panes() {
        let scene = lustre_geometry::builtin::stained_glass::stained_glass();
        let one = windows(&scene, PaneLight::default()).unwrap();
        assert_eq!(one.len(), 1);
        assert_eq!(one[0].surfaces.len(), 16);
        assert_eq!((one[0].texture.width, one[0].texture.height), (256, 256));
        let (corner, size) = lustre_geometry::builtin::stained_glass::WINDOW;
        let rect = one[0].rectangle();
        for c in [corner, corner + Vec3::new(size, size, 0.0)] {
            assert!(
                rect.iter().any(|r| (*r - c).length() < 1e-5),
                "{c} in {rect:?}"
            );
        }
        assert_eq!(windows(&scene, PaneLight::PerPane).unwrap().len(), 16);
        assert!(windows(&scene, PaneLight::Off).unwrap().is_empty());
        assert!(windows(&scene, PaneLight::Projective { size: 0 }).is_err());
        // Rough panes are left to the splats and beams.
        let rough = lustre_geometry::builtin::stained_glass::stained_glass_with(0.1);
        assert!(windows(&rough, PaneLight::default()).unwrap().is_empty());
    }
}
