//! The `tree` built-in scene (García et al. 2003, sections 2.7 and 2.9):
//! triangle counts, ground squares, leaf and branch sizes, determinism,
//! validity, the mobile ball's path against the ground, the tree and the
//! shadow, and its Mitsuba export.

use glam::Vec3;
use lustre_geometry::builtin::tree::{
    BALL_CLEARANCE, BALL_PATH_DURATION, BALL_PATH_RADIUS, BALL_RADIUS, GROUND_CELL,
    GROUND_HALF_SIZE, LIGHT_CENTRE, STATIC_TRIANGLES, ball_path,
};
use lustre_geometry::light::Light;
use lustre_geometry::mitsuba::{ExportOptions, export, read_ply};
use lustre_geometry::{Aabb, Bvh, PathEnd, Ray, Scene, SurfaceKind, builtin};

fn mesh_id(scene: &Scene, name: &str) -> u32 {
    scene
        .meshes()
        .iter()
        .position(|m| m.name == name)
        .unwrap_or_else(|| panic!("no mesh {name}")) as u32
}

/// Closest point of triangle `[a, b, c]` to `p` (Ericson, Real-Time Collision Detection, 5.1.5).
fn closest_point_on_triangle(p: Vec3, [a, b, c]: [Vec3; 3]) -> Vec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

#[test]
fn closest_point_helper_is_right() {
    let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let near = |a: Vec3, b: Vec3| a.abs_diff_eq(b, 1e-6);
    assert!(near(
        closest_point_on_triangle(Vec3::new(0.2, 0.2, 1.0), tri),
        Vec3::new(0.2, 0.2, 0.0)
    ));
    assert!(near(
        closest_point_on_triangle(Vec3::new(-1.0, -1.0, 0.0), tri),
        Vec3::ZERO
    ));
    assert!(near(
        closest_point_on_triangle(Vec3::new(1.0, 1.0, 0.0), tri),
        Vec3::new(0.5, 0.5, 0.0)
    ));
    assert!(near(
        closest_point_on_triangle(Vec3::new(0.5, -2.0, 3.0), tri),
        Vec3::new(0.5, 0.0, 0.0)
    ));
}

#[test]
fn triangle_counts_match_the_paper() {
    let scene = builtin("tree").unwrap();
    let count = |name: &str| scene.meshes()[mesh_id(&scene, name) as usize].indices.len();
    let (ground, branches, leaves, ball, light) = (
        count("ground"),
        count("branches"),
        count("leaves"),
        count("ball"),
        count("light"),
    );
    assert_eq!(ground, 20_000);
    // Ground + tree: the paper's 71 966 triangles; the mobile object: 500.
    assert_eq!(ground + branches + leaves, STATIC_TRIANGLES);
    assert_eq!(STATIC_TRIANGLES, 71_966);
    assert_eq!(ball, 500);
    assert_eq!(light, 2);
    assert_eq!(scene.triangle_count(), 71_966 + 500 + 2);
    // Both parts of the tree are substantial.
    assert!(branches > 10_000 && leaves > 20_000, "{branches} {leaves}");
    let tree = scene.object_by_name("tree").unwrap();
    assert_eq!(
        scene.objects()[tree as usize].meshes,
        vec![mesh_id(&scene, "branches"), mesh_id(&scene, "leaves")]
    );
}

#[test]
fn ground_is_one_plane_of_002_squares() {
    let scene = builtin("tree").unwrap();
    let g = mesh_id(&scene, "ground");
    let ground = &scene.meshes()[g as usize];
    assert_eq!(ground.positions.len(), 101 * 101, "vertices are shared");
    for t in 0..ground.indices.len() {
        let [a, b, c] = ground.triangle(t);
        let mut edges = [a.distance(b), b.distance(c), c.distance(a)];
        edges.sort_by(f32::total_cmp);
        assert!((edges[0] - GROUND_CELL).abs() < 1e-5, "{edges:?}");
        assert!((edges[1] - GROUND_CELL).abs() < 1e-5, "{edges:?}");
        assert!(
            (edges[2] - GROUND_CELL * 2f32.sqrt()).abs() < 1e-5,
            "{edges:?}"
        );
        assert!(ground.geometric_normal(t).abs_diff_eq(Vec3::Y, 1e-6));
    }
    assert!(ground.normals.iter().all(|&n| n == Vec3::Y));
    let b = ground.bounds();
    assert_eq!(b.min, Vec3::new(-GROUND_HALF_SIZE, 0.0, -GROUND_HALF_SIZE));
    assert!(
        b.max
            .abs_diff_eq(Vec3::new(GROUND_HALF_SIZE, 0.0, GROUND_HALF_SIZE), 1e-5)
    );
    let surfaces: Vec<_> = scene.surfaces().iter().filter(|s| s.mesh == g).collect();
    assert_eq!(surfaces.len(), 1);
    assert!(
        matches!(surfaces[0].kind, SurfaceKind::Planar(p) if p.normal.abs_diff_eq(Vec3::Y, 1e-6))
    );
    assert!((surfaces[0].area - 4.0).abs() < 1e-3);
}

