//! `shadowlab inspect`: what a map holds, as JSON (faces, triangles after tessellation, vertices,
//! shaders, lightmaps, leaves, clusters, edges).

use super::{CommonArgs, scene_options};
use anyhow::{Context, Result, bail};
use shadowlab::q3::builder::SceneBuilder;
use shadowlab::q3::pk3::Vfs;
use shadowlab::q3::world;
use shadowlab::scene_file::{SceneFile, load_shader_library};
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// A scene file whose map to inspect.
    #[arg(long, conflicts_with_all = ["data", "all"])]
    scene: Option<PathBuf>,
    /// A folder holding pk3 files (or a data folder with baseoa/ in it).
    #[arg(long)]
    data: Option<PathBuf>,
    /// Every map in the data set, one JSON line each.
    #[arg(long, requires = "data")]
    all: bool,
    /// A map name (`oa_dm1`) or a bsp path inside the pk3s (`maps/oa_dm1.bsp`).
    map: Option<String>,
}

pub fn bsp_path(map: &str) -> String {
    if map.to_ascii_lowercase().ends_with(".bsp") {
        map.to_string()
    } else {
        format!("maps/{map}.bsp")
    }
}

pub fn run(common: &CommonArgs, args: &Args) -> Result<()> {
    let (vfs, maps, options) = match (&args.scene, &args.data) {
        (Some(scene), _) => {
            let file = SceneFile::read(scene)?;
            let options = scene_options(common, &file.options)?;
            let map = file
                .map
                .as_ref()
                .context("the scene has no [map]: nothing to inspect")?;
            let data = map
                .data
                .clone()
                .unwrap_or_else(shadowlab::q3::pk3::data_dir);
            (Vfs::open_data_dir(&data)?, vec![map.bsp.clone()], options)
        }
        (None, Some(dir)) => {
            let vfs = Vfs::open_data_dir(dir)?;
            let maps = match (&args.map, args.all) {
                (Some(m), false) => vec![bsp_path(m)],
                (None, true) => vfs.list("maps/", ".bsp"),
                _ => bail!("give a MAP name, or --all"),
            };
            (vfs, maps, scene_options(common, &toml::Table::new())?)
        }
        (None, None) => bail!("give --scene FILE, or --data DIR with a MAP or --all"),
    };
    let mut warnings = Vec::new();
    let shaders = load_shader_library(&vfs, &mut warnings);
    let mut failed = 0;
    for map in &maps {
        let mut builder = SceneBuilder::new(map, &shaders);
        match world::load_map(&mut builder, &vfs, map, &options.q3) {
            Ok(info) => println!("{}", serde_json::to_string(&info.counts)?),
            Err(e) => {
                failed += 1;
                eprintln!("error: {e}");
            }
        }
    }
    if failed > 0 {
        bail!("{failed} of {} maps could not be loaded", maps.len());
    }
    Ok(())
}
