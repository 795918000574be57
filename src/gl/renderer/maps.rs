//! Shadow-map passes: every mapped light's views into their textures, and the lit or marking
//! passes that read them.

use super::*;
use crate::options::CasterSpace;
use crate::plan::ImageCasters;

impl<'a> FrameRun<'a> {
    /// Every shadow-mapped light's views into their depth textures (drawn again only when
    /// the plan's key for the view changed), when they fit the budget together; none when
    /// each light's come just before its own pass (`Plan::maps_per_light`, `light_maps`).
    pub(crate) fn shadow_map_passes(&mut self) -> Flow<Vec<ViewMap>> {
        let plan = self.ctx.plan;
        let mut maps: Vec<ViewMap> = Vec::new();
        self.shadow_maps.start_frame();
        if plan.maps_per_light {
            return Ok(ControlFlow::Continue(maps));
        }
        for (pi, lp) in plan.lights.iter().enumerate() {
            if lp.technique.uses_maps() {
                maps.extend(go_on!(self.light_maps(pi)));
                self.queue.light_sent().map_err(RenderError::Gl)?;
            }
        }
        self.finish_maps();
        Ok(ControlFlow::Continue(maps))
    }

    /// Light `pi`'s views into their depth textures (drawn again only when the plan's key for
    /// the view changed), for its lit passes.
    pub(crate) fn light_maps(&mut self, pi: usize) -> Flow<Vec<ViewMap>> {
        let (gl, plan) = (self.ctx.gl, self.ctx.plan);
        let lp = &plan.lights[pi];
        let sm = &self.ctx.settings.shadow_map;
        let buffer = lp.buffer;
        let fbo = if !self.copy || buffer == MapBuffer::Id {
            Some(self.shadow_maps.fbo(gl).map_err(RenderError::Gl)?)
        } else {
            None
        };
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
        // A light's scissor is its lit pass's, not its maps': the one before may have set it.
        set_scissor(gl, None);
        let mut maps = Vec::with_capacity(lp.views.len());
        for vi in 0..lp.views.len() {
            let (map, kind) = go_on!(self.map_view((pi, lp, vi), (table, table_changed), fbo));
            if !self.map_kinds.contains(&kind) {
                self.map_kinds.push(kind);
            }
            maps.push(map);
        }
        Ok(ControlFlow::Continue(maps))
    }

