//! Every column the grid kinds write, declared once (name, unit, class, meaning), and the two tables
//! that read them from a point's measurement ([`MAIN`], [`HIST`]); `raycost doc columns` prints
//! them. A column a point does not have (a finite scene's grid size in an infinite scene, the
//! scaling columns of another kind) is absent from its row.

use super::config::GridConfig;
use super::measure::{FiniteFacts, GridMeasured, HistBin, SceneFacts};
use crate::output::column::{Class, Column};
use crate::output::table::{col, Cell, Table};
use crate::stats::Theory;
use crate::theory::grid::query_time;

/// N_I without mailboxing.
pub const N_I: Column = Column::vs_band(
    "n_i",
    "tests",
    "ray–sphere tests per ray, a sphere listed in several visited cells counted each time; theory: the no-mailbox predictor inside Result 3.1/3.2's band",
);
/// N_I with mailboxing.
pub const N_I_MB: Column = Column::vs_band(
    "n_i_mb",
    "tests",
    "ray–sphere tests per ray with mailboxing (distinct spheres); theory: the mailboxed predictor inside Result 3.1/3.2's band",
);
/// The plain predictor.
pub const N_I_PLAIN_THEORY: Column = Column::value(
    "n_i_plain_theory",
    "tests",
    Class::Theory,
    "(1 + E[N_S])·ρ|o(a,r)|: every visited cell's whole list, no exclusion correction",
);
/// Where the sharper predictors are derived.
pub const PREDICTOR_REGIME: Column = Column::value(
    "predictor_regime",
    "1",
    Class::Theory,
    "r<a/2 where the sharper predictors are derived, r>=a/2 outside",
);
/// N_S.
pub const N_S: Column = Column::vs_prediction(
    "n_s",
    "steps",
    "cell steps per ray; theory: exact E[N_S] for the eye placement",
);
/// t*.
pub const T_HIT: Column = Column::vs_prediction(
    "t_hit",
    "length",
    "first-hit distance of hitting rays; theory: E[t*] = 1/(ρπΣα r²) (conditioned on hitting inside a finite cube)",
);
/// Hit fraction.
pub const HIT: Column = Column::vs_prediction(
    "hit",
    "1",
    "fraction of rays that hit; theory: 1 (infinite scene) or the exponential law over the cube",
);
/// KS statistic.
pub const T_HIT_KS: Column = Column::value(
    "t_hit_ks",
    "1",
    Class::Measured,
    "Kolmogorov–Smirnov distance of t* from the exponential law (first 10⁶ hits; NaN in a finite cube)",
);
/// KS p-value.
pub const T_HIT_KS_P: Column = Column::value("t_hit_ks_p", "1", Class::Measured, "its p-value");
/// χ² of t*.
pub const T_HIT_CHI2: Column = Column::value(
    "t_hit_chi2",
    "1",
    Class::Measured,
    "χ² of the t* histogram against the exponential law",
);
/// Its degrees of freedom.
pub const T_HIT_CHI2_DOF: Column = Column::value(
    "t_hit_chi2_dof",
    "1",
    Class::Measured,
    "its degrees of freedom",
);
/// Its p-value.
pub const T_HIT_CHI2_P: Column = Column::value("t_hit_chi2_p", "1", Class::Measured, "its p-value");
/// Geometric fit.
pub const N_I_GEOMETRIC_P: Column = Column::value(
    "n_i_geometric_p",
    "1",
    Class::Measured,
    "p of the geometric law fitted to N_I,mb of hitting rays (1/mean)",
);
/// Cylinder radius.
pub const N_I_CYLINDER_RADIUS: Column = Column::value(
    "n_i_cylinder_radius",
    "length",
    Class::Measured,
    "the cylinder radius s that fitted p implies in the paper's eq. 9, p = (r/(s+r))²",
);
/// χ² of N_I.
pub const N_I_MB_CHI2: Column = Column::value(
    "n_i_mb_chi2",
    "1",
    Class::Measured,
    "χ² of N_I,mb of hitting rays against the fitted geometric law",
);
/// Degrees of freedom.
pub const N_I_MB_CHI2_DOF: Column = Column::value(
    "n_i_mb_chi2_dof",
    "1",
    Class::Measured,
    "its degrees of freedom",
);
/// p-value.
pub const N_I_MB_CHI2_P: Column =
    Column::value("n_i_mb_chi2_p", "1", Class::Measured, "its p-value");
