//! `NAME.replica_errors.csv`: with engine `reference` and ≥ 2 replicas, each estimator's relative
//! MSE in each replica at the point — what `raycost crossover` bootstraps over replicas to find
//! the photons a configuration needs for a target error.
//!
//! The points table holds the same numbers in full (every replica's value at every disc), but it
//! grows with points × sweep points (tens of MB for a fronts sweep); this table has one row per
//! estimator and replica, so a fronts run can be committed and regenerated without its points
//! table. Both are computed by [`relative_mse`] from the same values in the same order, so the
//! crossover reads the same bits from either.

use super::config::DetpConfig;
use super::engines::relative_mse;
use super::estimators::path_tracing::PT_REPLICA;
use crate::output::column::{Class, Column};
use crate::output::table::{col, Table};

/// The estimator name of DETP's own rows (its engines agree bit for bit, so one row stands for
/// all of them).
pub const DETP: &str = "detp";

/// One row: one estimator in one replica.
#[derive(Clone, Debug, PartialEq)]
pub struct ReplicaErrorRow {
    /// [`DETP`] or a photon map's column stem (`photon_map`, `photon_map_growing`).
    pub estimator: &'static str,
    /// The replica.
    pub replica: u64,
    /// Its relative MSE against the reference over the point's discs.
    pub relative_mse: f64,
}

/// The rows of a point: DETP's replicas `detp[r][i]` and each photon map's `(stem,
/// values[r][i])`, judged against the reference `refr` per disc. None with fewer than 2 replicas
/// (the crossover's bootstrap needs two).
pub fn rows(
    detp: &[Vec<f64>],
    maps: &[(&'static str, Vec<Vec<f64>>)],
    refr: &[(f64, f64)],
) -> Vec<ReplicaErrorRow> {
    if detp.len() < 2 {
        return Vec::new();
    }
    let series = std::iter::once((DETP, detp)).chain(maps.iter().map(|(s, v)| (*s, v.as_slice())));
    series
        .flat_map(|(estimator, replicas)| {
            replicas
                .iter()
                .enumerate()
                .map(move |(k, v)| ReplicaErrorRow {
                    estimator,
                    replica: k as u64,
                    relative_mse: relative_mse(v, refr),
                })
        })
        .collect()
}

/// The estimator.
pub const ESTIMATOR: Column = Column::value(
    "estimator",
    "",
    Class::Measured,
    "the estimator judged: detp (every DETP engine: they agree bit for bit) or a baseline that keeps one estimate per replica, by its column name (the photon maps)",
);

/// Relative MSE of one replica.
pub const RELATIVE_MSE: Column = Column::value(
    "relative_mse",
    "1",
    Class::Measured,
    "this replica's [mean_i (E_i − R_i)² − mean_i se_R,i²] / (mean_i R_i)² over the point's discs against engine reference (its squared error relative to the truth, the reference's variance subtracted)",
);

/// `NAME.replica_errors.csv`: one row per estimator and replica.
pub const REPLICA_ERRORS_TABLE: Table<DetpConfig, ReplicaErrorRow> = Table::of(&[
    col(&ESTIMATOR, |_, r| r.estimator.into()),
    col(&PT_REPLICA, |_, r| r.replica.into()),
    col(&RELATIVE_MSE, |_, r| r.relative_mse.into()),
]);

#[cfg(test)]
mod tests {
    use super::*;

    /// Truth 2 and 4 (SE 0): DETP's replicas off by ±1 at both discs give 1/9 each; a map's rows
    /// follow DETP's; one replica gives no rows.
    #[test]
    fn one_row_per_estimator_and_replica() {
        let refr = [(2.0, 0.0), (4.0, 0.0)];
        let detp = vec![vec![3.0, 5.0], vec![1.0, 3.0]];
        let maps = vec![("photon_map", vec![vec![2.0, 4.0], vec![2.0, 6.0]])];
        let r = rows(&detp, &maps, &refr);
        let got: Vec<(&str, u64, f64)> =
            r.iter().map(|x| (x.estimator, x.replica, x.relative_mse)).collect();
        assert_eq!(
            got,
            [
                ("detp", 0, 1.0 / 9.0),
                ("detp", 1, 1.0 / 9.0),
                ("photon_map", 0, 0.0),
                ("photon_map", 1, 2.0 / 9.0)
            ]
        );
        assert!(rows(&detp[..1], &maps, &refr).is_empty());
    }
}
