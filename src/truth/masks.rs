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

/// The majority mask of `fine` over blocks of `factor`×`factor` pixels: a pixel of the coarse
/// mask is shadowed where more of its block's receiver samples are shadowed than lit, lit where
/// fewer, and no receiver where none is; with it, per pixel, whether its block decided (a tie
/// decides nothing). With `fine` the exact mask at `factor` times a frame's size, it is the
/// reference for a pixel that covers many map texels: what most of its area sees, where one
/// sample at its centre is what a point-sampled map approximates.
pub fn majority(fine: &Mask, factor: u32) -> (Mask, Vec<bool>) {
    let factor = factor.max(1);
    let (width, height) = (fine.width / factor, fine.height / factor);
    let mut values = Vec::with_capacity((width * height) as usize);
    let mut decided = Vec::with_capacity(values.capacity());
    for y in 0..height {
        for x in 0..width {
            let (mut lit, mut shadowed) = (0u32, 0u32);
            for j in 0..factor {
                for i in 0..factor {
                    match fine.get(x * factor + i, y * factor + j) {
                        MaskValue::Lit => lit += 1,
                        MaskValue::Shadowed => shadowed += 1,
                        MaskValue::NotReceiver => {}
                    }
                }
            }
            let v = match lit.cmp(&shadowed) {
                _ if lit + shadowed == 0 => MaskValue::NotReceiver,
                std::cmp::Ordering::Less => MaskValue::Shadowed,
                _ => MaskValue::Lit,
            };
            values.push(v as u8);
            decided.push(lit != shadowed || lit + shadowed == 0);
        }
    }
    let mask = Mask {
        light: fine.light,
        width,
        height,
        values,
    };
    (mask, decided)
}

/// `rendered` against the [`majority`] of `fine` (the exact mask at `factor` times its size),
/// the pixels whose block ties left out.
pub fn compare_majority(rendered: &Mask, fine: &Mask, factor: u32) -> super::Counts {
    let (reference, decided) = majority(fine, factor);
    super::compare_where(rendered, &reference, |i| decided[i])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn majority_takes_what_most_of_a_block_sees() {
        // 4x2 fine pixels, blocks of 2: left block 3 shadowed 1 lit, right block one each.
        let fine = Mask {
            light: 3,
            width: 4,
            height: 2,
            values: vec![2, 2, 1, 2, 1, 2, 0, 0],
        };
        let (m, decided) = majority(&fine, 2);
        assert_eq!((m.width, m.height, m.light), (2, 1, 3));
        assert_eq!(m.get(0, 0), MaskValue::Shadowed);
        assert_eq!(decided, vec![true, false]);
        let none = Mask {
            light: 0,
            width: 2,
            height: 2,
            values: vec![0; 4],
        };
        let (m, decided) = majority(&none, 2);
        assert_eq!((m.get(0, 0), decided[0]), (MaskValue::NotReceiver, true));
    }
}
