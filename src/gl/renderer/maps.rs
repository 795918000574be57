//! Shadow-map passes: every mapped light's views into their textures, and the lit or marking
//! passes that read them.

use super::*;

impl<'a> FrameRun<'a> {
    /// Every shadow-mapped light's views into their depth textures (drawn again only when
    /// the plan's key for the view changed).
    pub(crate) fn shadow_map_passes(&mut self) -> Flow<Vec<ViewMap>> {
        let (gl, plan) = (self.ctx.gl, self.ctx.plan);
        let sm = &self.ctx.settings.shadow_map;
        let mut maps: Vec<ViewMap> = Vec::new();
        let mut kinds: Vec<MapKey> = Vec::new();
        let any_ids = plan
            .lights
            .iter()
            .any(|lp| lp.technique.uses_maps() && lp.buffer == MapBuffer::Id);
        let fbo = if plan.any_maps() && (!self.copy || any_ids) {
            Some(self.shadow_maps.fbo(gl).map_err(RenderError::Gl)?)
        } else {
            None
        };
        for (pi, lp) in plan.lights.iter().enumerate() {
            if !lp.technique.uses_maps() {
                continue;
            }
            let buffer = lp.buffer;
            let (table, table_changed) = self
                .id_tables
                .table(
                    gl,
                    self.ctx.scene,
                    self.ctx.gpu,
                    buffer,
                    sm.id_unit,
                    lp.light,
                )
                .map_err(RenderError::Gl)?;
            for vi in 0..lp.views.len() {
                let (map, kind) = go_on!(self.map_view((pi, lp, vi), (table, table_changed), fbo));
                if !kinds.contains(&kind) {
                    kinds.push(kind);
                }
                maps.push(map);
            }
        }
        self.shadow_maps.release_unlike(gl, &kinds);
        Ok(ControlFlow::Continue(maps))
    }

    /// One view of a light into its map (its six faces for a cube), drawn again only when the
    /// plan's key for it changed; the map for the lit passes and the kind of texture it holds.
    fn map_view(
        &mut self,
        (pi, lp, vi): (usize, &LightPlan, usize),
        (table, table_changed): (Option<glow::Texture>, bool),
        fbo: Option<glow::Framebuffer>,
    ) -> Flow<(ViewMap, MapKey)> {
        let gl = self.ctx.gl;
        let sm = &self.ctx.settings.shadow_map;
        let (view, buffer) = (&lp.views[vi], lp.buffer);
        // A priority buffer's mip chain (never a cube: priority maps are six spots).
        let mipmapped = buffer == MapBuffer::Priority && sm.priority_mipmap;
        let cube = view.kind == ViewKind::Cube;
        let size = view.map_size(sm.size);
        let kind = MapKey {
            cube,
            size,
            bits: sm.depth_bits,
            buffer,
            levels: if mipmapped && !cube {
                priority_mips::levels(size)
            } else {
                1
            },
        };
        let (texture, mut holds) = self
            .shadow_maps
            .slot(gl, (lp.light, vi), kind)
            .map_err(RenderError::Gl)?;
        let ids = if buffer == MapBuffer::Id {
            let (t, fresh) = self
                .shadow_maps
                .id_texture(gl, lp.light, vi, size)
                .map_err(RenderError::Gl)?;
            if fresh {
                holds = None;
            }
            Some(t)
        } else {
            None
        };
        // Maps drawn with another table hold other priorities.
        if table_changed {
            holds = None;
        }
        let key = lp.view_keys.get(vi).copied().flatten();
        let faces = if key.is_some() && holds == key {
            self.cache.maps_reused += 1;
            Vec::new()
        } else {
            self.cache.maps_rendered += 1;
            view.face_view_projs(self.ctx.scene.lights[lp.light].position)
        };
        let drawn = !faces.is_empty();
        for (face, view_proj) in faces {
            let buffers = MapBuffers {
                depth: texture,
                ids,
                table,
                buffer,
            };
            go_on!(self.map_face(lp, vi, (face, view_proj), fbo, buffers));
        }
        if drawn && kind.levels > 1 {
            let mip_fbo = self.shadow_maps.fbo(gl).map_err(RenderError::Gl)?;
            priority_mips::build(
                gl,
                &self.programs.priority_mips,
                self.empty_vao,
                mip_fbo,
                (texture, size, kind.levels),
            );
        }
        self.shadow_maps.set_content(lp.light, vi, key);
        if ids.is_none() {
            ShadowMaps::configure(gl, texture, (cube, kind.levels > 1), sm.compare, sm.filter);
        }
        self.last_maps.push(LastMap {
            light: lp.light,
            view: vi,
            texture,
            ids,
            cube,
            size,
        });
        Ok(ControlFlow::Continue((
            ViewMap {
                plan_index: pi,
                view_index: vi,
                texture: ids.unwrap_or(texture),
                table,
            },
            kind,
        )))
    }

