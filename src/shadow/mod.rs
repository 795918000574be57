//! Shadow algorithms' CPU side: projections and light frusta (more arrives with each technique).

pub mod projection;
