//! Scene files (TOML): a Quake 3 map or the built-in room, a camera, lights, models and option
//! overrides. `assets/scenes/` holds the benchmark scenes.
//!
//! ```toml
//! name = "oa_dm1"
//! flythrough = "../paths/oa_dm1.path"  # the camera path `bench` takes by default
//! [map]
//! bsp = "maps/oa_dm1.bsp"        # path inside the data set
//! # data = "/somewhere"           # default: $SHADOWLAB_DATA or ~/.cache/shadowlab/openarena
//! # paks = ["baseoa/pak0.pk3"]    # default: every baseoa/*.pk3, later names override earlier
//! [camera]
//! spawn = 0                       # the map's first spawn point, eye 26 units up, its yaw
//! # position = [x, y, z]  yaw = 90  pitch = -10  target = [x, y, z]  fov = 90  near = 4
//! [lights]
//! from = "none"                   # or "entities" (the map's light entities) or "rtlights"
//! # rtlights = "oa_dm3.rtlights"  # a DarkPlaces file, relative to this scene file
//! # exclude = ["light0"]          # drop these lights of the map (by name)
//! [[light]]
//! kind = "spot"                   # or "omni"
//! position = [0, 0, 100]
//! target = [0, 0, 0]              # or direction = [0, 0, -1]
//! cutoff = 40                     # spot half-angle, degrees (0..180)
//! radius = 800                    # range
//! color = [1, 1, 1]
//! [[light_motion]]
//! light = "light0"                # any light of the scene, by name (the map's too)
//! orbit = { centre = [0, 0, 0], period = 6 }   # circling the vertical through centre
//! #                                             (or radius = 40 instead of centre),
//! # route = [[0, 0, 100], [200, 0, 100]]  speed = 100   # or along a closed route,
//! # flicker = { amount = 0.4, rate = 6 }                 # or in place, its brightness varying
//! [[model]]                       # needs [map], or base = "empty" (read from the default data)
//! player = "sarge"                # or md3 = "models/..."; skin = "default"; frame = 0
//! position = [0, 0, 24]
//! yaw = 90
//! # animation = "run"             # a player's legs animation (torso_animation: default stand)
//! # route = [[0, 0, 24], [300, 0, 24]]  speed = 150   # walked in a loop, facing the way
//! [options]
//! "shadow_map.size" = 1024
//! ```

pub mod load;

use crate::options::Options;
use crate::q3::builder::SceneBuilder;
use crate::q3::entities::{self, Entity, SpawnPoint};
use crate::q3::md3::AnimationId;
use crate::q3::model::{self, ModelError};
use crate::q3::pk3::{self, Vfs, VfsError};
use crate::q3::rtlights;
use crate::q3::shader::ShaderLibrary;
use crate::q3::world::{self, MapCounts, MapError};
use crate::scene::authored::ShapeSection;
use crate::scene::motion::{LightMotion, LightPath, Route, Walk};
use crate::scene::{Camera, Light, LightKind, Scene, builtin};
use glam::{Mat4, Vec3};
use serde::Deserialize;
use std::path::{Path, PathBuf};
use std::time::Instant;
use thiserror::Error;

#[derive(Debug, Error)]
pub enum SceneFileError {
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: {message}")]
    Toml { path: PathBuf, message: String },
    #[error("{path}: {message}")]
    Invalid { path: PathBuf, message: String },
    #[error(transparent)]
    Vfs(#[from] VfsError),
    #[error(transparent)]
    Map(#[from] MapError),
    #[error(transparent)]
    Model(#[from] ModelError),
}

#[derive(Debug, Clone, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct MapSection {
    pub bsp: String,
    pub data: Option<PathBuf>,
    pub paks: Option<Vec<PathBuf>>,
}

#[derive(Debug, Clone, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct CameraSection {
    pub spawn: Option<usize>,
    pub position: Option<[f32; 3]>,
    pub target: Option<[f32; 3]>,
    pub yaw: Option<f32>,
    pub pitch: Option<f32>,
    pub fov: Option<f32>,
    pub near: Option<f32>,
}

#[derive(Debug, Clone, Copy, Deserialize, Default, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum LightSource {
    /// Only the `[[light]]` entries.
    #[default]
    None,
    /// The map's `light` entities.
    Entities,
    /// A DarkPlaces `.rtlights` file.
    Rtlights,
    /// One omni light above each spawn point and item (`q3::entities::placed_lights`).
    Placed,
    /// The map's `light` entities, or placed lights where it has none (Quake 3's compiler
    /// usually strips them).
    EntitiesOrPlaced,
}

