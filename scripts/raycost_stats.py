"""Statistics shared by scripts/claims.py and the plot scripts (standard library only, no plotting).

- Student-t: exact quantiles and CDF for every degree of freedom (the regularised incomplete beta
  function), normal beyond 10⁴ degrees of freedom exactly as the Rust side (`src/stats/mod.rs`,
  statrs' StudentsT) does, so a CI printed by `raycost` and one printed here agree.
- Samplers of per-point means: `Parametric` (each mean drawn within its SE, Student-t on its degrees
  of freedom: the points are independent) and `Clustered` (a two-stage cluster bootstrap over
  separate process runs, then replicas within a run: the points of one cluster share their random
  numbers, so a cluster is resampled whole).
- `bootstrap`: a derived figure and its percentile interval, with the share of draws in which the
  figure is undefined reported, never dropped silently.
- Smooth curves: a weighted polynomial whose degree is chosen by a fixed rule (the lowest degree
  whose χ² is acceptable), its roots (a crossover) or its minimum (an optimum), with the fit's
  misfit (the Birge ratio) scaling the interval.
- Ratios (Fieller), cost constants fitted to seconds with a case-resampling bootstrap (the misfit
  inside the interval), an order-free (Shapley) decomposition into factors, and run-level pooling of
  K tables of the same spec.
"""

import math
import re
import random
from collections import namedtuple
from statistics import NormalDist

# Beyond this many degrees of freedom the Rust side uses the normal quantile (src/stats/mod.rs).
NORMAL_BEYOND_DOF = 10_000
_NORMAL = NormalDist()


# ----------------------------------------------------------------------------------------------
# Student-t, χ², normal


def _betacf(a, b, x):
    """Continued fraction of the incomplete beta function (modified Lentz)."""
    tiny, eps = 1e-300, 1e-16
    qab, qap, qam = a + b, a + 1.0, a - 1.0
    c, d = 1.0, 1.0 - qab * x / qap
    d = 1.0 / (d if abs(d) > tiny else tiny)
    h = d
    for m in range(1, 10_000):
        m2 = 2 * m
        aa = m * (b - m) * x / ((qam + m2) * (a + m2))
        d = 1.0 + aa * d
        d = 1.0 / (d if abs(d) > tiny else tiny)
        c = 1.0 + aa / c
        c = c if abs(c) > tiny else tiny
        h *= d * c
        aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2))
        d = 1.0 + aa * d
        d = 1.0 / (d if abs(d) > tiny else tiny)
        c = 1.0 + aa / c
        c = c if abs(c) > tiny else tiny
        delta = d * c
        h *= delta
        if abs(delta - 1.0) < eps:
            break
    return h


def beta_reg(a, b, x):
    """The regularised incomplete beta function I_x(a, b)."""
    if x <= 0:
        return 0.0
    if x >= 1:
        return 1.0
    ln = math.lgamma(a + b) - math.lgamma(a) - math.lgamma(b) + a * math.log(x) + b * math.log1p(-x)
    front = math.exp(ln)
    if x < (a + 1) / (a + b + 2):
        return front * _betacf(a, b, x) / a
    return 1.0 - front * _betacf(b, a, 1.0 - x) / b


def beta_quantile(q, a, b):
    """The x with I_x(a, b) = q (bisection: I is increasing in x), for 0 ≤ q ≤ 1."""
    lo, hi = 0.0, 1.0
    for _ in range(64):  # 2⁻⁶⁴: below a double's resolution near the quantiles that matter
        mid = 0.5 * (lo + hi)
        if beta_reg(a, b, mid) < q:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def clopper_pearson(k, n, level=0.95):
    """Two-sided exact (Clopper–Pearson) interval of a binomial share from k successes in n trials:
    (lo, hi) with P(X ≥ k | lo) = P(X ≤ k | hi) = (1 − level)/2; (nan, nan) for n = 0."""
    if n <= 0:
        return math.nan, math.nan
    a = (1.0 - level) / 2.0
    lo = 0.0 if k <= 0 else beta_quantile(a, k, n - k + 1)
    hi = 1.0 if k >= n else beta_quantile(1.0 - a, k + 1, n - k)
    return lo, hi


def t_cdf(x, dof):
    """P(T ≤ x) for Student's t with `dof` > 0 degrees of freedom (any real dof)."""
    if x != x or dof != dof or dof <= 0:
        return math.nan
    if dof > NORMAL_BEYOND_DOF:
        return _NORMAL.cdf(x)
    tail = 0.5 * beta_reg(dof / 2.0, 0.5, dof / (dof + x * x))
    return 1.0 - tail if x > 0 else tail


