//! Mobile objects of a scene (García et al. 2003, section 2.2.2): paths
//! registered with `Scene::with_mobile`, posing with `Scene::pose_at`, the
//! incremental re-derivation against a full one, and the Cornell box's small
//! box staying inside the box and clear of the large box.

use glam::{Affine3A, Quat, Vec2, Vec3};
use lustre_geometry::builtin::small_box_path;
use lustre_geometry::{
    Camera, GeometryError, Keyframe, Material, Mesh, Object, ObjectPath, PathEnd, Scene, builtin,
};

fn mesh_id(scene: &Scene, name: &str) -> u32 {
    scene.meshes().iter().position(|m| m.name == name).unwrap() as u32
}

/// The scene built from scratch with `scene`'s objects as posed now (no explicit lights).
fn rebuilt(scene: &Scene) -> Scene {
    Scene::new(
        scene.name.clone(),
        scene.meshes().to_vec(),
        scene.materials().to_vec(),
        scene.objects().to_vec(),
        Vec::new(),
        *scene.camera(),
    )
    .unwrap()
}

/// Asserts that the derived data of `a` (posed incrementally) equals that of a full build.
fn assert_same_derivation(a: &Scene) {
    let b = rebuilt(a);
    assert_eq!(a.surfaces(), b.surfaces());
    assert_eq!(a.lights(), b.lights());
    assert_eq!(a.bounds(), b.bounds());
    for id in 0..a.triangle_count() as u32 {
        assert_eq!(a.triangle_surface(id), b.triangle_surface(id));
    }
}

#[test]
fn posing_incrementally_equals_a_full_derivation() {
    for name in ["cornell", "glosbox", "tree"] {
        let mut scene = builtin(name).unwrap();
        assert_same_derivation(&scene);
        let path = scene.mobile_objects()[0].path.clone();
        for t in [0.3, 1.7, 4.0, 7.9, 11.5] {
            scene.pose_at(t).unwrap();
            let object = scene.mobile_objects()[0].object;
            assert_eq!(scene.objects()[object as usize].transform, path.at(t));
            assert_same_derivation(&scene);
        }
    }
    // Moving an object that changes the scene's size still matches (a full derivation).
    let mut scene = builtin("cornell").unwrap();
    let small = scene.object_by_name("small-box").unwrap();
    scene
        .set_object_transform(small, Affine3A::from_translation(Vec3::new(0.0, 3.0, 0.0)))
        .unwrap();
    assert_same_derivation(&scene);
}

#[test]
fn cornell_boxes_have_the_small_box_mobile_and_start_at_rest() {
    for name in ["cornell", "glosbox"] {
        let scene = builtin(name).unwrap();
        let small = scene.object_by_name("small-box").unwrap();
        assert_eq!(scene.mobile_objects().len(), 1);
        assert_eq!(scene.mobile_objects()[0].object, small);
        assert_eq!(scene.mobile_objects()[0].path, small_box_path());
        // Time 0 is Mitsuba's pose, bit for bit.
        assert_eq!(
            scene.objects()[small as usize].transform,
            Affine3A::IDENTITY
        );
        let m = mesh_id(&scene, "small-box");
        assert_eq!(
            scene.world_positions(m),
            scene.meshes()[m as usize].positions
        );
    }
    let path = small_box_path();
    assert_eq!(path.end(), PathEnd::Loop);
    assert!(path.duration() > 0.0);
    assert!(
        path.at(path.duration())
            .abs_diff_eq(Affine3A::IDENTITY, 1e-6)
    );
}

/// Projection interval of `points` on `axis`.
fn interval(points: &[Vec3], axis: Vec3) -> (f32, f32) {
    points
        .iter()
        .map(|p| p.dot(axis))
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), d| {
            (lo.min(d), hi.max(d))
        })
}

#[test]
fn small_box_stays_inside_and_clear_of_the_large_box() {
    for name in ["cornell", "glosbox"] {
        let mut scene = builtin(name).unwrap();
        let (small, large) = (mesh_id(&scene, "small-box"), mesh_id(&scene, "large-box"));
        let large_positions = scene.world_positions(large);
        let large_normals = scene.world_normals(large);
        let path = scene.mobile_objects()[0].path.clone();
        let mut closest = f32::INFINITY;
        let mut turned = 0.0f32;
        let mut moved = 0.0f32;
        for t in path.frame_times(400) {
            scene.pose_at(t).unwrap();
            let positions = scene.world_positions(small);
            let normals = scene.world_normals(small);
            // Inside the box [-1, 1]³, resting on the floor.
            for p in &positions {
                assert!(p.abs().max_element() <= 1.0 + 1e-5, "{name} t = {t}: {p}");
            }
            let (bottom, _) = interval(&positions, Vec3::Y);
            assert!(
                (bottom + 1.0).abs() < 1e-5,
                "{name} t = {t}: bottom {bottom}"
            );
            // Both boxes stand upright, so their vertical faces' normals are
            // the separating axes to try (the y ranges overlap).
            let separation = normals
                .iter()
                .chain(&large_normals)
                .filter(|n| n.y.abs() < 0.5)
                .map(|&n| {
                    let (a0, a1) = interval(&positions, n);
                    let (b0, b1) = interval(&large_positions, n);
                    (b0 - a1).max(a0 - b1)
                })
                .fold(f32::NEG_INFINITY, f32::max);
            closest = closest.min(separation);
            let xf = scene.objects()[scene.mobile_objects()[0].object as usize].transform;
            turned = turned.max(Quat::from_mat3a(&xf.matrix3).angle_between(Quat::IDENTITY));
            moved = moved.max(xf.translation.length());
        }
        assert!(closest > 0.02, "{name}: the boxes come within {closest}");
        assert!(
            turned > 1.0 && moved > 0.3,
            "{name}: turned {turned}, moved {moved}"
        );
    }
}

