//! Depth textures of shadow mapping, one per light and view, kept across frames and reallocated
//! only when their kind, size or precision change (so long runs create no GL objects); those
//! of a kind the frame no longer draws are deleted. Each
//! remembers what it was drawn from, so that the planner's cache can reuse it.

use crate::options::{Compare, DepthBits, Filter, MapBuffer};
use crate::plan::map_memory;
use glow::HasContext;

/// What a map's texture is: a map of another kind holds nothing reusable.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MapKey {
    pub cube: bool,
    pub size: u32,
    pub bits: DepthBits,
    pub buffer: MapBuffer,
    /// Mip levels (1: none; a priority buffer's chain, `shadow_map.priority_mipmap`).
    pub levels: u32,
}

impl MapKey {
    /// Bytes the texture holds (as `shadow_map.budget_mb` counts them).
    fn bytes(&self) -> u64 {
        map_memory::depth_texture_bytes(self.cube, self.size, self.bits, self.levels)
    }
}

struct Slot {
    texture: glow::Texture,
    key: MapKey,
    /// The plan's key of what the texture holds (None: nothing reusable).
    content: Option<u64>,
    /// The stamp it was last used at: one of the current stamp is in use and never given up.
    used: u64,
}

type Slots = std::collections::HashMap<(usize, usize), Slot>;

/// A view's map or its static map.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Role {
    Map,
    Static,
}

/// The depth textures and the framebuffer used to render into them (the FBO path), within
/// the plan's budget (`shadow_map.budget_mb`): past it, a new view takes over a texture of
/// its kind that no view of the current stamp uses, or the least recently used are deleted.
#[derive(Default)]
pub struct ShadowMaps {
    /// Bytes the textures may hold together (None: no limit).
    budget: Option<u64>,
    /// Advanced once per frame when every light's maps are drawn first, once per light when
    /// each light's are drawn before its pass: textures used at the current stamp are in use.
    stamp: u64,
    /// The stamps the frame and the one before began at: textures used since `frame_start`
    /// were used by this frame, those used since `previous_start` before it by the last.
    frame_start: u64,
    previous_start: u64,
    /// Textures taken over or deleted to stay within the budget, since the renderer began.
    given_up: usize,
    slots: Slots,
    /// Static maps: per view whose map is made from one, the depth of its casters that do not
    /// move (`LightPlan::view_static_keys`), of its map's kind.
    statics: Slots,
    /// ID buffers' colour textures (RGBA8: an ID's four bytes), with their size.
    ids: std::collections::HashMap<(usize, usize), (glow::Texture, u32)>,
    fbo: Option<glow::Framebuffer>,
    /// The framebuffer a static map is read through when it is copied.
    read_fbo: Option<glow::Framebuffer>,
}

/// Internal format, format and type of a depth texture of `bits`.
pub fn depth_format(bits: DepthBits) -> (u32, u32, u32) {
    match bits {
        DepthBits::D16 => (
            glow::DEPTH_COMPONENT16,
            glow::DEPTH_COMPONENT,
            glow::UNSIGNED_SHORT,
        ),
        DepthBits::D24 => (
            glow::DEPTH_COMPONENT24,
            glow::DEPTH_COMPONENT,
            glow::UNSIGNED_INT,
        ),
        DepthBits::D32f => (glow::DEPTH_COMPONENT32F, glow::DEPTH_COMPONENT, glow::FLOAT),
    }
}

