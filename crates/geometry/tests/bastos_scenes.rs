//! The `pyramid` and `house` built-in scenes (Bastos, Hoff, Wynn & Lastra
//! 1999, section 9 and table 1): triangle counts, the planar glossy
//! reflectors (each one planar mesh of a non-diffuse material, and nothing
//! else glossy), closed meshes, lights, cameras inside the rooms and seeing
//! what they should, the house's recorded walkthrough (the file matches
//! `house_path`, it moves through door openings only and keeps the
//! reflectors in view), no degenerate triangles, and the Mitsuba export.

use std::collections::{HashMap, HashSet};
use std::path::Path;

mod support;

use support::{check_closed, check_closed_meshes, check_no_degenerate_triangles, mesh};

use glam::{Vec2, Vec3};
use lustre_geometry::builtin::house::{self, HOUSE_REFLECTORS, ROOMS, house_path};
use lustre_geometry::builtin::pyramid;
use lustre_geometry::camera_path::CameraPath;
use lustre_geometry::light::Light;
use lustre_geometry::material::ConductorFresnel;
use lustre_geometry::mitsuba::{ExportOptions, export, read_ply, scene_xml};
use lustre_geometry::{Bvh, MaterialModel, Mesh, Ray, Scene, SurfaceKind, builtin};

/// Checks that `name` is a planar reflector: one mesh whose vertices all lie
/// within 1e-5 of one plane, flat shaded along that plane, a non-diffuse
/// material, and only planar surfaces in that plane. Returns its unit normal
/// and the plane's offset `n · p`.
fn check_reflector(scene: &Scene, name: &str) -> (Vec3, f32) {
    let (m, reflector) = mesh(scene, name);
    let material = &scene.materials()[reflector.material as usize];
    assert!(
        !material.model.is_diffuse() && !material.is_emissive(),
        "{name}: {material:?}"
    );
    let mut sum = Vec3::ZERO;
    for t in 0..reflector.indices.len() {
        let [a, b, c] = reflector.triangle(t);
        sum += (b - a).cross(c - a);
    }
    let normal = sum.normalize();
    let offset = normal.dot(reflector.positions[0]);
    for p in &reflector.positions {
        let d = normal.dot(*p) - offset;
        assert!(d.abs() < 1e-5, "{name}: {p} is {d} off its plane");
    }
    for n in &reflector.normals {
        assert!(n.dot(normal) > 0.9999, "{name}: normal {n} vs {normal}");
    }
    let surfaces: Vec<_> = scene.surfaces().iter().filter(|s| s.mesh == m).collect();
    assert!(!surfaces.is_empty());
    for s in surfaces {
        let SurfaceKind::Planar(plane) = s.kind else {
            panic!("{name}: a curved surface");
        };
        assert!(plane.normal.dot(normal) > 0.9999, "{name}");
        assert!((plane.signed_distance(reflector.positions[0])).abs() < 1e-5);
    }
    (normal, offset)
}

/// The names of the meshes with a non-diffuse material.
fn glossy_meshes(scene: &Scene) -> HashSet<&str> {
    scene
        .meshes()
        .iter()
        .filter(|m| !scene.materials()[m.material as usize].model.is_diffuse())
        .map(|m| m.name.as_str())
        .collect()
}

/// The mesh hit first by the ray from `eye` towards `target`.
fn first_hit<'a>(scene: &'a Scene, bvh: &Bvh, eye: Vec3, target: Vec3) -> Option<&'a str> {
    let hit = bvh.closest_hit(&Ray::new(eye, (target - eye).normalize()))?;
    let mesh = scene.surfaces()[hit.surface as usize].mesh;
    Some(scene.meshes()[mesh as usize].name.as_str())
}

/// Whether `p` is inside the field of view of the scene's camera (aspect 1).
fn in_view(scene: &Scene, p: Vec3) -> bool {
    let camera = scene.camera();
    let (right, up, forward) = camera.frame();
    let d = p - camera.position;
    let depth = d.dot(forward);
    let half = (0.5 * camera.fov_y_degrees.to_radians()).tan();
    depth > 0.0 && d.dot(right).abs() < half * depth && d.dot(up).abs() < half * depth
}

