//! Glossy images (Diefenbach & Badler 1997, section 3, "glossy marble") on
//! the GPU: with no shear and one sample a glossy face's image is the mirror
//! image of the same face (the specular path, to float precision); with `N`
//! sheared samples the image of a small emitter in a glossy floor, seen
//! straight down, is blurred as wide as the Gaussian slope lobe the shear
//! samples were mapped to (CPU: the lobe integrated over the emitter per
//! pixel, in closed form with erf). Frosted glass: the sheared slab view
//! with no shear is the clear slab's image, and the blur of an emitter seen
//! through it is the paraxial `(η − 1) m` lobe's. Paired lights
//! (`lustre_mpr::light_group`): with vanishing shears the sheared views
//! that each draw one group of the lights, weighted, sum to the image of
//! every light, under shadow volumes and under shadow maps.

mod support;

use glam::{Vec2, Vec3};
use lustre_geometry::light::PointLight;
use lustre_geometry::material::{ConductorFresnel, MaterialModel, MicrofacetDistribution};
use lustre_geometry::{Bvh, Camera, Light, Material, Mesh, Object, Plane, Ray, Rgb, Scene};
use lustre_mpr::frame::{AccumulatedSplats, FrameInputs};
use lustre_mpr::light_group::GlossyLights;
use lustre_mpr::passes::glossy_image::{
    Fog, GlossySettings, ShearModel, fog_factor, microfacet_shears, shear_slopes,
};
use lustre_mpr::passes::specular::SpecularSettings;
use lustre_mpr::passes::tonemap::Tonemap;
use lustre_mpr::readback::read_rgba_f32;
use lustre_mpr::view::face_frame;
use lustre_mpr::{FrameGraph, GpuContext, RenderTargets, SceneBuffers};
use support::gpu_or_skip;

const SIZE: u32 = 96;
const OUTPUT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

fn quad(name: &str, corners: [Vec3; 4], material: u32) -> Mesh {
    Mesh::flat(name, &corners, &[[0, 1, 2], [0, 2, 3]], material)
}

/// The 4 m × 4 m floor at `y = 0`, facing up, of material 0.
fn floor_quad() -> Mesh {
    quad(
        "floor",
        [
            Vec3::new(-2.0, 0.0, 2.0),
            Vec3::new(2.0, 0.0, 2.0),
            Vec3::new(2.0, 0.0, -2.0),
            Vec3::new(-2.0, 0.0, -2.0),
        ],
        0,
    )
}

fn rough_mirror(alpha: f32, reflectance: f32) -> MaterialModel {
    MaterialModel::RoughConductor {
        distribution: MicrofacetDistribution::Beckmann,
        alpha,
        fresnel: ConductorFresnel::None,
        specular: Rgb::splat(reflectance),
    }
}

/// A 4 × 4 m floor at y = 0 facing up of `floor`, an emissive square of
/// half-size `half` at height `height` facing down, and (with `walls`) two
/// emissive walls of other colours; the camera `camera`.
fn floor_scene(floor: MaterialModel, half: f32, height: f32, walls: bool, camera: Camera) -> Scene {
    floor_scene_with_back(floor, None, half, height, walls, camera)
}

/// [`floor_scene`] whose back wall (with `walls`) reflects as `back` instead of emitting.
fn floor_scene_with_back(
    floor: MaterialModel,
    back: Option<MaterialModel>,
    half: f32,
    height: f32,
    walls: bool,
    camera: Camera,
) -> Scene {
    let mut materials = vec![
        Material::new("floor", floor),
        Material::diffuse("glow", Rgb::ZERO).with_emission(Rgb::new(1.0, 0.5, 0.25)),
        Material::diffuse("blue", Rgb::ZERO).with_emission(Rgb::new(0.1, 0.2, 0.7)),
        Material::diffuse("green", Rgb::ZERO).with_emission(Rgb::new(0.2, 0.6, 0.1)),
    ];
    materials.truncate(if walls { 4 } else { 2 });
    if let (true, Some(back)) = (walls, back) {
        materials[2] = Material::new("back", back);
    }
    let mut meshes = vec![
        floor_quad(),
        quad(
            "emitter",
            [
                Vec3::new(-half, height, -half),
                Vec3::new(half, height, -half),
                Vec3::new(half, height, half),
                Vec3::new(-half, height, half),
            ],
            1,
        ),
    ];
    if walls {
        meshes.push(quad(
            "back",
            [
                Vec3::new(-2.0, 0.0, -2.0),
                Vec3::new(2.0, 0.0, -2.0),
                Vec3::new(2.0, 2.0, -2.0),
                Vec3::new(-2.0, 2.0, -2.0),
            ],
            2,
        ));
        meshes.push(quad(
            "left",
            [
                Vec3::new(-2.0, 0.0, 2.0),
                Vec3::new(-2.0, 0.0, -2.0),
                Vec3::new(-2.0, 2.0, -2.0),
                Vec3::new(-2.0, 2.0, 2.0),
            ],
            3,
        ));
    }
    let objects = Object::one_per_mesh(&meshes);
    Scene::new(
        "glossy-floor",
        meshes,
        materials,
        objects,
        Vec::new(),
        camera,
    )
    .unwrap()
}

