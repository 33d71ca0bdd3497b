//! Artifact Control (section 1.2.1): reachable areas against the analytic areas of discs cut by a wall and by a corner, the concave extension, and DETP with and without Artifact Control against the analytic irradiance `I cos θ / d²` of a point light.

use std::f64::consts::PI;

use glam::{Affine3A, Vec3};
use lustre_density::artifact::{
    ArtifactOptions, artifact_controlled_detp, extend_ray_set, extension, inward_directions,
    is_concave, mesh_triangles, reachable_area, reachable_area_near, reachable_areas,
};
use lustre_density::triangle_grid::TriangleGrid;
use lustre_density::{
    DensityError, Disc, RaySegment, RaySet, RaySetOptions, SegmentHit, detp, trace_ray_set,
};
use lustre_geometry::light::PointLight;
use lustre_geometry::{Bvh, Camera, Light, Material, Mesh, Object, Rgb, Scene, builtin};

/// Allowed deviation from the expectation, in standard deviations of the estimator's noise.
const SIGMAS: f64 = 5.0;
/// Intensity `I` of the point lights (W/sr).
const INTENSITY: f64 = 1.0;
/// Photons of the DETP tests.
const PHOTONS: u64 = 300_000;

/// A black (absorbing) scene of the given meshes, one object each, under an isotropic point light.
fn black_scene(meshes: Vec<Mesh>, light: Vec3) -> Scene {
    let objects = (0..meshes.len())
        .map(|i| Object {
            name: format!("object-{i}"),
            meshes: vec![i as u32],
            transform: Affine3A::IDENTITY,
        })
        .collect();
    Scene::new(
        "artifact",
        meshes,
        vec![Material::diffuse("black", Rgb::ZERO)],
        objects,
        vec![Light::Point(PointLight {
            position: light,
            intensity: Rgb::splat(INTENSITY as f32),
        })],
        Camera::look_at(Vec3::new(0.0, 3.0, 3.0), Vec3::ZERO, Vec3::Y, 40.0),
    )
    .expect("valid scene")
}

/// The floor `y = 0`, `[-2, 2]²`, facing +y, as a fan around `centre` so that it is a vertex.
fn floor_fan(centre: Vec3) -> Mesh {
    let positions = [
        centre,
        Vec3::new(-2.0, 0.0, -2.0),
        Vec3::new(-2.0, 0.0, 2.0),
        Vec3::new(2.0, 0.0, 2.0),
        Vec3::new(2.0, 0.0, -2.0),
    ];
    Mesh::flat(
        "floor",
        &positions,
        &[[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 1]],
        0,
    )
}

/// A quad `[a, b, c, d]` (counter-clockwise seen from its front).
fn quad(name: &str, corners: [Vec3; 4]) -> Mesh {
    Mesh::flat(name, &corners, &[[0, 1, 2], [2, 3, 0]], 0)
}

/// The wall `x = d` facing −x (towards the origin).
fn wall_x(d: f32) -> Mesh {
    quad(
        "wall-x",
        [
            Vec3::new(d, -0.5, -2.0),
            Vec3::new(d, -0.5, 2.0),
            Vec3::new(d, 3.0, 2.0),
            Vec3::new(d, 3.0, -2.0),
        ],
    )
}

/// The wall `z = d` facing −z (towards the origin).
fn wall_z(d: f32) -> Mesh {
    quad(
        "wall-z",
        [
            Vec3::new(-2.0, -0.5, d),
            Vec3::new(-2.0, 3.0, d),
            Vec3::new(2.0, 3.0, d),
            Vec3::new(2.0, -0.5, d),
        ],
    )
}

/// Area of the part of the disc of radius `r` at the origin beyond the line `x = d`: `r² acos(d/r) − d √(r² − d²)`.
fn segment_area(r: f64, d: f64) -> f64 {
    if d >= r {
        0.0
    } else if d <= -r {
        PI * r * r
    } else {
        r * r * (d / r).acos() - d * (r * r - d * d).sqrt()
    }
}

/// Area of the part of the disc beyond both `x = a` and `z = b` (midpoint rule on 20 000 strips of the exact chord lengths).
fn quadrant_area(r: f64, a: f64, b: f64) -> f64 {
    let (lo, hi) = (a.max(-r), r);
    if lo >= hi {
        return 0.0;
    }
    let n = 20_000;
    let h = (hi - lo) / n as f64;
    (0..n)
        .map(|i| {
            let x = lo + (i as f64 + 0.5) * h;
            let half = (r * r - x * x).max(0.0).sqrt();
            (half - b.max(-half)).max(0.0)
        })
        .sum::<f64>()
        * h
}