#[test]
fn tree_triangles_are_about_001_and_shaded_as_asked() {
    let scene = builtin("tree").unwrap();
    let (b, l) = (mesh_id(&scene, "branches"), mesh_id(&scene, "leaves"));
    let leaves = &scene.meshes()[l as usize];
    for t in 0..leaves.indices.len() {
        let [p, q, r] = leaves.triangle(t);
        let longest = p.distance(q).max(q.distance(r)).max(r.distance(p));
        assert!((0.01..0.016).contains(&longest), "leaf edge {longest}");
    }
    // Flat leaves: each leaf quad is one planar surface; smooth branches: one curved surface.
    let of = |m: u32| scene.surfaces().iter().filter(move |s| s.mesh == m);
    assert_eq!(of(l).count(), leaves.indices.len() / 2);
    assert!(of(l).all(|s| matches!(s.kind, SurfaceKind::Planar(_)) && s.triangles.len() == 2));
    assert_eq!(of(b).count(), 1);
    assert!(of(b).all(|s| s.kind == SurfaceKind::Curved));
    // Branch triangles: mean longest edge of the order of a centimetre.
    let branches = &scene.meshes()[b as usize];
    let mean = (0..branches.indices.len())
        .map(|t| {
            let [p, q, r] = branches.triangle(t);
            p.distance(q).max(q.distance(r)).max(r.distance(p))
        })
        .sum::<f32>()
        / branches.indices.len() as f32;
    assert!((0.008..0.03).contains(&mean), "mean branch edge {mean}");
    // Smooth normals point away from the axis: outward winding agrees with them.
    let agree = (0..branches.indices.len())
        .filter(|&t| {
            let n = branches.geometric_normal(t);
            branches.indices[t]
                .iter()
                .all(|&i| branches.normals[i as usize].dot(n) > 0.0)
        })
        .count();
    assert_eq!(agree, branches.indices.len());
    // The trunk stands on the ground; nothing of the tree is below it.
    let tree_bounds = branches.bounds().union(leaves.bounds());
    assert!(tree_bounds.min.y >= 0.0, "{tree_bounds:?}");
    assert!(
        tree_bounds.max.y > 1.0 && tree_bounds.max.y < 2.0,
        "{tree_bounds:?}"
    );
}

#[test]
fn builds_are_identical_and_valid() {
    let start = std::time::Instant::now();
    let a = builtin("tree").unwrap();
    let elapsed = start.elapsed();
    let mut b = builtin("tree").unwrap();
    let start = std::time::Instant::now();
    for i in 0..100 {
        b.pose_at(i as f32 * 0.08).unwrap();
    }
    let posing = start.elapsed() / 100;
    b.pose_at(0.0).unwrap();
    eprintln!("builtin(\"tree\") took {elapsed:?}, pose_at {posing:?}");
    assert_eq!(a.meshes(), b.meshes());
    assert_eq!(a.surfaces(), b.surfaces());
    assert_eq!(a.objects(), b.objects());
    for mesh in a.meshes() {
        mesh.validate().unwrap();
    }
    assert!(
        a.materials()
            .iter()
            .all(|m| matches!(m.model, lustre_geometry::MaterialModel::Diffuse { .. }))
    );
    // One area light: the rectangle, facing down.
    assert_eq!(a.lights().len(), 1);
    let Light::Area(light) = &a.lights()[0] else {
        panic!("{:?}", a.lights()[0])
    };
    assert!(light.shape.mean_normal().abs_diff_eq(-Vec3::Y, 1e-6));
    assert!(light.shape.centroid().abs_diff_eq(LIGHT_CENTRE, 1e-5));
    // The camera sees the trunk's middle.
    let camera = a.camera();
    let forward = (Vec3::new(0.0, 0.3, 0.0) - camera.position).normalize();
    let (_, _, axis) = camera.frame();
    assert!(forward.dot(axis) > (0.5 * camera.fov_y_degrees.to_radians()).cos());
}

