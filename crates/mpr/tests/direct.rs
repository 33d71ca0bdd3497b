//! The direct light pass (Stürzlinger & Bastos 1997, section 2.2.1) on the
//! GPU against its CPU twin (BVH ray casts and shadow rays, BRDFs from
//! `lustre-brdf`) on `cornell` and `glosbox` with their area light replaced
//! by an oriented point light of equal power, against the analytic radiance
//! of point, oriented and spot lights over a diffuse plane, and the shadow
//! cube against CPU ray casts from the light.

mod support;

use std::sync::Arc;

use glam::{Affine3A, Vec2, Vec3};
use lustre_geometry::light::{
    Light, OrientedPointLight, PointLight, SpotLight, jittered_point_lights,
};
use lustre_geometry::sampling::Frame;
use lustre_geometry::{
    Bvh, Camera, Material, MaterialModel, Mesh, Object, Rgb, Scene, Texture, WorldTriangle, builtin,
};
use lustre_mpr::material::{GlossyModel, scene_materials};
use lustre_mpr::passes::depth::DepthPass;
use lustre_mpr::passes::direct::{
    DirectLights, DirectPass, DirectPixel, cpu_brdf, direct_pass_cpu, direct_pixels_cpu_with_lights,
};
use lustre_mpr::passes::shadow::{NO_OCCLUDER, ShadowSettings, shadow_cube_cpu};
use lustre_mpr::readback::{read_rgba_f32, read_u32};
use lustre_mpr::{GpuContext, MprError, NO_SURFACE, RenderTargets, SceneBuffers};
use support::gpu_or_skip;

const SIZE: u32 = 96;
/// Pixels closer than this (px) to a projected surface-boundary edge are not compared:
/// the GPU and the CPU may see different surfaces there.
const EDGE_MARGIN: f32 = 1.0;
/// Pixels within this many pixels (Chebyshev) of a pixel whose CPU light visibility differs are not compared:
/// the shadow map resolves shadow boundaries to a texel and the bias moves them slightly.
const SHADOW_MARGIN: i32 = 2;
/// Relative tolerance of GPU against CPU radiance. Both evaluate the same
/// formula in f32 with independent BRDF code, the GPU at interpolated
/// positions and normals; lavapipe measures at most 1.2e-5. Hardware GPUs
/// use approximate exp, pow and rsqrt instructions (a few ulp) and may
/// interpolate less precisely, so 1e-3 leaves room for them while any
/// formula error (a lost π, cosine, lobe weight or Fresnel) is 1e-2 or more.
const RELATIVE_TOLERANCE: f32 = 1e-3;
/// Absolute tolerance, as a fraction of the image's largest CPU radiance:
/// covers near-zero values (grazing light on the ceiling next to the light,
/// where the shadow map's slope bias is capped).
const ABSOLUTE_TOLERANCE: f32 = 1e-4;

/// `scene` with every emissive mesh (the luminaire) removed and its area light
/// replaced by `AreaLight::to_oriented_point` (equal power; section 3 of the paper).
fn point_light_scene(scene: &Scene) -> Scene {
    let emissive = |m: &Mesh| scene.materials()[m.material as usize].is_emissive();
    let mut new_index = Vec::new();
    let mut meshes = Vec::new();
    for mesh in scene.meshes() {
        if emissive(mesh) {
            new_index.push(None);
        } else {
            new_index.push(Some(meshes.len() as u32));
            meshes.push(mesh.clone());
        }
    }
    let objects: Vec<Object> = scene
        .objects()
        .iter()
        .filter_map(|o| {
            let kept: Vec<u32> = o
                .meshes
                .iter()
                .filter_map(|&m| new_index[m as usize])
                .collect();
            (!kept.is_empty()).then(|| Object {
                name: o.name.clone(),
                meshes: kept,
                transform: o.transform,
            })
        })
        .collect();
    let lights: Vec<Light> = scene
        .lights()
        .iter()
        .map(|l| match l {
            Light::Area(a) => Light::OrientedPoint(a.to_oriented_point()),
            other => other.clone(),
        })
        .collect();
    Scene::new(
        format!("{}-point", scene.name),
        meshes,
        scene.materials().to_vec(),
        objects,
        lights,
        *scene.camera(),
    )
    .unwrap()
}

/// Depth pre-pass, shadow cubes and direct pass into cleared targets; returns HDR radiance and surface ids.
fn gpu_direct(
    ctx: &GpuContext,
    scene: &Scene,
    camera: &Camera,
    glossy: GlossyModel,
    size: u32,
) -> (Vec<[f32; 4]>, Vec<u32>) {
    let direct = DirectPass::new(ctx, ctx.hdr_format()).unwrap();
    let lights = DirectLights::new(ctx, &direct, scene, glossy).unwrap();
    render_direct(ctx, scene, camera, &direct, &lights, size)
}

