//! OBJ/MTL loading: round trips, normal generation, the MTL mapping, texture
//! paths, emitters, and every malformed input the loader must reject with a
//! typed error naming the file and line.

use std::f32::consts::PI;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use glam::{Vec2, Vec3};
use lustre_geometry::light::{AreaShape, Light};
use lustre_geometry::material::{ConductorFresnel, MicrofacetDistribution};
use lustre_geometry::obj::{DEFAULT_MATERIAL_NAME, framing_camera, framing_direction, load_mtl};
use lustre_geometry::{
    Aabb, GeometryError, LoadedScene, Material, MaterialModel, Mesh, ObjOptions, Rgb, Scene,
    SurfaceKind, builtin, load_obj, load_obj_with,
};
use proptest::prelude::*;

// ---------------------------------------------------------------------------
// Helpers.

/// A fresh, empty directory for one test (or one proptest case).
fn test_dir(name: &str) -> PathBuf {
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let dir = std::env::temp_dir()
        .join(format!("lustre-obj-loader-{}", std::process::id()))
        .join(format!(
            "{name}-{}",
            COUNTER.fetch_add(1, Ordering::Relaxed)
        ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    if let Some(parent) = path.parent() {
        std::fs::create_dir_all(parent).unwrap();
    }
    std::fs::write(&path, text).unwrap();
    path
}

/// Material of the light every test scene carries (a scene needs a light).
const LIGHT_MTL: &str = "\nnewmtl light\nKd 0 0 0\nKe 1 1 1\n";
/// A 1 m² emitter far from everything, facing -Y, with relative indices so it
/// can be appended to any OBJ text.
const LIGHT_OBJ: &str =
    "\no light\nusemtl light\nv 10 10 10\nv 11 10 10\nv 11 10 11\nv 10 10 11\nf -4 -3 -2 -1\n";

struct Files {
    dir: PathBuf,
    obj: PathBuf,
    mtl: PathBuf,
}

/// Writes `scene.mtl` (`mtl` plus the light's material) and `scene.obj`
/// (`mtllib scene.mtl`, `obj`, then the light).
fn scene_files(test: &str, obj: &str, mtl: &str) -> Files {
    let dir = test_dir(test);
    let mtl = write(&dir, "scene.mtl", &format!("{mtl}{LIGHT_MTL}"));
    let obj = write(
        &dir,
        "scene.obj",
        &format!("mtllib scene.mtl\n{obj}{LIGHT_OBJ}"),
    );
    Files { dir, obj, mtl }
}

fn load(files: &Files) -> LoadedScene {
    match load_obj(&files.obj) {
        Ok(loaded) => loaded,
        Err(e) => panic!("{e}"),
    }
}

/// One-based number of the only line of `path` that contains `needle`.
fn line_of(path: &Path, needle: &str) -> usize {
    let text = std::fs::read_to_string(path).unwrap();
    let lines: Vec<usize> = text
        .lines()
        .enumerate()
        .filter(|(_, l)| l.contains(needle))
        .map(|(i, _)| i + 1)
        .collect();
    assert_eq!(
        lines.len(),
        1,
        "`{needle}` must be on exactly one line of {}",
        path.display()
    );
    lines[0]
}

/// Asserts a `Parse` error at `file`, on the line containing `needle`.
fn assert_parse_error(result: Result<LoadedScene, GeometryError>, file: &Path, needle: &str) {
    match result {
        Err(GeometryError::Parse { location, message }) => {
            assert_eq!(location.file, file, "wrong file for `{needle}`: {message}");
            assert_eq!(
                location.line,
                Some(line_of(file, needle)),
                "wrong line for `{needle}`: {message}"
            );
        }
        Err(other) => panic!("expected a parse error at `{needle}`, got {other:?}"),
        Ok(_) => panic!("expected a parse error at `{needle}`, but the file loaded"),
    }
}

fn material<'a>(scene: &'a Scene, name: &str) -> &'a Material {
    scene
        .materials()
        .iter()
        .find(|m| m.name == name)
        .unwrap_or_else(|| panic!("no material `{name}`"))
}

fn mesh<'a>(scene: &'a Scene, name: &str) -> &'a Mesh {
    scene
        .meshes()
        .iter()
        .find(|m| m.name == name)
        .unwrap_or_else(|| panic!("no mesh `{name}`"))
}

fn assert_vec3_near(a: Vec3, b: Vec3, tol: f32) {
    assert!((a - b).abs().max_element() <= tol, "{a} != {b}");
}

/// Geometric unit normal of triangle `t` of `mesh`, computed here.
fn face_normal(mesh: &Mesh, t: usize) -> Vec3 {
    let [a, b, c] = mesh.indices[t].map(|i| mesh.positions[i as usize]);
    (b - a).cross(c - a).normalize()
}

const CUBE: &str = "\
v -1 -1 -1
v 1 -1 -1
v 1 1 -1
v -1 1 -1
v -1 -1 1
v 1 -1 1
v 1 1 1
v -1 1 1
f 1 4 3 2
f 5 6 7 8
f 1 2 6 5
f 4 8 7 3
f 1 5 8 4
f 2 3 7 6
";

const OCTAHEDRON: &str = "\
v 1 0 0
v -1 0 0
v 0 1 0
v 0 -1 0
v 0 0 1
v 0 0 -1
f 1 3 5
f 3 2 5
f 2 4 5
f 4 1 5
f 3 1 6
f 2 3 6
f 4 2 6
f 1 4 6
";

// ---------------------------------------------------------------------------
// Round trips.

#[test]
fn quad_round_trip_keeps_positions_indices_uvs_normals_and_material() {
    let files = scene_files(
        "quad",
        "o quad\nv 0 0 0\nv 2 0 0\nv 2 0 1\nv 0 0 1\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 1 0\n\
         usemtl shiny\nf 1/1/1 4/4/1 3/3/1 2/2/1\n",
        "newmtl shiny\nKd 0.25 0.5 0.125\nKs 0.5 0.25 0.125\nNs 42\n",
    );
    let loaded = load(&files);
    let scene = &loaded.scene;
    assert_eq!(scene.name, "scene");
    assert_eq!(loaded.degenerate_triangles_dropped, 0);
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);

    let names: Vec<&str> = scene.objects().iter().map(|o| o.name.as_str()).collect();
    assert_eq!(names, ["quad", "light"]);
    let quad = mesh(scene, "quad");
    // The fan (1 4 3), (1 3 2) numbers vertices in order of first use.
    assert_eq!(
        quad.positions,
        [
            Vec3::ZERO,
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(2.0, 0.0, 1.0),
            Vec3::new(2.0, 0.0, 0.0)
        ]
    );
    assert_eq!(quad.indices, [[0, 1, 2], [0, 2, 3]]);
    assert_eq!(
        quad.uvs,
        [
            Vec2::new(0.0, 0.0),
            Vec2::new(0.0, 1.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(1.0, 0.0)
        ]
    );
    assert_eq!(quad.normals, [Vec3::Y; 4]);

    let shiny = &scene.materials()[quad.material as usize];
    assert_eq!(shiny.name, "shiny");
    assert_eq!(
        shiny.model,
        MaterialModel::Phong {
            diffuse: Rgb::new(0.25, 0.5, 0.125),
            specular: Rgb::new(0.5, 0.25, 0.125),
            exponent: 42.0,
        }
    );
    assert_eq!(shiny.emission, Rgb::ZERO);
    assert_eq!(shiny.opacity, 1.0);

    // One planar surface for the quad (area 2 x 1), one for the light (1 x 1).
    assert_eq!(scene.surfaces().len(), 2);
    let quad_id = scene
        .meshes()
        .iter()
        .position(|m| m.name == "quad")
        .unwrap() as u32;
    let surface = scene.surfaces().iter().find(|s| s.mesh == quad_id).unwrap();
    assert!((surface.area - 2.0).abs() < 1e-6);
    match surface.kind {
        SurfaceKind::Planar(plane) => assert_vec3_near(plane.normal, Vec3::Y, 1e-6),
        SurfaceKind::Curved => panic!("a flat quad is planar"),
    }
}