/// The HDR image of `scene` drawn with the emission pass and specular images (depth 1), glossy ones under `glossy`.
fn render(ctx: &GpuContext, scene: &Scene, glossy: &GlossySettings) -> Vec<Vec3> {
    render_to_depth(ctx, scene, glossy, 1)
}

/// [`render`] with specular images to recursion depth `depth`.
fn render_to_depth(
    ctx: &GpuContext,
    scene: &Scene,
    glossy: &GlossySettings,
    depth: u32,
) -> Vec<Vec3> {
    render_accumulated(ctx, scene, glossy, depth, 1)
}

/// [`render_to_depth`] through `FrameGraph::render_accumulated` with `aa` jittered frames.
fn render_accumulated(
    ctx: &GpuContext,
    scene: &Scene,
    glossy: &GlossySettings,
    depth: u32,
    aa: u32,
) -> Vec<Vec3> {
    let targets = RenderTargets::new(ctx, SIZE, SIZE).unwrap();
    let buffers = SceneBuffers::upload(ctx, scene).unwrap();
    let output = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("output"),
        size: wgpu::Extent3d {
            width: SIZE,
            height: SIZE,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: OUTPUT_FORMAT,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
        view_formats: &[],
    });
    let graph = FrameGraph::new(ctx, OUTPUT_FORMAT)
        .unwrap()
        .with_emission(ctx, targets.hdr_format(), scene)
        .unwrap()
        .with_glossy_images(
            ctx,
            targets.hdr_format(),
            scene,
            SpecularSettings {
                max_depth: depth,
                limit_radiance: Vec3::ZERO,
                clip: None,
            },
            glossy,
        )
        .unwrap()
        .with_accumulation(ctx, targets.hdr_format())
        .unwrap();
    let camera = scene.camera().with_aspect(1.0);
    graph
        .render_accumulated(
            ctx,
            &FrameInputs {
                graph_terms: lustre_mpr::GraphTerms::ALL,
                scene: &buffers,
                camera: &camera,
                tonemap: &Tonemap::default(),
                targets: &targets,
                output: &output.create_view(&Default::default()),
                splats: None,
                direct: None,
                diffuse: None,
            },
            aa,
            AccumulatedSplats::Once,
            &mut |_| Ok(()),
        )
        .unwrap();
    read_rgba_f32(ctx, &targets.hdr.texture)
        .unwrap()
        .iter()
        .map(|p| Vec3::new(p[0], p[1], p[2]))
        .collect()
}

#[test]
fn zero_shear_and_one_sample_is_the_mirror_image() {
    let Some(ctx) = gpu_or_skip("zero_shear_and_one_sample_is_the_mirror_image") else {
        return;
    };
    let camera = Camera::look_at(
        Vec3::new(0.4, 1.2, 1.8),
        Vec3::new(-0.3, 0.0, -0.6),
        Vec3::Y,
        60.0,
    );
    let mirror = floor_scene(
        MaterialModel::Mirror {
            reflectance: Rgb::splat(0.6),
        },
        0.3,
        1.0,
        true,
        camera,
    );
    let glossy = floor_scene(rough_mirror(0.2, 0.6), 0.3, 1.0, true, camera);
    let settings = GlossySettings {
        samples: 1,
        depth: 1,
        fog: Fog::Off,
        fog_radiance: Vec3::ZERO,
        hide_emitters: false,
        shear: ShearModel::Isotropic,
        frosted_alpha: 0.0,
        lights: GlossyLights::All,
    };
    let expected = render(&ctx, &mirror, &GlossySettings::default());
    let image = render(&ctx, &glossy, &settings);
    let reflected = expected
        .iter()
        .zip(&image)
        .filter(|(e, _)| e.max_element() > 0.0 && e.max_element() < 0.9 * 0.7)
        .count();
    assert!(
        reflected > 500,
        "the floor must reflect the walls: {reflected} pixels"
    );
    for (i, (e, g)) in expected.iter().zip(&image).enumerate() {
        // One product R · L in f32 (or f16) either way: equal to rounding.
        assert!(
            (*e - *g).abs().max_element() <= 1e-3 * e.max_element().max(1e-3),
            "pixel {i}: mirror {e}, glossy {g}"
        );
    }
}

