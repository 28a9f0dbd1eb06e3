"""Statistics shared by scripts/claims.py and the plot scripts (no plotting, no third-party deps):
Student-t quantiles, a parametric bootstrap for figures derived from several means, the
optimum of a cost curve and cost constants fitted to timings.
"""

import math
import random

Z95 = 1.96

T95 = {1: 12.706, 2: 4.303, 3: 3.182, 4: 2.776, 5: 2.571, 6: 2.447, 7: 2.365, 8: 2.306, 9: 2.262,
       10: 2.228, 15: 2.131, 20: 2.086, 30: 2.042}


def draw_error(rng, dof):
    """One standard error's worth of noise for a mean estimated from clusters − 1 = dof degrees of
    freedom: Student-t (a normal mean's posterior with its variance unknown, flat prior), normal
    where dof is unknown or large."""
    z = rng.gauss(0, 1)
    if dof is None or dof != dof or dof > 1000:
        return z
    if dof < 1:
        return math.nan
    return z / math.sqrt(rng.gammavariate(dof / 2, 2) / dof)


def bootstrap(f, means, ses, draws=4000, seed=1, dofs=None):
    """f(means) and the 2.5/97.5 percentiles of f over draws of every mean within its SE (NaN SEs as
    0): Student-t draws on each mean's degrees of freedom (`dofs`, clusters − 1), normal without."""
    rng = random.Random(seed)
    dofs = dofs if dofs is not None else [None] * len(means)
    vals = []
    for _ in range(draws):
        x = [m + (s * draw_error(rng, d) if s == s else 0.0) for m, s, d in zip(means, ses, dofs)]
        if any(v != v for v in x):
            continue
        v = f(x)
        if v == v:
            vals.append(v)
    vals.sort()
    if not vals:
        return f(means), math.nan, math.nan
    lo = vals[int(0.025 * (len(vals) - 1))]
    hi = vals[int(0.975 * (len(vals) - 1))]
    return f(means), lo, hi


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


def t95(dof):
    """Student-t's two-sided 95 % quantile (normal beyond 30 degrees of freedom; NaN below 1: one
    sample has no CI)."""
    if dof is None or dof != dof:
        return Z95
    if dof < 1:
        return math.nan
    if dof > 30:
        return Z95
    dof = int(dof)
    while dof not in T95:
        dof -= 1
    return T95[dof]


def optimum_q(rows):
    """Continuous optimum of a quadratic fitted to log(cost) over the 5 Q values around the minimum."""
    qs = [r["detp.q"] for r in rows]

    def f(costs):
        if min(costs) <= 0:
            return math.nan
        i = costs.index(min(costs))
        lo, hi = max(0, i - 2), min(len(qs), i + 3)
        x, y = qs[lo:hi], [math.log(c) for c in costs[lo:hi]]
        if len(x) < 3:
            return qs[i]
        # least squares y = a + b x + c x²
        n = len(x)
        sx = [sum(v ** k for v in x) for k in range(5)]
        sy = [sum(yy * v ** k for v, yy in zip(x, y)) for k in range(3)]
        a = [[sx[0], sx[1], sx[2]], [sx[1], sx[2], sx[3]], [sx[2], sx[3], sx[4]]]
        sol = solve(a, sy)
        if sol is None or sol[2] <= 0:
            return qs[i]
        return min(max(-sol[1] / (2 * sol[2]), x[0]), x[-1])
    return f


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


def fit_costs(x_cols, y):
    """Non-negative least squares on relative residuals: y ≈ Σ_j c_j·x_cols[j] with c ≥ 0, each point
    weighted by 1/y (times span decades). Solves every subset of columns (there are at most four)
    and keeps the best non-negative solution. Returns (c, relative residuals)."""
    k, n = len(x_cols), len(y)
    w = [[x_cols[j][i] / y[i] for j in range(k)] for i in range(n)]
    best = None
    for mask in range(1, 1 << k):
        cols = [j for j in range(k) if mask >> j & 1]
        ata = [[sum(w[i][a] * w[i][b] for i in range(n)) for b in cols] for a in cols]
        atb = [sum(w[i][a] for i in range(n)) for a in cols]
        sub = solve(ata, atb)
        if sub is None or any(v < 0 for v in sub):
            continue
        c = [0.0] * k
        for j, v in zip(cols, sub):
            c[j] = v
        res = [(sum(c[j] * x_cols[j][i] for j in range(k)) - y[i]) / y[i] for i in range(n)]
        if best is None or sum(r * r for r in res) < sum(r * r for r in best[1]):
            best = (c, res)
    return best


