//! Rows kept by content ([`RowStore`]): a bench takes the configurations its store holds
//! instead of measuring them again.

use super::{Bench, BenchConfig, BenchSettings, View, options_key};
use crate::report::store::{RowStore, key, scene_fingerprint};
use std::collections::HashMap;

/// What one bench of a scene hands on to the next: the rows kept, the exact masks and
/// errors of its first view, and what each configuration's renderer held.
#[derive(Default)]
pub struct Kept {
    pub store: RowStore,
    pub view: View,
    pub held: HashMap<String, u64>,
}

impl<'a> Bench<'a> {
    /// Keeps rows in `store`, shared with other benches and runs: configurations it holds
    /// (same code, GL, scene content, options and frame settings) are taken from it.
    pub fn with_store(mut self, store: RowStore) -> Bench<'a> {
        self.put_store(store);
        self
    }

    /// [`Bench::with_store`] on a bench already made.
    pub fn put_store(&mut self, store: RowStore) {
        if self.fingerprint.is_empty() {
            self.fingerprint = scene_fingerprint(&self.scene);
        }
        self.store = store;
    }

    /// Measures with what an earlier bench of the same scene kept.
    pub fn with_kept(mut self, kept: Kept) -> Bench<'a> {
        self.put_kept(kept);
        self
    }

    /// [`Bench::with_kept`] on a bench already made.
    pub fn put_kept(&mut self, kept: Kept) {
        self.put_store(kept.store);
        self.put_view(kept.view);
        self.held.extend(kept.held);
    }

    /// Takes what this bench kept (for the next bench of the scene), leaving it none.
    pub fn take_kept(&mut self) -> Kept {
        Kept {
            store: std::mem::take(&mut self.store),
            view: self.take_view(),
            held: std::mem::take(&mut self.held),
        }
    }

    /// The rows kept, and how many were reused.
    pub fn store(&self) -> &RowStore {
        &self.store
    }

    /// The store's key of `c`'s row: everything the row depends on but the code.
    pub(super) fn row_key(&self, c: &BenchConfig) -> String {
        // Every setting but the progress bar, so that a setting added later is in the key too.
        let frames = format!(
            "{:?}",
            BenchSettings {
                progress: false,
                ..self.settings.clone()
            }
        );
        let caps = self.renderer.caps();
        let gl = format!("{} {} {}", caps.renderer, caps.version, caps.vendor);
        key(&[&gl, &self.fingerprint, &options_key(&c.options), &frames])
    }
}
