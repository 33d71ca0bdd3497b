//! Glossy surfaces (section 2.10): each glossy vertex keeps the rays crossing its DETP disc, updated every frame with the Old and New Rays, and turns them into the view-dependent radiance of equation 2.1 when the camera moves.
//!
//! The DETP discretisation of equation 2.1 is
//! `L(x, ωo) = Σ_j f_r(x, ω_j, ωo) φ_j / A`, the sum over the rays `j`
//! crossing the disc (incoming direction `ω_j`, power `φ_j`) and `A = π r²`,
//! or the disc's reachable area under artifact control (section 1.2.1,
//! [`crate::artifact`]). The cosine of equation 2.1 is already in the flux
//! crossing the disc. A diffuse `f_r = ρ/π` gives back `ρ/π E` (equation 2.2).
//!
//! Beyond the paper, which uses one disc for both, the glossy disc may be
//! larger than the diffuse one: only the rays inside a narrow lobe count
//! towards `f_r`'s non-diffuse part, so its estimate on the diffuse disc is
//! speckled. [`GlossyVertices::lobe_radiance`] gives
//! `Σ_j (f_r − ρ/π) φ_j / A` on the glossy disc, with `ρ` the Lambertian
//! reflectance of the material's diffuse part
//! ([`lustre_geometry::MaterialModel::diffuse_reflectance`]), and
//! [`crate::QuasiStatic::glossy_radiance`] adds `ρ/π E` from the diffuse discs.
//! A diffuse map changes only the diffuse part (`ρ` becomes `ρ ⊙ t(uv)`, see
//! [`lustre_geometry::Material::diffuse_reflectance_at`]), so the lobe is the untextured one.
//! The rays crossing each disc are found with disc indexing (section 2.7,
//! [`DiscSet::crossings`]), exactly those [`Disc::is_crossed_by`] accepts.
//!
//! The rays of a vertex are kept in one of three stores ([`GlossyMode`]): a
//! plain list, the QuadTree of section 2.10.1 without summarising (exact,
//! faster estimates), or with summarising (the variant the paper proposes
//! but did not implement; approximate, see [`crate::quadtree`]).
//!
//! Beyond the paper, a frame's Old and New Rays may be deferred on a vertex
//! whose tangent plane faces away from the eye
//! ([`GlossyVertices::update_towards`]): its radiance towards that eye is
//! zero whatever its rays (every BRDF is zero for `ωo` below the plane), so
//! the frames' insertions and removals wait until an eye in front of it asks
//! ([`GlossyVertices::catch_up`]). They are kept as their net change: a ray
//! removed and inserted again, or inserted by one frame and removed by a
//! later one (a shadow that passes), cancels out and never reaches the store.
//! The exact stores depend on the multiset of their rays alone, so applying
//! the net change gives the store that applying every frame at once gives,
//! bit for bit (for consistent updates, whose Old Rays are all held). Exact
//! stores only (a list or a QuadTree without summarising). A vertex defers at
//! most a quarter as many rays as it holds, plus 64 ([`MAX_DEFERRED_SHARE`]):
//! the lists' memory grows by less than a tenth at worst (at most 28 bytes a
//! deferred ray, each distinct one kept once with its net multiplicity,
//! against about [`BYTES_PER_STORED_RAY`] a stored one), and beyond it the
//! net change is applied.
//!
//! Beyond the paper, an Old Ray and a New Ray of one frame with the same
//! origin, direction and power ([`crate::Twins`]: a re-traced path's
//! first changed segment keeps them and only ends elsewhere) are the same
//! incident ray at every disc both cross, so there they cancel before the
//! store sees them ([`DiscSet::net_crossings`], which also traverses such a
//! pair once, beyond the nearer of its ends only): an exact store gets the
//! same multiset, bit for bit, with about a quarter fewer insertions and
//! removals on a dense glossy model, and a vertex whose rays all cancel
//! keeps its radiance. Summarised stores get every ray, as the formula of
//! section 2.10.1 asks.

use std::cmp::Ordering;

use glam::{DVec3, Vec3};
use lustre_brdf::{BoxedBrdf, Brdf};
use lustre_geometry::sampling::Frame;
use lustre_geometry::{MaterialId, MeshId, Rgb, Scene};
use rayon::prelude::*;

use crate::accel::{Acceleration, DiscSet, DiscSetOptions, PreTest, mean_edge};
use crate::detp::Disc;
use crate::error::{DensityError, Result};
use crate::quadtree::{QuadTree, QuadTreeOptions, SummaryTree};
use crate::ray_set::{RaySegment, RaySet};
use crate::update::Twins;

/// One ray of a glossy vertex's list (section 2.10, "the actual set of rays which affected the point"): its incoming direction in the vertex's shading frame and its power.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IncidentRay {
    /// Unit direction towards where the ray came from, in the local frame of the vertex (+Z the disc normal): the `ω` of equation 2.1.
    pub wi: Vec3,
    /// Power `φ` (W, RGB) the ray carries.
    pub power: Rgb,
}

/// The bit pattern that identifies an [`IncidentRay`]: rays are matched by exact equality of direction and power (section 2.3: an Old Ray is a copy of the ray it replaces).
pub type RayKey = [u32; 6];

impl IncidentRay {
    /// The incident ray of a segment crossing a disc whose shading frame is `frame` (section 2.10): `ω = −direction` in that frame.
    pub fn from_segment(frame: &Frame, segment: &RaySegment) -> Self {
        Self {
            wi: frame.to_local(-segment.direction),
            power: segment.power,
        }
    }

    /// The exact bit pattern of direction and power, the identity used to remove Old Rays (section 2.10).
    pub fn key(&self) -> RayKey {
        [
            self.wi.x.to_bits(),
            self.wi.y.to_bits(),
            self.wi.z.to_bits(),
            self.power.x.to_bits(),
            self.power.y.to_bits(),
            self.power.z.to_bits(),
        ]
    }

