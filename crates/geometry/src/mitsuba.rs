//! Export of a [`Scene`] to Mitsuba 3's XML scene format (version 3.0.0), so
//! that an independent path tracer can render a reference (DESIGN.md,
//! "Built-in scenes" and "Testing").
//!
//! Every mesh is written as a binary little-endian PLY file in a `meshes/`
//! folder beside the XML, in world space (the object transforms applied),
//! with positions, shading normals, UVs and triangles. The mapping:
//!
//! | Lustre | Mitsuba 3 |
//! |---|---|
//! | [`MaterialModel::Diffuse`] | `diffuse` with `reflectance` |
//! | [`MaterialModel::RoughConductor`] (Beckmann, GGX) | `roughconductor` with `distribution`, `alpha`, `eta`/`k` (or `material="none"` for F = 1) and `specular_reflectance` |
//! | [`MaterialModel::Mirror`] | `conductor` with `material="none"` and `specular_reflectance` |
//! | [`MaterialModel::Dielectric`] | `dielectric` with `int_ior`, `ext_ior = 1` and `specular_transmittance` |
//! | `MaterialModel::Named` `thin-dielectric` ([`crate::material::THIN_DIELECTRIC`]) | `thindielectric` with `int_ior`, `ext_ior = 1` and `specular_transmittance`; a rough one is approximated as smooth |
//! | [`MaterialModel::Blend`] | `blendbsdf` with `weight` (the weight of the second nested BSDF in both) |
//! | opacity < 1 (non-dielectric) | the BSDF nested in `mask` with `opacity` |
//! | emissive mesh | its shape with an `area` emitter of the material's `radiance`, keeping the material's BSDF |
//! | [`Light::Point`] | `point` emitter with `position` and `intensity`; with [`ExportOptions::point_light_radius`] a `sphere` with a `null` BSDF and an `area` emitter of the same power |
//! | [`Light::Spot`] | `spot` emitter with `intensity`, `cutoff_angle` and `beam_width` in degrees |
//! | [`Camera`] | `perspective` sensor with `fov_axis="y"`, a `lookat` `to_world`, `hdrfilm` and an `independent` sampler |
//!
//! A material's decoded diffuse map ([`Material::diffuse_map`]) is exported
//! as a `bitmap` texture for the `reflectance` of the `diffuse` BSDF that
//! carries its Lambertian part (that of `Diffuse`, of the diffuse term of an
//! approximated Phong or Ward, of each diffuse BSDF nested in a `blendbsdf`):
//! the texels times that BSDF's reflectance, baked into a linear float32
//! OpenEXR file in a `textures/` folder beside the XML, read `raw` (not
//! re-linearised), filtered bilinearly and repeated like
//! [`crate::Texture::sample`]. Mitsuba's bitmap has `(0, 0)` at the image's
//! top-left corner (its `v` grows downwards, checked against Mitsuba 3.9 by
//! `tests/tests/mitsuba_equivalence.rs`) while the PLY UVs keep OBJ's `v`
//! up, so the texture's `to_uv` maps `(u, v)` to `(u, 1 − v)`.
//!
//! Mitsuba has no Phong, Ward, Gaussian-distribution or named models, no
//! cosine point light and no explicit (mesh-less) area light, and texture
//! files that were not decoded (and specular maps) are not exported; they
//! are [`GeometryError::Unsupported`] unless
//! [`ExportOptions::approximate`] asks for an approximation (Phong and Ward
//! become their diffuse term, Gaussian becomes Beckmann of the same alpha, a
//! named model a diffuse reflector, a cosine point light a tiny square area
//! light of the same far field, a mesh-less area light an emitting shape
//! with a `null` BSDF, those textures are dropped), each listed in
//! [`ExportReport::warnings`].
//!
//! UVs are written as stored (OBJ's convention, v up); Mitsuba's PLY loader
//! does not flip them. Mitsuba's BSDFs are one-sided, as in its own
//! `cornell_box()`; [`ExportOptions::two_sided`] wraps them in `twosided`.
//! `cornell` exported with `max_depth` 8 and a Gaussian filter renders the
//! same image as `mi.cornell_box()` (`tests/tests/mitsuba_equivalence.rs`).

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};

use crate::light::{AreaShape, Light};
use crate::material::{
    ConductorFresnel, Material, MaterialModel, MicrofacetDistribution, THIN_DIELECTRIC,
};
use crate::{Camera, GeometryError, Result, Rgb, Scene};

/// The reconstruction filter of Mitsuba's film.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ReconstructionFilter {
    /// One-pixel box filter: each sample counts only in its own pixel.
    Box,
    /// Gaussian filter with the given standard deviation in pixels (Mitsuba's default is 0.5).
    Gaussian {
        /// Standard deviation in pixels.
        stddev: f32,
    },
}

/// Mitsuba's integrator for the exported render.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Integrator {
    /// `path`: unidirectional path tracing from the camera.
    #[default]
    Path,
    /// `ptracer`: particle (light) tracing, each light path's non-delta
    /// vertices connected to the camera. It finds point lights through
    /// delta surfaces (light → window pane → floor) exactly, and misses what
    /// the camera sees through or in a delta surface (a pane's reflection).
    ParticleTracer,
}

impl Integrator {
    /// Mitsuba's plugin name.
    pub fn plugin(self) -> &'static str {
        match self {
            Self::Path => "path",
            Self::ParticleTracer => "ptracer",
        }
    }
}

/// Settings of the exported render: film, sampler, integrator and what to do with unsupported items.
#[derive(Debug, Clone, PartialEq)]
pub struct ExportOptions {
    /// Film width in pixels.
    pub width: u32,
    /// Film height in pixels.
    pub height: u32,
    /// Samples per pixel of the `independent` sampler.
    pub spp: u32,
    /// Seed of the sampler.
    pub seed: u32,
    /// The integrator.
    pub integrator: Integrator,
    /// Longest path of the integrator (-1: unbounded, Russian roulette ends paths).
    pub max_depth: i32,
    /// Reconstruction filter of the film.
    pub filter: ReconstructionFilter,
    /// Wrap every non-transmissive BSDF in `twosided` (Mitsuba's BSDFs are black from behind).
    pub two_sided: bool,
    /// Approximate what Mitsuba lacks instead of failing (each approximation is a warning in the report).
    pub approximate: bool,
    /// Export every isotropic point light ([`Light::Point`]) as a small
    /// spherical area light of this radius `r` in metres instead of Mitsuba's
    /// `point` emitter, so that a path tracer finds the light along
    /// delta-delta paths (light → mirror or water surface → diffuse floor →
    /// camera: caustics, which no path from the camera reaches a point
    /// light along). The sphere, centred on the light with a `null` BSDF (as
    /// the other approximated lights: invisible to paths, seen as an
    /// emitter), emits the uniform radiance `L = I / (π r²)`: a Lambertian
    /// emitter of area `4π r²` emits `Φ = π L · 4π r² = 4π I`, the point
    /// light's power, and its intensity seen from afar is `L · π r² = I` in
    /// every direction (a fully visible uniform sphere lights every point
    /// outside it exactly as the point light would). As a point light, the
    /// spheres are hidden from camera rays (the `path` integrator's
    /// `hide_emitters`) when nothing else in the scene emits. Spot lights and
    /// oriented point lights are exported as without it (a warning each).
    /// `None`: `point` emitters. The radius must be positive and finite.
    pub point_light_radius: Option<f32>,
}

impl Default for ExportOptions {
    fn default() -> Self {
        Self {
            width: 256,
            height: 256,
            spp: 64,
            seed: 0,
            integrator: Integrator::Path,
            max_depth: -1,
            filter: ReconstructionFilter::Box,
            two_sided: false,
            approximate: false,
            point_light_radius: None,
        }
    }
}

/// What [`export`] wrote and what it had to approximate.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ExportReport {
    /// The scene XML.
    pub xml: PathBuf,
    /// The PLY files: one per mesh in mesh order, then those of approximated lights.
    pub meshes: Vec<PathBuf>,
    /// The EXR files of the diffuse maps, in material order.
    pub textures: Vec<PathBuf>,
    /// Every approximation or mismatch, one line each (empty for an exact export).
    pub warnings: Vec<String>,
}