#[test]
fn cube_round_trip_has_six_planar_faces_of_the_right_area() {
    let files = scene_files(
        "cube",
        &format!("o cube\nusemtl white\n{CUBE}"),
        "newmtl white\nKd 0.8 0.8 0.8\n",
    );
    let loaded = load(&files);
    let scene = &loaded.scene;
    let cube = mesh(scene, "cube");
    assert_eq!(cube.indices.len(), 12);
    // Each corner is split between its three faces: 24 vertices.
    assert_eq!(cube.positions.len(), 24);
    let expected: Vec<Vec3> = CUBE
        .lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|l| {
            let v: Vec<f32> = l.split(' ').map(|t| t.parse().unwrap()).collect();
            Vec3::new(v[0], v[1], v[2])
        })
        .collect();
    for p in &cube.positions {
        assert!(expected.contains(p), "{p} is not a corner of the cube");
    }
    assert!((cube.area() - 24.0).abs() < 1e-5);
    let cube_id = scene
        .meshes()
        .iter()
        .position(|m| m.name == "cube")
        .unwrap() as u32;
    let faces: Vec<_> = scene
        .surfaces()
        .iter()
        .filter(|s| s.mesh == cube_id)
        .collect();
    assert_eq!(faces.len(), 6);
    for face in faces {
        assert!((face.area - 4.0).abs() < 1e-5);
        assert!(matches!(face.kind, SurfaceKind::Planar(_)));
    }
    // Outward winding: every face normal points away from the centre.
    for t in 0..cube.indices.len() {
        let [a, _, _] = cube.triangle(t);
        assert!(face_normal(cube, t).dot(a) > 0.0);
    }
}

#[test]
fn objects_groups_and_materials_split_into_objects_and_meshes() {
    let files = scene_files(
        "objects",
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n\
         usemtl red\nf 1 2 3\n\
         o table\nusemtl red\nf 1 3 4\nusemtl blue\nf 1 2 4\n\
         g chair\nf 2 3 4\n\
         o table\nusemtl red\nf 1 2 3\n",
        "newmtl red\nKd 1 0 0\nnewmtl blue\nKd 0 0 1\n",
    );
    let scene = load(&files).scene;
    let objects: Vec<(&str, usize)> = scene
        .objects()
        .iter()
        .map(|o| (o.name.as_str(), o.meshes.len()))
        .collect();
    // Faces before any `o` belong to an object named after the file.
    assert_eq!(
        objects,
        [("scene", 1), ("table", 2), ("chair", 1), ("light", 1)]
    );
    let table = &scene.objects()[1];
    let names: Vec<&str> = table
        .meshes
        .iter()
        .map(|&m| scene.meshes()[m as usize].name.as_str())
        .collect();
    assert_eq!(names, ["table:red", "table:blue"]);
    // `o table` twice with `red`: one mesh of two triangles.
    assert_eq!(mesh(&scene, "table:red").indices.len(), 2);
    assert_eq!(
        scene.materials()[mesh(&scene, "chair").material as usize].name,
        "blue"
    );
}

#[test]
fn faces_without_usemtl_get_the_default_material() {
    let dir = test_dir("default-material");
    write(&dir, "l.mtl", LIGHT_MTL);
    let obj = write(
        &dir,
        "plain.obj",
        &format!("mtllib l.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n{LIGHT_OBJ}"),
    );
    let scene = load_obj(&obj).unwrap().scene;
    let plain = mesh(&scene, "plain");
    let default = &scene.materials()[plain.material as usize];
    assert_eq!(default.name, DEFAULT_MATERIAL_NAME);
    assert_eq!(
        default.model,
        MaterialModel::Diffuse {
            reflectance: Rgb::splat(0.5)
        }
    );
}

#[test]
fn polygons_relative_indices_w_comments_and_crlf_load() {
    let files = scene_files(
        "polygons",
        "# a pentagon in the z = 0 plane\r\no penta\r\nusemtl white\r\nv 0 0 0\r\nv 2 0 0 1 # trailing comment\r\n\
         v 4 2 0 2\r\nv 1 3 0\r\nv 0 2 0 0.5 0.5 0.5\r\ns 1\r\nf -5 -4 -3 -2 -1\r\n",
        "newmtl white\nKd 1 1 1\n",
    );
    let loaded = load(&files);
    let penta = mesh(&loaded.scene, "penta");
    assert_eq!(penta.indices.len(), 3);
    // w divides: (4, 2, 0) / 2 = (2, 1, 0); colours are ignored.
    assert!(penta.positions.contains(&Vec3::new(2.0, 1.0, 0.0)));
    assert!(penta.positions.contains(&Vec3::new(0.0, 2.0, 0.0)));
    // Area of the pentagon (0,0) (2,0) (2,1) (1,3) (0,2) by the shoelace formula.
    let p = [(0.0, 0.0), (2.0, 0.0), (2.0, 1.0), (1.0, 3.0), (0.0, 2.0)];
    let shoelace: f32 = 0.5
        * (0..5)
            .map(|i| {
                let (a, b) = (p[i], p[(i + 1) % 5]);
                a.0 * b.1 - b.0 * a.1
            })
            .sum::<f32>();
    assert!((penta.area() - shoelace).abs() < 1e-5);
    assert_eq!(penta.uvs, vec![Vec2::ZERO; penta.positions.len()]);
    for n in &penta.normals {
        assert_vec3_near(*n, Vec3::Z, 1e-6);
    }
}

#[test]
fn concave_polygons_are_triangulated_inside_their_outline() {
    // An L-shaped hexagon listed from the corner where a fan around the first
    // vertex would put the triangle (2,1) (1,1) (1,2) in the notch, outside
    // the L, with the opposite winding.
    let files = scene_files(
        "concave",
        "o ell\nusemtl white\nv 2 1 0\nv 1 1 0\nv 1 2 0\nv 0 2 0\nv 0 0 0\nv 2 0 0\nf 1 2 3 4 5 6\n",
        "newmtl white\nKd 1 1 1\n",
    );
    let loaded = load(&files);
    let ell = mesh(&loaded.scene, "ell");
    assert_eq!(ell.indices.len(), 4);
    // The L's area by the shoelace formula, and every triangle wound like the face.
    let p = [
        (2.0, 1.0),
        (1.0, 1.0),
        (1.0, 2.0),
        (0.0, 2.0),
        (0.0, 0.0),
        (2.0, 0.0),
    ];
    let shoelace: f32 = 0.5
        * (0..6)
            .map(|i| {
                let (a, b) = (p[i], p[(i + 1) % 6]);
                a.0 * b.1 - b.0 * a.1
            })
            .sum::<f32>();
    assert!((shoelace.abs() - 3.0).abs() < 1e-6);
    assert!((ell.area() - shoelace.abs()).abs() < 1e-5, "{}", ell.area());
    for t in 0..ell.indices.len() {
        assert_vec3_near(face_normal(ell, t), Vec3::Z * shoelace.signum(), 1e-6);
        // No triangle's centroid lies in the notch x > 1, y > 1.
        let c = ell.triangle(t).iter().sum::<Vec3>() / 3.0;
        assert!(!(c.x > 1.0 && c.y > 1.0), "triangle {t} in the notch: {c}");
    }
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
}

#[test]
fn non_planar_concave_polygons_fall_back_to_a_fan_with_a_warning() {
    // The L of the test above with its reflex corner lifted out of the plane.
    let files = scene_files(
        "warped",
        "o warped\nusemtl white\nv 2 1 0\nv 1 1 0.5\nv 1 2 0\nv 0 2 0\nv 0 0 0\nv 2 0 0\nf 1 2 3 4 5 6\n",
        "newmtl white\nKd 1 1 1\n",
    );
    let loaded = load(&files);
    assert_eq!(mesh(&loaded.scene, "warped").indices.len(), 4);
    let line = line_of(&files.obj, "f 1 2 3 4 5 6");
    assert!(
        loaded
            .warnings
            .iter()
            .any(|w| w.contains(&format!(":{line}: face is not a simple planar polygon"))),
        "{:?}",
        loaded.warnings
    );
}

#[test]
fn lines_points_and_unknown_statements_are_ignored_with_a_warning() {
    let files = scene_files(
        "ignored",
        "usemtl white\nv 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2 3\np 1\ncstype bezier\nf 1 2 3\n",
        "newmtl white\nKd 1 1 1\nmap_Bump bump.png\nsharpness 60\n",
    );
    let loaded = load(&files);
    assert_eq!(mesh(&loaded.scene, "scene").indices.len(), 1);
    for keyword in ["`l`", "`p`", "`cstype`", "`map_Bump`", "`sharpness`"] {
        assert!(
            loaded.warnings.iter().any(|w| w.contains(keyword)),
            "no warning for {keyword}: {:?}",
            loaded.warnings
        );
    }
    let l = line_of(&files.obj, "l 1 2 3");
    assert!(
        loaded
            .warnings
            .iter()
            .any(|w| w.contains(&format!("scene.obj:{l}:")))
    );
}

