//! Camera rays, matrices and the mirror transform.

use glam::{Vec2, Vec3, Vec4Swizzles};
use lustre_geometry::{Camera, Plane};
use proptest::prelude::*;

fn camera() -> Camera {
    Camera::look_at(
        Vec3::new(0.3, 0.2, 3.9),
        Vec3::new(0.0, -0.1, 0.0),
        Vec3::Y,
        39.3077,
    )
    .with_aspect(1.5)
}

fn project(cam: &Camera, p: Vec3) -> Vec3 {
    let clip = cam.view_projection() * p.extend(1.0);
    clip.xyz() / clip.w
}

proptest! {
    /// A point along the primary ray through an NDC position projects back to it.
    #[test]
    fn primary_rays_agree_with_the_projection(x in -1.0f32..1.0, y in -1.0f32..1.0, t in 0.5f32..50.0) {
        let cam = camera();
        let ray = cam.primary_ray(Vec2::new(x, y));
        prop_assert!((ray.direction.length() - 1.0).abs() < 1e-5);
        let ndc = project(&cam, ray.at(t));
        prop_assert!((ndc.x - x).abs() < 1e-4 && (ndc.y - y).abs() < 1e-4, "{ndc} vs {x},{y}");
        // Reverse Z: depth in (0, 1], decreasing with distance.
        let farther = project(&cam, ray.at(t * 2.0));
        prop_assert!(ndc.z > 0.0 && ndc.z <= 1.0 && farther.z < ndc.z);
    }

    /// Mirroring is an involution that fixes the plane and preserves distances.
    #[test]
    fn reflection_about_a_plane(nx in -1.0f32..1.0, ny in -1.0f32..1.0, nz in -1.0f32..1.0, d in -2.0f32..2.0,
                                px in -3.0f32..3.0, py in -3.0f32..3.0, pz in -3.0f32..3.0) {
        prop_assume!(Vec3::new(nx, ny, nz).length() > 0.1);
        let plane = Plane { normal: Vec3::new(nx, ny, nz).normalize(), offset: d };
        let m = plane.reflection_matrix();
        let p = Vec3::new(px, py, pz);
        let r = m.transform_point3(p);
        prop_assert!((r - plane.reflect_point(p)).length() < 1e-4);
        prop_assert!((m.transform_point3(r) - p).length() < 1e-4);
        prop_assert!((plane.signed_distance(r) + plane.signed_distance(p)).abs() < 1e-4);
        prop_assert!((m.determinant() + 1.0).abs() < 1e-4);
        let on_plane = p - plane.signed_distance(p) * plane.normal;
        prop_assert!((m.transform_point3(on_plane) - on_plane).length() < 1e-4);
    }
}

#[test]
fn view_looks_down_negative_z_and_fov_is_vertical() {
    let cam = Camera::look_at(Vec3::new(0.0, 0.0, 3.9), Vec3::ZERO, Vec3::Y, 39.3077);
    let v = cam.view_matrix().transform_point3(Vec3::ZERO);
    assert!((v - Vec3::new(0.0, 0.0, -3.9)).length() < 1e-5);
    // The top edge of the image is half the vertical fov above the axis.
    let top = cam.primary_ray(Vec2::new(0.0, 1.0));
    let angle = top.direction.dot(-Vec3::Z).acos().to_degrees();
    assert!((angle - 39.3077 / 2.0).abs() < 1e-3, "{angle}");
    assert!(top.direction.y > 0.0);
    // Pixel (0, 0) is the top-left corner.
    let ndc = Camera::pixel_ndc(0, 0, 256, 256, Vec2::ZERO);
    assert_eq!(ndc, Vec2::new(-1.0, 1.0));
    let centre = Camera::pixel_ndc(128, 128, 256, 256, Vec2::ZERO);
    assert_eq!(centre, Vec2::ZERO);
}

#[test]
fn mirrored_view_sees_reflections_where_the_mirror_shows_them() {
    // A floor mirror at y = -1: a point above the floor, seen through the
    // mirror, appears where the real camera sees its reflection below the floor.
    let cam = camera();
    let floor = Plane::from_point_normal(Vec3::new(0.0, -1.0, 0.0), Vec3::Y);
    let p = Vec3::new(0.2, 0.4, -0.3);
    let through_mirror = cam.projection_matrix() * cam.mirrored_view_matrix(&floor) * p.extend(1.0);
    let direct = cam.view_projection() * floor.reflect_point(p).extend(1.0);
    assert!((through_mirror - direct).length() < 1e-4);
    // The reflected (proper) camera sits below the floor, looking up at p's side.
    let virtual_cam = cam.reflected(&floor);
    assert!((virtual_cam.position.y - (-2.0 - cam.position.y)).abs() < 1e-5);
    let (_, up, forward) = virtual_cam.frame();
    assert!(up.length() > 0.99 && forward.length() > 0.99);
}

/// Jittered accumulation (Diefenbach & Badler 1997, section 7): a camera with
/// pixel offset `o` projects the point its pixel sees at `o` onto the pixel's
/// centre, and its primary rays follow the shift.
#[test]
fn pixel_offsets_shift_the_image_by_a_fraction_of_a_pixel() {
    let (width, height) = (64, 48);
    let cam = camera().with_aspect(width as f32 / height as f32);
    assert_eq!(cam.with_pixel_offset(Vec2::splat(0.5), width, height), cam);
    for offset in [Vec2::new(0.1, 0.9), Vec2::new(0.75, 0.25)] {
        let jittered = cam.with_pixel_offset(offset, width, height);
        for (x, y) in [(0, 0), (10, 30), (63, 47)] {
            // The point the unjittered camera sees at offset `offset` of the pixel...
            let ray = cam.primary_ray(Camera::pixel_ndc(x, y, width, height, offset));
            let p = ray.at(2.0);
            // ...is at the pixel's centre in the jittered image.
            let ndc = project(&jittered, p);
            let centre = Camera::pixel_ndc(x, y, width, height, Vec2::splat(0.5));
            assert!(
                (ndc.truncate() - centre).length() < 1e-4,
                "{ndc} vs {centre}"
            );
            // The jittered camera's ray through the centre is the same ray.
            let through = jittered.primary_ray(centre);
            assert!((through.direction - ray.direction).length() < 1e-5);
        }
    }
}