#[derive(Debug, Clone, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct LightsSection {
    #[serde(default)]
    pub from: LightSource,
    pub rtlights: Option<PathBuf>,
    /// Lights of the map (entities or rtlights) to leave out, by name.
    #[serde(default)]
    pub exclude: Vec<String>,
}

#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum LightKindName {
    Spot,
    Omni,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightSection {
    pub name: Option<String>,
    pub kind: LightKindName,
    pub position: [f32; 3],
    pub target: Option<[f32; 3]>,
    pub direction: Option<[f32; 3]>,
    pub cutoff: Option<f32>,
    pub radius: f32,
    pub color: Option<[f32; 3]>,
}

/// How one light of the scene moves (give one of `orbit`, `route` and `flicker`). A spot
/// with a `target` keeps pointing at it.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightMotionSection {
    /// The light's name (`[[light]] name`, or a map light's: `light0`, `rt0`, …).
    pub light: String,
    /// Moves in a horizontal circle.
    pub orbit: Option<OrbitSection>,
    /// Moves along these points in a closed loop at `speed`.
    pub route: Option<Vec<[f32; 3]>>,
    /// Units per second along `route` (default 100).
    pub speed: Option<f32>,
    /// Stays put, its brightness varying.
    pub flicker: Option<FlickerSection>,
}

/// A light's circle, starting from the light's position (which sets its height), once every
/// `period` seconds: about the vertical line through `centre`, or of `radius` about the line
/// that far along -X from the light (for map lights, whose positions the file does not hold).
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OrbitSection {
    pub centre: Option<[f32; 3]>,
    pub radius: Option<f32>,
    pub period: f32,
}

/// A light's flicker: brightness between `1 - amount` and 1, about `rate` times a second.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FlickerSection {
    pub amount: f32,
    pub rate: f32,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelSection {
    pub player: Option<String>,
    pub md3: Option<String>,
    pub skin: Option<String>,
    pub position: [f32; 3],
    #[serde(default)]
    pub yaw: f32,
    /// Frame of a single MD3.
    pub frame: Option<usize>,
    /// Legs and torso frames of a player (default: idle legs, standing torso).
    pub legs_frame: Option<usize>,
    pub torso_frame: Option<usize>,
    /// A player's legs animation, played in a loop (`run`, `walk`, `idle`, …: the names of
    /// `animation.cfg` without `LEGS_`).
    pub animation: Option<String>,
    /// The torso's animation with `animation` (default `stand`).
    pub torso_animation: Option<String>,
    /// Points the model walks in a closed loop, facing the way it goes (its origin on them).
    pub route: Option<Vec<[f32; 3]>>,
    /// Units per second along `route` (default 150; Quake 3 runs at 320).
    pub speed: Option<f32>,
}

/// A parsed scene file.
#[derive(Debug, Clone, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    pub name: Option<String>,
    /// The scene's recorded camera path (relative to the file): `bench` takes it when given
    /// no `--path`.
    pub flythrough: Option<PathBuf>,
    /// The Quake 3 map; without one the scene is `base`.
    pub map: Option<MapSection>,
    /// Without a map: the built-in room (default) or nothing, for scenes made of `[[shape]]`s.
    #[serde(default)]
    pub base: Base,
    /// Geometry written in the file (see `scene/authored.rs`).
    #[serde(default)]
    pub shape: Vec<ShapeSection>,
    #[serde(default)]
    pub camera: CameraSection,
    #[serde(default)]
    pub lights: LightsSection,
    #[serde(default)]
    pub light: Vec<LightSection>,
    #[serde(default)]
    pub light_motion: Vec<LightMotionSection>,
    #[serde(default)]
    pub model: Vec<ModelSection>,
    /// Option overrides, as `shadowlab options` lists them.
    #[serde(default)]
    pub options: toml::Table,
    #[serde(skip)]
    pub path: PathBuf,
}

