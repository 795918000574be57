//! DarkPlaces `.rtlights` files: hand-placed realtime lights for a map, one per line:
//!
//! ```text
//! [!]x y z radius r g b [style ["cubemap" [corona [ax ay az [coronasizescale [ambientscale
//!     [diffusescale [specularscale [flags]]]]]]]]]
//! ```
//!
//! A leading `!` turns the light's shadows off. Trailing fields may be left out (older files);
//! they take DarkPlaces' defaults. Blank lines and `//` comments are ignored.

use crate::scene::Light;
use glam::Vec3;
use thiserror::Error;

/// `flags` bit: the light is used when realtime world lighting is off.
pub const LIGHTFLAG_NORMAL_MODE: u32 = 1;
/// `flags` bit: the light is used in realtime world lighting mode.
pub const LIGHTFLAG_REALTIME_MODE: u32 = 2;

/// Why an `.rtlights` file could not be read. Lines are 1-based.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum RtLightsError {
    #[error("line {line}: field `{field}` is missing")]
    MissingField { line: usize, field: &'static str },
    #[error("line {line}: field `{field}`: `{text}` is not a valid number")]
    BadNumber {
        line: usize,
        field: &'static str,
        text: String,
    },
    #[error("line {line}: field `cubemap`: string not closed")]
    UnterminatedString { line: usize },
    #[error("line {line}: unexpected `{text}` after the last field")]
    ExtraField { line: usize, text: String },
}

/// One light of an `.rtlights` file, every field kept.
#[derive(Debug, Clone, PartialEq)]
pub struct RtLight {
    /// Line of the file it came from.
    pub line: usize,
    pub origin: Vec3,
    pub radius: f32,
    /// Linear colour; components may exceed 1 (overbright lights).
    pub color: Vec3,
    /// Light style (animation) index; 0 is steady.
    pub style: i32,
    /// Cubemap filter name, empty for none.
    pub cubemap: String,
    /// Corona brightness, 0 for none.
    pub corona: f32,
    /// Orientation (pitch yaw roll, degrees), for the cubemap.
    pub angles: Vec3,
    pub corona_size_scale: f32,
    pub ambient_scale: f32,
    pub diffuse_scale: f32,
    pub specular_scale: f32,
    /// [`LIGHTFLAG_NORMAL_MODE`] | [`LIGHTFLAG_REALTIME_MODE`] bits.
    pub flags: u32,
    /// False when the line starts with `!`.
    pub casts_shadows: bool,
}

impl RtLight {
    /// The omni light for the renderer: origin, radius and colour as given. Whether it casts
    /// shadows is [`RtLight::casts_shadows`], which [`Light`] does not hold.
    pub fn to_light(&self, name: &str) -> Light {
        let mut light = Light::omni(name, self.origin, self.radius);
        light.color = self.color;
        light
    }
}

/// Field names in file order, for messages.
const FIELDS: [&str; 18] = [
    "x",
    "y",
    "z",
    "radius",
    "r",
    "g",
    "b",
    "style",
    "cubemap",
    "corona",
    "ax",
    "ay",
    "az",
    "coronasizescale",
    "ambientscale",
    "diffusescale",
    "specularscale",
    "flags",
];

/// Splits a line into fields: whitespace-separated, a `"..."` field may hold spaces, `//` starts
/// a comment. Quoted fields are returned without their quotes.
fn split_fields(text: &str, line: usize) -> Result<Vec<&str>, RtLightsError> {
    let mut out = Vec::new();
    let mut rest = text.trim_start();
    while !rest.is_empty() {
        if rest.starts_with("//") {
            break;
        }
        if let Some(quoted) = rest.strip_prefix('"') {
            let end = quoted
                .find('"')
                .ok_or(RtLightsError::UnterminatedString { line })?;
            out.push(&quoted[..end]);
            rest = &quoted[end + 1..];
        } else {
            let end = rest.find(char::is_whitespace).unwrap_or(rest.len());
            out.push(&rest[..end]);
            rest = &rest[end..];
        }
        rest = rest.trim_start();
    }
    Ok(out)
}

