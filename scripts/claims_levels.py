"""Statistics over the sphere cache's levels (the `NAME.levels.csv` side tables): the rays-per-level
law level by level, the level where misses peak, and the ratio of two orderings' misses at chosen
levels. Which levels count is a registered rule (from level 1 down to the deepest level holding at
least `min_spheres` spheres), never a window in the code.
"""

import math
import random

import claims_rules as R
import raycost_stats as S
from claims_data import Missing, group, label, matches, show
from claims_measures import Measured, est, fmt, headline, sources_of, t_ci


def levels_by_point(ctx, name):
    out = {}
    for r in ctx.tables.rows(name, "levels"):
        out.setdefault(r["point"], []).append(r)
    return {p: sorted(v, key=lambda r: r["level"]) for p, v in out.items()}


def counted_levels(levels, metric, min_spheres):
    """Levels 1 … the deepest whose `metric` rests on at least min_spheres spheres (M_n)."""
    ok = [r["level"] for r in levels if r["level"] >= 1 and (r.get(metric + "_n") or 0) >= min_spheres]
    deepest = max(ok, default=0)
    return [r for r in levels if 1 <= r["level"] <= deepest]


def law_error(r, metric, theory, level):
    """(law − measured)/measured and its interval from the measurement's (the law is exact)."""
    m, se = r[metric + "_mean"], r[metric + "_se"]
    d = (r.get(metric + "_clusters") or r.get(metric + "_n")) - 1
    lo, hi = t_ci(m, se, d, level)
    th = r[theory]
    err = th / m - 1
    return err, (th / hi - 1 if hi > 0 else math.nan), (th / lo - 1 if lo > 0 else math.inf)


def kind_level_law(v, ctx):
    """Per unit (a scene, a Q): every counted level's law error against the band; the unit is
    judged by `verdict.levels` ("all" or "most") over its levels."""
    units, needs = [], []
    band = R.band_of(v["tolerance"])
    metric, theory = v["metric"], v["theory"]
    for name in sources_of(v):
        try:
            main = [r for r in ctx.tables.rows(name) if matches(r, v.get("select"))]
            levels = levels_by_point(ctx, name)
        except Missing as e:
            needs.append(str(e))
            continue
        for _, g in group(main, v["units"]):
            for row in g:
                lv = counted_levels(levels.get(row["point"], []), metric, ctx.min_spheres)
                per, errs = [], []
                for r in lv:
                    e, lo, hi = law_error(r, metric, theory, ctx.level)
                    j, why = R.interval_judgement(lo, hi, band)
                    per.append(R.Unit("level %d" % r["level"], "%+.1f %%" % (100 * e), j, why))
                    if e == e:
                        errs.append(100 * e)
                j, why = R.group_judgement(per, v["verdict"]["levels"])
                text = "levels 1–%d: %d of %d within %s, %d outside (law %+.1f … %+.1f %%%s)" % (
                    len(per), sum(u.judgement == R.INSIDE for u in per), len(per), R.band_text(band),
                    sum(u.judgement == R.OUTSIDE for u in per), min(errs, default=math.nan),
                    max(errs, default=math.nan), "" if len(errs) == len(per) else
                    "; %d levels without a measurement" % (len(per) - len(errs)))
                inside = sum(u.judgement == R.INSIDE for u in per)
                units.append(R.Unit(label(row, v["units"]), text, j, why, "%d/%d" % (inside, len(per)),
                                    inside / len(per) if per else None))
    # Every unit by name: how many of its levels lie within the band.
    head = "levels within %s: %s" % (R.band_text(band), ", ".join(
        "%s %s" % (u.label, u.brief) if u.label else u.brief for u in units)) if units else ""
    return Measured(units, needs, [], head)


def level_means(levels, metric):
    return ([r[metric + "_mean"] for r in levels], [r[metric + "_se"] for r in levels],
            [(r.get(metric + "_clusters") or r.get(metric + "_n")) - 1 for r in levels])


