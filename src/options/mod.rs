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

mod choices;
mod table;
mod value;

pub use choices::*;
pub use table::*;
pub use value::*;

use std::collections::BTreeMap;
use std::fmt;

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
    fn technique_overrides(&self) -> Result<Vec<(usize, Candidate)>, OptionError> {
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
                let candidate = match Technique::parse_value(technique.trim()) {
                    // `none` and `auto` are overrides too, though no candidate of `auto`'s.
                    Ok(t @ (Technique::None | Technique::Auto)) => Candidate::of(t, self),
                    _ => Candidate::parse(technique, self).map_err(bad)?,
                };
                Ok((index, candidate))
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
                    let size = c.size.map_or(String::new(), |s| format!("@{s}"));
                    format!("shadow_map:depth{size}")
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
        self.candidate_for(index).technique
    }

    /// What light `index` runs with: its override (which may name a map buffer or size,
    /// `3:shadow_map@2048`), else `technique` with its options' buffer and size.
    pub fn candidate_for(&self, index: usize) -> Candidate {
        self.technique_overrides()
            .unwrap_or_default()
            .iter()
            .rev()
            .find(|(i, _)| *i == index)
            .map_or_else(|| Candidate::of(self.technique, self), |(_, c)| *c)
    }

    /// Sets (or with `None` removes) light `index`'s technique override.
    pub fn set_technique_for(&mut self, index: usize, technique: Option<Technique>) {
        // The other lights' entries as written (a buffer or size they name stays).
        let mut pairs: Vec<(usize, String)> = self
            .lighting
            .techniques
            .split(',')
            .filter_map(|pair| {
                let (i, what) = pair.split_once(':')?;
                Some((i.trim().parse::<usize>().ok()?, what.trim().to_string()))
            })
            .filter(|(i, _)| *i != index)
            .collect();
        if let Some(t) = technique {
            pairs.push((index, t.to_string()));
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
    fn auto_among_takes_a_map_size_for_standard_maps_only() {
        let mut o = Options {
            auto_among: "shadow_map@256, shadow_map:id@2048,shadow_map".into(),
            ..Options::default()
        };
        o.validate().unwrap();
        let choices = o.auto_choices();
        let names: Vec<String> = choices.iter().map(|c| c.to_string()).collect();
        assert_eq!(
            names,
            ["shadow_map@256", "shadow_map:id@2048", "shadow_map"]
        );
        assert_eq!(
            choices.iter().map(|c| c.size).collect::<Vec<_>>(),
            [Some(256), Some(2048), None]
        );
        for bad in [
            "shadow_volume@512",
            "shadow_map@",
            "shadow_map@big",
            "shadow_map@8",
            "shadow_map@100000",
        ] {
            let b = Options {
                auto_among: bad.into(),
                ..Options::default()
            };
            assert!(b.validate().is_err(), "{bad}");
        }
        // Without ID buffers, an ID buffer of a size becomes a depth map of that size.
        o.auto_among = "shadow_map:id@2048,shadow_volume".into();
        assert_eq!(
            o.auto_among_depth_only(),
            "shadow_map:depth@2048,shadow_volume"
        );
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
        // A shadow-map entry may name its map's size and buffer; a set elsewhere keeps them.
        o.set("lighting.techniques", "2:shadow_map@2048, 4:shadow_map:id")
            .unwrap();
        o.validate().unwrap();
        assert_eq!(o.candidate_for(2).size, Some(2048));
        assert_eq!(o.candidate_for(4).buffer, MapBuffer::Id);
        assert_eq!(o.candidate_for(0), Candidate::of(Technique::ShadowMap, &o));
        o.set_technique_for(3, Some(Technique::ShadowVolume));
        assert_eq!(
            o.lighting.techniques,
            "2:shadow_map@2048,3:shadow_volume,4:shadow_map:id"
        );
        for bad in ["1", "x:shadow_map", "1:nope", "1:shadow_volume@512"] {
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
