//! The sampled reference along a bench's path: per frame, per light pooled over the path, and
//! what sampling cost beside the frame.

use super::error::PathSample;
use super::stats::median;
use crate::truth::sampled::{Interval, LightSample, pooled};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// One frame of the path against the sampled reference.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SampledFrame {
    /// Index into the path.
    pub frame: usize,
    /// The error over every light's receivers, with its 95% interval.
    pub error: Interval,
    /// Shadow rays traced.
    pub rays: usize,
}

/// The sampled reference along the path, and what it cost.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SampledPath {
    /// Pixels traced per light and frame.
    pub samples_per_light: u32,
    pub frames: Vec<SampledFrame>,
    /// Median and largest per-frame error (fractions).
    pub median: f64,
    pub max: f64,
    /// Median milliseconds per frame to draw and read the G-buffer and masks (untimed: within
    /// the frame where a mask reads work the frame did, after it otherwise).
    pub masks_ms: f64,
    /// Median milliseconds per frame to trace the samples (rayon, every core).
    pub trace_ms: f64,
    /// What the G-buffer and the record add to a frame along a path: the median excess of
    /// each sampled frame over the plain one drawn right after it (sampled every few frames),
    /// else of the sampled frames' median over the configuration's; 0 on a still camera.
    #[serde(default)]
    pub frame_extra_ms: f64,
    /// `frame_extra_ms + masks_ms + trace_ms` over the configuration's median frame time:
    /// what sampling every frame would add to it.
    pub share_of_frame: f64,
    /// Median milliseconds of the sampled frames themselves: beside the configuration's frame
    /// time, what recording each light's decision in its lit pass (`gl::record`) adds.
    #[serde(default)]
    pub frame_ms: f64,
    /// Each light's error pooled over the sampled frames, worst first: what a target per
    /// light (`accuracy`) is held to along the path.
    #[serde(default)]
    pub lights: Vec<LightOnPath>,
    /// What the lights ran with along the path, every frame (sampled or plain) counted, in
    /// light-frames by candidate (as the row's `ran` counts its timed frames).
    #[serde(default)]
    pub ran: BTreeMap<String, usize>,
}

/// One light's sampled error over a path's sampled frames.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct LightOnPath {
    pub light: usize,
    /// Its receivers' share decided wrong, pooled over the frames, with its 95% interval.
    pub error: Interval,
    /// Sampled frames it was sampled in.
    pub frames: usize,
    /// Frames of the path (sampled or plain) it was planned in, by what it ran with: under
    /// `auto`, when it chose what.
    #[serde(default)]
    pub ran: BTreeMap<String, usize>,
}

impl SampledPath {
    /// `frames` sampled, against the configuration's median `frame_ms`; `along_path`: sampled
    /// frame by frame along the path rather than once on a still camera.
    pub(super) fn new(
        samples: u32,
        frames: Vec<PathSample>,
        (frame_ms, along_path): (f64, bool),
    ) -> SampledPath {
        let mut errors: Vec<f64> = frames.iter().map(|f| f.1.total.value).collect();
        let mut masks: Vec<f64> = frames.iter().map(|f| f.2).collect();
        let mut trace: Vec<f64> = frames.iter().map(|f| f.3).collect();
        let mut own: Vec<f64> = frames.iter().map(|f| f.4).collect();
        let (masks_ms, trace_ms) = (median(&mut masks), median(&mut trace));
        let sampled_frame_ms = median(&mut own);
        // Each sampled frame against the plain frame drawn right after it where there is one
        // (the same motion, moments apart); else against the timed frames, drawn earlier.
        let mut paired: Vec<f64> = frames.iter().filter_map(|f| Some(f.4 - f.5?)).collect();
        let frame_extra_ms = match (along_path, paired.is_empty()) {
            (false, _) => 0.0,
            (true, false) => median(&mut paired).max(0.0),
            (true, true) => (sampled_frame_ms - frame_ms).max(0.0),
        };
        SampledPath {
            lights: lights_on_path(&frames),
            samples_per_light: samples,
            max: errors.iter().copied().fold(0.0, f64::max),
            median: median(&mut errors),
            frames: frames
                .into_iter()
                .map(|(i, f, ..)| SampledFrame {
                    frame: i,
                    error: f.total,
                    rays: f.rays,
                })
                .collect(),
            masks_ms,
            trace_ms,
            frame_extra_ms,
            share_of_frame: if frame_ms > 0.0 {
                (frame_extra_ms + masks_ms + trace_ms) / frame_ms
            } else {
                0.0
            },
            frame_ms: sampled_frame_ms,
            ran: BTreeMap::new(),
        }
    }
}

