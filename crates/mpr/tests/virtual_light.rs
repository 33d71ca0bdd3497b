//! Virtual lights on the GPU (Diefenbach & Badler 1997, sections 4.2, 4.3,
//! 7.1): `mirrors` at 96×96, its ceiling light as one point light, through
//! the frame graph with shadow volumes and virtual lights up to two
//! mirrors deep, against the CPU twin that follows every unfolded light
//! path with BVH ray casts (`virtual_light::path_visible`): the real
//! light's direct radiance plus each virtual light's where its whole path
//! is free. Pixels whose 5×5 neighbourhood changes surface or the set of
//! lights that reach it are left out (light-volume and shadow boundaries
//! are decided by rasterisation there); ≥ 99.5 % of the rest agree within
//! the direct tests' tolerance, and the virtual lights must matter in a
//! good share of them, which the frame without them fails.

mod support;

use glam::Vec2;
use lustre_geometry::light::jittered_point_lights;
use lustre_geometry::{Bvh, Camera, Light, Mesh, Scene, builtin};
use lustre_mpr::material::GlossyModel;
use lustre_mpr::passes::direct::{DirectPixel, direct_pixels_cpu_with_lights};
use lustre_mpr::passes::specular::specular_faces;
use lustre_mpr::projective_texture::{PaneLight, Window, windows};
use lustre_mpr::virtual_light::{
    SpecularShadows, VirtualLightSettings, specular_paths, virtual_direct_pixels_cpu, window_faces,
};
use lustre_mpr::{FrameGraph, GpuContext, NO_SURFACE};
use support::gpu_or_skip;

const SIZE: u32 = 96;
const OUTPUT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// A frame graph with direct light under shadow volumes, with virtual
/// lights of `depth` when `depth > 0`.
fn graph(ctx: &GpuContext, scene: &Scene, lights: &[Light], depth: u32) -> FrameGraph {
    graph_with(ctx, scene, lights, depth, PaneLight::default())
}

/// [`graph`] with the stained-glass panes drawn as `panes` says.
fn graph_with(
    ctx: &GpuContext,
    scene: &Scene,
    lights: &[Light],
    depth: u32,
    panes: PaneLight,
) -> FrameGraph {
    let hdr = ctx.hdr_format();
    let mut graph = FrameGraph::new(ctx, OUTPUT_FORMAT)
        .unwrap()
        .with_direct(ctx, hdr)
        .unwrap()
        .with_shadow_volumes(ctx, hdr, scene, lights)
        .unwrap();
    if depth > 0 {
        graph = graph
            .with_virtual_lights(
                ctx,
                scene,
                VirtualLightSettings {
                    depth,
                    shadows: SpecularShadows::All,
                    panes,
                },
            )
            .unwrap();
    }
    graph
}

/// One frame's HDR radiance and surface ids through [`graph`].
fn render(
    ctx: &GpuContext,
    scene: &Scene,
    camera: &Camera,
    lights: &[Light],
    depth: u32,
) -> (Vec<[f32; 4]>, Vec<u32>) {
    render_with(
        ctx,
        &graph(ctx, scene, lights, depth),
        scene,
        camera,
        lights,
    )
}

/// One frame of `graph`'s HDR radiance and surface ids.
fn render_with(
    ctx: &GpuContext,
    graph: &FrameGraph,
    scene: &Scene,
    camera: &Camera,
    lights: &[Light],
) -> (Vec<[f32; 4]>, Vec<u32>) {
    support::direct_frame(ctx, graph, scene, camera, lights, SIZE)
}

/// The CPU twins: the real lights' direct light with BVH shadow rays, and
/// the virtual lights' of chains up to `depth` along unfolded paths.
fn cpu_twin(
    scene: &Scene,
    lights: &[Light],
    faces: &[lustre_mpr::passes::specular::SpecularFace],
    windows: &[Window],
    depth: u32,
    bvh: &Bvh,
    camera: &Camera,
) -> (Vec<DirectPixel>, Vec<DirectPixel>) {
    let real =
        direct_pixels_cpu_with_lights(scene, lights, bvh, camera, SIZE, SIZE, GlossyModel::Exact)
            .unwrap();
    let virt = virtual_direct_pixels_cpu(
        scene,
        lights,
        faces,
        windows,
        depth,
        bvh,
        camera,
        SIZE,
        SIZE,
        GlossyModel::Exact,
    )
    .unwrap();
    (real, virt)
}

