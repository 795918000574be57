//! The virtual file system of Quake 3: several pk3 (zip) archives and folders, where a later
//! source overrides an earlier one and names are case-insensitive. Files are read into memory.
//!
//! Hostile archives cannot hang or exhaust memory: every read is capped at [`MAX_FILE_BYTES`],
//! the declared size is checked before allocating, the decompressed stream is cut off at the cap
//! whatever the header claims, and an entry that inflates more than [`MAX_RATIO`] times is refused.

use std::collections::HashMap;
use std::fs::File;
use std::io::{BufReader, Cursor, Read, Seek};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use thiserror::Error;
use zip::ZipArchive;

/// Largest file the VFS reads (the biggest OpenArena bsp is about 10 MiB).
pub const MAX_FILE_BYTES: u64 = 256 << 20;
/// Largest accepted decompressed/compressed ratio (text compresses about 10:1; bombs 1000:1).
pub const MAX_RATIO: u64 = 200;
/// Entries per archive (OpenArena's largest has about 10 000).
pub const MAX_ENTRIES: usize = 1 << 20;

/// Environment variable naming the data folder.
pub const DATA_ENV: &str = "SHADOWLAB_DATA";

#[derive(Debug, Error)]
pub enum VfsError {
    #[error("`{0}` is not in any pk3 or folder of the data set")]
    NotFound(String),
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{archive}: not a readable zip archive: {message}")]
    Zip { archive: PathBuf, message: String },
    #[error("{archive}: {entries} entries is more than the {MAX_ENTRIES} accepted")]
    TooManyEntries { archive: PathBuf, entries: usize },
    #[error("`{name}` in {archive}: {size} bytes is more than the {limit}-byte limit")]
    TooLarge {
        archive: PathBuf,
        name: String,
        size: u64,
        limit: u64,
    },
    #[error(
        "`{name}` in {archive}: inflates {compressed} bytes to more than {MAX_RATIO}x (zip bomb?)"
    )]
    Bomb {
        archive: PathBuf,
        name: String,
        compressed: u64,
    },
    #[error("`{name}` in {archive}: declared {declared} bytes but holds {actual}")]
    SizeMismatch {
        archive: PathBuf,
        name: String,
        declared: u64,
        actual: u64,
    },
    #[error(
        "no OpenArena data in {0}: run scripts/fetch-openarena.sh (or set {DATA_ENV} to a folder holding baseoa/*.pk3)"
    )]
    NoData(PathBuf),
}

/// What an archive is read from: a file, or bytes in memory (tests and fuzzing), through the
/// same code.
trait ZipInput: Read + Seek + Send {}
impl<T: Read + Seek + Send> ZipInput for T {}

enum Source {
    Zip {
        path: PathBuf,
        archive: Mutex<ZipArchive<Box<dyn ZipInput>>>,
    },
    Dir {
        root: PathBuf,
    },
}

/// Where a name resolves to.
#[derive(Debug, Clone)]
struct Location {
    source: usize,
    /// Entry index for archives, relative path for folders.
    entry: usize,
    real_name: String,
}

/// Several archives and folders seen as one tree.
#[derive(Default)]
pub struct Vfs {
    sources: Vec<Source>,
    index: HashMap<String, Location>,
}

/// Lower-case with forward slashes: the key every lookup uses. Idempotent (a key normalizes to
/// itself), so that every listed name can be looked up: leading slashes and spaces are stripped
/// together (an entry named `/ x` used to become ` x`, which no lookup could reach).
pub fn normalize(name: &str) -> String {
    name.replace('\\', "/")
        .trim_start_matches(|c: char| c == '/' || c.is_whitespace())
        .trim_end()
        .to_ascii_lowercase()
}

/// The folder the fetch script fills: `$SHADOWLAB_DATA`, else `~/.cache/shadowlab/openarena`.
pub fn data_dir() -> PathBuf {
    if let Some(d) = std::env::var_os(DATA_ENV).filter(|d| !d.is_empty()) {
        return PathBuf::from(d);
    }
    let home = std::env::var_os("HOME").map_or_else(|| PathBuf::from("."), PathBuf::from);
    home.join(".cache/shadowlab/openarena")
}

impl Vfs {
    pub fn new() -> Vfs {
        Vfs::default()
    }