#[test]
fn mixed_texture_coordinates_in_one_mesh_are_dropped_with_a_warning() {
    let files = scene_files(
        "mixed",
        "usemtl white\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0.5 0.5\nf 1/1 2/1 3/1\nf 2 4 3\n",
        "newmtl white\nKd 1 1 1\n",
    );
    let loaded = load(&files);
    let m = mesh(&loaded.scene, "scene");
    assert_eq!(m.indices.len(), 2);
    assert_eq!(m.uvs, vec![Vec2::ZERO; m.positions.len()]);
    assert!(
        loaded
            .warnings
            .iter()
            .any(|w| w.contains("texture coordinates")),
        "{:?}",
        loaded.warnings
    );
}

#[test]
fn degenerate_triangles_are_dropped_and_counted() {
    let files = scene_files(
        "degenerate",
        "usemtl white\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 0.1 0.2 0.3\nv 0.2 0.4 0.6\nv 0.3 0.6 0.9\n\
         f 1 2 3 4\nf 1 2 5\nf 1 1 3\nf 6 7 8\n",
        "newmtl white\nKd 1 1 1\n",
    );
    let loaded = load(&files);
    assert_eq!(loaded.degenerate_triangles_dropped, 3);
    let m = mesh(&loaded.scene, "scene");
    assert_eq!(m.indices.len(), 2);
    assert!((m.area() - 1.0).abs() < 1e-6);
}

#[test]
fn framing_camera_sees_the_whole_box() {
    let files = scene_files(
        "camera",
        &format!("usemtl white\n{CUBE}"),
        "newmtl white\nKd 1 1 1\n",
    );
    let scene = load(&files).scene;
    let bounds = scene.bounds();
    let camera = *scene.camera();
    assert_eq!(camera, framing_camera(bounds));
    assert_eq!(camera.fov_y_degrees, 40.0);
    assert_eq!(camera.up, Vec3::Y);
    let forward = (camera.target - camera.position).normalize();
    // A three-quarter view from above, not straight down an axis.
    assert_vec3_near(forward, -framing_direction(), 1e-6);
    assert!(
        forward.y < -0.3 && forward.x < -0.2 && forward.z < -0.6,
        "{forward}"
    );
    assert_vec3_near(camera.target, bounds.center(), 1e-6);
    for i in 0..8 {
        let corner = Vec3::new(
            if i & 1 == 0 {
                bounds.min.x
            } else {
                bounds.max.x
            },
            if i & 2 == 0 {
                bounds.min.y
            } else {
                bounds.max.y
            },
            if i & 4 == 0 {
                bounds.min.z
            } else {
                bounds.max.z
            },
        );
        let to = (corner - camera.position).normalize();
        let angle = to.dot(forward).clamp(-1.0, 1.0).acos().to_degrees();
        assert!(angle <= 20.0 + 1e-3, "corner {corner} is {angle}° off axis");
    }
    // A unit box is framed at distance r / sin 20° from its centre.
    let unit = framing_camera(Aabb::from_points([Vec3::ZERO, Vec3::ONE]));
    let r = 0.5 * 3f32.sqrt();
    assert_vec3_near(
        unit.position,
        Vec3::splat(0.5) + framing_direction() * (r / 20f32.to_radians().sin()),
        1e-5,
    );
}

// ---------------------------------------------------------------------------
// Normals.

#[test]
fn octahedron_smooth_normals_are_the_normalised_positions() {
    let files = scene_files(
        "octahedron",
        &format!("o ball\nusemtl white\n{OCTAHEDRON}"),
        "newmtl white\nKd 1 1 1\n",
    );
    // Faces around a vertex of an octahedron differ by up to 109.5°: smooth all.
    let loaded = load_obj_with(
        &files.obj,
        &ObjOptions {
            crease_angle_degrees: 180.0,
        },
    )
    .unwrap();
    let ball = mesh(&loaded.scene, "ball");
    assert_eq!(ball.positions.len(), 6);
    for (p, n) in ball.positions.iter().zip(&ball.normals) {
        assert_vec3_near(*n, p.normalize(), 1e-6);
    }
    let ball_id = loaded
        .scene
        .meshes()
        .iter()
        .position(|m| m.name == "ball")
        .unwrap() as u32;
    let kinds: Vec<_> = loaded
        .scene
        .surfaces()
        .iter()
        .filter(|s| s.mesh == ball_id)
        .map(|s| s.kind)
        .collect();
    assert_eq!(kinds, [SurfaceKind::Curved]);

    // At the default 60° every face of the octahedron (70.5° from its
    // neighbours) stays flat: 8 faces x 3 corners.
    let flat = load(&files);
    let ball = mesh(&flat.scene, "ball");
    assert_eq!(ball.positions.len(), 24);
    for t in 0..ball.indices.len() {
        for &i in &ball.indices[t] {
            assert_vec3_near(ball.normals[i as usize], face_normal(ball, t), 1e-6);
        }
    }
}

#[test]
fn cube_keeps_flat_face_normals_at_the_default_crease() {
    let files = scene_files(
        "cube-normals",
        &format!("o cube\nusemtl white\n{CUBE}"),
        "newmtl white\nKd 1 1 1\n",
    );
    let cube_scene = load(&files).scene;
    let cube = mesh(&cube_scene, "cube");
    for t in 0..cube.indices.len() {
        let n = face_normal(cube, t);
        // Axis-aligned unit normal.
        assert!((n.abs().max_element() - 1.0).abs() < 1e-6);
        for &i in &cube.indices[t] {
            assert_vec3_near(cube.normals[i as usize], n, 1e-6);
        }
    }
}

/// Two triangles of area 1/2 sharing the edge (0,0,0)-(0,0,1): the first in
/// y = 0 with normal +Y, the second turned about the edge so that the
/// normals are `angle_degrees` apart.
fn hinge(test: &str, angle_degrees: f32) -> Files {
    let (s, c) = angle_degrees.to_radians().sin_cos();
    let obj = format!(
        "o hinge\nusemtl white\nv 0 0 0\nv 0 0 1\nv 1 0 0\nv {} {} 0\nf 1 2 3\nf 2 1 4\n",
        -c, s
    );
    scene_files(test, &obj, "newmtl white\nKd 1 1 1\n")
}

#[test]
fn crease_angle_decides_between_smooth_and_split() {
    let files = hinge("hinge-30", 30.0);
    let smooth = load_obj_with(
        &files.obj,
        &ObjOptions {
            crease_angle_degrees: 60.0,
        },
    )
    .unwrap();
    let m = mesh(&smooth.scene, "hinge");
    assert_eq!(m.positions.len(), 4, "the shared edge is smooth");
    let (n1, n2) = (face_normal(m, 0), face_normal(m, 1));
    assert!((n1.dot(n2) - 30f32.to_radians().cos()).abs() < 1e-5);
    // Equal areas: the shared vertices get the bisector.
    for (p, n) in m.positions.iter().zip(&m.normals) {
        if p.x == 0.0 && p.y == 0.0 {
            assert_vec3_near(*n, (n1 + n2).normalize(), 1e-6);
        }
    }
    let split = load_obj_with(
        &files.obj,
        &ObjOptions {
            crease_angle_degrees: 20.0,
        },
    )
    .unwrap();
    let m = mesh(&split.scene, "hinge");
    assert_eq!(m.positions.len(), 6, "the shared edge is split");
    for t in 0..2 {
        for &i in &m.indices[t] {
            assert_vec3_near(m.normals[i as usize], face_normal(m, t), 1e-6);
        }
    }

    // A right angle is split at the default 60° and smoothed at 100°.
    let files = hinge("hinge-90", 90.0);
    assert_eq!(mesh(&load(&files).scene, "hinge").positions.len(), 6);
    let wide = load_obj_with(
        &files.obj,
        &ObjOptions {
            crease_angle_degrees: 100.0,
        },
    )
    .unwrap();
    assert_eq!(mesh(&wide.scene, "hinge").positions.len(), 4);
}

#[test]
fn generated_normals_are_area_weighted() {
    // A large triangle (area 2) and a small one (area 0.125) sharing the
    // corner at the origin, their normals 20° apart.
    let (s, c) = 20f32.to_radians().sin_cos();
    let obj = format!(
        "o fan\nusemtl white\nv 0 0 0\nv 2 0 0\nv 0 2 0\nv -0.5 0 0\nv 0 {} {}\nf 1 2 3\nf 1 5 4\n",
        0.5 * c,
        0.5 * s
    );
    let files = scene_files("area-weighted", &obj, "newmtl white\nKd 1 1 1\n");
    let scene = load(&files).scene;
    let m = mesh(&scene, "fan");
    let (big, small) = (
        (Vec3::new(2.0, 0.0, 0.0)).cross(Vec3::new(0.0, 2.0, 0.0)),
        Vec3::new(0.0, 0.5 * c, 0.5 * s).cross(Vec3::new(-0.5, 0.0, 0.0)),
    );
    assert!((big.length() / 2.0 - 2.0).abs() < 1e-6 && (small.length() / 2.0 - 0.125).abs() < 1e-6);
    let expected = (big + small).normalize();
    let origin = m.positions.iter().position(|p| *p == Vec3::ZERO).unwrap();
    assert_vec3_near(m.normals[origin], expected, 1e-6);
    assert_eq!(m.positions.len(), 5);
}