#[test]
fn nested_glossy_images_of_two_samples_each_are_the_nested_mirror_images() {
    let Some(ctx) = gpu_or_skip("nested_glossy_images_are_the_nested_mirror_images") else {
        return;
    };
    // The floor reflects the back wall, which reflects the floor: two levels,
    // the floor's image averaging two (vanishingly sheared) samples, each
    // with the wall's one-sample image inside, whose accumulation must not
    // overwrite the outer one's.
    let camera = Camera::look_at(
        Vec3::new(0.4, 1.2, 1.8),
        Vec3::new(-0.3, 0.0, -0.6),
        Vec3::Y,
        60.0,
    );
    let mirror = |r: f32| MaterialModel::Mirror {
        reflectance: Rgb::splat(r),
    };
    let expected_scene =
        floor_scene_with_back(mirror(0.6), Some(mirror(0.7)), 0.3, 1.0, true, camera);
    let glossy_scene = floor_scene_with_back(
        rough_mirror(1e-6, 0.6),
        Some(rough_mirror(1e-6, 0.7)),
        0.3,
        1.0,
        true,
        camera,
    );
    let settings = GlossySettings {
        samples: 2,
        depth: 2,
        fog: Fog::Off,
        fog_radiance: Vec3::ZERO,
        hide_emitters: false,
        shear: ShearModel::Isotropic,
        frosted_alpha: 0.0,
        lights: GlossyLights::All,
    };
    let expected = render_to_depth(&ctx, &expected_scene, &GlossySettings::default(), 2);
    let image = render_to_depth(&ctx, &glossy_scene, &settings, 2);
    // Pixels showing the wall inside the floor: R_floor R_wall Le of the emitter or green wall.
    let twice = expected
        .iter()
        .filter(|e| e.max_element() > 0.0 && e.max_element() < 0.6 * 0.7 * 0.61)
        .count();
    assert!(
        twice > 50,
        "the test must show images in images: {twice} pixels"
    );
    let wrong = expected
        .iter()
        .zip(&image)
        .filter(|(e, g)| (**e - **g).abs().max_element() > 1e-3 * e.max_element().max(1e-3))
        .count();
    // Shears of 1e-6 move no pixel centre across an edge but a handful.
    assert!(wrong <= 10, "{wrong} pixels differ");
}

#[test]
fn accumulated_frames_share_the_shears_out() {
    let Some(ctx) = gpu_or_skip("accumulated_frames_share_the_shears_out") else {
        return;
    };
    // 16 shears over 4 jittered frames (4 each, interleaved) against the 16
    // in one frame: the same blur, the frames' sub-pixel jitter aside.
    let camera = Camera::look_at(Vec3::new(0.0, 0.5, 0.0), Vec3::ZERO, Vec3::Z, 30.0);
    let scene = floor_scene(rough_mirror(ALPHA, 0.8), HALF, HEIGHT, false, camera);
    let settings = GlossySettings {
        samples: 16,
        depth: 1,
        fog: Fog::Off,
        fog_radiance: Vec3::ZERO,
        hide_emitters: false,
        shear: ShearModel::Isotropic,
        frosted_alpha: 0.0,
        lights: GlossyLights::All,
    };
    let to_f64 = |image: Vec<Vec3>| image.iter().map(|v| f64::from(v.x)).collect::<Vec<_>>();
    let one = to_f64(render_to_depth(&ctx, &scene, &settings, 1));
    let four = to_f64(render_accumulated(&ctx, &scene, &settings, 1, 4));
    for axis in 0..2 {
        let (m1, mean1, var1) = moments(&one, axis);
        let (m4, mean4, var4) = moments(&four, axis);
        eprintln!(
            "axis {axis}: mass {m1:.3} / {m4:.3}, mean {mean1:.2} / {mean4:.2}, width {:.3} / {:.3}",
            var1.sqrt(),
            var4.sqrt()
        );
        // Each of the 16 footprints (~12 px wide) is point sampled through
        // another sub-pixel offset: ±1 px per footprint edge, averaged: 2 %.
        assert!((m4 / m1 - 1.0).abs() < 0.02, "axis {axis}");
        assert!(
            (var4.sqrt() / var1.sqrt() - 1.0).abs() < 0.02,
            "axis {axis}"
        );
        assert!((mean4 - mean1).abs() < 0.5, "axis {axis}");
    }
}

#[test]
fn microfacet_shears_draw_their_weighted_images() {
    let Some(ctx) = gpu_or_skip("microfacet_shears_draw_their_weighted_images") else {
        return;
    };
    // The emitter's blur seen at about 45° incidence at the centroid: the microfacet shears
    // (stretched in the plane of incidence, weighted) against the CPU sum of
    // the same shears' footprints times their weights.
    // Aimed a little in front of the mirror point of the emitter's centre (z = 1/6), where the weighted blur lies.
    let camera = Camera::look_at(
        Vec3::new(0.0, 0.5, 0.5),
        Vec3::new(0.0, 0.0, 0.3),
        Vec3::Y,
        40.0,
    );
    let reflectance = 0.8;
    let scene = floor_scene(
        rough_mirror(ALPHA, reflectance),
        HALF,
        HEIGHT,
        false,
        camera,
    );
    let settings = GlossySettings {
        samples: SAMPLES,
        depth: 1,
        fog: Fog::Off,
        fog_radiance: Vec3::ZERO,
        hide_emitters: false,
        shear: ShearModel::Microfacet,
        frosted_alpha: 0.0,
        lights: GlossyLights::All,
    };
    let gpu: Vec<f64> = render(&ctx, &scene, &settings)
        .iter()
        .map(|v| f64::from(v.x))
        .collect();
    // The shears of the face's centroid (the floor's centre, as the pass takes it).
    let plane = Plane::from_point_normal(Vec3::ZERO, Vec3::Y);
    let (t, b) = face_frame(&plane);
    let shears: Vec<(Vec2, f32)> =
        microfacet_shears(ALPHA, SAMPLES, camera.position, &plane, Vec3::ZERO)
            .into_iter()
            .map(|(d, w)| {
                let v = t * d.x + b * d.y;
                (Vec2::new(v.x, v.z), w)
            })
            .collect();
    let weights: f32 = shears.iter().map(|(_, w)| w).sum();
    assert!(
        weights > 0.5 * SAMPLES as f32,
        "the lobe must reflect: {weights}"
    );
    let le = f64::from(reflectance);
    let discrete = cpu_image(&scene, |p| {
        let sum: f32 = shears
            .iter()
            .filter(|(d, _)| {
                let q = p + HEIGHT * *d;
                q.x.abs() < HALF && q.y.abs() < HALF
            })
            .map(|(_, w)| w)
            .sum();
        le * f64::from(sum) / f64::from(SAMPLES)
    });
    for axis in 0..2 {
        let (m_gpu, mean_gpu, var_gpu) = moments(&gpu, axis);
        let (m_disc, mean_disc, var_disc) = moments(&discrete, axis);
        eprintln!(
            "axis {axis}: mass {m_gpu:.3} / {m_disc:.3}, mean {mean_gpu:.2} / {mean_disc:.2}, \
             width {:.3} / {:.3}",
            var_gpu.sqrt(),
            var_disc.sqrt()
        );
        assert!(m_disc > 1.0, "the emitter must be seen");
        // As in the blur test: the same point samples, so 1 %.
        assert!((m_gpu / m_disc - 1.0).abs() < 0.01, "axis {axis}");
        assert!(
            (var_gpu.sqrt() / var_disc.sqrt() - 1.0).abs() < 0.01,
            "axis {axis}"
        );
        assert!((mean_gpu - mean_disc).abs() < 0.5, "axis {axis}");
    }
}

