//! Estimator `photon-map`: Jensen's k-nearest-neighbour estimate over the same photons (scenes
//! only), a baseline; its engine serves `photon-map-growing` too.

use crate::experiment::detp::columns::*;
use crate::experiment::detp::config::DetpConfig;
use crate::experiment::detp::engines::{
    per_replica, timed, Engine, EngineMeasured, Output, Pooled, ReferenceCache,
};
use crate::experiment::detp::{PointSet, RaySet};
use crate::output::table::{col, Table};
use super::photon_map_growing::PhotonMapGrowing;
use super::{Crossover, Estimator, Role, Shards};
use crate::output::column::Column;
use crate::detp::photon_map::{self, Filter};
use crate::experiment::detp::engines::errors;
use crate::experiment::detp::spec::{FilterChoice, RawDetp};
use crate::experiment::kind::{refuse, ConfigError, Need};
use crate::stats::Estimate;

/// Estimator `photon-map`.
pub struct PhotonMap;

/// Why photon shards refuse a photon map.
pub(super) const NO_SHARDS: Shards =
    Shards::Refuse("the photon map gathers each point's nearest photons among all of them");

impl Estimator for PhotonMap {
    const NAME: &'static str = "photon-map";
    const COLUMN: &'static str = "photon_map";
    const ROLE: Role = Role::Baseline;
    const CROSSOVER: Option<Crossover> = Some(Crossover::PhotonMap {
        replica: &PHOTON_MAP_REPLICA,
    });
    const SHARDS: Shards = NO_SHARDS;
    type Measured = MapMeasured;
    const COLUMNS: Table<DetpConfig, MapMeasured> = Table::of(&[
        col(&PHOTON_MAP_RMSE, |_, e| e.rmse.into()),
        col(&PHOTON_MAP_BIAS, |_, e| e.bias.into()),
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
        Box::<Runs>::default()
    }
}

/// A photon map needs photon impacts on surfaces.
pub(super) fn needs_a_scene(name: &str, lines: bool) -> Result<(), ConfigError> {
    if lines {
        return refuse(
            "detp.engines",
            format!(
                "the photon map needs photon impacts on surfaces (\"{name}\"): use detp.source = \"scene\""
            ),
        );
    }
    Ok(())
}

/// The k-d tree of the impacts (the same for either photon map).
pub(super) fn kd_tree(segments: f64) -> Need {
    Need {
        bytes: segments * 48.0,
        key: "detp.photons",
        what: "photon-map k-d tree of the impacts".into(),
        per_photon: true,
    }
}

/// The photon map against the exact irradiance, one sample per replica.
#[derive(Clone, Debug)]
pub struct MapMeasured {
    /// Root-mean-square error.
    pub rmse: Estimate,
    /// Mean error.
    pub bias: Estimate,
    /// Seconds of the queries (per point), summed over replicas.
    pub seconds: f64,
    /// Seconds building the kd-tree (once per photon set), summed over replicas.
    pub build_s: f64,
    /// The k it used.
    pub k: u64,
}

/// Jensen's photon map over the same photons' impacts (a baseline): with a fixed k
/// (`photon-map`), or k(N) = k₀·(N/N₀)^β growing with the photons so that its error keeps falling
/// (`photon-map-growing`). With `detp.direct = "nee"` the store holds the indirect segments only
/// and the NEE direct part is added at each point, as for DETP.
#[derive(Default)]
pub(super) struct Runs {
    /// k grows with the photons.
    growing: bool,
    /// Per replica: estimates, query seconds, build seconds.
    runs: Vec<(Vec<f64>, f64, f64)>,
}

impl Runs {
    /// The engine of `photon-map-growing`.
    pub(super) fn growing() -> Self {
        Self {
            growing: true,
            ..Self::default()
        }
    }

    /// The k at this point's photon count.
    fn k(&self, cfg: &DetpConfig) -> usize {
        if self.growing {
            cfg.k_growth.k(cfg.photons)
        } else {
            cfg.photon_map_k as usize
        }
    }
}

impl Engine for Runs {
    fn run(&mut self, cfg: &DetpConfig, rays: &RaySet, pts: &PointSet) -> Output {
        let filter = match cfg.photon_map_filter {
            FilterChoice::Cone => Filter::Cone,
            FilterChoice::Disc => Filter::Disc,
        };
        let (map, build_s) = timed(|| photon_map::PhotonMap::build(&rays.store));
        let (mut e, s) = timed(|| {
            map.estimate(&pts.discs.centers, &pts.discs.normals, self.k(cfg), filter)
        });
        if let Some(direct) = &rays.direct {
            for (e, d) in e.iter_mut().zip(&direct.values) {
                *e += d.mean;
            }
        }
        self.runs.push((e, s, build_s));
        Output::Baseline
    }
    fn seconds(&self) -> f64 {
        // A baseline: not part of the DETP engines' speed.
        0.0
    }
    fn replica_points(&self) -> Vec<Vec<f64>> {
        self.runs.iter().map(|r| r.0.clone()).collect()
    }
    fn per_point(&self, p: &Pooled) -> Option<Vec<(f64, f64)>> {
        let n = self.runs.first().map_or(0, |r| r.0.len());
        let k = self.k(p.cfg) as f64;
        Some(
            (0..n)
                .map(|i| {
                    let v: Vec<f64> = self.runs.iter().map(|r| r.0[i]).collect();
                    let e = per_replica(&v);
                    // One replica: a k-nearest-neighbour estimate has relative SE ≈ 1/√k.
                    let se = if v.len() == 1 {
                        e.mean.abs() / k.sqrt()
                    } else {
                        e.se
                    };
                    (e.mean, se)
                })
                .collect(),
        )
    }
    fn measured(&self, p: &Pooled) -> EngineMeasured {
        let errs: Vec<(f64, f64)> = self.runs.iter().map(|r| errors(&r.0, p.exact)).collect();
        let m = MapMeasured {
            rmse: per_replica(&errs.iter().map(|e| e.0).collect::<Vec<_>>()),
            bias: per_replica(&errs.iter().map(|e| e.1).collect::<Vec<_>>()),
            seconds: self.runs.iter().map(|r| r.1).sum(),
            build_s: self.runs.iter().map(|r| r.2).sum(),
            k: self.k(p.cfg) as u64,
        };
        if self.growing {
            EngineMeasured::of::<PhotonMapGrowing>(m)
        } else {
            EngineMeasured::of::<PhotonMap>(m)
        }
    }
}

/// Photon-map RMSE.
pub const PHOTON_MAP_RMSE: Column = Column::estimate(
    "photon_map_rmse",
    "W/m²",
    "photon map: root-mean-square error against the exact irradiance (where the scene has one), one sample per replica",
);

/// Photon-map bias.
pub const PHOTON_MAP_BIAS: Column = Column::estimate(
    "photon_map_bias",
    "W/m²",
    "photon map: mean error against the exact irradiance, one sample per replica",
);

/// A fixed-k photon map's value at a point in each replica.
pub const PHOTON_MAP_REPLICA: Column = Column::value(
    "photon_map_replica_{}",
    "W/m²",
    crate::output::column::Class::Measured,
    "photon-map: its irradiance at the point in replica {} (with ≥ 2 replicas): one replica is one map of N photons, so its error is judged per replica (a fixed-k map's variance goes as 1/k whatever N), the replicas the units of a bootstrap",
);