    /// After the frame's last map: the textures of kinds it no longer draws, and the static
    /// maps of views drawn whole now, deleted.
    pub(crate) fn finish_maps(&mut self) {
        let (gl, plan) = (self.ctx.gl, self.ctx.plan);
        self.shadow_maps.release_unlike(gl, &self.map_kinds);
        let lights: Vec<usize> = plan
            .lights
            .iter()
            .filter(|lp| lp.technique.uses_maps())
            .map(|lp| lp.light)
            .collect();
        let split: Vec<(usize, usize)> = plan
            .lights
            .iter()
            .flat_map(|lp| {
                let keys = lp.view_static_keys.iter().enumerate();
                keys.filter(|(_, k)| k.is_some())
                    .map(|(vi, _)| (lp.light, vi))
            })
            .collect();
        self.shadow_maps.release_statics(gl, &lights, &split);
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
        let cube = view.kind == ViewKind::Cube;
        let size = view.map_size();
        let kind = MapKey {
            cube,
            size,
            bits: sm.depth_bits,
            buffer,
            levels: map_memory::view_levels(buffer, sm.priority_mipmap, cube, size),
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
        let drawn = key.is_none() || holds != key;
        let buffers = MapBuffers {
            depth: texture,
            ids,
            table,
            buffer,
        };
        if drawn {
            // What the texture held is gone, whether or not the frame stops before the end.
            self.shadow_maps.set_content(lp.light, vi, None);
            self.cache.maps_rendered += 1;
            let eye = self.ctx.scene.lights[lp.light].position;
            let faces = view.face_view_projs(eye, self.map_origin(lp));
            match lp.view_static_keys.get(vi).copied().flatten() {
                Some(static_key) => {
                    go_on!(self.map_over_static((lp, vi), &faces, static_key, buffers, kind))
                }
                None => go_on!(self.map_base_faces((lp, vi), &faces, fbo, buffers)),
            }
        } else {
            self.cache.maps_reused += 1;
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

    /// View `vi` of light `lp` made from its static map (the casters that do not move): the
    /// static map drawn first where it does not hold `static_key`, then per image copied into
    /// the map and the moving casters drawn over the copy, straight into the map (a depth
    /// map is the nearest depth of its casters, whatever the order they are drawn in).
    fn map_over_static(
        &mut self,
        (lp, vi): (&LightPlan, usize),
        faces: &[(Option<usize>, glam::Mat4)],
        static_key: u64,
        buffers: MapBuffers,
        kind: MapKey,
    ) -> Flow<()> {
        let gl = self.ctx.gl;
        let at = (lp.light, vi);
        let (kept, holds) = self
            .shadow_maps
            .static_slot(gl, at, kind)
            .map_err(RenderError::Gl)?;
        if holds == Some(static_key) {
            self.cache.maps_models_only += 1;
        } else {
            self.shadow_maps.set_static_content(at, None);
            self.cache.maps_static_drawn += 1;
            let fbo = (!self.copy)
                .then(|| self.shadow_maps.fbo(gl))
                .transpose()
                .map_err(RenderError::Gl)?;
            let into_static = MapBuffers {
                depth: kept,
                ..buffers
            };
            go_on!(self.map_base_faces((lp, vi), faces, fbo, into_static));
            self.shadow_maps.set_static_content(at, Some(static_key));
        }
        let size = lp.views[vi].map_size();
        let fbo = self.shadow_maps.fbo(gl).map_err(RenderError::Gl)?;
        self.timer
            .begin(gl, PassId::light(lp.light, Stage::ShadowMap));
        for (i, &(face, view_proj)) in faces.iter().enumerate() {
            self.shadow_maps
                .copy_static(gl, at, buffers.depth, face, size)
                .map_err(RenderError::Gl)?;
            let moving = image_casters(lp, vi, i, |c| &c.moving).filter(|m| !m.is_empty());
            if moving.is_some() {
                let draw = FaceDraw {
                    face,
                    view_proj,
                    casters: moving,
                    over: true,
                };
                go_on!(self.map_face(lp, vi, draw, Some(fbo), buffers));
            }
        }
        Ok(ControlFlow::Continue(()))
    }

    /// One view (or cube face) of a light drawn into its map, and copied there from the frame
    /// when maps are copies (never over a static map's copy, which is in the map already).
    /// Every face of view `vi` drawn into `buffers` with the casters that do not move (all of
    /// them where none does).
    fn map_base_faces(
        &mut self,
        (lp, vi): (&LightPlan, usize),
        faces: &[(Option<usize>, glam::Mat4)],
        fbo: Option<glow::Framebuffer>,
        buffers: MapBuffers,
    ) -> Flow<()> {
        for (i, &(face, view_proj)) in faces.iter().enumerate() {
            let casters = image_casters(lp, vi, i, |c| &c.base);
            let draw = FaceDraw {
                face,
                view_proj,
                casters,
                over: false,
            };
            go_on!(self.map_face(lp, vi, draw, fbo, buffers));
        }
        Ok(ControlFlow::Continue(()))
    }

    /// The origin of the positions a light's depth pass transforms
    /// (`shadow_map.caster_space`): the light's position, or none (world positions) where the
    /// paper's space is chosen or the legacy pipeline loads the matrices itself.
    fn map_origin(&self, lp: &LightPlan) -> Option<glam::Vec3> {
        let relative = self.ctx.settings.shadow_map.caster_space == CasterSpace::Light;
        (relative && self.fixed.is_none()).then(|| self.ctx.scene.lights[lp.light].position)
    }

    pub(super) fn map_face(
        &mut self,
        lp: &LightPlan,
        vi: usize,
        draw: FaceDraw,
        fbo: Option<glow::Framebuffer>,
        buffers: MapBuffers,
    ) -> Flow<()> {
        let gl = self.ctx.gl;
        let size = lp.views[vi].map_size();
        let (face, view_proj) = (draw.face, draw.view_proj);
        let origin = self.map_origin(lp);
        let shown = face.or(Some(vi));
        let texture = buffers.depth;
        // ID buffers are drawn through the FBO: their IDs are colour, the frame's is not theirs.
        let through_fbo = !self.copy || buffers.ids.is_some() || draw.over;
        let target = match fbo {
            Some(fbo) if through_fbo => DepthTarget::Fbo {
                fbo,
                texture,
                colour: buffers.ids,
            },
            _ => DepthTarget::Copy {
                frame: self.copy_from,
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
            casters: draw.casters,
            depth_view_proj: lp.views[vi].depth_matrix_from(origin),
            origin: origin.unwrap_or(glam::Vec3::ZERO),
            buffer: buffers.buffer,
            table: buffers.table,
            light_position: self.ctx.scene.lights[lp.light].position,
            over: draw.over,
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
        let fbo_of_frame = self.copy_from.fbo;
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
            copy_depth(gl, self.copy_from, texture, size, face);
            go_on!(self.step(StepKind::DepthCopy, Some(lp), shown, |_| {
                let depth = debug::read_depth_texture(gl, texture, face, size);
                debug::depth_image(&depth, size, size)
            }));
        }
        Ok(ControlFlow::Continue(()))
    }
}

/// One image of a view to draw: its cube face (None: a 2D map), matrix and casters (None:
/// every caster), and whether it is drawn over the map's copy of its static map.
#[derive(Clone, Copy)]
pub(super) struct FaceDraw<'c> {
    face: Option<usize>,
    view_proj: glam::Mat4,
    casters: Option<&'c [u32]>,
    over: bool,
}

/// The casters `which` picks of image `i` of light `lp`'s view `vi`, or the view's casters
/// where the plan lists no images.
fn image_casters<'p>(
    lp: &'p LightPlan,
    vi: usize,
    i: usize,
    which: impl Fn(&'p ImageCasters) -> &'p Vec<u32>,
) -> Option<&'p [u32]> {
    match lp.view_images.get(vi) {
        Some(images) => images.get(i).map(|c| which(c).as_slice()),
        None => lp.view_casters.get(vi).map(Vec::as_slice),
    }
}

impl<'a> FrameRun<'a> {
    /// Light `pi`'s mask drawn from its maps `maps` into the bound mask target.
    pub(super) fn map_mask(&self, lp: &LightPlan, maps: &[ViewMap], pi: usize) {
        draw_maps(
            &self.ctx,
            lp,
            &self.bindings(maps, pi),
            |v| self.lit_program(v),
            (MapPass::Mask, false),
        )
    }

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

/// How many lit passes [`draw_maps`] draws for a light with these map views.
pub(super) fn lit_passes(
    lp: &LightPlan,
    bindings: &[(bool, ShadowBinding, &[u32], Option<Scissor>)],
) -> usize {
    match bindings.len() {
        0 => 1,
        6 if lp.merged => 1,
        n => n,
    }
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
    let marks = Marks::of(ctx.settings.lighting.light_once, lit_passes(lp, bindings));
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
            MapPass::Lit => passes::lit::draw(ctx, p, lp, s, (receivers, marks)),
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
