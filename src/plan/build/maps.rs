//! A shadow-mapped light's views: their casters, receivers, keys and rectangles, warped views,
//! and several frusta for an omni light.

use super::{FrameFacts, hash_of, mat_bits, spot_exceeds_frustum};
use crate::geometry::{Aabb, Frustum};
use crate::options::{
    DepthBits, DepthSource, MapBuffer, OmniMode, Outside, ShadowMapOptions, Warp,
};
use crate::plan::scissor::{self, Scissor};
use crate::plan::{ImageCasters, LightPlan, PlanStats, cull};
use crate::scene::{Light, LightKind, SurfaceOwner};
use crate::shadow::frusta;
use crate::shadow::views::{Rect, ShadowView, ViewKind, shadow_views};
use crate::shadow::warp::{self, WarpInput};
use glam::Mat4;

/// How far (in the face's image plane) a receiver may reach past a kept frustum's rectangle:
/// within the one-texel margin of any map of up to 2048 texels (`plan.keep_frusta`).
const KEEP_SLACK: f32 = 1.0 / 2048.0;

/// The smallest map one of several frusta gets (`shadow_map.omni = frusta`).
const MIN_FRUSTUM_SIZE: u32 = 32;

/// The largest, unless `shadow_map.size` is larger: at most four times its side (GL 3.3
/// guarantees 1024; the GL layer refuses a map past GL_MAX_TEXTURE_SIZE).
const MAX_FRUSTUM_SIZE: u32 = 4096;

/// The stats' line for a light's frusta: how many, their texels against the six faces' budget,
/// and each one's face and map side.
fn frusta_line(
    light: usize,
    views: &[crate::shadow::views::ShadowView],
    o: &ShadowMapOptions,
    kept: bool,
) -> String {
    let texels: u64 = views.iter().map(|v| u64::from(v.map_size()).pow(2)).sum();
    let each: Vec<String> = views
        .iter()
        .map(|v| match v.kind {
            ViewKind::Face(f) => format!("{f}:{}", v.map_size()),
            _ => format!("{}", v.map_size()),
        })
        .collect();
    format!(
        "light {light}: {} frusta{}, {texels} texels (six faces: {}): {}",
        views.len(),
        if kept { " (kept)" } else { "" },
        6 * u64::from(o.size).pow(2),
        each.join(" ")
    )
}

