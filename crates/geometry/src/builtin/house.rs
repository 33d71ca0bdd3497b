//! `house`: the class of the house model of Bastos, Hoff, Wynn & Lastra 1999
//! (section 9, table 1: "a large radiosity-illuminated and textured
//! 140,000-triangle house model with five planar reflectors", walked through
//! along "a pre-recorded path (944 frames)"), built procedurally: a living
//! room, a music room with a grand piano and its bench, a hall with mirrored
//! closet doors and a dining room, connected by door openings, furnished
//! with finely tessellated boxes, lathed parts, tubes and ellipsoids.
//!
//! Geometry, in metres (+y up; the house spans x ∈ [-7, 7], z ∈ [-5, 7]):
//!
//! - Rooms ([`ROOMS`], floor to wall centre lines, [`WALL_HEIGHT`] high):
//!   living room x ∈ [-7, 1], z ∈ [-5, 1]; music room x ∈ [1, 7],
//!   z ∈ [-5, 1]; hall x ∈ [-7, 7], z ∈ [1, 2.8]; dining room x ∈ [-7, 0],
//!   z ∈ [2.8, 7]. Walls (`walls`, one mesh of boxes [`WALL_THICKNESS`]
//!   thick, centred on the lines) with door openings ([`DOORS`],
//!   [`DOOR_HEIGHT`] high, a lintel box above each): living room to hall at
//!   x ∈ [-3.4, -1.8], music room to hall at x ∈ [4.6, 5.6] (both in the
//!   wall z = 1), living room to music room at z ∈ [-2.8, -1.2] (wall
//!   x = 1), hall to dining room at x ∈ [-4.2, -3] (wall z = 2.8).
//!   Floors facing up at y = 0, cut into cells; ceilings (`ceiling`) facing
//!   down at y = 2.7.
//! - Reflectors ([`HOUSE_REFLECTORS`], table 1), each a single planar mesh:
//!   `piano-top`, the closed lid of the grand piano at y = 0.98 (glossy
//!   black lacquer); `living-floor`, the living room's floor (32 × 24 cells
//!   of 0.25 m, glossy varnished wood); `door-mirror`, two mirrors on the
//!   closet doors in the hall, in the plane z = 2.699 facing -z,
//!   x ∈ [4.05, 4.75] and [5.15, 5.85], y ∈ [0.25, 1.95]; `music-floor`,
//!   the music room's floor (24 × 24 cells, glossy varnished wood of a
//!   lighter colour); `bench-top`, the top of the piano bench at y = 0.5,
//!   x ∈ [3.55, 4.35], z ∈ [-0.93, -0.57] (glossy lacquer). Every other
//!   material is diffuse.
//! - Music room: the grand piano ([`PIANO_CORNER`], keyboard towards +z):
//!   a case from y = 0.62 to 0.98 over a convex outline 1.5 m wide and 1.9 m
//!   long (straight spine, bentside a quarter ellipse), open at the top where
//!   `piano-top` closes it, three turned legs, a key bed with 52 white and 36
//!   black keys, a music desk; the bench in front of it on four turned legs;
//!   an armchair, a music stand, a bookcase of scores, a floor lamp, two
//!   plants, two pictures.
//! - Living room: a sofa of rounded cushions along the north wall, a coffee
//!   table, two armchairs, a bookcase of some 550 books on the west wall, two
//!   floor lamps, a sideboard with vases, two plants, a picture.
//! - Hall: the two closet doors with their mirrors and knobs, a console
//!   table with a vase, a coat rack, an umbrella stand, two pictures.
//! - Dining room: a table on turned legs with a fruit bowl and candlesticks,
//!   six chairs, a sideboard with vases, a plant, a picture.
//! - Plants are pots with 60 leaves each, thin ellipsoids (some 36,000
//!   triangles in all).
//! - Lights ([`LIGHT_RADIANCE`]): rectangles facing down 1 mm under the
//!   ceilings: `living-light` 1.2 × 0.8 at (-3, -2), `music-light`
//!   1.0 × 0.8 at (4, -2), `hall-light-west` and `hall-light-east`
//!   0.6 × 0.4 at (∓3.5, 1.9), `dining-light` 1.0 × 0.6 at (-3.5, 4.9).
//! - Camera at (1.8, 1.2, 0.3) in the music room looking at
//!   (4.0, 0.95, -2.2), 60° vertical field of view: almost parallel to the
//!   floor and the piano top (the paper's colour plate (b)).
//! - Walkthrough: [`house_path`] (the file `tests/paths/house-walk.json`),
//!   34 s from the west end of the hall into the living room, through the
//!   wide opening into the music room round the piano and its bench, and out
//!   into the hall to face the door mirrors.
//!
//! The meshes of [`CLOSED_MESHES`] are closed manifolds with outward faces.

use std::f32::consts::{FRAC_PI_2, PI, TAU};

use glam::{Affine3A, Quat, Vec2, Vec3};

use super::parts::{
    Outline, append, cells, cuboid, cylinder, edges, empty, frame_solid, lathe, open_top,
    push_facing, push_triangle, quad, sphere, transformed, tube,
};
use super::pyramid::varnish;
use crate::Object;
use crate::camera_path::{CameraKeyframe, CameraPath};
use crate::{Camera, Material, MaterialModel, Mesh, Rgb, Scene};