/// `(agree, compared, pixels where the virtual lights add ≥ 5 %)` of `gpu`
/// against `real + virtual` over pixels whose 5×5 neighbourhood shows one
/// surface and one set of reaching lights on the CPU, and the same surface on the GPU.
fn agreement(
    gpu: &[[f32; 4]],
    ids: &[u32],
    real: &[DirectPixel],
    virt: &[DirectPixel],
) -> (usize, usize, usize) {
    let total = |i: usize| -> [f32; 3] {
        std::array::from_fn(|k| real[i].radiance[k] + virt[i].radiance[k])
    };
    let max = (0..real.len()).flat_map(&total).fold(0.0f32, f32::max);
    let s = SIZE as i32;
    let (mut agree, mut compared, mut lit_virtually) = (0, 0, 0);
    for y in 2..s - 2 {
        for x in 2..s - 2 {
            let i = (y * s + x) as usize;
            if real[i].surface == NO_SURFACE {
                continue;
            }
            let steady = (-2..=2).all(|dy| {
                (-2..=2).all(|dx| {
                    let j = ((y + dy) * s + x + dx) as usize;
                    real[j].surface == real[i].surface
                        && ids[j] == real[i].surface
                        && real[j].visible == real[i].visible
                        && virt[j].visible == virt[i].visible
                })
            });
            if !steady {
                continue;
            }
            let expected = total(i);
            compared += 1;
            let v = virt[i].radiance.iter().sum::<f32>();
            lit_virtually += usize::from(v >= 0.05 * expected.iter().sum::<f32>() && v > 0.0);
            // The direct tests' tolerance: f32 shading, 1e-3 relative plus 1e-4 of the maximum.
            agree += usize::from(
                (0..3).all(|k| (gpu[i][k] - expected[k]).abs() <= 1e-3 * expected[k] + 1e-4 * max),
            );
        }
    }
    (agree, compared, lit_virtually)
}

/// Virtual lights through the glass of `bathroom`'s shower door (a slab:
/// the paraxial shift of section 4.2) and its vanity mirror light it as the
/// unfolded paths do, seen from inside the shower, where the overhead
/// light falls through the door onto the tub and the tiles.
#[test]
fn virtual_lights_through_glass_match_unfolded_light_paths() {
    let Some(ctx) = gpu_or_skip("virtual_lights_through_glass_match_unfolded_light_paths") else {
        return;
    };
    let scene = builtin::bathroom();
    let bvh = Bvh::build(&scene);
    let lights = jittered_point_lights(scene.lights(), 1, Vec2::ZERO);
    let faces = specular_faces(&scene);
    let slabs = faces
        .iter()
        .filter(|f| {
            matches!(
                f.kind,
                lustre_mpr::passes::specular::SpecularKind::Slab { .. }
            )
        })
        .count();
    assert!(slabs >= 2, "{slabs} slab faces");
    let camera = Camera::look_at(
        glam::Vec3::new(1.35, 1.7, 0.2),
        glam::Vec3::new(1.1, 0.3, -1.2),
        glam::Vec3::Y,
        70.0,
    )
    .with_aspect(1.0);
    let (real, virt) = cpu_twin(&scene, &lights, &faces, &[], 1, &bvh, &camera);
    let (gpu, ids) = render(&ctx, &scene, &camera, &lights, 1);
    let (agree, compared, lit) = agreement(&gpu, &ids, &real, &virt);
    eprintln!(
        "bathroom: {agree}/{compared} pixels agree, \
         {lit} of them with >= 5 % of their light from virtual lights"
    );
    assert!(compared > (SIZE * SIZE / 4) as usize, "{compared} compared");
    assert!(lit > compared / 20, "virtual lights matter in {lit} pixels");
    assert!(
        agree as f64 >= 0.995 * compared as f64,
        "{agree}/{compared}"
    );
}

