//! The option table: `define_options!`, which generates `Options`, its groups, defaults, setters,
//! getters and listing, and its one invocation with every key.

use super::choices::*;
use super::value::{OptionError, OptionKind, OptionValue, bad_value};
use serde::{Deserialize, Serialize};

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
        /// buffer too: `shadow_map,shadow_map:id,shadow_volume`. `shadow_map@N` is standard
        /// maps of N texels a side whatever `shadow_map.size` says, so that each light gets
        /// the size it needs: `shadow_map@256,shadow_map@2048,shadow_volume` (both forms
        /// together: `shadow_map:id@1024`). Each one is measured before a one-frame command's
        /// frame, so every addition costs learning frames.
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
        /// Skip lights whose range misses the view frustum or every receiver in view, and give
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
        /// Build a still light's shadow-volume pieces of still casters (the world, models as
        /// they were last frame) against every receiver in its range, not only those in view,
        /// with both caps, and keep them while out of view (`shadow_volume.kept_mb`): neither
        /// the camera nor the counting rebuilds them; a moving model counts as the box its
        /// motion keeps it in. Off: built against the receivers in view, as the camera moves.
        keep_volumes: bool = true;
        /// With `keep_volumes`, build each still shadow-volume light's kept pieces for its
        /// whole range before the first frame (`Renderer::prepare`, which `bench` and the
        /// viewer call after loading a scene), nearest lights to the camera first, until
        /// `shadow_volume.kept_mb` is reached, and upload them: the first sight of a room then
        /// builds nothing. Off: each piece is built the first time a frame draws it.
        build_ahead: bool = true;
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
        /// algorithm per case). A shadow-map entry may name its buffer and size as `auto_among`
        /// does (`3:shadow_map@2048`, `4:shadow_map:id`): each light its own map.
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
        /// Memory for shadow maps, in MiB (depth, static and ID textures together). A frame
        /// whose maps fit draws every light's maps first, as the paper does, and keeps them
        /// for later frames while they fit; one whose maps would hold more draws each light's
        /// maps just before its own pass, into textures the lights share, so memory stays
        /// within this whatever the lights and sizes (on oa_dm3, 51 omni lights of
        /// 2048-texel cubes would hold 5 GB); the maps that fit are kept for the next frame
        /// (the one needed again furthest ahead is given up first), so a still camera draws
        /// again only those that did not fit. A paper's frame (`plan.enabled = false`) keeps
        /// no map for a later frame: drawing per light, it holds one light's maps at a time,
        /// and where its lights also hold volume buffers (hybrid) it draws per light whenever
        /// a budget is set (no draw more). The planner's frames of the five benchmark scenes
        /// hold at most 318 MB (oa_dm3). 0: no limit, every map first (the paper).
        budget_mb: f32 = 512.0, in 0.0 ..= 1048576.0;
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
        /// What the depth pass transforms: world positions (the paper) or positions relative to
        /// the light, which keep the stored depth within a step of the lit pass's
        /// (docs/checks.md, oa_koth2).
        caster_space: CasterSpace = CasterSpace::Light;
        /// Compare the depth of the receiver's point lifted along its normal by the exact
        /// reference's own ray-origin lift (0.01 units plus 4e-6 of its largest coordinate),
        /// where the compared depth is computed per fragment (`texgen = fragment`, cube maps).
        /// The interpolated position is a float step off the surface (1.5e-5 units at 232), and
        /// where a face's near plane is fitted close to a wall it sees head-on, the offset's
        /// constant units are smaller than that step in world units (oa_ctf2's six spots: 1.3%
        /// of the receivers falsely shadowed in rows; docs/shadow-maps.md).
        normal_offset: bool = true;
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
        /// Where `plan.cull_casters` leaves out a piece's facing triangles whose shadow reaches
        /// no receiver, keep a flat surface whole: a triangle joined to a kept one through
        /// coplanar neighbours stays. Off, the cull can split a surface, and the side quad that
        /// closes the kept part rises from the surface itself and ties with it in the depth
        /// test along the pixels whose centres lie on the split (oa_dm3: 28 pixels shadowed
        /// that no cull shadows); on, more cap triangles are drawn.
        cull_whole_planes: bool = true;
        /// Additive lit pass where stencil = 0 (paper) or Bestimt and Freitag's fill quad.
        shading: VolumeShading = VolumeShading::Additive;
        /// Rebuild a light's volumes only when the light or a caster moved. On the paper's
        /// frame (`plan.enabled = false`) it also keeps a light's draws whole while nothing
        /// they are made from changed (what `plan.reuse_volume_draws` does for the planner).
        caching: bool = true;
        /// Memory for kept volume parts, in MiB (of vertices in the GPU's buffer): a still
        /// light's pieces of still casters are built once against every receiver in its range
        /// and kept while out of view; beyond this the least recently planned are dropped.
        /// The CPU's copies of uploaded parts are held within as much again (least recently
        /// planned given up first) where `plan.cull_clipped` reads their triangles, and not
        /// at all elsewhere under `relayout_on_gpu`.
        kept_mb: f32 = 256.0, in 0.0 ..= 65536.0;
        /// Lay a light's volume buffer out again on the GPU: a part already uploaded is
        /// copied from its old place (glCopyBufferSubData) into the new layout, so the CPU
        /// gives up its copy once the upload is made (the paper's frame of oa_dm3 held
        /// 268 MB of such copies beside 645 MB of buffers). Off: the CPU keeps copies within
        /// `kept_mb`, and a part whose copy was given up is built again when the layout
        /// changes. Without glCopyBufferSubData (GL 3.1, `GL_ARB_copy_buffer`) it is off.
        relayout_on_gpu: bool = true;
        /// Whose volumes the GPU extrudes (with infinite extrusion and the shader pipeline;
        /// elsewhere the CPU builds them all). Those volumes are whole caster groups, counted
        /// depth-fail, without the planner's per-piece culling, truncation, scissors or depth
        /// clips. Default none: on llvmpipe, where the vertex shader runs on the CPU too, the
        /// CPU's culled, cached pieces were faster for models and the world alike along every
        /// flythrough measured (docs/motion.md).
        gpu_extrusion: GpuExtrusion = GpuExtrusion::Auto;
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
        /// Lights the frame sends between two fences: after every this many lights' passes
        /// (and maps, when they come first) it inserts a fence and waits for the one before
        /// (`glClientWaitSync`), so the GL holds at most two such groups queued. A CPU
        /// rasteriser bins what it is sent ahead of its threads: oa_dm3's paper's frame of
        /// 64 lights' shadow maps held 2.8 GB binned unbounded, 1.2 GB with 8 (a fence flushes,
        /// and one per light cost its shadows-off frame a quarter more). 0: never waits.
        /// Under `plan.profile = gpu` 0: a GPU's driver bounds its own queue, and a wait there
        /// would stall its pipeline.
        lights_per_fence: u32 = 8, in 0 ..= 1024;
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