    /// One view (or cube face) of a light drawn into its map, and copied there from the frame
    /// when maps are copies.
    pub(super) fn map_face(
        &mut self,
        lp: &LightPlan,
        vi: usize,
        (face, view_proj): (Option<usize>, glam::Mat4),
        fbo: Option<glow::Framebuffer>,
        buffers: MapBuffers,
    ) -> Flow<()> {
        let gl = self.ctx.gl;
        let size = lp.views[vi].map_size(self.ctx.settings.shadow_map.size);
        let shown = face.or(Some(vi));
        let texture = buffers.depth;
        // ID buffers are drawn through the FBO: their IDs are colour, the frame's is not theirs.
        let through_fbo = !self.copy || buffers.ids.is_some();
        let target = match fbo {
            Some(fbo) if through_fbo => DepthTarget::Fbo {
                fbo,
                texture,
                colour: buffers.ids,
            },
            _ => DepthTarget::Copy {
                frame: self.target,
                texture,
            },
        };
        self.timer
            .begin(gl, PassId::light(lp.light, Stage::ShadowMap));
        let view = passes::shadow_map::MapView {
            view_proj,
            size,
            cube_face: face,
            offset: lp.map_offset,
            casters: lp.view_casters.get(vi).map(Vec::as_slice),
            depth_view_proj: lp.views[vi].depth_view_proj,
            buffer: buffers.buffer,
            table: buffers.table,
            light_position: self.ctx.scene.lights[lp.light].position,
        };
        let depth_program = if view.depth_view_proj.is_some() {
            &self.programs.depth_warp
        } else {
            self.programs
                .depth_buffers
                .get(&buffers.buffer)
                .unwrap_or(&self.programs.depth)
        };
        match self.fixed {
            Some(ff) => fixed::shadow_map::render(&self.ctx, ff, &view, &target),
            None => passes::shadow_map::render(&self.ctx, depth_program, &view, &target),
        }
        let copy = !through_fbo;
        let fbo_of_frame = self.target.fbo;
        go_on!(self.step(StepKind::LightView, Some(lp), shown, |_| {
            // An ID buffer shows its IDs; a priority buffer's depth is its priority ramp.
            if let Some(ids) = buffers.ids {
                return debug::id_image(gl, ids, size);
            }
            let depth = if copy {
                debug::read_depth(gl, fbo_of_frame, size, size)
            } else {
                debug::read_depth_texture(gl, texture, face, size)
            };
            debug::depth_image(&depth, size, size)
        }));
        if copy {
            self.timer
                .begin(gl, PassId::light(lp.light, Stage::DepthCopy));
            copy_depth(gl, self.target, texture, size, face);
            go_on!(self.step(StepKind::DepthCopy, Some(lp), shown, |_| {
                let depth = debug::read_depth_texture(gl, texture, face, size);
                debug::depth_image(&depth, size, size)
            }));
        }
        Ok(ControlFlow::Continue(()))
    }
}

