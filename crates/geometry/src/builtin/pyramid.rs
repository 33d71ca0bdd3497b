//! `pyramid`: the test scene of Bastos, Hoff, Wynn & Lastra 1999 (section 9
//! and the colour plate): a copper pyramid and a diffuse teapot inside a
//! textured cube, 16,350 triangles (the paper's had 16,000; 14,032 of ours
//! are the teapot's), with eight planar glossy reflectors (the paper's scene
//! had "up to 11").
//!
//! The scene model has no image textures for the diffuse albedo, so the
//! room's texture is made of geometry: every face of the cube is cut into
//! 0.5 m cells, each cell a flat quad of one of a few diffuse materials
//! (coplanar cells meet exactly on shared corners, no overlap).
//!
//! Geometry, in metres (+y up; the camera looks towards -z):
//!
//! - Room ([`ROOM_HALF`], [`ROOM_HEIGHT`]): x ∈ [-2, 2], y ∈ [0, 4],
//!   z ∈ [-2, 2], inward-facing cells of [`CELL`]: a checkerboard floor of
//!   light and dark tiles (`floor-light`, `floor-dark`), a checkerboard
//!   ceiling of two whites (`ceiling-light`, `ceiling-dark`), and walls with
//!   a 1 m terracotta wainscot (`wainscot`) under vertical stripes of sand
//!   and sage panels (`wall-sand`, `wall-sage`).
//! - Glossy wall panels ([`GLOSSY_PANEL`], red lacquer, [`varnish`]): `glossy-panel-back`
//!   (z = -2, facing +z), `glossy-panel-left` (x = -2, facing +x) and
//!   `glossy-panel-right` (x = 2, facing -x), each the 2 m × 1.5 m of cells
//!   in the middle of its wall from y = 1 to 2.5 (horizontal coordinate in
//!   [-1, 1]), in place of the striped cells there.
//! - Plinth (`plinth`, diffuse grey): the box x ∈ [0.05, 0.75],
//!   y ∈ [0, 0.199], z ∈ [-0.85, -0.15].
//! - Pyramid ([`PYRAMID_CENTRE`], [`PYRAMID_HALF_BASE`],
//!   [`PYRAMID_HEIGHT`], copper): a square base of side 1 at y = 0.2 centred
//!   at (0.4, 0.2, -0.5), overhanging the plinth, apex 0.8 m above it; four
//!   slanted faces `pyramid-front` (+z), `pyramid-right` (+x),
//!   `pyramid-back` (-z), `pyramid-left` (-x), each a triangle cut into
//!   [`PYRAMID_LEVELS`]² = 256 triangles, and `pyramid-base` facing down
//!   (16 × 16 cells, 512 triangles); the five meshes meet on shared
//!   vertices and together close the solid.
//! - Teapot (`teapot`, diffuse ivory, [`TEAPOT_CENTRE`]): a procedural
//!   teapot on the floor at (-0.65, 0, 0), 0.43 m high: a lathed body
//!   (radius 0.16 at the foot, 0.25 at the belly, a rolled rim), a lathed lid
//!   with a knob, a tapering spout towards +x and a handle towards -x (tubes
//!   along cubic Bézier curves); four closed parts, smooth shaded.
//! - Light: a 1.2 × 0.8 m rectangle centred at (0, 3.999, 0) facing down,
//!   radiance [`LIGHT_RADIANCE`].
//! - Camera at (0.35, 1.55, 1.45) looking at (-0.1, 0.5, -0.45), 55°
//!   vertical field of view: in front of the pyramid and above it, it sees three of
//!   its faces (front, left and right, each at its own angle to the viewer,
//!   as in the paper's plate), the teapot on the left and the back panel.
//!
//! Reflectors ([`REFLECTORS`]): the five copper faces and the three lacquer
//! panels, each a single planar mesh. Everything else is diffuse.
//!
//! Closed meshes ([`CLOSED_MESHES`]): the plinth and the teapot; the five
//! pyramid meshes are closed together.

use std::f32::consts::PI;

use glam::{Vec2, Vec3};

use super::parts::{
    Outline, append, bezier, cells, cuboid, edges, empty, lathe, push_triangle, quad, tube,
};
use crate::Object;
use crate::material::{ConductorFresnel, MicrofacetDistribution};
use crate::{Camera, Material, MaterialModel, Mesh, Rgb, Scene};