/// [`gpu_direct`] with a given pass and lights.
fn render_direct(
    ctx: &GpuContext,
    scene: &Scene,
    camera: &Camera,
    direct: &DirectPass,
    lights: &DirectLights,
    size: u32,
) -> (Vec<[f32; 4]>, Vec<u32>) {
    let targets = RenderTargets::new(ctx, size, size).unwrap();
    let buffers = SceneBuffers::upload(ctx, scene).unwrap();
    let depth = DepthPass::new(ctx).unwrap();
    let (views, slot) = lustre_mpr::ViewBuffer::for_camera(ctx, camera).unwrap();
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("clear-hdr"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: &targets.hdr.view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                store: wgpu::StoreOp::Store,
            },
        })],
        depth_stencil_attachment: None,
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    depth.encode(&mut encoder, &buffers, &targets, &views, slot, true);
    direct.encode_shadows(&mut encoder, &buffers, lights);
    direct.encode(&mut encoder, &buffers, &targets, lights, &views, slot);
    ctx.queue.submit([encoder.finish()]);
    (
        read_rgba_f32(ctx, &targets.hdr.texture).unwrap(),
        read_u32(ctx, &targets.surface_id.texture).unwrap(),
    )
}

// --- Surface-boundary distance, as in tests/depth.rs. ---

/// Triangle edges across which the surface id can change (not shared with a triangle of the same surface).
fn boundary_edges(triangles: &[WorldTriangle], eps: f32) -> Vec<[Vec3; 2]> {
    let same = |a: [Vec3; 2], b: [Vec3; 2]| {
        (a[0].distance(b[0]) <= eps && a[1].distance(b[1]) <= eps)
            || (a[0].distance(b[1]) <= eps && a[1].distance(b[0]) <= eps)
    };
    let edges = |t: &WorldTriangle| {
        let p = t.positions;
        [[p[0], p[1]], [p[1], p[2]], [p[2], p[0]]]
    };
    let mut out = Vec::new();
    for (i, t) in triangles.iter().enumerate() {
        for e in edges(t) {
            let shared = triangles.iter().enumerate().any(|(j, u)| {
                j != i && u.surface == t.surface && edges(u).iter().any(|&f| same(e, f))
            });
            if !shared {
                out.push(e);
            }
        }
    }
    out
}

/// The edge clipped to the near plane and projected to pixel coordinates; `None` if behind.
fn project_edge(camera: &Camera, [a, b]: [Vec3; 2], size: u32) -> Option<[Vec2; 2]> {
    let view = camera.view_matrix();
    let (mut a, mut b) = (view.transform_point3(a), view.transform_point3(b));
    let limit = -camera.near;
    match (a.z <= limit, b.z <= limit) {
        (false, false) => return None,
        (true, false) => b = a + (b - a) * ((limit - a.z) / (b.z - a.z)),
        (false, true) => a = b + (a - b) * ((limit - b.z) / (a.z - b.z)),
        (true, true) => {}
    }
    let projection = camera.projection_matrix();
    let to_pixels = |p: Vec3| {
        let ndc = projection.project_point3(p);
        Vec2::new(
            (ndc.x + 1.0) * 0.5 * size as f32,
            (1.0 - ndc.y) * 0.5 * size as f32,
        )
    };
    Some([to_pixels(a), to_pixels(b)])
}

