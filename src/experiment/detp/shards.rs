//! `--photon-shard K/N` for kind `detp`: the seam between tracing a part of a point's photons and
//! measuring the point.
//!
//! A shard traces photons `[K·P/N, (K+1)·P/N)` of every replica (a photon's stream and power depend
//! on its id and P only, so each is the photon the unsplit run traces) and keeps, per replica, a
//! [`ReplicaPart`]: every DETP engine's integer sum per disc, brute force's sums on the keyed check
//! subset, the segment counts, the integer sum of segment powers, and each engine's counts. All of
//! them add across disjoint photon subsets, so the merge adds the N parts and hands the total to
//! the same code that absorbs an unsplit replica ([`super::measure`]): every measured column is the
//! unsplit run's, bit for bit. Seconds add (bytes take the larger); the path-traced reference needs
//! no photons and is computed by the merge.
//!
//! Engines whose counts do not add are refused: the sphere cache (a sphere is subdivided when it
//! holds at least `detp.threshold` rays, a decision on the whole photon set) and the photon map (a
//! point's k nearest impacts are among all photons).

use std::ops::Range;

use serde::{Deserialize, Serialize};

use super::engines::{EnginePart, Gathered};
use super::estimators::{DynEstimator, Shards, ESTIMATORS};
use super::{DetpConfig, RaySet};
use crate::experiment::photon_shards::{add_replica_parts, RangePart};
use crate::detp::fixed::{Acc, PowerScale};

/// One replica's counts over a range of its photons (see the module doc).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ReplicaPart {
    /// The photon ids traced, `[lo, hi)`.
    pub ids: (u64, u64),
    /// Segments stored (what the engines read).
    pub segments: u64,
    /// `detp.direct = "nee"`: direct segments traced and left out of the store.
    #[serde(default)]
    pub segments_direct: u64,
    /// Segments meeting the law's ball.
    pub rays_in_root: u64,
    /// Σ of the segments' power units, in decimal (it may exceed 64 bits).
    power_units: String,
    /// The power scale's watts per unit, as IEEE bits (every shard must have the same).
    scale: u64,
    /// The root sphere's radius, as bits.
    pub root_radius: u64,
    /// The law ball's radius, as bits.
    pub law_radius: u64,
    /// Seconds tracing.
    pub trace_s: f64,
    /// Seconds on `detp.edge`.
    pub edge_s: f64,
    /// Each DETP engine's sum per disc, in engine order.
    pub sums: Vec<Vec<Acc>>,
    /// Brute force's sums on the check subset, in subset order.
    pub bf: Vec<Acc>,
    /// With `detp.radius_crossings`: each DETP engine's radius per disc (IEEE bits), in engine
    /// order (else empty, and absent from a shard's file). Such a point is never split.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub radii: Vec<Vec<u64>>,
    /// With `detp.radius_crossings`: brute force's radius on the check subset (else empty).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub bf_radii: Vec<u64>,
    /// Each engine's counts, in engine order.
    pub engines: Vec<EnginePart>,
}

impl ReplicaPart {
    /// The part of `rays` (photons `ids`) with the engines' sums and the check subset's.
    pub(super) fn new(ids: (u64, u64), rays: &RaySet, sums: Vec<Gathered>, bf: Gathered) -> Self {
        let power: u128 = rays
            .store
            .segments
            .iter()
            .map(|s| u128::from(s.power))
            .sum();
        Self {
            ids,
            segments: rays.store.len() as u64,
            segments_direct: rays.segments_direct,
            rays_in_root: rays.rays_in_root,
            power_units: power.to_string(),
            scale: rays.store.scale.watts_per_unit.to_bits(),
            root_radius: rays.root.1.to_bits(),
            law_radius: rays.law_radius.to_bits(),
            trace_s: rays.trace_s,
            edge_s: rays.edge_s,
            radii: sums
                .iter()
                .filter(|g| !g.radii.is_empty())
                .map(|g| g.radii.clone())
                .collect(),
            sums: sums.into_iter().map(|g| g.units).collect(),
            bf_radii: bf.radii,
            bf: bf.units,
            engines: Vec::new(),
        }
    }

    /// The power scale.
    pub(super) fn scale(&self) -> PowerScale {
        PowerScale {
            watts_per_unit: f64::from_bits(self.scale),
        }
    }

    /// Σ of the segments' power units.
    pub(super) fn power_units(&self) -> u128 {
        self.power_units
            .parse()
            .expect("parts are checked when they are read")
    }

    /// Whether the decimal power sum reads.
    fn valid(&self) -> bool {
        self.power_units.parse::<u128>().is_ok()
    }
}