#[test]
fn fog_fades_the_image_towards_the_fog_radiance_with_distance_from_the_face() {
    let Some(ctx) = gpu_or_skip("fog_fades_the_image_towards_the_fog_radiance") else {
        return;
    };
    let camera = Camera::look_at(
        Vec3::new(0.4, 1.2, 1.8),
        Vec3::new(-0.3, 0.0, -0.6),
        Vec3::Y,
        60.0,
    );
    let (reflectance, f_max, fog) = (0.6, 1.5, Vec3::new(0.3, 0.2, 0.1));
    let mirror = floor_scene(
        MaterialModel::Mirror {
            reflectance: Rgb::splat(reflectance),
        },
        0.3,
        1.0,
        true,
        camera,
    );
    let glossy = floor_scene(rough_mirror(0.2, reflectance), 0.3, 1.0, true, camera);
    let settings = GlossySettings {
        samples: 1,
        depth: 1,
        fog: Fog::Distance(f_max),
        fog_radiance: fog,
        hide_emitters: false,
        shear: ShearModel::Isotropic,
        frosted_alpha: 0.0,
        lights: GlossyLights::All,
    };
    let unfogged = render(&ctx, &mirror, &GlossySettings::default());
    let image = render(&ctx, &glossy, &settings);
    // CPU: per pixel centre, the floor hit and the height z of what its mirror ray meets.
    let bvh = Bvh::build(&mirror);
    let cam = camera.with_aspect(1.0);
    let (mut checked, mut wrong, mut fogged) = (0, 0, 0);
    for (i, (u, g)) in unfogged.iter().zip(&image).enumerate() {
        let (x, y) = (i as u32 % SIZE, i as u32 / SIZE);
        let ray = cam.primary_ray(Camera::pixel_ndc(x, y, SIZE, SIZE, Vec2::splat(0.5)));
        let expected = match bvh.closest_hit(&ray) {
            Some(hit) if hit.material == 0 => {
                let d = Vec3::new(ray.direction.x, -ray.direction.y, ray.direction.z);
                match bvh.closest_hit(&Ray::new(hit.position + 1e-4 * Vec3::Y, d)) {
                    // f L + (1 - f) L_fog, times R; the background is not fogged.
                    Some(seen) => {
                        let f = fog_factor(seen.position.y, f_max);
                        if f < 0.99 {
                            fogged += 1;
                        }
                        f * *u + (1.0 - f) * reflectance * fog
                    }
                    None => Vec3::ZERO,
                }
            }
            _ => *u,
        };
        checked += 1;
        if (*g - expected).abs().max_element() > 1e-3 * expected.max_element().max(1e-2) {
            wrong += 1;
        }
    }
    eprintln!("{fogged} fogged pixels, {wrong} of {checked} differ");
    assert!(fogged > 500, "the test must fog: {fogged} pixels");
    // Pixels whose centre ray and rasterised coverage disagree lie on edges: 1 %.
    assert!(wrong * 100 <= checked, "{wrong} of {checked} pixels differ");
}

/// erf by Abramowitz & Stegun 7.1.26 (absolute error below 1.5e-7).
fn erf(x: f64) -> f64 {
    let t = 1.0 / (1.0 + 0.327_591_1 * x.abs());
    let poly = t
        * (0.254_829_592
            + t * (-0.284_496_736
                + t * (1.421_413_741 + t * (-1.453_152_027 + t * 1.061_405_429))));
    let y = 1.0 - poly * (-x * x).exp();
    if x < 0.0 { -y } else { y }
}

/// Probability that `c + g` lies in `[-half, half]` for `g` normal with deviation `sigma`.
fn box_probability(c: f64, half: f64, sigma: f64) -> f64 {
    let s = sigma * std::f64::consts::SQRT_2;
    0.5 * (erf((half - c) / s) - erf((-half - c) / s))
}

