"""The statistics a pre-registered rule can name (`statistic = "…"` in claims/preregistered.toml).

Each kind reads the tables a claim lists, computes its statistic for every unit (a point, a level,
a scene, an index kind …) with a 95 % interval, and judges each unit by a generic rule of
claims_rules (an interval against the registered band, a p-value against two thresholds). Every
number that decides — bands, thresholds, levels, targets — comes from the claim's entry; a kind
knows only how to compute. A kind raises nothing for missing data: it returns what the tables lack
as `needs` (the claim is then inconclusive), with whatever could still be measured.
"""

import math
import re
from collections import namedtuple

import claims_rules as R
import raycost_stats as S
from claims_data import Missing, group, label, matches, quantity, show, short, terms_of

Measured = namedtuple("Measured", "units needs notes headline", defaults=("",))
Measured.__doc__ = """A kind's result: judged units, what the tables lack ("needs …" texts), notes
(fit, share of undefined draws, derived figures) for the measured column, and the headline: the
number (or interval) a reader compares with the paper's, with the unit count — presentation only,
written by each kind from its units (`headline`), never judged."""

HEADLINE_UNITS = 2  # a headline names up to this many units; more are counted and spanned


def fmt(x, digits=4):
    if x is None or x != x:
        return "–"
    if math.isinf(x):
        return "∞" if x > 0 else "−∞"
    if x == 0:
        return "0"
    mag = math.floor(math.log10(abs(x)))
    if -3 <= mag <= 5:
        return ("%." + str(max(0, digits - 1 - mag)) + "f") % x
    return ("%." + str(digits - 1) + "e") % x


def est(value, lo, hi, digits=4):
    return "%s [%s, %s]" % (fmt(value, digits), fmt(lo, digits), fmt(hi, digits))


def inside_count(units, what=""):
    """"k/n inside" (`what` after it) and how many are undecided, if any."""
    k = sum(u.judgement == R.INSIDE for u in units)
    u = sum(u.judgement == R.UNDECIDED for u in units)
    return "%d/%d inside%s%s" % (k, len(units), what, ", %d undecided" % u if u else "")


def span(units):
    """The briefs of the units of smallest and largest value (one when they coincide); "" when no
    unit has a value."""
    valued = [u for u in units if u.value is not None and u.value == u.value]
    if not valued:
        return ""
    a = min(valued, key=lambda u: u.value)
    b = max(valued, key=lambda u: u.value)
    if a.brief == b.brief:
        return a.brief
    # The words before the number ("share ", "drift slope ") once: "share 0.05 […] … 0.67 […]".
    words = re.match(r"[^\d+\-−]*", a.brief).group(0)
    return "%s … %s" % (a.brief, b.brief[len(words):] if b.brief.startswith(words) else b.brief)


def counted_span(units):
    return "; ".join(x for x in (inside_count(units), span(units)) if x)


def headline(units, groups=None):
    """A kind's headline from its judged units: up to HEADLINE_UNITS units each by label and brief;
    more as the count inside and the span of their values. With `groups` ([(name, units)], e.g. a
    claim's series) each group so, named: one unit by its brief, several counted and spanned."""
    if groups is not None:
        parts = []
        for name, us in groups:
            if us:
                body = us[0].brief or us[0].text if len(us) == 1 else counted_span(us)
                parts.append("%s: %s" % (name, body) if name else body)
        return "; ".join(parts)
    if len(units) <= HEADLINE_UNITS:
        return "; ".join("%s: %s" % (u.label, u.brief or u.text) if u.label else u.brief or u.text for u in units)
    return counted_span(units)


def series_groups(v, per_series):
    """The groups a headline shows: one per registered series (by its label), none without series."""
    if "series" not in v:
        return None
    return [(s.get("label", ""), us) for s, us in zip(v["series"], per_series)]


def sources_of(v):
    if "sources" in v:
        return list(v["sources"])
    if "series" in v:
        return [s["source"] for s in v["series"]]
    return [v["source"]]


def series_of(v):
    """A claim's series (each with its own source), or the claim itself as its only series."""
    return v["series"] if "series" in v else [v]


def t_ci(mean, se, dof, level):
    if se != se:
        return mean, mean  # no SE in the table: the value stands as exact
    h = S.t_for_level(level, dof) * se
    return mean - h, mean + h


def rows_of(ctx, s):
    """The rows of a series' source (a side table joined to its main rows), selected."""
    name = s["source"]
    rows = ctx.tables.joined(name, s["side"]) if s.get("side") else ctx.tables.rows(name)
    return [r for r in rows if matches(r, s.get("select"))]


def terms(ctx, v, s):
    """The {column: weight} a series measures: its `quantity`, or its `cost` in the accounting."""
    if s.get("quantity"):
        return s["quantity"]
    if v.get("quantity"):
        return v["quantity"]
    return terms_of(ctx, s.get("cost", v.get("cost")), v["accounting"])


# ----------------------------------------------------------------------------------------------
# bands, goodness of fit, p-values