fn parse_line(text: &str, line: usize) -> Result<Option<RtLight>, RtLightsError> {
    let mut text = text.trim_start();
    let casts_shadows = match text.strip_prefix('!') {
        Some(rest) => {
            text = rest;
            false
        }
        None => true,
    };
    let fields = split_fields(text, line)?;
    if fields.is_empty() && casts_shadows {
        return Ok(None);
    }
    if let Some(extra) = fields.get(FIELDS.len()) {
        return Err(RtLightsError::ExtraField {
            line,
            text: extra.to_string(),
        });
    }
    let bad = |i: usize| RtLightsError::BadNumber {
        line,
        field: FIELDS[i],
        text: fields[i].to_string(),
    };
    // Field `i` as a finite float, or `default` when the line stops before it.
    let float = |i: usize, default: Option<f32>| -> Result<f32, RtLightsError> {
        match fields.get(i) {
            Some(t) => t
                .parse::<f32>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| bad(i)),
            None => default.ok_or(RtLightsError::MissingField {
                line,
                field: FIELDS[i],
            }),
        }
    };
    let vec3 = |i: usize, default: Option<f32>| -> Result<Vec3, RtLightsError> {
        Ok(Vec3::new(
            float(i, default)?,
            float(i + 1, default)?,
            float(i + 2, default)?,
        ))
    };
    let origin = vec3(0, None)?;
    let radius = float(3, None)?;
    // A light must reach somewhere: falloff divides by the radius.
    if radius <= 0.0 {
        return Err(bad(3));
    }
    let color = vec3(4, None)?;
    let style = match fields.get(7) {
        Some(t) => t.parse::<i32>().map_err(|_| bad(7))?,
        None => 0,
    };
    let cubemap = fields.get(8).map_or("", |c| *c).to_string();
    let flags = match fields.get(17) {
        Some(t) => t.parse::<u32>().map_err(|_| bad(17))?,
        // DarkPlaces' default for files written before the field existed.
        None => LIGHTFLAG_REALTIME_MODE,
    };
    Ok(Some(RtLight {
        line,
        origin,
        radius,
        color,
        style,
        cubemap,
        corona: float(9, Some(0.0))?,
        angles: vec3(10, Some(0.0))?,
        corona_size_scale: float(13, Some(0.25))?,
        ambient_scale: float(14, Some(0.0))?,
        diffuse_scale: float(15, Some(1.0))?,
        specular_scale: float(16, Some(1.0))?,
        flags,
        casts_shadows,
    }))
}