/// Writes `scene` as a Mitsuba 3 XML file at `xml_path`, with its meshes as
/// PLY files in `meshes/` and its diffuse maps as EXR files in `textures/`
/// beside it; every file is written to a temporary name and renamed.
pub fn export(scene: &Scene, xml_path: &Path, options: &ExportOptions) -> Result<ExportReport> {
    let dir = match xml_path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let mut warnings = Vec::new();
    let (xml, extra, baked) = build(scene, options, &mut warnings)?;
    let mut textures = Vec::with_capacity(baked.len());
    if !baked.is_empty() {
        let texture_dir = dir.join("textures");
        std::fs::create_dir_all(&texture_dir).map_err(|source| GeometryError::Io {
            path: texture_dir.clone(),
            source,
        })?;
    }
    for texture in &baked {
        let path = dir.join(&texture.file);
        write_atomically(&path, &texture.exr(&path)?)?;
        textures.push(path);
    }
    let mesh_dir = dir.join("meshes");
    std::fs::create_dir_all(&mesh_dir).map_err(|source| GeometryError::Io {
        path: mesh_dir.clone(),
        source,
    })?;
    let mut meshes = Vec::with_capacity(scene.meshes().len() + extra.len());
    let scene_meshes = scene
        .meshes()
        .iter()
        .enumerate()
        .map(|(m, mesh)| ExtraMesh {
            file: mesh_file(m, &mesh.name),
            name: mesh.name.clone(),
            mesh: PlyMesh {
                positions: scene.world_positions(m as u32),
                normals: scene.world_normals(m as u32),
                uvs: mesh.uvs.clone(),
                indices: mesh.indices.clone(),
            },
        });
    for item in scene_meshes.chain(extra) {
        let path = dir.join(&item.file);
        let bytes = write_ply(&item.mesh, &item.name)?;
        write_atomically(&path, &bytes)?;
        meshes.push(path);
    }
    write_atomically(xml_path, xml.as_bytes())?;
    Ok(ExportReport {
        xml: xml_path.to_path_buf(),
        meshes,
        textures,
        warnings,
    })
}

/// A diffuse map baked for one `diffuse` BSDF: its texels times that BSDF's reflectance, to write beside the XML.
struct BakedTexture {
    /// Path relative to the XML.
    file: String,
    /// Width in texels.
    width: u32,
    /// Height in texels.
    height: u32,
    /// Linear RGB, row by row from the top.
    texels: Vec<Rgb>,
}

impl BakedTexture {
    /// The texels as a float32 RGB OpenEXR file (row 0 at the top, ZIP-compressed); `path` names the file in errors.
    fn exr(&self, path: &Path) -> Result<Vec<u8>> {
        use exr::prelude::{Encoding, Image, SpecificChannels, WritableImage};
        let width = self.width as usize;
        let size = (width, self.height as usize);
        let mut bytes = std::io::Cursor::new(Vec::new());
        Image::from_encoded_channels(
            size,
            Encoding::SMALL_LOSSLESS,
            SpecificChannels::rgb(|p: exr::math::Vec2<usize>| {
                let t = self.texels[p.y() * width + p.x()];
                (t.x, t.y, t.z)
            }),
        )
        .write()
        .to_buffered(&mut bytes)
        .map_err(|e| GeometryError::Io {
            path: path.to_path_buf(),
            source: std::io::Error::other(e),
        })?;
        Ok(bytes.into_inner())
    }
}

/// The diffuse map of the material being written and where its baked copies go.
struct DiffuseMap<'a> {
    /// The decoded map.
    texture: &'a crate::Texture,
    /// The stem of the baked files' names (`textures/STEM-K.exr`).
    stem: String,
    /// The baked textures of the whole export.
    out: &'a mut Vec<BakedTexture>,
}

impl DiffuseMap<'_> {
    /// Bakes `reflectance ⊙ texels` and writes the `bitmap` texture that reads it as `reflectance`: raw, bilinear, repeated, with `to_uv` turning OBJ's `v` up into Mitsuba's `v` down.
    fn reflectance(&mut self, x: &mut Xml, reflectance: Rgb) {
        let file = format!("textures/{}-{}.exr", self.stem, self.out.len());
        self.out.push(BakedTexture {
            file: file.clone(),
            width: self.texture.width(),
            height: self.texture.height(),
            texels: self
                .texture
                .texels()
                .iter()
                .map(|t| *t * reflectance)
                .collect(),
        });
        x.open("texture", &[("type", "bitmap"), ("name", "reflectance")]);
        x.property("string", "filename", &file);
        x.property("boolean", "raw", true);
        x.property("string", "filter_type", "bilinear");
        x.property("string", "wrap_mode", "repeat");
        // (u, v) ↦ (u, 1 − v): Mitsuba's (0, 0) is the image's top-left corner.
        x.open("transform", &[("name", "to_uv")]);
        x.leaf("scale", &[("x", "1"), ("y", "-1")]);
        x.leaf("translate", &[("x", "0"), ("y", "1")]);
        x.close();
        x.close();
    }
}

/// A PLY file to write beside the XML.
struct ExtraMesh {
    /// Path relative to the XML.
    file: String,
    /// Name for messages and the PLY comment.
    name: String,
    /// The geometry.
    mesh: PlyMesh,
}

/// A small XML writer: indents, escapes attribute values and closes what it opened.
#[derive(Default)]
struct Xml {
    out: String,
    open: Vec<&'static str>,
}

impl Xml {
    /// Writes `<tag a="v" ...` at the current depth, without the closing `>`.
    fn start(&mut self, tag: &str, attrs: &[(&str, &str)]) {
        let _ = write!(self.out, "{}<{tag}", "    ".repeat(self.open.len()));
        for (key, value) in attrs {
            let _ = write!(self.out, " {key}=\"{}\"", escape(value));
        }
    }

    /// Opens an element that will hold children.
    fn open(&mut self, tag: &'static str, attrs: &[(&str, &str)]) {
        self.start(tag, attrs);
        self.out.push_str(">\n");
        self.open.push(tag);
    }

    /// Writes an empty element.
    fn leaf(&mut self, tag: &str, attrs: &[(&str, &str)]) {
        self.start(tag, attrs);
        self.out.push_str("/>\n");
    }

    /// Closes the innermost open element.
    fn close(&mut self) {
        let tag = self.open.pop().expect("close matches an open");
        let _ = writeln!(self.out, "{}</{tag}>", "    ".repeat(self.open.len()));
    }

    /// Writes a comment (control characters and `--` made safe for comments).
    fn comment(&mut self, text: &str) {
        let mut text: String = text
            .chars()
            .map(|c| if c.is_control() { ' ' } else { c })
            .collect();
        while text.contains("--") {
            text = text.replace("--", "- -");
        }
        let _ = writeln!(
            self.out,
            "{}<!-- {text} -->",
            "    ".repeat(self.open.len())
        );
    }

    /// A `<TYPE name="NAME" value="VALUE"/>` property.
    fn property(&mut self, ty: &str, name: &str, value: impl std::fmt::Display) {
        self.leaf(ty, &[("name", name), ("value", &value.to_string())]);
    }

    /// An `<rgb>` property.
    fn rgb(&mut self, name: &str, c: Rgb) {
        self.property("rgb", name, format!("{}, {}, {}", c.x, c.y, c.z));
    }

    /// A `to_world` transform from a look-at pose.
    fn lookat(&mut self, origin: Vec3, target: Vec3, up: Vec3) {
        self.open("transform", &[("name", "to_world")]);
        let [o, t, u] = [origin, target, up].map(|v| format!("{}, {}, {}", v.x, v.y, v.z));
        self.leaf("lookat", &[("origin", &o), ("target", &t), ("up", &u)]);
        self.close();
    }
}

/// The Mitsuba 3 XML of `scene`, naming its meshes `meshes/NNN-name.ply`
/// relative to the XML file; approximations are appended to `warnings`.
pub fn scene_xml(
    scene: &Scene,
    options: &ExportOptions,
    warnings: &mut Vec<String>,
) -> Result<String> {
    build(scene, options, warnings).map(|(xml, _, _)| xml)
}

/// The XML, the PLY files of approximated lights and the baked diffuse maps (the scene's meshes are written by [`export`]).
fn build(
    scene: &Scene,
    options: &ExportOptions,
    warnings: &mut Vec<String>,
) -> Result<(String, Vec<ExtraMesh>, Vec<BakedTexture>)> {
    if options.width == 0 || options.height == 0 || options.spp == 0 {
        return Err(GeometryError::Unsupported {
            what: format!("scene `{}`", scene.name),
            why: format!(
                "film {}x{} with {} spp: width, height and spp must be positive",
                options.width, options.height, options.spp
            ),
        });
    }
    if let Some(r) = options.point_light_radius
        && !(r.is_finite() && r > 0.0)
    {
        return Err(GeometryError::Unsupported {
            what: format!("scene `{}`", scene.name),
            why: format!("point light radius {r}: it must be positive and finite"),
        });
    }
    let mut x = Xml::default();
    x.out
        .push_str("<?xml version=\"1.0\" encoding=\"utf-8\"?>\n");
    x.comment(&format!(
        "Lustre export of scene \"{}\" (lustre_geometry::mitsuba)",
        scene.name
    ));
    x.open("scene", &[("version", "3.0.0")]);
    x.open("integrator", &[("type", options.integrator.plugin())]);
    x.property("integer", "max_depth", options.max_depth);
    if options.point_light_radius.is_some() && hides_point_light_spheres(scene, warnings) {
        x.property("boolean", "hide_emitters", true);
    }
    x.close();
    sensor_xml(&mut x, scene, options, warnings);
    let mut textures = Vec::new();
    for (i, material) in scene.materials().iter().enumerate() {
        x.comment(&format!("material \"{}\"", material.name));
        material_bsdf(
            &mut x,
            material,
            &material_id(i, &material.name),
            options,
            warnings,
            &mut textures,
        )?;
    }
    for (m, mesh) in scene.meshes().iter().enumerate() {
        let material = &scene.materials()[mesh.material as usize];
        let id = format!("mesh-{m}-{}", sanitize(&mesh.name));
        x.open("shape", &[("type", "ply"), ("id", &id)]);
        x.property("string", "filename", mesh_file(m, &mesh.name));
        x.leaf(
            "ref",
            &[("id", &material_id(mesh.material as usize, &material.name))],
        );
        if material.is_emissive() {
            x.open("emitter", &[("type", "area")]);
            x.rgb("radiance", material.emission);
            x.close();
        }
        x.close();
    }
    let mut extra = Vec::new();
    for (i, light) in scene.lights().iter().enumerate() {
        light_xml(&mut x, i, light, scene, options, warnings, &mut extra)?;
    }
    x.close();
    debug_assert!(x.open.is_empty());
    Ok((x.out, extra, textures))
}

