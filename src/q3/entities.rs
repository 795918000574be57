//! The entity lump of a Quake 3 map: `{ "key" "value" ... }` blocks, and what shadowlab takes
//! from them (spawn points for cameras, `light` entities for lights).

use crate::scene::Light;
use glam::Vec3;
use thiserror::Error;

/// Why an entity lump could not be read. Lines are 1-based.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum EntityError {
    #[error("line {line}: string not closed on its line")]
    UnterminatedString { line: usize },
    #[error("line {line}: entity opened here is never closed")]
    UnterminatedBlock { line: usize },
    #[error("line {line}: expected `{{`, found `{found}`")]
    ExpectedOpen { line: usize, found: String },
    #[error("line {line}: `{{` inside an entity")]
    NestedBlock { line: usize },
    #[error("line {line}: key `{key}` has no value")]
    MissingValue { line: usize, key: String },
}

/// One entity: its key/value pairs in file order.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Entity {
    pub pairs: Vec<(String, String)>,
}

/// Whitespace-separated numbers, exactly `N` of them, all parsed.
fn parse_floats<const N: usize>(text: &str) -> Option<[f32; N]> {
    let mut out = [0.0; N];
    let mut words = text.split_whitespace();
    for v in &mut out {
        *v = words.next()?.parse().ok()?;
    }
    words.next().is_none().then_some(out)
}

impl Entity {
    /// The value of `key` (case-insensitive); the first one if the key repeats, as the game reads
    /// it.
    pub fn get(&self, key: &str) -> Option<&str> {
        self.pairs
            .iter()
            .find(|(k, _)| k.eq_ignore_ascii_case(key))
            .map(|(_, v)| v.as_str())
    }

    pub fn classname(&self) -> Option<&str> {
        self.get("classname")
    }

    /// `origin` as three numbers; `None` if missing or malformed (it may be non-finite).
    pub fn origin(&self) -> Option<Vec3> {
        parse_floats::<3>(self.get("origin")?).map(Vec3::from_array)
    }

    /// Yaw in degrees: `angle`, else the second of `angles` ("pitch yaw roll").
    pub fn angle(&self) -> Option<f32> {
        if let Some(a) = self.get("angle").and_then(|a| a.trim().parse().ok()) {
            return Some(a);
        }
        parse_floats::<3>(self.get("angles")?).map(|[_, yaw, _]| yaw)
    }

    fn is(&self, classname: &str) -> bool {
        self.classname()
            .is_some_and(|c| c.eq_ignore_ascii_case(classname))
    }
}

#[derive(Debug, PartialEq)]
enum Tok<'a> {
    Open,
    Close,
    Str(&'a str),
}

/// Reads the next token: `{`, `}`, a quoted string (on one line) or a bare word. Skips whitespace
/// and `//` comments; a NUL ends the text (lumps are NUL-terminated).
fn next_token<'a>(
    text: &'a str,
    pos: &mut usize,
    line: &mut usize,
) -> Result<Option<(Tok<'a>, usize)>, EntityError> {
    let b = text.as_bytes();
    // Only ASCII bytes are ever sliced at, so the slices are on char boundaries.
    loop {
        let Some(&c) = b.get(*pos) else {
            return Ok(None);
        };
        match c {
            0 => return Ok(None),
            b'\n' => {
                *line += 1;
                *pos += 1;
            }
            c if c <= b' ' => *pos += 1,
            b'/' if b.get(*pos + 1) == Some(&b'/') => {
                while *pos < b.len() && b[*pos] != b'\n' {
                    *pos += 1;
                }
            }
            b'{' => {
                *pos += 1;
                return Ok(Some((Tok::Open, *line)));
            }
            b'}' => {
                *pos += 1;
                return Ok(Some((Tok::Close, *line)));
            }
            b'"' => {
                let start = *pos + 1;
                let mut j = start;
                while j < b.len() && !matches!(b[j], b'"' | b'\n' | 0) {
                    j += 1;
                }
                if b.get(j) != Some(&b'"') {
                    return Err(EntityError::UnterminatedString { line: *line });
                }
                *pos = j + 1;
                return Ok(Some((Tok::Str(&text[start..j]), *line)));
            }
            _ => {
                let start = *pos;
                while *pos < b.len() && b[*pos] > b' ' && !matches!(b[*pos], b'{' | b'}' | b'"') {
                    *pos += 1;
                }
                return Ok(Some((Tok::Str(&text[start..*pos]), *line)));
            }
        }
    }
}

