//! Conservative envelopes of discs and ray segments (sections 2.6–2.8): regions that hold every point where [`Disc::is_crossed_by`] can accept a crossing in spite of its `f32` rounding, so that every acceleration structure prunes only pairs that cannot cross.
//!
//! When `is_crossed_by` accepts a pair, its computed point `p = o + t d`
//! lies within `r` of the centre; the exact ray point `q` at the same
//! (computed) `t` differs from `p` by a few ulps of `|o| + |t d|`, and lies
//! within a few ulps of `|c − o| + |t d|` of the disc's plane — the product
//! `t (d·n)` reproduces the rounded numerator almost exactly even for a
//! grazing ray. Every such error is below `4.4e-6 (|c|∞ + |o|∞ + r)`; the
//! envelopes pad by [`REL`]` = 8e-5` of those magnitudes, split into a disc
//! part (`REL (|c|∞ + r)`, in the disc's box) and a segment part
//! (`REL |o|∞`, added around the segment), so every test below is done in
//! `f64` with margins thousands of times its own rounding.

use glam::DVec3;

use crate::detp::Disc;
use crate::ray_set::RaySegment;

/// Relative pad of every envelope (see the module documentation): about 1 300 times the `f32` unit roundoff, 18 times the worst error bound.
pub(crate) const REL: f64 = 8e-5;
/// Absolute floor of the disc pad, above `f32` underflow of `|p − c|²`.
pub(crate) const ABS: f64 = 1e-20;
/// Relative pad on the magnitude of a clipping box, above the `f64` rounding of the structures' own arithmetic.
pub(crate) const REL_F64: f64 = 1e-9;
/// Smallest `cos` between a ray and a disc normal for which a plane-based pre-test may reject (section 2.8): below it the rounded crossing parameter of `is_crossed_by` is too ill-conditioned.
pub(crate) const MIN_PRETEST_COS: f64 = 0.25;

/// An axis-aligned box in `f64`; empty when `min > max` on an axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Box3 {
    /// Smallest corner.
    pub min: DVec3,
    /// Largest corner.
    pub max: DVec3,
}

impl Box3 {
    /// The empty box.
    pub const EMPTY: Self = Self {
        min: DVec3::INFINITY,
        max: DVec3::NEG_INFINITY,
    };

    /// The smallest box holding both.
    pub fn union(self, other: Self) -> Self {
        Self {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    /// Whether the box holds no point.
    pub fn is_empty(&self) -> bool {
        self.min.cmpgt(self.max).any()
    }

    /// The box grown by `pad` on every side.
    pub fn padded(self, pad: f64) -> Self {
        Self {
            min: self.min - DVec3::splat(pad),
            max: self.max + DVec3::splat(pad),
        }
    }

    /// Whether `other` lies inside this box (closed).
    pub fn contains_box(&self, other: &Self) -> bool {
        other.min.cmpge(self.min).all() && other.max.cmple(self.max).all()
    }

    /// Centre of a non-empty box.
    pub fn centre(&self) -> DVec3 {
        0.5 * (self.min + self.max)
    }

    /// Largest absolute coordinate of the box (zero when empty).
    pub fn max_abs(&self) -> f64 {
        if self.is_empty() {
            0.0
        } else {
            self.min.abs().max(self.max.abs()).max_element()
        }
    }
}

/// The conservative region of one disc: every point where `is_crossed_by` may accept lies within `reach` (+ the segment's pad) of `centre` and within `pad` (+ the segment's pad) of its plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct DiscEnvelope {
    /// Centre `c`.
    pub centre: DVec3,
    /// Unit normal of the plane.
    pub normal: DVec3,
    /// Lateral reach `r (1 + 1e-6) + pad`.
    pub reach: f64,
    /// The disc's pad `REL (|c|∞ + r) + ABS`, also the plane thickness.
    pub pad: f64,
    /// Box of the region `{|x − c| ≤ reach, |(x − c)·n| ≤ pad}`.
    pub bounds: Box3,
}

/// The envelope of a disc, or `None` for a disc no segment can cross (a zero normal). The disc must have passed [`check_disc`].
pub(crate) fn disc_envelope(disc: &Disc) -> Option<DiscEnvelope> {
    let n = disc.normal.as_dvec3();
    let len = n.length();
    if !(len > 0.0) {
        return None;
    }
    let normal = n / len;
    let centre = disc.centre.as_dvec3();
    let r = disc.radius as f64;
    let pad = REL * (centre.abs().max_element() + r) + ABS;
    let reach = r * (1.0 + 1e-6) + pad;
    let half = DVec3::new(
        reach * (1.0 - normal.x * normal.x).max(0.0).sqrt() + pad * normal.x.abs(),
        reach * (1.0 - normal.y * normal.y).max(0.0).sqrt() + pad * normal.y.abs(),
        reach * (1.0 - normal.z * normal.z).max(0.0).sqrt() + pad * normal.z.abs(),
    )
    .min(DVec3::splat(reach));
    Some(DiscEnvelope {
        centre,
        normal,
        reach,
        pad,
        bounds: Box3 {
            min: centre - half,
            max: centre + half,
        },
    })
}

/// Why a disc is rejected, or `None` when the envelopes' reasoning holds for it: finite centre, finite non-negative radius, a normal that is zero or of unit length (within 1e-3).
pub(crate) fn check_disc(disc: &Disc) -> Option<String> {
    if !disc.centre.is_finite() {
        return Some(format!("centre {} is not finite", disc.centre));
    }
    if !(disc.radius >= 0.0 && disc.radius.is_finite()) {
        return Some(format!(
            "radius {} is not a finite non-negative number",
            disc.radius
        ));
    }
    if !disc.normal.is_finite() {
        return Some(format!("normal {} is not finite", disc.normal));
    }
    let len2 = disc.normal.as_dvec3().length_squared();
    if len2 != 0.0 && (len2 - 1.0).abs() > 1e-3 {
        return Some(format!(
            "normal {} is neither zero nor of unit length",
            disc.normal
        ));
    }
    None
}

/// The conservative extent of one ray segment: the points `o + t d`, `t ∈ [t_lo, t_hi]`, padded by `pad`, hold every crossing point it can have with a disc inside the clipping box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct SegmentEnvelope {
    /// Origin `o`.
    pub origin: DVec3,
    /// Direction `d` (not necessarily unit).
    pub direction: DVec3,
    /// `1 / d` per axis (infinite on a zero axis).
    pub inv_direction: DVec3,
    /// `1 / |d|²`.
    pub inv_len2: f64,
    /// `|d|`.
    pub len: f64,
    /// Plücker moment `o × d` (section 2.8).
    pub moment: DVec3,
    /// Start of the useful parameter range (after clipping).
    pub t_lo: f64,
    /// End of the useful parameter range: the largest reach plus slack, clipped.
    pub t_hi: f64,
    /// The segment's pad, `REL |o|∞` plus the clipping box's `f64` pad.
    pub pad: f64,
    /// `|o|∞`: a plane-based pre-test applies only to segments starting inside the disc set's magnitude.
    pub origin_norm: f64,
    /// Whether clipping removed part of `[0, reach + slack]` (the segment leaves the clipping box).
    pub clipped: bool,
}

