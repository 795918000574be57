//! One loaded scene, measured: configurations as bench rows, frames as images, and the command
//! lines that regenerate them.

use super::{ReproduceError, Settings};
use crate::images::Rgba;
use crate::options::Options;
use crate::report::bench::{Bench, BenchConfig, BenchRow, BenchSettings, Capture, Kept};
use crate::run::Renderer;
use crate::scene::Scene;
use crate::scene::path::PathKey;
use crate::truth;
use indicatif::ProgressBar;
use std::path::Path;

pub struct Lab<'a> {
    bench: Bench<'a>,
    pub scene: &'a Scene,
    /// The scene file's name without `.toml`.
    pub name: String,
    /// The scene file as the commands name it (`assets/scenes/<name>.toml` unless set).
    scene_file: String,
    /// The scene's options at the report's size.
    pub base: Options,
    /// Assignments every measurement of this lab carries (and its commands print): the paper's
    /// frame.
    fixed: Vec<&'static str>,
    pub quick: bool,
    /// Measured frames per configuration (`Settings::frames`).
    pub frames: usize,
    /// Unmeasured frames before each configuration (`Settings::warmup`).
    warmup: usize,
    /// `Settings::enough_seconds`: fewer frames for configurations that take seconds.
    pub enough_seconds: Option<f64>,
    out: &'a Path,
    bar: &'a ProgressBar,
    rows: Vec<BenchRow>,
}

