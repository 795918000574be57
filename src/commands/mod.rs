//! Subcommands and what they share: option assembly, scene loading, context creation.

pub mod allocator;
pub mod bench;
pub mod check;
pub mod flythrough;
pub mod info;
pub mod inspect;
pub mod merge;
pub mod options;
pub mod render;
pub mod reproduce;
pub mod subdivide;
pub mod tune;
#[cfg(feature = "window")]
pub mod view;

use anyhow::{Context, Result};
use shadowlab::gl::legacy::Legacy;
use shadowlab::gl::{GlContext, Profile, create_context};
use shadowlab::options::{BackendChoice, OptionValue, Options, Pipeline};
use shadowlab::presets::Preset;
use shadowlab::run::Renderer;
use shadowlab::scene::{Scene, builtin};
use shadowlab::scene_file::LoadReport;
pub use shadowlab::scene_file::load::Loaded;
use shadowlab::scene_file::load::{LoadError, layered_options, load_file};

/// Arguments every command accepts.
#[derive(clap::Args, Clone, Default)]
pub struct CommonArgs {
    /// GL context path: auto (egl, then egl_es, then osmesa), egl, egl_es, osmesa or window.
    #[arg(long, global = true, value_name = "auto|egl|egl_es|osmesa|window")]
    pub backend: Option<String>,
    /// A named set of option values, applied before `--set`: `paper` (the paper's frame and
    /// choices) or `default`; `shadowlab options` lists their values.
    #[arg(long, global = true, value_name = "paper|default")]
    pub preset: Option<String>,
    /// Set an option (repeatable); `shadowlab options` lists the keys.
    #[arg(long = "set", global = true, value_name = "KEY=VALUE")]
    pub sets: Vec<String>,
    /// Frame size, e.g. 640x480 (the paper's resolution, the default).
    #[arg(long, global = true, value_name = "WxH")]
    pub size: Option<String>,
}

/// The camera path of `--path`: `turn`, a recorded path file, or the scene's camera when absent.
pub fn camera_path(
    camera: &shadowlab::scene::Camera,
    path: Option<&str>,
) -> Result<Vec<shadowlab::scene::path::PathKey>> {
    use shadowlab::scene::path;
    Ok(match path {
        None => vec![path::PathKey::of(camera)],
        Some("turn") => path::turn(camera, path::TURN_FRAMES),
        Some(file) => path::read(std::path::Path::new(file))?,
    })
}

/// Parses `WxH`.
pub fn parse_size(s: &str) -> Result<(u32, u32)> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .with_context(|| format!("size `{s}` is not of the form WIDTHxHEIGHT"))?;
    let w: u32 = w
        .trim()
        .parse()
        .with_context(|| format!("bad width in `{s}`"))?;
    let h: u32 = h
        .trim()
        .parse()
        .with_context(|| format!("bad height in `{s}`"))?;
    Ok((w, h))
}

/// Defaults, then a scene's `[options]`, then the command line (which wins).
pub fn scene_options(common: &CommonArgs, table: &toml::Table) -> Result<Options> {
    layered_options(table, |o| common.apply(o)).map_err(load_error)
}

/// A loading error as the commands report it.
fn load_error(e: LoadError<anyhow::Error>) -> anyhow::Error {
    match e {
        LoadError::File(e) => e.into(),
        LoadError::Options(e) => anyhow::Error::new(e).context("in the scene's [options]"),
        LoadError::Overrides(e) => e,
    }
}

impl CommonArgs {
    /// Defaults, then the scene's `[options]`, then the command line (which wins).
    pub fn options_for(&self, scene: &Scene) -> Result<Options> {
        scene_options(self, &scene.options)
    }

    fn apply(&self, mut o: Options) -> Result<Options> {
        if let Some(name) = &self.preset {
            Preset::parse(name)?.apply(&mut o).context("in --preset")?;
        }
        for s in &self.sets {
            o.set_assignment(s).context("in --set")?;
        }
        if let Some(b) = &self.backend {
            o.backend =
                BackendChoice::parse_value(b).map_err(|e| anyhow::anyhow!("--backend {b}: {e}"))?;
        }
        if let Some(size) = &self.size {
            let (w, h) = parse_size(size)?;
            o.set("width", &w.to_string()).context("in --size")?;
            o.set("height", &h.to_string()).context("in --size")?;
        }
        o.validate()?;
        Ok(o)
    }
}

/// The scene a command works on: the built-in one unless a file is given.
pub fn load(common: &CommonArgs, path: Option<&std::path::Path>) -> Result<Loaded> {
    match path {
        None => {
            let scene = builtin::default_scene();
            let options = common.options_for(&scene)?;
            Ok(Loaded {
                scene,
                options,
                report: LoadReport::default(),
            })
        }
        Some(p) => {
            let mut loaded = load_file(p, |o| common.apply(o)).map_err(load_error)?;
            loaded
                .report
                .warnings
                .extend(enclosed_light_warnings(&loaded.scene));
            Ok(loaded)
        }
    }
}

/// Warns about lights that sit inside or behind geometry (see `truth::enclosure`).
pub fn enclosed_light_warnings(scene: &Scene) -> Vec<String> {
    let warnings = shadowlab::truth::enclosure::scene_warnings(scene);
    for w in &warnings {
        log::warn!("{w}");
    }
    warnings
}

/// A context on the chosen path and a renderer on it.
pub fn start_gl(options: &Options) -> Result<(GlContext, Renderer)> {
    // The legacy calls need a compatibility profile; everything else runs on core (or ES).
    let fixed_function = options.gl.pipeline == Pipeline::FixedFunction;
    let profile = if fixed_function {
        Profile::Compatibility
    } else {
        Profile::Core
    };
    let ctx = create_context(options.backend, options.width, options.height, profile)?;
    let mut renderer = Renderer::new(ctx.gl.clone(), options.width, options.height)?;
    if fixed_function {
        let legacy = Legacy::load(|name| ctx.proc_address(name)).map_err(anyhow::Error::msg)?;
        renderer.use_legacy(std::rc::Rc::new(legacy))?;
    }
    Ok((ctx, renderer))
}

/// The error and its causes, each said once: library errors often print their cause in their
/// own message too, and `{:#}` would then repeat it ("x: gone: gone").
pub fn error_message(e: &anyhow::Error) -> String {
    let mut message = e.to_string();
    for cause in e.chain().skip(1) {
        let text = cause.to_string();
        if !message.contains(&text) {
            message.push_str(": ");
            message.push_str(&text);
        }
    }
    message
}

#[cfg(test)]
mod tests {
    use super::error_message;

    #[derive(Debug, thiserror::Error)]
    #[error("{path}: {source}")]
    struct Repeats {
        path: String,
        #[source]
        source: std::io::Error,
    }

    #[test]
    fn each_cause_is_said_once() {
        let io = std::io::Error::new(std::io::ErrorKind::NotFound, "no such file");
        let e = anyhow::Error::new(Repeats {
            path: "a.toml".into(),
            source: io,
        });
        assert_eq!(error_message(&e), "a.toml: no such file");
        let e = anyhow::anyhow!("inner cause").context("while loading b.bsp");
        assert_eq!(error_message(&e), "while loading b.bsp: inner cause");
    }
}
