//! Frames measured while they run: a frame rendered with its masks, sampled against the exact
//! reference (`truth::sampled`), and the errors given to `technique = auto`.

use crate::frame::Frame;
use crate::images::GBuffer;
use crate::options::{Options, Technique};
use crate::plan::auto::learning_frames;
use crate::run::{FrameRequest, RenderError, Renderer};
use crate::scene::{Camera, Scene};
use crate::truth::Reference;
use crate::truth::sampled::{FrameSample, sample_frame};
use std::time::Instant;

/// How many times `estimate.samples` the learning frames trace.
pub const LEARNING_SAMPLES: u32 = 4;

/// A frame with its masks and its sampled error.
pub struct SampledFrame {
    pub frame: Frame,
    pub sample: FrameSample,
    /// Milliseconds spent drawing and reading the G-buffer and masks, after the timed frame.
    pub masks_ms: f64,
    /// Milliseconds spent tracing the samples.
    pub trace_ms: f64,
}

/// The G-buffer of a frame rendered with masks.
pub fn gbuffer_of(frame: &Frame) -> Result<&GBuffer, RenderError> {
    frame
        .gbuffer
        .as_ref()
        .ok_or(RenderError::Gl("the renderer returned no G-buffer".into()))
}

/// Samples a frame rendered with masks (`options.estimate.samples` pixels per light; `index`
/// numbers the frame's random streams); also gives the milliseconds the tracing took.
pub fn sample_masks(
    reference: &Reference,
    scene: &Scene,
    frame: &Frame,
    options: &Options,
    index: u64,
) -> Result<(FrameSample, f64), RenderError> {
    let gbuffer = gbuffer_of(frame)?;
    let start = Instant::now();
    let sample = sample_frame(
        reference,
        gbuffer,
        &scene.lights,
        &frame.masks,
        options.estimate.samples as usize,
        u64::from(options.estimate.seed),
        index,
    );
    Ok((sample, start.elapsed().as_secs_f64() * 1e3))
}

/// Renders a frame of `scene` from `camera` with its masks and samples them (see
/// [`sample_masks`]); `frame_only` times the frame without per-pass timing, as benchmarks do.
pub fn render_sampled(
    renderer: &mut Renderer,
    scene: &Scene,
    camera: &Camera,
    options: &Options,
    reference: &Reference,
    (index, frame_only): (u64, bool),
) -> Result<SampledFrame, RenderError> {
    let start = Instant::now();
    let frame = renderer.render_at(
        scene,
        camera,
        options,
        FrameRequest {
            masks: true,
            frame_only,
            ..FrameRequest::default()
        },
    )?;
    // The masks are drawn after the timed frame: the rest of the call is their cost.
    let masks_ms = (start.elapsed().as_secs_f64() * 1e3 - frame.frame_ms).max(0.0);
    let (sample, trace_ms) = sample_masks(reference, scene, &frame, options, index)?;
    Ok(SampledFrame {
        frame,
        sample,
        masks_ms,
        trace_ms,
    })
}

/// [`render_sampled`] with per-pass timing, giving the errors to the renderer's `auto`.
pub fn sampled_frame(
    renderer: &mut Renderer,
    scene: &Scene,
    camera: &Camera,
    options: &Options,
    reference: &Reference,
    index: u64,
) -> Result<SampledFrame, RenderError> {
    let s = render_sampled(renderer, scene, camera, options, reference, (index, false))?;
    renderer.record_errors(&s.sample.per_light, options);
    Ok(s)
}

/// The frames a one-frame command renders before the one it keeps, so that `auto` has run and
/// measured each technique of every light: sampled when `estimate.samples` is above 0 (its
/// error measured, not assumed), else timed only. Nothing when no light uses `auto`. These
/// frames trace `LEARNING_SAMPLES` times the samples: one frame each is all `auto` gets, and a
/// technique it does not run must show its whole interval under the target.
pub fn learn_auto(
    renderer: &mut Renderer,
    scene: &Scene,
    options: &Options,
    reference: Option<&Reference>,
) -> Result<(), RenderError> {
    if !options.uses(scene.lights.len(), Technique::Auto) {
        return Ok(());
    }
    let mut learning = options.clone();
    learning.estimate.samples = options.estimate.samples.saturating_mul(LEARNING_SAMPLES);
    for i in 0..learning_frames(options) {
        match reference.filter(|_| options.estimate.samples > 0) {
            Some(r) => {
                sampled_frame(renderer, scene, &scene.camera, &learning, r, i as u64)?;
            }
            None => {
                renderer.render_with(scene, options, FrameRequest::default())?;
            }
        }
    }
    Ok(())
}
