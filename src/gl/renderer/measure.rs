//! After the timed frame, when asked: the G-buffer (drawn by the base pass) and each light's
//! decision mask read back.

use super::*;
impl<'a> FrameRun<'a> {
    /// The G-buffer and each light's decision mask, when the request asks for masks
    /// (untimed, after the frame).
    pub(super) fn measure(
        &mut self,
        maps: &[ViewMap],
    ) -> (Option<GBuffer>, Vec<Mask>, Vec<HybridStats>) {
        let gl = self.ctx.gl;
        let plan = self.ctx.plan;
        let Some((gtarget, mtarget)) = self.measure_targets.filter(|_| self.request.masks) else {
            return (None, Vec::new(), Vec::new());
        };
        let hybrid_stats = std::mem::take(&mut self.hybrid_in_frame);
        // The base pass wrote the G-buffer, unless the legacy pipeline drew it: then a pass
        // of its own, without reach bits (that pipeline records nothing).
        let reach_lights = match self.reach_lights.take() {
            Some(lights) => lights,
            None => {
                gtarget_bind(gl, gtarget);
                let program = &self.programs.unlit_gbuffer;
                passes::base::draw(&self.ctx, program, Some(&[]));
                Vec::new()
            }
        };
        self.mark_reached(gtarget, &reach_lights);
        let reach = match reach_lights.is_empty() {
            true => Vec::new(),
            false => gtarget.read_reach(gl),
        };
        // Kept on the GPU when asked, unless the legacy pipeline's masks read it.
        let whole = !self.request.gbuffer_kept || self.fixed.is_some();
        let gbuffer = whole.then(|| read_gbuffer(gl, gtarget));
        let mut masks = Vec::with_capacity(plan.lights.len() + plan.culled.len());
        let mut drawn = std::mem::take(&mut self.masks_in_frame);
        for (pi, lp) in plan.lights.iter().enumerate() {
            if let Some(mask) = self.recorded_mask(lp, (&reach, &reach_lights)) {
                masks.push(mask);
                continue;
            }
            if let Some(i) = drawn.iter().position(|m| m.light == lp.light) {
                masks.push(drawn.swap_remove(i));
                continue;
            }
            let own;
            let maps = if plan.maps_per_light && lp.technique.uses_maps() {
                own = self.maps_again(pi);
                &own[..]
            } else {
                maps
            };
            mtarget.bind(gl);
            clear_mask(gl, lp.scissor);
            if let Some(ff) = self.fixed {
                self.fixed_mask(ff, lp, &self.bindings(maps, pi));
                set_scissor(gl, None);
                let mut values = mtarget.read(gl);
                if let Some(gbuffer) = &gbuffer {
                    keep_reached(&mut values, gbuffer, &self.ctx.scene.lights[lp.light]);
                }
                masks.push(Mask {
                    light: lp.light,
                    width: mtarget.width,
                    height: mtarget.height,
                    values,
                });
                continue;
            }
            // Lights with volumes, fragments or maps drawn per light had theirs drawn within
            // the frame (`mask_in_frame`): what is left reads maps the frame kept.
            self.map_mask(lp, maps, pi);
            set_scissor(gl, None);
            masks.push(Mask {
                light: lp.light,
                width: mtarget.width,
                height: mtarget.height,
                values: mtarget.read(gl),
            });
        }
        // Culled lights reach no pixel in view.
        for &light in &plan.culled {
            masks.push(Mask {
                light,
                width: mtarget.width,
                height: mtarget.height,
                values: vec![0; (mtarget.width * mtarget.height) as usize],
            });
        }
        masks.sort_by_key(|m| m.light);
        (gbuffer, masks, hybrid_stats)
    }

    /// Whether light `lp`'s mask is drawn within the frame, right after the work it reads
    /// (its volumes' or fragments' stencil before its lit pass marks it, a hybrid light's
    /// maps and volumes after its pass, or its maps drawn just before its pass, before a
    /// later light takes their textures over), rather than after the frame, which would do
    /// that work again. The legacy pipeline draws its masks after the frame.
    pub(super) fn mask_in_frame(&self, lp: &LightPlan) -> bool {
        let redone_after = self.volumes_of(lp).is_some()
            || self.fragments_of(lp).is_some()
            || (self.ctx.plan.maps_per_light && lp.technique.uses_maps());
        self.request.masks
            && self.measure_targets.is_some()
            && self.fixed.is_none()
            && self.layer_of(lp).is_none()
            && redone_after
    }

