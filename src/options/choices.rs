//! The option enums (the choices an option offers), the `auto` candidates and the warps.

use super::Options;
use super::value::OptionValue;
use crate::option_enum;
use std::fmt;

option_enum! {
    /// How the passes are drawn.
    pub enum Pipeline {
        /// GLSL programs on a core-profile context: every option works (the default).
        Shaders = "shaders",
        /// The paper's legacy calls on a compatibility-profile context (glAlphaFunc, glTexGen,
        /// DEPTH_TEXTURE_MODE, glClipPlane, texture environments, glLight): options it cannot
        /// draw are replaced and listed as fallbacks (`plan::fixed_function`).
        FixedFunction = "fixed_function",
    }
}

option_enum! {
    /// Which GL context path to take.
    pub enum BackendChoice {
        /// The chain: EGL desktop GL 3.3 core, then EGL OpenGL ES 3.0, then OSMesa (for the
        /// compatibility profile: EGL, then OSMesa).
        Auto = "auto",
        /// EGL device platform, surfaceless desktop GL context, rendering into our own
        /// framebuffers.
        Egl = "egl",
        /// EGL device platform, OpenGL ES 3.0 (GLSL ES 3.00 shaders; what ES lacks falls back,
        /// see docs/gl-paths.md).
        EglEs = "egl_es",
        /// libOSMesa loaded at run time.
        Osmesa = "osmesa",
        /// A winit window with a glutin context (needs a display, e.g. `xvfb-run`).
        Window = "window",
    }
}

option_enum! {
    /// Which shadow algorithm the lit passes use.
    pub enum Technique {
        /// No shadows: every receiver is lit (the base renderer, paper section 2).
        None = "none",
        /// Shadow mapping (paper section 3).
        ShadowMap = "shadow_map",
        /// Stenciled shadow volumes (paper section 4).
        ShadowVolume = "shadow_volume",
        /// Per light, the cheaper of the two whose estimated error meets `accuracy` (thesis
        /// chapter 7: pick the algorithm for the case); the planner says why.
        Auto = "auto",
        /// Perspective shadow maps (Stamminger & Drettakis 2002, thesis chapter 4): each map
        /// drawn in the camera's post-perspective space (`psm.*`); a light where that
        /// degenerates falls back to a standard map and the stats say why.
        Psm = "psm",
        /// Trapezoidal shadow maps (Martin & Tan 2004, after Forsyth's slides): the light's
        /// view of the camera frustum warped by a trapezoid onto the map (`psm.*` shared).
        Tsm = "tsm",
        /// Chan & Durand's hybrid (2004, thesis chapter 5): a shadow map decides where its
        /// 2×2 compares agree; shadow volumes are counted only at the other pixels (`hybrid.*`).
        Hybrid = "hybrid",
        /// Vector's light-volume subdivision (Chin & Feiner's shadow-volume BSP tree): each
        /// light's receivers cut once, in object space, into lit and shadowed fragments (built
        /// when the light or a triangle in its range changes, kept on disk like `shadowlab
        /// subdivide`); the shadowed ones are marked into the stencil over the frame's depth
        /// and the lit pass draws where none is. Alpha-tested casters are solid. Meant for
        /// static lights and casters: a moving one is subdivided again every frame.
        Subdivision = "subdivision",
    }
}

impl Options {
    /// What `technique`'s maps store: `shadow_map.buffer` for standard maps; the warped maps
    /// and the hybrid keep depth.
    pub fn map_buffer(&self, technique: Technique) -> MapBuffer {
        if technique == Technique::ShadowMap {
            self.shadow_map.buffer
        } else {
            MapBuffer::Depth
        }
    }
}

/// What `technique = auto` chooses for a light: a technique and, for standard maps, what they
/// store and their size. Written `shadow_map:id` or `shadow_map@1024` (or both,
/// `shadow_map:id@1024`) in `auto_among`; a bare `shadow_map` stores what `shadow_map.buffer`
/// says at `shadow_map.size`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Candidate {
    pub technique: Technique,
    /// Depth for every technique but `shadow_map` (see [`Options::map_buffer`]).
    pub buffer: MapBuffer,
    /// The light's own map size (`shadow_map@1024`); None: `shadow_map.size`.
    pub size: Option<u32>,
}

/// The map sizes `shadow_map@N` may name: `shadow_map.size`'s range.
const CANDIDATE_SIZES: std::ops::RangeInclusive<u32> = 16..=8192;

