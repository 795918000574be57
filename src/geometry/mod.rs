//! Geometry every layer shares, free of scene data and GL: boxes, frusta and projection
//! matrices.

pub mod aabb;
pub mod clip;
pub mod frustum;
pub mod overlap;
pub mod projection;

pub use aabb::Aabb;
pub use frustum::Frustum;