def t_quantile(p, dof):
    """The p-quantile of Student's t: exact (Newton on the CDF from the normal start, guarded by
    bisection), closed forms at 1 and 2 degrees of freedom, the normal beyond 10⁴ as the Rust side."""
    if not (0.0 < p < 1.0) or dof != dof or dof <= 0:
        return math.nan
    if dof > NORMAL_BEYOND_DOF:
        return _NORMAL.inv_cdf(p)
    if p < 0.5:
        return -t_quantile(1.0 - p, dof)
    if p == 0.5:
        return 0.0
    if dof == 1:
        return math.tan(math.pi * (p - 0.5))
    if dof == 2:
        a = 4.0 * p * (1.0 - p)
        return (2.0 * p - 1.0) * math.sqrt(2.0 / a)
    lo, hi = 0.0, 1.0
    while t_cdf(hi, dof) < p:
        lo, hi = hi, hi * 2.0
    x = min(max(_NORMAL.inv_cdf(p), lo), hi)
    log_c = math.lgamma((dof + 1) / 2) - math.lgamma(dof / 2) - 0.5 * math.log(dof * math.pi)
    for _ in range(200):
        f = t_cdf(x, dof) - p
        if f > 0:
            hi = x
        else:
            lo = x
        pdf = math.exp(log_c - (dof + 1) / 2 * math.log1p(x * x / dof))
        step = f / pdf if pdf > 0 else math.inf
        nx = x - step
        if not (lo < nx < hi):
            nx = 0.5 * (lo + hi)
        if abs(nx - x) <= 1e-15 * max(1.0, abs(x)):
            return nx
        x = nx
    return x


def t_for_level(level, dof):
    """Two-sided Student-t quantile for a confidence level (0.95 → 1.96 at ∞; NaN below 1 dof:
    one sample has no CI). `dof` None or NaN (unknown) gives the normal quantile."""
    if dof is None or dof != dof:
        return _NORMAL.inv_cdf(0.5 + 0.5 * level)
    if dof <= 0:
        return math.nan
    return t_quantile(0.5 + 0.5 * level, dof)


def t95(dof):
    """Two-sided 95 % Student-t quantile on `dof` degrees of freedom (exact for every dof)."""
    if dof is not None and dof == dof and dof < 1:
        return math.nan
    return t_for_level(0.95, dof)


def chi2_sf(x, k):
    """P(χ²_k ≥ x): the regularised upper incomplete gamma Q(k/2, x/2)."""
    if x != x or k <= 0:
        return math.nan
    if x <= 0:
        return 1.0
    a, z = k / 2.0, x / 2.0
    if z < a + 1:  # series for P, then Q = 1 − P
        term = total = 1.0 / a
        n = a
        for _ in range(100_000):
            n += 1
            term *= z / n
            total += term
            if abs(term) < abs(total) * 1e-16:
                break
        return max(0.0, 1.0 - total * math.exp(-z + a * math.log(z) - math.lgamma(a)))
    tiny = 1e-300  # continued fraction for Q (Lentz)
    b = z + 1 - a
    c, d = 1 / tiny, 1 / b
    h = d
    for i in range(1, 100_000):
        an = -i * (i - a)
        b += 2
        d = an * d + b
        d = 1 / (d if abs(d) > tiny else tiny)
        c = b + an / c
        c = c if abs(c) > tiny else tiny
        delta = d * c
        h *= delta
        if abs(delta - 1) < 1e-16:
            break
    return math.exp(-z + a * math.log(z) - math.lgamma(a)) * h


def normal_score(t, dof):
    """The standard-normal value with the same CDF as t on `dof` degrees of freedom, so that
    t-statistics on different dof can be summed as χ² (z = Φ⁻¹(F_t(t)))."""
    p = t_cdf(t, dof) if dof == dof and dof is not None else _NORMAL.cdf(t)
    p = min(max(p, 1e-300), 1 - 1e-16)
    return _NORMAL.inv_cdf(p)


# ----------------------------------------------------------------------------------------------
# table rows


def dof(row, metric):
    """Degrees of freedom of metric's SE in a table row: M_clusters − 1, or M_n − 1 in a table
    written before the clusters column existed."""
    c = row.get(metric + "_clusters")
    if c is None or c != c:
        c = row.get(metric + "_n")
    return math.nan if c is None or c != c else c - 1


def ci95(row, metric):
    """Half-width of the 95 % CI of metric in a table row: Student-t on its degrees of freedom
    (NaN without a standard error)."""
    se = row.get(metric + "_se")
    return math.nan if se is None else t95(dof(row, metric)) * se


# ----------------------------------------------------------------------------------------------
# samplers and the bootstrap


def draw_error(rng, dof):
    """One standard error's worth of noise for a mean estimated on `dof` degrees of freedom:
    Student-t (a normal mean's posterior with its variance unknown, flat prior), normal where dof
    is unknown or beyond 10⁴."""
    z = rng.gauss(0, 1)
    if dof is None or dof != dof or dof > NORMAL_BEYOND_DOF:
        return z
    if dof < 1:
        return math.nan
    return z / math.sqrt(rng.gammavariate(dof / 2, 2) / dof)


class Parametric:
    """Independent means, each drawn as mean + SE·t(dof). `observed()` and `draw(rng)` both return
    (means, variances of the means); a NaN SE counts as 0 (an exact value)."""

    def __init__(self, means, ses, dofs=None):
        self.means = list(means)
        self.ses = [s if s == s else 0.0 for s in ses]
        self.dofs = list(dofs) if dofs is not None else [None] * len(self.means)

    def observed(self):
        return self.means, [s * s for s in self.ses]

    def draw(self, rng):
        x = [m + s * draw_error(rng, d) if s > 0 else m for m, s, d in zip(self.means, self.ses, self.dofs)]
        return x, [s * s for s in self.ses]

    def clusters(self):
        finite = [d for d in self.dofs if d is not None and d == d]
        return (min(finite) + 1) if finite else math.nan