def kind_band(v, ctx):
    """Every row × metric: the mean's interval against the row's own band [M_lower, M_upper]."""
    units = []
    for r in rows_of(ctx, v):
        for m in v["metrics"]:
            mean, se, dof = quantity(r, {m: 1}, v["source"])
            lo, hi = t_ci(mean, se, dof, ctx.level)
            band = (r[m + "_lower"], r[m + "_upper"])
            j, why = R.interval_judgement(lo, hi, band)
            units.append(R.Unit(label(r, v.get("units", [])) + " " + m, "%s in %s" % (
                est(mean, lo, hi), R.band_text(band)), j, why))
    return Measured(units, [], [], inside_count(units, " their bands"))


def kind_z_gof(v, ctx):
    """Σ of normal scores² of (mean − theory)/SE over every row against χ² on the row count."""
    m = v["metric"]
    zs = []
    for r in rows_of(ctx, v):
        mean, se, dof = quantity(r, {m: 1}, v["source"])
        zs.append(S.normal_score((mean - r[m + "_theory"]) / se, dof))
    chi2 = sum(z * z for z in zs)
    p = S.chi2_sf(chi2, len(zs))
    tol = v["tolerance"]
    j, why = R.p_judgement(p, tol["alpha_hold"], tol["alpha_reject"])
    text = "%d points: Σz² = %.1f on %d dof, p = %.2g; rms z = %.2f, largest |z| = %.2f" % (
        len(zs), chi2, len(zs), p, math.sqrt(chi2 / len(zs)), max(abs(z) for z in zs))
    brief = "p = %.2g (Σz² = %.1f on %d points)" % (p, chi2, len(zs))
    units = [R.Unit(m, text, j, why, brief, p)]
    return Measured(units, [], [], headline(units))


def kind_p_values(v, ctx):
    """A column of p-values, Bonferroni over the rows (k·min p, at most 1)."""
    ps = [r[v["column"]] for r in rows_of(ctx, v)]
    p = min(1.0, len(ps) * min(ps))
    tol = v["tolerance"]
    j, why = R.p_judgement(p, tol["alpha_hold"], tol["alpha_reject"])
    text = "p = %s at %d points; Bonferroni k·min p = %.2g" % (
        ", ".join("%.2g" % x for x in ps), len(ps), p)
    units = [R.Unit(v["column"], text, j, why, "Bonferroni p = %.2g over %d points" % (p, len(ps)), p)]
    return Measured(units, [], [], headline(units))


# ----------------------------------------------------------------------------------------------
# slopes and values


def in_domain(r, domain):
    if not domain:
        return True
    x = r.get(domain["column"])
    return isinstance(x, float) and domain.get("min", -math.inf) <= x <= domain.get("max", math.inf)


def slope_unit(xs, q, fit, ctx):
    """The slope of log(mean) against log(x): (value, lo, hi, note). `fit` registers the weights
    ("se": 1/variance; "equal": every x alike) and the misfit ("birge": the line's Birge ratio
    widens the interval; "report": the largest residual is shown beside it)."""
    weights = fit.get("weights", "se")
    sampler = S.Parametric([a for a, _, _ in q], [b for _, b, _ in q], [c for _, _, c in q])
    lx = [math.log(x) for x in xs]
    # Variances of log(mean) for "se" weights; NaN makes polyfit weigh every x alike.
    w = [((b / a) ** 2 if b == b else 0.0) if weights == "se" else math.nan for a, b, _ in q]

    def f(means, _var):
        if min(means) <= 0:
            return math.nan
        return S.wls_line(lx, [math.log(m) for m in means], w)[1]
    iv = S.bootstrap(f, sampler, ctx.draws, ctx.seed, ctx.level)
    a0, b0, chi2, rdof = S.wls_line(lx, [math.log(a) for a, _, _ in q], w)
    if fit.get("misfit", "birge") == "birge":
        k = max(1.0, math.sqrt(chi2 / rdof)) if rdof > 0 and chi2 == chi2 and weights == "se" else 1.0
        lo, hi = S.scale_interval(iv.value, iv.lo, iv.hi, k)
        return iv.value, lo, hi, "; misfit ×%.2f" % k if k > 1 else ""
    res = max(abs(math.log(a) - (a0 + b0 * x)) for (a, _, _), x in zip(q, lx))
    return iv.value, iv.lo, iv.hi, "; curvature beside the line ≤ %.3f in log" % res


