//! The base pass and what follows it before the lights: the depth the planner reads, the
//! volume draws uploaded, the subdivided lights' fragments.

use super::*;
impl<'a> FrameRun<'a> {
    /// The unlit world, then the depth the planner asks for.
    pub(super) fn base_pass(&mut self) -> Flow<()> {
        let gl = self.ctx.gl;
        self.timer.begin(gl, PassId::frame(Stage::Base));
        self.target.bind(gl);
        match self.fixed {
            Some(ff) => fixed::base::draw(&self.ctx, ff),
            None => passes::base::draw(&self.ctx, &self.programs.unlit),
        }
        go_on!(self.step(StepKind::Base, None, None, Self::color_image));
        let need = self.planner.depth_need(
            self.ctx.scene,
            self.ctx.plan,
            self.ctx.options,
            self.target.float_depth,
        );
        self.cache.depth_reused = need == DepthNeed::Reuse;
        if let DepthNeed::Read { reduced } = need {
            self.timer.end(gl);
            let t = Instant::now();
            let depth = self.read_depth(reduced)?;
            self.timer.record_cpu(
                PassId::frame(Stage::Occlusion),
                t.elapsed().as_secs_f64() * 1e3,
            );
            self.target.bind(gl);
            self.planner.take_depth(depth, self.ctx.options);
        } else if need == DepthNeed::Reuse {
            self.timer.end(gl);
        }
        Ok(ControlFlow::Continue(()))
    }

    /// The frame's depth for the planner: reduced by a shader, or read whole.
    pub(super) fn read_depth(
        &mut self,
        reduced: bool,
    ) -> Result<Option<DepthPyramid>, RenderError> {
        let gl = self.ctx.gl;
        let (w, h) = (self.target.width, self.target.height);
        if !reduced {
            let values = debug::read_depth_bottom_up(gl, self.target.fbo, w, h);
            return Ok(DepthPyramid::from_bottom_up(values, w as usize, h as usize));
        }
        if !self.depth_reducer.as_ref().is_some_and(|r| r.fits(w, h)) {
            if let Some(old) = self.depth_reducer.take() {
                old.delete(gl);
            }
            let r = DepthReducer::new(gl, w, h).map_err(RenderError::Gl)?;
            *self.depth_reducer = Some(r);
        }
        let reducer = self.depth_reducer.as_ref().expect("created above");
        Ok(reducer.read(gl, &self.programs.depth_reduce, self.empty_vao, self.target))
    }

    /// Each shadow-volume light's draws from the planner, uploaded.
    pub(super) fn volume_draws(&mut self) -> Result<(), RenderError> {
        let (gl, plan) = (self.ctx.gl, self.ctx.plan);
        if !plan.any_volumes() {
            return Ok(());
        }
        let prepare_start = Instant::now();
        let mut builds_ms = 0.0;
        for lp in plan.lights.iter().filter(|l| l.counts_volumes()) {
            let v = self
                .planner
                .volume_draws(self.ctx.scene, plan, lp, self.ctx.options)?;
            if let Err(e) = self.volume_buffers.upload(gl, v) {
                self.planner.forget_volume_draws(lp.light);
                return Err(RenderError::Gl(e));
            }
            let build_ms = if v.stats.rebuilt {
                v.stats.build_ms
            } else {
                0.0
            };
            self.timer
                .record_cpu(PassId::light(lp.light, Stage::VolumeBuild), build_ms);
            builds_ms += build_ms;
            self.cache.volume_parts_built += v.stats.parts_built;
            self.cache.volume_parts_reused += v.stats.parts_reused;
            self.volume_stats.push(v.stats);
            self.extruded_draws(lp)?;
        }
        // The per-frame decisions on the pieces (receivers, rectangles, merges, depth clips)
        // and the uploads, less the builds timed above.
        let ms = prepare_start.elapsed().as_secs_f64() * 1e3 - builds_ms;
        self.timer
            .record_cpu(PassId::frame(Stage::VolumePieces), ms.max(0.0));
        Ok(())
    }

    /// The light's groups the GPU extrudes: their meshes uploaded where their pose changed, and
    /// their draws for the stencil pass.
    pub(super) fn extruded_draws(&mut self, lp: &LightPlan) -> Result<(), RenderError> {
        if lp.extruded.is_empty() {
            return Ok(());
        }
        let (gl, scene) = (self.ctx.gl, self.ctx.scene);
        let groups = self.planner.casters(scene);
        let double = self.ctx.options.shadow_volume.casters == crate::options::VolumeCasters::Both;
        let light = scene.lights[lp.light].position;
        let mut draws = Vec::with_capacity(lp.extruded.len());
        for &(g, counting) in &lp.extruded {
            let group = &groups.groups[g];
            if self
                .extrusions
                .ensure(gl, g, group, double)
                .map_err(RenderError::Gl)?
            {
                self.cache.extrusions_uploaded += 1;
            }
            let model = crate::shadow::volume::group_transform(scene, group.owner);
            draws.extend(self.extrusions.draw_of(g, model, light, counting));
        }
        self.extruded.insert(lp.light, draws);
        Ok(())
    }

    /// Each subdivided light's fragments made current (kept while the light and the triangles
    /// in its range stay as they were).
    pub(super) fn subdivisions(&mut self) -> Result<(), RenderError> {
        let (gl, plan) = (self.ctx.gl, self.ctx.plan);
        if !plan.any(Technique::Subdivision) {
            return Ok(());
        }
        // The pass before is over: the CPU work here is timed on its own.
        self.timer.end(gl);
        for lp in plan.lights.iter() {
            if lp.technique != Technique::Subdivision {
                continue;
            }
            let geometry = lp.subdivided.unwrap_or(Geometry::Everything);
            let update = self
                .fragments
                .update(gl, self.ctx.scene, (lp.light, geometry))?;
            self.timer
                .record_cpu(PassId::light(lp.light, Stage::Subdivision), update.ms);
            self.cache.subdivisions_renewed += usize::from(update.renewed);
            self.cache.fragment_triangles += self
                .fragments
                .draw_of(lp.light)
                .map_or(0, |f| f.triangles());
        }
        Ok(())
    }

    /// The light's shadowed fragments, when it is subdivided this frame.
    pub(super) fn fragments_of(&self, lp: &LightPlan) -> Option<LightFragmentDraw> {
        (lp.technique == Technique::Subdivision)
            .then(|| self.fragments.draw_of(lp.light))
            .flatten()
    }

    /// The light's volume draws with their buffers, when it has volumes this frame.
    pub(super) fn volumes_of(&self, lp: &LightPlan) -> Option<LightVolumes<'_>> {
        if !lp.counts_volumes() {
            return None;
        }
        let draws = self.planner.last_volume_draws(lp.light)?;
        let extruded = self.extruded.get(&lp.light).map_or(&[][..], Vec::as_slice);
        self.volume_buffers.with(draws, extruded)
    }
}
