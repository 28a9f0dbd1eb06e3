//! Closed forms for a regular grid of cubic cells over Poisson spheres: what a ray costs until its
//! first hit.
//!
//! Setting (docs/theory.md §1): sphere centres form a homogeneous Poisson process of intensity ρ (centres
//! per unit volume), split into radius classes (class i: fraction α_i, Σα_i = 1, radius law R_i);
//! the eye is at the origin, directions are uniform on the unit sphere, and spheres containing the
//! eye are ignored as hits (but they are listed in the cells and tested, so they count in N_I).
//! Cells are cubes of width a. A visited cell's whole list is tested (lists are unordered), and the
//! traversal stops in the cell holding the first hit.
//!
//! | function | source |
//! |---|---|
//! | [`offset_cube_volume`] | §3.3, Steiner volume of o(a, r) |
//! | [`first_hit_survival`], [`first_hit_rate`], [`mean_first_hit`] | eq. (4)/(5); §3.4 for classes |
//! | [`geometric_pmf`], [`geometric_p_for_s`] | eq. (8)–(9), cylinder model |
//! | [`n_i_band`] | Result 3.1 (one constant radius), Result 3.2 (classes) |
//! | [`n_s_uniform_eye`], [`n_s_corner_eye`] | beyond the paper (docs/theory.md §1), derived there |
//! | [`n_i_predictor`], [`n_i_plain_predictor`], [`n_i_mb_predictor`] | beyond the paper, derived there |
//! | [`query_time`], [`model_query_time`], [`best_cell_width`] | §3, t = N_I·T_I + N_S·T_S |
//!
//! # Two meanings of "class i has random radius R_i" ([`RadiusDraw`])
//! - **PerScene** (the paper's literal Result 3.2): all spheres of class i share one radius R_i,
//!   drawn once per scene. Every result is computed for fixed radii r = (r_1..r_n) and then
//!   integrated over Π f_{R_i}(r_i) by a tensor product of the classes' Gauss–Legendre rules.
//!   Here t* given r is Exponential(ρπΣα_i r_i²), so t* itself is a mixture of exponentials.
//! - **PerSphere** (marked Poisson process): each sphere draws its own radius. The spheres of class i
//!   whose ball meets the segment \[0, τ\] without containing the eye have centres in the capsule of
//!   radius R around the segment minus B(0, R), volume πR²τ; by the marking theorem their number is
//!   Poisson(ρπτ Σα_i E\[R_i²\]), so t* ~ Exponential(λ) with λ = ρπΣα_iE\[R_i²\] exactly. In the
//!   cylinder model the refused centres of class i (radius R) lie in a shell of cross-section
//!   π((s_i+R)² − R²); given t* = τ their total is Poisson(ρπτ Σα_iE\[(s_i+R_i)² − R_i²\]), and
//!   mixing a Poisson(κτ) over τ ~ Exp(λ) gives a geometric law: P(N_I = k+1) = (1−p)^k p with
//!   p = λ/(λ+κ) = Σα_iE\[R_i²\] / Σα_iE\[(s_i+R_i)²\]. Hence
//!   E\[N_I\] = Σα_iE\[(s_i+R_i)²\]/Σα_iE\[R_i²\] + c, 0 ≤ c ≤ ρΣα_iE|o(a, R_i)|, with s_i's lower end
//!   max(0, a/√(√3π) − R_i) inside the expectation.
//!
//! Both reduce to Result 3.1 for a single class of constant radius (tested).
//!
//! Per-sphere expectations use 16 Gauss–Legendre nodes per panel of [`RadiusDist::quadrature`];
//! per-scene tensor products use fewer per class (16, 8, 3 for 1, 2, ≥3 classes) to keep the
//! product below about 10⁵ nodes.
//!
//! [`RadiusDist::quadrature`]: crate::sample::radius::RadiusDist::quadrature

use crate::sample::radius::{gauss_legendre_panels, RadiusClass, RadiusDraw};
use std::f64::consts::PI;
use std::sync::OnceLock;

/// Everything the grid closed forms depend on.
#[derive(Clone, Copy, Debug)]
pub struct GridTheoryInput<'a> {
    /// ρ: sphere centres per unit volume (all classes together), > 0.
    pub intensity: f64,
    /// The radius classes; fractions sum to 1, radii in length units, every radius > 0.
    pub classes: &'a [RadiusClass],
    /// Whether a class's radius is drawn per sphere or once per scene.
    pub draw: RadiusDraw,
    /// a: cell width (length units), > 0.
    pub cell_width: f64,
}

/// Where the eye sits relative to the grid (also the spec's `grid.eye`, spelled in kebab case).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Eye {
    /// Exactly at a cell corner (the floor effect lowers N_S slightly).
    Corner,
    /// Uniformly distributed inside its cell (a fresh position per ray).
    #[default]
    Uniform,
}

/// A closed interval `\[lower, upper\]` for an expected count (dimensionless).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Band {
    /// Lower end.
    pub lower: f64,
    /// Upper end.
    pub upper: f64,
}

/// What one query costs in the model t = N_I·T_I + N_S·T_S, and which variant is modelled.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QueryCost {
    /// T_I: time of one ray–sphere test (any time unit, e.g. seconds).
    pub t_i: f64,
    /// T_S: time of one cell step (same unit as `t_i`).
    pub t_s: f64,
    /// Eye placement, which sets E\[N_S\].
    pub eye: Eye,
    /// Whether the grid mailboxes (tests each distinct sphere once per ray).
    pub mailbox: bool,
}

/// Gauss–Legendre nodes per panel for per-sphere expectations (as [`RadiusDist::expect`]).
///
/// [`RadiusDist::expect`]: crate::sample::radius::RadiusDist::expect
const SPHERE_NODES: usize = 16;

/// Nodes per panel per class for per-scene tensor products, by number of classes.
fn scene_nodes(classes: usize) -> usize {
    match classes {
        0 | 1 => 16,
        2 => 8,
        _ => 3,
    }
}

/// The radius-mixture operator M(g) = Σ α_i E\[g(R_i)\] (per sphere) or Σ α_i g(r_i) (fixed radii).
type Mix<'m> = &'m dyn Fn(&dyn Fn(f64) -> f64) -> f64;

/// Evaluates a fixed-radii formula `f(M)` and averages it according to `draw`: per sphere, `f` is
/// called once with the mixture over the radius laws; per scene, `f` is integrated over the product
/// of the classes' radius laws (`n` Gauss–Legendre nodes per panel per class).
fn average(inp: &GridTheoryInput, draw: RadiusDraw, n: usize, f: impl Fn(Mix) -> f64) -> f64 {
    average_over(inp, draw, &nodes(inp, n), f)
}

/// Each class's `n`-node quadrature of its radius law.
fn nodes(inp: &GridTheoryInput, n: usize) -> Vec<Vec<(f64, f64)>> {
    debug_assert!(!inp.classes.is_empty(), "at least one radius class");
    debug_assert!(
        (inp.classes.iter().map(|c| c.fraction).sum::<f64>() - 1.0).abs() < 1e-9,
        "class fractions sum to 1"
    );
    inp.classes.iter().map(|c| c.radius.quadrature(n)).collect()
}

