//! The scene model and the built-in scenes, checked against DESIGN.md by hand-computed values.

use std::f32::consts::PI;

use glam::{Affine3A, Quat, Vec3};
use lustre_geometry::light::{AreaShape, Light};
use lustre_geometry::material::{ConductorFresnel, MaterialModel, MicrofacetDistribution};
use lustre_geometry::{
    GeometryError, Material, Mesh, Object, Scene, SurfaceKind, builtin, builtin::BUILTIN_SCENES,
};

fn surface_of<'a>(scene: &'a Scene, mesh: &str) -> Vec<&'a lustre_geometry::Surface> {
    let m = scene.meshes().iter().position(|m| m.name == mesh).unwrap() as u32;
    scene.surfaces().iter().filter(|s| s.mesh == m).collect()
}

#[test]
fn cornell_matches_the_design() {
    let scene = builtin("cornell").unwrap();
    assert_eq!(scene.triangle_count(), 6 * 2 + 2 * 12);
    let b = scene.bounds();
    // The large box (centre y = -0.4, half height 0.61) sinks 1 cm into the floor, as in Mitsuba.
    let expected_min = Vec3::new(-1.0, -1.01, -1.0);
    assert!(
        (b.min - expected_min).length() < 1e-6 && (b.max - Vec3::ONE).length() < 1e-6,
        "{b:?}"
    );
    // Six walls and the light are one planar surface each; each box has six faces.
    assert_eq!(scene.surfaces().len(), 6 + 12);
    for (name, normal) in [
        ("floor", Vec3::Y),
        ("ceiling", -Vec3::Y),
        ("back", Vec3::Z),
        ("green-wall", -Vec3::X),
        ("red-wall", Vec3::X),
        ("light", -Vec3::Y),
    ] {
        let s = surface_of(&scene, name);
        assert_eq!(s.len(), 1, "{name}");
        let SurfaceKind::Planar(plane) = s[0].kind else {
            panic!("{name} is not planar")
        };
        assert!(
            (plane.normal - normal).length() < 1e-6,
            "{name}: {:?}",
            plane.normal
        );
        let expected_area = if name == "light" { 0.46 * 0.38 } else { 4.0 };
        assert!(
            (s[0].area - expected_area).abs() < 1e-5,
            "{name}: {}",
            s[0].area
        );
    }
    // Boxes: side 0.6 (scale 0.3 of [-1,1]); the large box is 1.22 tall.
    let small: f32 = surface_of(&scene, "small-box").iter().map(|s| s.area).sum();
    assert!((small - 6.0 * 0.36).abs() < 1e-4, "{small}");
    let large: Vec<f32> = surface_of(&scene, "large-box")
        .iter()
        .map(|s| s.area)
        .collect();
    assert_eq!(large.len(), 6);
    assert!((large.iter().sum::<f32>() - (2.0 * 0.36 + 4.0 * 0.6 * 1.22)).abs() < 1e-4);
    // The small box stands on the floor: its bottom at y = -1, top at y = -0.4.
    let small_id = scene
        .meshes()
        .iter()
        .position(|m| m.name == "small-box")
        .unwrap() as u32;
    let ys: Vec<f32> = scene
        .world_positions(small_id)
        .iter()
        .map(|p| p.y)
        .collect();
    assert!((ys.iter().copied().fold(f32::MAX, f32::min) + 1.0).abs() < 1e-6);
    assert!((ys.iter().copied().fold(f32::MIN, f32::max) + 0.4).abs() < 1e-6);
    // One area light: the rectangle, with power π L A.
    assert_eq!(scene.lights().len(), 1);
    let Light::Area(light) = &scene.lights()[0] else {
        panic!("not an area light")
    };
    let AreaShape::Rectangle {
        origin,
        edge_u,
        edge_v,
    } = light.shape
    else {
        panic!("not a rectangle")
    };
    let centre = origin + 0.5 * (edge_u + edge_v);
    assert!(
        (centre - Vec3::new(0.0, 0.99, 0.01)).length() < 1e-6,
        "{centre}"
    );
    assert!(edge_u.cross(edge_v).normalize().dot(-Vec3::Y) > 0.9999);
    let radiance = Vec3::new(18.387, 13.9873, 6.75357);
    assert!((scene.total_power() - PI * radiance * 0.46 * 0.38).length() < 1e-4);
    // Materials: the walls' reflectances.
    let diffuse = |name: &str| {
        let m = scene
            .meshes()
            .iter()
            .find(|m| m.name == name)
            .unwrap()
            .material;
        match &scene.materials()[m as usize].model {
            MaterialModel::Diffuse { reflectance } => *reflectance,
            other => panic!("{other:?}"),
        }
    };
    assert_eq!(
        diffuse("red-wall"),
        Vec3::new(0.570068, 0.0430135, 0.0443706)
    );
    assert_eq!(
        diffuse("green-wall"),
        Vec3::new(0.105421, 0.37798, 0.076425)
    );
    assert_eq!(diffuse("floor"), Vec3::new(0.885809, 0.698859, 0.666422));
    assert_eq!(diffuse("light"), Vec3::new(0.885809, 0.698859, 0.666422));
    let cam = scene.camera();
    assert_eq!(
        (cam.position, cam.target, cam.fov_y_degrees),
        (Vec3::new(0.0, 0.0, 3.9), Vec3::ZERO, 39.3077)
    );
}

