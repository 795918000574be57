//! Collects a scene from Quake 3 pieces (map faces, models): materials from shader names, texture
//! references loaded in one parallel batch at the end.

use super::pk3::Vfs;
use super::shader::{ShaderLibrary, normalize_name};
use super::textures;
use crate::scene::{Cull, Material, Scene};
use std::collections::HashMap;

// Quake 3 surface and content flags (q_shared/surfaceflags.h values), for BSP shaders that have
// no script.
const SURF_SKY: i32 = 0x4;
const SURF_NODRAW: i32 = 0x80;
const CONTENTS_FOG: i32 = 0x40;

/// `path` without its extension: Quake 3 looks shaders up by the stripped name.
pub fn strip_extension(path: &str) -> String {
    let n = normalize_name(path);
    let start = n.rfind('/').map_or(0, |i| i + 1);
    match n[start..].rfind('.') {
        Some(dot) => n[..start + dot].to_string(),
        None => n,
    }
}

pub struct SceneBuilder<'a> {
    pub scene: Scene,
    shaders: &'a ShaderLibrary,
    materials: HashMap<String, usize>,
    image_refs: Vec<String>,
    image_slots: HashMap<String, usize>,
}

impl<'a> SceneBuilder<'a> {
    pub fn new(name: &str, shaders: &'a ShaderLibrary) -> SceneBuilder<'a> {
        SceneBuilder {
            scene: Scene::named(name),
            shaders,
            materials: HashMap::new(),
            image_refs: Vec::new(),
            image_slots: HashMap::new(),
        }
    }

    fn image_slot(&mut self, reference: &str) -> usize {
        let key = strip_extension(reference);
        if let Some(&s) = self.image_slots.get(&key) {
            return s;
        }
        self.image_refs.push(key.clone());
        self.image_slots.insert(key, self.image_refs.len() - 1);
        self.image_refs.len() - 1
    }

    /// The material for a shader name (a map shader, or a model skin's image path). Without a
    /// script the name is the image (Quake 3's implicit shader); `flags` are a BSP shader's
    /// surface and content flags.
    pub fn material(&mut self, shader_name: &str, flags: Option<(i32, i32)>) -> usize {
        let key = strip_extension(shader_name);
        if let Some(&m) = self.materials.get(&key) {
            return m;
        }
        let shaders = self.shaders;
        let mut material = match shaders.get(&key) {
            Some(def) => {
                let slot = def.texture.clone().map(|t| self.image_slot(&t));
                def.to_material(slot)
            }
            None => {
                let usable = !key.is_empty() && key != "noshader";
                let slot = usable.then(|| self.image_slot(&key));
                let mut m = Material::opaque(&key, slot);
                m.visible = usable;
                m.casts_shadows = usable;
                m.receives_light = usable;
                m
            }
        };
        if let Some((surface, content)) = flags
            && (surface & (SURF_SKY | SURF_NODRAW) != 0 || content & CONTENTS_FOG != 0)
        {
            material.visible = false;
            material.casts_shadows = false;
            material.receives_light = false;
        }
        material.name = key.clone();
        self.scene.materials.push(material);
        let index = self.scene.materials.len() - 1;
        self.materials.insert(key, index);
        index
    }

    /// A material from a fixed description (built-in parts of Quake 3 scenes).
    pub fn plain_material(&mut self, name: &str, cull: Cull) -> usize {
        let mut m = Material::opaque(name, None);
        m.cull = cull;
        self.scene.materials.push(m);
        self.scene.materials.len() - 1
    }

    /// Loads every referenced image, fills the scene's textures and returns what was missing.
    pub fn finish(mut self, vfs: &Vfs, progress: bool) -> (Scene, Vec<(String, String)>) {
        // Only images of drawn materials are loaded.
        let mut used = vec![false; self.image_refs.len()];
        for m in &self.scene.materials {
            if let (true, Some(t)) = (m.visible, m.texture) {
                used[t] = true;
            }
        }
        let wanted: Vec<String> = self
            .image_refs
            .iter()
            .zip(&used)
            .filter(|(_, u)| **u)
            .map(|(r, _)| r.clone())
            .collect();
        let mut remap = vec![None; self.image_refs.len()];
        let mut next = 0;
        for (i, u) in used.iter().enumerate() {
            if *u {
                remap[i] = Some(next);
                next += 1;
            }
        }
        let loaded = textures::load_images(vfs, &wanted, progress);
        self.scene.textures = loaded.images;
        for m in &mut self.scene.materials {
            m.texture = m.texture.and_then(|t| remap[t]);
        }
        (self.scene, loaded.missing)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn extensions_are_stripped_only_from_the_file_name() {
        assert_eq!(
            strip_extension("Models/Players/Sarge/band.TGA"),
            "models/players/sarge/band"
        );
        assert_eq!(strip_extension("textures/a.b/c"), "textures/a.b/c");
        assert_eq!(strip_extension("textures/base/wall"), "textures/base/wall");
    }

    #[test]
    fn implicit_and_flagged_materials() {
        let lib = ShaderLibrary::new();
        let mut b = SceneBuilder::new("t", &lib);
        let wall = b.material("textures/base/wall", Some((0, 1)));
        let again = b.material("TEXTURES/base/wall.jpg", None);
        assert_eq!(wall, again);
        let sky = b.material("textures/skies/sky", Some((SURF_SKY, 0)));
        let none = b.material("noshader", None);
        let m = &b.scene.materials;
        assert!(m[wall].visible && m[wall].casts_shadows && m[wall].texture.is_some());
        assert!(!m[sky].visible && !m[sky].casts_shadows);
        assert!(!m[none].visible && m[none].texture.is_none());
    }
}