/// Per pixel, on the CPU: where the camera's ray meets the floor, the mirror
/// slope there, and `model(slope at the emitter plane)`, the reflected
/// radiance for that mean slope (0 where the ray misses the floor).
fn cpu_image(scene: &Scene, model: impl Fn(Vec2) -> f64) -> Vec<f64> {
    let camera = scene.camera().with_aspect(1.0);
    let bvh = Bvh::build(scene);
    (0..SIZE)
        .flat_map(|y| (0..SIZE).map(move |x| (x, y)))
        .map(|(x, y)| {
            let ray: Ray =
                camera.primary_ray(Camera::pixel_ndc(x, y, SIZE, SIZE, Vec2::splat(0.5)));
            let Some(hit) = bvh.closest_hit(&ray) else {
                return 0.0;
            };
            if hit.material != 0 {
                return 0.0;
            }
            // Reflected direction: slope (x, z) over y; the unsheared ray reaches the
            // emitter plane at hit + height · slope.
            let r = Vec3::new(ray.direction.x, -ray.direction.y, ray.direction.z);
            let slope = Vec2::new(r.x / r.y, r.z / r.y);
            model(Vec2::new(hit.position.x, hit.position.z) + HEIGHT * slope)
        })
        .collect()
}

const HEIGHT: f32 = 1.0;
const HALF: f32 = 0.05;
const ALPHA: f32 = 0.05;
const SAMPLES: u32 = 64;

/// Radiance-weighted mean and variance of the pixel coordinates along `axis` (0: x, 1: y).
fn moments(image: &[f64], axis: usize) -> (f64, f64, f64) {
    let coord = |i: usize| {
        let (x, y) = (i as u32 % SIZE, i as u32 / SIZE);
        f64::from(if axis == 0 { x } else { y })
    };
    let mass: f64 = image.iter().sum();
    let mean = image
        .iter()
        .enumerate()
        .map(|(i, v)| v * coord(i))
        .sum::<f64>()
        / mass;
    let var = image
        .iter()
        .enumerate()
        .map(|(i, v)| v * (coord(i) - mean).powi(2))
        .sum::<f64>()
        / mass;
    (mass, mean, var)
}

#[test]
fn the_blur_of_a_small_emitter_is_as_wide_as_the_mapped_lobe() {
    let Some(ctx) = gpu_or_skip("the_blur_of_a_small_emitter_is_as_wide_as_the_mapped_lobe") else {
        return;
    };
    // Straight down from below the emitter: the floor maps to pixels nearly affinely.
    let camera = Camera::look_at(Vec3::new(0.0, 0.5, 0.0), Vec3::ZERO, Vec3::Z, 30.0);
    let reflectance = 0.8;
    let scene = floor_scene(
        rough_mirror(ALPHA, reflectance),
        HALF,
        HEIGHT,
        false,
        camera,
    );
    let settings = GlossySettings {
        samples: SAMPLES,
        depth: 1,
        fog: Fog::Off,
        fog_radiance: Vec3::ZERO,
        hide_emitters: false,
        shear: ShearModel::Isotropic,
        frosted_alpha: 0.0,
        lights: GlossyLights::All,
    };
    let gpu: Vec<f64> = render(&ctx, &scene, &settings)
        .iter()
        .map(|v| f64::from(v.x))
        .collect();
    let le = 1.0 * f64::from(reflectance);
    let (half, height) = (f64::from(HALF), f64::from(HEIGHT));
    // The lobe the shear was mapped to: slope shifts Δ = 2m, normal with
    // variance 2α² per axis; at the emitter plane a shift of height · Δ.
    let sigma = height * std::f64::consts::SQRT_2 * f64::from(ALPHA);
    let lobe = cpu_image(&scene, |p| {
        le * box_probability(f64::from(p.x), half, sigma)
            * box_probability(f64::from(p.y), half, sigma)
    });
    // The same with the N discrete shears the GPU drew: what the GPU must match pixel for pixel.
    // The shears lie in the face's frame (t, b); as world (x, z) slope shifts:
    let (t, b) = face_frame(&Plane::from_point_normal(Vec3::ZERO, Vec3::Y));
    let shears: Vec<Vec2> = shear_slopes(ALPHA, SAMPLES)
        .iter()
        .map(|d| {
            let w = t * d.x + b * d.y;
            Vec2::new(w.x, w.z)
        })
        .collect();
    let discrete = cpu_image(&scene, |p| {
        let inside = shears
            .iter()
            .filter(|d| {
                let q = p + HEIGHT * **d;
                q.x.abs() < HALF && q.y.abs() < HALF
            })
            .count();
        le * inside as f64 / f64::from(SAMPLES)
    });
    let second: Vec2 = shears.iter().map(|d| *d * *d).sum::<Vec2>() / SAMPLES as f32;
    eprintln!(
        "shear second moments {second} against the lobe's {}",
        2.0 * ALPHA * ALPHA
    );
    let lobe_moment = 2.0 * ALPHA * ALPHA;
    assert!(((second / lobe_moment) - Vec2::ONE).abs().max_element() < 0.05);
    for axis in 0..2 {
        let (m_gpu, mean_gpu, var_gpu) = moments(&gpu, axis);
        let (m_lobe, mean_lobe, var_lobe) = moments(&lobe, axis);
        let (m_disc, _, var_disc) = moments(&discrete, axis);
        let (w_gpu, w_lobe, w_disc) = (var_gpu.sqrt(), var_lobe.sqrt(), var_disc.sqrt());
        eprintln!(
            "axis {axis}: mass GPU {m_gpu:.3} discrete {m_disc:.3} lobe {m_lobe:.3}; \
             width (px) GPU {w_gpu:.3} discrete {w_disc:.3} lobe {w_lobe:.3}; mean {mean_gpu:.2} / {mean_lobe:.2}"
        );
        // The GPU against its discrete model: the same point samples of the
        // same footprints, so equal up to pixels whose centre lies on a
        // footprint's edge (a few per sample among ~100 lit pixels each): 1 %.
        assert!(
            (w_gpu / w_disc - 1.0).abs() < 0.01,
            "axis {axis}: {w_gpu} vs {w_disc}"
        );
        assert!(
            (m_gpu / m_disc - 1.0).abs() < 0.01,
            "axis {axis}: {m_gpu} vs {m_disc}"
        );
        // Against the lobe: the image's variance is the footprint's (exact)
        // plus height² times the shears' second moment, which the 64 fixed
        // stratified shears hold to 5 % of 2α² per axis (asserted above); the
        // width, a square root, so to 2.5 %, plus a little for the pixel
        // grid (the mass agrees to 0.1 %): 3 % on the width.
        assert!(
            (w_gpu / w_lobe - 1.0).abs() < 0.03,
            "axis {axis}: {w_gpu} vs {w_lobe}"
        );
        assert!((mean_gpu - mean_lobe).abs() < 0.5, "axis {axis}");
        assert!(
            (m_gpu / m_lobe - 1.0).abs() < 0.03,
            "axis {axis}: {m_gpu} vs {m_lobe}"
        );
    }
}

