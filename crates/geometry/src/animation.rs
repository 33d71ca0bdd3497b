//! Paths of mobile objects: keyframed rigid motions that move an object of a
//! quasi-static scene frame after frame (García et al. 2003, section 2.2.2:
//! "a static background and a moving character", the mobile object moves and
//! rotates with respect to the static scene).
//!
//! An [`ObjectPath`] is a list of [`Keyframe`]s (time, translation, rotation)
//! and a pivot: at a keyframe the object is turned by the rotation about the
//! pivot (a point of its rest pose) and the pivot is carried to the
//! translation, so the transform is `x ↦ rotation · (x − pivot) + translation`,
//! relative to the rest pose as [`crate::Scene::set_object_transform`] takes
//! it. Between keyframes the translation is interpolated linearly and the
//! rotation by slerp (the shorter arc). Outside the keyframes' times a
//! [`PathEnd::Clamp`] path holds its first or last pose, and a
//! [`PathEnd::Loop`] path repeats with its duration as period (continuous when
//! its last keyframe equals its first).

use glam::{Affine3A, Quat, Vec3};

use crate::{GeometryError, ObjectId, Result};

/// An object of the scene that moves along a path: the papers' mobile object (García et al. 2003, section 2.2.2).
#[derive(Debug, Clone, PartialEq)]
pub struct MobileObject {
    /// The object that moves.
    pub object: ObjectId,
    /// Its motion, relative to its rest pose.
    pub path: ObjectPath,
}

/// One pose of a path: where the pivot is and how the object is turned at a time (García et al. 2003, section 2.2.2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Keyframe {
    /// Time in seconds.
    pub time: f32,
    /// Where the pivot is carried to.
    pub translation: Vec3,
    /// Rotation about the pivot (normalised by [`ObjectPath::new`]).
    pub rotation: Quat,
}

impl Keyframe {
    /// A keyframe at `time` with the pivot at `translation` and the object turned by `rotation` (García et al. 2003, section 2.2.2).
    pub fn new(time: f32, translation: Vec3, rotation: Quat) -> Self {
        Self {
            time,
            translation,
            rotation,
        }
    }
}

/// What a path does outside its keyframes' times (García et al. 2003, section 2.2.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PathEnd {
    /// Hold the first pose before the first keyframe and the last pose after the last.
    #[default]
    Clamp,
    /// Repeat with the path's duration as period.
    Loop,
}

/// A keyframed rigid motion of a mobile object (García et al. 2003, section 2.2.2).
#[derive(Debug, Clone, PartialEq)]
pub struct ObjectPath {
    keyframes: Vec<Keyframe>,
    pivot: Vec3,
    end: PathEnd,
}

impl ObjectPath {
    /// A path through `keyframes` with the pivot at the origin; fails on no
    /// keyframes, non-finite values, a zero rotation or times that do not
    /// strictly increase; rotations are normalised (García et al. 2003, section 2.2.2).
    pub fn new(keyframes: Vec<Keyframe>, end: PathEnd) -> Result<Self> {
        if keyframes.is_empty() {
            return Err(invalid("a path needs at least one keyframe".into()));
        }
        let mut keyframes = keyframes;
        for (i, k) in keyframes.iter_mut().enumerate() {
            if !k.time.is_finite() || !k.translation.is_finite() || !k.rotation.is_finite() {
                return Err(invalid(format!("keyframe {i} is not finite")));
            }
            let length = k.rotation.length();
            if !(length > 1e-6) || !length.is_finite() {
                return Err(invalid(format!("keyframe {i} has a zero rotation")));
            }
            k.rotation /= length;
        }
        if let Some(i) = keyframes.windows(2).position(|w| w[1].time <= w[0].time) {
            return Err(invalid(format!(
                "keyframe {} at {} s does not come after keyframe {i} at {} s",
                i + 1,
                keyframes[i + 1].time,
                keyframes[i].time
            )));
        }
        let duration = keyframes[keyframes.len() - 1].time - keyframes[0].time;
        if !duration.is_finite() {
            return Err(invalid("the path's duration is not finite".into()));
        }
        Ok(Self {
            keyframes,
            pivot: Vec3::ZERO,
            end,
        })
    }

    /// The same path turning about `pivot` (a rest-pose point) instead of the origin; fails when it is not finite (García et al. 2003, section 2.2.2).
    pub fn with_pivot(mut self, pivot: Vec3) -> Result<Self> {
        if !pivot.is_finite() {
            return Err(invalid("the pivot is not finite".into()));
        }
        self.pivot = pivot;
        Ok(self)
    }

    /// The keyframes, in time order with unit rotations (García et al. 2003, section 2.2.2).
    pub fn keyframes(&self) -> &[Keyframe] {
        &self.keyframes
    }

