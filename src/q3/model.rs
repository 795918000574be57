//! MD3 models placed in a scene (paper 2.5): single models, and players assembled lower → upper
//! → head through their tags with the first (or named) skin.

use super::builder::SceneBuilder;
use super::md3::{self, Md3, Md3Error, PlacedSurface};
use super::pk3::{Vfs, VfsError};
use crate::scene::{ModelInstance, SurfaceKind, SurfaceOwner};
use glam::Mat4;
use thiserror::Error;

#[derive(Debug, Error)]
pub enum ModelError {
    #[error(transparent)]
    Vfs(#[from] VfsError),
    #[error("{path}: {source}")]
    Md3 { path: String, source: Md3Error },
}

fn read_md3(vfs: &Vfs, path: &str) -> Result<Md3, ModelError> {
    let data = vfs.read(path)?;
    md3::parse(&data).map_err(|source| ModelError::Md3 {
        path: path.to_string(),
        source,
    })
}

fn add_surfaces(
    builder: &mut SceneBuilder,
    name: &str,
    transform: Mat4,
    placed: Vec<PlacedSurface>,
    skin_shader: impl Fn(&PlacedSurface) -> Option<String>,
) -> usize {
    builder.scene.models.push(ModelInstance {
        name: name.to_string(),
        transform,
    });
    let model = builder.scene.models.len() - 1;
    for p in placed {
        let shader = skin_shader(&p).unwrap_or_else(|| p.shader.clone());
        let material = builder.material(&shader, None);
        if !builder.scene.materials[material].visible {
            continue;
        }
        builder.scene.push_surface(
            &p.vertices,
            &p.indices,
            material,
            SurfaceOwner::Model(model),
            SurfaceKind::Model,
        );
    }
    model
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
    Ok(add_surfaces(builder, path, transform, placed, |_| None))
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
    let dir = format!("models/players/{name}");
    let lower = read_md3(vfs, &format!("{dir}/lower.md3"))?;
    let upper = read_md3(vfs, &format!("{dir}/upper.md3"))?;
    let head = read_md3(vfs, &format!("{dir}/head.md3"))?;
    let (legs, torso) = match frames {
        Some(f) => f,
        None => vfs
            .read(&format!("{dir}/animation.cfg"))
            .ok()
            .and_then(|t| md3::parse_animation_cfg(&String::from_utf8_lossy(&t)).ok())
            .map_or((0, 0), |a| {
                (a.legs_idle_frame() as usize, a.torso_stand_frame() as usize)
            }),
    };
    let placed = md3::assemble_player(&lower, &upper, &head, legs, torso).map_err(|source| {
        ModelError::Md3 {
            path: dir.clone(),
            source,
        }
    })?;
    let skins: Vec<(String, md3::Skin)> = ["lower", "upper", "head"]
        .iter()
        .filter_map(|part| {
            let text = vfs.read(&format!("{dir}/{part}_{skin}.skin")).ok()?;
            Some((
                part.to_string(),
                md3::parse_skin(&String::from_utf8_lossy(&text)),
            ))
        })
        .collect();
    Ok(add_surfaces(builder, &dir, transform, placed, |p| {
        skins
            .iter()
            .find(|(part, _)| *part == p.part)
            .and_then(|(_, s)| s.shader_for(&p.surface_name))
            .map(str::to_string)
    }))
}