/// Truncated walks.
pub const TRUNCATED: Column = Column::value(
    "truncated",
    "rays",
    Class::Measured,
    "rays cut off at grid.max_steps cells (infinite scene)",
);
/// Spheres drawn.
pub const GENERATED: Column = Column::value(
    "generated_spheres_per_batch",
    "spheres",
    Class::Measured,
    "infinite scene: sphere centres drawn per batch of 256 rays",
);
/// Finite scene size.
pub const SPHERES: Column = Column::value(
    "spheres",
    "spheres",
    Class::Measured,
    "finite scene: spheres in the last replica",
);
/// Cells.
pub const GRID_CELLS: Column = Column::value(
    "grid_cells",
    "cells",
    Class::Measured,
    "finite scene: cells of its grid",
);
/// Listings.
pub const GRID_LISTINGS: Column = Column::value(
    "grid_listings",
    "listings",
    Class::Measured,
    "finite scene: sphere listings in the cell lists",
);
/// Bytes.
pub const GRID_BYTES: Column = Column::value(
    "grid_bytes",
    "bytes",
    Class::Measured,
    "finite scene: bytes of the cell lists",
);
/// Proposition 4.1 threshold.
pub const H_LOG: Column = Column::value(
    "h_log",
    "tests",
    Class::Theory,
    "grid-scaling: the threshold c·ln n of Proposition 4.1",
);
/// Tail probability.
pub const P_LOG: Column = Column::estimate("p_log", "1", "grid-scaling: P(N_I ≥ c·ln n)");
/// Proposition 4.1 threshold.
pub const H_SQRT: Column = Column::value(
    "h_sqrt",
    "tests",
    Class::Theory,
    "grid-scaling: the threshold c·√n",
);
/// Tail probability.
pub const P_SQRT: Column = Column::estimate("p_sqrt", "1", "grid-scaling: P(N_I ≥ c·√n)");
/// Brute-force rays.
pub const BF_RAYS: Column = Column::value(
    "bf_rays",
    "rays",
    Class::Check,
    "grid-scaling: rays also traced by brute force (n ≤ scaling.brute_force_max_n)",
);
/// Brute-force disagreements.
pub const BF_MISMATCHES: Column = Column::value(
    "bf_mismatches",
    "rays",
    Class::Check,
    "grid-scaling: rays whose first hit differs from brute force (0 when correct; the run fails otherwise)",
);
/// Brute-force speed.
pub const BF_RAYS_PER_S: Column = Column::value(
    "bf_rays_per_s",
    "rays/s",
    Class::Timing,
    "grid-scaling: brute force's speed",
);
/// Tracing time.
pub const TRACE_S: Column = Column::value(
    "trace_s",
    "s",
    Class::Timing,
    "wall seconds tracing (brute force excluded)",
);
/// Speed.
pub const RAYS_PER_S: Column = Column::value(
    "rays_per_s",
    "rays/s",
    Class::Timing,
    "rays traced per wall second",
);
/// Time per ray.
pub const TIME_PER_RAY_S: Column = Column::value(
    "time_per_ray_s",
    "s",
    Class::Timing,
    "thread seconds per ray",
);
/// Build time.
pub const BUILD_S: Column = Column::value(
    "build_s",
    "s",
    Class::Timing,
    "finite scene: seconds to build its grid (mean over replicas)",
);
/// T_I.
pub const T_I_S: Column = Column::value(
    "t_i_s",
    "s",
    Class::Timing,
    "grid-cost-model: one ray–sphere test, measured on this machine",
);
/// T_S.
pub const T_S_S: Column = Column::value(
    "t_s_s",
    "s",
    Class::Timing,
    "grid-cost-model: one cell step, measured on this machine",
);
/// Model from theory.
pub const TIME_MODEL_S: Column = Column::value(
    "time_model_s",
    "s",
    Class::Timing,
    "grid-cost-model: N_I·T_I + N_S·T_S with the predicted counts",
);
/// Model from counts.
pub const TIME_COUNTS_MODEL_S: Column = Column::value(
    "time_counts_model_s",
    "s",
    Class::Timing,
    "grid-cost-model: N_I·T_I + N_S·T_S with the measured counts",
);

/// N_I against the band, with `prediction`.
fn in_band(m: &GridMeasured, e: crate::stats::Estimate, prediction: f64) -> Cell {
    let band = m.theory.band;
    Cell::Judged(
        e,
        Theory::Band {
            prediction,
            lower: band.lower,
            upper: band.upper,
        },
    )
}

/// A finite scene's fact (absent in an infinite scene).
fn finite(m: &GridMeasured, f: fn(&FiniteFacts) -> Cell) -> Cell {
    match &m.scene {
        SceneFacts::Finite(facts) => f(facts),
        SceneFacts::Infinite { .. } => Cell::Absent,
    }
}

/// The tests the cost model counts: with or without mailboxing, as the point traced.
fn tested(p: &GridConfig, m: &GridMeasured) -> (f64, f64) {
    if p.mailbox {
        (m.n_i_mb.mean, m.theory.n_i_mb)
    } else {
        (m.n_i.mean, m.theory.n_i)
    }
}

