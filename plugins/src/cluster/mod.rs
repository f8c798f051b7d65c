//! The clustering of the rendering space (ALGORITHM.md sections 2 to 4): the cell grid and its
//! running sums, the feature vector of each cell, and clusters of cells. The cluster sampler
//! drives it; a reconstruction that needs clusters builds them with the same code.

pub mod clusters;
pub mod features;
pub mod grid;
pub mod queue;

pub use clusters::{Cluster, Clustering, Membership, Moments};
pub use features::{Feature, FeatureScale};
pub use grid::{CellGrid, CellSums};
