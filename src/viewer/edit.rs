//! Scene edits the viewer makes: lights added, removed, moved and re-aimed; models moved or
//! copied. GL-free; the caller re-uploads the scene when [`Edit::needs_upload`] says so.

use crate::options::Options;
use crate::scene::{Light, LightKind, Scene, SurfaceOwner};
use glam::{Mat4, Vec3};

/// What an edit changed, for the caller's caches.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Edit {
    /// Surfaces were added: the GPU copy of the scene must be rebuilt.
    pub needs_upload: bool,
}

/// Places model `m` with `transform` (its surfaces' bounds follow).
pub fn move_model(scene: &mut Scene, m: usize, transform: Mat4) -> Edit {
    scene.models[m].transform = transform;
    scene.model_moved(m);
    Edit {
        needs_upload: false,
    }
}

/// A second instance of model `m` with `transform`, sharing its vertices; returns its index.
pub fn copy_model(scene: &mut Scene, m: usize, transform: Mat4) -> (usize, Edit) {
    let index = scene.models.len();
    let name = format!("{} (copy)", scene.models[m].name);
    scene
        .models
        .push(crate::scene::ModelInstance::new(&name, transform));
    let copies: Vec<_> = scene
        .surfaces
        .iter()
        .filter(|s| s.owner == SurfaceOwner::Model(m))
        .cloned()
        .collect();
    for mut s in copies {
        s.owner = SurfaceOwner::Model(index);
        scene.add_surface(s);
        let i = scene.surfaces.len() - 1;
        scene.surfaces[i].bounds = scene.surface_bounds(i);
    }
    (index, Edit { needs_upload: true })
}

/// The transform that stands a model at `floor` facing `yaw_deg`, keeping nothing of the old one
/// but its scale-free rotation about Z.
pub fn standing_at(floor: Vec3, yaw_deg: f32) -> Mat4 {
    Mat4::from_translation(floor) * Mat4::from_rotation_z(yaw_deg.to_radians())
}

/// Points a spot light at `target` (omni lights have no direction).
pub fn aim_light(light: &mut Light, target: Vec3) {
    if let LightKind::Spot { direction, .. } = &mut light.kind {
        let d = target - light.position;
        if d.length_squared() > 1e-6 {
            *direction = d.normalize();
        }
    }
}

/// Adds a light; per-light options keep referring to the same lights.
pub fn add_light(scene: &mut Scene, light: Light) -> usize {
    scene.lights.push(light);
    scene.lights.len() - 1
}

/// Removes light `i` and renumbers the per-light options (`lighting.only`,
/// `lighting.techniques`) so that they keep meaning the same lights.
pub fn remove_light(scene: &mut Scene, options: &mut Options, i: usize) {
    if i >= scene.lights.len() {
        return;
    }
    let count = scene.lights.len();
    let techniques: Vec<_> = (0..count)
        .filter(|&l| l != i)
        .map(|l| (options.technique_for(l) != options.technique).then(|| options.technique_for(l)))
        .collect();
    let only_all = options.lighting.only.trim().eq_ignore_ascii_case("all")
        || options.lighting.only.trim().is_empty();
    let enabled: Vec<bool> = (0..count)
        .filter(|&l| l != i)
        .map(|l| options.light_enabled(l))
        .collect();
    scene.lights.remove(i);
    options.lighting.techniques.clear();
    for (l, t) in techniques.into_iter().enumerate() {
        if t.is_some() {
            options.set_technique_for(l, t);
        }
    }
    if !only_all {
        options.lighting.only = enabled
            .iter()
            .enumerate()
            .filter(|(_, e)| **e)
            .map(|(l, _)| l.to_string())
            .collect::<Vec<_>>()
            .join(",");
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::options::Technique;
    use crate::scene::builtin;

    #[test]
    fn removing_a_light_keeps_the_per_light_options_on_the_same_lights() {
        let mut scene = builtin::default_scene();
        add_light(
            &mut scene,
            Light::omni("third", Vec3::new(0.0, 0.0, 150.0), 300.0),
        );
        let mut o = Options::default();
        o.set("lighting.techniques", "2:shadow_volume").unwrap();
        o.set("lighting.only", "0,2").unwrap();
        remove_light(&mut scene, &mut o, 1);
        assert_eq!(scene.lights.len(), 2);
        assert_eq!(scene.lights[1].name, "third");
        assert_eq!(o.technique_for(1), Technique::ShadowVolume);
        assert_eq!(o.lighting.only, "0,1");
    }

    #[test]
    fn moved_and_copied_models_carry_their_bounds() {
        let mut scene = builtin::default_scene();
        // A one-triangle model.
        scene
            .models
            .push(crate::scene::ModelInstance::new("tri", Mat4::IDENTITY));
        let m = scene.models.len() - 1;
        let vertices: Vec<_> = [Vec3::ZERO, Vec3::X, Vec3::Y]
            .iter()
            .map(|p| crate::scene::Vertex::new(*p, Vec3::Z, [0.0, 0.0]))
            .collect();
        scene.push_surface(
            &vertices,
            &[0, 1, 2],
            0,
            SurfaceOwner::Model(m),
            crate::scene::SurfaceKind::Model,
        );
        let s = scene.surfaces.len() - 1;
        move_model(&mut scene, m, standing_at(Vec3::new(10.0, 0.0, 5.0), 0.0));
        assert_eq!(scene.surfaces[s].bounds.min, Vec3::new(10.0, 0.0, 5.0));
        let surfaces = scene.surfaces.len();
        let (copy, edit) = copy_model(&mut scene, m, standing_at(Vec3::new(0.0, 50.0, 0.0), 90.0));
        assert!(edit.needs_upload);
        assert_eq!(scene.surfaces.len(), surfaces + 1);
        let b = scene.surfaces[surfaces].bounds;
        assert_eq!(scene.surfaces[surfaces].owner, SurfaceOwner::Model(copy));
        assert!(
            (b.min - Vec3::new(-1.0, 50.0, 0.0)).length() < 1e-5,
            "{b:?}"
        );
    }

    #[test]
    fn aiming_turns_spots_only() {
        let mut spot = Light::spot("s", Vec3::ZERO, Vec3::X, 30.0, 100.0);
        aim_light(&mut spot, Vec3::new(0.0, 0.0, -5.0));
        assert_eq!(
            spot.kind,
            LightKind::Spot {
                direction: -Vec3::Z,
                cutoff_deg: 30.0
            }
        );
        let mut omni = Light::omni("o", Vec3::ZERO, 100.0);
        aim_light(&mut omni, Vec3::X);
        assert_eq!(omni.kind, LightKind::Omni);
    }
}