impl<'a> FrameRun<'a> {
    /// The shadow-map bindings of light `pi`'s lit passes: per view, whether it is a cube,
    /// its map, the receivers it lights and its rectangle.
    pub(super) fn bindings(
        &self,
        maps: &[ViewMap],
        pi: usize,
    ) -> Vec<(bool, ShadowBinding<'a>, &'a [u32], Option<Scissor>)> {
        let lp: &'a LightPlan = &self.ctx.plan.lights[pi];
        maps.iter()
            .filter(|m| m.plan_index == pi)
            .map(|m| {
                let view = &lp.views[m.view_index];
                let receivers = lp
                    .view_receivers
                    .get(m.view_index)
                    .map_or(lp.receivers.as_slice(), Vec::as_slice);
                let rect = lp.view_scissors.get(m.view_index).copied().flatten();
                (
                    view.kind == ViewKind::Cube,
                    ShadowBinding {
                        view,
                        texture: m.texture,
                        table: m.table,
                    },
                    receivers,
                    rect.or(lp.scissor),
                )
            })
            .collect()
    }
}

/// The fixed-function lit (or mask) passes of a light: one per shadow map view, or one without
/// shadows.
pub(super) fn fixed_maps(
    ctx: &PassContext,
    ff: &FixedFunction,
    lp: &LightPlan,
    bindings: &[(bool, ShadowBinding, &[u32], Option<Scissor>)],
    mask: bool,
) {
    let pass = |s: &LitShadow, receivers: &[u32]| {
        if mask {
            fixed::lit::draw_mask(ctx, ff, lp, s, receivers);
        } else {
            fixed::lit::draw(ctx, ff, lp, s, receivers);
        }
    };
    if bindings.is_empty() {
        pass(&LitShadow::None, &lp.receivers);
    }
    for (_, b, receivers, rect) in bindings {
        set_scissor(ctx.gl, *rect);
        pass(&LitShadow::Map(b), receivers);
    }
    set_scissor(ctx.gl, lp.scissor);
}

/// What a light's map passes write.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum MapPass {
    /// Light, added to the frame.
    Lit,
    /// The decision, into the mask target.
    Mask,
    /// The hybrid's computation mask, into the stencil (`overwrite`: over counts).
    Mark { overwrite: bool },
}

/// One light's lit (or mask, or marking) passes: one per shadow map view, one for an omni
/// light's six merged spots, or one without shadows; `hybrid` wraps the maps in
/// `LitShadow::Hybrid`.
pub(super) fn draw_maps<'p>(
    ctx: &PassContext,
    lp: &LightPlan,
    bindings: &[(bool, ShadowBinding, &[u32], Option<Scissor>)],
    program: impl Fn(LitVariant) -> &'p Program,
    (kind, hybrid): (MapPass, bool),
) {
    let pass = |six: bool, cube: bool, s: &LitShadow, receivers: &[u32]| {
        let shadow_map = !matches!(s, LitShadow::None);
        let v = LitVariant {
            shadow_map,
            cube,
            six,
            mask: kind == MapPass::Mask,
            hybrid,
            warp_depth: shadow_map && lp.technique == Technique::Tsm,
            buffer: if shadow_map {
                lp.buffer
            } else {
                MapBuffer::Depth
            },
        };
        let p = program(v);
        let wrapped;
        let s = if hybrid {
            wrapped = LitShadow::Hybrid(s);
            &wrapped
        } else {
            s
        };
        match kind {
            MapPass::Lit => passes::lit::draw(ctx, p, lp, s, receivers),
            MapPass::Mask => passes::lit::draw_mask(ctx, p, lp, s, receivers),
            MapPass::Mark { overwrite } => {
                passes::hybrid::mark(ctx, p, lp, s, receivers, overwrite)
            }
        }
    };
    if bindings.is_empty() {
        pass(false, false, &LitShadow::None, &lp.receivers);
    }
    if lp.merged && bindings.len() == 6 {
        let maps: Vec<&ShadowBinding> = bindings.iter().map(|(_, b, _, _)| b).collect();
        pass(true, false, &LitShadow::Faces(&maps), &lp.receivers);
        return;
    }
    for (cube, b, receivers, rect) in bindings {
        set_scissor(ctx.gl, *rect);
        pass(false, *cube, &LitShadow::Map(b), receivers);
    }
    set_scissor(ctx.gl, lp.scissor);
}
