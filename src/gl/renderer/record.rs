//! Lights recording their decisions as their lit passes shade (`gl::record`), and their
//! masks made from the record after the frame.

use super::*;
use crate::truth::recorded::{Rect, Undrawn, mask_from_record};

/// A light whose lit passes record into a layer of the frame's record.
pub(crate) struct RecordedLight {
    pub light: usize,
    pub layer: u32,
    pub undrawn: Undrawn,
}

impl FrameRun<'_> {
    /// Gives light `lp` the next layer when the frame records and the light's lit pass says
    /// all its mask would: not a hybrid light (its mask brings the stats of its volumes' own
    /// counting), not the fill shading (whose lit pass lights shadowed pixels too, darkened
    /// after), and while layers are left (the others' masks are drawn again).
    pub(super) fn assign_layer(&mut self, lp: &LightPlan) {
        let Some(record) = self.record else {
            return;
        };
        let stenciled = self.volumes_of(lp).is_some() || self.fragments_of(lp).is_some();
        let fill = self.fragments_of(lp).is_none()
            && self.volumes_of(lp).is_some()
            && self.ctx.settings.shadow_volume.shading == VolumeShading::Fill;
        let layer = self.recorded.len() as u32;
        if self.fixed.is_some() || lp.technique == Technique::Hybrid || fill {
            return;
        }
        if layer >= record.layers {
            return;
        }
        let alpha_test =
            lp.technique.uses_maps() && self.ctx.settings.shadow_map.result == CompareResult::Alpha;
        let undrawn = match stenciled || alpha_test {
            true => Undrawn::ShadowedWhereReached,
            false => Undrawn::NotReceiver,
        };
        self.recorded.push(RecordedLight {
            light: lp.light,
            layer,
            undrawn,
        });
    }

    /// Light `lp`'s layer, when it records.
    pub(super) fn layer_of(&self, lp: &LightPlan) -> Option<u32> {
        self.recorded
            .iter()
            .find(|r| r.light == lp.light)
            .map(|r| r.layer)
    }

    /// Attaches light `lp`'s layer (cleared within its scissor) to the bound frame before its
    /// lit passes; returns whether it did, for `end_record`.
    pub(super) fn begin_record(&self, lp: &LightPlan) -> bool {
        let (Some(record), Some(layer)) = (self.record, self.layer_of(lp)) else {
            return false;
        };
        set_scissor(self.ctx.gl, lp.scissor);
        record.attach(self.ctx.gl, layer);
        true
    }

    /// The frame's one colour output again after a recording light's lit passes.
    pub(super) fn end_record(&self, began: bool) {
        if began {
            DecisionRecord::detach(self.ctx.gl);
        }
    }

    /// Light `lp`'s mask from its layer, or None when it did not record.
    pub(super) fn recorded_mask(&self, lp: &LightPlan, gbuffer: &GBuffer) -> Option<Mask> {
        let record = self.record?;
        let r = self.recorded.iter().find(|r| r.light == lp.light)?;
        let values = record.read(self.ctx.gl, r.layer);
        let rect = Rect::of_scissor(lp.scissor, record.width, record.height);
        let light = &self.ctx.scene.lights[lp.light];
        Some(mask_from_record(
            (light, lp.light),
            gbuffer,
            &values,
            rect,
            r.undrawn,
        ))
    }
}
