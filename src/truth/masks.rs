//! Reference masks: for every pixel of a G-buffer that receives a light, the exact shadow ray.

use super::reference::{Reference, shadow_ray_origin};
use crate::images::{GBuffer, Mask, MaskValue};
use crate::scene::Light;
use glam::Vec3;
use rayon::prelude::*;

/// How shadow rays are traced.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Tracing {
    Bvh,
    /// Every triangle for every ray: slow, for checking the BVH.
    BruteForce,
}

/// The exact mask of `light` (index `index` in the scene) for the pixels of `gbuffer`.
pub fn reference_mask(
    reference: &Reference,
    gbuffer: &GBuffer,
    light: &Light,
    index: usize,
    tracing: Tracing,
) -> Mask {
    let target = light.position.as_dvec3();
    mask_by(gbuffer, light, index, |p, n| {
        let origin = shadow_ray_origin(p, n);
        match tracing {
            Tracing::Bvh => reference.occluded(origin, target),
            Tracing::BruteForce => reference.occluded_brute_force(origin, target),
        }
    })
}

/// A mask of `light` over `gbuffer`: receivers are the pixels the light reaches
/// (`Light::reaches`), each shadowed where `shadowed(position, normal)` says so.
pub fn mask_by(
    gbuffer: &GBuffer,
    light: &Light,
    index: usize,
    shadowed: impl Fn(Vec3, Vec3) -> bool + Sync,
) -> Mask {
    let w = gbuffer.width as usize;
    let mut values = vec![MaskValue::NotReceiver as u8; w * gbuffer.height as usize];
    values.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, out) in row.iter_mut().enumerate() {
            let i = y * w + x;
            if !gbuffer.is_receiver_surface(i) {
                continue;
            }
            let p = Vec3::from_array(gbuffer.position[i]);
            let n = Vec3::from_array(gbuffer.normal[i]);
            if !light.reaches(p.as_dvec3(), n.as_dvec3()) {
                continue;
            }
            *out = if shadowed(p, n) {
                MaskValue::Shadowed
            } else {
                MaskValue::Lit
            } as u8;
        }
    });
    Mask {
        light: index,
        width: gbuffer.width,
        height: gbuffer.height,
        values,
    }
}
