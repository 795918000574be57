//! Lights recording their decisions as their lit passes shade (`gl::record`), and their
//! masks made from the record after the frame.

use super::*;
use crate::gl::passes::gbuffer::REACH_LIGHTS;
use crate::truth::recorded::{Rect, mask_from_record};

/// A light whose lit passes record into a layer of the frame's record.
pub(crate) struct RecordedLight {
    pub light: usize,
    pub layer: u32,
    /// Its lit pass drops shadowed fragments before its shader (the stencil test): the pixels
    /// it reaches but did not draw are marked shadowed after the frame. (The alpha test of
    /// `shadow_map.result = alpha` keeps them while recording: `set_keep_shadowed`.)
    pub drops_shadowed: bool,
}

impl<'a> FrameRun<'a> {
    /// Gives light `lp` the next layer when the frame records and the light's lit pass says
    /// all its mask would: not a hybrid light (its mask brings the stats of its volumes' own
    /// counting), not the fill shading (whose lit pass lights shadowed pixels too, darkened
    /// after), and while layers are left (the others' masks are drawn again).
    pub(super) fn assign_layer(&mut self, lp: &LightPlan) {
        let Some(record) = self.record else {
            return;
        };
        // The stencil test drops shadowed fragments before the shader runs.
        let (volumes, fragments) = (
            self.volumes_of(lp).is_some(),
            self.fragments_of(lp).is_some(),
        );
        let stenciled = volumes || fragments;
        let fill =
            volumes && !fragments && self.ctx.settings.shadow_volume.shading == VolumeShading::Fill;
        let layer = self.recorded.len() as u32;
        if self.fixed.is_some() || lp.technique == Technique::Hybrid || fill {
            return;
        }
        if layer >= record.layers {
            return;
        }
        self.recorded.push(RecordedLight {
            light: lp.light,
            layer,
            drops_shadowed: stenciled,
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
        self.set_keep_shadowed(true);
        true
    }

    /// The frame's one colour output again after a recording light's lit passes.
    pub(super) fn end_record(&self, began: bool) {
        if began {
            DecisionRecord::detach(self.ctx.gl);
            self.set_keep_shadowed(false);
        }
    }

    /// Whether the lit programs' alpha test keeps rejected fragments (adding nothing, their
    /// decision recorded) rather than leaving: set on every lit program, whose uniforms keep
    /// it until set again, for a recording light's passes only.
    fn set_keep_shadowed(&self, keep: bool) {
        let gl = self.ctx.gl;
        for p in self.programs.lit.values() {
            p.bind(gl);
            p.set_i32(gl, "u_keep_shadowed", keep as i32);
        }
    }

    /// The G-buffer, when this frame writes one (asked for masks).
    pub(super) fn gbuffer_target(&self) -> Option<&'a GBufferTarget> {
        self.measure_targets
            .filter(|_| self.request.masks)
            .map(|(g, _)| g)
    }

    /// The lights given a reach bit when the base pass writes the G-buffer, before any light
    /// records: the first [`REACH_LIGHTS`] planned lights whose lit pass may drop shadowed
    /// fragments by the stencil test (volumes or subdivision; not hybrid lights or the fill
    /// shading, which do not record), none when the frame does not record.
    pub(super) fn reach_candidates(&self) -> Vec<usize> {
        if self.record.is_none() {
            return Vec::new();
        }
        let fill = self.ctx.settings.shadow_volume.shading == VolumeShading::Fill;
        self.ctx
            .plan
            .lights
            .iter()
            .filter(|lp| match lp.technique {
                Technique::Hybrid => false,
                Technique::Subdivision => true,
                _ => lp.counts_volumes() && !fill,
            })
            .map(|lp| lp.light)
            .take(REACH_LIGHTS)
            .collect()
    }

    /// After the frame, over the G-buffer `gtarget` holds: the pixels each recorded light that
    /// drops its shadowed fragments, without a reach bit (`reach_lights`), reaches but did not
    /// draw, marked shadowed in its layer (a full-screen pass each).
    pub(super) fn mark_reached(&self, gtarget: &GBufferTarget, reach_lights: &[usize]) {
        let Some(record) = self.record else {
            return;
        };
        let gl = self.ctx.gl;
        let beyond = self
            .recorded
            .iter()
            .filter(|r| r.drops_shadowed && !reach_lights.contains(&r.light));
        for r in beyond {
            let lp = self.ctx.plan.lights.iter().find(|lp| lp.light == r.light);
            let Some(lp) = lp else {
                continue;
            };
            record.bind_layer(gl, r.layer);
            set_scissor(gl, lp.scissor);
            passes::lit::draw_reached(
                &self.ctx,
                &self.programs.record_reach,
                lp,
                gtarget.textures(),
                self.empty_vao,
            );
        }
        set_scissor(gl, None);
    }

    /// Light `lp`'s mask from its layer, or None when it did not record; `reach`: the
    /// G-buffer's reach bits and the lights they stand for, in bit order.
    pub(super) fn recorded_mask(&self, lp: &LightPlan, reach: (&[u32], &[usize])) -> Option<Mask> {
        let record = self.record?;
        let r = self.recorded.iter().find(|r| r.light == lp.light)?;
        let values = record.read(self.ctx.gl, r.layer);
        let scissor = lp.scissor.map(|s| [s.x, s.y, s.width, s.height]);
        let rect = Rect::of_scissor(scissor, record.width, record.height);
        // A light drawing every fragment it reaches leaves none to mark (outside its clip
        // planes it draws none, and those are no receivers).
        let bit = match r.drops_shadowed {
            true => reach.1.iter().position(|&l| l == lp.light),
            false => None,
        };
        Some(mask_from_record(
            lp.light,
            (record.width, record.height),
            values.as_chunks::<2>().0,
            rect,
            bit.map(|b| (reach.0, b as u32)),
        ))
    }
}
