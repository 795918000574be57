//! Frames measured while they run: a frame rendered with its masks, sampled against the exact
//! reference (`truth::sampled`), and the errors given to `technique = auto`.

use crate::frame::Frame;
use crate::images::{GBuffer, GBufferPicks};
use crate::options::{Options, Technique};
use crate::plan::auto::learning_frames;
use crate::run::{FrameRequest, RenderError, Renderer};
use crate::scene::{Camera, Scene};
use crate::truth::Reference;
use crate::truth::sampled::{FrameSample, Picks, frame_picks, picked_pixels, sample_picked};
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

/// The picks of a frame whose G-buffer stayed on the GPU, and the G-buffer read at them.
pub struct Gathered {
    pub picks: Vec<Picks>,
    pub gbuffer: GBufferPicks,
}

/// Samples a frame rendered with masks (`options.estimate.samples` pixels per light; `index`
/// numbers the frame's random streams) over its G-buffer, or at the picks `gathered` read
/// where it stayed on the GPU ([`gather_picks`]); also gives the milliseconds the tracing
/// took.
pub fn sample_masks(
    reference: &Reference,
    scene: &Scene,
    (frame, gathered): (&Frame, Option<&Gathered>),
    options: &Options,
    index: u64,
) -> Result<(FrameSample, f64), RenderError> {
    let start = Instant::now();
    let (lights, masks) = (&scene.lights, &frame.masks);
    let sample = match gathered {
        Some(g) => sample_picked(reference, &g.gbuffer, lights, masks, &g.picks),
        None => {
            let picks = picks_of_frame(scene, frame, options, index);
            sample_picked(reference, gbuffer_of(frame)?, lights, masks, &picks)
        }
    };
    Ok((sample, start.elapsed().as_secs_f64() * 1e3))
}

/// The picks [`sample_masks`] will trace and the G-buffer read at them through `renderer`,
/// when the frame left it on the GPU (`FrameRequest::gbuffer_kept`); None when the frame has
/// it whole.
pub fn gather_picks(
    renderer: &mut Renderer,
    scene: &Scene,
    frame: &Frame,
    options: &Options,
    index: u64,
) -> Result<Option<Gathered>, RenderError> {
    if frame.gbuffer.is_some() {
        return Ok(None);
    }
    let picks = picks_of_frame(scene, frame, options, index);
    let gbuffer = renderer.gbuffer_at(picked_pixels(&picks))?;
    Ok(Some(Gathered { picks, gbuffer }))
}

/// The frame's picks: `options.estimate.samples` per light, from the streams `index` numbers.
fn picks_of_frame(scene: &Scene, frame: &Frame, options: &Options, index: u64) -> Vec<Picks> {
    let n = options.estimate.samples as usize;
    let seed = u64::from(options.estimate.seed);
    frame_picks(&scene.lights, &frame.masks, n, seed, index)
}

/// How much of the G-buffer a sampled frame reads back.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GBufferRead {
    /// Only the pixels the sample traces (`Frame::gbuffer` stays None).
    Picks,
    /// All of it, for a caller that uses the frame's G-buffer besides the sample.
    Whole,
}

/// Renders a frame of `scene` from `camera` with its masks and samples them (see
/// [`sample_masks`]); `frame_only` times the frame without per-pass timing, as benchmarks do.
pub fn render_sampled(
    renderer: &mut Renderer,
    scene: &Scene,
    camera: &Camera,
    options: &Options,
    reference: &Reference,
    (index, frame_only, read): (u64, bool, GBufferRead),
) -> Result<SampledFrame, RenderError> {
    let start = Instant::now();
    let frame = renderer.render_at(
        scene,
        camera,
        options,
        FrameRequest {
            masks: true,
            frame_only,
            gbuffer_kept: read == GBufferRead::Picks,
            ..FrameRequest::default()
        },
    )?;
    let gathered = gather_picks(renderer, scene, &frame, options, index)?;
    // The masks (and the G-buffer's picked pixels) are read after the timed frame: the rest
    // of the call is their cost.
    let masks_ms = (start.elapsed().as_secs_f64() * 1e3 - frame.frame_ms).max(0.0);
    let (sample, trace_ms) = sample_masks(
        reference,
        scene,
        (&frame, gathered.as_ref()),
        options,
        index,
    )?;
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
    (index, read): (u64, GBufferRead),
) -> Result<SampledFrame, RenderError> {
    let s = render_sampled(
        renderer,
        scene,
        camera,
        options,
        reference,
        (index, false, read),
    )?;
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
                let at = (i as u64, GBufferRead::Picks);
                sampled_frame(renderer, scene, &scene.camera, &learning, r, at)?;
            }
            None => {
                renderer.render_with(scene, options, FrameRequest::default())?;
            }
        }
    }
    Ok(())
}
