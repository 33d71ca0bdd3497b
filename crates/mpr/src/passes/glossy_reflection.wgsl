// "How it is reflected" (Bastos et al. 1999, section 8.2): the reflected
// image M convolved with the resampled kernel K over the pixels M covers
// and, where the frame's surface ids are given, the reflector's own pixels,
// then modulated by R(cos θ) from the flipped 1D table. CPU twin:
// lustre_ibr::glossy (convolve, modulate).
//
// Notation: a pixel's ray has direction normalize(forward + right x + up y)
// with x = (px - cx)/fx, y = (cy - py)/fy (lustre_ibr::view); cos θ is
// |ray · n| for the reflector's normal n; the table holds R at
// cos θ = (k + 1/2)/m, linearly interpolated with clamp to edge.

struct Params {
    // The reflected view (its eye unused here).
    eye: vec4f,
    right: vec4f,
    up: vec4f,
    forward: vec4f,
    // focal (fx, fy), principal point (cx, cy).
    focal_principal: vec4f,
    // Reflector plane: normal (xyz) and w, n.p + w = 0 on it.
    normal: vec4f,
    // width, height, tap count, table length.
    counts: vec4u,
    // x: the reflector's surface id, y: 1 when the id target masks the
    // domain, z: 1 for the kernel sized by each pixel's depth (section 9),
    // w: frame pixels per M pixel (lustre_ibr::resolution; the id target is
    // the frame's).
    mask: vec4u,
    // By depth: fy tan(phi_max), the mean d/(e + d), M's reverse-Z near,
    // K's texels per side.
    by_depth: vec4f,
};

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var m_color: texture_2d<f32>;
@group(0) @binding(2) var m_depth: texture_depth_2d;
// (dx, dy, weight, 0) per tap.
@group(0) @binding(3) var<storage, read> taps: array<vec4f>;
// R per table entry (rgb).
@group(0) @binding(4) var<storage, read> table: array<vec4f>;
@group(0) @binding(5) var out_term: texture_storage_2d<rgba32float, write>;
// The frame's surface ids (a 1x1 stand-in when unmasked).
@group(0) @binding(6) var ids: texture_2d<u32>;
// K's weights, row-major (by depth).
@group(0) @binding(7) var<storage, read> kernel: array<f32>;

// The most pixels a kernel sized by depth reaches (lustre_ibr::glossy::MAX_KERNEL_REACH).
const MAX_REACH: i32 = 48;

fn covered(p: vec2i) -> bool {
    return textureLoad(m_depth, p, 0) > 0.0;
}

// The reflector's own pixel: the id at the frame pixel in the centre of M's
// pixel p (lustre_ibr::resolution::coarse_mask).
fn in_mask(p: vec2i) -> bool {
    if (params.mask.y != 1u) {
        return false;
    }
    let s = i32(max(params.mask.w, 1u));
    let q = min(p * s + vec2i(s / 2), vec2i(textureDimensions(ids)) - 1);
    return textureLoad(ids, q, 0).x == params.mask.x;
}

// A void pixel: the reflector's own, uncovered by M and by its eight
// neighbours, where the mirrored ray left the scene and M is black; an
// uncovered pixel beside a covered one is a crack, left out
// (lustre_ibr::glossy::is_void).
fn is_void(p: vec2i) -> bool {
    if (!in_mask(p) || covered(p)) {
        return false;
    }
    let size = vec2i(params.counts.xy);
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            let s = p + vec2i(dx, dy);
            if (s.x >= 0 && s.y >= 0 && s.x < size.x && s.y < size.y && covered(s)) {
                return false;
            }
        }
    }
    return true;
}

fn reflectance(c: f32) -> vec3f {
    let m = params.counts.w;
    if (!(c > 0.0) || m == 0u) {
        return vec3f(0.0);
    }
    if (m == 1u) {
        return table[0].xyz;
    }
    let x = clamp(min(c, 1.0) * f32(m) - 0.5, 0.0, f32(m - 1u));
    let i = min(u32(floor(x)), m - 2u);
    let t = x - f32(i);
    return table[i].xyz * (1.0 - t) + table[i + 1u].xyz * t;
}

fn ray_at(pixel: vec2f) -> vec3f {
    let f = params.focal_principal;
    let x = (pixel.x - f.z) / f.x;
    let y = (f.w - pixel.y) / f.y;
    return normalize(params.forward.xyz + params.right.xyz * x + params.up.xyz * y);
}

