//! The frame's programs: compiled at start, lit variants and ID-buffer depth programs on first use.

use super::*;
/// The `#define`s of the lit program for these settings: with a shadow-map lookup (`shadow_map`,
/// from a cube map when `cube`) or without, writing light or the mask.
pub(super) fn lit_defines(
    settings: &PassSettings,
    v: LitVariant,
    texel_grid: bool,
) -> Vec<&'static str> {
    let LitVariant {
        shadow_map,
        cube,
        six,
        mask,
        hybrid,
        warp_depth,
        buffer,
    } = v;
    let mut d = Vec::new();
    if shadow_map {
        d.extend(buffer_defines(buffer, settings.shadow_map.id_edge_filter));
        if buffer == MapBuffer::Priority && settings.shadow_map.priority_mipmap && !cube {
            d.push("PRIORITY_MIPMAP");
        }
    }
    if hybrid {
        d.push("HYBRID");
    }
    if warp_depth {
        d.push("WARP_DEPTH");
    }
    if shadow_map {
        if six {
            d.push("SIX_SPOTS");
        }
        if texel_grid && !mask {
            d.push("TEXEL_GRID");
        }
        let o = &settings.shadow_map;
        d.push("SHADOW_MAP");
        if cube {
            d.push("SHADOW_CUBE");
        }
        if o.compare == Compare::Shader {
            d.push("COMPARE_SHADER");
        }
        match o.filter {
            Filter::Nearest => {}
            Filter::Hw2x2 => d.push("FILTER_HW2X2"),
            Filter::Pcf3x3 => d.push("FILTER_PCF3"),
            Filter::Pcf => d.push("FILTER_PCFN"),
        }
        match o.outside {
            Outside::Clamp => {}
            Outside::Range => d.push("OUTSIDE_RANGE"),
            Outside::ClipPlanes => d.push("CLIP_PLANES"),
        }
        if o.depth_bits != DepthBits::D32f {
            d.push("REF_CLAMP");
        }
        if o.texgen == TexgenSpace::Fragment && !cube {
            d.push("TEXGEN_FRAGMENT");
        }
        if o.result == CompareResult::Alpha {
            d.push("RESULT_ALPHA");
        }
    }
    if mask {
        d.push("MASK_OUTPUT");
    }
    d
}

/// The `#define`s of an ID or priority buffer, for the depth and lit programs alike.
pub(super) fn buffer_defines(buffer: MapBuffer, edge_filter: bool) -> Vec<&'static str> {
    match buffer {
        MapBuffer::Depth => vec![],
        MapBuffer::Id if edge_filter => vec!["ID_TABLE", "BUFFER_ID", "ID_EDGE_FILTER"],
        MapBuffer::Id => vec!["ID_TABLE", "BUFFER_ID"],
        MapBuffer::Priority => vec!["ID_TABLE", "BUFFER_PRIORITY"],
        MapBuffer::PriorityDepth => vec!["ID_TABLE", "BUFFER_PRIORITY_DEPTH"],
    }
}

/// Which lit program a pass needs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(super) struct LitVariant {
    /// With a shadow-map lookup...
    pub(super) shadow_map: bool,
    /// ...into one cube map...
    pub(super) cube: bool,
    /// ...or into an omni light's six spot maps at once.
    pub(super) six: bool,
    /// Writing the decision mask instead of light.
    pub(super) mask: bool,
    /// Chan & Durand's hybrid (with `shadow_map`).
    pub(super) hybrid: bool,
    /// The compared depth from the light's own view (trapezoidal maps).
    pub(super) warp_depth: bool,
    /// What the maps store (`shadow_map.buffer`; depth for every technique but shadow_map).
    pub(super) buffer: MapBuffer,
}

impl LitVariant {
    /// Without a shadow map: lit (or `mask`) as the stencil says.
    pub(super) fn plain(mask: bool) -> LitVariant {
        LitVariant {
            shadow_map: false,
            cube: false,
            six: false,
            mask,
            hybrid: false,
            warp_depth: false,
            buffer: MapBuffer::Depth,
        }
    }
}

/// Bestimt and Freitag's fill colour (their 0x00E0E0E0 with DESTCOLOR blending).
pub const FILL_SHADE: f32 = 224.0 / 255.0;

pub(super) struct Programs {
    pub(super) unlit: Program,
    /// The unlit pass writing the G-buffer too (`unlit.frag` with `GBUFFER`), for frames
    /// asked for masks.
    pub(super) unlit_gbuffer: Program,
    pub(super) depth: Program,
    /// The depth pass storing another matrix's depth than it draws with (trapezoidal maps).
    pub(super) depth_warp: Program,
    pub(super) volume: passes::stencil::VolumePrograms,
    /// The subdivision's shadowed fragments into the stencil.
    pub(super) fragments: Program,
    pub(super) fill: Program,
    /// A recording light's undrawn pixels it reaches, into its layer (`gl::record`).
    pub(super) record_reach: Program,
    /// The G-buffer at picked pixels (`gl::gather`).
    pub(super) gather: Program,
    /// The depth's 4×4 block maxima for the planner.
    pub(super) depth_reduce: Program,
    /// A priority buffer's mip levels (`shadow_map.priority_mipmap`).
    pub(super) priority_mips: Program,
    /// Volumes and silhouettes drawn over the frame (debug overlay).
    pub(super) debug_volume: Program,
    /// Lit programs by their define set, compiled on first use.
    pub(super) lit: HashMap<String, Program>,
    /// Depth programs of ID and priority buffers, compiled on first use.
    pub(super) depth_buffers: HashMap<MapBuffer, Program>,
}

