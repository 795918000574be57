//! `shadowlab view`: the walkthrough viewer. A window (winit + glutin) with the renderer's frame
//! and an egui interface: fly through the scene, switch techniques per light, edit every option,
//! look at the depth maps, stencil counts, volumes and errors, and step through a frame pass by
//! pass. Scripts (`--script`) drive it without a person, for tests and screenshots.

pub mod edit;
pub mod error_job;
pub mod fly;
pub mod live_error;
pub mod option_panel;
pub mod script;
pub mod state;
pub mod walkthrough;
// The window, its event loop and the egui interface: only with the `window` feature, so that the
// loaders and the headless renderer build without winit and egui (the fuzz targets do).
#[cfg(feature = "window")]
mod app;
#[cfg(feature = "window")]
pub mod ui;

#[cfg(feature = "window")]
pub use app::{ViewerError, ViewerSettings, run};