/// Parses a whole `.rtlights` file; the first bad line is the error.
pub fn parse_rtlights(text: &str) -> Result<Vec<RtLight>, RtLightsError> {
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        out.extend(parse_line(line, i + 1)?);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::LightKind;

    #[test]
    fn full_line_parses_exactly() {
        let lights = parse_rtlights("1160 504 88 400 1 1 1 0 \"\" 0 0 0 0 0.25 0 1 1 3\n").unwrap();
        assert_eq!(
            lights,
            [RtLight {
                line: 1,
                origin: Vec3::new(1160.0, 504.0, 88.0),
                radius: 400.0,
                color: Vec3::ONE,
                style: 0,
                cubemap: String::new(),
                corona: 0.0,
                angles: Vec3::ZERO,
                corona_size_scale: 0.25,
                ambient_scale: 0.0,
                diffuse_scale: 1.0,
                specular_scale: 1.0,
                flags: LIGHTFLAG_NORMAL_MODE | LIGHTFLAG_REALTIME_MODE,
                casts_shadows: true,
            }]
        );
        let l = lights[0].to_light("rt0");
        assert_eq!(l.name, "rt0");
        assert_eq!(l.kind, LightKind::Omni);
        assert_eq!(l.position, Vec3::new(1160.0, 504.0, 88.0));
        assert_eq!(l.radius, 400.0);
        assert_eq!(l.color, Vec3::ONE);
    }

    #[test]
    fn every_field_lands_in_its_place() {
        let text = "-1.5 2 3e2 250 2 0.5 1.25 7 \"cubemaps/a b\" 0.75 10 20 30 0.5 0.1 0.9 0.8 1";
        let l = &parse_rtlights(text).unwrap()[0];
        assert_eq!(l.origin, Vec3::new(-1.5, 2.0, 300.0));
        assert_eq!(l.color, Vec3::new(2.0, 0.5, 1.25));
        assert_eq!(l.style, 7);
        assert_eq!(l.cubemap, "cubemaps/a b");
        assert_eq!(l.corona, 0.75);
        assert_eq!(l.angles, Vec3::new(10.0, 20.0, 30.0));
        assert_eq!(
            (
                l.corona_size_scale,
                l.ambient_scale,
                l.diffuse_scale,
                l.specular_scale
            ),
            (0.5, 0.1, 0.9, 0.8)
        );
        assert_eq!(l.flags, LIGHTFLAG_NORMAL_MODE);
        // Overbright colour is kept.
        assert_eq!(l.to_light("x").color, Vec3::new(2.0, 0.5, 1.25));
    }

    #[test]
    fn bang_turns_shadows_off() {
        let lights = parse_rtlights(
            "!10 20 30 100 1 0.5 0.25 0 \"\" 0 0 0 0 0.25 0 1 1 3\n! 1 2 3 50 1 1 1",
        )
        .unwrap();
        assert_eq!(lights.len(), 2);
        assert!(!lights[0].casts_shadows && !lights[1].casts_shadows);
        assert_eq!(lights[0].origin, Vec3::new(10.0, 20.0, 30.0));
        assert_eq!(lights[0].color, Vec3::new(1.0, 0.5, 0.25));
        assert_eq!(lights[1].origin, Vec3::new(1.0, 2.0, 3.0));
    }

    #[test]
    fn short_line_takes_defaults_and_comments_are_skipped() {
        let text = "// a comment\n\n   \n8 16 -32 300 0.5 0.5 1 // trailing comment\n";
        let lights = parse_rtlights(text).unwrap();
        assert_eq!(lights.len(), 1);
        let l = &lights[0];
        assert_eq!(l.line, 4);
        assert_eq!(l.origin, Vec3::new(8.0, 16.0, -32.0));
        assert_eq!(l.radius, 300.0);
        assert_eq!(l.color, Vec3::new(0.5, 0.5, 1.0));
        assert_eq!(l.style, 0);
        assert_eq!(l.cubemap, "");
        assert_eq!(l.corona, 0.0);
        assert_eq!(l.angles, Vec3::ZERO);
        assert_eq!(l.corona_size_scale, 0.25);
        assert_eq!(l.ambient_scale, 0.0);
        assert_eq!(l.diffuse_scale, 1.0);
        assert_eq!(l.specular_scale, 1.0);
        assert_eq!(l.flags, LIGHTFLAG_REALTIME_MODE);
        assert!(l.casts_shadows);
    }

    #[test]
    fn errors_name_line_and_field() {
        let text = "1 2 3 100 1 1 1\n1 2 3 100 1 x 1\n";
        let err = parse_rtlights(text).unwrap_err();
        assert_eq!(
            err,
            RtLightsError::BadNumber {
                line: 2,
                field: "g",
                text: "x".to_string()
            }
        );
        assert_eq!(
            err.to_string(),
            "line 2: field `g`: `x` is not a valid number"
        );
        assert_eq!(
            parse_rtlights("1 2 3 100 1 1"),
            Err(RtLightsError::MissingField {
                line: 1,
                field: "b"
            })
        );
        assert!(matches!(
            parse_rtlights("1 2 3 0 1 1 1"),
            Err(RtLightsError::BadNumber {
                field: "radius",
                ..
            })
        ));
        assert!(matches!(
            parse_rtlights("1 2 3 10 1 1 1 0.5"),
            Err(RtLightsError::BadNumber { field: "style", .. })
        ));
        assert!(matches!(
            parse_rtlights("1 2 nan 10 1 1 1"),
            Err(RtLightsError::BadNumber { field: "z", .. })
        ));
        assert_eq!(
            parse_rtlights("\n\n1 2 3 10 1 1 1 0 \"open"),
            Err(RtLightsError::UnterminatedString { line: 3 })
        );
        assert!(matches!(
            parse_rtlights("1 2 3 10 1 1 1 0 \"\" 0 0 0 0 0.25 0 1 1 3 9"),
            Err(RtLightsError::ExtraField { line: 1, .. })
        ));
        assert_eq!(
            parse_rtlights("!"),
            Err(RtLightsError::MissingField {
                line: 1,
                field: "x"
            })
        );
    }
}