// d/(e + d) at p, negative where M is uncovered or the ray misses the plane
// (lustre_ibr::glossy::depth_ratio).
fn depth_ratio(p: vec2i) -> f32 {
    let depth = textureLoad(m_depth, p, 0);
    if (!(depth > 0.0)) {
        return -1.0;
    }
    let z = params.by_depth.z / depth;
    let d = ray_at(vec2f(p) + 0.5);
    let denom = dot(d, params.normal.xyz);
    if (abs(denom) < 1e-6) {
        return -1.0;
    }
    let t = -(dot(params.normal.xyz, params.eye.xyz) + params.normal.w) / denom;
    let e = t * dot(d, params.forward.xyz);
    if (!(e > 0.0) || z < e) {
        return -1.0;
    }
    return (z - e) / z;
}

// K's bilinear weight at (u, v) in its half-widths (lustre_ibr::glossy::kernel_lookup).
fn kernel_at(u: f32, v: f32) -> f32 {
    let size = u32(params.by_depth.w);
    let n = f32(size);
    let x = (u + 1.0) * 0.5 * n - 0.5;
    let y = (v + 1.0) * 0.5 * n - 0.5;
    if (x < -0.5 || y < -0.5 || x > n - 0.5 || y > n - 0.5) {
        return 0.0;
    }
    let cx = clamp(x, 0.0, n - 1.0);
    let cy = clamp(y, 0.0, n - 1.0);
    let i = u32(floor(cx));
    let j = u32(floor(cy));
    let i1 = min(i + 1u, size - 1u);
    let j1 = min(j + 1u, size - 1u);
    let fx = cx - f32(i);
    let fy = cy - f32(j);
    return kernel[j * size + i] * (1.0 - fx) * (1.0 - fy)
        + kernel[j * size + i1] * fx * (1.0 - fy)
        + kernel[j1 * size + i] * (1.0 - fx) * fy
        + kernel[j1 * size + i1] * fx * fy;
}

// M * K at p with the kernel sized by p's depth (lustre_ibr::glossy::convolve_by_depth).
fn blurred_by_depth(p: vec2i) -> vec3f {
    var ratio = depth_ratio(p);
    if (ratio < 0.0) {
        ratio = params.by_depth.y;
    }
    let radius = params.by_depth.x * ratio;
    if (!(radius >= 0.5)) {
        if (covered(p)) {
            return textureLoad(m_color, p, 0).xyz;
        }
        return vec3f(0.0);
    }
    let reach = min(i32(ceil(radius)), MAX_REACH);
    let size = vec2i(params.counts.xy);
    var sum = vec3f(0.0);
    var weight = 0.0;
    for (var dy = -reach; dy <= reach; dy++) {
        for (var dx = -reach; dx <= reach; dx++) {
            let s = p + vec2i(dx, dy);
            if (s.x < 0 || s.y < 0 || s.x >= size.x || s.y >= size.y) {
                continue;
            }
            let t = kernel_at(f32(dx) / radius, f32(dy) / radius);
            if (!(t > 0.0)) {
                continue;
            }
            if (covered(s)) {
                sum += textureLoad(m_color, s, 0).xyz * t;
                weight += t;
            } else if (is_void(s)) {
                weight += t;
            }
        }
    }
    if (weight > 0.0) {
        return sum / weight;
    }
    return vec3f(0.0);
}

@compute @workgroup_size(8, 8)
fn cs_main(@builtin(global_invocation_id) id: vec3u) {
    let size = params.counts.xy;
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    let p = vec2i(id.xy);
    if (!covered(p) && !in_mask(p)) {
        textureStore(out_term, p, vec4f(0.0));
        return;
    }
    var sum = vec3f(0.0);
    var weight = 0.0;
    if (params.mask.z == 1u) {
        let c = abs(dot(ray_at(vec2f(id.xy) + 0.5), params.normal.xyz));
        textureStore(out_term, p, vec4f(blurred_by_depth(p) * reflectance(c), 1.0));
        return;
    }
    for (var k = 0u; k < params.counts.z; k++) {
        let tap = taps[k];
        let s = p + vec2i(i32(tap.x), i32(tap.y));
        if (s.x < 0 || s.y < 0 || s.x >= i32(size.x) || s.y >= i32(size.y)) {
            continue;
        }
        if (covered(s)) {
            sum += textureLoad(m_color, s, 0).xyz * tap.z;
            weight += tap.z;
        } else if (is_void(s)) {
            weight += tap.z;
        }
    }
    var blurred = vec3f(0.0);
    if (weight > 0.0) {
        blurred = sum / weight;
    }
    let c = abs(dot(ray_at(vec2f(id.xy) + 0.5), params.normal.xyz));
    textureStore(out_term, p, vec4f(blurred * reflectance(c), 1.0));
}