def kind_slope(v, ctx):
    """Per unit, the slope of log(quantity) — or of log(quantity ÷ theory), the drift from a closed
    form — against log(x) over the rows in the domain, judged against the band."""
    units, per_series = [], []
    band = R.band_of(v["tolerance"])
    for s in series_of(v):
        per_series.append([])
        rows = [r for r in rows_of(ctx, s) if in_domain(r, v.get("domain"))]
        t = {v["metric"]: 1} if v.get("metric") else terms(ctx, v, s)
        for key, g in group(rows, s.get("units", v.get("units", []))):
            g = sorted(g, key=lambda r: r[v["x"]])
            name = label(g[0], s.get("units", v.get("units", [])), s.get("label", ""))
            xs = [r[v["x"]] for r in g]
            if len(xs) < 3:
                units.append(R.Unit(name, "fewer than 3 points", R.UNDECIDED, "fewer than 3 points",
                                    "fewer than 3 points"))
                per_series[-1].append(units[-1])
                continue
            q = [quantity(r, t, s["source"]) for r in g]
            extra = ""
            if s.get("theory"):
                th = [theory_value(r, s, s["source"]) for r in g]
                raw = slope_unit(xs, q, v.get("fit", {}), ctx)[0]
                exact = [(x, math.nan, math.nan) for x in th]
                extra = " (cost %.3f, closed form %.3f)" % (raw, slope_unit(xs, exact, {"misfit": "report"}, ctx)[0])
                q = [(a / x, b / x, c) for (a, b, c), x in zip(q, th)]
            val, lo, hi, note = slope_unit(xs, q, v.get("fit", {}), ctx)
            j, why = R.interval_judgement(lo, hi, band)
            text = "%sslope %s over %s = %s … %s%s%s" % (
                "drift from the closed form: " if s.get("theory") else "", est(val, lo, hi, 3),
                short(v["x"]), show(xs[0]), show(xs[-1]), extra, note)
            brief = "%sslope %s" % ("drift " if s.get("theory") else "", est(val, lo, hi, 3))
            units.append(R.Unit(name, text, j, why, brief, val))
            per_series[-1].append(units[-1])
    return Measured(units, [], [], headline(units, series_groups(v, per_series)))


def theory_value(r, s, source):
    if not s.get("theory"):
        return 1.0
    th, _, _ = quantity(r, s["theory"], source)
    return th


def kind_value(v, ctx):
    """Per row of every series: the quantity (÷ its theory, if given) against the band."""
    units, needs, per_series = [], [], []
    band = R.band_of(v["tolerance"])
    for s in series_of(v):
        per_series.append([])
        try:
            rows = rows_of(ctx, s)
            t = terms(ctx, v, s)
            for r in rows:
                mean, se, dof = quantity(r, t, s["source"])
                th = theory_value(r, s, s["source"])
                lo, hi = t_ci(mean, se, dof, ctx.level)
                val, lo, hi = mean / th, lo / th, hi / th
                j, why = R.interval_judgement(lo, hi, band)
                text = est(val, lo, hi, 3) + ("" if se == se else " (no SE in the table)")
                units.append(R.Unit(label(r, s.get("units", []), s.get("label", "")), text, j, why,
                                    est(val, lo, hi, 3), val))
                per_series[-1].append(units[-1])
            if not rows:
                needs.append("rows %s in %s" % (s.get("select", {}), s["source"]))
        except Missing as e:
            needs.append(str(e))
    return Measured(units, needs, [], headline(units, series_groups(v, per_series)))


def kind_share(v, ctx):
    """Per row: part ÷ whole (e.g. traversal's share of the counted cost), against the band."""
    units, needs, per_series = [], [], []
    band = R.band_of(v["tolerance"])
    for s in series_of(v):
        per_series.append([])
        try:
            for r in rows_of(ctx, s):
                a, sa, da = quantity(r, s["part"], s["source"])
                b, sb, db = quantity(r, s["whole"], s["source"])
                if sa == sa and sb == sb:
                    sampler = S.Parametric([a, b], [sa, sb], [da, db])
                    iv = S.bootstrap(lambda m, _v: m[0] / m[1], sampler, ctx.draws, ctx.seed, ctx.level)
                    val, lo, hi, note = iv.value, iv.lo, iv.hi, ""
                else:
                    val = lo = hi = a / b
                    note = " (no SE in the table)"
                j, why = R.interval_judgement(lo, hi, band)
                units.append(R.Unit(label(r, s.get("units", []), s.get("label", "")),
                                    est(val, lo, hi, 3) + note, j, why, "share " + est(val, lo, hi, 3), val))
                per_series[-1].append(units[-1])
        except Missing as e:
            needs.append(str(e))
    return Measured(units, needs, [], headline(units, series_groups(v, per_series)))


def kind_zero_count(v, ctx):
    """Per table: Σ count over Σ checked; 0 of > 0 checked is inside, any count outside."""
    units, needs = [], []
    differing = all_checked = 0
    for name in sources_of(v):
        try:
            rows = ctx.tables.rows(name)
        except Missing as e:
            needs.append(str(e))
            continue
        n = sum(r[v["count"]] for r in rows)
        checked = sum(r[v["checked"]] for r in rows)
        differing, all_checked = differing + n, all_checked + checked
        if checked <= 0:
            j, why = R.UNDECIDED, "nothing checked"
        else:
            j, why = (R.INSIDE, "") if n == 0 else (R.OUTSIDE, "%d differ" % n)
        units.append(R.Unit(name, "%d differing of %d checked" % (n, checked), j, why))
    return Measured(units, needs, [], "%d differing of %d checked in %d tables" % (differing, all_checked, len(units)))
