//! Camera paths for walkthroughs (Bastos et al. played 944 frames through
//! their house): keyframes of the camera's pose and field of view, recorded
//! in the viewer or written by hand, played back at fixed time steps.
//!
//! Between keyframes the position and the look-at target follow a cubic
//! Hermite curve whose tangents are the central differences of the
//! neighbouring keyframes over their times (Catmull–Rom for uneven times),
//! so the motion is smooth through every keyframe and passes it exactly; at
//! the ends the tangent is the one-sided difference. The up direction and
//! the field of view are interpolated linearly (the up vector renormalised).
//! Everything is plain `f32` arithmetic in a fixed order: the same file gives
//! the same cameras on every machine that rounds IEEE 754 the same way.
//!
//! The file format (JSON, `"format": "lustre-camera-path"`, version 1):
//!
//! ```json
//! {
//!   "format": "lustre-camera-path",
//!   "version": 1,
//!   "keyframes": [
//!     {"time": 0.0, "position": [0, 1, 3], "target": [0, 1, 0], "up": [0, 1, 0], "fov_y_degrees": 40},
//!     {"time": 2.5, "position": [2, 1, 2], "target": [0, 1, 0], "up": [0, 1, 0], "fov_y_degrees": 40}
//!   ]
//! }
//! ```
//!
//! Times are seconds and strictly increase; `up` may be left out (+Y).

use std::path::Path;

use glam::Vec3;
use serde_json::{Value, json};

use crate::Camera;
use crate::error::{GeometryError, Location, Result};

/// The `format` field of a camera path file.
pub const FORMAT: &str = "lustre-camera-path";
/// The version of the format this crate reads and writes.
pub const VERSION: u64 = 1;

/// One recorded pose of the camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraKeyframe {
    /// Seconds from the start of the path.
    pub time: f32,
    /// Centre of projection.
    pub position: Vec3,
    /// The point looked at.
    pub target: Vec3,
    /// The up direction.
    pub up: Vec3,
    /// Vertical field of view in degrees.
    pub fov_y_degrees: f32,
}

impl CameraKeyframe {
    /// The keyframe of a camera at `time`.
    pub fn of(camera: &Camera, time: f32) -> Self {
        Self {
            time,
            position: camera.position,
            target: camera.target,
            up: camera.up,
            fov_y_degrees: camera.fov_y_degrees,
        }
    }
}

/// A camera path: keyframes at increasing times.
#[derive(Debug, Clone, PartialEq)]
pub struct CameraPath {
    keyframes: Vec<CameraKeyframe>,
}

impl CameraPath {
    /// A path through `keyframes`; fails unless there is at least one, times strictly increase, every value is finite, no camera looks at its own position or along its up direction, and every field of view lies in (0°, 180°).
    pub fn new(keyframes: Vec<CameraKeyframe>) -> Result<Self> {
        let invalid = |i: usize, why: &str| {
            Err(GeometryError::InvalidPath(format!(
                "camera keyframe {i}: {why}"
            )))
        };
        if keyframes.is_empty() {
            return Err(GeometryError::InvalidPath(
                "a camera path needs a keyframe".into(),
            ));
        }
        for (i, k) in keyframes.iter().enumerate() {
            let finite = k.time.is_finite()
                && k.position.is_finite()
                && k.target.is_finite()
                && k.up.is_finite()
                && k.fov_y_degrees.is_finite();
            if !finite {
                return invalid(i, "a value is not finite");
            }
            let forward = k.target - k.position;
            if forward.length_squared() == 0.0 {
                return invalid(i, "the camera looks at its own position");
            }
            if forward.cross(k.up).length_squared()
                <= 1e-12 * forward.length_squared() * k.up.length_squared()
            {
                return invalid(i, "the up direction is zero or along the view direction");
            }
            if !(k.fov_y_degrees > 0.0 && k.fov_y_degrees < 180.0) {
                return invalid(i, "the field of view is not between 0 and 180 degrees");
            }
            if i > 0 && !(k.time > keyframes[i - 1].time) {
                return invalid(i, "times must strictly increase");
            }
        }
        Ok(Self { keyframes })
    }