/// [`average`] on given quadrature `nodes` (computed once by a caller that averages many times).
fn average_over(
    inp: &GridTheoryInput,
    draw: RadiusDraw,
    nodes: &[Vec<(f64, f64)>],
    f: impl Fn(Mix) -> f64,
) -> f64 {
    match draw {
        RadiusDraw::PerSphere => {
            let mix = |g: &dyn Fn(f64) -> f64| -> f64 {
                inp.classes
                    .iter()
                    .zip(nodes)
                    .map(|(c, q)| c.fraction * q.iter().map(|&(r, w)| w * g(r)).sum::<f64>())
                    .sum()
            };
            f(&mix)
        }
        RadiusDraw::PerScene => {
            let k = nodes.len();
            let mut idx = vec![0usize; k];
            let mut radii = vec![0.0; k];
            let mut total = 0.0;
            loop {
                // Current tensor node: radii and product weight
                let mut w = 1.0;
                for i in 0..k {
                    let (r, wi) = nodes[i][idx[i]];
                    radii[i] = r;
                    w *= wi;
                }
                if w > 0.0 {
                    let mix = |g: &dyn Fn(f64) -> f64| -> f64 {
                        inp.classes
                            .iter()
                            .zip(&radii)
                            .map(|(c, &r)| c.fraction * g(r))
                            .sum()
                    };
                    total += w * f(&mix);
                }
                // Odometer increment over the classes
                let mut i = 0;
                loop {
                    if i == k {
                        return total;
                    }
                    idx[i] += 1;
                    if idx[i] < nodes[i].len() {
                        break;
                    }
                    idx[i] = 0;
                    i += 1;
                }
            }
        }
    }
}

/// [`average`] with the default node count for the draw.
fn average_default(inp: &GridTheoryInput, f: impl Fn(Mix) -> f64) -> f64 {
    average(inp, inp.draw, default_nodes(inp), f)
}

/// The default node count for the input's draw.
fn default_nodes(inp: &GridTheoryInput) -> usize {
    match inp.draw {
        RadiusDraw::PerSphere => SPHERE_NODES,
        RadiusDraw::PerScene => scene_nodes(inp.classes.len()),
    }
}

/// |o(a, r)| = a³ + 6a²r + 3πar² + 4πr³/3: volume (length³) of the set of points within distance
/// `r` of a cube of width `a` (Steiner formula; §3.3). A cell's list holds the spheres whose centre
/// lies in this set, so its mean length is ρ|o(a, r)|.
pub fn offset_cube_volume(a: f64, r: f64) -> f64 {
    debug_assert!(a >= 0.0 && r >= 0.0);
    a * a * a + 6.0 * a * a * r + 3.0 * PI * a * r * r + 4.0 * PI * r * r * r / 3.0
}

/// 2a²r + 2πar² + 4πr³/3: volume (length³) of the r-offset of a square face of side `a` (a slab,
/// four half-cylinders, four ball quarters). For r ≤ a it is exactly the overlap of the r-offsets of
/// two face-adjacent cubes (beyond the paper: a point within r of both cubes is within r of the
/// shared face, and conversely).
pub fn offset_face_volume(a: f64, r: f64) -> f64 {
    debug_assert!(a >= 0.0 && r >= 0.0);
    2.0 * a * a * r + 2.0 * PI * a * r * r + 4.0 * PI * r * r * r / 3.0
}

/// Fraction of DDA steps that are turns (the step's axis differs from the previous step's), averaged
/// over uniform directions with the eye uniform in its cell: κ/1.5 with
/// κ = E_d\[Σ_i|d_i| − Σ_i |d_i| Π_{j≠i} (1 − |d_j|/|d_i|)⁺\] (dimensionless, ≈ 0.800, i.e. κ ≈ 1.200).
///
/// Derivation (beyond the paper): axis-i planes are crossed at rate |d_i|/a per unit length, with
/// independent uniform phases per axis when the eye is uniform. After an axis-i crossing the next
/// one is a/|d_i| further; no axis-j crossing falls in between with probability (1 − |d_j|/|d_i|)⁺,
/// independently for the two other axes. Steps per unit length: Σ|d_i|/a (mean 1.5/a).
pub fn turn_fraction() -> f64 {
    static CACHE: OnceLock<f64> = OnceLock::new();
    *CACHE.get_or_init(|| {
        // Octant by symmetry: z = |d_z| uniform on [0, 1], azimuth uniform on [0, π/2]
        let zs = gauss_legendre_panels(0.0, 1.0, 8, 96);
        let phis = gauss_legendre_panels(0.0, 0.5 * PI, 8, 96);
        let mut kappa = 0.0;
        for &(z, wz) in &zs {
            let s = (1.0 - z * z).max(0.0).sqrt();
            for &(phi, wp) in &phis {
                let u = [s * phi.cos(), s * phi.sin(), z];
                let mut same = 0.0;
                for i in 0..3 {
                    if u[i] <= 0.0 {
                        continue;
                    }
                    let mut p = u[i];
                    for (j, &uj) in u.iter().enumerate() {
                        if j != i {
                            p *= (1.0 - uj / u[i]).max(0.0);
                        }
                    }
                    same += p;
                }
                kappa += wz * wp * (u[0] + u[1] + u[2] - same);
            }
        }
        kappa / (0.5 * PI) / 1.5
    })
}

/// Volume (length³) that one DDA step adds, on average, to the union U of the r-offsets of the
/// visited cells: a³ + 4a²r + πar² − f_turn·(1 − π/4)·a·r², f_turn = [`turn_fraction`]. Valid for
/// r < a/2 up to O(r³) per step (see [`n_i_mb_predictor`] for the derivation).
pub fn mailbox_step_volume(a: f64, r: f64) -> f64 {
    offset_cube_volume(a, r)
        - offset_face_volume(a, r)
        - turn_fraction() * (1.0 - PI / 4.0) * a * r * r
}

/// Result 3.1 / 3.2: the band the paper gives for E\[N_I\] (dimensionless). For one class of constant
/// radius r: lower = max(1, a²/(√3·π·r²)) (that is ((s_lo + r)/r)² with s_lo = max(0, a/√(√3π) − r),
/// c = 0) and upper = ((a√3 + r)/r)² + ρ|o(a, r)|. With classes, the per-class endpoints enter
/// Σα_i(s_i+r_i)²/Σα_i r_i² + c, averaged as the module doc says for each [`RadiusDraw`].
pub fn n_i_band(inp: &GridTheoryInput) -> Band {
    let (a, rho) = (inp.cell_width, inp.intensity);
    // (max(0, k − r) + r)² = max(k, r)²
    let k = a / (3f64.sqrt() * PI).sqrt();
    let s_hi = a * 3f64.sqrt();
    let lower = average_default(inp, |m| m(&|r| r.max(k).powi(2)) / m(&|r| r * r));
    let upper = average_default(inp, |m| {
        m(&|r| (s_hi + r).powi(2)) / m(&|r| r * r) + rho * m(&|r| offset_cube_volume(a, r))
    });
    Band { lower, upper }
}

