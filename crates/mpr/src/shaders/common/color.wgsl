// Colour encoding shared by the passes: exposure, tone operators, sRGB OETF.
//
// Notation (DESIGN.md "Conventions"; Reinhard et al. 2002, eq. 3; IEC 61966-2-1)
// | symbol  | meaning                                             | unit         |
// |---------|-----------------------------------------------------|--------------|
// | L       | linear Rec.709 radiance, one channel                | W/(m^2 sr)   |
// | k       | exposure: scale from radiance to display units      | m^2 sr / W   |
// | x       | exposed value k L, clamped to [0, F32_MAX]          | 1            |
// | c       | display-referred linear value in [0, 1]             | 1            |
// | V       | sRGB-encoded value in [0, 1]                        | 1            |
// Operators: clamp c = min(x, 1); Reinhard c = x / (1 + x).

/// Largest finite f32; infinities are clamped to it so Reinhard gives 1.
const F32_MAX: f32 = 3.40282347e38;

/// Exposed value x = k L with NaN and negatives sent to 0 and +inf to F32_MAX.
fn exposed(radiance: f32, exposure: f32) -> f32 {
    let x = radiance * exposure;
    return select(0.0, min(x, F32_MAX), x > 0.0);
}

/// Clamp operator: c = min(x, 1).
fn tone_clamp(x: f32) -> f32 {
    return min(x, 1.0);
}

/// Reinhard's global operator per channel (Reinhard et al. 2002, eq. 3 with L_white = inf): c = x / (1 + x).
fn tone_reinhard(x: f32) -> f32 {
    return min(x / (1.0 + x), 1.0);
}

/// The sRGB opto-electronic transfer function (IEC 61966-2-1): c in [0, 1] -> V.
fn srgb_encode(c: f32) -> f32 {
    if c <= 0.0031308 {
        return 12.92 * c;
    }
    return 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}
