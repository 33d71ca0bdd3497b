// The blending pass of Bastos et al. 1999 (section 8.2, figure 4's last
// step): the reflector's view-dependent term ks (M * K) R, computed over the
// reflected image by glossy_reflection.wgsl, added into the frame's HDR
// target at the pixels where the reflector itself is the visible surface
// (the surface-id target: the reflector's stencil mask).
//
// Notation
// | symbol | meaning                                                   | unit       |
// |--------|-----------------------------------------------------------|------------|
// | term   | (M * K) R at the pixel                                     | W/(m^2 sr) |
// | ks     | the reflector's specular magnitude (its glossy lobe's)     | 1          |
// | id     | the surface seen at the pixel                              | -          |

struct Params {
    // rgb: ks.
    ks: vec4f,
    // x: the reflector's surface id, y: frame pixels per term pixel
    // (lustre_ibr::resolution).
    surface: vec4u,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var term: texture_2d<f32>;
@group(0) @binding(2) var ids: texture_2d<u32>;

@vertex
fn vs_main(@builtin(vertex_index) index: u32) -> @builtin(position) vec4f {
    // One triangle covering the viewport: (-1,-1), (3,-1), (-1,3).
    let uv = vec2f(f32((index << 1u) & 2u), f32(index & 2u));
    return vec4f(uv * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn fs_main(@builtin(position) pixel: vec4f) -> @location(0) vec4f {
    let p = vec2i(pixel.xy);
    if textureLoad(ids, p, 0).x != params.surface.x {
        discard;
    }
    let s = max(params.surface.y, 1u);
    if s == 1u {
        return vec4f(textureLoad(term, p, 0).xyz * params.ks.xyz, 0.0);
    }
    // Bilinear over the coarse term's valid pixels (alpha 1), renormalised
    // (lustre_ibr::resolution::upsample).
    let c = (pixel.xy) / f32(s) - 0.5;
    let base = floor(c);
    let f = c - base;
    let size = vec2i(textureDimensions(term));
    var sum = vec3f(0.0);
    var weight = 0.0;
    for (var k = 0; k < 4; k++) {
        let d = vec2i(k & 1, k >> 1u);
        let q = vec2i(base) + d;
        if (q.x < 0 || q.y < 0 || q.x >= size.x || q.y >= size.y) {
            continue;
        }
        let w = select(1.0 - f.x, f.x, d.x == 1) * select(1.0 - f.y, f.y, d.y == 1);
        let t = textureLoad(term, q, 0);
        if (t.w > 0.5 && w > 0.0) {
            sum += t.xyz * w;
            weight += w;
        }
    }
    if (weight > 0.0) {
        sum /= weight;
    }
    return vec4f(sum * params.ks.xyz, 0.0);
}
