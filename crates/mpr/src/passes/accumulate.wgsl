// Accumulation buffer (Diefenbach & Badler 1997, section 7: antialiasing by
// accumulating jittered renderings): each frame's HDR radiance, read texel for
// texel, is added into the accumulation target with blend weight w = 1/N
// (the blend constant), so N jittered frames average into a box-filtered image.
//
// Notation
// | symbol | meaning                                              | unit       |
// |--------|------------------------------------------------------|------------|
// | hdr    | one jittered frame's HDR radiance                    | W/(m^2 sr) |
// | w      | 1/N, the blend constant                              | 1          |
// | acc    | the accumulation target, acc += w hdr                | W/(m^2 sr) |

@group(0) @binding(0) var hdr: texture_2d<f32>;

@vertex
fn vs_main(@builtin(vertex_index) index: u32) -> @builtin(position) vec4f {
    // One triangle covering the viewport: (-1,-1), (3,-1), (-1,3).
    let uv = vec2f(f32((index << 1u) & 2u), f32(index & 2u));
    return vec4f(uv * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn fs_main(@builtin(position) pixel: vec4f) -> @location(0) vec4f {
    return textureLoad(hdr, vec2i(pixel.xy), 0);
}
