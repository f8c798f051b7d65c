//! sppm's tests: settings, the grid, the per-pixel update.
