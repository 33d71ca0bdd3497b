// Tone map (the display step after light accumulation, Diefenbach & Badler
// 1997, section 7.2): linear HDR radiance -> exposure -> clamp or Reinhard ->
// sRGB, drawn as one full-screen triangle. Prepended with common/color.wgsl,
// whose notation table applies here.
//
// Notation
// | symbol      | meaning                                               | unit |
// |-------------|-------------------------------------------------------|------|
// | hdr         | the HDR target, read texel for texel (no filtering)   | W/(m^2 sr) |
// | tone_operator | 0 = clamp, 1 = Reinhard                               | -    |
// | encode_srgb | 1: write V; 0: write c (an *Srgb target encodes it)   | -    |

struct TonemapUniforms {
    exposure: f32,
    tone_operator: u32,
    encode_srgb: u32,
    pad: u32,
}

@group(0) @binding(0) var<uniform> uniforms: TonemapUniforms;
@group(0) @binding(1) var hdr: texture_2d<f32>;

@vertex
fn vs_main(@builtin(vertex_index) index: u32) -> @builtin(position) vec4f {
    // One triangle covering the viewport: (-1,-1), (3,-1), (-1,3).
    let uv = vec2f(f32((index << 1u) & 2u), f32(index & 2u));
    return vec4f(uv * 2.0 - 1.0, 0.0, 1.0);
}

/// One channel: L -> x -> c -> V (or c).
fn map_channel(radiance: f32) -> f32 {
    let x = exposed(radiance, uniforms.exposure);
    var c = tone_clamp(x);
    if uniforms.tone_operator == 1u {
        c = tone_reinhard(x);
    }
    if uniforms.encode_srgb == 1u {
        return srgb_encode(c);
    }
    return c;
}

@fragment
fn fs_main(@builtin(position) position: vec4f) -> @location(0) vec4f {
    let texel = textureLoad(hdr, vec2i(position.xy), 0);
    return vec4f(map_channel(texel.r), map_channel(texel.g), map_channel(texel.b), 1.0);
}