/// Triangles of the paper's house: "a large ... 140,000-triangle house model" (Bastos et al. 1999, section 9).
pub const PAPER_TRIANGLES: usize = 140_000;
/// The five planar reflectors of table 1 (Bastos et al. 1999): piano top, living floor, door mirrors, music floor, bench top.
pub const HOUSE_REFLECTORS: [&str; 5] = [
    "piano-top",
    "living-floor",
    "door-mirror",
    "music-floor",
    "bench-top",
];
/// Height of the walls and ceilings.
pub const WALL_HEIGHT: f32 = 2.7;
/// Height of the door openings.
pub const DOOR_HEIGHT: f32 = 2.1;
/// Thickness of the walls, centred on the room boundaries.
pub const WALL_THICKNESS: f32 = 0.12;
/// The rooms: name, (x, z) of the floor's corner of least coordinates and of the greatest.
pub const ROOMS: [(&str, Vec2, Vec2); 4] = [
    ("living", Vec2::new(-7.0, -5.0), Vec2::new(1.0, 1.0)),
    ("music", Vec2::new(1.0, -5.0), Vec2::new(7.0, 1.0)),
    ("hall", Vec2::new(-7.0, 1.0), Vec2::new(7.0, 2.8)),
    ("dining", Vec2::new(-7.0, 2.8), Vec2::new(0.0, 7.0)),
];
/// The door openings: (the wall's axis, 0 for a wall of constant x and 2 for one of constant z; that constant; the opening's range along the wall).
pub const DOORS: [(usize, f32, (f32, f32)); 4] = [
    (2, 1.0, (-3.4, -1.8)),
    (2, 1.0, (4.6, 5.6)),
    (0, 1.0, (-2.8, -1.2)),
    (2, 2.8, (-4.2, -3.0)),
];
/// Front-left corner of the piano's case at floor level (x, z); the keyboard faces +z.
pub const PIANO_CORNER: Vec3 = Vec3::new(3.2, 0.0, -1.4);
/// Heights of the bottom and the top (the lid, `piano-top`) of the piano's case.
pub const PIANO_CASE: (f32, f32) = (0.62, 0.98);
/// The piano bench's seat: its corners of least and greatest coordinates; `bench-top` is its top face.
pub const BENCH: (Vec3, Vec3) = (Vec3::new(3.55, 0.42, -0.93), Vec3::new(4.35, 0.5, -0.57));
/// Radiance of every ceiling light, in W/(m² sr).
pub const LIGHT_RADIANCE: Rgb = Rgb::new(14.0, 13.5, 12.5);
/// Vertical field of view of the walkthrough, in degrees.
pub const WALK_FOV: f32 = 60.0;
/// The meshes that are closed manifolds with outward faces.
pub const CLOSED_MESHES: &[&str] = &[
    "piano-legs",
    "bench-legs",
    "fruit",
    "vases",
    "leaves",
    "pots",
    "lamps",
];

/// The walkthrough's keyframes: time (s), eye, the point looked at.
const WALK: [(f32, [f32; 3], [f32; 3]); 10] = [
    (0.0, [-6.0, 1.6, 1.9], [-2.6, 1.0, 0.0]),
    (4.0, [-2.6, 1.6, 1.9], [-2.6, 0.8, -2.0]),
    (8.0, [-2.6, 1.6, 0.0], [-3.0, 0.5, -3.0]),
    (12.0, [-1.5, 1.6, -1.5], [2.5, 0.8, -2.0]),
    (16.0, [1.0, 1.6, -2.0], [4.0, 0.9, -2.4]),
    (20.0, [2.4, 1.5, -0.4], [4.0, 0.7, -1.8]),
    (24.0, [5.6, 1.4, -0.3], [4.0, 0.8, -2.2]),
    (28.0, [5.1, 1.6, 0.6], [5.1, 1.2, 2.6]),
    (31.0, [5.1, 1.6, 1.6], [4.9, 1.2, 2.7]),
    (34.0, [3.0, 1.6, 1.7], [5.0, 1.1, 2.7]),
];

/// The recorded walkthrough of the house (`tests/paths/house-walk.json`):
/// hall, living room, music room round the piano, hall facing the door
/// mirrors; the reflectors are in view for most of it (Bastos et al. 1999,
/// section 9).
pub fn house_path() -> CameraPath {
    let keyframes = WALK
        .iter()
        .map(|&(time, position, target)| CameraKeyframe {
            time,
            position: Vec3::from(position),
            target: Vec3::from(target),
            up: Vec3::Y,
            fov_y_degrees: WALK_FOV,
        })
        .collect();
    CameraPath::new(keyframes).expect("the house walkthrough is valid")
}

/// Material names, in the order of the scene's materials.
const MATERIALS: [&str; 32] = [
    "plaster",
    "ceiling",
    "living-wood",
    "music-wood",
    "hall-tiles",
    "dining-wood",
    "black-lacquer",
    "bench-lacquer",
    "mirror",
    "piano-black",
    "ivory",
    "ebony",
    "oak",
    "walnut",
    "door-paint",
    "brass",
    "sofa-fabric",
    "chair-fabric",
    "shade",
    "book-red",
    "book-green",
    "book-blue",
    "book-cream",
    "leaf",
    "terracotta",
    "porcelain",
    "fruit",
    "frame",
    "picture-sea",
    "picture-field",
    "picture-sunset",
    "light",
];

/// Index of the material named `name`.
fn id(name: &str) -> u32 {
    MATERIALS
        .iter()
        .position(|n| *n == name)
        .unwrap_or_else(|| panic!("no house material {name}")) as u32
}

/// The materials, named as [`MATERIALS`].
fn materials() -> Vec<Material> {
    let d = Material::diffuse;
    let materials = vec![
        d("plaster", Rgb::new(0.78, 0.75, 0.68)),
        d("ceiling", Rgb::splat(0.82)),
        Material::new("living-wood", varnish(Rgb::new(0.55, 0.32, 0.16), 0.1)),
        Material::new("music-wood", varnish(Rgb::new(0.75, 0.55, 0.34), 0.08)),
        d("hall-tiles", Rgb::new(0.55, 0.5, 0.45)),
        d("dining-wood", Rgb::new(0.42, 0.3, 0.2)),
        Material::new("black-lacquer", varnish(Rgb::splat(0.04), 0.03)),
        Material::new("bench-lacquer", varnish(Rgb::new(0.08, 0.05, 0.04), 0.06)),
        Material::new(
            "mirror",
            MaterialModel::Mirror {
                reflectance: Rgb::splat(0.9),
            },
        ),
        d("piano-black", Rgb::splat(0.03)),
        d("ivory", Rgb::new(0.85, 0.83, 0.76)),
        d("ebony", Rgb::splat(0.03)),
        d("oak", Rgb::new(0.55, 0.4, 0.24)),
        d("walnut", Rgb::new(0.28, 0.17, 0.1)),
        d("door-paint", Rgb::new(0.85, 0.84, 0.8)),
        d("brass", Rgb::new(0.6, 0.45, 0.2)),
        d("sofa-fabric", Rgb::new(0.18, 0.28, 0.48)),
        d("chair-fabric", Rgb::new(0.55, 0.16, 0.12)),
        d("shade", Rgb::new(0.9, 0.85, 0.7)),
        d("book-red", Rgb::new(0.5, 0.1, 0.08)),
        d("book-green", Rgb::new(0.12, 0.32, 0.15)),
        d("book-blue", Rgb::new(0.1, 0.15, 0.4)),
        d("book-cream", Rgb::new(0.75, 0.7, 0.58)),
        d("leaf", Rgb::new(0.12, 0.35, 0.08)),
        d("terracotta", Rgb::new(0.6, 0.3, 0.18)),
        d("porcelain", Rgb::new(0.85, 0.85, 0.85)),
        d("fruit", Rgb::new(0.8, 0.4, 0.05)),
        d("frame", Rgb::new(0.55, 0.42, 0.15)),
        d("picture-sea", Rgb::new(0.15, 0.35, 0.5)),
        d("picture-field", Rgb::new(0.45, 0.5, 0.15)),
        d("picture-sunset", Rgb::new(0.7, 0.35, 0.15)),
        d("light", Rgb::splat(0.8)).with_emission(LIGHT_RADIANCE),
    ];
    debug_assert!(
        materials
            .iter()
            .zip(MATERIALS)
            .all(|(m, name)| m.name == name)
    );
    materials
}

