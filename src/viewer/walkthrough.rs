//! What each step of a frame does and which GL state it uses, in words, for the viewer's
//! walkthrough mode. The wording follows the options in force and what the frame actually
//! executed (the planner's stencil passes and counting), so a toggle changes the text.

use crate::frame::{Frame, Step, StepKind};
use crate::options::{
    CasterFaces, CompareResult, CountingMode, DepthSource, ModelShadows, Options, StencilWrap,
    VolumeProjection, VolumeShading,
};

/// What a frame executed, as far as the explanations need it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Executed {
    /// Stencil passes per light's volumes: 2 (culled passes) or 1 (glStencilOpSeparate).
    pub stencil_passes: usize,
    /// The step's light's volume parts counted (depth-fail, depth-pass), when it has volumes.
    pub parts: Option<(usize, usize)>,
}

impl Executed {
    /// What `frame` executed for `step`.
    pub fn of(frame: &Frame, step: &Step) -> Executed {
        Executed {
            stencil_passes: frame.plan_stats.stencil_passes,
            parts: frame
                .volumes
                .iter()
                .find(|v| Some(v.light) == step.light)
                .map(|v| (v.zfail_parts, v.zpass_parts)),
        }
    }
}

/// A step explained: a title, what it does, and the GL calls behind it.
#[derive(Debug, Clone, PartialEq)]
pub struct Explanation {
    pub title: String,
    pub what: String,
    pub gl_state: String,
}

fn light_name(step: &Step) -> String {
    match (step.light, step.face) {
        (Some(l), Some(f)) => format!("light {l}, view {f}"),
        (Some(l), None) => format!("light {l}"),
        _ => String::new(),
    }
}

/// How the light's volumes were counted: the parts the frame drew, or the option when the
/// frame has none to show.
fn counting_text(mode: CountingMode, parts: Option<(usize, usize)>) -> String {
    const ZFAIL: &str = "depth-fail: faces behind the surface are counted";
    const ZPASS: &str = "depth-pass: faces in front of the surface are counted";
    match (parts, mode) {
        (Some((zfail, 0)), _) if zfail > 0 => ZFAIL.into(),
        (Some((0, zpass)), _) if zpass > 0 => ZPASS.into(),
        (Some((zfail, zpass)), _) if zfail > 0 => format!(
            "{zfail} parts depth-fail, {zpass} depth-pass (the planner's choice per piece: \
             depth-pass where the view cannot start inside the piece's shadow)"
        ),
        (_, CountingMode::Zfail) => ZFAIL.into(),
        (_, CountingMode::Zpass) => ZPASS.into(),
        (_, CountingMode::Auto) => "each caster depth-pass where safe, else depth-fail".into(),
    }
}

/// Explains `step` under `options`, as `executed`.
pub fn explain(step: &Step, options: &Options, executed: Executed) -> Explanation {
    let who = light_name(step);
    match step.kind {
        StepKind::LightView => light_view(step, options, &who),
        StepKind::DepthCopy => depth_copy(&who),
        StepKind::Base => base(),
        StepKind::Fragments => fragments(options, &who),
        StepKind::Stencil => stencil(options, executed, &who),
        StepKind::Lit => lit(step, options, &who),
        StepKind::ComputationMask => computation_mask(options, &who),
        StepKind::Fill => fill(&who),
    }
}