def fit_costs_ci(x_cols, y, y_se, draws=2000, seed=1, dofs=None):
    """fit_costs and, per constant, the 2.5/97.5 percentiles of the refitted constant over normal
    draws of every y within its SE, Student-t on `dofs` (a parametric bootstrap over replicas: the
    fit's residual, the model's misfit, is reported beside it, not in it). The draws refit the
    columns the fit selected (its non-zero constants); a column it left at 0 adds nothing the data
    can separate from the others and gets (0, 0). Returns (c, residuals, [(lo, hi)] per c)."""
    c, res = fit_costs(x_cols, y)
    active = [j for j in range(len(c)) if c[j] > 0]
    rng = random.Random(seed)
    dofs = dofs if dofs is not None else [None] * len(y)
    draws_c = []
    for _ in range(draws):
        yy = [max(v + (s * draw_error(rng, d) if s == s else 0.0), 1e-300) for v, s, d in zip(y, y_se, dofs)]
        if any(v != v for v in yy):
            continue
        sub = fit_costs([x_cols[j] for j in active], yy)[0]
        draws_c.append(dict(zip(active, sub)))
    cis = []
    for j in range(len(c)):
        if j not in active:
            cis.append((0.0, 0.0))
            continue
        v = sorted(d[j] for d in draws_c)
        cis.append((v[int(0.025 * (len(v) - 1))], v[int(0.975 * (len(v) - 1))]))
    return c, res, cis


def break_even(x):
    """Frames until the static disc index has paid for itself, frame 0 included, from
    x = (frame 0 with the index, frame 0 without, update per frame with, update without): 0 when the
    index path is no slower at frame 0, infinity when it never saves."""
    f0_di, f0_sc, s_di, s_sc = x
    extra = f0_di - f0_sc
    saving = s_sc - s_di
    if extra <= 0:
        return 0.0
    if saving <= 0:
        return math.inf
    return extra / saving


def frame0(frames, point):
    """Mean, SE and count of frame 0's seconds of `point` over its replicas (NAME.frames.csv rows)."""
    v = [r["frame_s"] for r in frames if r["point"] == point and r["frame"] == 0]
    m = sum(v) / len(v)
    se = math.sqrt(sum((x - m) ** 2 for x in v) / (len(v) - 1) / len(v)) if len(v) > 1 else float("nan")
    return m, se, len(v)


def crossing(xs, a, b):
    """First x where log a − log b changes sign (log-linear interpolation between points), NaN if none."""
    for i in range(1, len(xs)):
        if min(a[i - 1], a[i], b[i - 1], b[i]) <= 0:
            continue
        d0, d1 = math.log(a[i - 1] / b[i - 1]), math.log(a[i] / b[i])
        if d0 <= 0 < d1 or d0 >= 0 > d1:
            return xs[i - 1] + (xs[i] - xs[i - 1]) * d0 / (d0 - d1)
    return math.nan


def rays_copied(levels):
    """Rays copied into new sphere-cache lists per sweep point (Σ over levels ≥ 1 of builds × mean
    list length), from a DETP levels table: {point: rays}."""
    held = {}
    for lv in levels:
        if (lv.get("builds_level") or 0) > 0 and lv["level"] > 0:
            held[lv["point"]] = held.get(lv["point"], 0.0) + lv["builds_level"] * lv["rays_level_mean"]
    return held


def engine_cost_fits(rows, levels, draws=2000):
    """Seconds per counted operation of each DETP engine (experiment detp-engines-cost), with CIs.

    The sphere cache's seconds are fitted as c·segments + t·(ray–sphere tests) + u·(ray–disc tests)
    + h·(rays copied into new lists, Σ builds × mean list length from the levels table), on every row
    (it runs alike whatever index a row uses); each disc index's as c·segments + u·(ray–disc tests)
    + v·(nodes visited), on its own rows. Totals over replicas throughout; a total's SE is the
    replicas' count × the per-replica SE. Returns {engine: (constants, residuals, CIs)}, engine
    "sphere-cache" or "disc-index (INDEX)"."""
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