/// Triangles of the paper's model: "a simple textured 16,000-triangle model" (Bastos et al. 1999, section 9).
pub const PAPER_TRIANGLES: usize = 16_000;
/// Half the side of the cube room.
pub const ROOM_HALF: f32 = 2.0;
/// Height of the cube room.
pub const ROOM_HEIGHT: f32 = 4.0;
/// Side of a texture cell of the floor, walls and ceiling.
pub const CELL: f32 = 0.5;
/// Centre of the pyramid's base.
pub const PYRAMID_CENTRE: Vec3 = Vec3::new(0.4, 0.2, -0.5);
/// Half the side of the pyramid's square base.
pub const PYRAMID_HALF_BASE: f32 = 0.5;
/// Height of the pyramid's apex above its base.
pub const PYRAMID_HEIGHT: f32 = 0.8;
/// Rows of triangles from base to apex on each slanted face.
pub const PYRAMID_LEVELS: u32 = 16;
/// Roughness of the copper: Beckmann alpha (Bastos et al. 1999, section 9: Cook-Torrance copper).
pub const COPPER_ALPHA: f32 = 0.1;
/// Complex index of refraction of copper at R, G, B (real part).
pub const COPPER_ETA: Rgb = Rgb::new(0.200438, 0.924033, 1.10221);
/// Complex index of refraction of copper at R, G, B (imaginary part).
pub const COPPER_K: Rgb = Rgb::new(3.91295, 2.45285, 2.14219);
/// Roughness (Beckmann alpha) of the lacquered wall panels.
pub const GLOSSY_PANEL_ALPHA: f32 = 0.05;
/// The glossy wall panels' extent along their walls and in y.
pub const GLOSSY_PANEL: ((f32, f32), (f32, f32)) = ((-1.0, 1.0), (1.0, 2.5));
/// Where the teapot stands (the centre of its foot).
pub const TEAPOT_CENTRE: Vec3 = Vec3::new(-0.65, 0.0, 0.0);
/// Radiance of the ceiling light, in W/(m² sr).
pub const LIGHT_RADIANCE: Rgb = Rgb::new(16.0, 15.5, 14.5);
/// Size (x, z) of the ceiling light.
pub const LIGHT_SIZE: Vec2 = Vec2::new(1.2, 0.8);
/// Where the camera stands.
pub const CAMERA_POSITION: Vec3 = Vec3::new(0.35, 1.55, 1.45);
/// The pyramid's four slanted faces, facing +z, +x, -z and -x.
pub const PYRAMID_FACES: [&str; 4] = [
    "pyramid-front",
    "pyramid-right",
    "pyramid-back",
    "pyramid-left",
];
/// The planar glossy reflectors: the copper pyramid's faces and base, and the lacquered panels.
pub const REFLECTORS: [&str; 8] = [
    "pyramid-front",
    "pyramid-right",
    "pyramid-back",
    "pyramid-left",
    "pyramid-base",
    "glossy-panel-back",
    "glossy-panel-left",
    "glossy-panel-right",
];
/// The meshes that are closed manifolds with outward faces.
pub const CLOSED_MESHES: &[&str] = &["plinth", "teapot"];

/// The copper of the pyramid: a Beckmann rough conductor with copper's complex index.
pub fn copper() -> MaterialModel {
    MaterialModel::RoughConductor {
        distribution: MicrofacetDistribution::Beckmann,
        alpha: COPPER_ALPHA,
        fresnel: ConductorFresnel::Complex {
            eta: COPPER_ETA,
            k: COPPER_K,
        },
        specular: Rgb::ONE,
    }
}

/// A varnished or lacquered surface: half a diffuse base of `diffuse` (so
/// `diffuse / 2` in all), half a Beckmann lobe of roughness `alpha` with the
/// Fresnel of a varnish of index 1.5 (a conductor's Fresnel with k = 0 is the
/// dielectric's): weak facing the viewer, strong at grazing angles
/// (Bastos et al. 1999, section 8.2.2, "varnished wood").
pub fn varnish(diffuse: Rgb, alpha: f32) -> MaterialModel {
    MaterialModel::Blend {
        weight: 0.5,
        first: Box::new(MaterialModel::Diffuse {
            reflectance: diffuse,
        }),
        second: Box::new(MaterialModel::RoughConductor {
            distribution: MicrofacetDistribution::Beckmann,
            alpha,
            fresnel: ConductorFresnel::Complex {
                eta: Rgb::splat(1.5),
                k: Rgb::ZERO,
            },
            specular: Rgb::ONE,
        }),
    }
}