/// A 2 × 2 × `t` glass slab (η = 1.5) whose near face is z = 0, facing +z,
/// and an emissive square of half-size `HALF` facing it at z = -`depth`;
/// the camera on the axis at z = 0.6.
fn slab_scene(thickness: f32, depth: f32) -> Scene {
    let glass = Material::new(
        "glass",
        MaterialModel::Dielectric {
            ior: 1.5,
            transmittance: Rgb::ONE,
        },
    );
    let glow = Material::diffuse("glow", Rgb::ZERO).with_emission(Rgb::new(1.0, 0.5, 0.25));
    let p = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    let (a, b) = (0.0, -thickness);
    let corners = [
        p(-1., -1., b),
        p(1., -1., b),
        p(1., 1., b),
        p(-1., 1., b),
        p(-1., -1., a),
        p(1., -1., a),
        p(1., 1., a),
        p(-1., 1., a),
    ];
    // Outward faces: +z (near), -z (far), +x, -x, +y, -y.
    let faces = [
        [4, 5, 6, 7],
        [1, 0, 3, 2],
        [5, 1, 2, 6],
        [0, 4, 7, 3],
        [7, 6, 2, 3],
        [0, 1, 5, 4],
    ];
    let indices: Vec<[u32; 3]> = faces
        .iter()
        .flat_map(|f| [[f[0], f[1], f[2]], [f[0], f[2], f[3]]])
        .collect();
    let slab = Mesh::flat("slab", &corners, &indices, 0);
    let emitter = quad(
        "emitter",
        [
            Vec3::new(-HALF, -HALF, -depth),
            Vec3::new(HALF, -HALF, -depth),
            Vec3::new(HALF, HALF, -depth),
            Vec3::new(-HALF, HALF, -depth),
        ],
        1,
    );
    let meshes = vec![slab, emitter];
    let objects = Object::one_per_mesh(&meshes);
    let camera = Camera::look_at(
        Vec3::new(0.0, 0.0, 0.6),
        Vec3::new(0.0, 0.0, -1.0),
        Vec3::Y,
        30.0,
    );
    Scene::new(
        "frosted",
        meshes,
        vec![glass, glow],
        objects,
        Vec::new(),
        camera,
    )
    .unwrap()
}

