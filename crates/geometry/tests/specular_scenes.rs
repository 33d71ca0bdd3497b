//! The `mirrors` and `bathroom` built-in scenes (Diefenbach & Badler 1997,
//! sections 3, 4 and 8, figures 1 and 16): closed meshes are oriented
//! manifolds (brute force over every edge), no triangle is degenerate, the
//! counts of triangles and lights, the specular materials, the nested mirror
//! images traced by brute force, and the Mitsuba export.

mod support;

use support::{check_closed, check_no_degenerate_triangles, mesh};

use glam::Vec3;
use lustre_geometry::builtin::{bathroom, mirrors};
use lustre_geometry::light::Light;
use lustre_geometry::mitsuba::{ExportOptions, export, read_ply};
use lustre_geometry::{Bvh, MaterialModel, Ray, Scene, SurfaceKind, builtin};

#[test]
fn the_edge_check_tells_closed_from_open_and_flipped() {
    let scene = builtin("mirrors").unwrap();
    let (_, pedestal) = mesh(&scene, "pedestal");
    let volume = check_closed(pedestal);
    assert!((volume - 0.3 * 0.3 * 0.75).abs() < 1e-5, "{volume}");
    let mut open = pedestal.clone();
    open.indices.pop();
    assert!(std::panic::catch_unwind(|| check_closed(&open)).is_err());
    let mut flipped = pedestal.clone();
    flipped.indices[0].swap(1, 2);
    assert!(std::panic::catch_unwind(|| check_closed(&flipped)).is_err());
    let mut inside_out = pedestal.clone();
    for t in &mut inside_out.indices {
        t.swap(1, 2);
    }
    assert!(check_closed(&inside_out) < 0.0);
}

#[test]
fn closed_meshes_are_outward_oriented_manifolds() {
    for (scene, closed) in [
        (builtin("mirrors").unwrap(), mirrors::CLOSED_MESHES),
        (builtin("bathroom").unwrap(), bathroom::CLOSED_MESHES),
    ] {
        for name in closed {
            let (_, m) = mesh(&scene, name);
            let volume = check_closed(m);
            // A bounding-box volume bounds it from above.
            let extent = m.bounds().extent();
            assert!(
                volume > 0.0 && volume <= extent.x * extent.y * extent.z * 1.0001,
                "{}: {name} has volume {volume}",
                scene.name
            );
        }
    }
    // Known volumes: the door slab and the tessellated ball.
    let scene = builtin("bathroom").unwrap();
    let door = check_closed(mesh(&scene, "shower-door").1);
    let slab = 0.01 * (2.0 - 0.552) * (0.29 + 1.39);
    assert!((door - slab).abs() < 1e-4 * slab, "{door} vs {slab}");
    let scene = builtin("mirrors").unwrap();
    let ball = check_closed(mesh(&scene, "ball").1);
    let exact = 4.0 / 3.0 * std::f32::consts::PI * mirrors::BALL_RADIUS.powi(3);
    assert!(ball < exact && ball > 0.97 * exact, "{ball} vs {exact}");
}

#[test]
fn no_triangle_is_degenerate() {
    for name in ["mirrors", "bathroom"] {
        check_no_degenerate_triangles(&builtin(name).unwrap());
    }
}