    /// One term of equation 2.1 before the division by the disc area: `f_r(ω, ωo) φ` (W/sr).
    pub fn term(&self, brdf: &dyn Brdf, wo: Vec3) -> Rgb {
        brdf.eval(self.wi, wo) * self.power
    }
}

/// Orders incident rays by their key (a total order on the bit patterns).
pub(crate) fn key_order(a: &IncidentRay, b: &IncidentRay) -> Ordering {
    a.key().cmp(&b.key())
}

/// The Old and New Rays between two ray lists as multisets (section 2.4.2, equations 2.5 and 2.6): `O = S^{t−1} − S^t` first, then `N = S^t − S^{t−1}`.
pub fn ray_difference(
    previous: &[IncidentRay],
    current: &[IncidentRay],
) -> (Vec<IncidentRay>, Vec<IncidentRay>) {
    let mut a = previous.to_vec();
    let mut b = current.to_vec();
    a.sort_by(key_order);
    b.sort_by(key_order);
    sorted_difference(&a, &b)
}

/// Two key-sorted multisets less their common part, `(a − b, b − a)`, each still sorted: every ray of `a` cancels one equal ray of `b`.
fn sorted_difference(a: &[IncidentRay], b: &[IncidentRay]) -> (Vec<IncidentRay>, Vec<IncidentRay>) {
    let (mut left, mut right) = (Vec::with_capacity(a.len()), Vec::with_capacity(b.len()));
    let (mut i, mut j) = (0, 0);
    while i < a.len() && j < b.len() {
        match key_order(&a[i], &b[j]) {
            Ordering::Less => {
                left.push(a[i]);
                i += 1;
            }
            Ordering::Greater => {
                right.push(b[j]);
                j += 1;
            }
            Ordering::Equal => {
                i += 1;
                j += 1;
            }
        }
    }
    left.extend_from_slice(&a[i..]);
    right.extend_from_slice(&b[j..]);
    (left, right)
}

/// A radiance estimate with its error bound (section 2.10.1): `value` and `bound` are both either sums `Σ f_r φ` (W/sr, the QuadTree's) or radiances (W/(m² sr), a vertex's, divided by the disc area).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Estimate {
    /// The estimate.
    pub value: Rgb,
    /// Per channel, a bound on `|value − exact per-ray sum|`: zero for an exact estimate, the QuadTree's bound (under the sampling assumption stated in [`crate::quadtree`]), or infinite for summaries, whose bound [`SummaryTree::error_bound`] computes on request.
    pub bound: Rgb,
    /// BRDF evaluations spent, the cost the QuadTree reduces.
    pub evaluations: usize,
}

/// The plain per-vertex ray list of section 2.10, kept sorted by [`IncidentRay::key`] so that equal multisets give bit-identical estimates.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RayList {
    rays: Vec<IncidentRay>,
}

impl RayList {
    /// An empty list.
    pub fn new() -> Self {
        Self::default()
    }

    /// A list holding the given rays (section 2.10, first frame).
    pub fn from_rays(rays: &[IncidentRay]) -> Self {
        let mut rays = rays.to_vec();
        rays.sort_by(key_order);
        Self { rays }
    }

    /// Adds a New Ray (section 2.10, "the ray list must be updated").
    pub fn insert(&mut self, ray: IncidentRay) {
        let key = ray.key();
        let at = self.rays.partition_point(|r| r.key() <= key);
        self.rays.insert(at, ray);
    }

    /// Removes one copy of an Old Ray (section 2.10); `false` when no ray of that key is in the list.
    pub fn remove(&mut self, ray: &IncidentRay) -> bool {
        let key = ray.key();
        match self.rays.binary_search_by(|r| r.key().cmp(&key)) {
            Ok(i) => {
                self.rays.remove(i);
                true
            }
            Err(_) => false,
        }
    }

    /// The rays, sorted by key.
    pub fn rays(&self) -> &[IncidentRay] {
        &self.rays
    }

    /// Number of rays.
    pub fn len(&self) -> usize {
        self.rays.len()
    }

    /// Whether the list is empty.
    pub fn is_empty(&self) -> bool {
        self.rays.is_empty()
    }

    /// Total power `Σ φ_j` (section 1.2: `E = Σ φ / A`).
    pub fn power(&self) -> Rgb {
        self.rays
            .iter()
            .map(|r| r.power.as_dvec3())
            .sum::<DVec3>()
            .as_vec3()
    }

    /// `Σ_j f_r(ω_j, ωo) φ_j` over every ray (equation 2.1 discretised, before the division by the disc area), `wo` in the local frame; exact, so the bound is zero.
    pub fn estimate(&self, brdf: &dyn Brdf, wo: Vec3) -> Estimate {
        let sum: DVec3 = self.rays.iter().map(|r| r.term(brdf, wo).as_dvec3()).sum();
        Estimate {
            value: sum.as_vec3(),
            bound: Rgb::ZERO,
            evaluations: self.rays.len(),
        }
    }
}

/// How a glossy vertex stores its rays (sections 2.10 and 2.10.1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum GlossyMode {
    /// The plain list of section 2.10: every ray, every estimate evaluates the BRDF once per ray.
    List,
    /// The QuadTree "without summarizing" of section 2.10.1: every ray, exactly removable; the estimate takes a node as a whole when the BRDF's relative variation over its rays' directions is at most `tolerance` (zero: per-ray, equal to the list).
    QuadTree {
        /// Leaf capacity and depth limit.
        options: QuadTreeOptions,
        /// Largest relative half-range of the BRDF over a node evaluated as a whole (0 disables it).
        tolerance: f32,
    },
    /// The QuadTree "with summarizing" of section 2.10.1: one mean ray per leaf of the first frame's tree, updated with the paper's formula; approximate.
    Summarised(QuadTreeOptions),
}