/// `house`: Bastos et al.'s house class with its five planar reflectors (section 9, table 1).
pub fn house() -> Scene {
    let mut meshes = structure();
    meshes.extend(piano());
    meshes.extend(living_room());
    meshes.extend(hall());
    meshes.extend(dining_room());
    meshes.extend(shared_parts());
    let lights: [(&str, Vec2, Vec2); 5] = [
        ("living-light", Vec2::new(-3.0, -2.0), Vec2::new(1.2, 0.8)),
        ("music-light", Vec2::new(4.0, -2.0), Vec2::new(1.0, 0.8)),
        ("hall-light-west", Vec2::new(-3.5, 1.9), Vec2::new(0.6, 0.4)),
        ("hall-light-east", Vec2::new(3.5, 1.9), Vec2::new(0.6, 0.4)),
        ("dining-light", Vec2::new(-3.5, 4.9), Vec2::new(1.0, 0.6)),
    ];
    for (name, centre, size) in lights {
        meshes.push(quad(
            name,
            Vec3::new(
                centre.x - 0.5 * size.x,
                WALL_HEIGHT - 0.001,
                centre.y - 0.5 * size.y,
            ),
            size.x * Vec3::X,
            size.y * Vec3::Z,
            id("light"),
        ));
    }
    let camera = Camera::look_at(
        Vec3::new(1.8, 1.2, 0.3),
        Vec3::new(4.0, 0.95, -2.2),
        Vec3::Y,
        60.0,
    );
    Scene::new(
        "house",
        meshes.clone(),
        materials(),
        Object::one_per_mesh(&meshes),
        Vec::new(),
        camera,
    )
    .expect("the built-in house scene is valid")
}

/// Walls, floors and ceilings.
fn structure() -> Vec<Mesh> {
    let mut walls = empty("walls", id("plaster"));
    let e = 0.5 * WALL_THICKNESS;
    // (a wall of constant x?, the constant, from, to); openings from DOORS.
    let lines: [(bool, f32, f32, f32); 8] = [
        (false, -5.0, -7.0 - e, 7.0 + e),
        (true, -7.0, -5.0 - e, 7.0 + e),
        (true, 7.0, -5.0 - e, 2.8 + e),
        (false, 2.8, -7.0 - e, 7.0 + e),
        (true, 0.0, 2.8, 7.0 + e),
        (false, 7.0, -7.0 - e, 0.0 + e),
        (false, 1.0, -7.0, 7.0),
        (true, 1.0, -5.0, 1.0),
    ];
    for (constant_x, at, from, to) in lines {
        let axis = if constant_x { 0 } else { 2 };
        let openings: Vec<(f32, f32)> = DOORS
            .iter()
            .filter(|d| d.0 == axis && d.1 == at)
            .map(|d| d.2)
            .collect();
        wall(&mut walls, constant_x, at, (from, to), &openings);
    }
    let floor = |name: &str, room: usize, cell: f32, material: &str| {
        let (_, min, max) = ROOMS[room];
        let (nx, nz) = (
            ((max.x - min.x) / cell).round() as u32,
            ((max.y - min.y) / cell).round() as u32,
        );
        // Axis y: cells along z (u) and x (v), facing up.
        cells(
            name,
            1,
            0.0,
            &edges(min.y, max.y, nz),
            &edges(min.x, max.x, nx),
            true,
            |_, _| true,
            id(material),
        )
    };
    let mut ceiling = empty("ceiling", id("ceiling"));
    for (_, min, max) in ROOMS {
        let part = cells(
            "ceiling",
            1,
            WALL_HEIGHT,
            &edges(min.y, max.y, ((max.y - min.y) / 1.0).ceil() as u32),
            &edges(min.x, max.x, ((max.x - min.x) / 1.0).ceil() as u32),
            false,
            |_, _| true,
            id("ceiling"),
        );
        append(&mut ceiling, &part);
    }
    vec![
        walls,
        floor("living-floor", 0, 0.25, "living-wood"),
        floor("music-floor", 1, 0.25, "music-wood"),
        floor("hall-floor", 2, 0.3, "hall-tiles"),
        floor("dining-floor", 3, 0.3, "dining-wood"),
        ceiling,
    ]
}

/// Appends a wall centred on the line x = `at` (or z = `at`) from
/// `range.0` to `range.1` along the other axis: a box per solid stretch
/// and a lintel over each opening.
fn wall(mesh: &mut Mesh, constant_x: bool, at: f32, range: (f32, f32), openings: &[(f32, f32)]) {
    let e = 0.5 * WALL_THICKNESS;
    let bx = |a: f32, b: f32, y0: f32, y1: f32| {
        if constant_x {
            cuboid(
                "walls",
                Vec3::new(at - e, y0, a),
                Vec3::new(at + e, y1, b),
                0,
            )
        } else {
            cuboid(
                "walls",
                Vec3::new(a, y0, at - e),
                Vec3::new(b, y1, at + e),
                0,
            )
        }
    };
    let mut start = range.0;
    for &(a, b) in openings {
        append(mesh, &bx(start, a, 0.0, WALL_HEIGHT));
        append(mesh, &bx(a, b, DOOR_HEIGHT, WALL_HEIGHT));
        start = b;
    }
    append(mesh, &bx(start, range.1, 0.0, WALL_HEIGHT));
}

/// A cheap deterministic hash of `(i, salt)` to [0, 1).
fn hash(i: u32, salt: u32) -> f32 {
    let mut x = i.wrapping_mul(0x9E37_79B9) ^ salt.wrapping_mul(0x85EB_CA6B) ^ 0x2545_F491;
    x ^= x >> 16;
    x = x.wrapping_mul(0x7FEB_352D);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846C_A68B);
    x ^= x >> 16;
    (x >> 8) as f32 / (1u32 << 24) as f32
}