/// Reachable area of the disc at the origin with walls at `x = a` and `z = b` (inclusion–exclusion).
fn corner_area(r: f64, a: f64, b: f64) -> f64 {
    PI * r * r - segment_area(r, a) - segment_area(r, b) + quadrant_area(r, a, b)
}

fn floor_disc(centre: Vec3, radius: f32) -> Disc {
    Disc {
        centre,
        normal: Vec3::Y,
        radius,
        mesh: Some(0),
    }
}

#[test]
fn reachable_area_matches_a_disc_cut_by_one_wall() {
    let r = 0.3f32;
    let full = PI * (r as f64).powi(2);
    for n in [16u32, 32, 64] {
        let options = ArtifactOptions {
            samples_per_axis: n,
            ..ArtifactOptions::default()
        };
        let mut worst: f64 = 0.0;
        for k in 0..=24 {
            let d = r * (k as f32 / 12.0 - 1.0) * 1.1;
            let scene = black_scene(
                vec![floor_fan(Vec3::ZERO), wall_x(d)],
                Vec3::new(-1.0, 1.0, 0.0),
            );
            let bvh = Bvh::build(&scene);
            let area = reachable_area(
                &bvh,
                &floor_disc(Vec3::ZERO, r),
                mesh_triangles(&scene, 0),
                Vec3::ZERO,
                &options,
            )
            .unwrap() as f64;
            let exact = full - segment_area(r as f64, d.abs() as f64);
            let error = (area - exact) / full;
            worst = worst.max(error.abs());
            if std::env::var_os("ARTIFACT_VERBOSE").is_some() {
                eprintln!("n = {n}, d = {d:.4}: error {error:.5}");
            }
            // The worst case of the module docs: 2.5 boundary cells per axis sample.
            assert!(
                error.abs() <= 2.5 / n as f64,
                "n = {n}, d = {d}: {area} against {exact}"
            );
        }
        eprintln!("one wall, n = {n}: worst |A − A_exact| = {worst:.5} π r²");
        if n >= 32 {
            assert!(worst < 0.005, "{worst}");
        }
    }
    // A wall whose back faces the vertex blocks as well (it is more than the offset away).
    let mut reversed = wall_x(0.1);
    reversed.indices.iter_mut().for_each(|t| t.swap(1, 2));
    let scene = black_scene(
        vec![floor_fan(Vec3::ZERO), reversed],
        Vec3::new(-1.0, 1.0, 0.0),
    );
    let bvh = Bvh::build(&scene);
    let area = reachable_area(
        &bvh,
        &floor_disc(Vec3::ZERO, r),
        mesh_triangles(&scene, 0),
        Vec3::ZERO,
        &ArtifactOptions::default(),
    )
    .unwrap() as f64;
    let exact = full - segment_area(r as f64, 0.1);
    assert!(
        (area - exact).abs() < 0.005 * full,
        "{area} against {exact}"
    );
}

/// A wall standing on the floor through the vertex, facing −x: `x = 0`, `y ∈ [0, 3]`.
fn wall_at_vertex() -> Mesh {
    quad(
        "wall-foot",
        [
            Vec3::new(0.0, 0.0, -2.0),
            Vec3::new(0.0, 0.0, 2.0),
            Vec3::new(0.0, 3.0, 2.0),
            Vec3::new(0.0, 3.0, -2.0),
        ],
    )
}

