//! Cook-Torrance / Beckmann with Smith G and conductor Fresnel against an independent evaluation and, when available, Mitsuba 3.

mod support;

use std::f64::consts::PI;
use std::path::PathBuf;
use std::process::{Command, Stdio};

use glam::Vec3;
use lustre_brdf::from_model;
use lustre_geometry::Rgb;
use lustre_geometry::material::{ConductorFresnel, MaterialModel, MicrofacetDistribution};
use support::{AU_ETA, AU_K, Rng, complex_fresnel, regularized_gamma_p};

/// The rough gold conductor of the glosbox (DESIGN.md) with α = `alpha`.
fn rough_gold(alpha: f32) -> MaterialModel {
    MaterialModel::RoughConductor {
        distribution: MicrofacetDistribution::Beckmann,
        alpha,
        fresnel: ConductorFresnel::Complex {
            eta: Vec3::from_array(AU_ETA),
            k: Vec3::from_array(AU_K),
        },
        specular: Rgb::ONE,
    }
}

/// Walter et al. 2007 equation 27: the rational fit of Smith's G1 for Beckmann, from spherical angles.
fn g1_rational(theta: f64, alpha: f64) -> f64 {
    let a = 1.0 / (alpha * theta.tan());
    if a >= 1.6 {
        1.0
    } else {
        (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a)
    }
}

/// Smith's exact G1 for Beckmann: 1 / (1 + Λ), Λ(a) = (erf(a) - 1)/2 + e^{-a²}/(2 a √π) (Walter et al. 2007 equation 25; erf(a) = P(1/2, a²)).
fn g1_exact(theta: f64, alpha: f64) -> f64 {
    let a = 1.0 / (alpha * theta.tan());
    let erf = regularized_gamma_p(0.5, a * a);
    let lambda = 0.5 * (erf - 1.0) + (-a * a).exp() / (2.0 * a * PI.sqrt());
    1.0 / (1.0 + lambda)
}

/// The rough conductor written from the formulas in spherical coordinates: f = F(θd) D(θh) G1(θi) G1(θo) / (4 cos θi cos θo).
fn reference(wi: Vec3, wo: Vec3, alpha: f64, exact_g: bool) -> [f64; 3] {
    let (wi, wo) = (wi.as_dvec3(), wo.as_dvec3());
    let theta_i = wi.z.acos();
    let theta_o = wo.z.acos();
    let h = (wi + wo).normalize();
    let theta_h = h.z.acos();
    let cos_d = wi.dot(h);
    let d = (-(theta_h.tan() / alpha).powi(2)).exp() / (PI * alpha * alpha * theta_h.cos().powi(4));
    let g = if exact_g {
        g1_exact(theta_i, alpha) * g1_exact(theta_o, alpha)
    } else {
        g1_rational(theta_i, alpha) * g1_rational(theta_o, alpha)
    };
    let mut out = [0.0; 3];
    for ch in 0..3 {
        let f = complex_fresnel(cos_d, f64::from(AU_ETA[ch]), f64::from(AU_K[ch]));
        out[ch] = f * d * g / (4.0 * wi.z * wo.z);
    }
    out
}

/// Random pairs of upper-hemisphere directions.
fn pairs(n: usize, seed: u64) -> Vec<(Vec3, Vec3)> {
    let mut rng = Rng::new(seed);
    (0..n).map(|_| (rng.upper(0.05), rng.upper(0.05))).collect()
}

#[test]
fn rough_conductor_equals_independent_evaluation() {
    for alpha in [0.1_f32, 0.3, 0.6] {
        let brdf = from_model(&rough_gold(alpha)).unwrap();
        for (wi, wo) in pairs(500, 9) {
            let ours = brdf.eval(wi, wo);
            let r = reference(wi, wo, f64::from(alpha), false);
            for ch in 0..3 {
                let tol = 1e-3 * r[ch].abs() + 1e-6;
                assert!(
                    (f64::from(ours[ch]) - r[ch]).abs() <= tol,
                    "α = {alpha}, wi = {wi}, wo = {wo}, channel {ch}: {} vs {}",
                    ours[ch],
                    r[ch]
                );
            }
            // The rational G1 is within 0.5 % of exact Smith per factor (Walter et al. 2007).
            let exact = reference(wi, wo, f64::from(alpha), true);
            assert!(
                (f64::from(ours.x) - exact[0]).abs() <= 1.2e-2 * exact[0] + 1e-6,
                "exact Smith: {} vs {}",
                ours.x,
                exact[0]
            );
        }
    }
}

