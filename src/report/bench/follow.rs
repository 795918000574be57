//! A configuration that uses `technique = auto` has its path sampled before it is timed, and
//! its timed frames run the choices `auto` made on the sampled frames (`AutoMemory::follow`).
//! Its learning goes on along a sampled path (errors sampled every few frames), but not along
//! timed frames, which sample nothing: timed on their own, they ran what the first frame had
//! taught, while the row's error came from the sampled path's choices (q3dm6ish's light 10
//! moved to volumes at frame 344 of the sampled path and stayed on maps in the timed frames).

use super::error::PathSample;
use super::sampled::SampledPath;
use super::{Bench, BenchConfig, BenchSettings, options_key};
use crate::options::{Candidate, Options, Technique};
use crate::run::{RenderError, Renderer};
use crate::scene::{Camera, Scene};
use indicatif::ProgressBar;
use std::collections::{BTreeMap, HashMap};

/// What each planned light ran with, by path frame.
pub(super) type Choices = Vec<Vec<(usize, Candidate)>>;

impl BenchSettings {
    /// Poses `scene` for path frame `i` and returns its camera; with `choices` (a sampled
    /// run's), `renderer`'s `auto` runs what it chose at that frame.
    pub(super) fn frame(
        &self,
        scene: &mut Scene,
        (renderer, choices): (&mut Renderer, Option<&Choices>),
        i: usize,
    ) -> Camera {
        self.pose(scene, i);
        if let Some(choices) = choices {
            renderer.follow(choices.get(i).or(choices.last()).map_or(&[], Vec::as_slice));
        }
        self.camera(scene, i)
    }
}

impl Bench<'_> {
    /// Whether `options`' timed frames follow the choices of their sampled path: `auto` in
    /// use, on a path sampled frame by frame (a still one samples its first frame only).
    pub(super) fn follows(&self, options: &Options, sample: bool) -> bool {
        sample && !self.path_is_still() && options.uses(self.scene.lights.len(), Technique::Auto)
    }

    /// The sampled path of each configuration whose timed frames follow it, drawn before
    /// any is timed; its choices are kept for the timing, and returned with its frames by
    /// options.
    pub(super) fn sample_ahead(
        &mut self,
        configs: &[BenchConfig],
        bar: &ProgressBar,
    ) -> Result<HashMap<String, (Vec<PathSample>, Choices)>, RenderError> {
        let mut frames = HashMap::new();
        for c in configs {
            let sample = c.options.estimate.samples > 0;
            if !self.follows(&c.options, sample) {
                continue;
            }
            bar.set_message(format!("{}: sampled reference along the path", c.label()));
            let (sampled, choices) = self.sample_path(&c.options)?;
            // The timing starts from the scene alone.
            self.renderer.release_kept();
            let key = options_key(&c.options);
            self.choices.insert(key.clone(), choices.clone());
            frames.insert(key, (sampled, choices));
        }
        Ok(frames)
    }
}

/// Light-frames (a light planned in a frame is one) by what the light ran with.
pub(super) fn light_frames<'a>(
    ran: impl Iterator<Item = &'a (usize, Candidate)>,
) -> BTreeMap<String, usize> {
    let mut counts = BTreeMap::new();
    for (_, candidate) in ran {
        *counts.entry(candidate.to_string()).or_default() += 1;
    }
    counts
}

impl SampledPath {
    /// Counts what the lights ran with along the path, all together and each light's own.
    pub(super) fn count_choices(&mut self, choices: &Choices) {
        self.ran = light_frames(choices.iter().flatten());
        for l in &mut self.lights {
            l.ran = light_frames(choices.iter().flatten().filter(|(i, _)| *i == l.light));
        }
    }
}
