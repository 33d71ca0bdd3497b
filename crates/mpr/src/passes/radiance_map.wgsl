// Radiance-map reprojection (Bastos et al. 1999, section 8.1.3): each drawn
// texel of a selected radiance map is a screen-aligned box of equation 3's
// size at its world point projected into the reflected view, depth-tested
// (reverse Z: depth = near / z). CPU twin: lustre_ibr::reprojection.
//
// Notation: the view maps X to camera coordinates c = ((X-eye)·right,
// (X-eye)·up, (X-eye)·forward) and to the pixel principal + (fx cx/cz,
// -fy cy/cz), row 0 at the top (lustre_ibr::view).

struct View {
    eye: vec4f,
    right: vec4f,
    up: vec4f,
    forward: vec4f,
    // focal (fx, fy), principal point (cx, cy), in pixels.
    focal_principal: vec4f,
    // image width, height, near distance, leaf count.
    size_near_leaves: vec4f,
};

struct Texel {
    // World point; w = 1 where the texel sees something, 0 elsewhere.
    point: vec4f,
    radiance: vec4f,
};

struct Leaf {
    // First column, first row, columns, rows of the leaf's texel rectangle.
    rect: vec4u,
    // step x, step y, drawn columns ceil(width / step x), offset of the map's texels.
    step_cols_offset: vec4u,
    // Drawn box size in pixels (x, y), map width, first instance of the leaf.
    size_width_first: vec4f,
};

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<storage, read> texels: array<Texel>;
@group(0) @binding(2) var<storage, read> leaves: array<Leaf>;

struct VsOut {
    @builtin(position) position: vec4f,
    @location(0) radiance: vec3f,
};

fn first_instance(k: u32) -> u32 {
    return bitcast<u32>(leaves[k].size_width_first.w);
}

@vertex
fn vs_main(@builtin(vertex_index) v: u32, @builtin(instance_index) instance: u32) -> VsOut {
    var out: VsOut;
    // Outside the clip volume: dropped.
    out.position = vec4f(2.0, 2.0, 2.0, 1.0);
    out.radiance = vec3f(0.0);
    // The last leaf whose first instance is at most this one.
    var lo = 0u;
    var hi = u32(view.size_near_leaves.w);
    while (hi - lo > 1u) {
        let mid = (lo + hi) / 2u;
        if (first_instance(mid) <= instance) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let leaf = leaves[lo];
    let local = instance - first_instance(lo);
    let cols = leaf.step_cols_offset.z;
    let i = leaf.rect.x + (local % cols) * leaf.step_cols_offset.x;
    let j = leaf.rect.y + (local / cols) * leaf.step_cols_offset.y;
    let map_width = bitcast<u32>(leaf.size_width_first.z);
    let texel = texels[leaf.step_cols_offset.w + j * map_width + i];
    if (texel.point.w == 0.0) {
        return out;
    }
    let d = texel.point.xyz - view.eye.xyz;
    let c = vec3f(dot(d, view.right.xyz), dot(d, view.up.xyz), dot(d, view.forward.xyz));
    if (!(c.z > 0.0)) {
        return out;
    }
    let focal = view.focal_principal.xy;
    let principal = view.focal_principal.zw;
    let pixel = principal + vec2f(focal.x * c.x / c.z, -focal.y * c.y / c.z);
    // Two triangles of the box [pixel - size/2, pixel + size/2].
    let corners = array<vec2f, 6>(
        vec2f(-0.5, -0.5), vec2f(0.5, -0.5), vec2f(0.5, 0.5),
        vec2f(-0.5, -0.5), vec2f(0.5, 0.5), vec2f(-0.5, 0.5),
    );
    let p = pixel + corners[v] * leaf.size_width_first.xy;
    let size = view.size_near_leaves.xy;
    out.position = vec4f(2.0 * p.x / size.x - 1.0, 1.0 - 2.0 * p.y / size.y, view.size_near_leaves.z / c.z, 1.0);
    out.radiance = texel.radiance.xyz;
    return out;
}

@fragment
fn fs_main(in: VsOut) -> @location(0) vec4f {
    return vec4f(in.radiance, 1.0);
}
