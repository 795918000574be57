//! Every pipeline choice of shadowlab, in one place.
//!
//! Each option is one field with a one-line meaning. The fixed-function choices default to
//! what the paper (Arneson, "Real-Time Shadows") or the thesis (Sindholt 2005) chose; two
//! defaults are not the paper's, so that a plain run shows shadows and runs fast: `technique =
//! auto` (the paper names one) and the frame planner (`plan.enabled`; the paper plans nothing).
//! `--preset paper` (see `presets`) is the paper's frame. The same keys are set
//! from the command line (`--set key=value`), from scene files (`[options]`), by bench sweeps and by the
//! viewer's panels; `shadowlab options` lists them.
//!
//! Options are declared once with [`define_options!`], which generates the plain-data structs
//! (serde), their defaults, the string setters and getters, and the listing.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fmt;
use thiserror::Error;

/// Why an option could not be set.
#[derive(Debug, Error, PartialEq)]
pub enum OptionError {
    #[error("unknown option `{0}` (run `shadowlab options` for the list)")]
    UnknownKey(String),
    #[error("option `{key}`: cannot use `{value}`: {reason}")]
    BadValue {
        key: String,
        value: String,
        reason: String,
    },
    #[error("`{0}` is not of the form key=value")]
    NotAssignment(String),
}

/// A type an option can hold: parsed from and written to the strings of `--set key=value`.
pub trait OptionValue: Sized {
    /// How `shadowlab options` describes the type, e.g. `u32` or `nearest|hw2x2|pcf3x3`.
    fn type_name() -> String;
    fn parse_value(text: &str) -> Result<Self, String>;
    fn format_value(&self) -> String;
    /// Bounds check for numbers; other types accept every parsed value.
    fn check_range(&self, _lo: f64, _hi: f64) -> Result<(), String> {
        Ok(())
    }
    /// What an editor needs to show the value (`range`: the declared bounds, if any).
    fn kind(_range: Option<(f64, f64)>) -> OptionKind {
        OptionKind::Text
    }
}