impl FrameFacts<'_> {
    /// A shadow-mapped light's views, with per view the casters drawn, the receivers lit, the
    /// key its map is kept by and its rectangle. Some(why) when no view has a caster.
    pub(super) fn plan_maps(
        &self,
        plan: &mut LightPlan,
        stats: &mut PlanStats,
    ) -> Option<&'static str> {
        let l = &self.scene.lights[plan.light];
        let p = &self.options.plan;
        let on = self.on();
        // A spot wider than one frustum covers gets an omni light's views; the lit pass's cone
        // test still bounds its light (`plan.wide_spot_omni`).
        let as_omni;
        let view_light = if on && p.wide_spot_omni && spot_exceeds_frustum(l) {
            as_omni = Light {
                kind: LightKind::Omni,
                ..l.clone()
            };
            &as_omni
        } else {
            l
        };
        // Warped maps are 2D: six spots, never a cube.
        let (six_spots, chosen_buffer);
        let map_options = if plan.technique.warp().is_some() {
            six_spots = ShadowMapOptions {
                omni: OmniMode::SixSpots,
                ..self.options.shadow_map.clone()
            };
            &six_spots
        } else if plan.buffer != self.map_options.buffer || plan.map_size.is_some() {
            // `auto` chose this light's buffer or size (`shadow_map:id`, `shadow_map@1024` in
            // `auto_among`).
            chosen_buffer = ShadowMapOptions {
                buffer: plan.buffer,
                size: plan.map_size.unwrap_or(self.map_options.size),
                ..self.map_options.clone()
            };
            &chosen_buffer
        } else {
            &self.map_options
        };
        plan.views = match map_options.omni {
            OmniMode::Frusta if view_light.kind == LightKind::Omni => {
                let chosen = self.frusta_of(plan.light, view_light, &plan.receivers, map_options);
                let views = chosen.as_ref().map(|(_, frusta, kept)| {
                    let views = frusta::frustum_views(
                        view_light,
                        frusta,
                        &self.caster_bounds,
                        map_options.fit_near_far,
                    );
                    stats
                        .frusta
                        .push(frusta_line(plan.light, &views, map_options, *kept));
                    views
                });
                plan.frusta = chosen.map(|(key, frusta, _)| (key, frusta));
                views
            }
            _ => None,
        }
        .unwrap_or_else(|| shadow_views(view_light, &self.caster_bounds, map_options));
        let light_key = hash_of((
            &self.map_options_text,
            plan.buffer,
            plan.map_size,
            plan.order,
            mat_bits(&Mat4::from_translation(l.position)),
            l.radius.to_bits(),
            format!("{:?}", l.kind),
        ));
        // Several frusta: each receiver's footprint on a face, once for all that face's frusta.
        let mut footprints: [Option<Vec<Option<Rect>>>; 6] = Default::default();
        let moving = self.splits_maps(plan).then(|| self.moving_models());
        for vi in 0..plan.views.len() {
            let view = &plan.views[vi];
            let mut drawn = self.map_casters(l, view.kind, &view.view_proj());
            let lit = self.view_receivers(l, view, &plan.receivers, &mut footprints);
            if let Some(kind) = plan.technique.warp() {
                self.warp_view(plan, vi, kind, (&lit, &mut drawn), stats);
            }
            let view = &plan.views[vi];
            stats.casters_drawn += drawn.len();
            stats.casters_culled += self.caster_list.len() - drawn.len();
            let key = (on && p.cache_maps).then(|| self.map_key(light_key, view, &drawn));
            let images = self.image_casters(l, view.kind, &drawn, moving.as_deref());
            let static_key = images
                .iter()
                .any(|i| !i.moving.is_empty())
                .then(|| self.static_map_key(light_key, view, &drawn, moving.as_deref()));
            let rect = self.face_rect(l, view, plan.scissor);
            plan.view_receivers.push(lit);
            plan.view_casters.push(drawn);
            plan.view_keys.push(key);
            plan.view_images.push(images);
            plan.view_static_keys.push(static_key);
            plan.view_scissors.push(rect);
        }
        plan.merged = self.merges_faces(&plan.views);
        if on && p.cull_lights && plan.view_casters.iter().all(|c| c.is_empty()) {
            plan.views.clear();
            plan.view_receivers.clear();
            plan.view_casters.clear();
            plan.view_keys.clear();
            plan.view_images.clear();
            plan.view_static_keys.clear();
            plan.view_scissors.clear();
            return Some("no caster in range");
        }
        None
    }

    /// The receivers view `view` of light `l` lights: one of several frusta only those in its
    /// cell (`footprints`: each receiver's footprint on a face, found once for all that face's
    /// frusta), a face of six spots those in its pyramid (`plan.cull_receivers`), other views
    /// all of `receivers`.
    fn view_receivers(
        &self,
        l: &Light,
        view: &ShadowView,
        receivers: &[u32],
        footprints: &mut [Option<Vec<Option<Rect>>>; 6],
    ) -> Vec<u32> {
        let (on, p) = (self.on(), &self.options.plan);
        match (view.kind, view.part) {
            // One of several frusta lights only the receivers in its cell.
            (ViewKind::Face(f), Some(part)) => {
                let on_face = footprints[f].get_or_insert_with(|| {
                    receivers
                        .iter()
                        .map(|&s| {
                            let b = &self.scene.surfaces[s as usize].bounds;
                            frusta::footprint(l.position, f, b)
                        })
                        .collect()
                });
                receivers
                    .iter()
                    .zip(on_face.iter())
                    .filter(|(_, r)| r.is_some_and(|r| r.intersection(&part.cell).is_some()))
                    .map(|(&s, _)| s)
                    .collect()
            }
            (ViewKind::Face(f), None) if on && p.cull_receivers => {
                let pyramid = cull::face_pyramid(l.position, f);
                receivers
                    .iter()
                    .copied()
                    .filter(|&s| pyramid.intersects_aabb(&self.scene.surfaces[s as usize].bounds))
                    .collect()
            }
            _ => receivers.to_vec(),
        }
    }

    /// Whether a light's views are six whole cube faces drawn as one merged map
    /// (`plan.merge_faces`; not with clip planes at the maps' edges).
    fn merges_faces(&self, views: &[ShadowView]) -> bool {
        self.on()
            && self.options.plan.merge_faces
            && views.iter().all(|v| v.part.is_none())
            && self.options.shadow_map.outside != Outside::ClipPlanes
            && views.len() == 6
            && views.iter().all(|v| matches!(v.kind, ViewKind::Face(_)))
    }

    /// Several frusta around the receivers in view of omni light `l` (index `index`;
    /// `shadow_map.omni = frusta`), each receiver asking for the screen pixels a world unit
    /// covers at its distance from the camera: the frusta, what they are chosen for (the key
    /// [`KeptFrusta`] keeps them by) and whether they are last frame's, kept
    /// (`plan.keep_frusta`). None where no receiver is beyond the near plane (six faces then).
    fn frusta_of(
        &self,
        index: usize,
        l: &Light,
        receivers: &[u32],
        o: &ShadowMapOptions,
    ) -> Option<(u64, Vec<frusta::FaceFrustum>, bool)> {
        // Pixels per world unit at distance 1: half the height over tan(fovy / 2).
        let pixels = 0.5 * self.camera.height as f32 * self.camera.projection.y_axis.y.abs();
        let eye = frusta::Eye {
            position: self.scene_camera.position,
            pixels,
            near: self.near,
            screen: self.camera.width.max(self.camera.height) as f32,
        };
        let mut needs = Vec::new();
        for &s in receivers {
            frusta::receiver_needs(self.scene.surfaces[s as usize].bounds, &eye, &mut needs);
        }
        let key = hash_of((
            &self.map_options_text,
            mat_bits(&Mat4::from_translation(l.position)),
            l.radius.to_bits(),
            (self.camera.width, self.camera.height),
        ));
        let keep = self.on() && self.options.plan.keep_frusta;
        if let Some(kept) = self.kept.get(index, key).filter(|_| keep)
            && frusta::still_cover(l.position, kept, &needs, KEEP_SLACK)
        {
            return Some((key, kept.to_vec(), true));
        }
        let budget = frusta::Budget {
            texels: 6 * u64::from(o.size).pow(2),
            max_frusta: o.max_frusta as usize,
            min_size: MIN_FRUSTUM_SIZE.min(o.size),
            max_size: o.size.max((4 * o.size).min(MAX_FRUSTUM_SIZE)),
        };
        let chosen = frusta::choose(l.position, &needs, &budget);
        (!chosen.is_empty()).then_some((key, chosen, false))
    }

    /// Replaces view `vi` of a `psm` or `tsm` light by its warp (`shadow::warp`), fitted to the
    /// receivers it lights (`lit`); keeps only the casters the warp can draw (`drawn`). Where
    /// the warp degenerates the standard view stays, and the stats say why.
    fn warp_view(
        &self,
        plan: &mut LightPlan,
        vi: usize,
        kind: Warp,
        (lit, drawn): (&[u32], &mut Vec<u32>),
        stats: &mut PlanStats,
    ) {
        let l = &self.scene.lights[plan.light];
        let bounds = |list: &[u32]| -> Vec<Aabb> {
            list.iter()
                .map(|&s| self.scene.surfaces[s as usize].bounds)
                .collect()
        };
        let (receivers, casters) = (bounds(lit), bounds(drawn));
        let view = &mut plan.views[vi];
        let input = WarpInput {
            camera: &self.scene_camera,
            aspect: self.camera.width as f32 / self.camera.height.max(1) as f32,
            light: l.position,
            standard: view.view_proj(),
            receivers: &receivers,
            casters: &casters,
            reach: Aabb {
                min: l.position - l.radius,
                max: l.position + l.radius,
            },
        };
        let name = plan.technique;
        let which = format!("light {} view {vi}", plan.light);
        match warp::warp(kind, &input, &self.options.psm) {
            Ok(w) => {
                view.view = w.view;
                view.projection = w.projection;
                view.depth_view_proj = w.depth;
                let mut keep = w.casters.iter();
                drawn.retain(|_| *keep.next().expect("one flag per caster"));
                let mut how = format!("{which}: {name}");
                if w.slide > 0.0 {
                    how += &format!(", camera slid back {:.1}", w.slide);
                }
                if w.inverted {
                    how += ", light behind the camera (depth reversed)";
                }
                stats.warps.push(how);
            }
            Err(d) => {
                stats.warp_fallbacks += 1;
                stats.warps.push(format!(
                    "{which}: {name} fell back to a standard map: {}",
                    d.describe()
                ));
            }
        }
    }

    /// The casters one view of light `l` draws: those in its range and view frustum.
    fn map_casters(&self, l: &Light, kind: ViewKind, view_proj: &Mat4) -> Vec<u32> {
        if !(self.on() && self.options.plan.cull_casters) {
            return self.caster_list.clone();
        }
        let view_frustum = (kind != ViewKind::Cube).then(|| Frustum::from_view_proj(view_proj));
        self.caster_list
            .iter()
            .copied()
            .filter(|&c| {
                let b = &self.scene.surfaces[c as usize].bounds;
                cull::sphere_meets_aabb(l.position, l.radius, b)
                    && view_frustum.as_ref().is_none_or(|f| f.intersects_aabb(b))
            })
            .collect()
    }

    /// What a view's map depends on (a map drawn with the same key is reused): the light and
    /// map options, the view, the casters drawn and where the moving ones stand, in which pose.
    fn map_key(
        &self,
        light_key: u64,
        view: &crate::shadow::views::ShadowView,
        drawn: &[u32],
    ) -> u64 {
        let moving: Vec<([u32; 16], u64)> = drawn
            .iter()
            .filter_map(|&c| match self.scene.surfaces[c as usize].owner {
                SurfaceOwner::Model(m) => {
                    let model = &self.scene.models[m];
                    Some((mat_bits(&model.transform), model.pose))
                }
                SurfaceOwner::World => None,
            })
            .collect();
        hash_of((
            light_key,
            mat_bits(&view.view_proj()),
            format!("{:?}", view.kind),
            view.part.map(|p| p.size),
            drawn,
            moving,
        ))
    }

    /// Whether light `plan`'s maps are kept apart from its moving casters: a static map of the
    /// casters that do not move, copied each frame a model moves and the models drawn over it.
    /// Only where that copy plus the models draw what one pass over every caster draws: maps
    /// kept by key (`plan.cache_maps`), of depth alone (an ID buffer's colour and a priority
    /// buffer's mip chain are drawn whole), not warped (a warp follows the camera, so its
    /// static map would not outlive a frame), of a light that does not move (the same), and
    /// drawn through a framebuffer object: the models go straight into the map, so where maps
    /// are copied from the frame (`shadow_map.depth_source = copy`) the frame's 24-bit depth
    /// must give the polygon offset the unit the map does (not with 16-bit maps).
    fn splits_maps(&self, plan: &LightPlan) -> bool {
        let o = &self.map_options;
        let fbo = crate::plan::fallback::disabled(self.options)
            .is_ok_and(|d| !d.contains(&"render_to_depth_texture"));
        let moves = self.scene.motion.moves_light(plan.light);
        self.on()
            && self.options.plan.cache_maps
            && plan.buffer == MapBuffer::Depth
            && plan.technique.warp().is_none()
            && !moves
            && fbo
            && (o.depth_source == DepthSource::Fbo || o.depth_bits != DepthBits::D16)
    }

    /// Per model, whether the scene's motion moves it (walks it or plays its animation): its
    /// surfaces are drawn over a copy of a static map rather than into it.
    fn moving_models(&self) -> Vec<bool> {
        let m = &self.scene.motion;
        let mut moving = vec![false; self.scene.models.len()];
        for i in m
            .rigs
            .iter()
            .map(|r| r.model)
            .chain(m.walks.iter().map(|w| w.model))
        {
            if let Some(flag) = moving.get_mut(i) {
                *flag = true;
            }
        }
        moving
    }

    /// Whether caster `c` belongs to a model `moving` marks.
    fn is_moving(&self, c: u32, moving: &[bool]) -> bool {
        match self.scene.surfaces[c as usize].owner {
            SurfaceOwner::Model(m) => moving.get(m).copied().unwrap_or(false),
            SurfaceOwner::World => false,
        }
    }

    /// The casters of each image of a view of light `l` whose casters are `drawn`: one image,
    /// or a cube's six faces, each with those in its frustum (`plan.cull_casters`; a caster
    /// outside a face's pyramid draws nothing there). With `moving` (the split), the moving
    /// models' surfaces are set apart.
    fn image_casters(
        &self,
        l: &Light,
        kind: ViewKind,
        drawn: &[u32],
        moving: Option<&[bool]>,
    ) -> Vec<ImageCasters> {
        let cull = kind == ViewKind::Cube && self.on() && self.options.plan.cull_casters;
        let faces: Vec<Option<Frustum>> = match kind {
            ViewKind::Cube => (0..6)
                .map(|f| cull.then(|| cull::face_pyramid(l.position, f)))
                .collect(),
            _ => vec![None],
        };
        faces
            .iter()
            .map(|pyramid| {
                let mut image = ImageCasters::default();
                for &c in drawn {
                    let b = &self.scene.surfaces[c as usize].bounds;
                    if pyramid.as_ref().is_some_and(|f| !f.intersects_aabb(b)) {
                        continue;
                    }
                    match moving.is_some_and(|m| self.is_moving(c, m)) {
                        true => image.moving.push(c),
                        false => image.base.push(c),
                    }
                }
                image
            })
            .collect()
    }

    /// What a view's static map depends on: [`Self::map_key`]'s light and view with only the
    /// casters that do not move (the models among them where they stand, in which pose).
    fn static_map_key(
        &self,
        light_key: u64,
        view: &ShadowView,
        drawn: &[u32],
        moving: Option<&[bool]>,
    ) -> u64 {
        let still: Vec<u32> = drawn
            .iter()
            .copied()
            .filter(|&c| !moving.is_some_and(|m| self.is_moving(c, m)))
            .collect();
        hash_of(("static", self.map_key(light_key, view, &still)))
    }

    /// Where a view's lit pass may draw: an omni light's six spots get the face's part of the
    /// light's rectangle, each of several frusta its cell's part; other views the light's
    /// rectangle.
    fn face_rect(
        &self,
        l: &Light,
        view: &crate::shadow::views::ShadowView,
        light_rect: Option<Scissor>,
    ) -> Option<Scissor> {
        let (c, pos, radius) = (&self.camera, l.position, l.radius);
        let part = match (view.kind, view.part) {
            (ViewKind::Face(_), Some(p)) => {
                Some(scissor::cell_scissor(c, pos, radius, &view.view, &p.cell))
            }
            (ViewKind::Face(f), None) => Some(scissor::face_scissor(c, pos, radius, f)),
            _ => None,
        };
        match (part, light_rect) {
            (Some(part), Some(light_rect)) => Some(part.map_or(
                Scissor {
                    width: 0,
                    height: 0,
                    ..light_rect
                },
                |r| r.intersect(&light_rect),
            )),
            _ => light_rect,
        }
    }
}
