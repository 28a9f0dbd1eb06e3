//! Estimator `reference`: the path-traced irradiance at every point ([`crate::lt::reference`]),
//! the ground truth DETP and the baselines are measured against (scenes only; computed once per
//! point set in a run, not per replica, and by the merge of photon shards, since it reads no
//! photons).

use std::sync::Arc;

use super::{Estimator, Role, Shards};
use crate::experiment::detp::columns::*;
use crate::experiment::detp::config::DetpConfig;
use crate::experiment::detp::engines::{
    point_set_key, timed, Engine, EngineMeasured, EnginePart, Output, Pooled, ReferenceCache,
};
use crate::experiment::detp::spec::RawDetp;
use crate::experiment::detp::{PointSet, RaySet};
use crate::experiment::kind::{refuse, ConfigError};
use crate::lt::reference::{self, Irradiance};
use crate::output::table::{col, Table};
use crate::sample::rng::{domain, hash_key};

/// Estimator `reference`.
pub struct Reference;

impl Estimator for Reference {
    const NAME: &'static str = "reference";
    const COLUMN: &'static str = "reference";
    const ROLE: Role = Role::Reference;
    const SHARDS: Shards = Shards::Skip;
    /// Its seconds.
    type Measured = f64;
    const COLUMNS: Table<DetpConfig, f64> = Table::of(&[col(&COST_S, |_, s| (*s).into())]);
    fn check(d: &RawDetp, lines: bool) -> Result<(), ConfigError> {
        if lines {
            return refuse(
                "detp.engines",
                "the reference path-traces a scene's lights and surfaces: it needs detp.source = \"scene\" (lines through the unit ball have an exact irradiance already)",
            );
        }
        if d.reference_samples < 2 {
            return refuse(
                "detp.reference_samples",
                "got 1, at least 2 (the reference's standard error comes from its samples' variance)",
            );
        }
        Ok(())
    }
    fn engine(refs: &ReferenceCache) -> Box<dyn Engine> {
        Box::new(Runs {
            cache: refs.clone(),
            result: None,
        })
    }
}

/// The path-traced reference irradiance per disc (a baseline: never part of DETP's sums or speed).
struct Runs {
    cache: ReferenceCache,
    /// Estimates per disc and the seconds they took to compute.
    result: Option<Arc<(Vec<Irradiance>, f64)>>,
}

impl Runs {
    /// The reference at the point's discs, once per point (it does not depend on the replica's
    /// photons), shared through the run's cache.
    fn compute(&mut self, cfg: &DetpConfig, pts: &PointSet) {
        if self.result.is_some() {
            return;
        }
        let Some(scene) = cfg.scene() else {
            unreachable!("configure refuses the reference without a scene")
        };
        let discs = &pts.discs;
        let key = point_set_key(cfg, pts, &[domain::REFERENCE, cfg.seed, cfg.reference_samples]);
        let r = self.cache.reference.get_or(key, || {
            timed(|| {
                reference::irradiance(
                    &scene.scene,
                    &discs.centers,
                    &discs.normals,
                    cfg.reference_samples,
                    hash_key(&[cfg.seed]),
                )
            })
        });
        self.result = Some(r);
    }
}

impl Engine for Runs {
    fn run(&mut self, cfg: &DetpConfig, _rays: &RaySet, pts: &PointSet) -> Output {
        self.compute(cfg, pts);
        Output::Baseline
    }
    fn part(&self) -> Option<EnginePart> {
        Some(EnginePart::unit("Reference"))
    }
    /// Photon shards skip the reference (it needs no photons); the merge computes it, once.
    fn absorb(&mut self, cfg: &DetpConfig, pts: &PointSet, _part: &EnginePart) {
        self.compute(cfg, pts);
    }
    fn seconds(&self) -> f64 {
        0.0
    }
    fn per_point(&self, _p: &Pooled) -> Option<Vec<(f64, f64)>> {
        self.result
            .as_ref()
            .map(|r| r.0.iter().map(|e| (e.mean, e.se)).collect())
    }
    fn measured(&self, _p: &Pooled) -> EngineMeasured {
        EngineMeasured::of::<Reference>(self.result.as_ref().map_or(0.0, |r| r.1))
    }
}