/// Small discs on the foot of a wall keep half their area, and in a corner a quarter: the visibility paths start `offset · r` from the walls (`4 · 10⁻⁵` m at r = 0.04), closer than the `10⁻⁴` within which the BVH's traversal culls thin boxes (the queries start further back for that reason).
#[test]
fn small_discs_at_a_wall_foot_lose_the_half_behind_it() {
    for r in [0.005f32, 0.02, 0.04, 0.05, 0.1] {
        let one = black_scene(
            vec![floor_fan(Vec3::ZERO), wall_at_vertex()],
            Vec3::new(-1.0, 1.0, 0.0),
        );
        let mut back = quad(
            "wall-back",
            [
                Vec3::new(-2.0, 0.0, 0.0),
                Vec3::new(-2.0, 3.0, 0.0),
                Vec3::new(2.0, 3.0, 0.0),
                Vec3::new(2.0, 0.0, 0.0),
            ],
        );
        back.name = "wall-back".into();
        let corner = black_scene(
            vec![floor_fan(Vec3::ZERO), wall_at_vertex(), back],
            Vec3::new(-1.0, 1.0, -1.0),
        );
        for (scene, expected) in [(one, 0.5), (corner, 0.25)] {
            let bvh = Bvh::build(&scene);
            let area = reachable_area(
                &bvh,
                &floor_disc(Vec3::ZERO, r),
                mesh_triangles(&scene, 0),
                Vec3::ZERO,
                &ArtifactOptions::default(),
            )
            .unwrap();
            let fraction = area / (std::f32::consts::PI * r * r);
            assert!(
                (fraction - expected).abs() < 0.01,
                "r {r}: {fraction} of the disc reachable, expected {expected}"
            );
        }
    }
}

#[test]
fn reachable_area_matches_a_disc_cut_by_a_corner() {
    let r = 0.3f32;
    let full = PI * (r as f64).powi(2);
    let options = ArtifactOptions::default();
    let mut worst: f64 = 0.0;
    for (a, b) in [
        (0.0, 0.0),
        (0.1, 0.05),
        (0.2, -0.1),
        (0.25, 0.25),
        (0.05, 0.28),
        (-0.15, 0.1),
    ] {
        let scene = black_scene(
            vec![floor_fan(Vec3::ZERO), wall_x(a), wall_z(b)],
            Vec3::new(-1.0, 1.0, -1.0),
        );
        let bvh = Bvh::build(&scene);
        let area = reachable_area(
            &bvh,
            &floor_disc(Vec3::ZERO, r),
            mesh_triangles(&scene, 0),
            Vec3::ZERO,
            &options,
        )
        .unwrap() as f64;
        let exact = corner_area(r as f64, (a as f64).abs(), (b as f64).abs());
        let error = (area - exact) / full;
        worst = worst.max(error.abs());
        eprintln!("corner ({a}, {b}): error {error:.5} π r²");
        assert!(
            error.abs() < 0.01,
            "corner ({a}, {b}): {area} against {exact}"
        );
    }
    eprintln!("corner, n = 32: worst |A − A_exact| = {worst:.5} π r²");
}

#[test]
fn cornell_floor_corners_lose_what_lies_behind_the_walls() {
    let scene = builtin("cornell").unwrap();
    let bvh = Bvh::build(&scene);
    let r = 0.2f32;
    let areas = reachable_areas(&scene, &bvh, r, &ArtifactOptions::default()).unwrap();
    assert_eq!(areas.len(), scene.meshes().len());
    for (m, a) in areas.iter().enumerate() {
        assert_eq!(a.len(), scene.meshes()[m].positions.len());
    }
    let full = std::f32::consts::PI * r * r;
    for (p, &a) in scene.world_positions(0).iter().zip(&areas[0]) {
        eprintln!("floor corner {p}: {:.4} π r²", a / full);
        if p.z < 0.0 {
            // The back corners (z = −1) meet two walls: a quarter.
            assert!((a / full - 0.25).abs() < 0.01, "{p}: {}", a / full);
        } else {
            // The front ones (the box is open) sit on the free edge of a side wall: paths from the vertex pass that edge, so the wall cuts at most the half behind its plane.
            assert!(a / full >= 0.49, "{p}: {}", a / full);
        }
    }
}

