//! Everything that talks to OpenGL. It executes plans; it decides nothing about what to draw.

pub mod caps;
pub mod context;
pub mod debug;
pub mod depth_bounds_ext;
pub mod depth_reduce;
pub mod egl;
pub mod extrusion;
pub mod fixed;
pub mod fragments;
pub mod gather;
pub mod id_tables;
pub mod legacy;
mod offset_probe;
pub mod osmesa;
pub mod passes;
mod primitive_id_probe;
pub mod priority_mips;
pub mod program;
pub mod query_ring;
pub mod record;
pub mod renderer;
mod scratch;
pub mod shadow_maps;
pub mod syncs;
pub mod target;
pub mod timing;
pub mod upload;
pub mod volumes;
#[cfg(feature = "window")]
pub mod window;

pub use context::{Backend, ContextError, GlApi, GlContext, Profile, create_context};
pub use renderer::{Drawer, FILL_SHADE, FrameRequest, FrameTexture, Overlays, RenderError};
