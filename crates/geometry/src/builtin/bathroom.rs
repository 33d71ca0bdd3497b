//! `bathroom`: the class of Diefenbach & Badler 1997's bathroom (figures 1,
//! 16 and 17; section 8: 40,463 polygons, "1 overhead and 4 vanity lights"),
//! built procedurally: a vanity mirror over a counter with a vessel sink, a
//! refractive shower door with a handle in front of a tub, tiles, a towel rail.
//!
//! Geometry, in metres (+y up; the camera looks towards -z):
//!
//! - Room: x ∈ [-1.6, 1.6], y ∈ [0, 2.5], z ∈ [-1.4, 1.4]; floor, ceiling
//!   and four walls, inward-facing quads (diffuse).
//! - Tub (`tub`): a lathed solid along the right wall over a rounded
//!   rectangle of footprint x ∈ [0.798, 1.598], z ∈ [-1.398, 0.302] (corner
//!   radius 0.25), 0.55 high: vertical outer walls, a rounded rim of radius
//!   0.035 on top, inner walls sloping 5 cm inwards down to a 0.1 m fillet and
//!   a flat basin floor at y = 0.06; flat bottom and basin caps; about 38,000
//!   triangles, smooth shaded.
//! - Shower door (`shower-door`, [`DOOR_IOR`]): a closed glass slab 1 cm
//!   thick, x ∈ [0.83, 0.84], y ∈ [0.552, 2.0], z ∈ [-1.39, 0.29], standing
//!   on the tub's rim; both faces refract (in- and out-refraction, section 2).
//! - Door handle (`door-handle`, diffuse bronze): a 2 × 2 × 40 cm grip bar
//!   at x ∈ [0.765, 0.785], y ∈ [1.0, 1.4], z ∈ [0.12, 0.14] on two
//!   standoffs reaching to 0.5 mm from the door's room-side face.
//! - Vanity on the back wall: cabinet x ∈ [-1.42, -0.28], y ∈ [0.001, 0.808],
//!   z ∈ [-1.399, -0.88]; counter slab x ∈ [-1.45, -0.25], y ∈ [0.81,
//!   0.85], z ∈ [-1.399, -0.85]; a lathed vessel sink of radius 0.2 and
//!   0.12 m high centred at (-0.85, 0.851, -1.1); a faucet of two boxes.
//! - Vanity mirror (`vanity-mirror`, [`MIRROR_REFLECTANCE`]): one quad in the
//!   plane z = -1.385 facing +z, x ∈ [-1.35, -0.35], y ∈ [1.1, 1.8], in a
//!   4 cm diffuse frame from the wall to z = -1.37.
//! - Lights: `overhead-light`, a 0.6 × 0.6 rectangle centred at (0, 2.499, 0)
//!   facing down, radiance [`OVERHEAD_RADIANCE`]; four `vanity-light-N`,
//!   0.2 × 0.1 rectangles facing down at y = 1.899 under 0.22 m wide fixture
//!   boxes above the mirror, centred at x = -1.225, -0.975, -0.725, -0.475,
//!   z = -1.34,
//!   radiance [`VANITY_RADIANCE`].
//! - Tiles: 135 tiles of 0.15 × 0.15 × 0.006 with 5 mm joints above the tub
//!   on the right and back walls (y ∈ [0.56, 1.955]).
//! - Towel rail on the left wall: a bar of radius 1.2 cm from z = -0.1 to 0.6
//!   at (x, y) = (-1.52, 1.15) on two posts, and a towel slab hanging in front.
//! - Camera at (-0.55, 1.55, 1.3) looking at (0.29, 0.95, -1.0), 70° vertical
//!   field of view: the mirror on the left, the door and the tub behind it on
//!   the right.
//!
//! Every mesh but the room's quads, the mirror and the light rectangles is a
//! closed manifold with outward faces ([`CLOSED_MESHES`]); the door is the
//! inside of its slab for the dielectric.

use std::f32::consts::PI;

use glam::{Vec2, Vec3};

use super::parts::{Outline, append, cuboid, cylinder, empty, frame_solid, lathe, quad};
use crate::Object;
use crate::{Camera, Material, MaterialModel, Mesh, Rgb, Scene};

