//! Estimator `photon-map-growing`: the photon map with k(N) = k₀·(N/N₀)^β growing with the photons
//! so that its error keeps falling (its engine is the photon map's; its errors are written as
//! every baseline's, `photon_map_growing_ref_*`).

use super::photon_map::{kd_tree, needs_a_scene, MapMeasured, Runs, NO_SHARDS};
use super::{Crossover, Estimator, Role, Shards};
use crate::output::column::{Class, Column};
use crate::experiment::detp::columns::*;
use crate::experiment::detp::config::DetpConfig;
use crate::experiment::detp::engines::{Engine, ReferenceCache};
use crate::experiment::detp::spec::RawDetp;
use crate::experiment::kind::{ConfigError, Need};
use crate::output::table::{col, Table};

/// Estimator `photon-map-growing`.
pub struct PhotonMapGrowing;

impl Estimator for PhotonMapGrowing {
    const NAME: &'static str = "photon-map-growing";
    const COLUMN: &'static str = "photon_map_growing";
    const ROLE: Role = Role::Baseline;
    const CROSSOVER: Option<Crossover> = Some(Crossover::PhotonMap {
        replica: &PHOTON_MAP_GROWING_REPLICA,
    });
    const SHARDS: Shards = NO_SHARDS;
    type Measured = MapMeasured;
    const COLUMNS: Table<DetpConfig, MapMeasured> = Table::of(&[
        col(&PHOTON_MAP_GROWING_K, |_, e| e.k.into()),
        col(&COST_S, |_, e| e.seconds.into()),
        col(&BUILD_S, |_, e| e.build_s.into()),
    ]);
    fn check(_d: &RawDetp, lines: bool) -> Result<(), ConfigError> {
        needs_a_scene(Self::NAME, lines)
    }
    fn memory(_cfg: &DetpConfig, segments: f64, _threads: f64) -> Vec<Need> {
        vec![kd_tree(segments)]
    }
    fn engine(_: &ReferenceCache) -> Box<dyn Engine> {
        Box::new(Runs::growing())
    }
}

/// The growing photon map's k.
pub const PHOTON_MAP_GROWING_K: Column = Column::value(
    "photon_map_growing_k",
    "photons",
    Class::Measured,
    "photon-map-growing: the k it used at this photon count, photon_map_k·(photons/photon_map_k_photons)^photon_map_k_growth rounded (at least 1)",
);

/// A growing-k photon map's value at a point in each replica.
pub const PHOTON_MAP_GROWING_REPLICA: Column = Column::value(
    "photon_map_growing_replica_{}",
    "W/m²",
    Class::Measured,
    "photon-map-growing: its irradiance at the point in replica {} (with ≥ 2 replicas), judged per replica as the fixed-k map's",
);