/// Distance from `p` to the segment `[a, b]`.
fn segment_distance(p: Vec2, [a, b]: [Vec2; 2]) -> f32 {
    let ab = b - a;
    let t = if ab.length_squared() > 0.0 {
        ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    p.distance(a + ab * t)
}

/// Per pixel: distance in pixels to the nearest projected surface-boundary edge.
fn edge_distance_image(scene: &Scene, camera: &Camera, size: u32) -> Vec<f32> {
    let eps = 1e-5 * scene.bounds().extent().max_element();
    let segments: Vec<_> = boundary_edges(&scene.world_triangles(), eps)
        .into_iter()
        .filter_map(|e| project_edge(camera, e, size))
        .collect();
    (0..size)
        .flat_map(|y| (0..size).map(move |x| Vec2::new(x as f32 + 0.5, y as f32 + 0.5)))
        .map(|c| {
            segments
                .iter()
                .map(|&s| segment_distance(c, s))
                .fold(f32::INFINITY, f32::min)
        })
        .collect()
}

/// Per pixel: whether a pixel within [`SHADOW_MARGIN`] has another CPU light-visibility mask.
fn near_shadow_boundary(cpu: &[DirectPixel], size: u32) -> Vec<bool> {
    let n = size as i32;
    (0..n * n)
        .map(|i| {
            let (x, y) = (i % n, i / n);
            let here = cpu[i as usize].visible;
            (-SHADOW_MARGIN..=SHADOW_MARGIN).any(|dy| {
                (-SHADOW_MARGIN..=SHADOW_MARGIN).any(|dx| {
                    let (u, v) = (x + dx, y + dy);
                    (0..n).contains(&u)
                        && (0..n).contains(&v)
                        && cpu[(v * n + u) as usize].visible != here
                })
            })
        })
        .collect()
}

/// Compares GPU radiance with the CPU twin; panics past the tolerances, else returns a summary.
fn compare(
    name: &str,
    scene: &Scene,
    lights: &[Light],
    camera: &Camera,
    glossy: GlossyModel,
    gpu: &[[f32; 4]],
    ids: &[u32],
) -> String {
    compare_within(
        name,
        scene,
        lights,
        camera,
        glossy,
        gpu,
        ids,
        [RELATIVE_TOLERANCE, ABSOLUTE_TOLERANCE],
    )
}

/// [`compare`] with `[relative, absolute as a fraction of the largest CPU radiance]` tolerances.
#[allow(clippy::too_many_arguments)]
fn compare_within(
    name: &str,
    scene: &Scene,
    lights: &[Light],
    camera: &Camera,
    glossy: GlossyModel,
    gpu: &[[f32; 4]],
    ids: &[u32],
    [relative, absolute]: [f32; 2],
) -> String {
    let bvh = Bvh::build(scene);
    let cpu =
        direct_pixels_cpu_with_lights(scene, lights, &bvh, camera, SIZE, SIZE, glossy).unwrap();
    let edges = edge_distance_image(scene, camera, SIZE);
    let shadow_edges = near_shadow_boundary(&cpu, SIZE);
    let max = cpu.iter().flat_map(|p| p.radiance).fold(0.0f32, f32::max);
    let floor = absolute * max;
    let (mut compared, mut near_edge, mut near_shadow, mut background) = (0, 0, 0, 0);
    let (mut worst_rel, mut worst_abs) = (0.0f32, 0.0f32);
    let mut worst_at = (0, 0);
    for (i, c) in cpu.iter().enumerate() {
        let (x, y) = (i as u32 % SIZE, i as u32 / SIZE);
        if edges[i] < EDGE_MARGIN {
            near_edge += 1;
            continue;
        }
        assert_eq!(
            ids[i], c.surface,
            "{name}: pixel ({x}, {y}) {:.2} px from an edge: GPU surface {} vs CPU {}",
            edges[i], ids[i], c.surface
        );
        if c.surface == NO_SURFACE {
            background += 1;
            assert!(
                gpu[i][..3].iter().all(|&v| v == 0.0),
                "{name}: light on the background"
            );
            continue;
        }
        if shadow_edges[i] {
            near_shadow += 1;
            continue;
        }
        compared += 1;
        for k in 0..3 {
            let (g, r) = (gpu[i][k], c.radiance[k]);
            let diff = (g - r).abs();
            assert!(
                diff <= relative * r + floor,
                "{name}: pixel ({x}, {y}) channel {k}: GPU {g} vs CPU {r} (surface {}, visible {:b})",
                c.surface,
                c.visible
            );
            if r > floor {
                let rel = diff / r;
                if rel > worst_rel {
                    worst_rel = rel;
                    worst_at = (x, y);
                }
            }
            worst_abs = worst_abs.max(diff);
        }
    }
    format!(
        "{name}: {compared} pixels compared ({background} background, {near_edge} near surface edges, \
         {near_shadow} near shadow boundaries not compared); max radiance {max:.4}; \
         worst relative difference {worst_rel:.2e} at {worst_at:?} (where CPU > {floor:.1e}), \
         worst absolute {worst_abs:.2e}"
    )
}

#[test]
fn gpu_direct_light_matches_cpu_on_cornell_and_glosbox() {
    let Some(ctx) = gpu_or_skip("gpu_direct_light_matches_cpu_on_cornell_and_glosbox") else {
        return;
    };
    for name in ["cornell", "glosbox"] {
        let scene = point_light_scene(&builtin(name).unwrap());
        // The scene camera, and one from above and to the side that sees the
        // boxes' tops, their shadows and the floor's highlight at a slant.
        let cameras = [
            scene.camera().with_aspect(1.0),
            Camera::look_at(
                Vec3::new(0.6, 0.7, 2.5),
                Vec3::new(-0.1, -0.6, -0.2),
                Vec3::Y,
                55.0,
            ),
        ];
        let models: &[GlossyModel] = if name == "glosbox" {
            &[GlossyModel::Exact, GlossyModel::FittedPhong]
        } else {
            &[GlossyModel::Exact]
        };
        for (k, camera) in cameras.iter().enumerate() {
            let mut images = Vec::new();
            for &glossy in models {
                let (gpu, ids) = gpu_direct(&ctx, &scene, camera, glossy, SIZE);
                let label = format!("{name} camera {k} {glossy:?}");
                eprintln!(
                    "{}",
                    compare(&label, &scene, scene.lights(), camera, glossy, &gpu, &ids)
                );
                images.push(gpu);
            }
            if let [exact, fitted] = &images[..] {
                // The fitted Phong really is another material buffer: the gold box differs.
                let differ = exact
                    .iter()
                    .zip(fitted)
                    .filter(|(a, b)| (a[0] - b[0]).abs() > 0.05 * a[0].max(b[0]))
                    .count();
                assert!(
                    differ > 20,
                    "{name} camera {k}: only {differ} pixels differ between Exact and FittedPhong"
                );
            }
        }
    }
}

/// A 20 m square diffuse plane at y = 0 lit by `lights`, seen from above at a slant.
fn plane_scene(reflectance: Rgb, lights: Vec<Light>) -> Scene {
    let half = 10.0;
    let mesh = Mesh {
        name: "plane".into(),
        positions: vec![
            Vec3::new(-half, 0.0, half),
            Vec3::new(half, 0.0, half),
            Vec3::new(half, 0.0, -half),
            Vec3::new(-half, 0.0, -half),
        ],
        normals: vec![Vec3::Y; 4],
        uvs: vec![Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y],
        indices: vec![[0, 1, 2], [2, 3, 0]],
        material: 0,
    };
    let camera = Camera::look_at(
        Vec3::new(0.5, 3.0, 4.0),
        Vec3::new(0.0, 0.0, 0.5),
        Vec3::Y,
        60.0,
    );
    Scene::new(
        "plane",
        vec![mesh],
        vec![Material::diffuse("grey", reflectance)],
        vec![Object {
            name: "plane".into(),
            meshes: vec![0],
            transform: Affine3A::IDENTITY,
        }],
        lights,
        camera,
    )
    .unwrap()
}

/// Radiance of the plane y = 0 (reflectance ρ) at `p`: Σ ρ/π I(w) cos θ / d², computed in f64.
fn analytic_plane_radiance(reflectance: Rgb, lights: &[Light], p: Vec3) -> [f64; 3] {
    let p = p.as_dvec3();
    let mut sum = [0.0f64; 3];
    for light in lights {
        let (position, intensity) = match light {
            Light::Point(l) => (l.position.as_dvec3(), l.intensity.as_dvec3()),
            Light::OrientedPoint(l) => {
                let w = (p - l.position.as_dvec3()).normalize();
                let cos = w.dot(l.normal.as_dvec3().normalize()).max(0.0);
                (l.position.as_dvec3(), l.intensity.as_dvec3() * cos)
            }
            Light::Spot(l) => {
                let w = (p - l.position.as_dvec3()).normalize();
                let theta = w
                    .dot(l.direction.as_dvec3().normalize())
                    .clamp(-1.0, 1.0)
                    .acos();
                let (b, c) = (f64::from(l.beam_width), f64::from(l.cutoff_angle));
                let falloff = if theta <= b {
                    1.0
                } else if theta >= c {
                    0.0
                } else {
                    (c - theta) / (c - b)
                };
                (l.position.as_dvec3(), l.intensity.as_dvec3() * falloff)
            }
            Light::Area(_) => unreachable!("point lights only"),
        };
        let to_light = position - p;
        let d2 = to_light.length_squared();
        let cos = (to_light.y / d2.sqrt()).max(0.0);
        let e = intensity * (cos / d2);
        let l = reflectance.as_dvec3() * e / std::f64::consts::PI;
        for k in 0..3 {
            sum[k] += l[k];
        }
    }
    sum
}

#[test]
fn point_oriented_and_spot_lights_over_a_diffuse_plane_match_the_analytic_radiance() {
    let Some(ctx) = gpu_or_skip(
        "point_oriented_and_spot_lights_over_a_diffuse_plane_match_the_analytic_radiance",
    ) else {
        return;
    };
    let reflectance = Rgb::new(0.8, 0.5, 0.25);
    let point = Light::Point(PointLight {
        position: Vec3::new(-0.4, 1.5, 0.2),
        intensity: Rgb::new(2.0, 3.0, 4.0),
    });
    let oriented = Light::OrientedPoint(OrientedPointLight {
        position: Vec3::new(0.8, 1.0, -0.5),
        normal: Vec3::new(0.5, -1.0, 0.3).normalize(),
        intensity: Rgb::new(5.0, 1.0, 2.0),
    });
    let spot = Light::Spot(SpotLight {
        position: Vec3::new(0.2, 2.0, 1.0),
        direction: Vec3::new(-0.2, -1.0, 0.1).normalize(),
        intensity: Rgb::new(6.0, 6.0, 1.0),
        cutoff_angle: 40f32.to_radians(),
        beam_width: 25f32.to_radians(),
    });
    // Each light alone (E = I cos θ / d², L = ρ/π E), then all three added in one pass.
    let cases = [
        ("point", vec![point.clone()]),
        ("oriented point", vec![oriented.clone()]),
        ("spot", vec![spot.clone()]),
        ("all three", vec![point, oriented, spot]),
    ];
    // f32 interpolation of positions and the GPU's acos (spot fall-off) against f64:
    // relative 1e-4 where the radiance is above 1e-4 of the maximum; 1e-5 of the maximum absolute elsewhere
    // (the spot's linear fall-off reaches zero at the cut-off, where relative errors are meaningless).
    const PLANE_RELATIVE: f64 = 1e-4;
    const PLANE_ABSOLUTE: f64 = 1e-5;
    for (name, lights) in cases {
        let scene = plane_scene(reflectance, lights.clone());
        let camera = scene.camera().with_aspect(1.0);
        let (gpu, ids) = gpu_direct(&ctx, &scene, &camera, GlossyModel::Exact, SIZE);
        let expected: Vec<Option<[f64; 3]>> = (0..SIZE * SIZE)
            .map(|i| {
                let ray = camera.primary_ray(Camera::pixel_ndc(
                    i % SIZE,
                    i / SIZE,
                    SIZE,
                    SIZE,
                    Vec2::splat(0.5),
                ));
                // The plane y = 0, bounded by |x|, |z| <= 10.
                let t = -ray.origin.y / ray.direction.y;
                let p = ray.at(t);
                (t > 0.0 && p.x.abs() < 9.9 && p.z.abs() < 9.9)
                    .then(|| analytic_plane_radiance(reflectance, &lights, p))
            })
            .collect();
        let max = expected
            .iter()
            .flatten()
            .flat_map(|l| *l)
            .fold(0.0f64, f64::max);
        let (mut worst_rel, mut worst_abs, mut pixels) = (0.0f64, 0.0f64, 0);
        for (i, e) in expected.iter().enumerate() {
            let Some(e) = e else { continue };
            assert_ne!(
                ids[i], NO_SURFACE,
                "{name}: pixel {i} misses the plane on the GPU"
            );
            pixels += 1;
            for k in 0..3 {
                let g = f64::from(gpu[i][k]);
                let diff = (g - e[k]).abs();
                assert!(
                    diff <= PLANE_RELATIVE * e[k] + PLANE_ABSOLUTE * max,
                    "{name}: pixel ({}, {}) channel {k}: GPU {g} vs analytic {}",
                    i as u32 % SIZE,
                    i as u32 / SIZE,
                    e[k]
                );
                if e[k] > 1e-4 * max {
                    worst_rel = worst_rel.max(diff / e[k]);
                }
                worst_abs = worst_abs.max(diff);
            }
        }
        eprintln!(
            "{name}: {pixels} plane pixels; max radiance {max:.4}; worst relative difference {worst_rel:.2e} \
             (where > 1e-4 of the max), worst absolute {worst_abs:.2e}"
        );
        // The CPU twin agrees with the same formula.
        let cpu = direct_pass_cpu(
            &scene,
            &Bvh::build(&scene),
            &camera,
            SIZE,
            SIZE,
            GlossyModel::Exact,
        )
        .unwrap();
        for (i, e) in expected.iter().enumerate() {
            let Some(e) = e else { continue };
            for k in 0..3 {
                let diff = (f64::from(cpu[i][k]) - e[k]).abs();
                assert!(
                    diff <= PLANE_RELATIVE * e[k] + PLANE_ABSOLUTE * max,
                    "{name}: CPU pixel {i}"
                );
            }
        }
    }
}

/// Reads one `R32Float` array layer of `texture` (`size`² texels).
fn read_layer(ctx: &GpuContext, texture: &wgpu::Texture, layer: u32, size: u32) -> Vec<f32> {
    let padded = lustre_mpr::readback::padded_bytes_per_row(size, 4);
    let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("layer-readback"),
        size: u64::from(padded * size),
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: 0,
            origin: wgpu::Origin3d {
                x: 0,
                y: 0,
                z: layer,
            },
            aspect: wgpu::TextureAspect::All,
        },
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded),
                rows_per_image: Some(size),
            },
        },
        wgpu::Extent3d {
            width: size,
            height: size,
            depth_or_array_layers: 1,
        },
    );
    ctx.queue.submit([encoder.finish()]);
    let slice = buffer.slice(..);
    slice.map_async(wgpu::MapMode::Read, |r| r.unwrap());
    ctx.wait().unwrap();
    let data = slice.get_mapped_range().unwrap();
    (0..size as usize)
        .flat_map(|y| {
            let row = &data[y * padded as usize..][..4 * size as usize];
            row.chunks_exact(4)
                .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .collect::<Vec<_>>()
        })
        .collect()
}

