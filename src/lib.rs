//! shadowlab: the classic hardware shadow pipeline of Arneson's "Real-Time Shadows" (shadow maps
//! and stenciled shadow volumes on Quake 3 maps), with every fixed-function choice a runtime option,
//! measured against an exact ray-cast reference.
//!
//! Data flows one way: loaders → [`scene::Scene`] → [`plan::Plan`] → GL passes → [`frame::Frame`]
//! → reports.

pub mod frame;
pub mod fuzz_entry;
pub mod geometry;
pub mod gl;
pub mod images;
pub mod options;
pub mod plan;
pub mod presets;
pub mod q3;
pub mod report;
pub mod run;
pub mod scene;
pub mod scene_file;
pub mod shadow;
pub mod truth;
pub mod viewer;
