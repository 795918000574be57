//! MD3 models placed in a scene (paper 2.5): single models, and players assembled lower → upper
//! → head through their tags with the first (or named) skin.

use super::builder::SceneBuilder;
use super::md3::{self, Md3, Md3Error, PlacedSurface};
use super::pk3::{Vfs, VfsError};
use crate::scene::motion::{Clip, KeyedMesh, Rig, RigPart, TagKey};
use crate::scene::{ModelInstance, SurfaceKind, SurfaceOwner};
use glam::Mat4;
use thiserror::Error;

#[derive(Debug, Error)]
pub enum ModelError {
    #[error(transparent)]
    Vfs(#[from] VfsError),
    #[error("{path}: {source}")]
    Md3 { path: String, source: Md3Error },
    #[error("{path}: {reason} (an animated player needs its animation.cfg)")]
    Animation { path: String, reason: String },
}

fn read_md3(vfs: &Vfs, path: &str) -> Result<Md3, ModelError> {
    let data = vfs.read(path)?;
    md3::parse(&data).map_err(|source| ModelError::Md3 {
        path: path.to_string(),
        source,
    })
}

/// Adds the placed surfaces as model `name`; returns the model index and, per placed surface,
/// the scene vertex its vertices start at (None: not drawn, e.g. a `nodraw` skin).
fn add_surfaces(
    builder: &mut SceneBuilder,
    name: &str,
    transform: Mat4,
    placed: Vec<PlacedSurface>,
    skin_shader: impl Fn(&PlacedSurface) -> Option<String>,
) -> (usize, Vec<Option<usize>>) {
    builder
        .scene
        .models
        .push(ModelInstance::new(name, transform));
    let model = builder.scene.models.len() - 1;
    let mut starts = Vec::with_capacity(placed.len());
    for p in placed {
        let shader = skin_shader(&p).unwrap_or_else(|| p.shader.clone());
        let material = builder.material(&shader, None);
        if !builder.scene.materials[material].visible {
            starts.push(None);
            continue;
        }
        starts.push(Some(builder.scene.vertices.len()));
        builder.scene.push_surface(
            &p.vertices,
            &p.indices,
            material,
            SurfaceOwner::Model(model),
            SurfaceKind::Model,
        );
    }
    (model, starts)
}

/// Adds one MD3 at `frame`, placed by `transform`. Returns the model index.
pub fn add_md3(
    builder: &mut SceneBuilder,
    vfs: &Vfs,
    path: &str,
    frame: usize,
    transform: Mat4,
) -> Result<usize, ModelError> {
    let m = read_md3(vfs, path)?;
    let placed = md3::place_model(&m, frame, Mat4::IDENTITY).map_err(|source| ModelError::Md3 {
        path: path.to_string(),
        source,
    })?;
    Ok(add_surfaces(builder, path, transform, placed, |_| None).0)
}

/// A player's three models, its animations (None: no readable `animation.cfg`) and skins.
struct Player {
    dir: String,
    lower: Md3,
    upper: Md3,
    head: Md3,
    animations: Result<md3::AnimationCfg, String>,
    skins: Vec<(String, md3::Skin)>,
}

impl Player {
    fn load(vfs: &Vfs, name: &str, skin: &str) -> Result<Player, ModelError> {
        let dir = format!("models/players/{name}");
        let lower = read_md3(vfs, &format!("{dir}/lower.md3"))?;
        let upper = read_md3(vfs, &format!("{dir}/upper.md3"))?;
        let head = read_md3(vfs, &format!("{dir}/head.md3"))?;
        let animations = vfs
            .read(&format!("{dir}/animation.cfg"))
            .map_err(|e| e.to_string())
            .and_then(|t| {
                md3::parse_animation_cfg(&String::from_utf8_lossy(&t)).map_err(|e| e.to_string())
            });
        let skins = ["lower", "upper", "head"]
            .iter()
            .filter_map(|part| {
                let text = vfs.read(&format!("{dir}/{part}_{skin}.skin")).ok()?;
                Some((
                    part.to_string(),
                    md3::parse_skin(&String::from_utf8_lossy(&text)),
                ))
            })
            .collect();
        Ok(Player {
            dir,
            lower,
            upper,
            head,
            animations,
            skins,
        })
    }

