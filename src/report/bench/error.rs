//! A configuration's error: the path's first frame drawn with its masks and compared with the
//! exact reference, and the sampled reference along the path.

use super::follow::Choices;
use super::{Bench, models_key, options_key};
use crate::frame::CacheStats;
use crate::frame::Frame;
use crate::images::Mask;
use crate::options::Options;
use crate::plan::PlanStats;
use crate::plan::fallback::Fallback;
use crate::plan::volume_draws::VolumeStats;
use crate::report::estimate::{GBufferRead, gbuffer_of, learn_auto, render_sampled, sample_masks};
use crate::run::{FrameRequest, RenderError, Renderer};
use crate::scene::Scene;
use crate::scene::path::PathKey;
use crate::truth::sampled::FrameSample;
use crate::truth::{Counts, ExactMasks, Reference};
use std::collections::HashMap;
use std::time::Instant;

/// One sampled frame of a path: its index, the sample, milliseconds of masks, of tracing and
/// of the frame itself (whose lit passes recorded its decisions), and of the plain frame drawn
/// right after it (along a path sampled every few frames: the same motion, without masks).
pub(super) type PathSample = (usize, FrameSample, f64, f64, f64, Option<f64>);

/// `auto`'s learning frames ([`learn_auto`]) on `renderer` at the path's first frame: each
/// technique of its lights drawn, timed and sampled, as a one-frame command does before its
/// frame, so that the bench's frames run what `auto` chooses from measurement rather than from
/// its constants (which, with no cost measured, chose shadow maps for every light of
/// q3dm6ish's error frame where its timed frames then ran volumes). Nothing without `auto`.
pub(super) fn learn_at_start(
    renderer: &mut Renderer,
    (scene, settings): (&mut Scene, &super::BenchSettings),
    options: &Options,
    reference: &Reference,
) -> Result<(), RenderError> {
    settings.pose(scene, 0);
    let first = settings.camera(scene, 0);
    let own = std::mem::replace(&mut scene.camera, first);
    let learned = learn_auto(renderer, scene, options, Some(reference));
    scene.camera = own;
    learned
}

/// A configuration's error, with its first frame's sample when one was asked for.
pub(super) type Errored = (FrameError, Option<PathSample>);

/// What the benches of one scene seen from one first view share: its exact masks, and each
/// configuration's error on that view (the error frame does not depend on how the frames are
/// timed), so that `tune`'s rungs and a report's sections draw each error frame once.
#[derive(Default)]
pub struct View {
    /// The path's first camera pose these hold for.
    first: Option<PathKey>,
    /// Exact masks of the view, by frame size and light.
    exact: ExactMasks,
    /// Errors by options (their sampling budget aside), with the first frame's sample when
    /// one was taken.
    errors: HashMap<String, (FrameError, Option<PathSample>)>,
}

impl View {
    /// The exact reference of the view's scene, built on first use.
    pub(super) fn reference(&mut self, scene: &Scene) -> &Reference {
        self.exact.reference(scene)
    }
}

/// The options an error frame depends on: all but the sampling budget, which only says how
/// many pixels the sample traces.
pub(super) fn error_key(options: &Options) -> String {
    let mut o = options.clone();
    o.estimate.samples = 0;
    options_key(&o)
}

/// One configuration's error on the path's first frame: all lights, per light, and the volume
/// work of that frame.
#[derive(Clone)]
pub(super) struct FrameError {
    pub(super) total: Counts,
    pub(super) per_light: Vec<(usize, Counts)>,
    pub(super) volumes: Vec<VolumeStats>,
    pub(super) plan: PlanStats,
    pub(super) cache: CacheStats,
    pub(super) fallbacks: Vec<Fallback>,
}

/// The path's first frame of one configuration, with its masks, the exact masks and the error.
#[derive(Debug, Clone)]
pub struct Capture {
    pub frame: Frame,
    /// The exact mask of each of `frame.masks`, in the same order.
    pub exact: Vec<Mask>,
    pub total: Counts,
    pub per_light: Vec<(usize, Counts)>,
}

