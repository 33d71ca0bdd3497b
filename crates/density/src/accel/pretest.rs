//! Pre-intersection tests of section 2.8: an equilateral triangle tangent to each disc (the disc inscribed, side `2√3 r`, in the disc's plane), tested before the ray–disc test with Badouel's projection method, Plücker coordinates or Möller–Trumbore.
//!
//! The tests only *reject*: a segment that misses the triangle cannot cross
//! the disc, anything else goes on to [`Disc::is_crossed_by`](crate::Disc::is_crossed_by).
//! To stay conservative under rounding, the triangle's inscribed radius is
//! the disc's envelope reach plus twice the largest segment pad (see
//! the `envelope` module), and the tests are done in `f64`; a
//! segment starting farther out than the disc set's magnitude, or meeting
//! the plane at a grazing angle (`cos < 1/4`, where the rounded crossing
//! point of `is_crossed_by` is ill-conditioned), is never rejected.

use glam::{DVec2, DVec3};

use super::envelope::{DiscEnvelope, MIN_PRETEST_COS, REL, SegmentEnvelope};

/// Which pre-intersection test runs before the ray–disc test (section 2.8, table 2.5).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub enum PreTest {
    /// No pre-test: every candidate goes to the ray–disc test.
    #[default]
    None,
    /// Badouel's ray–triangle test (section 2.8, ref. 3): plane intersection, projection on the dominant plane, 2D barycentric coordinates.
    Badouel,
    /// Plücker coordinates (section 2.8, ref. 16): the sides of the ray against the stored Plücker coordinates of the triangle's edges.
    Plucker,
    /// The Möller–Trumbore ray–triangle test (section 2.8, ref. 10).
    MollerTrumbore,
}

impl PreTest {
    /// Every pre-test, `None` first (section 2.8, table 2.5).
    pub const ALL: [PreTest; 4] = [
        PreTest::None,
        PreTest::Badouel,
        PreTest::Plucker,
        PreTest::MollerTrumbore,
    ];
}

/// What one disc's triangle stores for the chosen test.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Triangle {
    /// Badouel: centre, dominant-plane axes, first vertex and edges in 2D (relative to the centre), `1 / (e1 × e2)`.
    Badouel {
        centre: DVec3,
        axes: (usize, usize),
        v0: DVec2,
        e1: DVec2,
        e2: DVec2,
        inv_det: f64,
    },
    /// Plücker: each edge's direction and moment `V_k × V_{k+1}`.
    Plucker { edges: [(DVec3, DVec3); 3] },
    /// Möller–Trumbore: first vertex and the two edges from it.
    MollerTrumbore { v0: DVec3, e1: DVec3, e2: DVec3 },
}

/// The triangles of a disc set for one pre-test (section 2.8), built once with the set.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct PreTests {
    /// The chosen test.
    kind: PreTest,
    /// Segments whose `|o|∞` exceeds this are never rejected.
    near_limit: f64,
    /// Per disc: its unit normal and triangle, or `None` (no test, or a disc nothing crosses).
    entries: Vec<Option<(DVec3, Triangle)>>,
}

