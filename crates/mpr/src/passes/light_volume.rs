//! Light volumes and specular shadow volumes of virtual lights on the GPU
//! (Diefenbach & Badler 1997, sections 4.2, 4.3 and 7.1's `make_shadows` /
//! `make_spec_shadows`): every point light reflected or refracted by chains
//! of specular faces ([`crate::virtual_light`]) adds its light, per view,
//! where the stencil says it arrives.
//!
//! Per view, real light and chain `F₁ … F_k`, in the real light's render
//! pass over the HDR target ([`crate::passes::shadowed_direct`]): the view's area is set to `SHAD_ZERO + k`; each face's light
//! volume (the face's triangles, reversed, extruded from the virtual light
//! `L_j` that shines through it, moved by the faces after it) is counted
//! with the opposite sign, so only their intersection, where the light
//! passed every face, comes down to `SHAD_ZERO`; then each stretch's shadow
//! volumes (cast from `L_j` by the geometry that may block that stretch,
//! moved by the faces after it: section 4.3's transformed copies) count up
//! as the real light's do; the virtual light, its intensity times the
//! faces' factors, is added where the stencil is `SHAD_ZERO`, and the area
//! goes back to the view.
//!
//! Volumes are built once per central light position and chain prefix and
//! shared by every chain that begins with it (figure 6's reuse: `S₀₁₂` is
//! `S₀₁` moved by the second mirror). Jittered lights (section 4.4) pivot
//! them: per frame the jittered light is carried through each prefix and
//! its position and the suffix transform are written as one
//! [`VolumeLight`] block per draw.

use std::collections::HashMap;
use std::sync::Mutex;

use glam::{Mat4, Vec3};
use lustre_geometry::Scene;
use lustre_geometry::shadow_volume::{ShadowVolume, ShadowVolumeSet};

use crate::frame::FrameInputs;
use crate::passes::direct::{DirectLights, DirectPass, GpuLight, GpuWindow};
use crate::passes::shadow_volume::{
    SHAD_ZERO, ShadowVolumeBuffers, ShadowVolumePass, VolumeLight, VolumeLights,
};
use crate::passes::specular::{SpecularFace, SpecularKind};
use crate::projective_texture::{Projector, Window, upload_layers};
use crate::view::{ViewBuffer, ViewSlot, intersect_rects};
use crate::virtual_light::{
    MAX_SHADOW_DEPTH, SpecularPath, VirtualLightSettings, cone_planes, light_scissor, outgoing,
    shadow_generations, specular_paths,
};
use crate::{GpuContext, MprError, Result};

/// One volume draw of a virtual light.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Draw {
    /// Index into [`VirtualLights::buffers`].
    buffer: usize,
    /// The stretch (shadows) or face (light volume) index `j` it belongs to.
    j: usize,
    /// Counted inverted (a light volume).
    light_volume: bool,
}

/// The chains of one central light position and their draws.
#[derive(Debug, Clone)]
struct Chains {
    paths: Vec<SpecularPath>,
    draws: Vec<Vec<Draw>>,
}

/// What one prefix's volume is (the cache key's kind).
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
enum Role {
    /// Face `j`'s light volume.
    LightVolume,
    /// Stretch `j`'s shadows, bounded by the next face (`true` when `j < k`).
    Shadows(bool),
}

/// Per frame state: the draw blocks and the virtual lights' direct slots.
#[derive(Debug)]
struct FrameState {
    blocks: VolumeLights,
    /// Per real light: the index of its first virtual light in `direct`.
    first: Vec<usize>,
    direct: Option<DirectLights>,
    /// Per real light and chain: the first block of its draws.
    first_block: Vec<Vec<usize>>,
    /// Per real light and chain: the surfaces its light may reach.
    receivers: Vec<Vec<Vec<u32>>>,
    /// Per real light and chain: the virtual light and the box of its
    /// receivers, for the scissor of its passes in each view.
    reach: Vec<Vec<(Vec3, [Vec3; 2])>>,
}

/// The virtual lights of a scene's specular faces for the real point
/// lights of the direct pass (sections 4.2, 4.3), with their volumes on the GPU.
#[derive(Debug)]
pub struct VirtualLights {
    settings: VirtualLightSettings,
    faces: Vec<SpecularFace>,
    /// The windows the faces' [`SpecularKind::Pane`]s index (section 4.5).
    windows: Vec<Window>,
    /// Their transmittance textures, one layer each.
    window_textures: Option<wgpu::TextureView>,
    /// Per distinct central light position.
    chains: Vec<Chains>,
    buffers: Vec<ShadowVolumeBuffers>,
    bytes: usize,
    frame: Mutex<FrameState>,
}