/// The scene a file without a map starts from.
#[derive(Debug, Clone, Copy, Deserialize, Default, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum Base {
    #[default]
    Builtin,
    Empty,
}

/// What loading found besides the scene.
#[derive(Debug, Clone, Default)]
pub struct LoadReport {
    pub counts: Option<MapCounts>,
    /// The scene file's `flythrough`, resolved against the file's folder.
    pub flythrough: Option<PathBuf>,
    pub warnings: Vec<String>,
    pub load_ms: f64,
}

/// Most points a route may hold.
pub const MAX_ROUTE_POINTS: usize = 4096;

fn finite3(v: [f32; 3]) -> bool {
    v.iter().all(|x| x.is_finite())
}

impl SceneFile {
    pub fn read(path: &Path) -> Result<SceneFile, SceneFileError> {
        let text = std::fs::read_to_string(path).map_err(|source| SceneFileError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        SceneFile::parse(&text, path)
    }

    /// Parses a scene file's text; `path` names it in errors and anchors its relative paths.
    pub fn parse(text: &str, path: &Path) -> Result<SceneFile, SceneFileError> {
        let mut f: SceneFile = toml::from_str(text).map_err(|e| SceneFileError::Toml {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
        f.path = path.to_path_buf();
        Ok(f)
    }

    fn invalid(&self, message: impl Into<String>) -> SceneFileError {
        SceneFileError::Invalid {
            path: self.path.clone(),
            message: message.into(),
        }
    }

    fn relative(&self, p: &Path) -> PathBuf {
        if p.is_absolute() {
            p.to_path_buf()
        } else {
            self.path.parent().unwrap_or(Path::new(".")).join(p)
        }
    }

    fn light(&self, i: usize, l: &LightSection) -> Result<Light, SceneFileError> {
        let name = l.name.clone().unwrap_or_else(|| format!("light{i}"));
        if !(finite3(l.position) && l.radius.is_finite() && l.radius > 0.0) {
            return Err(self.invalid(format!(
                "[[light]] {name}: position and radius > 0 must be finite numbers"
            )));
        }
        let position = Vec3::from_array(l.position);
        let color = Vec3::from_array(l.color.unwrap_or([1.0; 3]));
        let kind = match l.kind {
            LightKindName::Omni => LightKind::Omni,
            LightKindName::Spot => {
                let dir = match (l.target, l.direction) {
                    (Some(t), _) => Vec3::from_array(t) - position,
                    (None, Some(d)) => Vec3::from_array(d),
                    (None, None) => {
                        return Err(self.invalid(format!(
                            "[[light]] {name}: a spot needs target or direction"
                        )));
                    }
                };
                let cutoff = l.cutoff.unwrap_or(45.0);
                if !(dir.length_squared() > 0.0
                    && dir.is_finite()
                    && cutoff > 0.0
                    && cutoff < 180.0)
                {
                    return Err(self.invalid(format!(
                        "[[light]] {name}: the direction must be non-zero and the cutoff within (0, 180) degrees"
                    )));
                }
                LightKind::Spot {
                    direction: dir.normalize(),
                    cutoff_deg: cutoff,
                }
            }
        };
        Ok(Light {
            name,
            kind,
            position,
            color,
            radius: l.radius,
        })
    }

    /// The motion `[[light_motion]]` `l` gives its light.
    fn light_motion(
        &self,
        scene: &Scene,
        l: &LightMotionSection,
    ) -> Result<LightMotion, SceneFileError> {
        let name = &l.light;
        let index = scene
            .lights
            .iter()
            .position(|x| &x.name == name)
            .ok_or_else(|| {
                let names: Vec<&str> = scene.lights.iter().map(|x| x.name.as_str()).collect();
                self.invalid(format!(
                    "[[light_motion]] names `{name}`, which is none of the scene's lights ({})",
                    names.join(", ")
                ))
            })?;
        let light = &scene.lights[index];
        let path = match (l.orbit, &l.route, l.flicker) {
            (Some(o), None, None) => {
                let centre = match (o.centre, o.radius) {
                    (Some(c), None) if finite3(c) => Some(Vec3::from_array(c)),
                    (None, Some(r)) if r.is_finite() => Some(light.position - Vec3::X * r),
                    _ => None,
                };
                let (Some(centre), true) = (centre, o.period.is_finite() && o.period > 0.0) else {
                    return Err(self.invalid(format!(
                        "[[light_motion]] {name}: orbit needs one finite centre or radius, and \
                         a period > 0"
                    )));
                };
                LightPath::Orbit {
                    centre,
                    start: light.position,
                    period: o.period,
                }
            }
            (None, Some(points), None) => LightPath::Route(self.route(
                &format!("[[light_motion]] {name}"),
                points,
                l.speed.unwrap_or(100.0),
            )?),
            (None, None, Some(f)) => {
                if !(f.amount.is_finite() && f.rate.is_finite()) {
                    return Err(self.invalid(format!(
                        "[[light_motion]] {name}: flicker needs finite amount and rate"
                    )));
                }
                LightPath::Flicker {
                    amount: f.amount,
                    rate: f.rate,
                }
            }
            _ => {
                return Err(self.invalid(format!(
                    "[[light_motion]] {name}: give one of orbit, route and flicker"
                )));
            }
        };
        // A spot keeps pointing where it pointed from its start.
        let aim = match light.kind {
            LightKind::Spot { direction, .. } => Some(light.position + direction * light.radius),
            LightKind::Omni => None,
        };
        Ok(LightMotion {
            light: index,
            path,
            aim,
            color: light.color,
        })
    }

    /// A route of `what`: at least two finite points, a finite speed >= 0, at most
    /// [`MAX_ROUTE_POINTS`].
    fn route(&self, what: &str, points: &[[f32; 3]], speed: f32) -> Result<Route, SceneFileError> {
        if points.len() < 2 || points.len() > MAX_ROUTE_POINTS {
            return Err(self.invalid(format!(
                "{what}: a route needs 2 to {MAX_ROUTE_POINTS} points, not {}",
                points.len()
            )));
        }
        if !(points.iter().all(|p| finite3(*p)) && speed.is_finite() && speed >= 0.0) {
            return Err(self.invalid(format!(
                "{what}: route points and speed must be finite (speed >= 0)"
            )));
        }
        Ok(Route {
            points: points.iter().map(|p| Vec3::from_array(*p)).collect(),
            speed,
        })
    }

    fn vfs(&self, map: &MapSection) -> Result<Vfs, SceneFileError> {
        let data = map
            .data
            .as_ref()
            .map(|d| self.relative(d))
            .unwrap_or_else(pk3::data_dir);
        match &map.paks {
            None => Ok(Vfs::open_data_dir(&data)?),
            Some(paks) => {
                let mut vfs = Vfs::new();
                for p in paks {
                    let full = data.join(p);
                    if !full.exists() {
                        return Err(VfsError::NoData(data.clone()).into());
                    }
                    vfs.add_pk3(&full)?;
                }
                Ok(vfs)
            }
        }
    }

    /// Builds the scene with `options` (which decide how maps are tessellated and lit).
    pub fn build(&self, options: &Options) -> Result<(Scene, LoadReport), SceneFileError> {
        let start = Instant::now();
        let mut report = LoadReport::default();
        let mut scene = match &self.map {
            None if self.model.is_empty() => match self.base {
                Base::Builtin => builtin::default_scene(),
                Base::Empty => Scene::named("empty"),
            },
            None => match self.base {
                // The built-in room's materials are not the model loader's.
                Base::Builtin => {
                    return Err(self.invalid(
                        "[[model]] needs a [map] or base = \"empty\" (the built-in room takes \
                         no models)",
                    ));
                }
                Base::Empty => self.build_models_alone(options, &mut report)?,
            },
            Some(map) => self.build_map(map, options, &mut report)?,
        };
        for (i, shape) in self.shape.iter().enumerate() {
            shape.add_to(i, &mut scene).map_err(|m| self.invalid(m))?;
        }
        self.apply_camera(&mut scene.camera)?;
        for (i, l) in self.light.iter().enumerate() {
            let light = self.light(i, l)?;
            scene.lights.push(light);
        }
        for m in &self.light_motion {
            let motion = self.light_motion(&scene, m)?;
            scene.motion.lights.push(motion);
        }
        if let Some(n) = &self.name {
            scene.name = n.clone();
        }
        settle_placed_lights(&mut scene);
        // The scene as loaded is the scene at t = 0.
        scene.pose_at(0.0);
        warn_of_lights_in_solid(&scene, &mut report);
        scene.options = self.options.clone();
        report.flythrough = self.flythrough.as_ref().map(|p| self.relative(p));
        report.load_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok((scene, report))
    }

    /// The scene of `[map]`: the world, the map's lights the file asks for, the `[[model]]`s,
    /// the camera at a spawn point when `[camera] spawn` names one.
    fn build_map(
        &self,
        map: &MapSection,
        options: &Options,
        report: &mut LoadReport,
    ) -> Result<Scene, SceneFileError> {
        let vfs = self.vfs(map)?;
        let shaders = load_shader_library(&vfs, &mut report.warnings);
        let mut builder = SceneBuilder::new(&world::map_name(&map.bsp), &shaders);
        let info = world::load_map(&mut builder, &vfs, &map.bsp, &options.q3)?;
        report.warnings.extend(info.warnings.iter().cloned());
        let mut lights = self.map_lights(&info.entities)?;
        builder.scene.lights.append(&mut lights);
        for (i, m) in self.model.iter().enumerate() {
            self.add_model(&mut builder, &vfs, i, m)?;
        }
        let (mut scene, missing) = builder.finish(&vfs, options.q3.progress);
        warn_of_missing_textures(&missing, report);
        scene.camera = self.spawn_camera(&info.spawns)?;
        report.counts = Some(info.counts);
        Ok(scene)
    }

    /// An empty scene with the `[[model]]`s, read from the default data set (no `[map]` names
    /// another).
    fn build_models_alone(
        &self,
        options: &Options,
        report: &mut LoadReport,
    ) -> Result<Scene, SceneFileError> {
        let vfs = Vfs::open_data_dir(&pk3::data_dir())?;
        let shaders = load_shader_library(&vfs, &mut report.warnings);
        let mut builder = SceneBuilder::new("empty", &shaders);
        for (i, m) in self.model.iter().enumerate() {
            self.add_model(&mut builder, &vfs, i, m)?;
        }
        let (scene, missing) = builder.finish(&vfs, options.q3.progress);
        warn_of_missing_textures(&missing, report);
        Ok(scene)
    }

    /// The map's lights `[lights]` asks for (from its entities or an `.rtlights` file), less
    /// those it excludes.
    fn map_lights(&self, map_entities: &[Entity]) -> Result<Vec<Light>, SceneFileError> {
        let mut lights = match self.lights.from {
            LightSource::None => Vec::new(),
            LightSource::Entities => entities::light_entities(map_entities),
            LightSource::Rtlights => self.rtlights()?,
            LightSource::Placed => entities::placed_lights(map_entities),
            LightSource::EntitiesOrPlaced => match entities::light_entities(map_entities) {
                found if found.is_empty() => entities::placed_lights(map_entities),
                found => found,
            },
        };
        for name in &self.lights.exclude {
            if !lights.iter().any(|l| &l.name == name) {
                return Err(self.invalid(format!(
                    "[lights] exclude names `{name}`, which the map's lights do not have"
                )));
            }
        }
        lights.retain(|l| !self.lights.exclude.contains(&l.name));
        Ok(lights)
    }

    /// The lights of `[lights] rtlights`, named `rt0`, `rt1`, …
    fn rtlights(&self) -> Result<Vec<Light>, SceneFileError> {
        let file = self.lights.rtlights.as_ref().ok_or_else(|| {
            self.invalid("[lights] from = \"rtlights\" needs rtlights = \"FILE\"")
        })?;
        let path = self.relative(file);
        let text = std::fs::read_to_string(&path).map_err(|source| SceneFileError::Io {
            path: path.clone(),
            source,
        })?;
        Ok(rtlights::parse_rtlights(&text)
            .map_err(|e| SceneFileError::Invalid {
                path,
                message: e.to_string(),
            })?
            .iter()
            .enumerate()
            .map(|(i, l)| l.to_light(&format!("rt{i}")))
            .collect())
    }

    /// Adds `[[model]]` number `i`, a player or a single MD3.
    fn add_model(
        &self,
        builder: &mut SceneBuilder,
        vfs: &Vfs,
        i: usize,
        m: &ModelSection,
    ) -> Result<(), SceneFileError> {
        if !finite3(m.position) || !m.yaw.is_finite() {
            return Err(self.invalid(format!("[[model]] {i}: position and yaw must be finite")));
        }
        let transform = Mat4::from_translation(Vec3::from_array(m.position))
            * Mat4::from_rotation_z(m.yaw.to_radians());
        let index = match (&m.player, &m.md3) {
            (Some(p), None) => {
                let skin = m.skin.as_deref().unwrap_or("default");
                match self.player_animations(i, m)? {
                    Some(clips) => {
                        let (index, rig) =
                            model::add_animated_player(builder, vfs, p, skin, clips, transform)?;
                        builder.scene.motion.rigs.push(rig);
                        index
                    }
                    None => {
                        let frames = m.legs_frame.zip(m.torso_frame);
                        model::add_player(builder, vfs, p, skin, frames, transform)?
                    }
                }
            }
            (None, Some(path)) => {
                if m.animation.is_some() || m.torso_animation.is_some() {
                    return Err(self.invalid(format!(
                        "[[model]] {i}: animation is for players (give frame for an md3)"
                    )));
                }
                model::add_md3(builder, vfs, path, m.frame.unwrap_or(0), transform)?
            }
            _ => {
                return Err(
                    self.invalid(format!("[[model]] {i}: give exactly one of player or md3"))
                );
            }
        };
        if let Some(points) = &m.route {
            let route = self.route(&format!("[[model]] {i}"), points, m.speed.unwrap_or(150.0))?;
            builder.scene.motion.walks.push(Walk {
                model: index,
                route,
                yaw_deg: 0.0,
            });
        }
        Ok(())
    }

    /// The (legs, torso) animations `[[model]]` `i` plays; None when it names none.
    fn player_animations(
        &self,
        i: usize,
        m: &ModelSection,
    ) -> Result<Option<(AnimationId, AnimationId)>, SceneFileError> {
        if m.animation.is_none() && m.torso_animation.is_none() {
            return Ok(None);
        }
        let named = |name: &str, legs: bool| {
            AnimationId::from_short_name(name)
                .filter(|id| id.is_legs_only() == legs)
                .ok_or_else(|| {
                    let which: Vec<String> = AnimationId::ALL
                        .into_iter()
                        .filter(|id| id.is_legs_only() == legs)
                        .filter_map(|id| id.name().split_once('_').map(|(_, n)| n.to_lowercase()))
                        .collect();
                    self.invalid(format!(
                        "[[model]] {i}: no {} animation `{name}` (one of {})",
                        if legs { "legs" } else { "torso" },
                        which.join(", ")
                    ))
                })
        };
        let legs = named(m.animation.as_deref().unwrap_or("idle"), true)?;
        let torso = named(m.torso_animation.as_deref().unwrap_or("stand"), false)?;
        Ok(Some((legs, torso)))
    }

    /// The camera at the spawn point `[camera] spawn` names (eye height up, its yaw), else the
    /// default camera.
    fn spawn_camera(&self, spawns: &[SpawnPoint]) -> Result<Camera, SceneFileError> {
        let Some(i) = self.camera.spawn else {
            return Ok(Camera::default());
        };
        let s = spawns.get(i).ok_or_else(|| {
            self.invalid(format!(
                "[camera] spawn = {i}, but the map has {} spawn points",
                spawns.len()
            ))
        })?;
        Ok(Camera {
            position: s.origin + Vec3::Z * crate::scene::camera::Q3_VIEW_HEIGHT,
            yaw_deg: s.yaw_deg,
            ..Camera::default()
        })
    }

    fn apply_camera(&self, c: &mut Camera) -> Result<(), SceneFileError> {
        let s = &self.camera;
        if let Some(p) = s.position {
            if !finite3(p) {
                return Err(self.invalid("[camera] position must be finite"));
            }
            c.position = Vec3::from_array(p);
        }
        if let Some(t) = s.target {
            let looking = Camera::looking_at(c.position, Vec3::from_array(t));
            c.yaw_deg = looking.yaw_deg;
            c.pitch_deg = looking.pitch_deg;
        }
        if let Some(y) = s.yaw {
            c.yaw_deg = y;
        }
        if let Some(p) = s.pitch {
            c.pitch_deg = p.clamp(-89.9, 89.9);
        }
        if let Some(f) = s.fov {
            if !(f > 1.0 && f < 179.0) {
                return Err(self.invalid("[camera] fov must be within (1, 179) degrees"));
            }
            c.fov_x_deg = f;
        }
        if let Some(n) = s.near {
            if !(n > 0.0 && n.is_finite()) {
                return Err(self.invalid("[camera] near must be > 0"));
            }
            c.near = n;
        }
        if !(c.yaw_deg.is_finite() && c.pitch_deg.is_finite()) {
            return Err(self.invalid("[camera] yaw and pitch must be finite"));
        }
        Ok(())
    }
}

/// Warns of every light inside solid geometry (outside every BSP cluster) of a Quake 3 world.
/// Such a light sees the backs of one-sided faces: the rasterized techniques ignore those, the
/// exact reference does not, so every comparison would be off.
/// Lowers each placed light (`q3::entities::placed_lights`) until it is out of solid
/// geometry: over an item in a low passage the usual height is inside the ceiling (oa_bases5:
/// 4.8% of the receivers wrong from lights in solid). Left where it is when no height is free
/// (then warned of).
fn settle_placed_lights(scene: &mut Scene) {
    let Some(world) = &scene.world else { return };
    for l in scene
        .lights
        .iter_mut()
        .filter(|l| l.name.starts_with("placed"))
    {
        let base = l.position - glam::Vec3::Z * entities::PLACED_LIGHT_HEIGHT;
        let free = [1.0, 0.75, 0.5, 0.25, 0.125]
            .map(|k| base + glam::Vec3::Z * entities::PLACED_LIGHT_HEIGHT * k)
            .into_iter()
            .find(|p| world.cluster_at(*p) >= 0);
        if let Some(p) = free {
            l.position = p;
        }
    }
}

fn warn_of_lights_in_solid(scene: &Scene, report: &mut LoadReport) {
    let Some(world) = &scene.world else { return };
    for l in &scene.lights {
        if world.cluster_at(l.position) < 0 {
            let w = format!(
                "light `{}` at {:?} is inside solid geometry (outside every BSP cluster): \
                 its shadows will be wrong; move it into the playable space",
                l.name,
                l.position.to_array()
            );
            log::warn!("{w}");
            report.warnings.push(w);
        }
    }
}

/// Every `scripts/*.shader` of the data set, in name order; warnings are collected.
/// A warning naming the textures a scene lacks (`(name, why)` each).
fn warn_of_missing_textures(missing: &[(String, String)], report: &mut LoadReport) {
    if missing.is_empty() {
        return;
    }
    let names: Vec<&str> = missing.iter().map(|(n, _)| n.as_str()).collect();
    let w = format!(
        "{} textures missing, drawn as a magenta checker: {}",
        missing.len(),
        names.join(", ")
    );
    log::warn!("{w}");
    report.warnings.push(w);
}

pub fn load_shader_library(vfs: &Vfs, warnings: &mut Vec<String>) -> ShaderLibrary {
    let mut lib = ShaderLibrary::new();
    for name in vfs.list("scripts/", ".shader") {
        match vfs.read(&name) {
            Ok(data) => {
                lib.add_script(&String::from_utf8_lossy(&data), &name);
            }
            Err(e) => warnings.push(format!("{name}: {e}")),
        }
    }
    let n = lib.warnings().len();
    if n > 0 {
        log::debug!("{n} shader script problems skipped");
    }
    lib
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_model_on_the_built_in_room_is_refused_not_dropped() {
        let text = "[[model]]\nplayer = \"sarge\"\nposition = [0, 0, 24]\nyaw = 0\n";
        let file = SceneFile::parse(text, Path::new("room.toml")).unwrap();
        let e = file.build(&Options::default()).unwrap_err().to_string();
        assert!(e.contains("needs a [map] or base = \"empty\""), "{e}");
    }
}
