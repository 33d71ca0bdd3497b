//! The window's camera controllers: orbit about a centre (the default, framed on the scene) and fly (WASD, Q/E, mouse look), both turning the scene's [`Camera`] into yaw, pitch and distance and back, with no window involved so they are tested alone.

use glam::Vec3;
use lustre_geometry::Aabb;
use lustre_geometry::Camera;

/// Largest pitch either controller allows (radians, just short of straight up or down, where yaw is undefined).
const MAX_PITCH: f32 = 1.55;

/// Yaw and pitch (radians) of a unit direction in a Y-up world: yaw 0 looks along −Z, positive yaw turns towards −X (to the left, as a mouse drawn left does).
pub fn yaw_pitch(direction: Vec3) -> (f32, f32) {
    let d = direction.normalize_or(Vec3::NEG_Z);
    let pitch = d.y.clamp(-1.0, 1.0).asin();
    let yaw = (-d.x).atan2(-d.z);
    (yaw, pitch)
}

/// The unit direction of a yaw and pitch ([`yaw_pitch`]'s inverse).
pub fn direction(yaw: f32, pitch: f32) -> Vec3 {
    Vec3::new(
        -yaw.sin() * pitch.cos(),
        pitch.sin(),
        -yaw.cos() * pitch.cos(),
    )
}

/// Orbit: the eye on a sphere about `centre`; drag to turn, scroll to zoom, shift-drag to pan.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Orbit {
    /// The point looked at and turned about.
    pub centre: Vec3,
    /// Eye distance from the centre.
    pub distance: f32,
    /// Yaw of the viewing direction (radians).
    pub yaw: f32,
    /// Pitch of the viewing direction (radians).
    pub pitch: f32,
}

impl Orbit {
    /// Radians turned per pixel dragged.
    pub const TURN_PER_PIXEL: f32 = 0.005;
    /// Distance factor per scroll line (a line in, the eye 10 % closer).
    pub const ZOOM_PER_LINE: f32 = 0.9;

    /// The orbit that reproduces `camera`: about its target, at its distance.
    pub fn from_camera(camera: &Camera) -> Self {
        let offset = camera.target - camera.position;
        let (yaw, pitch) = yaw_pitch(offset);
        Self {
            centre: camera.target,
            distance: offset.length().max(1e-4),
            yaw,
            pitch,
        }
    }

    /// An orbit framed on `bounds`: about their centre, from the front and a little above and to the side (a pleasing three-quarter view rather than straight down an axis), far enough that the bounding sphere fills `fov_y_degrees`.
    pub fn framing(bounds: &Aabb, fov_y_degrees: f32) -> Self {
        let centre = 0.5 * (bounds.min + bounds.max);
        let radius = (0.5 * (bounds.max - bounds.min).length()).max(1e-3);
        let half = (0.5 * fov_y_degrees.to_radians()).clamp(0.05, 1.5);
        Self {
            centre,
            distance: radius / half.sin(),
            yaw: (-30.0f32).to_radians(),
            pitch: (-20.0f32).to_radians(),
        }
    }

    /// Turns by a mouse drag of `dx`, `dy` pixels (right turns the view right, down looks down).
    pub fn drag(&mut self, dx: f32, dy: f32) {
        self.yaw -= dx * Self::TURN_PER_PIXEL;
        self.pitch = (self.pitch - dy * Self::TURN_PER_PIXEL).clamp(-MAX_PITCH, MAX_PITCH);
    }

    /// Moves the centre in the view plane by a drag of `dx`, `dy` pixels in a window `height` pixels high at `fov_y_degrees` (the point under the cursor follows it).
    pub fn pan(&mut self, dx: f32, dy: f32, height: f32, fov_y_degrees: f32) {
        let per_pixel =
            2.0 * self.distance * (0.5 * fov_y_degrees.to_radians()).tan() / height.max(1.0);
        let forward = direction(self.yaw, self.pitch);
        let right = forward.cross(Vec3::Y).normalize_or(Vec3::X);
        let up = right.cross(forward);
        self.centre += (-dx * right + dy * up) * per_pixel;
    }

    /// Zooms by `lines` scroll lines (positive: closer).
    pub fn zoom(&mut self, lines: f32) {
        self.distance = (self.distance * Self::ZOOM_PER_LINE.powf(lines)).max(1e-4);
    }

    /// The camera at this orbit with `template`'s field of view, aspect and near plane.
    pub fn camera(&self, template: &Camera) -> Camera {
        let forward = direction(self.yaw, self.pitch);
        Camera {
            position: self.centre - self.distance * forward,
            target: self.centre,
            up: Vec3::Y,
            ..*template
        }
    }
}

