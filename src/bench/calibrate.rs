//! T_I and T_S of the query grid on this machine, and the cell width the cost model then picks.
//!
//! The paper's cost model is t = N_I·T_I + N_S·T_S. Here the costs are measured on the query grid
//! itself (so the memory traffic of real lists is in them, unlike `experiment::machine`'s L1
//! microbenchmarks): the grid is built at several cell widths over one calibration scene, the same
//! rays are timed on one thread in alternating rounds ([`super::rounds`]), and the model is fitted to
//! the median time per ray by least squares (no intercept). The query grid tests 8 listings per
//! instruction, so T_I comes out near 1/8 of a step's cost and the optimum moves to wider cells
//! than a one-test-at-a-time grid would use.

use glam::DVec3;
use rayon::prelude::*;

use super::rounds::{alternate, median};
use crate::experiment::machine::MachineCosts;
use crate::geom::{Aabb, Ray, Sphere};
use crate::grid::build::frame_around;
use crate::grid::fast::FastGrid;
use crate::scene::{RadiusClass, RadiusDraw};
use crate::theory::grid::{self as th, Eye, GridTheoryInput, QueryCost};

/// Cell widths timed (in units of the mean spacing ρ^(−1/3)).
const WIDTHS: [f64; 5] = [1.0, 1.5, 2.0, 2.5, 3.0];

/// What the calibration measured and chose.
#[derive(Clone, Debug)]
pub struct Calibration {
    /// Fitted costs, seconds.
    pub costs: MachineCosts,
    /// (cell width, mean N_I, mean N_S, median seconds per ray) of every width timed.
    pub points: Vec<(f64, f64, f64, f64)>,
    /// The cell width the cost model picks with these costs.
    pub cell_width: f64,
}

/// Times the query grid over `spheres` (in `bounds`) at [`WIDTHS`] on `rays` (one thread, `rounds`
/// alternating rounds), fits T_I and T_S, and asks the cost model for the best width in
/// `[0.3, 6]`·ρ^(−1/3) for a scene of intensity `rho` and radius `classes`.
pub fn calibrate(
    spheres: &[Sphere],
    bounds: Aabb,
    rays: &[Ray],
    rounds: usize,
    rho: f64,
    classes: &[RadiusClass],
) -> anyhow::Result<Calibration> {
    let spacing = rho.powf(-1.0 / 3.0);
    let grids: Vec<FastGrid> = WIDTHS
        .iter()
        .map(|&w| FastGrid::build(frame_around(bounds, w * spacing, DVec3::ZERO), spheres))
        .collect();
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    let counts: Vec<(f64, f64)> = grids
        .iter()
        .map(|g| {
            // Integer counts: their f64 sums are exact in any order.
            let (ni, ns) = rays
                .par_iter()
                .map(|r| {
                    let q = g.trace(r);
                    (f64::from(q.n_i), f64::from(q.n_s))
                })
                .reduce(|| (0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1));
            (ni / rays.len() as f64, ns / rays.len() as f64)
        })
        .collect();
    let times = one.install(|| {
        alternate(grids.len(), rounds, |c, _| {
            for r in rays {
                std::hint::black_box(grids[c].trace(r));
            }
        })
    });
    let points: Vec<(f64, f64, f64, f64)> = WIDTHS
        .iter()
        .zip(&counts)
        .zip(&times.secs)
        .map(|((&w, &(ni, ns)), secs)| (w * spacing, ni, ns, median(secs) / rays.len() as f64))
        .collect();
    let costs = fit(&points);
    let probe = GridTheoryInput {
        intensity: rho,
        classes,
        draw: RadiusDraw::PerSphere,
        cell_width: spacing,
    };
    // The query grid tests every listing (no mailbox), so the model's N_I is the plain one.
    let cell_width = th::best_cell_width(
        &probe,
        &QueryCost {
            t_i: costs.t_i,
            t_s: costs.t_s,
            eye: Eye::Uniform,
            mailbox: false,
        },
        0.3 * spacing,
        6.0 * spacing,
    );
    Ok(Calibration {
        costs,
        points,
        cell_width,
    })
}

/// Least-squares fit of t = N_I·T_I + N_S·T_S (no intercept) to `(_, N_I, N_S, t)` points; each
/// cost is kept positive (a degenerate fit falls back to a tiny cost rather than a negative one).
fn fit(points: &[(f64, f64, f64, f64)]) -> MachineCosts {
    let (mut sii, mut sis, mut sss, mut sit, mut sst) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for &(_, ni, ns, t) in points {
        sii += ni * ni;
        sis += ni * ns;
        sss += ns * ns;
        sit += ni * t;
        sst += ns * t;
    }
    let det = sii * sss - sis * sis;
    MachineCosts {
        t_i: ((sit * sss - sst * sis) / det).max(1e-12),
        t_s: ((sst * sii - sit * sis) / det).max(1e-12),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fit_recovers_exact_costs() {
        let (t_i, t_s) = (2e-9, 30e-9);
        let points: Vec<_> = [(70.0, 40.0), (126.0, 27.0), (213.0, 20.0), (315.0, 16.0)]
            .iter()
            .map(|&(ni, ns)| (0.0, ni, ns, ni * t_i + ns * t_s))
            .collect();
        let c = fit(&points);
        assert!(
            (c.t_i - t_i).abs() < 1e-15 && (c.t_s - t_s).abs() < 1e-14,
            "{c:?}"
        );
    }
}