class Clustered:
    """Per-cluster values of several quantities: `values[(run, replica)] = [q_0, q_1, …]`, one
    cluster per replica of a separate process run (the quantities of one cluster share its random
    numbers: common random numbers across sweep points and engines).

    A mean of quantity j is the mean over runs of the run's mean over its replicas. The independent
    clusters are the runs when there are ≥ 2 (so between-run variation is inside every interval),
    else the replicas of the one run. A draw is a wild cluster bootstrap: each cluster's deviation
    from the mean, d_k, is weighted by an independent standard normal g_k, m* = m + Σ g_k·d_k /
    √(K(K − 1)), which has the clusters' covariance / K (across quantities too: the pairing of
    engines and sweep points is kept), and the whole draw is scaled by √((K − 1)/χ²_{K−1}), making it
    Student-t on K − 1 degrees of freedom. With few clusters (3 runs) this keeps its coverage where
    resampling clusters would not (scripts/tests/test_stats.py measures both)."""

    def __init__(self, values):
        self.runs = {}
        for (run, rep), v in sorted(values.items()):
            self.runs.setdefault(run, []).append(list(v))
        if not self.runs:
            raise ValueError("no clusters")
        self.width = len(next(iter(self.runs.values()))[0])
        if len(self.runs) >= 2:
            self.units = [[sum(c[j] for c in reps) / len(reps) for j in range(self.width)]
                          for reps in self.runs.values()]
        else:
            self.units = next(iter(self.runs.values()))
        k = len(self.units)
        self.means = [sum(u[j] for u in self.units) / k for j in range(self.width)]
        self.dev = [[u[j] - self.means[j] for j in range(self.width)] for u in self.units]
        self.var = [sum(d[j] ** 2 for d in self.dev) / (k - 1) / k if k > 1 else math.nan
                    for j in range(self.width)]

    def observed(self):
        return list(self.means), list(self.var)

    def draw(self, rng):
        k = len(self.units)
        if k < 2:
            return [math.nan] * self.width, list(self.var)
        g = [rng.gauss(0, 1) for _ in range(k)]
        scale = math.sqrt((k - 1) / rng.gammavariate((k - 1) / 2, 2)) / math.sqrt(k * (k - 1))
        m = [self.means[j] + scale * sum(gi * d[j] for gi, d in zip(g, self.dev)) for j in range(self.width)]
        return m, list(self.var)

    def clusters(self):
        """Independent clusters behind a mean: the runs when there are ≥ 2, else the replicas."""
        return len(self.units)

    def covariance(self, i, j):
        """Covariance of the means of quantities i and j (paired clusters)."""
        k = len(self.units)
        if k < 2:
            return math.nan
        return sum(d[i] * d[j] for d in self.dev) / (k - 1) / k


Interval = namedtuple("Interval", "value lo hi undefined categories")
Interval.__doc__ = """A derived figure, its percentile interval over the defined draws, the share of
draws in which it was undefined, and the share of each category a statistic reported
({category: fraction}; e.g. 'no crossing', 'several crossings')."""


def percentile(sorted_values, q):
    """The q-quantile of sorted values (the value at rank ⌊q·(n − 1)⌋, as before)."""
    return sorted_values[int(q * (len(sorted_values) - 1))]


def bootstrap(f, sampler, draws=4000, seed=1, level=0.95):
    """f over the sampler's observed means and over `draws` resamples.

    f(means, variances) returns a number, NaN (undefined) or a (category, number-or-NaN) pair: a
    category names why a draw has no value ('none', 'several') or sorts values ('ok'). The interval
    is the (1 ± level)/2 percentiles of the draws that have a value; the share without one is
    `undefined` and each category's share is in `categories`, so nothing is dropped silently."""
    if not isinstance(sampler, (Parametric, Clustered)):
        raise TypeError("sampler must be Parametric or Clustered")
    rng = random.Random(seed)

    def split(v):
        if isinstance(v, tuple):
            return v
        return ("ok", v) if v == v else ("undefined", v)

    value = split(f(*sampler.observed()))[1]
    vals, cats = [], {}
    for _ in range(draws):
        m, var = sampler.draw(rng)
        if any(x != x for x in m):
            cat, v = "undefined", math.nan
        else:
            cat, v = split(f(m, var))
        cats[cat] = cats.get(cat, 0) + 1
        if v == v and v is not None:
            vals.append(v)
    vals.sort()
    cats = {k: c / draws for k, c in sorted(cats.items())}
    undefined = 1.0 - len(vals) / draws
    if not vals:
        return Interval(value, math.nan, math.nan, undefined, cats)
    a = (1.0 - level) / 2.0
    return Interval(value, percentile(vals, a), percentile(vals, 1.0 - a), undefined, cats)


# ----------------------------------------------------------------------------------------------
# linear algebra and weighted polynomials


def solve(a, b):
    """The solution of the n×n system a·x = b (Gaussian elimination with pivoting), None if singular."""
    n = len(b)
    m = [row[:] + [v] for row, v in zip(a, b)]
    for c in range(n):
        p = max(range(c, n), key=lambda r: abs(m[r][c]))
        if abs(m[p][c]) < 1e-300:
            return None
        m[c], m[p] = m[p], m[c]
        for r in range(n):
            if r != c:
                f = m[r][c] / m[c][c]
                m[r] = [x - f * y for x, y in zip(m[r], m[c])]
    return [m[i][n] / m[i][i] for i in range(n)]