#[test]
fn file_normals_are_normalised_and_zero_ones_regenerated() {
    let files = scene_files(
        "file-normals",
        "o a\nusemtl white\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 3\nf 1//1 2//1 3//1\n\
         o b\nv 0 0 1\nv 1 0 1\nv 0 1 1\nvn 0 0 0\nf 4//2 5//2 6//2\n",
        "newmtl white\nKd 1 1 1\n",
    );
    let loaded = load(&files);
    assert_eq!(mesh(&loaded.scene, "a").normals, [Vec3::Z; 3]);
    assert_eq!(mesh(&loaded.scene, "b").normals, [Vec3::Z; 3]);
    assert!(
        loaded.warnings.iter().any(|w| w.contains("zero length")),
        "{:?}",
        loaded.warnings
    );
}

// ---------------------------------------------------------------------------
// Materials.

/// Loads `mtl` with one triangle using its first material.
fn materials_scene(test: &str, mtl: &str) -> (LoadedScene, Files) {
    let first = mtl
        .lines()
        .find_map(|l| l.strip_prefix("newmtl "))
        .unwrap()
        .trim()
        .to_owned();
    let obj = format!("usemtl {first}\nv 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n");
    let files = scene_files(test, &obj, mtl);
    (load(&files), files)
}

#[test]
fn standard_mtl_fields_map_to_models() {
    let mtl = "\
newmtl diffuse
Ka 0.1 0.1 0.1
Kd 0.5 0.25 0.125
newmtl grey
Kd 0.3
newmtl black
newmtl phong
Kd 0.2 0.2 0.2
Ks 0.5 0.4 0.3
Ns 50
illum 2
newmtl mirror
illum 3
Ks 0.9 0.8 0.7
newmtl fresnel_mirror
illum 5
Ks 1 1 1
newmtl glass
Kd 0 0 0
Ni 1.5
d 0.2
Tf 0.9 0.8 0.7
newmtl water
illum 7
Ni 1.33
newmtl cutout
Kd 0.5 0.5 0.5
d -halo 0.5
newmtl tr
Kd 0.5 0.5 0.5
Tr 0.25
newmtl glow
Kd 0 0 0
Ke 2 3 4
newmtl ks_without_ns
Kd 0.5 0.5 0.5
Ks 0.5 0.5 0.5
newmtl illum1
Kd 0.5 0.5 0.5
Ks 0.5 0.5 0.5
Ns 10
illum 1
newmtl illum4_without_ni
Kd 0.5 0.5 0.5
illum 4
";
    let (loaded, _) = materials_scene("standard-mtl", mtl);
    let scene = &loaded.scene;
    let model = |name: &str| material(scene, name).model.clone();
    let diffuse = |r, g, b| MaterialModel::Diffuse {
        reflectance: Rgb::new(r, g, b),
    };
    assert_eq!(model("diffuse"), diffuse(0.5, 0.25, 0.125));
    assert_eq!(model("grey"), diffuse(0.3, 0.3, 0.3));
    assert_eq!(model("black"), diffuse(0.0, 0.0, 0.0));
    assert_eq!(
        model("phong"),
        MaterialModel::Phong {
            diffuse: Rgb::splat(0.2),
            specular: Rgb::new(0.5, 0.4, 0.3),
            exponent: 50.0
        }
    );
    assert_eq!(
        model("mirror"),
        MaterialModel::Mirror {
            reflectance: Rgb::new(0.9, 0.8, 0.7)
        }
    );
    assert_eq!(
        model("fresnel_mirror"),
        MaterialModel::Mirror {
            reflectance: Rgb::ONE
        }
    );
    assert_eq!(
        model("glass"),
        MaterialModel::Dielectric {
            ior: 1.5,
            transmittance: Rgb::new(0.9, 0.8, 0.7)
        }
    );
    assert_eq!(material(scene, "glass").opacity, 0.2);
    assert_eq!(
        model("water"),
        MaterialModel::Dielectric {
            ior: 1.33,
            transmittance: Rgb::ONE
        }
    );
    assert_eq!(material(scene, "water").opacity, 1.0);
    assert_eq!(model("cutout"), diffuse(0.5, 0.5, 0.5));
    assert_eq!(material(scene, "cutout").opacity, 0.5);
    assert_eq!(material(scene, "tr").opacity, 0.75);
    assert_eq!(material(scene, "glow").emission, Rgb::new(2.0, 3.0, 4.0));
    assert!(material(scene, "glow").is_emissive());
    assert_eq!(model("glow"), diffuse(0.0, 0.0, 0.0));
    assert_eq!(model("ks_without_ns"), diffuse(0.5, 0.5, 0.5));
    assert_eq!(model("illum1"), diffuse(0.5, 0.5, 0.5));
    assert_eq!(model("illum4_without_ni"), diffuse(0.5, 0.5, 0.5));
    for what in ["ks_without_ns", "illum1", "illum4_without_ni"] {
        assert!(
            loaded
                .warnings
                .iter()
                .any(|w| w.contains(&format!("`{what}`"))),
            "{what}: {:?}",
            loaded.warnings
        );
    }
    for m in scene.materials() {
        assert!(m.diffuse_texture.is_none() && m.specular_texture.is_none());
    }
}

#[test]
fn pbr_extension_maps_to_rough_conductor_and_blend() {
    let mtl = "\
newmtl metal
Kd 0.9 0.6 0.2
Pm 1
Pr 0.5
newmtl half
Kd 0.4 0.4 0.4
Pm 0.25
Pr 0.4
newmtl plastic
Kd 0.4 0.5 0.6
Pr 0.3
newmtl polished
Kd 0.9 0.9 0.9
Pm 1
Pr 0
newmtl beckmann_metal
Kd 0.9 0.9 0.9
Pm 1
lustre_distribution beckmann
";
    let (loaded, _) = materials_scene("pbr", mtl);
    let scene = &loaded.scene;
    let metal = |kd: Rgb, alpha: f32, distribution| MaterialModel::RoughConductor {
        distribution,
        alpha,
        fresnel: ConductorFresnel::None,
        specular: kd,
    };
    let ggx = MicrofacetDistribution::Ggx;
    assert_eq!(
        material(scene, "metal").model,
        metal(Rgb::new(0.9, 0.6, 0.2), 0.25, ggx)
    );
    assert_eq!(
        material(scene, "half").model,
        MaterialModel::Blend {
            weight: 0.25,
            first: Box::new(MaterialModel::Diffuse {
                reflectance: Rgb::splat(0.4)
            }),
            second: Box::new(metal(Rgb::splat(0.4), 0.4 * 0.4, ggx)),
        }
    );
    assert_eq!(
        material(scene, "plastic").model,
        MaterialModel::Diffuse {
            reflectance: Rgb::new(0.4, 0.5, 0.6)
        }
    );
    assert_eq!(
        material(scene, "polished").model,
        MaterialModel::Mirror {
            reflectance: Rgb::splat(0.9)
        }
    );
    // Pr defaults to 1 (glTF); lustre_distribution overrides GGX.
    assert_eq!(
        material(scene, "beckmann_metal").model,
        metal(Rgb::splat(0.9), 1.0, MicrofacetDistribution::Beckmann)
    );
}

