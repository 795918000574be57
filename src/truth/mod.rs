//! The exact reference and the error measured against it (GL-free).

pub mod enclosure;
pub mod masks;
pub mod measure;
pub mod metrics;
pub mod recorded;
pub mod reference;
pub mod sampled;
pub mod subdivision;
pub mod tile_order;

pub use masks::{Tracing, compare_majority, majority, reference_mask};
pub use measure::{ExactMasks, Measurement, exact_mask, measure, measure_with};
pub use metrics::{
    Counts, MaskDifference, Rates, compare, compare_where, error_image, error_image_all,
    mask_difference,
};
pub use reference::{Blocker, Reference};