/// Parses an entity lump. Strict about structure (the compiler wrote it), tolerant of `//`
/// comments, bare words for keys or values, and a trailing NUL.
pub fn parse_entities(text: &str) -> Result<Vec<Entity>, EntityError> {
    let (mut pos, mut line) = (0, 1);
    let mut out = Vec::new();
    while let Some((tok, open_line)) = next_token(text, &mut pos, &mut line)? {
        match tok {
            Tok::Open => {}
            Tok::Close => {
                return Err(EntityError::ExpectedOpen {
                    line: open_line,
                    found: "}".to_string(),
                });
            }
            Tok::Str(s) => {
                return Err(EntityError::ExpectedOpen {
                    line: open_line,
                    found: s.to_string(),
                });
            }
        }
        let mut entity = Entity::default();
        loop {
            let key = match next_token(text, &mut pos, &mut line)? {
                None => return Err(EntityError::UnterminatedBlock { line: open_line }),
                Some((Tok::Close, _)) => break,
                Some((Tok::Open, l)) => return Err(EntityError::NestedBlock { line: l }),
                Some((Tok::Str(k), l)) => (k, l),
            };
            match next_token(text, &mut pos, &mut line)? {
                Some((Tok::Str(v), _)) => entity.pairs.push((key.0.to_string(), v.to_string())),
                Some((Tok::Open, l)) => return Err(EntityError::NestedBlock { line: l }),
                Some((Tok::Close, _)) | None => {
                    return Err(EntityError::MissingValue {
                        line: key.1,
                        key: key.0.to_string(),
                    });
                }
            }
        }
        out.push(entity);
    }
    Ok(out)
}

/// Where players spawn: candidate camera positions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpawnPoint {
    pub origin: Vec3,
    /// Facing, degrees counter-clockwise from +X.
    pub yaw_deg: f32,
}

/// `info_player_deathmatch` and `info_player_start` entities with a finite origin, in entity
/// order. A missing or malformed yaw is 0.
pub fn spawn_points(ents: &[Entity]) -> Vec<SpawnPoint> {
    ents.iter()
        .filter(|e| e.is("info_player_deathmatch") || e.is("info_player_start"))
        .filter_map(|e| {
            let origin = e.origin().filter(|o| o.is_finite())?;
            let yaw_deg = e.angle().filter(|a| a.is_finite()).unwrap_or(0.0);
            Some(SpawnPoint { origin, yaw_deg })
        })
        .collect()
}

/// How far above a spawn point or item a placed light sits (a little over a player's eye
/// height of 56, so the player model and the item cast shadows below it).
pub const PLACED_LIGHT_HEIGHT: f32 = 64.0;
/// A placed light's radius: about a room of an arena map.
pub const PLACED_LIGHT_RADIUS: f32 = 400.0;

/// Whether an entity is one a player picks up (Quake 3's item classes).
fn is_item(e: &Entity) -> bool {
    e.classname().is_some_and(|c| {
        let c = c.to_ascii_lowercase();
        ["item_", "weapon_", "ammo_", "holdable_"]
            .iter()
            .any(|p| c.starts_with(p))
    })
}

/// One white omni light above each spawn point and item, for maps whose light entities were
/// compiled away: named `placed0`, `placed1`, … in entity order.
pub fn placed_lights(ents: &[Entity]) -> Vec<Light> {
    ents.iter()
        .filter(|e| {
            e.is("info_player_deathmatch")
                || e.is("info_player_start")
                || e.classname()
                    .is_some_and(|c| c.to_ascii_lowercase().starts_with("team_ctf_"))
                    && e.classname()
                        .is_some_and(|c| c.to_ascii_lowercase().contains("spawn"))
                || is_item(e)
        })
        .filter_map(|e| e.origin().filter(|o| o.is_finite()))
        .enumerate()
        .map(|(i, origin)| {
            Light::omni(
                &format!("placed{i}"),
                origin + Vec3::Z * PLACED_LIGHT_HEIGHT,
                PLACED_LIGHT_RADIUS,
            )
        })
        .collect()
}

/// Quake 3's default `light` value.
pub const DEFAULT_LIGHT_INTENSITY: f32 = 300.0;
/// Quake 3's default spot cone radius at the target (`radius` key).
pub const DEFAULT_SPOT_RADIUS: f32 = 64.0;