#[test]
fn lustre_keys_map_to_models() {
    let mtl = "\
newmtl ward
Kd 0.3 0.3 0.3
Ks 0.2 0.2 0.2
lustre_model ward
lustre_alpha_x 0.1
lustre_alpha_y 0.2
newmtl ward_iso
lustre_model Ward
lustre_alpha 0.3
newmtl gold
lustre_model beckmann
lustre_alpha 0.1
lustre_eta 0.143 0.374 1.442
lustre_k 3.983 2.385 1.603
newmtl ggx_mirror
lustre_model rough-conductor
lustre_distribution ggx
lustre_alpha 0.2
lustre_fresnel none
Ks 0.9 0.9 0.9
newmtl gaussian
lustre_model conductor
lustre_distribution gaussian
lustre_alpha_x 0.4
lustre_alpha_y 0.4
lustre_fresnel conductor
lustre_eta 1.5
lustre_k 2
newmtl floor
Kd 0.885809 0.698859 0.666422
lustre_model blend
lustre_blend_weight 0.3
lustre_alpha 0.05
lustre_fresnel none
newmtl velvet
Kd 0.5 0.5 0.5
lustre_model oren-nayar
lustre_param sigma 0.3
lustre_param albedo 0.5 0.6 0.7
newmtl explicit_diffuse
Kd 0.1 0.2 0.3
lustre_model diffuse
newmtl explicit_phong
Kd 0.1 0.1 0.1
Ks 0.2 0.2 0.2
Ns 7
lustre_model phong
newmtl explicit_mirror
lustre_model mirror
newmtl explicit_dielectric
Ni 1.7
Tf 0.5 0.5 0.5
lustre_model dielectric
newmtl stray
Kd 0.5 0.5 0.5
lustre_alpha 0.1
lustre_param sigma 1
";
    let (loaded, files) = materials_scene("lustre-keys", mtl);
    let scene = &loaded.scene;
    let model = |name: &str| material(scene, name).model.clone();
    assert_eq!(
        model("ward"),
        MaterialModel::Ward {
            diffuse: Rgb::splat(0.3),
            specular: Rgb::splat(0.2),
            alpha_x: 0.1,
            alpha_y: 0.2
        }
    );
    assert_eq!(
        model("ward_iso"),
        MaterialModel::Ward {
            diffuse: Rgb::ZERO,
            specular: Rgb::ZERO,
            alpha_x: 0.3,
            alpha_y: 0.3
        }
    );
    // The glosbox's gold, as the built-in scene defines it.
    let glosbox = builtin("glosbox").unwrap();
    let builtin_model = |f: &dyn Fn(&MaterialModel) -> bool| {
        glosbox
            .materials()
            .iter()
            .map(|m| m.model.clone())
            .find(|m| f(m))
            .unwrap()
    };
    let builtin_gold = builtin_model(&|m| matches!(m, MaterialModel::RoughConductor { .. }));
    assert_eq!(model("gold"), builtin_gold);
    assert_eq!(
        model("gold"),
        MaterialModel::RoughConductor {
            distribution: MicrofacetDistribution::Beckmann,
            alpha: 0.1,
            fresnel: ConductorFresnel::Complex {
                eta: Rgb::new(0.143, 0.374, 1.442),
                k: Rgb::new(3.983, 2.385, 1.603)
            },
            specular: Rgb::ONE,
        }
    );
    assert_eq!(
        model("ggx_mirror"),
        MaterialModel::RoughConductor {
            distribution: MicrofacetDistribution::Ggx,
            alpha: 0.2,
            fresnel: ConductorFresnel::None,
            specular: Rgb::splat(0.9),
        }
    );
    assert_eq!(
        model("gaussian"),
        MaterialModel::RoughConductor {
            distribution: MicrofacetDistribution::Gaussian,
            alpha: 0.4,
            fresnel: ConductorFresnel::Complex {
                eta: Rgb::splat(1.5),
                k: Rgb::splat(2.0)
            },
            specular: Rgb::ONE,
        }
    );
    // The glosbox floor, as the built-in scene defines it.
    let builtin_floor = builtin_model(&|m| matches!(m, MaterialModel::Blend { .. }));
    assert_eq!(model("floor"), builtin_floor);
    let MaterialModel::Named {
        model: name,
        params,
    } = model("velvet")
    else {
        panic!("velvet is a named model")
    };
    assert_eq!(name, "oren-nayar");
    assert_eq!(params.len(), 2);
    assert_eq!(params["sigma"], [0.3]);
    assert_eq!(params["albedo"], [0.5, 0.6, 0.7]);
    assert_eq!(
        model("explicit_diffuse"),
        MaterialModel::Diffuse {
            reflectance: Rgb::new(0.1, 0.2, 0.3)
        }
    );
    assert_eq!(
        model("explicit_phong"),
        MaterialModel::Phong {
            diffuse: Rgb::splat(0.1),
            specular: Rgb::splat(0.2),
            exponent: 7.0
        }
    );
    assert_eq!(
        model("explicit_mirror"),
        MaterialModel::Mirror {
            reflectance: Rgb::ONE
        }
    );
    assert_eq!(
        model("explicit_dielectric"),
        MaterialModel::Dielectric {
            ior: 1.7,
            transmittance: Rgb::splat(0.5)
        }
    );
    assert_eq!(
        model("stray"),
        MaterialModel::Diffuse {
            reflectance: Rgb::splat(0.5)
        }
    );
    // Keys the chosen model does not read are warned about at their line.
    for (key, line) in [
        ("lustre_alpha", "lustre_alpha 0.1\nlustre_param"),
        ("lustre_param", "lustre_param sigma 1"),
    ] {
        let text = std::fs::read_to_string(&files.mtl).unwrap();
        let n = text[..text.find(line).unwrap()].lines().count() + 1;
        assert!(
            loaded
                .warnings
                .iter()
                .any(|w| w.contains(&format!("scene.mtl:{n}: material `stray`: `{key}`"))),
            "{key}: {:?}",
            loaded.warnings
        );
    }
}

#[test]
fn load_mtl_reads_a_library_on_its_own() {
    let dir = test_dir("load-mtl");
    let path = write(
        &dir,
        "lib.mtl",
        "newmtl a\nKd 0.1 0.1 0.1\nnewmtl b\nKd 0.2 0.2 0.2\nnewmtl a\nKd 0.3 0.3 0.3\nfoo 1\n",
    );
    let lib = load_mtl(&path).unwrap();
    let names: Vec<&str> = lib.materials.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["a", "b"]);
    assert_eq!(
        lib.materials[0].model,
        MaterialModel::Diffuse {
            reflectance: Rgb::splat(0.3)
        }
    );
    assert!(lib.warnings.iter().any(|w| w.contains("`foo`")));
}

#[test]
fn later_material_definitions_replace_earlier_ones_with_a_warning() {
    let dir = test_dir("redefined");
    write(
        &dir,
        "a.mtl",
        &format!("newmtl paint\nKd 1 0 0\n{LIGHT_MTL}"),
    );
    write(&dir, "b.mtl", "newmtl paint\nKd 0 1 0\n");
    let obj = write(
        &dir,
        "s.obj",
        &format!(
            "mtllib a.mtl b.mtl\nusemtl paint\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n{LIGHT_OBJ}"
        ),
    );
    let loaded = load_obj(&obj).unwrap();
    assert_eq!(
        material(&loaded.scene, "paint").model,
        MaterialModel::Diffuse {
            reflectance: Rgb::Y
        }
    );
    assert_eq!(
        loaded
            .scene
            .materials()
            .iter()
            .filter(|m| m.name == "paint")
            .count(),
        1
    );
    assert!(loaded.warnings.iter().any(|w| w.contains("defined again")));
}

#[test]
fn texture_paths_resolve_relative_to_the_mtl_folder() {
    let dir = test_dir("textures");
    write(&dir, "materials/tex/wood.png", "not really a png");
    write(&dir, "materials/tex/my spec.png", "");
    write(&dir, "materials/tex/bump.png", "");
    write(
        &dir,
        "materials/lib.mtl",
        &format!(
            "newmtl wood\nKd 1 1 1\nmap_Kd -s 2 2 1 -o 0.5 0.5 -clamp on tex/wood.png\nmap_Ks tex\\my spec.png\n{LIGHT_MTL}"
        ),
    );
    let obj = write(
        &dir,
        "room.obj",
        &format!(
            "mtllib materials/lib.mtl\nusemtl wood\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n{LIGHT_OBJ}"
        ),
    );
    let loaded = load_obj(&obj).unwrap();
    let wood = material(&loaded.scene, "wood");
    let diffuse = wood.diffuse_texture.as_ref().unwrap();
    assert_eq!(diffuse, &dir.join("materials").join("tex/wood.png"));
    assert!(diffuse.is_file());
    assert!(wood.specular_texture.as_ref().unwrap().is_file());
    assert!(
        wood.specular_texture
            .as_ref()
            .unwrap()
            .ends_with("tex/my spec.png")
    );
    assert!(
        loaded
            .warnings
            .iter()
            .any(|w| w.contains("texture options"))
    );
}