/// A slab over the rectangle `min`..`max` (x, z) from `min.y` to `max.y`
/// with vertical corners rounded to `corner` and its top and bottom edges to
/// `edge` (< `corner`): a closed lathed solid, smooth shaded.
fn rounded(name: &str, min: Vec3, max: Vec3, corner: f32, edge: f32, material: u32) -> Mesh {
    let centre = 0.5 * (min + max);
    let half = 0.5 * (max - min);
    let outline = Outline {
        centre: Vec2::new(centre.x, centre.z),
        half: Vec2::new(half.x - corner, half.z - corner),
        radius: corner,
        arc_segments: 6,
        side_step: 0.06,
    };
    let steps = 5;
    let mut profile = Vec::new();
    for k in 0..=steps {
        // The bottom edge: from the cap (inset `edge`) out to the side.
        let phi = -FRAC_PI_2 - FRAC_PI_2 * k as f32 / steps as f32;
        profile.push(Vec2::new(edge, min.y + edge) + edge * Vec2::new(phi.cos(), phi.sin()));
    }
    for k in 0..=steps {
        let phi = PI - FRAC_PI_2 * k as f32 / steps as f32;
        profile.push(Vec2::new(edge, max.y - edge) + edge * Vec2::new(phi.cos(), phi.sin()));
    }
    lathe(name, &outline, &profile, material)
}

/// A turned (lathed, round) part standing on `foot` (x, y, z), `height`
/// high, radius `radius(t)` at height fraction t, `segments` round and
/// `steps` up.
fn turned(
    name: &str,
    foot: Vec3,
    height: f32,
    radius: impl Fn(f32) -> f32,
    segments: u32,
    steps: u32,
    material: u32,
) -> Mesh {
    let r: Vec<f32> = (0..=steps)
        .map(|k| radius(k as f32 / steps as f32))
        .collect();
    let widest = r.iter().copied().fold(0.0, f32::max);
    let outline = Outline {
        centre: Vec2::new(foot.x, foot.z),
        half: Vec2::ZERO,
        radius: widest,
        arc_segments: segments.div_ceil(4),
        side_step: 1.0,
    };
    let profile: Vec<Vec2> = r
        .iter()
        .enumerate()
        .map(|(k, r)| Vec2::new(widest - r, foot.y + height * k as f32 / steps as f32))
        .collect();
    lathe(name, &outline, &profile, material)
}

/// A turned leg `height` high at `foot`: a square-ish foot, a bulb and a
/// slender neck, radius at most `radius`.
fn leg(name: &str, foot: Vec3, height: f32, radius: f32, material: u32) -> Mesh {
    turned(
        name,
        foot,
        height,
        |t| {
            let bulb = (-((t - 0.3) / 0.12).powi(2)).exp();
            let ring = (-((t - 0.85) / 0.04).powi(2)).exp();
            radius * (0.45 + 0.1 * (1.0 - t) + 0.45 * bulb + 0.35 * ring).min(1.0)
        },
        24,
        22,
        material,
    )
}

/// A closed ellipsoid with semi-axes `axes`, rotated by `rotation`, centred at `centre`.
fn ellipsoid(
    name: &str,
    centre: Vec3,
    axes: Vec3,
    rotation: Quat,
    slices: u32,
    stacks: u32,
    material: u32,
) -> Mesh {
    let unit = sphere(name, Vec3::ZERO, 1.0, slices, stacks, material);
    transformed(
        unit,
        Affine3A::from_scale_rotation_translation(axes, rotation, centre),
    )
}

/// One mesh of several closed boxes `(min, max)`.
fn boxes(name: &str, parts: &[(Vec3, Vec3)], material: u32) -> Mesh {
    let mut mesh = empty(name, material);
    for &(min, max) in parts {
        append(&mut mesh, &cuboid(name, min, max, material));
    }
    mesh
}

