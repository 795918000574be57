//! Reports: benchmark runs, their tables and figures.

pub mod bench;
pub mod plot;
pub mod table;
