//! Ray-triangle intersection and BVH queries against independent computations.

use glam::{DVec3, Vec2, Vec3};
use lustre_geometry::{
    Bvh, Material, Mesh, Object, Ray, Scene, WorldTriangle, builtin, intersect_triangle,
};
use proptest::prelude::*;

/// Independent ray-triangle test in f64: intersect the plane, then signed
/// sub-triangle areas give barycentrics. Returns (t, u, v) and the smallest
/// barycentric, so callers can skip edge-grazing cases.
fn reference_intersection(ray: &Ray, tri: [Vec3; 3]) -> Option<(f64, f64, f64, f64)> {
    let [a, b, c] = tri.map(|p| p.as_dvec3());
    let o = ray.origin.as_dvec3();
    let d = ray.direction.as_dvec3();
    let n = (b - a).cross(c - a);
    let denom = n.dot(d);
    if denom.abs() < 1e-12 {
        return None;
    }
    let t = n.dot(a - o) / denom;
    let q = o + t * d;
    let area2 = n.length_squared();
    let w0 = (b - q).cross(c - q).dot(n) / area2;
    let u = (c - q).cross(a - q).dot(n) / area2;
    let v = (a - q).cross(b - q).dot(n) / area2;
    let min_bary = w0.min(u).min(v);
    Some((t, u, v, min_bary))
}

