"""Statistics that compare engines or settings along a swept curve: the crossover of two engines'
costs (a root of a smooth fit of their log ratio), the optimum of one cost curve (the minimum of a
smooth fit), the ratio of two engines' costs, the break-even frame of an index build, the bias of
an estimator on regions of points, and the §4.1 predictor's picks.

Where the frames tables give per-replica values, the intervals come from a cluster bootstrap over
separate runs and the replicas within them (raycost_stats.Clustered); a crossover's or optimum's
draws that have no single value are counted and shown, never dropped.
"""

import math

import claims_rules as R
import raycost_stats as S
from claims_data import Missing, group, label, matches, per_replica, quantity, show
from claims_measures import Measured, est, fmt, headline, rows_of, series_of, series_groups, terms


def pairs(rows, cmp, x=None):
    """{x value (or None): (numerator row, denominator row)} of one unit's rows."""
    out = {}
    for r in rows:
        side = show(r[cmp["column"]])
        if side not in (cmp["numerator"], cmp["denominator"]):
            continue
        k = r[x] if x else None
        slot = out.setdefault(k, {})
        if side in slot:
            raise Missing("one row per %s and %s in a unit (two found)" % (cmp["column"], side))
        slot[side] = r
    bad = [k for k, s in out.items() if len(s) != 2]
    if bad:
        raise Missing("both %s and %s at every point" % (cmp["numerator"], cmp["denominator"]))
    return {k: (s[cmp["numerator"]], s[cmp["denominator"]]) for k, s in sorted(out.items(), key=lambda kv: kv[0] or 0)}


def fit_rule(v, ctx):
    return v.get("fit_degrees", ctx.defaults["fit_degrees"]), ctx.defaults["fit_alpha"]


def category_text(iv):
    parts = ["%.1f %% %s" % (100 * f, {"ok": "single value", "none": "no crossing", "several": "several crossings",
                                         "edge": "minimum at an end of the range", "undefined": "undefined"}.get(k, k))
             for k, f in iv.categories.items()]
    return "draws: " + ", ".join(parts)


def kind_crossover(v, ctx):
    """Per unit: the root in the range of a smooth fit of log(numerator cost / denominator cost)."""
    units = []
    t = terms(ctx, v, v)
    rows = rows_of(ctx, v)
    degrees, alpha = fit_rule(v, ctx)
    tol = v["tolerance"]
    band = R.band_of(tol)
    for _, g in group(rows, v["units"]):
        pr = pairs(g, v["compare"], v["x"])
        xs = list(pr)
        pts = [a["point"] for a, _ in pr.values()] + [b["point"] for _, b in pr.values()]
        cl = S.Clustered(per_replica(ctx.tables, v["source"], pts, t))
        ratio = S.paired_log_ratio(len(xs), cl)
        # x_scale = "log": the fit runs over log x (a cost ratio that goes as a power of x is a
        # straight line there) and the root is read back in x.
        to_fit, back = (math.log, math.exp) if v.get("x_scale") == "log" else (float, float)
        fx = [to_fit(x) for x in xs]
        c = S.crossover(fx, cl, ratio, degrees, alpha, ctx.draws, ctx.seed, ctx.level)
        iv, fit, k, roots, lo, hi = c
        iv = iv._replace(value=back(iv.value) if iv.value == iv.value else iv.value,
                         lo=back(iv.lo) if iv.lo == iv.lo else iv.lo, hi=back(iv.hi) if iv.hi == iv.hi else iv.hi)
        roots, lo, hi = [back(r) for r in roots], back(lo), back(hi)
        ys = ratio(*cl.observed())[0]
        if fit is None:
            units.append(R.Unit(label(g[0], v["units"]), "no fit of log(%s/%s) over %d points" % (
                v["compare"]["numerator"], v["compare"]["denominator"], len(xs)), R.UNDECIDED, "no fit", "no fit"))
            continue
        j, why = crossover_judgement(iv, roots, lo, hi, band, tol, ctx, v["compare"], fit, fx)
        text = "%s; log(%s/%s) %s at %s = %s; fit degree %d%s%s; %s" % (
            "crossing at " + est(iv.value, lo, hi, 3) if len(roots) == 1 else "%d crossings of the fit" % len(roots),
            v["compare"]["numerator"], v["compare"]["denominator"], ", ".join("%+.2f" % y for y in ys),
            v["x"].split(".")[-1], ", ".join("%g" % x for x in xs),
            fit.degree, (" in log " + v["x"].split(".")[-1]) if v.get("x_scale") == "log" else "",
            ", misfit ×%.2f" % k if k > 1 else "", category_text(iv))
        one = len(roots) == 1
        brief = "crossing %s" % est(iv.value, lo, hi, 3) if one else (
            "no crossing" if not roots else "%d crossings" % len(roots))
        units.append(R.Unit(label(g[0], v["units"]), text, j, why, brief, iv.value if one else None))
    return Measured(units, [], [], headline(units))