    /// The rest-pose point the rotations turn about (García et al. 2003, section 2.2.2).
    pub fn pivot(&self) -> Vec3 {
        self.pivot
    }

    /// What the path does outside its keyframes' times (García et al. 2003, section 2.2.2).
    pub fn end(&self) -> PathEnd {
        self.end
    }

    /// Time of the first keyframe in seconds (García et al. 2003, section 2.2.2).
    pub fn start(&self) -> f32 {
        self.keyframes[0].time
    }

    /// Time from the first keyframe to the last in seconds, zero for one keyframe (García et al. 2003, section 2.2.2).
    pub fn duration(&self) -> f32 {
        self.keyframes[self.keyframes.len() - 1].time - self.start()
    }

    /// The pivot's position and the rotation at time `t` (García et al. 2003, section 2.2.2).
    pub fn pose(&self, t: f32) -> (Vec3, Quat) {
        let first = &self.keyframes[0];
        let last = &self.keyframes[self.keyframes.len() - 1];
        let duration = self.duration();
        let t = match self.end {
            _ if duration <= 0.0 || t.is_nan() => first.time,
            PathEnd::Clamp => t.clamp(first.time, last.time),
            PathEnd::Loop if !t.is_finite() => first.time,
            PathEnd::Loop if t >= first.time && t <= last.time => t,
            PathEnd::Loop => first.time + (t - first.time).rem_euclid(duration),
        };
        // The segment [k[i], k[i + 1]] holding t.
        let i = self
            .keyframes
            .partition_point(|k| k.time <= t)
            .clamp(1, self.keyframes.len().max(2) - 1)
            - 1;
        let a = &self.keyframes[i];
        let Some(b) = self.keyframes.get(i + 1) else {
            return (a.translation, a.rotation);
        };
        let s = ((t - a.time) / (b.time - a.time)).clamp(0.0, 1.0);
        if s == 0.0 {
            return (a.translation, a.rotation);
        }
        if s == 1.0 {
            return (b.translation, b.rotation);
        }
        (
            a.translation.lerp(b.translation, s),
            a.rotation.slerp(b.rotation, s).normalize(),
        )
    }

    /// The object's transform relative to its rest pose at time `t` (García et al. 2003, section 2.2.2).
    pub fn at(&self, t: f32) -> Affine3A {
        let (translation, rotation) = self.pose(t);
        Affine3A::from_rotation_translation(rotation, translation)
            * Affine3A::from_translation(-self.pivot)
    }

    /// `k` evenly spaced times: from the start to the end inclusive for a
    /// clamped path, over one period without its end (which repeats its
    /// start) for a looping one; the start alone for `k` = 1 (García et al. 2003, section 2.2.2).
    pub fn frame_times(&self, k: usize) -> Vec<f32> {
        let steps = match (self.end, k) {
            (_, 0) => return Vec::new(),
            (_, 1) => return vec![self.start()],
            (PathEnd::Clamp, k) => k - 1,
            (PathEnd::Loop, k) => k,
        };
        (0..k)
            .map(|i| self.start() + self.duration() * (i as f32 / steps as f32))
            .collect()
    }

    /// The transforms at [`ObjectPath::frame_times`]`(k)`: an animation of `k` frames (García et al. 2003, section 2.2.2).
    pub fn frames(&self, k: usize) -> Vec<Affine3A> {
        self.frame_times(k)
            .into_iter()
            .map(|t| self.at(t))
            .collect()
    }
}