#[test]
fn pyramid_has_the_papers_triangle_count_and_reflectors() {
    let scene = builtin("pyramid").unwrap();
    let triangles = scene.triangle_count();
    assert!((12_000..=20_000).contains(&triangles), "{triangles}");
    assert!(
        triangles.abs_diff(pyramid::PAPER_TRIANGLES) < pyramid::PAPER_TRIANGLES / 10,
        "{triangles}"
    );
    // Between 5 and 11 planar glossy reflectors (section 9), and nothing else glossy.
    let reflectors = pyramid::REFLECTORS;
    assert!((5..=11).contains(&reflectors.len()));
    assert_eq!(glossy_meshes(&scene), HashSet::from(reflectors));
    let mut planes = Vec::new();
    for name in reflectors {
        planes.push(check_reflector(&scene, name));
        // One planar surface each: the cells and lattice triangles join up.
        let (m, _) = mesh(&scene, name);
        assert_eq!(
            scene.surfaces().iter().filter(|s| s.mesh == m).count(),
            1,
            "{name}"
        );
    }
    // The slanted faces: copper, tilted at atan(h / b) from the base, facing out.
    let (b, h) = (pyramid::PYRAMID_HALF_BASE, pyramid::PYRAMID_HEIGHT);
    for (k, out) in [Vec3::Z, Vec3::X, -Vec3::Z, -Vec3::X]
        .into_iter()
        .enumerate()
    {
        let (normal, _) = planes[k];
        let expected = (out * h + Vec3::Y * b).normalize();
        assert!(normal.abs_diff_eq(expected, 1e-5), "{normal} vs {expected}");
        let (_, face) = mesh(&scene, pyramid::PYRAMID_FACES[k]);
        let n = pyramid::PYRAMID_LEVELS as usize;
        assert_eq!(face.indices.len(), n * n);
        let model = &scene.materials()[face.material as usize].model;
        let MaterialModel::RoughConductor {
            alpha,
            fresnel: ConductorFresnel::Complex { eta, k },
            ..
        } = model
        else {
            panic!("{model:?}");
        };
        assert_eq!(*alpha, pyramid::COPPER_ALPHA);
        assert_eq!((*eta, *k), (pyramid::COPPER_ETA, pyramid::COPPER_K));
        // Copper is reddish: red reflects most at normal incidence.
        let f0 = |c: usize| {
            ((eta[c] - 1.0).powi(2) + k[c].powi(2)) / ((eta[c] + 1.0).powi(2) + k[c].powi(2))
        };
        assert!(f0(0) > f0(1) && f0(1) > f0(2), "{}", f0(0));
    }
    assert!(planes[4].0.abs_diff_eq(-Vec3::Y, 1e-6));
    assert!((planes[4].1 + pyramid::PYRAMID_CENTRE.y).abs() < 1e-6);
}

