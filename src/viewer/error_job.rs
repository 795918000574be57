//! The error view's work: exact reference masks for a frame's G-buffer, computed on a worker
//! thread so that the window stays live, with progress (one step for the BVH, one per light).

use crate::frame::Frame;
use crate::images::Rgba;
use crate::scene::Scene;
use crate::truth::{self, Counts, Reference};
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::thread::JoinHandle;

/// What the reference says about a frame.
#[derive(Debug, Clone)]
pub struct ErrorResult {
    /// Red false shadow, blue false lit, greys correct, yellow receiver mismatch.
    pub image: Rgba,
    pub total: Counts,
    pub per_light: Vec<(usize, Counts)>,
}

pub struct ErrorJob {
    done: Arc<AtomicUsize>,
    total: usize,
    handle: Option<JoinHandle<Option<ErrorResult>>>,
    /// What the frame was rendered from (camera, options, scene edits), to know when the
    /// result no longer applies.
    pub key: u64,
}

impl ErrorJob {
    /// Starts on a frame rendered with masks.
    pub fn start(scene: Arc<Scene>, frame: &Frame, key: u64) -> ErrorJob {
        let done = Arc::new(AtomicUsize::new(0));
        let total = frame.masks.len() + 1;
        let gbuffer = frame.gbuffer.clone();
        let masks = frame.masks.clone();
        let (width, height) = (frame.width(), frame.height());
        let progress = done.clone();
        let handle = std::thread::spawn(move || {
            let gbuffer = gbuffer?;
            let reference = Reference::build(&scene);
            progress.fetch_add(1, Ordering::Relaxed);
            let measured = truth::measure_with(&masks, |m| {
                let e = truth::exact_mask(&scene, &reference, &gbuffer, m);
                progress.fetch_add(1, Ordering::Relaxed);
                e
            });
            let rendered: Vec<&crate::images::Mask> = masks.iter().collect();
            let exact_refs: Vec<&crate::images::Mask> = measured.exact.iter().collect();
            Some(ErrorResult {
                image: Rgba {
                    width,
                    height,
                    data: truth::error_image_all(&rendered, &exact_refs),
                },
                total: measured.total,
                per_light: measured.per_light,
            })
        });
        ErrorJob {
            done,
            total,
            handle: Some(handle),
            key,
        }
    }

    /// Fraction done, 0 to 1.
    pub fn progress(&self) -> f32 {
        self.done.load(Ordering::Relaxed) as f32 / self.total.max(1) as f32
    }

    /// The result once the worker has finished (`None` while it runs, or if it failed).
    pub fn poll(&mut self) -> Option<ErrorResult> {
        if self.handle.as_ref().is_some_and(|h| h.is_finished()) {
            return self.handle.take()?.join().ok().flatten();
        }
        None
    }

    pub fn finished(&self) -> bool {
        self.handle.is_none()
    }
}