    /// OpenArena's data set: `DIR/baseoa/*.pk3` in name order (pak0 first, later ones win), or
    /// `DIR/*.pk3` when DIR holds the archives itself.
    pub fn open_data_dir(dir: &Path) -> Result<Vfs, VfsError> {
        let base = if dir.join("baseoa").is_dir() {
            dir.join("baseoa")
        } else {
            dir.to_path_buf()
        };
        let mut paks: Vec<PathBuf> = std::fs::read_dir(&base)
            .map_err(|_| VfsError::NoData(dir.to_path_buf()))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("pk3")))
            .collect();
        if paks.is_empty() {
            return Err(VfsError::NoData(dir.to_path_buf()));
        }
        paks.sort();
        let mut vfs = Vfs::new();
        for p in paks {
            vfs.add_pk3(&p)?;
        }
        Ok(vfs)
    }

    /// Adds an archive; its files override those already added.
    pub fn add_pk3(&mut self, path: &Path) -> Result<(), VfsError> {
        let file = File::open(path).map_err(|source| VfsError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        self.add_archive(path, Box::new(BufReader::new(file)))
    }

    /// Adds an archive held in memory, named `label` in errors; it overrides like [`Vfs::add_pk3`].
    pub fn add_pk3_bytes(&mut self, label: &Path, bytes: Vec<u8>) -> Result<(), VfsError> {
        self.add_archive(label, Box::new(Cursor::new(bytes)))
    }

    fn add_archive(&mut self, path: &Path, input: Box<dyn ZipInput>) -> Result<(), VfsError> {
        let archive = ZipArchive::new(input).map_err(|e| VfsError::Zip {
            archive: path.to_path_buf(),
            message: e.to_string(),
        })?;
        if archive.len() > MAX_ENTRIES {
            return Err(VfsError::TooManyEntries {
                archive: path.to_path_buf(),
                entries: archive.len(),
            });
        }
        let source = self.sources.len();
        for (entry, raw) in archive.file_names_raw().enumerate() {
            let name = String::from_utf8_lossy(raw);
            if name.ends_with('/') || name.is_empty() {
                continue;
            }
            self.index.insert(
                normalize(&name),
                Location {
                    source,
                    entry,
                    real_name: name.into_owned(),
                },
            );
        }
        self.sources.push(Source::Zip {
            path: path.to_path_buf(),
            archive: Mutex::new(archive),
        });
        Ok(())
    }

    /// Adds a folder (walked up to 16 levels and 200 000 files); it overrides what came before.
    pub fn add_dir(&mut self, root: &Path) -> Result<(), VfsError> {
        let source = self.sources.len();
        let mut stack = vec![(root.to_path_buf(), 0usize)];
        let mut count = 0usize;
        while let Some((dir, depth)) = stack.pop() {
            let entries = std::fs::read_dir(&dir).map_err(|source| VfsError::Io {
                path: dir.clone(),
                source,
            })?;
            for e in entries.flatten() {
                let p = e.path();
                let Ok(kind) = e.file_type() else { continue };
                if kind.is_dir() && depth < 16 {
                    stack.push((p, depth + 1));
                } else if kind.is_file() && count < 200_000 {
                    count += 1;
                    if let Ok(rel) = p.strip_prefix(root) {
                        let rel = rel.to_string_lossy().replace('\\', "/");
                        self.index.insert(
                            normalize(&rel),
                            Location {
                                source,
                                entry: 0,
                                real_name: rel,
                            },
                        );
                    }
                }
            }
        }
        self.sources.push(Source::Dir {
            root: root.to_path_buf(),
        });
        Ok(())
    }

    pub fn contains(&self, name: &str) -> bool {
        self.index.contains_key(&normalize(name))
    }

    /// Every file name (normalized) under `prefix` ending with `suffix`, sorted.
    pub fn list(&self, prefix: &str, suffix: &str) -> Vec<String> {
        let (p, s) = (normalize(prefix), suffix.to_ascii_lowercase());
        let mut v: Vec<String> = self
            .index
            .keys()
            .filter(|k| k.starts_with(&p) && k.ends_with(&s))
            .cloned()
            .collect();
        v.sort();
        v
    }

    /// Which archive or folder a name resolves to.
    pub fn origin(&self, name: &str) -> Option<PathBuf> {
        let loc = self.index.get(&normalize(name))?;
        Some(match &self.sources[loc.source] {
            Source::Zip { path, .. } => path.clone(),
            Source::Dir { root } => root.clone(),
        })
    }

    /// Reads a whole file.
    pub fn read(&self, name: &str) -> Result<Vec<u8>, VfsError> {
        let loc = self
            .index
            .get(&normalize(name))
            .ok_or_else(|| VfsError::NotFound(name.to_string()))?;
        match &self.sources[loc.source] {
            Source::Dir { root } => {
                let path = root.join(&loc.real_name);
                let len = std::fs::metadata(&path)
                    .map_err(|source| VfsError::Io {
                        path: path.clone(),
                        source,
                    })?
                    .len();
                if len > MAX_FILE_BYTES {
                    return Err(VfsError::TooLarge {
                        archive: root.clone(),
                        name: loc.real_name.clone(),
                        size: len,
                        limit: MAX_FILE_BYTES,
                    });
                }
                std::fs::read(&path).map_err(|source| VfsError::Io { path, source })
            }
            Source::Zip { path, archive } => {
                let mut archive = archive.lock().unwrap_or_else(|p| p.into_inner());
                read_entry(&mut archive, loc.entry, path, &loc.real_name)
            }
        }
    }
}