def crossover_judgement(iv, roots, lo, hi, band, tol, ctx, cmp, fit, xs):
    undefined = ctx.defaults["max_undefined"]
    cats = iv.categories
    if len(roots) > 1:
        return R.UNDECIDED, "the fitted curve crosses %d times" % len(roots)
    if not roots:
        if cats.get("none", 0.0) >= 1 - undefined:
            cheaper = cmp["denominator"] if S.fit_value(fit, xs[0]) > 0 else cmp["numerator"]
            return R.OUTSIDE, "no crossing in %g–%g: %s cheaper throughout" % (xs[0], xs[-1], cheaper)
        return R.UNDECIDED, "no crossing in the fit, but %.0f %% of draws cross" % (100 * (1 - cats.get("none", 0)))
    if 1 - cats.get("ok", 0.0) > undefined:
        return R.UNDECIDED, "%.0f %% of draws do not cross exactly once" % (100 * (1 - cats.get("ok", 0.0)))
    return R.interval_judgement(lo, hi, band, tol.get("max_half_width"), iv.value)


def kind_optimum(v, ctx):
    """Per unit: the minimum in the range of a smooth fit of log(cost) against x."""
    units = []
    t = terms(ctx, v, v)
    degrees, alpha = fit_rule(v, ctx)
    band = R.band_of(v["tolerance"])
    for _, g in group(rows_of(ctx, v), v["units"]):
        g = sorted(g, key=lambda r: r[v["x"]])
        xs = [r[v["x"]] for r in g]
        q = [quantity(r, t, v["source"]) for r in g]
        sampler = S.Parametric([a for a, _, _ in q], [b for _, b, _ in q], [c for _, _, c in q])
        iv, fit, k, (xmin, where), lo, hi = S.optimum(xs, sampler, degrees, alpha, ctx.draws, ctx.seed, ctx.level)
        bad = 1 - iv.categories.get("ok", 0.0)
        if where != "interior":
            j, why = R.UNDECIDED, "the fit's minimum is at an end of the range"
        elif bad > ctx.defaults["max_undefined"]:
            j, why = R.UNDECIDED, "%.0f %% of draws have no interior minimum" % (100 * bad)
        else:
            j, why = R.interval_judgement(lo, hi, band)
        text = "x* = %s over %s = %s … %s (%d values); fit degree %d%s; %s" % (
            est(iv.value, lo, hi, 3), v["x"].split(".")[-1], show(xs[0]), show(xs[-1]), len(xs), fit.degree,
            ", misfit ×%.2f" % k if k > 1 else "", category_text(iv))
        brief = "minimum at %s = %s" % (v["x"].split(".")[-1], est(iv.value, lo, hi, 3))
        units.append(R.Unit(label(g[0], v["units"]), text, j, why, brief, iv.value))
    return Measured(units, [], [], headline(units))


def kind_engine_ratio(v, ctx):
    """Per unit of every series: mean cost of the numerator engine ÷ the denominator's per frame
    (frames ≥ 1), percentile interval of the cluster bootstrap."""
    units, needs, per_series = [], [], []
    band = R.band_of(v["tolerance"])
    for s in series_of(v):
        per_series.append([])
        try:
            t = terms(ctx, v, s)
            for _, g in group(rows_of(ctx, s), s["units"]):
                (a, b), = pairs(g, v["compare"]).values()
                cl = S.Clustered(per_replica(ctx.tables, s["source"], [a["point"], b["point"]], t))
                iv = S.bootstrap(lambda m, _v: m[0] / m[1] if m[1] > 0 else math.nan, cl, ctx.draws, ctx.seed, ctx.level)
                j, why = R.interval_judgement(iv.lo, iv.hi, band)
                units.append(R.Unit(label(a, s["units"], s.get("label", "")), est(iv.value, iv.lo, iv.hi, 3), j, why,
                                    est(iv.value, iv.lo, iv.hi, 3), iv.value))
                per_series[-1].append(units[-1])
        except Missing as e:
            needs.append(str(e))
    return Measured(units, needs, [], headline(units, series_groups(v, per_series)))


