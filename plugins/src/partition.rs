//! A sampler's partition of the film into clusters, as a reconstruction filter receives it.

/// Which cluster each pixel of the (cropped) film belongs to.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Partition {
    /// Film width in pixels.
    pub width: u32,
    /// Film height in pixels.
    pub height: u32,
    /// Each pixel's cluster, row-major.
    pub cluster: Vec<u32>,
}

impl Partition {
    /// How many clusters there are (one more than the largest id; 0 when empty).
    pub fn clusters(&self) -> usize {
        self.cluster.iter().max().map_or(0, |&m| m as usize + 1)
    }
}