/// Index of refraction of the shower door (Diefenbach & Badler 1997, section 3).
pub const DOOR_IOR: f32 = 1.5;
/// Reflectance of the vanity mirror (Diefenbach & Badler 1997, section 3).
pub const MIRROR_REFLECTANCE: Rgb = Rgb::new(0.9, 0.9, 0.9);
/// Radiance of the overhead light, in W/(m² sr) (Diefenbach & Badler 1997, figure 1).
pub const OVERHEAD_RADIANCE: Rgb = Rgb::new(10.5, 10.0, 9.5);
/// Radiance of each vanity light, in W/(m² sr) (Diefenbach & Badler 1997, figure 1).
pub const VANITY_RADIANCE: Rgb = Rgb::new(25.0, 22.6, 18.8);
/// x of the centres of the four vanity lights.
pub const VANITY_LIGHT_X: [f32; 4] = [-1.225, -0.975, -0.725, -0.475];
/// The polygon count of the paper's bathroom (Diefenbach & Badler 1997, section 8).
pub const PAPER_POLYGONS: usize = 40_463;
/// The meshes that are closed manifolds with outward faces (section 4.1's shadow volumes need them).
pub const CLOSED_MESHES: &[&str] = &[
    "tub",
    "shower-door",
    "door-handle",
    "cabinet",
    "counter",
    "sink",
    "faucet",
    "mirror-frame",
    "vanity-fixtures",
    "tiles",
    "towel-rail",
    "towel",
];

/// `bathroom`: the paper's bathroom class (Diefenbach & Badler 1997, figures 1 and 16).
pub fn bathroom() -> Scene {
    let names = [
        "wall",
        "floor",
        "ceiling",
        "tub",
        "glass",
        "bronze",
        "wood",
        "counter",
        "porcelain",
        "chrome",
        "mirror",
        "frame",
        "tile",
        "towel",
        "overhead",
        "vanity",
    ];
    let id = |name: &str| names.iter().position(|n| *n == name).unwrap_or(0) as u32;
    let materials = vec![
        Material::diffuse("wall", Rgb::new(0.75, 0.7, 0.6)),
        Material::diffuse("floor", Rgb::new(0.4, 0.36, 0.32)),
        Material::diffuse("ceiling", Rgb::splat(0.8)),
        Material::diffuse("tub", Rgb::new(0.85, 0.85, 0.82)),
        Material::new(
            "glass",
            MaterialModel::Dielectric {
                ior: DOOR_IOR,
                transmittance: Rgb::ONE,
            },
        ),
        Material::diffuse("bronze", Rgb::new(0.3, 0.2, 0.12)),
        Material::diffuse("wood", Rgb::new(0.45, 0.3, 0.18)),
        Material::diffuse("counter", Rgb::new(0.25, 0.25, 0.27)),
        Material::diffuse("porcelain", Rgb::new(0.85, 0.85, 0.85)),
        Material::diffuse("chrome", Rgb::splat(0.6)),
        Material::new(
            "mirror",
            MaterialModel::Mirror {
                reflectance: MIRROR_REFLECTANCE,
            },
        ),
        Material::diffuse("frame", Rgb::new(0.2, 0.15, 0.1)),
        Material::diffuse("tile", Rgb::new(0.7, 0.8, 0.85)),
        Material::diffuse("towel", Rgb::new(0.1, 0.45, 0.5)),
        Material::diffuse("overhead", Rgb::splat(0.8)).with_emission(OVERHEAD_RADIANCE),
        Material::diffuse("vanity", Rgb::splat(0.8)).with_emission(VANITY_RADIANCE),
    ];
    debug_assert_eq!(materials.len(), names.len());
    let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
    let (hx, top, hz) = (1.6, 2.5, 1.4);
    let (v, v2) = (Vec3::new, Vec2::new);
    let mut meshes = vec![
        quad(
            "floor",
            v(-hx, 0.0, -hz),
            2.0 * hz * z,
            2.0 * hx * x,
            id("floor"),
        ),
        quad(
            "ceiling",
            v(-hx, top, -hz),
            2.0 * hx * x,
            2.0 * hz * z,
            id("ceiling"),
        ),
        quad(
            "wall-left",
            v(-hx, 0.0, -hz),
            top * y,
            2.0 * hz * z,
            id("wall"),
        ),
        quad(
            "wall-right",
            v(hx, 0.0, -hz),
            2.0 * hz * z,
            top * y,
            id("wall"),
        ),
        quad(
            "wall-back",
            v(-hx, 0.0, -hz),
            2.0 * hx * x,
            top * y,
            id("wall"),
        ),
        quad(
            "wall-front",
            v(-hx, 0.0, hz),
            top * y,
            2.0 * hx * x,
            id("wall"),
        ),
        tub(id("tub")),
        cuboid(
            "shower-door",
            v(0.83, 0.552, -1.39),
            v(0.84, 2.0, 0.29),
            id("glass"),
        ),
        door_handle(id("bronze")),
        cuboid(
            "cabinet",
            v(-1.42, 0.001, -1.399),
            v(-0.28, 0.808, -0.88),
            id("wood"),
        ),
        cuboid(
            "counter",
            v(-1.45, 0.81, -1.399),
            v(-0.25, 0.85, -0.85),
            id("counter"),
        ),
        sink(id("porcelain")),
        boxes(
            "faucet",
            &[
                (v(-0.87, 0.851, -1.38), v(-0.83, 1.04, -1.34)),
                (v(-0.865, 1.0, -1.345), v(-0.835, 1.03, -1.2)),
            ],
            id("chrome"),
        ),
        quad(
            "vanity-mirror",
            v(-1.35, 1.1, -1.385),
            1.0 * x,
            0.7 * y,
            id("mirror"),
        ),
        frame_solid(
            "mirror-frame",
            2,
            (-1.399, -1.37),
            (v2(-1.39, 1.06), v2(-0.31, 1.84)),
            (v2(-1.35, 1.1), v2(-0.35, 1.8)),
            id("frame"),
        ),
        boxes(
            "vanity-fixtures",
            &VANITY_LIGHT_X.map(|c| (v(c - 0.11, 1.9, -1.399), v(c + 0.11, 1.96, -1.28))),
            id("chrome"),
        ),
        tiles(id("tile")),
        towel_rail(id("chrome")),
        cuboid(
            "towel",
            v(-1.5, 0.6, 0.0),
            v(-1.49, 1.16, 0.45),
            id("towel"),
        ),
        quad(
            "overhead-light",
            v(-0.3, top - 0.001, -0.3),
            0.6 * x,
            0.6 * z,
            id("overhead"),
        ),
    ];
    for (i, c) in VANITY_LIGHT_X.iter().enumerate() {
        meshes.push(quad(
            &format!("vanity-light-{}", i + 1),
            v(c - 0.1, 1.899, -1.39),
            0.2 * x,
            0.1 * z,
            id("vanity"),
        ));
    }
    let camera = Camera::look_at(v(-0.55, 1.55, 1.3), v(0.29, 0.95, -1.0), Vec3::Y, 70.0);
    Scene::new(
        "bathroom",
        meshes.clone(),
        materials,
        Object::one_per_mesh(&meshes),
        Vec::new(),
        camera,
    )
    .expect("the built-in bathroom scene is valid")
}