#[test]
fn shadow_cube_faces_hold_the_distance_to_the_nearest_surface() {
    let Some(ctx) = gpu_or_skip("shadow_cube_faces_hold_the_distance_to_the_nearest_surface")
    else {
        return;
    };
    let scene = point_light_scene(&builtin("cornell").unwrap());
    // Away from the ceiling, so every face sees several surfaces at an angle.
    let light = Light::Point(PointLight {
        position: Vec3::new(0.1, 0.2, 0.3),
        intensity: Rgb::ONE,
    });
    let size = 64;
    let settings = ShadowSettings {
        size,
        ..ShadowSettings::default()
    };
    let buffers = SceneBuffers::upload(&ctx, &scene).unwrap();
    let direct = DirectPass::new(&ctx, ctx.hdr_format()).unwrap();
    let materials = scene_materials(&scene, GlossyModel::Exact).unwrap();
    let lights = DirectLights::with_settings(
        &ctx,
        &direct,
        std::slice::from_ref(&light),
        &materials,
        settings,
    )
    .unwrap();
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    direct.encode_shadows(&mut encoder, &buffers, &lights);
    ctx.queue.submit([encoder.finish()]);
    let cube = lights.shadow_cube(0).unwrap();
    let cpu = shadow_cube_cpu(
        &Bvh::build(&scene),
        Vec3::new(0.1, 0.2, 0.3),
        size,
        settings.near,
    );
    // Texels whose 3×3 CPU neighbourhood is smooth (no silhouette: every
    // neighbour within 5 %) must agree within 1e-4 relative; at silhouettes
    // the GPU's coverage of the texel centre may pick the other surface.
    let n = size as i32;
    let (mut compared, mut worst) = (0, 0.0f32);
    for face in 0..6 {
        let gpu = read_layer(&ctx, &cube.texture, face as u32, size);
        let c = &cpu[face];
        // The box is open towards +z: those texels must stay cleared on the GPU too.
        let escaped = c.iter().filter(|&&d| d == NO_OCCLUDER).count();
        let gpu_escaped = gpu.iter().filter(|&&d| d == NO_OCCLUDER).count();
        assert!(
            escaped.abs_diff(gpu_escaped) <= 2 * size as usize,
            "face {face}: {escaped} CPU and {gpu_escaped} GPU texels see no surface"
        );
        for y in 1..n - 1 {
            for x in 1..n - 1 {
                let i = (y * n + x) as usize;
                let smooth = (-1..=1).all(|dy| {
                    (-1..=1).all(|dx| {
                        let j = ((y + dy) * n + x + dx) as usize;
                        (c[j] - c[i]).abs() <= 0.05 * c[i]
                    })
                });
                if !smooth || c[i] == NO_OCCLUDER {
                    continue;
                }
                compared += 1;
                let rel = (gpu[i] - c[i]).abs() / c[i];
                assert!(
                    rel <= 1e-4,
                    "face {face} texel ({x}, {y}): GPU {} vs CPU {}",
                    gpu[i],
                    c[i]
                );
                worst = worst.max(rel);
            }
        }
    }
    eprintln!(
        "shadow cube: {compared} smooth texels compared; worst relative difference {worst:.2e}"
    );
}