/// `pyramid`: Bastos et al.'s copper pyramid and teapot in a textured cube (section 9).
pub fn pyramid() -> Scene {
    let names = [
        "floor-light",
        "floor-dark",
        "ceiling-light",
        "ceiling-dark",
        "wainscot",
        "wall-sand",
        "wall-sage",
        "lacquer",
        "copper",
        "plinth",
        "teapot",
        "light",
    ];
    let id = |name: &str| names.iter().position(|n| *n == name).unwrap_or(0) as u32;
    let materials = vec![
        Material::diffuse("floor-light", Rgb::new(0.78, 0.75, 0.68)),
        Material::diffuse("floor-dark", Rgb::new(0.22, 0.2, 0.19)),
        Material::diffuse("ceiling-light", Rgb::splat(0.82)),
        Material::diffuse("ceiling-dark", Rgb::splat(0.68)),
        Material::diffuse("wainscot", Rgb::new(0.55, 0.3, 0.2)),
        Material::diffuse("wall-sand", Rgb::new(0.78, 0.7, 0.55)),
        Material::diffuse("wall-sage", Rgb::new(0.45, 0.55, 0.42)),
        Material::new(
            "lacquer",
            varnish(Rgb::new(0.5, 0.12, 0.1), GLOSSY_PANEL_ALPHA),
        ),
        Material::new("copper", copper()),
        Material::diffuse("plinth", Rgb::splat(0.5)),
        Material::diffuse("teapot", Rgb::new(0.8, 0.78, 0.7)),
        Material::diffuse("light", Rgb::splat(0.8)).with_emission(LIGHT_RADIANCE),
    ];
    debug_assert_eq!(materials.len(), names.len());
    let mut meshes = room(&id);
    meshes.push(cuboid(
        "plinth",
        Vec3::new(0.05, 0.0, -0.85),
        Vec3::new(0.75, 0.199, -0.15),
        id("plinth"),
    ));
    meshes.extend(pyramid_meshes(id("copper")));
    meshes.push(teapot("teapot", TEAPOT_CENTRE, id("teapot")));
    let s = LIGHT_SIZE;
    meshes.push(quad(
        "light",
        Vec3::new(-0.5 * s.x, ROOM_HEIGHT - 0.001, -0.5 * s.y),
        s.x * Vec3::X,
        s.y * Vec3::Z,
        id("light"),
    ));
    let camera = Camera::look_at(CAMERA_POSITION, Vec3::new(-0.1, 0.5, -0.45), Vec3::Y, 55.0);
    Scene::new(
        "pyramid",
        meshes.clone(),
        materials,
        Object::one_per_mesh(&meshes),
        Vec::new(),
        camera,
    )
    .expect("the built-in pyramid scene is valid")
}