impl GlossyMode {
    /// Checks the mode's parameters.
    pub fn validate(&self) -> Result<()> {
        match self {
            Self::List => Ok(()),
            Self::QuadTree { options, tolerance } => {
                options.validate()?;
                if !(tolerance.is_finite() && *tolerance >= 0.0) {
                    return Err(DensityError::InvalidOption {
                        option: "tolerance",
                        message: format!("{tolerance} is not a finite non-negative tolerance"),
                    });
                }
                Ok(())
            }
            Self::Summarised(options) => options.validate(),
        }
    }
}

/// The store behind a [`GlossyVertex`].
#[derive(Debug, Clone, PartialEq)]
enum Store {
    List(RayList),
    Tree(QuadTree, f32),
    Summary(SummaryTree),
}

/// What one frame's update did to a vertex's list (section 2.10).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct UpdateStats {
    /// Old Rays crossing the disc, removed.
    pub removed: usize,
    /// New Rays crossing the disc, inserted.
    pub inserted: usize,
    /// Old Rays crossing the disc that were not in the list (always zero for a consistent update; summaries cannot tell).
    pub missing: usize,
}

impl std::ops::AddAssign for UpdateStats {
    fn add_assign(&mut self, other: Self) {
        self.removed += other.removed;
        self.inserted += other.inserted;
        self.missing += other.missing;
    }
}

/// A vertex defers at most `1 / MAX_DEFERRED_SHARE` as many rays as it holds, plus 64 (module docs).
pub const MAX_DEFERRED_SHARE: usize = 4;

/// Rays with a multiplicity (negative: removals).
type SignedRays = Vec<(IncidentRay, i32)>;

thread_local! {
    /// Per thread, the frame's signed rays and the merged change of [`Deferred::add`], reused from vertex to vertex.
    static SCRATCH: std::cell::RefCell<(SignedRays, SignedRays)> =
        const { std::cell::RefCell::new((Vec::new(), Vec::new())) };
}

/// The net change of the frames a vertex deferred: each distinct ray once with its net multiplicity (negative: to remove, positive: to insert), sorted by [`IncidentRay::key`], none zero.
#[derive(Debug, Clone, Default, PartialEq)]
struct Deferred {
    rays: SignedRays,
}

impl Deferred {
    /// Adds a frame's Old Rays (multiplicity −1 each) and New Rays (+1): the multiplicities of equal rays add, so each ray cancels one equal ray of the other kind, of this frame or an earlier one. One sort of the frame's rays and one merge with those held.
    fn add(
        &mut self,
        old: impl Iterator<Item = IncidentRay>,
        new: impl Iterator<Item = IncidentRay>,
    ) {
        SCRATCH.with_borrow_mut(|(frame, merged)| {
            frame.clear();
            frame.extend(old.map(|r| (r, -1)).chain(new.map(|r| (r, 1))));
            // Equal keys are equal rays, so their order among themselves does not matter.
            frame.sort_unstable_by(|a, b| key_order(&a.0, &b.0));
            merged.clear();
            let (mut a, mut b) = (self.rays.iter().peekable(), frame.iter().peekable());
            loop {
                let next = match (a.peek(), b.peek()) {
                    (Some(x), Some(y)) if key_order(&y.0, &x.0) == Ordering::Less => b.next(),
                    (Some(_), _) => a.next(),
                    (None, _) => b.next(),
                };
                let Some(&(ray, k)) = next else {
                    break;
                };
                match merged.last_mut() {
                    Some((last, n)) if key_order(last, &ray) == Ordering::Equal => {
                        *n += k;
                        if *n == 0 {
                            merged.pop();
                        }
                    }
                    _ => merged.push((ray, k)),
                }
            }
            self.rays.clear();
            self.rays.extend_from_slice(merged);
        });
    }

    /// Number of rays held, `Σ |multiplicity|`.
    fn len(&self) -> usize {
        self.rays
            .iter()
            .map(|(_, k)| k.unsigned_abs() as usize)
            .sum()
    }

    /// Whether no ray is held.
    fn is_empty(&self) -> bool {
        self.rays.is_empty()
    }

    /// The rays to remove and the rays to insert, each sorted by key; leaves the change empty.
    fn take(&mut self) -> (Vec<IncidentRay>, Vec<IncidentRay>) {
        let (mut old, mut new) = (Vec::new(), Vec::new());
        for (ray, k) in std::mem::take(self).rays {
            let side = if k < 0 { &mut old } else { &mut new };
            side.extend(std::iter::repeat_n(ray, k.unsigned_abs() as usize));
        }
        (old, new)
    }
}

/// A glossy vertex (section 2.10): its DETP disc, its shading frame, the area that divides the flux, and the rays crossing the disc.
#[derive(Debug, Clone, PartialEq)]
pub struct GlossyVertex {
    disc: Disc,
    frame: Frame,
    area: f32,
    slack: f32,
    store: Store,
    /// The net change of the frames not yet applied to the store (see the module docs: deferred while the eye is behind the tangent plane).
    deferred: Deferred,
}

