//! A shadow-volume light's parts (and a subdivided light's): which pieces are extruded, with
//! which counting, and which the GPU extrudes.

use super::FrameFacts;
use crate::geometry::Aabb;
use crate::options::{
    CountingMode, GpuExtrusion, ModelShadows, Pipeline, ShadowVolumeOptions, VolumeCasters,
};
use crate::plan::{LightPlan, PartTriangles, PlanStats, VolumePart, cull};
use crate::scene::{Scene, SurfaceOwner};
use crate::shadow::volume::{self, CasterGroup, Counting, PieceRef};
use crate::truth::subdivision::Geometry;
use glam::Vec3;

impl FrameFacts<'_> {
    /// A shadow-volume light's parts: each piece whose shadow may reach a receiver in view,
    /// with its counting. Some(why) when none is left.
    pub(super) fn plan_volumes(
        &self,
        plan: &mut LightPlan,
        stats: &mut PlanStats,
    ) -> Option<&'static str> {
        self.volume_parts(plan, stats, false);
        if self.on() && self.options.plan.cull_lights && plan.volumes.is_empty() {
            return Some("no caster whose shadow reaches the view");
        }
        self.hand_to_gpu(plan);
        None
    }

    /// A subdivided light: which triangles are cut and, when the models are not among them
    /// (`subdivision.models = volumes`), the volumes of the models and of the world's pieces
    /// whose shadow may fall on a model (the world's shadows on the world are the marks').
    pub(super) fn plan_subdivision(&self, plan: &mut LightPlan, stats: &mut PlanStats) {
        let geometry = match self.options.subdivision.models {
            ModelShadows::Volumes => Geometry::World,
            ModelShadows::Subdivided => Geometry::Everything,
        };
        plan.subdivided = Some(geometry);
        if geometry == Geometry::World {
            self.volume_parts(plan, stats, true);
            self.hand_to_gpu(plan);
        }
    }

    /// Pushes the light's volume parts to `plan.volumes`: the pieces whose shadow may meet a
    /// receiver in view; with `world_on_models`, the world's pieces only where it may meet a
    /// model. Culling casters, the receivers' boxes become `plan.volume_receivers`.
    fn volume_parts(&self, plan: &mut LightPlan, stats: &mut PlanStats, world_on_models: bool) {
        let p = &self.options.plan;
        let on = self.on();
        let l = &self.scene.lights[plan.light];
        let is_model = |owner| matches!(owner, SurfaceOwner::Model(_));
        // Receiver boxes: a piece whose shadow meets none of them shadows nothing in view
        // (Forsyth).
        let receiver_boxes: Vec<Aabb> = plan
            .receivers
            .iter()
            .map(|&r| self.scene.surfaces[r as usize].bounds)
            .collect();
        let model_boxes: Vec<Aabb> = plan
            .receivers
            .iter()
            .map(|&r| &self.scene.surfaces[r as usize])
            .filter(|s| world_on_models && is_model(s.owner))
            .map(|s| s.bounds)
            .collect();
        for &(group, piece, bounds, g) in &self.pieces {
            let world_for_models = world_on_models && !is_model(g.owner);
            let boxes = match world_for_models {
                true => &model_boxes,
                false => &receiver_boxes,
            };
            let keep = match on && p.cull_casters {
                // Unculled, every piece, but the world's for models (under a subdivided light)
                // only where its shadow may meet a model, as `subdivision.models = volumes`
                // defines them: the subdivision decides the world's pixels. On the paper's
                // frame of oa_dm3 every world piece of every light was built and uploaded
                // beside the fragments (1.68 GiB peak resident for the frame).
                false if world_for_models => {
                    cull::sphere_meets_aabb(l.position, l.radius, &bounds) && {
                        let shadow = cull::shadow_bounds(&bounds, l.position, l.radius);
                        model_boxes.iter().any(|r| r.intersects(&shadow))
                    }
                }
                false => true,
                // The range test first: most pieces of a map are out of a light's range, and
                // it is cheaper than their shadow's box.
                true => {
                    cull::sphere_meets_aabb(l.position, l.radius, &bounds) && {
                        let shadow = cull::shadow_bounds(&bounds, l.position, l.radius);
                        self.view_frustum.intersects_aabb(&shadow)
                            && boxes.iter().any(|r| r.intersects(&shadow))
                    }
                }
            };
            if !keep {
                stats.casters_culled += 1;
                continue;
            }
            stats.casters_drawn += 1;
            let part = |counting, triangles| VolumePart {
                group,
                piece,
                counting,
                triangles,
            };
            match self.counting_of(plan, g, piece, &bounds) {
                Some(counting) => {
                    match counting {
                        Counting::ZFail => stats.zfail_parts += 1,
                        Counting::ZPass => stats.zpass_parts += 1,
                    }
                    plan.volumes.push(part(counting, PartTriangles::All));
                }
                None => {
                    let i = plan.near_plane_triangles.len() - 1;
                    stats.split_parts += 1;
                    stats.zfail_parts += 1;
                    stats.zpass_parts += 1;
                    plan.volumes
                        .push(part(Counting::ZFail, PartTriangles::NearPlane(i)));
                    plan.volumes
                        .push(part(Counting::ZPass, PartTriangles::Rest(i)));
                }
            }
        }
        if on && p.cull_casters {
            plan.volume_receivers = receiver_boxes;
        }
    }

    /// Moves the parts of groups the GPU extrudes (`shadow_volume.gpu_extrusion`) out of the
    /// CPU's list: each such group is drawn whole, depth-fail (its pieces the planner culled
    /// are drawn too, and no per-piece test says depth-pass is safe for them).
    fn hand_to_gpu(&self, plan: &mut LightPlan) {
        let o = &self.options;
        let light_moves = self.scene.motion.moves_light(plan.light);
        let gpu = |owner: SurfaceOwner| match o.shadow_volume.gpu_extrusion {
            // `auto` is resolved by the profile before planning; unresolved, the CPU builds.
            GpuExtrusion::None | GpuExtrusion::Auto => false,
            GpuExtrusion::Models => matches!(owner, SurfaceOwner::Model(_)),
            GpuExtrusion::Moving => light_moves || matches!(owner, SurfaceOwner::Model(_)),
            GpuExtrusion::All => true,
        };
        // The shader extrudes to infinity only, and needs the shader pipeline.
        if matches!(
            o.shadow_volume.gpu_extrusion,
            GpuExtrusion::None | GpuExtrusion::Auto
        ) || o.shadow_volume.extrusion != volume::Extrusion::Infinite
            || o.gl.pipeline == Pipeline::FixedFunction
        {
            return;
        }
        // The groups handed over, by index (pieces list each group's pieces in a run).
        let mut extruded_groups: Vec<usize> = Vec::new();
        for &(group, _, _, g) in &self.pieces {
            if gpu(g.owner) && extruded_groups.last() != Some(&group) {
                extruded_groups.push(group);
            }
        }
        let mut kept = Vec::with_capacity(plan.volumes.len());
        for part in std::mem::take(&mut plan.volumes) {
            if !extruded_groups.contains(&part.group) {
                kept.push(part);
                continue;
            }
            if !plan.extruded.iter().any(|(g, _)| *g == part.group) {
                plan.extruded.push((part.group, Counting::ZFail));
            }
        }
        plan.volumes = kept;
    }

    /// How a piece's volume is counted. The planner turns depth-fail into a per-piece choice
    /// (`plan.counting`); a depth-pass asked for stays. None: the piece is depth-fail only for
    /// its triangles near the near plane, which are split off (`plan.split_counting`; their
    /// list is pushed to `plan.near_plane_triangles`).
    fn counting_of(
        &self,
        plan: &mut LightPlan,
        g: &CasterGroup,
        piece: PieceRef,
        bounds: &Aabb,
    ) -> Option<Counting> {
        let p = &self.options.plan;
        let on = self.on();
        let counting_auto = match self.options.shadow_volume.counting {
            CountingMode::Auto => true,
            CountingMode::Zfail => on && p.counting,
            CountingMode::Zpass => false,
        };
        if !counting_auto {
            return Some(match self.options.shadow_volume.counting {
                CountingMode::Zpass => Counting::ZPass,
                _ => Counting::ZFail,
            });
        }
        // A ray seen through an alpha-tested caster's holes enters its volume through the
        // front cap, which depth-pass does not draw; an open surface keeps the paper's
        // depth-fail (see `Component::open`).
        let pos = self.scene.lights[plan.light].position;
        let open = g.piece(piece).open && p.open_depth_fail;
        let see_through = g.piece(piece).alpha_tested || open;
        let boxed = volume::potentially_inside_shadow(bounds, self.camera.position, pos, self.near);
        // The eye within a closed piece's box (grown by the near distance): it may stand
        // inside the caster, whose inner faces are culled, so that rays leave it through its
        // lit faces into the volume, past the front cap depth-pass does not draw, whatever the
        // near plane holds (oa_dm3's flythrough walked through the running player: 16% wrong
        // at frame 448).
        let eye_in_box = !g.piece(piece).open && {
            let e = self.camera.position;
            let grown = self.near;
            e.cmpge(bounds.min - grown).all() && e.cmple(bounds.max + grown).all()
        };
        match (see_through, boxed, on && p.near_plane_test) {
            (true, _, _) => Some(Counting::ZFail),
            (false, false, _) => Some(Counting::ZPass),
            (false, true, false) => Some(Counting::ZFail),
            (false, true, true) if eye_in_box => Some(Counting::ZFail),
            (false, true, true) => {
                let near_tris = near_plane_triangles(
                    self.scene,
                    g,
                    piece,
                    pos,
                    &self.near_quad,
                    &self.options.shadow_volume,
                );
                if near_tris.is_empty() {
                    Some(Counting::ZPass)
                } else if p.split_counting {
                    plan.near_plane_triangles.push(near_tris);
                    None
                } else {
                    Some(Counting::ZFail)
                }
            }
        }
    }
}

/// `plan.near_plane_test` for one piece of caster group `g`: its facing triangles whose shadow from a light at `light` may hold part of the
/// camera's near-plane rectangle `near_quad` (world space), tested in the group's own space;
/// sorted.
fn near_plane_triangles(
    scene: &Scene,
    g: &CasterGroup,
    piece: PieceRef,
    light: Vec3,
    near_quad: &[Vec3; 4],
    o: &ShadowVolumeOptions,
) -> Vec<u32> {
    let to_local = volume::group_transform(scene, g.owner).inverse();
    let mut near: Vec<u32> = volume::near_plane_triangles(
        g,
        g.piece(piece),
        to_local.transform_point3(light).as_dvec3(),
        &near_quad.map(|q| to_local.transform_point3(q).as_dvec3()),
        o.facing_epsilon,
        o.casters == VolumeCasters::Both,
    )
    .collect();
    // Sorted once here: both parts of the split look triangles up in it.
    near.sort_unstable();
    near
}
