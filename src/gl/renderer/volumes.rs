//! The base pass and the stages between it and the lights: the depth the planner reads, each
//! light's volume draws uploaded, the subdivided lights' fragments.

use super::*;

impl<'a> FrameRun<'a> {
    /// The unlit world.
    pub(crate) fn base_pass(&mut self) -> Flow<()> {
        let gl = self.ctx.gl;
        self.timer.begin(gl, PassId::frame(Stage::Base));
        self.target.bind(gl);
        match (self.fixed, self.gbuffer_target()) {
            (Some(ff), _) => fixed::base::draw(&self.ctx, ff),
            (None, Some(gtarget)) => {
                // The frame's own surfaces make the G-buffer, from the same fragments.
                let reach_lights = self.reach_candidates();
                gtarget.attach_to_bound(gl);
                GBufferTarget::draw_into_bound(gl);
                let program = &self.programs.unlit_gbuffer;
                passes::base::draw(&self.ctx, program, Some(&reach_lights));
                GBufferTarget::detach_from_bound(gl);
                self.reach_lights = Some(reach_lights);
            }
            (None, None) => passes::base::draw(&self.ctx, &self.programs.unlit, None),
        }
        go_on!(self.step(StepKind::Base, None, None, Self::color_image));
        Ok(ControlFlow::Continue(()))
    }

    /// Whether the frame's depth buffer is 32-bit float (part of what the planner's depth
    /// is keyed by).
    pub(crate) fn float_depth(&self) -> bool {
        self.target.float_depth
    }

    /// The frame's depth for the planner after the base pass, timed as its own stage: reduced
    /// by a shader to 4×4 block maxima, or read whole.
    pub(crate) fn depth_for_planner(
        &mut self,
        reduced: bool,
    ) -> Result<Option<DepthPyramid>, RenderError> {
        let gl = self.ctx.gl;
        self.timer.end(gl);
        let t = Instant::now();
        let depth = self.read_depth(reduced)?;
        self.timer.record_cpu(
            PassId::frame(Stage::Occlusion),
            t.elapsed().as_secs_f64() * 1e3,
        );
        self.target.bind(gl);
        Ok(depth)
    }

    /// The planner takes the last frame's depth: nothing is read, the base pass ends here.
    pub(crate) fn depth_reused(&mut self) {
        self.timer.end(self.ctx.gl);
        self.cache.depth_reused = true;
    }

    /// The frame's depth: reduced by a shader, or read whole.
    fn read_depth(&mut self, reduced: bool) -> Result<Option<DepthPyramid>, RenderError> {
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

    /// A shadow-volume light's draws, as the planner made them, uploaded with the meshes of
    /// the groups the GPU extrudes (`groups`, where it has any); returns the milliseconds the
    /// planner spent building its parts this frame (0 where it reused them).
    pub(crate) fn upload_volumes(
        &mut self,
        lp: &LightPlan,
        v: &LightVolumeDraws,
        groups: Option<&CasterGroups>,
    ) -> Result<f64, RenderError> {
        self.volume_buffers
            .upload(self.ctx.gl, v)
            .map_err(RenderError::Gl)?;
        let build_ms = if v.stats.rebuilt {
            v.stats.build_ms
        } else {
            0.0
        };
        self.timer
            .record_cpu(PassId::light(lp.light, Stage::VolumeBuild), build_ms);
        self.cache.volume_parts_built += v.stats.parts_built;
        self.cache.volume_parts_reused += v.stats.parts_reused;
        self.volume_stats.push(v.stats);
        if let Some(groups) = groups {
            self.extruded_draws(lp, groups)?;
        }
        Ok(build_ms)
    }

    /// Records the milliseconds of a stage the CPU ran between the GL's passes.
    pub(crate) fn record_cpu(&mut self, pass: PassId, ms: f64) {
        self.timer.record_cpu(pass, ms);
    }

    /// Every volume light's draws for this frame's stencil passes, by light.
    pub(crate) fn use_volume_draws(&mut self, draws: HashMap<usize, &'a LightVolumeDraws>) {
        self.volume_draws = draws;
    }

    /// The light's groups the GPU extrudes: their meshes uploaded where their pose changed, and
    /// their draws for the stencil pass.
    fn extruded_draws(&mut self, lp: &LightPlan, groups: &CasterGroups) -> Result<(), RenderError> {
        let (gl, scene) = (self.ctx.gl, self.ctx.scene);
        let double = self.ctx.settings.shadow_volume.casters == crate::options::VolumeCasters::Both;
        let light = scene.lights[lp.light].position;
        let mut draws = Vec::with_capacity(lp.extruded.len());
        for &(g, counting) in &lp.extruded {
            let group = &groups.groups[g];
            if let Some(ms) = self
                .extrusions
                .ensure(gl, g, group, double)
                .map_err(RenderError::Gl)?
            {
                self.cache.extrusions_uploaded += 1;
                self.own_ms += ms;
            }
            let model = crate::shadow::volume::group_transform(scene, group.owner);
            draws.extend(self.extrusions.draw_of(g, model, light, counting));
        }
        self.extruded.insert(lp.light, draws);
        Ok(())
    }

    /// Each subdivided light's fragments made current (kept while the light and the triangles
    /// in its range stay as they were).
    pub(crate) fn subdivisions(&mut self) -> Result<(), RenderError> {
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
        let draws = self.volume_draws.get(&lp.light)?;
        let extruded = self.extruded.get(&lp.light).map_or(&[][..], Vec::as_slice);
        self.volume_buffers.with(draws, extruded)
    }
}