Fit = namedtuple("Fit", "coef degree chi2 dof p centre scale")
Fit.__doc__ = """A weighted polynomial in u = (x − centre)/scale: coefficients (constant first), its
degree, weighted χ², residual degrees of freedom and χ² p-value."""


def polyfit(xs, ys, variances, degree):
    """Weighted least squares polynomial of `degree` (weights 1/variance; equal weights where a
    variance is 0 or NaN for every point). x is centred and scaled for conditioning."""
    n = len(xs)
    centre = sum(xs) / n
    scale = max(abs(x - centre) for x in xs) or 1.0
    us = [(x - centre) / scale for x in xs]
    good = [v for v in variances if v == v and v > 0]
    if len(good) == n:
        w = [1.0 / v for v in variances]
    else:
        w = [1.0] * n
    k = degree + 1
    ata = [[sum(w[i] * us[i] ** (a + b) for i in range(n)) for b in range(k)] for a in range(k)]
    atb = [sum(w[i] * ys[i] * us[i] ** a for i in range(n)) for a in range(k)]
    coef = solve(ata, atb)
    if coef is None:
        return None
    chi2 = sum(w[i] * (ys[i] - poly_at(coef, us[i])) ** 2 for i in range(n))
    rdof = n - k
    p = chi2_sf(chi2, rdof) if rdof > 0 and len(good) == n else math.nan
    return Fit(coef, degree, chi2, rdof, p, centre, scale)


def poly_at(coef, u):
    v = 0.0
    for c in reversed(coef):
        v = v * u + c
    return v


def fit_value(fit, x):
    return poly_at(fit.coef, (x - fit.centre) / fit.scale)


def choose_fit(xs, ys, variances, degrees, alpha):
    """The degree rule: the lowest degree in `degrees` (each leaving ≥ 1 residual degree of freedom)
    whose χ² p-value is ≥ alpha; if none, the highest. Returns the Fit (None if none can be made)."""
    usable = [d for d in degrees if d + 2 <= len(xs)]
    last = None
    for d in usable:
        fit = polyfit(xs, ys, variances, d)
        if fit is None:
            continue
        last = fit
        if fit.p == fit.p and fit.p >= alpha:
            return fit
    return last


def birge(fit):
    """The Birge ratio √(χ²/dof) of a fit, at least 1: the factor by which the misfit widens an
    interval taken from the points' own errors."""
    if fit is None or fit.dof <= 0 or fit.chi2 != fit.chi2:
        return 1.0
    return max(1.0, math.sqrt(fit.chi2 / fit.dof))


def scale_interval(value, lo, hi, factor):
    """Widens [lo, hi] about value by `factor` (the misfit)."""
    if factor <= 1.0 or value != value:
        return lo, hi
    return value - factor * (value - lo), value + factor * (hi - value)


def real_roots(coef, lo, hi):
    """The real roots of the polynomial `coef` (constant first) in [lo, hi], in order: between
    consecutive roots of its derivative the polynomial is monotone, so each sign change there is
    one root, found by bisection."""
    while len(coef) > 1 and coef[-1] == 0:
        coef = coef[:-1]
    if len(coef) == 1:
        return []
    if len(coef) == 2:
        x = -coef[0] / coef[1]
        return [x] if lo <= x <= hi else []
    deriv = [k * c for k, c in enumerate(coef)][1:]
    cuts = [lo] + real_roots(deriv, lo, hi) + [hi]
    out = []
    for a, b in zip(cuts, cuts[1:]):
        fa, fb = poly_at(coef, a), poly_at(coef, b)
        if fa == 0.0:
            if not out or abs(out[-1] - a) > 1e-12:
                out.append(a)
            continue
        if fa * fb < 0:
            for _ in range(100):
                m = 0.5 * (a + b)
                fm = poly_at(coef, m)
                if (fm < 0) == (fa < 0):
                    a, fa = m, fm
                else:
                    b = m
            out.append(0.5 * (a + b))
    if poly_at(coef, hi) == 0.0 and (not out or abs(out[-1] - hi) > 1e-12):
        out.append(hi)
    return out


def roots_in(fit, lo, hi):
    """The points where the fitted curve changes sign (or is 0) on [lo, hi], in order."""
    u0, u1 = (lo - fit.centre) / fit.scale, (hi - fit.centre) / fit.scale
    return [fit.centre + fit.scale * u for u in real_roots(fit.coef, u0, u1)]


def minimum_in(fit, lo, hi):
    """(x, where) of the fitted curve's minimum on [lo, hi]: where is 'interior' (a minimum of the
    curve inside the range) or 'edge' (the smallest value is at an end)."""
    u0, u1 = (lo - fit.centre) / fit.scale, (hi - fit.centre) / fit.scale
    deriv = [k * c for k, c in enumerate(fit.coef)][1:]
    cands = [(u, "interior") for u in real_roots(deriv, u0, u1) if u0 < u < u1]
    cands += [(u0, "edge"), (u1, "edge")]
    u, where = min(cands, key=lambda c: poly_at(fit.coef, c[0]))
    return fit.centre + fit.scale * u, where


