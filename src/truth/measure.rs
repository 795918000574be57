//! A frame's masks measured against the exact reference: each light's exact mask traced over the
//! frame's G-buffer, and the error counts of the rendered mask against it, per light and summed.
//! The one place the bench, the viewer's error view, `render --mask` and the tests do this.

use super::masks::{Tracing, reference_mask};
use super::metrics::{Counts, compare};
use super::reference::Reference;
use crate::images::{GBuffer, Mask};
use crate::scene::Scene;
use std::collections::HashMap;

/// A frame's masks against the exact ones.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Measurement {
    /// The exact mask of each rendered mask, in the same order.
    pub exact: Vec<Mask>,
    /// Each rendered mask's counts with its light, in the same order.
    pub per_light: Vec<(usize, Counts)>,
    /// The counts summed over the lights.
    pub total: Counts,
}

impl Measurement {
    /// Adds one light: its rendered mask and the exact mask of the same light and frame.
    pub fn push(&mut self, rendered: &Mask, exact: Mask) {
        let c = compare(rendered, &exact);
        self.total.add(&c);
        self.per_light.push((rendered.light, c));
        self.exact.push(exact);
    }
}

/// The exact mask answering the rendered `mask`: its light, traced over `gbuffer` with the BVH.
pub fn exact_mask(scene: &Scene, reference: &Reference, gbuffer: &GBuffer, mask: &Mask) -> Mask {
    reference_mask(
        reference,
        gbuffer,
        &scene.lights[mask.light],
        mask.light,
        Tracing::Bvh,
    )
}

/// Measures `masks` (rendered over `gbuffer`) against the exact masks of `scene`'s lights.
pub fn measure(
    scene: &Scene,
    reference: &Reference,
    gbuffer: &GBuffer,
    masks: &[Mask],
) -> Measurement {
    measure_with(masks, |m| exact_mask(scene, reference, gbuffer, m))
}

/// [`measure`] with each exact mask given by `exact` (usually [`exact_mask`] wrapped in a
/// cache, a timer or a progress count), called once per mask in order.
pub fn measure_with(masks: &[Mask], mut exact: impl FnMut(&Mask) -> Mask) -> Measurement {
    let mut out = Measurement::default();
    for m in masks {
        let e = exact(m);
        out.push(m, e);
    }
    out
}

/// Exact masks of one view of a scene, kept by frame size and light: the G-buffer does not depend
/// on the shadow technique, so every configuration rendered from the view shares them. The
/// reference is built on first use unless given.
#[derive(Default)]
pub struct ExactMasks {
    reference: Option<Reference>,
    masks: HashMap<(u32, u32, usize), Mask>,
}

impl ExactMasks {
    pub fn new() -> ExactMasks {
        ExactMasks::default()
    }

    /// With the reference already built.
    pub fn with_reference(reference: Reference) -> ExactMasks {
        ExactMasks {
            reference: Some(reference),
            masks: HashMap::new(),
        }
    }

    /// Measures `masks` (rendered over `gbuffer`, a frame of `scene` from this view), tracing the
    /// exact masks not yet kept.
    pub fn measure(&mut self, scene: &Scene, gbuffer: &GBuffer, masks: &[Mask]) -> Measurement {
        let reference = self
            .reference
            .get_or_insert_with(|| Reference::build(scene));
        let kept = &mut self.masks;
        measure_with(masks, |m| {
            kept.entry((gbuffer.width, gbuffer.height, m.light))
                .or_insert_with(|| exact_mask(scene, reference, gbuffer, m))
                .clone()
        })
    }

    /// The reference, built on first use.
    pub fn reference(&mut self, scene: &Scene) -> &Reference {
        self.reference
            .get_or_insert_with(|| Reference::build(scene))
    }

    /// The exact mask of light `light` for frames of `width` x `height`, once measured.
    pub fn get(&self, width: u32, height: u32, light: usize) -> Option<&Mask> {
        self.masks.get(&(width, height, light))
    }

