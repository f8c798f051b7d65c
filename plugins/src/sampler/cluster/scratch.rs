//! The cluster sampler's scratch: buffers kept from round to round only so that each round
//! need not allocate (fresh ones cost page faults). Nothing in them is read across calls;
//! its state is [`super::state::State`].

use super::state::Round;
use crate::cells::cell_features::Squashed;
use crate::cells::grid::MAX_DIMS;

/// Buffers reused between rounds, each empty (or meaningless) between calls.
#[derive(Default)]
pub(super) struct Scratch {
    /// The cell and in-cell offsets of each point of the round being planned (or of the
    /// first stage's batch being observed), in batch order.
    pub round_cells: Vec<(u32, [f32; MAX_DIMS])>,
    /// Observed rounds' buffers, for the next rounds.
    pub spare: Vec<Round>,
    /// The pixel (row << 32 | column, from the space's corner) of each point drawn in a
    /// round, in draw order.
    pub drawn: Vec<u64>,
    /// A bit per cell: whether it got samples since the last update (set by an observation,
    /// cleared by the update that follows it in the same call).
    pub touched: Vec<u64>,
    /// A bit per cluster, clear between updates: the update's scratch for listing each
    /// changed cluster once.
    pub cluster_marks: Vec<u64>,
    /// The cells an update recomputes.
    pub dirty: Vec<u32>,
    /// What an update reads of each of those cells' sums.
    pub cell_updates: Vec<CellUpdate>,
    /// The cells whose features an update changed.
    pub changes: Vec<Change>,
    /// The sample counts of the clusters a round picked (see `requeue_picked`).
    pub counts: Vec<u64>,
}

impl Scratch {
    /// Empty buffers, with a clear bit for each of `cells` cells.
    pub fn new(cells: usize) -> Self {
        Self {
            touched: vec![0; cells.div_ceil(64)],
            ..Self::default()
        }
    }

    /// Bytes held by the buffers that grow with the cells.
    pub fn bytes(&self) -> usize {
        self.touched.capacity() * 8
    }
}

/// A cell whose feature changed in an update, with what the serial moves need of it.
#[derive(Clone, Copy, Debug)]
pub(super) struct Change {
    /// The cell.
    pub cell: u32,
    /// Its squashed feature before.
    pub old: Squashed,
    /// Its squashed feature now.
    pub new: Squashed,
    /// Its samples.
    pub samples: u32,
}

/// What an update reads of a touched cell's own sums (an empty neighbour's: its level alone).
#[derive(Clone, Copy, Debug)]
pub(super) struct CellUpdate {
    /// Its new level.
    pub level: f32,
    /// Its raw variance feature (0 for an empty neighbour).
    pub variance: f32,
    /// Its samples.
    pub samples: u32,
}