impl<'a> Bench<'a> {
    /// Measures from `view`, kept by an earlier bench of the same scene: its exact masks and
    /// errors are reused when its first camera pose is this path's (else they start empty).
    pub fn with_view(mut self, view: View) -> Bench<'a> {
        self.put_view(view);
        self
    }

    /// [`Bench::with_view`] on a bench already made (giving back what `take_view` took).
    pub fn put_view(&mut self, view: View) {
        let first = self.settings.path.first().copied();
        self.view = if view.first.is_none() || view.first == first {
            view
        } else {
            View::default()
        };
        self.view.first = first;
    }

    /// Takes the view's masks and errors (for the next bench of the scene), leaving none.
    pub fn take_view(&mut self) -> View {
        std::mem::take(&mut self.view)
    }

    /// The first frame of the path with `options`, compared with the exact reference.
    pub fn capture(&mut self, options: &Options) -> Result<Capture, RenderError> {
        Ok(self.capture_timed(options)?.0)
    }

    /// [`Bench::capture`], with the milliseconds its masks took (the frame's time leaves them
    /// out).
    fn capture_timed(&mut self, options: &Options) -> Result<(Capture, f64), RenderError> {
        // The exact masks kept are those of the first frame, posed at its time.
        self.settings.pose(&mut self.scene, 0);
        let camera = self.settings.camera(&self.scene, 0);
        let start = Instant::now();
        let frame = self.renderer.render_at(
            &self.scene,
            &camera,
            options,
            FrameRequest {
                masks: true,
                ..FrameRequest::default()
            },
        )?;
        let masks_ms = (start.elapsed().as_secs_f64() * 1e3 - frame.frame_ms).max(0.0);
        let m = self
            .view
            .exact
            .measure(&self.scene, gbuffer_of(&frame)?, &frame.masks);
        let capture = Capture {
            frame,
            exact: m.exact,
            total: m.total,
            per_light: m.per_light,
        };
        Ok((capture, masks_ms))
    }

    /// [`learn_at_start`] on this bench's renderer, against the view's reference.
    pub(super) fn learn_auto(&mut self, options: &Options) -> Result<(), RenderError> {
        let reference = self.view.reference(&self.scene);
        learn_at_start(
            self.renderer,
            (&mut self.scene, &self.settings),
            options,
            reference,
        )
    }

    /// Whether every measured frame shows what the first shows: one camera, and a scene that
    /// stands (or is held). Sampling such frames again would draw the same masks.
    pub(super) fn path_is_still(&self) -> bool {
        self.settings.is_still(&self.scene)
    }

    /// Every measured frame of the path with `options`, its masks drawn (untimed) and sampled:
    /// the error along the path and, per frame, milliseconds of masks and of tracing; and
    /// what each light ran with at every frame of the path (`auto`'s choices).
    pub(super) fn sample_path(
        &mut self,
        options: &Options,
    ) -> Result<(Vec<PathSample>, Choices), RenderError> {
        let mut out: Vec<PathSample> = Vec::with_capacity(self.settings.frames);
        let mut choices: Choices = Vec::with_capacity(self.settings.frames);
        self.learn_auto(options)?;
        let moving = self.settings.scene_moves(&self.scene);
        let every = self.settings.sample_every.max(1);
        let auto = options.uses(self.scene.lights.len(), crate::options::Technique::Auto);
        for i in 0..self.settings.frames.max(1) {
            self.settings.pose(&mut self.scene, i);
            if i % every != 0 {
                // The frames between samples are drawn too, plain: every frame then moves
                // one step from the last, as the timed ones do, and the one after a sampled
                // frame is what that frame costs without sampling, at the same moment. The
                // others are timed pass by pass under `auto`, which learns each light's costs
                // from them as the path goes, as it does in the viewer.
                let passes = auto && i % every > 1;
                let plain_ms = self.plain_frame_ms(options, i, passes)?;
                choices.push(self.renderer.ran().to_vec());
                if let Some(last) = out.last_mut().filter(|l| l.0 + 1 == i) {
                    last.5 = Some(plain_ms);
                }
                continue;
            }
            let camera = self.settings.camera(&self.scene, i);
            // A moving scene's casters are where this frame put them: a reference of its
            // own, built again when a model moved (untimed, like the rest of the sampling).
            let reference = if moving {
                let key = models_key(&self.scene);
                let stale = self.posed_reference.as_ref().is_none_or(|(k, _)| *k != key);
                if stale {
                    self.posed_reference = Some((key, Reference::build(&self.scene)));
                }
                match &self.posed_reference {
                    Some((_, r)) => r,
                    None => self.view.exact.reference(&self.scene),
                }
            } else {
                self.view.exact.reference(&self.scene)
            };
            let s = render_sampled(
                self.renderer,
                &self.scene,
                &camera,
                options,
                reference,
                (i as u64, true, GBufferRead::Picks),
            )?;
            // `auto` judges its lights again by the errors sampled along the path, as the
            // viewer's live estimate has it do.
            self.renderer.record_errors(&s.sample.per_light, options);
            choices.push(self.renderer.ran().to_vec());
            out.push((i, s.sample, s.masks_ms, s.trace_ms, s.frame.frame_ms, None));
        }
        Ok((out, choices))
    }

    /// Path frame `i` drawn without masks (the scene posed for it), timed pass by pass with
    /// `passes`: its frame time.
    fn plain_frame_ms(
        &mut self,
        options: &Options,
        i: usize,
        passes: bool,
    ) -> Result<f64, RenderError> {
        let camera = self.settings.camera(&self.scene, i);
        let request = FrameRequest {
            frame_only: !passes,
            ..FrameRequest::default()
        };
        let frame = self
            .renderer
            .render_at(&self.scene, &camera, options, request)?;
        Ok(frame.frame_ms)
    }

    /// Whether [`Bench::error`] of `options` would be taken from the view, drawing nothing.
    pub(super) fn error_is_known(&self, options: &Options, sample: bool) -> bool {
        self.view
            .errors
            .get(&error_key(options))
            .is_some_and(|(_, sampled)| sampled.is_some() || !sample)
    }

    /// Error of `options` on the first frame of the path, with that frame's volume stats; with
    /// `sample`, also that frame's masks sampled against the reference (as `sample_path` would
    /// sample its frame 0, without drawing them again).
    pub(super) fn error(
        &mut self,
        options: &Options,
        sample: bool,
    ) -> Result<Errored, RenderError> {
        if self.error_is_known(options, sample) {
            let (error, sampled) = &self.view.errors[&error_key(options)];
            return Ok((error.clone(), sampled.clone().filter(|_| sample)));
        }
        let key = error_key(options);
        self.error_frames += 1;
        // Frusta kept from the path's last frames are sized for another view: the first frame's
        // error is the configuration's own, not its history's.
        self.renderer.forget_kept_frusta();
        self.learn_auto(options)?;
        let (c, masks_ms) = self.capture_timed(options)?;
        let sampled = if sample {
            let reference = self.view.exact.reference(&self.scene);
            let (s, trace_ms) = sample_masks(reference, &self.scene, (&c.frame, None), options, 0)?;
            Some((0, s, masks_ms, trace_ms, c.frame.frame_ms, None))
        } else {
            None
        };
        let error = FrameError {
            total: c.total,
            per_light: c.per_light,
            volumes: c.frame.volumes,
            plan: c.frame.plan_stats,
            cache: c.frame.cache,
            fallbacks: c.frame.fallbacks,
        };
        self.view
            .errors
            .insert(key, (error.clone(), sampled.clone()));
        Ok((error, sampled))
    }
}
