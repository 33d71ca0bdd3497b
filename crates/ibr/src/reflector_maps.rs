//! All radiance maps of one reflector, with their quadtrees, and their memory as in the paper's table 1 (Bastos et al. 1999, sections 8.1.3 and 9).

use lustre_geometry::Rgb;

use crate::error::{IbrError, Result};
use crate::quadtree::{MapQuadtree, QuadtreeSettings};
use crate::radiance_map::{RadianceMap, RadianceSource};
use crate::reflector::Reflector;
use crate::reprojection::{PointSizing, ReflectedImage, reconstruct, reproject};
use crate::sampling::{SampleCamera, SamplingSettings, sample_cameras};
use crate::selection::{SelectionRule, select};
use crate::view::PinholeView;

/// One reflector's radiance maps, hemisphere by hemisphere, and the quadtree of each.
#[derive(Debug, Clone, PartialEq)]
pub struct ReflectorMaps {
    /// The reflector.
    pub reflector: Reflector,
    /// How it was sampled.
    pub sampling: SamplingSettings,
    /// The maps, hemisphere by hemisphere.
    pub maps: Vec<RadianceMap>,
    /// The quadtree of each map.
    pub trees: Vec<MapQuadtree>,
}

/// The memory of one reflector's maps, the columns of the paper's table 1.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MemoryReport {
    /// The reflector's surface id.
    pub surface: u32,
    /// Hemispheres (reflector elements).
    pub hemispheres: u32,
    /// Radiance maps per hemisphere.
    pub maps_per_hemisphere: u32,
    /// Texels per map along `u` and `v`.
    pub resolution: (u32, u32),
    /// Bytes of texels and quadtree nodes.
    pub bytes: usize,
}

impl ReflectorMaps {
    /// Samples `reflector` under `sampling` and captures every map from `source`, calling `progress(done, total)` after each map (section 8.1.3).
    pub fn capture(
        reflector: &Reflector,
        sampling: &SamplingSettings,
        quadtree: &QuadtreeSettings,
        source: &dyn RadianceSource,
        progress: &mut dyn FnMut(usize, usize),
    ) -> Result<Self> {
        let (w, h) = sampling.map_resolution;
        Self::capture_with(
            reflector,
            sampling,
            quadtree,
            &mut |camera| Ok::<_, IbrError>(RadianceMap::capture(camera, w, h, source)),
            progress,
        )
    }

    /// Samples `reflector` under `sampling` and has `draw` capture each camera's map at `sampling.map_resolution` (a renderer that draws whole maps at once, as the GPU does), calling `progress(done, total)` after each map (section 8.1.3).
    pub fn capture_with<E: From<IbrError>>(
        reflector: &Reflector,
        sampling: &SamplingSettings,
        quadtree: &QuadtreeSettings,
        draw: &mut dyn FnMut(&SampleCamera) -> std::result::Result<RadianceMap, E>,
        progress: &mut dyn FnMut(usize, usize),
    ) -> std::result::Result<Self, E> {
        sampling.validate()?;
        quadtree.validate()?;
        let (nu, nv) = sampling.planar_resolution;
        let elements = reflector.elements(nu, nv)?;
        let cameras = sample_cameras(&elements, sampling)?;
        let mut maps = Vec::with_capacity(cameras.len());
        for (k, camera) in cameras.iter().enumerate() {
            maps.push(draw(camera)?);
            progress(k + 1, cameras.len());
        }
        Ok(Self::from_maps(
            reflector.clone(),
            *sampling,
            maps,
            quadtree,
        )?)
    }

    /// The bundle of already captured `maps` (e.g. read from a cache or from the GPU), their quadtrees built under `quadtree`.
    pub fn from_maps(
        reflector: Reflector,
        sampling: SamplingSettings,
        maps: Vec<RadianceMap>,
        quadtree: &QuadtreeSettings,
    ) -> Result<Self> {
        let trees = maps
            .iter()
            .map(|m| MapQuadtree::build(m, quadtree))
            .collect::<Result<Vec<_>>>()?;
        Ok(Self {
            reflector,
            sampling,
            maps,
            trees,
        })
    }

    /// The maps' sample cameras, in order.
    pub fn cameras(&self) -> Vec<SampleCamera> {
        self.maps.iter().map(|m| m.camera).collect()
    }

    /// Memory of the maps and quadtrees (table 1).
    pub fn memory(&self) -> MemoryReport {
        let (nu, nv) = self.sampling.planar_resolution;
        let hemispheres = nu * nv;
        MemoryReport {
            surface: self.reflector.surface,
            hemispheres,
            maps_per_hemisphere: self.maps.len() as u32 / hemispheres.max(1),
            resolution: self.sampling.map_resolution,
            bytes: self
                .maps
                .iter()
                .map(RadianceMap::texel_bytes)
                .sum::<usize>()
                + self.trees.iter().map(MapQuadtree::bytes).sum::<usize>(),
        }
    }

    /// The mirror-like reflected image M of this reflector for `view` (the reflected view, [`PinholeView::mirrored`]): the `k` best maps of each hemisphere under `rule`, reprojected and reconstructed on the CPU (section 8.1.3).
    pub fn reflected_image(
        &self,
        view: &PinholeView,
        k: usize,
        rule: SelectionRule,
        sizing: PointSizing,
    ) -> ReflectedImage {
        let mut image = ReflectedImage::new(view.width, view.height);
        for i in select(&self.cameras(), view.eye, k, rule) {
            let points = reproject(&self.maps[i], &self.trees[i], view, sizing);
            reconstruct(&mut image, &points);
        }
        image
    }

    /// The mean radiance of every map's valid texels (for reports).
    pub fn mean_radiance(&self) -> Rgb {
        let (mut sum, mut n) = (glam::DVec3::ZERO, 0u64);
        for m in &self.maps {
            for j in 0..m.height {
                for i in 0..m.width {
                    if m.depth[m.index(i, j)].is_finite() {
                        sum += m.radiance_at(i, j).as_dvec3();
                        n += 1;
                    }
                }
            }
        }
        if n == 0 {
            Rgb::ZERO
        } else {
            (sum / n as f64).as_vec3()
        }
    }
}
