//! What `gl.pipeline = fixed_function` draws: the options the legacy calls cannot express are
//! replaced by the nearest ones they can, and each replacement is listed with the frame's
//! fallbacks (feature `fixed_function`), so nothing is silently ignored.
//!
//! Legacy GL has no program to compare depths (`shadow_map.compare = shader`), to average
//! several compares (`pcf3x3`, `pcf`: the hardware's 2x2 LINEAR filter is the one it has),
//! to compare against a depth cube map or keep each of several frusta to its cell (omni
//! lights take the paper's six spot maps), to light six faces in one pass, to set the stencil
//! of both faces in one pass (no glStencilOpSeparate in the paper's GL) or to clip volumes by
//! clip distances.

use super::fallback::Fallback;
use crate::options::{Compare, Filter, OmniMode, Options, Pipeline, StencilPasses};

const FEATURE: &str = "fixed_function";

/// `options` as this GL and pipeline run them: each choice that needs a missing feature
/// replaced (`fallback::resolve`, `has` says what the GL has), then each one the
/// fixed-function pipeline cannot draw; every replacement listed.
pub fn resolve_all(options: &Options, has: impl Fn(&str) -> bool) -> (Options, Vec<Fallback>) {
    let (options, mut taken) = super::fallback::resolve(options, has);
    let (options, legacy) = resolve(&options);
    taken.extend(legacy);
    (options, taken)
}

/// `options` as the fixed-function pipeline runs them, with the replacements made; unchanged
/// under `gl.pipeline = shaders`.
pub fn resolve(options: &Options) -> (Options, Vec<Fallback>) {
    let mut o = options.clone();
    let mut taken = Vec::new();
    if o.gl.pipeline != Pipeline::FixedFunction {
        return (o, taken);
    }
    let mut replace = |option: &'static str, o: &mut Options, to: &str| {
        let asked = o.get(option).expect("a known key");
        if asked != to {
            o.set(option, to).expect("a valid value");
            taken.push(Fallback {
                feature: FEATURE.into(),
                option: option.into(),
                asked,
                used: to.to_string(),
            });
        }
    };
    if o.shadow_map.compare == Compare::Shader {
        replace("shadow_map.compare", &mut o, "hardware");
    }
    if matches!(o.shadow_map.filter, Filter::Pcf3x3 | Filter::Pcf) {
        replace("shadow_map.filter", &mut o, "hw2x2");
    }
    // Cube maps need the shaders' cube lookups; frusta their per-cell discard.
    if matches!(o.shadow_map.omni, OmniMode::Cube | OmniMode::Frusta) {
        replace("shadow_map.omni", &mut o, "six_spots");
    }
    // ID and priority buffers need shaders (gl_PrimitiveID, the table lookups).
    if o.shadow_map.buffer != crate::options::MapBuffer::Depth {
        replace("shadow_map.buffer", &mut o, "depth");
    }
    let depth_only = o.auto_among_depth_only();
    if depth_only != o.auto_among {
        replace("auto_among", &mut o, &depth_only);
    }
    if o.shadow_volume.stencil == StencilPasses::Separate {
        replace("shadow_volume.stencil", &mut o, "two_pass");
    }
    // The planner's switches matter only while it is on (the paper's frame has it off).
    if o.plan.enabled {
        for key in [
            "plan.omni_cube",
            "plan.merge_faces",
            "plan.one_pass_stencil",
            "plan.depth_clip",
        ] {
            replace(key, &mut o, "false");
        }
    }
    (o, taken)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shaders_pipeline_keeps_every_option() {
        let mut o = Options::default();
        o.set("shadow_map.filter", "pcf").unwrap();
        let (same, taken) = resolve(&o);
        assert_eq!(same, o);
        assert!(taken.is_empty());
    }

    #[test]
    fn fixed_function_replaces_what_it_cannot_draw_and_lists_it() {
        let mut o = Options::default();
        o.set("gl.pipeline", "fixed_function").unwrap();
        o.set("shadow_map.filter", "pcf3x3").unwrap();
        o.set("shadow_map.compare", "shader").unwrap();
        o.set("shadow_map.omni", "frusta").unwrap();
        let (ff, taken) = resolve(&o);
        assert_eq!(ff.shadow_map.filter, Filter::Hw2x2);
        assert_eq!(ff.shadow_map.omni, OmniMode::SixSpots);
        assert_eq!(ff.shadow_map.compare, Compare::Hardware);
        assert!(!ff.plan.omni_cube && !ff.plan.one_pass_stencil && !ff.plan.depth_clip);
        let keys: Vec<&str> = taken.iter().map(|f| f.option.as_ref()).collect();
        assert!(keys.contains(&"shadow_map.filter") && keys.contains(&"plan.depth_clip"));
        assert!(keys.contains(&"shadow_map.omni"));
        assert!(taken.iter().all(|f| f.feature == "fixed_function"));
        // What was replaced needs no second replacement, and the paper's frame none at all.
        let (_, none) = resolve(&ff);
        assert!(none.is_empty());
        let mut paper = crate::presets::Preset::Paper.options();
        paper.set("gl.pipeline", "fixed_function").unwrap();
        assert!(resolve(&paper).1.is_empty());
    }
}