/// The casters drawn from the light into its depth buffer.
fn light_view(step: &Step, options: &Options, who: &str) -> Explanation {
    let sm = &options.shadow_map;
    Explanation {
        title: format!("Light view ({who})"),
        what: format!(
            "The casters are drawn from the light into a {0}x{0} depth buffer: the shadow map \
             stores, per texel, the depth of the nearest {1} the light sees. Brighter is \
             nearer.{2}",
            sm.size,
            match sm.cull {
                CasterFaces::Front => "front face",
                CasterFaces::Back => "back face",
                CasterFaces::Both => "face of either side",
            },
            match step.technique {
                Some(crate::options::Technique::Psm) => {
                    " Perspective shadow map: the scene is first taken into the camera's \
                     post-perspective space (the camera slid back behind the casters), where \
                     near things are large, and the light's frustum there is fitted to the \
                     receivers in view: the near field gets most of the texels. A view where \
                     that degenerates keeps its standard map (render --stats lists them)."
                }
                Some(crate::options::Technique::Tsm) => {
                    " Trapezoidal shadow map: the light's view of the camera frustum is \
                     bounded by a trapezoid whose short edge lies at the camera, and the \
                     trapezoid is stretched onto the square map (Martin & Tan's 80% rule \
                     places its apex): the near field gets most of the texels."
                }
                _ if sm.omni == crate::options::OmniMode::Frusta => {
                    " With shadow_map.omni = frusta an omni light's views are several \
                     frusta fitted around the receivers in view, each a rectangle of one \
                     cube face with its own map size (the sizes above are the option's; \
                     render --stats lists each light's frusta): receivers near the camera \
                     get more texels per unit, those far off fewer."
                }
                _ => "",
            }
        ),
        gl_state: format!(
            "glColorMask(0,0,0,0); glViewport(0,0,{0},{0}); {1}; glPolygonOffset({2}, {3}) x (1 + {4} x light order){5}; depth test \
             GL_LESS; target: {6}.",
            sm.size,
            match sm.cull {
                CasterFaces::Front => "glEnable(GL_CULL_FACE) keeping front faces",
                CasterFaces::Back => "glEnable(GL_CULL_FACE) keeping back faces",
                CasterFaces::Both => "glDisable(GL_CULL_FACE): both faces",
            },
            sm.offset_factor,
            sm.offset_units,
            sm.offset_growth,
            if sm.offset { "" } else { " (offset off)" },
            match sm.depth_source {
                DepthSource::Copy => "the frame's own depth buffer (copied next)",
                DepthSource::Fbo => "an FBO with the depth texture attached",
            }
        ),
    }
}

/// The depth buffer copied into the light's texture.
fn depth_copy(who: &str) -> Explanation {
    Explanation {
        title: format!("Depth copy ({who})"),
        what: "The depth buffer just drawn is copied into the light's depth texture \
               (the paper's way: no render-to-texture on its hardware)."
            .into(),
        gl_state: "glBindTexture(GL_TEXTURE_2D, map); glCopyTexSubImage2D(GL_TEXTURE_2D, 0, \
                   0, 0, 0, 0, size, size); then GL_TEXTURE_COMPARE_MODE = \
                   GL_COMPARE_REF_TO_TEXTURE, GL_TEXTURE_COMPARE_FUNC = GL_LEQUAL."
            .into(),
    }
}

/// The unlit pass, which lays down the depth.
fn base() -> Explanation {
    Explanation {
        title: "Unlit world".into(),
        what: "Every visible surface with its baked light only (lightmaps, vertex light, a \
               constant level for models). This pass also lays down the depth that every \
               later pass tests against."
            .into(),
        gl_state: "glClear(COLOR|DEPTH|STENCIL); depth test GL_LESS, depth writes on; no \
                   blending; alpha-tested surfaces discard in the shader (glAlphaFunc \
                   emulated)."
            .into(),
    }
}

