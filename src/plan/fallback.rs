//! The fallback each missing GL feature selects: options that need a feature the GL lacks
//! are replaced by the option that does without it, and the frame says so. The features are
//! the capability probe's (`gl::caps`), less those `gl.disable` names, so that every fallback
//! can be run on any GL.

use crate::options::{
    DepthBits, DepthSource, OmniMode, Options, Outside, StencilPasses, StencilWrap, Technique,
    VolumeProjection,
};
use serde::Serialize;

/// The features `gl.disable` may name (those a fallback exists for).
pub const FEATURES: [&str; 13] = [
    "render_to_depth_texture",
    "depth_copy",
    "depth_read",
    "float_depth",
    "clip_distances",
    "depth_clamp",
    "separate_stencil",
    "stencil_wrap",
    "timer_query",
    "depth_bounds",
    "primitive_id",
    "offset_per_fragment",
    "copy_buffer",
];

/// The slope factor maps fitted tightly in depth take where the GL adds the polygon offset per
/// vertex (`offset_per_fragment` missing): measured on softpipe, it cures the built-in scene's
/// frusta (0.662% → 0.440%, llvmpipe 0.443%) and the near receiver's perspective map
/// (28.5% → 0.79%, llvmpipe 1.08%); docs/drivers.md.
pub const PER_VERTEX_OFFSET_FACTOR: f32 = 10.0;

/// One option replaced because the GL lacks a feature.
#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize)]
pub struct Fallback {
    pub feature: std::borrow::Cow<'static, str>,
    pub option: std::borrow::Cow<'static, str>,
    pub asked: String,
    pub used: String,
}

/// The features `gl.disable` names; an unknown name is an error naming the known ones.
pub fn disabled(options: &Options) -> Result<Vec<&'static str>, String> {
    options
        .gl
        .disable
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|name| {
            FEATURES.into_iter().find(|f| *f == name).ok_or_else(|| {
                format!(
                    "gl.disable: unknown feature `{name}` (known: {})",
                    FEATURES.join(", ")
                )
            })
        })
        .collect()
}