/// An orthonormal pair spanning the plane of unit normal `n` (Duff et al. 2017).
fn basis(n: DVec3) -> (DVec3, DVec3) {
    let sign = 1.0f64.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        DVec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// The three vertices of the equilateral triangle circumscribing the circle of radius `inradius` about `centre` in the plane of `normal` (circumradius `2 inradius`, side `2√3 inradius`).
pub(crate) fn tangent_triangle(centre: DVec3, normal: DVec3, inradius: f64) -> [DVec3; 3] {
    let (u, v) = basis(normal);
    let k = std::f64::consts::TAU / 3.0;
    [0.0, 1.0, 2.0].map(|i| {
        let theta = std::f64::consts::FRAC_PI_2 + i * k;
        centre + 2.0 * inradius * (theta.cos() * u + theta.sin() * v)
    })
}

impl PreTests {
    /// The triangles of every disc (section 2.8); `near_limit` is the disc set's largest absolute coordinate.
    pub fn new(kind: PreTest, envelopes: &[Option<DiscEnvelope>], near_limit: f64) -> Self {
        let entries = if kind == PreTest::None {
            Vec::new()
        } else {
            envelopes
                .iter()
                .map(|e| e.map(|e| (e.normal, Self::triangle(kind, &e, near_limit))))
                .collect()
        };
        Self {
            kind,
            near_limit,
            entries,
        }
    }

    /// The chosen test.
    pub fn kind(&self) -> PreTest {
        self.kind
    }

    /// The inscribed radius of a disc's triangle: its envelope reach, its plane pad and twice the largest segment pad, enlarged by `1e-6`.
    fn inradius(e: &DiscEnvelope, near_limit: f64) -> f64 {
        (e.reach + e.pad + 2.0 * REL * near_limit) * (1.0 + 1e-6)
    }

    /// One disc's triangle data.
    fn triangle(kind: PreTest, e: &DiscEnvelope, near_limit: f64) -> Triangle {
        let v = tangent_triangle(e.centre, e.normal, Self::inradius(e, near_limit));
        match kind {
            PreTest::Badouel | PreTest::None => {
                let n = e.normal.abs();
                let axes = if n.x >= n.y && n.x >= n.z {
                    (1, 2)
                } else if n.y >= n.z {
                    (2, 0)
                } else {
                    (0, 1)
                };
                let project = |p: DVec3| {
                    let p = p - e.centre;
                    DVec2::new(p[axes.0], p[axes.1])
                };
                let v0 = project(v[0]);
                let e1 = project(v[1]) - v0;
                let e2 = project(v[2]) - v0;
                Triangle::Badouel {
                    centre: e.centre,
                    axes,
                    v0,
                    e1,
                    e2,
                    inv_det: 1.0 / e1.perp_dot(e2),
                }
            }
            PreTest::Plucker => Triangle::Plucker {
                edges: [0, 1, 2].map(|k| {
                    let (a, b) = (v[k], v[(k + 1) % 3]);
                    (b - a, a.cross(b))
                }),
            },
            PreTest::MollerTrumbore => Triangle::MollerTrumbore {
                v0: v[0],
                e1: v[1] - v[0],
                e2: v[2] - v[0],
            },
        }
    }

    /// Whether the chosen test proves that the segment misses disc `disc` (section 2.8); `false` means "run the ray–disc test".
    #[inline]
    pub fn rejects(&self, disc: usize, s: &SegmentEnvelope) -> bool {
        let Some(Some((normal, triangle))) = self.entries.get(disc) else {
            return false;
        };
        if s.origin_norm > self.near_limit {
            return false;
        }
        let dn = s.direction.dot(*normal);
        if !(dn <= -MIN_PRETEST_COS * s.len) {
            return false;
        }
        match *triangle {
            Triangle::Badouel {
                centre,
                axes,
                v0,
                e1,
                e2,
                inv_det,
            } => {
                let oc = s.origin - centre;
                let t = -oc.dot(*normal) / dn;
                let p = oc + t * s.direction;
                let q = DVec2::new(p[axes.0], p[axes.1]) - v0;
                let a = q.perp_dot(e2) * inv_det;
                let b = e1.perp_dot(q) * inv_det;
                !(a >= 0.0 && b >= 0.0 && a + b <= 1.0)
            }
            Triangle::Plucker { edges } => {
                let side = |(e, m): (DVec3, DVec3)| s.direction.dot(m) + e.dot(s.moment);
                let (a, b, c) = (side(edges[0]), side(edges[1]), side(edges[2]));
                let all_pos = a >= 0.0 && b >= 0.0 && c >= 0.0;
                let all_neg = a <= 0.0 && b <= 0.0 && c <= 0.0;
                !(all_pos || all_neg)
            }
            Triangle::MollerTrumbore { v0, e1, e2 } => {
                let p = s.direction.cross(e2);
                let inv_det = 1.0 / e1.dot(p);
                let t = s.origin - v0;
                let u = t.dot(p) * inv_det;
                if !(0.0..=1.0).contains(&u) {
                    return true;
                }
                let q = t.cross(e1);
                let v = s.direction.dot(q) * inv_det;
                !(v >= 0.0 && u + v <= 1.0)
            }
        }
    }

    /// Checks the stored triangles: each one's inscribed circle holds its disc's envelope reach, each lies in its disc's plane.
    pub fn validate(&self, envelopes: &[Option<DiscEnvelope>]) -> Result<(), String> {
        if self.kind == PreTest::None {
            return if self.entries.is_empty() {
                Ok(())
            } else {
                Err("entries without a pre-test".into())
            };
        }
        if self.entries.len() != envelopes.len() {
            return Err(format!(
                "{} triangles for {} discs",
                self.entries.len(),
                envelopes.len()
            ));
        }
        for (i, (entry, env)) in self.entries.iter().zip(envelopes).enumerate() {
            match (entry, env) {
                (None, None) => {}
                (Some((normal, _)), Some(env)) => {
                    if *normal != env.normal {
                        return Err(format!("disc {i}: triangle normal differs from the disc's"));
                    }
                    let inradius = Self::inradius(env, self.near_limit);
                    let v = tangent_triangle(env.centre, env.normal, inradius);
                    for (k, p) in v.iter().enumerate() {
                        let a = *p;
                        let b = v[(k + 1) % 3];
                        // Distance from the centre to the edge line.
                        let e = (b - a).normalize();
                        let w = env.centre - a;
                        let dist = (w - w.dot(e) * e).length();
                        if !(dist >= env.reach + env.pad) {
                            return Err(format!(
                                "disc {i}: edge {k} at {dist} from the centre, inside the reach {}",
                                env.reach + env.pad
                            ));
                        }
                        let off = (a - env.centre).dot(env.normal).abs();
                        if !(off <= 1e-9 * inradius + 1e-14 * env.centre.abs().max_element()) {
                            return Err(format!("disc {i}: vertex {k} is {off} off the plane"));
                        }
                    }
                }
                _ => {
                    return Err(format!(
                        "disc {i}: triangle presence differs from its envelope"
                    ));
                }
            }
        }
        Ok(())
    }
}