impl GlossyVertex {
    /// Collects the segments crossing the disc (section 1.2, [`Disc::is_crossed_by`] with `slack`) into the store `mode` asks for; the area is `π r²`. Fails on a disc without a positive finite radius or a unit normal, a negative or non-finite slack, or invalid mode parameters.
    pub fn build<'a>(
        disc: Disc,
        slack: f32,
        mode: GlossyMode,
        segments: impl IntoIterator<Item = &'a RaySegment>,
    ) -> Result<Self> {
        crate::artifact::check_disc(&disc)?;
        if !(slack >= 0.0 && slack.is_finite()) {
            return Err(DensityError::InvalidOption {
                option: "slack",
                message: format!("{slack} is not a finite non-negative distance"),
            });
        }
        mode.validate()?;
        Self::from_crossing(
            disc,
            slack,
            mode,
            segments
                .into_iter()
                .filter(|s| disc.is_crossed_by(s, slack)),
        )
    }

    /// [`GlossyVertex::build`] from segments already known to cross the disc, with the disc, slack and mode already checked.
    fn from_crossing<'a>(
        disc: Disc,
        slack: f32,
        mode: GlossyMode,
        crossing: impl IntoIterator<Item = &'a RaySegment>,
    ) -> Result<Self> {
        let frame = Frame::from_normal(disc.normal);
        let rays: Vec<IncidentRay> = crossing
            .into_iter()
            .map(|s| IncidentRay::from_segment(&frame, s))
            .collect();
        let store = match mode {
            GlossyMode::List => Store::List(RayList::from_rays(&rays)),
            GlossyMode::QuadTree { options, tolerance } => {
                Store::Tree(QuadTree::from_rays(options, &rays)?, tolerance)
            }
            GlossyMode::Summarised(options) => {
                Store::Summary(SummaryTree::from_rays(options, &rays)?)
            }
        };
        Ok(Self {
            disc,
            frame,
            area: std::f32::consts::PI * disc.radius * disc.radius,
            slack,
            store,
            deferred: Deferred::default(),
        })
    }

    /// The vertex's disc.
    pub fn disc(&self) -> &Disc {
        &self.disc
    }

    /// The shading frame the incident directions are expressed in (+Z the disc normal).
    pub fn frame(&self) -> &Frame {
        &self.frame
    }

    /// The area that divides the flux: `π r²`, or the reachable area under artifact control (section 1.2.1).
    pub fn area(&self) -> f32 {
        self.area
    }

    /// Sets the area that divides the flux, e.g. the reachable area of [`crate::artifact::reachable_area`] (section 1.2.1); fails unless it is positive and finite.
    pub fn set_area(&mut self, area: f32) -> Result<()> {
        if !(area > 0.0 && area.is_finite()) {
            return Err(DensityError::InvalidOption {
                option: "area",
                message: format!("{area} is not a positive finite area"),
            });
        }
        self.area = area;
        Ok(())
    }

    /// Number of rays the vertex holds (for a summarised store, the count the summaries represent).
    pub fn len(&self) -> usize {
        match &self.store {
            Store::List(l) => l.len(),
            Store::Tree(t, _) => t.len(),
            Store::Summary(s) => s.len() as usize,
        }
    }

    /// Whether no ray crosses the disc.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The exact store's rays (list or QuadTree); `None` for a summarised store, whose rays are lost (section 2.10.1).
    pub fn rays(&self) -> Option<Vec<IncidentRay>> {
        match &self.store {
            Store::List(l) => Some(l.rays().to_vec()),
            Store::Tree(t, _) => Some(t.rays()),
            Store::Summary(_) => None,
        }
    }

    /// The QuadTree store, if any.
    pub fn quadtree(&self) -> Option<&QuadTree> {
        match &self.store {
            Store::Tree(t, _) => Some(t),
            _ => None,
        }
    }

    /// The summarised store, if any.
    pub fn summary_tree(&self) -> Option<&SummaryTree> {
        match &self.store {
            Store::Summary(s) => Some(s),
            _ => None,
        }
    }

    /// The incident ray of a segment if it crosses the disc.
    pub fn incident(&self, segment: &RaySegment) -> Option<IncidentRay> {
        self.disc
            .is_crossed_by(segment, self.slack)
            .then(|| IncidentRay::from_segment(&self.frame, segment))
    }

    /// One frame's update (section 2.10: "the new rays and old rays ... must be checked against the ray list in the vertex"): removes the Old Rays that cross the disc, then inserts the New Rays that cross it. A summarised store applies the formula of section 2.10.1 and fails, unchanged, when more rays leave a summary than it holds.
    pub fn update(&mut self, old: &[RaySegment], new: &[RaySegment]) -> Result<UpdateStats> {
        let old: Vec<IncidentRay> = old.iter().filter_map(|s| self.incident(s)).collect();
        let new: Vec<IncidentRay> = new.iter().filter_map(|s| self.incident(s)).collect();
        let mut stats = self.catch_up()?;
        stats += self.apply(old, new)?;
        Ok(stats)
    }

    /// [`GlossyVertex::update`] with the Old and New Rays already known to cross the disc; with an `eye` the vertex faces away from, an exact store with room for them keeps them deferred instead (`None`; see the module docs).
    fn update_crossing<'a>(
        &mut self,
        old: impl Iterator<Item = &'a RaySegment>,
        new: impl Iterator<Item = &'a RaySegment>,
        eye: Option<Vec3>,
    ) -> Result<Option<UpdateStats>> {
        let frame = self.frame;
        let old = old.map(|s| IncidentRay::from_segment(&frame, s));
        let new = new.map(|s| IncidentRay::from_segment(&frame, s));
        let exact = !matches!(self.store, Store::Summary(_));
        if exact && eye.is_some_and(|eye| self.faces_away_from(eye)) {
            self.deferred.add(old, new);
            if self.deferred.len() <= self.len() / MAX_DEFERRED_SHARE + 64 {
                return Ok(None);
            }
            return self.catch_up().map(Some);
        }
        let mut stats = self.catch_up()?;
        stats += self.apply(old.collect(), new.collect())?;
        Ok(Some(stats))
    }

    /// Whether `eye` lies clearly behind the tangent plane (by more than a thousandth of its distance), where the vertex's radiance is zero whatever its rays.
    pub fn faces_away_from(&self, eye: Vec3) -> bool {
        let to_eye = eye - self.disc.centre;
        to_eye.dot(self.frame.n) < -1e-3 * to_eye.length()
    }

    /// Number of deferred Old and New Rays not yet applied to the store.
    pub fn deferred_rays(&self) -> usize {
        self.deferred.len()
    }

    /// Applies the net change of the deferred frames.
    pub fn catch_up(&mut self) -> Result<UpdateStats> {
        if self.deferred.is_empty() {
            return Ok(UpdateStats::default());
        }
        let (old, new) = self.deferred.take();
        self.apply(old, new)
    }

    /// The vertex with its deferred rays applied: itself when none are deferred, else a caught-up copy.
    fn caught_up(&self) -> Result<std::borrow::Cow<'_, Self>> {
        if self.deferred.is_empty() {
            return Ok(std::borrow::Cow::Borrowed(self));
        }
        let mut copy = self.clone();
        copy.catch_up()?;
        Ok(std::borrow::Cow::Owned(copy))
    }

    /// Removes the Old Rays, then inserts the New Rays (section 2.10).
    fn apply(&mut self, old: Vec<IncidentRay>, new: Vec<IncidentRay>) -> Result<UpdateStats> {
        let mut stats = UpdateStats {
            removed: old.len(),
            inserted: new.len(),
            missing: 0,
        };
        match &mut self.store {
            Store::List(l) => {
                stats.missing = old.iter().filter(|r| !l.remove(r)).count();
                new.into_iter().for_each(|r| l.insert(r));
            }
            Store::Tree(t, _) => stats.missing = t.update(&old, &new),
            Store::Summary(s) => s.update(&old, &new)?,
        }
        stats.removed -= stats.missing;
        Ok(stats)
    }

    /// The view-dependent radiance `L(x, ωo) = Σ f_r(ω_j, ωo) φ_j / A` towards the world direction `wo` (equation 2.1 on the DETP disc), with its error bound; zero when `wo` is below the tangent plane.
    pub fn estimate(&self, brdf: &dyn Brdf, wo: Vec3) -> Estimate {
        let wo = self.frame.to_local(wo.normalize_or_zero());
        let sum = match &self.store {
            Store::List(l) => l.estimate(brdf, wo),
            Store::Tree(t, tolerance) => t.estimate(brdf, wo, *tolerance),
            Store::Summary(s) => s.estimate(brdf, wo),
        };
        Estimate {
            value: sum.value / self.area,
            bound: sum.bound / self.area,
            evaluations: sum.evaluations,
        }
    }

    /// The radiance of the BRDF's non-diffuse part, `Σ_j (f_r(ω_j, ωo) − ρ/π) φ_j / A` towards the world direction `wo`, with `ρ` the Lambertian reflectance of its diffuse part (beyond the paper: equation 2.1 with `f_r − ρ/π` in place of `f_r`, so that the diffuse part `ρ/π E` can come from another disc); clamped at zero, since `f_r ≥ ρ/π` makes every term non-negative. Its bound is [`GlossyVertex::estimate`]'s.
    pub fn lobe_estimate(&self, brdf: &dyn Brdf, wo: Vec3, diffuse: Rgb) -> Estimate {
        let full = self.estimate(brdf, wo);
        let lambert = diffuse * std::f32::consts::FRAC_1_PI * self.irradiance();
        Estimate {
            value: (full.value - lambert).max(Rgb::ZERO),
            ..full
        }
    }

    /// The radiance of [`GlossyVertex::estimate`] alone (equation 2.1 on the DETP disc).
    pub fn radiance(&self, brdf: &dyn Brdf, wo: Vec3) -> Rgb {
        self.estimate(brdf, wo).value
    }

    /// The DETP irradiance `E = Σ φ_j / A` of the rays held (section 1.2).
    pub fn irradiance(&self) -> Rgb {
        let power = match &self.store {
            Store::List(l) => l.power(),
            Store::Tree(t, _) => t.power(),
            Store::Summary(s) => s.power(),
        };
        power / self.area
    }
}