def kind_break_even(v, ctx):
    """Per unit: the index's build seconds ÷ the per-frame saving (numerator engine − denominator
    engine, the index being the denominator), unclipped, with Fieller's interval on the clusters'
    degrees of freedom. The build comes per replica from the frames table (frame 0's row) when it
    has the column, else from the main table as one value without SE (the rule then needs it)."""
    units, needs = [], []
    band = R.band_of(v["tolerance"])
    t = terms(ctx, v, v)
    build = v["build"]
    for _, g in group(rows_of(ctx, v), v["units"]):
        (a, b), = pairs(g, v["compare"]).values()
        try:
            cl = S.Clustered(per_replica(ctx.tables, v["source"], [a["point"], b["point"]], t,
                                         extra=[(b["point"], {build: 1}, 0)]))
            (ma, mb, mbuild), var = cl.observed()
            vbuild, cov_ba, cov_bb = var[2], cl.covariance(2, 0), cl.covariance(2, 1)
        except Missing:
            cl = S.Clustered(per_replica(ctx.tables, v["source"], [a["point"], b["point"]], t))
            (ma, mb), var = cl.observed()
            mbuild, vbuild, cov_ba, cov_bb = b[build], 0.0, 0.0, 0.0
        saving = ma - mb
        vsave = var[0] + var[1] - 2 * cl.covariance(0, 1)
        tq = S.t_for_level(ctx.level, cl.clusters() - 1)
        ratio, lo, hi, bounded = S.fieller(mbuild, vbuild, saving, vsave, cov_ba - cov_bb, tq)
        save_hi = saving + tq * math.sqrt(vsave)
        if save_hi < 0:
            j, why = R.OUTSIDE, "the index is slower per frame: it never pays"
        elif not bounded:
            j, why = R.UNDECIDED, "the per-frame saving is not distinguishable from 0"
        else:
            j, why = R.interval_judgement(lo, hi, band)
        text = "%s frames (build %s s, saving %s ± %s s per frame)" % (
            est(ratio, lo, hi, 3), fmt(mbuild, 3), fmt(saving, 3), fmt(tq * math.sqrt(vsave), 2))
        units.append(R.Unit(label(b, v["units"]), text, j, why, "%s frames" % est(ratio, lo, hi, 3),
                            ratio if bounded else None))
    return Measured(units, needs, [], headline(units))


def region_bias(points, replicas, keep):
    """Per replica, Σ(E − reference)/Σ reference over the kept points; the reference's own error
    (√Σ reference_se² / Σ reference) joined by Welch–Satterthwaite. Returns (mean, se, dof, n)."""
    pts = [p for p in points if keep(p)]
    if not pts:
        return math.nan, math.nan, math.nan, 0
    ref = sum(p["reference_e"] for p in pts)
    if not ref > 0:
        # No light reaches these points by the reference: a relative bias does not exist.
        return math.nan, math.nan, math.nan, len(pts)
    per = [sum(p["irradiance_replica_%d" % k] - p["reference_e"] for p in pts) / ref for k in range(replicas)]
    m = sum(per) / replicas
    v_rep = sum((x - m) ** 2 for x in per) / (replicas - 1) / replicas
    v_ref = sum(p["reference_se"] ** 2 for p in pts) / ref ** 2
    v = v_rep + v_ref
    dof = v * v / (v_rep ** 2 / (replicas - 1)) if v_rep > 0 else math.inf
    return m, math.sqrt(v), dof, len(pts)


def kind_bias(v, ctx):
    """Per unit: DETP's relative bias against the reference on the points whose distance to the
    nearest edge or other surface is at least d (the paper's open surfaces); s < d beside."""
    units, needs = [], []
    band = R.band_of(v["tolerance"])
    col = v["edge_column"]
    for name in v["sources"]:
        try:
            main = [r for r in ctx.tables.rows(name) if matches(r, v.get("select"))]
            pts = ctx.tables.rows(name, "points")
        except Missing as e:
            needs.append(str(e))
            continue
        if not pts or col not in pts[0] or "irradiance_replica_0" not in pts[0] or "reference_se" not in pts[0]:
            units += [R.Unit(label(r, v["units"]), all_points_text(r), R.UNDECIDED, "no per-point edge distance")
                      for r in main]
            continue
        for r in main:
            mine = [p for p in pts if p["point"] == r["point"]]
            reps = int(r["detp.replicas"])
            d = r["detp.disc_radius"]
            m, se, dof, n = region_bias(mine, reps, lambda p: p[col] >= d)
            m2, se2, dof2, n2 = region_bias(mine, reps, lambda p: p[col] < d)
            if math.isnan(m):
                text = "s ≥ d (%d points): the reference irradiance sums to 0 there, no relative bias" % n
                units.append(R.Unit(label(r, v["units"]), text, R.UNDECIDED, "no lit point with s ≥ d"))
                continue
            lo, hi = m - S.t_for_level(ctx.level, dof) * se, m + S.t_for_level(ctx.level, dof) * se
            j, why = R.interval_judgement(lo, hi, band)
            h2 = S.t_for_level(ctx.level, dof2) * se2 if n2 and not math.isnan(m2) else math.nan
            text = "s ≥ d (%d points): %+.1f %% [%+.1f, %+.1f]; s < d (%d points): %+.1f ± %.1f %%" % (
                n, 100 * m, 100 * lo, 100 * hi, n2, 100 * m2, 100 * h2)
            units.append(R.Unit(label(r, v["units"]), text, j, why,
                                "bias %+.1f %% [%+.1f, %+.1f]" % (100 * m, 100 * lo, 100 * hi), m))
    return Measured(units, needs, [], headline(units))