impl Programs {
    pub(super) fn new(gl: &glow::Context) -> Result<Programs, ProgramError> {
        let unlit = |name, defines| {
            Program::new(
                gl,
                name,
                sources::WORLD_VERT,
                Some(sources::UNLIT_FRAG),
                defines,
            )
        };
        Ok(Programs {
            unlit: unlit("unlit", &[])?,
            unlit_gbuffer: unlit("unlit[GBUFFER]", &["GBUFFER"])?,
            depth: Program::new(
                gl,
                "depth",
                sources::DEPTH_VERT,
                Some(sources::DEPTH_FRAG),
                &[],
            )?,
            depth_warp: Program::new(
                gl,
                "depth_warp",
                sources::DEPTH_VERT,
                Some(sources::DEPTH_FRAG),
                &["WARP_DEPTH"],
            )?,
            volume: passes::stencil::VolumePrograms {
                built: Program::new(
                    gl,
                    "volume",
                    sources::VOLUME_VERT,
                    Some(sources::VOLUME_FRAG),
                    &[],
                )?,
                extruded: Program::new(
                    gl,
                    "volume_gpu",
                    sources::VOLUME_GPU_VERT,
                    Some(sources::VOLUME_FRAG),
                    &[],
                )?,
            },
            fragments: Program::new(
                gl,
                "fragments",
                sources::FRAGMENTS_VERT,
                Some(sources::VOLUME_FRAG),
                &[],
            )?,
            fill: Program::new(
                gl,
                "fill",
                sources::FULLSCREEN_VERT,
                Some(sources::FILL_FRAG),
                &[],
            )?,
            gather: Program::new(
                gl,
                "gather",
                sources::GATHER_VERT,
                Some(sources::GATHER_FRAG),
                &[],
            )?,
            record_reach: Program::new(
                gl,
                "record_reach",
                sources::FULLSCREEN_VERT,
                Some(sources::RECORD_REACH_FRAG),
                &[],
            )?,
            depth_reduce: Program::new(
                gl,
                "depth_reduce",
                sources::FULLSCREEN_VERT,
                Some(sources::DEPTH_REDUCE_FRAG),
                &[],
            )?,
            priority_mips: Program::new(
                gl,
                "priority_mips",
                sources::FULLSCREEN_VERT,
                Some(sources::PRIORITY_MIPS_FRAG),
                &[],
            )?,
            debug_volume: Program::new(
                gl,
                "debug_volume",
                sources::DEBUG_VOLUME_VERT,
                Some(sources::DEBUG_VOLUME_FRAG),
                &[],
            )?,
            lit: HashMap::new(),
            depth_buffers: HashMap::new(),
        })
    }

    /// Compiles the depth program of `buffer` if needed (none for depth maps).
    pub(super) fn depth_buffer(
        &mut self,
        gl: &glow::Context,
        buffer: MapBuffer,
    ) -> Result<(), ProgramError> {
        if buffer == MapBuffer::Depth || self.depth_buffers.contains_key(&buffer) {
            return Ok(());
        }
        let p = Program::new(
            gl,
            &format!("depth[{buffer}]"),
            sources::DEPTH_VERT,
            Some(sources::DEPTH_FRAG),
            &buffer_defines(buffer, false),
        )?;
        self.depth_buffers.insert(buffer, p);
        Ok(())
    }

    /// Compiles the lit variant for `defines` if needed; returns its key.
    pub(super) fn lit_variant(
        &mut self,
        gl: &glow::Context,
        defines: &[&str],
    ) -> Result<String, ProgramError> {
        let key = defines.join(" ");
        if !self.lit.contains_key(&key) {
            let fragment = if defines.contains(&"SHADOW_MAP") {
                format!("{}\n{}", sources::SHADOW, sources::LIT_FRAG)
            } else {
                sources::LIT_FRAG.to_string()
            };
            let p = Program::new(
                gl,
                &format!("lit[{key}]"),
                sources::WORLD_VERT,
                Some(&fragment),
                defines,
            )?;
            self.lit.insert(key.clone(), p);
        }
        Ok(key)
    }

    pub(super) fn delete(&mut self, gl: &glow::Context) {
        for p in [
            &self.unlit,
            &self.unlit_gbuffer,
            &self.depth,
            &self.depth_warp,
            &self.volume.built,
            &self.volume.extruded,
            &self.fragments,
            &self.fill,
            &self.record_reach,
            &self.gather,
            &self.depth_reduce,
            &self.priority_mips,
            &self.debug_volume,
        ] {
            p.delete(gl);
        }
        for p in self.depth_buffers.values() {
            p.delete(gl);
        }
        for p in self.lit.values() {
            p.delete(gl);
        }
        self.lit.clear();
    }
}