/// Whether the integrator should hide directly visible emitters when point
/// lights are exported as spheres ([`ExportOptions::point_light_radius`]): a
/// point light is invisible to camera rays, and Mitsuba's `hide_emitters`
/// removes only what camera rays hit first (light from the spheres reflected,
/// refracted or scattered stays), so it is set when the spheres are the only
/// emitters that could be seen. With emissive meshes or area lights as well
/// it would hide those too: the spheres stay visible, with a warning.
fn hides_point_light_spheres(scene: &Scene, warnings: &mut Vec<String>) -> bool {
    if !scene.lights().iter().any(|l| matches!(l, Light::Point(_))) {
        return false;
    }
    let others = scene.lights().iter().any(|l| matches!(l, Light::Area(_)))
        || scene.materials().iter().any(Material::is_emissive);
    if others {
        warnings.push(
            "the spheres of the point lights are visible to the camera: hiding them \
             (`hide_emitters`) would hide the scene's other emitters too"
                .into(),
        );
    }
    !others
}

/// The `perspective` sensor with film and sampler.
fn sensor_xml(x: &mut Xml, scene: &Scene, options: &ExportOptions, warnings: &mut Vec<String>) {
    let camera: &Camera = scene.camera();
    let film_aspect = options.width as f32 / options.height as f32;
    if (film_aspect - camera.aspect).abs() > 1e-3 * camera.aspect {
        warnings.push(format!(
            "film {}x{} (aspect {film_aspect}) differs from the camera's aspect {}; \
             the vertical field of view is kept",
            options.width, options.height, camera.aspect
        ));
    }
    // Far enough to see every point of the scene.
    let bounds = scene.bounds();
    let far = (bounds.max - camera.position)
        .abs()
        .max((bounds.min - camera.position).abs())
        .length();
    x.open("sensor", &[("type", "perspective")]);
    x.property("string", "fov_axis", "y");
    x.property("float", "fov", camera.fov_y_degrees);
    x.property("float", "near_clip", camera.near);
    x.property("float", "far_clip", (2.0 * far).max(100.0));
    x.lookat(camera.position, camera.target, camera.up);
    x.open("sampler", &[("type", "independent")]);
    x.property("integer", "sample_count", options.spp);
    x.property("integer", "seed", options.seed);
    x.close();
    x.open("film", &[("type", "hdrfilm")]);
    x.property("integer", "width", options.width);
    x.property("integer", "height", options.height);
    x.property("string", "pixel_format", "rgb");
    x.property("string", "component_format", "float32");
    match options.filter {
        ReconstructionFilter::Box => x.leaf("rfilter", &[("type", "box")]),
        ReconstructionFilter::Gaussian { stddev } => {
            x.open("rfilter", &[("type", "gaussian")]);
            x.property("float", "stddev", stddev);
            x.close();
        }
    }
    x.close();
    x.close();
}

/// One light's emitter, or nothing for area lights written with their mesh.
fn light_xml(
    x: &mut Xml,
    index: usize,
    light: &Light,
    scene: &Scene,
    options: &ExportOptions,
    warnings: &mut Vec<String>,
    extra: &mut Vec<ExtraMesh>,
) -> Result<()> {
    let id = format!("light-{index}");
    if let (Some(r), Light::Spot(_) | Light::OrientedPoint(_)) = (options.point_light_radius, light)
    {
        warnings.push(format!(
            "light #{index}: the point light radius {r} applies to isotropic point lights only; \
             exported as without it"
        ));
    }
    match light {
        Light::Point(p) => {
            let [px, py, pz] = p.position.to_array().map(|c| c.to_string());
            match options.point_light_radius {
                Some(r) => {
                    // L = I / (π r²): power π L · 4π r² = 4π I (ExportOptions::point_light_radius).
                    x.open("shape", &[("type", "sphere"), ("id", &id)]);
                    x.leaf(
                        "point",
                        &[("name", "center"), ("x", &px), ("y", &py), ("z", &pz)],
                    );
                    x.property("float", "radius", r);
                    x.leaf("bsdf", &[("type", "null")]);
                    x.open("emitter", &[("type", "area")]);
                    x.rgb("radiance", p.intensity / (std::f32::consts::PI * r * r));
                    x.close();
                }
                None => {
                    x.open("emitter", &[("type", "point"), ("id", &id)]);
                    x.leaf(
                        "point",
                        &[("name", "position"), ("x", &px), ("y", &py), ("z", &pz)],
                    );
                    x.rgb("intensity", p.intensity);
                }
            }
            x.close();
        }
        Light::Spot(s) => {
            x.open("emitter", &[("type", "spot"), ("id", &id)]);
            x.lookat(
                s.position,
                s.position + s.direction,
                tangents(s.direction).0,
            );
            x.rgb("intensity", s.intensity);
            x.property("float", "cutoff_angle", s.cutoff_angle.to_degrees());
            x.property("float", "beam_width", s.beam_width.to_degrees());
            x.close();
        }
        Light::Area(a) if a.mesh.is_some() => {}
        Light::Area(a) => {
            let what = format!("light #{index} (an area light without a mesh)");
            if !options.approximate {
                return Err(GeometryError::Unsupported {
                    what,
                    why: "Mitsuba's area emitters sit on shapes; enable `approximate` to export \
                          it as an emitting shape with a `null` BSDF"
                        .into(),
                });
            }
            warnings.push(format!(
                "{what}: exported as an emitting shape with a `null` BSDF"
            ));
            let triangles = match &a.shape {
                AreaShape::Rectangle {
                    origin,
                    edge_u,
                    edge_v,
                } => {
                    let (o, u, v) = (*origin, *edge_u, *edge_v);
                    vec![[o, o + u, o + u + v], [o + u + v, o + v, o]]
                }
                AreaShape::Triangles { triangles, .. } => triangles.clone(),
            };
            null_emitter_shape(x, &id, &triangles, a.radiance, extra);
        }
        Light::OrientedPoint(p) => {
            let what = format!("light #{index} (an oriented point light)");
            if !options.approximate {
                return Err(GeometryError::Unsupported {
                    what,
                    why: "Mitsuba has no point light with cosine emission; enable `approximate` \
                          to export it as a tiny one-sided square area light"
                        .into(),
                });
            }
            // A square of side s facing `normal` with radiance I0 / s² has the far field I0 cos θ.
            let side = 1e-3 * scene.bounds().extent().max_element().max(1e-3);
            let (u, v) = tangents(p.normal);
            let (u, v) = (u * side, v * side);
            let o = p.position - 0.5 * (u + v);
            let triangles = vec![[o, o + u, o + u + v], [o + u + v, o + v, o]];
            warnings.push(format!(
                "{what}: exported as a {side} m square area light of radiance I0 / side² \
                 with a `null` BSDF"
            ));
            null_emitter_shape(x, &id, &triangles, p.intensity / (side * side), extra);
        }
    }
    Ok(())
}

/// An emitting shape with a `null` BSDF (invisible to paths, visible as an
/// emitter) made of flat triangles; its PLY is queued in `extra`.
fn null_emitter_shape(
    x: &mut Xml,
    id: &str,
    triangles: &[[Vec3; 3]],
    radiance: Rgb,
    extra: &mut Vec<ExtraMesh>,
) {
    let mut ply = PlyMesh::default();
    for t in triangles {
        let n = (t[1] - t[0]).cross(t[2] - t[0]).normalize_or_zero();
        let base = ply.positions.len() as u32;
        ply.positions.extend(t);
        ply.normals.extend([n; 3]);
        ply.uvs.extend([Vec2::ZERO, Vec2::X, Vec2::Y]);
        ply.indices.push([base, base + 1, base + 2]);
    }
    let file = format!("meshes/{id}.ply");
    x.open("shape", &[("type", "ply"), ("id", id)]);
    x.property("string", "filename", &file);
    x.leaf("bsdf", &[("type", "null")]);
    x.open("emitter", &[("type", "area")]);
    x.rgb("radiance", radiance);
    x.close();
    x.close();
    extra.push(ExtraMesh {
        file,
        name: id.to_owned(),
        mesh: ply,
    });
}