/// The `light` entities as dynamic lights, named `light0`, `light1`, ... in entity order over the
/// lights kept.
///
/// - The intensity (`light`, or q3map2's `_light`; default 300) becomes the light's radius:
///   DarkPlaces' convention for Quake 3 maps, which have no radius of their own.
/// - `_color` is scaled so its largest component is 1; white if missing or unusable.
/// - With a `target` naming another entity's `targetname`, the light is a spot aimed at that
///   entity's origin, its cone half-angle atan(spot radius / distance), with the spot radius the
///   `radius` key (default 64, Quake 3's), clamped to 1°..=89°. Otherwise it is omni.
/// - Lights without a finite origin, or with a zero, negative or malformed intensity, are
///   skipped.
pub fn light_entities(ents: &[Entity]) -> Vec<Light> {
    let mut out = Vec::new();
    for e in ents.iter().filter(|e| e.is("light")) {
        let Some(origin) = e.origin().filter(|o| o.is_finite()) else {
            log::debug!("light entity without a usable origin skipped");
            continue;
        };
        let intensity = match e.get("light").or_else(|| e.get("_light")) {
            None => DEFAULT_LIGHT_INTENSITY,
            Some(v) => match v.trim().parse::<f32>() {
                Ok(i) if i.is_finite() && i > 0.0 => i,
                _ => {
                    log::debug!("light at {origin} with intensity `{v}` skipped");
                    continue;
                }
            },
        };
        let color = e
            .get("_color")
            .and_then(parse_floats::<3>)
            .map(Vec3::from_array)
            .filter(|c| c.is_finite() && c.min_element() >= 0.0 && c.max_element() > 0.0)
            .map_or(Vec3::ONE, |c| c / c.max_element());
        let target = e
            .get("target")
            .and_then(|t| {
                ents.iter().find(|o| {
                    o.get("targetname")
                        .is_some_and(|n| n.eq_ignore_ascii_case(t))
                })
            })
            .and_then(Entity::origin)
            .filter(|t| t.is_finite() && t.distance(origin) > 1e-3);
        let name = format!("light{}", out.len());
        let mut light = match target {
            Some(target) => {
                let spot_radius = e
                    .get("radius")
                    .and_then(|r| r.trim().parse::<f32>().ok())
                    .filter(|r| r.is_finite() && *r > 0.0)
                    .unwrap_or(DEFAULT_SPOT_RADIUS);
                let cutoff = (spot_radius / target.distance(origin))
                    .atan()
                    .to_degrees()
                    .clamp(1.0, 89.0);
                Light::spot(&name, origin, target, cutoff, intensity)
            }
            None => Light::omni(&name, origin, intensity),
        };
        light.color = color;
        out.push(light);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::LightKind;

    const LUMP: &str = r#"{
"classname" "worldspawn"
"message" "Test { map }"
}
// a comment between entities
{
"classname" "info_player_deathmatch"
"origin" "10 20 30"
"angle" "90"
}
{
"classname" "info_player_start"
"origin" "-1 -2 -3"
"angles" "0 45 0"
}
{
"classname" "info_player_deathmatch"
"origin" "0 0 0"
}
{
"classname" "info_player_deathmatch"
"origin" "broken"
}
{
"classname" "light"
"origin" "0 0 100"
"target" "spot1"
"light" "500"
}
{
"classname" "info_null"
"targetname" "spot1"
"origin" "0 0 0"
}
{
"classname" "light"
"origin" "5 5 5"
"_color" "0.5 0.25 0"
}
{
"classname" "light"
"origin" "7 7 7"
"light" "0"
}
{
"classname" "light"
"light" "200"
}
{
"classname" "light"
"origin" "1 2 3"
"target" "nowhere"
"light" "150"
}
"#;

    #[test]
    fn parses_pairs_and_comments() {
        let ents = parse_entities(&format!("{LUMP}\0")).unwrap();
        assert_eq!(ents.len(), 11);
        assert_eq!(ents[0].classname(), Some("worldspawn"));
        assert_eq!(ents[0].get("MESSAGE"), Some("Test { map }"));
        assert_eq!(ents[1].origin(), Some(Vec3::new(10.0, 20.0, 30.0)));
        assert_eq!(ents[1].angle(), Some(90.0));
        assert_eq!(ents[2].angle(), Some(45.0));
        assert_eq!(ents[3].angle(), None);
        assert_eq!(ents[4].origin(), None);
    }

    #[test]
    fn placed_lights_sit_above_spawn_points_and_items_only() {
        let ents = parse_entities(
            "{\n\"classname\" \"info_player_deathmatch\"\n\"origin\" \"0 0 0\"\n}\n\
             {\n\"classname\" \"weapon_rocketlauncher\"\n\"origin\" \"100 0 8\"\n}\n\
             {\n\"classname\" \"misc_model\"\n\"origin\" \"5 5 5\"\n}\n\
             {\n\"classname\" \"item_armor_body\"\n\"origin\" \"nan 0 0\"\n}\n",
        )
        .unwrap();
        let lights = placed_lights(&ents);
        let at: Vec<Vec3> = lights.iter().map(|l| l.position).collect();
        assert_eq!(at, [Vec3::new(0.0, 0.0, 64.0), Vec3::new(100.0, 0.0, 72.0)]);
        assert_eq!(lights[1].name, "placed1");
    }

    #[test]
    fn spawn_points_in_order_with_yaw() {
        let ents = parse_entities(LUMP).unwrap();
        let spawns = spawn_points(&ents);
        assert_eq!(
            spawns,
            [
                SpawnPoint {
                    origin: Vec3::new(10.0, 20.0, 30.0),
                    yaw_deg: 90.0
                },
                SpawnPoint {
                    origin: Vec3::new(-1.0, -2.0, -3.0),
                    yaw_deg: 45.0
                },
                SpawnPoint {
                    origin: Vec3::ZERO,
                    yaw_deg: 0.0
                },
            ]
        );
    }

    #[test]
    fn targeted_light_is_a_spot() {
        let ents = parse_entities(LUMP).unwrap();
        let lights = light_entities(&ents);
        let names: Vec<&str> = lights.iter().map(|l| l.name.as_str()).collect();
        assert_eq!(names, ["light0", "light1", "light2"]);
        let spot = &lights[0];
        assert_eq!(spot.position, Vec3::new(0.0, 0.0, 100.0));
        assert_eq!(spot.radius, 500.0);
        assert_eq!(spot.color, Vec3::ONE);
        let LightKind::Spot {
            direction,
            cutoff_deg,
        } = spot.kind
        else {
            panic!("not a spot: {spot:?}");
        };
        assert_eq!(direction, Vec3::new(0.0, 0.0, -1.0));
        assert!((cutoff_deg - 0.64f32.atan().to_degrees()).abs() < 1e-4);
        assert!((cutoff_deg - 32.62).abs() < 0.01);
    }

    #[test]
    fn omni_light_colour_and_defaults() {
        let ents = parse_entities(LUMP).unwrap();
        let lights = light_entities(&ents);
        let coloured = &lights[1];
        assert_eq!(coloured.kind, LightKind::Omni);
        assert_eq!(coloured.position, Vec3::splat(5.0));
        assert_eq!(coloured.color, Vec3::new(1.0, 0.5, 0.0));
        assert_eq!(coloured.radius, DEFAULT_LIGHT_INTENSITY);
        // A target that names nothing leaves an omni light.
        assert_eq!(lights[2].kind, LightKind::Omni);
        assert_eq!(lights[2].radius, 150.0);
    }

    #[test]
    fn spot_cone_uses_radius_key_and_is_clamped() {
        let text = r#"
{ "classname" "light" "origin" "0 0 0" "target" "t" "radius" "1e9" }
{ "classname" "light" "origin" "0 0 0" "target" "t" "radius" "100" }
{ "classname" "target_position" "targetname" "T" "origin" "100 0 0" }
"#;
        let lights = light_entities(&parse_entities(text).unwrap());
        let cutoffs: Vec<f32> = lights
            .iter()
            .map(|l| match l.kind {
                LightKind::Spot { cutoff_deg, .. } => cutoff_deg,
                LightKind::Omni => f32::NAN,
            })
            .collect();
        assert_eq!(cutoffs[0], 89.0);
        assert!((cutoffs[1] - 45.0).abs() < 1e-4);
    }

    #[test]
    fn malformed_text_is_an_error_with_its_line() {
        assert_eq!(
            parse_entities("{\n\"classname\" \"light\n}\n"),
            Err(EntityError::UnterminatedString { line: 2 })
        );
        assert_eq!(
            parse_entities("{ \"a\" \"b\" }\n\n{\n\"classname\" \"light\"\n"),
            Err(EntityError::UnterminatedBlock { line: 3 })
        );
        assert_eq!(
            parse_entities("{\n\"a\" \"b\"\n\"key\"\n}"),
            Err(EntityError::MissingValue {
                line: 3,
                key: "key".to_string()
            })
        );
        assert_eq!(
            parse_entities("{\n}\n}"),
            Err(EntityError::ExpectedOpen {
                line: 3,
                found: "}".to_string()
            })
        );
        assert_eq!(
            parse_entities("{\n\"a\" {\n}"),
            Err(EntityError::NestedBlock { line: 2 })
        );
        let e = parse_entities("{\n\"a\" \"b").unwrap_err();
        assert_eq!(e.to_string(), "line 2: string not closed on its line");
    }

    #[test]
    fn empty_and_nul_terminated_lumps() {
        assert_eq!(parse_entities(""), Ok(vec![]));
        assert_eq!(parse_entities("\0garbage after the end"), Ok(vec![]));
        assert_eq!(parse_entities("{}\n\0").unwrap().len(), 1);
    }
}