/// A one-triangle-and-a-light scene without mobile objects.
fn plain_scene() -> Scene {
    let tri = Mesh::flat("tri", &[Vec3::ZERO, Vec3::X, Vec3::Z], &[[0, 2, 1]], 0);
    let light = Mesh::flat(
        "light",
        &[Vec3::Y, Vec3::Y + Vec3::X, Vec3::Y + Vec3::Z],
        &[[0, 1, 2]],
        1,
    );
    let object = |name: &str, m: u32| Object {
        name: name.into(),
        meshes: vec![m],
        transform: Affine3A::IDENTITY,
    };
    Scene::new(
        "plain",
        vec![tri, light],
        vec![
            Material::diffuse("white", Vec3::splat(0.5)),
            Material::diffuse("light", Vec3::ONE).with_emission(Vec3::ONE),
        ],
        vec![object("tri", 0), object("light", 1)],
        Vec::new(),
        Camera::look_at(Vec3::new(0.0, 2.0, 3.0), Vec3::ZERO, Vec3::Y, 40.0),
    )
    .unwrap()
}

fn slide(to: Vec3) -> ObjectPath {
    ObjectPath::new(
        vec![
            Keyframe::new(0.0, Vec3::new(0.1, 0.0, 0.0), Quat::IDENTITY),
            Keyframe::new(2.0, to, Quat::from_rotation_y(0.5)),
        ],
        PathEnd::Clamp,
    )
    .unwrap()
}

#[test]
fn with_mobile_registers_poses_and_replaces() {
    let mut scene = plain_scene();
    assert!(scene.mobile_objects().is_empty());
    scene.pose_at(3.0).unwrap();
    assert!(matches!(
        plain_scene().with_mobile("nope", slide(Vec3::X)),
        Err(GeometryError::UnknownObject(_))
    ));
    let scene = scene.with_mobile("tri", slide(Vec3::X)).unwrap();
    let tri = scene.object_by_name("tri").unwrap();
    assert_eq!(
        scene.objects()[tri as usize].transform,
        Affine3A::from_translation(Vec3::new(0.1, 0.0, 0.0)),
        "posed at the path's start"
    );
    let mut scene = scene.with_mobile("tri", slide(Vec3::Z)).unwrap();
    assert_eq!(
        scene.mobile_objects().len(),
        1,
        "a second path replaces the first"
    );
    assert_eq!(scene.mobile_objects()[0].path, slide(Vec3::Z));
    scene.pose_at(2.0).unwrap();
    let expected = Affine3A::from_rotation_translation(Quat::from_rotation_y(0.5), Vec3::Z);
    assert!(
        scene.objects()[tri as usize]
            .transform
            .abs_diff_eq(expected, 1e-6)
    );
    assert_same_derivation(&scene);
}

#[test]
fn mobile_objects_survive_new_materials_and_meshes() {
    let mut scene = builtin("cornell").unwrap();
    scene.pose_at(3.0).unwrap();
    let posed = scene.objects().to_vec();
    let with_materials = scene.with_materials(scene.materials().to_vec()).unwrap();
    assert_eq!(with_materials.mobile_objects(), scene.mobile_objects());
    assert_eq!(with_materials.objects(), &posed[..]);
    let with_meshes = scene.with_meshes(scene.meshes().to_vec()).unwrap();
    assert_eq!(with_meshes.mobile_objects(), scene.mobile_objects());
    assert_eq!(with_meshes.objects(), &posed[..]);
    let points = scene.with_area_lights_as_points().unwrap();
    assert_eq!(points.mobile_objects(), scene.mobile_objects());
    // The UVs of a mesh are untouched by posing.
    let m = mesh_id(&scene, "small-box");
    assert!(
        scene.meshes()[m as usize]
            .uvs
            .iter()
            .all(|uv| *uv != Vec2::NAN)
    );
}