/// Virtual lights through one and two mirrors light `mirrors` as the
/// unfolded ray paths do, from the scene camera and from a camera looking
/// at the wall behind the ball, where the reflected light of both mirrors
/// and the ball's and pedestal's bent shadows fall.
#[test]
fn virtual_lights_match_unfolded_light_paths() {
    let Some(ctx) = gpu_or_skip("virtual_lights_match_unfolded_light_paths") else {
        return;
    };
    let scene = builtin::mirrors();
    let bvh = Bvh::build(&scene);
    let lights = jittered_point_lights(scene.lights(), 1, Vec2::ZERO);
    let faces = specular_faces(&scene);
    assert_eq!(faces.len(), 2);
    let back_wall = Camera::look_at(
        glam::Vec3::new(0.6, 1.2, 1.4),
        glam::Vec3::new(-0.6, 0.5, -1.5),
        glam::Vec3::Y,
        75.0,
    );
    for (name, camera) in [
        ("scene camera", scene.camera().with_aspect(1.0)),
        ("back wall", back_wall.with_aspect(1.0)),
    ] {
        for depth in [1, 2] {
            let paths = specular_paths(
                &faces,
                lustre_geometry::shadow_volume::light_position(&lights[0]),
                depth,
            );
            assert_eq!(paths.len(), 2 * depth as usize);
            let (real, virt) = cpu_twin(&scene, &lights, &faces, &[], depth, &bvh, &camera);
            let (gpu, ids) = render(&ctx, &scene, &camera, &lights, depth);
            let (agree, compared, lit) = agreement(&gpu, &ids, &real, &virt);
            eprintln!(
                "{name}, depth {depth}: {agree}/{compared} pixels agree, \
                 {lit} of them with >= 5 % of their light from virtual lights"
            );
            assert!(
                compared > (SIZE * SIZE / 3) as usize,
                "{name}: {compared} compared"
            );
            assert!(
                lit > compared / 5,
                "{name}: virtual lights matter in {lit} pixels"
            );
            assert!(
                agree as f64 >= 0.995 * compared as f64,
                "{name}, depth {depth}: {agree}/{compared}"
            );
            if depth == 1 {
                // Without virtual lights the same comparison fails.
                let (plain, plain_ids) = render(&ctx, &scene, &camera, &lights, 0);
                let (agree, compared, _) = agreement(&plain, &plain_ids, &real, &virt);
                assert!(
                    (agree as f64) < 0.9 * compared as f64,
                    "{name}: {agree}/{compared} agree without virtual lights"
                );
            }
        }
    }
}

/// Moving the pedestal and ball rebuilds the volumes, the virtual lights'
/// with them (section 4.3: regenerated when an object moves), and the frame
/// then matches the unfolded paths of the moved scene.
#[test]
fn virtual_lights_follow_a_moved_object() {
    let Some(ctx) = gpu_or_skip("virtual_lights_follow_a_moved_object") else {
        return;
    };
    let mut scene = builtin::mirrors();
    let lights = jittered_point_lights(scene.lights(), 1, Vec2::ZERO);
    let mut graph = graph(&ctx, &scene, &lights, 1);
    let before = graph
        .shadow_volumes
        .as_ref()
        .and_then(|v| v.virtual_lights())
        .map(|v| v.byte_size())
        .unwrap();
    for name in ["pedestal", "ball"] {
        let object = scene.objects().iter().position(|o| o.name == name).unwrap() as u32;
        let moved = glam::Affine3A::from_translation(glam::Vec3::new(0.7, 0.0, -0.5))
            * scene.objects()[object as usize].transform;
        scene.set_object_transform(object, moved).unwrap();
    }
    assert_eq!(
        graph.update_shadow_volumes(&ctx, &scene, &lights).unwrap(),
        2
    );
    let after = graph
        .shadow_volumes
        .as_ref()
        .and_then(|v| v.virtual_lights())
        .map(|v| v.byte_size())
        .unwrap();
    eprintln!("virtual light volumes: {before} bytes before, {after} after the move");
    let camera = scene.camera().with_aspect(1.0);
    let bvh = Bvh::build(&scene);
    let faces = specular_faces(&scene);
    let (real, virt) = cpu_twin(&scene, &lights, &faces, &[], 1, &bvh, &camera);
    let (gpu, ids) = render_with(&ctx, &graph, &scene, &camera, &lights);
    let (agree, compared, lit) = agreement(&gpu, &ids, &real, &virt);
    eprintln!("moved: {agree}/{compared} pixels agree, {lit} lit by virtual lights");
    assert!(compared > (SIZE * SIZE / 3) as usize && lit > compared / 5);
    assert!(
        agree as f64 >= 0.995 * compared as f64,
        "{agree}/{compared}"
    );
}