/// Each light's sampled error pooled over the sampled frames of a path (each frame weighted by
/// the light's receivers in it), worst first; lights with no receiver in any frame left out.
fn lights_on_path(frames: &[PathSample]) -> Vec<LightOnPath> {
    let mut by_light: BTreeMap<usize, Vec<LightSample>> = BTreeMap::new();
    for (_, sample, ..) in frames {
        for l in &sample.per_light {
            by_light.entry(l.light).or_default().push(*l);
        }
    }
    let mut out: Vec<LightOnPath> = by_light
        .into_iter()
        .filter(|(_, parts)| parts.iter().any(|p| p.receivers > 0.0))
        .map(|(light, parts)| LightOnPath {
            light,
            error: pooled(&parts),
            frames: parts.len(),
            ran: BTreeMap::new(),
        })
        .collect();
    out.sort_by(|a, b| b.error.value.total_cmp(&a.error.value));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sampled frame's excess is over the plain frame drawn right after it: 50, 20, 60 ms
    /// over 45, 18, 52 is 5, 2, 8, median 5 (the medians over a configuration's 40 ms: 10).
    #[test]
    fn sampled_frames_are_weighed_against_the_plain_frame_after_them() {
        let frame = |i, own, plain| (i, Default::default(), 1.0, 0.5, own, plain);
        let paired = vec![
            frame(0, 50.0, Some(45.0)),
            frame(4, 20.0, Some(18.0)),
            frame(8, 60.0, Some(52.0)),
        ];
        let p = SampledPath::new(512, paired, (40.0, true));
        assert_eq!(p.frame_extra_ms, 5.0);
        assert_eq!(p.frame_ms, 50.0);
        assert_eq!(p.share_of_frame, (5.0 + 1.0 + 0.5) / 40.0);
        let unpaired = vec![frame(0, 50.0, None), frame(1, 44.0, None)];
        assert_eq!(
            SampledPath::new(512, unpaired.clone(), (40.0, true)).frame_extra_ms,
            7.0
        );
        // A still camera's one sampled frame is the cold first one: no excess counted.
        assert_eq!(
            SampledPath::new(512, unpaired, (40.0, false)).frame_extra_ms,
            0.0
        );
    }

    /// A light's error along the path is pooled over its frames by its receivers: light 2 at
    /// 1% of 300 receivers and 0% of 100 is 0.75%, above light 5 at 0.5% in both; a light with
    /// no receivers anywhere is left out.
    #[test]
    fn each_lights_error_is_pooled_over_the_path_worst_first() {
        use crate::truth::sampled::{FrameSample, LightSample};
        let light = |light, receivers, value| LightSample {
            light,
            receivers,
            samples: 100,
            effective: 100.0,
            exact: false,
            error: Interval::wilson(value, 100.0, false),
            alpha_holes: Interval::default(),
        };
        let frame = |i, lights: Vec<LightSample>| {
            let sample = FrameSample {
                per_light: lights,
                ..FrameSample::default()
            };
            (i, sample, 1.0, 0.5, 40.0, None)
        };
        let frames = vec![
            frame(
                0,
                vec![
                    light(2, 300.0, 0.01),
                    light(5, 50.0, 0.005),
                    light(7, 0.0, 0.0),
                ],
            ),
            frame(
                4,
                vec![
                    light(2, 100.0, 0.0),
                    light(5, 50.0, 0.005),
                    light(7, 0.0, 0.0),
                ],
            ),
        ];
        let p = SampledPath::new(512, frames, (40.0, true));
        let got: Vec<(usize, usize)> = p.lights.iter().map(|l| (l.light, l.frames)).collect();
        assert_eq!(got, [(2, 2), (5, 2)]);
        assert!((p.lights[0].error.value - 0.0075).abs() < 1e-12);
        assert!((p.lights[1].error.value - 0.005).abs() < 1e-12);
        assert!(p.lights[0].error.low < 0.0075 && p.lights[0].error.high > 0.0075);
    }
}