/// The `<bsdf id="ID">` element of a material, nested in `mask` and `twosided` as needed.
fn material_bsdf(
    x: &mut Xml,
    material: &Material,
    id: &str,
    options: &ExportOptions,
    warnings: &mut Vec<String>,
    textures: &mut Vec<BakedTexture>,
) -> Result<()> {
    let what = format!("material `{}`", material.name);
    // A decoded diffuse map is exported; a file that was not decoded is what Lustre renders without.
    let undecoded = material
        .diffuse_texture
        .as_ref()
        .filter(|_| material.diffuse_map.is_none());
    for (texture, kind) in [
        (undecoded, "diffuse"),
        (material.specular_texture.as_ref(), "specular"),
    ] {
        if let Some(path) = texture {
            if !options.approximate {
                return Err(GeometryError::Unsupported {
                    what,
                    why: format!(
                        "its {kind} texture {} is not exported; enable `approximate` to drop it",
                        path.display()
                    ),
                });
            }
            warnings.push(format!("{what}: {kind} texture {} dropped", path.display()));
        }
    }
    let transmissive = match &material.model {
        MaterialModel::Dielectric { .. } => true,
        MaterialModel::Named { model, .. } => model == THIN_DIELECTRIC,
        _ => false,
    };
    let mut attr = ("id", id);
    let mut wrappers = 0;
    if material.opacity < 1.0 && !transmissive {
        x.open("bsdf", &[("type", "mask"), attr]);
        x.property("float", "opacity", material.opacity);
        attr = ("name", "nested");
        wrappers += 1;
    }
    if options.two_sided && !transmissive {
        x.open("bsdf", &[("type", "twosided"), attr]);
        attr = ("name", "nested");
        wrappers += 1;
    }
    let mut map = material.diffuse_map.as_deref().map(|texture| DiffuseMap {
        texture,
        stem: sanitize(id),
        out: textures,
    });
    model_bsdf(
        x,
        &material.model,
        attr,
        &what,
        options,
        warnings,
        map.as_mut(),
    )?;
    for _ in 0..wrappers {
        x.close();
    }
    Ok(())
}

/// The `<bsdf>` element of a reflectance model, with one attribute (its id or its name).
fn model_bsdf(
    x: &mut Xml,
    model: &MaterialModel,
    attr: (&str, &str),
    what: &str,
    options: &ExportOptions,
    warnings: &mut Vec<String>,
    mut map: Option<&mut DiffuseMap<'_>>,
) -> Result<()> {
    let mut approximate = |why: &str, approximation: &str| -> Result<()> {
        if options.approximate {
            warnings.push(format!("{what}: {why}; exported as {approximation}"));
            Ok(())
        } else {
            Err(GeometryError::Unsupported {
                what: what.to_owned(),
                why: format!("{why}; enable `approximate` to export it as {approximation}"),
            })
        }
    };
    // The Lambertian part: its reflectance, or the diffuse map times it.
    let diffuse = |x: &mut Xml, reflectance: Rgb, map: Option<&mut DiffuseMap<'_>>| {
        x.open("bsdf", &[("type", "diffuse"), attr]);
        match map {
            Some(map) => map.reflectance(x, reflectance),
            None => x.rgb("reflectance", reflectance),
        }
        x.close();
    };
    match model {
        MaterialModel::Diffuse { reflectance } => diffuse(x, *reflectance, map),
        MaterialModel::RoughConductor {
            distribution,
            alpha,
            fresnel,
            specular,
        } => {
            let name = match distribution {
                MicrofacetDistribution::Beckmann => "beckmann",
                MicrofacetDistribution::Ggx => "ggx",
                MicrofacetDistribution::Gaussian => {
                    approximate(
                        "Mitsuba has no Gaussian microfacet distribution",
                        "a Beckmann distribution of the same alpha",
                    )?;
                    "beckmann"
                }
            };
            x.open("bsdf", &[("type", "roughconductor"), attr]);
            x.property("string", "distribution", name);
            x.property("float", "alpha", alpha);
            conductor_params(x, fresnel, *specular);
            x.close();
        }
        MaterialModel::Mirror { reflectance } => {
            x.open("bsdf", &[("type", "conductor"), attr]);
            conductor_params(x, &ConductorFresnel::None, *reflectance);
            x.close();
        }
        MaterialModel::Dielectric { ior, transmittance } => {
            x.open("bsdf", &[("type", "dielectric"), attr]);
            x.property("float", "int_ior", ior);
            x.property("float", "ext_ior", 1);
            if *transmittance != Rgb::ONE {
                x.rgb("specular_transmittance", *transmittance);
            }
            x.close();
        }
        MaterialModel::Blend {
            weight,
            first,
            second,
        } => {
            // Mitsuba's `weight` is that of the second nested BSDF, as ours. It
            // orders the nested BSDFs as they appear (its docs say: by name), so
            // they are named in the same order.
            x.open("bsdf", &[("type", "blendbsdf"), attr]);
            x.property("float", "weight", weight);
            model_bsdf(
                x,
                first,
                ("name", "bsdf_0"),
                what,
                options,
                warnings,
                map.as_deref_mut(),
            )?;
            model_bsdf(x, second, ("name", "bsdf_1"), what, options, warnings, map)?;
            x.close();
        }
        MaterialModel::Phong { diffuse: kd, .. } => {
            approximate("Mitsuba has no Phong model", "its diffuse term")?;
            diffuse(x, *kd, map);
        }
        MaterialModel::Ward { diffuse: kd, .. } => {
            approximate("Mitsuba has no Ward model", "its diffuse term")?;
            diffuse(x, *kd, map);
        }
        MaterialModel::Named { model, params } if model == THIN_DIELECTRIC => {
            let value = |name: &str| params.get(name).map(Vec::as_slice);
            let bad = |name: &str| GeometryError::Unsupported {
                what: what.to_owned(),
                why: format!(
                    "`{THIN_DIELECTRIC}` parameter `{name}` has the wrong number of values"
                ),
            };
            let ior = match value("ior") {
                None => 1.5,
                Some([v]) => *v,
                Some(_) => return Err(bad("ior")),
            };
            let roughness = match value("roughness") {
                None => 0.0,
                Some([v]) => *v,
                Some(_) => return Err(bad("roughness")),
            };
            let transmittance = match value("transmittance") {
                None => Rgb::ONE,
                Some([g]) => Rgb::splat(*g),
                Some([r, g, b]) => Rgb::new(*r, *g, *b),
                Some(_) => return Err(bad("transmittance")),
            };
            if roughness > 0.0 {
                approximate(
                    "Mitsuba has no rough thin dielectric",
                    "a smooth `thindielectric`",
                )?;
            }
            x.open("bsdf", &[("type", "thindielectric"), attr]);
            x.property("float", "int_ior", ior);
            x.property("float", "ext_ior", 1);
            if transmittance != Rgb::ONE {
                x.rgb("specular_transmittance", transmittance);
            }
            x.close();
        }
        MaterialModel::Named { model, params } => {
            approximate(
                &format!("Mitsuba has no `{model}` model"),
                "a diffuse reflector (its `reflectance`, `diffuse`, `kd` or `albedo` \
                 parameter, else 0.5 grey)",
            )?;
            let kd = ["reflectance", "diffuse", "kd", "albedo"]
                .iter()
                .find_map(|k| params.get(*k))
                .and_then(|v| match v.as_slice() {
                    [g] => Some(Rgb::splat(*g)),
                    [r, g, b] => Some(Rgb::new(*r, *g, *b)),
                    _ => None,
                })
                .unwrap_or(Rgb::splat(0.5));
            // A named model has no Lambertian part in Lustre (`diffuse_reflectance` is 0), so its map changes nothing.
            diffuse(x, kd, None);
        }
    }
    Ok(())
}

/// `eta`/`k` of a conductor, or `material="none"` for F = 1, and a non-white `specular_reflectance`.
fn conductor_params(x: &mut Xml, fresnel: &ConductorFresnel, specular: Rgb) {
    match fresnel {
        ConductorFresnel::Complex { eta, k } => {
            x.rgb("eta", *eta);
            x.rgb("k", *k);
        }
        // Mitsuba's "none" is eta = 0, k = 1: a reflectance of exactly one at every angle.
        ConductorFresnel::None => x.property("string", "material", "none"),
    }
    if specular != Rgb::ONE {
        x.rgb("specular_reflectance", specular);
    }
}

/// The id of material `i`.
fn material_id(i: usize, name: &str) -> String {
    format!("bsdf-{i}-{}", sanitize(name))
}

/// The PLY file of mesh `m`, relative to the XML.
fn mesh_file(m: usize, name: &str) -> String {
    format!("meshes/{m:03}-{}.ply", sanitize(name))
}

/// `name` reduced to ASCII letters, digits, `-` and `_` (for ids and file names).
fn sanitize(name: &str) -> String {
    let s: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .take(64)
        .collect();
    if s.is_empty() { "unnamed".into() } else { s }
}