# ----------------------------------------------------------------------------------------------
# curve statistics: crossover and optimum


def crossover_statistic(xs, degrees, alpha, log_ratio):
    """f(means, variances) for `bootstrap`: the root of a smooth fit of log(cost A / cost B) over
    the whole range. `log_ratio(means, variances)` returns the per-x (y, var y). Categories: 'ok'
    (exactly one root), 'none', 'several'."""
    lo, hi = min(xs), max(xs)

    def f(means, variances):
        ys, vs = log_ratio(means, variances)
        if any(y != y for y in ys):
            return ("undefined", math.nan)
        fit = choose_fit(xs, ys, vs, degrees, alpha)
        if fit is None:
            return ("undefined", math.nan)
        r = roots_in(fit, lo, hi)
        if len(r) == 1:
            return ("ok", r[0])
        return ("none" if not r else "several", math.nan)
    return f


def paired_log_ratio(n_points, clustered=None):
    """log_ratio for crossover_statistic over means laid out [A_0 … A_{n−1}, B_0 … B_{n−1}]: y_i =
    log(A_i/B_i), var y_i by the delta method (with the A–B covariance of paired clusters)."""
    def f(means, variances):
        ys, vs = [], []
        for i in range(n_points):
            a, b = means[i], means[n_points + i]
            if a <= 0 or b <= 0:
                return [math.nan], [math.nan]
            va, vb = variances[i], variances[n_points + i]
            cov = clustered.covariance(i, n_points + i) if clustered is not None else 0.0
            cov = cov if cov == cov else 0.0
            ys.append(math.log(a / b))
            vs.append(va / a ** 2 + vb / b ** 2 - 2 * cov / (a * b))
        return ys, vs
    return f


def optimum_statistic(xs, degrees, alpha):
    """f(means, variances) for `bootstrap`: the minimum of a smooth fit of log(cost) over the whole
    range. Categories 'ok' (interior minimum) and 'edge' (the minimum is at an end of the range)."""
    lo, hi = min(xs), max(xs)

    def f(means, variances):
        if min(means) <= 0:
            return ("undefined", math.nan)
        ys = [math.log(m) for m in means]
        vs = [v / m ** 2 for v, m in zip(variances, means)]
        fit = choose_fit(xs, ys, vs, degrees, alpha)
        if fit is None:
            return ("undefined", math.nan)
        x, where = minimum_in(fit, lo, hi)
        return ("ok", x) if where == "interior" else ("edge", math.nan)
    return f


Curve = namedtuple("Curve", "interval fit misfit found lo hi")
Curve.__doc__ = """A crossover or optimum: the bootstrap Interval (value, shares of categories), the
observed Fit, its Birge ratio, what the observed fit gives (its roots, or (x, 'interior'/'edge') of
its minimum) and the interval widened by the misfit (lo, hi)."""


def crossover(xs, sampler, log_ratio, degrees, alpha, draws=4000, seed=1, level=0.95):
    """The crossover of two cost curves: the root in [min xs, max xs] of a weighted polynomial fit
    of log(A/B) (degree by choose_fit, chosen again in every draw), its bootstrap interval over the
    sampler's draws widened by the observed fit's Birge ratio, and the shares of draws with one, no
    or several crossings. The widened interval is cut to the range (nothing outside was measured). `log_ratio(means, variances)` gives the per-x (y, var y)."""
    iv = bootstrap(crossover_statistic(xs, degrees, alpha, log_ratio), sampler, draws, seed, level)
    ys, vs = log_ratio(*sampler.observed())
    fit = choose_fit(xs, ys, vs, degrees, alpha)
    roots = roots_in(fit, min(xs), max(xs)) if fit else []
    k = birge(fit)
    lo, hi = scale_interval(iv.value, iv.lo, iv.hi, k)
    return Curve(iv, fit, k, roots, max(lo, min(xs)), min(hi, max(xs)))


def optimum(xs, sampler, degrees, alpha, draws=4000, seed=1, level=0.95):
    """The optimum of a cost curve: the minimum in [min xs, max xs] of a weighted polynomial fit of
    log(cost) (degree by choose_fit, chosen again in every draw: the model's uncertainty is inside
    the interval), widened by the observed fit's Birge ratio; draws whose minimum is at an end of
    the range are counted ('edge')."""
    iv = bootstrap(optimum_statistic(xs, degrees, alpha), sampler, draws, seed, level)
    means, var = sampler.observed()
    ys = [math.log(m) for m in means]
    vs = [v / m ** 2 for v, m in zip(var, means)]
    fit = choose_fit(xs, ys, vs, degrees, alpha)
    found = minimum_in(fit, min(xs), max(xs)) if fit else (math.nan, "edge")
    k = birge(fit)
    lo, hi = scale_interval(iv.value, iv.lo, iv.hi, k)
    return Curve(iv, fit, k, found, max(lo, min(xs)), min(hi, max(xs)))


# ----------------------------------------------------------------------------------------------
# ratios, slopes, fitted seconds, decomposition