impl RangePart for ReplicaPart {
    fn ids(&self) -> (u64, u64) {
        self.ids
    }
    /// The part of the union of `self`'s photons and `o`'s, which follow them.
    fn then(&self, o: &Self) -> Result<Self, String> {
        let same = |what: &str, a: u64, b: u64| {
            (a == b)
                .then_some(())
                .ok_or_else(|| format!("the shards' {what} differ"))
        };
        same("power scales", self.scale, o.scale)?;
        same("root spheres", self.root_radius, o.root_radius)?;
        same("law radii", self.law_radius, o.law_radius)?;
        if !(self.radii.is_empty() && o.radii.is_empty()) {
            return Err("the parts keep k-nearest radii, which do not add".into());
        }
        let shape = |p: &Self| (p.sums.iter().map(Vec::len).collect::<Vec<_>>(), p.bf.len());
        if shape(self) != shape(o) || self.engines.len() != o.engines.len() {
            return Err("the shards' disc or engine counts differ".into());
        }
        let add_vec = |a: &[Acc], b: &[Acc]| a.iter().zip(b).map(|(x, y)| x + y).collect();
        Ok(Self {
            ids: (self.ids.0, o.ids.1),
            segments: self.segments + o.segments,
            segments_direct: self.segments_direct + o.segments_direct,
            rays_in_root: self.rays_in_root + o.rays_in_root,
            power_units: (self.power_units() + o.power_units()).to_string(),
            scale: self.scale,
            root_radius: self.root_radius,
            law_radius: self.law_radius,
            trace_s: self.trace_s + o.trace_s,
            edge_s: self.edge_s + o.edge_s,
            sums: self
                .sums
                .iter()
                .zip(&o.sums)
                .map(|(a, b)| add_vec(a, b))
                .collect(),
            bf: add_vec(&self.bf, &o.bf),
            radii: Vec::new(),
            bf_radii: Vec::new(),
            engines: self
                .engines
                .iter()
                .zip(&o.engines)
                .map(|(a, b)| a.add(b).ok_or("the shards' engines differ"))
                .collect::<Result<_, _>>()?,
        })
    }
}

/// The photons `[K·P/N, (K+1)·P/N)` of shard K of N, for P photons.
pub fn photon_range(photons: u64, k: u64, n: u64) -> Range<u64> {
    let at = |k: u64| (u128::from(photons) * u128::from(k) / u128::from(n)) as u64;
    at(k)..at(k + 1)
}

/// Why `cfg` cannot be split by photons, if it cannot: it lists estimators whose counts do not
/// add ([`Shards::Refuse`]).
pub fn refusal(cfg: &DetpConfig) -> Option<String> {
    if cfg.radius_crossings.is_some() {
        // The k smallest of a union are the k smallest of the parts' k smallest, so a merge could
        // be exact; but a crossing is ordered by its segment's number in its own store, which
        // restarts in every part, and the parts carry sums, not each disc's kept crossings.
        return Some(
            "detp.radius_crossings keeps each disc's k nearest crossings, which photon shards and batches do not carry between their parts yet: run the point in one pass (raise detp.memory_budget_gib if it is over budget)".into(),
        );
    }
    let refused = |e: &&dyn DynEstimator| matches!(e.shards(), Shards::Refuse(_));
    let bad: Vec<&str> = cfg
        .engines
        .iter()
        .filter(|e| refused(&e.estimator()))
        .map(|e| e.as_str())
        .collect();
    (!bad.is_empty()).then(|| {
        let mut why: Vec<&str> = Vec::new();
        for e in ESTIMATORS {
            if let Shards::Refuse(w) = e.shards() {
                if !why.contains(&w) {
                    why.push(w);
                }
            }
        }
        let ok: Vec<&str> = ESTIMATORS
            .iter()
            .filter(|e| !refused(e))
            .map(|e| e.name())
            .collect();
        let ok = match ok.split_last() {
            Some((last, rest)) if !rest.is_empty() => format!("{} and {last}", rest.join(", ")),
            _ => ok.join(""),
        };
        format!(
            "detp.engines has {}: its counts do not add across photon shards ({}); --photon-shard needs engines among {ok}",
            bad.join(" and "),
            why.join(", ")
        )
    })
}

/// The replicas of one point summed over its shards' parts (one `Vec<ReplicaPart>` per shard, in
/// shard order), checked to cover photons `0..photons` of every replica exactly once.
pub fn add_parts(
    cfg: &DetpConfig,
    shards: &[Vec<ReplicaPart>],
) -> Result<Vec<ReplicaPart>, String> {
    if shards.iter().flatten().any(|p| !p.valid()) {
        return Err("a power sum is not a whole number".into());
    }
    add_replica_parts(cfg.replicas as usize, cfg.photons, shards)
}

#[cfg(test)]
mod tests {
    use super::photon_range;

    #[test]
    fn photon_ranges_tile_the_photons_in_order() {
        for (p, n) in [(1u64, 1u64), (10, 3), (7, 7), (5, 8), (1 << 32, 5)] {
            let mut next = 0;
            for k in 0..n {
                let r = photon_range(p, k, n);
                assert_eq!(r.start, next, "P = {p}, N = {n}, K = {k}");
                assert!(r.end >= r.start);
                next = r.end;
            }
            assert_eq!(next, p);
        }
    }
}