fn allocate(gl: &glow::Context, key: MapKey) -> Result<glow::Texture, String> {
    let (internal, format, ty) = depth_format(key.bits);
    // SAFETY: storage for a new texture; the binding is reset afterwards.
    unsafe {
        let t = gl.create_texture()?;
        let target = if key.cube {
            glow::TEXTURE_CUBE_MAP
        } else {
            glow::TEXTURE_2D
        };
        gl.bind_texture(target, Some(t));
        let faces: Vec<u32> = if key.cube {
            (0..6)
                .map(|f| glow::TEXTURE_CUBE_MAP_POSITIVE_X + f)
                .collect()
        } else {
            vec![glow::TEXTURE_2D]
        };
        for face in faces {
            for level in 0..key.levels.max(1) {
                let side = super::priority_mips::level_size(key.size, level) as i32;
                gl.tex_image_2d(
                    face,
                    level as i32,
                    internal as i32,
                    side,
                    side,
                    0,
                    format,
                    ty,
                    glow::PixelUnpackData::Slice(None),
                );
            }
        }
        gl.tex_parameter_i32(
            target,
            glow::TEXTURE_MAX_LEVEL,
            key.levels.saturating_sub(1) as i32,
        );
        // GL_CLAMP in the paper: outside [0,1] the edge texels are read.
        gl.tex_parameter_i32(target, glow::TEXTURE_WRAP_S, glow::CLAMP_TO_EDGE as i32);
        gl.tex_parameter_i32(target, glow::TEXTURE_WRAP_T, glow::CLAMP_TO_EDGE as i32);
        gl.tex_parameter_i32(target, glow::TEXTURE_WRAP_R, glow::CLAMP_TO_EDGE as i32);
        gl.bind_texture(target, None);
        Ok(t)
    }
}

/// Deletes the textures of `slots` whose kind none of `kinds` has (cube or not aside).
fn release_in(slots: &mut Slots, gl: &glow::Context, kinds: &[MapKey]) {
    slots.retain(|_, s| {
        let keep = kinds.iter().any(|k| {
            MapKey {
                cube: s.key.cube,
                ..*k
            } == s.key
        });
        if !keep {
            // SAFETY: our texture; no view of this frame reads it.
            unsafe { gl.delete_texture(s.texture) };
        }
        keep
    });
}

impl ShadowMaps {
    /// The budget the textures keep within from now on (None: no limit).
    pub fn set_budget(&mut self, budget: Option<u64>) {
        self.budget = budget;
    }

    /// Starts a frame (and its first stamp).
    pub fn start_frame(&mut self) {
        self.previous_start = self.frame_start;
        self.stamp += 1;
        self.frame_start = self.stamp;
    }

    /// Starts a new stamp: the textures used so far may be given up for those used next.
    pub fn next_stamp(&mut self) {
        self.stamp += 1;
    }

    /// The order in which a texture last used at `used` is given up (lowest first), or None
    /// while the current stamp uses it: first those neither this frame nor the last used,
    /// least recently used first; then this frame's, most recently used first; then those
    /// the last frame used and this one has not yet, most recently used first. Lights draw
    /// their maps in the same order every frame, so this gives up the map needed again
    /// furthest ahead (the optimal choice for a fixed order). Least recently used first gave
    /// up exactly the map the next light needs: over the budget with each light's maps drawn
    /// before its pass, a still camera drew every map again every frame.
    fn give_up_order(&self, used: u64) -> Option<(u8, i64)> {
        let used_i = used as i64;
        if used >= self.stamp {
            None
        } else if used < self.previous_start {
            Some((0, used_i))
        } else if used >= self.frame_start {
            Some((1, -used_i))
        } else {
            Some((2, -used_i))
        }
    }

    /// Textures taken over or deleted to keep within the budget so far.
    pub fn given_up(&self) -> usize {
        self.given_up
    }

    /// Bytes the textures hold together.
    pub fn bytes(&self) -> u64 {
        let maps: u64 = self
            .slots
            .values()
            .chain(self.statics.values())
            .map(|s| s.key.bytes())
            .sum();
        let ids: u64 = self
            .ids
            .values()
            .map(|&(_, size)| map_memory::id_texture_bytes(size))
            .sum();
        maps + ids
    }

    fn slots_in(&self, role: Role) -> &Slots {
        match role {
            Role::Map => &self.slots,
            Role::Static => &self.statics,
        }
    }

    fn slots_of(&mut self, role: Role) -> &mut Slots {
        match role {
            Role::Map => &mut self.slots,
            Role::Static => &mut self.statics,
        }
    }

    /// The texture of view `at` (light, view), (re)allocated to match, and the key of what it
    /// holds.
    pub fn slot(
        &mut self,
        gl: &glow::Context,
        at: (usize, usize),
        key: MapKey,
    ) -> Result<(glow::Texture, Option<u64>), String> {
        self.slot_of(gl, Role::Map, at, key)
    }