#[test]
fn frosted_glass_without_shear_is_the_clear_slab_and_blurs_as_its_lobe() {
    let Some(ctx) = gpu_or_skip("frosted_glass_blurs_as_its_lobe") else {
        return;
    };
    let (thickness, depth, frost) = (0.05, 1.0, 0.2);
    let scene = slab_scene(thickness, depth);
    let clear = render(&ctx, &scene, &GlossySettings::default());
    let one = GlossySettings {
        samples: 1,
        depth: 1,
        fog: Fog::Off,
        fog_radiance: Vec3::ZERO,
        hide_emitters: true,
        shear: ShearModel::Isotropic,
        frosted_alpha: frost,
        lights: GlossyLights::All,
    };
    let unsheared = render(&ctx, &scene, &one);
    let lit = clear.iter().filter(|v| v.x > 0.0).count();
    assert!(
        lit > 50,
        "the emitter must be seen through the slab: {lit} pixels"
    );
    for (i, (c, u)) in clear.iter().zip(&unsheared).enumerate() {
        assert!(
            (*c - *u).abs().max_element() <= 1e-3 * c.max_element().max(1e-3),
            "pixel {i}: clear {c}, one unsheared sample {u}"
        );
    }
    // N sheared slab views against the CPU: the pixel's ray meets the near
    // face at x; with the world moved by shift = t (1 - 1/η) towards the eye
    // and the shear Δ, it meets the emitter plane at x_t + s d_t - depth Δ
    // (s the parameter where the moved ray reaches depth).
    let frosted = GlossySettings {
        samples: SAMPLES,
        ..one
    };
    let gpu: Vec<f64> = render(&ctx, &scene, &frosted)
        .iter()
        .map(|v| f64::from(v.x))
        .collect();
    let eta = 1.5f32;
    let shift = thickness * (1.0 - 1.0 / eta);
    let alpha = frost * (eta - 1.0) / 2.0;
    let (t, b) = face_frame(&Plane::from_point_normal(Vec3::ZERO, Vec3::Z));
    let shears: Vec<Vec2> = shear_slopes(alpha, SAMPLES)
        .iter()
        .map(|d| {
            let w = t * d.x + b * d.y;
            Vec2::new(w.x, w.y)
        })
        .collect();
    let pass = (1.0 - ((eta - 1.0) / (eta + 1.0)).powi(2)).powi(2);
    let le = f64::from(pass);
    let camera = scene.camera().with_aspect(1.0);
    let image = |model: &dyn Fn(Vec2) -> f64| -> Vec<f64> {
        (0..SIZE)
            .flat_map(|y| (0..SIZE).map(move |x| (x, y)))
            .map(|(x, y)| {
                let ray = camera.primary_ray(Camera::pixel_ndc(x, y, SIZE, SIZE, Vec2::splat(0.5)));
                let d = ray.direction;
                let at_face = ray.origin + d * (-ray.origin.z / d.z);
                let s = (depth - shift) / -d.z;
                model(Vec2::new(at_face.x + s * d.x, at_face.y + s * d.y))
            })
            .collect()
    };
    let discrete = image(&|p| {
        let inside = shears
            .iter()
            .filter(|d| {
                let q = p - depth * **d;
                q.x.abs() < HALF && q.y.abs() < HALF
            })
            .count();
        le * inside as f64 / f64::from(SAMPLES)
    });
    let sigma = f64::from(depth) * std::f64::consts::SQRT_2 * f64::from(alpha);
    let lobe = image(&|p| {
        le * box_probability(f64::from(p.x), f64::from(HALF), sigma)
            * box_probability(f64::from(p.y), f64::from(HALF), sigma)
    });
    for axis in 0..2 {
        let (m_gpu, mean_gpu, var_gpu) = moments(&gpu, axis);
        let (m_disc, _, var_disc) = moments(&discrete, axis);
        let (m_lobe, mean_lobe, var_lobe) = moments(&lobe, axis);
        let (w_gpu, w_disc, w_lobe) = (var_gpu.sqrt(), var_disc.sqrt(), var_lobe.sqrt());
        eprintln!(
            "frosted axis {axis}: mass {m_gpu:.3} / {m_disc:.3} / {m_lobe:.3}, \
             width {w_gpu:.3} / {w_disc:.3} / {w_lobe:.3}, mean {mean_gpu:.2} / {mean_lobe:.2}"
        );
        // As for the glossy floor: the GPU against the same shears 1 %, the
        // width against the lobe 3 % (the same 64 shears, scaled).
        assert!((m_gpu / m_disc - 1.0).abs() < 0.01, "axis {axis}");
        assert!((w_gpu / w_disc - 1.0).abs() < 0.01, "axis {axis}");
        assert!((w_gpu / w_lobe - 1.0).abs() < 0.03, "axis {axis}");
        assert!((mean_gpu - mean_lobe).abs() < 0.5, "axis {axis}");
    }
}

/// A glossy floor of roughness `alpha` under `lights`, a white diffuse back
/// wall and a diffuse block between them that shadows wall and floor
/// differently from each light; camera looking down at the floor.
fn lit_floor_scene(alpha: f32, lights: &[Light]) -> (Scene, Camera) {
    let camera = Camera::look_at(
        Vec3::new(0.3, 1.4, 1.9),
        Vec3::new(-0.2, 0.2, -0.8),
        Vec3::Y,
        60.0,
    );
    let materials = vec![
        Material::new("floor", rough_mirror(alpha, 0.7)),
        Material::diffuse("wall", Rgb::splat(0.8)),
        Material::diffuse("block", Rgb::new(0.7, 0.3, 0.2)),
    ];
    let block = |y0: f32, y1: f32| {
        let (x0, x1, z0, z1) = (-0.4, 0.2, -1.4, -1.0);
        let c = [
            Vec3::new(x0, y0, z1),
            Vec3::new(x1, y0, z1),
            Vec3::new(x1, y1, z1),
            Vec3::new(x0, y1, z1),
            Vec3::new(x0, y0, z0),
            Vec3::new(x1, y0, z0),
            Vec3::new(x1, y1, z0),
            Vec3::new(x0, y1, z0),
        ];
        let faces = [
            [0, 1, 2],
            [0, 2, 3],
            [5, 4, 7],
            [5, 7, 6],
            [4, 0, 3],
            [4, 3, 7],
            [1, 5, 6],
            [1, 6, 2],
            [3, 2, 6],
            [3, 6, 7],
        ];
        Mesh::flat("block", &c, &faces, 2)
    };
    let meshes = vec![
        floor_quad(),
        quad(
            "back",
            [
                Vec3::new(-2.0, 0.0, -2.0),
                Vec3::new(2.0, 0.0, -2.0),
                Vec3::new(2.0, 2.0, -2.0),
                Vec3::new(-2.0, 2.0, -2.0),
            ],
            1,
        ),
        block(0.0, 0.8),
    ];
    let objects = Object::one_per_mesh(&meshes);
    let scene = Scene::new(
        "lit-floor",
        meshes,
        materials,
        objects,
        lights.to_vec(),
        camera,
    )
    .unwrap();
    (scene, camera)
}