/// The meshes whose material is not a plain diffuse reflector, the "glossy" ones of section 2.10 that need per-vertex ray lists.
pub fn glossy_meshes(scene: &Scene) -> Vec<MeshId> {
    scene
        .meshes()
        .iter()
        .enumerate()
        .filter(|(_, m)| {
            scene
                .materials()
                .get(m.material as usize)
                .is_some_and(|mat| !mat.model.is_diffuse())
        })
        .map(|(i, _)| i as MeshId)
        .collect()
}

/// The glossy vertices of a scene (section 2.10), indexed `[mesh][vertex]`; meshes not asked for hold no vertex, and a vertex without a valid normal is `None`.
#[derive(Debug, Clone)]
pub struct GlossyVertices {
    meshes: Vec<Vec<Option<GlossyVertex>>>,
    materials: Vec<MaterialId>,
    /// The Lambertian reflectance of each mesh's material ([`lustre_geometry::MaterialModel::diffuse_reflectance`]), for [`GlossyVertices::lobe_radiance`].
    diffuse: Vec<Rgb>,
    /// The vertices' discs with their disc index (section 2.7), for finding which Old and New Rays cross each.
    discs: DiscSet,
    /// The disc of each vertex in `discs`, `[mesh][vertex]`.
    disc_of: Vec<Vec<Option<u32>>>,
    /// Whether the stores are summaries ([`GlossyMode::Summarised`]), which take every Old and New Ray.
    summarised: bool,
}

impl PartialEq for GlossyVertices {
    /// Equal vertices and materials (the disc set follows from the vertices).
    fn eq(&self, other: &Self) -> bool {
        self.meshes == other.meshes
            && self.materials == other.materials
            && self.diffuse == other.diffuse
    }
}

/// About how many bytes a ray costs in a glossy vertex's list while the lists are built: the 32-byte entry of the QuadTree, its share of the nodes, and the crossing's index. Measured when each leaf had a vector of its own and each inner node boxed children: `lustre render --technique detp` of `dense_glossy`'s blob peaked 2.1 GB higher with the QuadTree estimate than without, for 31.7 M rays, 66 bytes a ray; rounded up. The tree's two arrays hold less (the `dense_glossy` bench's peak fell by 0.43 GB, 14 %), so this is now a looser bound.
pub const BYTES_PER_STORED_RAY: usize = 80;

impl GlossyVertices {
    /// Builds the ray lists of every vertex of the given meshes from the whole ray set (section 2.10, first frame), with discs of `radius` on the tangent planes of the meshes' world normals as [`crate::detp`] does; the crossing rays are found with disc indexing (section 2.7, [`DiscSet::crossings`]: exactly the rays [`Disc::is_crossed_by`] accepts), the stores built in parallel. Fails on a bad radius, mode or mesh id.
    pub fn build(
        scene: &Scene,
        rays: &RaySet,
        radius: f32,
        mode: GlossyMode,
        meshes: &[MeshId],
    ) -> Result<Self> {
        Self::build_limited(scene, rays, radius, mode, meshes, None)
    }

