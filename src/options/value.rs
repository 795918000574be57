//! The values options hold: the `OptionValue` trait, its impls for numbers, bools, strings
//! and `option_enum!` enums, and the errors setting a value can give.

use serde::Serialize;
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

pub(super) fn bad_value(key: &str, value: &str, reason: String) -> OptionError {
    OptionError::BadValue {
        key: key.to_string(),
        value: value.to_string(),
        reason,
    }
}