def fieller(a, va, b, vb, cov=0.0, tq=1.96):
    """Fieller's interval for the ratio a/b of two estimates (variances va, vb, covariance cov) at
    the quantile tq: (ratio, lo, hi, bounded). Unbounded (bounded False, NaN ends) when b is not
    significantly different from 0 at that level."""
    r = a / b if b != 0 else math.nan
    g = tq * tq * vb / (b * b) if b != 0 else math.inf
    if g >= 1:
        return r, math.nan, math.nan, False
    disc = va - 2 * r * cov + r * r * vb - g * (va - cov * cov / vb if vb > 0 else va)
    disc = max(disc, 0.0)
    centre = r - g * cov / vb if vb > 0 else r
    half = tq / abs(b) * math.sqrt(disc)
    lo, hi = (centre - half) / (1 - g), (centre + half) / (1 - g)
    return r, min(lo, hi), max(lo, hi), True


def wls_line(xs, ys, variances):
    """Weighted least squares y = a + b·x: (a, b, χ², residual dof)."""
    fit = polyfit(xs, ys, variances, 1)
    if fit is None:
        return math.nan, math.nan, math.nan, 0
    a = fit.coef[0] - fit.coef[1] * fit.centre / fit.scale
    return a, fit.coef[1] / fit.scale, fit.chi2, fit.dof


def log_slope_statistic(xs):
    """f(means, variances) for `bootstrap`: the slope of log(mean) against log(x), weighted."""
    lx = [math.log(x) for x in xs]

    def f(means, variances):
        if min(means) <= 0:
            return math.nan
        ly = [math.log(m) for m in means]
        lv = [v / m ** 2 for v, m in zip(variances, means)]
        return wls_line(lx, ly, lv)[1]
    return f


def fit_costs(x_cols, y):
    """Non-negative least squares on relative residuals: y ≈ Σ_j c_j·x_cols[j] with c ≥ 0, each point
    weighted by 1/y (weighted_nnls with weights 1/y²). Returns (c, relative residuals), or None if
    no subset of the columns fits with non-negative coefficients."""
    c = weighted_nnls(x_cols, y, [1.0 / (v * v) for v in y])
    if not any(v > 0 for v in c):
        return None
    k = len(x_cols)
    res = [(sum(c[j] * x_cols[j][i] for j in range(k)) - y[i]) / y[i] for i in range(len(y))]
    return c, res


def weighted_nnls(x_cols, y, w):
    """Non-negative weighted least squares y ≈ Σ_j c_j·x_cols[j], weights w: every subset of the
    columns solved (at most four), the all-zero solution included, the least Σ w·(y − f)² kept
    (ties keep the earlier subset, as the Rust `nnls` does). Returns c."""
    k, n = len(x_cols), len(y)

    def ssr(c):
        return sum(w[i] * (y[i] - sum(c[j] * x_cols[j][i] for j in range(k))) ** 2 for i in range(n))

    best = ([0.0] * k, ssr([0.0] * k))
    for mask in range(1, 1 << k):
        cols = [j for j in range(k) if mask >> j & 1]
        if n < len(cols):
            continue
        ata = [[sum(w[i] * x_cols[a][i] * x_cols[b][i] for i in range(n)) for b in cols] for a in cols]
        atb = [sum(w[i] * x_cols[a][i] * y[i] for i in range(n)) for a in cols]
        sub = solve(ata, atb)
        if sub is None or any(v < 0 for v in sub):
            continue
        c = [0.0] * k
        for j, v in zip(cols, sub):
            c[j] = v
        r = ssr(c)
        if r < best[1]:
            best = (c, r)
    return best[0]


def fit_relative_iterated(x_cols, y, rounds=3):
    """The error model's fit (the Rust `ErrorFit::fit_relative`, held equal to it on the shared
    cases of tests/data/error_fit_cases.txt): non-negative least squares weighted by 1/f², f the
    fitted value, an MSE estimate's noise being proportional to its size. It starts from the
    measured values (weights 1/y², a value ≤ 0 getting the smallest positive value's weight) and
    reweighs by the fitted ones `rounds` times. Rows with a non-finite value are skipped. Returns
    (c, relative residuals (y − f)/f), the shape of fit_costs' answer, or None without a row."""
    keep = [i for i in range(len(y)) if math.isfinite(y[i]) and all(math.isfinite(col[i]) for col in x_cols)]
    if not keep:
        return None
    cols = [[col[i] for i in keep] for col in x_cols]
    yy = [y[i] for i in keep]
    smallest = min((v for v in yy if v > 0), default=math.inf)

    def weight(v):
        return 1.0 / max(v, smallest) ** 2

    def fitted(c):
        return [sum(c[j] * cols[j][i] for j in range(len(cols))) for i in range(len(yy))]

    c = weighted_nnls(cols, yy, [weight(v) for v in yy])
    for _ in range(rounds):
        c = weighted_nnls(cols, yy, [weight(f) for f in fitted(c)])
    res = [(v - f) / f if f > 0 else math.nan for v, f in zip(yy, fitted(c))]
    return c, res


CostFit = namedtuple("CostFit", "constants residuals cis undefined")
CostFit.__doc__ = """Fitted seconds per counted operation: constants, relative residuals (the misfit),
per-constant (lo, hi) from the case-resampling bootstrap, and the share of draws that could not be
fitted (too few distinct cases)."""