    /// The keyframes.
    pub fn keyframes(&self) -> &[CameraKeyframe] {
        &self.keyframes
    }

    /// Seconds from the first keyframe to the last.
    pub fn duration(&self) -> f32 {
        self.keyframes[self.keyframes.len() - 1].time - self.keyframes[0].time
    }

    /// The camera at `time` (held at the ends), with aspect 1 and the default near plane.
    pub fn at(&self, time: f32) -> Camera {
        let k = &self.keyframes;
        let last = k.len() - 1;
        let i = k.partition_point(|f| f.time <= time);
        if i == 0 || last == 0 {
            return camera_of(&k[0]);
        }
        if i > last {
            return camera_of(&k[last]);
        }
        // time lies in [k[i-1].time, k[i].time).
        let (a, b) = (&k[i - 1], &k[i]);
        let span = b.time - a.time;
        let s = ((time - a.time) / span).clamp(0.0, 1.0);
        let tangent = |j: usize, pick: fn(&CameraKeyframe) -> Vec3| -> Vec3 {
            let (lo, hi) = (j.saturating_sub(1), (j + 1).min(last));
            (pick(&k[hi]) - pick(&k[lo])) / (k[hi].time - k[lo].time)
        };
        let hermite = |pick: fn(&CameraKeyframe) -> Vec3| {
            let (p0, p1) = (pick(a), pick(b));
            let (m0, m1) = (tangent(i - 1, pick) * span, tangent(i, pick) * span);
            let (s2, s3) = (s * s, s * s * s);
            (2.0 * s3 - 3.0 * s2 + 1.0) * p0
                + (s3 - 2.0 * s2 + s) * m0
                + (-2.0 * s3 + 3.0 * s2) * p1
                + (s3 - s2) * m1
        };
        let position = hermite(|f| f.position);
        let mut target = hermite(|f| f.target);
        if target == position {
            target = position + a.target - a.position;
        }
        let up = a.up.lerp(b.up, s).normalize_or(a.up);
        let fov = a.fov_y_degrees + (b.fov_y_degrees - a.fov_y_degrees) * s;
        Camera::look_at(position, target, up, fov)
    }

    /// `count` cameras at evenly spaced times from the first keyframe to the last, both included (one camera: the first keyframe).
    pub fn frames(&self, count: usize) -> Vec<Camera> {
        let start = self.keyframes[0].time;
        let step = if count > 1 {
            self.duration() / (count - 1) as f32
        } else {
            0.0
        };
        (0..count)
            .map(|i| {
                if i + 1 == count && count > 1 {
                    camera_of(&self.keyframes[self.keyframes.len() - 1])
                } else {
                    self.at(start + step * i as f32)
                }
            })
            .collect()
    }

    /// The path as the JSON of the module docs.
    pub fn to_json(&self) -> String {
        let keyframes: Vec<Value> = self
            .keyframes
            .iter()
            .map(|k| {
                json!({
                    "time": k.time,
                    "position": k.position.to_array(),
                    "target": k.target.to_array(),
                    "up": k.up.to_array(),
                    "fov_y_degrees": k.fov_y_degrees,
                })
            })
            .collect();
        let doc = json!({"format": FORMAT, "version": VERSION, "keyframes": keyframes});
        serde_json::to_string_pretty(&doc).unwrap_or_default()
    }