/// One mesh of several closed boxes `(min, max)`.
fn boxes(name: &str, parts: &[(Vec3, Vec3)], material: u32) -> Mesh {
    let mut mesh = empty(name, material);
    for &(min, max) in parts {
        append(&mut mesh, &cuboid(name, min, max, material));
    }
    mesh
}

/// Points `(centre + radius (cos φ, sin φ))` for `steps + 1` angles from `from` to `to`, the first left out when `skip_first`.
fn arc(centre: Vec2, radius: Vec2, from: f32, to: f32, steps: u32, skip_first: bool) -> Vec<Vec2> {
    (u32::from(skip_first)..=steps)
        .map(|k| {
            let phi = from + (to - from) * k as f32 / steps as f32;
            centre + radius * Vec2::new(phi.cos(), phi.sin())
        })
        .collect()
}

/// Points from `a` to `b` in `steps` equal steps, `a` left out.
fn line(a: Vec2, b: Vec2, steps: u32) -> Vec<Vec2> {
    (1..=steps)
        .map(|k| a.lerp(b, k as f32 / steps as f32))
        .collect()
}

/// The tub: outer wall, rolled rim, sloping inner wall, fillet and basin floor.
fn tub(material: u32) -> Mesh {
    let (height, rim, floor, fillet, slope) = (0.55, 0.035, 0.06, 0.1, 0.05);
    let outline = Outline {
        centre: Vec2::new(1.198, -0.548),
        half: Vec2::new(0.15, 0.6),
        radius: 0.25,
        arc_segments: 24,
        side_step: 0.02,
    };
    // (inset, y) from the outer bottom edge up and over the rim into the basin.
    let mut profile = vec![Vec2::new(0.0, 0.0)];
    profile.extend(line(profile[0], Vec2::new(0.0, height - rim), 16));
    profile.extend(arc(
        Vec2::new(rim, height - rim),
        Vec2::splat(rim),
        PI,
        0.0,
        24,
        true,
    ));
    let wall_foot = Vec2::new(2.0 * rim + slope, floor + fillet);
    profile.extend(line(Vec2::new(2.0 * rim, height - rim), wall_foot, 20));
    profile.extend(arc(
        wall_foot + Vec2::new(fillet, 0.0),
        Vec2::splat(fillet),
        PI,
        1.5 * PI,
        16,
        true,
    ));
    lathe("tub", &outline, &profile, material)
}

