//! Texture images from the VFS: Quake 3's lookup order (.tga, then .jpg, whatever extension the
//! reference names), decoded in parallel with bounded sizes, and a visible checker for what is
//! missing or unreadable.

use super::pk3::Vfs;
use super::shader::image_candidates;
use crate::images::Rgba;
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use std::io::Cursor;

/// Largest texture side accepted (Quake 3 textures are at most 1024).
pub const MAX_TEXTURE_SIDE: u32 = 4096;

/// The texture drawn where an image is missing: magenta and black, impossible to overlook.
pub fn missing_checker() -> Rgba {
    let size = 64u32;
    let mut rgba = Vec::with_capacity((size * size * 4) as usize);
    for y in 0..size {
        for x in 0..size {
            let on = ((x / 8) + (y / 8)).is_multiple_of(2);
            rgba.extend_from_slice(if on {
                &[255, 0, 255, 255]
            } else {
                &[0, 0, 0, 255]
            });
        }
    }
    Rgba {
        width: size,
        height: size,
        data: rgba,
    }
}

/// Decodes a TGA or JPEG with size limits; `None` if it is not a readable image.
pub fn decode(name: &str, data: &[u8]) -> Result<Rgba, String> {
    let format = if name.ends_with(".jpg") || name.ends_with(".jpeg") {
        image::ImageFormat::Jpeg
    } else if name.ends_with(".tga") {
        image::ImageFormat::Tga
    } else if name.ends_with(".png") {
        image::ImageFormat::Png
    } else {
        return Err(format!("{name}: unknown image type"));
    };
    let mut reader = image::ImageReader::with_format(Cursor::new(data), format);
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(MAX_TEXTURE_SIDE);
    limits.max_image_height = Some(MAX_TEXTURE_SIDE);
    limits.max_alloc = Some(256 << 20);
    reader.limits(limits);
    let img = reader.decode().map_err(|e| format!("{name}: {e}"))?;
    let rgba = img.to_rgba8();
    let (width, height) = rgba.dimensions();
    if width == 0 || height == 0 {
        return Err(format!("{name}: empty image"));
    }
    Ok(Rgba {
        width,
        height,
        data: rgba.into_raw(),
    })
}

/// Loaded images in the order of the references given, and which references failed.
pub struct LoadedImages {
    pub images: Vec<Rgba>,
    /// (reference, why) for each reference that got the checker.
    pub missing: Vec<(String, String)>,
}

/// Loads every reference (`textures/x/y.tga` or without extension). Shows a progress bar on a
/// terminal when `progress` is set.
pub fn load_images(vfs: &Vfs, references: &[String], progress: bool) -> LoadedImages {
    let bar = if progress {
        let b = ProgressBar::new(references.len() as u64);
        b.set_style(
            ProgressStyle::with_template("{msg:>10} [{bar:30}] {pos}/{len} textures")
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> "),
        );
        b.set_message("loading");
        b
    } else {
        ProgressBar::hidden()
    };
    // Reading from the archives is serialised inside the VFS; decoding runs in parallel.
    let results: Vec<Result<Rgba, String>> = references
        .par_iter()
        .map(|r| {
            let found = image_candidates(r).into_iter().find(|c| vfs.contains(c));
            let result = match found {
                None => Err(format!("{r}: no .tga or .jpg in the data set")),
                Some(path) => vfs
                    .read(&path)
                    .map_err(|e| e.to_string())
                    .and_then(|data| decode(&path, &data)),
            };
            bar.inc(1);
            result
        })
        .collect();
    bar.finish_and_clear();
    let mut images = Vec::with_capacity(results.len());
    let mut missing = Vec::new();
    for (r, res) in references.iter().zip(results) {
        match res {
            Ok(img) => images.push(img),
            Err(why) => {
                missing.push((r.clone(), why));
                images.push(missing_checker());
            }
        }
    }
    LoadedImages { images, missing }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decodes_a_tga_and_rejects_garbage() {
        // 2x1 uncompressed true-colour TGA, bottom-up, BGRA.
        let mut tga = vec![0u8, 0, 2, 0, 0, 0, 0, 0, 0, 0, 0, 0, 2, 0, 1, 0, 32, 8];
        tga.extend_from_slice(&[255, 0, 0, 255, 0, 0, 255, 128]);
        let img = decode("a.tga", &tga).unwrap();
        assert_eq!((img.width, img.height), (2, 1));
        assert_eq!(&img.data, &[0, 0, 255, 255, 255, 0, 0, 128]);
        assert!(decode("b.tga", &tga[..10]).is_err());
        assert!(decode("c.jpg", b"not a jpeg").is_err());
        assert!(decode("d.bmp", &tga).is_err());
    }

    #[test]
    fn an_absurd_size_is_refused_before_allocating() {
        // TGA header claiming 65535 x 65535 pixels with no data.
        let tga = [
            0u8, 0, 2, 0, 0, 0, 0, 0, 0, 0, 0, 0, 255, 255, 255, 255, 32, 8,
        ];
        assert!(decode("huge.tga", &tga).is_err());
    }

    #[test]
    fn checker_is_half_magenta() {
        let c = missing_checker();
        let magenta = c
            .data
            .chunks_exact(4)
            .filter(|p| p == &[255, 0, 255, 255])
            .count();
        assert_eq!(magenta * 2, (c.width * c.height) as usize);
    }
}