#[test]
fn box_transforms_are_the_rotations_mitsuba_builds() {
    // Mitsuba builds the boxes as translate * rotate_y * scale; the matrices in
    // DESIGN.md are those products. Check ours against the product.
    let scene = builtin("cornell").unwrap();
    for (name, t, degrees, s) in [
        (
            "small-box",
            Vec3::new(0.335, -0.7, 0.38),
            -17.0f32,
            Vec3::splat(0.3),
        ),
        (
            "large-box",
            Vec3::new(-0.33, -0.4, -0.28),
            18.25,
            Vec3::new(0.3, 0.61, 0.3),
        ),
    ] {
        let xf = Affine3A::from_scale_rotation_translation(
            s,
            Quat::from_rotation_y(degrees.to_radians()),
            t,
        );
        let id = scene.meshes().iter().position(|m| m.name == name).unwrap() as u32;
        for p in scene.world_positions(id) {
            // Every corner is xf of a corner of [-1, 1]^3.
            let local = xf.inverse().transform_point3(p);
            assert!(
                local.abs().cmple(Vec3::splat(1.0 + 1e-4)).all()
                    && (local.abs() - Vec3::ONE).abs().max_element() < 1e-4,
                "{name}: {local}"
            );
        }
    }
}

#[test]
fn glosbox_has_the_gold_box_and_the_glossy_floor() {
    let scene = builtin("glosbox").unwrap();
    let material = |name: &str| {
        let m = scene
            .meshes()
            .iter()
            .find(|m| m.name == name)
            .unwrap()
            .material;
        scene.materials()[m as usize].model.clone()
    };
    assert_eq!(
        material("large-box"),
        MaterialModel::RoughConductor {
            distribution: MicrofacetDistribution::Beckmann,
            alpha: 0.1,
            fresnel: ConductorFresnel::Complex {
                eta: Vec3::new(0.143, 0.374, 1.442),
                k: Vec3::new(3.983, 2.385, 1.603)
            },
            specular: Vec3::ONE,
        }
    );
    let MaterialModel::Blend {
        weight,
        first,
        second,
    } = material("floor")
    else {
        panic!()
    };
    assert_eq!(weight, 0.3);
    assert_eq!(
        *first,
        MaterialModel::Diffuse {
            reflectance: Vec3::new(0.885809, 0.698859, 0.666422)
        }
    );
    assert!(matches!(
        *second,
        MaterialModel::RoughConductor {
            alpha: 0.05,
            fresnel: ConductorFresnel::None,
            ..
        }
    ));
    // Everything else is the Cornell box.
    let cornell = builtin("cornell").unwrap();
    assert_eq!(scene.triangle_count(), cornell.triangle_count());
    assert_eq!(scene.total_power(), cornell.total_power());
    for name in BUILTIN_SCENES {
        assert!(builtin(name).is_ok());
    }
    assert!(matches!(
        builtin("nope"),
        Err(GeometryError::UnknownScene { .. })
    ));
}