/// The vessel sink on the counter: a round bowl with a rolled rim.
fn sink(material: u32) -> Mesh {
    let (base, height, rim) = (0.851, 0.12, 0.006);
    let outline = Outline {
        centre: Vec2::new(-0.85, -1.1),
        half: Vec2::ZERO,
        radius: 0.2,
        arc_segments: 16,
        side_step: 1.0,
    };
    let mut profile = vec![Vec2::new(0.1, base)];
    // Outer bowl: a quarter ellipse from the foot out and up to the rim.
    profile.extend(arc(
        Vec2::new(0.1, base + height),
        Vec2::new(-0.1, -height),
        0.5 * PI,
        0.0,
        18,
        true,
    ));
    profile.extend(arc(
        Vec2::new(rim, base + height),
        Vec2::splat(rim),
        PI,
        0.0,
        10,
        true,
    ));
    // Inner bowl: a quarter ellipse down to the basin floor 2 cm above the foot.
    profile.extend(arc(
        Vec2::new(0.11, base + height),
        Vec2::new(-(0.11 - 2.0 * rim), -(height - 0.02)),
        0.0,
        0.5 * PI,
        18,
        true,
    ));
    lathe("sink", &outline, &profile, material)
}

/// The shower door's handle: a grip bar on two standoffs, on the room side.
fn door_handle(material: u32) -> Mesh {
    let v = Vec3::new;
    boxes(
        "door-handle",
        &[
            (v(0.765, 1.0, 0.12), v(0.785, 1.4, 0.14)),
            (v(0.78, 1.04, 0.123), v(0.8295, 1.06, 0.137)),
            (v(0.78, 1.34, 0.123), v(0.8295, 1.36, 0.137)),
        ],
        material,
    )
}

/// Wall tiles above the tub on the right (x = 1.6) and back (z = -1.4) walls.
fn tiles(material: u32) -> Mesh {
    let (size, pitch, thick) = (0.15, 0.155, 0.006);
    let mut mesh = empty("tiles", material);
    for row in 0..9 {
        let y0 = 0.56 + row as f32 * pitch;
        for col in 0..10 {
            let z0 = -1.39 + col as f32 * pitch;
            let min = Vec3::new(1.599 - thick, y0, z0);
            append(
                &mut mesh,
                &cuboid("tiles", min, min + Vec3::new(thick, size, size), material),
            );
        }
        for col in 0..5 {
            let x0 = 0.8 + col as f32 * pitch;
            let min = Vec3::new(x0, y0, -1.399);
            append(
                &mut mesh,
                &cuboid("tiles", min, min + Vec3::new(size, size, thick), material),
            );
        }
    }
    mesh
}

/// The towel rail: a bar on two posts from the left wall.
fn towel_rail(material: u32) -> Mesh {
    let v = Vec3::new;
    let mut mesh = empty("towel-rail", material);
    append(
        &mut mesh,
        &cylinder(
            "towel-rail",
            v(-1.52, 1.15, -0.1),
            v(-1.52, 1.15, 0.6),
            0.012,
            32,
            24,
            material,
        ),
    );
    for zc in [-0.05, 0.55] {
        append(
            &mut mesh,
            &cylinder(
                "towel-rail",
                v(-1.599, 1.15, zc),
                v(-1.515, 1.15, zc),
                0.01,
                24,
                4,
                material,
            ),
        );
    }
    mesh
}