/// The triangle grid's shortcut (a disc no triangle of another mesh comes near keeps `π r²` without casting a path) gives the area the paths give, at every vertex of the Cornell box meshed at 0.1 m, for radii below, at and above the mesh edge; and it does skip the paths of most vertices.
#[test]
fn grid_shortcut_gives_the_areas_of_the_paths() {
    let base = builtin("cornell").unwrap();
    let meshes = base
        .meshes()
        .iter()
        .map(|m| lustre_geometry::meshing::subdivide(m, 0.1).unwrap())
        .collect();
    let scene = base.with_meshes(meshes).unwrap();
    let bvh = Bvh::build(&scene);
    let options = ArtifactOptions {
        samples_per_axis: 8,
        ..ArtifactOptions::default()
    };
    for r in [0.03f32, 0.04, 0.05, 0.1, 0.15] {
        let grid = TriangleGrid::new(&bvh, 2.0 * r);
        let full = std::f32::consts::PI * r * r;
        let (mut cut, mut compared) = (0, 0);
        for m in 0..scene.meshes().len() as u32 {
            let own = mesh_triangles(&scene, m);
            let positions = scene.world_positions(m);
            let normals = scene.world_normals(m);
            let inward =
                inward_directions(&positions, &normals, &scene.meshes()[m as usize].indices);
            for ((&centre, &normal), &inward) in positions.iter().zip(&normals).zip(&inward) {
                let disc = Disc {
                    centre,
                    normal: normal.normalize(),
                    radius: r,
                    mesh: Some(m),
                };
                let paths = reachable_area(&bvh, &disc, own.clone(), inward, &options).unwrap();
                let gridded =
                    reachable_area_near(&bvh, &grid, &disc, own.clone(), inward, &options).unwrap();
                assert_eq!(gridded, paths, "mesh {m} vertex {centre} r {r}");
                cut += usize::from(paths < full);
                compared += 1;
            }
        }
        let skipped = (0..scene.meshes().len() as u32)
            .flat_map(|m| {
                let own = mesh_triangles(&scene, m);
                scene
                    .world_positions(m)
                    .into_iter()
                    .map(move |c| (c, own.clone()))
            })
            .filter(|(c, own)| !grid.foreign_near(*c, 1.02 * r, own))
            .count();
        eprintln!("r {r}: {cut} of {compared} discs cut, {skipped} skipped by the grid");
        assert!(
            cut > 100,
            "r {r}: only {cut} discs are cut; the test proves little"
        );
        assert!(
            2 * skipped > compared,
            "r {r}: the grid skips only {skipped} of {compared}"
        );
    }
}

/// The concave rule (section 1.2.1) cannot change a crossing on a mesh that is not concave ([`is_concave`]): on the Cornell box, whose walls and boxes are all flat or convex, the ray set leaves every segment unextended, and DETP over it equals DETP over the same segments extended through their meshes; the grooved mesh is concave and its segments are extended.
#[test]
fn convex_meshes_need_no_concave_extension() {
    let base = builtin("cornell").unwrap();
    let meshes = base
        .meshes()
        .iter()
        .map(|m| lustre_geometry::meshing::subdivide(m, 0.25).unwrap())
        .collect();
    let scene = base.with_meshes(meshes).unwrap();
    let epsilon = 2e-5;
    for m in 0..scene.meshes().len() as u32 {
        assert!(
            !is_concave(&scene, m, epsilon),
            "{}",
            scene.meshes()[m as usize].name
        );
    }
    let bvh = Bvh::build(&scene);
    let r = 0.2;
    let options = RaySetOptions {
        photons: 20_000,
        seed: 5,
        max_segments: 8,
        extension: 4.0 * r,
    };
    let rays = trace_ray_set(&scene, &bvh, &options).unwrap();
    assert!(rays.segments().all(|s| s.extension == 0.0));
    let mut extended = rays.clone();
    extend_ray_set(&scene, &bvh, &mut extended, 4.0 * r).unwrap();
    let longer = extended.segments().filter(|s| s.extension > 0.0).count();
    assert!(longer > 10_000, "only {longer} segments extended");
    assert_eq!(
        detp(&scene, &rays, r).unwrap(),
        detp(&scene, &extended, r).unwrap()
    );
    // A groove is concave, and the ray set extends the segments that hit it.
    let groove = black_scene(vec![groove_mesh()], Vec3::new(0.0, 1.0, 0.0));
    assert!(is_concave(&groove, 0, epsilon));
    let bvh = Bvh::build(&groove);
    let rays = trace_ray_set(&groove, &bvh, &options).unwrap();
    assert!(rays.segments().any(|s| s.extension > 0.0));
}

