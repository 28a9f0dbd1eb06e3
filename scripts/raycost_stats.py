"""Statistics shared by scripts/claims.py and the plot scripts (no plotting, no third-party deps):
Student-t quantiles, a parametric bootstrap for figures derived from several means, and the
optimum of a cost curve.
"""

import math
import random

Z95 = 1.96

T95 = {1: 12.706, 2: 4.303, 3: 3.182, 4: 2.776, 5: 2.571, 6: 2.447, 7: 2.365, 8: 2.306, 9: 2.262,
       10: 2.228, 15: 2.131, 20: 2.086, 30: 2.042}


def bootstrap(f, means, ses, draws=4000, seed=1):
    """f(means) and the 2.5/97.5 percentiles of f over normal draws of every mean (NaN SEs as 0)."""
    rng = random.Random(seed)
    vals = []
    for _ in range(draws):
        x = [m + (s if s == s else 0.0) * rng.gauss(0, 1) for m, s in zip(means, ses)]
        v = f(x)
        if v == v:
            vals.append(v)
    vals.sort()
    if not vals:
        return f(means), math.nan, math.nan
    lo = vals[int(0.025 * (len(vals) - 1))]
    hi = vals[int(0.975 * (len(vals) - 1))]
    return f(means), lo, hi


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
        sol = solve3(a, sy)
        if sol is None or sol[2] <= 0:
            return qs[i]
        return min(max(-sol[1] / (2 * sol[2]), x[0]), x[-1])
    return f


def solve3(a, b):
    """The solution of the 3×3 system a·x = b (Gaussian elimination with pivoting), None if singular."""
    m = [row[:] + [v] for row, v in zip(a, b)]
    for c in range(3):
        p = max(range(c, 3), key=lambda r: abs(m[r][c]))
        if abs(m[p][c]) < 1e-300:
            return None
        m[c], m[p] = m[p], m[c]
        for r in range(3):
            if r != c:
                f = m[r][c] / m[c][c]
                m[r] = [x - f * y for x, y in zip(m[r], m[c])]
    return [m[i][3] / m[i][i] for i in range(3)]


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