    /// The static map of view `at` (light, view; of the kind of its map), (re)allocated to
    /// match, and the key of what it holds.
    pub fn static_slot(
        &mut self,
        gl: &glow::Context,
        at: (usize, usize),
        key: MapKey,
    ) -> Result<(glow::Texture, Option<u64>), String> {
        self.slot_of(gl, Role::Static, at, key)
    }

    /// The texture of `at` among `role`'s, (re)allocated to match `key` within the budget,
    /// and the key of what it holds.
    fn slot_of(
        &mut self,
        gl: &glow::Context,
        role: Role,
        at: (usize, usize),
        key: MapKey,
    ) -> Result<(glow::Texture, Option<u64>), String> {
        let stamp = self.stamp;
        let slots = self.slots_of(role);
        if let Some(slot) = slots.get_mut(&at) {
            if slot.key == key {
                slot.used = stamp;
                return Ok((slot.texture, slot.content));
            }
            let old = slots.remove(&at).expect("present");
            // SAFETY: the old texture is ours and no longer referenced.
            unsafe { gl.delete_texture(old.texture) };
        }
        let texture = match self.take_over(gl, role, key) {
            Some(t) => t,
            None => {
                self.evict_for(gl, key.bytes());
                allocate(gl, key)?
            }
        };
        let content = None;
        let slot = Slot {
            texture,
            key,
            content,
            used: stamp,
        };
        self.slots_of(role).insert(at, slot);
        Ok((texture, content))
    }

    /// Over the budget with one more texture of `key`: the least recently used texture of
    /// `role` and that kind no view of the current stamp uses, taken from its view.
    fn take_over(&mut self, gl: &glow::Context, role: Role, key: MapKey) -> Option<glow::Texture> {
        let budget = self.budget?;
        if self.bytes() + key.bytes() <= budget {
            return None;
        }
        let at = self
            .slots_in(role)
            .iter()
            .filter(|(_, s)| s.key == key)
            .filter_map(|(at, s)| Some((self.give_up_order(s.used)?, *at)))
            .min()
            .map(|(_, at)| at)?;
        let slot = self.slots_of(role).remove(&at).expect("present");
        if role == Role::Map {
            self.delete_ids(gl, at);
        }
        self.given_up += 1;
        Some(slot.texture)
    }

    /// Deletes the least recently used textures no view of the current stamp uses until
    /// `need` more bytes fit the budget, or none is left to delete.
    fn evict_for(&mut self, gl: &glow::Context, need: u64) {
        let Some(budget) = self.budget else {
            return;
        };
        while self.bytes() + need > budget {
            let first = [Role::Map, Role::Static]
                .into_iter()
                .flat_map(|role| {
                    self.slots_in(role)
                        .iter()
                        .map(move |(at, s)| (role, *at, s.used))
                })
                .filter_map(|(role, at, used)| Some((self.give_up_order(used)?, role, at)))
                .min_by_key(|&(order, _, at)| (order, at));
            let Some((_, role, at)) = first else {
                return;
            };
            let slot = self.slots_of(role).remove(&at).expect("present");
            // SAFETY: our texture; no view of the current stamp reads it.
            unsafe { gl.delete_texture(slot.texture) };
            if role == Role::Map {
                self.delete_ids(gl, at);
            }
            self.given_up += 1;
        }
    }

    /// Deletes the ID texture of view `at`, whose map was given up.
    fn delete_ids(&mut self, gl: &glow::Context, at: (usize, usize)) {
        if let Some((t, _)) = self.ids.remove(&at) {
            // SAFETY: our texture; its map is gone.
            unsafe { gl.delete_texture(t) };
        }
    }

    /// Records what the static map of view `at` now holds.
    pub fn set_static_content(&mut self, at: (usize, usize), content: Option<u64>) {
        if let Some(s) = self.statics.get_mut(&at) {
            s.content = content;
        }
    }

    /// Deletes the static maps of `lights`' views not in `used`: those views are drawn whole
    /// now (no model in them, or the light moves), and keeping a static map per view any
    /// model ever crossed would hold up to twice the maps' memory.
    pub fn release_statics(
        &mut self,
        gl: &glow::Context,
        lights: &[usize],
        used: &[(usize, usize)],
    ) {
        self.statics.retain(|at, s| {
            let keep = !lights.contains(&at.0) || used.contains(at);
            if !keep {
                // SAFETY: our texture; this frame reads no static map it does not use.
                unsafe { gl.delete_texture(s.texture) };
            }
            keep
        });
    }

