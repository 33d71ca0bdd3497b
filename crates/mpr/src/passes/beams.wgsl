// Light beams on receivers (Duvenhage, Bouatouch & Kourie 2010, sections 3.1
// and 4.3): every scene triangle redrawn over the depth pre-pass (equal depth,
// additive), and per fragment every beam that may hold it evaluated: the
// paper's linear traversal of all beams, or the hierarchy over the beams'
// slab boxes (its section 5.2, future work). A beam adds
//   L += f_r(wi, wo) E,  wi = -d,
// E = Phi_s / A_perp cos(theta) inside a specular beam (equation 1),
// E = Phi_s / A_perp cos(theta) min(P_E, 1) for a glossy one (figures 11, 12),
// negative for shadow beams. The CPU twin is lustre-beams' Beam::arrival
// (passes/beams.rs: beam_pixels_cpu); every function below mirrors the one of
// lustre-beams named beside it. A receiver's diffuse map scales its kd at the
// fragment's uv (common/diffuse_map.wgsl). Needs the BRDF, material and
// diffuse map modules before it (beams.rs: beams_wgsl).
//
// Notation
// | symbol     | meaning                                                          | unit      |
// |------------|------------------------------------------------------------------|-----------|
// | P          | the fragment's world position (F in the paper)                   | m         |
// | n_F        | the beam's average wavefront normal: the flux plane's normal     | -         |
// | X_i        | where vertex ray i crosses the flux plane through P (A_F, B_F, C_F) | m      |
// | A_perp     | area of the flux triangle X_0 X_1 X_2                            | m²        |
// | b_i        | P's barycentrics in the flux triangle                            | -         |
// | d          | the vertex directions interpolated with max(b_i, 0), unit        | -         |
// | sigma²     | per-axis variance of the glossy scatter angle (0: specular)      | rad²      |
// | P_E        | volume under the scatter Gaussian over the domain ABC            | -         |
// | E          | irradiance from one beam at P                                    | W/m²      |

const SCATTER_REFLECT: u32 = 0u;
const SCATTER_REFRACT: u32 = 1u;

const SPLIT_DOMAIN: u32 = 0u;
const SPLIT_PAPER: u32 = 1u;

const VOLUME_FACETS: u32 = 0u;

// Whether the shader holds the paper's planar facets (equation 5 and the
// split points of figures 11 and 12) beside the integrated volume. beams.rs
// compiles it without them when no beam uses them: llvmpipe runs a branch
// that no lane takes under an empty mask, and the facets' code was about
// 30 % of the pass there.
const FACET_VOLUMES: bool = true;

const PI: f32 = 3.14159265358979;

// 8-point Gauss-Legendre nodes (positive half) and weights.
const GL8_X = array<f32, 4>(0.18343464, 0.5255324, 0.7966665, 0.9602899);
const GL8_W = array<f32, 4>(0.3626838, 0.31370665, 0.22238103, 0.10122854);
// Panels per fan edge (lustre-brdf's INTEGRATED_PANELS).
const INTEGRATED_PANELS: u32 = 4u;

// One beam (GpuBeam in beams.rs; lustre-beams' Beam).
struct GpuBeam {
    vertices: array<vec4f, 3>,
    directions: array<vec4f, 3>,
    // The directions bounding a glossy beam's support (Beam::support_directions).
    support: array<vec4f, 3>,
    // The scatterer's vertex normals on the light's side (for the split point).
    normals: array<vec4f, 3>,
    // rgb: Phi_s (negative for shadow beams); w: sigma², 0 for a specular beam.
    flux: vec4f,
    // xyz: the generator plane's unit normal towards the beam; w: its offset.
    generator: vec4f,
    // xyz: n_F; w: eta of a refracted beam (far index over near index).
    wavefront: vec4f,
    // xyz: the light's position.
    light: vec4f,
    // SCATTER_REFLECT, SCATTER_REFRACT or straight (2).
    scatter: u32,
    // SPLIT_DOMAIN, SPLIT_PAPER or rescattered (2).
    split: u32,
    // VOLUME_FACETS (the paper's) or the integrated Gaussian (1).
    volume: u32,
    pad: u32,
}