/// Which way the fly camera moves this instant, each axis −1, 0 or 1.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FlyKeys {
    /// W/S: forwards (+1) and back.
    pub forward: f32,
    /// D/A: right (+1) and left.
    pub right: f32,
    /// E/Q: up (+1) and down.
    pub up: f32,
    /// Shift: fast.
    pub fast: bool,
}

impl FlyKeys {
    /// Whether any movement key is held.
    pub fn moving(&self) -> bool {
        self.forward != 0.0 || self.right != 0.0 || self.up != 0.0
    }
}

/// Fly: a free eye with WASD, Q/E down and up, Shift faster, drag to look.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fly {
    /// The eye.
    pub position: Vec3,
    /// Yaw of the viewing direction (radians).
    pub yaw: f32,
    /// Pitch of the viewing direction (radians).
    pub pitch: f32,
    /// Speed in scene units per second (Shift: [`Fly::FAST`] times more).
    pub speed: f32,
    /// Distance to the point looked at when turned back into an orbit.
    pub focus: f32,
}

impl Fly {
    /// Speed factor while Shift is held.
    pub const FAST: f32 = 4.0;

    /// The fly camera at `camera`'s eye and direction, crossing a scene of size `scene_size` in about four seconds.
    pub fn from_camera(camera: &Camera, scene_size: f32) -> Self {
        let offset = camera.target - camera.position;
        let (yaw, pitch) = yaw_pitch(offset);
        Self {
            position: camera.position,
            yaw,
            pitch,
            speed: (0.25 * scene_size).max(1e-3),
            focus: offset.length().max(1e-3),
        }
    }

    /// Looks by a mouse drag of `dx`, `dy` pixels.
    pub fn look(&mut self, dx: f32, dy: f32) {
        self.yaw -= dx * Orbit::TURN_PER_PIXEL;
        self.pitch = (self.pitch - dy * Orbit::TURN_PER_PIXEL).clamp(-MAX_PITCH, MAX_PITCH);
    }

    /// Moves for `seconds` with `keys` held: forwards along the view, sideways level with the ground, up along +Y.
    pub fn advance(&mut self, keys: FlyKeys, seconds: f32) {
        let forward = direction(self.yaw, self.pitch);
        let right = forward.cross(Vec3::Y).normalize_or(Vec3::X);
        let speed = if keys.fast {
            self.speed * Self::FAST
        } else {
            self.speed
        };
        let step = keys.forward * forward + keys.right * right + keys.up * Vec3::Y;
        self.position += step * speed * seconds;
    }

    /// The camera at this eye with `template`'s field of view, aspect and near plane.
    pub fn camera(&self, template: &Camera) -> Camera {
        Camera {
            position: self.position,
            target: self.position + self.focus * direction(self.yaw, self.pitch),
            up: Vec3::Y,
            ..*template
        }
    }
}

/// The window's active controller.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Controller {
    /// Orbit about a centre.
    Orbit(Orbit),
    /// Fly freely.
    Fly(Fly),
}

impl Controller {
    /// The camera it gives, with `template`'s lens.
    pub fn camera(&self, template: &Camera) -> Camera {
        match self {
            Controller::Orbit(o) => o.camera(template),
            Controller::Fly(f) => f.camera(template),
        }
    }

    /// The other controller at the same camera (Tab).
    pub fn toggled(&self, template: &Camera, scene_size: f32) -> Self {
        let camera = self.camera(template);
        match self {
            Controller::Orbit(_) => Controller::Fly(Fly::from_camera(&camera, scene_size)),
            Controller::Fly(_) => Controller::Orbit(Orbit::from_camera(&camera)),
        }
    }