    /// Copies the static map of `at` into `texture` (one face of each where `cube_face`),
    /// both of `size`² and the same format: a depth blit between two framebuffers (GL 3.0,
    /// ES 3.0), NEAREST, as depth blits must be.
    pub fn copy_static(
        &mut self,
        gl: &glow::Context,
        at: (usize, usize),
        texture: glow::Texture,
        cube_face: Option<usize>,
        size: u32,
    ) -> Result<(), String> {
        let source = self
            .statics
            .get(&at)
            .ok_or("no static map to copy")?
            .texture;
        let draw = self.fbo(gl)?;
        let read = match self.read_fbo {
            Some(f) => f,
            // SAFETY: creating a framebuffer object.
            None => *self.read_fbo.insert(unsafe { gl.create_framebuffer()? }),
        };
        let image = super::passes::shadow_map::image_target(cube_face);
        let s = size as i32;
        // SAFETY: two framebuffers of our own, each with one of our depth textures; both are
        // detached and unbound afterwards. A blit writes only where the scissor lets it.
        unsafe {
            gl.disable(glow::SCISSOR_TEST);
            gl.depth_mask(true);
            for (target, fbo, t) in [
                (glow::READ_FRAMEBUFFER, read, source),
                (glow::DRAW_FRAMEBUFFER, draw, texture),
            ] {
                gl.bind_framebuffer(target, Some(fbo));
                gl.framebuffer_texture_2d(target, glow::DEPTH_ATTACHMENT, image, Some(t), 0);
            }
            gl.read_buffer(glow::NONE);
            gl.draw_buffers(&[glow::NONE]);
            gl.blit_framebuffer(
                0,
                0,
                s,
                s,
                0,
                0,
                s,
                s,
                glow::DEPTH_BUFFER_BIT,
                glow::NEAREST,
            );
            for target in [glow::READ_FRAMEBUFFER, glow::DRAW_FRAMEBUFFER] {
                gl.framebuffer_texture_2d(target, glow::DEPTH_ATTACHMENT, image, None, 0);
                gl.bind_framebuffer(target, None);
            }
        }
        Ok(())
    }

    /// The ID buffer's colour texture of `light`'s view `view`, and whether it was just made
    /// (it then holds nothing).
    pub fn id_texture(
        &mut self,
        gl: &glow::Context,
        light: usize,
        view: usize,
        size: u32,
    ) -> Result<(glow::Texture, bool), String> {
        if let Some(&(t, s)) = self.ids.get(&(light, view)) {
            if s == size {
                return Ok((t, false));
            }
            // SAFETY: our texture, replaced.
            unsafe { gl.delete_texture(t) };
            self.ids.remove(&(light, view));
        }
        self.evict_for(gl, map_memory::id_texture_bytes(size));
        // SAFETY: storage for a new texture; the binding is reset afterwards.
        let t = unsafe {
            let t = gl.create_texture()?;
            gl.bind_texture(glow::TEXTURE_2D, Some(t));
            gl.tex_image_2d(
                glow::TEXTURE_2D,
                0,
                glow::RGBA8 as i32,
                size as i32,
                size as i32,
                0,
                glow::RGBA,
                glow::UNSIGNED_BYTE,
                glow::PixelUnpackData::Slice(None),
            );
            for p in [glow::TEXTURE_MIN_FILTER, glow::TEXTURE_MAG_FILTER] {
                gl.tex_parameter_i32(glow::TEXTURE_2D, p, glow::NEAREST as i32);
            }
            for p in [glow::TEXTURE_WRAP_S, glow::TEXTURE_WRAP_T] {
                gl.tex_parameter_i32(glow::TEXTURE_2D, p, glow::CLAMP_TO_EDGE as i32);
            }
            gl.bind_texture(glow::TEXTURE_2D, None);
            t
        };
        self.ids.insert((light, view), (t, size));
        Ok((t, true))
    }