    /// [`GlossyVertices::build`] that fails with [`DensityError::TooManyRays`] before building any list when the lists would hold more than `max_rays` rays in all (a bound on memory, [`BYTES_PER_STORED_RAY`] each).
    pub fn build_limited(
        scene: &Scene,
        rays: &RaySet,
        radius: f32,
        mode: GlossyMode,
        meshes: &[MeshId],
        max_rays: Option<u64>,
    ) -> Result<Self> {
        if !(radius > 0.0 && radius.is_finite()) {
            return Err(DensityError::InvalidOption {
                option: "radius",
                message: format!("{radius} is not a positive finite disc radius"),
            });
        }
        mode.validate()?;
        if let Some(&m) = meshes.iter().find(|&&m| m as usize >= scene.meshes().len()) {
            return Err(DensityError::InvalidOption {
                option: "meshes",
                message: format!("mesh {m} does not exist"),
            });
        }
        let slack = crate::accel::scene_slack(scene);
        // One disc per vertex with a usable normal, and where it goes.
        let mut meshes = meshes.to_vec();
        meshes.sort_unstable();
        meshes.dedup();
        let mut discs = Vec::new();
        let mut slots = Vec::new();
        for &m in &meshes {
            let positions = scene.world_positions(m);
            let normals = scene.world_normals(m);
            for (v, (&centre, &normal)) in positions.iter().zip(&normals).enumerate() {
                let normal = normal.normalize_or_zero();
                if normal != Vec3::ZERO {
                    discs.push(Disc {
                        centre,
                        normal,
                        radius,
                        mesh: Some(m),
                    });
                    slots.push((m, v));
                }
            }
        }
        let set = DiscSet::new(
            discs,
            DiscSetOptions {
                slack,
                // Tuned for the edges of the meshes the discs lie on.
                acceleration: Acceleration::tuned_disc_index(
                    radius,
                    mean_edge(scene, meshes.iter().copied()),
                ),
                pretest: PreTest::None,
            },
        )?;
        // Without a disc (no glossy mesh of this kind, e.g. a frame's mobile ones) no segment is looked at.
        let segments: Vec<RaySegment> = if set.discs().is_empty() {
            Vec::new()
        } else {
            rays.segments().copied().collect()
        };
        if let Some(limit) = max_rays {
            // One segment in 64 first, so that lists far too large fail before their crossings are gathered (12 bytes each).
            let sample: Vec<RaySegment> = segments.iter().step_by(64).copied().collect();
            let estimate = 64 * set.crossings(&sample)?.pairs() as u64;
            if estimate > 2 * limit {
                return Err(DensityError::TooManyRays {
                    rays: estimate,
                    limit,
                });
            }
        }
        let crossings = set.crossings(&segments)?;
        let total = crossings.pairs() as u64;
        if let Some(limit) = max_rays.filter(|&limit| total > limit) {
            return Err(DensityError::TooManyRays { rays: total, limit });
        }
        let built = set
            .discs()
            .par_iter()
            .enumerate()
            .map(|(d, &disc)| {
                let ids = &crossings[d];
                // DiscSet::new checked the discs, and its crossings are exactly the segments `is_crossed_by` accepts.
                GlossyVertex::from_crossing(
                    disc,
                    slack,
                    mode,
                    ids.iter().map(|&i| &segments[i as usize]),
                )
            })
            .collect::<Result<Vec<_>>>()?;
        let mut out: Vec<Vec<Option<GlossyVertex>>> = vec![Vec::new(); scene.meshes().len()];
        let mut disc_of: Vec<Vec<Option<u32>>> = vec![Vec::new(); scene.meshes().len()];
        for &m in &meshes {
            out[m as usize] = vec![None; scene.meshes()[m as usize].positions.len()];
            disc_of[m as usize] = vec![None; scene.meshes()[m as usize].positions.len()];
        }
        for (d, ((m, v), vertex)) in slots.into_iter().zip(built).enumerate() {
            out[m as usize][v] = Some(vertex);
            disc_of[m as usize][v] = Some(d as u32);
        }
        Ok(Self {
            meshes: out,
            materials: scene.meshes().iter().map(|m| m.material).collect(),
            diffuse: scene
                .meshes()
                .iter()
                .map(|m| {
                    scene
                        .materials()
                        .get(m.material as usize)
                        .map_or(Rgb::ZERO, |mat| mat.model.diffuse_reflectance())
                })
                .collect(),
            discs: set,
            disc_of,
            summarised: matches!(mode, GlossyMode::Summarised(_)),
        })
    }

    /// The vertices of a mesh (empty for a mesh that was not built). A vertex holding deferred rays ([`GlossyVertex::deferred_rays`], after [`GlossyVertices::update_towards`]) has the store of the frame before them until [`GlossyVertex::catch_up`].
    pub fn vertices(&self, mesh: MeshId) -> &[Option<GlossyVertex>] {
        self.meshes.get(mesh as usize).map_or(&[], |v| v.as_slice())
    }

    /// Mutable access to the vertices of a mesh.
    pub fn vertices_mut(&mut self, mesh: MeshId) -> &mut [Option<GlossyVertex>] {
        self.meshes
            .get_mut(mesh as usize)
            .map_or(&mut [], |v| v.as_mut_slice())
    }

    /// One frame's update of every vertex's list from the frame's Old and New Rays (section 2.10), in parallel; the statistics are summed over vertices. The Old Rays must be the segments exactly as they were inserted (same direction, power and extension). On an error (a summary losing more rays than it holds) the other vertices keep their update.
    pub fn update(&mut self, old: &[RaySegment], new: &[RaySegment]) -> Result<UpdateStats> {
        self.update_listing(old, new).map(|(stats, _)| stats)
    }