#[test]
fn emissive_material_becomes_an_area_light_with_power_pi_l_a() {
    let files = scene_files(
        "emitter",
        "o floor\nusemtl white\nv -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nf 1 4 3 2\n\
         o lamp\nusemtl lamp\nv -0.25 1 -0.125\nv 0.25 1 -0.125\nv 0.25 1 0.125\nv -0.25 1 0.125\nf 5 6 7 8\n\
         o spark\nusemtl spark\nv 0 0.5 0\nv 0.3 0.5 0\nv 0 0.5 0.2\nf 9 10 11\n",
        "newmtl white\nKd 0.8 0.8 0.8\nnewmtl lamp\nKd 0 0 0\nKe 10 20 30\nnewmtl spark\nKe 5 5 5\n",
    );
    let scene = load(&files).scene;
    // lamp, spark and the helper light.
    assert_eq!(scene.lights().len(), 3);
    let lamp_id = scene
        .meshes()
        .iter()
        .position(|m| m.name == "lamp")
        .unwrap() as u32;
    let spark_id = scene
        .meshes()
        .iter()
        .position(|m| m.name == "spark")
        .unwrap() as u32;
    let area_of = |id| {
        scene
            .lights()
            .iter()
            .find_map(|l| match l {
                Light::Area(a) if a.mesh == Some(id) => Some(a.clone()),
                _ => None,
            })
            .unwrap()
    };
    let lamp = area_of(lamp_id);
    assert_eq!(lamp.radiance, Rgb::new(10.0, 20.0, 30.0));
    let lamp_area = 0.5 * 0.25;
    assert!(matches!(lamp.shape, AreaShape::Rectangle { .. }));
    let expected = PI * Rgb::new(10.0, 20.0, 30.0) * lamp_area;
    assert_vec3_near(Light::Area(lamp).power(), expected, 1e-4);
    let spark = area_of(spark_id);
    let spark_area = 0.5 * 0.3 * 0.2;
    assert_vec3_near(
        Light::Area(spark).power(),
        PI * Rgb::splat(5.0) * spark_area,
        1e-5,
    );
    let total = expected + PI * Rgb::splat(5.0) * spark_area + PI * Rgb::ONE * 1.0;
    assert_vec3_near(scene.total_power(), total, 1e-4);
}

// ---------------------------------------------------------------------------
// Malformed input: a typed error naming the file and the offending line.

/// OBJ bodies with one bad line each, and that line.
const BAD_OBJ: &[(&str, &str, &str)] = &[
    (
        "bad number",
        "v 0 0 0\nv 1 x 0\nv 0 1 0\nf 1 2 3\n",
        "v 1 x 0",
    ),
    (
        "NaN coordinate",
        "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n",
        "v nan 0 0",
    ),
    (
        "inf coordinate",
        "v 0 0 0\nv 1 0 0\nv 0 inf 0\nf 1 2 3\n",
        "v 0 inf 0",
    ),
    (
        "overflowing coordinate",
        "v 0 0 0\nv 1e39 0 0\nv 0 1 0\nf 1 2 3\n",
        "v 1e39 0 0",
    ),
    (
        "two coordinates",
        "v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n",
        "v 1 0",
    ),
    (
        "five numbers",
        "v 0 0 0\nv 1 0 0 1 1\nv 0 1 0\nf 1 2 3\n",
        "v 1 0 0 1 1",
    ),
    (
        "w zero",
        "v 0 0 0\nv 1 0 0 0\nv 0 1 0\nf 1 2 3\n",
        "v 1 0 0 0",
    ),
    (
        "bad texcoord",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0.5 oops\nf 1 2 3\n",
        "vt 0.5 oops",
    ),
    (
        "texcoord NaN",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt NaN 0\nf 1 2 3\n",
        "vt NaN 0",
    ),
    (
        "four texcoords",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0 0 0\nf 1 2 3\n",
        "vt 0 0 0 0",
    ),
    (
        "bad normal",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 1\nf 1 2 3\n",
        "vn 0 1",
    ),
    (
        "normal inf",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 -inf 0\nf 1 2 3\n",
        "vn 0 -inf 0",
    ),
    (
        "index out of range",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n",
        "f 1 2 4",
    ),
    (
        "index beyond the vertices so far",
        "v 0 0 0\nv 1 0 0\nf 1 2 3\nv 0 1 0\n",
        "f 1 2 3",
    ),
    (
        "relative index out of range",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n",
        "f -1 -2 -4",
    ),
    (
        "index zero",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n",
        "f 0 1 2",
    ),
    (
        "texcoord index out of range",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/2 3/1\n",
        "f 1/1 2/2 3/1",
    ),
    (
        "texcoord index zero",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/0 2/1 3/1\n",
        "f 1/0 2/1 3/1",
    ),
    (
        "relative normal index out of range",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//-2\n",
        "f 1//1 2//1 3//-2",
    ),
    (
        "normal index out of range",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//2 3//1\n",
        "f 1//1 2//2 3//1",
    ),
    (
        "texcoord without any vt",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1 2/1 3/1\n",
        "f 1/1 2/1 3/1",
    ),
    (
        "huge index",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999999999999\n",
        "f 1 2 99999999999999999999",
    ),
    (
        "huge relative index",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -9223372036854775808\n",
        "f 1 2 -9223372036854775808",
    ),
    (
        "not an index",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 three\n",
        "f 1 2 three",
    ),
    (
        "too many slashes",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3/1/1/1\n",
        "f 1 2 3/1/1/1",
    ),
    (
        "missing position index",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1 2 /1\n",
        "f 1 2 /1",
    ),
    (
        "two-vertex face",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n",
        "f 1 2",
    ),
    (
        "usemtl without a name",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl\nf 1 2 3\n",
        "usemtl",
    ),
    (
        "mtllib without a name",
        "mtllib\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        "mtllib",
    ),
];

/// One-based number of the only line of `path` equal to `line`.
fn exact_line(path: &Path, line: &str) -> usize {
    let text = std::fs::read_to_string(path).unwrap();
    let found: Vec<usize> = text
        .lines()
        .enumerate()
        .filter(|(_, l)| *l == line)
        .map(|(i, _)| i + 1)
        .collect();
    assert_eq!(
        found.len(),
        1,
        "`{line}` must be exactly one line of {}",
        path.display()
    );
    found[0]
}

#[test]
fn every_malformed_obj_line_is_reported_with_its_line() {
    for (what, body, bad) in BAD_OBJ {
        let files = scene_files(
            &what.replace(' ', "-"),
            &format!("usemtl white\n{body}"),
            "newmtl white\nKd 1 1 1\n",
        );
        match load_obj(&files.obj) {
            Err(GeometryError::Parse { location, message }) => {
                assert_eq!(location.file, files.obj, "{what}: {message}");
                assert_eq!(
                    location.line,
                    Some(exact_line(&files.obj, bad)),
                    "{what}: {message}"
                );
            }
            other => panic!("{what}: expected a parse error, got {other:?}"),
        }
    }
}

#[test]
fn missing_obj_file_is_an_io_error_naming_it() {
    let path = test_dir("missing-obj").join("nothere.obj");
    match load_obj(&path) {
        Err(GeometryError::Io { path: p, source }) => {
            assert_eq!(p, path);
            assert_eq!(source.kind(), std::io::ErrorKind::NotFound);
        }
        other => panic!("{other:?}"),
    }
}

/// The one warning of `loaded` that contains `needle`.
fn warning_with<'a>(loaded: &'a LoadedScene, needle: &str) -> &'a str {
    let found: Vec<&String> = loaded
        .warnings
        .iter()
        .filter(|w| w.contains(needle))
        .collect();
    assert_eq!(found.len(), 1, "{needle} in {:?}", loaded.warnings);
    found[0]
}

/// The material of the only mesh made of `triangles` triangles.
fn material_of(loaded: &LoadedScene, mesh: &str) -> String {
    let scene = &loaded.scene;
    let m = scene
        .meshes()
        .iter()
        .find(|m| m.name == mesh)
        .unwrap_or_else(|| panic!("no mesh {mesh}"));
    scene.materials()[m.material as usize].name.clone()
}