// A node of the beam hierarchy (lustre-beams' HierarchyNode): a leaf's items
// are items[link .. link + count]; an inner node's left child follows it, its
// right child is at link.
struct BeamNode {
    min: vec3f,
    link: u32,
    max: vec3f,
    count: u32,
}

// One slab box of a beam: its beam and the range [lo, hi) of n_F . P it
// covers, so that a beam is counted in only one of its boxes.
struct BeamItem {
    beam: u32,
    pad: u32,
    lo: f32,
    hi: f32,
}

struct BeamSettings {
    // The hierarchy's region (the scene's box): points outside are evaluated linearly.
    bounds_min: vec3f,
    // 1: traverse the hierarchy; 0: every beam (the paper's linear traversal).
    hierarchy: u32,
    bounds_max: vec3f,
    beam_count: u32,
    node_count: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

@group(1) @binding(0) var<storage, read> materials: array<GpuMaterial>;
@group(1) @binding(1) var<storage, read> beams: array<GpuBeam>;
@group(1) @binding(2) var<storage, read> nodes: array<BeamNode>;
@group(1) @binding(3) var<storage, read> items: array<BeamItem>;
// A storage buffer, not a uniform block: lavapipe recompiles a fragment
// shader whose branches read uniforms at every bind group change (beams.rs).
@group(1) @binding(4) var<storage, read> settings: BeamSettings;
@group(1) @binding(5) var diffuse_maps: texture_2d_array<f32>;
@group(1) @binding(6) var diffuse_map_sampler: sampler;

struct VertexOutput {
    // Invariant, computed exactly as depth.wgsl's vs_main: the equal-depth test needs bit-identical depth.
    @builtin(position) @invariant clip: vec4f,
    //clip_distances: @builtin(clip_distances) clip_distances: array<f32, 1>,
    @location(0) world: vec3f,
    @location(1) normal: vec3f,
    @location(2) @interpolate(flat) material: u32,
    @location(3) uv: vec2f,
}

@vertex
fn vs_main(
    @location(0) position: vec3f,
    @location(2) normal: vec3f,
    @location(3) material: u32,
    @location(6) uv: vec2f,
) -> VertexOutput {
    var out: VertexOutput;
    out.clip = view.view_projection * vec4f(position, 1.0);
    //clip_distances: out.clip_distances[0] = view_clip_distance(position);
    out.world = position;
    out.normal = normal;
    out.material = material;
    out.uv = uv;
    return out;
}

// Finite: neither infinite nor NaN (by the exponent bits; comparisons may be folded away).
fn is_finite(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) != 0x7f800000u;
}

fn normalize_or_zero(v: vec3f) -> vec3f {
    let l = length(v);
    if l > 0.0 && is_finite(l) {
        return v / l;
    }
    return vec3f(0.0);
}

fn normalize2_or_zero(v: vec2f) -> vec2f {
    let l = length(v);
    if l > 0.0 && is_finite(l) {
        return v / l;
    }
    return vec2f(0.0);
}

fn perp_dot(a: vec2f, b: vec2f) -> f32 {
    return a.x * b.y - a.y * b.x;
}

// The flux triangle of a beam's rays at the flux plane through P (flux_triangle).
struct FluxTriangle {
    x: array<vec3f, 3>,
    area: f32,
    b: vec3f,
    ok: bool,
}

