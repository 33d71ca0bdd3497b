//! `mirrors`: two facing planar mirrors for the recursive specular images of
//! Diefenbach & Badler 1997, section 3 (and the reflected shadow volumes of
//! section 4.3): a small diffuse room, a mirror on each of the walls x = ±1.5,
//! exactly parallel, and a red ball on a blue pedestal between them, whose
//! nested images recede into the mirror the camera looks at.
//!
//! Geometry, in metres (+y up):
//!
//! - Room: x ∈ [-1.5, 1.5], y ∈ [0, 2.5], z ∈ [-1.5, 1.5]; floor, ceiling
//!   and four walls, each one inward-facing quad (diffuse).
//! - Mirrors ([`MIRROR_X`]): single quads 2.4 m wide (z ∈ [-1.2, 1.2]) and
//!   1.7 m high (y ∈ [0.4, 2.1]); `mirror-a` in the plane x = -1.48 facing
//!   +x, `mirror-b` in the plane x = +1.48 facing -x, 2 cm in front of their
//!   walls. Each sits in a diffuse frame, a 5 cm border from the wall to 2 cm
//!   in front of the mirror (|x| ∈ [1.46, 1.5]).
//! - Pedestal: the box x, z ∈ [-0.15, 0.15], y ∈ [0, 0.75] (blue).
//! - Ball: a UV sphere of radius 0.12 centred at (0, 0.87, 0) resting on the
//!   pedestal (40 slices × 20 stacks, red).
//! - Light: a 0.6 × 0.6 m rectangle centred at (0, 2.499, 0) facing down,
//!   radiance (15, 14.5, 13.5) W/(m² sr).
//! - Camera at (1.1, 1.6, 0.85) looking at (-1.48, 0.9, 0.03), 60° vertical
//!   field of view: beside and above the ball, 1.12 m off the line of its
//!   images, it looks down into `mirror-a`, where the images of the ball lie
//!   at x = -2.96 k (k = 1, 2, …: k reflections, alternating between the
//!   mirrors), their brightness falling as 0.9^k, receding towards the
//!   point of `mirror-a` opposite the camera.
//!
//! The pedestal, the ball and the frames are closed manifolds with outward
//! faces ([`CLOSED_MESHES`]).

use glam::{Vec2, Vec3};

use super::parts::{cuboid, frame_solid, quad, sphere};
use crate::{Camera, Material, MaterialModel, Mesh, Object, Rgb, Scene};

/// |x| of the two mirror planes (Diefenbach & Badler 1997, section 3).
pub const MIRROR_X: f32 = 1.48;
/// Half the width (along z) of each mirror.
pub const MIRROR_HALF_WIDTH: f32 = 1.2;
/// Bottom and top (y) of each mirror.
pub const MIRROR_Y: (f32, f32) = (0.4, 2.1);
/// Reflectance of both mirrors.
pub const MIRROR_REFLECTANCE: Rgb = Rgb::new(0.9, 0.9, 0.9);
/// Half the room's size along x and z; the room is 2.5 m high.
pub const ROOM_HALF: f32 = 1.5;
/// Height of the room.
pub const ROOM_HEIGHT: f32 = 2.5;
/// Centre of the ball.
pub const BALL_CENTRE: Vec3 = Vec3::new(0.0, 0.87, 0.0);
/// Radius of the ball.
pub const BALL_RADIUS: f32 = 0.12;
/// Reflectance of the ball: a vivid red, so that its images can be counted.
pub const BALL_REFLECTANCE: Rgb = Rgb::new(0.8, 0.06, 0.05);
/// Reflectance of the pedestal: a vivid blue.
pub const PEDESTAL_REFLECTANCE: Rgb = Rgb::new(0.08, 0.15, 0.65);
/// Radiance of the ceiling light, in W/(m² sr).
pub const LIGHT_RADIANCE: Rgb = Rgb::new(15.0, 14.5, 13.5);
/// Side of the square ceiling light.
pub const LIGHT_SIZE: f32 = 0.6;
/// Where the camera stands: 1.12 m off the line of the ball's images, so
/// that the nearer images hide little of the farther ones.
pub const CAMERA_POSITION: Vec3 = Vec3::new(1.1, 1.6, 0.85);
/// The meshes that are closed manifolds with outward faces.
pub const CLOSED_MESHES: &[&str] = &["frame-a", "frame-b", "pedestal", "ball"];