#[test]
fn missing_mtl_file_is_a_warning_and_the_default_material() {
    let dir = test_dir("missing-mtl");
    let obj = write(
        &dir,
        "s.obj",
        "# scene\nmtllib nothere.mtl\nusemtl paint\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    );
    let loaded = load_obj(&obj).unwrap();
    let w = warning_with(&loaded, "nothere.mtl");
    assert!(w.contains("s.obj:2:"), "{w}");
    let w = warning_with(&loaded, "unknown material `paint`");
    assert!(w.contains("s.obj:3:"), "{w}");
    assert_eq!(material_of(&loaded, "s"), DEFAULT_MATERIAL_NAME);
    // Without a light it also got the default studio.
    assert!(loaded.studio.is_some());
}

#[test]
fn usemtl_before_its_mtllib_is_an_unknown_material() {
    let dir = test_dir("usemtl-early");
    write(
        &dir,
        "s.mtl",
        &format!("newmtl white\nKd 1 1 1\n{LIGHT_MTL}"),
    );
    let obj = write(
        &dir,
        "s.obj",
        &format!("usemtl white\nmtllib s.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n{LIGHT_OBJ}"),
    );
    let loaded = load_obj(&obj).unwrap();
    let w = warning_with(&loaded, "unknown material `white`");
    assert!(w.contains("s.obj:1:"), "{w}");
    assert_eq!(material_of(&loaded, "s"), DEFAULT_MATERIAL_NAME);
    // The library's light is there: no studio.
    assert!(loaded.studio.is_none());
}

#[test]
fn missing_texture_is_a_warning_at_the_mtl_line() {
    let files = scene_files(
        "missing-texture",
        "usemtl wood\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        "newmtl wood\nKd 1 1 1\nmap_Kd -s 1 1 1 textures/wood.png\n",
    );
    let loaded = load_obj(&files.obj).unwrap();
    let w = warning_with(&loaded, "wood.png");
    let line = exact_line(&files.mtl, "map_Kd -s 1 1 1 textures/wood.png");
    assert!(w.contains(&format!("scene.mtl:{line}:")), "{w}");
    let wood = loaded
        .scene
        .materials()
        .iter()
        .find(|m| m.name == "wood")
        .unwrap();
    assert_eq!(wood.diffuse_texture, None);
    let files = scene_files(
        "missing-specular-texture",
        "usemtl wood\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        "newmtl wood\nKd 1 1 1\nmap_Ks\n",
    );
    assert_parse_error(load_obj(&files.obj), &files.mtl, "map_Ks");
}

/// MTL bodies (after `newmtl m`) with one bad line each, and the needle of that line.
const BAD_MTL: &[(&str, &str)] = &[
    ("Kd 0.5 abc 0.5", "bad number"),
    ("Kd 1.5 0.5 0.5", "diffuse reflectance above 1"),
    ("Kd -0.1 0.5 0.5", "negative reflectance"),
    ("Kd 0.5 0.5", "two components"),
    ("Kd spectral file.rfl", "spectral colour"),
    ("Ks nan 0 0", "NaN"),
    ("Ks 2 2 2", "specular above 1"),
    ("Ke -1 0 0", "negative emission"),
    ("Ke inf 0 0", "infinite emission"),
    ("Tf 1.2 1 1", "transmittance above 1"),
    ("Ns -1", "negative exponent"),
    ("Ns", "missing exponent"),
    ("Ni 0", "zero ior"),
    ("d 1.5", "opacity above 1"),
    ("d -0.1", "negative opacity"),
    ("Tr 2", "transparency above 1"),
    ("Pr -0.5", "negative roughness"),
    ("Pm 2", "metallic above 1"),
    ("illum 12", "illum out of range"),
    ("illum two", "illum not a number"),
    ("lustre_alpha -0.1", "negative alpha"),
    ("lustre_alpha 0", "zero alpha"),
    ("lustre_alpha_x inf", "infinite alpha_x"),
    ("lustre_eta 0 1 1", "zero eta"),
    ("lustre_k -1 0 0", "negative k"),
    ("lustre_blend_weight 1.5", "weight above 1"),
    ("lustre_distribution phong", "unknown distribution"),
    ("lustre_fresnel schlick", "unknown fresnel"),
    ("lustre_model", "model without a name"),
    ("lustre_param sigma 1 2", "two-value parameter"),
    ("lustre_param", "parameter without a name"),
    ("map_Kd -s", "texture option without a value"),
];

#[test]
fn every_malformed_mtl_line_is_reported_with_its_line() {
    for (line, what) in BAD_MTL {
        let files = scene_files(
            &format!("bad-mtl-{}", what.replace(' ', "-")),
            "usemtl m\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
            &format!("# {what}\nnewmtl m\nKa 0 0 0\n{line}\n"),
        );
        let result = load_obj(&files.obj);
        let text = std::fs::read_to_string(&files.mtl).unwrap();
        let expected = text.lines().position(|l| l == *line).unwrap() + 1;
        match result {
            Err(GeometryError::Parse { location, message }) => {
                assert_eq!(location.file, files.mtl, "{what}: {message}");
                assert_eq!(location.line, Some(expected), "{what}: {message}");
                assert!(message.contains("material `m`"), "{what}: {message}");
            }
            other => panic!("{what}: expected a parse error, got {other:?}"),
        }
    }
}

/// Material mappings that cannot be built, and the line that is at fault.
const BAD_LUSTRE: &[(&str, &str, &str)] = &[
    (
        "ward without alpha",
        "lustre_model ward\nKd 0.5 0.5 0.5\n",
        "lustre_model",
    ),
    (
        "beckmann without alpha",
        "lustre_model beckmann\n",
        "lustre_model",
    ),
    (
        "anisotropic conductor",
        "lustre_model rough-conductor\nlustre_alpha_x 0.1\nlustre_alpha_y 0.2\n",
        "lustre_model",
    ),
    (
        "blend without weight",
        "lustre_model blend\nlustre_alpha 0.1\n",
        "lustre_model",
    ),
    (
        "phong without Ns",
        "lustre_model phong\nKs 0.5 0.5 0.5\n",
        "lustre_model",
    ),
    (
        "dielectric without Ni",
        "lustre_model dielectric\n",
        "lustre_model",
    ),
    (
        "eta without k",
        "lustre_model beckmann\nlustre_alpha 0.1\nlustre_eta 1 1 1\n",
        "lustre_eta",
    ),
    (
        "k without eta",
        "lustre_model beckmann\nlustre_alpha 0.1\nlustre_k 1 1 1\n",
        "lustre_k",
    ),
    (
        "conductor fresnel without eta",
        "lustre_model beckmann\nlustre_alpha 0.1\nlustre_fresnel conductor\n",
        "lustre_fresnel",
    ),
    (
        "beckmann with ggx",
        "lustre_model beckmann\nlustre_alpha 0.1\nlustre_distribution ggx\n",
        "lustre_distribution",
    ),
];

#[test]
fn impossible_lustre_models_are_reported_at_the_line_at_fault() {
    for (what, body, needle) in BAD_LUSTRE {
        let files = scene_files(
            &format!("bad-lustre-{}", what.replace(' ', "-")),
            "usemtl m\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
            &format!("newmtl m\n{body}"),
        );
        assert_parse_error(load_obj(&files.obj), &files.mtl, needle);
    }
}

#[test]
fn mtl_statement_before_newmtl_and_nameless_newmtl_are_errors() {
    let files = scene_files(
        "before-newmtl",
        "usemtl m\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        "# header\nKd 1 1 1\nnewmtl m\n",
    );
    assert_parse_error(load_obj(&files.obj), &files.mtl, "Kd 1 1 1");
    let files = scene_files(
        "nameless-newmtl",
        "usemtl m\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        "newmtl m\nnewmtl   \n",
    );
    assert_parse_error(load_obj(&files.obj), &files.mtl, "newmtl   ");
}

#[test]
fn file_without_faces_is_an_empty_mesh_naming_the_file() {
    let dir = test_dir("no-faces");
    let obj = write(&dir, "points.obj", "o cloud\nv 0 0 0\nv 1 0 0\nv 0 1 0\n");
    match load_obj(&obj) {
        Err(GeometryError::EmptyMesh { mesh, file }) => {
            assert_eq!(mesh, "points");
            assert_eq!(file, Some(obj.clone()));
        }
        other => panic!("{other:?}"),
    }
    // An empty file too.
    let empty = write(&dir, "empty.obj", "");
    assert!(
        matches!(load_obj(&empty), Err(GeometryError::EmptyMesh { file: Some(f), .. }) if f == empty)
    );
}

#[test]
fn mesh_of_only_degenerate_triangles_is_an_empty_mesh_naming_the_file() {
    let files = scene_files(
        "all-degenerate",
        "o sliver\nusemtl white\nv 0 0 0\nv 1 1 1\nv 2 2 2\nf 1 2 3\nf 1 1 2\n",
        "newmtl white\nKd 1 1 1\n",
    );
    match load_obj(&files.obj) {
        Err(GeometryError::EmptyMesh { mesh, file }) => {
            assert_eq!(mesh, "sliver");
            assert_eq!(file, Some(files.obj.clone()));
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn invalid_utf8_is_reported_at_its_line() {
    let dir = test_dir("utf8");
    let obj = dir.join("bad.obj");
    std::fs::write(&obj, b"v 0 0 0\nv 1 0 0\no caf\xe9\nv 0 1 0\nf 1 2 3\n").unwrap();
    match load_obj(&obj) {
        Err(GeometryError::Parse { location, .. }) => {
            assert_eq!(location.file, obj);
            assert_eq!(location.line, Some(3));
        }
        other => panic!("{other:?}"),
    }
}

/// A model without an emitter gets the default studio: a ground plane at
/// the bottom of its box and an area light above it whose irradiance under
/// it is about π W/m² (checked against the area light's own exact
/// irradiance by sampling it), the same for the model in millimetres.
#[test]
fn obj_without_an_emitter_gets_a_default_studio() {
    let dir = test_dir("no-light");
    for (name, scale) in [("dark", 1.0f32), ("dark-mm", 1000.0)] {
        let v = |x: f32, y: f32, z: f32| format!("v {} {} {}\n", x * scale, y * scale, z * scale);
        let text = format!(
            "{}{}{}{}f 1 2 3\nf 1 3 4\n",
            v(0.0, 0.2, 0.0),
            v(1.0, 0.2, 0.0),
            v(1.0, 0.7, 1.0),
            v(0.0, 0.7, 1.0)
        );
        let obj = write(&dir, &format!("{name}.obj"), &text);
        let loaded = load_obj(&obj).unwrap();
        let studio = loaded.studio.expect("a studio");
        warning_with(&loaded, "default studio");
        let scene = &loaded.scene;
        assert_eq!(scene.name, name);
        assert_eq!(scene.lights().len(), 1);
        // A thousandth of the largest extent (1) under the model's base.
        assert!((studio.ground_height - 0.199 * scale).abs() < 1e-5 * scale);
        assert!((studio.light_side - 0.5 * scale).abs() < 1e-4 * scale);
        // Irradiance at the ground under the light's centre, by the area
        // light's own sampling (Monte Carlo over its quad).
        let p = Vec3::new(
            studio.light_centre.x,
            studio.ground_height,
            studio.light_centre.z,
        );
        let light = &scene.lights()[0];
        let n = 64;
        let mut e = 0.0;
        for i in 0..n {
            for j in 0..n {
                let u = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                if let Some(s) = light.sample_direct(p, u) {
                    e += s.weight.y * s.direction.y.max(0.0);
                }
            }
        }
        e /= (n * n) as f32;
        assert!((e / PI - 1.0).abs() < 0.1, "{name}: E = {e}");
        // The camera looks at the model, not at the studio.
        let camera = scene.camera();
        let model = Aabb::from_points([
            Vec3::new(0.0, 0.2, 0.0) * scale,
            Vec3::new(1.0, 0.7, 1.0) * scale,
        ]);
        assert_vec3_near(camera.target, model.center(), 1e-4 * scale);
    }
}

// ---------------------------------------------------------------------------
// Garbage never panics.

const VALID_OBJ: &str = "o box\nusemtl white\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\nf 1/1/1 2/2/1 3/3/1\nf 1 3 4\n";
const VALID_MTL: &str = "newmtl white\nKd 0.5 0.5 0.5\nKs 0.1 0.1 0.1\nNs 10\n";

fn garbage_line() -> impl Strategy<Value = String> {
    let keyword = prop_oneof![
        Just("v"),
        Just("vt"),
        Just("vn"),
        Just("f"),
        Just("o"),
        Just("g"),
        Just("l"),
        Just("p"),
        Just("s"),
        Just("usemtl"),
        Just("mtllib"),
        Just("newmtl"),
        Just("Kd"),
        Just("Ks"),
        Just("Ke"),
        Just("Ns"),
        Just("Ni"),
        Just("d"),
        Just("Tr"),
        Just("illum"),
        Just("map_Kd"),
        Just("Pr"),
        Just("lustre_model"),
        Just("lustre_alpha"),
        Just("lustre_param"),
        Just("#"),
        Just(""),
    ];
    let token = prop_oneof![
        any::<i64>().prop_map(|i| i.to_string()),
        (-20i64..20).prop_map(|i| i.to_string()),
        any::<f32>().prop_map(|f| f.to_string()),
        "[0-9/+-]{1,8}",
        "[ -~]{0,10}",
        Just("nan".to_owned()),
        Just("-inf".to_owned()),
        Just("1//".to_owned()),
        Just("white".to_owned()),
        "\\PC{0,6}",
    ];
    prop_oneof![
        (keyword, prop::collection::vec(token, 0..6))
            .prop_map(|(k, t)| format!("{k} {}", t.join(" "))),
        "[ -~]{0,40}",
        "\\PC{0,20}",
    ]
}

fn insert_lines(base: &str, inserts: &[(usize, String)]) -> String {
    let mut lines: Vec<String> = base.lines().map(str::to_owned).collect();
    for (at, line) in inserts {
        let at = at % (lines.len() + 1);
        lines.insert(at, line.replace(['\n', '\r'], " "));
    }
    lines.join("\n") + "\n"
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn garbage_lines_in_a_valid_obj_never_panic(
        obj_inserts in prop::collection::vec((any::<usize>(), garbage_line()), 1..4),
        mtl_inserts in prop::collection::vec((any::<usize>(), garbage_line()), 0..3),
        crease in prop_oneof![Just(60.0f32), 0.0f32..180.0, Just(f32::NAN), Just(-5.0f32)],
    ) {
        let files = scene_files(
            "garbage",
            &insert_lines(VALID_OBJ, &obj_inserts),
            &insert_lines(VALID_MTL, &mtl_inserts),
        );
        match load_obj_with(&files.obj, &ObjOptions { crease_angle_degrees: crease }) {
            Ok(loaded) => {
                for m in loaded.scene.meshes() {
                    prop_assert!(m.validate().is_ok());
                }
            }
            Err(GeometryError::Parse { location, .. }) => {
                prop_assert!(location.file == files.obj || location.file == files.mtl);
            }
            Err(_) => {}
        }
        let _ = std::fs::remove_dir_all(&files.dir);
    }
}

/// One statement of a structurally plausible OBJ stream.
fn statement() -> impl Strategy<Value = String> {
    let coordinate = || prop_oneof![(-2i32..3).prop_map(|i| i as f32), -2.0f32..2.0];
    // Mostly in range of the four `v`, two `vt` and two `vn` every stream starts with.
    let index = |n: i64| prop_oneof![8 => 1..=n, 8 => -n..=-1, 1 => -n - 2..n + 3];
    let attribute = |n: i64| prop_oneof![2 => Just(None), 1 => index(n).prop_map(Some)];
    let reference = (index(4), attribute(2), attribute(2)).prop_map(|(v, vt, vn)| match (vt, vn) {
        (None, None) => v.to_string(),
        (Some(t), None) => format!("{v}/{t}"),
        (None, Some(n)) => format!("{v}//{n}"),
        (Some(t), Some(n)) => format!("{v}/{t}/{n}"),
    });
    prop_oneof![
        4 => (coordinate(), coordinate(), coordinate()).prop_map(|(x, y, z)| format!("v {x} {y} {z}")),
        1 => (coordinate(), coordinate()).prop_map(|(u, v)| format!("vt {u} {v}")),
        1 => (coordinate(), coordinate(), coordinate()).prop_map(|(x, y, z)| format!("vn {x} {y} {z}")),
        4 => prop::collection::vec(reference, 3..6).prop_map(|r| format!("f {}", r.join(" "))),
        1 => prop_oneof![Just("o a"), Just("o b"), Just("g a"), Just("g")].prop_map(str::to_owned),
        1 => prop_oneof![Just("usemtl white"), Just("usemtl red")].prop_map(str::to_owned),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, failure_persistence: None, ..ProptestConfig::default() })]

    /// Random streams of `v`, `vt`, `vn`, `f`, `o`/`g` and `usemtl` either
    /// load, with every fan triangle kept or counted as degenerate and every
    /// mesh valid, or fail with an error naming the OBJ file.
    #[test]
    fn random_statement_streams_load_or_fail_cleanly(statements in prop::collection::vec(statement(), 1..40)) {
        let body = format!("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 1\nvt 0 0\nvt 1 0\nvn 0 0 1\nvn 0 1 0\n{}\n", statements.join("\n"));
        let files = scene_files("streams", &body, "newmtl white\nKd 1 1 1\nnewmtl red\nKd 1 0 0\n");
        let fan_triangles: usize = statements
            .iter()
            .filter(|s| s.starts_with("f "))
            .map(|s| s.split_whitespace().count() - 3)
            .sum();
        match load_obj(&files.obj) {
            Ok(loaded) => {
                for m in loaded.scene.meshes() {
                    prop_assert!(m.validate().is_ok());
                }
                // The light's two triangles come on top.
                prop_assert_eq!(
                    loaded.scene.triangle_count() + loaded.degenerate_triangles_dropped,
                    fan_triangles + 2
                );
            }
            Err(GeometryError::Parse { location, .. }) => {
                prop_assert_eq!(&location.file, &files.obj);
                prop_assert!(location.line.is_some());
            }
            Err(GeometryError::EmptyMesh { file, .. }) => prop_assert_eq!(file, Some(files.obj.clone())),
            Err(other) => prop_assert!(false, "unexpected error {other}"),
        }
        let _ = std::fs::remove_dir_all(&files.dir);
    }
}