fn flux_triangle(bi: u32, support: bool, p: vec3f) -> FluxTriangle {
    var ft: FluxTriangle;
    let n = beams[bi].wavefront.xyz;
    // Upstream of every vertex no ray reaches the plane (Beam::flux_triangle).
    var ahead = false;
    for (var i = 0u; i < 3u; i++) {
        let o = beams[bi].vertices[i].xyz;
        var d = beams[bi].directions[i].xyz;
        if support {
            d = beams[bi].support[i].xyz;
        }
        let t = dot(p - o, n) / dot(d, n);
        ahead = ahead || t > 0.0;
        ft.x[i] = o + t * d;
    }
    let total = dot(cross(ft.x[1] - ft.x[0], ft.x[2] - ft.x[0]), n);
    ft.ok = ahead && total != 0.0 && is_finite(total);
    if !ft.ok {
        return ft;
    }
    ft.b = vec3f(
        dot(cross(ft.x[1] - p, ft.x[2] - p), n),
        dot(cross(ft.x[2] - p, ft.x[0] - p), n),
        dot(cross(ft.x[0] - p, ft.x[1] - p), n),
    ) / total;
    ft.area = 0.5 * abs(total);
    return ft;
}

fn inside(ft: FluxTriangle) -> bool {
    return ft.ok && all(ft.b >= vec3f(0.0));
}

// Beam::in_front: strictly on the beam's side of the generator plane.
fn in_front(bi: u32, p: vec3f) -> bool {
    let g = beams[bi].generator;
    return dot(g.xyz, p) - g.w > 0.0;
}

// construction::reflect.
fn mirror_direction(w: vec3f, n: vec3f) -> vec3f {
    return w - 2.0 * dot(w, n) * n;
}

// construction::refract (Snell's law); w = 0 on total internal reflection.
fn refracted_direction(w: vec3f, n: vec3f, eta: f32) -> vec4f {
    let cos_i = -dot(w, n);
    let r = 1.0 / eta;
    let sin2_t = r * r * max(1.0 - cos_i * cos_i, 0.0);
    if sin2_t >= 1.0 {
        return vec4f(0.0);
    }
    let cos_t = sqrt(1.0 - sin2_t);
    return vec4f(normalize(r * w + (r * cos_i - cos_t) * n), 1.0);
}

// A ray re-scattered from the scatterer's edge i -> j at parameter t, and where it crosses the flux plane through P.
struct EdgeRay {
    origin: vec3f,
    direction: vec3f,
    at: vec3f,
    ok: bool,
}

fn edge_ray(bi: u32, i: u32, j: u32, t: f32, p: vec3f) -> EdgeRay {
    var out: EdgeRay;
    let n = beams[bi].wavefront.xyz;
    let dw = mix(beams[bi].vertices[i].xyz, beams[bi].vertices[j].xyz, t);
    let normal = normalize_or_zero(mix(beams[bi].normals[i].xyz, beams[bi].normals[j].xyz, t));
    let w = normalize_or_zero(dw - beams[bi].light.xyz);
    var sd = w;
    switch beams[bi].scatter {
        case SCATTER_REFLECT: {
            sd = mirror_direction(w, normal);
        }
        case SCATTER_REFRACT: {
            let r = refracted_direction(w, normal, beams[bi].wavefront.w);
            if r.w == 0.0 {
                out.ok = false;
                return out;
            }
            sd = r.xyz;
        }
        default: {}
    }
    let den = dot(sd, n);
    out.ok = den > 0.0;
    if !out.ok {
        return out;
    }
    out.origin = dw;
    out.direction = sd;
    out.at = dw + sd * (dot(p - dw, n) / den);
    return out;
}