#[test]
fn bathroom_has_the_papers_polygon_count_and_lights() {
    let scene = builtin("bathroom").unwrap();
    let triangles: usize = scene.meshes().iter().map(|m| m.indices.len()).sum();
    assert_eq!(scene.triangle_count(), triangles);
    assert!(triangles >= bathroom::PAPER_POLYGONS, "{triangles}");
    // One overhead and four vanity lights (figure 1), rectangles facing down.
    let mut areas: Vec<f32> = scene
        .lights()
        .iter()
        .map(|l| match l {
            Light::Area(a) => {
                assert!(a.shape.mean_normal().abs_diff_eq(-Vec3::Y, 1e-5));
                a.shape.area()
            }
            other => panic!("unexpected light {other:?}"),
        })
        .collect();
    areas.sort_by(f32::total_cmp);
    let expected = [0.02, 0.02, 0.02, 0.02, 0.36];
    assert_eq!(areas.len(), expected.len());
    for (a, e) in areas.iter().zip(expected) {
        assert!((a - e).abs() < 1e-5 * e.max(1.0), "{areas:?}");
    }
    // The vanity lights sit over the mirror, the overhead light at the ceiling.
    let (_, mirror) = mesh(&scene, "vanity-mirror");
    let top = mirror.bounds().max.y;
    for (i, x) in bathroom::VANITY_LIGHT_X.iter().enumerate() {
        let (_, light) = mesh(&scene, &format!("vanity-light-{}", i + 1));
        let centre = light.bounds().center();
        assert!(centre.y > top && (centre.x - x).abs() < 1e-5);
        assert!(centre.x > mirror.bounds().min.x && centre.x < mirror.bounds().max.x);
    }
    // The total power is π L A summed over the five rectangles.
    let power = scene.total_power();
    let expected = std::f32::consts::PI
        * (bathroom::OVERHEAD_RADIANCE * 0.36 + bathroom::VANITY_RADIANCE * 4.0 * 0.02);
    assert!(power.abs_diff_eq(expected, 1e-3 * expected.max_element()));
}

#[test]
fn bathroom_has_a_vanity_mirror_and_a_refractive_door() {
    let scene = builtin("bathroom").unwrap();
    let model = |name: &str| &scene.materials()[mesh(&scene, name).1.material as usize].model;
    assert!(matches!(
        model("vanity-mirror"),
        MaterialModel::Mirror { .. }
    ));
    assert!(matches!(model("shower-door"), MaterialModel::Dielectric { ior, .. } if *ior == 1.5));
    // Only the mirror and the door are specular.
    let specular: Vec<&str> = scene
        .meshes()
        .iter()
        .filter(|m| !scene.materials()[m.material as usize].model.is_diffuse())
        .map(|m| m.name.as_str())
        .collect();
    assert_eq!(specular, ["shower-door", "vanity-mirror"]);
    // The door is 1 cm thick: two large faces 1 cm apart, facing away from each other.
    let (d, door) = mesh(&scene, "shower-door");
    let planes: Vec<_> = scene
        .surfaces()
        .iter()
        .filter(|s| s.mesh == d && s.area > 1.0)
        .map(|s| match s.kind {
            SurfaceKind::Planar(p) => p,
            SurfaceKind::Curved => panic!("the door is flat"),
        })
        .collect();
    assert_eq!(planes.len(), 2);
    assert!(planes[0].normal.abs_diff_eq(-planes[1].normal, 1e-6));
    let gap = planes[0].signed_distance(door.positions[0]).abs()
        + planes[1].signed_distance(door.positions[0]).abs();
    assert!((gap - 0.01).abs() < 1e-5, "{gap}");
    // The handle is on the room side of the door, clear of the glass.
    let (_, handle) = mesh(&scene, "door-handle");
    assert!(handle.bounds().max.x < door.bounds().min.x);
    // The camera sees the mirror and the door directly.
    let bvh = Bvh::build(&scene);
    let eye = scene.camera().position;
    for name in ["vanity-mirror", "shower-door"] {
        let (m, target) = mesh(&scene, name);
        let ray = Ray::new(eye, (target.bounds().center() - eye).normalize());
        let hit = bvh.closest_hit(&ray).expect("inside the room");
        assert_eq!(scene.surfaces()[hit.surface as usize].mesh, m, "{name}");
    }
}

#[test]
fn mirrors_are_exactly_parallel_and_facing() {
    let scene = builtin("mirrors").unwrap();
    let mut planes = Vec::new();
    for name in ["mirror-a", "mirror-b"] {
        let (m, quad) = mesh(&scene, name);
        assert_eq!(quad.indices.len(), 2, "a single quad");
        let material = &scene.materials()[quad.material as usize].model;
        assert!(
            matches!(material, MaterialModel::Mirror { reflectance } if *reflectance == mirrors::MIRROR_REFLECTANCE)
        );
        let surfaces: Vec<_> = scene.surfaces().iter().filter(|s| s.mesh == m).collect();
        assert_eq!(surfaces.len(), 1);
        let SurfaceKind::Planar(plane) = surfaces[0].kind else {
            panic!("{name} is flat")
        };
        planes.push(plane);
    }
    assert_eq!(planes[0].normal, Vec3::X);
    assert_eq!(planes[1].normal, -Vec3::X);
    for p in scene.meshes()[mesh(&scene, "mirror-a").0 as usize]
        .positions
        .iter()
    {
        assert_eq!(p.x, -mirrors::MIRROR_X);
    }
    for p in scene.meshes()[mesh(&scene, "mirror-b").0 as usize]
        .positions
        .iter()
    {
        assert_eq!(p.x, mirrors::MIRROR_X);
    }
    assert_eq!(scene.lights().len(), 1);
}