/// Escapes the five XML special characters (control characters become spaces).
pub fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c if c.is_control() => out.push(' '),
            c => out.push(c),
        }
    }
    out
}

/// Two unit tangents `(u, v)` with `u × v = n`.
fn tangents(n: Vec3) -> (Vec3, Vec3) {
    let n = n.normalize();
    let helper = if n.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
    let u = helper.cross(n).normalize();
    (u, n.cross(u))
}

/// A triangle mesh as stored in a PLY file.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PlyMesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Vertex normals.
    pub normals: Vec<Vec3>,
    /// Vertex texture coordinates.
    pub uvs: Vec<Vec2>,
    /// Triangles.
    pub indices: Vec<[u32; 3]>,
}

/// Encodes a mesh as binary little-endian PLY (`x y z nx ny nz u v` floats,
/// faces as `uchar`-counted `int` lists), the layout Mitsuba's `ply` shape reads.
pub fn write_ply(mesh: &PlyMesh, name: &str) -> Result<Vec<u8>> {
    let n = mesh.positions.len();
    let bad = |message: String| GeometryError::InvalidMesh {
        mesh: name.to_owned(),
        message,
    };
    if mesh.normals.len() != n || mesh.uvs.len() != n {
        return Err(bad(format!(
            "{n} positions but {} normals and {} uvs",
            mesh.normals.len(),
            mesh.uvs.len()
        )));
    }
    if n > i32::MAX as usize {
        return Err(bad(format!("{n} vertices do not fit PLY `int` indices")));
    }
    if let Some(t) = mesh
        .indices
        .iter()
        .position(|t| t.iter().any(|&i| i as usize >= n))
    {
        return Err(bad(format!(
            "triangle {t} indexes a vertex beyond the {n} vertices"
        )));
    }
    let comment: String = name
        .chars()
        .map(|c| if c.is_control() { ' ' } else { c })
        .collect();
    let header = format!(
        "ply\nformat binary_little_endian 1.0\ncomment Lustre mesh {comment}\nelement vertex {n}\n\
         property float x\nproperty float y\nproperty float z\n\
         property float nx\nproperty float ny\nproperty float nz\n\
         property float u\nproperty float v\n\
         element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        mesh.indices.len()
    );
    let mut out = Vec::with_capacity(header.len() + n * 32 + mesh.indices.len() * 13);
    out.extend_from_slice(header.as_bytes());
    for i in 0..n {
        let (p, nn, uv) = (mesh.positions[i], mesh.normals[i], mesh.uvs[i]);
        for f in [p.x, p.y, p.z, nn.x, nn.y, nn.z, uv.x, uv.y] {
            out.extend_from_slice(&f.to_le_bytes());
        }
    }
    for t in &mesh.indices {
        out.push(3);
        for &i in t {
            out.extend_from_slice(&(i as i32).to_le_bytes());
        }
    }
    Ok(out)
}

/// Decodes the PLY layout [`write_ply`] writes (binary little-endian, float
/// vertex properties `x y z` and optionally `nx ny nz`, `u v`; triangle faces
/// as `uchar`-counted `int`/`uint` lists); `path` only names the file in errors.
pub fn read_ply(bytes: &[u8], path: &Path) -> Result<PlyMesh> {
    let bad = |message: String| GeometryError::Parse {
        location: crate::Location {
            file: path.to_path_buf(),
            line: None,
        },
        message,
    };
    const END: &[u8] = b"end_header\n";
    let end = bytes
        .windows(END.len())
        .position(|w| w == END)
        .ok_or_else(|| bad("no `end_header` line".into()))?
        + END.len();
    let header =
        std::str::from_utf8(&bytes[..end]).map_err(|_| bad("header is not UTF-8".into()))?;
    let mut lines = header.lines();
    if lines.next() != Some("ply") {
        return Err(bad("does not start with `ply`".into()));
    }
    let (mut vertices, mut faces) = (None, None);
    let mut vertex_props: Vec<String> = Vec::new();
    let mut face_list = None;
    let mut element = "";
    for line in lines {
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.as_slice() {
            ["format", "binary_little_endian", _] => {}
            ["format", other, ..] => return Err(bad(format!("format `{other}` is not supported"))),
            ["comment", ..] | ["obj_info", ..] | ["end_header"] | [] => {}
            ["element", "vertex", count] => {
                element = "vertex";
                vertices = Some(
                    count
                        .parse::<usize>()
                        .map_err(|e| bad(format!("vertex count: {e}")))?,
                );
            }
            ["element", "face", count] => {
                element = "face";
                faces = Some(
                    count
                        .parse::<usize>()
                        .map_err(|e| bad(format!("face count: {e}")))?,
                );
            }
            ["element", other, ..] => {
                return Err(bad(format!("element `{other}` is not supported")));
            }
            ["property", "float", name] if element == "vertex" => {
                vertex_props.push((*name).to_owned())
            }
            ["property", "list", "uchar", ty @ ("int" | "uint"), _] if element == "face" => {
                face_list = Some(*ty);
            }
            _ => return Err(bad(format!("header line `{line}` is not supported"))),
        }
    }
    let vertices = vertices.ok_or_else(|| bad("no vertex element".into()))?;
    let faces = faces.ok_or_else(|| bad("no face element".into()))?;
    if faces > 0 && face_list.is_none() {
        return Err(bad("faces without a `uchar` list of `int` indices".into()));
    }
    let column = |name: &str| vertex_props.iter().position(|p| p == name);
    let stride = vertex_props.len() * 4;
    let body = &bytes[end..];
    let vertex_bytes = vertices
        .checked_mul(stride)
        .filter(|&b| b <= body.len())
        .ok_or_else(|| bad(format!("file too short for {vertices} vertices")))?;
    let float = |v: usize, c: usize| {
        let at = v * stride + c * 4;
        f32::from_le_bytes([body[at], body[at + 1], body[at + 2], body[at + 3]])
    };
    let get3 = |names: [&str; 3]| -> Option<Vec<Vec3>> {
        let cols = [column(names[0])?, column(names[1])?, column(names[2])?];
        Some(
            (0..vertices)
                .map(|v| Vec3::new(float(v, cols[0]), float(v, cols[1]), float(v, cols[2])))
                .collect(),
        )
    };
    let positions = get3(["x", "y", "z"]).ok_or_else(|| bad("vertices without x, y, z".into()))?;
    let normals = get3(["nx", "ny", "nz"]).unwrap_or_default();
    let uvs = match (column("u"), column("v")) {
        (Some(cu), Some(cv)) => (0..vertices)
            .map(|v| Vec2::new(float(v, cu), float(v, cv)))
            .collect(),
        _ => Vec::new(),
    };
    let mut at = vertex_bytes;
    let mut indices = Vec::with_capacity(faces);
    for f in 0..faces {
        let count = *body
            .get(at)
            .ok_or_else(|| bad(format!("file ends in face {f}")))?;
        if count != 3 {
            return Err(bad(format!("face {f} has {count} vertices, not 3")));
        }
        let raw = body
            .get(at + 1..at + 13)
            .ok_or_else(|| bad(format!("file ends in face {f}")))?;
        let mut tri = [0u32; 3];
        for (k, slot) in tri.iter_mut().enumerate() {
            let w = [raw[4 * k], raw[4 * k + 1], raw[4 * k + 2], raw[4 * k + 3]];
            let i = u32::from_le_bytes(w);
            if i as usize >= vertices || (face_list == Some("int") && (i as i32) < 0) {
                return Err(bad(format!("face {f} indexes vertex {i} of {vertices}")));
            }
            *slot = i;
        }
        indices.push(tri);
        at += 13;
    }
    if at != body.len() {
        return Err(bad(format!(
            "{} bytes after the last face",
            body.len() - at
        )));
    }
    Ok(PlyMesh {
        positions,
        normals,
        uvs,
        indices,
    })
}