// Beam::rescattered_split (figure 12, step 3): D_F where the line from P
// through flux vertex k crosses the opposite edge, its parameter s, D_W on
// the scatterer's edge (at s, or with `matched` where its ray meets D_F,
// by bisection) and its re-scattered ray.
fn rescattered_split(bi: u32, ft: FluxTriangle, k: u32, p: vec3f, matched: bool) -> EdgeRay {
    var none: EdgeRay;
    none.ok = false;
    let n = beams[bi].wavefront.xyz;
    let i = (k + 1u) % 3u;
    let j = (k + 2u) % 3u;
    let towards = ft.x[k] - p;
    let edge = ft.x[j] - ft.x[i];
    let denom = dot(cross(edge, towards), n);
    if denom == 0.0 {
        return none;
    }
    let s = clamp(dot(cross(p - ft.x[i], towards), n) / denom, 0.0, 1.0);
    if !matched {
        return edge_ray(bi, i, j, s, p);
    }
    var lo = 0.0;
    var hi = 1.0;
    let edge2 = dot(edge, edge);
    for (var step = 0; step < 24; step++) {
        let mid = 0.5 * (lo + hi);
        let r = edge_ray(bi, i, j, mid, p);
        if !r.ok {
            return none;
        }
        if dot(r.at - ft.x[i], edge) / edge2 < s {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return edge_ray(bi, i, j, 0.5 * (lo + hi), p);
}

// An orthonormal pair perpendicular to unit n (Duff et al. 2017, as glam's any_orthonormal_pair).
fn basis_u(n: vec3f) -> vec3f {
    let sign = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    return vec3f(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
}

fn basis_v(n: vec3f) -> vec3f {
    let sign = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    return vec3f(b, sign + n.y * n.y * a, -n.y);
}

// Section 4.2.1: a ray from `origin` along `d` to the domain point phi * l,
// phi the angle between origin -> P and d, l the unit direction from P to `towards` in the flux plane.
fn to_domain(bi: u32, p: vec3f, origin: vec3f, d: vec3f, towards: vec3f) -> vec2f {
    let n = beams[bi].wavefront.xyz;
    let to_f = p - origin;
    let phi = atan2(length(cross(to_f, d)), dot(to_f, d));
    let l = towards - p;
    return normalize2_or_zero(vec2f(dot(l, basis_u(n)), dot(l, basis_v(n)))) * phi;
}

// ScatterDistribution::density: rho(phi) = exp(-|phi|²/(2 sigma²)) / (2 pi sigma²).
fn scatter_density(phi: vec2f, variance: f32) -> f32 {
    return exp(-dot(phi, phi) / (2.0 * variance)) / (2.0 * PI * variance);
}

// Equation 5's planar facet: area times the mean of its corner densities.
fn facet(p: vec2f, q: vec2f, r: vec2f, variance: f32) -> f32 {
    return 0.5 * abs(perp_dot(q - p, r - p))
        * (scatter_density(p, variance) + scatter_density(q, variance) + scatter_density(r, variance)) / 3.0;
}

// One fan edge O P Q of ScatterDistribution::triangle_volume_integrated:
// the integral of (1 - exp(-r(theta)²/(2 sigma²))) / (2 pi) over its angles.
fn fan_edge(p: vec2f, q: vec2f, variance: f32) -> f32 {
    let cross = perp_dot(p, q);
    let e = q - p;
    let len2 = dot(e, e);
    if cross == 0.0 || len2 == 0.0 || all(p == vec2f(0.0)) || all(q == vec2f(0.0)) {
        return 0.0;
    }
    let t0 = atan2(p.y, p.x);
    let sweep = atan2(cross, dot(p, q));
    let dist = abs(cross) / sqrt(len2);
    let foot = p - e * (dot(p, e) / len2);
    let tn = atan2(foot.y, foot.x);
    let h = sweep / f32(INTEGRATED_PANELS);
    var sum = 0.0;
    for (var panel = 0u; panel < INTEGRATED_PANELS; panel++) {
        let mid = t0 + (f32(panel) + 0.5) * h;
        for (var k = 0u; k < 4u; k++) {
            for (var side = 0u; side < 2u; side++) {
                let t = mid + select(-0.5, 0.5, side == 1u) * h * GL8_X[k];
                let r = dist / cos(t - tn);
                sum += GL8_W[k] * (1.0 - exp(-r * r / (2.0 * variance)));
            }
        }
    }
    return sum * 0.5 * h / (2.0 * PI);
}

// Beam::scatter_volume through ScatterDistribution::triangle_volume_split
// (section 4.2.2, figures 11 and 12): P_E over the domain ABC, clamped to one.
fn scatter_volume(bi: u32, ft: FluxTriangle, p: vec3f) -> f32 {
    let variance = beams[bi].flux.w;
    var v: array<vec2f, 3>;
    for (var i = 0u; i < 3u; i++) {
        v[i] = to_domain(bi, p, beams[bi].vertices[i].xyz, beams[bi].directions[i].xyz, ft.x[i]);
    }
    let a = v[0];
    let b = v[1];
    let c = v[2];
    if !FACET_VOLUMES || beams[bi].volume != VOLUME_FACETS {
        return min(abs(fan_edge(a, b, variance) + fan_edge(b, c, variance) + fan_edge(c, a, variance)), 1.0);
    }
    let orient = perp_dot(b - a, c - a);
    if orient == 0.0 || !is_finite(orient) {
        return 0.0;
    }
    var outside_count = 0u;
    var k = 0u;
    for (var e = 0u; e < 3u; e++) {
        let pe = v[(e + 1u) % 3u];
        let qe = v[(e + 2u) % 3u];
        if perp_dot(qe - pe, -pe) * orient < 0.0 {
            outside_count += 1u;
            k = e;
        }
    }
    let o = vec2f(0.0);
    var volume = 0.0;
    if outside_count == 0u {
        volume = facet(a, o, b, variance) + facet(b, o, c, variance) + facet(c, o, a, variance);
    } else if outside_count == 1u {
        let vk = v[k];
        let pe = v[(k + 1u) % 3u];
        let qe = v[(k + 2u) % 3u];
        let e = qe - pe;
        let denom = perp_dot(vk, e);
        if denom == 0.0 {
            volume = facet(a, b, c, variance);
        } else {
            let s = clamp(perp_dot(vk, -pe) / denom, 0.0, 1.0);
            var d = pe + e * s;
            if beams[bi].split != SPLIT_DOMAIN {
                let r = rescattered_split(bi, ft, k, p, beams[bi].split != SPLIT_PAPER);
                if r.ok {
                    d = to_domain(bi, p, r.origin, r.direction, r.at);
                }
            }
            volume = facet(vk, pe, d, variance) + facet(vk, d, qe, variance);
        }
    } else {
        volume = facet(a, b, c, variance);
    }
    return min(volume, 1.0);
}

// Beam::arrival: E (rgb) and the direction d the light travels at P (w = 0: nothing).
struct Arrival {
    e: vec3f,
    d: vec3f,
    ok: bool,
}

fn beam_arrival(bi: u32, p: vec3f, normal: vec3f) -> Arrival {
    var out: Arrival;
    out.ok = false;
    if !in_front(bi, p) {
        return out;
    }
    let ft = flux_triangle(bi, false, p);
    if !ft.ok {
        return out;
    }
    // Beam::support, with a specular beam's flux triangle computed once.
    let glossy = beams[bi].flux.w > 0.0;
    if (!glossy && !inside(ft)) || (glossy && !inside(flux_triangle(bi, true, p))) {
        return out;
    }
    let b = max(ft.b, vec3f(0.0));
    if !(b.x + b.y + b.z > 0.0) {
        return out;
    }
    let d = normalize_or_zero(
        beams[bi].directions[0].xyz * b.x + beams[bi].directions[1].xyz * b.y + beams[bi].directions[2].xyz * b.z,
    );
    let cos_theta = max(-dot(d, normal), 0.0);
    if cos_theta <= 0.0 {
        return out;
    }
    var e = beams[bi].flux.xyz / ft.area * cos_theta;
    if beams[bi].flux.w > 0.0 {
        e *= min(scatter_volume(bi, ft, p), 1.0);
    }
    out.e = e;
    out.d = d;
    out.ok = true;
    return out;
}

// Whether P lies where beam_arrival may give light: in front of the
// generator plane, its flux triangle defined, inside the support. The
// traversal asks it before a beam counts as found, so that the evaluation
// runs only for beams that may light some fragment of the block: llvmpipe
// runs a loop's body as often as its busiest lane needs, but every branch
// inside it whatever the lanes take.
fn beam_supports(bi: u32, p: vec3f) -> bool {
    if !in_front(bi, p) {
        return false;
    }
    let ft = flux_triangle(bi, false, p);
    if !ft.ok {
        return false;
    }
    if beams[bi].flux.w > 0.0 {
        return inside(flux_triangle(bi, true, p));
    }
    return inside(ft);
}

// One beam's radiance towards the eye: f_r(-d, wo) E, every lobe's kd scaled
// by the receiver's diffuse map tint (1 without a map: f_r exactly).
fn beam_radiance(bi: u32, p: vec3f, n: vec3f, basis: mat3x3f, wo_local: vec3f, mi: u32, tint: vec3f) -> vec3f {
    let a = beam_arrival(bi, p, n);
    if !a.ok {
        return vec3f(0.0);
    }
    return material_brdf_tinted(mi, material_to_local(basis, -a.d), wo_local, tint) * a.e;
}

fn in_bounds(p: vec3f) -> bool {
    return all(p >= settings.bounds_min) && all(p <= settings.bounds_max);
}

@fragment
fn fs_main(in: VertexOutput) -> @location(0) vec4f {
    // The map once per fragment, its derivatives in uniform control flow.
    let duv_dx = dpdx(in.uv);
    let duv_dy = dpdy(in.uv);
    let tint = diffuse_tint_grad(materials[in.material].diffuse_map.x, in.uv, duv_dx, duv_dy);
    let wo_world = normalize(view.eye.xyz - in.world);
    var n = normalize(in.normal);
    if dot(n, wo_world) < 0.0 {
        n = -n;
    }
    let basis = material_basis(n);
    let wo_local = material_to_local(basis, wo_world);
    let p = in.world;
    var l = vec3f(0.0);
    // One call site of beam_radiance for both traversals: lavapipe inlines
    // every call, so a second site doubles the shader it compiles. The
    // beams come in the order each traversal visits them, as before.
    let hierarchy = settings.hierarchy == 1u && settings.node_count > 0u && in_bounds(p);
    // Depth first over the hierarchy; the tree is balanced (median splits,
    // leaves of four), so 64 entries hold any tree of fewer than 2^31 boxes.
    var stack: array<u32, 64>;
    var top = select(0u, 1u, hierarchy);
    stack[0] = 0u;
    // The current leaf's items [k, k_end), or the linear traversal's next beam k.
    var k = 0u;
    var k_end = select(settings.beam_count, 0u, hierarchy);
    loop {
        var bi = 0u;
        var found = false;
        loop {
            if k < k_end {
                var candidate = k;
                var counted = true;
                if hierarchy {
                    let item = items[k];
                    candidate = item.beam;
                    let s = dot(beams[item.beam].wavefront.xyz, p);
                    counted = s >= item.lo && s < item.hi;
                }
                k += 1u;
                // A beam that cannot light P adds nothing: skipped here.
                if counted && beam_supports(candidate, p) {
                    bi = candidate;
                    found = true;
                    break;
                }
                continue;
            }
            if top == 0u {
                break;
            }
            top -= 1u;
            let i = stack[top];
            let node = nodes[i];
            if any(p < node.min) || any(p > node.max) {
                continue;
            }
            if node.count > 0u {
                k = node.link;
                k_end = node.link + node.count;
            } else if top + 2u <= 64u {
                stack[top] = node.link;
                stack[top + 1u] = i + 1u;
                top += 2u;
            }
        }
        if !found {
            break;
        }
        l += beam_radiance(bi, p, n, basis, wo_local, in.material, tint);
    }
    return vec4f(l, 0.0);
}
