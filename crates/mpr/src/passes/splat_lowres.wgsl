// Splats at a lower resolution (lustre_mpr::passes::splat_lowres): the splat
// pass of Stürzlinger & Bastos 1997, section 2.2, drawn f times smaller per
// axis, then added at full resolution by a joint bilateral upsampling.
//
// Notation
// | symbol | meaning                                                          | unit       |
// |--------|------------------------------------------------------------------|------------|
// | f      | the reduction factor per axis                                    | 1          |
// | q      | a full-resolution pixel; its centre q + 1/2                      | px         |
// | u      | q's centre in low-resolution pixel coordinates, (q + 1/2)/f - 1/2 | low px     |
// | d      | depth-buffer value (reverse Z, proportional to 1/z)              | 1          |
// | tau    | relative depth difference at which a weight falls to 1/e         | 1          |
// | L      | the low-resolution splat radiance                                | W/(m^2 sr) |
//
// fs_guide (low resolution, two targets): each low-resolution pixel i takes the
// surface id and depth of the full-resolution pixel f i + f/2 (per axis), the
// guide the splats are restricted by (fs_splat_id of splat.wgsl reads the id)
// and upsampled along; vs_splat_low shifts the splats by half a
// full-resolution pixel so that the low-resolution sample lies on that
// pixel's centre: each sample is the full-resolution pixel's value.
//
// fs_upsample (full resolution, added into the HDR target): a joint bilateral
// upsampling (Kopf et al. 2007) guided by surface id and depth: the bilinear
// weights of the 2x2 low-resolution samples around the pixel, each multiplied
// by [same surface id] and a Gaussian of the relative depth difference,
// renormalised. Where none of the four sees the pixel's surface, the 4x4
// samples around it with inverse squared distance weights; where none of
// those either, nothing is added. Samples of another surface never contribute.
//
// CPU twin: lustre_mpr::passes::splat_lowres::{guides_cpu, upsample_cpu}.

struct LowResParams {
    // Full-resolution width and height.
    full_size: vec2u,
    // Low-resolution width and height.
    low_size: vec2u,
    // f.
    factor: f32,
    // tau.
    depth_tau: f32,
    pad: vec2f,
}

const NO_SURFACE: u32 = 0xffffffffu;

@group(0) @binding(0) var<uniform> params: LowResParams;
@group(0) @binding(1) var full_ids: texture_2d<u32>;
@group(0) @binding(2) var full_depth: texture_depth_2d;
@group(0) @binding(3) var low_ids: texture_2d<u32>;
@group(0) @binding(4) var low_depth: texture_2d<f32>;
@group(0) @binding(5) var low_radiance: texture_2d<f32>;

@vertex
fn vs_main(@builtin(vertex_index) index: u32) -> @builtin(position) vec4f {
    // One triangle covering the viewport: (-1,-1), (3,-1), (-1,3).
    let uv = vec2f(f32((index << 1u) & 2u), f32(index & 2u));
    return vec4f(uv * 2.0 - 1.0, 0.0, 1.0);
}

struct Guide {
    @location(0) id: u32,
    @location(1) depth: f32,
}

@fragment
fn fs_guide(@builtin(position) pixel: vec4f) -> Guide {
    var out: Guide;
    // The full-resolution pixel holding the low-resolution pixel's centre.
    let centre = (floor(pixel.xy) + 0.5) * params.factor;
    if any(centre >= vec2f(params.full_size)) {
        // A partial last row or column: outside the splats' viewport.
        out.id = NO_SURFACE;
        out.depth = 0.0;
        return out;
    }
    let q = vec2i(floor(centre));
    out.id = textureLoad(full_ids, q, 0).r;
    out.depth = textureLoad(full_depth, q, 0);
    return out;
}

// The depth term of a sample at depth d_low for a pixel at depth d.
fn depth_weight(d: f32, d_low: f32) -> f32 {
    let rel = abs(d_low - d) / max(d, 1e-30);
    let x = rel / params.depth_tau;
    return exp(-x * x);
}

@fragment
fn fs_upsample(@builtin(position) pixel: vec4f) -> @location(0) vec4f {
    let q = vec2i(pixel.xy);
    let id = textureLoad(full_ids, q, 0).r;
    if id == NO_SURFACE {
        discard;
    }
    let d = textureLoad(full_depth, q, 0);
    let u = (vec2f(q) + 0.5) / params.factor - 0.5;
    let base = vec2i(floor(u));
    let t = u - floor(u);
    let low = vec2i(params.low_size);
    var sum = vec3f(0.0);
    var weight = 0.0;
    for (var j = 0; j < 2; j++) {
        for (var i = 0; i < 2; i++) {
            let s = base + vec2i(i, j);
            if any(s < vec2i(0)) || any(s >= low) || textureLoad(low_ids, s, 0).r != id {
                continue;
            }
            let wx = select(1.0 - t.x, t.x, i == 1);
            let wy = select(1.0 - t.y, t.y, j == 1);
            let w = wx * wy * depth_weight(d, textureLoad(low_depth, s, 0).r);
            sum += w * textureLoad(low_radiance, s, 0).rgb;
            weight += w;
        }
    }
    if weight > 0.0 {
        return vec4f(sum / weight, 0.0);
    }
    for (var j = -1; j < 3; j++) {
        for (var i = -1; i < 3; i++) {
            let s = base + vec2i(i, j);
            if any(s < vec2i(0)) || any(s >= low) || textureLoad(low_ids, s, 0).r != id {
                continue;
            }
            let r = vec2f(s) - u;
            let w = depth_weight(d, textureLoad(low_depth, s, 0).r) / (1.0 + dot(r, r));
            sum += w * textureLoad(low_radiance, s, 0).rgb;
            weight += w;
        }
    }
    if weight > 0.0 {
        return vec4f(sum / weight, 0.0);
    }
    discard;
}