#[test]
fn area_lights_are_an_error_naming_the_conversion() {
    let scene = builtin("cornell").unwrap();
    let bvh = Bvh::build(&scene);
    let camera = scene.camera().with_aspect(1.0);
    let err = direct_pass_cpu(&scene, &bvh, &camera, 4, 4, GlossyModel::Exact).unwrap_err();
    assert!(
        matches!(err, MprError::InvalidSetting { .. })
            && err.to_string().contains("to_oriented_point"),
        "{err}"
    );
    let Some(ctx) = gpu_or_skip("area_lights_are_an_error_naming_the_conversion") else {
        return;
    };
    let direct = DirectPass::new(&ctx, ctx.hdr_format()).unwrap();
    let err = DirectLights::new(&ctx, &direct, &scene, GlossyModel::Exact).unwrap_err();
    assert!(
        matches!(err, MprError::InvalidSetting { .. })
            && err.to_string().contains("to_oriented_point"),
        "{err}"
    );
}

#[test]
fn moved_lights_are_shaded_at_their_new_pose_after_their_shadows_are_redrawn() {
    let Some(ctx) =
        gpu_or_skip("moved_lights_are_shaded_at_their_new_pose_after_their_shadows_are_redrawn")
    else {
        return;
    };
    let scene = point_light_scene(&builtin("cornell").unwrap());
    let camera = scene.camera().with_aspect(1.0);
    let direct = DirectPass::new(&ctx, ctx.hdr_format()).unwrap();
    // Built for a light near the floor, then moved to the scene's light.
    let Light::OrientedPoint(target) = scene.lights()[0].clone() else {
        panic!("cornell's light converts to an oriented point light");
    };
    let start = Light::OrientedPoint(OrientedPointLight {
        position: Vec3::new(0.3, -0.5, 0.4),
        ..target
    });
    let materials = scene_materials(&scene, GlossyModel::Exact).unwrap();
    let lights = DirectLights::with_settings(
        &ctx,
        &direct,
        &[start],
        &materials,
        ShadowSettings::default(),
    )
    .unwrap();
    let (before, _) = render_direct(&ctx, &scene, &camera, &direct, &lights, SIZE);
    lights
        .set_lights(&direct, &ctx.queue, scene.lights())
        .unwrap();
    let (gpu, ids) = render_direct(&ctx, &scene, &camera, &direct, &lights, SIZE);
    assert_ne!(before, gpu);
    eprintln!(
        "{}",
        compare(
            "cornell, moved light",
            &scene,
            scene.lights(),
            &camera,
            GlossyModel::Exact,
            &gpu,
            &ids
        )
    );
    let err = lights.set_lights(&direct, &ctx.queue, &[]).unwrap_err();
    assert!(matches!(err, MprError::InvalidSetting { .. }), "{err}");
}

