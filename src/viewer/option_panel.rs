//! The options panel's model: one editable field per option, built from [`Options::specs`] and
//! written back with [`Options::set`], so the panel shows exactly what `shadowlab options`
//! lists and accepts exactly what `--set` accepts. GL- and egui-free (the drawing is in `ui`).

use crate::options::{OptionError, OptionKind, Options};

/// An option's value as a widget holds it.
#[derive(Debug, Clone, PartialEq)]
pub enum FieldValue {
    Bool(bool),
    Choice {
        choices: Vec<&'static str>,
        index: usize,
    },
    Float {
        value: f64,
        min: f64,
        max: f64,
    },
    Integer {
        value: i64,
        min: f64,
        max: f64,
    },
    Text(String),
}

impl FieldValue {
    /// The value as `--set` writes it.
    pub fn text(&self) -> String {
        match self {
            FieldValue::Bool(b) => b.to_string(),
            FieldValue::Choice { choices, index } => choices[*index].to_string(),
            FieldValue::Float { value, .. } => format!("{value}"),
            FieldValue::Integer { value, .. } => value.to_string(),
            FieldValue::Text(t) => t.clone(),
        }
    }
}

/// One option in the panel.
#[derive(Debug, Clone, PartialEq)]
pub struct Field {
    pub key: &'static str,
    /// The group (the part of the key before the dot), `general` for root options.
    pub group: &'static str,
    /// The option's one-line meaning (the tooltip).
    pub meaning: String,
    pub default: String,
    pub value: FieldValue,
}

/// Keys the panel leaves to other controls (the window decides the frame size; the context
/// path cannot change in a running window).
pub fn hidden(key: &str) -> bool {
    matches!(key, "width" | "height" | "backend")
}

/// Every option's field with its current value, in declaration order.
pub fn fields(options: &Options) -> Vec<Field> {
    Options::specs()
        .into_iter()
        .filter(|s| !hidden(s.key))
        .map(|s| {
            let current = options.get(s.key).unwrap_or_else(|_| s.default.clone());
            let value = match &s.kind {
                OptionKind::Bool => FieldValue::Bool(current == "true"),
                OptionKind::Choice { choices } => FieldValue::Choice {
                    index: choices.iter().position(|c| *c == current).unwrap_or(0),
                    choices: choices.clone(),
                },
                OptionKind::Float { min, max } => FieldValue::Float {
                    value: current.parse().unwrap_or(*min),
                    min: *min,
                    max: *max,
                },
                OptionKind::Integer { min, max } => FieldValue::Integer {
                    value: current.parse().unwrap_or(*min as i64),
                    min: *min,
                    max: *max,
                },
                OptionKind::Text => FieldValue::Text(current),
            };
            Field {
                key: s.key,
                group: s.key.split_once('.').map_or("general", |(g, _)| g),
                meaning: s.meaning,
                default: s.default,
                value,
            }
        })
        .collect()
}

/// Writes a field back; the options are unchanged when the value is refused.
pub fn apply(options: &mut Options, field: &Field) -> Result<(), OptionError> {
    let mut next = options.clone();
    next.set(field.key, &field.value.text())?;
    next.validate()?;
    *options = next;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn changed() -> Options {
        let mut o = Options::default();
        for a in [
            "technique=shadow_volume",
            "lighting.only=0,2",
            "lighting.ambient=0.35",
            "lighting.techniques=1:shadow_map",
            "shadow_map.size=1024",
            "shadow_map.filter=pcf3x3",
            "shadow_map.offset=false",
            "shadow_map.offset_factor=2.5",
            "shadow_volume.counting=auto",
            "culling.pvs=false",
        ] {
            o.set_assignment(a).unwrap();
        }
        o
    }

    #[test]
    fn panel_fields_round_trip_every_option() {
        let o = changed();
        let mut back = Options::default();
        for f in fields(&o) {
            apply(&mut back, &f).unwrap_or_else(|e| panic!("{}: {e}", f.key));
        }
        assert_eq!(back, o);
        // Every option but the window's own is in the panel, with its meaning as tooltip.
        let keys: Vec<&str> = fields(&o).iter().map(|f| f.key).collect();
        assert_eq!(keys.len(), Options::specs().len() - 3);
        assert!(fields(&o).iter().all(|f| !f.meaning.is_empty()));
    }

    #[test]
    fn editing_one_field_changes_only_its_key() {
        let base = changed();
        for mut f in fields(&base) {
            f.value = match f.value.clone() {
                FieldValue::Bool(b) => FieldValue::Bool(!b),
                FieldValue::Choice { choices, index } => FieldValue::Choice {
                    index: (index + 1) % choices.len(),
                    choices,
                },
                FieldValue::Float { value, min, max } => FieldValue::Float {
                    value: if value < max {
                        (value + max) / 2.0
                    } else {
                        min
                    },
                    min,
                    max,
                },
                FieldValue::Integer { value, min, max } => FieldValue::Integer {
                    value: if (value as f64) < max {
                        value + 1
                    } else {
                        min as i64
                    },
                    min,
                    max,
                },
                FieldValue::Text(_) if f.key == "lighting.techniques" => {
                    FieldValue::Text("0:none".into())
                }
                FieldValue::Text(_) if f.key == "auto_among" => {
                    FieldValue::Text("shadow_map,hybrid".into())
                }
                FieldValue::Text(_) => FieldValue::Text("1".into()),
            };
            let mut o = base.clone();
            apply(&mut o, &f).unwrap_or_else(|e| panic!("{}: {e}", f.key));
            let (a, b) = (base.to_map(), o.to_map());
            let differing: Vec<&String> = a.keys().filter(|k| a[*k] != b[*k]).collect();
            assert_eq!(differing, vec![f.key], "{}", f.key);
        }
    }

    #[test]
    fn refused_values_leave_the_options_alone() {
        let mut o = changed();
        let before = o.clone();
        let mut f = fields(&o)
            .into_iter()
            .find(|f| f.key == "lighting.techniques")
            .unwrap();
        f.value = FieldValue::Text("zero:nothing".into());
        assert!(apply(&mut o, &f).is_err());
        assert_eq!(o, before);
    }
}