#[test]
fn pyramid_room_is_textured_with_geometry() {
    let scene = builtin("pyramid").unwrap();
    // The checkerboard: 64 floor cells, half light and half dark, in two
    // diffuse materials of distinct albedo.
    let (_, light) = mesh(&scene, "floor-light");
    let (_, dark) = mesh(&scene, "floor-dark");
    assert_eq!(light.indices.len() + dark.indices.len(), 2 * 64);
    assert_eq!(light.indices.len(), dark.indices.len());
    let albedo = |m: &Mesh| {
        scene.materials()[m.material as usize]
            .model
            .diffuse_reflectance()
    };
    assert!(albedo(light).min_element() > 2.0 * albedo(dark).max_element());
    // Walls: all four faces of 64 cells each, less the three glossy panels.
    let wall_triangles: usize = ["wainscot", "wall-sand", "wall-sage"]
        .iter()
        .map(|n| mesh(&scene, n).1.indices.len())
        .sum();
    let panels: usize = [
        "glossy-panel-back",
        "glossy-panel-left",
        "glossy-panel-right",
    ]
    .iter()
    .map(|n| mesh(&scene, n).1.indices.len())
    .sum();
    assert_eq!(wall_triangles + panels, 4 * 2 * 64);
    // The floor, walls and ceiling close the room: every edge of the room's
    // cells on the room's boundary occurs twice, once each way.
    let mut room = Mesh {
        name: "room".into(),
        positions: Vec::new(),
        normals: Vec::new(),
        uvs: Vec::new(),
        indices: Vec::new(),
        material: 0,
    };
    for name in [
        "floor-light",
        "floor-dark",
        "ceiling-light",
        "ceiling-dark",
        "wainscot",
        "wall-sand",
        "wall-sage",
        "glossy-panel-back",
        "glossy-panel-left",
        "glossy-panel-right",
    ] {
        let (_, m) = mesh(&scene, name);
        let base = room.positions.len() as u32;
        room.positions.extend_from_slice(&m.positions);
        room.indices
            .extend(m.indices.iter().map(|t| t.map(|i| i + base)));
    }
    // Inward faces: the volume is negative, the cube's.
    let volume = check_closed(&room);
    let side = 2.0 * pyramid::ROOM_HALF;
    assert!(
        (volume + side * side * pyramid::ROOM_HEIGHT).abs() < 1e-3,
        "{volume}"
    );
}

#[test]
fn pyramid_closed_meshes_and_the_closed_pyramid() {
    let scene = builtin("pyramid").unwrap();
    check_closed_meshes(&scene, pyramid::CLOSED_MESHES);
    // The four faces and the base close the pyramid: volume b² · 4 · h / 3.
    let mut solid = mesh(&scene, "pyramid-base").1.clone();
    for name in pyramid::PYRAMID_FACES {
        let (_, m) = mesh(&scene, name);
        let base = solid.positions.len() as u32;
        solid.positions.extend_from_slice(&m.positions);
        solid
            .indices
            .extend(m.indices.iter().map(|t| t.map(|i| i + base)));
    }
    let volume = check_closed(&solid);
    let b = pyramid::PYRAMID_HALF_BASE;
    let expected = 4.0 * b * b * pyramid::PYRAMID_HEIGHT / 3.0;
    assert!((volume - expected).abs() < 1e-4, "{volume} vs {expected}");
    // The teapot stands on the floor, under 0.5 m high, 0.9 m long with spout and handle.
    let teapot = mesh(&scene, "teapot").1.bounds();
    assert!(teapot.min.y >= 0.0 && teapot.max.y < 0.5, "{teapot:?}");
    assert!(
        teapot.extent().x < 0.9 && teapot.extent().z < 0.6,
        "{teapot:?}"
    );
    check_no_degenerate_triangles(&scene);
}

#[test]
fn pyramid_camera_sees_three_faces_and_the_light_is_on_the_ceiling() {
    let scene = builtin("pyramid").unwrap();
    let eye = scene.camera().position;
    let (h, top) = (pyramid::ROOM_HALF, pyramid::ROOM_HEIGHT);
    assert!(eye.x.abs() < h && eye.z.abs() < h && eye.y > 0.0 && eye.y < top);
    let bvh = Bvh::build(&scene);
    // Three faces seen (each at several points), the back one hidden.
    for (k, name) in pyramid::PYRAMID_FACES.iter().enumerate() {
        let (_, face) = mesh(&scene, name);
        // The lattice's first row runs along the base, its last point is the apex.
        let n = pyramid::PYRAMID_LEVELS as usize;
        let corners = [
            face.positions[0],
            face.positions[n],
            *face.positions.last().unwrap(),
        ];
        let centroid = (corners[0] + corners[1] + corners[2]) / 3.0;
        let points = corners.map(|c| centroid.lerp(c, 0.5));
        let seen = points
            .iter()
            .chain([&centroid])
            .filter(|&&p| in_view(&scene, p) && first_hit(&scene, &bvh, eye, p) == Some(*name))
            .count();
        if k == 2 {
            assert_eq!(seen, 0, "the back face is hidden");
        } else {
            assert_eq!(seen, 4, "{name}");
        }
    }
    // The teapot and the back panel are in the picture too.
    let teapot = mesh(&scene, "teapot").1.bounds().center();
    assert!(in_view(&scene, teapot));
    assert_eq!(first_hit(&scene, &bvh, eye, teapot), Some("teapot"));
    let panel = Vec3::new(0.0, 1.2, -pyramid::ROOM_HALF);
    assert!(in_view(&scene, panel));
    assert_eq!(
        first_hit(&scene, &bvh, eye, panel),
        Some("glossy-panel-back")
    );
    // One rectangular light facing down under the ceiling.
    let [Light::Area(light)] = scene.lights() else {
        panic!("{:?}", scene.lights());
    };
    assert!(light.shape.mean_normal().abs_diff_eq(-Vec3::Y, 1e-6));
    let size = pyramid::LIGHT_SIZE;
    assert!((light.shape.area() - size.x * size.y).abs() < 1e-5);
    assert!((light.shape.centroid().y - top).abs() < 0.01);
}