#[test]
fn extension_follows_the_own_mesh_until_another() {
    // A V-groove (one mesh) over a floor (another mesh) 0.5 below the crease.
    let groove = groove_mesh();
    let floor = quad(
        "floor",
        [
            Vec3::new(-2.0, -0.5, -2.0),
            Vec3::new(-2.0, -0.5, 2.0),
            Vec3::new(2.0, -0.5, 2.0),
            Vec3::new(2.0, -0.5, -2.0),
        ],
    );
    let scene = black_scene(vec![groove, floor], Vec3::new(-0.6, 1.0, 0.1));
    let bvh = Bvh::build(&scene);
    let own = mesh_triangles(&scene, 0);
    assert_eq!(own, 0..6);
    assert_eq!(mesh_triangles(&scene, 1), 6..8);
    let shoot = |origin: Vec3, direction: Vec3| -> RaySegment {
        let direction = direction.normalize();
        let hit = bvh
            .closest_hit(&lustre_geometry::Ray::new(origin, direction))
            .unwrap();
        RaySegment::new(
            origin,
            direction,
            Some(SegmentHit {
                triangle: hit.triangle,
                mesh: scene.triangle_source(hit.triangle).0,
                mobile: false,
                position: hit.position,
                normal: hit.geometric_normal,
                distance: hit.t,
            }),
            Rgb::ONE,
        )
    };
    // Straight down onto the rising face at x = 0.3 (y = 0.3): through it, 0.8 to the floor.
    let s = shoot(Vec3::new(0.3, 2.0, 0.0), -Vec3::Y);
    assert!((s.hit.unwrap().distance - 1.7).abs() < 1e-5);
    assert!((extension(&bvh, &s, own.clone(), 10.0) - 0.8).abs() < 1e-4);
    // The cap.
    assert_eq!(extension(&bvh, &s, own.clone(), 0.25), 0.25);
    // Down onto the flat face at x = −0.5: 0.5 to the floor.
    let s = shoot(Vec3::new(-0.5, 2.0, 0.0), -Vec3::Y);
    assert!((extension(&bvh, &s, own.clone(), 10.0) - 0.5).abs() < 1e-4);
    // A slanted ray through the rising face meets the floor next: its remaining path to y = −0.5.
    let d = Vec3::new(-1.0, -2.0, 0.0).normalize();
    let s = shoot(Vec3::new(1.5, 2.0, 0.0), d);
    assert!((s.hit.unwrap().position - Vec3::ONE.with_z(0.0)).length() < 1e-5);
    let expected = (s.hit.unwrap().position.y + 0.5) / -d.y;
    assert!((extension(&bvh, &s, own.clone(), 10.0) - expected).abs() < 1e-4);
    // A segment that hit the floor gets no extension through the groove's range, and none without a hit.
    let s = shoot(Vec3::new(1.9, 0.0, 0.0), -Vec3::Y);
    assert_eq!(s.hit.unwrap().mesh, 1);
    assert_eq!(extension(&bvh, &s, own.clone(), 10.0), 0.0);
    // Through the floor (its own mesh) nothing else follows: the cap.
    assert_eq!(extension(&bvh, &s, mesh_triangles(&scene, 1), 3.0), 3.0);
    let miss = RaySegment::new(Vec3::ZERO, Vec3::Y, None, Rgb::ONE);
    assert_eq!(extension(&bvh, &miss, own.clone(), 10.0), 0.0);
    assert_eq!(extension(&bvh, &s, own, f32::NAN), 0.0);
}

/// The V-groove: a flat face `y = 0`, `x ∈ [−2, 0]` fanned around `(−D, 0, 0)`, and a face rising at 45° from the crease `x = 0`, in one mesh.
fn groove_mesh() -> Mesh {
    let c = Vec3::new(-GROOVE_D, 0.0, 0.0);
    let l = 2.0 * std::f32::consts::FRAC_1_SQRT_2;
    let positions = [
        c,
        Vec3::new(-2.0, 0.0, -2.0),
        Vec3::new(-2.0, 0.0, 2.0),
        Vec3::new(0.0, 0.0, 2.0),
        Vec3::new(0.0, 0.0, -2.0),
        Vec3::new(l, l, 2.0),
        Vec3::new(l, l, -2.0),
    ];
    Mesh::flat(
        "groove",
        &positions,
        &[
            [0, 1, 2],
            [0, 2, 3],
            [0, 3, 4],
            [0, 4, 1],
            [4, 3, 5],
            [5, 6, 4],
        ],
        0,
    )
}

/// Distance of the test vertex from the crease.
const GROOVE_D: f32 = 0.1;