/// The grand piano, its bench and the rest of the music room.
fn piano() -> Vec<Mesh> {
    let o = PIANO_CORNER;
    let (bottom, top) = PIANO_CASE;
    // The outline (x, z): front edge, cheek, bentside (a quarter ellipse), tail, spine.
    let straight = |a: Vec2, b: Vec2| {
        let n = (a.distance(b) / 0.1).ceil().max(1.0) as u32;
        (0..n).map(move |k| a.lerp(b, k as f32 / n as f32))
    };
    let mut outline: Vec<Vec2> = straight(Vec2::new(0.0, 0.0), Vec2::new(1.5, 0.0)).collect();
    outline.extend(straight(Vec2::new(1.5, 0.0), Vec2::new(1.5, -0.35)));
    let arc = 48;
    for k in 0..arc {
        let phi = -FRAC_PI_2 * k as f32 / arc as f32;
        outline.push(Vec2::new(0.35 + 1.15 * phi.cos(), -0.35 + 1.55 * phi.sin()));
    }
    outline.extend(straight(Vec2::new(0.35, -1.9), Vec2::new(0.0, -1.9)));
    outline.extend(straight(Vec2::new(0.0, -1.9), Vec2::new(0.0, 0.0)));
    let at = |p: Vec2, y: f32| Vec3::new(o.x + p.x, y, o.z + p.y);
    let n = outline.len();
    let centroid = outline.iter().copied().sum::<Vec2>() / n as f32;
    // The case: sides (flat quads) and the bottom (a fan facing down), open at the top.
    let mut case = empty("piano", id("piano-black"));
    for i in 0..n {
        let (a, b) = (outline[i], outline[(i + 1) % n]);
        let mid = 0.5 * (a + b) - centroid;
        push_facing(
            &mut case,
            [at(a, bottom), at(b, bottom), at(b, top), at(a, top)],
            Vec3::new(mid.x, 0.0, mid.y),
        );
    }
    let base = case.positions.len() as u32;
    case.positions.push(at(centroid, bottom));
    for &p in &outline {
        case.positions.push(at(p, bottom));
    }
    case.normals.extend(std::iter::repeat_n(-Vec3::Y, n + 1));
    case.uvs.extend(std::iter::repeat_n(Vec2::ZERO, n + 1));
    for i in 0..n as u32 {
        push_triangle(
            &mut case,
            [base, base + 1 + i, base + 1 + (i + 1) % n as u32],
            -Vec3::Y,
        );
    }
    // The lid: rings shrinking towards the centroid, the outermost the outline itself.
    let rings = 12;
    let mut lid = empty("piano-top", id("black-lacquer"));
    lid.positions.push(at(centroid, top));
    for k in 1..=rings {
        for &p in &outline {
            let q = if k == rings {
                p
            } else {
                centroid + (p - centroid) * (k as f32 / rings as f32)
            };
            lid.positions.push(at(q, top));
        }
    }
    lid.normals = vec![Vec3::Y; lid.positions.len()];
    lid.uvs = lid
        .positions
        .iter()
        .map(|p| Vec2::new((p.x - o.x) / 1.5, (o.z - p.z) / 1.9))
        .collect();
    let ring = |k: u32, i: usize| 1 + (k - 1) * n as u32 + (i % n) as u32;
    for i in 0..n {
        push_triangle(&mut lid, [0, ring(1, i), ring(1, i + 1)], Vec3::Y);
        for k in 1..rings {
            let (a, b) = (ring(k, i), ring(k, i + 1));
            let (c, d) = (ring(k + 1, i + 1), ring(k + 1, i));
            push_triangle(&mut lid, [a, d, c], Vec3::Y);
            push_triangle(&mut lid, [a, c, b], Vec3::Y);
        }
    }
    // Legs under the case, ending 1 mm below it.
    let mut legs = empty("piano-legs", id("piano-black"));
    for (x, z) in [(0.15, -0.12), (1.35, -0.12), (0.3, -1.65)] {
        append(
            &mut legs,
            &leg(
                "piano-legs",
                at(Vec2::new(x, z), 0.0),
                bottom - 0.001,
                0.07,
                0,
            ),
        );
    }
    // The key bed and cheek blocks in front of the case, the keys on the bed.
    let v = Vec3::new;
    let front = o.z;
    let keybed = boxes(
        "keybed",
        &[
            (v(o.x, bottom, front), v(o.x + 1.5, 0.72, front + 0.2)),
            (v(o.x, 0.72, front), v(o.x + 0.13, 0.79, front + 0.2)),
            (v(o.x + 1.37, 0.72, front), v(o.x + 1.5, 0.79, front + 0.2)),
            (v(o.x + 0.13, 0.72, front), v(o.x + 1.37, 0.8, front + 0.03)),
        ],
        id("piano-black"),
    );
    let (x0, width) = (o.x + 0.14, 1.22 / 52.0);
    let mut white = empty("keys-white", id("ivory"));
    let mut black = empty("keys-black", id("ebony"));
    for i in 0..52u32 {
        let left = x0 + width * i as f32;
        append(
            &mut white,
            &cuboid(
                "keys-white",
                v(left + 0.0005, 0.72, front + 0.03),
                v(left + width - 0.0005, 0.742, front + 0.18),
                0,
            ),
        );
        // A black key after A, C, D, F and G (white keys from A0: A B C D E F G).
        if i < 51 && [0, 2, 3, 5, 6].contains(&(i % 7)) {
            let mid = left + width;
            append(
                &mut black,
                &cuboid(
                    "keys-black",
                    v(mid - 0.0068, 0.735, front + 0.03),
                    v(mid + 0.0068, 0.756, front + 0.125),
                    0,
                ),
            );
        }
    }
    let desk = cuboid(
        "music-desk",
        v(o.x + 0.4, top, front - 0.25),
        v(o.x + 1.1, top + 0.3, front - 0.23),
        id("piano-black"),
    );
    // The bench: a seat box open at the top, closed by `bench-top`, on four legs.
    let (b0, b1) = BENCH;
    let bench = open_top(cuboid("bench", b0, b1, id("piano-black")));
    let bench_top = cells(
        "bench-top",
        1,
        b1.y,
        &edges(b0.z, b1.z, 4),
        &edges(b0.x, b1.x, 8),
        true,
        |_, _| true,
        id("bench-lacquer"),
    );
    let mut bench_legs = empty("bench-legs", id("piano-black"));
    for (x, z) in [(b0.x, b0.z), (b1.x, b0.z), (b0.x, b1.z), (b1.x, b1.z)] {
        let inset = Vec3::new((b0.x + b1.x) * 0.5 - x, 0.0, (b0.z + b1.z) * 0.5 - z);
        let foot = v(x, 0.0, z) + inset.normalize() * 0.05;
        append(
            &mut bench_legs,
            &leg("bench-legs", foot, b0.y - 0.001, 0.03, 0),
        );
    }
    // A music stand: a tripod post and a tilted desk of boxes.
    let mut stand = cylinder(
        "music-stand",
        v(6.0, 0.02, -0.6),
        v(6.0, 1.1, -0.6),
        0.012,
        16,
        8,
        id("brass"),
    );
    for k in 0..3 {
        let phi = TAU * k as f32 / 3.0;
        append(
            &mut stand,
            &cylinder(
                "music-stand",
                v(6.0, 0.3, -0.6),
                v(6.0 + 0.3 * phi.cos(), 0.01, -0.6 + 0.3 * phi.sin()),
                0.01,
                12,
                6,
                0,
            ),
        );
    }
    let tilt = Quat::from_rotation_x(-0.35);
    append(
        &mut stand,
        &transformed(
            cuboid(
                "music-stand",
                v(-0.25, -0.18, -0.01),
                v(0.25, 0.18, 0.01),
                0,
            ),
            Affine3A::from_rotation_translation(tilt, v(6.0, 1.2, -0.6)),
        ),
    );
    let scores = shelf_with_books("music", v(6.6, 0.0, -4.2), 2.4, 4, true);
    let mut meshes = vec![
        case, lid, legs, keybed, white, black, desk, bench, bench_top, bench_legs, stand,
    ];
    meshes.extend(scores);
    meshes.extend(armchair("music-armchair", v(2.2, 0.0, -4.2), 0.6));
    meshes
}