#[test]
fn house_has_the_papers_triangle_count_and_five_reflectors() {
    let scene = builtin("house").unwrap();
    let triangles: usize = scene.meshes().iter().map(|m| m.indices.len()).sum();
    assert_eq!(scene.triangle_count(), triangles);
    assert!(triangles >= house::PAPER_TRIANGLES, "{triangles}");
    assert!(triangles < 200_000, "{triangles}");
    // Exactly table 1's five reflectors are glossy.
    assert_eq!(glossy_meshes(&scene), HashSet::from(HOUSE_REFLECTORS));
    let planes: Vec<(Vec3, f32)> = HOUSE_REFLECTORS
        .iter()
        .map(|name| check_reflector(&scene, name))
        .collect();
    let model = |name: &str| &scene.materials()[mesh(&scene, name).1.material as usize].model;
    // Piano top, living floor, music floor and bench top face up; the door mirrors face -z.
    for (name, (normal, offset)) in HOUSE_REFLECTORS.iter().zip(&planes) {
        match *name {
            "door-mirror" => {
                assert!(normal.abs_diff_eq(-Vec3::Z, 1e-6));
                assert!(matches!(model(name), MaterialModel::Mirror { .. }));
            }
            _ => {
                assert!(normal.abs_diff_eq(Vec3::Y, 1e-6), "{name}");
                assert!(matches!(model(name), MaterialModel::Blend { .. }), "{name}");
            }
        }
        let y = match *name {
            "piano-top" => house::PIANO_CASE.1,
            "bench-top" => house::BENCH.1.y,
            "door-mirror" => continue,
            _ => 0.0,
        };
        assert!((offset - y).abs() < 1e-6, "{name}: {offset}");
    }
    // The floors cover their rooms; the mirrors hang on the closet doors in the hall.
    for (name, room) in [("living-floor", 0), ("music-floor", 1)] {
        let b = mesh(&scene, name).1.bounds();
        let (_, min, max) = ROOMS[room];
        assert_eq!(
            (b.min.x, b.min.z, b.max.x, b.max.z),
            (min.x, min.y, max.x, max.y)
        );
    }
    let mirror = mesh(&scene, "door-mirror").1.bounds();
    let doors = mesh(&scene, "closet-doors").1.bounds();
    assert!(mirror.max.z < doors.min.z && doors.min.z - mirror.max.z < 0.002);
    assert!(mirror.min.x > doors.min.x && mirror.max.x < doors.max.x);
    let (_, hall_min, hall_max) = ROOMS[2];
    assert!(mirror.min.z > hall_min.y && mirror.max.z < hall_max.y);
    // The lids close the piano's case and the bench's seat.
    let piano = mesh(&scene, "piano").1.bounds();
    let top = mesh(&scene, "piano-top").1.bounds();
    assert_eq!(piano.max.y, top.max.y);
    assert!(top.min.x >= piano.min.x && top.max.x <= piano.max.x);
    let bench = mesh(&scene, "bench").1.bounds();
    let bench_top = mesh(&scene, "bench-top").1.bounds();
    assert_eq!(
        (bench.min.x, bench.max.x),
        (bench_top.min.x, bench_top.max.x)
    );
    assert_eq!(
        (bench.min.z, bench.max.z),
        (bench_top.min.z, bench_top.max.z)
    );
}

