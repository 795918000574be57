//! Shadow algorithms' CPU side: edge connectivity, shadow volumes and light views.

pub mod edges;
pub mod extrusion;
pub mod frusta;
pub mod parts;
pub mod views;
pub mod volume;
pub mod warp;