    /// [`GlossyVertices::update`], also listing the vertices whose lists changed (an Old or New Ray crossed their disc), as `(mesh, vertex)` in mesh and vertex order: the others keep their radiance towards any eye.
    pub fn update_listing(
        &mut self,
        old: &[RaySegment],
        new: &[RaySegment],
    ) -> Result<(UpdateStats, Vec<(MeshId, u32)>)> {
        self.update_towards(old, new, &Twins::by_bits(old, new), None)
    }

    /// [`GlossyVertices::update_listing`] that defers the rays of the vertices facing away from `eye` (see the module docs): they are not listed, since their radiance towards `eye` stays zero, and their stats are those of the net change, counted when it is applied. The listed vertices had their earlier deferred rays applied first. `twins` are those of `old` and `new` ([`Twins`]; an exact store leaves out what cancels). Fails as [`GlossyVertices::update`] does, or when `twins` are not those of `old` and `new`.
    pub fn update_towards(
        &mut self,
        old: &[RaySegment],
        new: &[RaySegment],
        twins: &Twins,
        eye: Option<Vec3>,
    ) -> Result<(UpdateStats, Vec<(MeshId, u32)>)> {
        // The rays crossing each disc, by disc indexing (section 2.7): what each vertex's own test would accept,
        // less the twins that cancel there for an exact store (module docs).
        let (old_crossing, new_crossing) = if self.summarised {
            (self.discs.crossings(old)?, self.discs.crossings(new)?)
        } else {
            self.discs.net_crossings(old, new, twins)?
        };
        let per_vertex: Vec<(UpdateStats, (MeshId, u32))> = self
            .meshes
            .par_iter_mut()
            .zip(self.disc_of.par_iter())
            .enumerate()
            .flat_map(|(m, (v, d))| {
                v.par_iter_mut()
                    .zip(d.par_iter())
                    .enumerate()
                    .map(move |(i, vd)| ((m as MeshId, i as u32), vd))
            })
            .filter_map(|(id, (v, d))| {
                // The crossings first: a vertex no ray crossed is not read.
                let &Some(d) = d else {
                    return None;
                };
                let (old_in, new_in) = (&old_crossing[d as usize], &new_crossing[d as usize]);
                if old_in.is_empty() && new_in.is_empty() {
                    return None;
                }
                let v = v.as_mut()?;
                v.update_crossing(
                    old_in.iter().map(|&i| &old[i as usize]),
                    new_in.iter().map(|&i| &new[i as usize]),
                    eye,
                )
                .map(|stats| stats.map(|stats| (stats, id)))
                .transpose()
            })
            .collect::<Result<_>>()?;
        let mut total = UpdateStats::default();
        let mut changed = Vec::with_capacity(per_vertex.len());
        for (stats, id) in per_vertex {
            total += stats;
            changed.push(id);
        }
        Ok((total, changed))
    }

    /// Applies the deferred rays of every vertex that does not face away from `eye`, listing them as `(mesh, vertex)` in mesh and vertex order: their radiance towards `eye` may have changed.
    pub fn catch_up(&mut self, eye: Vec3) -> Result<Vec<(MeshId, u32)>> {
        self.meshes
            .par_iter_mut()
            .enumerate()
            .flat_map(|(m, vertices)| {
                vertices
                    .par_iter_mut()
                    .enumerate()
                    .map(move |(i, v)| ((m as MeshId, i as u32), v))
            })
            .filter_map(|(id, v)| {
                let v = v.as_mut()?;
                (!v.deferred.is_empty() && !v.faces_away_from(eye))
                    .then(|| v.catch_up().map(|_| id))
            })
            .collect()
    }

    /// Number of deferred Old and New Rays over every vertex.
    pub fn deferred_rays(&self) -> usize {
        self.meshes
            .iter()
            .flatten()
            .flatten()
            .map(GlossyVertex::deferred_rays)
            .sum()
    }

    /// Uses per-vertex areas (e.g. [`crate::artifact::reachable_areas`], section 1.2.1) instead of `π r²`; a zero area leaves `π r²`. Fails when the shape does not match or an area is negative or not finite.
    pub fn set_areas(&mut self, areas: &[Vec<f32>]) -> Result<()> {
        for (m, vertices) in self.meshes.iter_mut().enumerate() {
            for (v, vertex) in vertices.iter_mut().enumerate() {
                let Some(vertex) = vertex else { continue };
                let area = areas.get(m).and_then(|a| a.get(v)).ok_or_else(|| {
                    DensityError::InvalidOption {
                        option: "areas",
                        message: format!("no area for vertex {v} of mesh {m}"),
                    }
                })?;
                if *area != 0.0 {
                    vertex.set_area(*area)?;
                }
            }
        }
        Ok(())
    }

    /// The radiance of every vertex towards the eye (equation 2.1 per vertex, recomputed when the camera moves), `[mesh][vertex]`, with `brdfs` one per material (`lustre_photon::trace::scene_brdfs`); empty for meshes not built; zero without an estimate for the vertices that face away from the eye. Fails when a mesh's material has no BRDF.
    pub fn radiance(&self, brdfs: &[BoxedBrdf], eye: Vec3) -> Result<Vec<Vec<Rgb>>> {
        self.per_vertex(brdfs, eye, |v, brdf, _| {
            v.radiance(brdf, eye - v.disc().centre)
        })
    }

    /// The radiance of the non-diffuse part of every vertex's BRDF towards the eye, [`GlossyVertex::lobe_estimate`] with the mesh material's Lambertian reflectance (beyond the paper: the diffuse part `ρ/π E` is left to the diffuse estimate), `[mesh][vertex]`; empty for meshes not built. Fails when a mesh's material has no BRDF.
    pub fn lobe_radiance(&self, brdfs: &[BoxedBrdf], eye: Vec3) -> Result<Vec<Vec<Rgb>>> {
        self.per_vertex(brdfs, eye, |v, brdf, diffuse| {
            lobe_towards(v, brdf, eye, diffuse)
        })
    }