def all_points_text(r):
    ref = r["reference_irradiance_mean"]
    b = r["irradiance_ref_bias_mean"]
    h = S.ci95(r, "irradiance_ref_bias")
    return "all points (no edge distance to split them): %+.1f ± %.1f %%" % (100 * b / ref, 100 * h / ref)


def kind_predictor(v, ctx):
    """Per unit (predictor) and ratio: where the engines' warm timings differ (the interval of
    log(sphere cache / disc index) excludes 0), the share of picks (every replica of every run:
    the pooled table holds each run's pick_replica_K) that were the faster engine. As the rule
    states: the unit holds when that share is ≥ min_right at every such ratio; it differs when the
    pooled share's interval (Clopper–Pearson at the claims' level, all decisive ratios' picks
    together) lies below min_right; else it is undecided."""
    units, needs = [], []
    need = ["warm_sphere_cache_s_mean", "warm_disc_index_s_mean", "pick_replica_0"]
    try:
        rows = rows_of(ctx, v)
    except Missing as e:
        return Measured([], [str(e)], [])
    if not rows or any(c not in rows[0] for c in need):
        return Measured([], ["column %s in %s.csv" % (c, v["source"]) for c in need if not rows or c not in rows[0]], [])
    tol = v["tolerance"]["min_right"]
    for _, g in group(rows, v["units"]):
        counts = []
        for r in sorted(g, key=lambda r: r[v["x"]]):
            a, sa, da = quantity(r, {"warm_sphere_cache_s": 1})
            b, sb, db = quantity(r, {"warm_disc_index_s": 1})
            h = S.t_for_level(ctx.level, min(da, db)) * math.sqrt((sa / a) ** 2 + (sb / b) ** 2)
            lr = math.log(a / b)
            if abs(lr) <= h:
                continue  # the engines' timings do not differ here: no right pick to make
            faster = "sphere-cache" if lr < 0 else "disc-index"
            picks = [r[k] for k in sorted(r) if k.startswith("pick_replica_")]
            picks = [p for p in picks if p == p and p not in (None, "")]
            counts.append((r[v["x"]], sum(p == faster for p in picks), len(picks)))
        right, total = sum(c[1] for c in counts), sum(c[2] for c in counts)
        lo, hi = S.clopper_pearson(right, total, ctx.level)
        if not total:
            j, why = R.UNDECIDED, "no ratio where the engines' timings differ"
        elif all(ok >= tol * n for _, ok, n in counts):
            j, why = R.INSIDE, ""
        elif hi < tol:
            j, why = R.OUTSIDE, "right in %.0f %% of picks [%.0f, %.0f] %%, below %g" % (
                100 * right / total, 100 * lo, 100 * hi, tol)
        else:
            j, why = R.UNDECIDED, "right in %.0f %% of picks [%.0f, %.0f] %%: below %g at a ratio, the interval reaches it" % (
                100 * right / total, 100 * lo, 100 * hi, tol)
        per = "; ".join("%g: %d of %d" % c for c in counts)
        text = "right picks at decisive ratios — %s; pooled %d of %d [%.0f, %.0f] %%" % (
            per, right, total, 100 * lo, 100 * hi) if total else "right picks at decisive ratios — none"
        brief = "%d/%d right [%.0f, %.0f] %%" % (right, total, 100 * lo, 100 * hi) if total else "no decisive ratio"
        units.append(R.Unit(label(g[0], v["units"]), text, j, why, brief, right / total if total else None))
    return Measured(units, needs, [], headline(units))