#[test]
fn moving_an_object_moves_its_light_and_keeps_its_areas() {
    let mut scene = builtin("cornell").unwrap();
    let before: Vec<f32> = scene.surfaces().iter().map(|s| s.area).collect();
    let light = scene.object_by_name("light").unwrap();
    let motion =
        Affine3A::from_rotation_translation(Quat::from_rotation_y(0.7), Vec3::new(0.1, -0.2, 0.05));
    scene.set_object_transform(light, motion).unwrap();
    let after: Vec<f32> = scene.surfaces().iter().map(|s| s.area).collect();
    for (a, b) in before.iter().zip(&after) {
        assert!((a - b).abs() < 1e-5);
    }
    let Light::Area(l) = &scene.lights()[0] else {
        panic!()
    };
    let expected = motion.transform_point3(Vec3::new(0.0, 0.99, 0.01));
    assert!((l.shape.centroid() - expected).length() < 1e-5);
    assert!(scene.set_object_transform(99, Affine3A::IDENTITY).is_err());
    assert!(
        scene
            .set_object_transform(light, Affine3A::from_scale(Vec3::splat(f32::NAN)))
            .is_err()
    );
}

fn quad(name: &str, y: f32, material: u32) -> Mesh {
    Mesh::flat(
        name,
        &[
            Vec3::new(-1.0, y, -1.0),
            Vec3::new(-1.0, y, 1.0),
            Vec3::new(1.0, y, 1.0),
            Vec3::new(1.0, y, -1.0),
        ],
        &[[0, 1, 2], [2, 3, 0]],
        material,
    )
}

#[test]
fn invalid_scenes_are_typed_errors() {
    let cam = lustre_geometry::Camera::look_at(Vec3::Z, Vec3::ZERO, Vec3::Y, 40.0);
    let white = Material::diffuse("white", Vec3::splat(0.5));
    let object = |meshes: Vec<u32>| Object {
        name: "o".into(),
        meshes,
        transform: Affine3A::IDENTITY,
    };
    // No light.
    let err = Scene::new(
        "dark",
        vec![quad("q", 0.0, 0)],
        vec![white.clone()],
        vec![object(vec![0])],
        vec![],
        cam,
    );
    assert!(matches!(err, Err(GeometryError::NoLight(_))), "{err:?}");
    // A mesh in no object, a mesh in two, a missing material, an index out of range, NaN, empty.
    let lit = || vec![white.clone(), white.clone().with_emission(Vec3::ONE)];
    let two = || vec![quad("q", 0.0, 0), quad("l", 1.0, 1)];
    assert!(Scene::new("s", two(), lit(), vec![object(vec![0])], vec![], cam).is_err());
    assert!(
        Scene::new(
            "s",
            two(),
            lit(),
            vec![object(vec![0, 1]), object(vec![1])],
            vec![],
            cam
        )
        .is_err()
    );
    assert!(
        Scene::new(
            "s",
            vec![quad("q", 0.0, 5)],
            lit(),
            vec![object(vec![0])],
            vec![],
            cam
        )
        .is_err()
    );
    let mut bad = two();
    bad[0].indices[0] = [0, 1, 99];
    assert!(matches!(
        Scene::new("s", bad, lit(), vec![object(vec![0, 1])], vec![], cam),
        Err(GeometryError::InvalidMesh { .. })
    ));
    let mut nan = two();
    nan[0].positions[0].x = f32::NAN;
    assert!(matches!(
        Scene::new("s", nan, lit(), vec![object(vec![0, 1])], vec![], cam),
        Err(GeometryError::InvalidMesh { .. })
    ));
    let mut empty = two();
    empty[0].indices.clear();
    assert!(matches!(
        Scene::new("s", empty, lit(), vec![object(vec![0, 1])], vec![], cam),
        Err(GeometryError::EmptyMesh { .. })
    ));
    // A valid one: the emissive quad became a rectangle light with the right orientation.
    let scene = Scene::new("s", two(), lit(), vec![object(vec![0, 1])], vec![], cam).unwrap();
    let Light::Area(l) = &scene.lights()[0] else {
        panic!()
    };
    assert!(matches!(l.shape, AreaShape::Rectangle { .. }));
    assert!((l.shape.mean_normal() - Vec3::Y).length() < 1e-6);
    assert_eq!(l.mesh, Some(1));
}

#[test]
fn degenerate_triangles_are_removed_and_counted() {
    let mut m = quad("q", 0.0, 0);
    // A triangle with a repeated corner, and one whose corners are collinear.
    m.indices.push([0, 0, 1]);
    m.positions.push(Vec3::new(0.0, 0.0, -1.0)); // midway between corners 0 and 4
    m.normals.push(Vec3::Y);
    m.uvs.push(glam::Vec2::ZERO);
    let n = m.positions.len() as u32;
    assert_eq!(
        (m.positions[0], m.positions[4]),
        (Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 0.0, -1.0))
    );
    m.indices.push([0, 4, n - 1]);
    let removed = m.remove_degenerate(1e-12);
    assert_eq!(removed, 2);
    assert_eq!(m.indices.len(), 2);
}