/// `∫ E dA` over the part of the disc of radius `r` at `(cx, cz)` on `y = 0` with `x < cx + a` and `z < cz + b`, for the point light at `light`; `E = I h / dist³` (`I cos θ / d²`). Midpoint rule on 600 × 600 strips with exact chord limits.
fn flux_integral(light: Vec3, cx: f64, cz: f64, r: f64, a: f64, b: f64) -> f64 {
    let (lx, h, lz) = (light.x as f64, light.y as f64, light.z as f64);
    let e = |x: f64, z: f64| {
        let d2 = (x - lx).powi(2) + h * h + (z - lz).powi(2);
        INTENSITY * h / (d2 * d2.sqrt())
    };
    let n = 600;
    let x_hi = a.min(r);
    if x_hi <= -r {
        return 0.0;
    }
    let hx = (x_hi + r) / n as f64;
    let mut sum = 0.0;
    for i in 0..n {
        let x = -r + (i as f64 + 0.5) * hx;
        let half = (r * r - x * x).max(0.0).sqrt();
        let z_hi = half.min(b);
        if z_hi <= -half {
            continue;
        }
        let hz = (z_hi + half) / n as f64;
        for j in 0..n {
            let z = -half + (j as f64 + 0.5) * hz;
            sum += e(cx + x, cz + z) * hz;
        }
    }
    sum * hx
}

/// The analytic irradiance `I cos θ / d²` at a point of `y = 0`.
fn analytic(light: Vec3, p: Vec3) -> f64 {
    let d = (light - p).as_dvec3();
    INTENSITY * d.y / d.length().powi(3)
}

fn trace(scene: &Scene, bvh: &Bvh) -> RaySet {
    trace_ray_set(
        scene,
        bvh,
        &RaySetOptions {
            photons: PHOTONS,
            seed: 11,
            max_segments: 4,
            extension: 0.0,
        },
    )
    .unwrap()
}

/// Index of the first vertex of mesh 0 at `p`.
fn vertex_at(scene: &Scene, p: Vec3) -> usize {
    scene
        .world_positions(0)
        .iter()
        .position(|&q| q.distance(p) < 1e-6)
        .expect("the test vertex")
}

/// Plain DETP and DETP with Artifact Control at the floor vertex at the origin with walls at `x = a` (and `z = b` when given), against their expectations and the analytic irradiance.
fn check_walls(a: f32, b: Option<f32>) {
    let r = 0.3f32;
    let light = Vec3::new(-0.4, 1.0, -0.3);
    let mut meshes = vec![floor_fan(Vec3::ZERO), wall_x(a)];
    if let Some(b) = b {
        meshes.push(wall_z(b));
    }
    let scene = black_scene(meshes, light);
    let bvh = Bvh::build(&scene);
    let rays = trace(&scene, &bvh);
    let options = ArtifactOptions::default();
    let v = vertex_at(&scene, Vec3::ZERO);
    let plain = detp(&scene, &rays, r).unwrap()[0][v].x as f64;
    let controlled =
        artifact_controlled_detp(&scene, &bvh, &rays, r, &options).unwrap()[0][v].x as f64;
    let area = reachable_areas(&scene, &bvh, r, &options).unwrap()[0][v] as f64;
    let (rf, bf) = (r as f64, b.map_or(f64::INFINITY, |b| b as f64));
    let integral = flux_integral(light, 0.0, 0.0, rf, a as f64, bf);
    let full = PI * rf * rf;
    let phi = 4.0 * PI * INTENSITY / PHOTONS as f64;
    let exact = analytic(light, Vec3::ZERO);
    let (mean_plain, sigma_plain) = (integral / full, (phi * integral).sqrt() / full);
    let (mean_ac, sigma_ac) = (integral / area, (phi * integral).sqrt() / area);
    let reach = corner_area(rf, a as f64, bf) / full;
    eprintln!(
        "walls x = {a}, z = {b:?}: E = {exact:.5}, plain {plain:.5} ({:.3} E, reachable fraction {reach:.3}), controlled {controlled:.5} ({:.3} E, expected {:.3} E ± {:.4} E)",
        plain / exact,
        controlled / exact,
        mean_ac / exact,
        sigma_ac / exact
    );
    assert!(
        (plain - mean_plain).abs() <= SIGMAS * sigma_plain,
        "plain {plain} against {mean_plain} ± {sigma_plain}"
    );
    assert!(
        (controlled - mean_ac).abs() <= SIGMAS * sigma_ac,
        "controlled {controlled} against {mean_ac} ± {sigma_ac}"
    );
    // Plain DETP underestimates by the reachable fraction; Artifact Control removes it, up to the disc-mean bias.
    let disc_bias = (integral / (reach * full) - exact).abs();
    assert!((plain / controlled - area / full).abs() < 1e-5);
    assert!((controlled - exact).abs() <= disc_bias + 0.005 * exact + SIGMAS * sigma_ac);
    assert!((controlled - exact).abs() < 0.25 * (plain - exact).abs());
}