/// A bookcase against the wall x = ±7 (facing the room): its `corner`
/// (x at the wall, floor, least z), `length` along z, `shelves` shelves of
/// books; returns the case and the books by colour. `east` puts it on the
/// east wall (facing -x).
fn shelf_with_books(
    prefix: &str,
    corner: Vec3,
    length: f32,
    shelves: u32,
    east: bool,
) -> Vec<Mesh> {
    let depth = 0.32;
    let (xa, xb) = if east {
        (corner.x + 0.33 - depth, corner.x + 0.33)
    } else {
        (corner.x, corner.x + depth)
    };
    let (z0, z1) = (corner.z, corner.z + length);
    let pitch = 0.36;
    let height = pitch * shelves as f32 + 0.04;
    let v = Vec3::new;
    let mut parts = vec![
        (v(xa, 0.0, z0), v(xb, height, z0 + 0.03)),
        (v(xa, 0.0, z1 - 0.03), v(xb, height, z1)),
    ];
    let back = if east { xb - 0.01 } else { xa };
    parts.push((v(back, 0.0, z0 + 0.03), v(back + 0.01, height, z1 - 0.03)));
    for s in 0..=shelves {
        let y = pitch * s as f32;
        parts.push((v(xa, y, z0 + 0.03), v(xb, y + 0.03, z1 - 0.03)));
    }
    let case = boxes(&format!("{prefix}-bookcase"), &parts, id("walnut"));
    let colours = ["book-red", "book-green", "book-blue", "book-cream"];
    let mut books: Vec<Mesh> = colours
        .iter()
        .map(|c| empty(&format!("{prefix}-books-{}", &c[5..]), id(c)))
        .collect();
    let mut count = 0u32;
    for s in 0..shelves {
        let y = pitch * s as f32 + 0.03;
        let mut z = z0 + 0.035;
        loop {
            let salt = count + 7919 * s;
            let thick = 0.018 + 0.03 * hash(salt, 1);
            if z + thick > z1 - 0.035 {
                break;
            }
            let tall = 0.2 + 0.1 * hash(salt, 2);
            let deep = 0.18 + 0.08 * hash(salt, 3);
            let (bx0, bx1) = if east {
                (xb - 0.012 - deep, xb - 0.012)
            } else {
                (xa + 0.012, xa + 0.012 + deep)
            };
            let colour = (hash(salt, 4) * 4.0) as usize % 4;
            let name = books[colour].name.clone();
            append(
                &mut books[colour],
                &cuboid(&name, v(bx0, y, z), v(bx1, y + tall, z + thick - 0.001), 0),
            );
            z += thick;
            count += 1;
        }
    }
    let mut meshes = vec![case];
    meshes.extend(books);
    meshes
}

/// An armchair with its back towards -z rotated by `turn` radians about
/// y, standing at `at`: a base, a back and arms of rounded slabs, a cushion.
fn armchair(name: &str, at: Vec3, turn: f32) -> Vec<Mesh> {
    let v = Vec3::new;
    let xf = Affine3A::from_rotation_translation(Quat::from_rotation_y(turn), at);
    let fabric = id("chair-fabric");
    let mut frame = empty(name, fabric);
    for (min, max) in [
        (v(-0.42, 0.08, -0.4), v(0.42, 0.4, 0.4)),
        (v(-0.42, 0.4, -0.4), v(0.42, 0.95, -0.22)),
        (v(-0.42, 0.4, -0.22), v(-0.3, 0.65, 0.4)),
        (v(0.3, 0.4, -0.22), v(0.42, 0.65, 0.4)),
    ] {
        append(&mut frame, &rounded(name, min, max, 0.05, 0.03, 0));
    }
    let cushion_name = format!("{name}-cushion");
    let cushion = rounded(
        &cushion_name,
        v(-0.3, 0.4, -0.22),
        v(0.3, 0.52, 0.38),
        0.06,
        0.04,
        fabric,
    );
    let mut feet = empty(&format!("{name}-feet"), id("walnut"));
    for (x, z) in [(-0.36, -0.34), (0.36, -0.34), (-0.36, 0.34), (0.36, 0.34)] {
        append(
            &mut feet,
            &cylinder("feet", v(x, 0.0, z), v(x, 0.08, z), 0.025, 16, 2, 0),
        );
    }
    vec![
        transformed(frame, xf),
        transformed(cushion, xf),
        transformed(feet, xf),
    ]
}

/// The living room's furniture.
fn living_room() -> Vec<Mesh> {
    let v = Vec3::new;
    let mut meshes = Vec::new();
    // The sofa along the north wall: a base, arms, a back and six cushions.
    let (x0, x1) = (-4.6, -1.4);
    let fabric = id("sofa-fabric");
    let mut sofa = empty("sofa", fabric);
    for (min, max) in [
        (v(x0, 0.1, -4.92), v(x1, 0.42, -4.0)),
        (v(x0, 0.42, -4.92), v(x0 + 0.25, 0.68, -4.0)),
        (v(x1 - 0.25, 0.42, -4.92), v(x1, 0.68, -4.0)),
        (v(x0 + 0.25, 0.42, -4.92), v(x1 - 0.25, 0.98, -4.72)),
    ] {
        append(&mut sofa, &rounded("sofa", min, max, 0.08, 0.04, 0));
    }
    let mut cushions = empty("sofa-cushions", fabric);
    let w = (x1 - x0 - 0.5) / 3.0;
    for k in 0..3 {
        let a = x0 + 0.25 + w * k as f32;
        append(
            &mut cushions,
            &rounded(
                "c",
                v(a + 0.01, 0.42, -4.71),
                v(a + w - 0.01, 0.58, -4.02),
                0.08,
                0.05,
                0,
            ),
        );
        append(
            &mut cushions,
            &rounded(
                "c",
                v(a + 0.02, 0.58, -4.71),
                v(a + w - 0.02, 0.92, -4.5),
                0.08,
                0.06,
                0,
            ),
        );
    }
    let mut sofa_feet = empty("sofa-feet", id("walnut"));
    for (x, z) in [
        (x0 + 0.08, -4.84),
        (x1 - 0.08, -4.84),
        (x0 + 0.08, -4.08),
        (x1 - 0.08, -4.08),
    ] {
        append(
            &mut sofa_feet,
            &cylinder("f", v(x, 0.0, z), v(x, 0.1, z), 0.03, 16, 2, 0),
        );
    }
    meshes.extend([sofa, cushions, sofa_feet]);
    // The coffee table: a rounded top on four turned legs.
    let top = rounded(
        "coffee-table",
        v(-3.6, 0.38, -3.3),
        v(-2.4, 0.42, -2.7),
        0.1,
        0.015,
        id("oak"),
    );
    let mut legs = empty("coffee-table-legs", id("oak"));
    for (x, z) in [(-3.5, -3.2), (-2.5, -3.2), (-3.5, -2.8), (-2.5, -2.8)] {
        append(&mut legs, &leg("l", v(x, 0.0, z), 0.379, 0.035, 0));
    }
    meshes.extend([top, legs]);
    meshes.extend(armchair("armchair-west", v(-5.4, 0.0, -2.6), FRAC_PI_2));
    meshes.extend(armchair("armchair-east", v(-0.8, 0.0, -3.9), -0.6));
    meshes.extend(shelf_with_books(
        "living",
        v(-6.94, 0.0, -4.6),
        3.0,
        6,
        false,
    ));
    // A sideboard against the south wall with vases.
    meshes.push(boxes(
        "living-sideboard",
        &[(v(-6.6, 0.0, 0.5), v(-4.6, 0.8, 0.93))],
        id("walnut"),
    ));
    meshes
}