/// The cube's cells: floor, ceiling, walls and the glossy panels.
fn room(id: &dyn Fn(&str) -> u32) -> Vec<Mesh> {
    let (h, top) = (ROOM_HALF, ROOM_HEIGHT);
    let across = edges(-h, h, (2.0 * h / CELL) as u32);
    let up = edges(0.0, top, (top / CELL) as u32);
    let checker = |i: usize, j: usize| (i + j).is_multiple_of(2);
    // The floor and ceiling: axis y, cells along z (u) and x (v).
    let mut meshes = vec![
        cells(
            "floor-light",
            1,
            0.0,
            &across,
            &across,
            true,
            checker,
            id("floor-light"),
        ),
        cells(
            "floor-dark",
            1,
            0.0,
            &across,
            &across,
            true,
            |i, j| !checker(i, j),
            id("floor-dark"),
        ),
        cells(
            "ceiling-light",
            1,
            top,
            &across,
            &across,
            false,
            checker,
            id("ceiling-light"),
        ),
        cells(
            "ceiling-dark",
            1,
            top,
            &across,
            &across,
            false,
            |i, j| !checker(i, j),
            id("ceiling-dark"),
        ),
    ];
    // Walls: (axis, at, facing +axis, whether it carries a glossy panel).
    // For axis x the cells run along y (u) and z (v); for axis z along x (u) and y (v).
    let walls = [
        (0, -h, true, Some("glossy-panel-left")),
        (0, h, false, Some("glossy-panel-right")),
        (2, -h, true, Some("glossy-panel-back")),
        (2, h, false, None),
    ];
    let ((p0, p1), (q0, q1)) = GLOSSY_PANEL;
    let in_panel = |along: usize, height: usize| {
        let (a, y) = (across[along] + 0.5 * CELL, up[height] + 0.5 * CELL);
        a > p0 && a < p1 && y > q0 && y < q1
    };
    let mut wall_parts: [Mesh; 3] = [
        empty("wainscot", id("wainscot")),
        empty("wall-sand", id("wall-sand")),
        empty("wall-sage", id("wall-sage")),
    ];
    for (axis, at, positive, panel) in walls {
        // (along, height) of cell (i, j) of this wall's grid.
        let cell = move |i: usize, j: usize| if axis == 0 { (j, i) } else { (i, j) };
        let (u, v) = if axis == 0 {
            (&up, &across)
        } else {
            (&across, &up)
        };
        let kind = |i: usize, j: usize| {
            let (along, height) = cell(i, j);
            if panel.is_some() && in_panel(along, height) {
                None
            } else if up[height] < 1.0 {
                Some(0)
            } else {
                Some(1 + along % 2)
            }
        };
        for (k, part) in wall_parts.iter_mut().enumerate() {
            let name = part.name.clone();
            let material = part.material;
            append(
                part,
                &cells(
                    &name,
                    axis,
                    at,
                    u,
                    v,
                    positive,
                    |i, j| kind(i, j) == Some(k),
                    material,
                ),
            );
        }
        if let Some(name) = panel {
            meshes.push(cells(
                name,
                axis,
                at,
                u,
                v,
                positive,
                |i, j| kind(i, j).is_none(),
                id("lacquer"),
            ));
        }
    }
    meshes.extend(wall_parts);
    meshes
}

/// Lattice (X, Z) of column `j` (from -s to s in steps of 2) of a face's row of half-width `s`.
type Column = fn(i32, i32) -> (i32, i32);

/// The copper pyramid: four slanted faces and the base, on one lattice.
fn pyramid_meshes(material: u32) -> Vec<Mesh> {
    let n = PYRAMID_LEVELS as i32;
    let (c, b, height) = (PYRAMID_CENTRE, PYRAMID_HALF_BASE, PYRAMID_HEIGHT);
    // Lattice point (X, level, Z): X and Z in units of b / n from the centre,
    // level in units of height / n up from the base. Each point is one
    // function of its integers, so faces share edge vertices bit for bit.
    let point = |x: i32, level: i32, z: i32| {
        Vec3::new(
            c.x + b * (x as f32 / n as f32),
            c.y + height * (level as f32 / n as f32),
            c.z + b * (z as f32 / n as f32),
        )
    };
    // Each face: its outward direction in the base plane, and (X, Z) of the
    // j-th of the 2 s + 1 lattice columns at half-width s (row step 2).
    let faces: [(&str, Vec3, Column); 4] = [
        (PYRAMID_FACES[0], Vec3::Z, |s, x| (x, s)),
        (PYRAMID_FACES[1], Vec3::X, |s, z| (s, -z)),
        (PYRAMID_FACES[2], -Vec3::Z, |s, x| (-x, -s)),
        (PYRAMID_FACES[3], -Vec3::X, |s, z| (-s, z)),
    ];
    let mut meshes = Vec::new();
    for (name, out, column) in faces {
        let normal = (out * height + Vec3::Y * b).normalize();
        let mut mesh = empty(name, material);
        // Row r (level r) holds n - r + 1 points, from column -s to s in steps of 2, s = n - r.
        let mut rows = Vec::new();
        for r in 0..=n {
            let s = n - r;
            let start = mesh.positions.len() as u32;
            for j in 0..=s {
                let (x, z) = column(s, 2 * j - s);
                mesh.positions.push(point(x, r, z));
                mesh.normals.push(normal);
                mesh.uvs.push(Vec2::new(
                    if s > 0 { j as f32 / s as f32 } else { 0.5 },
                    r as f32 / n as f32,
                ));
            }
            rows.push(start);
        }
        for r in 0..n as usize {
            let (lo, hi, s) = (rows[r], rows[r + 1], (n - r as i32) as u32);
            for j in 0..s {
                push_triangle(&mut mesh, [lo + j, lo + j + 1, hi + j], normal);
                if j + 1 < s {
                    push_triangle(&mut mesh, [lo + j + 1, hi + j + 1, hi + j], normal);
                }
            }
        }
        meshes.push(mesh);
    }
    // The base: (n × n) cells of the lattice's even points at level 0, facing down.
    let mut base = empty("pyramid-base", material);
    for i in 0..n {
        for k in 0..n {
            let (x0, z0) = (2 * i - n, 2 * k - n);
            let start = base.positions.len() as u32;
            for (dx, dz) in [(0, 0), (2, 0), (2, 2), (0, 2)] {
                base.positions.push(point(x0 + dx, 0, z0 + dz));
                base.normals.push(-Vec3::Y);
                base.uvs.push(Vec2::new(
                    (x0 + dx + n) as f32 / (2 * n) as f32,
                    (z0 + dz + n) as f32 / (2 * n) as f32,
                ));
            }
            push_triangle(&mut base, [start, start + 1, start + 2], -Vec3::Y);
            push_triangle(&mut base, [start + 2, start + 3, start], -Vec3::Y);
        }
    }
    meshes.push(base);
    meshes
}

