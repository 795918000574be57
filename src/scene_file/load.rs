//! Loading a scene file with its options layered: the defaults, then the file's `[options]`, then
//! the caller's overrides (the command line, a run's settings, a test's), which win. The one
//! place the commands, `reproduce` and the tests do this.

use super::{LoadReport, SceneFile, SceneFileError};
use crate::options::{OptionError, Options};
use crate::scene::Scene;
use std::path::Path;

/// Where loading failed.
#[derive(Debug, thiserror::Error)]
pub enum LoadError<E> {
    /// Reading or building the scene file.
    #[error(transparent)]
    File(#[from] SceneFileError),
    /// The scene's `[options]`.
    #[error("in the scene's [options]: {0}")]
    Options(OptionError),
    /// The caller's overrides.
    #[error("{0}")]
    Overrides(E),
}

/// A scene ready to render, the options that apply to it, and what loading reported.
pub struct Loaded {
    pub scene: Scene,
    pub options: Options,
    pub report: LoadReport,
}

/// The defaults, then `table` (a scene's `[options]`), then `overrides`.
pub fn layered_options<E>(
    table: &toml::Table,
    overrides: impl FnOnce(Options) -> Result<Options, E>,
) -> Result<Options, LoadError<E>> {
    layered_over(Options::default(), table, overrides)
}

/// [`layered_options`] from `base` instead of the defaults.
pub fn layered_over<E>(
    base: Options,
    table: &toml::Table,
    overrides: impl FnOnce(Options) -> Result<Options, E>,
) -> Result<Options, LoadError<E>> {
    let mut options = base;
    options.apply_toml(table).map_err(LoadError::Options)?;
    overrides(options).map_err(LoadError::Overrides)
}

/// Reads the scene file at `path` and builds its scene with [`layered_options`].
pub fn load_file<E>(
    path: &Path,
    overrides: impl FnOnce(Options) -> Result<Options, E>,
) -> Result<Loaded, LoadError<E>> {
    load_file_over(Options::default(), path, overrides)
}

/// [`load_file`] with the options layered over `base` instead of the defaults.
pub fn load_file_over<E>(
    base: Options,
    path: &Path,
    overrides: impl FnOnce(Options) -> Result<Options, E>,
) -> Result<Loaded, LoadError<E>> {
    let file = SceneFile::read(path)?;
    let options = layered_over(base, &file.options, overrides)?;
    let (scene, report) = file.build(&options)?;
    Ok(Loaded {
        scene,
        options,
        report,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table(text: &str) -> toml::Table {
        text.parse().unwrap()
    }

    #[test]
    fn the_file_overrides_the_defaults_and_the_caller_overrides_the_file() {
        let t = table("width = 320\nheight = 200\n");
        let o = layered_options(&t, |mut o| {
            o.set("height", "100")?;
            Ok::<_, OptionError>(o)
        })
        .unwrap();
        assert_eq!((o.width, o.height), (320, 100));
        let bad = table("no_such_key = 1\n");
        let e = layered_options(&bad, Ok::<_, OptionError>).unwrap_err();
        assert!(matches!(e, LoadError::Options(_)), "{e}");
        let e = layered_options(&t, |_| Err::<Options, _>("refused")).unwrap_err();
        assert!(matches!(e, LoadError::Overrides("refused")), "{e}");
    }
}
