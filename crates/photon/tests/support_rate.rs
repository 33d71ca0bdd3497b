//! The variance of the splat estimate as photons are added (equation 3 against
//! Silverman's bandwidth rate): a kernel estimate's variance is
//! `≈ R(K) g(x) / (n h²)` for `n` points of density `g` (Silverman 1986,
//! equation 4.10), so with equation 3's `h ∝ n^(-1/2)` it stays, and with
//! `h ∝ n^(-1/6)` it falls as `n^(-2/3)`.

mod support;

use glam::Vec3;
use lustre_geometry::material::{ConductorFresnel, MaterialModel, MicrofacetDistribution};
use lustre_geometry::sampling::Frame;
use lustre_geometry::{Bvh, Material, Rgb};
use lustre_photon::{
    BounceSelection, EstimatorOptions, Kernel, NoProgress, SplatEstimator, Support, TraceOptions,
    kernel_support, trace_photons,
};

/// A rough mirror (Beckmann α = 0.3, F = 1; its lobe is wide against the kernels here, so the BRDF is nearly constant under a kernel and the rate is the kernel estimate's own) under an isotropic point light 1 m above.
fn glossy_plane() -> lustre_geometry::Scene {
    support::point_over_plane(1.0, 1.0, 0.5, 10.0)
        .with_materials(vec![Material::new(
            "glossy",
            MaterialModel::RoughConductor {
                distribution: MicrofacetDistribution::Beckmann,
                alpha: 0.3,
                fresnel: ConductorFresnel::None,
                specular: Rgb::ONE,
            },
        )])
        .unwrap()
}

/// Relative variance `Var[L]/L²` of the estimate at `x0` towards `wo`, from the photons' own contributions (each photon has at most one hit: one bounce).
fn relative_variance(photons: u64, mut support: impl FnMut(usize) -> Support) -> f64 {
    let scene = glossy_plane();
    let bvh = Bvh::build(&scene);
    let options = TraceOptions {
        photons,
        seed: 5,
        max_bounces: 1,
        ..TraceOptions::default()
    };
    let map = trace_photons(&scene, &bvh, &options, &NoProgress).unwrap();
    let n = map.records().iter().filter(|r| r.surface == 0).count();
    let estimator = SplatEstimator::build(
        &scene,
        &map,
        EstimatorOptions {
            kernel: Kernel::Silverman,
            support: support(n),
            selection: BounceSelection::All,
            edges: lustre_photon::Edges::Truncated,
        },
    )
    .unwrap();
    let brdf = lustre_brdf::from_model(&scene.materials()[0].model).unwrap();
    let h = estimator.support(0);
    let x0 = Vec3::new(0.2, 0.0, 0.1);
    // Near the mirror direction of the light at x0.
    let wo = Vec3::new(0.25, 1.0, 0.1).normalize();
    let frame = Frame::from_normal(Vec3::Y);
    let (mut s1, mut s2) = (0.0f64, 0.0f64);
    for s in estimator.splats() {
        let k = Kernel::Silverman.scaled((s.position - x0).length_squared(), h);
        let c =
            f64::from(k * s.power.x * brdf.eval(frame.to_local(s.incoming), frame.to_local(wo)).x);
        s1 += c;
        s2 += c * c;
    }
    let estimate = f64::from(estimator.radiance(0, x0, Vec3::Y, wo).x);
    assert!(
        (s1 - estimate).abs() < 1e-3 * estimate,
        "{s1} vs {estimate}"
    );
    (s2 - s1 * s1 / photons as f64) / (s1 * s1)
}

/// With 16 times the photons, equation 3 leaves the relative variance where it was (ratio 1); Silverman's rate divides it by `16^(2/3) ≈ 6.35`.
#[test]
fn equation_3_keeps_the_variance_and_silverman_rate_lowers_it() {
    let (n1, n2) = (20_000u64, 320_000u64);
    let c = 4.0f32;
    let area = 4.0f32;
    let scaled = |_: usize| Support::Scaled(c);
    let ratio_scaled = relative_variance(n2, scaled) / relative_variance(n1, scaled);
    // Silverman's c chosen to give equation 3's support at the first count of hits.
    let mut c_silverman = 0.0f32;
    let first = relative_variance(n1, |n| {
        c_silverman = kernel_support(c, area, n) / (area.sqrt() * (n as f32).powf(-1.0 / 6.0));
        Support::Silverman(c_silverman)
    });
    let ratio_silverman = relative_variance(n2, |_| Support::Silverman(c_silverman)) / first;
    println!(
        "variance ratio for 16x the photons: equation 3 {ratio_scaled:.3} (theory 1), Silverman {ratio_silverman:.3} (theory {:.3})",
        16f64.powf(-2.0 / 3.0)
    );
    assert!((0.75..1.33).contains(&ratio_scaled), "{ratio_scaled}");
    let theory = 16f64.powf(-2.0 / 3.0);
    assert!(
        (0.75 * theory..1.33 * theory).contains(&ratio_silverman),
        "{ratio_silverman}"
    );
}
