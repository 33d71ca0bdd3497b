//! Special functions the models need: the complementary error function.

/// Complementary error function `erfc(x)` with fractional error below 1.2e-7 everywhere (the Chebyshev fit of Press et al., *Numerical Recipes*, 2nd ed., section 6.2, `erfcc`), in `f64`.
pub fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let poly = -z * z - 1.265_512_23
        + t * (1.000_023_68
            + t * (0.374_091_96
                + t * (0.096_784_18
                    + t * (-0.186_288_06
                        + t * (0.278_868_07
                            + t * (-1.135_203_98
                                + t * (1.488_515_87 + t * (-0.822_152_23 + t * 0.170_872_77))))))));
    let r = t * poly.exp();
    if x >= 0.0 { r } else { 2.0 - r }
}

/// Error function `erf(x) = 1 - erfc(x)` (Abramowitz & Stegun 7.1.2).
pub fn erf(x: f64) -> f64 {
    1.0 - erfc(x)
}
