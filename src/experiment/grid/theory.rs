//! The closed forms a grid point is held against, computed once per point from its parameters alone
//! (`theory::grid` restated for the point: the band of Results 3.1/3.2, the sharper predictors, the
//! exact E[N_S], and the first-hit law, conditioned on hitting inside the cube for a finite scene).

use glam::DVec3;

use super::config::{GridConfig, SceneModel};
use crate::theory::grid::{self as th, Band, Eye, GridTheoryInput};

/// The theory input of a config.
pub fn input(cfg: &GridConfig) -> GridTheoryInput<'_> {
    GridTheoryInput {
        intensity: cfg.intensity,
        classes: &cfg.classes,
        draw: cfg.draw,
        cell_width: cfg.cell_width,
    }
}

/// Every closed form of one grid point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridTheory {
    /// Result 3.1/3.2's band for E[N_I].
    pub band: Band,
    /// The no-mailbox predictor of E[N_I] (NaN below 1, outside its expansion).
    pub n_i: f64,
    /// The mailboxed predictor (likewise).
    pub n_i_mb: f64,
    /// (1 + E[N_S])·ρ|o(a,r)|.
    pub n_i_plain: f64,
    /// E[N_S] for the eye placement.
    pub n_s: f64,
    /// Where the sharper predictors are derived: `r<a/2`, else `r>=a/2`.
    pub regime: &'static str,
    /// E[t*] of the infinite scene (the histogram's scale).
    pub mean_t: f64,
    /// P(hit): 1 in an infinite scene, the exponential law over the cube in a finite one.
    pub hit: f64,
    /// E[t* | hit] (conditioned on hitting inside a finite cube).
    pub t_hit: f64,
}

impl GridTheory {
    /// The closed forms of `cfg`.
    pub fn of(cfg: &GridConfig) -> Self {
        let inp = input(cfg);
        let mean_t = th::mean_first_hit(&inp);
        let n_s = th::n_s_mean(&inp, cfg.eye);
        // Every hitting ray tests at least one sphere: a predictor below 1 is outside its expansion.
        let at_least_one = |x: f64| if x >= 1.0 { x } else { f64::NAN };
        // The sharper predictors are derived for r < a/2 (no overlap of non-adjacent cells' offsets).
        let r_max = cfg
            .classes
            .iter()
            .map(|c| c.radius.max())
            .fold(0.0, f64::max);
        // In a finite cube hits are cut off at the faces: condition the law on hitting inside.
        let (hit, t_hit) = match &cfg.scene {
            SceneModel::Infinite => (1.0, mean_t),
            SceneModel::Finite(_) => finite_hit_theory(cfg, &inp),
        };
        Self {
            band: th::n_i_band(&inp),
            n_i: at_least_one(th::n_i_predictor_for_eye(&inp, cfg.eye)),
            n_i_mb: at_least_one(th::n_i_mb_predictor_for_eye(&inp, cfg.eye)),
            n_i_plain: th::n_i_plain_predictor(&inp, n_s),
            n_s,
            regime: if r_max < 0.5 * cfg.cell_width {
                "r<a/2"
            } else {
                "r>=a/2"
            },
            mean_t,
            hit,
            t_hit,
        }
    }
}

/// The exponential law restricted to a finite cube: `(P(hit), E[t* | hit])` for rays from the eye
/// (at the centre, or uniform in its cell) to the faces of the cube holding the centres.
///
/// With L the distance to the cube along the ray, P(hit) = E[1 − S(L)] and
/// E[t*·1{hit}] = E[∫₀^L S(t) dt − L·S(L)], where S is the infinite-scene survival function. Both
/// expectations are over directions (a 100 × 200 midpoint rule in z and φ, uniform on the sphere)
/// and over eye positions (the corner, or a 3 × 3 × 3 midpoint rule in the cell); the t integral
/// uses 8-node Gauss–Legendre. An approximation: it ignores the layer of width r beyond the faces
/// where spheres centred inside the cube can still be hit.
fn finite_hit_theory(cfg: &GridConfig, inp: &GridTheoryInput) -> (f64, f64) {
    let SceneModel::Finite(fs) = &cfg.scene else {
        return (1.0, th::mean_first_hit(inp));
    };
    let b = fs.centre_box();
    let a = cfg.cell_width;
    let eyes: Vec<DVec3> = match cfg.eye {
        Eye::Corner => vec![fs.center],
        Eye::Uniform => (0..27)
            .map(|k| {
                fs.center
                    + DVec3::new(
                        (k % 3) as f64 + 0.5,
                        (k / 3 % 3) as f64 + 0.5,
                        (k / 9) as f64 + 0.5,
                    ) * (a / 3.0)
            })
            .collect(),
    };
    let (gx, gw) = crate::sample::radius::gauss_legendre(8);
    let (nz, nphi) = (100, 200);
    let (mut p_hit, mut t_hit) = (0.0, 0.0);
    for i in 0..nz {
        let z = -1.0 + (i as f64 + 0.5) * 2.0 / nz as f64;
        let s = (1.0 - z * z).sqrt();
        for j in 0..nphi {
            let phi = (j as f64 + 0.5) * std::f64::consts::TAU / nphi as f64;
            let d = DVec3::new(s * phi.cos(), s * phi.sin(), z);
            for e in &eyes {
                // Distance to the cube's faces along d.
                let l = (0..3)
                    .map(|k| {
                        let (dk, ek) = (d[k], e[k]);
                        if dk > 0.0 {
                            ((b.hi[k] - ek) / dk).max(0.0)
                        } else if dk < 0.0 {
                            ((b.lo[k] - ek) / dk).max(0.0)
                        } else {
                            f64::INFINITY
                        }
                    })
                    .fold(f64::INFINITY, f64::min);
                let s_l = th::first_hit_survival(inp, l);
                p_hit += 1.0 - s_l;
                let integral: f64 = gx
                    .iter()
                    .zip(&gw)
                    .map(|(x, w)| 0.5 * l * w * th::first_hit_survival(inp, 0.5 * l * (x + 1.0)))
                    .sum();
                t_hit += integral - l * s_l;
            }
        }
    }
    (p_hit / (nz * nphi * eyes.len()) as f64, t_hit / p_hit)
}