/// The subdivision's shadowed fragments marked in the stencil.
fn fragments(options: &Options, who: &str) -> Explanation {
    Explanation {
        title: format!("Shadowed fragments into the stencil ({who})"),
        what: format!(
            "Vector's light-volume subdivision cut the light's receivers, once and in \
             object space, into lit and shadowed fragments (each caster's light volume \
             clipping what lies behind it). The shadowed fragments are drawn over the \
             unlit pass's depth without colour or depth writes: where one is the visible \
             surface the stencil becomes 1 (bright). {}",
            match options.subdivision.models {
                ModelShadows::Volumes => {
                    "Only the world was cut: the models, which move, had their shadow \
                     volumes (and those of the world's pieces whose shadow may reach a \
                     model) counted into the stencil just before; a mark replaces a count, \
                     shadowed either way. A moving model costs volumes, not a new \
                     subdivision, and the camera moves for free."
                }
                ModelShadows::Subdivided => {
                    "Nothing is counted and no volume reaches the camera: the camera moves \
                     for free (a moving model makes the light be cut again)."
                }
            }
        ),
        gl_state: format!(
            "glClear(GL_STENCIL_BUFFER_BIT) unless volumes were counted; \
             glColorMask(0,0,0,0); glDepthMask(0); \
             glDepthFunc(GL_LEQUAL); glPolygonOffset({}, {}) (the fragments' corners were \
             rounded from f64); glStencilFunc(GL_ALWAYS, 1, ~0), glStencilOp(KEEP, KEEP, \
             REPLACE); each surface's fragments culled as its material is.",
            crate::gl::passes::stencil::FRAGMENT_OFFSET.0,
            crate::gl::passes::stencil::FRAGMENT_OFFSET.1
        ),
    }
}

/// The light's volumes counted in the stencil.
fn stencil(options: &Options, executed: Executed, who: &str) -> Explanation {
    let sv = &options.shadow_volume;
    Explanation {
        title: format!("Shadow volumes into the stencil ({who})"),
        what: format!(
            "The light's shadow volumes are drawn without colour or depth writes; each \
             pixel's stencil ends up counting the volumes it lies in ({}). Non-zero means \
             shadowed.",
            counting_text(sv.counting, executed.parts)
        ),
        gl_state: format!(
            "glClear(GL_STENCIL_BUFFER_BIT); glColorMask(0,0,0,0); glDepthMask(0); \
             glStencilFunc(GL_ALWAYS, 0, ~0); {}; {} arithmetic; {}.",
            if executed.stencil_passes == 2 {
                "two passes with glCullFace: back faces GL_INCR on depth fail, then front \
                 faces GL_DECR"
            } else {
                "one pass with glStencilOpSeparate for front and back faces"
            },
            // One pass always wraps (see the stencil pass).
            if sv.wrap == StencilWrap::Saturate && executed.stencil_passes == 2 {
                "saturating"
            } else {
                "wrapping"
            },
            match sv.projection {
                VolumeProjection::Infinite => "infinite far plane",
                VolumeProjection::InfiniteEpsilon => "infinite far plane with Lengyel's epsilon",
                VolumeProjection::DepthClamp => "finite far plane with depth clamping",
            }
        ),
    }
}

/// The light's additive pass, with the shadow test its technique makes.
fn lit(step: &Step, options: &Options, who: &str) -> Explanation {
    let sm = &options.shadow_map;
    let sv = &options.shadow_volume;
    let technique = step.technique.unwrap_or(crate::options::Technique::None);
    let shadow = match technique {
        crate::options::Technique::ShadowMap => match sm.result {
            CompareResult::Alpha => {
                "each fragment is projected into the light's map (texgen emulated in the \
                 vertex shader); the depth compare's result goes to alpha and the alpha \
                 test (glAlphaFunc emulated) drops shadowed fragments"
            }
            CompareResult::Intensity => {
                "each fragment is projected into the light's map; the depth compare's \
                 result scales the light"
            }
        },
        crate::options::Technique::ShadowVolume => match sv.shading {
            VolumeShading::Additive => "the stencil test keeps only fragments whose count is zero",
            VolumeShading::Fill => {
                "every fragment is lit; the fill quad darkens the shadowed ones next"
            }
        },
        crate::options::Technique::Psm | crate::options::Technique::Tsm => {
            "each fragment is projected into the light's warped map (the same matrix \
             drew it: the camera's post-perspective space for psm, the trapezoid for \
             tsm) and compared there"
        }
        crate::options::Technique::Hybrid => {
            "where the 2×2 compares around the fragment's map position agree the map \
             decides; at the other (silhouette) pixels the stencil count does, so the \
             stencil test keeps count zero and non-silhouette pixels alike and the \
             shader drops the fragments the map shadows"
        }
        crate::options::Technique::Subdivision => {
            "the stencil test keeps only fragments where no shadowed fragment of the \
             subdivision was marked"
        }
        crate::options::Technique::None | crate::options::Technique::Auto => "no shadow test",
    };
    Explanation {
        title: format!("Lit pass ({who})"),
        what: format!(
            "The light's diffuse contribution is added to the frame where it reaches: {shadow}."
        ),
        gl_state: "glBlendFunc(GL_ONE, GL_ONE); depth test GL_LEQUAL against the unlit \
                   pass's depth, depth writes off."
            .into(),
    }
}