/// A triangle's corners as exact bits, to find a face's own triangles.
fn triangle_key(t: &[Vec3; 3]) -> [u32; 9] {
    let mut key = [0u32; 9];
    for (i, p) in t.iter().enumerate() {
        key[3 * i..3 * i + 3].copy_from_slice(&p.to_array().map(f32::to_bits));
    }
    key
}

/// The keys of `face`'s triangles (its `corners`, three per triangle).
fn face_triangles(face: &SpecularFace) -> Vec<[u32; 9]> {
    face.corners
        .chunks_exact(3)
        .map(|t| triangle_key(&[t[0], t[1], t[2]]))
        .collect()
}

impl VirtualLights {
    /// Builds the chains of `faces` (at most `settings.depth` long) for
    /// each of `positions` (the distinct central light positions of `set`)
    /// and uploads their light and shadow volumes, cast by `set`'s casters,
    /// and the transmittance textures of `windows`, which the faces'
    /// [`SpecularKind::Pane`]s index.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        ctx: &GpuContext,
        pass: &ShadowVolumePass,
        scene: &Scene,
        set: &ShadowVolumeSet,
        faces: &[SpecularFace],
        windows: &[Window],
        positions: &[Vec3],
        settings: VirtualLightSettings,
    ) -> Result<Self> {
        let window_textures = match windows.first() {
            None => None,
            Some(first) => {
                let (width, height) = (first.texture.width, first.texture.height);
                if windows
                    .iter()
                    .any(|w| (w.texture.width, w.texture.height) != (width, height))
                {
                    return Err(MprError::InvalidSetting {
                        what: "projective textures",
                        message: "every window's texture must have the same size".into(),
                    });
                }
                let layers: Vec<Vec<[f32; 4]>> =
                    windows.iter().map(|w| w.texture.texels.clone()).collect();
                Some(ctx.checked("window texture upload", || {
                    upload_layers(&ctx.device, &ctx.queue, width, height, &layers)
                })?)
            }
        };
        if settings.depth > MAX_SHADOW_DEPTH {
            return Err(MprError::InvalidSetting {
                what: "shadow recursion depth",
                message: format!(
                    "{} exceeds {MAX_SHADOW_DEPTH} (one stencil value per face above SHAD_ZERO)",
                    settings.depth
                ),
            });
        }
        let epsilon = 1e-4 * scene.bounds().extent().max_element().max(1e-6);
        let mut volumes: Vec<Vec<ShadowVolume>> = Vec::new();
        // One buffer per central position, face prefix and role: chains
        // sharing a prefix draw the same volumes (section 4.3's reuse).
        let mut cache: HashMap<(usize, Vec<usize>, Role), usize> = HashMap::new();
        // The volumes every caster casts from `source` with the triangles `keep` selects.
        let mut build = |key: (usize, Vec<usize>, Role),
                         source: Vec3,
                         keep: &dyn Fn(&[Vec3; 3]) -> bool,
                         reversed: bool|
         -> Result<usize> {
            if let Some(&b) = cache.get(&key) {
                return Ok(b);
            }
            let built = (0..set.casters().len())
                .map(|caster| set.volume_where(scene, caster, source, keep, reversed))
                .collect::<lustre_geometry::Result<Vec<_>>>()
                .map_err(geometry_error)?;
            volumes.push(built.into_iter().filter(|v| !v.is_empty()).collect());
            cache.insert(key, volumes.len() - 1);
            Ok(volumes.len() - 1)
        };
        let mut chains = Vec::with_capacity(positions.len());
        for (c, &light) in positions.iter().enumerate() {
            let paths = specular_paths(faces, light, settings.depth);
            let mut draws = Vec::with_capacity(paths.len());
            for path in &paths {
                let k = path.len();
                let mut list = Vec::new();
                for j in 1..=k {
                    let face = &faces[path.faces[j - 1]];
                    let own = face_triangles(face);
                    let keep = |t: &[Vec3; 3]| own.contains(&triangle_key(t));
                    // Turned to face the light's side (an interface's
                    // turned-round face is wound that way already).
                    let reversed = face.corners.chunks_exact(3).next().is_some_and(|t| {
                        (t[1] - t[0]).cross(t[2] - t[0]).dot(face.plane.normal) > 0.0
                    });
                    let buffer = build(
                        (c, path.faces[..j].to_vec(), Role::LightVolume),
                        path.prefix[j].transform_point3(light),
                        &keep,
                        reversed,
                    )?;
                    list.push(Draw {
                        buffer,
                        j,
                        light_volume: true,
                    });
                }
                for j in path.shadowed_stretches(settings.shadows) {
                    let bounded = j < k;
                    let prefix = path.faces[..if bounded { j + 1 } else { k }].to_vec();
                    let bounds = path.stretch_bounds(faces, j);
                    let cone = path.stretch_cone(faces, light, j);
                    // Between the faces, and not wholly outside the cone of
                    // the light that passes them.
                    let keep = |t: &[Vec3; 3]| {
                        bounds.iter().all(|h| h.holds_triangle(t, epsilon))
                            && !cone
                                .iter()
                                .any(|h| t.iter().all(|&p| h.depth(p) < -epsilon))
                    };
                    let buffer = build(
                        (c, prefix, Role::Shadows(bounded)),
                        path.prefix[j].transform_point3(light),
                        &keep,
                        false,
                    )?;
                    list.push(Draw {
                        buffer,
                        j,
                        light_volume: false,
                    });
                }
                draws.push(list);
            }
            chains.push(Chains { paths, draws });
        }
        let bytes = volumes.iter().flatten().map(ShadowVolume::byte_size).sum();
        let buffers = volumes
            .iter()
            .map(|v| ShadowVolumeBuffers::upload(ctx, v))
            .collect::<Result<Vec<_>>>()?;
        Ok(Self {
            settings,
            faces: faces.to_vec(),
            windows: windows.to_vec(),
            window_textures,
            chains,
            buffers,
            bytes,
            frame: Mutex::new(FrameState {
                blocks: VolumeLights::new(ctx, pass, 1),
                first: Vec::new(),
                direct: None,
                first_block: Vec::new(),
                receivers: Vec::new(),
                reach: Vec::new(),
            }),
        })
    }

    /// The settings they were built with.
    pub fn settings(&self) -> VirtualLightSettings {
        self.settings
    }

    /// The specular faces they pass.
    pub fn faces(&self) -> &[SpecularFace] {
        &self.faces
    }

    /// The windows whose light they draw (section 4.5).
    pub fn windows(&self) -> &[Window] {
        &self.windows
    }

    /// The slide projector of the window `path` passes, for a light at
    /// `light` (section 4.5): the projector from the virtual light before
    /// the window, applied after the later faces' transforms are undone.
    fn window_of(&self, path: &SpecularPath, light: Vec3) -> GpuWindow {
        let Some((j, window)) =
            path.faces
                .iter()
                .enumerate()
                .find_map(|(j, &f)| match self.faces[f].kind {
                    SpecularKind::Pane { window } => Some((j + 1, window)),
                    _ => None,
                })
        else {
            return GpuWindow::NONE;
        };
        let Some(w) = self.windows.get(window as usize) else {
            return GpuWindow::NONE;
        };
        let source = path.prefix[j - 1].transform_point3(light);
        let Some(projector) = Projector::new(w, source) else {
            // The light lies in the window's plane: no light passes.
            return GpuWindow {
                u: [0.0, 0.0, 0.0, window as f32],
                ..GpuWindow::NONE
            };
        };
        let undo = Mat4::from(path.suffix(j).inverse());
        GpuWindow {
            projector: (projector.matrix * undo).to_cols_array_2d(),
            origin: w.origin.extend(w.ior).to_array(),
            u: w.u.extend(window as f32).to_array(),
            v: w.v.extend(0.0).to_array(),
            source: source.extend(1.0).to_array(),
        }
    }

    /// The chains of the `i`-th central light position.
    pub fn paths(&self, position: usize) -> &[SpecularPath] {
        self.chains
            .get(position)
            .map(|c| c.paths.as_slice())
            .unwrap_or_default()
    }

    /// Bytes of the light and shadow volumes on the GPU (section 4.3's storage).
    pub fn byte_size(&self) -> usize {
        self.bytes
    }

    /// Shadow-volume generations per image for the `i`-th central light
    /// position: 1 for the light itself and one per drawn stretch of each
    /// chain (equation 7's count, section 8.1).
    pub fn shadow_generations(&self, position: usize) -> usize {
        shadow_generations(self.paths(position), self.settings.shadows)
    }

    /// Writes, for the real lights `direct` holds now (light `i` has the
    /// chains of central position `chain_of[i]`), every virtual light and
    /// every draw's block: the jittered light carried through each prefix,
    /// the suffix transform (section 4.4's pivot, carried through the faces);
    /// the surfaces each may light are found among `surface_boxes` (per
    /// surface its world box, [`crate::view::surface_boxes`]).
    #[allow(clippy::too_many_arguments)]
    pub fn prepare(
        &self,
        ctx: &GpuContext,
        pass: &ShadowVolumePass,
        direct_pass: &DirectPass,
        direct: &DirectLights,
        chain_of: &[usize],
        surface_boxes: &[[Vec3; 2]],
    ) -> Result<()> {
        let mut frame = self.frame.lock().unwrap_or_else(|e| e.into_inner());
        let mut lights: Vec<GpuLight> = Vec::new();
        let mut blocks: Vec<VolumeLight> = Vec::new();
        let mut first = Vec::with_capacity(chain_of.len());
        let mut first_block = Vec::with_capacity(chain_of.len());
        let mut receivers = Vec::with_capacity(chain_of.len());
        let mut reach = Vec::with_capacity(chain_of.len());
        for (light, &c) in direct.lights().zip(chain_of) {
            first.push(lights.len());
            let chains = &self.chains[c];
            let mut starts = Vec::with_capacity(chains.paths.len());
            let mut reached = Vec::with_capacity(chains.paths.len());
            let mut boxes = Vec::with_capacity(chains.paths.len());
            for (path, draws) in chains.paths.iter().zip(&chains.draws) {
                let mut virtual_light = light.through(path.transform(), path.factor);
                virtual_light.window = self.window_of(path, light.position());
                let surfaces = self.receivers(path, virtual_light.position(), surface_boxes);
                let bound =
                    surfaces
                        .iter()
                        .fold([Vec3::INFINITY, Vec3::NEG_INFINITY], |[lo, hi], &s| {
                            let [a, b] = surface_boxes[s as usize];
                            [lo.min(a), hi.max(b)]
                        });
                boxes.push((virtual_light.position(), bound));
                reached.push(surfaces);
                lights.push(virtual_light);
                starts.push(blocks.len());
                for draw in draws {
                    let source = path.prefix[draw.j].transform_point3(light.position());
                    blocks.push(VolumeLight::new(source, path.suffix(draw.j)));
                }
            }
            first_block.push(starts);
            receivers.push(reached);
            reach.push(boxes);
        }
        frame.blocks.write_blocks(ctx, pass, &blocks)?;
        let reusable = frame
            .direct
            .as_ref()
            .is_some_and(|d| d.len() == lights.len() && d.shares_materials(direct));
        if reusable {
            if let Some(d) = &frame.direct {
                d.set_gpu_lights(&ctx.queue, &lights)?;
            }
        } else {
            frame.direct = Some(direct.unshadowed_like(
                ctx,
                direct_pass,
                &lights,
                self.window_textures.as_ref(),
            )?);
        }
        frame.first = first;
        frame.first_block = first_block;
        frame.receivers = receivers;
        frame.reach = reach;
        Ok(())
    }

    /// The surfaces the virtual light at `source` may light through `path`:
    /// not wholly behind its last face nor wholly outside the cone from
    /// `source` through it (its light volume, section 4.2), tested on each
    /// surface's box (section 8's culling).
    fn receivers(
        &self,
        path: &SpecularPath,
        source: Vec3,
        surface_boxes: &[[Vec3; 2]],
    ) -> Vec<u32> {
        let Some(&last) = path.faces.last() else {
            return Vec::new();
        };
        let face = &self.faces[last];
        let mut planes = cone_planes(source, face);
        planes.push(outgoing(face));
        let mut out = Vec::new();
        for (surface, [lo, hi]) in surface_boxes.iter().enumerate() {
            if !lo.is_finite() {
                continue;
            }
            let corners = (0..8).map(|i| {
                Vec3::new(
                    if i & 1 == 0 { lo.x } else { hi.x },
                    if i & 2 == 0 { lo.y } else { hi.y },
                    if i & 4 == 0 { lo.z } else { hi.z },
                )
            });
            let outside = planes.iter().any(|h| {
                corners
                    .clone()
                    .all(|c| h.depth(c) < -1e-4 * (*hi - *lo).length().max(1e-3))
            });
            if !outside {
                out.push(surface as u32);
            }
        }
        out
    }

    /// Records into `render` (over the HDR target and the depth-stencil,
    /// [`ShadowVolumePass::begin_pass`]), for the view of `slot`, the
    /// virtual lights of real light `light`, whose chains are those of
    /// central position `chain` (sections 4.2, 4.3, 7.1): per chain the area
    /// raised, the light volumes, the shadow volumes, the light under the
    /// stencil and the restore, its lit redraw over the receivers among
    /// `visible` (the surfaces that may show in the view, ascending). Run
    /// after [`VirtualLights::prepare`] in the
    /// same submission.
    #[allow(clippy::too_many_arguments)]
    pub fn record_view(
        &self,
        render: &mut wgpu::RenderPass<'_>,
        pass: &ShadowVolumePass,
        direct_pass: &DirectPass,
        frame: &FrameInputs<'_>,
        views: &ViewBuffer,
        slot: ViewSlot,
        light: usize,
        chain: usize,
        visible: &[u32],
    ) -> Result<()> {
        let state = self.frame.lock().unwrap_or_else(|e| e.into_inner());
        let (Some(direct), Some(&first), Some(starts)) = (
            state.direct.as_ref(),
            state.first.get(light),
            state.first_block.get(light),
        ) else {
            return Err(MprError::InvalidSetting {
                what: "virtual lights",
                message: format!("light #{light} was not prepared (call VirtualLights::prepare)"),
            });
        };
        let chains = &self.chains[chain];
        let (width, height) = (frame.targets.width, frame.targets.height);
        let region = slot.scissor_in(width, height);
        for (p, (path, draws)) in chains.paths.iter().zip(&chains.draws).enumerate() {
            // Every stencil step and the lit redraw of this chain stay inside
            // the pixels its light may reach in this view; a chain whose
            // light reaches none of them is left out of the view.
            let (Some(&last), Some(&(apex, bound))) = (
                path.faces.last(),
                state.reach.get(light).and_then(|r| r.get(p)),
            ) else {
                continue;
            };
            // Its receivers that may show in this view (both lists ascend).
            let receivers = sorted_intersection(&state.receivers[light][p], visible);
            if receivers.is_empty() {
                continue;
            }
            let Some(rect) = light_scissor(
                slot.view_projection,
                apex,
                &self.faces[last],
                bound,
                width,
                height,
            ) else {
                continue;
            };
            let [x, y, w, h] = intersect_rects(rect, region);
            if w == 0 || h == 0 {
                continue;
            }
            render.set_scissor_rect(x, y, w, h);
            pass.record_begin_at(
                render,
                slot.stencil_reference,
                SHAD_ZERO + path.len() as u32,
            )?;
            for (d, draw) in draws.iter().enumerate() {
                let mirrors = path.suffix(draw.j).matrix3.determinant() < 0.0;
                pass.record_volumes_as(
                    render,
                    views,
                    slot,
                    &state.blocks,
                    starts[p] + d,
                    &self.buffers[draw.buffer],
                    slot.mirrored ^ mirrors ^ draw.light_volume,
                )?;
            }
            direct_pass.record_light_on_surfaces_under_stencil(
                render,
                frame.scene,
                direct,
                first + p,
                views,
                slot,
                &receivers,
            )?;
            pass.record_end(render, slot.stencil_reference)?;
        }
        let [x, y, w, h] = region;
        render.set_scissor_rect(x, y, w, h);
        Ok(())
    }
}

/// The values in both ascending lists.
fn sorted_intersection(a: &[u32], b: &[u32]) -> Vec<u32> {
    let (mut i, mut j, mut out) = (0, 0, Vec::new());
    while i < a.len() && j < b.len() {
        match a[i].cmp(&b[j]) {
            std::cmp::Ordering::Less => i += 1,
            std::cmp::Ordering::Greater => j += 1,
            std::cmp::Ordering::Equal => {
                out.push(a[i]);
                i += 1;
                j += 1;
            }
        }
    }
    out
}

fn geometry_error(e: lustre_geometry::GeometryError) -> MprError {
    MprError::InvalidSetting {
        what: "virtual light volumes",
        message: e.to_string(),
    }
}