/// Follows a ray through mirror reflections; returns the mesh it ends on and how many mirrors it met.
fn trace(scene: &Scene, bvh: &Bvh, mut ray: Ray, max_bounces: u32) -> Option<(String, u32)> {
    for bounces in 0..=max_bounces {
        let hit = bvh.closest_hit(&ray)?;
        let mesh = &scene.meshes()[scene.surfaces()[hit.surface as usize].mesh as usize];
        if !matches!(
            scene.materials()[mesh.material as usize].model,
            MaterialModel::Mirror { .. }
        ) {
            return Some((mesh.name.clone(), bounces));
        }
        let n = hit.geometric_normal;
        let direction = ray.direction - 2.0 * ray.direction.dot(n) * n;
        ray = Ray::segment(hit.position, direction, 1e-4, f32::INFINITY);
    }
    None
}

#[test]
fn the_ball_recedes_into_the_mirror_through_nested_images() {
    let scene = builtin("mirrors").unwrap();
    let bvh = Bvh::build(&scene);
    let eye = scene.camera().position;
    let (forward, right, up) = {
        let (r, u, f) = scene.camera().frame();
        (f, r, u)
    };
    let half = (0.5 * scene.camera().fov_y_degrees.to_radians()).tan();
    // The ball itself, then its image after k reflections: the ball's centre
    // mirrored k times alternately, at x = -2 k MIRROR_X.
    for k in 0..=6u32 {
        let image = mirrors::BALL_CENTRE - Vec3::X * (2.0 * k as f32 * mirrors::MIRROR_X);
        let direction = (image - eye).normalize();
        // In the picture: inside the field of view.
        let d = direction / direction.dot(forward);
        assert!(
            d.dot(right).abs() < half && d.dot(up).abs() < half,
            "image {k} is outside the picture"
        );
        let (name, bounces) = trace(&scene, &bvh, Ray::new(eye, direction), 20)
            .unwrap_or_else(|| panic!("image {k}: the ray escapes"));
        assert_eq!((name.as_str(), bounces), ("ball", k), "image {k}");
    }
}

#[test]
fn the_new_scenes_export_to_mitsuba() {
    let dir = std::env::temp_dir().join(format!("lustre-specular-scenes-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    for name in ["mirrors", "bathroom"] {
        let scene = builtin(name).unwrap();
        let xml_path = dir.join(name).join("scene.xml");
        let report = export(&scene, &xml_path, &ExportOptions::default()).unwrap();
        assert!(report.warnings.is_empty(), "{name}: {:?}", report.warnings);
        assert_eq!(report.meshes.len(), scene.meshes().len());
        let xml = std::fs::read_to_string(&xml_path).unwrap();
        assert_eq!(
            xml.matches("<emitter type=\"area\">").count(),
            scene.lights().len()
        );
        assert_eq!(
            xml.matches("<shape type=\"ply\"").count(),
            scene.meshes().len()
        );
        assert!(
            xml.contains("<bsdf type=\"conductor\""),
            "{name}: no mirror"
        );
        assert_eq!(
            xml.contains("<bsdf type=\"dielectric\""),
            name == "bathroom"
        );
        if name == "bathroom" {
            assert!(xml.contains("<float name=\"int_ior\" value=\"1.5\"/>"));
        }
        for (m, path) in report.meshes.iter().enumerate() {
            let back = read_ply(&std::fs::read(path).unwrap(), path).unwrap();
            assert_eq!(back.positions, scene.world_positions(m as u32));
            assert_eq!(back.indices, scene.meshes()[m].indices);
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