fn vec3() -> impl Strategy<Value = Vec3> {
    (-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

/// Random unit directions, and axis-aligned ones with signed zeros (which
/// once made the BVH traversal miss).
fn direction() -> impl Strategy<Value = Vec3> {
    prop_oneof![
        4 => vec3().prop_filter("non-zero", |v| v.length() > 0.1).prop_map(Vec3::normalize),
        1 => (0usize..3, any::<bool>(), any::<bool>()).prop_map(|(axis, negative, negative_zeros)| {
            let zero = if negative_zeros { -0.0 } else { 0.0 };
            let mut d = Vec3::splat(zero);
            d[axis] = if negative { -1.0 } else { 1.0 };
            d
        }),
    ]
}

fn triangle() -> impl Strategy<Value = [Vec3; 3]> {
    (vec3(), vec3(), vec3())
        .prop_map(|(a, b, c)| [a, b, c])
        .prop_filter("not degenerate", |[a, b, c]| {
            (*b - *a).cross(*c - *a).length() > 1e-2
        })
}

fn world(triangles: &[[Vec3; 3]]) -> Vec<WorldTriangle> {
    // Distinct corner normals, UVs and materials per triangle, so that a
    // record assembled from the wrong parts shows.
    triangles
        .iter()
        .enumerate()
        .map(|(i, &positions)| {
            let n = (positions[1] - positions[0])
                .cross(positions[2] - positions[0])
                .normalize();
            let f = i as f32;
            let tilt = |k: f32| (n + 0.1 * Vec3::new(k.sin(), (2.0 * k).cos(), 0.5)).normalize();
            WorldTriangle {
                positions,
                normals: [tilt(f), tilt(f + 1.0), tilt(f + 2.0)],
                uvs: [
                    Vec2::new(f, 0.5),
                    Vec2::new(f + 1.0, 0.25),
                    Vec2::new(f, 1.0 + f),
                ],
                surface: i as u32,
                material: (i % 5) as u32,
            }
        })
        .collect()
}

/// Brute-force closest hit: every triangle tested.
fn brute_closest(ray: &Ray, triangles: &[[Vec3; 3]]) -> Option<(usize, f32)> {
    triangles
        .iter()
        .enumerate()
        .filter_map(|(i, &t)| intersect_triangle(ray, t).map(|h| (i, h.t)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn moller_trumbore_matches_plane_and_areas(tri in triangle(), origin in vec3(), dir in direction()) {
        let ray = Ray::new(origin * 3.0, dir);
        let ours = intersect_triangle(&ray, tri);
        match reference_intersection(&ray, tri) {
            // Clear hit or clear miss only; within 1e-4 of an edge either answer is fine.
            Some((t, u, v, min_bary)) if min_bary.abs() > 1e-4 && t.abs() > 1e-4 => {
                if min_bary > 0.0 && t > 0.0 {
                    let h = ours.expect("reference hits but Möller-Trumbore misses");
                    prop_assert!((h.t as f64 - t).abs() < 1e-4 * t.max(1.0));
                    prop_assert!((h.u as f64 - u).abs() < 1e-4);
                    prop_assert!((h.v as f64 - v).abs() < 1e-4);
                } else {
                    prop_assert!(ours.is_none(), "reference misses but got {ours:?}");
                }
            }
            _ => {}
        }
    }

    #[test]
    fn bvh_closest_and_any_hit_match_brute_force(
        tris in prop::collection::vec(triangle(), 1..200),
        rays in prop::collection::vec((vec3(), direction(), 0.1f32..4.0), 1..50),
    ) {
        let bvh = Bvh::from_triangles(world(&tris));
        bvh.validate();
        for (origin, dir, t_max) in rays {
            let ray = Ray::segment(origin * 2.0, dir, 0.0, t_max);
            let expected = brute_closest(&ray, &tris);
            let got = bvh.closest_hit(&ray);
            match (expected, got) {
                (None, None) => {}
                (Some((i, t)), Some(h)) => {
                    prop_assert_eq!(h.t, t);
                    // Ties at equal distance may pick either triangle.
                    if h.triangle as usize != i {
                        prop_assert_eq!(intersect_triangle(&ray, tris[h.triangle as usize]).unwrap().t, t);
                    }
                    prop_assert_eq!(h.surface, h.triangle);
                    prop_assert!((h.position - ray.at(t)).length() < 1e-5);
                }
                (e, g) => prop_assert!(false, "brute force {e:?} but BVH {g:?}"),
            }
            prop_assert_eq!(bvh.any_hit(&ray), expected.is_some());
            // Filtered: the even triangles only, beyond half the segment.
            let accept = |id: u32, t: f32| id.is_multiple_of(2) && t > 0.5 * t_max;
            let filtered = tris.iter().enumerate().any(|(i, &tri)| {
                intersect_triangle(&ray, tri).is_some_and(|h| accept(i as u32, h.t))
            });
            prop_assert_eq!(bvh.any_hit_where(&ray, accept), filtered);
        }
    }

    #[test]
    fn bvh_overlapping_matches_brute_force(
        tris in prop::collection::vec(triangle(), 1..200),
        boxes in prop::collection::vec((vec3(), (0.0f32..0.5, 0.0f32..0.5, 0.0f32..0.5)), 1..20),
    ) {
        let bvh = Bvh::from_triangles(world(&tris));
        for (centre, (x, y, z)) in boxes {
            let (min, max) = (centre - Vec3::new(x, y, z), centre + Vec3::new(x, y, z));
            let mut got = Vec::new();
            bvh.overlapping(min, max, |t| got.push(t as usize));
            got.sort_unstable();
            let expected: Vec<usize> = tris
                .iter()
                .enumerate()
                .filter(|(_, [a, b, c])| {
                    a.min(*b).min(*c).cmple(max).all() && a.max(*b).max(*c).cmpge(min).all()
                })
                .map(|(i, _)| i)
                .collect();
            prop_assert_eq!(got, expected);
        }
    }
}

#[test]
fn batches_equal_single_queries() {
    let scene = builtin("cornell").unwrap();
    let bvh = Bvh::build(&scene);
    let cam = scene.camera();
    let rays: Vec<Ray> = (0..32 * 32)
        .map(|i| {
            let ndc = lustre_geometry::Camera::pixel_ndc(i % 32, i / 32, 32, 32, Vec2::splat(0.5));
            cam.primary_ray(ndc)
        })
        .collect();
    let hits = bvh.closest_hits(&rays);
    let any = bvh.any_hits(&rays);
    for (i, ray) in rays.iter().enumerate() {
        assert_eq!(hits[i], bvh.closest_hit(ray));
        assert_eq!(any[i], bvh.any_hit(ray));
        // The box's open front spans all but the outermost pixels (half-angle
        // atan(1 / 2.9) = 19.0° of the 19.65° half field of view).
        let (x, y) = (i as i32 % 32, i as i32 / 32);
        if (1..31).contains(&x) && (1..31).contains(&y) {
            assert!(hits[i].is_some(), "pixel {x},{y} sees nothing");
        }
    }
}

#[test]
fn hit_record_interpolates_normals_and_uvs() {
    // One triangle with distinct corner normals and UVs; the hit at known barycentrics.
    let positions = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let normals = [
        Vec3::Z,
        Vec3::new(1.0, 0.0, 1.0).normalize(),
        Vec3::new(0.0, 1.0, 1.0).normalize(),
    ];
    let uvs = [
        Vec2::new(0.0, 0.0),
        Vec2::new(1.0, 0.0),
        Vec2::new(0.0, 1.0),
    ];
    let bvh = Bvh::from_triangles(vec![WorldTriangle {
        positions,
        normals,
        uvs,
        surface: 7,
        material: 3,
    }]);
    let (u, v) = (0.25f32, 0.5f32);
    let target = (1.0 - u - v) * positions[0] + u * positions[1] + v * positions[2];
    let ray = Ray::new(
        target + Vec3::new(0.1, -0.2, 2.0),
        (-Vec3::new(0.1, -0.2, 2.0)).normalize(),
    );
    let h = bvh.closest_hit(&ray).unwrap();
    assert!((h.u - u).abs() < 1e-5 && (h.v - v).abs() < 1e-5, "{h:?}");
    assert!((h.position - target).length() < 1e-5);
    assert_eq!(h.geometric_normal, Vec3::Z);
    let shading = ((1.0 - u - v) * normals[0] + u * normals[1] + v * normals[2]).normalize();
    assert!((h.shading_normal - shading).length() < 1e-5);
    assert!((h.uv - Vec2::new(u, v)).length() < 1e-5);
    assert_eq!((h.surface, h.material, h.triangle), (7, 3, 0));
}

#[test]
fn hit_records_carry_each_triangles_surface_and_material() {
    // A row of unit triangles along x, one per id, hit at their centroids
    // from above; surfaces and materials assigned three ways: surfaces that
    // each have one material (looked up by surface), a surface with two
    // materials, and sparse surface ids (both looked up by triangle).
    let row = |surface: &dyn Fn(u32) -> u32, material: &dyn Fn(u32) -> u32| -> Vec<WorldTriangle> {
        (0..12u32)
            .map(|i| {
                let x = 2.0 * i as f32;
                WorldTriangle {
                    positions: [
                        Vec3::new(x, 0.0, 0.0),
                        Vec3::new(x + 1.0, 0.0, 0.0),
                        Vec3::new(x, 1.0, 0.0),
                    ],
                    normals: [Vec3::Z; 3],
                    uvs: [Vec2::ZERO; 3],
                    surface: surface(i),
                    material: material(i),
                }
            })
            .collect()
    };
    let cases = [
        row(&|i| i / 3, &|i| 10 + i / 3),
        row(&|i| i / 3, &|i| i % 2),
        row(&|i| u32::MAX - i, &|i| 5 * i),
    ];
    for triangles in cases {
        let bvh = Bvh::from_triangles(triangles.clone());
        for (id, tri) in triangles.iter().enumerate() {
            let centroid = (tri.positions[0] + tri.positions[1] + tri.positions[2]) / 3.0;
            let ray = Ray::new(centroid + Vec3::Z, -Vec3::Z);
            let h = bvh.closest_hit(&ray).unwrap();
            assert_eq!(
                (h.triangle, h.surface, h.material),
                (id as u32, tri.surface, tri.material)
            );
            let lean = bvh.closest_hit_lean(&ray).unwrap();
            assert_eq!(bvh.hit_record(&ray, lean), h);
        }
    }
}

#[test]
fn t_interval_is_respected() {
    let tri = [
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(1.0, -1.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
    ];
    let bvh = Bvh::from_triangles(world(&[tri]));
    let d = -Vec3::Z;
    assert!(
        bvh.closest_hit(&Ray::segment(Vec3::Z, d, 0.0, 0.999))
            .is_none()
    );
    assert!(
        bvh.closest_hit(&Ray::segment(Vec3::Z, d, 1.001, 2.0))
            .is_none()
    );
    assert!(bvh.any_hit(&Ray::segment(Vec3::Z, d, 0.5, 1.5)));
    assert!(!bvh.any_hit(&Ray::segment(Vec3::Z, d, 0.0, 0.5)));
    let empty = Bvh::from_triangles(Vec::new());
    assert!(empty.is_empty() && empty.closest_hit(&Ray::new(Vec3::ZERO, d)).is_none());
    assert!(!empty.any_hit(&Ray::new(Vec3::ZERO, d)));
}

#[test]
fn rebuild_after_moving_an_object_sees_the_new_pose() {
    let material = Material::diffuse("white", Vec3::splat(0.5));
    let quad = |name: &str, z: f32, emissive: u32| {
        Mesh::flat(
            name,
            &[
                Vec3::new(-1.0, -1.0, z),
                Vec3::new(1.0, -1.0, z),
                Vec3::new(1.0, 1.0, z),
                Vec3::new(-1.0, 1.0, z),
            ],
            &[[0, 1, 2], [2, 3, 0]],
            emissive,
        )
    };
    let meshes = vec![quad("mover", 0.0, 0), quad("light", -5.0, 1)];
    let objects = vec![
        Object {
            name: "mover".into(),
            meshes: vec![0],
            transform: glam::Affine3A::IDENTITY,
        },
        Object {
            name: "light".into(),
            meshes: vec![1],
            transform: glam::Affine3A::IDENTITY,
        },
    ];
    let cam = lustre_geometry::Camera::look_at(Vec3::Z * 3.0, Vec3::ZERO, Vec3::Y, 40.0);
    let mut scene = Scene::new(
        "mover",
        meshes,
        vec![material.clone(), material.with_emission(Vec3::ONE)],
        objects,
        vec![],
        cam,
    )
    .unwrap();
    let ray = Ray::new(Vec3::new(0.0, 0.0, 3.0), -Vec3::Z);
    assert!((Bvh::build(&scene).closest_hit(&ray).unwrap().t - 3.0).abs() < 1e-5);
    let id = scene.object_by_name("mover").unwrap();
    scene
        .set_object_transform(
            id,
            glam::Affine3A::from_translation(Vec3::new(0.0, 0.0, 1.0)),
        )
        .unwrap();
    let hit = Bvh::build(&scene).closest_hit(&ray).unwrap();
    assert!((hit.t - 2.0).abs() < 1e-5, "{hit:?}");
    scene
        .set_object_transform(
            id,
            glam::Affine3A::from_translation(Vec3::new(5.0, 0.0, 0.0)),
        )
        .unwrap();
    let hit = Bvh::build(&scene).closest_hit(&ray).unwrap();
    assert!(
        (hit.t - 8.0).abs() < 1e-4,
        "the ray now reaches the light quad: {hit:?}"
    );
    let _ = DVec3::ZERO;
}

/// Unit squares, two triangles each, on the integer grid of an axis plane (shared edges and corners, boxes flat in one axis).
fn axis_plane_grid(axis: usize, offset: f32, n: i32) -> Vec<[Vec3; 3]> {
    let point = |a: i32, b: i32| {
        let mut p = Vec3::splat(offset);
        p[(axis + 1) % 3] = a as f32 * 0.25;
        p[(axis + 2) % 3] = b as f32 * 0.25;
        p
    };
    let mut out = Vec::new();
    for a in -n..n {
        for b in -n..n {
            out.push([point(a, b), point(a + 1, b), point(a + 1, b + 1)]);
            out.push([point(a, b), point(a + 1, b + 1), point(a, b + 1)]);
        }
    }
    out
}

/// The lean closest hit against brute force (same distance, the same triangle or one at the same distance), and the full record (assembled from the leaf and the shading table) against [`Bvh::hit_record`] of the lean hit (from the triangle), field by field, bit for bit.
fn check_lean_hit(bvh: &Bvh, tris: &[[Vec3; 3]], ray: &Ray) -> Result<(), TestCaseError> {
    let expected = brute_closest(ray, tris);
    let got = bvh.closest_hit_lean(ray);
    match (expected, got) {
        (None, None) => {}
        (Some((i, t)), Some(h)) => {
            prop_assert_eq!(h.t, t);
            if h.triangle as usize != i {
                prop_assert_eq!(
                    intersect_triangle(ray, tris[h.triangle as usize]).map(|x| x.t),
                    Some(t)
                );
            }
            prop_assert_eq!(bvh.closest_hit(ray), Some(bvh.hit_record(ray, h)));
        }
        (e, g) => prop_assert!(false, "brute force {e:?} but the BVH {g:?} for {ray:?}"),
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn lean_closest_hit_matches_brute_force_on_axis_plane_grids(
        axes in prop::collection::vec((0usize..3, -4i32..4), 1..4),
        rays in prop::collection::vec((vec3(), direction(), any::<bool>()), 1..40),
    ) {
        let tris: Vec<[Vec3; 3]> = axes
            .iter()
            .flat_map(|&(axis, k)| axis_plane_grid(axis, k as f32 * 0.25, 4))
            .collect();
        let bvh = Bvh::from_triangles(world(&tris));
        for (origin, dir, snap) in rays {
            // Origins on the grid's lines and planes too, where slabs are flat.
            let origin = if snap { (origin * 8.0).round() * 0.25 } else { origin * 2.0 };
            check_lean_hit(&bvh, &tris, &Ray::new(origin, dir))?;
        }
    }
}

#[test]
fn lean_closest_hit_matches_brute_force_on_thousands_of_triangles() {
    // A deterministic cloud of small triangles (several BVH levels), random rays.
    let mut state = 0x1234_5678_9abc_def0u64;
    let mut next = move || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((state >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
    };
    let mut tris = Vec::new();
    while tris.len() < 4000 {
        let c = Vec3::new(next(), next(), next()) * 3.0;
        let t = [
            c,
            c + Vec3::new(next(), next(), next()) * 0.2,
            c + Vec3::new(next(), next(), next()) * 0.2,
        ];
        if (t[1] - t[0]).cross(t[2] - t[0]).length() > 1e-4 {
            tris.push(t);
        }
    }
    let bvh = Bvh::from_triangles(world(&tris));
    let mut hits = 0;
    for _ in 0..1500 {
        let origin = Vec3::new(next(), next(), next()) * 3.5;
        let dir = Vec3::new(next(), next(), next());
        if dir.length() < 0.1 {
            continue;
        }
        let ray = Ray::new(origin, dir.normalize());
        check_lean_hit(&bvh, &tris, &ray).unwrap();
        hits += usize::from(bvh.closest_hit_lean(&ray).is_some());
    }
    assert!(hits > 300, "{hits} hits");
}