#[test]
fn house_closed_meshes_lights_and_camera() {
    let scene = builtin("house").unwrap();
    check_closed_meshes(&scene, house::CLOSED_MESHES);
    // The piano's case is closed by its lid; the bench's seat is a box open at the top.
    let mut piano = mesh(&scene, "piano").1.clone();
    let (_, lid) = mesh(&scene, "piano-top");
    let base = piano.positions.len() as u32;
    piano.positions.extend_from_slice(&lid.positions);
    piano
        .indices
        .extend(lid.indices.iter().map(|t| t.map(|i| i + base)));
    let (b, t) = house::PIANO_CASE;
    let volume = check_closed(&piano);
    let footprint = volume / (t - b);
    // Between the inscribed and the circumscribed shape of the outline.
    assert!(
        footprint > 1.5 * 1.9 * 0.7 && footprint < 1.5 * 1.9,
        "{footprint}"
    );
    assert_eq!(mesh(&scene, "bench").1.indices.len(), 10);
    check_no_degenerate_triangles(&scene);
    // A light on the ceiling of every room, facing down.
    let lights = scene.lights();
    assert_eq!(lights.len(), 5);
    let mut lit = HashSet::new();
    for light in lights {
        let Light::Area(light) = light else {
            panic!("{light:?}")
        };
        assert!(light.shape.mean_normal().abs_diff_eq(-Vec3::Y, 1e-6));
        let c = light.shape.centroid();
        assert!((c.y - house::WALL_HEIGHT).abs() < 0.01);
        let room = room_of(c).expect("a light over a room");
        lit.insert(room);
    }
    assert_eq!(lit.len(), ROOMS.len());
    // The camera stands in the music room, looking at the piano top over the floor.
    let eye = scene.camera().position;
    assert_eq!(room_of(eye), Some("music"));
    let bvh = Bvh::build(&scene);
    let lid = mesh(&scene, "piano-top").1.bounds().center();
    assert!(in_view(&scene, lid));
    assert_eq!(first_hit(&scene, &bvh, eye, lid), Some("piano-top"));
    let floor = Vec3::new(2.8, 0.0, -2.4);
    assert!(in_view(&scene, floor));
    assert_eq!(first_hit(&scene, &bvh, eye, floor), Some("music-floor"));
}

/// The room whose floor is under `p` (x, z), if any.
fn room_of(p: Vec3) -> Option<&'static str> {
    ROOMS
        .iter()
        .find(|(_, min, max)| p.x >= min.x && p.x <= max.x && p.z >= min.y && p.z <= max.y)
        .map(|r| r.0)
}

