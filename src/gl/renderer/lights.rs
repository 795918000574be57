//! Each light's passes: volumes counted into the stencil and lit over it, or lit through its
//! maps; hybrid and subdivided lights; the overlays over the finished frame.

use super::*;
impl<'a> FrameRun<'a> {
    /// Each planned light's passes: its volumes counted and lit through the stencil, or lit
    /// through its shadow maps (or without shadows). Returns the stencil counts asked for.
    pub(crate) fn light_passes(&mut self, maps: &[ViewMap]) -> Flow<Option<StencilImage>> {
        let plan = self.ctx.plan;
        let mut stencil_image = None;
        for (pi, lp) in plan.lights.iter().enumerate() {
            // Over the map budget, each light's maps are drawn just before its passes, into
            // textures the lights before it may have used.
            let own;
            let maps = if plan.maps_per_light && lp.technique.uses_maps() {
                self.shadow_maps.next_stamp();
                own = go_on!(self.light_maps(pi));
                self.target.bind(self.ctx.gl);
                &own[..]
            } else {
                maps
            };
            set_scissor(self.ctx.gl, lp.scissor);
            self.assign_layer(lp);
            if lp.technique == Technique::Hybrid {
                if let Some(image) = go_on!(self.hybrid_light(pi, maps)) {
                    stencil_image = Some(image);
                }
            } else if let Some(f) = self.fragments_of(lp) {
                if let Some(image) = go_on!(self.subdivision_light(lp, &f)) {
                    stencil_image = Some(image);
                }
            } else if self.volumes_of(lp).is_some() {
                if let Some(image) = go_on!(self.volume_light(lp)) {
                    stencil_image = Some(image);
                }
            } else {
                self.timer
                    .begin(self.ctx.gl, PassId::light(lp.light, Stage::Lit));
                let bindings = self.bindings(maps, pi);
                // Marks on every surface are cleared once for all the light's passes (marks
                // on overlapping surfaces alone are cleared by the pass that makes them).
                let once = self.ctx.settings.lighting.light_once;
                if Marks::of(once, lit_passes(lp, &bindings)) == Marks::Everywhere {
                    passes::lit::clear_marks(self.ctx.gl);
                }
                match self.fixed {
                    Some(ff) => fixed_maps(&self.ctx, ff, lp, &bindings, false),
                    None => {
                        let recording = self.begin_record(lp);
                        draw_maps(
                            &self.ctx,
                            lp,
                            &bindings,
                            |v| self.lit_program(v),
                            (MapPass::Lit, false),
                        );
                        self.end_record(recording);
                    }
                }
                go_on!(self.step(StepKind::Lit, Some(lp), None, Self::color_image));
                if self.mask_in_frame(lp) {
                    self.mask_now(lp, |run, _| run.map_mask(lp, maps, pi));
                }
            }
            self.queue.light_sent().map_err(RenderError::Gl)?;
        }
        if plan.maps_per_light {
            self.finish_maps();
        }
        Ok(ControlFlow::Continue(stencil_image))
    }

    /// Light `lp`'s stencil as it stands, when the request asks for it (`wraps`: its counts
    /// wrapped rather than saturated).
    pub(super) fn requested_stencil(&self, lp: &LightPlan, wraps: bool) -> Option<StencilImage> {
        let gl = self.ctx.gl;
        (self.request.stencil_of == Some(lp.light)).then(|| {
            let (w, h) = (self.target.width, self.target.height);
            let values = debug::read_stencil(gl, self.target.fbo, w, h);
            self.target.bind(gl);
            StencilImage {
                light: lp.light,
                width: w,
                height: h,
                values,
                wraps,
            }
        })
    }