/// The parameter interval in which the line `o + t d` lies in the box `[lo, hi]`, intersected with `[t0, t1]`, or `None` when empty.
pub(crate) fn slab(
    origin: DVec3,
    direction: DVec3,
    inv_direction: DVec3,
    lo: DVec3,
    hi: DVec3,
    mut t0: f64,
    mut t1: f64,
) -> Option<(f64, f64)> {
    for axis in 0..3 {
        let (o, d) = (origin[axis], direction[axis]);
        if d == 0.0 {
            if !(o >= lo[axis] && o <= hi[axis]) {
                return None;
            }
        } else {
            let inv = inv_direction[axis];
            let a = (lo[axis] - o) * inv;
            let b = (hi[axis] - o) * inv;
            t0 = t0.max(a.min(b));
            t1 = t1.min(a.max(b));
        }
    }
    (t0 <= t1).then_some((t0, t1))
}

/// The largest parameter at which `is_crossed_by` may accept a crossing of the segment with any disc (its largest reach plus `slack`, rounded as `is_crossed_by` rounds it), or `None` when it can cross no disc at all: a non-finite origin or direction, a zero direction, a NaN or negative reach.
pub(crate) fn segment_limit(segment: &RaySegment, slack: f32) -> Option<f32> {
    if !(segment.origin.is_finite() && segment.direction.is_finite()) {
        return None;
    }
    if !(segment.direction.as_dvec3().length_squared() > 0.0) {
        return None;
    }
    let mut reach = segment.length();
    if let Some(hit) = segment.hit {
        reach = reach.max(hit.distance + segment.extension);
    }
    let limit = reach + slack;
    (limit >= 0.0).then_some(limit)
}

/// The envelope of a segment within a clipping box (that holds the boxes of every disc it will meet), or `None` when it cannot cross any disc inside: a non-finite origin or direction, a zero direction, a reach that is NaN or negative, or no part within the box.
pub(crate) fn segment_envelope(
    segment: &RaySegment,
    slack: f32,
    clip: &Box3,
) -> Option<SegmentEnvelope> {
    if clip.is_empty() {
        return None;
    }
    let limit = segment_limit(segment, slack)?;
    let t_max = limit as f64 * (1.0 + 1e-9);
    let origin = segment.origin.as_dvec3();
    let direction = segment.direction.as_dvec3();
    let len2 = direction.length_squared();
    let origin_norm = origin.abs().max_element();
    let pad = REL * origin_norm + REL_F64 * (clip.max_abs() + origin_norm);
    let inv_direction = DVec3::ONE / direction;
    let clip = clip.padded(pad);
    let (t_lo, t_hi) = slab(
        origin,
        direction,
        inv_direction,
        clip.min,
        clip.max,
        0.0,
        t_max,
    )?;
    Some(SegmentEnvelope {
        origin,
        direction,
        inv_direction,
        inv_len2: 1.0 / len2,
        len: len2.sqrt(),
        moment: origin.cross(direction),
        t_lo,
        t_hi,
        pad,
        origin_norm,
        clipped: t_lo > 0.0 || t_hi < t_max,
    })
}

impl SegmentEnvelope {
    /// Whether the padded segment comes within `radius` of `centre` (the ray cache's sphere test, section 2.6).
    pub fn meets_sphere(&self, centre: DVec3, radius: f64) -> bool {
        let w = centre - self.origin;
        let t = (w.dot(self.direction) * self.inv_len2).clamp(self.t_lo, self.t_hi);
        let v = w - t * self.direction;
        let r = radius + self.pad;
        v.length_squared() <= r * r
    }

    /// Whether the padded segment meets a box (the disc index's node test, section 2.7).
    pub fn meets_box(&self, b: &Box3) -> bool {
        let lo = b.min - DVec3::splat(self.pad);
        let hi = b.max + DVec3::splat(self.pad);
        slab(
            self.origin,
            self.direction,
            self.inv_direction,
            lo,
            hi,
            self.t_lo,
            self.t_hi,
        )
        .is_some()
    }
}