/// Soft shadows (Diefenbach & Badler 1997, section 4.4): `cornell`'s area
/// light as `K` jittered point lights, each with its own shadow cube, through
/// [`DirectLights::jittered`] on the GPU against the CPU twin with the same lights.
#[test]
fn jittered_point_lights_on_the_gpu_match_the_cpu_twin() {
    let Some(ctx) = gpu_or_skip("jittered_point_lights_on_the_gpu_match_the_cpu_twin") else {
        return;
    };
    for name in ["cornell", "glosbox"] {
        let scene = builtin(name).unwrap();
        let camera = scene.camera().with_aspect(1.0);
        let k = 16;
        let direct = DirectPass::new(&ctx, ctx.hdr_format()).unwrap();
        let lights = DirectLights::jittered(&ctx, &direct, &scene, GlossyModel::Exact, k).unwrap();
        assert_eq!(
            lights.len(),
            k as usize,
            "one shadow cube per jittered light"
        );
        let points = jittered_point_lights(scene.lights(), k, Vec2::ZERO);
        let total: Rgb = points.iter().map(Light::power).sum();
        let area: Rgb = scene.lights().iter().map(Light::power).sum();
        assert!(
            (total - area).abs().max_element() <= 1e-5 * area.max_element(),
            "the jittered lights carry the area light's power: {total} vs {area}"
        );
        let (gpu, ids) = render_direct(&ctx, &scene, &camera, &direct, &lights, SIZE);
        eprintln!(
            "{}",
            compare(
                &format!("{name}, {k} jittered lights"),
                &scene,
                &points,
                &camera,
                GlossyModel::Exact,
                &gpu,
                &ids
            )
        );
    }
}

