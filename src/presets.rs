//! Named sets of option values. `paper` is the paper's frame and choices (Arneson, "Real-Time
//! Shadows"): no frame planner, six spot maps per omni light copied from the frame's depth at
//! 512², the paper's polygon offsets, two saturating stencil passes, depth-fail everywhere,
//! infinite volumes and projection. `default` is the library's defaults: the planner on and
//! `technique = auto`, so that a plain run shows shadows and runs fast.
//!
//! A preset is applied over the defaults and a scene's `[options]`; `--set` wins over it.

use crate::options::{OptionError, Options};
use serde::Serialize;
use thiserror::Error;

/// A named set of option values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Preset {
    Default,
    Paper,
}

#[derive(Debug, Error, PartialEq)]
#[error("unknown preset `{0}` (presets: default, paper)")]
pub struct UnknownPreset(pub String);

/// The paper's values, written out (the defaults of these keys are the paper's today; a test
/// checks that they still are, so that a changed default is a decision, not an accident).
const PAPER: &[(&str, &str)] = &[
    ("plan.enabled", "false"),
    // The paper's subject is both techniques; its frame names one. `--set technique=shadow_map`
    // after the preset gives its shadow maps.
    ("technique", "shadow_volume"),
    ("shadow_map.depth_source", "copy"),
    ("shadow_map.size", "512"),
    ("shadow_map.budget_mb", "0"),
    ("shadow_map.depth_bits", "24"),
    ("shadow_map.compare", "hardware"),
    ("shadow_map.result", "alpha"),
    ("shadow_map.filter", "nearest"),
    ("shadow_map.offset", "true"),
    ("shadow_map.offset_factor", "1.1"),
    ("shadow_map.offset_units", "4"),
    ("shadow_map.offset_growth", "1"),
    ("shadow_map.offset_pass", "shadow_map"),
    ("shadow_map.outside", "clamp"),
    ("shadow_map.omni", "six_spots"),
    ("shadow_map.cull", "front"),
    ("shadow_map.texgen", "eye_linear"),
    ("shadow_map.caster_space", "world"),
    ("shadow_map.normal_offset", "false"),
    ("shadow_map.buffer", "depth"),
    ("shadow_volume.casters", "front"),
    ("shadow_volume.counting", "zfail"),
    ("shadow_volume.stencil", "two_pass"),
    ("shadow_volume.wrap", "saturate"),
    ("shadow_volume.edge_rule", "paper"),
    ("shadow_volume.extrusion", "infinite"),
    ("shadow_volume.projection", "infinite"),
    ("shadow_volume.shading", "additive"),
    ("shadow_volume.gpu_extrusion", "none"),
    ("lighting.light_once", "false"),
];

/// One option whose value differs from a preset's.
#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize)]
pub struct Difference {
    pub key: String,
    pub value: String,
    /// The preset's value.
    pub preset: String,
}

impl Preset {
    pub const ALL: [Preset; 2] = [Preset::Default, Preset::Paper];

    pub fn name(self) -> &'static str {
        match self {
            Preset::Default => "default",
            Preset::Paper => "paper",
        }
    }

    /// One line on what the preset is, for `shadowlab options`.
    pub fn meaning(self) -> &'static str {
        match self {
            Preset::Default => {
                "the library's defaults: the frame planner on, technique = auto (every light shadowed)"
            }
            Preset::Paper => {
                "the paper's frame and choices: no planner, shadow volumes (two saturating depth-fail \
                 passes, infinite), six copied 512² spot maps per omni light, the paper's offsets"
            }
        }
    }

    pub fn parse(name: &str) -> Result<Preset, UnknownPreset> {
        Preset::ALL
            .into_iter()
            .find(|p| p.name() == name.trim())
            .ok_or_else(|| UnknownPreset(name.to_string()))
    }

    /// The option values the preset sets.
    pub fn values(self) -> &'static [(&'static str, &'static str)] {
        match self {
            Preset::Default => &[],
            Preset::Paper => PAPER,
        }
    }

    /// Sets the preset's values on `options` (`default` sets none: it is the defaults).
    pub fn apply(self, options: &mut Options) -> Result<(), OptionError> {
        for (key, value) in self.values() {
            options.set(key, value)?;
        }
        Ok(())
    }

    /// The defaults with the preset applied.
    pub fn options(self) -> Options {
        let mut o = Options::default();
        self.apply(&mut o).expect("preset values are valid");
        o
    }

    /// The options of `options` that differ from this preset's, in key order.
    pub fn differences(self, options: &Options) -> Vec<Difference> {
        let preset = self.options().to_map();
        options
            .to_map()
            .into_iter()
            .filter_map(|(key, value)| {
                let p = &preset[&key];
                (p != &value).then(|| Difference {
                    key,
                    value,
                    preset: p.clone(),
                })
            })
            .collect()
    }

    /// The preset `options` equals, if any.
    pub fn matching(options: &Options) -> Option<Preset> {
        Preset::ALL
            .into_iter()
            .find(|p| p.differences(options).is_empty())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_parse_back_and_unknown_names_are_errors() {
        for p in Preset::ALL {
            assert_eq!(Preset::parse(p.name()), Ok(p));
        }
        assert_eq!(
            Preset::parse("fast"),
            Err(UnknownPreset("fast".to_string()))
        );
    }

    #[test]
    fn the_paper_differs_from_the_defaults_only_where_the_options_say_why() {
        // Guards the claim in the options' docs that the other defaults are the paper's (the
        // casters: the paper's one-sided faces lose shadows on open worlds; the offset growth
        // erases later lights' contact shadows on maps with many lights; the light marks keep
        // overlapping triangles from taking a light twice; docs/checks.md; the texgen space:
        // eye-linear planes round past the offset at Quake 3 scale, docs/shadow-maps.md, and so
        // does the depth pass's world-space transform, docs/checks.md; GPU
        // extrusion: `auto` extrudes what moves on the GPU under the gpu profile, the paper
        // builds every volume on the CPU; the map budget: the paper draws every map first,
        // whatever memory they take).
        let keys: Vec<String> = Preset::Paper
            .differences(&Options::default())
            .into_iter()
            .map(|d| d.key)
            .collect();
        assert_eq!(
            keys,
            [
                "lighting.light_once",
                "plan.enabled",
                "shadow_map.budget_mb",
                "shadow_map.caster_space",
                "shadow_map.cull",
                "shadow_map.normal_offset",
                "shadow_map.offset_growth",
                "shadow_map.texgen",
                "shadow_volume.casters",
                "shadow_volume.gpu_extrusion",
                "technique"
            ]
        );
    }

    #[test]
    fn a_set_after_the_preset_is_the_one_difference() {
        let mut o = Preset::Paper.options();
        assert_eq!(Preset::matching(&o), Some(Preset::Paper));
        o.set("shadow_map.size", "1024").unwrap();
        assert_eq!(
            Preset::Paper.differences(&o),
            [Difference {
                key: "shadow_map.size".into(),
                value: "1024".into(),
                preset: "512".into(),
            }]
        );
        assert_eq!(Preset::matching(&o), None);
        assert_eq!(Preset::matching(&Options::default()), Some(Preset::Default));
    }
}