    /// Reads the JSON of the module docs; `file` names it in errors.
    pub fn from_json(text: &str, file: &Path) -> Result<Self> {
        let fail = |message: String| GeometryError::Parse {
            location: Location {
                file: file.to_owned(),
                line: None,
            },
            message,
        };
        let doc: Value = serde_json::from_str(text).map_err(|e| fail(format!("not JSON: {e}")))?;
        if doc["format"] != FORMAT {
            return Err(fail(format!(
                "not a camera path (`format` is not \"{FORMAT}\")"
            )));
        }
        if doc["version"].as_u64() != Some(VERSION) {
            return Err(fail(format!(
                "camera path version {} is not {VERSION}",
                doc["version"]
            )));
        }
        let keyframes = doc["keyframes"]
            .as_array()
            .ok_or_else(|| fail("no `keyframes` array".into()))?
            .iter()
            .enumerate()
            .map(|(i, k)| {
                let number = |key: &str| -> Result<f32> {
                    k[key]
                        .as_f64()
                        .map(|v| v as f32)
                        .ok_or_else(|| fail(format!("keyframe {i}: `{key}` is not a number")))
                };
                let vector = |key: &str, default: Option<Vec3>| -> Result<Vec3> {
                    match (k.get(key), default) {
                        (None, Some(d)) => Ok(d),
                        (v, _) => v
                            .and_then(Value::as_array)
                            .filter(|a| a.len() == 3)
                            .and_then(|a| {
                                let c: Option<Vec<f32>> =
                                    a.iter().map(|v| v.as_f64().map(|v| v as f32)).collect();
                                c.map(|c| Vec3::new(c[0], c[1], c[2]))
                            })
                            .ok_or_else(|| {
                                fail(format!("keyframe {i}: `{key}` is not three numbers"))
                            }),
                    }
                };
                Ok(CameraKeyframe {
                    time: number("time")?,
                    position: vector("position", None)?,
                    target: vector("target", None)?,
                    up: vector("up", Some(Vec3::Y))?,
                    fov_y_degrees: number("fov_y_degrees")?,
                })
            })
            .collect::<Result<Vec<_>>>()?;
        Self::new(keyframes).map_err(|e| fail(e.to_string()))
    }

    /// Reads a camera path file.
    pub fn load(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(|source| GeometryError::Io {
            path: path.to_owned(),
            source,
        })?;
        Self::from_json(&text, path)
    }

    /// Writes the path to `path` (through a temporary file, renamed).
    pub fn save(&self, path: &Path) -> Result<()> {
        crate::mitsuba::write_atomically(path, self.to_json().as_bytes())
    }
}