def fit_costs_ci(x_cols, y, y_se, draws=2000, seed=1, dofs=None, level=0.95, fit=None):
    """fit_costs with intervals that carry the fit's misfit: every draw resamples the cases (table
    rows) with replacement, and moves each drawn y within its SE (Student-t on `dofs`), then refits
    the columns the full fit selected (non-zero constants). A column left at 0 adds nothing the data
    can separate and gets (0, 0). Draws with fewer distinct cases than constants, and draws that
    move a y to ≤ 0 (relative residuals need a positive value; a time drawn within a wide SE can
    cross 0), are counted in `undefined`, not dropped silently and not fitted on a clamped value.
    `fit` is the fit refitted in every draw (fit_costs unless given: fit_relative_iterated is the
    error model's)."""
    fit = fit or fit_costs
    best = fit(x_cols, y)
    if best is None:
        raise ValueError("no non-negative fit")
    c, res = best
    active = [j for j in range(len(c)) if c[j] > 0]
    rng = random.Random(seed)
    dofs = dofs if dofs is not None else [None] * len(y)
    n = len(y)
    got = []
    failed = 0
    for _ in range(draws):
        idx = [rng.randrange(n) for _ in range(n)]
        if len(set(idx)) <= len(active):
            failed += 1
            continue
        yy = [y[i] + (y_se[i] * draw_error(rng, dofs[i]) if y_se[i] == y_se[i] else 0.0) for i in idx]
        if not all(v > 0 for v in yy):
            failed += 1
            continue
        sub = fit([[x_cols[j][i] for i in idx] for j in active], yy)
        if sub is None or not all(math.isfinite(v) for v in sub[0]):
            failed += 1
            continue
        got.append(dict(zip(active, sub[0])))
    a = (1 - level) / 2
    cis = []
    for j in range(len(c)):
        if j not in active or not got:
            cis.append((0.0, 0.0) if j not in active else (math.nan, math.nan))
            continue
        v = sorted(d[j] for d in got)
        cis.append((percentile(v, a), percentile(v, 1 - a)))
    return CostFit(c, res, cis, failed / draws)


def shapley_factors(value, factors):
    """Order-free decomposition of a positive quantity into multiplicative factors.

    `value(switched)` gives the quantity with the factors in the frozenset `switched` changed (all
    2^k combinations must be measured). Switching factor i on its own changes the quantity by a
    ratio that depends on what was switched before; its Shapley factor is the geometric mean of
    that ratio over every order of switching all k factors (equivalently over subsets S without i,
    weighted |S|!(k−|S|−1)!/k!). The factors multiply exactly to value(all)/value(none), whatever
    the order. Returns {factor: (shapley, smallest, largest ratio over orders)}."""
    k = len(factors)
    out = {}
    for f in factors:
        others = [g for g in factors if g != f]
        total, lo, hi = 0.0, math.inf, -math.inf
        for mask in range(1 << (k - 1)):
            s = frozenset(g for j, g in enumerate(others) if mask >> j & 1)
            ratio = value(s | {f}) / value(s)
            w = math.factorial(len(s)) * math.factorial(k - len(s) - 1) / math.factorial(k)
            total += w * math.log(ratio)
            lo, hi = min(lo, ratio), max(hi, ratio)
        out[f] = (math.exp(total), lo, hi)
    return out


# ----------------------------------------------------------------------------------------------
# run-level pooling


def pool_runs(tables, keys, metrics):
    """Pools K tables of the same spec (separate process runs) point by point.

    `tables` are lists of row dicts; rows are matched by the values of `keys` (the swept columns);
    every metric M in `metrics` (with M_mean, M_se, M_clusters or M_n) is pooled with the runs as
    clusters: M_mean is the mean of the runs' means weighted by their clusters, M_se comes from the
    spread of the run means (so between-run variation is inside it) on K − 1 degrees of freedom
    (M_clusters = K), M_n is the sum. M_se_within keeps the within-run SE of the pooled mean for
    comparison and M_runs the number of runs. Per-replica members (`F_replica_K`, e.g. the
    predictor's pick_replica_K) are every run's: run 0's replicas keep their K, the next run's
    follow them (K + R₀, …), so a rule over replicas sees every run's. A point missing from a run is
    an error. With one table the rows come back unchanged (M_runs = 1)."""
    if not tables:
        raise ValueError("no tables to pool")
    index = []
    for t in tables:
        by = {}
        for r in t:
            key = tuple(r.get(k) for k in keys)
            if key in by:
                raise ValueError("two rows with %s = %s in one run" % (keys, key))
            by[key] = r
        index.append(by)
    out = []
    for key, first in index[0].items():
        rows = []
        for i, by in enumerate(index):
            if key not in by:
                raise ValueError("run %d has no row with %s = %s" % (i, keys, key))
            rows.append(by[key])
        pooled = {k: v for k, v in first.items() if not _REPLICA_MEMBER.match(k)}
        pooled.update(_pool_replica_members(rows))
        for m in metrics:
            pooled.update(_pool_metric(rows, m))
        out.append(pooled)
    return out


_REPLICA_MEMBER = re.compile(r"^(.*_replica_)(\d+)$")