/// λ = ρπΣα_iE\[R_i²\] (1/length): the first-hit rate (eq. 5; §3.4). Per sphere, t* ~ Exponential(λ)
/// exactly. Per scene, t* given the radii is Exponential(λ(r)) and this returns the mean rate
/// E\[λ(R)\] (t* is then not exponential; use [`first_hit_survival`] and [`mean_first_hit`]).
pub fn first_hit_rate(inp: &GridTheoryInput) -> f64 {
    let per_sphere = GridTheoryInput {
        draw: RadiusDraw::PerSphere,
        ..*inp
    };
    average_default(&per_sphere, |m| rate(inp.intensity, m))
}

fn rate(rho: f64, m: Mix) -> f64 {
    rho * PI * m(&|r| r * r)
}

/// P(t* ≥ τ) (dimensionless) for a distance `tau` (length) along the ray: exp(−λτ) per sphere
/// (eq. 4); E_R\[exp(−ρπΣα_iR_i²τ)\] per scene.
pub fn first_hit_survival(inp: &GridTheoryInput, tau: f64) -> f64 {
    average_default(inp, |m| (-rate(inp.intensity, m) * tau).exp())
}

/// [`first_hit_survival`] as a function of τ, its quadrature computed once: the same numbers, for
/// callers that evaluate it at every sample (a KS test over 10⁵ first-hit distances would otherwise
/// spend more time rebuilding Gauss–Legendre nodes than tracing the rays).
pub fn first_hit_survival_fn<'a>(inp: &'a GridTheoryInput<'a>) -> impl Fn(f64) -> f64 + 'a {
    let nodes = nodes(inp, default_nodes(inp));
    move |tau| {
        average_over(inp, inp.draw, &nodes, |m| {
            (-rate(inp.intensity, m) * tau).exp()
        })
    }
}

/// E\[t*\] (length): 1/λ per sphere; E_R\[1/(ρπΣα_iR_i²)\] per scene (≥ 1/E\[λ(R)\] by Jensen).
pub fn mean_first_hit(inp: &GridTheoryInput) -> f64 {
    average_default(inp, |m| 1.0 / rate(inp.intensity, m))
}

/// E\[N_S\] (cell steps) with the eye uniform in its cell: 1.5·E\[t*\]/a.
///
/// Derivation (beyond the paper): the ray crosses axis-x planes at ⌊x₀ + |d_x|t/a⌋ for a uniform
/// phase x₀, whose mean is exactly |d_x|t/a; E|d_x| = 1/2 over uniform directions, three axes, and
/// the traversal stops in the cell holding the hit at t*. Linear in t*, so per scene it is
/// 1.5·E_R\[E\[t* | R\]\]/a as well.
pub fn n_s_uniform_eye(inp: &GridTheoryInput) -> f64 {
    1.5 * mean_first_hit(inp) / inp.cell_width
}

/// E\[N_S\] (cell steps) with the eye at a cell corner: 3∫₀¹ du/(exp(λa/u) − 1); per scene, the same
/// with λ(r), integrated over the radii. See [`n_s_corner_eye_mu`].
pub fn n_s_corner_eye(inp: &GridTheoryInput) -> f64 {
    let a = inp.cell_width;
    average_default(inp, |m| n_s_corner_eye_mu(rate(inp.intensity, m) * a))
}

/// E\[N_S\] for the corner eye as a function of μ = λa > 0 (dimensionless):
/// 3∫₀¹ du/(e^{μ/u} − 1).
///
/// Derivation (beyond the paper): with the eye at a corner the axis-x crossings up to t are
/// ⌊|d_x|t/a⌋; |d_x| is uniform on \[0, 1\] (Archimedes), and given |d_x| = u, Y = ut/a is
/// Exponential(μ/u), with E⌊Y⌋ = Σ_{k≥1} e^{−kμ/u} = 1/(e^{μ/u} − 1).
///
/// Numerics: for μ < 1 the integrand is exponentially flat near u = 0 and ≈ u/μ − 1/2 elsewhere, so
/// write 1/(e^x − 1) = 1/x − 1/2 + h(x) (x = μ/u) and get exactly
/// ∫₀¹ = 1/(2μ) − 1/2 + μ∫_μ^∞ h(x)x⁻² dx, the last integral on a log scale (integrand → 1/12 as
/// x → 0, series for h at small x) with the closed tail ∫_X^∞ (1/2 − 1/x)x⁻² dx beyond X = 40.
/// For μ ≥ 1, substitute u = 1/(1 + w/μ): ∫₀¹ = (e^{−μ}/μ)∫₀^∞ e^{−w}(1 + w/μ)⁻²/(1 − e^{−μ−w}) dw,
/// which keeps full relative accuracy however small the result (no overflow for large μ).
pub fn n_s_corner_eye_mu(mu: f64) -> f64 {
    debug_assert!(mu > 0.0, "μ = λa must be positive, got {mu}");
    3.0 * if mu < 1.0 {
        corner_integral_small(mu)
    } else {
        corner_integral_large(mu)
    }
}

/// h(x) = 1/(e^x − 1) − 1/x + 1/2, with its series below 1e-2 (the direct form cancels there).
fn bose_remainder(x: f64) -> f64 {
    if x < 1e-2 {
        let x2 = x * x;
        x / 12.0 - x * x2 / 720.0 + x * x2 * x2 / 30240.0
    } else {
        1.0 / x.exp_m1() - 1.0 / x + 0.5
    }
}

fn corner_integral_small(mu: f64) -> f64 {
    const X: f64 = 40.0;
    let (y_lo, y_hi) = (mu.ln(), X.ln());
    let panels = ((y_hi - y_lo) / 1.0).ceil().max(1.0) as usize;
    let body: f64 = gauss_legendre_panels(y_lo, y_hi, 12, panels)
        .into_iter()
        .map(|(y, w)| {
            let x = y.exp();
            w * bose_remainder(x) / x
        })
        .sum();
    // h(x) = 1/2 − 1/x + O(e^{−40}) beyond X
    let tail = 0.5 / X - 0.5 / (X * X);
    0.5 / mu - 0.5 + mu * (body + tail)
}

fn corner_integral_large(mu: f64) -> f64 {
    let body: f64 = gauss_legendre_panels(0.0, 60.0, 12, 40)
        .into_iter()
        .map(|(w_, wt)| {
            let q = 1.0 + w_ / mu;
            wt * (-w_).exp() / (q * q * -(-mu - w_).exp_m1())
        })
        .sum();
    (-mu).exp() / mu * body
}

/// E\[N_S\] (cell steps) for the eye placement.
pub fn n_s_mean(inp: &GridTheoryInput, eye: Eye) -> f64 {
    match eye {
        Eye::Uniform => n_s_uniform_eye(inp),
        Eye::Corner => n_s_corner_eye(inp),
    }
}

/// E\[N_S | radii\] from the rate λ (1/length) for fixed radii.
fn n_s_for_rate(eye: Eye, lambda: f64, a: f64) -> f64 {
    match eye {
        Eye::Uniform => 1.5 / (lambda * a),
        Eye::Corner => n_s_corner_eye_mu(lambda * a),
    }
}