/// The camera of a keyframe.
fn camera_of(k: &CameraKeyframe) -> Camera {
    Camera::look_at(k.position, k.target, k.up, k.fov_y_degrees)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(time: f32, position: Vec3) -> CameraKeyframe {
        CameraKeyframe {
            time,
            position,
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov_y_degrees: 40.0,
        }
    }

    #[test]
    fn keyframes_are_passed_exactly_and_held_at_the_ends() {
        let keys = vec![
            key(0.0, Vec3::new(0.0, 1.0, 5.0)),
            key(1.0, Vec3::new(3.0, 1.0, 4.0)),
            key(3.0, Vec3::new(5.0, 2.0, 0.0)),
        ];
        let path = CameraPath::new(keys.clone()).unwrap();
        for k in &keys {
            assert_eq!(path.at(k.time).position, k.position);
        }
        assert_eq!(path.at(-1.0).position, keys[0].position);
        assert_eq!(path.at(9.0).position, keys[2].position);
        assert_eq!(path.duration(), 3.0);
        let frames = path.frames(7);
        assert_eq!(frames.len(), 7);
        assert_eq!(frames[0].position, keys[0].position);
        assert_eq!(frames[6].position, keys[2].position);
        assert_eq!(path.frames(1)[0].position, keys[0].position);
    }

    #[test]
    fn uniform_motion_stays_uniform_and_the_curve_is_smooth() {
        // Evenly timed keyframes on a line at constant speed: the curve is that motion.
        let v = Vec3::new(1.0, 0.5, -2.0);
        let keys: Vec<_> = (0..5)
            .map(|i| key(i as f32 * 0.5, Vec3::ONE + v * (i as f32 * 0.5)))
            .collect();
        let path = CameraPath::new(keys).unwrap();
        for i in 0..=40 {
            let t = i as f32 * 0.05;
            let p = path.at(t).position;
            assert!((p - (Vec3::ONE + v * t)).length() < 1e-5, "{t}: {p}");
        }
        // Smooth through an uneven keyframe: the velocity just before equals the velocity just after.
        let bent = CameraPath::new(vec![
            key(0.0, Vec3::new(0.0, 0.0, 5.0)),
            key(1.0, Vec3::new(4.0, 0.0, 4.0)),
            key(4.0, Vec3::new(6.0, 3.0, 0.0)),
        ])
        .unwrap();
        let h = 1e-3;
        let before = (bent.at(1.0).position - bent.at(1.0 - h).position) / h;
        let after = (bent.at(1.0 + h).position - bent.at(1.0).position) / h;
        assert!(
            (before - after).length() < 0.02 * before.length(),
            "{before} {after}"
        );
    }

    #[test]
    fn files_round_trip_and_bad_ones_are_refused() {
        let path = CameraPath::new(vec![
            CameraKeyframe {
                up: Vec3::new(0.1, 1.0, 0.0),
                fov_y_degrees: 55.5,
                ..key(0.25, Vec3::new(1.5, 2.0, -3.25))
            },
            key(2.0, Vec3::new(0.0, 1.0, 7.0)),
        ])
        .unwrap();
        let file = Path::new("walk.json");
        assert_eq!(CameraPath::from_json(&path.to_json(), file).unwrap(), path);
        // `up` defaults to +Y.
        let text = r#"{"format": "lustre-camera-path", "version": 1, "keyframes": [
            {"time": 0, "position": [0, 1, 3], "target": [0, 1, 0], "fov_y_degrees": 40}]}"#;
        assert_eq!(
            CameraPath::from_json(text, file).unwrap().keyframes()[0].up,
            Vec3::Y
        );
        for (bad, expected) in [
            ("[", "not JSON"),
            (
                r#"{"format": "other", "version": 1, "keyframes": []}"#,
                "not a camera path",
            ),
            (
                r#"{"format": "lustre-camera-path", "version": 2, "keyframes": []}"#,
                "version 2",
            ),
            (
                r#"{"format": "lustre-camera-path", "version": 1, "keyframes": []}"#,
                "needs a keyframe",
            ),
            (
                r#"{"format": "lustre-camera-path", "version": 1, "keyframes": [{"time": 0, "position": [0, 1], "target": [0, 0, 0], "fov_y_degrees": 40}]}"#,
                "`position` is not three numbers",
            ),
            (
                r#"{"format": "lustre-camera-path", "version": 1, "keyframes": [
                    {"time": 1, "position": [0, 1, 3], "target": [0, 0, 0], "fov_y_degrees": 40},
                    {"time": 1, "position": [0, 1, 4], "target": [0, 0, 0], "fov_y_degrees": 40}]}"#,
                "strictly increase",
            ),
            (
                r#"{"format": "lustre-camera-path", "version": 1, "keyframes": [{"time": 0, "position": [0, 0, 0], "target": [0, 0, 0], "fov_y_degrees": 40}]}"#,
                "own position",
            ),
            (
                r#"{"format": "lustre-camera-path", "version": 1, "keyframes": [{"time": 0, "position": [0, 1, 0], "target": [0, 0, 0], "fov_y_degrees": 40}]}"#,
                "along the view direction",
            ),
            (
                r#"{"format": "lustre-camera-path", "version": 1, "keyframes": [{"time": 0, "position": [0, 1, 3], "target": [0, 0, 0], "fov_y_degrees": 180}]}"#,
                "field of view",
            ),
        ] {
            let error = CameraPath::from_json(bad, file).unwrap_err().to_string();
            assert!(
                error.contains("walk.json") && error.contains(expected),
                "{bad}: {error}"
            );
        }
    }
}