    /// Light `lp`'s mask drawn now by `draw` into the mask target (over the frame's depth and
    /// stencil as they stand), read back and kept for the frame's end; untimed (its time is
    /// left out of the frame's), and the frame's own target bound again. Returns what `draw`
    /// returned (None without a mask target).
    pub(super) fn mask_now<T>(
        &mut self,
        lp: &LightPlan,
        draw: impl FnOnce(&Self, &MaskTarget) -> T,
    ) -> Option<T> {
        let gl = self.ctx.gl;
        let (_, mtarget) = self.measure_targets?;
        self.timer.end(gl);
        // The frame's work so far finishes on the frame's clock: the read-back below would
        // wait for it, and the mask's time is the mask's alone.
        syncs::finish(gl);
        let start = Instant::now();
        mtarget.bind(gl);
        clear_mask(gl, lp.scissor);
        let drawn = draw(self, mtarget);
        set_scissor(gl, None);
        self.masks_in_frame.push(Mask {
            light: lp.light,
            width: mtarget.width,
            height: mtarget.height,
            values: mtarget.read(gl),
        });
        self.target.bind(gl);
        set_scissor(gl, lp.scissor);
        self.masks_in_frame_ms += start.elapsed().as_secs_f64() * 1e3;
        Some(drawn)
    }

    /// Hybrid light `pi`'s mask within the frame, after its lit pass (the mask draws its
    /// maps' marks and volumes' counts again into the stencil, which the next light clears),
    /// with its stats.
    pub(super) fn hybrid_mask_now(&mut self, pi: usize, maps: &[ViewMap]) {
        let plan = self.ctx.plan;
        let lp = &plan.lights[pi];
        let drawn = self.mask_now(lp, |run, mtarget| match run.volumes_of(lp) {
            Some(v) => Some(run.hybrid_mask(pi, maps, &v, mtarget)),
            // No volumes drawn: its maps decide alone, as the frame's lit pass had them.
            None => {
                let bindings = run.bindings(maps, pi);
                draw_maps(
                    &run.ctx,
                    lp,
                    &bindings,
                    |v| run.lit_program(v),
                    (MapPass::Mask, false),
                );
                None
            }
        });
        if let (Some(Some((stencil, fragments))), Some(mask)) = (drawn, self.masks_in_frame.last())
        {
            let stats = hybrid_stats_of(lp.light, &mask.values, &stencil, fragments);
            self.hybrid_in_frame.push(stats);
        }
    }

    /// Light `pi`'s maps for its mask when each light's were drawn before its pass: drawn
    /// again where a later light took their textures over, untimed, uncounted and outside
    /// the frame's steps.
    fn maps_again(&mut self, pi: usize) -> Vec<ViewMap> {
        let (cache, steps, shown) = (self.cache, self.stepper.steps.len(), self.last_maps.len());
        let stop = self.stepper.stop.take();
        self.timer.start_frame(false);
        self.shadow_maps.next_stamp();
        let maps = match self.light_maps(pi) {
            Ok(ControlFlow::Continue(maps)) => maps,
            // No step stops it (`stop` is taken); on a GL error the mask is drawn without the
            // light's maps, and the frame's next error check reports it.
            _ => Vec::new(),
        };
        self.cache = cache;
        self.stepper.steps.truncate(steps);
        self.stepper.stop = stop;
        self.last_maps.truncate(shown);
        maps
    }

    /// Light `lp`'s mask where its stencil is zero, after its volumes or fragments.
    pub(super) fn mask_over_stencil(&self, lp: &LightPlan) {
        passes::lit::draw_mask(
            &self.ctx,
            self.lit_program(LitVariant::plain(true)),
            lp,
            &LitShadow::Stencil { test: true },
            &lp.receivers,
        );
    }