/// P(N_I = k) = (1 − p)^(k−1)·p for k ≥ 1, 0 for k = 0 (eq. 8's geometric law; dimensionless).
pub fn geometric_pmf(p: f64, k: u64) -> f64 {
    debug_assert!((0.0..=1.0).contains(&p));
    match k {
        0 => 0.0,
        1 => p,
        _ => p * ((k - 1) as f64 * (-p).ln_1p()).exp(),
    }
}

/// p = (r/(s + r))²: the geometric parameter of the cylinder model of radius `s` for spheres of
/// radius `r` (both lengths; eq. 9).
pub fn geometric_p_for_s(r: f64, s: f64) -> f64 {
    debug_assert!(r > 0.0 && s >= 0.0);
    (r / (s + r)).powi(2)
}

/// Sharper predictor (beyond the paper) of E\[N_I\] without mailboxing (tests, dimensionless), given
/// the mean number of cell steps `n_s_mean`:
/// E\[N_I\] ≈ (1 + E\[N_S\])·ρΣα_iE|o(a, R_i)| − 4·Σα_iE\[R_i³\]/(a·Σα_iE\[R_i²\]); for one radius r the
/// correction is −4r/a.
///
/// # Derivation
/// Let the visited cells be C_0..C_{N_S}; every list is tested in full, so N_I = Σ_k #(centres in
/// o(C_k, r)), a centre counted once per visited cell it is listed in. Condition on the direction,
/// the eye and t* = τ: the process is Poisson(ρ) outside K∖B, where K is the capsule of radius r
/// around \[0, τ\] and B = B(0, r) (K∖B holds no centre, |K∖B| = πr²τ), plus one hit centre c. So,
/// exactly, E\[N_I\] = (1 + E\[N_S\])ρ|o| − E\[X_excl\] + E\[X_hit\] with X_excl = ρ∫_{K∖B} m(x)dx,
/// m(x) = #visited cells within r of x, and X_hit = m(c).
///
/// - X_excl: a capsule point x lies in a visited cell, and every lattice plane within r of x
///   separates it from a cell that the ray also visits (the ray crosses that plane on the shared
///   face unless it runs nearly parallel to it: probability O((r/a)·ln(a/r))). So at first order
///   m(x) = 1 + #(planes within r of x), whose mean is 1 + 3·2r/a = 1 + 6r/a. Note this is larger
///   than the chord count 1 + 1.5·(4r/3)/a = 1 + 2r/a: a cell within r of x need not be entered by
///   the ray inside B(x, r). With E\[ρπr²t*\] = 1: E\[X_excl\] ≈ 1 + 6r/a.
/// - X_hit: c = q + r·n with q = τd the hit point and n = cos θ·d + sin θ·e (e ⊥ d uniform,
///   sin²θ uniform on \[0,1\], so E\[n\] = (2/3)d). The ball B(c, r) contains q ∈ C_{N_S}; cells beyond
///   q are not visited. An axis-i plane crossed a distance σ before q is within r of c iff
///   σ|d_i| ≤ r(1 − n_i·sgn d_i), and such crossings occur at rate |d_i|/a, so
///   E\[X_hit\] ≈ 1 + Σ_i E\[r(1 − n_i sgn d_i)\]/a = 1 + (r/a)(3 − (2/3)·E Σ|d_i|) = 1 + 2r/a.
/// - Net: −(1 + 6r/a) + (1 + 2r/a) = −4r/a. With classes the excluded volume weights class i by
///   α_iR_i², and the hit sphere's radius is size-biased by R² (its class is chosen at rate πR²):
///   both give Σα_iE\[R_i³\]/Σα_iE\[R_i²\] in place of r.
///
/// Neglected: O((r/a)² ln(a/r)) per capsule point (points near cell edges, rays nearly parallel to
/// a plane), the ends of the capsule (relative weight O(λr)·O(r/a), λ = ρπr²), and the first step's
/// cells near the eye. Valid for r ≪ a. Per scene, `n_s_mean` is treated as independent of the
/// radii (E\[N_S·f(R)\] ≈ E\[N_S\]·E\[f(R)\]); [`n_i_predictor_for_eye`] integrates exactly instead.
pub fn n_i_predictor(inp: &GridTheoryInput, n_s_mean: f64) -> f64 {
    let (rho, a) = (inp.intensity, inp.cell_width);
    average_default(inp, |m| n_i_fixed(rho, a, m, n_s_mean))
}

/// [`n_i_predictor`] with E\[N_S | radii\] from the eye model, integrated over the radii per scene.
pub fn n_i_predictor_for_eye(inp: &GridTheoryInput, eye: Eye) -> f64 {
    let (rho, a) = (inp.intensity, inp.cell_width);
    average_default(inp, |m| {
        n_i_fixed(rho, a, m, n_s_for_rate(eye, rate(rho, m), a))
    })
}

/// The uncorrected predictor (1 + E\[N_S\])·ρΣα_iE|o(a, R_i)| (tests, dimensionless): every visited
/// cell's mean list length. It exceeds [`n_i_predictor`] by 4Σα_iE\[R_i³\]/(aΣα_iE\[R_i²\]).
pub fn n_i_plain_predictor(inp: &GridTheoryInput, n_s_mean: f64) -> f64 {
    let (rho, a) = (inp.intensity, inp.cell_width);
    average_default(inp, |m| {
        (1.0 + n_s_mean) * rho * m(&|r| offset_cube_volume(a, r))
    })
}

fn n_i_fixed(rho: f64, a: f64, m: Mix, n_s: f64) -> f64 {
    (1.0 + n_s) * rho * m(&|r| offset_cube_volume(a, r))
        - 4.0 * m(&|r| r * r * r) / (a * m(&|r| r * r))
}

/// Sharper predictor (beyond the paper) of E\[N_I,mb\] with mailboxing (distinct spheres tested,
/// dimensionless), given the mean number of cell steps `n_s_mean`:
/// E\[N_I,mb\] ≈ ρΣα_iE\[|o(a, R_i)| + E\[N_S\]·v(a, R_i)\], v = [`mailbox_step_volume`]
/// = a³ + 4a²r + πar² − f_turn(1 − π/4)ar².
///
/// # Derivation
/// The tested spheres are the distinct centres in U = ∪_k o(C_k, r). Given the direction, the eye
/// and t* = τ, the centres outside K∖B are Poisson(ρ) (K the capsule, B = B(0, r), as in
/// [`n_i_predictor`]), K ⊂ U (every point of \[0, τ\] lies in a visited cell), and the hit centre is in
/// U. So E\[N_I,mb | τ, cells\] = ρ(|U| − πr²τ) + 1, and since E\[ρπr²t*\] = 1, **exactly**
/// E\[N_I,mb\] = ρE|U|. (Per sphere with classes: ρΣα_iE|U_{R_i}| − E\[λt*\] + 1, the same.)
///
/// |U|: C_0 gives |o(a, r)|. Step k adds |o(C_k) ∖ ∪_{j<k} o(C_j)|. C_k shares a face with C_{k−1}
/// and their offsets overlap exactly in the face's offset ([`offset_face_volume`]), leaving
/// a³ + 4a²r + πar². The DDA path is monotone, so for r < a/2 the only other cells whose offsets
/// reach o(C_k) are C_{k−2} when step k turns (edge-adjacent) and C_{k−3} when the last three steps
/// use three different axes (vertex-adjacent). The lead's sketch put the edge term at O(r³); it is
/// not: in the quadrant of the shared edge that belongs to neither C_{k−1} nor the two cells, the
/// points within r of both C_{k−2} and C_k but farther than r from C_{k−1} form the square
/// \[0, r\]² minus a quarter disc, i.e. (1 − π/4)r² per unit edge length, (1 − π/4)ar² per turn.
/// Turns make a fraction f_turn ≈ 0.80 of the steps ([`turn_fraction`]). Neglected: the O(r³) ends of
/// that region and the vertex term, the first step (it cannot be a turn: O(r²a) once), and the
/// dependence of the turn count on the eye placement. Valid for r < a/2, accurate for r ≪ a.
pub fn n_i_mb_predictor(inp: &GridTheoryInput, n_s_mean: f64) -> f64 {
    let (rho, a) = (inp.intensity, inp.cell_width);
    average_default(inp, |m| n_i_mb_fixed(rho, a, m, n_s_mean))
}