/// A small deterministic generator for the brute-force integral (SplitMix64).
fn splitmix(state: &mut u64) -> f32 {
    *state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
}

/// The direct radiance of `cornell` by brute force: per pixel `M` stratified
/// random points on the area light (`Light::sample_direct`, the solid-angle
/// estimator of `∫ L f cos θᵢ dω`) with BVH shadow rays; and the fraction of them visible.
fn brute_force_direct(
    scene: &Scene,
    bvh: &Bvh,
    camera: &Camera,
    size: u32,
    m: u32,
) -> Vec<(f64, f64)> {
    let eps = 1e-4 * scene.bounds().extent().max_element();
    let light = &scene.lights()[0];
    let side = (m as f64).sqrt() as u32;
    (0..size * size)
        .map(|i| {
            let (x, y) = (i % size, i / size);
            let ray = camera.primary_ray(Camera::pixel_ndc(x, y, size, size, Vec2::splat(0.5)));
            let Some(hit) = bvh.closest_hit(&ray) else {
                return (0.0, 0.0);
            };
            let wo = -ray.direction;
            let n = if hit.shading_normal.dot(wo) < 0.0 {
                -hit.shading_normal
            } else {
                hit.shading_normal
            };
            let frame = Frame::from_normal(n);
            let brdf = cpu_brdf(
                &scene.materials()[hit.material as usize].model,
                GlossyModel::Exact,
            )
            .unwrap();
            let mut state = u64::from(i) * 0x1234_5678 + 1;
            let (mut sum, mut seen, mut toward) = (0.0f64, 0u32, 0u32);
            for j in 0..side * side {
                let u = Vec2::new(
                    ((j % side) as f32 + splitmix(&mut state)) / side as f32,
                    ((j / side) as f32 + splitmix(&mut state)) / side as f32,
                );
                let Some(sample) = light.sample_direct(hit.position, u) else {
                    continue;
                };
                let wi = frame.to_local(sample.direction);
                if wi.z <= 0.0 {
                    continue;
                }
                toward += 1;
                let shadow = lustre_geometry::Ray::segment(
                    hit.position,
                    sample.direction,
                    eps,
                    sample.distance - eps,
                );
                if bvh.any_hit(&shadow) {
                    continue;
                }
                seen += 1;
                sum += f64::from((brdf.eval(wi, frame.to_local(wo)) * sample.weight * wi.z).x);
            }
            let visible = if toward == 0 {
                0.0
            } else {
                f64::from(seen) / f64::from(toward)
            };
            (sum / f64::from(side * side), visible)
        })
        .collect()
}

/// Diefenbach's jittered point lights estimate the area light's direct
/// light: in the tall box's penumbra on `cornell` the CPU twin with `K`
/// jittered lights approaches a brute-force Monte Carlo integral over the
/// light with shadow rays as `K` grows, while one point light (the paper's
/// replacement) shows a hard shadow there.
#[test]
fn jittered_point_lights_converge_to_the_area_light_in_the_penumbra() {
    let scene = builtin("cornell").unwrap();
    let bvh = Bvh::build(&scene);
    let size = 48;
    let camera = scene.camera().with_aspect(1.0);
    let m = 4096;
    let reference = brute_force_direct(&scene, &bvh, &camera, size, m);
    // Penumbra: pixels from which part of the light is hidden, away from full shadow.
    let penumbra: Vec<usize> = (0..reference.len())
        .filter(|&i| (0.1..=0.9).contains(&reference[i].1) && reference[i].0 > 0.0)
        .collect();
    assert!(penumbra.len() >= 30, "{} penumbra pixels", penumbra.len());
    let mut errors = Vec::new();
    for k in [1u32, 4, 16, 64, 256] {
        let lights = jittered_point_lights(scene.lights(), k, Vec2::ZERO);
        let cpu = direct_pixels_cpu_with_lights(
            &scene,
            &lights,
            &bvh,
            &camera,
            size,
            size,
            GlossyModel::Exact,
        )
        .unwrap();
        let (mut se, mut sr) = (0.0, 0.0);
        for &i in &penumbra {
            let d = f64::from(cpu[i].radiance[0]) - reference[i].0;
            se += d * d;
            sr += reference[i].0 * reference[i].0;
        }
        let rel_rms = (se / sr).sqrt();
        eprintln!(
            "K = {k}: relative RMS error {rel_rms:.4} over {} penumbra pixels",
            penumbra.len()
        );
        errors.push(rel_rms);
    }
    // The reference's own noise: M stratified samples, visibility a step over
    // the light, relative standard deviation below ~1/sqrt(M) per pixel.
    let noise = 1.0 / f64::from(m).sqrt();
    for w in errors.windows(2) {
        assert!(w[1] < w[0], "error grows with K: {errors:?}");
    }
    assert!(
        errors[0] > 0.2,
        "one point light misses the penumbra: {errors:?}"
    );
    // Stratified (Hammersley) light samples over a step in visibility
    // converge at least as K^(-1/2): 16 times the lights, 4 times smaller.
    assert!(errors[4] * 4.0 <= errors[2], "{errors:?}");
    assert!(errors[4] <= 0.05 + 3.0 * noise, "{errors:?}");
}