/// The hall: closet doors with their mirrors, a console table, a coat rack.
fn hall() -> Vec<Mesh> {
    let v = Vec3::new;
    let face = 2.8 - 0.5 * WALL_THICKNESS;
    let doors = boxes(
        "closet-doors",
        &[
            (v(3.9, 0.0, face - 0.04), v(4.9, DOOR_HEIGHT, face)),
            (v(5.0, 0.0, face - 0.04), v(6.0, DOOR_HEIGHT, face)),
        ],
        id("door-paint"),
    );
    let mut u = edges(4.05, 4.75, 4);
    u.extend(edges(5.15, 5.85, 4));
    let mirror = cells(
        "door-mirror",
        2,
        face - 0.041,
        &u,
        &edges(0.25, 1.95, 8),
        false,
        |i, _| i != 4,
        id("mirror"),
    );
    let mut knobs = empty("door-knobs", id("brass"));
    for x in [4.82, 5.08] {
        append(
            &mut knobs,
            &sphere("k", v(x, 1.0, face - 0.07), 0.025, 24, 12, 0),
        );
        append(
            &mut knobs,
            &cylinder(
                "k",
                v(x, 1.0, face - 0.05),
                v(x, 1.0, face - 0.0405),
                0.008,
                12,
                1,
                0,
            ),
        );
    }
    let console = boxes(
        "console",
        &[
            (v(-1.6, 0.8, 2.4), v(-0.4, 0.84, 2.73)),
            (v(-1.58, 0.0, 2.42), v(-1.54, 0.8, 2.46)),
            (v(-0.46, 0.0, 2.42), v(-0.42, 0.8, 2.46)),
            (v(-1.58, 0.0, 2.67), v(-1.54, 0.8, 2.71)),
            (v(-0.46, 0.0, 2.67), v(-0.42, 0.8, 2.71)),
        ],
        id("oak"),
    );
    let mut rack = cylinder(
        "coat-rack",
        v(-6.7, 0.02, 2.5),
        v(-6.7, 1.8, 2.5),
        0.02,
        20,
        12,
        id("walnut"),
    );
    for k in 0..6 {
        let phi = TAU * k as f32 / 6.0;
        let d = v(phi.cos(), 0.0, phi.sin());
        append(
            &mut rack,
            &tube(
                "coat-rack",
                &[v(-6.7, 1.62, 2.5) + 0.015 * d, v(-6.7, 1.7, 2.5) + 0.15 * d],
                &[0.01, 0.01],
                Vec3::Y.cross(d),
                12,
                0,
            ),
        );
        append(
            &mut rack,
            &sphere("coat-rack", v(-6.7, 1.7, 2.5) + 0.155 * d, 0.018, 16, 8, 0),
        );
    }
    append(
        &mut rack,
        &turned("coat-rack", v(-6.7, 0.0, 2.5), 0.03, |_| 0.2, 32, 1, 0),
    );
    let umbrella = turned(
        "umbrella-stand",
        v(-6.6, 0.0, 1.3),
        0.55,
        |t| 0.1 + 0.02 * (PI * t).sin(),
        32,
        12,
        id("brass"),
    );
    vec![doors, mirror, knobs, console, rack, umbrella]
}

/// The dining room: a table with a fruit bowl and candlesticks, six chairs, a sideboard.
fn dining_room() -> Vec<Mesh> {
    let v = Vec3::new;
    let (cx, cz) = (-3.5, 4.9);
    let mut meshes = vec![rounded(
        "dining-table",
        v(cx - 1.0, 0.72, cz - 0.5),
        v(cx + 1.0, 0.76, cz + 0.5),
        0.12,
        0.015,
        id("oak"),
    )];
    let mut legs = empty("dining-table-legs", id("oak"));
    for (dx, dz) in [(-0.88, -0.38), (0.88, -0.38), (-0.88, 0.38), (0.88, 0.38)] {
        append(
            &mut legs,
            &leg("l", v(cx + dx, 0.0, cz + dz), 0.719, 0.05, 0),
        );
    }
    meshes.push(legs);
    // Six chairs, three a side, facing the table.
    let mut chairs = empty("dining-chairs", id("walnut"));
    let mut seats = empty("dining-chair-seats", id("chair-fabric"));
    for side in [-1.0f32, 1.0] {
        for k in [-1.0f32, 0.0, 1.0] {
            let (x, z) = (cx + 0.7 * k, cz + side * 0.75);
            // Local frame: the back is away from the table (at +side).
            let p = |dx: f32, y: f32, dz: f32| v(x + dx, y, z + side * dz);
            for (dx, dz) in [(-0.2, -0.2), (0.2, -0.2), (-0.2, 0.2), (0.2, 0.2)] {
                let top = if dz > 0.0 { 1.0 } else { 0.44 };
                append(
                    &mut chairs,
                    &cylinder("c", p(dx, 0.0, dz), p(dx, top, dz), 0.02, 16, 6, 0),
                );
            }
            for y in [0.7, 0.85, 0.98] {
                let (a, b) = (p(-0.2, y - 0.03, 0.185), p(0.2, y, 0.215));
                append(&mut chairs, &cuboid("c", a.min(b), a.max(b), 0));
            }
            let (a, b) = (p(-0.23, 0.44, -0.23), p(0.23, 0.5, 0.23));
            append(&mut seats, &rounded("s", a.min(b), a.max(b), 0.05, 0.02, 0));
        }
    }
    meshes.extend([chairs, seats]);
    // A fruit bowl and two candlesticks on the table.
    meshes.push(turned(
        "fruit-bowl",
        v(cx, 0.76, cz),
        0.1,
        |t| 0.06 + 0.1 * t.sqrt(),
        48,
        10,
        id("porcelain"),
    ));
    let mut fruit = empty("fruit", id("fruit"));
    // Seven round the bowl's top and two on them.
    for k in 0..7 {
        let phi = TAU * k as f32 / 7.0;
        let centre = v(cx + 0.09 * phi.cos(), 0.9, cz + 0.09 * phi.sin());
        append(&mut fruit, &sphere("f", centre, 0.04, 24, 12, 0));
    }
    for dx in [-0.03, 0.04] {
        append(
            &mut fruit,
            &sphere("f", v(cx + dx, 0.96, cz), 0.04, 24, 12, 0),
        );
    }
    meshes.push(fruit);
    let mut candles = empty("candlesticks", id("brass"));
    for dx in [-0.6, 0.6] {
        append(
            &mut candles,
            &turned(
                "k",
                v(cx + dx, 0.76, cz),
                0.3,
                |t| {
                    let foot = 0.05 * (1.0 - t / 0.15).max(0.0);
                    let knop = 0.01 * (-((t - 0.6) / 0.05).powi(2)).exp();
                    let cup = 0.015 * (-((t - 0.97) / 0.03).powi(2)).exp();
                    0.012 + foot + knop + cup
                },
                24,
                30,
                0,
            ),
        );
    }
    meshes.push(candles);
    meshes.push(boxes(
        "dining-sideboard",
        &[(v(-6.93, 0.0, 3.6), v(-6.45, 0.9, 6.0))],
        id("walnut"),
    ));
    meshes
}