/// The shape of an option's value, for editors (the viewer's panel).
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum OptionKind {
    Bool,
    Choice { choices: Vec<&'static str> },
    Float { min: f64, max: f64 },
    Integer { min: f64, max: f64 },
    Text,
}

macro_rules! numeric_option_value {
    ($($t:ty),*) => {$(
        impl OptionValue for $t {
            fn type_name() -> String {
                stringify!($t).to_string()
            }
            fn parse_value(text: &str) -> Result<Self, String> {
                text.trim().parse::<$t>().map_err(|e| e.to_string())
            }
            fn format_value(&self) -> String {
                self.to_string()
            }
            fn kind(range: Option<(f64, f64)>) -> OptionKind {
                let (min, max) = range.unwrap_or((<$t>::MIN as f64, <$t>::MAX as f64));
                if stringify!($t).starts_with('f') {
                    OptionKind::Float { min, max }
                } else {
                    OptionKind::Integer { min, max }
                }
            }
            fn check_range(&self, lo: f64, hi: f64) -> Result<(), String> {
                let v = *self as f64;
                if v.is_finite() && v >= lo && v <= hi {
                    Ok(())
                } else {
                    Err(format!("must be within {lo}..={hi}"))
                }
            }
        }
    )*};
}
numeric_option_value!(u32, f32);

impl OptionValue for bool {
    fn type_name() -> String {
        "bool".to_string()
    }
    fn parse_value(text: &str) -> Result<Self, String> {
        match text.trim().to_ascii_lowercase().as_str() {
            "true" | "on" | "yes" | "1" => Ok(true),
            "false" | "off" | "no" | "0" => Ok(false),
            other => Err(format!(
                "`{other}` is not one of true|false|on|off|yes|no|1|0"
            )),
        }
    }
    fn format_value(&self) -> String {
        self.to_string()
    }
    fn kind(_range: Option<(f64, f64)>) -> OptionKind {
        OptionKind::Bool
    }
}

impl OptionValue for String {
    fn type_name() -> String {
        "string".to_string()
    }
    fn parse_value(text: &str) -> Result<Self, String> {
        Ok(text.trim().to_string())
    }
    fn format_value(&self) -> String {
        self.clone()
    }
}

/// Declares an enum whose variants are option values, written in snake_case.
#[macro_export]
macro_rules! option_enum {
    (
        $(#[doc = $doc:literal])*
        pub enum $name:ident { $( $(#[doc = $vdoc:literal])* $variant:ident = $text:literal ),+ $(,)? }
    ) => {
        $(#[doc = $doc])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
        pub enum $name { $( $(#[doc = $vdoc])* #[serde(rename = $text)] $variant ),+ }

        impl $name {
            /// Every value, in declaration order (the default first).
            pub const ALL: &'static [$name] = &[$($name::$variant),+];
            pub fn as_str(self) -> &'static str {
                match self { $($name::$variant => $text),+ }
            }
        }

        impl std::fmt::Display for $name {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str(self.as_str())
            }
        }

        impl $crate::options::OptionValue for $name {
            fn type_name() -> String {
                [$($text),+].join("|")
            }
            fn parse_value(text: &str) -> Result<Self, String> {
                let t = text.trim();
                $( if t.eq_ignore_ascii_case($text) { return Ok($name::$variant); } )+
                Err(format!("expected one of {}", Self::type_name()))
            }
            fn format_value(&self) -> String {
                self.as_str().to_string()
            }
            fn kind(_range: Option<(f64, f64)>) -> $crate::options::OptionKind {
                $crate::options::OptionKind::Choice { choices: vec![$($text),+] }
            }
        }
    };
}

/// One row of `shadowlab options`.
#[derive(Debug, Clone, Serialize)]
pub struct OptionSpec {
    pub key: &'static str,
    #[serde(rename = "type")]
    pub type_name: String,
    pub default: String,
    pub meaning: String,
    /// The value's shape, for editors.
    #[serde(flatten)]
    pub kind: OptionKind,
}

fn join_doc(lines: &[&str]) -> String {
    lines
        .iter()
        .map(|l| l.trim())
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join(" ")
}

fn bad_value(key: &str, value: &str, reason: String) -> OptionError {
    OptionError::BadValue {
        key: key.to_string(),
        value: value.to_string(),
        reason,
    }
}

/// Declares the option groups. Each group is a struct (the root group is [`Options`] itself); each
/// field has its doc lines (the first is the one-line meaning), type, default and optional range.
macro_rules! define_options {
    (
        root {
            $( $(#[doc = $rdoc:literal])* $rfield:ident : $rty:ty = $rdefault:expr $(, in $rlo:literal ..= $rhi:literal)? ; )*
        }
        $(
            $(#[doc = $gdoc:literal])*
            group $group:ident : $gty:ident {
                $( $(#[doc = $fdoc:literal])* $field:ident : $fty:ty = $fdefault:expr $(, in $flo:literal ..= $fhi:literal)? ; )*
            }
        )*
    ) => {
        $(
            $(#[doc = $gdoc])*
            #[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
            #[serde(default, deny_unknown_fields)]
            pub struct $gty {
                $( $(#[doc = $fdoc])* pub $field: $fty, )*
            }

            impl Default for $gty {
                fn default() -> Self {
                    Self { $( $field: $fdefault, )* }
                }
            }
        )*

        /// Every pipeline choice (see the module docs for which defaults are the paper's).
        #[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
        #[serde(default, deny_unknown_fields)]
        pub struct Options {
            $( $(#[doc = $rdoc])* pub $rfield: $rty, )*
            $( $(#[doc = $gdoc])* pub $group: $gty, )*
        }

        impl Default for Options {
            fn default() -> Self {
                Self {
                    $( $rfield: $rdefault, )*
                    $( $group: $gty::default(), )*
                }
            }
        }

        impl Options {
            /// Every key with its type, default and meaning, in declaration order.
            pub fn specs() -> Vec<OptionSpec> {
                let defaults = Options::default();
                let mut specs = Vec::new();
                $(
                    specs.push(OptionSpec {
                        key: stringify!($rfield),
                        type_name: <$rty as OptionValue>::type_name()
                            $( + &format!(" ({}..={})", $rlo, $rhi) )?,
                        default: defaults.$rfield.format_value(),
                        meaning: join_doc(&[$($rdoc),*]),
                        kind: <$rty as OptionValue>::kind(
                            None $( .or(Some(($rlo as f64, $rhi as f64))) )?
                        ),
                    });
                )*
                $($(
                    specs.push(OptionSpec {
                        key: concat!(stringify!($group), ".", stringify!($field)),
                        type_name: <$fty as OptionValue>::type_name()
                            $( + &format!(" ({}..={})", $flo, $fhi) )?,
                        default: defaults.$group.$field.format_value(),
                        meaning: join_doc(&[$($fdoc),*]),
                        kind: <$fty as OptionValue>::kind(
                            None $( .or(Some(($flo as f64, $fhi as f64))) )?
                        ),
                    });
                )*)*
                specs
            }

            /// Sets one option from its textual value, checking type and range.
            pub fn set(&mut self, key: &str, value: &str) -> Result<(), OptionError> {
                match key.trim() {
                    $(
                        stringify!($rfield) => {
                            let v = <$rty as OptionValue>::parse_value(value)
                                .map_err(|r| bad_value(key, value, r))?;
                            $( v.check_range($rlo as f64, $rhi as f64).map_err(|r| bad_value(key, value, r))?; )?
                            self.$rfield = v;
                            Ok(())
                        }
                    )*
                    $($(
                        concat!(stringify!($group), ".", stringify!($field)) => {
                            let v = <$fty as OptionValue>::parse_value(value)
                                .map_err(|r| bad_value(key, value, r))?;
                            $( v.check_range($flo as f64, $fhi as f64).map_err(|r| bad_value(key, value, r))?; )?
                            self.$group.$field = v;
                            Ok(())
                        }
                    )*)*
                    other => Err(OptionError::UnknownKey(other.to_string())),
                }
            }

            /// The current value of one option, as `--set` would write it.
            pub fn get(&self, key: &str) -> Result<String, OptionError> {
                match key.trim() {
                    $( stringify!($rfield) => Ok(self.$rfield.format_value()), )*
                    $($( concat!(stringify!($group), ".", stringify!($field)) => Ok(self.$group.$field.format_value()), )*)*
                    other => Err(OptionError::UnknownKey(other.to_string())),
                }
            }
        }
    };
}

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
/// store. Written `shadow_map:id` in `auto_among`; a bare `shadow_map` stores what
/// `shadow_map.buffer` says.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Candidate {
    pub technique: Technique,
    /// Depth for every technique but `shadow_map` (see [`Options::map_buffer`]).
    pub buffer: MapBuffer,
}

impl Candidate {
    /// `technique` with the buffer `options` give it.
    pub fn of(technique: Technique, options: &Options) -> Candidate {
        Candidate {
            technique,
            buffer: options.map_buffer(technique),
        }
    }

    /// One `auto_among` entry: `technique` or `shadow_map:buffer`, resolved under `options`.
    fn parse(text: &str, options: &Options) -> Result<Candidate, String> {
        let (technique, buffer) = match text.split_once(':') {
            Some((t, b)) => (t, Some(b)),
            None => (text, None),
        };
        let technique = Technique::parse_value(technique)?;
        if matches!(technique, Technique::None | Technique::Auto) {
            return Err(format!("`{technique}` is not a shadow technique"));
        }
        match buffer {
            None => Ok(Candidate::of(technique, options)),
            Some(b) if technique == Technique::ShadowMap => Ok(Candidate {
                technique,
                buffer: MapBuffer::parse_value(b)?,
            }),
            Some(_) => Err(format!(
                "`{}`: only shadow_map takes a buffer (shadow_map:id)",
                text.trim()
            )),
        }
    }
}

/// A technique whose maps (if any) store depth.
impl From<Technique> for Candidate {
    fn from(technique: Technique) -> Candidate {
        Candidate {
            technique,
            buffer: MapBuffer::Depth,
        }
    }
}

impl fmt::Display for Candidate {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.buffer {
            MapBuffer::Depth => write!(f, "{}", self.technique),
            b => write!(f, "{}:{b}", self.technique),
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
        /// None: every volume is built on the CPU (the paper's frame).
        None = "none",
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

define_options! {
    root {
        /// Shadow technique for every light. The default, `auto`, shadows every light with
        /// the technique the planner picks for it (see `accuracy`); the paper's frame names one
        /// (`shadow_map` or `shadow_volume`) with `plan.enabled = false` (`--preset paper`).
        technique: Technique = Technique::Auto;
        /// Frame width in pixels (the paper renders 640x480).
        width: u32 = 640, in 16 ..= 16384;
        /// Frame height in pixels.
        height: u32 = 480, in 16 ..= 16384;
        /// GL context path: auto tries egl (desktop GL), then egl_es (OpenGL ES 3.0), then osmesa.
        backend: BackendChoice = BackendChoice::Auto;
        /// For `technique = auto`: the share of a light's receiver pixels, in percent, its
        /// technique may get wrong: measured on sampled pixels where the frames are sampled
        /// (`estimate.*`), else estimated (see `plan::auto`).
        accuracy: f32 = 0.5, in 0.0 ..= 100.0;
        /// The techniques `technique = auto` chooses among, comma separated (any of
        /// shadow_map, psm, tsm, shadow_volume, hybrid, subdivision; the subdivision's first
        /// frame builds it, its cost is the cheapest of its first frames, as for every
        /// technique). `shadow_map:B` is standard maps storing B (depth, id, priority,
        /// priority_depth) whatever `shadow_map.buffer` says, so that `auto` chooses the
        /// buffer too: `shadow_map,shadow_map:id,shadow_volume`. Each one is measured
        /// before a one-frame command's frame, so every addition costs learning frames.
        auto_among: String = "shadow_map,shadow_volume".to_string();
    }

    /// The frame planner (beyond the paper, whose section 4.2 leaves this speed on the table:
    /// it culls no light and no caster). Every decision is conservative (the masks equal those
    /// with the planner off) and has its own switch so that its effect can be measured; the
    /// paper's frame is `plan.enabled = false`.
    group plan: PlanOptions {
        /// Master switch for every decision below.
        enabled: bool = true;
        /// The machine the decisions are weighed for: `software` (a CPU rasteriser: fill is
        /// dear, a read-back cheap), `gpu` (a pipelined GPU: no decision reads the frame
        /// back, so a frame never waits on it) or `auto` (`software` on llvmpipe, softpipe
        /// and OSMesa, else `gpu`). The decisions each profile turns off say so below.
        profile: Profile = Profile::Auto;
        /// Skip lights whose range misses the view frustum or every visible BSP leaf, and give
        /// no shadow work to a light with no caster in range.
        cull_lights: bool = true;
        /// Per light, draw only visible receivers within its range (and, for an omni light's
        /// six spots, within each face's pyramid).
        cull_receivers: bool = true;
        /// Skip casters outside a light's range; outside a map's frustum (shadow maps); whose
        /// shadow cannot reach the view (shadow volumes, after Forsyth).
        cull_casters: bool = true;
        /// Scissor each light's stencil and lit passes to its range's screen rectangle.
        scissor: bool = true;
        /// Scissor each shadow-volume piece's stencil draw to the screen rectangle of the
        /// receiver boxes its shadow can reach (needs `cull_casters`, which finds them): a
        /// closed piece changes no count outside the receivers it shadows.
        piece_scissor: bool = true;
        /// End each shadow-volume piece just past the receivers its shadow can reach (a far
        /// cap, drawn under depth-pass too) instead of at infinity (needs `cull_casters`):
        /// the volume's fragments behind those receivers are never rasterised. Only under
        /// `shadow_volume.extrusion = infinite`: a finite extrusion is left as set.
        truncate_volumes: bool = true;
        /// Read the depth buffer back after the base pass and leave out of the shadow-volume
        /// work every receiver whose box it hides wholly (a max-depth pyramid, as a GPU's
        /// hierarchical Z): casters that shadow only hidden receivers drop out. Off under
        /// `profile = gpu`: the read-back would stall the GPU's pipeline mid-frame.
        occlusion: bool = true;
        /// Read that depth back as the farthest depth of each 4×4 block, reduced by a shader
        /// (level 2 of the pyramid: the CPU converts and copies a sixteenth of the pixels),
        /// instead of every pixel. Bounds on rectangles and boxes under about 16 pixels come
        /// out a few pixels wider; every decision stays conservative.
        reduce_depth: bool = true;
        /// Clip each depth-pass shadow-volume part's stencil draw (gl_ClipDistance) behind the
        /// depth buffer within its rectangle (read after the base pass): fragments there would
        /// fail the depth test, so they are not rasterised. A depth bounds test applied to the
        /// volume. Depth-fail parts are left whole: the mirror clip (nothing nearer than the
        /// nearest stored depth) is as exact in theory but broke counts on llvmpipe. Off under
        /// `profile = gpu` (it reads the depth back, as `occlusion` does).
        depth_clip: bool = true;
        /// Clip planes per part for `depth_clip`, chosen greedily among the farthest depth in
        /// the rectangle and tilted planes fitted to the depth of the whole, its halves,
        /// quarters and ninths, each lifted above every pixel; the draw keeps what lies under
        /// all of them (see `plan::depth_bounds`).
        depth_clip_planes: u32 = 4, in 1 ..= 4;
        /// Restrict each shadow-volume part's stencil draw with `EXT_depth_bounds_test`
        /// (glDepthBoundsEXT) to the window-depth range of the receivers its shadow reaches:
        /// the test reads the depth already stored at the pixel, and a surface outside that
        /// range is outside the part's volume (its counts cancel) or out of the light's range.
        /// It replaces `depth_clip` (the emulation) for every part. Where the GL lacks the
        /// extension, or `gl.disable=depth_bounds`, the fallback sets this false and the
        /// frame lists it.
        depth_bounds_test: bool = true;
        /// Keep the fitted clip planes for the next frame and use them while its depth buffer
        /// (as read back for the planner) is the same: a fit reads nothing else but its
        /// rectangle. A still camera over a still scene then fits nothing.
        reuse_depth_fits: bool = true;
        /// Take the depth the planner reads (`occlusion`, `depth_clip`) from the last frame,
        /// without reading it back, while everything the base pass draws it from is the same:
        /// the camera, the surfaces in view, the models' transforms and the frame's depth
        /// format. The readback waits for the GL to finish the base pass (on llvmpipe the
        /// frame's one stall); a still camera over a still scene then has none.
        reuse_depth: bool = true;
        /// Keep each light's shadow-volume draws (parts, rectangles, clip planes, index lists)
        /// and draw them again while nothing they are made from changed: the light's plan,
        /// the camera, the depth read back, the volume options, the light and the casters'
        /// transforms. A still camera over a still scene then redoes none of the piece work.
        reuse_volume_draws: bool = true;
        /// Leave out of each depth-clipped part's stencil draw the triangles one of its clip
        /// planes rejects wholly (tested on the CPU, a block of triangles at a time where its
        /// box decides, the rest drawn through an index list): the GL would clip them away,
        /// but llvmpipe transforms and assembles them first, on the thread that issues the
        /// draws. The same fragments either way.
        cull_clipped: bool = true;
        /// Draw neighbouring shadow-volume chunks of one caster (the halves of the cuts
        /// `cull_casters` culls by) as one piece where a light keeps both with the same
        /// counting and their rectangles overlap: the sides each chunk extrudes along the
        /// cut, which cancel, are not rasterised (see `plan::merge`).
        merge_pieces: bool = true;
        /// Under `shadow_volume.counting = zfail`, count depth-pass, without caps, each caster
        /// piece whose shadow cannot hold the camera (Doom 3's test) and that is not
        /// alpha-tested, depth-fail the others (as `counting = auto`; `zpass` stays `zpass`).
        counting: bool = true;
        /// With `counting`: pieces of open surfaces (an edge with one triangle) stay
        /// depth-fail, as in the paper's frame: depth-pass on them changed masks on open maps.
        open_depth_fail: bool = true;
        /// Refine that test (and `counting = auto`'s): a piece counts depth-fail only if one
        /// of its facing triangles meets the hull of the light and the camera's near-plane
        /// rectangle, not whenever its box, grown by the near distance, holds the light or the
        /// eye or meets the segment between them.
        near_plane_test: bool = true;
        /// With that test, split a piece it sends to depth-fail: only the facing triangles
        /// whose shadow may hold part of the near-plane rectangle count depth-fail (with
        /// caps), the rest of the piece depth-pass, each part closed along the cut. Most of a
        /// depth-fail piece's fragments lie behind the visible surface, where its entering and
        /// leaving faces cancel; as depth-pass, the depth clip drops them.
        split_counting: bool = true;
        /// Count each light's volumes in one pass with glStencilOpSeparate and wrapping
        /// operations (GL 2.0 core), instead of `shadow_volume.stencil`'s two culled passes:
        /// each volume is transformed, clipped and set up once instead of twice. The same
        /// counts, modulo 256 rather than saturating at 0 and 255.
        one_pass_stencil: bool = true;
        /// Reuse a shadow map while its light, view and casters stay as they were.
        cache_maps: bool = true;
        /// `shadow_map.omni = frusta`: a static omni light keeps its frusta (and so its maps)
        /// while the receivers in view stay within them, choosing again one frame in 16 at a
        /// phase of its own (Forsyth's persistent frusta); off: chosen every frame. Changes
        /// pixels: kept frusta are sized for an earlier frame's view.
        keep_frusta: bool = true;
        /// Light an omni light's six spot maps in one pass, each fragment reading its face's
        /// map (the paper draws six passes; not with `shadow_map.outside = clip_planes`).
        merge_faces: bool = true;
        /// Shadow-map an omni light with one cube map (`shadow_map.omni = cube`: one lookup,
        /// one interpolated direction) instead of the paper's six spot maps, where both cover
        /// the same directions (`fov_scale = 1`, not `outside = clip_planes`). Changes pixels:
        /// each face's depth range is the cube's, not its own.
        omni_cube: bool = true;
        /// Shadow-map a spot light whose cone one frustum cannot cover (cutoff near or past
        /// 90°: the paper's single map is capped at 179°) with an omni light's views (six
        /// spots or a cube, as `shadow_map.omni` and `omni_cube` say); the lit pass's cone
        /// test still bounds its light. Off (and in the paper's frame) one frustum is used,
        /// and points behind the light's plane read as shadowed (ARB_shadow's q <= 0 rule).
        wide_spot_omni: bool = true;
    }

    /// The sampled reference (`truth::sampled`): each frame, per light, a few receiver pixels
    /// traced exactly and compared with the technique's decision there. It needs the frame's
    /// G-buffer and masks, drawn after the timed frame. Read by `bench` (the per-frame error
    /// along a path), `render --stats`, the viewer's overlay and `auto`'s measured choice.
    group estimate: EstimateOptions {
        /// Receiver pixels traced per light and frame (0: none). With 512, a light's 95%
        /// interval is about ±2.6 points at 10% error and under 0.75% when nothing is wrong.
        samples: u32 = 512, in 0 ..= 1048576;
        /// Seed of the sample positions: the same seed, frame and light draw the same pixels.
        seed: u32 = 1;
        /// Frames pooled into a light's running estimate (the viewer's overlay, `auto`).
        window: u32 = 8, in 1 ..= 4096;
        /// Share of frame time the viewer's live error may spend drawing masks and tracing
        /// samples: it samples a frame whenever its spending so far is under this share of
        /// the frames' time (every frame where masks are cheap; on llvmpipe, where a frame's
        /// masks cost about as much as the frame, one frame in ten or so).
        budget: f32 = 0.1, in 0.0 ..= 10.0;
        /// `auto` leaves a light's measured technique for another that meets `accuracy` only
        /// when that one is cheaper by more than this share of the current one's time, so that
        /// noise in the pass times does not flip it back and forth.
        hysteresis: f32 = 0.25, in 0.0 ..= 1.0;
    }

    /// Lights and the unshadowed lighting model.
    group lighting: LightingOptions {
        /// Draw the per-light additive passes at all (off = only the unlit world).
        lights: bool = true;
        /// Add each light to a pixel once: the lit pass marks the stencil where it adds and
        /// passes only where no mark is. Quake 3 maps have planar surfaces whose own triangles
        /// overlap (48 of the 58 OpenArena maps, `shadowlab inspect`'s
        /// `overlapping_surfaces`); without marks the light is added twice there, in bands with
        /// z-fighting edges (the paper's additive passes do that).
        light_once: bool = true;
        /// Comma-separated light indices to draw, or `all`.
        only: String = "all".to_string();
        /// Per-light technique overrides, `index:technique` pairs separated by commas (e.g.
        /// `0:shadow_volume,2:shadow_map`); other lights use `technique` (thesis 7: pick the
        /// algorithm per case).
        techniques: String = String::new();
        /// Brightness of the unlit pass where a surface has no lightmap (built-in scene, paper 2.4).
        ambient: f32 = 0.2, in 0.0 ..= 4.0;
        /// Use maps' lightmaps and vertex light in the unlit pass; off draws every surface at the
        /// constant ambient level (a debug view for dark maps).
        baked: bool = true;
        /// Constant light level of MD3 models in the unlit pass (paper 2.5: "constant, moderate").
        model_ambient: f32 = 0.5, in 0.0 ..= 4.0;
        /// Multiplier on every dynamic light's colour.
        intensity: f32 = 1.0, in 0.0 ..= 16.0;
    }

    /// Surface culling of the base renderer (paper 2.2: the PVS and frustum tests are its only
    /// culling).
    group culling: CullingOptions {
        /// Skip BSP leaves outside the camera cluster's potentially visible set.
        pvs: bool = true;
        /// Skip BSP nodes and leaves whose boxes miss the view frustum.
        frustum: bool = true;
    }

    /// Shadow mapping (paper section 3, thesis chapter 2). Defaults: the paper's pipeline.
    group shadow_map: ShadowMapOptions {
        /// Copy the depth buffer into the texture (paper) or render to it through an FBO.
        depth_source: DepthSource = DepthSource::Copy;
        /// Side of each square depth texture in texels (the paper found 512 sharp enough).
        size: u32 = 512, in 16 ..= 8192;
        /// Depth texture precision: 24-bit (paper), 16-bit or 32-bit float.
        depth_bits: DepthBits = DepthBits::D24;
        /// Hardware compare (sampler2DShadow, LEQUAL) or a compare in the shader.
        compare: Compare = Compare::Hardware;
        /// Compare result in alpha, then the alpha test (paper), or intensity (thesis 2.2.6).
        result: CompareResult = CompareResult::Alpha;
        /// glAlphaFunc's function for the alpha result (Paul's Projects, the paper's [5]: GEQUAL).
        alpha_func: AlphaTestFunc = AlphaTestFunc::Gequal;
        /// glAlphaFunc's reference value (Paul's Projects: 0.99).
        alpha_ref: f32 = 0.99, in 0.0 ..= 1.0;
        /// Compare filtering: nearest (paper), hw2x2 (LINEAR), pcf3x3 (paper 3.1), pcf (N x N).
        filter: Filter = Filter::Nearest;
        /// N of the N x N percentage-closer filter (filter = pcf).
        pcf_size: u32 = 5, in 2 ..= 15;
        /// Apply glPolygonOffset at all.
        offset: bool = true;
        /// glPolygonOffset factor (thesis 2.2.8: 1.1, after Kilgard). Raised to 10 for warped
        /// maps and frusta where the GL adds the offset per vertex (`offset_per_fragment`
        /// missing in `info`: softpipe), and the frame lists the fallback.
        offset_factor: f32 = 1.1, in 0.0 ..= 1000.0;
        /// glPolygonOffset units (thesis 2.2.8: 4).
        offset_units: f32 = 4.0, in 0.0 ..= 100000.0;
        /// Growth per subsequent light: light k uses the offset times (1 + growth k). The paper
        /// (3.1) grows it by 1; the default 0 keeps every light's offset the same, since each
        /// light has its own map and nothing accumulates: with 161 lights the paper's growth
        /// gives light 84 85 times the offset and erases its contact shadows (docs/checks.md).
        offset_growth: f32 = 0.0, in 0.0 ..= 100.0;
        /// Which pass the offset applies to: the shadow map (thesis), the lit pass (paper), both.
        offset_pass: OffsetPass = OffsetPass::ShadowMap;
        /// Points outside a map's frustum: clamp to the edge (the artifact), range test, or
        /// clip planes.
        outside: Outside = Outside::Clamp;
        /// Shadow frustum field of view relative to what it must cover (2 x cutoff for spots, 90
        /// degrees per cube face); below 1 it leaves part of the light outside the map.
        fov_scale: f32 = 1.0, in 0.1 ..= 2.0;
        /// Caster faces drawn into the map: front (toward the light, the paper), back (thesis
        /// 2.2.8), or both (the default: Quake 3 worlds are open, and a one-sided face seen
        /// from behind casts too; `shadowlab check --all`, docs/checks.md).
        cull: CasterFaces = CasterFaces::Both;
        /// Fit near and far to the casters in the light's view (thesis 2.2.2); off: near 1, far =
        /// the light's radius.
        fit_near_far: bool = true;
        /// Omni lights as six 90-degree spot lights (paper), one cube map, or several frusta
        /// fitted to the receivers in view.
        omni: OmniMode = OmniMode::SixSpots;
        /// `omni = frusta`: the most frusta per light (each is one more depth and lit pass);
        /// a light has at least one per face with receivers.
        max_frusta: u32 = 12, in 6 ..= 64;
        /// Alpha-tested casters: alpha test in the depth pass, or drawn solid.
        alpha_casters: AlphaCasters = AlphaCasters::Test;
        /// What the map stores: depth (the paper), IDs, priorities, or priorities with depth
        /// (Forsyth's ID and priority buffers).
        buffer: MapBuffer = MapBuffer::Depth;
        /// What an ID or priority stands for: a surface, a convex part, or a triangle.
        id_unit: IdUnit = IdUnit::Part;
        /// Bits of an ID buffer's IDs: IDs are stored modulo 2^bits, as an 8-bit colour
        /// channel would keep them (per-triangle IDs collide below 24).
        id_bits: u32 = 32, in 8 ..= 32;
        /// ID buffers: lit where the fragment's ID is stored at its texel or at any of the
        /// eight around it (Forsyth's cure for edge acne; shrinks shadows by about a texel).
        id_edge_filter: bool = false;
        /// Priority buffers (`buffer = priority`): a mip chain, each texel the upper median of
        /// the four below it, read at the level of the fragment's footprint, so that a map
        /// finer than the screen decides by about half the texels a pixel covers, not by one
        /// (Forsyth: priorities "can be filtered and mipmapped"; docs/id-buffers.md).
        priority_mipmap: bool = false;
        /// Hybrid priority and depth: the bias, as a share of each unit's own depth range.
        priority_bias: f32 = 0.02, in 0.0 ..= 1.0;
        /// Where the texgen planes apply: eye coordinates as glTexGen does (the paper);
        /// positions relative to the light with the planes composed in double precision, per
        /// vertex (`light`) or per fragment (`fragment`, the default: it holds on every
        /// rasteriser measured).
        texgen: TexgenSpace = TexgenSpace::Fragment;
    }

    /// Warped shadow maps: perspective (`technique = psm`, thesis chapter 4) and trapezoidal
    /// (`technique = tsm`). Each view of the light (a spot's frustum, each of an omni light's
    /// six faces) is warped on its own; the rest of `shadow_map.*` applies as to a standard map.
    group psm: PsmOptions {
        /// Fit the warped map to the receivers in view and the casters that can shadow them
        /// (the thesis's cube clipping); off, to the whole view frustum within the light's
        /// range and view.
        fit: bool = true;
        /// Move the virtual camera back until every caster that can shadow the view lies in
        /// front of it (Stamminger & Drettakis: a caster behind the camera would be projected
        /// through infinity); off, such casters are left out of the map.
        slide_back: bool = true;
        /// A light behind the virtual camera lands beyond the infinity plane in
        /// post-perspective space, where the order of depths along its rays inverts: draw it
        /// with the depth range reversed (Kozlov's inversion). Off, such a light falls back.
        invert: bool = true;
        /// Near plane of the virtual camera as a share of its far plane, at least: the warp's
        /// strength (smaller is stronger: more texels near the camera, fewer far away).
        min_near: f32 = 0.05, in 0.0001 ..= 1.0;
        /// Widest field of view, in degrees, of the light's frustum in post-perspective space;
        /// a light that needs a wider one (it sees the view from inside it) falls back.
        max_fov: f32 = 150.0, in 10.0 ..= 179.0;
        /// Forsyth's duelling frusta: the light shines toward the camera when the angle between
        /// the view direction and the light's direction to the view exceeds this (degrees);
        /// the warp then gives the near field nothing, and the light falls back.
        duel_angle: f32 = 135.0, in 90.0 ..= 180.0;
        /// Trapezoidal maps: the share of the view's depth range (from its near end) that
        /// Martin & Tan's 80% rule maps onto the first 80% of the map's height.
        tsm_focus: f32 = 0.5, in 0.05 ..= 0.95;
    }

    /// Chan & Durand's hybrid (`technique = hybrid`): the shadow map's compares decide where
    /// they agree; elsewhere (the silhouette pixels) the stencil volumes decide.
    group hybrid: HybridOptions {
        /// Texels around the fragment's map position whose compares must agree for the map to
        /// decide: 1 is the paper's 2×2 bilinear footprint; 2 looks at 4×4 (more silhouette
        /// pixels, fewer map errors left).
        radius: u32 = 1, in 1 ..= 4;
        /// Keep the volumes' rasterisation to silhouette pixels with the stencil's top bit (the
        /// computation mask, tested before the count); off, the volumes are counted everywhere
        /// and only the final shading takes the map's decision elsewhere.
        mask: bool = true;
    }

    /// Stenciled shadow volumes (paper section 4, thesis chapter 3). Defaults: the paper's pipeline.
    group shadow_volume: ShadowVolumeOptions {
        /// Stencil counting: zfail (paper), zpass (no caps), or auto per caster.
        counting: CountingMode = CountingMode::Zfail;
        /// Two stencil passes (paper) or one pass with separate front and back operations.
        stencil: StencilPasses = StencilPasses::TwoPass;
        /// Saturating INCR/DECR (the paper's card) or INCR_WRAP/DECR_WRAP (two-pass only: one
        /// pass always wraps).
        wrap: StencilWrap = StencilWrap::Saturate;
        /// Which edges become sides: the paper's world rule, every edge, or the naive manifold rule.
        edge_rule: EdgeRule = EdgeRule::Paper;
        /// Which triangles cast: those facing the light (the paper) or every one (the
        /// default: open worlds lose shadows otherwise; docs/checks.md).
        casters: VolumeCasters = VolumeCasters::Both;
        /// Extrude to infinity (w = 0, paper) or by a finite distance.
        extrusion: Extrusion = Extrusion::Infinite;
        /// Distance of finite extrusion, in world units.
        finite_distance: f32 = 1000.0, in 1.0 ..= 1000000.0;
        /// Camera projection: infinite far plane (paper), Doom 3's epsilon form, or depth clamp.
        projection: VolumeProjection = VolumeProjection::Infinite;
        /// Draw volumes with glPolygonOffset(0, 1) away from the camera (Doom 3).
        depth_offset: bool = false;
        /// Forsyth's fix for chopped Gouraud shading: a triangle faces the light when N.L > -eps
        /// (with `casters = front`; two-sided casting casts every triangle either way).
        facing_epsilon: f32 = 0.0, in 0.0 ..= 1.0;
        /// Additive lit pass where stencil = 0 (paper) or Bestimt and Freitag's fill quad.
        shading: VolumeShading = VolumeShading::Additive;
        /// Rebuild a light's volumes only when the light or a caster moved.
        caching: bool = true;
        /// Whose volumes the GPU extrudes (with infinite extrusion and the shader pipeline;
        /// elsewhere the CPU builds them all). Those volumes are whole caster groups, counted
        /// depth-fail, without the planner's per-piece culling, truncation, scissors or depth
        /// clips. Default none: on llvmpipe, where the vertex shader runs on the CPU too, the
        /// CPU's culled, cached pieces were faster for models and the world alike along every
        /// flythrough measured (docs/motion.md).
        gpu_extrusion: GpuExtrusion = GpuExtrusion::None;
    }

    /// Vector's light-volume subdivision (`technique = subdivision`).
    group subdivision: SubdivisionOptions {
        /// Who casts the models' shadows and the world's shadows on models. `volumes`: the
        /// world alone is subdivided, and models (which move) get shadow volumes counted into
        /// the same stencil, with the world's pieces whose shadow reaches a model, so a
        /// moving model costs volumes, not a new subdivision. `subdivided`: models are cut
        /// with the world (Vector's method as written; a light is subdivided again whenever a
        /// model in its range moves).
        models: ModelShadows = ModelShadows::Volumes;
    }

    /// The GL the frame runs on.
    group gl: GlOptions {
        /// `shaders`, or `fixed_function`: the paper's passes with the legacy calls themselves
        /// (needs a compatibility-profile context, which EGL and OSMesa on Mesa offer).
        pipeline: Pipeline = Pipeline::Shaders;
        /// Features the capability probe reports missing although the GL has them, comma
        /// separated (`render_to_depth_texture`, `float_depth`, `clip_distances`,
        /// `depth_clamp`, `separate_stencil`, `stencil_wrap`, `timer_query`; `shadowlab info`
        /// lists them), so that each fallback can be run anywhere.
        disable: String = String::new();
    }

    /// Loading Quake 3 maps and models (applied when a scene is loaded).
    group q3: Q3Options {
        /// Quads per side of each 3x3 Bezier patch segment, tessellated once at load (paper 2.3).
        patch_level: u32 = 8, in 1 ..= 64;
        /// Also load the movable brush models (doors, lifts); the paper renders world model 0 only.
        brush_models: bool = false;
        /// Quake 3's r_overBrightBits: the unlit pass multiplies lightmaps by 2^bits.
        overbright_bits: u32 = 1, in 0 ..= 2;
        /// Quake 3's r_mapOverBrightBits: lightmaps are brightened by 2^(map bits - bits) at load.
        map_overbright_bits: u32 = 2, in 0 ..= 4;
        /// Show a progress bar while textures load (on a terminal only).
        progress: bool = true;
    }
}

impl Options {
    /// Applies `key=value`.
    pub fn set_assignment(&mut self, assignment: &str) -> Result<(), OptionError> {
        let (key, value) = assignment
            .split_once('=')
            .ok_or_else(|| OptionError::NotAssignment(assignment.to_string()))?;
        self.set(key, value)
    }

    /// Every key with its current value.
    pub fn to_map(&self) -> BTreeMap<String, String> {
        Self::specs()
            .into_iter()
            .map(|s| {
                let v = self.get(s.key).expect("every spec key is gettable");
                (s.key.to_string(), v)
            })
            .collect()
    }

    /// Applies a TOML table of overrides (a scene file's `[options]`): either dotted keys
    /// (`"shadow_map.size" = 1024`) or nested tables (`[options.shadow_map] size = 1024`).
    pub fn apply_toml(&mut self, table: &toml::Table) -> Result<(), OptionError> {
        fn walk(opts: &mut Options, prefix: &str, table: &toml::Table) -> Result<(), OptionError> {
            for (k, v) in table {
                let key = if prefix.is_empty() {
                    k.clone()
                } else {
                    format!("{prefix}.{k}")
                };
                match v {
                    toml::Value::Table(t) => walk(opts, &key, t)?,
                    toml::Value::String(s) => opts.set(&key, s)?,
                    toml::Value::Integer(i) => opts.set(&key, &i.to_string())?,
                    toml::Value::Float(f) => opts.set(&key, &f.to_string())?,
                    toml::Value::Boolean(b) => opts.set(&key, &b.to_string())?,
                    other => {
                        return Err(bad_value(
                            &key,
                            &other.to_string(),
                            "expected a string, number or bool".into(),
                        ));
                    }
                }
            }
            Ok(())
        }
        walk(self, "", table)
    }

    /// Which lights the `lighting.only` filter admits, for a scene with `count` lights.
    pub fn light_enabled(&self, index: usize) -> bool {
        if !self.lighting.lights {
            return false;
        }
        let only = self.lighting.only.trim();
        if only.is_empty() || only.eq_ignore_ascii_case("all") {
            return true;
        }
        only.split(',')
            .filter_map(|s| s.trim().parse::<usize>().ok())
            .any(|i| i == index)
    }

    /// The `lighting.techniques` overrides, in order.
    fn technique_overrides(&self) -> Result<Vec<(usize, Technique)>, OptionError> {
        let text = self.lighting.techniques.trim();
        if text.is_empty() {
            return Ok(Vec::new());
        }
        let bad = |reason: String| bad_value("lighting.techniques", text, reason);
        text.split(',')
            .map(|pair| {
                let (index, technique) = pair
                    .split_once(':')
                    .ok_or_else(|| bad(format!("`{pair}` is not index:technique")))?;
                let index = index
                    .trim()
                    .parse::<usize>()
                    .map_err(|e| bad(format!("`{index}`: {e}")))?;
                let technique = Technique::parse_value(technique).map_err(bad)?;
                Ok((index, technique))
            })
            .collect()
    }

    /// What `auto` chooses among (`auto_among`); the default pair if it does not parse
    /// (`validate` reports that).
    pub fn auto_choices(&self) -> Vec<Candidate> {
        self.parse_auto_among().unwrap_or_else(|_| {
            [Technique::ShadowMap, Technique::ShadowVolume]
                .map(|t| Candidate::of(t, self))
                .to_vec()
        })
    }

    /// `auto_among` with every map buffer but depth replaced by depth (`shadow_map:depth`),
    /// for a context that cannot draw them.
    pub fn auto_among_depth_only(&self) -> String {
        let mut out: Vec<String> = Vec::new();
        for part in self.auto_among.split(',') {
            let part = part.trim();
            let entry = match Candidate::parse(part, self) {
                Ok(c) if c.technique == Technique::ShadowMap && part.contains(':') => {
                    "shadow_map:depth".to_string()
                }
                _ => part.to_string(),
            };
            if !out.contains(&entry) {
                out.push(entry);
            }
        }
        out.join(",")
    }

    fn parse_auto_among(&self) -> Result<Vec<Candidate>, OptionError> {
        let text = self.auto_among.trim();
        let bad = |reason: String| bad_value("auto_among", text, reason);
        let mut out = Vec::new();
        for part in text.split(',') {
            let c = Candidate::parse(part, self).map_err(bad)?;
            if !out.contains(&c) {
                out.push(c);
            }
        }
        Ok(out)
    }

    /// The technique light `index` uses: its override, else `technique`.
    pub fn technique_for(&self, index: usize) -> Technique {
        self.technique_overrides()
            .unwrap_or_default()
            .iter()
            .rev()
            .find(|(i, _)| *i == index)
            .map_or(self.technique, |(_, t)| *t)
    }

    /// Sets (or with `None` removes) light `index`'s technique override.
    pub fn set_technique_for(&mut self, index: usize, technique: Option<Technique>) {
        let mut pairs: Vec<(usize, Technique)> = self
            .technique_overrides()
            .unwrap_or_default()
            .into_iter()
            .filter(|(i, _)| *i != index)
            .collect();
        if let Some(t) = technique {
            pairs.push((index, t));
        }
        pairs.sort_by_key(|(i, _)| *i);
        self.lighting.techniques = pairs
            .iter()
            .map(|(i, t)| format!("{i}:{t}"))
            .collect::<Vec<_>>()
            .join(",");
    }

    /// Every technique some light of a scene with `lights` lights uses.
    pub fn uses(&self, lights: usize, technique: Technique) -> bool {
        (0..lights).any(|i| self.light_enabled(i) && self.technique_for(i) == technique)
    }

    /// Whether some enabled light of `lights` runs a technique for which `test` holds.
    pub fn uses_where(&self, lights: usize, test: impl Fn(Technique) -> bool) -> bool {
        (0..lights).any(|i| self.light_enabled(i) && test(self.technique_for(i)))
    }

    /// Validates cross-field rules that a single `set` cannot see.
    pub fn validate(&self) -> Result<(), OptionError> {
        self.technique_overrides()?;
        self.parse_auto_among()?;
        let only = self.lighting.only.trim();
        if !(only.is_empty() || only.eq_ignore_ascii_case("all")) {
            for part in only.split(',') {
                if part.trim().parse::<usize>().is_err() {
                    return Err(bad_value(
                        "lighting.only",
                        only,
                        "expected `all` or comma-separated light indices".into(),
                    ));
                }
            }
        }
        Ok(())
    }
}

impl fmt::Display for Options {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (k, v) in self.to_map() {
            writeln!(f, "{k} = {v}")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_the_papers_frame_size_and_show_shadows() {
        let o = Options::default();
        assert_eq!((o.width, o.height), (640, 480));
        // `render` and `view` shadow every light without options.
        assert_eq!(o.technique, Technique::Auto);
    }

    #[test]
    fn auto_among_takes_a_map_buffer_for_standard_maps_only() {
        let mut o = Options {
            auto_among: "shadow_map, shadow_map:id,shadow_volume".into(),
            ..Options::default()
        };
        let names: Vec<String> = o.auto_choices().iter().map(|c| c.to_string()).collect();
        assert_eq!(names, ["shadow_map", "shadow_map:id", "shadow_volume"]);
        // A bare `shadow_map` stores what `shadow_map.buffer` says: here the same as `:id`.
        o.shadow_map.buffer = MapBuffer::Id;
        assert_eq!(o.auto_choices().len(), 2);
        for bad in [
            "shadow_volume:id",
            "shadow_map:nonsense",
            "auto",
            "shadow_map:",
        ] {
            let b = Options {
                auto_among: bad.into(),
                ..Options::default()
            };
            assert!(b.validate().is_err(), "{bad}");
        }
        // Where the context draws no ID buffers, they become depth maps.
        o.auto_among = "shadow_map:priority,shadow_map:id,shadow_volume".into();
        assert_eq!(o.auto_among_depth_only(), "shadow_map:depth,shadow_volume");
    }

    #[test]
    fn set_and_get_round_trip_for_every_key() {
        let defaults = Options::default();
        for spec in Options::specs() {
            let mut o = Options::default();
            o.set(spec.key, &spec.default).unwrap();
            assert_eq!(o, defaults, "{}", spec.key);
            assert_eq!(o.get(spec.key).unwrap(), spec.default);
            assert!(!spec.meaning.is_empty(), "{} has no meaning", spec.key);
        }
    }

    #[test]
    fn per_light_techniques_override_the_global_one() {
        let mut o = Options::default();
        o.set("technique", "shadow_map").unwrap();
        o.set("lighting.techniques", "1:shadow_volume, 3:none")
            .unwrap();
        o.validate().unwrap();
        assert_eq!(o.technique_for(0), Technique::ShadowMap);
        assert_eq!(o.technique_for(1), Technique::ShadowVolume);
        assert_eq!(o.technique_for(3), Technique::None);
        assert!(o.uses(2, Technique::ShadowVolume) && !o.uses(1, Technique::ShadowVolume));
        o.set_technique_for(1, None);
        o.set_technique_for(0, Some(Technique::ShadowVolume));
        assert_eq!(o.lighting.techniques, "0:shadow_volume,3:none");
        for bad in ["1", "x:shadow_map", "1:nope"] {
            o.set("lighting.techniques", bad).unwrap();
            assert!(o.validate().is_err(), "{bad}");
        }
    }

    #[test]
    fn specs_describe_their_values_for_editors() {
        let specs = Options::specs();
        let kind = |k: &str| specs.iter().find(|s| s.key == k).unwrap().kind.clone();
        assert_eq!(kind("culling.pvs"), OptionKind::Bool);
        assert_eq!(
            kind("technique"),
            OptionKind::Choice {
                choices: vec![
                    "none",
                    "shadow_map",
                    "shadow_volume",
                    "auto",
                    "psm",
                    "tsm",
                    "hybrid",
                    "subdivision"
                ]
            }
        );
        assert_eq!(
            kind("shadow_map.size"),
            OptionKind::Integer {
                min: 16.0,
                max: 8192.0
            }
        );
        assert!(matches!(kind("lighting.ambient"), OptionKind::Float { max, .. } if max == 4.0));
        assert_eq!(kind("lighting.only"), OptionKind::Text);
    }

    #[test]
    fn bad_values_are_rejected_with_the_key() {
        let mut o = Options::default();
        assert!(matches!(
            o.set("nope", "1"),
            Err(OptionError::UnknownKey(_))
        ));
        assert!(matches!(
            o.set("width", "abc"),
            Err(OptionError::BadValue { .. })
        ));
        assert!(matches!(
            o.set("width", "0"),
            Err(OptionError::BadValue { .. })
        ));
        assert!(matches!(
            o.set("backend", "vulkan"),
            Err(OptionError::BadValue { .. })
        ));
        assert!(matches!(
            o.set("lighting.ambient", "NaN"),
            Err(OptionError::BadValue { .. })
        ));
        o.set("backend", "OSMesa").unwrap();
        assert_eq!(o.backend, BackendChoice::Osmesa);
    }

    #[test]
    fn toml_overrides_accept_dotted_and_nested_keys() {
        let mut o = Options::default();
        let t: toml::Table =
            toml::from_str("width = 320\n\"lighting.ambient\" = 0.5\n[lighting]\nlights = false\n")
                .unwrap();
        o.apply_toml(&t).unwrap();
        assert_eq!(o.width, 320);
        assert_eq!(o.lighting.ambient, 0.5);
        assert!(!o.lighting.lights);
    }

    #[test]
    fn light_filter() {
        let mut o = Options::default();
        assert!(o.light_enabled(3));
        o.set("lighting.only", "0, 2").unwrap();
        assert!(o.light_enabled(0) && !o.light_enabled(1) && o.light_enabled(2));
        o.set("lighting.only", "x").unwrap();
        assert!(o.validate().is_err());
    }
}
