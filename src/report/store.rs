//! Measured rows kept by content, so that a long run interrupted or run again redoes only what
//! changed: each row is filed under a key of everything it depends on (the code that measured
//! it, the GL, the scene's content, the options, how frames were taken). A configuration met
//! twice in one run (the same options in two sections) is measured once.
//!
//! The key holds the running executable's own hash: a rebuilt binary measures everything anew,
//! since any change to the code may change what it measures.

use crate::report::bench::BenchRow;
use crate::scene::Scene;
use std::collections::HashMap;
use std::hash::{DefaultHasher, Hash, Hasher};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// Rows by key: in memory, and in a folder when one is given (one JSON file per row).
#[derive(Debug, Default)]
pub struct RowStore {
    dir: Option<PathBuf>,
    rows: HashMap<String, BenchRow>,
    /// Rows asked for and found (in memory or on disk).
    pub reused: usize,
    /// Rows filed after being measured.
    pub measured: usize,
    /// Why rows could not be kept on disk (the first failure), if they could not: the run
    /// goes on with them in memory.
    pub write_error: Option<String>,
}

impl RowStore {
    /// A store that lives as long as the run.
    pub fn in_memory() -> RowStore {
        RowStore::default()
    }

    /// A store in `dir` (created if absent), kept between runs.
    pub fn on_disk(dir: &Path) -> std::io::Result<RowStore> {
        std::fs::create_dir_all(dir)?;
        Ok(RowStore {
            dir: Some(dir.to_path_buf()),
            ..RowStore::default()
        })
    }

    /// The folder rows are kept in, if any.
    pub fn dir(&self) -> Option<&Path> {
        self.dir.as_deref()
    }

    fn file(&self, key: &str) -> Option<PathBuf> {
        self.dir.as_ref().map(|d| d.join(format!("{key}.json")))
    }

    /// The row filed under `key`. A file that cannot be read as a row (a run killed while
    /// writing it, an older format) counts as absent: the row is measured again.
    pub fn get(&mut self, key: &str) -> Option<BenchRow> {
        let row = match self.rows.get(key) {
            Some(row) => Some(row.clone()),
            None => self.file(key).and_then(|path| {
                let text = std::fs::read_to_string(path).ok()?;
                serde_json::from_str::<BenchRow>(&text).ok()
            }),
        };
        if let Some(row) = &row {
            self.reused += 1;
            self.rows.insert(key.to_string(), row.clone());
        }
        row
    }

    /// Files `row` under `key`; on disk through a temporary file renamed into place, so that
    /// an interrupted write leaves no half row behind.
    pub fn put(&mut self, key: &str, row: &BenchRow) {
        self.measured += 1;
        self.rows.insert(key.to_string(), row.clone());
        if let Some(path) = self.file(key)
            && let Err(e) = write_row(&path, row)
        {
            self.write_error
                .get_or_insert_with(|| format!("{}: {e}", path.display()));
        }
    }

    /// `reused 12 of 40 configurations from DIR`, for the run's closing lines (with why rows
    /// could not be kept, if they could not).
    pub fn summary(&self) -> String {
        let from = self
            .dir
            .as_ref()
            .map(|d| format!(" from {}", d.display()))
            .unwrap_or_default();
        let mut text = format!(
            "reused {} of {} configurations{from}",
            self.reused,
            self.reused + self.measured
        );
        if let Some(e) = &self.write_error {
            text.push_str(&format!(" (rows not kept on disk: {e})"));
        }
        text
    }
}

fn write_row(path: &Path, row: &BenchRow) -> std::io::Result<()> {
    let text = serde_json::to_string(row).map_err(std::io::Error::other)?;
    let partial = path.with_extension("json.partial");
    std::fs::write(&partial, text)?;
    std::fs::rename(&partial, path)
}

/// The key of a row: a hash of the code, then of every part given (GL, scene, options,
/// frame settings), as 32 hex digits.
pub fn key(parts: &[&str]) -> String {
    let mut a = DefaultHasher::new();
    code_version().hash(&mut a);
    parts.hash(&mut a);
    // A second hash over the parts in another order widens the key to 128 bits.
    let mut b = DefaultHasher::new();
    parts.iter().rev().for_each(|p| p.hash(&mut b));
    code_version().hash(&mut b);
    format!("{:016x}{:016x}", a.finish(), b.finish())
}

/// A hash of the running executable's bytes (0 when it cannot be read: then only the
/// package version tells builds apart).
fn code_version() -> u64 {
    static VERSION: OnceLock<u64> = OnceLock::new();
    *VERSION.get_or_init(|| {
        let mut h = DefaultHasher::new();
        env!("CARGO_PKG_VERSION").hash(&mut h);
        if let Ok(bytes) = std::env::current_exe().and_then(std::fs::read) {
            bytes.hash(&mut h);
        }
        h.finish()
    })
}

/// A hash of what a scene's measurements depend on: its geometry, materials, images,
/// models, lights, camera, motion and option overrides.
pub fn scene_fingerprint(scene: &Scene) -> String {
    let mut h = DefaultHasher::new();
    scene.name.hash(&mut h);
    for v in &scene.vertices {
        let floats = v.position.iter().chain(&v.normal).chain(&v.uv);
        floats
            .chain(&v.lightmap_uv)
            .for_each(|f| f.to_bits().hash(&mut h));
        v.color.hash(&mut h);
    }
    scene.indices.hash(&mut h);
    for image in scene.textures.iter().chain(&scene.lightmaps) {
        (image.width, image.height, &image.data).hash(&mut h);
    }
    // The rest is small: its debug text covers every field.
    format!(
        "{:?}{:?}{:?}{:?}{:?}{:?}{}",
        scene.surfaces,
        scene.materials,
        scene.models,
        scene.lights,
        scene.camera,
        scene.motion,
        scene.options
    )
    .hash(&mut h);
    format!("{:016x}", h.finish())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::bench::test_row;

    #[test]
    fn keys_differ_with_any_part() {
        let k = key(&["gl", "scene", "options"]);
        assert_eq!(k, key(&["gl", "scene", "options"]));
        assert_eq!(k.len(), 32);
        assert_ne!(k, key(&["gl", "scene", "options2"]));
        assert_ne!(k, key(&["gl", "sceneoptions", ""]));
    }

    #[test]
    fn rows_survive_on_disk_and_broken_files_count_as_absent() {
        let dir = std::env::temp_dir().join(format!("shadowlab-store-{}", std::process::id()));
        let row = test_row("shadow_map", "SM", 2.0, 0.01);
        let mut first = RowStore::on_disk(&dir).unwrap();
        assert!(first.get("k").is_none());
        first.put("k", &row);
        assert_eq!(first.write_error, None);
        let mut again = RowStore::on_disk(&dir).unwrap();
        let back = again.get("k").expect("the row filed before");
        assert_eq!((back.label, back.error.total), (row.label, row.error.total));
        assert_eq!((again.reused, again.measured), (1, 0));
        std::fs::write(dir.join("broken.json"), "{\"label\":").unwrap();
        assert!(again.get("broken").is_none());
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn a_scene_changed_anywhere_has_another_fingerprint() {
        let scene = crate::scene::builtin::default_scene();
        let mut moved = scene.clone();
        moved.lights[0].position.x += 1.0;
        assert_eq!(scene_fingerprint(&scene), scene_fingerprint(&scene.clone()));
        assert_ne!(scene_fingerprint(&scene), scene_fingerprint(&moved));
    }
}