/// [`n_i_mb_predictor`] with E\[N_S | radii\] from the eye model, integrated over the radii per scene.
pub fn n_i_mb_predictor_for_eye(inp: &GridTheoryInput, eye: Eye) -> f64 {
    let (rho, a) = (inp.intensity, inp.cell_width);
    average_default(inp, |m| {
        n_i_mb_fixed(rho, a, m, n_s_for_rate(eye, rate(rho, m), a))
    })
}

fn n_i_mb_fixed(rho: f64, a: f64, m: Mix, n_s: f64) -> f64 {
    rho * (m(&|r| offset_cube_volume(a, r)) + n_s * m(&|r| mailbox_step_volume(a, r)))
}

/// t = N_I·T_I + N_S·T_S (§3): query time in the unit of `t_i` and `t_s` (times of one ray–sphere
/// test and one cell step), for `n_i` tests and `n_s` steps.
pub fn query_time(n_i: f64, n_s: f64, t_i: f64, t_s: f64) -> f64 {
    n_i * t_i + n_s * t_s
}

/// Model query time (unit of `cost.t_i`) at `inp.cell_width`: [`query_time`] of the sharper predictor
/// ([`n_i_mb_predictor_for_eye`] or [`n_i_predictor_for_eye`]) and [`n_s_mean`].
pub fn model_query_time(inp: &GridTheoryInput, cost: &QueryCost) -> f64 {
    let n_i = if cost.mailbox {
        n_i_mb_predictor_for_eye(inp, cost.eye)
    } else {
        n_i_predictor_for_eye(inp, cost.eye)
    };
    query_time(n_i, n_s_mean(inp, cost.eye), cost.t_i, cost.t_s)
}