impl Candidate {
    /// `technique` with the buffer `options` give it.
    pub fn of(technique: Technique, options: &Options) -> Candidate {
        Candidate {
            technique,
            buffer: options.map_buffer(technique),
            size: None,
        }
    }

    /// Standard maps storing `buffer`, at `shadow_map.size`.
    pub fn maps(buffer: MapBuffer) -> Candidate {
        Candidate {
            technique: Technique::ShadowMap,
            buffer,
            size: None,
        }
    }

    /// The same candidate with maps of `size` texels a side.
    pub fn sized(self, size: u32) -> Candidate {
        Candidate {
            size: Some(size),
            ..self
        }
    }

    /// One `auto_among` entry: `technique`, `shadow_map:buffer`, `shadow_map@size` or
    /// `shadow_map:buffer@size`, resolved under `options`.
    pub(super) fn parse(text: &str, options: &Options) -> Result<Candidate, String> {
        let (name, size) = match text.split_once('@') {
            Some((n, s)) => {
                let size: u32 = s
                    .trim()
                    .parse()
                    .map_err(|_| format!("`{}`: the size after @ is a number", text.trim()))?;
                if !CANDIDATE_SIZES.contains(&size) {
                    return Err(format!(
                        "`{}`: a map size is within {}..={}",
                        text.trim(),
                        CANDIDATE_SIZES.start(),
                        CANDIDATE_SIZES.end()
                    ));
                }
                (n, Some(size))
            }
            None => (text, None),
        };
        let (technique, buffer) = match name.split_once(':') {
            Some((t, b)) => (t, Some(b)),
            None => (name, None),
        };
        let technique = Technique::parse_value(technique)?;
        if matches!(technique, Technique::None | Technique::Auto) {
            return Err(format!("`{technique}` is not a shadow technique"));
        }
        if technique != Technique::ShadowMap && (buffer.is_some() || size.is_some()) {
            return Err(format!(
                "`{}`: only shadow_map takes a buffer or a size (shadow_map:id, shadow_map@1024)",
                text.trim()
            ));
        }
        let candidate = match buffer {
            None => Candidate::of(technique, options),
            Some(b) => Candidate::maps(MapBuffer::parse_value(b)?),
        };
        Ok(Candidate { size, ..candidate })
    }
}

/// A technique whose maps (if any) store depth.
impl From<Technique> for Candidate {
    fn from(technique: Technique) -> Candidate {
        Candidate {
            technique,
            buffer: MapBuffer::Depth,
            size: None,
        }
    }
}

impl fmt::Display for Candidate {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.technique)?;
        if self.buffer != MapBuffer::Depth {
            write!(f, ":{}", self.buffer)?;
        }
        match self.size {
            Some(size) => write!(f, "@{size}"),
            None => Ok(()),
        }
    }
}

impl Technique {
    /// Whether the technique draws shadow maps (its lit pass reads them).
    pub fn uses_maps(self) -> bool {
        matches!(
            self,
            Technique::ShadowMap | Technique::Psm | Technique::Tsm | Technique::Hybrid
        )
    }

    /// Whether the technique counts shadow volumes into the stencil.
    pub fn uses_volumes(self) -> bool {
        matches!(self, Technique::ShadowVolume | Technique::Hybrid)
    }

    /// The warp its maps are drawn with (`psm`, `tsm`), if any.
    pub fn warp(self) -> Option<Warp> {
        match self {
            Technique::Psm => Some(Warp::Perspective),
            Technique::Tsm => Some(Warp::Trapezoid),
            _ => None,
        }
    }
}

/// How a warped shadow map reparameterises the light's view.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Warp {
    /// The camera's post-perspective space (`psm`).
    Perspective,
    /// A trapezoid around the camera frustum in the light's view (`tsm`).
    Trapezoid,
}

option_enum! {
    /// What the planner's costs are weighed for (`plan.profile`).
    pub enum Profile {
        /// `software` where the GL renderer is a CPU rasteriser (llvmpipe, softpipe, OSMesa's
        /// swrast), else `gpu`.
        Auto = "auto",
        /// Fill costs the CPU that draws it, and waiting for the GL costs little (its
        /// "GPU" is the same CPU): decisions that read the frame back to save fill are on.
        Software = "software",
        /// A pipelined GPU: reading anything back mid-frame stalls it for a whole pipeline's
        /// depth, so every decision that reads the frame back (`occlusion`, `depth_clip`) is
        /// off; `depth_bounds_test`, which needs no read-back, stays.
        Gpu = "gpu",
    }
}