/// The ball's world centre at each of `k` frames of its path.
fn ball_centres(k: usize) -> Vec<Vec3> {
    ball_path()
        .frames(k)
        .iter()
        .map(|xf| xf.transform_point3(Vec3::ZERO))
        .collect()
}

#[test]
fn ball_is_the_mobile_object_and_rolls_round_a_closed_loop() {
    let scene = builtin("tree").unwrap();
    let ball = scene.object_by_name("ball").unwrap();
    let mobile = scene.mobile_objects();
    assert_eq!(mobile.len(), 1);
    assert_eq!(mobile[0].object, ball);
    assert_eq!(mobile[0].path, ball_path());
    let path = &mobile[0].path;
    assert_eq!(path.end(), PathEnd::Loop);
    assert_eq!(path.duration(), BALL_PATH_DURATION);
    // Posed at the start.
    assert_eq!(scene.objects()[ball as usize].transform, path.at(0.0));
    assert!(path.at(BALL_PATH_DURATION).abs_diff_eq(path.at(0.0), 1e-6));
    // On the circle, at a steady pace.
    let centres = ball_centres(256);
    for c in &centres {
        let r = Vec3::new(c.x, 0.0, c.z).length();
        assert!((r - BALL_PATH_RADIUS).abs() < 0.002, "{c}");
        assert!((c.y - BALL_RADIUS - BALL_CLEARANCE).abs() < 1e-6);
    }
    // Rolling without slipping: the lowest point of the ball barely moves
    // between close frames, while the centre moves by a ball circumference
    // per 1/7 of the loop.
    let frames = path.frames(2048);
    let step = BALL_PATH_DURATION / 2048.0;
    for (i, xf) in frames.iter().enumerate() {
        let next = path.at(path.start() + (i as f32 + 0.01) * step);
        let contact = xf.transform_point3(Vec3::ZERO) - Vec3::Y * BALL_RADIUS;
        let rest = xf.inverse().transform_point3(contact);
        let slip = next.transform_point3(rest).distance(contact);
        let travel = next
            .transform_point3(Vec3::ZERO)
            .distance(xf.transform_point3(Vec3::ZERO));
        assert!(
            slip < 0.1 * travel + 1e-6,
            "frame {i}: slip {slip} travel {travel}"
        );
    }
}

#[test]
fn ball_stays_on_the_ground_and_clear_of_the_tree() {
    let mut scene = builtin("tree").unwrap();
    let (g, b, l, ball) = (
        mesh_id(&scene, "ground"),
        mesh_id(&scene, "branches"),
        mesh_id(&scene, "leaves"),
        mesh_id(&scene, "ball"),
    );
    let tree: Vec<[Vec3; 3]> = [b, l]
        .iter()
        .flat_map(|&m| {
            let mesh = &scene.meshes()[m as usize];
            (0..mesh.indices.len()).map(move |t| mesh.triangle(t))
        })
        .collect();
    // The trunk: the branch vertices below the lowest fork.
    let trunk = Aabb::from_points(
        scene.meshes()[b as usize]
            .positions
            .iter()
            .copied()
            .filter(|p| p.y < 0.2),
    );
    assert!(
        trunk.extent().x < 0.1 && trunk.extent().z < 0.1,
        "{trunk:?}"
    );
    let ground = scene.meshes()[g as usize].bounds();
    let path = ball_path();
    let mut closest = f32::INFINITY;
    for t in path.frame_times(128) {
        scene.pose_at(t).unwrap();
        let positions = scene.world_positions(ball);
        let bounds = Aabb::from_points(positions.iter().copied());
        assert!(bounds.min.y >= BALL_CLEARANCE - 1e-5, "t = {t}: {bounds:?}");
        assert!(
            bounds.min.x > ground.min.x
                && bounds.max.x < ground.max.x
                && bounds.min.z > ground.min.z
                && bounds.max.z < ground.max.z,
            "t = {t}: off the ground {bounds:?}"
        );
        let overlap = bounds.min.cmple(trunk.max).all() && trunk.min.cmple(bounds.max).all();
        assert!(!overlap, "t = {t}: the ball's box meets the trunk's");
        let centre = path.at(t).transform_point3(Vec3::ZERO);
        for &tri in &tree {
            let lo = tri[0].min(tri[1]).min(tri[2]);
            let hi = tri[0].max(tri[1]).max(tri[2]);
            // Triangles beyond 0.5 m on an axis from the ball's centre cannot come close.
            let far = 0.5;
            if (centre - hi).max_element() > far || (lo - centre).max_element() > far {
                continue;
            }
            closest = closest.min(closest_point_on_triangle(centre, tri).distance(centre));
        }
    }
    assert!(
        closest > BALL_RADIUS && closest.is_finite(),
        "the ball's centre comes within {closest} of the tree"
    );
}