/// An axis-aligned box with outward winding.
fn cuboid(name: &str, min: glam::Vec3, max: glam::Vec3, material: u32) -> Mesh {
    let p = |x: f32, y: f32, z: f32| {
        glam::Vec3::new(
            if x > 0.0 { max.x } else { min.x },
            if y > 0.0 { max.y } else { min.y },
            if z > 0.0 { max.z } else { min.z },
        )
    };
    let corners = [
        p(0., 0., 0.),
        p(1., 0., 0.),
        p(1., 1., 0.),
        p(0., 1., 0.),
        p(0., 0., 1.),
        p(1., 0., 1.),
        p(1., 1., 1.),
        p(0., 1., 1.),
    ];
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
    Mesh::flat(name, &corners, &indices, material)
}

/// A pool: a diffuse floor, an open water surface (η = 1.33, a single
/// interface facing up) half a metre above it, a box under the water and
/// one between the point light and the water.
fn pool() -> Scene {
    use glam::Vec3;
    use lustre_geometry::material::MaterialModel;
    use lustre_geometry::{Material, Mesh, Object, Rgb};
    let materials = vec![
        Material::diffuse("floor", Rgb::new(0.7, 0.7, 0.6)),
        Material::new(
            "water",
            MaterialModel::Dielectric {
                ior: 1.33,
                transmittance: Rgb::ONE,
            },
        ),
        Material::diffuse("box", Rgb::new(0.6, 0.2, 0.2)),
    ];
    let square = |name: &str, y: f32, half: f32, material: u32| {
        let c = [
            Vec3::new(-half, y, -half),
            Vec3::new(-half, y, half),
            Vec3::new(half, y, half),
            Vec3::new(half, y, -half),
        ];
        Mesh::flat(name, &c, &[[0, 1, 2], [0, 2, 3]], material)
    };
    let meshes = vec![
        square("floor", 0.0, 2.0, 0),
        square("water", 0.5, 1.0, 1),
        cuboid(
            "sunk",
            Vec3::new(-0.55, 0.0, 0.15),
            Vec3::new(-0.25, 0.3, 0.45),
            2,
        ),
        cuboid(
            "hanging",
            Vec3::new(0.2, 1.1, -0.1),
            Vec3::new(0.4, 1.3, 0.1),
            2,
        ),
    ];
    let objects = (0..meshes.len() as u32)
        .map(|m| Object {
            name: meshes[m as usize].name.clone(),
            meshes: vec![m],
            transform: glam::Affine3A::IDENTITY,
        })
        .collect();
    let light = Light::Point(lustre_geometry::light::PointLight {
        position: Vec3::new(0.2, 2.0, 0.1),
        intensity: Rgb::splat(4.0),
    });
    let camera = Camera::look_at(
        Vec3::new(0.9, 0.4, 0.9),
        Vec3::new(-0.3, 0.0, -0.3),
        Vec3::Y,
        70.0,
    );
    Scene::new("pool", meshes, materials, objects, vec![light], camera).unwrap()
}