option_enum! {
    /// Where stencil counting happens.
    pub enum CountingMode {
        /// Depth-fail, Carmack's reverse: back faces increment and front faces decrement where the
        /// depth test fails; needs capped volumes, works with the camera inside (the paper).
        Zfail = "zfail",
        /// Depth-pass: front faces increment and back faces decrement where it passes; no caps,
        /// wrong when the camera is inside a volume.
        Zpass = "zpass",
        /// Per caster: depth-pass where the view cannot be inside its shadow (Doom 3's test),
        /// depth-fail elsewhere (what the paper says it should have done).
        Auto = "auto",
    }
}

option_enum! {
    /// How the volumes reach the stencil buffer.
    pub enum StencilPasses {
        /// Back faces in one pass, front faces in another (the paper: no two-sided stencil).
        TwoPass = "two_pass",
        /// One pass with glStencilOpSeparate for front and back faces; always with wrapping
        /// arithmetic, since interleaved faces would underflow saturating counts.
        Separate = "separate",
    }
}

option_enum! {
    /// Stencil arithmetic at 0 and 255.
    pub enum StencilWrap {
        /// INCR / DECR clamp (the paper's card lacked EXT_stencil_wrap).
        Saturate = "saturate",
        /// INCR_WRAP / DECR_WRAP.
        Wrap = "wrap",
    }
}

option_enum! {
    /// Which edges become volume sides.
    pub enum EdgeRule {
        /// The paper's world rule: skip an edge only when exactly two triangles share it and both
        /// face the light; otherwise each facing triangle on it extrudes it.
        Paper = "paper",
        /// Every edge of every facing triangle (the paper's first, brute-force fix).
        All = "all",
        /// The textbook 2-manifold rule: an edge is a silhouette when exactly one of its first two
        /// triangles faces the light; open edges never are (it leaks on Quake 3 worlds).
        Manifold = "manifold",
        /// Robust (not in the paper): facing triangles that run along an edge in opposite
        /// directions cancel; each unmatched one extrudes it. Duplicated triangles and
        /// non-manifold fans, where the paper's rule leaves volumes open, stay closed.
        Signed = "signed",
    }
}

option_enum! {
    /// Where extruded vertices go.
    pub enum Extrusion {
        /// To infinity, w = 0 (paper 4.1).
        Infinite = "infinite",
        /// shadow_volume.finite_distance away from the light.
        Finite = "finite",
    }
}

option_enum! {
    /// The camera projection under shadow volumes.
    pub enum VolumeProjection {
        /// The far plane at infinity, P = lim f→∞ (paper 4.1).
        Infinite = "infinite",
        /// Doom 3's form: third row crunched by ε = 0.001, so w = 0 points stay inside the far plane.
        InfiniteEpsilon = "infinite_epsilon",
        /// A finite far plane beyond the scene, with GL_DEPTH_CLAMP while volumes are drawn.
        DepthClamp = "depth_clamp",
    }
}

option_enum! {
    /// How shadowed pixels are shaded.
    pub enum VolumeShading {
        /// Each light's additive pass where the stencil is 0 (the paper).
        Additive = "additive",
        /// Bestimt and Freitag: light everything, then a full-screen quad darkens stencil > 0
        /// pixels (DESTCOLOR x 0.878) and zeroes the stencil as it goes.
        Fill = "fill",
    }
}

option_enum! {
    /// Where a shadow map's depth values come from.
    pub enum DepthSource {
        /// Draw the light's view into the frame's own depth buffer, then glCopyTexSubImage2D into
        /// the light's depth texture (the paper: its card had no pbuffers).
        Copy = "copy",
        /// Render straight into the depth texture through a framebuffer object (thesis 2.2.10's
        /// pbuffer path).
        Fbo = "fbo",
    }
}

option_enum! {
    /// Depth texture precision.
    pub enum DepthBits {
        /// DEPTH_COMPONENT24 (the paper).
        D24 = "24",
        D16 = "16",
        /// DEPTH_COMPONENT32F (the frame's depth buffer becomes 32F too, so copies keep it).
        D32f = "32f",
    }
}

option_enum! {
    /// How the stored depth is compared with the fragment's light-space depth.
    pub enum Compare {
        /// sampler2DShadow with COMPARE_REF_TO_TEXTURE and LEQUAL (ARB_shadow).
        Hardware = "hardware",
        /// A plain depth fetch compared in the shader.
        Shader = "shader",
    }
}