/// The main table, in column order.
pub const MAIN: Table<GridConfig, GridMeasured> = Table::of(&[
    col(&N_I, |_, m| in_band(m, m.n_i, m.theory.n_i)),
    col(&N_I_MB, |_, m| in_band(m, m.n_i_mb, m.theory.n_i_mb)),
    col(&N_I_PLAIN_THEORY, |_, m| m.theory.n_i_plain.into()),
    col(&PREDICTOR_REGIME, |_, m| m.theory.regime.into()),
    col(&N_S, |_, m| {
        Cell::Judged(m.n_s, Theory::Prediction(m.theory.n_s))
    }),
    col(&T_HIT, |_, m| {
        Cell::Judged(m.t_hit, Theory::Prediction(m.theory.t_hit))
    }),
    col(&HIT, |_, m| {
        Cell::Judged(m.hit, Theory::Prediction(m.theory.hit))
    }),
    col(&T_HIT_KS, |_, m| m.laws.ks.into()),
    col(&T_HIT_KS_P, |_, m| m.laws.ks_p.into()),
    col(&T_HIT_CHI2, |_, m| m.laws.chi_t.statistic.into()),
    col(&T_HIT_CHI2_DOF, |_, m| m.laws.chi_t.dof.into()),
    col(&T_HIT_CHI2_P, |_, m| m.laws.chi_t.p_value.into()),
    col(&N_I_GEOMETRIC_P, |_, m| m.laws.geometric_p.into()),
    col(&N_I_CYLINDER_RADIUS, |_, m| m.laws.cylinder_radius.into()),
    col(&N_I_MB_CHI2, |_, m| m.laws.chi_g.statistic.into()),
    col(&N_I_MB_CHI2_DOF, |_, m| m.laws.chi_g.dof.into()),
    col(&N_I_MB_CHI2_P, |_, m| m.laws.chi_g.p_value.into()),
    col(&TRUNCATED, |_, m| m.truncated.into()),
    col(&GENERATED, |_, m| match m.scene {
        SceneFacts::Infinite {
            generated_per_batch,
        } => generated_per_batch.into(),
        SceneFacts::Finite { .. } => Cell::Absent,
    }),
    col(&SPHERES, |_, m| finite(m, |f| f.spheres.into())),
    col(&GRID_CELLS, |_, m| finite(m, |f| f.cells.into())),
    col(&GRID_LISTINGS, |_, m| finite(m, |f| f.listings.into())),
    col(&GRID_BYTES, |_, m| finite(m, |f| f.bytes.into())),
    col(&H_LOG, |p, m| {
        m.scaling.map(|s| p.concentration_c * s.n.ln()).into()
    }),
    col(&P_LOG, |_, m| m.scaling.map(|s| s.p_log).into()),
    col(&H_SQRT, |p, m| {
        m.scaling.map(|s| p.concentration_c * s.n.sqrt()).into()
    }),
    col(&P_SQRT, |_, m| m.scaling.map(|s| s.p_sqrt).into()),
    col(&BF_RAYS, |_, m| m.scaling.map(|s| s.bf_rays).into()),
    col(&BF_MISMATCHES, |_, m| {
        m.scaling.map(|s| s.bf_mismatches).into()
    }),
    col(&BF_RAYS_PER_S, |_, m| {
        m.scaling.map(|s| s.bf_rays_per_s).into()
    }),
    col(&TRACE_S, |_, m| m.trace_s.into()),
    col(&RAYS_PER_S, |_, m| m.rays_per_s.into()),
    col(&TIME_PER_RAY_S, |_, m| m.time_per_ray_s.into()),
    col(&BUILD_S, |_, m| finite(m, |f| f.build_s.into())),
    col(&T_I_S, |_, m| m.machine.map(|c| c.t_i).into()),
    col(&T_S_S, |_, m| m.machine.map(|c| c.t_s).into()),
    col(&TIME_MODEL_S, |p, m| {
        let th = tested(p, m).1;
        m.machine
            .map(|c| query_time(th, m.theory.n_s, c.t_i, c.t_s))
            .into()
    }),
    col(&TIME_COUNTS_MODEL_S, |p, m| {
        let counted = tested(p, m).0;
        m.machine
            .map(|c| query_time(counted, m.n_s.mean, c.t_i, c.t_s))
            .into()
    }),
]);

/// Histogram table: which metric.
pub const HIST_METRIC: Column = Column::value(
    "metric",
    "1",
    Class::Measured,
    "t_hit (the first-hit distance) or n_i_mb (tests of hitting rays)",
);
/// Bin start.
pub const HIST_BIN_LO: Column =
    Column::value("bin_lo", "length or tests", Class::Measured, "bin start");
/// Bin end.
pub const HIST_BIN_HI: Column = Column::value(
    "bin_hi",
    "length or tests",
    Class::Measured,
    "bin end (inf for the overflow bin)",
)
.open_ended();
/// Count.
pub const HIST_COUNT: Column = Column::value("count", "rays", Class::Measured, "rays in the bin");
/// Expected.
pub const HIST_EXPECTED: Column = Column::value(
    "expected",
    "rays",
    Class::Theory,
    "rays the law expects in the bin (exponential for t_hit, the fitted geometric for n_i_mb)",
);

/// `NAME.hist.csv`.
pub const HIST: Table<GridConfig, HistBin> = Table::of(&[
    col(&HIST_METRIC, |_, b| b.metric.into()),
    col(&HIST_BIN_LO, |_, b| b.lo.into()),
    col(&HIST_BIN_HI, |_, b| b.hi.into()),
    col(&HIST_COUNT, |_, b| b.count.into()),
    col(&HIST_EXPECTED, |_, b| b.expected.into()),
]);