/// `options` with every choice the GL cannot run replaced by its fallback; `has` says whether
/// a feature works here (and is not disabled).
pub fn resolve(options: &Options, has: impl Fn(&str) -> bool) -> (Options, Vec<Fallback>) {
    let mut o = options.clone();
    let mut taken = Vec::new();
    let mut fall = |feature: &'static str, option: &'static str, o: &mut Options, to: &str| {
        let asked = o.get(option).expect("a known key");
        if asked != to {
            o.set(option, to).expect("a valid fallback value");
            taken.push(Fallback {
                feature: feature.into(),
                option: option.into(),
                asked,
                used: to.to_string(),
            });
        }
    };
    if !has("render_to_depth_texture")
        && has("depth_copy")
        && o.shadow_map.depth_source == DepthSource::Fbo
    {
        fall(
            "render_to_depth_texture",
            "shadow_map.depth_source",
            &mut o,
            "copy",
        );
    }
    // ES 3.0 cannot copy depth (glCopyTexSubImage2D takes colour only): draw into the map.
    // Where neither works nothing is replaced, and the frame's GL error says so.
    if !has("depth_copy")
        && has("render_to_depth_texture")
        && o.shadow_map.depth_source == DepthSource::Copy
    {
        fall("depth_copy", "shadow_map.depth_source", &mut o, "fbo");
    }
    // ES 3.0 reads no depth: the planner's depth comes reduced by a shader, read as colour.
    if !has("depth_read") && !o.plan.reduce_depth {
        fall("depth_read", "plan.reduce_depth", &mut o, "true");
    }
    if !has("primitive_id") && o.shadow_map.buffer != crate::options::MapBuffer::Depth {
        fall("primitive_id", "shadow_map.buffer", &mut o, "depth");
    }
    let depth_only = o.auto_among_depth_only();
    if !has("primitive_id") && depth_only != o.auto_among {
        fall("primitive_id", "auto_among", &mut o, &depth_only);
    }
    // A GL that adds the offset per vertex, clamping each vertex to the far plane first, loses
    // it where a vertex lies near that plane: warped maps and frusta, fitted tightly in depth,
    // then shadow their own receivers. A larger slope factor makes up for it.
    let tight_in_depth = matches!(o.technique, Technique::Psm | Technique::Tsm)
        || o.shadow_map.omni == OmniMode::Frusta;
    if !has("offset_per_fragment")
        && tight_in_depth
        && o.shadow_map.offset_factor < PER_VERTEX_OFFSET_FACTOR
    {
        fall(
            "offset_per_fragment",
            "shadow_map.offset_factor",
            &mut o,
            &PER_VERTEX_OFFSET_FACTOR.to_string(),
        );
    }
    if !has("float_depth") && o.shadow_map.depth_bits == DepthBits::D32f {
        fall("float_depth", "shadow_map.depth_bits", &mut o, "24");
    }
    if !has("clip_distances") {
        if o.shadow_map.outside == Outside::ClipPlanes {
            fall("clip_distances", "shadow_map.outside", &mut o, "range");
        }
        // The planner's depth clip draws through gl_ClipDistance too.
        if o.plan.depth_clip {
            fall("clip_distances", "plan.depth_clip", &mut o, "false");
        }
    }
    if !has("depth_clamp") && o.shadow_volume.projection == VolumeProjection::DepthClamp {
        fall(
            "depth_clamp",
            "shadow_volume.projection",
            &mut o,
            "infinite",
        );
    }
    // One stencil pass needs glStencilOpSeparate, and wraps.
    let one_pass_possible = has("separate_stencil") && has("stencil_wrap");
    if !one_pass_possible {
        let feature = if has("separate_stencil") {
            "stencil_wrap"
        } else {
            "separate_stencil"
        };
        if o.shadow_volume.stencil == StencilPasses::Separate {
            fall(feature, "shadow_volume.stencil", &mut o, "two_pass");
        }
        if o.plan.one_pass_stencil {
            fall(feature, "plan.one_pass_stencil", &mut o, "false");
        }
    }
    // The planner's depth bounds test (it alone uses it) gives way to its emulation,
    // `plan.depth_clip`'s clip planes.
    if !has("depth_bounds") && o.plan.enabled && o.plan.depth_bounds_test {
        fall("depth_bounds", "plan.depth_bounds_test", &mut o, "false");
    }
    if !has("stencil_wrap") && o.shadow_volume.wrap == StencilWrap::Wrap {
        fall("stencil_wrap", "shadow_volume.wrap", &mut o, "saturate");
    }
    // Without copies between buffers the CPU keeps the uploaded volume parts it lays out.
    if !has("copy_buffer") && o.shadow_volume.relayout_on_gpu {
        fall(
            "copy_buffer",
            "shadow_volume.relayout_on_gpu",
            &mut o,
            "false",
        );
    }
    (o, taken)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn without(missing: &'static str) -> impl Fn(&str) -> bool {
        move |f| f != missing
    }

    #[test]
    fn every_feature_falls_back_to_the_option_that_needs_none() {
        let mut asked = Options::default();
        for s in [
            "shadow_map.depth_source=fbo",
            "shadow_map.depth_bits=32f",
            "shadow_map.outside=clip_planes",
            "shadow_volume.projection=depth_clamp",
            "shadow_volume.stencil=separate",
            "shadow_volume.wrap=wrap",
        ] {
            asked.set_assignment(s).unwrap();
        }
        let (all, none) = resolve(&asked, |_| true);
        assert_eq!((all, none), (asked.clone(), vec![]));
        let options_of = |missing| {
            let (o, taken) = resolve(&asked, without(missing));
            let keys: Vec<String> = taken.iter().map(|t| t.option.to_string()).collect();
            (o, keys)
        };
        let (o, keys) = options_of("render_to_depth_texture");
        assert_eq!(o.shadow_map.depth_source, DepthSource::Copy);
        assert_eq!(keys, ["shadow_map.depth_source"]);
        let mut copy = asked.clone();
        copy.set("shadow_map.depth_source", "copy").unwrap();
        let (o, taken) = resolve(&copy, without("depth_copy"));
        assert_eq!(o.shadow_map.depth_source, DepthSource::Fbo);
        assert_eq!(taken.len(), 1);
        // Neither way to fill a map: nothing to fall back to.
        let neither = |f: &str| f != "depth_copy" && f != "render_to_depth_texture";
        assert_eq!(resolve(&copy, neither).1, vec![]);
        let mut whole = asked.clone();
        whole.set("plan.reduce_depth", "false").unwrap();
        let (o, taken) = resolve(&whole, without("depth_read"));
        assert!(o.plan.reduce_depth);
        assert_eq!(taken.len(), 1);
        let (o, keys) = options_of("float_depth");
        assert_eq!(o.shadow_map.depth_bits, DepthBits::D24);
        assert_eq!(keys, ["shadow_map.depth_bits"]);
        let (o, keys) = options_of("clip_distances");
        assert_eq!(
            (o.shadow_map.outside, o.plan.depth_clip),
            (Outside::Range, false)
        );
        assert_eq!(keys, ["shadow_map.outside", "plan.depth_clip"]);
        let (o, keys) = options_of("depth_bounds");
        assert!(!o.plan.depth_bounds_test && o.plan.depth_clip);
        assert_eq!(keys, ["plan.depth_bounds_test"]);
        // Without the planner nothing uses it: nothing to replace.
        let mut paper = asked.clone();
        paper.set("plan.enabled", "false").unwrap();
        assert_eq!(resolve(&paper, without("depth_bounds")).1, vec![]);
        let (o, _) = options_of("depth_clamp");
        assert_eq!(o.shadow_volume.projection, VolumeProjection::Infinite);
        let (o, keys) = options_of("separate_stencil");
        assert_eq!(o.shadow_volume.stencil, StencilPasses::TwoPass);
        assert!(!o.plan.one_pass_stencil);
        assert_eq!(keys, ["shadow_volume.stencil", "plan.one_pass_stencil"]);
        let (o, keys) = options_of("stencil_wrap");
        assert_eq!(
            (o.shadow_volume.stencil, o.shadow_volume.wrap),
            (StencilPasses::TwoPass, StencilWrap::Saturate)
        );
        assert_eq!(
            keys,
            [
                "shadow_volume.stencil",
                "plan.one_pass_stencil",
                "shadow_volume.wrap"
            ]
        );
        let (o, keys) = options_of("copy_buffer");
        assert!(!o.shadow_volume.relayout_on_gpu);
        assert_eq!(keys, ["shadow_volume.relayout_on_gpu"]);
    }

    #[test]
    fn unknown_features_are_errors_naming_the_known_ones() {
        let mut o = Options::default();
        o.set("gl.disable", "float_depth, depth_clamp").unwrap();
        assert_eq!(disabled(&o), Ok(vec!["float_depth", "depth_clamp"]));
        o.set("gl.disable", "warp_drive").unwrap();
        assert!(disabled(&o).unwrap_err().contains("clip_distances"));
    }
}