    /// A hybrid light (Chan & Durand): its computation mask marked from its maps, its volumes
    /// counted where the mask lets them, then one lit pass where the map decides or the count
    /// is zero (`passes::hybrid`). Returns its stencil (mask bit and counts) when the request
    /// asks for it.
    pub(super) fn hybrid_light(
        &mut self,
        pi: usize,
        maps: &[ViewMap],
    ) -> Flow<Option<StencilImage>> {
        let gl = self.ctx.gl;
        let lp = &self.ctx.plan.lights[pi];
        let masked = self.ctx.settings.hybrid.mask;
        let bindings = self.bindings(maps, pi);
        let mark = |run: &Self, overwrite: bool| {
            draw_maps(
                &run.ctx,
                lp,
                &bindings,
                |v| run.lit_program(v),
                (MapPass::Mark { overwrite }, true),
            )
        };
        self.timer
            .begin(gl, PassId::light(lp.light, Stage::Classify));
        if masked {
            passes::lit::clear_marks(gl);
            mark(self, false);
        }
        self.timer
            .begin(gl, PassId::light(lp.light, Stage::Stencil));
        if let Some(v) = self.volumes_of(lp) {
            passes::stencil::draw(&self.ctx, &self.programs.volume, &v, lp.scissor, masked);
        }
        if !masked {
            self.timer
                .begin(gl, PassId::light(lp.light, Stage::Classify));
            mark(self, true);
        }
        let (w, h) = (self.target.width, self.target.height);
        let fbo = self.target.fbo;
        go_on!(self.step(StepKind::ComputationMask, Some(lp), None, |_| {
            debug::stencil_image(&debug::read_stencil(gl, fbo, w, h), w, h, true)
        }));
        let stencil = self.requested_stencil(lp, true);
        self.timer.begin(gl, PassId::light(lp.light, Stage::Lit));
        draw_maps(
            &self.ctx,
            lp,
            &bindings,
            |v| self.lit_program(v),
            (MapPass::Lit, true),
        );
        go_on!(self.step(StepKind::Lit, Some(lp), None, Self::color_image));
        if self.mask_in_frame(lp) {
            self.hybrid_mask_now(pi, maps);
        }
        Ok(ControlFlow::Continue(stencil))
    }

    /// A shadow-volume light: its volumes into the stencil, its lit pass where the count is
    /// zero (or everywhere, then the fill quad: `shadow_volume.shading = fill`). Returns its
    /// stencil counts when the request asks for them.
    pub(super) fn volume_light(&mut self, lp: &LightPlan) -> Flow<Option<StencilImage>> {
        let gl = self.ctx.gl;
        let o = self.ctx.settings;
        let fill = o.shadow_volume.shading == VolumeShading::Fill;
        self.timer
            .begin(gl, PassId::light(lp.light, Stage::Stencil));
        self.count_volumes(lp);
        let wraps = self.counts_wrap();
        go_on!(self.stencil_step(StepKind::Stencil, lp, wraps));
        let stencil = self.requested_stencil(lp, wraps);
        if self.mask_in_frame(lp) {
            self.mask_now(lp, |run, _| run.mask_over_stencil(lp));
        }
        go_on!(self.lit_over_stencil(lp, !fill));
        if fill {
            self.timer.begin(gl, PassId::light(lp.light, Stage::Fill));
            match self.fixed {
                Some(ff) => fixed::stencil::fill(gl, ff, FILL_SHADE),
                None => passes::stencil::fill(gl, &self.programs.fill, self.empty_vao, FILL_SHADE),
            }
            go_on!(self.step(StepKind::Fill, Some(lp), None, Self::color_image));
        }
        Ok(ControlFlow::Continue(stencil))
    }

    /// A subdivided light: its models' volumes counted (`subdivision.models = volumes`), its
    /// shadowed fragments marked into the same stencil, its lit pass where the stencil is
    /// zero. Returns its stencil when the request asks for it.
    pub(super) fn subdivision_light(
        &mut self,
        lp: &LightPlan,
        f: &LightFragmentDraw,
    ) -> Flow<Option<StencilImage>> {
        let gl = self.ctx.gl;
        self.timer
            .begin(gl, PassId::light(lp.light, Stage::Stencil));
        let counted = self.count_volumes(lp);
        let wraps = counted && self.counts_wrap();
        if counted {
            go_on!(self.stencil_step(StepKind::Stencil, lp, wraps));
        }
        self.mark_fragments(f, !counted);
        go_on!(self.stencil_step(StepKind::Fragments, lp, wraps));
        let stencil = self.requested_stencil(lp, wraps);
        if self.mask_in_frame(lp) {
            self.mask_now(lp, |run, _| run.mask_over_stencil(lp));
        }
        go_on!(self.lit_over_stencil(lp, true));
        Ok(ControlFlow::Continue(stencil))
    }