option_enum! {
    /// Where the compare result goes (ARB_depth_texture's DEPTH_TEXTURE_MODE).
    pub enum CompareResult {
        /// ALPHA, then the alpha test rejects shadowed fragments (the paper).
        Alpha = "alpha",
        /// INTENSITY: the light is multiplied by the result (thesis 2.2.6).
        Intensity = "intensity",
    }
}

option_enum! {
    /// glAlphaFunc's comparison, emulated in the shader.
    pub enum AlphaTestFunc {
        Never = "never",
        Less = "less",
        Equal = "equal",
        Lequal = "lequal",
        Greater = "greater",
        Notequal = "notequal",
        Gequal = "gequal",
        Always = "always",
    }
}

option_enum! {
    /// Filtering of the compare.
    pub enum Filter {
        /// One compare at the nearest texel (the paper).
        Nearest = "nearest",
        /// LINEAR filtering of the compare: the hardware's 2x2 percentage-closer filter.
        Hw2x2 = "hw2x2",
        /// Nine compares at the texel and its eight neighbours, averaged (paper 3.1).
        Pcf3x3 = "pcf3x3",
        /// N x N compares (N = shadow_map.pcf_size), averaged.
        Pcf = "pcf",
    }
}

option_enum! {
    /// Which passes glPolygonOffset applies to.
    pub enum OffsetPass {
        /// Push the shadow map away from the light (thesis 2.2.8).
        ShadowMap = "shadow_map",
        /// Pull the lit pass toward the camera (the paper's "offset the polygons" of section 3.1).
        Lit = "lit",
        Both = "both",
    }
}

option_enum! {
    /// What happens to points the light reaches that lie outside a shadow map's frustum.
    pub enum Outside {
        /// s and t clamp to the map's edge texels (GL_CLAMP; the artifact).
        Clamp = "clamp",
        /// A texgen range test: outside [0,1] no compare is made (the point is unshadowed).
        Range = "range",
        /// The light's frustum planes clip the lit pass (gl_ClipDistance; paper Fig. 1 anomalies).
        ClipPlanes = "clip_planes",
    }
}

option_enum! {
    /// Which faces of casters are drawn into the shadow map.
    pub enum CasterFaces {
        /// Faces toward the light (back-face culling, as the thesis draws them).
        Front = "front",
        /// Faces away from the light (thesis 2.2.8: no bias needed, but only closed meshes cast).
        Back = "back",
        /// Both faces: one-sided Quake 3 faces seen from behind cast too (open worlds), as the
        /// exact reference counts every face as solid.
        Both = "both",
    }
}

option_enum! {
    /// Whose shadow volumes a vertex shader extrudes from a mesh built once per caster and pose
    /// (`shaders/volume_gpu.vert`), instead of the CPU building them per light.
    pub enum GpuExtrusion {
        /// `moving` under `plan.profile = gpu`, `none` under `software` (on llvmpipe the
        /// vertex shader runs on the CPU too, and the CPU's pieces are culled and cached:
        /// docs/motion.md).
        Auto = "auto",
        /// None: every volume is built on the CPU (the paper's frame).
        None = "none",
        /// What the CPU would build again every frame: models', and every caster's under a
        /// light that moves (an orbit or a route in the scene's motion).
        Moving = "moving",
        /// Models' (players and other MD3s): an animated model's volumes would be built anew on
        /// the CPU for every frame and light; the world's stay on the CPU, cached.
        Models = "models",
        /// Every caster's, the world's too.
        All = "all",
    }
}

option_enum! {
    /// Which triangles of casters extrude shadow volumes.
    pub enum VolumeCasters {
        /// Triangles facing the light (the paper): a one-sided face seen from behind casts
        /// nothing, so open worlds lose shadows.
        Front = "front",
        /// Every triangle: those facing away are extruded with the opposite winding, and edges
        /// become sides by the signed rule (`edge_rule` is then `signed` whatever it says), as
        /// the exact reference counts every face as solid.
        Both = "both",
    }
}

option_enum! {
    /// How an omni light is shadow mapped.
    pub enum OmniMode {
        /// Six 90-degree spot lights, each lighting the directions of its own cube face (the paper).
        SixSpots = "six_spots",
        /// One depth cube map and one lit pass.
        Cube = "cube",
        /// Several frusta around the receivers in view (Forsyth's multiple frustums), each a
        /// rectangle of a cube face with its own map size, sized by the texels per unit the
        /// receivers' size on screen asks for, within the texels of six faces of
        /// `shadow_map.size` (`shadow::frusta`).
        Frusta = "frusta",
    }
}