impl<'a> Lab<'a> {
    pub fn new(
        renderer: &'a mut Renderer,
        scene: &'a Scene,
        name: &str,
        base: Options,
        settings: &Settings,
        out: &'a Path,
        bar: &'a ProgressBar,
    ) -> Lab<'a> {
        let bench = Bench::new(
            renderer,
            scene,
            BenchSettings {
                warmup: settings.warmup,
                frames: settings.frames,
                path: vec![PathKey::of(&scene.camera)],
                progress: false,
                // The figures' sweeps are long; one renderer keeps their memory bounded.
                interleave: false,
                breakdown: true,
                pipelined: true,
                // The scene as loaded: these measure techniques, not motion.
                motion: false,
                sample_every: 1,
                memory_mb: None,
                enough_seconds: settings.enough_seconds,
            },
        );
        Lab {
            bench,
            scene,
            name: name.to_string(),
            scene_file: format!("assets/scenes/{name}.toml"),
            base,
            fixed: super::PAPER_FRAME.to_vec(),
            quick: settings.quick,
            frames: settings.frames,
            warmup: settings.warmup,
            enough_seconds: settings.enough_seconds,
            out,
            bar,
            rows: Vec::new(),
        }
    }

    /// The lab of a scene file outside `assets/scenes` (a hard case), as its commands name it.
    pub fn with_scene_file(mut self, file: &str) -> Lab<'a> {
        self.scene_file = file.to_string();
        self
    }

    /// Every row measured so far.
    pub fn rows(&self) -> &[BenchRow] {
        &self.rows
    }

    /// The rows kept and the exact masks and errors of the lab's view, taken to measure more
    /// of the scene elsewhere (`tune`); [`Lab::put_kept`] gives them back.
    pub fn take_kept(&mut self) -> Kept {
        self.bench.take_kept()
    }

    pub fn put_kept(&mut self, kept: Kept) {
        self.bench.put_kept(kept);
    }

    /// The renderer the lab measures on.
    pub fn renderer(&mut self) -> &mut Renderer {
        self.bench.renderer()
    }

    pub fn bar(&self) -> &ProgressBar {
        self.bar
    }

    /// Where a file of the report goes.
    pub fn out_path(&self, file: &str) -> std::path::PathBuf {
        self.out.join(file)
    }

    /// Measures with what an earlier lab kept (its view only if of the same scene).
    pub fn with_kept(mut self, kept: Kept) -> Lab<'a> {
        self.bench.put_kept(kept);
        self
    }

    /// Every row this lab measured, and what it kept (for the next lab).
    pub fn into_parts(mut self) -> (Vec<BenchRow>, Kept) {
        let kept = self.bench.take_kept();
        (self.rows, kept)
    }

    /// The scene's options with `KEY=VALUE` assignments applied.
    pub fn options(&self, sets: &[&str]) -> Result<Options, ReproduceError> {
        let mut o = self.base.clone();
        for s in self.fixed.iter().chain(sets) {
            o.set_assignment(s)?;
        }
        o.validate()?;
        Ok(o)
    }

    /// Measures named configurations (`name`, assignments): time, ratio to shadows off, error.
    pub fn measure(
        &mut self,
        configs: &[(&str, Vec<&str>)],
    ) -> Result<Vec<BenchRow>, ReproduceError> {
        let configs: Vec<BenchConfig> = configs
            .iter()
            .map(|(name, sets)| Ok(BenchConfig::named(name, self.options(sets)?)))
            .collect::<Result<_, ReproduceError>>()?;
        let mut rows = Vec::with_capacity(configs.len());
        for c in configs {
            self.bar
                .set_message(format!("{}: {}", self.name, c.label()));
            let hidden = ProgressBar::hidden();
            rows.extend(self.bench.run_with(std::slice::from_ref(&c), &hidden)?);
        }
        self.rows.extend(rows.iter().cloned());
        Ok(rows)
    }

    /// The scene camera's frame with these assignments, and the exact masks.
    pub fn capture(&mut self, sets: &[&str]) -> Result<Capture, ReproduceError> {
        let options = self.options(sets)?;
        self.bar
            .set_message(format!("{}: frame {}", self.name, sets.join(" ")));
        Ok(self.bench.capture(&options)?)
    }

    /// Writes an image into the output folder and gives its file name.
    pub fn save(&self, image: &Rgba, file: &str) -> Result<String, ReproduceError> {
        image.save(&self.out_path(file))?;
        Ok(file.to_string())
    }

    /// The frame of a capture as an image.
    pub fn frame_image(capture: &Capture) -> Rgba {
        capture.frame.image.clone()
    }

    /// Every light's errors of a capture in one image (red false shadow, blue false lit).
    pub fn error_image(capture: &Capture) -> Rgba {
        let rendered: Vec<&crate::images::Mask> = capture.frame.masks.iter().collect();
        let exact: Vec<&crate::images::Mask> = capture.exact.iter().collect();
        Rgba {
            width: capture.frame.width(),
            height: capture.frame.height(),
            data: truth::error_image_all(&rendered, &exact),
        }
    }

    /// `shadowlab render` with this scene and these assignments, writing masks.
    pub fn render_command(&self, sets: &[&str]) -> String {
        let mut s = format!(
            "shadowlab render --scene {} --size {}x{}",
            self.scene_file, self.base.width, self.base.height
        );
        for a in self.fixed.iter().chain(sets) {
            s.push_str(&format!(" --set {a}"));
        }
        s.push_str(" --mask masks/");
        s
    }

    /// `shadowlab bench` with this scene, fixed assignments and one sweep, measured as the
    /// lab measures: the still camera, the scene standing, one configuration after another.
    pub fn bench_command(&self, sets: &[&str], sweep: &str) -> String {
        let mut s = format!(
            "shadowlab bench --scene {} --size {}x{} --path still --no-motion --sequential \
             --warmup {} --frames {}",
            self.scene_file, self.base.width, self.base.height, self.warmup, self.frames
        );
        if let Some(enough) = self.enough_seconds {
            s.push_str(&format!(" --enough-seconds {enough}"));
        }
        for a in self.fixed.iter().chain(sets) {
            s.push_str(&format!(" --set {a}"));
        }
        s.push_str(&format!(" --sweep {sweep}"));
        s
    }
}

/// Percent with a sensible number of decimals.
pub fn pct(x: f64) -> String {
    let p = 100.0 * x;
    if p >= 10.0 {
        format!("{p:.1}%")
    } else if p >= 0.1 {
        format!("{p:.2}%")
    } else {
        format!("{p:.3}%")
    }
}
