//! Stürzlinger & Bastos 1997, section 3.2: the tabulated BRDF meets its error bound on fresh random directions, independent of its grid and of its validation set.

use glam::Vec2;
use lustre_brdf::models::{ModifiedPhong, OrenNayarFull, Ward, WardNormalisation};
use lustre_brdf::table::{BrdfTable, TableLayout, validation_pairs};
use lustre_brdf::{Brdf, BrdfError};
use lustre_geometry::Rgb;

/// Largest `|t - f| / max(f, 0.01 f_peak)` over fresh pairs, computed here without the table's own error routine.
fn fresh_error(table: &BrdfTable, brdf: &dyn Brdf, seed: u64, count: usize) -> f32 {
    let pairs = validation_pairs(seed, count);
    let exact: Vec<Rgb> = pairs.iter().map(|&(i, o)| brdf.eval(i, o)).collect();
    let peak = exact.iter().fold(Rgb::ZERO, |a, &c| a.max(c));
    let mut worst = 0.0f32;
    for (&(wi, wo), f) in pairs.iter().zip(exact) {
        let t = table.eval(wi, wo);
        for ch in 0..3 {
            let denom = f[ch].max(0.01 * peak[ch]);
            worst = worst.max((t[ch] - f[ch]).abs() / denom);
        }
    }
    worst
}

#[test]
fn isotropic_tables_meet_the_bound_on_fresh_directions() {
    let models: Vec<(Box<dyn Brdf>, f32)> = vec![
        (
            Box::new(OrenNayarFull::new(Rgb::new(0.9, 0.5, 0.2), 0.6).unwrap()),
            0.03,
        ),
        (
            Box::new(ModifiedPhong::new(Rgb::splat(0.3), Rgb::splat(0.6), 4.0).unwrap()),
            0.05,
        ),
    ];
    for (brdf, bound) in models {
        let table = BrdfTable::with_error_bound(brdf.as_ref(), bound).unwrap();
        assert_eq!(table.layout, TableLayout::Isotropic, "{}", brdf.name());
        // Seeds other than the builder's validation seed: directions it never saw.
        for seed in [1, 2, 3] {
            let e = fresh_error(&table, brdf.as_ref(), seed, 20_000);
            assert!(
                e <= bound,
                "{} at resolution {}: error {e} > bound {bound}",
                brdf.name(),
                table.resolution
            );
        }
    }
}

#[test]
fn anisotropic_model_gets_the_four_dimensional_table_and_meets_the_bound() {
    // A 4D table is coarse (32 polar × 64 azimuth nodes at most), so the
    // lobe is broad and the bound loose: Ward with αx = 0.8, αy = 0.4
    // within 80 % of its value (or of 1 % of its peak).
    let ward = Ward::new(
        Rgb::splat(0.5),
        Rgb::splat(0.3),
        0.8,
        0.4,
        WardNormalisation::Original,
    )
    .unwrap();
    let bound = 0.8;
    let table = BrdfTable::with_error_bound(&ward, bound).unwrap();
    assert_eq!(table.layout, TableLayout::Anisotropic);
    let e = fresh_error(&table, &ward, 11, 20_000);
    assert!(e <= bound, "resolution {}: {e} > {bound}", table.resolution);
}

#[test]
fn table_is_exact_at_its_nodes_and_samples_consistently() {
    // At a grid node the interpolation returns the stored value f(node) itself.
    let brdf = OrenNayarFull::new(Rgb::splat(0.8), 0.4).unwrap();
    let n = 16;
    let table = BrdfTable::new(&brdf, TableLayout::Isotropic, n).unwrap();
    let theta = |k: usize| k as f32 * lustre_brdf::table::TABLE_MAX_THETA / (n - 1) as f32;
    let dir = |t: f32, p: f32| glam::Vec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos());
    for (i, o, d) in [(0, 3, 0), (5, 9, 7), (15, 2, 15)] {
        let dphi = d as f32 * std::f32::consts::PI / (n - 1) as f32;
        let (wi, wo) = (dir(theta(i), dphi + 0.3), dir(theta(o), 0.3));
        let (t, f) = (table.eval(wi, wo), brdf.eval(wi, wo));
        assert!(
            (t - f).abs().max_element() <= 1e-4 * f.max_element(),
            "node {i} {o} {d}: {t} vs {f}"
        );
    }
    let wo = dir(0.7, 1.0);
    for k in 0..64 {
        let u = Vec2::new((k as f32 + 0.5) / 64.0, (k * 37 % 64) as f32 / 64.0);
        let Some(s) = table.sample(wo, u, 0.5) else {
            continue;
        };
        let w = table.eval(s.wi, wo) * s.wi.z / table.pdf(s.wi, wo);
        assert!((s.weight - w).abs().max_element() < 1e-5);
    }
}

#[test]
fn impossible_bounds_and_bad_resolutions_are_errors() {
    let phong = ModifiedPhong::new(Rgb::ZERO, Rgb::ONE, 5000.0).unwrap();
    assert!(matches!(
        BrdfTable::with_layout_and_error_bound(&phong, TableLayout::Isotropic, 1e-6),
        Err(BrdfError::ErrorBoundNotMet { .. })
    ));
    assert!(BrdfTable::with_error_bound(&phong, f32::NAN).is_err());
    assert!(BrdfTable::new(&phong, TableLayout::Isotropic, 1).is_err());
    assert!(BrdfTable::new(&phong, TableLayout::Anisotropic, 1000).is_err());
}
