//! The clustering of the rendering space (docs/algorithm.md §2 to §4): the cell grid and its
//! running sums, the feature vector of each cell, and clusters of cells. The cluster sampler
//! drives it; a reconstruction that needs clusters builds them with the same code.

pub mod build;
pub mod by_noise;
pub mod clusters;
pub mod features;
pub mod grid;
pub mod queue;
pub mod sums;

pub use clusters::{Cluster, Clustering, Membership, Moments};
pub use features::{Feature, FeatureScale};
pub use grid::CellGrid;
pub use sums::CellSums;

/// A grid's cells, their sums and, when a sampler made them, their clusters: what the
/// polynomial reconstruction reads.
#[derive(Clone, Copy, Debug)]
pub struct CellView<'a> {
    /// The grid.
    pub grid: &'a CellGrid,
    /// Each cell's running sums.
    pub sums: &'a CellSums,
    /// The clusters of the cells, if made (else the reconstruction makes them).
    pub clustering: Option<&'a Clustering>,
}