    /// Adds the player assembled at (legs, torso) frames; returns the model index and the
    /// scene vertex each placed surface starts at.
    fn add(
        &self,
        builder: &mut SceneBuilder,
        (legs, torso): (usize, usize),
        transform: Mat4,
    ) -> Result<(usize, Vec<Option<usize>>), ModelError> {
        let placed = md3::assemble_player(&self.lower, &self.upper, &self.head, legs, torso)
            .map_err(|source| ModelError::Md3 {
                path: self.dir.clone(),
                source,
            })?;
        Ok(add_surfaces(builder, &self.dir, transform, placed, |p| {
            self.skins
                .iter()
                .find(|(part, _)| *part == p.part)
                .and_then(|(_, s)| s.shader_for(&p.surface_name))
                .map(str::to_string)
        }))
    }
}

/// Adds the player model `models/players/<name>` with `skin` (e.g. "default"), standing in its
/// idle pose unless `frames` = (legs, torso) is given. Returns the model index.
pub fn add_player(
    builder: &mut SceneBuilder,
    vfs: &Vfs,
    name: &str,
    skin: &str,
    frames: Option<(usize, usize)>,
    transform: Mat4,
) -> Result<usize, ModelError> {
    let player = Player::load(vfs, name, skin)?;
    let frames = frames.unwrap_or_else(|| {
        player.animations.as_ref().map_or((0, 0), |a| {
            (a.legs_idle_frame() as usize, a.torso_stand_frame() as usize)
        })
    });
    Ok(player.add(builder, frames, transform)?.0)
}

/// Adds a player playing `legs` and `torso` (animations of its `animation.cfg`); returns the
/// model index and the rig that animates it ([`crate::scene::motion`]).
pub fn add_animated_player(
    builder: &mut SceneBuilder,
    vfs: &Vfs,
    name: &str,
    skin: &str,
    (legs, torso): (md3::AnimationId, md3::AnimationId),
    transform: Mat4,
) -> Result<(usize, Rig), ModelError> {
    let player = Player::load(vfs, name, skin)?;
    let animations = player
        .animations
        .as_ref()
        .map_err(|reason| ModelError::Animation {
            path: player.dir.clone(),
            reason: reason.clone(),
        })?;
    let clip = |id: md3::AnimationId| {
        let a = animations.get(id);
        Clip {
            first: a.first_frame,
            frames: a.num_frames.max(1),
            looping: a.looping_frames,
            fps: a.fps as f32,
            reversed: a.reversed,
        }
    };
    let (legs_clip, torso_clip) = (clip(legs), clip(torso));
    // Placed at each clip's first frame; posing writes every later frame.
    let first = (legs_clip.first as usize, torso_clip.first as usize);
    let (model, starts) = player.add(builder, first, transform)?;
    let mut starts = starts.into_iter();
    let mut part = |md3: &Md3, name: &str, clip: Clip, parent: Option<(usize, usize)>| RigPart {
        name: name.to_string(),
        meshes: md3
            .surfaces
            .iter()
            .zip(starts.by_ref())
            .filter_map(|(s, start)| {
                Some(KeyedMesh {
                    name: s.name.clone(),
                    first_vertex: start?,
                    verts: s.num_verts,
                    positions: s.positions.clone().into(),
                    normals: s.normals.clone().into(),
                })
            })
            .collect(),
        tags: tag_keys(md3),
        clip,
        parent,
    };
    // assemble_player found both tags, so they exist.
    let torso_tag = tag_index(&player.lower, "tag_torso");
    let head_tag = tag_index(&player.upper, "tag_head");
    let parts = vec![
        part(&player.lower, "lower", legs_clip, None),
        part(
            &player.upper,
            "upper",
            torso_clip,
            torso_tag.map(|t| (0, t)),
        ),
        part(
            &player.head,
            "head",
            Clip::still(0),
            head_tag.map(|t| (1, t)),
        ),
    ];
    Ok((model, Rig { model, parts }))
}

/// Each tag of `md3` by name with its key in every frame.
fn tag_keys(md3: &Md3) -> Vec<(String, Vec<TagKey>)> {
    let n = md3.tag_names.len();
    md3.tag_names
        .iter()
        .enumerate()
        .map(|(t, name)| {
            let keys = md3
                .tags
                .iter()
                .skip(t)
                .step_by(n.max(1))
                .map(md3::Tag::key)
                .collect();
            (name.clone(), keys)
        })
        .collect()
}

fn tag_index(md3: &Md3, name: &str) -> Option<usize> {
    md3.tag_names.iter().position(|n| n == name)
}