/// `mirrors`: the facing-mirrors room (Diefenbach & Badler 1997, section 3).
pub fn mirrors() -> Scene {
    let (wall, floor, ceiling, frame, mirror, ball, pedestal, light) = (0, 1, 2, 3, 4, 5, 6, 7);
    let materials = vec![
        Material::diffuse("wall", Rgb::new(0.75, 0.73, 0.7)),
        Material::diffuse("floor", Rgb::new(0.45, 0.42, 0.38)),
        Material::diffuse("ceiling", Rgb::splat(0.8)),
        Material::diffuse("frame", Rgb::new(0.3, 0.2, 0.12)),
        Material::new(
            "mirror",
            MaterialModel::Mirror {
                reflectance: MIRROR_REFLECTANCE,
            },
        ),
        Material::diffuse("ball", BALL_REFLECTANCE),
        Material::diffuse("pedestal", PEDESTAL_REFLECTANCE),
        Material::diffuse("light", Rgb::splat(0.8)).with_emission(LIGHT_RADIANCE),
    ];
    let (h, top) = (ROOM_HALF, ROOM_HEIGHT);
    let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
    let (y0, y1) = MIRROR_Y;
    let w = MIRROR_HALF_WIDTH;
    let mut meshes = vec![
        quad(
            "floor",
            Vec3::new(-h, 0.0, -h),
            2.0 * h * z,
            2.0 * h * x,
            floor,
        ),
        quad(
            "ceiling",
            Vec3::new(-h, top, -h),
            2.0 * h * x,
            2.0 * h * z,
            ceiling,
        ),
        quad(
            "wall-left",
            Vec3::new(-h, 0.0, -h),
            top * y,
            2.0 * h * z,
            wall,
        ),
        quad(
            "wall-right",
            Vec3::new(h, 0.0, -h),
            2.0 * h * z,
            top * y,
            wall,
        ),
        quad(
            "wall-back",
            Vec3::new(-h, 0.0, -h),
            2.0 * h * x,
            top * y,
            wall,
        ),
        quad(
            "wall-front",
            Vec3::new(-h, 0.0, h),
            top * y,
            2.0 * h * x,
            wall,
        ),
        quad(
            "mirror-a",
            Vec3::new(-MIRROR_X, y0, -w),
            (y1 - y0) * y,
            2.0 * w * z,
            mirror,
        ),
        quad(
            "mirror-b",
            Vec3::new(MIRROR_X, y0, -w),
            2.0 * w * z,
            (y1 - y0) * y,
            mirror,
        ),
        mirror_frame("frame-a", -1.0, frame),
        mirror_frame("frame-b", 1.0, frame),
        cuboid(
            "pedestal",
            Vec3::new(-0.15, 0.0, -0.15),
            Vec3::new(0.15, 0.75, 0.15),
            pedestal,
        ),
        sphere("ball", BALL_CENTRE, BALL_RADIUS, 40, 20, ball),
    ];
    let s = LIGHT_SIZE;
    meshes.push(quad(
        "light",
        Vec3::new(-0.5 * s, top - 0.001, -0.5 * s),
        s * x,
        s * z,
        light,
    ));
    let camera = Camera::look_at(
        CAMERA_POSITION,
        Vec3::new(-MIRROR_X, 0.9, 0.03),
        Vec3::Y,
        60.0,
    );
    Scene::new(
        "mirrors",
        meshes.clone(),
        materials,
        Object::one_per_mesh(&meshes),
        Vec::new(),
        camera,
    )
    .expect("the built-in mirrors scene is valid")
}

/// The frame of the mirror on the wall x = `side` · 1.5: a 5 cm border
/// round the mirror, from the wall to 2 cm in front of the mirror.
fn mirror_frame(name: &str, side: f32, material: u32) -> Mesh {
    let (y0, y1) = MIRROR_Y;
    let w = MIRROR_HALF_WIDTH;
    let bar = 0.05;
    let depth = if side < 0.0 {
        (-ROOM_HALF, -MIRROR_X + 0.02)
    } else {
        (MIRROR_X - 0.02, ROOM_HALF)
    };
    frame_solid(
        name,
        0,
        depth,
        (Vec2::new(y0 - bar, -w - bar), Vec2::new(y1 + bar, w + bar)),
        (Vec2::new(y0, -w), Vec2::new(y1, w)),
        material,
    )
}
