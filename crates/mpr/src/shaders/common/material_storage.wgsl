// The BRDF of a material in a pass's storage array of materials (splat,
// direct and beams passes), after common/material.wgsl. The pass declares
// `materials: array<GpuMaterial>` in storage; this module only reads it.
//
// Notation: as common/material.wgsl; mi is the MaterialId.
//
// The four lobe slots (MAX_LOBES, checked in shaders.rs) are written out,
// not looped over, and each slot's lobe is copied only when its kind and
// weight say it adds something. On llvmpipe a loop indexing the slots by
// its counter made the direct pass about twice as slow (BENCHMARKS.md, the
// notes after the walkthrough section); copying every slot's whole lobe
// unconditionally made it slower still. Same terms in the same order as
// the loop: the same value bit for bit.

// Whether lobe slot `slot` of materials[mi] adds anything (a kind and a positive weight).
fn material_slot_active(mi: u32, slot: u32) -> bool {
    return materials[mi].lobes[slot].kind != LOBE_NONE && materials[mi].lobes[slot].weight > 0.0;
}

// f(wi, wo) of materials[mi]: the weighted sum of its lobes.
fn material_brdf_at(mi: u32, wi: vec3f, wo: vec3f) -> vec3f {
    var f = vec3f(0.0);
    if material_slot_active(mi, 0u) {
        f += materials[mi].lobes[0].weight * material_lobe(materials[mi].lobes[0], wi, wo);
    }
    if material_slot_active(mi, 1u) {
        f += materials[mi].lobes[1].weight * material_lobe(materials[mi].lobes[1], wi, wo);
    }
    if material_slot_active(mi, 2u) {
        f += materials[mi].lobes[2].weight * material_lobe(materials[mi].lobes[2], wi, wo);
    }
    if material_slot_active(mi, 3u) {
        f += materials[mi].lobes[3].weight * material_lobe(materials[mi].lobes[3], wi, wo);
    }
    return f;
}

// f(wi, wo) of materials[mi] with every lobe's kd scaled by tint (its diffuse map's texel, common/diffuse_map.wgsl).
fn material_brdf_tinted(mi: u32, wi: vec3f, wo: vec3f, tint: vec3f) -> vec3f {
    var f = vec3f(0.0);
    if material_slot_active(mi, 0u) {
        f += materials[mi].lobes[0].weight * material_lobe_kd(materials[mi].lobes[0], materials[mi].lobes[0].kd.xyz * tint, wi, wo);
    }
    if material_slot_active(mi, 1u) {
        f += materials[mi].lobes[1].weight * material_lobe_kd(materials[mi].lobes[1], materials[mi].lobes[1].kd.xyz * tint, wi, wo);
    }
    if material_slot_active(mi, 2u) {
        f += materials[mi].lobes[2].weight * material_lobe_kd(materials[mi].lobes[2], materials[mi].lobes[2].kd.xyz * tint, wi, wo);
    }
    if material_slot_active(mi, 3u) {
        f += materials[mi].lobes[3].weight * material_lobe_kd(materials[mi].lobes[3], materials[mi].lobes[3].kd.xyz * tint, wi, wo);
    }
    return f;
}