    /// [`GlossyVertices::lobe_radiance`] of the listed `(mesh, vertex)` only, in their order (zero for a vertex without a list). Fails when a vertex does not exist or a mesh's material has no BRDF.
    pub fn lobe_radiance_of(
        &self,
        brdfs: &[BoxedBrdf],
        eye: Vec3,
        vertices: &[(MeshId, u32)],
    ) -> Result<Vec<Rgb>> {
        vertices
            .par_iter()
            .map(|&(m, v)| {
                let slot = self
                    .meshes
                    .get(m as usize)
                    .and_then(|vs| vs.get(v as usize))
                    .ok_or_else(|| DensityError::InvalidOption {
                        option: "vertices",
                        message: format!("no vertex {v} in mesh {m}"),
                    })?;
                let Some(vertex) = slot else {
                    return Ok(Rgb::ZERO);
                };
                let brdf = brdf_of(brdfs, self.materials[m as usize])?;
                let diffuse = self.diffuse[m as usize];
                seen_from(vertex, eye, |v| lobe_towards(v, brdf, eye, diffuse))
            })
            .collect()
    }

    /// `f(vertex, its mesh's BRDF, its mesh's Lambertian reflectance)` at every built vertex as [`seen_from`] `eye` gives it, zero for a vertex without one.
    fn per_vertex(
        &self,
        brdfs: &[BoxedBrdf],
        eye: Vec3,
        f: impl Fn(&GlossyVertex, &dyn Brdf, Rgb) -> Rgb + Sync,
    ) -> Result<Vec<Vec<Rgb>>> {
        self.meshes
            .iter()
            .zip(&self.materials)
            .zip(&self.diffuse)
            .map(|((vertices, &material), &diffuse)| {
                if vertices.is_empty() {
                    return Ok(Vec::new());
                }
                let brdf = brdf_of(brdfs, material)?;
                vertices
                    .par_iter()
                    .map(|v| match v {
                        Some(v) => seen_from(v, eye, |v| f(v, brdf, diffuse)),
                        None => Ok(Rgb::ZERO),
                    })
                    .collect()
            })
            .collect()
    }
}

/// The BRDF of `material` among `brdfs` (one per material); an error when there is none.
fn brdf_of(brdfs: &[BoxedBrdf], material: MaterialId) -> Result<&(dyn Brdf + Send + Sync)> {
    brdfs
        .get(material as usize)
        .map(|b| b.as_ref())
        .ok_or_else(|| DensityError::InvalidOption {
            option: "brdfs",
            message: format!("no BRDF for material {material}"),
        })
}

/// An estimate `f` of the vertex towards `eye`: zero, without evaluating it, for a vertex that faces away from `eye` (every BRDF is zero for `ωo` below the tangent plane, so its radiance is zero whatever its rays: back-face culling), else `f` of the vertex with its deferred rays applied (on a copy).
fn seen_from(
    vertex: &GlossyVertex,
    eye: Vec3,
    f: impl FnOnce(&GlossyVertex) -> Rgb,
) -> Result<Rgb> {
    if vertex.faces_away_from(eye) {
        Ok(Rgb::ZERO)
    } else {
        Ok(f(vertex.caught_up()?.as_ref()))
    }
}

/// [`GlossyVertex::lobe_estimate`] of `vertex` towards `eye`: the radiance of its BRDF's non-diffuse part.
fn lobe_towards(vertex: &GlossyVertex, brdf: &dyn Brdf, eye: Vec3, diffuse: Rgb) -> Rgb {
    vertex
        .lobe_estimate(brdf, eye - vertex.disc().centre, diffuse)
        .value
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    /// Frames of Old and New Rays drawn from a few distinct rays (so that rays repeat within a frame and across
    /// frames, and cancel both ways): the deferred change equals the net multiplicities counted one ray at a
    /// time, and gives them back as sorted removals and insertions.
    #[test]
    fn deferred_change_is_the_net_multiset() {
        let ray = |i: u32| IncidentRay {
            wi: Vec3::new(i as f32 * 0.1, 0.3, 0.9).normalize(),
            power: Rgb::splat(1.0 + (i % 3) as f32),
        };
        let mut state = 99u64;
        let mut next = |n: u64| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 33) % n
        };
        let mut deferred = Deferred::default();
        let mut counts: BTreeMap<RayKey, (IncidentRay, i64)> = BTreeMap::new();
        for _ in 0..200 {
            let old: Vec<IncidentRay> = (0..next(6)).map(|_| ray(next(7) as u32)).collect();
            let new: Vec<IncidentRay> = (0..next(6)).map(|_| ray(next(7) as u32)).collect();
            for (rays, sign) in [(&old, -1), (&new, 1)] {
                for r in rays {
                    counts.entry(r.key()).or_insert((*r, 0)).1 += sign;
                }
            }
            deferred.add(old.into_iter(), new.into_iter());
            let expected: Vec<(IncidentRay, i32)> = counts
                .values()
                .filter(|(_, n)| *n != 0)
                .map(|&(r, n)| (r, n as i32))
                .collect();
            assert_eq!(deferred.rays, expected);
            let held: i64 = counts.values().map(|(_, n)| n.abs()).sum();
            assert_eq!(deferred.len(), held as usize);
            assert_eq!(deferred.is_empty(), held == 0);
        }
        let (old, new) = deferred.clone().take();
        let expand = |negative: bool| -> Vec<IncidentRay> {
            counts
                .values()
                .filter(|(_, n)| (*n < 0) == negative && *n != 0)
                .flat_map(|&(r, n)| std::iter::repeat_n(r, n.unsigned_abs() as usize))
                .collect()
        };
        assert_eq!((old, new), (expand(true), expand(false)));
        // Taking the change leaves none.
        deferred.take();
        assert!(deferred.is_empty());
        assert_eq!(deferred.len(), 0);
    }
}
