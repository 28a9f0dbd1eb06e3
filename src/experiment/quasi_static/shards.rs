//! `--photon-shard K/N` for kind `quasi-static`: one replica's run over a range of its photons, in
//! a form that adds across shards ([`ReplicaPart`]), and what cannot be split.
//!
//! A shard runs every frame with photons `[K·P/N, (K+1)·P/N)` only
//! ([`QuasiStatic::start_photons`](crate::detp::quasi_static::QuasiStatic::start_photons)): a
//! photon's stream and power depend on its id and P, and the segment index's query is exact (the
//! segments meeting a ball, whatever the grid), so the shard re-traces exactly its own share of the
//! photons the whole run re-traces, and its integer sums per point are its share of the whole run's.
//! The unsplit run is the one part covering `0..P`; the merge adds the N parts and measures the
//! total through the same code ([`super::measure`]), so every measured column is the unsplit run's,
//! bit for bit:
//! - per frame, the counts of [`FrameStats::add`] (re-traced photons and segments, the disc index's
//!   tests and traversal — its per-segment work does not depend on the other segments);
//! - per checked frame, incremental minus full recalculation per point (the nonzero ones): the
//!   whole run's difference at a point is the sum of the shards';
//! - replica 0's sums at the points table's frame, with the live segments and their power units.
//!
//! The segment index's own work (search cells, listings and tests, and `dynamic.feed`'s query) is
//! what a shard's index — sized and compacted by the shard's segments — did: the merge writes it
//! summed over the shards, as the work done across them, and classes those columns timing
//! ([`crate::output::column::Column::accelerator_work`]). Seconds add.
//!
//! Refused: the sphere cache (`detp.engine` other than "disc-index": it subdivides a sphere when it
//! holds `detp.threshold` rays, a decision on all the photons), the §4.1 predictor (it times a
//! fraction of all photons) and the reference run (`irradiance_rel_rmse` is not a sum).

use serde::{Deserialize, Serialize};

use super::measure::{f64_bits, from_bits};
use super::spec::QuasiStaticConfig;
use crate::detp::fixed::Acc;
use crate::detp::quasi_static::{FrameStats, QuasiStatic};
use crate::experiment::detp::DynamicEngine;
use crate::experiment::photon_shards::{add_replica_parts, RangePart};

/// A full recalculation of one frame: its seconds, and incremental minus full at every point
/// where they differ.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct FullCheck {
    /// Seconds.
    pub seconds: f64,
    /// (point, incremental − full), the nonzero ones, by point.
    pub diffs: Vec<(u32, Acc)>,
}

impl FullCheck {
    /// The check of the union of two disjoint photon ranges: differences add point by point.
    fn add(&self, o: &Self) -> Self {
        let mut diffs: std::collections::BTreeMap<u32, Acc> = self.diffs.iter().copied().collect();
        for &(i, d) in &o.diffs {
            *diffs.entry(i).or_default() += d;
        }
        Self {
            seconds: self.seconds + o.seconds,
            diffs: diffs.into_iter().filter(|&(_, d)| d != 0).collect(),
        }
    }
}

/// One frame of a replica's part.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct FramePart {
    /// Its counts and seconds.
    pub stats: FrameStats,
    /// Its check against a full recalculation, where checked.
    pub full: Option<FullCheck>,
}

/// The sums the points table shows (replica 0, `detp.write_points`) and what its standard error
/// needs.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct PointsAt {
    /// The frame.
    pub frame: u32,
    /// Every point's sum (static, then each object's).
    pub sums: Vec<Acc>,
    /// Centres, as IEEE bits.
    pub centers: Vec<[u64; 3]>,
    /// Normals, as IEEE bits.
    pub normals: Vec<[u64; 3]>,
    /// Live segments at that frame.
    pub live_segments: u64,
    /// Σ of their power units, in decimal (it may exceed 64 bits).
    pub power_units: String,
}

/// What a replica's geometry and engines fix, whatever its photons: equal in every shard.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Facts {
    /// r_0, as bits.
    pub r0: u64,
    /// Static points.
    pub points_static: u64,
    /// Each object's points.
    pub points_dynamic: Vec<u64>,
    /// Each object's r_D/r_0, as bits.
    pub ratios: Vec<u64>,
    /// The hybrid's crossover, as bits.
    pub crossover: u64,
    /// The power scale's watts per unit, as bits.
    pub scale: u64,
}

impl Facts {
    /// The facts of a run after its last frame.
    pub fn of(qs: &QuasiStatic) -> Self {
        let r0 = qs.r0();
        let (n_s, n_dyn) = qs.point_counts();
        Self {
            r0: r0.to_bits(),
            points_static: n_s as u64,
            points_dynamic: n_dyn.iter().map(|&n| n as u64).collect(),
            ratios: qs
                .scene
                .movers
                .iter()
                .map(|m| (m.radius() / r0).to_bits())
                .collect(),
            crossover: qs.params().crossover.to_bits(),
            scale: qs.scale().watts_per_unit.to_bits(),
        }
    }
}

/// One replica's run over a range of its photons (see the module doc).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ReplicaPart {
    /// The photon ids run, `[lo, hi)`.
    pub ids: (u64, u64),
    /// Geometry and engine facts.
    pub facts: Facts,
    /// Segments live after frame 0.
    pub n_r: u64,
    /// Seconds building the static points' index.
    pub static_index_build_s: f64,
    /// Frames 0 … F − 1.
    pub frames: Vec<FramePart>,
    /// The points table's sums, where asked.
    pub points_at: Option<PointsAt>,
}