fn read_entry(
    archive: &mut ZipArchive<Box<dyn ZipInput>>,
    entry: usize,
    path: &Path,
    name: &str,
) -> Result<Vec<u8>, VfsError> {
    let zip_err = |e: zip::result::ZipError| VfsError::Zip {
        archive: path.to_path_buf(),
        message: format!("`{name}`: {e}"),
    };
    let file = archive.by_index(entry).map_err(zip_err)?;
    let declared = file.size();
    let compressed = file.compressed_size();
    if declared > MAX_FILE_BYTES {
        return Err(VfsError::TooLarge {
            archive: path.to_path_buf(),
            name: name.to_string(),
            size: declared,
            limit: MAX_FILE_BYTES,
        });
    }
    if declared > compressed.saturating_mul(MAX_RATIO).saturating_add(1 << 16) {
        return Err(VfsError::Bomb {
            archive: path.to_path_buf(),
            name: name.to_string(),
            compressed,
        });
    }
    // The declared size is bounded but may still lie: reserve at most 1 MiB ahead of the data.
    let mut data = Vec::with_capacity(declared.min(1 << 20) as usize);
    // Never trust the header: read at most one byte more than declared.
    file.take(declared + 1)
        .read_to_end(&mut data)
        .map_err(|e| VfsError::Zip {
            archive: path.to_path_buf(),
            message: format!("`{name}`: {e}"),
        })?;
    if data.len() as u64 != declared {
        return Err(VfsError::SizeMismatch {
            archive: path.to_path_buf(),
            name: name.to_string(),
            declared,
            actual: data.len() as u64,
        });
    }
    Ok(data)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;
    use zip::write::SimpleFileOptions;

    fn temp(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("shadowlab-pk3-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn write_pk3(path: &Path, files: &[(&str, &[u8])]) {
        let mut z = zip::ZipWriter::new(File::create(path).unwrap());
        for (name, data) in files {
            z.start_file(*name, SimpleFileOptions::default()).unwrap();
            z.write_all(data).unwrap();
        }
        z.finish().unwrap();
    }

    #[test]
    fn later_archives_override_and_lookup_ignores_case() {
        let d = temp("override");
        write_pk3(
            &d.join("pak0.pk3"),
            &[("Scripts/A.shader", b"old"), ("maps/x.bsp", b"x")],
        );
        write_pk3(&d.join("pak1.pk3"), &[("scripts/a.SHADER", b"new")]);
        let mut v = Vfs::new();
        v.add_pk3(&d.join("pak0.pk3")).unwrap();
        v.add_pk3(&d.join("pak1.pk3")).unwrap();
        assert_eq!(v.read("SCRIPTS\\a.shader").unwrap(), b"new");
        assert_eq!(v.read("Maps/X.bsp").unwrap(), b"x");
        assert_eq!(v.list("scripts/", ".shader"), vec!["scripts/a.shader"]);
        assert!(matches!(v.read("nope"), Err(VfsError::NotFound(_))));
        std::fs::remove_dir_all(&d).ok();
    }

    #[test]
    fn folders_override_archives() {
        let d = temp("dir");
        write_pk3(&d.join("pak0.pk3"), &[("textures/t.tga", b"zip")]);
        std::fs::create_dir_all(d.join("loose/textures")).unwrap();
        std::fs::write(d.join("loose/textures/T.tga"), b"loose").unwrap();
        let mut v = Vfs::new();
        v.add_pk3(&d.join("pak0.pk3")).unwrap();
        v.add_dir(&d.join("loose")).unwrap();
        assert_eq!(v.read("textures/t.tga").unwrap(), b"loose");
        std::fs::remove_dir_all(&d).ok();
    }

    #[test]
    fn hostile_archives_give_errors() {
        let d = temp("hostile");
        // Not a zip at all, and a truncated zip.
        std::fs::write(d.join("junk.pk3"), b"this is not a zip archive").unwrap();
        assert!(matches!(
            Vfs::new().add_pk3(&d.join("junk.pk3")),
            Err(VfsError::Zip { .. })
        ));
        write_pk3(&d.join("ok.pk3"), &[("a.txt", b"hello hello hello")]);
        let bytes = std::fs::read(d.join("ok.pk3")).unwrap();
        for cut in [10, bytes.len() / 2, bytes.len() - 5] {
            std::fs::write(d.join("cut.pk3"), &bytes[..cut]).unwrap();
            assert!(
                Vfs::new().add_pk3(&d.join("cut.pk3")).is_err(),
                "cut at {cut}"
            );
        }
        // A deflated run of zeros: 8 MiB from a few KiB is a ratio far beyond MAX_RATIO.
        let mut z = zip::ZipWriter::new(File::create(d.join("bomb.pk3")).unwrap());
        z.start_file(
            "zeros.bin",
            SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated),
        )
        .unwrap();
        z.write_all(&vec![0u8; 8 << 20]).unwrap();
        z.finish().unwrap();
        let mut v = Vfs::new();
        v.add_pk3(&d.join("bomb.pk3")).unwrap();
        assert!(matches!(v.read("zeros.bin"), Err(VfsError::Bomb { .. })));
        std::fs::remove_dir_all(&d).ok();
    }

    #[test]
    fn a_lying_size_header_is_caught() {
        let d = temp("lying");
        // Stored entry: the local header's and central directory's size fields say 5 bytes of
        // "hello world"; patch both to claim 3.
        write_pk3(&d.join("a.pk3"), &[("f.txt", b"hello world")]);
        let mut bytes = std::fs::read(d.join("a.pk3")).unwrap();
        let mut patched = 0;
        for sig in [[0x50u8, 0x4b, 3, 4], [0x50, 0x4b, 1, 2]] {
            let pos = bytes.windows(4).position(|w| w == sig).unwrap();
            // Uncompressed size: offset 22 in the local header, 24 in the central one.
            let off = if sig[2] == 3 { pos + 22 } else { pos + 24 };
            bytes[off..off + 4].copy_from_slice(&3u32.to_le_bytes());
            patched += 1;
        }
        assert_eq!(patched, 2);
        std::fs::write(d.join("a.pk3"), &bytes).unwrap();
        let mut v = Vfs::new();
        v.add_pk3(&d.join("a.pk3")).unwrap();
        let r = v.read("f.txt");
        assert!(r.is_err(), "{r:?}");
        std::fs::remove_dir_all(&d).ok();
    }

    #[test]
    fn normalized_names_normalize_to_themselves() {
        for name in ["/ x", "\\ \\Maps\\X.bsp ", " /a/b", "a", "", "/"] {
            let key = normalize(name);
            assert_eq!(normalize(&key), key, "{name:?}");
        }
        assert_eq!(normalize("/ Maps\\X.BSP"), "maps/x.bsp");
    }

    #[test]
    fn archives_in_memory_read_like_files() {
        let d = temp("memory");
        write_pk3(
            &d.join("a.pk3"),
            &[("maps/X.bsp", b"ibsp"), ("../up.txt", b"up")],
        );
        let mut v = Vfs::new();
        v.add_pk3_bytes(
            Path::new("mem.pk3"),
            std::fs::read(d.join("a.pk3")).unwrap(),
        )
        .unwrap();
        assert_eq!(v.read("maps/x.bsp").unwrap(), b"ibsp");
        assert_eq!(v.origin("maps/x.bsp").unwrap(), Path::new("mem.pk3"));
        // A climbing name is only a key: it reads its own entry and nothing outside.
        assert_eq!(v.read("../up.txt").unwrap(), b"up");
        assert!(matches!(v.read("up.txt"), Err(VfsError::NotFound(_))));
        assert!(matches!(
            Vfs::new().add_pk3_bytes(Path::new("junk.pk3"), b"PK\x05\x06".to_vec()),
            Err(VfsError::Zip { .. })
        ));
        std::fs::remove_dir_all(&d).ok();
    }

    #[test]
    fn missing_data_dir_says_how_to_fetch() {
        let e = Vfs::open_data_dir(Path::new("/nonexistent/shadowlab"))
            .err()
            .unwrap();
        assert!(e.to_string().contains("scripts/fetch-openarena.sh"));
    }
}