#[test]
fn curved_meshes_form_one_curved_surface() {
    // An octahedron with smooth normals (the normalised positions): one curved surface.
    let p = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
    let indices = vec![
        [0, 2, 4],
        [2, 1, 4],
        [1, 3, 4],
        [3, 0, 4],
        [2, 0, 5],
        [1, 2, 5],
        [3, 1, 5],
        [0, 3, 5],
    ];
    let mesh = Mesh {
        name: "ball".into(),
        positions: p.to_vec(),
        normals: p.to_vec(),
        uvs: vec![glam::Vec2::ZERO; 6],
        indices,
        material: 0,
    };
    let area = mesh.area();
    let white = Material::diffuse("white", Vec3::splat(0.5));
    let scene = Scene::new(
        "ball",
        vec![mesh, quad("l", 3.0, 1)],
        vec![white.clone(), white.with_emission(Vec3::ONE)],
        vec![Object {
            name: "o".into(),
            meshes: vec![0, 1],
            transform: Affine3A::IDENTITY,
        }],
        vec![],
        lustre_geometry::Camera::look_at(Vec3::Z * 4.0, Vec3::ZERO, Vec3::Y, 40.0),
    )
    .unwrap();
    let ball: Vec<_> = scene.surfaces().iter().filter(|s| s.mesh == 0).collect();
    assert_eq!(ball.len(), 1);
    assert_eq!(ball[0].kind, SurfaceKind::Curved);
    assert!((ball[0].area - area).abs() < 1e-5);
    assert!((area - 8.0 * 3f32.sqrt() / 2.0).abs() < 1e-5);
}

#[test]
fn area_lights_become_cosine_point_lights_of_equal_power_and_stay_so_after_a_move() {
    let scene = builtin("cornell").unwrap();
    let points = scene.with_area_lights_as_points().unwrap();
    assert!(points.area_lights_as_points());
    assert_eq!(points.lights().len(), scene.lights().len());
    for (a, p) in scene.lights().iter().zip(points.lights()) {
        let Light::Area(area) = a else {
            panic!("cornell's light is an area light");
        };
        let Light::OrientedPoint(o) = p else {
            panic!("not replaced: {p:?}");
        };
        // Independent expectation: the centroid of cornell's light rectangle and I0 = L A.
        assert!((o.position - Vec3::new(0.0, 0.99, 0.01)).length() < 1e-4);
        let expected = area.radiance * (0.46 * 0.38);
        assert!((o.intensity - expected).abs().max_element() < 1e-3 * expected.max_element());
        assert!((p.power() - a.power()).abs().max_element() < 1e-3 * a.power().max_element());
    }
    // The emitter mesh stays as geometry.
    assert_eq!(points.triangle_count(), scene.triangle_count());
    let mut moved = points.clone();
    moved
        .set_object_transform(0, Affine3A::from_translation(Vec3::ZERO))
        .unwrap();
    assert!(matches!(moved.lights()[0], Light::OrientedPoint(_)));
}

#[test]
fn with_meshes_replaces_the_geometry_and_keeps_the_rest() {
    let scene = builtin("cornell")
        .unwrap()
        .with_area_lights_as_points()
        .unwrap();
    // The floor with unshared vertices: two more vertices, the same triangles and surfaces.
    let mut meshes = scene.meshes().to_vec();
    let floor = &meshes[0];
    let split = Mesh::flat(
        floor.name.clone(),
        &floor.positions,
        &floor.indices,
        floor.material,
    );
    assert_eq!(split.positions.len(), 6);
    meshes[0] = split;
    let replaced = scene.with_meshes(meshes).unwrap();
    assert_eq!(replaced.meshes()[0].positions.len(), 6);
    assert_eq!(replaced.triangle_count(), scene.triangle_count());
    assert_eq!(replaced.surfaces().len(), scene.surfaces().len());
    assert!(replaced.area_lights_as_points());
    assert_eq!(replaced.materials(), scene.materials());
    assert_eq!(replaced.camera(), scene.camera());
    let err = scene.with_meshes(Vec::new()).unwrap_err().to_string();
    assert!(err.contains("0 meshes given to replace 8"), "{err}");
}