#[test]
fn house_walk_goes_through_the_doors_with_the_reflectors_in_view() {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/paths/house-walk.json");
    let path = CameraPath::load(&file).unwrap();
    assert_eq!(path, house_path(), "the file is house_path()");
    let scene = builtin("house").unwrap();
    let bvh = Bvh::build(&scene);
    // About the paper's 944 frames at 30 frames a second; every fourth here.
    let frames = path.frames(241);
    assert!(path.duration() * 30.0 > 944.0);
    let reflectors: HashSet<&str> = HashSet::from(HOUSE_REFLECTORS);
    let mut rooms = Vec::new();
    let mut seen: HashMap<&str, usize> = HashMap::new();
    let mut with_reflector = 0;
    for (f, camera) in frames.iter().enumerate() {
        let eye = camera.position;
        let room = room_of(eye).unwrap_or_else(|| panic!("frame {f} at {eye} is in no room"));
        if rooms.last() != Some(&room) {
            rooms.push(room);
        }
        assert!(eye.y > 1.0 && eye.y < 2.0, "frame {f}: {eye}");
        // Nothing within 20 cm of the eye: a sphere of rays.
        for d in [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z] {
            assert!(
                !bvh.any_hit(&Ray::segment(eye, d, 0.0, 0.2)),
                "frame {f}: {eye} by a wall"
            );
        }
        // The straight way to the next frame is free: no walking through walls.
        if let Some(next) = frames.get(f + 1) {
            let step = next.position - eye;
            if step.length() > 0.0 {
                let ray = Ray::segment(eye, step.normalize(), 0.0, step.length());
                assert!(!bvh.any_hit(&ray), "frame {f}: {eye} -> {}", next.position);
            }
        }
        // What the frame shows, on a coarse grid at the paper's 720x486.
        let camera = camera.with_aspect(720.0 / 486.0);
        let mut in_frame = HashSet::new();
        for j in 0..12 {
            for i in 0..16 {
                let ndc = Vec2::new((i as f32 + 0.5) / 8.0 - 1.0, (j as f32 + 0.5) / 6.0 - 1.0);
                if let Some(hit) = bvh.closest_hit(&camera.primary_ray(ndc)) {
                    let m = scene.surfaces()[hit.surface as usize].mesh;
                    let name = scene.meshes()[m as usize].name.as_str();
                    if reflectors.contains(name) {
                        in_frame.insert(name);
                    }
                }
            }
        }
        if !in_frame.is_empty() {
            with_reflector += 1;
        }
        for name in in_frame {
            *seen.entry(name).or_default() += 1;
        }
    }
    // Hall, living room, music room, hall.
    assert_eq!(rooms, ["hall", "living", "music", "hall"]);
    assert!(
        with_reflector * 10 >= frames.len() * 9,
        "{with_reflector} of {} frames show a reflector",
        frames.len()
    );
    for name in HOUSE_REFLECTORS {
        let frames_seen = seen.get(name).copied().unwrap_or(0);
        assert!(frames_seen * 10 >= frames.len(), "{name}: {seen:?}");
    }
}

#[test]
fn the_bastos_scenes_export_to_mitsuba() {
    // The pyramid in full; the house's XML only (its PLY files are as any scene's).
    let dir = std::env::temp_dir().join(format!("lustre-bastos-scenes-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let scene = builtin("pyramid").unwrap();
    let xml_path = dir.join("pyramid").join("scene.xml");
    let report = export(&scene, &xml_path, &ExportOptions::default()).unwrap();
    assert!(report.warnings.is_empty(), "{:?}", report.warnings);
    let xml = std::fs::read_to_string(&xml_path).unwrap();
    assert_eq!(xml.matches("<emitter type=\"area\">").count(), 1);
    assert_eq!(
        xml.matches("<shape type=\"ply\"").count(),
        scene.meshes().len()
    );
    for needle in [
        "<bsdf type=\"roughconductor\"",
        "<string name=\"distribution\" value=\"beckmann\"/>",
        "<rgb name=\"eta\" value=\"0.200438, 0.924033, 1.10221\"/>",
        "<rgb name=\"k\" value=\"3.91295, 2.45285, 2.14219\"/>",
        "<bsdf type=\"blendbsdf\"",
    ] {
        assert!(xml.contains(needle), "pyramid XML lacks {needle}");
    }
    let teapot = mesh(&scene, "teapot").0 as usize;
    let back = read_ply(
        &std::fs::read(&report.meshes[teapot]).unwrap(),
        &report.meshes[teapot],
    )
    .unwrap();
    assert_eq!(back.indices, scene.meshes()[teapot].indices);
    std::fs::remove_dir_all(&dir).unwrap();
    let scene = builtin("house").unwrap();
    let mut warnings = Vec::new();
    let xml = scene_xml(&scene, &ExportOptions::default(), &mut warnings).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(xml.matches("<emitter type=\"area\">").count(), 5);
    assert_eq!(
        xml.matches("<shape type=\"ply\"").count(),
        scene.meshes().len()
    );
    assert!(xml.contains("<bsdf type=\"conductor\""), "the mirror");
    assert_eq!(
        xml.matches("<bsdf type=\"blendbsdf\"").count(),
        4,
        "four varnishes"
    );
}