#[test]
fn artifact_control_removes_the_wall_bias() {
    check_walls(0.1, None);
}

#[test]
fn artifact_control_removes_the_corner_bias() {
    check_walls(0.12, Some(0.05));
}

#[test]
fn artifact_control_counts_rays_through_a_concave_mesh() {
    let r = 0.3f32;
    let light = Vec3::new(-0.6, 1.0, 0.1);
    let scene = black_scene(vec![groove_mesh()], light);
    let bvh = Bvh::build(&scene);
    let rays = trace(&scene, &bvh);
    let options = ArtifactOptions::default();
    let c = Vec3::new(-GROOVE_D, 0.0, 0.0);
    let v = vertex_at(&scene, c);
    // The groove is the vertex's own mesh: nothing is cut from the disc.
    let area = reachable_areas(&scene, &bvh, r, &options).unwrap()[0][v];
    assert_eq!(area, std::f32::consts::PI * r * r);
    let plain = detp(&scene, &rays, r).unwrap()[0][v].x as f64;
    let controlled =
        artifact_controlled_detp(&scene, &bvh, &rays, r, &options).unwrap()[0][v].x as f64;
    let rf = r as f64;
    let full = PI * rf * rf;
    let phi = 4.0 * PI * INTENSITY / PHOTONS as f64;
    let cx = -GROOVE_D as f64;
    // Without the extension the rising face hides the disc beyond the crease; with it the whole disc counts.
    let hidden = flux_integral(light, cx, 0.0, rf, GROOVE_D as f64, f64::INFINITY);
    let whole = flux_integral(light, cx, 0.0, rf, f64::INFINITY, f64::INFINITY);
    let exact = analytic(light, c);
    let sigma = |i: f64| (phi * i).sqrt() / full;
    eprintln!(
        "V-groove: E = {exact:.5}, plain {plain:.5} ({:.3} E, expected {:.3} E), controlled {controlled:.5} ({:.3} E, expected {:.3} E ± {:.4} E)",
        plain / exact,
        hidden / full / exact,
        controlled / exact,
        whole / full / exact,
        sigma(whole) / exact
    );
    assert!((plain - hidden / full).abs() <= SIGMAS * sigma(hidden));
    assert!((controlled - whole / full).abs() <= SIGMAS * sigma(whole));
    assert!((controlled - exact).abs() < 0.25 * (plain - exact).abs());
    // extend_ray_set gives the same extensions as extension() segment by segment.
    let mut extended = rays.clone();
    extend_ray_set(&scene, &bvh, &mut extended, 1.2).unwrap();
    let own = mesh_triangles(&scene, 0);
    for (a, b) in extended.segments().zip(rays.segments()).take(2000) {
        assert_eq!(a.extension, extension(&bvh, b, own.clone(), 1.2));
    }
}

#[test]
fn invalid_options_are_errors() {
    let scene = builtin("cornell").unwrap();
    let bvh = Bvh::build(&scene);
    let good = ArtifactOptions::default();
    for r in [0.0, -1.0, f32::NAN, f32::INFINITY] {
        assert!(matches!(
            reachable_areas(&scene, &bvh, r, &good),
            Err(DensityError::InvalidOption { .. })
        ));
    }
    for bad in [
        ArtifactOptions {
            samples_per_axis: 0,
            ..good
        },
        ArtifactOptions {
            offset: 0.0,
            ..good
        },
        ArtifactOptions {
            max_extension: f32::NAN,
            ..good
        },
    ] {
        assert!(reachable_areas(&scene, &bvh, 0.1, &bad).is_err());
    }
    let tiny = black_scene(vec![floor_fan(Vec3::ZERO)], Vec3::Y);
    assert!(reachable_areas(&tiny, &bvh, 0.1, &good).is_err());
    assert!(artifact_controlled_detp(&tiny, &bvh, &RaySet::default(), 0.1, &good).is_err());
    let disc = Disc {
        centre: Vec3::ZERO,
        normal: Vec3::new(0.0, 2.0, 0.0),
        radius: 0.1,
        mesh: None,
    };
    assert!(reachable_area(&bvh, &disc, 0..0, Vec3::ZERO, &good).is_err());
    let mut rays = RaySet::default();
    assert!(extend_ray_set(&scene, &bvh, &mut rays, -1.0).is_err());
}
