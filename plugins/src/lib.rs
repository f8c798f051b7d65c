//! acr-plugins: sampler and reconstruction-filter plugins over the abstract rendering space.
//! Nothing here knows about geometry, so every plugin is testable on analytic integrands.

pub mod filters;

pub use filters::{FilterKernel, Kernel};
