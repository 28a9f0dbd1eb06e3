//! The DETP irradiance at a view's discs, from a store of photon segments, through a grid disc
//! index (every segment walks it once; sums are exact integers).

use crate::detp::disc::Discs;
use crate::detp::disc_index::{DiscIndex, GridIndex};
use crate::detp::fixed::Acc;
use crate::detp::store::SegmentStore;

/// Cells the grid may have at most (its offsets take 4 bytes a cell).
const MAX_CELLS: f64 = (1u64 << 24) as f64;

/// Sums of power units per disc (in `discs` order).
pub fn gather(discs: &Discs, store: &SegmentStore) -> Vec<Acc> {
    let mut acc = vec![0; discs.len()];
    if discs.is_empty() {
        return acc;
    }
    // Cell width 2d, widened if the discs' box would need more than MAX_CELLS cells.
    let b = discs.bounds_all();
    let ext = (b.hi - b.lo).max(glam::DVec3::splat(discs.radius));
    let w = (2.0 * discs.radius).max((ext.x * ext.y * ext.z / MAX_CELLS).cbrt());
    let index = GridIndex::build(discs, w);
    index.accumulate(store, None, 1, &mut acc);
    acc
}
