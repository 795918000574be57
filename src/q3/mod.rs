//! Quake 3 content: pk3 archives, IBSP v46 maps, Bezier patches, shader scripts, MD3 models,
//! entities and DarkPlaces `.rtlights` files. Everything here is GL-free and never panics on bad
//! input: each loader returns a `thiserror` error naming what is wrong.

pub mod bsp;
pub mod builder;
pub(crate) mod bytes;
pub mod entities;
pub mod md3;
pub mod model;
pub mod patch;
pub mod pk3;
pub mod rtlights;
pub mod shader;
pub mod textures;
pub mod world;