option_enum! {
    /// The positions a shadow map's depth pass transforms (the shader pipeline; the legacy one
    /// loads the light's matrices as glLoadMatrix does, in world space).
    pub enum CasterSpace {
        /// World positions through the light's view and projection in single precision, as
        /// glLoadMatrix does (the paper). At Quake 3 scale (coordinates in the thousands) the
        /// view's translation cancels most of each product, and the depth the map stores is off
        /// by several steps of a 24-bit map: more than the offset's 4 units on a wall facing the
        /// light head-on (oa_koth2's light 41: 12.3% of its receivers falsely shadowed).
        World = "world",
        /// Positions relative to the light (the light's position subtracted in the vertex
        /// shader), through the view and projection composed in double precision: no large
        /// numbers cancel, and the stored depth is what the lit pass's light-relative texgen
        /// computes for the same point.
        Light = "light",
    }
}

option_enum! {
    /// Where the lit pass's texgen planes are applied (the shader pipeline; the legacy one is
    /// glTexGen's own, eye-linear).
    pub enum TexgenSpace {
        /// To eye coordinates, with planes composed in single precision through the camera's
        /// inverse, as glTexGen(GL_EYE_LINEAR) does (the paper). At Quake 3 scale (coordinates
        /// in the thousands, lights tens of units from walls) the rounding exceeds the polygon
        /// offset's constant term: walls facing an omni light's face head-on get acne (oa_dm3's
        /// light 2: 4.7% of its receivers falsely shadowed under six spot maps).
        EyeLinear = "eye_linear",
        /// The same planes composed in double precision and applied, per vertex, to the position
        /// relative to the light, so no large coordinates cancel. The projective coordinates
        /// (s, t, r, q) are then interpolated, and how a rasteriser rounds that interpolation
        /// shows on walls facing a face head-on: oa_dm3's light 2 under six spot maps, 0.058%
        /// falsely shadowed on llvmpipe but 0.485% on softpipe (docs/shadow-maps.md).
        Light = "light",
        /// The light-relative planes applied per fragment to the interpolated world position
        /// minus the light's, as the cube map computes its compared depth: only the position,
        /// linear, is interpolated (oa_dm3's light 2: 0.058% on llvmpipe, 0.078% on softpipe,
        /// as the cube map).
        Fragment = "fragment",
    }
}

option_enum! {
    /// What a shadow map stores (Forsyth's slides; docs/id-buffers.md). Every kind but
    /// `depth` needs gl_PrimitiveID in fragment shaders (not on ES 3.0, where `depth` is
    /// used and the frame says so) and applies to standard maps (`technique = shadow_map`);
    /// an omni light is then always six spot maps (`shadow_map.omni = cube` is not used).
    pub enum MapBuffer {
        /// Depth from the light, compared with the fragment's (the paper).
        Depth = "depth",
        /// The ID (`id_unit`) of the nearest surface, as colour: lit where the fragment's own
        /// ID is stored. No bias; where two IDs meet, a texel of the neighbour falsely
        /// shadows ("edge acne", cured by `id_edge_filter`).
        Id = "id",
        /// Priorities: the units (`id_unit`) sorted by their nearest distance from the light
        /// and drawn at constant depths, nearest first; lit where no nearer unit covers the
        /// texel. No bias; a wrong sort (interpenetrating or circular units) shadows wrongly.
        Priority = "priority",
        /// Hybrid priority and depth: each unit a range of depth by its priority, its own
        /// distances from the light spread within it; the bias (`priority_bias`) is per unit,
        /// a share of its own range, and there is no peter panning between units.
        PriorityDepth = "priority_depth",
    }
}

option_enum! {
    /// How `technique = subdivision` shadows with models (`subdivision.models`).
    pub enum ModelShadows {
        /// The world subdivided; models' shadows, and the world's on models, by volumes.
        Volumes = "volumes",
        /// Models subdivided with the world.
        Subdivided = "subdivided",
    }
}

option_enum! {
    /// What one ID of an ID or priority buffer stands for.
    pub enum IdUnit {
        /// A scene surface (a Quake 3 face, patch or model surface).
        Surface = "surface",
        /// A convex part of a caster group (`shadow::parts`): cannot shadow itself.
        Part = "part",
        /// A triangle (needs more than 8 bits of ID).
        Triangle = "triangle",
    }
}

option_enum! {
    /// Alpha-tested surfaces in the shadow map pass.
    pub enum AlphaCasters {
        /// The depth pass samples alpha and discards like the surface does.
        Test = "test",
        /// Drawn solid.
        Ignore = "ignore",
    }
}
