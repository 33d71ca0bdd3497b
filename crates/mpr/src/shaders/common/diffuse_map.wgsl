// Diffuse texture maps (crates/mpr/src/diffuse_map.rs): the tint by which a
// map scales the kd of a material's lobes, bilinear with repeat at
// (u, 1 - v) (lustre-geometry's Texture::sample on level 0). The pass declares
// `diffuse_maps: texture_2d_array<f32>` and `diffuse_map_sampler`; the layer
// is materials[mi].diffuse_map.x or a pass's own copy of it.
//
// Notation
// | symbol | meaning                                                          | unit |
// |--------|------------------------------------------------------------------|------|
// | uv     | texture coordinates, OBJ's convention (v up, (0, 0) bottom-left) | 1    |
// | layer  | the map's layer in diffuse_maps; 0 is white (no map)             | -    |
// | tint   | the map's linear RGB at uv, 1 without a map                      | 1    |

// The tint at uv with explicit uv derivatives (the fragment's, taken in uniform control flow).
fn diffuse_tint_grad(layer: u32, uv: vec2f, duv_dx: vec2f, duv_dy: vec2f) -> vec3f {
    if layer == 0u {
        return vec3f(1.0);
    }
    let st = vec2f(uv.x, 1.0 - uv.y);
    let flip = vec2f(1.0, -1.0);
    return textureSampleGrad(diffuse_maps, diffuse_map_sampler, st, layer, duv_dx * flip, duv_dy * flip).rgb;
}

// The tint at uv from level 0 (at a point: a photon's hit).
fn diffuse_tint_level0(layer: u32, uv: vec2f) -> vec3f {
    if layer == 0u {
        return vec3f(1.0);
    }
    let st = vec2f(uv.x, 1.0 - uv.y);
    return textureSampleLevel(diffuse_maps, diffuse_map_sampler, st, layer, 0.0).rgb;
}