#[test]
fn ball_passes_through_the_shadow() {
    let scene = builtin("tree").unwrap();
    let ball = mesh_id(&scene, "ball");
    // Everything but the ball, which stands below the rays.
    let static_triangles = scene
        .world_triangles()
        .into_iter()
        .filter(|t| scene.surfaces()[t.surface as usize].mesh != ball)
        .collect();
    let bvh = Bvh::from_triangles(static_triangles);
    let path = ball_path();
    let mut shadowed = Vec::new();
    for t in path.frame_times(32) {
        let top = path.at(t).transform_point3(Vec3::ZERO) + Vec3::Y * (BALL_RADIUS + 1e-3);
        let to_light = LIGHT_CENTRE - top;
        let ray = Ray::segment(top, to_light.normalize(), 0.0, to_light.length() - 1e-3);
        shadowed.push(bvh.any_hit(&ray));
    }
    let count = shadowed.iter().filter(|&&s| s).count();
    // Lit at the start (on the light's side), in shadow half-way round.
    assert!(!shadowed[0], "{shadowed:?}");
    assert!(shadowed[16], "{shadowed:?}");
    assert!(
        (4..28).contains(&count),
        "{count} of 32 frames in shadow: {shadowed:?}"
    );
}

#[test]
fn mitsuba_export_has_every_mesh_and_the_light() {
    let dir = std::env::temp_dir().join(format!("lustre-tree-mitsuba-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let scene = builtin("tree").unwrap();
    let report = export(&scene, &dir.join("tree.xml"), &ExportOptions::default()).unwrap();
    assert!(report.warnings.is_empty(), "{:?}", report.warnings);
    assert_eq!(report.meshes.len(), scene.meshes().len());
    let xml = std::fs::read_to_string(&report.xml).unwrap();
    assert!(xml.starts_with("<?xml"));
    assert!(xml.contains("<scene version=\"3.0.0\">") && xml.trim_end().ends_with("</scene>"));
    assert_eq!(
        xml.matches("<shape type=\"ply\"").count(),
        scene.meshes().len()
    );
    assert_eq!(xml.matches("<emitter type=\"area\">").count(), 1);
    assert_eq!(xml.matches("<emitter").count(), 1);
    assert!(xml.contains("<rgb name=\"radiance\" value=\"40, 38, 34\"/>"));
    assert_eq!(
        xml.matches("<bsdf type=\"diffuse\"").count(),
        scene.materials().len()
    );
    assert!(xml.contains("<float name=\"fov\" value=\"45\"/>"));
    for (m, path) in report.meshes.iter().enumerate() {
        let rel = path
            .strip_prefix(&dir)
            .unwrap()
            .to_str()
            .unwrap()
            .to_owned();
        assert!(
            xml.contains(&format!("value=\"{rel}\"")),
            "{rel} not in the XML"
        );
        let back = read_ply(&std::fs::read(path).unwrap(), path).unwrap();
        assert_eq!(back.indices, scene.meshes()[m].indices);
        assert_eq!(back.positions, scene.world_positions(m as u32));
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