/// A procedural teapot standing at `at` (the centre of its foot), 0.43 m
/// high, spout towards +x: body, lid, spout and handle, each closed.
pub(crate) fn teapot(name: &str, at: Vec3, material: u32) -> Mesh {
    let (body_height, belly, foot) = (0.3, 0.25, 0.16);
    let circle = |radius: f32, arc_segments: u32| Outline {
        centre: Vec2::new(at.x, at.z),
        half: Vec2::ZERO,
        radius,
        arc_segments,
        side_step: 1.0,
    };
    // Body: radius foot + (belly - foot) sin(π t^0.9) over height t, then a rolled rim.
    let mut profile: Vec<Vec2> = (0..=44)
        .map(|k| {
            let t = k as f32 / 44.0;
            let r = foot + (belly - foot) * (PI * t.powf(0.9)).sin();
            Vec2::new(belly - r, at.y + body_height * t)
        })
        .collect();
    let rim_top = at.y + body_height + 0.016;
    for k in 1..=6 {
        let phi = PI * k as f32 / 6.0;
        // Half a circle of radius 8 mm outwards over the rim, ending 16 mm higher.
        let r = foot + 0.008 * phi.sin();
        profile.push(Vec2::new(
            belly - r,
            at.y + body_height + 0.008 * (1.0 - phi.cos()),
        ));
    }
    let mut mesh = lathe(name, &circle(belly, 20), &profile, material);
    // Lid: a low dome from just inside the rim to a knob.
    let lid_radius = 0.15;
    let mut lid: Vec<Vec2> = (0..=14)
        .map(|k| {
            let phi = 1.3 * k as f32 / 14.0;
            let r = lid_radius * phi.cos();
            Vec2::new(lid_radius - r, rim_top + 0.055 * phi.sin())
        })
        .collect();
    // The knob: a neck of radius 0.02, then a squashed ball of radius 0.032
    // (0.024 high) closing at a 6 mm cap.
    let neck = rim_top + 0.055 * 1.3f32.sin();
    let knob = neck + 0.035;
    lid.push(Vec2::new(lid_radius - 0.02, knob - 0.02));
    for k in 0..=8 {
        let phi = -0.85 + (1.38 + 0.85) * k as f32 / 8.0;
        lid.push(Vec2::new(
            lid_radius - 0.032 * phi.cos(),
            knob + 0.024 * phi.sin(),
        ));
    }
    append(
        &mut mesh,
        &lathe(name, &circle(lid_radius, 16), &lid, material),
    );
    // Spout: from inside the body out and up, tapering.
    let v = |x: f32, y: f32| at + Vec3::new(x, y, 0.0);
    let spout = bezier(
        [v(0.12, 0.09), v(0.3, 0.07), v(0.3, 0.24), v(0.39, 0.3)],
        22,
    );
    let spout_radii: Vec<f32> = (0..spout.len())
        .map(|k| 0.05 - 0.026 * k as f32 / (spout.len() - 1) as f32)
        .collect();
    append(
        &mut mesh,
        &tube(name, &spout, &spout_radii, Vec3::Z, 32, material),
    );
    // Handle: a C from the upper back of the body round to its lower back.
    let handle = bezier(
        [
            v(-0.19, 0.23),
            v(-0.44, 0.26),
            v(-0.42, 0.03),
            v(-0.19, 0.07),
        ],
        24,
    );
    append(
        &mut mesh,
        &tube(
            name,
            &handle,
            &vec![0.022; handle.len()],
            Vec3::Z,
            24,
            material,
        ),
    );
    mesh
}