/// Writes `bytes` to a temporary file beside `path`, then renames it to `path` (the Mitsuba and glTF exports).
pub(crate) fn write_atomically(path: &Path, bytes: &[u8]) -> Result<()> {
    let io = |source| GeometryError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut tmp_name = path.file_name().unwrap_or_default().to_os_string();
    tmp_name.push(format!(".tmp-{}", std::process::id()));
    let tmp = path.with_file_name(tmp_name);
    let result = (|| {
        let mut file = std::fs::File::create(&tmp)?;
        file.write_all(bytes)?;
        file.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map_err(io)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::builtin;
    use crate::material::Material;

    /// A minimal well-formedness check: tags nest and close, attributes are quoted,
    /// no raw `<`/`&` appears in attribute values, and there is one root element.
    fn check_well_formed(xml: &str) -> std::result::Result<Vec<String>, String> {
        let mut stack: Vec<String> = Vec::new();
        let mut roots = 0;
        let mut opened = Vec::new();
        let mut rest = xml;
        while let Some(start) = rest.find('<') {
            let text = &rest[..start];
            if text.contains('>') {
                return Err(format!("stray `>` in text {text:?}"));
            }
            rest = &rest[start..];
            if let Some(r) = rest.strip_prefix("<?") {
                let end = r.find("?>").ok_or("unterminated declaration")?;
                rest = &r[end + 2..];
                continue;
            }
            if let Some(r) = rest.strip_prefix("<!--") {
                let end = r.find("-->").ok_or("unterminated comment")?;
                if r[..end].contains("--") {
                    return Err("`--` inside a comment".into());
                }
                rest = &r[end + 3..];
                continue;
            }
            let end = rest.find('>').ok_or("unterminated tag")?;
            let tag = &rest[1..end];
            rest = &rest[end + 1..];
            if let Some(name) = tag.strip_prefix('/') {
                let open = stack
                    .pop()
                    .ok_or_else(|| format!("`</{name}>` closes nothing"))?;
                if open != name.trim() {
                    return Err(format!("`<{open}>` closed by `</{name}>`"));
                }
                continue;
            }
            let self_closing = tag.ends_with('/');
            let tag = tag.trim_end_matches('/');
            let name_end = tag.find(char::is_whitespace).unwrap_or(tag.len());
            let name = &tag[..name_end];
            if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
                return Err(format!("bad tag name {name:?}"));
            }
            // Attributes: key="value" pairs.
            let mut attrs = tag[name_end..].trim();
            while !attrs.is_empty() {
                let eq = attrs
                    .find("=\"")
                    .ok_or_else(|| format!("unquoted attribute in {tag:?}"))?;
                let key = attrs[..eq].trim();
                if key.is_empty() || key.contains(char::is_whitespace) {
                    return Err(format!("bad attribute name in {tag:?}"));
                }
                let value_end = attrs[eq + 2..].find('"').ok_or("unterminated attribute")?;
                let value = &attrs[eq + 2..eq + 2 + value_end];
                if value.contains('<')
                    || value
                        .replace("&amp;", "")
                        .replace("&lt;", "")
                        .replace("&gt;", "")
                        .replace("&quot;", "")
                        .replace("&apos;", "")
                        .contains('&')
                {
                    return Err(format!("unescaped value {value:?}"));
                }
                attrs = attrs[eq + 2 + value_end + 1..].trim_start();
            }
            if stack.is_empty() {
                roots += 1;
            }
            opened.push(name.to_owned());
            if !self_closing {
                stack.push(name.to_owned());
            }
        }
        if !stack.is_empty() {
            return Err(format!("unclosed {stack:?}"));
        }
        if roots != 1 || !rest.trim().is_empty() {
            return Err(format!("{roots} root elements, trailing {rest:?}"));
        }
        Ok(opened)
    }

    #[test]
    fn cornell_and_glosbox_xml_is_well_formed() {
        for name in ["cornell", "glosbox"] {
            let scene = builtin(name).unwrap();
            let mut warnings = Vec::new();
            let xml = scene_xml(&scene, &ExportOptions::default(), &mut warnings).unwrap();
            let tags = check_well_formed(&xml).unwrap_or_else(|e| panic!("{name}: {e}\n{xml}"));
            assert!(warnings.is_empty(), "{warnings:?}");
            assert!(xml.contains("<scene version=\"3.0.0\">"));
            assert_eq!(
                tags.iter().filter(|t| *t == "shape").count(),
                scene.meshes().len()
            );
            assert_eq!(tags.iter().filter(|t| *t == "emitter").count(), 1);
            assert!(xml.contains("<string name=\"fov_axis\" value=\"y\"/>"));
            assert!(xml.contains("<float name=\"fov\" value=\"39.3077\"/>"));
            assert!(xml.contains("<rgb name=\"radiance\" value=\"18.387, 13.9873, 6.75357\"/>"));
        }
        let xml = scene_xml(
            &builtin("glosbox").unwrap(),
            &ExportOptions::default(),
            &mut Vec::new(),
        )
        .unwrap();
        for needle in [
            "<bsdf type=\"blendbsdf\"",
            "<float name=\"weight\" value=\"0.3\"/>",
            "<bsdf type=\"diffuse\" name=\"bsdf_0\">",
            "<bsdf type=\"roughconductor\" name=\"bsdf_1\">",
            "<string name=\"material\" value=\"none\"/>",
            "<rgb name=\"eta\" value=\"0.143, 0.374, 1.442\"/>",
            "<rgb name=\"k\" value=\"3.983, 2.385, 1.603\"/>",
            "<string name=\"distribution\" value=\"beckmann\"/>",
        ] {
            assert!(xml.contains(needle), "glosbox XML lacks {needle}:\n{xml}");
        }
    }

    #[test]
    fn tree_xml_is_well_formed() {
        let scene = builtin("tree").unwrap();
        let mut warnings = Vec::new();
        let xml = scene_xml(&scene, &ExportOptions::default(), &mut warnings).unwrap();
        let tags = check_well_formed(&xml).unwrap_or_else(|e| panic!("tree: {e}\n{xml}"));
        assert!(warnings.is_empty(), "{warnings:?}");
        assert_eq!(
            tags.iter().filter(|t| *t == "shape").count(),
            scene.meshes().len()
        );
        assert_eq!(tags.iter().filter(|t| *t == "emitter").count(), 1);
        assert_eq!(
            tags.iter().filter(|t| *t == "bsdf").count(),
            scene.materials().len()
        );
        assert!(xml.contains("<rgb name=\"radiance\" value=\"40, 38, 34\"/>"));
    }

    #[test]
    fn mirrors_and_bathroom_xml_is_well_formed() {
        for name in ["mirrors", "bathroom"] {
            let scene = builtin(name).unwrap();
            let mut warnings = Vec::new();
            let xml = scene_xml(&scene, &ExportOptions::default(), &mut warnings).unwrap();
            let tags = check_well_formed(&xml).unwrap_or_else(|e| panic!("{name}: {e}\n{xml}"));
            assert!(warnings.is_empty(), "{name}: {warnings:?}");
            let count = |tag: &str| tags.iter().filter(|t| *t == tag).count();
            assert_eq!(count("shape"), scene.meshes().len(), "{name}");
            assert_eq!(count("emitter"), scene.lights().len(), "{name}");
            assert_eq!(count("bsdf"), scene.materials().len(), "{name}");
            // The mirrors are F = 1 conductors scaled by their reflectance.
            assert!(xml.contains("<bsdf type=\"conductor\""), "{name}");
            assert!(xml.contains("<rgb name=\"specular_reflectance\" value=\"0.9, 0.9, 0.9\"/>"));
        }
        let xml = scene_xml(
            &builtin("bathroom").unwrap(),
            &ExportOptions::default(),
            &mut Vec::new(),
        )
        .unwrap();
        for needle in [
            "<bsdf type=\"dielectric\"",
            "<float name=\"int_ior\" value=\"1.5\"/>",
            "<float name=\"ext_ior\" value=\"1\"/>",
        ] {
            assert!(xml.contains(needle), "bathroom XML lacks {needle}");
        }
    }

    #[test]
    fn names_are_escaped() {
        assert_eq!(escape("a<b>&\"c'"), "a&lt;b&gt;&amp;&quot;c&apos;");
        assert_eq!(sanitize("white wall/1"), "white_wall_1");
        let mut scene = builtin("cornell").unwrap();
        scene.name = "odd <name> & \"quotes\" -- here".into();
        let xml = scene_xml(&scene, &ExportOptions::default(), &mut Vec::new()).unwrap();
        check_well_formed(&xml).unwrap();
    }

    #[test]
    fn ply_round_trip() {
        let scene = builtin("glosbox").unwrap();
        for (m, mesh) in scene.meshes().iter().enumerate() {
            let ply = PlyMesh {
                positions: scene.world_positions(m as u32),
                normals: scene.world_normals(m as u32),
                uvs: mesh.uvs.clone(),
                indices: mesh.indices.clone(),
            };
            let bytes = write_ply(&ply, &mesh.name).unwrap();
            let back = read_ply(&bytes, Path::new("test.ply")).unwrap();
            assert_eq!(back, ply, "mesh {}", mesh.name);
        }
        // Truncation and garbage are errors, not panics.
        let ply = PlyMesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            normals: vec![Vec3::Z; 3],
            uvs: vec![Vec2::ZERO; 3],
            indices: vec![[0, 1, 2]],
        };
        let bytes = write_ply(&ply, "tri").unwrap();
        for cut in [5, bytes.len() - 20, bytes.len() - 1] {
            assert!(read_ply(&bytes[..cut], Path::new("cut.ply")).is_err());
        }
        let mut bad_index = bytes.clone();
        let n = bad_index.len();
        bad_index[n - 4..].copy_from_slice(&7i32.to_le_bytes());
        assert!(read_ply(&bad_index, Path::new("bad.ply")).is_err());
        let wrong = PlyMesh {
            indices: vec![[0, 1, 3]],
            ..ply
        };
        assert!(write_ply(&wrong, "wrong").is_err());
    }

    #[test]
    fn export_writes_xml_and_meshes() {
        let dir = std::env::temp_dir().join(format!("lustre-mitsuba-unit-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let scene = builtin("cornell").unwrap();
        let report = export(&scene, &dir.join("cornell.xml"), &ExportOptions::default()).unwrap();
        assert!(report.warnings.is_empty());
        assert_eq!(report.meshes.len(), scene.meshes().len());
        let xml = std::fs::read_to_string(&report.xml).unwrap();
        for (m, path) in report.meshes.iter().enumerate() {
            let rel = path
                .strip_prefix(&dir)
                .unwrap()
                .to_str()
                .unwrap()
                .to_owned();
            assert!(
                xml.contains(&format!("value=\"{rel}\"")),
                "{rel} not named in the XML"
            );
            let back = read_ply(&std::fs::read(path).unwrap(), path).unwrap();
            assert_eq!(back.positions, scene.world_positions(m as u32));
            assert_eq!(back.indices, scene.meshes()[m].indices);
        }
        // No temporary files are left behind.
        let leftovers: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .chain(std::fs::read_dir(dir.join("meshes")).unwrap())
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.contains(".tmp-"))
            .collect();
        assert!(leftovers.is_empty(), "{leftovers:?}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A 2 × 1 texture (red, blue) on cornell's first material with `model`.
    fn textured(model: MaterialModel) -> Scene {
        let scene = builtin("cornell").unwrap();
        let mut materials = scene.materials().to_vec();
        let map = crate::Texture::new(
            "two",
            2,
            1,
            vec![Rgb::new(0.5, 0.0, 0.0), Rgb::new(0.0, 0.0, 0.25)],
        )
        .unwrap();
        materials[0] = Material::new("painted", model).with_diffuse_map(std::sync::Arc::new(map));
        scene.with_materials(materials).unwrap()
    }

    #[test]
    fn diffuse_maps_are_exported_as_baked_bitmaps() {
        let kd = Rgb::new(0.8, 0.6, 0.4);
        let dir = std::env::temp_dir().join(format!("lustre-mitsuba-maps-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        // Diffuse: one bitmap, Kd · texel, raw, bilinear, repeated, v flipped.
        let scene = textured(MaterialModel::Diffuse { reflectance: kd });
        let report = export(&scene, &dir.join("a.xml"), &ExportOptions::default()).unwrap();
        assert!(report.warnings.is_empty(), "{:?}", report.warnings);
        let xml = std::fs::read_to_string(&report.xml).unwrap();
        check_well_formed(&xml).unwrap();
        assert_eq!(xml.matches("type=\"bitmap\"").count(), 1, "{xml}");
        for needle in [
            "<texture type=\"bitmap\" name=\"reflectance\">",
            "<boolean name=\"raw\" value=\"true\"/>",
            "<string name=\"filter_type\" value=\"bilinear\"/>",
            "<string name=\"wrap_mode\" value=\"repeat\"/>",
            "<transform name=\"to_uv\">",
            "<scale x=\"1\" y=\"-1\"/>",
            "<translate x=\"0\" y=\"1\"/>",
        ] {
            assert!(xml.contains(needle), "{needle} missing:\n{xml}");
        }
        assert_eq!(report.textures.len(), 1);
        let rel = report.textures[0]
            .strip_prefix(&dir)
            .unwrap()
            .to_str()
            .unwrap()
            .to_owned();
        assert!(
            rel.starts_with("textures/") && rel.ends_with(".exr"),
            "{rel}"
        );
        assert!(xml.contains(&format!("value=\"{rel}\"")), "{rel} not named");
        let image = exr::prelude::read_first_rgba_layer_from_file(
            &report.textures[0],
            |r, _| (r.width(), vec![[0.0f32; 3]; r.width() * r.height()]),
            |(w, px): &mut (usize, Vec<[f32; 3]>), p, (r, g, b, _a): (f32, f32, f32, f32)| {
                px[p.y() * *w + p.x()] = [r, g, b];
            },
        )
        .unwrap();
        let (w, px) = image.layer_data.channel_data.pixels;
        assert_eq!(w, 2);
        assert_eq!(px, vec![[0.5 * kd.x, 0.0, 0.0], [0.0, 0.0, 0.25 * kd.z]]);
        // Blend of a diffuse and an approximated Phong: each nested diffuse gets its own bake.
        let kd2 = Rgb::new(0.2, 0.4, 0.6);
        let blend = textured(MaterialModel::Blend {
            weight: 0.3,
            first: Box::new(MaterialModel::Diffuse { reflectance: kd }),
            second: Box::new(MaterialModel::Phong {
                diffuse: kd2,
                specular: Rgb::splat(0.2),
                exponent: 10.0,
            }),
        });
        let options = ExportOptions {
            approximate: true,
            ..ExportOptions::default()
        };
        let report = export(&blend, &dir.join("b.xml"), &options).unwrap();
        let xml = std::fs::read_to_string(&report.xml).unwrap();
        check_well_formed(&xml).unwrap();
        assert_eq!(report.textures.len(), 2);
        assert_eq!(xml.matches("type=\"bitmap\"").count(), 2, "{xml}");
        assert_ne!(report.textures[0], report.textures[1]);
        // Untextured scenes write no texture folder.
        let plain = export(
            &builtin("cornell").unwrap(),
            &dir.join("c.xml"),
            &ExportOptions::default(),
        )
        .unwrap();
        assert!(plain.textures.is_empty());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// The cornell scene with material `material` (the white walls) replaced by `model`.
    fn with_model(model: MaterialModel) -> Scene {
        let scene = builtin("cornell").unwrap();
        let mut materials = scene.materials().to_vec();
        materials[0] = Material::new("strange", model);
        scene.with_materials(materials).unwrap()
    }

    #[test]
    fn unsupported_materials_are_reported() {
        let gaussian = MaterialModel::RoughConductor {
            distribution: MicrofacetDistribution::Gaussian,
            alpha: 0.2,
            fresnel: ConductorFresnel::None,
            specular: Rgb::ONE,
        };
        let unsupported = [
            MaterialModel::Phong {
                diffuse: Rgb::splat(0.5),
                specular: Rgb::splat(0.2),
                exponent: 20.0,
            },
            MaterialModel::Ward {
                diffuse: Rgb::splat(0.5),
                specular: Rgb::splat(0.2),
                alpha_x: 0.1,
                alpha_y: 0.2,
            },
            MaterialModel::Named {
                model: "oren-nayar".into(),
                params: Default::default(),
            },
            gaussian.clone(),
            // Nested inside a blend, too.
            MaterialModel::Blend {
                weight: 0.5,
                first: Box::new(MaterialModel::Diffuse {
                    reflectance: Rgb::ONE,
                }),
                second: Box::new(gaussian),
            },
        ];
        for model in unsupported {
            let scene = with_model(model.clone());
            let err = scene_xml(&scene, &ExportOptions::default(), &mut Vec::new()).unwrap_err();
            let message = err.to_string();
            assert!(
                matches!(err, GeometryError::Unsupported { .. }) && message.contains("`strange`"),
                "{}: {message}",
                model.name()
            );
            let mut warnings = Vec::new();
            let options = ExportOptions {
                approximate: true,
                ..Default::default()
            };
            let xml = scene_xml(&scene, &options, &mut warnings).unwrap();
            check_well_formed(&xml).unwrap();
            assert_eq!(warnings.len(), 1, "{warnings:?}");
            assert!(warnings[0].contains("`strange`"), "{warnings:?}");
        }
    }

    #[test]
    fn supported_models_and_lights_map_to_mitsuba_plugins() {
        use crate::light::{OrientedPointLight, PointLight, SpotLight};
        let cases = [
            (
                MaterialModel::Mirror {
                    reflectance: Rgb::splat(0.9),
                },
                "<bsdf type=\"conductor\" id=\"bsdf-0-strange\">\n        <string name=\"material\" value=\"none\"/>\n        <rgb name=\"specular_reflectance\" value=\"0.9, 0.9, 0.9\"/>",
            ),
            (
                MaterialModel::Dielectric {
                    ior: 1.5,
                    transmittance: Rgb::ONE,
                },
                "<bsdf type=\"dielectric\" id=\"bsdf-0-strange\">\n        <float name=\"int_ior\" value=\"1.5\"/>\n        <float name=\"ext_ior\" value=\"1\"/>",
            ),
            (
                MaterialModel::RoughConductor {
                    distribution: MicrofacetDistribution::Ggx,
                    alpha: 0.25,
                    fresnel: ConductorFresnel::None,
                    specular: Rgb::new(0.5, 0.6, 0.7),
                },
                "<string name=\"distribution\" value=\"ggx\"/>\n        <float name=\"alpha\" value=\"0.25\"/>\n        <string name=\"material\" value=\"none\"/>\n        <rgb name=\"specular_reflectance\" value=\"0.5, 0.6, 0.7\"/>",
            ),
        ];
        for (model, needle) in cases {
            let xml = scene_xml(
                &with_model(model),
                &ExportOptions::default(),
                &mut Vec::new(),
            )
            .unwrap();
            check_well_formed(&xml).unwrap();
            assert!(xml.contains(needle), "{needle}\nnot in\n{xml}");
        }

        let base = builtin("cornell").unwrap();
        let point = Light::Point(PointLight {
            position: Vec3::new(0.0, 0.5, 0.0),
            intensity: Rgb::splat(2.0),
        });
        let spot = Light::Spot(SpotLight {
            position: Vec3::new(0.0, 0.9, 0.0),
            direction: Vec3::NEG_Y,
            intensity: Rgb::splat(3.0),
            cutoff_angle: 30f32.to_radians(),
            beam_width: 20f32.to_radians(),
        });
        let oriented = Light::OrientedPoint(OrientedPointLight {
            position: Vec3::new(0.0, 0.9, 0.0),
            normal: Vec3::NEG_Y,
            intensity: Rgb::splat(1.0),
        });
        let scene = |lights: Vec<Light>| {
            Scene::new(
                "lights",
                base.meshes().to_vec(),
                base.materials().to_vec(),
                base.objects().to_vec(),
                lights,
                *base.camera(),
            )
            .unwrap()
        };
        let xml = scene_xml(
            &scene(vec![point, spot]),
            &ExportOptions::default(),
            &mut Vec::new(),
        )
        .unwrap();
        check_well_formed(&xml).unwrap();
        assert!(xml.contains("<emitter type=\"point\" id=\"light-0\">\n        <point name=\"position\" x=\"0\" y=\"0.5\" z=\"0\"/>\n        <rgb name=\"intensity\" value=\"2, 2, 2\"/>"), "{xml}");
        assert!(
            xml.contains("<lookat origin=\"0, 0.9, 0\" target=\"0, -0.100000024, 0\""),
            "{xml}"
        );
        assert!(
            xml.contains("<float name=\"cutoff_angle\" value=\"30"),
            "{xml}"
        );
        assert!(
            xml.contains("<float name=\"beam_width\" value=\"20"),
            "{xml}"
        );

        let err = scene_xml(
            &scene(vec![oriented.clone()]),
            &ExportOptions::default(),
            &mut Vec::new(),
        )
        .unwrap_err();
        assert!(matches!(err, GeometryError::Unsupported { .. }), "{err}");
        assert!(err.to_string().contains("oriented point"), "{err}");
        let mut warnings = Vec::new();
        let options = ExportOptions {
            approximate: true,
            ..Default::default()
        };
        let xml = scene_xml(&scene(vec![oriented]), &options, &mut warnings).unwrap();
        check_well_formed(&xml).unwrap();
        assert_eq!(warnings.len(), 1);
        assert!(xml.contains("<shape type=\"ply\" id=\"light-0\">"), "{xml}");
    }

    /// The numbers of the `value` attribute (or of `x`, `y`, `z`) of the first element after `after` that starts with `prefix`.
    fn numbers_after(xml: &str, after: &str, prefix: &str) -> Vec<f64> {
        let from = xml.find(after).expect("anchor in the XML") + after.len();
        let start = from + xml[from..].find(prefix).expect("element after the anchor");
        let element = &xml[start..start + xml[start..].find("/>").expect("a leaf")];
        let value = |name: &str| {
            let key = format!(" {name}=\"");
            element.find(&key).map(|i| {
                let rest = &element[i + key.len()..];
                rest[..rest.find('"').unwrap()].to_owned()
            })
        };
        let text = value("value").unwrap_or_else(|| {
            ["x", "y", "z"]
                .map(|k| value(k).expect("x, y and z"))
                .join(", ")
        });
        text.split(',').map(|v| v.trim().parse().unwrap()).collect()
    }

    #[test]
    fn the_integrator_is_path_or_the_particle_tracer() {
        let scene = builtin("stained-glass").unwrap();
        for (integrator, plugin) in [
            (Integrator::Path, "path"),
            (Integrator::ParticleTracer, "ptracer"),
        ] {
            let options = ExportOptions {
                integrator,
                max_depth: 7,
                ..ExportOptions::default()
            };
            let xml = scene_xml(&scene, &options, &mut Vec::new()).unwrap();
            check_well_formed(&xml).unwrap();
            assert!(
                xml.contains(&format!("<integrator type=\"{plugin}\">")),
                "{xml}"
            );
            assert!(xml.contains("<integer name=\"max_depth\" value=\"7\"/>"));
            // The point light stays a point: light tracing finds it through the panes.
            assert!(xml.contains("<emitter type=\"point\""), "{xml}");
        }
    }

    #[test]
    fn point_lights_become_spheres_of_equal_power() {
        use crate::light::SpotLight;
        for (name, r) in [("cardioid", 0.01), ("pool", 0.004), ("cardioid", 0.25)] {
            let scene = builtin(name).unwrap();
            let Light::Point(light) = scene.lights()[0] else {
                panic!("{name} has a point light");
            };
            let options = ExportOptions {
                point_light_radius: Some(r),
                ..ExportOptions::default()
            };
            let mut warnings = Vec::new();
            let xml = scene_xml(&scene, &options, &mut warnings).unwrap();
            check_well_formed(&xml).unwrap();
            assert!(warnings.is_empty(), "{warnings:?}");
            assert!(!xml.contains("<emitter type=\"point\""), "{xml}");
            assert!(xml.contains("<boolean name=\"hide_emitters\" value=\"true\"/>"));
            let anchor = "<shape type=\"sphere\" id=\"light-0\">";
            let center = numbers_after(&xml, anchor, "<point name=\"center\"");
            let radius = numbers_after(&xml, anchor, "<float name=\"radius\"")[0];
            let radiance = numbers_after(&xml, anchor, "<rgb name=\"radiance\"");
            assert_eq!(radius as f32, r, "{name}");
            for c in 0..3 {
                assert_eq!(center[c] as f32, light.position[c], "{name}");
                // A Lambertian emitter of area 4π r² and radiance L emits π L · 4π r².
                let sphere = std::f64::consts::PI
                    * radiance[c]
                    * 4.0
                    * std::f64::consts::PI
                    * radius
                    * radius;
                let point = 4.0 * std::f64::consts::PI * f64::from(light.intensity[c]);
                assert!(
                    (sphere / point - 1.0).abs() < 1e-6,
                    "{name}, channel {c}: sphere {sphere} W, point light {point} W"
                );
                assert!((f64::from(Light::Point(light).power()[c]) / point - 1.0).abs() < 1e-6);
            }
        }
        let xml = scene_xml(
            &builtin("pool").unwrap(),
            &ExportOptions::default(),
            &mut Vec::new(),
        )
        .unwrap();
        assert!(!xml.contains("hide_emitters"), "{xml}");
        // Invalid radii are refused; other lights are kept, with a warning.
        for r in [0.0, -0.01, f32::NAN, f32::INFINITY] {
            let options = ExportOptions {
                point_light_radius: Some(r),
                ..ExportOptions::default()
            };
            let err = scene_xml(&builtin("pool").unwrap(), &options, &mut Vec::new()).unwrap_err();
            assert!(err.to_string().contains("radius"), "{err}");
        }
        let base = builtin("cornell").unwrap();
        let spot = Light::Spot(SpotLight {
            position: Vec3::new(0.0, 0.9, 0.0),
            direction: Vec3::NEG_Y,
            intensity: Rgb::splat(3.0),
            cutoff_angle: 30f32.to_radians(),
            beam_width: 20f32.to_radians(),
        });
        let scene = Scene::new(
            "spot",
            base.meshes().to_vec(),
            base.materials().to_vec(),
            base.objects().to_vec(),
            vec![spot],
            *base.camera(),
        )
        .unwrap();
        let options = ExportOptions {
            point_light_radius: Some(0.01),
            ..ExportOptions::default()
        };
        let mut warnings = Vec::new();
        let xml = scene_xml(&scene, &options, &mut warnings).unwrap();
        assert!(
            xml.contains("<emitter type=\"spot\" id=\"light-0\">"),
            "{xml}"
        );
        assert_eq!(warnings.len(), 1, "{warnings:?}");
        // Beside an emissive mesh the sphere stays visible, with a warning.
        let point = Light::Point(crate::light::PointLight {
            position: Vec3::new(0.0, 0.5, 0.0),
            intensity: Rgb::splat(2.0),
        });
        let mut lights = base.lights().to_vec();
        lights.push(point);
        let scene = Scene::new(
            "both",
            base.meshes().to_vec(),
            base.materials().to_vec(),
            base.objects().to_vec(),
            lights,
            *base.camera(),
        )
        .unwrap();
        let mut warnings = Vec::new();
        let xml = scene_xml(&scene, &options, &mut warnings).unwrap();
        assert!(xml.contains("<shape type=\"sphere\""), "{xml}");
        assert!(!xml.contains("hide_emitters"), "{xml}");
        assert_eq!(warnings.len(), 1, "{warnings:?}");
        assert!(warnings[0].contains("visible"), "{warnings:?}");
    }
}