/// Parts spread over several rooms: vases, plants, lamps, pictures.
fn shared_parts() -> Vec<Mesh> {
    let v = Vec3::new;
    // Vases: (foot, height, widest radius).
    let vase_spots = [
        (v(-6.1, 0.8, 0.72), 0.35, 0.09),
        (v(-5.2, 0.8, 0.72), 0.25, 0.07),
        (v(-1.0, 0.84, 2.56), 0.4, 0.08),
        (v(-6.69, 0.9, 4.2), 0.3, 0.1),
        (v(-6.69, 0.9, 5.4), 0.45, 0.08),
    ];
    let mut vases = empty("vases", id("porcelain"));
    for (foot, height, r) in vase_spots {
        append(
            &mut vases,
            &turned(
                "v",
                foot,
                height,
                |t| r * (0.45 + 0.55 * (PI * (0.15 + 0.75 * t)).sin() - 0.25 * t),
                32,
                24,
                0,
            ),
        );
    }
    // Plants: a pot and leaves as thin ellipsoids on arching stems.
    let plant_spots = [
        v(-6.5, 0.0, -0.6),
        v(0.5, 0.0, -4.5),
        v(6.5, 0.0, 0.5),
        v(-0.5, 0.0, 6.5),
        v(6.5, 0.0, -4.6),
    ];
    let mut pots = empty("pots", id("terracotta"));
    let mut leaves = empty("leaves", id("leaf"));
    for (p, &at) in plant_spots.iter().enumerate() {
        append(
            &mut pots,
            &turned("p", at, 0.4, |t| 0.14 + 0.06 * t, 40, 8, 0),
        );
        for k in 0..60u32 {
            let salt = 1000 * p as u32 + k;
            let phi = TAU * hash(salt, 5);
            let rise = 0.45 + 0.9 * hash(salt, 6);
            let reach = 0.1 + 0.3 * hash(salt, 7);
            let centre = at + v(reach * phi.cos(), 0.4 + rise, reach * phi.sin());
            let rotation =
                Quat::from_rotation_y(-phi) * Quat::from_rotation_z(0.3 + 0.6 * hash(salt, 8));
            append(
                &mut leaves,
                &ellipsoid("l", centre, v(0.11, 0.008, 0.035), rotation, 12, 6, 0),
            );
        }
    }
    // Floor lamps: a base, a pole and a shade.
    let mut lamps = empty("lamps", id("brass"));
    let mut shades = empty("lamp-shades", id("shade"));
    for at in [v(-6.3, 0.0, -4.55), v(0.4, 0.0, -0.4), v(6.3, 0.0, -1.4)] {
        append(
            &mut lamps,
            &turned("l", at, 0.04, |t| 0.16 - 0.02 * t, 40, 3, 0),
        );
        append(
            &mut lamps,
            &cylinder(
                "l",
                at + v(0.0, 0.04, 0.0),
                at + v(0.0, 1.45, 0.0),
                0.015,
                20,
                16,
                0,
            ),
        );
        append(
            &mut shades,
            &turned(
                "s",
                at + v(0.0, 1.45, 0.0),
                0.3,
                |t| 0.22 - 0.1 * t,
                48,
                6,
                0,
            ),
        );
    }
    // Pictures: frames and canvases on the walls (facing into the rooms).
    let mut frames = empty("picture-frames", id("frame"));
    let mut pictures = Vec::new();
    let wall_face = |at: f32, into: f32| at + into * 0.5 * WALL_THICKNESS;
    // (axis of the wall, the wall's face, which way the picture faces, centre along, centre y, half size, canvas)
    let hangings = [
        (
            2,
            wall_face(-5.0, 1.0),
            true,
            -5.8,
            1.6,
            v(0.4, 0.3, 0.0),
            "picture-sea",
        ),
        (
            2,
            wall_face(-5.0, 1.0),
            true,
            3.0,
            1.7,
            v(0.6, 0.4, 0.0),
            "picture-sunset",
        ),
        (
            2,
            wall_face(1.0, 1.0),
            true,
            -5.5,
            1.6,
            v(0.5, 0.35, 0.0),
            "picture-field",
        ),
        (
            2,
            wall_face(1.0, 1.0),
            true,
            1.8,
            1.6,
            v(0.35, 0.45, 0.0),
            "picture-sea",
        ),
        (
            0,
            wall_face(-7.0, 1.0),
            true,
            5.0,
            1.7,
            v(0.7, 0.45, 0.0),
            "picture-sunset",
        ),
        (
            0,
            wall_face(7.0, -1.0),
            false,
            -0.4,
            1.6,
            v(0.5, 0.35, 0.0),
            "picture-field",
        ),
    ];
    for (k, (axis, at, positive, along, y, half, canvas)) in hangings.into_iter().enumerate() {
        let dir = if positive { 1.0 } else { -1.0 };
        // frame_solid's u, v: the axes after `axis`, cyclically (x: y, z; z: x, y).
        let uv = |a: f32, h: f32| {
            if axis == 0 {
                Vec2::new(h, a)
            } else {
                Vec2::new(a, h)
            }
        };
        let (ha, hh) = (half.x, half.y);
        let depth = if positive {
            (at, at + 0.03)
        } else {
            (at - 0.03, at)
        };
        append(
            &mut frames,
            &frame_solid(
                "f",
                axis,
                depth,
                (
                    uv(along - ha - 0.05, y - hh - 0.05),
                    uv(along + ha + 0.05, y + hh + 0.05),
                ),
                (uv(along - ha, y - hh), uv(along + ha, y + hh)),
                0,
            ),
        );
        let canvas_at = at + dir * 0.01;
        let (ua, va) = if axis == 0 {
            (edges(y - hh, y + hh, 1), edges(along - ha, along + ha, 1))
        } else {
            (edges(along - ha, along + ha, 1), edges(y - hh, y + hh, 1))
        };
        pictures.push(cells(
            &format!("picture-{}", k + 1),
            axis,
            canvas_at,
            &ua,
            &va,
            positive,
            |_, _| true,
            id(canvas),
        ));
    }
    let mut meshes = vec![vases, pots, leaves, lamps, shades, frames];
    meshes.extend(pictures);
    meshes
}