/// The hybrid's computation mask and counts.
fn computation_mask(options: &Options, who: &str) -> Explanation {
    Explanation {
        title: format!("Computation mask and counts ({who})"),
        what: format!(
            "Chan & Durand's hybrid: the light's receivers are drawn over the unlit depth and \
             each fragment compares its depth with the {0}x{0} texels of the map around its \
             position. Where they all agree the map decides and the stencil's top bit is set \
             (bright here); where they disagree — a silhouette pixel — the volumes are \
             counted in the low seven bits, and only there.",
            2 * options.hybrid.radius
        ),
        gl_state: if options.hybrid.mask {
            "glClear(GL_STENCIL_BUFFER_BIT); marking: glStencilFunc(GL_ALWAYS, 0x80, ~0), \
             glStencilOp(KEEP, KEEP, REPLACE), glStencilMask(0x80), colour writes off; \
             volumes: glStencilFunc(GL_EQUAL, 0, 0x80), glStencilMask(0x7f), counted as \
             shadow volumes are."
                .into()
        } else {
            "hybrid.mask off: the volumes are counted everywhere first, then the marking \
             pass overwrites the stencil with 0x80 where the map decides."
                .into()
        },
    }
}

/// The fill quad that darkens the shadowed pixels.
fn fill(who: &str) -> Explanation {
    Explanation {
        title: format!("Fill quad ({who})"),
        what: "Bestimt and Freitag's shading: a full-screen quad darkens every pixel whose \
               stencil is not zero, and clears it."
            .into(),
        gl_state: "glStencilFunc(GL_NOTEQUAL, 0, ~0); glBlendFunc(GL_DST_COLOR, GL_ZERO); \
                   colour 224/255."
            .into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const PAPER: Executed = Executed {
        stencil_passes: 2,
        parts: None,
    };

    #[test]
    fn explanations_follow_the_options() {
        let step = Step {
            kind: StepKind::LightView,
            light: Some(1),
            face: Some(2),
            technique: None,
        };
        let mut o = Options::default();
        let a = explain(&step, &o, PAPER);
        assert!(a.title.contains("light 1, view 2"));
        assert!(a.gl_state.contains("frame's own depth buffer"));
        o.shadow_map.depth_source = DepthSource::Fbo;
        assert!(explain(&step, &o, PAPER).gl_state.contains("FBO"));
        let stencil = Step {
            kind: StepKind::Stencil,
            light: Some(0),
            face: None,
            technique: None,
        };
        assert!(explain(&stencil, &o, PAPER).what.contains("depth-fail"));
        o.shadow_volume.counting = CountingMode::Zpass;
        assert!(explain(&stencil, &o, PAPER).what.contains("depth-pass"));
    }

    #[test]
    fn the_stencil_step_says_what_the_planner_ran() {
        let stencil = Step {
            kind: StepKind::Stencil,
            light: Some(0),
            face: None,
            technique: None,
        };
        // The options ask for two saturating depth-fail passes; the planner ran one wrapping
        // pass with both countings.
        let o = Options::default();
        let paper = explain(&stencil, &o, PAPER);
        assert!(paper.gl_state.contains("two passes") && paper.gl_state.contains("saturating"));
        let planned = explain(
            &stencil,
            &o,
            Executed {
                stencil_passes: 1,
                parts: Some((3, 5)),
            },
        );
        assert!(planned.gl_state.contains("one pass") && planned.gl_state.contains("wrapping"));
        assert!(
            planned.what.contains("3 parts depth-fail, 5 depth-pass"),
            "{}",
            planned.what
        );
    }
}