/// Light refracted by a single interface (the water surface, paraxially:
/// the light seen from under water at η times its height) lights the pool
/// floor as the unfolded paths do, with the shadow of the box above the
/// water (bent by the surface: section 4.3's transformed volume) and of the
/// sunk box (cast from the virtual light); the real light reaches nothing
/// under the water.
#[test]
fn virtual_lights_through_a_single_interface_match_unfolded_light_paths() {
    let Some(ctx) = gpu_or_skip("virtual_lights_through_a_single_interface") else {
        return;
    };
    let scene = pool();
    let bvh = Bvh::build(&scene);
    let lights = scene.lights().to_vec();
    let faces = specular_faces(&scene);
    assert_eq!(faces.len(), 2);
    let paths = specular_paths(&faces, glam::Vec3::new(0.2, 2.0, 0.1), 2);
    assert_eq!(
        paths.len(),
        1,
        "only the turned-round face lets the light under water"
    );
    let camera = scene.camera().with_aspect(1.0);
    let (real, virt) = cpu_twin(&scene, &lights, &faces, &[], 1, &bvh, &camera);
    let shadowed = (0..virt.len())
        .filter(|&i| real[i].surface == 0 && virt[i].visible == 0)
        .count();
    let (gpu, ids) = render(&ctx, &scene, &camera, &lights, 1);
    let (agree, compared, lit) = agreement(&gpu, &ids, &real, &virt);
    eprintln!(
        "pool: {agree}/{compared} pixels agree, {lit} lit through the water, \
         {shadowed} floor pixels in the refracted light's shadows or outside it"
    );
    assert!(compared > (SIZE * SIZE / 3) as usize, "{compared} compared");
    assert!(
        lit > compared / 3 && shadowed > 200,
        "{lit} lit, {shadowed} shadowed"
    );
    assert!(
        agree as f64 >= 0.995 * compared as f64,
        "{agree}/{compared}"
    );
}

/// Light through `stained-glass`'s window as one light volume modulated by
/// the window's projective texture (section 4.5) matches the CPU twin that
/// finds the pane each unfolded path crosses and applies its filter and the
/// thin slab's Fresnel transmittance at that angle (lustre-brdf's
/// `ThinDielectric`), over the floor's coloured patches away from pane
/// edges (where the texture's bilinear filter and the exact pane lookup
/// differ within a texel, and which the 5×5 rule leaves out by requiring
/// one colour). One light volume per pane (the uniform faces of 4.2) gives
/// the same image there.
#[test]
fn stained_glass_light_matches_the_panes_it_passes() {
    let Some(ctx) = gpu_or_skip("stained_glass_light_matches_the_panes_it_passes") else {
        return;
    };
    let scene = builtin::stained_glass::stained_glass();
    let bvh = Bvh::build(&scene);
    let lights = jittered_point_lights(scene.lights(), 1, Vec2::ZERO);
    let windows = windows(&scene, PaneLight::default()).unwrap();
    assert_eq!(windows.len(), 1);
    let mut faces = specular_faces(&scene);
    faces.extend(window_faces(&windows));
    // Looking down at the floor where the window's light falls.
    let camera = Camera::look_at(
        glam::Vec3::new(0.0, 2.6, 3.6),
        glam::Vec3::new(0.1, 0.0, 1.6),
        glam::Vec3::Y,
        60.0,
    )
    .with_aspect(1.0);
    let (real, virt) = cpu_twin(&scene, &lights, &faces, &windows, 1, &bvh, &camera);
    // One colour per neighbourhood: the same chromaticity of virtual light.
    let chroma = |p: &DirectPixel| {
        let sum: f32 = p.radiance.iter().sum();
        (sum > 0.0).then(|| [p.radiance[0] / sum, p.radiance[1] / sum])
    };
    let s = SIZE as i32;
    let one_colour = |i: usize| {
        let (x, y) = (i as i32 % s, i as i32 / s);
        let c = chroma(&virt[i]);
        (-2..=2).all(|dy| {
            (-2..=2).all(|dx| {
                let (xx, yy) = (x + dx, y + dy);
                if xx < 0 || yy < 0 || xx >= s || yy >= s {
                    return false;
                }
                match (c, chroma(&virt[(yy * s + xx) as usize])) {
                    (None, None) => true,
                    (Some(a), Some(b)) => (a[0] - b[0]).abs() < 1e-3 && (a[1] - b[1]).abs() < 1e-3,
                    _ => false,
                }
            })
        })
    };
    let masked = |v: &[DirectPixel]| -> Vec<DirectPixel> {
        v.iter()
            .enumerate()
            .map(|(i, p)| DirectPixel {
                surface: if one_colour(i) { p.surface } else { NO_SURFACE },
                ..*p
            })
            .collect()
    };
    let (real_m, virt_m) = (masked(&real), masked(&virt));
    let colours: std::collections::BTreeSet<[i32; 2]> = virt_m
        .iter()
        .filter(|p| p.surface != NO_SURFACE)
        .filter_map(chroma)
        .map(|c| [(c[0] * 100.0).round() as i32, (c[1] * 100.0).round() as i32])
        .collect();
    for (name, panes) in [
        ("projective texture", PaneLight::default()),
        ("one light volume per pane", PaneLight::PerPane),
    ] {
        let graph = graph_with(&ctx, &scene, &lights, 1, panes);
        let (gpu, ids) = render_with(&ctx, &graph, &scene, &camera, &lights);
        let (agree, compared, lit) = agreement(&gpu, &ids, &real_m, &virt_m);
        eprintln!(
            "stained glass, {name}: {agree}/{compared} pixels agree, {lit} of them lit through \
             the window, {} colours",
            colours.len()
        );
        assert!(compared > (SIZE * SIZE / 4) as usize, "{compared} compared");
        assert!(lit > compared / 5, "the window lights {lit} pixels");
        assert!(colours.len() >= 5, "{colours:?}");
        assert!(
            agree as f64 >= 0.995 * compared as f64,
            "{name}: {agree}/{compared}"
        );
    }
    // Without virtual lights the window's light is missing.
    let plain = graph_with(&ctx, &scene, &lights, 1, PaneLight::Off);
    let (gpu, ids) = render_with(&ctx, &plain, &scene, &camera, &lights);
    let (agree, compared, _) = agreement(&gpu, &ids, &real_m, &virt_m);
    assert!(
        (agree as f64) < 0.9 * compared as f64,
        "{agree}/{compared} agree without the window's light"
    );
}