    /// A hybrid light's mask, drawn as its frame drew it (mask, counts, the decision), with
    /// its volume fragments counted with and without the mask on the way. Returns the
    /// stencil (its top bit: where the map decides) and the two fragment counts.
    pub(super) fn hybrid_mask(
        &self,
        pi: usize,
        maps: &[ViewMap],
        v: &LightVolumes<'_>,
        mtarget: &MaskTarget,
    ) -> (Vec<u8>, (Option<u64>, Option<u64>)) {
        let gl = self.ctx.gl;
        let lp = &self.ctx.plan.lights[pi];
        let masked = self.ctx.settings.hybrid.mask;
        let bindings = self.bindings(maps, pi);
        let pass = |kind| {
            draw_maps(
                &self.ctx,
                lp,
                &bindings,
                |variant| self.lit_program(variant),
                (kind, true),
            )
        };
        let volume = &self.programs.volume;
        let fragments;
        if masked {
            passes::lit::clear_marks(gl);
            pass(MapPass::Mark { overwrite: false });
            fragments = (
                passes::hybrid::volume_fragments(&self.ctx, volume, v, (true, lp.scissor)),
                passes::hybrid::volume_fragments(&self.ctx, volume, v, (false, lp.scissor)),
            );
            passes::stencil::draw(&self.ctx, volume, v, lp.scissor, true);
        } else {
            passes::stencil::draw(&self.ctx, volume, v, lp.scissor, false);
            let all = passes::hybrid::volume_fragments(&self.ctx, volume, v, (false, lp.scissor));
            fragments = (all, all);
            pass(MapPass::Mark { overwrite: true });
        }
        pass(MapPass::Mask);
        let stencil = debug::read_stencil(gl, mtarget.fbo, mtarget.width, mtarget.height);
        mtarget.bind(gl);
        (stencil, fragments)
    }
}

impl FrameRun<'_> {
    /// Sets the mask of light `lp` from the fixed-function passes: its volumes' counts, or its maps.
    pub(super) fn fixed_mask(
        &self,
        ff: &FixedFunction,
        lp: &LightPlan,
        bindings: &[(bool, ShadowBinding, &[u32], Option<Scissor>)],
    ) {
        let shadow = LitShadow::Stencil { test: true };
        match self.volumes_of(lp) {
            _ if let Some(f) = self.fragments_of(lp) => {
                self.subdivision_stencil(lp, &f);
                fixed::lit::draw_mask(&self.ctx, ff, lp, &shadow, &lp.receivers);
            }
            Some(_) => {
                self.count_volumes(lp);
                fixed::lit::draw_mask(&self.ctx, ff, lp, &shadow, &lp.receivers);
            }
            None => fixed_maps(&self.ctx, ff, lp, bindings, true),
        }
    }
}

/// Clears the bound mask to "not a receiver" and scissors to `scissor` for the light's mask.
fn clear_mask(gl: &glow::Context, scissor: Option<Scissor>) {
    set_scissor(gl, None);
    // SAFETY: clears the mask's colour; depth and stencil untouched.
    unsafe {
        gl.color_mask(true, true, true, true);
        gl.clear_color(0.0, 0.0, 0.0, 0.0);
        gl.clear(glow::COLOR_BUFFER_BIT);
    }
    set_scissor(gl, scissor);
}

pub(super) fn keep_reached(values: &mut [u8], gbuffer: &GBuffer, light: &crate::scene::Light) {
    for (i, v) in values.iter_mut().enumerate() {
        let reached = gbuffer.is_receiver_surface(i) && {
            let p = glam::Vec3::from_array(gbuffer.position[i]).as_dvec3();
            let n = glam::Vec3::from_array(gbuffer.normal[i]).as_dvec3();
            light.reaches(p, n)
        };
        if !reached {
            *v = MaskValue::NotReceiver as u8;
        }
    }
}

/// A hybrid light's stats from its mask values and its stencil after the frame's passes.
pub(super) fn hybrid_stats_of(
    light: usize,
    values: &[u8],
    stencil: &[u8],
    (volume_fragments, volume_fragments_unmasked): (Option<u64>, Option<u64>),
) -> HybridStats {
    let receiver = |v: u8| v == MaskValue::Lit as u8 || v == MaskValue::Shadowed as u8;
    let mut stats = HybridStats {
        light,
        receiver_pixels: 0,
        silhouette_pixels: 0,
        volume_fragments,
        volume_fragments_unmasked,
    };
    for (&v, &s) in values.iter().zip(stencil) {
        if receiver(v) {
            stats.receiver_pixels += 1;
            if s as u32 & passes::lit::MAP_DECIDES == 0 {
                stats.silhouette_pixels += 1;
            }
        }
    }
    stats
}

pub(super) fn gtarget_bind(gl: &glow::Context, t: &GBufferTarget) {
    // SAFETY: the G-buffer framebuffer is complete.
    unsafe {
        gl.bind_framebuffer(glow::FRAMEBUFFER, Some(t.fbo));
        gl.viewport(0, 0, t.width as i32, t.height as i32);
    }
}

pub(super) fn read_gbuffer(gl: &glow::Context, t: &GBufferTarget) -> GBuffer {
    let (position, normal, kind) = GBufferTarget::fields(&t.read(gl, 0), &t.read(gl, 1));
    GBuffer {
        width: t.width,
        height: t.height,
        kind,
        position,
        normal,
    }
}