def _pool_replica_members(rows):
    """Every run's `F_replica_K` cells, renumbered consecutively over the runs in run order (see
    pool_runs); empty cells (a run with fewer replicas at this point) are left out."""
    out, next_k = {}, {}
    for r in rows:
        members = sorted((m.group(1), int(m.group(2)), v) for m, v in
                         ((_REPLICA_MEMBER.match(key), v) for key, v in r.items()) if m)
        for fam, _, value in members:
            if value is None or value == "" or value != value:
                continue
            k = next_k.get(fam, 0)
            out["%s%d" % (fam, k)] = value
            next_k[fam] = k + 1
    return out


def _pool_metric(rows, m):
    k = len(rows)
    means = [r[m + "_mean"] for r in rows]
    w = [r.get(m + "_clusters") if r.get(m + "_clusters") == r.get(m + "_clusters") and r.get(m + "_clusters")
         else r.get(m + "_n", 1.0) for r in rows]
    w = [x if x and x == x else 1.0 for x in w]
    mean = sum(a * b for a, b in zip(means, w)) / sum(w)
    within = math.sqrt(sum((b * r[m + "_se"]) ** 2 for b, r in zip(w, rows))) / sum(w)
    if k == 1:
        r = rows[0]
        return {m + "_mean": r[m + "_mean"], m + "_se": r[m + "_se"], m + "_n": r.get(m + "_n"),
                m + "_clusters": r.get(m + "_clusters", r.get(m + "_n")), m + "_se_within": r[m + "_se"],
                m + "_runs": 1}
    # Weighted spread of the run means: unbiased for equal weights, the usual effective-size form else.
    wsum = sum(w)
    var_between = sum(b * (a - mean) ** 2 for a, b in zip(means, w)) / wsum * k / (k - 1)
    se = math.sqrt(var_between / k)
    return {m + "_mean": mean, m + "_se": se, m + "_n": sum(r.get(m + "_n", 0) for r in rows),
            m + "_clusters": k, m + "_se_within": within, m + "_runs": k}


# ----------------------------------------------------------------------------------------------
# quasi-static helpers kept for the plot scripts


def break_even(x):
    """Frames until the static disc index has paid for itself, unclipped: (build seconds) ÷
    (per-frame saving) from x = (build, update per frame with the index, update without). Negative
    when the index saves nothing per frame (it never pays), which the caller reports as such."""
    build, s_di, s_sc = x
    saving = s_sc - s_di
    if saving == 0:
        return math.nan
    return build / saving


def frame0(frames, point):
    """Mean, SE and count of frame 0's seconds of `point` over its replicas (NAME.frames.csv rows)."""
    v = [r["frame_s"] for r in frames if r["point"] == point and r["frame"] == 0]
    m = sum(v) / len(v)
    se = math.sqrt(sum((x - m) ** 2 for x in v) / (len(v) - 1) / len(v)) if len(v) > 1 else float("nan")
    return m, se, len(v)


def rays_copied(levels):
    """Rays copied into new sphere-cache lists per sweep point (Σ over levels ≥ 1 of builds × mean
    list length), from a DETP levels table: {point: rays}."""
    held = {}
    for lv in levels:
        if (lv.get("builds_level") or 0) > 0 and lv["level"] > 0:
            held[lv["point"]] = held.get(lv["point"], 0.0) + lv["builds_level"] * lv["rays_level_mean"]
    return held


def engine_cost_fits(rows, levels, draws=2000):
    """Seconds per counted operation of each DETP engine (experiment detp-engines-cost), with CIs
    that carry the fits' misfit (fit_costs_ci: cases resampled).

    The sphere cache's seconds are fitted as c·segments + t·(ray–sphere tests) + u·(ray–disc tests)
    + h·(rays copied into new lists, Σ builds × mean list length from the levels table), on every row
    (it runs alike whatever index a row uses); each disc index's as c·segments + u·(ray–disc tests)
    + v·(nodes visited), on its own rows. Totals over replicas throughout; a total's SE is the
    replicas' count × the per-replica SE. Returns {engine: CostFit}, engine "sphere-cache" or
    "disc-index (INDEX)"."""
    held = rays_copied(levels)

    def total_se(r, engine):
        return r["cost_%s_per_replica_s_se" % engine] * r["cost_%s_per_replica_s_n" % engine]

    def dofs(sub, engine):
        return [dof(r, "cost_%s_per_replica_s" % engine) for r in sub]

    col = lambda sub, key: [r[key] for r in sub]  # noqa: E731
    fits = {"sphere-cache": fit_costs_ci(
        [col(rows, "segments"), col(rows, "ray_sphere_tests"), col(rows, "ray_disc_tests"),
         [held.get(r["point"], 0.0) for r in rows]],
        col(rows, "cost_sphere_cache_s"), [total_se(r, "sphere_cache") for r in rows], draws,
        dofs=dofs(rows, "sphere_cache"))}
    for index in sorted({r["detp.index"] for r in rows}):
        sub = [r for r in rows if r["detp.index"] == index]
        fits["disc-index (%s)" % index] = fit_costs_ci(
            [col(sub, "segments"), col(sub, "tests_disc_index"), col(sub, "nodes_disc_index")],
            col(sub, "cost_disc_index_s"), [total_se(r, "disc_index") for r in sub], draws,
            dofs=dofs(sub, "disc_index"))
    return fits
