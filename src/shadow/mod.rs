//! Shadow algorithms' CPU side: edge connectivity, projections and light frusta.

pub mod edges;
pub mod projection;
pub mod views;
pub mod volume;
