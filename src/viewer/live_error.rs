//! The viewer's live error: each frame's masks sampled against the exact reference
//! (`truth::sampled`) as the frames run, each light's estimate pooled over the last
//! `estimate.window` frames. The reference (a BVH of the scene's casters) is built once on a
//! worker thread; until it is ready the overlay says so.

use crate::options::{Options, Technique};
use crate::report::estimate::{gather_picks, sample_masks};
use crate::scene::Scene;
use crate::truth::Reference;
use crate::truth::sampled::{FrameSample, Interval, Running};
use std::collections::{BTreeMap, HashMap};
use std::sync::Arc;
use std::thread::JoinHandle;

/// A light's running estimate and the technique it ran with.
#[derive(Debug, Clone)]
pub struct LightEstimate {
    pub technique: Option<Technique>,
    pub error: Interval,
    /// Frames pooled.
    pub frames: usize,
}

#[derive(Default)]
pub struct LiveError {
    pub on: bool,
    reference: Option<Arc<Reference>>,
    building: Option<JoinHandle<Reference>>,
    /// Per light and technique, the last frames' samples.
    running: HashMap<(usize, Option<Technique>), Running>,
    /// The technique each light ran with in the last sampled frame.
    last: BTreeMap<usize, Option<Technique>>,
    frames: u64,
    /// Milliseconds the last frame's sample took: the G-buffer read where it picks, and the
    /// tracing.
    pub trace_ms: f64,
    /// The last frame's sample, all lights.
    pub last_frame: Option<FrameSample>,
    /// The options the estimates were taken under (a change starts them again).
    options: String,
    /// Milliseconds of frames and of sampling (masks and tracing) since it was turned on.
    frame_ms: f64,
    sampling_ms: f64,
    /// A running mean of the frames drawn without sampling, against which a sampled frame's
    /// own excess (its base pass writing the G-buffer, its lights recording) counts as
    /// sampling.
    plain_frame_ms: Option<f64>,
}

impl LiveError {
    /// Whether this frame should be drawn with masks for sampling: on, the reference built,
    /// and the sampling so far under `budget` times the frames' time.
    pub fn wants_masks(&mut self, scene: &Arc<Scene>, budget: f64) -> bool {
        if !self.on {
            self.frame_ms = 0.0;
            self.sampling_ms = 0.0;
            return false;
        }
        if self.reference.is_none() && self.building.is_none() {
            let scene = scene.clone();
            self.building = Some(std::thread::spawn(move || Reference::build(&scene)));
        }
        if self.building.as_ref().is_some_and(|h| h.is_finished())
            && let Some(h) = self.building.take()
        {
            self.reference = h.join().ok().map(Arc::new);
        }
        self.reference.is_some() && self.sampling_ms <= budget * self.frame_ms
    }

    /// Counts a frame's time and, when it was sampled, what sampling cost after it: its
    /// excess over the frames drawn without sampling counts as sampling too.
    pub fn spend(&mut self, frame_ms: f64, sampling_ms: Option<f64>) {
        let Some(sampling_ms) = sampling_ms else {
            let mean = self
                .plain_frame_ms
                .map_or(frame_ms, |m| 0.9 * m + 0.1 * frame_ms);
            self.plain_frame_ms = Some(mean);
            self.frame_ms += frame_ms;
            return;
        };
        let plain = self.plain_frame_ms.unwrap_or(frame_ms).min(frame_ms);
        self.frame_ms += plain;
        self.sampling_ms += sampling_ms + (frame_ms - plain);
    }

    /// The share of frame time spent sampling since it was turned on.
    pub fn share(&self) -> f64 {
        if self.frame_ms > 0.0 {
            self.sampling_ms / self.frame_ms
        } else {
            0.0
        }
    }

    /// Frames sampled since the viewer started.
    pub fn sampled_frames(&self) -> u64 {
        self.frames
    }

    /// Whether the reference is still being built.
    pub fn building(&self) -> bool {
        self.building.is_some()
    }

    /// Forgets the reference (the scene's surfaces changed) and the estimates.
    pub fn reset(&mut self) {
        self.reference = None;
        self.building = None;
        self.running.clear();
        self.last.clear();
        self.last_frame = None;
    }

    /// Samples a frame drawn with masks; `techniques` are what each light ran with. Returns the
    /// frame's samples per light, for `auto`.
    pub fn sample(
        &mut self,
        scene: &Scene,
        frame: &crate::frame::Frame,
        renderer: &mut crate::run::Renderer,
        options: &Options,
    ) -> Option<&FrameSample> {
        let reference = self.reference.as_ref()?;
        let start = std::time::Instant::now();
        // The G-buffer where the sample picks, when the frame left it on the GPU.
        let gathered = gather_picks(renderer, scene, frame, options, self.frames).ok()?;
        let gather_ms = start.elapsed().as_secs_f64() * 1e3;
        let text = serde_json::to_string(options).unwrap_or_default();
        if text != self.options {
            self.running.clear();
            self.options = text;
        }
        let at = (frame, gathered.as_ref());
        let (s, trace_ms) = sample_masks(reference, scene, at, options, self.frames).ok()?;
        self.trace_ms = gather_ms + trace_ms;
        self.frames += 1;
        let techniques: BTreeMap<usize, Technique> = frame
            .steps
            .iter()
            .filter_map(|st| Some((st.light?, st.technique?)))
            .collect();
        self.last.clear();
        for l in &s.per_light {
            let t = techniques.get(&l.light).copied();
            self.last.insert(l.light, t);
            self.running
                .entry((l.light, t))
                .or_insert_with(|| Running::new(options.estimate.window as usize))
                .push(*l);
        }
        self.last_frame = Some(s);
        self.last_frame.as_ref()
    }

    /// Each light of the last sampled frame: its technique and its running estimate.
    pub fn lights(&self) -> Vec<(usize, LightEstimate)> {
        self.last
            .iter()
            .filter_map(|(&light, &technique)| {
                let r = self.running.get(&(light, technique))?;
                Some((
                    light,
                    LightEstimate {
                        technique,
                        error: r.estimate()?,
                        frames: r.frames(),
                    },
                ))
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::LiveError;

    #[test]
    fn a_sampled_frames_excess_over_the_plain_frames_counts_as_sampling() {
        let mut live = LiveError::default();
        live.spend(20.0, None);
        live.spend(20.0, None);
        // 6 ms more than a plain frame (the G-buffer, the record), then 2 ms of masks and rays.
        live.spend(26.0, Some(2.0));
        assert!(
            (live.share() - 8.0 / 60.0).abs() < 1e-12,
            "{}",
            live.share()
        );
        // Faster than the plain frames: nothing of the frame counts as sampling.
        live.spend(15.0, Some(1.0));
        assert!(
            (live.share() - 9.0 / 75.0).abs() < 1e-12,
            "{}",
            live.share()
        );
    }
}