/// The direct light of `lights` through glossy images under `settings`
/// (depth 1, one frame), with shadow volumes or shadow maps: HDR radiance.
fn render_lit(
    ctx: &GpuContext,
    scene: &Scene,
    camera: &Camera,
    lights: &[Light],
    settings: &GlossySettings,
    volumes: bool,
) -> Vec<Vec3> {
    let hdr = ctx.hdr_format();
    let mut graph = FrameGraph::new(ctx, OUTPUT_FORMAT)
        .unwrap()
        .with_direct(ctx, hdr)
        .unwrap()
        .with_glossy_images(
            ctx,
            hdr,
            scene,
            SpecularSettings {
                max_depth: 1,
                limit_radiance: Vec3::ZERO,
                clip: None,
            },
            settings,
        )
        .unwrap();
    if volumes {
        graph = graph.with_shadow_volumes(ctx, hdr, scene, lights).unwrap();
    }
    let camera = camera.with_aspect(1.0);
    support::direct_frame(ctx, &graph, scene, &camera, lights, SIZE)
        .0
        .iter()
        .map(|p| Vec3::new(p[0], p[1], p[2]))
        .collect()
}

#[test]
fn paired_lights_sum_to_every_light_over_the_shears() {
    let Some(ctx) = gpu_or_skip("paired_lights_sum_to_every_light_over_the_shears") else {
        return;
    };
    // Four point lights where one area light's jittered points would be,
    // and four sheared views of vanishing shear: paired, view p draws one
    // light weighted 4, so the four views' average is the sum of the four
    // lights, as drawing every light in every view gives.
    let lights: Vec<Light> = [(-0.6, -0.3), (0.5, -0.4), (-0.4, 0.6), (0.6, 0.5)]
        .iter()
        .map(|&(x, z)| {
            Light::Point(PointLight {
                position: Vec3::new(x, 1.8, z),
                intensity: Rgb::splat(0.5),
            })
        })
        .collect();
    let settings = |alpha_samples: u32, lights: GlossyLights| GlossySettings {
        samples: alpha_samples,
        depth: 1,
        fog: Fog::Off,
        fog_radiance: Vec3::ZERO,
        hide_emitters: true,
        shear: ShearModel::Isotropic,
        frosted_alpha: 0.0,
        lights,
    };
    // (every light, paired) drawn through glossy images of `samples` shears.
    let both = |scene: &Scene, camera: &Camera, samples: u32, volumes: bool| {
        [GlossyLights::All, GlossyLights::Paired].map(|mode| {
            render_lit(
                &ctx,
                scene,
                camera,
                &lights,
                &settings(samples, mode),
                volumes,
            )
        })
    };
    let (still, camera) = lit_floor_scene(1e-6, &lights);
    for volumes in [true, false] {
        let [all, paired] = both(&still, &camera, 4, volumes);
        let max = all.iter().map(|v| v.max_element()).fold(0.0f32, f32::max);
        assert!(max > 0.0, "the scene must be lit");
        let wrong = all
            .iter()
            .zip(&paired)
            .filter(|(a, p)| {
                (**a - **p).abs().max_element() > 2e-3 * a.max_element().max(1e-2 * max)
            })
            .count();
        // Shears of 1e-6 move no pixel centre across an edge but a handful.
        assert!(wrong <= 10, "volumes {volumes}: {wrong} pixels differ");
    }
    // With real shears each view draws another light: the image differs
    // from drawing every light, pixel by pixel, but not in its total.
    let (rough, camera) = lit_floor_scene(0.15, &lights);
    let [all, paired] = both(&rough, &camera, 8, true);
    let differ = all
        .iter()
        .zip(&paired)
        .filter(|(a, p)| (**a - **p).abs().max_element() > 1e-2 * a.max_element().max(1e-3))
        .count();
    assert!(
        differ > 100,
        "paired views must draw fewer lights: {differ} pixels differ"
    );
    let total = |image: &[Vec3]| {
        image
            .iter()
            .map(|v| f64::from(v.x + v.y + v.z))
            .sum::<f64>()
    };
    let ratio = total(&paired) / total(&all);
    assert!(
        (ratio - 1.0).abs() < 0.02,
        "total light paired / all: {ratio}"
    );
}