/// The cell width (length) in `\[lo, hi\]` (0 < lo < hi) that minimises [`model_query_time`];
/// `inp.cell_width` is ignored. A scan of 64 log-spaced widths brackets the best one, then a
/// golden-section search on ln a refines it (to a relative width of about 1e-9), so a model that is
/// not unimodal still yields its global minimum on the scan's resolution.
pub fn best_cell_width(inp: &GridTheoryInput, cost: &QueryCost, lo: f64, hi: f64) -> f64 {
    debug_assert!(0.0 < lo && lo < hi);
    let time = |ln_a: f64| {
        model_query_time(
            &GridTheoryInput {
                cell_width: ln_a.exp(),
                ..*inp
            },
            cost,
        )
    };
    const SCAN: usize = 64;
    let (l0, l1) = (lo.ln(), hi.ln());
    let grid: Vec<f64> = (0..SCAN)
        .map(|i| l0 + (l1 - l0) * i as f64 / (SCAN - 1) as f64)
        .collect();
    let values: Vec<f64> = grid.iter().map(|&x| time(x)).collect();
    let best = (0..SCAN)
        .min_by(|&i, &j| values[i].total_cmp(&values[j]))
        .expect("the scan has points");
    // Golden-section search on the bracket around the best scan point
    let (mut x0, mut x3) = (grid[best.saturating_sub(1)], grid[(best + 1).min(SCAN - 1)]);
    let g = (5f64.sqrt() - 1.0) / 2.0;
    let (mut x1, mut x2) = (x3 - g * (x3 - x0), x0 + g * (x3 - x0));
    let (mut f1, mut f2) = (time(x1), time(x2));
    while x3 - x0 > 1e-9 {
        if f1 <= f2 {
            x3 = x2;
            x2 = x1;
            f2 = f1;
            x1 = x3 - g * (x3 - x0);
            f1 = time(x1);
        } else {
            x0 = x1;
            x1 = x2;
            f1 = f2;
            x2 = x0 + g * (x3 - x0);
            f2 = time(x2);
        }
    }
    let x = if f1 <= f2 { x1 } else { x2 };
    // Keep the scan's best if the refinement did not beat it (flat or non-unimodal model)
    if time(x) <= values[best] {
        x.exp()
    } else {
        grid[best].exp()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The lognormal radius law of the grid experiments (median 0.1, σ = 0.5, truncated at 0.4).
    const LOGNORMAL: RadiusDist = RadiusDist::LogNormal {
        median: 0.1,
        sigma: 0.5,
        max: 0.4,
    };
    use crate::sample::directions::uniform_direction;
    use crate::sample::radius::RadiusDist;
    use crate::sample::rng::stream;
    use rand::Rng;

    /// Mean and standard error of the mean.
    fn mean_se(xs: &[f64]) -> (f64, f64) {
        let n = xs.len() as f64;
        let m = xs.iter().sum::<f64>() / n;
        let v = xs.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1.0);
        (m, (v / n).sqrt())
    }

    fn one_class(r: RadiusDist) -> [RadiusClass; 1] {
        [RadiusClass {
            fraction: 1.0,
            radius: r,
        }]
    }

    fn input(classes: &[RadiusClass], draw: RadiusDraw, rho: f64, a: f64) -> GridTheoryInput<'_> {
        GridTheoryInput {
            intensity: rho,
            classes,
            draw,
            cell_width: a,
        }
    }

    /// Distance from `p` to the axis-aligned box \[lo, hi\].
    fn dist_box(p: [f64; 3], lo: [f64; 3], hi: [f64; 3]) -> f64 {
        (0..3)
            .map(|i| (lo[i] - p[i]).max(p[i] - hi[i]).max(0.0).powi(2))
            .sum::<f64>()
            .sqrt()
    }

    /// Monte Carlo volume of {p in box : pred(p)} with its SE.
    fn mc_volume(
        key: u64,
        lo: [f64; 3],
        hi: [f64; 3],
        n: usize,
        pred: impl Fn([f64; 3]) -> bool,
    ) -> (f64, f64) {
        let mut rng = stream(&[key]);
        let vol: f64 = (0..3).map(|i| hi[i] - lo[i]).product();
        let xs: Vec<f64> = (0..n)
            .map(|_| {
                let p = [0, 1, 2].map(|i| rng.gen_range(lo[i]..hi[i]));
                if pred(p) {
                    vol
                } else {
                    0.0
                }
            })
            .collect();
        mean_se(&xs)
    }

    #[test]
    fn offset_cube_volume_matches_monte_carlo() {
        let (a, r) = (1.0, 0.3);
        let (m, se) = mc_volume(1, [-r; 3], [a + r; 3], 1_000_000, |p| {
            dist_box(p, [0.0; 3], [a; 3]) <= r
        });
        assert!(
            (m - offset_cube_volume(a, r)).abs() < 5.0 * se,
            "{m} ± {se} vs {}",
            offset_cube_volume(a, r)
        );
    }

    #[test]
    fn face_adjacent_offsets_overlap_in_the_face_offset() {
        let (a, r) = (1.0, 0.3);
        let (m, se) = mc_volume(2, [-r, -r, -r], [r, a + r, a + r], 1_000_000, |p| {
            dist_box(p, [-a, 0.0, 0.0], [0.0, a, a]) <= r && dist_box(p, [0.0; 3], [a; 3]) <= r
        });
        assert!(
            (m - offset_face_volume(a, r)).abs() < 5.0 * se,
            "{m} ± {se} vs {}",
            offset_face_volume(a, r)
        );
    }

    /// The turn overlap that mailbox_step_volume subtracts: the points within r of C_{k−2} and C_k but
    /// not of C_{k−1}, for a path C_{k−2} → C_{k−1} (+x) → C_k (−y). Expected (1 − π/4)r²(a + 4r/3),
    /// the 4r/3 being the two O(r³) end pieces the predictor neglects.
    #[test]
    fn turn_overlap_is_order_a_r_squared() {
        let (a, r) = (1.0, 0.3);
        let (c2, c1, c0) = (
            ([-a, 0.0, 0.0], [0.0, a, a]),
            ([0.0; 3], [a; 3]),
            ([0.0, -a, 0.0], [a, 0.0, a]),
        );
        let (m, se) = mc_volume(3, [-r, -r, -r], [r, r, a + r], 1_000_000, |p| {
            dist_box(p, c2.0, c2.1) <= r
                && dist_box(p, c0.0, c0.1) <= r
                && dist_box(p, c1.0, c1.1) > r
        });
        let want = (1.0 - PI / 4.0) * r * r * (a + 4.0 * r / 3.0);
        assert!((m - want).abs() < 5.0 * se, "{m} ± {se} vs {want}");
    }

    #[test]
    fn band_collapses_to_result_3_1() {
        let rho = 2.0;
        // r large: s_lo = 0, so lower = 1
        let c = one_class(RadiusDist::Constant(1.0));
        let b = n_i_band(&input(&c, RadiusDraw::PerSphere, rho, 1.0));
        assert!((b.lower - 1.0).abs() < 1e-12);
        let up = (3f64.sqrt() + 1.0).powi(2) + rho * offset_cube_volume(1.0, 1.0);
        assert!((b.upper - up).abs() < 1e-12 * up);
        // r small: lower = a²/(√3πr²)
        let c = one_class(RadiusDist::Constant(0.05));
        for draw in [RadiusDraw::PerSphere, RadiusDraw::PerScene] {
            let b = n_i_band(&input(&c, draw, rho, 1.0));
            let lo = 1.0 / (3f64.sqrt() * PI * 0.0025);
            assert!((b.lower - lo).abs() < 1e-12 * lo, "{} vs {lo}", b.lower);
            let up = ((3f64.sqrt() + 0.05) / 0.05).powi(2) + rho * offset_cube_volume(1.0, 0.05);
            assert!((b.upper - up).abs() < 1e-12 * up);
        }
    }

    #[test]
    fn per_scene_equals_per_sphere_for_constant_radii() {
        let c = [
            RadiusClass {
                fraction: 0.3,
                radius: RadiusDist::Constant(0.05),
            },
            RadiusClass {
                fraction: 0.7,
                radius: RadiusDist::Constant(0.12),
            },
        ];
        let (p, s) = (
            input(&c, RadiusDraw::PerSphere, 3.0, 0.4),
            input(&c, RadiusDraw::PerScene, 3.0, 0.4),
        );
        let close =
            |x: f64, y: f64| assert!((x - y).abs() <= 1e-12 * x.abs().max(1.0), "{x} vs {y}");
        close(n_i_band(&p).lower, n_i_band(&s).lower);
        close(n_i_band(&p).upper, n_i_band(&s).upper);
        close(mean_first_hit(&p), mean_first_hit(&s));
        close(mean_first_hit(&p), 1.0 / first_hit_rate(&p));
        close(first_hit_survival(&p, 2.0), first_hit_survival(&s, 2.0));
        // The memoised law is the same function, to the bit, for either draw and radius laws
        // with real quadratures.
        let mixed = [
            RadiusClass {
                fraction: 0.5,
                radius: RadiusDist::Uniform { lo: 0.05, hi: 0.15 },
            },
            RadiusClass {
                fraction: 0.5,
                radius: LOGNORMAL,
            },
        ];
        let (mp, ms) = (
            input(&mixed, RadiusDraw::PerSphere, 1.0, 0.5),
            input(&mixed, RadiusDraw::PerScene, 1.0, 0.5),
        );
        for inp in [&p, &s, &mp, &ms] {
            let law = first_hit_survival_fn(inp);
            for tau in [0.0, 0.3, 2.0, 17.5, 400.0] {
                assert_eq!(law(tau).to_bits(), first_hit_survival(inp, tau).to_bits());
            }
        }
        close(n_s_corner_eye(&p), n_s_corner_eye(&s));
        close(n_s_uniform_eye(&p), n_s_uniform_eye(&s));
        close(n_i_predictor(&p, 10.0), n_i_predictor(&s, 10.0));
        close(
            n_i_mb_predictor_for_eye(&p, Eye::Corner),
            n_i_mb_predictor_for_eye(&s, Eye::Corner),
        );
        close(
            n_i_predictor_for_eye(&p, Eye::Uniform),
            n_i_predictor(&p, n_s_uniform_eye(&p)),
        );
    }

    #[test]
    fn lognormal_integration_converges() {
        let c = one_class(LOGNORMAL);
        let two = [
            RadiusClass {
                fraction: 0.5,
                radius: LOGNORMAL,
            },
            RadiusClass {
                fraction: 0.5,
                radius: RadiusDist::Uniform { lo: 0.05, hi: 0.2 },
            },
        ];
        let (rho, a) = (2.0, 0.5);
        let k = a / (3f64.sqrt() * PI).sqrt();
        let upper = |m: Mix| {
            m(&|r| (a * 3f64.sqrt() + r).powi(2)) / m(&|r| r * r)
                + rho * m(&|r| offset_cube_volume(a, r))
        };
        let lower = |m: Mix| m(&|r| r.max(k).powi(2)) / m(&|r| r * r);
        let corner = |m: Mix| n_s_corner_eye_mu(rate(rho, m) * a);
        let mean_t = |m: Mix| 1.0 / rate(rho, m);
        let fs: [&dyn Fn(Mix) -> f64; 4] = [&upper, &lower, &corner, &mean_t];
        for classes in [&c[..], &two[..]] {
            let inp = input(classes, RadiusDraw::PerScene, rho, a);
            let n = scene_nodes(classes.len());
            for (i, f) in fs.iter().enumerate() {
                for draw in [RadiusDraw::PerScene, RadiusDraw::PerSphere] {
                    let (x, y) = (average(&inp, draw, n, f), average(&inp, draw, 2 * n, f));
                    // The kink of max(r, k) limits `lower` to algebraic convergence
                    let tol = if i == 1 { 1e-4 } else { 1e-7 };
                    assert!(
                        (x - y).abs() < tol * y.abs(),
                        "f{i} {draw:?} {} classes: {x} vs {y}",
                        classes.len()
                    );
                }
            }
        }
    }

    #[test]
    fn survival_integrates_to_mean_first_hit_per_scene() {
        let c = one_class(RadiusDist::Uniform { lo: 0.05, hi: 0.2 });
        let inp = input(&c, RadiusDraw::PerScene, 2.0, 0.5);
        let lambda_min = 2.0 * PI * 0.05 * 0.05;
        let integral: f64 = gauss_legendre_panels(0.0, 60.0 / lambda_min, 16, 400)
            .into_iter()
            .map(|(t, w)| w * first_hit_survival(&inp, t))
            .sum();
        let m = mean_first_hit(&inp);
        assert!((integral - m).abs() < 1e-6 * m, "{integral} vs {m}");
        assert!(m > 1.0 / first_hit_rate(&inp), "Jensen: E[1/λ] > 1/E[λ]");
    }

    #[test]
    fn corner_integral_branches_agree_and_limit() {
        let (s, l) = (
            corner_integral_small(1.0 - 1e-12),
            corner_integral_large(1.0),
        );
        assert!((s - l).abs() < 1e-11 * l, "{s} vs {l}");
        // μ → 0: 1/(2μ) − 1/2 + O(μ ln μ)
        let mu = 1e-9;
        assert!((corner_integral_small(mu) - (0.5 / mu - 0.5)).abs() < 1e-7);
        // μ large: (e^{−μ}/μ)(1 − 2/μ + …), finite and positive, no overflow
        assert!(corner_integral_large(700.0) > 0.0);
        assert_eq!(
            corner_integral_large(800.0),
            0.0,
            "underflows cleanly below e^-745"
        );
        let x = corner_integral_large(50.0) * 50.0 * 50f64.exp();
        assert!((x - (1.0 - 2.0 / 50.0 + 6.0 / 2500.0)).abs() < 1e-3, "{x}");
    }

    /// E\[N_S\] for the corner eye against a direct simulation of Σ_axes ⌊|d_i|t/a⌋, t ~ Exp(λ); and the
    /// uniform eye against Σ_axes ⌊x_i + |d_i|t/a⌋ with x uniform in \[0, 1)³.
    #[test]
    fn cell_step_means_match_monte_carlo() {
        let a = 0.5;
        for (key, lambda) in [(10u64, 0.02), (11, 1.0), (12, 2.0), (13, 6.0)] {
            let c = one_class(RadiusDist::Constant((lambda / PI).sqrt()));
            let inp = input(&c, RadiusDraw::PerSphere, 1.0, a);
            assert!((first_hit_rate(&inp) - lambda).abs() < 1e-12 * lambda);
            let mut rng = stream(&[key]);
            let n = 400_000;
            let (mut corner, mut uniform) = (Vec::with_capacity(n), Vec::with_capacity(n));
            for _ in 0..n {
                let d = uniform_direction(&mut rng);
                let t = -(1.0 - rng.gen::<f64>()).ln() / lambda;
                let steps = |x0: [f64; 3]| -> f64 {
                    (0..3).map(|i| (x0[i] + d[i].abs() * t / a).floor()).sum()
                };
                corner.push(steps([0.0; 3]));
                uniform.push(steps([rng.gen(), rng.gen(), rng.gen()]));
            }
            let (m, se) = mean_se(&corner);
            let want = n_s_corner_eye(&inp);
            assert!(
                (m - want).abs() < 5.0 * se,
                "λ={lambda}: corner {m} ± {se} vs {want}"
            );
            let (m, se) = mean_se(&uniform);
            let want = n_s_uniform_eye(&inp);
            assert!(
                (m - want).abs() < 5.0 * se,
                "λ={lambda}: uniform {m} ± {se} vs {want}"
            );
        }
    }

    /// Turn fraction against a DDA walk: the eye uniform in a unit cell, the previous step's axis taken
    /// from the last crossing behind the eye (so the count is stationary), turns per unit length.
    #[test]
    fn turn_fraction_matches_dda_walk() {
        let mut rng = stream(&[20]);
        let (n, len) = (100_000, 50.0);
        let mut turns_per_len = Vec::with_capacity(n);
        for _ in 0..n {
            let d = uniform_direction(&mut rng);
            let u = [d.x.abs(), d.y.abs(), d.z.abs()];
            let x0: [f64; 3] = [rng.gen(), rng.gen(), rng.gen()];
            // Last crossing behind the eye, and the next crossing ahead, per axis
            let behind = (0..3)
                .min_by(|&i, &j| (x0[i] / u[i]).total_cmp(&(x0[j] / u[j])))
                .expect("3 axes");
            let mut next = [0, 1, 2].map(|i| (1.0 - x0[i]) / u[i]);
            let (mut prev, mut turns) = (behind, 0u32);
            loop {
                let i = (0..3)
                    .min_by(|&i, &j| next[i].total_cmp(&next[j]))
                    .expect("3 axes");
                if next[i] > len {
                    break;
                }
                turns += u32::from(i != prev);
                prev = i;
                next[i] += 1.0 / u[i];
            }
            turns_per_len.push(turns as f64 / len);
        }
        let (m, se) = mean_se(&turns_per_len);
        let want = 1.5 * turn_fraction();
        assert!((m - want).abs() < 5.0 * se, "{m} ± {se} vs {want}");
    }

    #[test]
    fn geometric_pmf_sums_to_one_with_mean_one_over_p() {
        let p = geometric_p_for_s(0.1, 0.3);
        assert!((p - 1.0 / 16.0).abs() < 1e-15);
        let (mut s, mut m) = (0.0, 0.0);
        for k in 0..2000u64 {
            s += geometric_pmf(p, k);
            m += k as f64 * geometric_pmf(p, k);
        }
        assert!((s - 1.0).abs() < 1e-12, "{s}");
        assert!((m - 1.0 / p).abs() < 1e-9, "{m}");
        assert_eq!(geometric_pmf(1.0, 1), 1.0);
        assert_eq!(geometric_pmf(1.0, 2), 0.0);
    }

    #[test]
    fn best_cell_width_is_a_minimum_of_the_model() {
        let classes = [
            RadiusClass {
                fraction: 0.6,
                radius: RadiusDist::Constant(0.05),
            },
            RadiusClass {
                fraction: 0.4,
                radius: RadiusDist::Uniform { lo: 0.05, hi: 0.15 },
            },
        ];
        for (draw, eye, mailbox) in [
            (RadiusDraw::PerSphere, Eye::Uniform, false),
            (RadiusDraw::PerSphere, Eye::Corner, true),
            (RadiusDraw::PerScene, Eye::Uniform, true),
        ] {
            let inp = input(&classes, draw, 5.0, 1.0);
            let cost = QueryCost {
                t_i: 1.0,
                t_s: 0.5,
                eye,
                mailbox,
            };
            let (lo, hi) = (0.02, 5.0);
            let best = best_cell_width(&inp, &cost, lo, hi);
            let at = |a: f64| {
                model_query_time(
                    &GridTheoryInput {
                        cell_width: a,
                        ..inp
                    },
                    &cost,
                )
            };
            let t_best = at(best);
            assert!(
                best > lo && best < hi,
                "interior minimum expected, got {best}"
            );
            assert!(t_best <= at(best * 1.001) && t_best <= at(best / 1.001));
            for i in 0..=300 {
                let a = lo * (hi / lo).powf(i as f64 / 300.0);
                assert!(
                    t_best <= at(a) * (1.0 + 1e-12),
                    "a={a}: {} < {t_best}",
                    at(a)
                );
            }
        }
    }

    /// One ray through a lazily generated Poisson scene (constant radius r < a/2, eye uniform in
    /// cell (0,0,0)), traversed like the grid engine: whole lists tested, stop in the cell holding
    /// the first hit that does not contain the eye. Returns (N_I, N_I,mb, N_S).
    fn simulate_ray(
        rng: &mut crate::sample::rng::Stream,
        rho: f64,
        r: f64,
        a: f64,
    ) -> (f64, f64, f64) {
        use rand_distr::{Distribution, Poisson};
        use rustc_hash::{FxHashMap, FxHashSet};
        let pois = Poisson::new(rho * a * a * a).expect("positive mean");
        let mut cells: FxHashMap<[i64; 3], Vec<[f64; 3]>> = FxHashMap::default();
        let o: [f64; 3] = [
            rng.gen::<f64>() * a,
            rng.gen::<f64>() * a,
            rng.gen::<f64>() * a,
        ];
        let dv = uniform_direction(rng);
        let d = [dv.x, dv.y, dv.z];
        let mut cell = [0i64; 3];
        let step = [0, 1, 2].map(|i| if d[i] >= 0.0 { 1i64 } else { -1 });
        let delta = [0, 1, 2].map(|i| a / d[i].abs());
        let mut t_max = [0, 1, 2].map(|i| {
            if d[i] >= 0.0 {
                (a - o[i]) / d[i]
            } else {
                o[i] / -d[i]
            }
        });
        let (mut n_i, mut n_s) = (0.0, 0.0);
        let mut seen: FxHashSet<([i64; 3], usize)> = FxHashSet::default();
        let mut best = f64::INFINITY;
        loop {
            let lo = cell.map(|c| c as f64 * a);
            let hi = lo.map(|x| x + a);
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        let key = [cell[0] + dx, cell[1] + dy, cell[2] + dz];
                        let pts = cells.entry(key).or_insert_with(|| {
                            let k = pois.sample(rng) as usize;
                            (0..k)
                                .map(|_| [0, 1, 2].map(|i| (key[i] as f64 + rng.gen::<f64>()) * a))
                                .collect()
                        });
                        for (id, c) in pts.iter().enumerate() {
                            if dist_box(*c, lo, hi) > r {
                                continue;
                            }
                            n_i += 1.0;
                            seen.insert((key, id));
                            let oc = [c[0] - o[0], c[1] - o[1], c[2] - o[2]];
                            let oc2 = oc[0] * oc[0] + oc[1] * oc[1] + oc[2] * oc[2];
                            if oc2 < r * r {
                                continue; // contains the eye: ignored as a hit
                            }
                            let b = oc[0] * d[0] + oc[1] * d[1] + oc[2] * d[2];
                            let disc = b * b - (oc2 - r * r);
                            if disc >= 0.0 && b > 0.0 {
                                best = best.min(b - disc.sqrt());
                            }
                        }
                    }
                }
            }
            let axis = (0..3)
                .min_by(|&i, &j| t_max[i].total_cmp(&t_max[j]))
                .expect("3 axes");
            if best <= t_max[axis] {
                return (n_i, seen.len() as f64, n_s);
            }
            cell[axis] += step[axis];
            t_max[axis] += delta[axis];
            n_s += 1.0;
        }
    }

    /// The sharper predictors against a direct simulation. Paired estimators remove the N_S noise:
    /// D = N_I − (1 + N_S)ρ|o| has mean −E\[X_excl\] + E\[X_hit\] (predicted −4r/a), and
    /// D_mb = N_I,mb − ρ(|o| + N_S·v) has mean ≈ 0. Tolerance: 5 SE plus the neglected orders,
    /// 4(r/a)² for D and ρ·E\[N_S\]·2r³ for D_mb (stated, not tuned).
    #[test]
    fn sharper_predictors_match_simulation() {
        // Runs by default (a few seconds in the release test profile): the README's claim that the
        // predictors are checked against simulation rests on it.
        for (key, rho, r, a, rays) in [
            (30u64, 1.0, 0.1, 0.4, 15_000),
            (31, 20.0, 0.05, 0.5, 30_000),
            (32, 0.3, 0.1, 1.0, 15_000),
        ] {
            let c = one_class(RadiusDist::Constant(r));
            let inp = input(&c, RadiusDraw::PerSphere, rho, a);
            let mut rng = stream(&[key]);
            let (mut d, mut d_mb, mut ns, mut ni) = (vec![], vec![], vec![], vec![]);
            let (o, v) = (offset_cube_volume(a, r), mailbox_step_volume(a, r));
            for _ in 0..rays {
                let (n_i, n_mb, n_s) = simulate_ray(&mut rng, rho, r, a);
                d.push(n_i - (1.0 + n_s) * rho * o);
                d_mb.push(n_mb - rho * (o + n_s * v));
                ns.push(n_s);
                ni.push(n_i);
            }
            let ((md, sd), (mmb, smb), (mns, sns), (mni, sni)) =
                (mean_se(&d), mean_se(&d_mb), mean_se(&ns), mean_se(&ni));
            eprintln!(
                "rho={rho} r={r} a={a}: N_S {mns:.3}±{sns:.3} (theory {:.3}); N_I {mni:.3}±{sni:.3} (pred {:.3}, plain {:.3}); \
                 D {md:.4}±{sd:.4} (pred {:.4}); D_mb {mmb:.4}±{smb:.4} (turn term {:.4})",
                n_s_uniform_eye(&inp),
                n_i_predictor_for_eye(&inp, Eye::Uniform),
                n_i_plain_predictor(&inp, n_s_uniform_eye(&inp)),
                -4.0 * r / a,
                -rho * mns * turn_fraction() * (1.0 - PI / 4.0) * a * r * r,
            );
            assert!(
                (md + 4.0 * r / a).abs() < 5.0 * sd + 4.0 * (r / a).powi(2),
                "D {md} ± {sd}"
            );
            assert!(
                mmb.abs() < 5.0 * smb + rho * mns * 2.0 * r.powi(3),
                "D_mb {mmb} ± {smb}"
            );
            assert!((mns - n_s_uniform_eye(&inp)).abs() < 5.0 * sns);
        }
    }
}