    /// Whether volume counts wrap rather than saturate.
    pub(super) fn counts_wrap(&self) -> bool {
        self.ctx.settings.shadow_volume.wrap == StencilWrap::Wrap
            || self.ctx.plan.stencil == StencilPasses::Separate
    }

    /// The light's volumes counted into the cleared stencil (a subdivided light's: its
    /// models', and the world's on models); false when it has none this frame (the stencil is
    /// left as it was).
    pub(super) fn count_volumes(&self, lp: &LightPlan) -> bool {
        let Some(v) = self.volumes_of(lp) else {
            return false;
        };
        match self.fixed {
            Some(ff) => fixed::stencil::draw(&self.ctx, ff, &v, lp.scissor),
            None => passes::stencil::draw(&self.ctx, &self.programs.volume, &v, lp.scissor, false),
        }
        true
    }

    /// A subdivided light's shadowed fragments marked into the stencil (cleared first with
    /// `clear`; else over the counts of its volumes).
    pub(super) fn mark_fragments(&self, f: &LightFragmentDraw, clear: bool) {
        match self.fixed {
            Some(ff) => fixed::stencil::mark_fragments(&self.ctx, ff, f, clear),
            None => passes::stencil::mark_fragments(&self.ctx, &self.programs.fragments, f, clear),
        }
    }

    /// A subdivided light's whole stencil, as its frame leaves it: its volumes counted, then
    /// its fragments marked over them.
    pub(super) fn subdivision_stencil(&self, lp: &LightPlan, f: &LightFragmentDraw) {
        let counted = self.count_volumes(lp);
        self.mark_fragments(f, !counted);
    }

    /// A walkthrough step showing light `lp`'s stencil as it stands (`wraps`: counts wrapped).
    pub(super) fn stencil_step(&mut self, kind: StepKind, lp: &LightPlan, wraps: bool) -> Flow<()> {
        let gl = self.ctx.gl;
        let (w, h) = (self.target.width, self.target.height);
        let fbo = self.target.fbo;
        self.step(kind, Some(lp), None, |_| {
            debug::stencil_image(&debug::read_stencil(gl, fbo, w, h), w, h, wraps)
        })
    }

    /// Light `lp`'s lit pass over the stencil its volumes or fragments left (`test`: only
    /// where it is zero; off, everywhere, for the fill variant).
    pub(super) fn lit_over_stencil(&mut self, lp: &LightPlan, test: bool) -> Flow<()> {
        self.timer
            .begin(self.ctx.gl, PassId::light(lp.light, Stage::Lit));
        let shadow = LitShadow::Stencil { test };
        match self.fixed {
            Some(ff) => fixed::lit::draw(&self.ctx, ff, lp, &shadow, &lp.receivers),
            None => {
                let recording = self.begin_record(lp);
                passes::lit::draw(
                    &self.ctx,
                    self.lit_program(LitVariant::plain(false)),
                    lp,
                    &shadow,
                    (
                        &lp.receivers,
                        Marks::of(self.ctx.settings.lighting.light_once, 1),
                    ),
                );
                self.end_record(recording);
            }
        }
        self.step(StepKind::Lit, Some(lp), None, Self::color_image)
    }

    /// Volumes and silhouettes drawn over the finished frame, when asked for (untimed).
    pub(super) fn overlays(&self) {
        let o = self.request.overlays;
        if !(o.volumes || o.silhouettes) {
            return;
        }
        self.target.bind(self.ctx.gl);
        let shown = self
            .ctx
            .plan
            .lights
            .iter()
            .filter(|lp| o.light.is_none_or(|l| l == lp.light));
        for lp in shown {
            if let Some(v) = self.volumes_of(lp) {
                passes::debug::volumes(
                    &self.ctx,
                    &self.programs.debug_volume,
                    &v,
                    o.volumes,
                    o.silhouettes,
                );
            }
        }
    }
}