    /// The controller's name for the panel.
    pub fn name(&self) -> &'static str {
        match self {
            Controller::Orbit(_) => "orbit",
            Controller::Fly(_) => "fly",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).length() < 1e-4 * (1.0 + b.length())
    }

    fn cam(position: Vec3, target: Vec3) -> Camera {
        Camera::look_at(position, target, Vec3::Y, 40.0)
    }

    #[test]
    fn yaw_and_pitch_invert_each_other() {
        for d in [
            Vec3::new(0.0, 0.0, -1.0),
            Vec3::new(1.0, 0.5, 0.3),
            Vec3::new(-0.2, -0.9, 0.4),
            Vec3::new(0.0, 0.3, 1.0),
        ] {
            let (yaw, pitch) = yaw_pitch(d);
            assert!(close(direction(yaw, pitch), d.normalize()), "{d}");
        }
        // Yaw 0 looks down −Z; a positive yaw turns left, towards −X.
        assert!(close(direction(0.0, 0.0), Vec3::NEG_Z));
        assert!(direction(0.3, 0.0).x < 0.0);
    }

    #[test]
    fn an_orbit_from_a_camera_gives_the_camera_back() {
        let c = cam(Vec3::new(0.5, 1.2, 3.0), Vec3::new(0.1, 0.4, -0.2));
        let back = Orbit::from_camera(&c).camera(&c);
        assert!(close(back.position, c.position));
        assert!(close(back.target, c.target));
        assert_eq!(back.fov_y_degrees, c.fov_y_degrees);
    }

    #[test]
    fn orbit_drag_keeps_distance_and_centre_and_clamps_pitch() {
        let c = cam(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO);
        let mut o = Orbit::from_camera(&c);
        o.drag(120.0, 0.0);
        let moved = o.camera(&c);
        assert!(close(moved.target, Vec3::ZERO));
        assert!(((moved.position - moved.target).length() - 3.0).abs() < 1e-4);
        // Dragging right turns the view right: the eye swings to −X around the centre.
        assert!(moved.position.x < 0.0, "{}", moved.position);
        o.drag(0.0, 1e6);
        assert!(o.pitch >= -MAX_PITCH && o.pitch <= MAX_PITCH);
        assert!(o.camera(&c).position.is_finite());
    }

    #[test]
    fn orbit_zoom_and_pan() {
        let c = cam(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO);
        let mut o = Orbit::from_camera(&c);
        o.zoom(1.0);
        assert!((o.distance - 3.6).abs() < 1e-5);
        o.zoom(-1.0);
        assert!((o.distance - 4.0).abs() < 1e-5);
        // A drag of half the window's height moves the centre by half the view's height at the centre's distance.
        o.pan(0.0, 50.0, 100.0, 90.0);
        assert!(close(o.centre, Vec3::new(0.0, 4.0, 0.0)), "{}", o.centre);
        o.pan(50.0, 0.0, 100.0, 90.0);
        assert!(close(o.centre, Vec3::new(-4.0, 4.0, 0.0)), "{}", o.centre);
    }

    #[test]
    fn framing_sees_the_whole_bounding_sphere_from_an_oblique_angle() {
        let bounds = Aabb {
            min: Vec3::new(-1.0, 0.0, -2.0),
            max: Vec3::new(3.0, 2.0, 2.0),
        };
        let o = Orbit::framing(&bounds, 40.0);
        let c = o.camera(&cam(Vec3::Z, Vec3::ZERO));
        let radius = 0.5 * (bounds.max - bounds.min).length();
        let centre = 0.5 * (bounds.min + bounds.max);
        // The sphere's angular radius equals half the field of view.
        let seen = (radius / (c.position - centre).length())
            .asin()
            .to_degrees();
        assert!((seen - 20.0).abs() < 1e-3, "{seen}");
        // Not straight down an axis: every component of the view direction is non-zero.
        let d = (c.target - c.position).normalize();
        assert!(d.x.abs() > 0.1 && d.y.abs() > 0.1 && d.z.abs() > 0.1, "{d}");
    }

    #[test]
    fn fly_moves_along_the_view_and_faster_with_shift() {
        let c = cam(Vec3::new(0.0, 1.0, 5.0), Vec3::new(0.0, 1.0, 0.0));
        let mut f = Fly::from_camera(&c, 4.0);
        assert_eq!(f.speed, 1.0);
        f.advance(
            FlyKeys {
                forward: 1.0,
                ..FlyKeys::default()
            },
            2.0,
        );
        assert!(
            close(f.position, Vec3::new(0.0, 1.0, 3.0)),
            "{}",
            f.position
        );
        f.advance(
            FlyKeys {
                right: 1.0,
                fast: true,
                ..FlyKeys::default()
            },
            0.5,
        );
        assert!(
            close(f.position, Vec3::new(2.0, 1.0, 3.0)),
            "{}",
            f.position
        );
        f.advance(
            FlyKeys {
                up: -1.0,
                ..FlyKeys::default()
            },
            1.0,
        );
        assert!(
            close(f.position, Vec3::new(2.0, 0.0, 3.0)),
            "{}",
            f.position
        );
        // The camera keeps looking the same way.
        let moved = f.camera(&c);
        assert!(close(
            (moved.target - moved.position).normalize(),
            Vec3::NEG_Z
        ));
    }

    #[test]
    fn toggling_keeps_the_camera() {
        let c = cam(Vec3::new(1.0, 2.0, 3.0), Vec3::new(0.0, 0.5, 0.0));
        let orbit = Controller::Orbit(Orbit::from_camera(&c));
        let fly = orbit.toggled(&c, 5.0);
        assert_eq!(fly.name(), "fly");
        let back = fly.toggled(&c, 5.0);
        for other in [fly, back] {
            let got = other.camera(&c);
            assert!(close(got.position, c.position));
            assert!(close(got.target, c.target));
        }
    }
}