/// A quad `corner + s u + t v` facing `u × v`, two triangles.
fn quad(name: &str, corner: glam::Vec3, u: glam::Vec3, v: glam::Vec3, material: u32) -> Mesh {
    Mesh::flat(
        name,
        &[corner, corner + u, corner + u + v, corner + v],
        &[[0, 1, 2], [2, 3, 0]],
        material,
    )
}

/// Stained glass on chains with mirrors (section 4.5 with 4.2, figure
/// 10's real and virtual sources through one window): `stained-glass` with
/// a mirror behind the light outside (its virtual light shines through the
/// window: the projector from the mirrored light) and a mirror on the floor
/// inside (the window's coloured light reflected onto a back wall: the
/// projector taken back through the floor mirror), at shadow depth 3,
/// against the CPU twin's unfolded paths.
#[test]
fn stained_glass_through_mirrors_matches_the_unfolded_paths() {
    let Some(ctx) = gpu_or_skip("stained_glass_through_mirrors_matches_the_unfolded_paths") else {
        return;
    };
    use glam::Vec3;
    let base = builtin::stained_glass::stained_glass();
    let mut meshes = base.meshes().to_vec();
    let mut materials = base.materials().to_vec();
    let mirror = materials.len() as u32;
    materials.push(lustre_geometry::Material::new(
        "mirror",
        lustre_geometry::material::MaterialModel::Mirror {
            reflectance: lustre_geometry::Rgb::splat(0.9),
        },
    ));
    let wall = 1;
    let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
    // Outside, behind the light (z = -2), facing the window.
    meshes.push(quad(
        "mirror-outside",
        Vec3::new(-1.5, 0.5, -3.0),
        3.0 * x,
        4.0 * y,
        mirror,
    ));
    // On the floor under the window's light, facing up (a hair above it).
    meshes.push(quad(
        "mirror-floor",
        Vec3::new(-0.5, 0.002, 1.1),
        1.0 * z,
        1.0 * x,
        mirror,
    ));
    // A back wall at z = 4 facing the window, to receive the reflection.
    meshes.push(quad(
        "back-wall",
        Vec3::new(2.0, 0.0, 4.0),
        -4.0 * x,
        4.0 * y,
        wall,
    ));
    let objects = lustre_geometry::Object::one_per_mesh(&meshes);
    let camera = Camera::look_at(
        Vec3::new(0.0, 1.2, 0.6),
        Vec3::new(0.0, 1.0, 4.0),
        Vec3::Y,
        80.0,
    )
    .with_aspect(1.0);
    let scene = Scene::new(
        "stained-glass-mirrors",
        meshes,
        materials,
        objects,
        base.lights().to_vec(),
        camera,
    )
    .unwrap();
    let bvh = Bvh::build(&scene);
    let lights = jittered_point_lights(scene.lights(), 1, Vec2::ZERO);
    let windows = windows(&scene, PaneLight::default()).unwrap();
    let mut faces = specular_faces(&scene);
    faces.extend(window_faces(&windows));
    let depth = 3;
    let paths = specular_paths(
        &faces,
        lustre_geometry::shadow_volume::light_position(&lights[0]),
        depth,
    );
    let chains: Vec<Vec<&str>> = paths
        .iter()
        .map(|p| {
            p.faces
                .iter()
                .map(|&f| match faces[f].kind {
                    lustre_mpr::passes::specular::SpecularKind::Pane { .. } => "window",
                    _ => scene.meshes()[scene.surfaces()[faces[f].surface as usize].mesh as usize]
                        .name
                        .as_str(),
                })
                .collect()
        })
        .collect();
    for want in [
        vec!["mirror-outside", "window"],
        vec!["window", "mirror-floor"],
        vec!["mirror-outside", "window", "mirror-floor"],
    ] {
        assert!(chains.contains(&want), "{want:?} not in {chains:?}");
    }
    let (real, virt) = cpu_twin(&scene, &lights, &faces, &windows, depth, &bvh, &camera);
    // Compare where one chain's colour fills the neighbourhood (as above).
    let s = SIZE as i32;
    let steady_colour = |i: usize| {
        let (px, py) = (i as i32 % s, i as i32 / s);
        let c = virt[i].radiance;
        let sum: f32 = c.iter().sum();
        (-2..=2).all(|dy| {
            (-2..=2).all(|dx| {
                let (xx, yy) = (px + dx, py + dy);
                if xx < 0 || yy < 0 || xx >= s || yy >= s {
                    return false;
                }
                let d = virt[(yy * s + xx) as usize].radiance;
                let dsum: f32 = d.iter().sum();
                (sum == 0.0 && dsum == 0.0)
                    || (sum > 0.0
                        && dsum > 0.0
                        && (0..2).all(|k| (c[k] / sum - d[k] / dsum).abs() < 1e-3))
            })
        })
    };
    let masked = |v: &[DirectPixel]| -> Vec<DirectPixel> {
        v.iter()
            .enumerate()
            .map(|(i, p)| DirectPixel {
                surface: if steady_colour(i) {
                    p.surface
                } else {
                    NO_SURFACE
                },
                ..*p
            })
            .collect()
    };
    let (real_m, virt_m) = (masked(&real), masked(&virt));
    let graph = graph_with(&ctx, &scene, &lights, depth, PaneLight::default());
    let (gpu, ids) = render_with(&ctx, &graph, &scene, &camera, &lights);
    let (agree, compared, lit) = agreement(&gpu, &ids, &real_m, &virt_m);
    eprintln!(
        "stained glass with mirrors: {agree}/{compared} pixels agree, {lit} lit by virtual lights, \
         chains {chains:?}"
    );
    // Each chain through the window lights some of the compared pixels.
    let lit_by = |chain: &[&str]| {
        let c = chains.iter().position(|c| c == chain).unwrap();
        virt_m
            .iter()
            .filter(|p| p.surface != NO_SURFACE && p.visible & (1 << c) != 0)
            .count()
    };
    for chain in [
        &["window"][..],
        &["mirror-outside", "window"],
        &["window", "mirror-floor"],
        &["mirror-outside", "window", "mirror-floor"],
    ] {
        let n = lit_by(chain);
        eprintln!("{chain:?}: {n} compared pixels");
        assert!(n > 20, "{chain:?} lights {n} compared pixels");
    }
    assert!(
        compared > (SIZE * SIZE / 10) as usize,
        "{compared} compared"
    );
    assert!(lit > compared / 10, "virtual lights light {lit} pixels");
    assert!(
        agree as f64 >= 0.995 * compared as f64,
        "{agree}/{compared}"
    );
}