def kind_peak_level(v, ctx):
    """Per unit: the level of the largest mean in every draw (each level's mean within its SE) and
    the next level's share of the peak."""
    units = []
    tol = v["tolerance"]
    target, max_drop = tol["level"], tol["max_drop"]
    metric = v["metric"]
    levels = levels_by_point(ctx, v["source"])
    for row in [r for r in ctx.tables.rows(v["source"]) if matches(r, v.get("select"))]:
        lv = levels.get(row["point"], [])
        means, ses, dofs = level_means(lv, metric)
        names = [r["level"] for r in lv]
        rng = random.Random(ctx.seed)
        hits, drops = 0, []
        for _ in range(ctx.draws):
            x = [m + (s * S.draw_error(rng, d) if s == s else 0.0) for m, s, d in zip(means, ses, dofs)]
            i = max(range(len(x)), key=x.__getitem__)
            if names[i] == target:
                hits += 1
                if i + 1 < len(x):
                    drops.append(x[i + 1] / x[i])
        share = hits / ctx.draws
        i = max(range(len(means)), key=means.__getitem__)
        drops.sort()
        a = (1 - ctx.level) / 2
        dlo, dhi = (S.percentile(drops, a), S.percentile(drops, 1 - a)) if drops else (math.nan, math.nan)
        drop = means[i + 1] / means[i] if i + 1 < len(means) else math.nan
        if share >= ctx.level and dhi <= max_drop:
            j, why = R.INSIDE, ""
        elif share <= 1 - ctx.level:
            j, why = R.OUTSIDE, "the peak is level %d" % names[i]
        elif drops and dlo > max_drop:
            j, why = R.OUTSIDE, "the next level keeps more than %g of the peak" % max_drop
        else:
            j, why = R.UNDECIDED, "peak at level %d in %.0f %% of draws" % (target, 100 * share)
        text = "peak at level %d (%s per replica; level %d in %.0f %% of draws); next level / peak %s" % (
            names[i], fmt(means[i]), target, 100 * share, est(drop, dlo, dhi, 3))
        brief = "peak at level %d, next / peak %s" % (names[i], est(drop, dlo, dhi, 3))
        units.append(R.Unit(label(row, v["units"]), text, j, why, brief, drop))
    return Measured(units, [], [], headline(units))


def radius_levels(levels, min_spheres, count="rays_level"):
    """The levels whose radius is nearest r_0·2^(−k), k = 1, 2, … down to the deepest level holding
    at least min_spheres spheres."""
    lv = counted_levels(levels, count, min_spheres)
    if not lv:
        return []
    r0 = next(r["radius"] for r in levels if r["level"] == 0)
    out, k = [], 1
    while True:
        target = math.log(r0 * 2.0 ** (-k))
        best = min(lv, key=lambda r: abs(math.log(r["radius"]) - target))
        if best["radius"] < r0 * 2.0 ** (-k) * math.sqrt(0.5) or best["level"] in [r["level"] for r in out]:
            break
        out.append(best)
        k += 1
    return out


def kind_level_ratio(v, ctx):
    """Per unit and per level of radius ≈ r_0·2^(−k): numerator / denominator (e.g. Hilbert /
    Morton misses), Fieller's interval on the smaller degrees of freedom."""
    units = []
    band = R.band_of(v["tolerance"])
    cmp, metric = v["compare"], v["metric"]
    levels = levels_by_point(ctx, v["source"])
    rows = [r for r in ctx.tables.rows(v["source"]) if matches(r, v.get("select"))]
    for _, g in group(rows, v["units"]):
        num = [r for r in g if show(r[cmp["column"]]) == cmp["numerator"]]
        den = [r for r in g if show(r[cmp["column"]]) == cmp["denominator"]]
        if len(num) != 1 or len(den) != 1:
            raise Missing("one %s and one %s row per unit in %s" % (cmp["numerator"], cmp["denominator"], v["source"]))
        ln, ld = levels[num[0]["point"]], levels[den[0]["point"]]
        byd = {r["level"]: r for r in ld}
        for r in radius_levels(ln, ctx.min_spheres):
            d = byd.get(r["level"])
            if d is None:
                continue
            a, sa = r[metric + "_mean"], r[metric + "_se"]
            b, sb = d[metric + "_mean"], d[metric + "_se"]
            dof = min(r[metric + "_clusters"], d[metric + "_clusters"]) - 1
            ratio, lo, hi, bounded = S.fieller(a, sa * sa, b, sb * sb, 0.0, S.t_for_level(ctx.level, dof))
            j, why = R.interval_judgement(lo, hi, band) if bounded else (R.UNDECIDED, "unbounded ratio")
            units.append(R.Unit("%s, level %d" % (label(num[0], v["units"]), r["level"]),
                                est(ratio, lo, hi, 3), j, why, "%s at level %d" % (est(ratio, lo, hi, 3), r["level"]),
                                ratio if bounded else None))
    return Measured(units, [], [], headline(units))