    /// Deletes every texture of a size, precision or buffer this frame's maps (`kinds`: the
    /// keys they were drawn with) do not have: such a map would be reallocated before its next
    /// use anyway, and a frame with other options (a `tune` candidate, a toggle in the viewer)
    /// would otherwise keep every light's old maps beside its own (on oa_dm3, 51 lights of
    /// 2048-texel cubes are 5 GB). Cube or not is left out: the planner picks it per light and
    /// view, so it changes with the camera. ID textures go with their maps. A frame that draws
    /// no maps (volumes only) keeps them all, so that a run switching between maps and volumes
    /// every frame creates no GL objects.
    pub fn release_unlike(&mut self, gl: &glow::Context, kinds: &[MapKey]) {
        if kinds.is_empty() {
            return;
        }
        release_in(&mut self.slots, gl, kinds);
        release_in(&mut self.statics, gl, kinds);
        let slots = &self.slots;
        self.ids.retain(|at, (t, size)| {
            let keep = slots
                .get(at)
                .is_some_and(|s| s.key.buffer == MapBuffer::Id && s.key.size == *size);
            if !keep {
                // SAFETY: our texture; its map is gone or stores no IDs.
                unsafe { gl.delete_texture(*t) };
            }
            keep
        });
    }

    /// Records what `light`'s view `view` now holds.
    pub fn set_content(&mut self, light: usize, view: usize, content: Option<u64>) {
        if let Some(s) = self.slots.get_mut(&(light, view)) {
            s.content = content;
        }
    }

    /// Forgets every map's contents (a new scene).
    pub fn forget(&mut self) {
        for s in self.slots.values_mut().chain(self.statics.values_mut()) {
            s.content = None;
        }
    }

    /// Sampling state for the lit pass: compare mode (ARB_shadow) and filtering (between
    /// texels, and from the nearest level when `mipmapped`).
    pub fn configure(
        gl: &glow::Context,
        texture: glow::Texture,
        (cube, mipmapped): (bool, bool),
        compare: Compare,
        filter: Filter,
    ) {
        let target = if cube {
            glow::TEXTURE_CUBE_MAP
        } else {
            glow::TEXTURE_2D
        };
        let linear = filter == Filter::Hw2x2 && compare == Compare::Hardware;
        let f = if linear { glow::LINEAR } else { glow::NEAREST } as i32;
        // From the nearest level: blending two levels' compares measured worse (docs/id-buffers.md).
        let min = match (mipmapped, linear) {
            (false, _) => f,
            (true, false) => glow::NEAREST_MIPMAP_NEAREST as i32,
            (true, true) => glow::LINEAR_MIPMAP_NEAREST as i32,
        };
        // SAFETY: parameters of our texture.
        unsafe {
            gl.bind_texture(target, Some(texture));
            gl.tex_parameter_i32(target, glow::TEXTURE_MIN_FILTER, min);
            gl.tex_parameter_i32(target, glow::TEXTURE_MAG_FILTER, f);
            let mode = match compare {
                Compare::Hardware => glow::COMPARE_REF_TO_TEXTURE,
                Compare::Shader => glow::NONE,
            };
            gl.tex_parameter_i32(target, glow::TEXTURE_COMPARE_MODE, mode as i32);
            gl.tex_parameter_i32(target, glow::TEXTURE_COMPARE_FUNC, glow::LEQUAL as i32);
        }
    }

    /// A depth-only framebuffer for rendering straight into the maps.
    pub fn fbo(&mut self, gl: &glow::Context) -> Result<glow::Framebuffer, String> {
        if let Some(f) = self.fbo {
            return Ok(f);
        }
        // SAFETY: creating a framebuffer object.
        let f = unsafe { gl.create_framebuffer()? };
        self.fbo = Some(f);
        Ok(f)
    }

    pub fn texture_count(&self) -> usize {
        self.slots.len() + self.statics.len() + self.ids.len()
    }

    pub fn delete(&mut self, gl: &glow::Context) {
        // SAFETY: called once by the owner.
        unsafe {
            for (_, s) in self.slots.drain().chain(self.statics.drain()) {
                gl.delete_texture(s.texture);
            }
            for (_, (t, _)) in self.ids.drain() {
                gl.delete_texture(t);
            }
            for f in [self.fbo.take(), self.read_fbo.take()]
                .into_iter()
                .flatten()
            {
                gl.delete_framebuffer(f);
            }
        }
    }
}
