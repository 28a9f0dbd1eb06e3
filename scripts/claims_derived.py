"""Derived figures a claim shows beside its verdict (`[[claim.derived]]`), never judged: seconds per
counted operation fitted with the cases resampled (the misfit inside the interval), and a quantity
split into factors averaged over every order of switching them (Shapley).
"""

import raycost_stats as S
from claims_data import Missing, matches, show


def derived_cost_fits(d, ctx):
    """Seconds per operation of each engine (raycost_stats.engine_cost_fits)."""
    fits = S.engine_cost_fits(ctx.tables.rows(d["source"]), ctx.tables.rows(d["source"], "levels"), ctx.draws)
    ns = lambda v, ci: "%.3g ns [%.3g, %.3g]" % (v * 1e9, ci[0] * 1e9, ci[1] * 1e9)  # noqa: E731
    parts = []
    for name, fit in fits.items():
        c, res, cis = fit.constants, fit.residuals, fit.cis
        names = (("per segment", "per ray–sphere test", "per ray–disc test", "per ray copied")
                 if name == "sphere-cache" else ("per segment", "per ray–disc test", "per node visited"))
        terms = ["%s %s" % (ns(v, ci), n) for v, ci, n in zip(c, cis, names) if v > 0]
        parts.append("%s: %s (misfit ≤ %.0f %%, inside the intervals: cases resampled%s)" % (
            name, " + ".join(terms), 100 * max(abs(x) for x in res),
            "; %.1f %% of draws unfit" % (100 * fit.undefined) if fit.undefined else ""))
    return "seconds fitted per operation — " + "; ".join(parts)


def derived_shapley(d, ctx):
    """Factors of quantity/theory switched from raycost's settings to the paper's, each the
    geometric mean over every order of switching (the range over orders beside)."""
    rows = [r for r in ctx.tables.rows(d["source"]) if matches(r, d.get("select"))]
    factors = d["factors"]

    def value(switched):
        want = {f["column"]: (f["to"] if f["label"] in switched else f["from"]) for f in factors}
        hit = [r for r in rows if all(show(r[k]) == v for k, v in want.items())]
        if len(hit) != 1:
            raise Missing("one row of %s with %s" % (d["source"], want))
        return hit[0][d["quantity"]] / hit[0][d["theory"]]

    labels = [f["label"] for f in factors]
    sh = S.shapley_factors(value, labels)
    start, end = value(frozenset()), value(frozenset(labels))
    parts = ["%s ×%.2f (%.2f–%.2f over orders)" % (k, v[0], v[1], v[2]) for k, v in sh.items()]
    return "%s / theory from raycost's settings to the paper's: %.2f → %.2f = %s (Shapley: averaged over every order; no SE in the table)" % (
        d["quantity"], start, end, " · ".join(parts))


DERIVED = {"cost-fits": derived_cost_fits, "shapley": derived_shapley}