/// A [`GeometryError::InvalidPath`].
fn invalid(message: String) -> GeometryError {
    GeometryError::InvalidPath(message)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Affine3A, b: Affine3A) -> bool {
        a.abs_diff_eq(b, 1e-5)
    }

    fn two_keys(end: PathEnd) -> ObjectPath {
        ObjectPath::new(
            vec![
                Keyframe::new(1.0, Vec3::ZERO, Quat::IDENTITY),
                Keyframe::new(3.0, Vec3::new(2.0, 0.0, -4.0), Quat::from_rotation_y(1.0)),
            ],
            end,
        )
        .unwrap()
    }

    #[test]
    fn endpoints_and_midpoint() {
        let path = two_keys(PathEnd::Clamp);
        assert_eq!(path.start(), 1.0);
        assert_eq!(path.duration(), 2.0);
        assert!(close(path.at(1.0), Affine3A::IDENTITY));
        let end = Affine3A::from_rotation_translation(
            Quat::from_rotation_y(1.0),
            Vec3::new(2.0, 0.0, -4.0),
        );
        assert!(close(path.at(3.0), end));
        let mid = Affine3A::from_rotation_translation(
            Quat::from_rotation_y(0.5),
            Vec3::new(1.0, 0.0, -2.0),
        );
        assert!(close(path.at(2.0), mid));
        // Clamped outside.
        assert!(close(path.at(-5.0), Affine3A::IDENTITY));
        assert!(close(path.at(9.0), end));
    }

    #[test]
    fn loop_wraps_and_frames_cover_one_period() {
        let path = two_keys(PathEnd::Loop);
        assert!(close(path.at(3.5), path.at(1.5)));
        assert!(close(path.at(0.5), path.at(2.5)));
        assert!(close(path.at(-7.25), path.at(2.75)));
        assert_eq!(path.frame_times(4), vec![1.0, 1.5, 2.0, 2.5]);
        let clamped = two_keys(PathEnd::Clamp);
        assert_eq!(clamped.frame_times(5), vec![1.0, 1.5, 2.0, 2.5, 3.0]);
        assert_eq!(clamped.frame_times(1), vec![1.0]);
        assert!(clamped.frame_times(0).is_empty());
        assert_eq!(clamped.frames(3).len(), 3);
    }

    #[test]
    fn pivot_stays_at_the_translation() {
        let pivot = Vec3::new(0.3, -0.7, 0.4);
        let path = ObjectPath::new(
            vec![
                Keyframe::new(0.0, pivot, Quat::IDENTITY),
                Keyframe::new(1.0, Vec3::new(1.0, -0.7, 0.0), Quat::from_rotation_y(2.0)),
            ],
            PathEnd::Clamp,
        )
        .unwrap()
        .with_pivot(pivot)
        .unwrap();
        assert!(close(path.at(0.0), Affine3A::IDENTITY));
        for t in [0.25, 0.5, 1.0] {
            let (translation, _) = path.pose(t);
            assert!(
                path.at(t)
                    .transform_point3(pivot)
                    .abs_diff_eq(translation, 1e-6)
            );
        }
    }

    #[test]
    fn slerp_is_unit_and_takes_the_short_arc() {
        // 350° about y is -10°: the short way passes through -5°, not 175°.
        let path = ObjectPath::new(
            vec![
                Keyframe::new(0.0, Vec3::ZERO, Quat::IDENTITY),
                Keyframe::new(1.0, Vec3::ZERO, Quat::from_rotation_y(350f32.to_radians())),
            ],
            PathEnd::Clamp,
        )
        .unwrap();
        for i in 0..=20 {
            let (_, q) = path.pose(i as f32 / 20.0);
            assert!((q.length() - 1.0).abs() < 1e-5);
        }
        let (_, q) = path.pose(0.5);
        assert!(q.angle_between(Quat::from_rotation_y(-5f32.to_radians())) < 1e-4);
    }

    #[test]
    fn single_keyframe_holds_still() {
        let path = ObjectPath::new(
            vec![Keyframe::new(
                2.0,
                Vec3::X,
                Quat::from_rotation_x(0.3) * 3.0,
            )],
            PathEnd::Loop,
        )
        .unwrap();
        assert_eq!(path.duration(), 0.0);
        assert!((path.keyframes()[0].rotation.length() - 1.0).abs() < 1e-6);
        assert!(close(path.at(-1.0), path.at(100.0)));
        assert!(close(path.at(f32::NAN), path.at(2.0)));
        let looping = two_keys(PathEnd::Loop);
        assert!(close(looping.at(f32::INFINITY), looping.at(1.0)));
        assert!(close(looping.at(f32::NEG_INFINITY), looping.at(1.0)));
        assert_eq!(path.frames(3).len(), 3);
    }

    #[test]
    fn invalid_paths_are_errors() {
        let k = |t: f32| Keyframe::new(t, Vec3::ZERO, Quat::IDENTITY);
        let bad = [
            vec![],
            vec![k(0.0), k(0.0)],
            vec![k(1.0), k(0.5)],
            vec![k(f32::NAN)],
            vec![k(0.0), k(f32::INFINITY)],
            vec![Keyframe::new(0.0, Vec3::NAN, Quat::IDENTITY)],
            vec![Keyframe::new(
                0.0,
                Vec3::ZERO,
                Quat::from_xyzw(0.0, 0.0, 0.0, 0.0),
            )],
            vec![Keyframe::new(
                0.0,
                Vec3::ZERO,
                Quat::from_xyzw(f32::NAN, 0.0, 0.0, 1.0),
            )],
            vec![k(-f32::MAX), k(f32::MAX)],
        ];
        for keys in bad {
            assert!(
                matches!(
                    ObjectPath::new(keys.clone(), PathEnd::Clamp),
                    Err(GeometryError::InvalidPath(_))
                ),
                "{keys:?}"
            );
        }
        let path = ObjectPath::new(vec![k(0.0)], PathEnd::Clamp).unwrap();
        assert!(matches!(
            path.with_pivot(Vec3::INFINITY),
            Err(GeometryError::InvalidPath(_))
        ));
    }
}