/// An 8 × 8 map whose texels all differ (red grows to the right, green down the rows, blue a checker), so that a flipped, mirrored or transposed lookup shows.
fn asymmetric_map() -> Arc<Texture> {
    let texels = (0..64)
        .map(|i| {
            let (x, y) = ((i % 8) as f32, (i / 8) as f32);
            Rgb::new(
                0.1 + 0.8 * x / 7.0,
                0.1 + 0.8 * y / 7.0,
                if (i % 8 + i / 8) % 2 == 0 { 0.9 } else { 0.2 },
            )
        })
        .collect();
    Arc::new(Texture::new("asymmetric", 8, 8, texels).unwrap())
}

/// A 2 m floor at y = 0 with UVs 0..1 (u along +x, v along -z) of `material`, lit by a point light above, and a camera above it that sees each of the map's texels over several pixels.
fn textured_floor_scene(material: Material) -> (Scene, Camera) {
    let mesh = Mesh {
        name: "floor".into(),
        positions: vec![
            Vec3::new(-1.0, 0.0, 1.0),
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::new(1.0, 0.0, -1.0),
            Vec3::new(-1.0, 0.0, -1.0),
        ],
        normals: vec![Vec3::Y; 4],
        uvs: vec![Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y],
        indices: vec![[0, 1, 2], [2, 3, 0]],
        material: 0,
    };
    let light = Light::Point(PointLight {
        position: Vec3::new(0.3, 1.2, 0.4),
        intensity: Rgb::splat(2.0),
    });
    let camera =
        Camera::look_at(Vec3::new(0.2, 2.2, 1.2), Vec3::ZERO, Vec3::Y, 50.0).with_aspect(1.0);
    let scene = Scene::new(
        "textured-floor",
        vec![mesh],
        vec![material],
        vec![Object {
            name: "floor".into(),
            meshes: vec![0],
            transform: Affine3A::IDENTITY,
        }],
        vec![light],
        camera,
    )
    .unwrap();
    (scene, camera)
}

/// Tolerances of a textured surface against the CPU twin: the GPU reads the
/// map in `Rgba16Float` (relative rounding 2⁻¹¹) and weighs texels with the
/// sampler's sub-texel precision (Vulkan requires 4 bits, lavapipe and most
/// GPUs have 8: a weight off by up to 2⁻⁹ of neighbours that differ by at
/// most 0.7 here), so the tint may differ by about 2⁻¹¹ + 0.7 × 2⁻⁹ ≈ 2e-3
/// of its value of at least 0.1: relative 2e-2 in all. A tint lost, flipped
/// or shifted by a texel changes the radiance by 10 % or more.
const TEXTURED_RELATIVE: f32 = 2e-2;

#[test]
fn a_textured_floor_matches_the_cpu_twin_and_differs_from_the_untextured_one() {
    let Some(ctx) =
        gpu_or_skip("a_textured_floor_matches_the_cpu_twin_and_differs_from_the_untextured_one")
    else {
        return;
    };
    let map = asymmetric_map();
    let models = [
        (
            "diffuse",
            MaterialModel::Diffuse {
                reflectance: Rgb::splat(0.8),
            },
        ),
        (
            "phong",
            MaterialModel::Phong {
                diffuse: Rgb::new(0.6, 0.5, 0.4),
                specular: Rgb::splat(0.3),
                exponent: 30.0,
            },
        ),
    ];
    for (name, model) in models {
        let plain = Material::new(name, model);
        let (untextured, camera) = textured_floor_scene(plain.clone());
        let (scene, _) = textured_floor_scene(plain.with_diffuse_map(map.clone()));
        let (gpu, ids) = gpu_direct(&ctx, &scene, &camera, GlossyModel::Exact, SIZE);
        eprintln!(
            "{}",
            compare_within(
                &format!("textured {name}"),
                &scene,
                scene.lights(),
                &camera,
                GlossyModel::Exact,
                &gpu,
                &ids,
                [TEXTURED_RELATIVE, ABSOLUTE_TOLERANCE],
            )
        );
        // The map really is drawn: most floor pixels differ from the untextured floor by more than the tolerance.
        let (plain_gpu, _) = gpu_direct(&ctx, &untextured, &camera, GlossyModel::Exact, SIZE);
        let floor = ids.iter().filter(|&&id| id != NO_SURFACE).count();
        let differ = gpu
            .iter()
            .zip(&plain_gpu)
            .filter(|(a, b)| (a[0] - b[0]).abs() > 0.1 * b[0])
            .count();
        assert!(
            floor > SIZE as usize * SIZE as usize / 4,
            "{name}: the floor covers {floor} pixels"
        );
        assert!(
            differ > floor / 2,
            "{name}: only {differ} of {floor} pixels show the map"
        );
    }
}
