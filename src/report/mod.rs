//! Reports: benchmark runs, their tables and figures.

pub mod bench;
pub mod check;
pub mod estimate;
pub mod flythrough;
pub mod images;
pub mod plot;
pub mod progress;
pub mod reproduce;
pub mod shard;
pub mod store;
pub mod table;
pub mod tune;
