//! Kind `detp` (being built).

use crate::spec::DetpConfig;

/// One DETP point.
pub fn run_point(
    _cfg: &DetpConfig,
    _point: u64,
    _progress: &(dyn Fn(u64) + Sync),
) -> anyhow::Result<super::PointResult> {
    anyhow::bail!("kind detp is not built yet")
}

/// One line describing a DETP point for `raycost check`.
pub fn describe(cfg: &DetpConfig) -> String {
    format!("{} rays", cfg.photons)
}