/// The Python of the Mitsuba 3 comparison: reads JSON pairs on stdin, prints `f cos θi` of `roughconductor`.
const MITSUBA_SCRIPT: &str = r#"
import sys, json
import mitsuba as mi
mi.set_variant('scalar_rgb')
d = json.loads(sys.stdin.read())
bsdf = mi.load_dict({'type': 'roughconductor', 'distribution': 'beckmann', 'alpha': d['alpha'],
                     'eta': {'type': 'rgb', 'value': d['eta']}, 'k': {'type': 'rgb', 'value': d['k']}})
ctx = mi.BSDFContext()
out = []
for wi, wo in d['pairs']:
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(wo)
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    v = bsdf.eval(ctx, si, mi.Vector3f(wi))
    out.append([float(v[0]), float(v[1]), float(v[2])])
print(json.dumps(out))
"#;

/// The Python interpreter with Mitsuba: `LUSTRE_MITSUBA_PYTHON`, else the workspace's `.mitsuba-venv`.
fn mitsuba_python() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("LUSTRE_MITSUBA_PYTHON") {
        return Some(PathBuf::from(p));
    }
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../.mitsuba-venv/bin/python");
    p.exists().then_some(p)
}

/// Skips the Mitsuba comparison with `why`, or fails when the environment
/// variable `CI` is set (CI installs Mitsuba and must not skip), as
/// `tests/tests/mitsuba_equivalence.rs` does.
fn skip_or_fail_under_ci(why: &str) {
    if std::env::var_os("CI").is_some() {
        panic!("Mitsuba is required under CI: {why}; run `cargo xtask reference --install-only`");
    }
    eprintln!("skipping the Mitsuba comparison: {why}");
}

#[test]
fn rough_conductor_matches_mitsuba_roughconductor() {
    let Some(python) = mitsuba_python() else {
        skip_or_fail_under_ci("no .mitsuba-venv (or LUSTRE_MITSUBA_PYTHON)");
        return;
    };
    let alpha = 0.3_f32;
    let pairs = pairs(200, 21);
    let fmt = |v: Vec3| format!("[{},{},{}]", v.x, v.y, v.z);
    let json = format!(
        "{{\"alpha\":{alpha},\"eta\":[{},{},{}],\"k\":[{},{},{}],\"pairs\":[{}]}}",
        AU_ETA[0],
        AU_ETA[1],
        AU_ETA[2],
        AU_K[0],
        AU_K[1],
        AU_K[2],
        pairs
            .iter()
            .map(|(i, o)| format!("[{},{}]", fmt(*i), fmt(*o)))
            .collect::<Vec<_>>()
            .join(",")
    );
    let child = Command::new(&python)
        .args(["-c", MITSUBA_SCRIPT])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn();
    let Ok(mut child) = child else {
        skip_or_fail_under_ci(&format!("cannot run {}", python.display()));
        return;
    };
    use std::io::Write;
    child
        .stdin
        .take()
        .unwrap()
        .write_all(json.as_bytes())
        .unwrap();
    let out = child.wait_with_output().unwrap();
    if !out.status.success() {
        skip_or_fail_under_ci(&String::from_utf8_lossy(&out.stderr));
        return;
    }
    let text = String::from_utf8(out.stdout).unwrap();
    let values: Vec<f64> = text
        .trim()
        .trim_start_matches('[')
        .trim_end_matches(']')
        .split([',', '[', ']'])
        .filter(|s| !s.trim().is_empty())
        .map(|s| s.trim().parse().unwrap())
        .collect();
    assert_eq!(values.len(), 3 * pairs.len());
    let brdf = from_model(&rough_gold(alpha)).unwrap();
    for (j, (wi, wo)) in pairs.iter().enumerate() {
        let ours = brdf.eval(*wi, *wo) * wi.z;
        for ch in 0..3 {
            let m = values[3 * j + ch];
            assert!(
                (f64::from(ours[ch]) - m).abs() <= 2e-3 * m.abs() + 1e-5,
                "wi = {wi}, wo = {wo}, channel {ch}: ours {} vs Mitsuba {m}",
                ours[ch]
            );
        }
    }
}