impl RangePart for ReplicaPart {
    fn ids(&self) -> (u64, u64) {
        self.ids
    }
    fn then(&self, o: &Self) -> Result<Self, String> {
        if self.facts != o.facts {
            return Err("the shards' scenes, points or engines differ".into());
        }
        if self.frames.len() != o.frames.len() {
            return Err("the shards' frame counts differ".into());
        }
        let frames = self
            .frames
            .iter()
            .zip(&o.frames)
            .map(|(a, b)| {
                let stats = a.stats.add(&b.stats).ok_or_else(|| {
                    format!("frame {}: the shards' engines differ", a.stats.frame)
                })?;
                let full = match (&a.full, &b.full) {
                    (Some(x), Some(y)) => Some(x.add(y)),
                    (None, None) => None,
                    _ => return Err(format!("frame {}: checked in one shard only", a.stats.frame)),
                };
                Ok(FramePart { stats, full })
            })
            .collect::<Result<_, String>>()?;
        let points_at = match (&self.points_at, &o.points_at) {
            (Some(x), Some(y)) => Some(x.add(y)?),
            (None, None) => None,
            _ => return Err("the points table is in one shard only".into()),
        };
        Ok(Self {
            ids: (self.ids.0, o.ids.1),
            facts: self.facts.clone(),
            n_r: self.n_r + o.n_r,
            static_index_build_s: self.static_index_build_s + o.static_index_build_s,
            frames,
            points_at,
        })
    }
}

impl PointsAt {
    /// The sums of `qs` at its current frame.
    pub fn of(qs: &QuasiStatic) -> Self {
        let discs = qs.discs();
        let bits = |v: &[glam::DVec3]| v.iter().map(|p| f64_bits(p.to_array())).collect();
        let live = qs.live_store();
        let power: u128 = live.segments.iter().map(|s| u128::from(s.power)).sum();
        Self {
            frame: qs.frame,
            sums: qs.sums(),
            centers: bits(&discs.centers),
            normals: bits(&discs.normals),
            live_segments: live.len() as u64,
            power_units: power.to_string(),
        }
    }

    /// Σ of the live segments' power units.
    pub fn power_units(&self) -> Result<u128, String> {
        self.power_units
            .parse()
            .map_err(|_| format!("power sum {:?} is not a whole number", self.power_units))
    }

    /// Centres and normals.
    pub fn discs(&self) -> (Vec<glam::DVec3>, Vec<glam::DVec3>) {
        let v = |b: &[[u64; 3]]| b.iter().map(|&x| from_bits(x).into()).collect();
        (v(&self.centers), v(&self.normals))
    }

    fn add(&self, o: &Self) -> Result<Self, String> {
        if (self.frame, &self.centers, &self.normals) != (o.frame, &o.centers, &o.normals)
            || self.sums.len() != o.sums.len()
        {
            return Err("the shards' points tables differ in their points".into());
        }
        Ok(Self {
            frame: self.frame,
            sums: self.sums.iter().zip(&o.sums).map(|(a, b)| a + b).collect(),
            centers: self.centers.clone(),
            normals: self.normals.clone(),
            live_segments: self.live_segments + o.live_segments,
            power_units: (self.power_units()? + o.power_units()?).to_string(),
        })
    }
}

/// Why `cfg`'s photons cannot be split, if they cannot.
pub fn refusal(cfg: &QuasiStaticConfig) -> Option<String> {
    let why = if cfg.engine != DynamicEngine::DiscIndex {
        format!(
            "detp.engine is {:?}: {}; --photon-shard needs detp.engine = \"disc-index\" (its sums and counts add across photon shards)",
            cfg.engine.as_str(),
            match cfg.engine {
                DynamicEngine::Predicted => "the predictor picks an engine on seconds measured over all the photons, and may pick the sphere cache",
                DynamicEngine::Hybrid => "it gives objects below the crossover to the sphere cache, whose counts do not add across photon shards (it subdivides a sphere by how many rays it holds, among all the photons)",
                _ => "the sphere cache's counts do not add across photon shards (it subdivides a sphere by how many rays it holds, among all the photons)",
            }
        )
    } else if cfg.predict.is_some() {
        "dynamic.predict times the engines on a fraction of all the photons, which no photon shard holds".into()
    } else if cfg.reference_photons.is_some() {
        "dynamic.reference_photons: irradiance_rel_rmse compares the whole run's irradiance with a reference, which is not a sum over photon shards; run the reference unsplit".into()
    } else if cfg.path_tracing() {
        "detp.engines has \"path-tracing\": it path-traces each replica's checked frames in the posed scene, which a merge of photon shards does not hold; run it unsplit".into()
    } else {
        return None;
    };
    Some(format!("kind quasi-static cannot split these photons: {why}"))
}

/// The replicas of one point summed over its shards' parts (one `Vec<ReplicaPart>` per shard, in
/// shard order), checked to cover photons `0..photons` of every replica exactly once.
pub fn add_parts(
    cfg: &QuasiStaticConfig,
    shards: &[Vec<ReplicaPart>],
) -> Result<Vec<ReplicaPart>, String> {
    add_replica_parts(cfg.detp.replicas.max(1) as usize, cfg.detp.photons, shards)
}

#[cfg(test)]
mod tests {
    use super::FullCheck;

    #[test]
    fn full_check_differences_add_point_by_point_and_cancel() {
        let a = FullCheck {
            seconds: 1.0,
            diffs: vec![(1, 5), (4, -2)],
        };
        let b = FullCheck {
            seconds: 0.5,
            diffs: vec![(1, -5), (3, 7), (4, -1)],
        };
        let sum = a.add(&b);
        assert_eq!(sum.diffs, vec![(3, 7), (4, -3)]);
        assert_eq!(sum.seconds, 1.5);
    }
}
