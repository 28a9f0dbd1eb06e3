//! Scene sources of kind `detp`: photons traced from a scene file, points on its surfaces or read
//! from a CSV, and the photon-map baseline (arriving with the light-transport layer).

use super::{PointSet, RaySet};
use crate::detp::disc::Discs;
use crate::detp::store::SegmentStore;
use crate::spec::DetpConfig;

/// Sample points on the scene's surfaces or from a CSV.
pub(super) fn points(_cfg: &DetpConfig, _point: u64) -> anyhow::Result<PointSet> {
    anyhow::bail!("scene sources are not built yet")
}

/// Photons of one replica.
pub(super) fn photons(_cfg: &DetpConfig, _point: u64, _replica: u64) -> anyhow::Result<RaySet> {
    anyhow::bail!("scene sources are not built yet")
}

/// The photon-map estimate at every disc.
pub(super) fn photon_map(
    _cfg: &DetpConfig,
    _store: &SegmentStore,
    _discs: &Discs,
) -> anyhow::Result<Vec<f64>> {
    anyhow::bail!("scene sources are not built yet")
}