    /// Forgets the masks (the view moved); the reference is kept.
    pub fn clear(&mut self) {
        self.masks.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::images::MaskValue;
    use crate::scene::shapes::MeshData;
    use crate::scene::{Light, Material, SurfaceKind, SurfaceOwner};
    use glam::Vec3;

    /// A 10x10 square occluder at z = 50 over the ground; light 0 straight above it at z = 100,
    /// light 1 above x = 50.
    fn scene() -> Scene {
        let mut scene = Scene::default();
        scene.materials.push(Material::opaque("occluder", None));
        let mut m = MeshData::default();
        let z = 50.0;
        m.quad(
            Vec3::new(-5.0, -5.0, z),
            Vec3::new(5.0, -5.0, z),
            Vec3::new(5.0, 5.0, z),
            Vec3::new(-5.0, 5.0, z),
            [1.0, 1.0],
        );
        scene.push_surface(
            &m.vertices,
            &m.indices,
            0,
            SurfaceOwner::World,
            SurfaceKind::Mesh,
        );
        scene.lights = vec![
            Light::omni("above", Vec3::new(0.0, 0.0, 100.0), 1000.0),
            Light::omni("aside", Vec3::new(50.0, 0.0, 100.0), 1000.0),
        ];
        scene
    }

    /// One row of five ground pixels: background, under the occluder, at x = 50, at x = -50, and
    /// a surface that receives no dynamic light.
    fn gbuffer() -> GBuffer {
        let at = |x: f32| [x, 0.0, 0.0];
        GBuffer {
            width: 5,
            height: 1,
            position: vec![at(0.0), at(0.0), at(50.0), at(-50.0), at(20.0)],
            normal: vec![[0.0, 0.0, 1.0]; 5],
            kind: vec![0, 1, 1, 1, 2],
        }
    }

    fn mask(light: usize, row: &str) -> Mask {
        let values = row
            .bytes()
            .map(|b| match b {
                b'L' => MaskValue::Lit,
                b'S' => MaskValue::Shadowed,
                _ => MaskValue::NotReceiver,
            } as u8)
            .collect();
        Mask {
            light,
            width: row.len() as u32,
            height: 1,
            values,
        }
    }

    #[test]
    fn counts_per_light_and_in_total_by_hand() {
        let scene = scene();
        let g = gbuffer();
        // Light 1 first: the order of the frame's masks is kept.
        let rendered = [mask(1, ".LLSL"), mask(0, ".LSL.")];
        let reference = Reference::build(&scene);
        let m = measure(&scene, &reference, &g, &rendered);
        // Light 0 shadows the pixel under the occluder; light 1 the one at x = -50 (its ray
        // crosses z = 50 at x = 0).
        assert_eq!(m.exact, vec![mask(1, ".LLS."), mask(0, ".SLL.")]);
        let light1 = Counts {
            receiver_pixels: 3,
            reference_shadowed: 1,
            false_shadow: 0,
            false_lit: 0,
            // Only the pixel under the occluder has no shadowed neighbour.
            receivers_excl_boundary: 1,
            false_shadow_excl_boundary: 0,
            false_lit_excl_boundary: 0,
            // The last pixel is lit by the renderer but receives nothing in the reference.
            receiver_mismatch: 1,
        };
        let light0 = Counts {
            receiver_pixels: 3,
            reference_shadowed: 1,
            false_shadow: 1,
            false_lit: 1,
            receivers_excl_boundary: 1,
            false_shadow_excl_boundary: 0,
            false_lit_excl_boundary: 0,
            receiver_mismatch: 0,
        };
        assert_eq!(m.per_light, vec![(1, light1), (0, light0)]);
        let mut total = light1;
        total.add(&light0);
        assert_eq!(m.total, total);
        assert_eq!((m.total.receiver_pixels, m.total.false_shadow), (6, 1));
        assert_eq!((m.total.false_lit, m.total.receiver_mismatch), (1, 1));
    }

    #[test]
    fn kept_exact_masks_give_the_same_measurement_until_cleared() {
        let scene = scene();
        let g = gbuffer();
        let rendered = [mask(0, ".LSL."), mask(1, ".LLSL")];
        let reference = Reference::build(&scene);
        let direct = measure(&scene, &reference, &g, &rendered);
        let mut kept = ExactMasks::new();
        assert_eq!(kept.get(5, 1, 0), None);
        assert_eq!(kept.measure(&scene, &g, &rendered), direct);
        assert_eq!(kept.get(5, 1, 0), Some(&mask(0, ".SLL.")));
        // A kept mask is reused as it is, even where the G-buffer changed.
        let mut moved = g.clone();
        moved.kind = vec![0; 5];
        assert_eq!(kept.measure(&scene, &moved, &rendered), direct);
        kept.clear();
        assert_eq!(kept.get(5, 1, 0), None);
        let fresh = kept.measure(&scene, &moved, &rendered);
        assert_eq!(fresh.exact[0], mask(0, "....."));
        assert_eq!(fresh.total.receiver_pixels, 0);
    }
}
