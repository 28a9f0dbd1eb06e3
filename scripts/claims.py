#!/usr/bin/env python3
"""The claims of both papers, judged from the committed result tables.

Reads results/*/NAME.csv (and side tables), computes each claim's measurement with its 95 % CI and
its verdict by the rule written beside it, and writes

  results/claims.toml      one [[claim]] per claim (the format `raycost report` reads, docs/report.md)
  README.md                the claims table between the markers <!-- claims:begin --> and <!-- claims:end -->

Derived figures (an optimum Q, a crossover ratio, a break-even frame) get their CI from a parametric
bootstrap over the per-point means and standard errors (each mean ~ Normal(mean, SE), 4000 draws,
fixed seed), which is valid because every point's replicas are independent of every other point's.

Usage:
  python3 scripts/claims.py            # rewrite results/claims.toml and README's table
  python3 scripts/claims.py --check    # exit 1 if either differs from what the tables give (CI)
"""

import argparse
import csv
import math
import os
import sys
import tomllib

from raycost_stats import bootstrap, break_even, ci95, crossing, dof, engine_cost_fits, frame0, optimum_q

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
RESULTS = os.path.join(ROOT, "results")
BEGIN, END = "<!-- claims:begin -->", "<!-- claims:end -->"


# ----------------------------------------------------------------------------------------------
# reading tables


def table(name, side=None):
    """Rows of results/NAME/NAME.csv (or NAME.SIDE.csv) as dicts of floats where they parse."""
    file = "%s.%s.csv" % (name, side) if side else "%s.csv" % name
    path = os.path.join(RESULTS, name, file)
    with open(path, newline="") as f:
        out = []
        for r in csv.DictReader(f):
            out.append({k: num(v) for k, v in r.items()})
        return out


def num(v):
    if v is None or v == "":
        return math.nan
    try:
        return float(v)
    except ValueError:
        return v


BUSY_CORES = 0.25  # raycost's own busy-machine threshold (src/output/meta.rs)


def timing(name):
    """Where a claim's seconds were taken: the CPU and the other processes' mean CPU use during the
    run, from results/NAME/NAME.meta.toml, and whether that run counts as quiet."""
    with open(os.path.join(RESULTS, name, "%s.meta.toml" % name), "rb") as f:
        meta = tomllib.load(f)
    cores = meta["run"].get("other_cores", math.nan)
    quiet = cores == cores and cores <= BUSY_CORES
    threads = meta["run"]["threads"]
    text = "seconds on %s, %d thread%s, other processes %.2f cores%s" % (
        meta["machine"]["cpu"], threads, "" if threads == 1 else "s", cores,
        "" if quiet else " (busy machine: seconds unreliable)")
    return text, quiet


def source(name, side=None):
    return "%s/%s.%s.csv" % (name, name, side) if side else "%s/%s.csv" % (name, name)


def where(rows, **kv):
    """Rows whose columns equal the given values (dots in keys written as __)."""
    out = []
    for r in rows:
        if all(close(r.get(k.replace("__", ".")), v) for k, v in kv.items()):
            out.append(r)
    return out


def close(a, b):
    if isinstance(a, float) and isinstance(b, (int, float)):
        return abs(a - b) <= 1e-9 * max(1.0, abs(b))
    return a == b


def one(rows, **kv):
    r = where(rows, **kv)
    if len(r) != 1:
        raise SystemExit("error: expected one row with %s, found %d" % (kv, len(r)))
    return r[0]


def estimate(row, metric):
    """(mean, se, n) of metric M from M_mean, M_se, M_n."""
    return row[metric + "_mean"], row[metric + "_se"], row[metric + "_n"]


def fmt(x, digits=4):
    if x != x:
        return "–"
    if x == 0:
        return "0"
    mag = math.floor(math.log10(abs(x)))
    if -3 <= mag <= 5:
        d = max(0, digits - 1 - mag)
        return ("%." + str(d) + "f") % x
    return ("%." + str(digits - 1) + "e") % x



def pow10(x):
    """10⁵ for 100000, 2.5·10⁵ for 250000, 2¹⁸ for 262144."""
    sup = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")
    two = math.log2(abs(x))
    if x >= 1024 and two == int(two):
        return "2" + str(int(two)).translate(sup)
    e = int(math.floor(math.log10(abs(x))))
    m = x / 10 ** e
    head = "" if abs(m - 1) < 1e-9 else ("%g·" % round(m, 3))
    return head + "10" + str(e).translate(sup)


def pm(mean, ci, digits=4):
    return "%s ± %s" % (fmt(mean, digits), fmt(ci, 2))


def interval(lo, hi, digits=3):
    return "[%s, %s]" % (fmt(lo, digits), fmt(hi, digits))


# ----------------------------------------------------------------------------------------------
# the claims: each returns a dict with claim, reference, paper, measured (text), value/ci (numbers or
# None), verdict, source, note


CLAIMS = []


def claim(fn):
    CLAIMS.append(fn)
    return fn


GRID = "Márton & Szirmay-Kalos"
DETP = "DETP paper"


@claim
def result_3_1():
    rows = table("grid-cell-width")
    inside = sum(1 for r in rows if r["n_i_mb_band"] == "inside")
    plain = sum(1 for r in rows if r["n_i_band"] == "inside")
    r = one(rows, scene__intensity=0.5, grid__eye="uniform", grid__cell_width=0.5)
    m, _, _ = estimate(r, "n_i_mb")
    ci = ci95(r, "n_i_mb")
    return dict(
        claim="E[N_I] lies in Result 3.1's band",
        reference=GRID + ", Result 3.1",
        paper="band [%s, %s] at ρ = 0.5, r = 0.1, a = 0.5" % (fmt(r["n_i_mb_lower"]), fmt(r["n_i_mb_upper"])),
        measured="%s; %d of %d points inside (mailboxed), %d of %d without a mailbox"
        % (pm(m, ci), inside, len(rows), plain, len(rows)),
        value=m, ci=ci,
        verdict="holds" if inside == len(rows) else "differs",
        source=source("grid-cell-width"),
        note="the band is a factor 7–23 wide; raycost's predictor lands within 0.1–4 % (docs/findings-grid.md)",
    )


@claim
def first_hit_mean():
    rows = table("grid-cell-width")
    z = [(r["t_hit_mean"] - r["t_hit_theory"]) / r["t_hit_se"] for r in rows]
    rms = math.sqrt(sum(x * x for x in z) / len(z))
    worst = max(z, key=abs)
    r = one(rows, scene__intensity=0.5, grid__eye="uniform", grid__cell_width=0.5)
    m, _, _ = estimate(r, "t_hit")
    ci = ci95(r, "t_hit")
    return dict(
        claim="first-hit distance: E[t*] = 1/(ρπr²)",
        reference=GRID + ", eq. 4",
        paper="%s at ρ = 0.5, r = 0.1" % fmt(r["t_hit_theory"]),
        measured="%s; over %d points rms z = %.2f, largest |z| = %.2f" % (pm(m, ci), len(rows), rms, abs(worst)),
        value=m, ci=ci,
        verdict="holds" if rms < 1.3 else "differs",
        source=source("grid-cell-width"),
        note="the largest |z| was replicated with 10⁶ rays under 4 seeds: chance (docs/findings-grid.md)",
    )


@claim
def first_hit_law():
    rows = table("grid-first-hit")
    ps = [r["t_hit_ks_p"] for r in rows]
    return dict(
        claim="t* is exponential: P(t* ≥ τ) = exp(−ρπr²τ)",
        reference=GRID + ", eq. 4",
        paper="exponential law",
        measured="KS p = %s at %d points (one independent scene per ray)" % (", ".join("%.2f" % p for p in ps), len(ps)),
        value=None, ci=None,
        verdict="holds" if min(ps) > 0.01 / len(ps) else "refuted",
        source=source("grid-first-hit"),
        note="",
    )


@claim
def cylinder_geometric():
    rows = table("grid-first-hit")
    ps = [r["n_i_mb_chi2_p"] for r in rows]
    return dict(
        claim="N_I is geometric (the cylinder model, eq. 9)",
        reference=GRID + ", eq. 9",
        paper="geometric law",
        measured="χ² p %s at every one of %d points" % ("< 10⁻³⁰⁰" if max(ps) == 0 else "≤ %s" % fmt(max(ps), 2), len(ps)),
        value=None, ci=None,
        verdict="refuted" if max(ps) < 0.001 else "holds",
        source=source("grid-first-hit"),
        note="the law belongs to the cylinder model; the grid's first cell adds a Poisson-like offset. The mean still follows raycost's predictor",
    )


@claim
def result_3_2():
    rows = table("grid-radius-classes")
    inside = sum(1 for r in rows if r["n_i_mb_band"] == "inside" and r["n_i_band"] == "inside")
    return dict(
        claim="E[N_I] with radius classes lies in Result 3.2's band",
        reference=GRID + ", Result 3.2",
        paper="integrated band",
        measured="%d of %d points inside (per-sphere and per-scene radii, with and without a mailbox)" % (inside, len(rows)),
        value=None, ci=None,
        verdict="holds" if inside == len(rows) else "differs",
        source=source("grid-radius-classes"),
        note="",
    )


@claim
def superoptimal():
    rows = table("grid-scaling")
    big = [r for r in rows if r["scene.spheres"] >= 1e5]
    theory = big[0]["n_i_mb_theory"]
    zs = [(r["n_i_mb_mean"] - theory) / r["n_i_mb_se"] for r in big]
    # Independent realisations per size (n_i_mb_clusters): the CI is Student-t on their count − 1.
    parts = ["%s: %s" % (pow10(r["scene.spheres"]), pm(r["n_i_mb_mean"], ci95(r, "n_i_mb"), 3)) for r in big]
    bf = sum(r["bf_mismatches"] for r in rows)
    return dict(
        claim="E[N_I] does not grow with n: O(1) expected query time",
        reference=GRID + ", §4",
        paper="independent of n (infinite-scene value %s)" % fmt(theory),
        measured="n = %s; brute force disagrees on %d rays" % ("; ".join(parts), bf),
        value=None, ci=None,
        verdict="holds" if max(abs(z) for z in zs) < 3 and bf == 0 else "differs",
        source=source("grid-scaling"),
        note="below n ≈ 10⁴ rays leave the finite cube and the counts are lower",
    )


@claim
def proposition_4_1():
    rows = table("grid-concentration")
    parts = []
    falls = True
    for c in sorted({r["scaling.c"] for r in rows}):
        g = sorted(where(rows, scaling__c=c), key=lambda r: r["scene.spheres"])
        p = [r["p_log_mean"] for r in g]
        falls &= all(b <= a for a, b in zip(p, p[1:]))
        parts.append("c = %g: %.3f → %.3f" % (c, p[0], p[-1]))
    n = sorted({r["scene.spheres"] for r in rows})
    return dict(
        claim="P(N_I ≥ c·log n) → 0 as n → ∞",
        reference=GRID + ", Proposition 4.1",
        paper="→ 0",
        measured="n = %s … %s: %s" % (pow10(n[0]), pow10(n[-1]), "; ".join(parts)),
        value=None, ci=None,
        verdict="holds" if falls else "differs",
        source=source("grid-concentration"),
        note="it falls at every c, slowly: c·log n stays below E[N_I] until n ≈ e²⁰ at r = 0.1",
    )


# ----------------------------------------------------------------------------------------------
# DETP


def levels_of(name, **kv):
    """The levels rows of the points of NAME whose main row matches kv, by level."""
    main = table(name)
    points = {r["point"] for r in where(main, **kv)}
    rows = [r for r in table(name, "levels") if r["point"] in points]
    return main, sorted(rows, key=lambda r: r["level"])


@claim
def rays_per_level():
    _, lv = levels_of("lines-rays-per-level", detp__q=0.6, detp__list_mode="exact")
    r9 = one(lv, level=9)
    m, se, n = estimate(r9, "rays_level_inside")
    _, lvi = levels_of("lines-rays-per-level", detp__q=0.6, detp__list_mode="inherited")
    i9 = one(lvi, level=9)
    mi, sei, _ = estimate(i9, "rays_level")
    z = (m - r9["rays_level_theory"]) / se
    return dict(
        claim="a level-i sphere holds n_R·Q^(2i) rays (uniform lines)",
        reference=DETP + ", §4.2 (integral geometry)",
        paper="%s at level 9, Q = 0.6, n_R = 2²⁰ (r_0 = 1 + d)" % fmt(r9["rays_level_theory"]),
        measured="exact lists, spheres inside the ball: %s (z = %+.1f); the paper's cache (inherited lists), all spheres: %s"
        % (pm(m, ci95(r9, "rays_level_inside")), z, pm(mi, ci95(i9, "rays_level"))),
        value=m, ci=ci95(r9, "rays_level_inside"),
        verdict="holds" if abs(z) < 3 else "differs",
        source=source("lines-rays-per-level", "levels"),
        note="a child rebuilt around a point sticks out of its parent, so inherited lists hold fewer rays than meet it",
    )


@claim
def level_nine():
    _, lv = levels_of("lines-rays-per-level", detp__q=0.6, detp__list_mode="inherited")
    r9 = one(lv, level=9)
    m, se, n = estimate(r9, "rays_level_leaf")
    mean_all, _, _ = estimate(r9, "rays_level")
    th = r9["rays_level_leaf_theory"]
    ci = ci95(r9, "rays_level_leaf")
    _, lve = levels_of("lines-rays-per-level", detp__q=0.6, detp__list_mode="exact")
    e9 = one(lve, level=9)
    me, see, _ = estimate(e9, "rays_level_leaf")
    ok = abs(m - 94.6) <= ci
    return dict(
        claim="level 9 holds 94.6 rays on average",
        reference=DETP + ", §4.2",
        paper="94.6",
        measured="the paper's cache: all level-9 spheres %s; the %d never subdivided (< 100 rays) %s; exact lists: never subdivided %s, against E[X | X < 100] = %s for X ~ Poisson(law)"
        % (fmt(mean_all), n, pm(m, ci), pm(me, ci95(e9, "rays_level_leaf")), fmt(th)),
        value=m, ci=ci,
        verdict="holds" if ok else "differs",
        source=source("lines-rays-per-level", "levels"),
        note="no natural convention gives 94.6 for the level mean; it is close to the mean of the spheres that are not subdivided",
    )


def misses(name, **kv):
    _, lv = levels_of(name, **kv)
    return ([r["level"] for r in lv], [r["misses_level_per_replica_mean"] for r in lv],
            [r["misses_level_per_replica_se"] for r in lv], [dof(r, "misses_level_per_replica") for r in lv])


@claim
def figure_9():
    lv, m, se, _ = misses("lines-cache-misses", detp__q=0.6, detp__order="morton", detp__points=1e6)
    peak = lv[m.index(max(m))]
    drop = m[m.index(max(m)) + 1] / max(m) if m.index(max(m)) + 1 < len(m) else math.nan
    return dict(
        claim="misses per level rise until level 9, then drop sharply (Q = 0.6, Lebesgue order)",
        reference=DETP + ", Figure 9",
        paper="peak at level 9",
        measured="peak at level %d (%s misses per run); the next level has %.0f %% of it"
        % (peak, fmt(max(m)), 100 * drop),
        value=peak, ci=None,
        verdict="holds" if peak == 9 and drop < 0.95 else "differs",
        source=source("lines-cache-misses", "levels"),
        note="the paper's cache, 10⁶ points, 4 replicas; with raycost's exact lists the drop is milder (their level-9 spheres hold 106.7 rays, above the threshold, so level 10 is built under more of them)",
    )


@claim
def figure_10():
    lh, mh, sh, dh = misses("lines-cache-misses", detp__q=0.9, detp__order="hilbert", detp__points=1e6)
    lm, mm, sm, dm = misses("lines-cache-misses", detp__q=0.9, detp__order="morton", detp__points=1e6)
    k = len(mh)
    peak, lo, hi = bootstrap(lambda x: max(x[:k]) / max(x[k:]), mh + mm, sh + sm, dofs=dh + dm)
    # Misses that start at each level: the first difference of the cumulative count.
    start_h = [b - a for a, b in zip([0] + mh, mh)]
    start_m = [b - a for a, b in zip([0] + mm, mm)]
    lows = []
    low_ratios = []
    kk = 1
    while True:
        level = round(kk * math.log(2) / -math.log(0.9))
        if level >= min(len(start_h), len(start_m)):
            break
        if start_m[level] > 0:
            low_ratios.append(start_h[level] / start_m[level])
            lows.append("L%d %.2f" % (level, low_ratios[-1]))
        kk += 1
    return dict(
        claim="Hilbert order has much smaller peaks than Lebesgue (Q = 0.9)",
        reference=DETP + ", Figure 10",
        paper="smaller peaks",
        measured="peak of misses per level, Hilbert/Morton: %s %s; misses that start at the levels of radius 2^(−k): Hilbert/Morton %s"
        % (fmt(peak, 3), interval(lo, hi), ", ".join(lows)),
        value=peak, ci=(hi - lo) / 2,
        verdict="holds" if hi < 0.9 else ("holds in part" if sum(r < 0.9 for r in low_ratios) * 2 >= len(low_ratios) else "differs"),
        source=source("lines-cache-misses", "levels"),
        note="the paper's cache (inherited lists), 10⁶ points, 4 replicas. Read as cumulative misses per level the overall peaks (deep levels, where both orders rebuild for nearly every point) are equal; read as misses starting at each level Hilbert is lower at most of the 2^(−k) levels, where the paper sees its local maxima",
    )


@claim
def proposition_1():
    main = table("sphere-cache-q")
    out = {}
    for mode in ("inherited", "exact"):
        rows = sorted(where(main, detp__list_mode=mode), key=lambda r: r["detp.q"])
        m = [r["tests_sphere_cache_per_replica_mean"] for r in rows]
        s = [r["tests_sphere_cache_per_replica_se"] for r in rows]
        d = [dof(r, "tests_sphere_cache_per_replica") for r in rows]
        out[mode] = bootstrap(optimum_q(rows), m, s, dofs=d)
    q, lo, hi = out["inherited"]
    qe, loe, hie = out["exact"]
    return dict(
        claim="the sphere cache's cost is smallest at Q = 2/3",
        reference=DETP + ", Proposition 1",
        paper="2/3",
        measured="counted tests, the paper's cache: Q* = %.2f %s; exact lists: %.2f %s"
        % (q, interval(lo, hi, 2), qe, interval(loe, hie, 2)),
        value=q, ci=(hi - lo) / 2,
        verdict="holds" if lo <= 2 / 3 <= hi else "differs",
        source=source("sphere-cache-q"),
        note="Q* from a quadratic fit of log(tests) over the five Q values around the minimum; CI by parametric bootstrap over four replicas per Q (the fit window is not in it). The minimum is flat: the paper's cache costs 2–3 % more at 2/3 than at 0.6",
    )

@claim
def theorem_1():
    main = table("detp-engines-cost")
    big = max(r["detp.photons"] for r in main)
    rows = where(main, detp__photons=big, detp__index="grid")
    r = max(rows, key=lambda r: r["detp.points"])
    reps = r["tests_sphere_cache_per_replica_n"]

    def ratio(row, total, per_replica, theory):
        """total / theory and the half-width of its 95 % CI (the per-replica SE scaled to the total)."""
        th = row[theory]
        return row[total] / th, ci95(row, per_replica) * row[per_replica + "_n"] / th

    sc = ratio(r, "tests_sphere_cache", "tests_sphere_cache_per_replica", "tests_sphere_cache_theory")
    di = ratio(r, "tests_disc_index", "tests_disc_index_per_replica", "tests_disc_index_theory")
    di_all = r["counted_cost_disc_index"] / r["tests_disc_index_theory"]
    ratios_sc = [x["tests_sphere_cache"] / x["tests_sphere_cache_theory"] for x in main]
    ratios_di = [x["counted_cost_disc_index"] / x["tests_disc_index_theory"] for x in main]
    fits = engine_cost_fits(main, table("detp-engines-cost", "levels"))
    (_, t, _, _), sc_res, _ = fits["sphere-cache"]  # c·segments + t·(ray–sphere tests) + …
    ns = lambda v, ci: "%.3g ns [%.3g, %.3g]" % (v * 1e9, ci[0] * 1e9, ci[1] * 1e9)  # noqa: E731
    seg = lambda v, ci: "%.3g µs [%.3g, %.3g]" % (v * 1e6, ci[0] * 1e6, ci[1] * 1e6)  # noqa: E731
    c_sc, t_ci = fits["sphere-cache"][0], fits["sphere-cache"][2]
    unused = [name for name, v in zip(("ray–disc tests", "rays copied into new lists"), c_sc[2:]) if v == 0]
    secs = ["sphere cache t = %s per ray–sphere test + %s per segment (fit residuals ≤ %.0f %%%s)"
            % (ns(t, t_ci[1]), seg(c_sc[0], t_ci[0]), 100 * max(abs(x) for x in sc_res),
               "; %s add nothing the fit can separate" % " and ".join(unused) if unused else "")]
    for name, (c, res, ci) in fits.items():
        if name != "sphere-cache":
            nodes = ("+ %s per node visited" % ns(c[2], ci[2]) if c[2] > 0
                     else "(nodes visited add nothing the fit can separate)")
            secs.append("%s u = %s per ray–disc test %s (≤ %.0f %%)" % (
                name, ns(c[1], ci[1]), nodes, 100 * max(abs(x) for x in res)))
    when, _ = timing("detp-engines-cost")
    return dict(
        claim="Theorem 1: sphere cache t·n_R/Q²·(∛n_P − 1)/(1 − Q) + (4/3)·u·n_R·∛n_P; disc index u·n_R·∛n_P",
        reference=DETP + ", Theorem 1",
        paper="counted / theory = 1 (t = u = 1)",
        measured="at n_R = %s, n_P = %s (grid index): sphere cache %s×; disc index %s× in ray–disc tests, %.1f× with its traversal (box tests, DDA steps); over the sweep sphere cache %.1f–%.1f×, disc index with traversal %.1f–%.1f×. Fitted to seconds: %s; %s"
        % (pow10(big), pow10(r["detp.points"]), pm(*sc, digits=3), pm(*di, digits=3), di_all, min(ratios_sc), max(ratios_sc),
           min(ratios_di), max(ratios_di), "; ".join(secs), when),
        value=sc[0], ci=sc[1],
        verdict="differs",
        source=source("detp-engines-cost"),
        note="constant factors; the decomposition of the sphere cache's excess (list mode, pop rule, point layout) is in docs/findings-detp.md. %d replicas per point; fit CIs by parametric bootstrap over the replicas' timings" % reps,
    )


def crossover(rows, metric):
    sc = sorted(where(rows, detp__engine="sphere-cache"), key=lambda r: r["dynamic.ratio"])
    di = sorted(where(rows, detp__engine="disc-index"), key=lambda r: r["dynamic.ratio"])
    xs = [r["dynamic.ratio"] for r in sc]
    k = len(sc)
    f = lambda v: crossing(xs, v[:k], v[k:])
    means = [r[metric + "_mean"] for r in sc] + [r[metric + "_mean"] for r in di]
    ses = [r[metric + "_se"] for r in sc] + [r[metric + "_se"] for r in di]
    dofs = [dof(r, metric) for r in sc + di]
    return bootstrap(f, means, ses, dofs=dofs)


def crossing_text(c):
    x, lo, hi = c
    if x != x:
        return "no crossing in 0.05–0.55"
    return "%.3f %s" % (x, interval(lo, hi, 3))


@claim
def theorem_2():
    main = table("quasi-static-crossover")
    feeds = sorted({r["dynamic.feed"] for r in main}) if "dynamic.feed" in main[0] else [None]
    parts = []
    found = {}
    for feed in feeds:
        rows = where(main, dynamic__feed=feed) if feed else main
        t = crossover(rows, "dynamic_s")
        c = crossover(rows, "dynamic_counted_cost")
        found[feed] = (t, c)
        parts.append("%s: seconds %s, counted %s" % (feed or "as run", crossing_text(t), crossing_text(c)))
    theory = main[0]["crossover_theory"]
    lo_th, hi_th = min(0.35, theory), max(0.35, theory)

    def agrees(x):
        """The CI of a crossover reaches the theorem's value (0.35, or its value at this n_D)."""
        return x[1] == x[1] and x[1] <= hi_th and x[2] >= lo_th

    # The theorem's own model is the paper's feed; its t and u are costs in time, so seconds test it
    # and the counted tests (t = u = 1) test its cost model.
    t, c = found.get("paper", found[feeds[0]])
    verdict = {(True, True): "holds", (True, False): "holds in seconds, not in counted tests",
               (False, True): "holds in counted tests, not in seconds", (False, False): "differs"}[(agrees(t), agrees(c))]
    reps = int(main[0].get("detp.replicas", 1))
    return dict(
        claim="Theorem 2: for dynamic points the sphere cache wins below r_D/r_0 ≈ 0.35, disc indexing above",
        reference=DETP + ", Theorem 2",
        paper="0.35 (%.2f at this n_D)" % theory,
        measured="crossover r_D/r_0 by feed — " + "; ".join(parts),
        value=None, ci=None,
        verdict=verdict,
        source=source("quasi-static-crossover"),
        note="feeds: paper = the sphere cache gets the segment index's answer and the disc index every segment (the theorem's model, judged); segment-index = both get that answer; all = both get every segment. CIs by parametric bootstrap over %d replicas (Student-t draws); %s" % (reps, timing("quasi-static-crossover")[0]),
    )


@claim
def amortisation():
    main = table("quasi-static-amortisation")
    frames = table("quasi-static-amortisation", "frames")
    parts = []
    lows = []
    for d in sorted({r["detp.disc_radius"] for r in main}):
        for n in sorted({r["detp.photons"] for r in main}):
            di = one(main, detp__disc_radius=d, detp__photons=n, detp__engine="disc-index")
            sc = one(main, detp__disc_radius=d, detp__photons=n, detp__engine="sphere-cache")
            a, b = frame0(frames, di["point"]), frame0(frames, sc["point"])
            f, lo, hi = bootstrap(break_even, [a[0], b[0], di["static_s_mean"], sc["static_s_mean"]],
                                  [a[1], b[1], di["static_s_se"], sc["static_s_se"]],
                                  dofs=[a[2] - 1, b[2] - 1, dof(di, "static_s"), dof(sc, "static_s")])
            lows.append(hi)
            parts.append("d = %g, %s photons: %s %s" % (d, pow10(n), fmt(f, 2), interval(lo, hi, 2)))
    return dict(
        claim="building the static disc index pays off after 180 to about 7000 frames",
        reference=DETP + ", §5 (the authors' earlier study)",
        paper="180 … 7000 frames",
        measured="break-even frame (frame 0 included) — " + "; ".join(parts),
        value=None, ci=None,
        verdict="differs" if max(lows) < 180 else "holds",
        source=source("quasi-static-amortisation"),
        note="raycost's index is a counting sort of discs into cells, cheap to build; the paper's build is not described; " + timing("quasi-static-amortisation")[0],
    )


@claim
def static_points():
    main = table("quasi-static-static-points")
    parts = []
    ratios = []
    for sp in sorted({r["detp.point_spacing"] for r in main}, reverse=True):
        sc = one(main, detp__point_spacing=sp, detp__engine="sphere-cache")
        di = one(main, detp__point_spacing=sp, detp__engine="disc-index")
        f = lambda x: x[0] / x[1]
        r, lo, hi = bootstrap(f, [sc["static_counted_cost_mean"], di["static_counted_cost_mean"]],
                              [sc["static_counted_cost_se"], di["static_counted_cost_se"]],
                              dofs=[dof(sc, "static_counted_cost"), dof(di, "static_counted_cost")])
        d = sc.get("detp.disc_radius", 10.0)
        ratios.append((lo, hi))
        parts.append("d/spacing = %g: %.1f %s" % (d / sp, r, interval(lo, hi, 2)))
    return dict(
        claim="static points: the sphere cache costs 4.04× the disc index (eqs. 13–14)",
        reference=DETP + ", eqs. 12–14",
        paper="4.04 (8.08 like for like: raycost's cache passes over old and new rays)",
        measured="counted cost per frame, sphere cache / disc index (traversal included) — " + "; ".join(parts),
        value=None, ci=None,
        verdict="holds" if any(lo <= 8.08 <= hi for lo, hi in ratios) else "differs",
        source=source("quasi-static-static-points"),
        note="disc indexing wins in counted cost, as the paper says; the ratio moves with d/spacing",
    )


@claim
def real_scene_levels():
    main = table("real-scene-levels")
    out = []
    within = {}
    for scene in sorted({r["detp.scene"] for r in main}):
        _, lv = levels_of("real-scene-levels", detp__scene=scene, detp__list_mode="inherited")
        lv = [r for r in lv if 1 <= r["level"] <= 9 and r["rays_level_n"] > 0]
        err = [100 * (r["rays_level_theory"] - r["rays_level_mean"]) / r["rays_level_mean"] for r in lv]
        name = scene.split("/")[-1].replace(".aff", "")
        within[name] = sum(abs(e) <= 5 for e in err)
        out.append("%s: %d of %d levels within 5 %% (law %+.0f … %+.0f %%)" % (name, within[name], len(err), min(err), max(err)))
    best = max(within, key=within.get)
    return dict(
        claim="rays per level in real scenes: the law is within 5 % in most levels",
        reference=DETP + ", §4.1, Figures 6–7",
        paper="< 5 % in most levels",
        measured="BART kitchen, the paper's cache, levels 1–9, error of the law relative to the measurement — " + "; ".join(out),
        value=None, ci=None,
        verdict="holds without the backdrop" if within[best] * 2 > 9 and best.endswith("no-garden") else ("holds" if within[best] * 2 > 9 else "differs"),
        source=source("real-scene-levels", "levels"),
        note="the kitchen's root sphere (6.04 m) encloses a garden backdrop 3.75 m outside the window; without it (root 3.52 m) the law holds at the middle levels and fails only at the deepest, where only rich parents get children. Cornell box: results/cornell-levels",
    )


@claim
def retraced_rays():
    main = table("quasi-static-frames")
    rows = where(main, detp__engine="disc-index")
    r = [(x["dynamic.ratio"], x["retraced_rays_mean"] / x["retraced_rays_theory"]) for x in rows]
    return dict(
        claim="rays re-traced per frame f_R = n_R·(r_D/r_0)² (eq. 11)",
        reference=DETP + ", eq. 11",
        paper="measured / f_R = 1",
        measured="Cornell box, a sphere circling under the light: measured / f_R = %s"
        % ", ".join("%.1f at %g" % (b, a) for a, b in r),
        value=None, ci=None,
        verdict="differs",
        source=source("quasi-static-frames"),
        note="eq. 11 assumes μ-random lines over the root sphere; the object circles where the photons are densest",
    )


@claim
def incremental_exact():
    total, checked = 0, 0
    best = 0.0
    for name in ("quasi-static-frames", "quasi-static-crossover", "quasi-static-static-points",
                 "quasi-static-amortisation", "predict-engine", "quasi-static-robots"):
        for r in table(name):
            total += r["full_mismatch"]
            checked += r["full_checked"]
            if name == "quasi-static-frames" and r["detp.engine"] == "disc-index":
                best = max(best, r["full_frame_s_mean"] / r["frame_s_mean"])
    return dict(
        claim="a quasi-static frame re-traces only the rays a moving object touches",
        reference=DETP + ", §3",
        paper="incremental recalculation",
        measured="incremental = full recalculation bit for bit: %d differing points in %d checked frames; up to %.0f× faster per frame (quasi-static-frames)"
        % (total, checked, best),
        value=None, ci=None,
        verdict="holds" if total == 0 else "refuted",
        source=source("quasi-static-frames"),
        note="raycost's exactness is by construction (integer sums, photons re-traced from their own streams); speed-up " + timing("quasi-static-frames")[0],
    )


def accuracy(name, label):
    main = table(name)
    big = max(r["detp.photons"] for r in main)
    rows = where(main, detp__photons=big)
    parts = []
    worst = 0.0
    for r in sorted(rows, key=lambda r: r["detp.disc_radius"]):
        ref = r["reference_irradiance_mean"]
        b, pb = r["irradiance_ref_bias_mean"], r["photon_map_ref_bias_mean"]
        worst = max(worst, abs(b) / ref)
        parts.append("d = %g: DETP %+.1f ± %.1f %%, photon map %+.1f ± %.1f %%" % (
            r["detp.disc_radius"], 100 * b / ref, 100 * ci95(r, "irradiance_ref_bias") / ref, 100 * pb / ref,
            100 * ci95(r, "photon_map_ref_bias") / ref))
    return big, parts, worst


@claim
def detp_unbiased():
    big_c, cornell, worst_c = accuracy("speed-vs-error-cornell", "Cornell box")
    big_k, kitchen, worst_k = accuracy("speed-vs-error", "kitchen")
    return dict(
        claim="DETP estimates irradiance from photon segments crossing a tangent disc of radius d",
        reference=DETP + ", §2",
        paper="density estimation on the tangent plane (bias O(d²) on smooth open surfaces)",
        measured="mean error against raycost's path-traced reference, relative to the mean irradiance — Cornell box (%s photons): %s; BART kitchen (%s photons): %s"
        % (pow10(big_c), "; ".join(cornell), pow10(big_k), "; ".join(kitchen)),
        value=None, ci=None,
        verdict="holds" if worst_c < 0.03 else "differs",
        source=source("speed-vs-error-cornell"),
        note="where a point's disc reaches past an edge into another solid (s < d) DETP is biased by tens of per cent and leaks light under objects; detp.edge = \"clamp-first-hit\" removes most of it (docs/hard-cases.md, results/detp-hard-cases)",
    )


# ----------------------------------------------------------------------------------------------
# output


def collect():
    out = []
    for fn in CLAIMS:
        try:
            out.append(fn())
        except FileNotFoundError as e:
            raise SystemExit("error: %s: %s (run the experiment first)" % (fn.__name__, e.filename))
    return out


def toml_str(s):
    return '"%s"' % s.replace("\\", "\\\\").replace('"', '\\"')


def render_toml(claims):
    lines = ["# The claims of both papers and what raycost measured for each. Written by",
             "# scripts/claims.py from the committed tables; do not edit by hand (CI checks it).", ""]
    for c in claims:
        lines.append("[[claim]]")
        lines.append("claim = %s" % toml_str(c["claim"]))
        lines.append("reference = %s" % toml_str(c["reference"]))
        lines.append("paper = %s" % toml_str(c["paper"]))
        lines.append("source = %s" % toml_str(c["source"]))
        # The measurement as the table states it (its CI inside the text), and the number alone
        # for tools, where there is one.
        lines.append("measured = %s" % toml_str(c["measured"]))
        lines.append("verdict = %s" % toml_str(c["verdict"]))
        if c["note"]:
            lines.append("note = %s" % toml_str(c["note"]))
        lines.append("")
    return "\n".join(lines)


def render_table(claims):
    rows = ["| claim | paper says | raycost measured (± 95 % CI) | verdict | table |",
            "|---|---|---|---|---|"]
    for c in claims:
        note = " — " + c["note"] if c["note"] else ""
        cells = [c["claim"] + " (" + c["reference"] + ")", c["paper"], c["measured"] + note]
        cells = [x.replace("|", "\\|") for x in cells]
        rows.append("| %s | %s | %s | **%s** | [%s](results/%s) |" % (
            cells[0], cells[1], cells[2], c["verdict"], c["source"].split("/")[0], c["source"]))
    return "\n".join(rows)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--check", action="store_true", help="fail if the committed files differ")
    args = ap.parse_args()
    claims = collect()
    toml_text = render_toml(claims)
    table_text = render_table(claims)
    readme_path = os.path.join(ROOT, "README.md")
    readme = open(readme_path).read()
    if BEGIN not in readme or END not in readme:
        raise SystemExit("error: README.md has no %s … %s markers" % (BEGIN, END))
    a, rest = readme.split(BEGIN, 1)
    _, b = rest.split(END, 1)
    new_readme = a + BEGIN + "\n" + table_text + "\n" + END + b
    toml_path = os.path.join(RESULTS, "claims.toml")
    old_toml = open(toml_path).read() if os.path.exists(toml_path) else ""
    if args.check:
        bad = []
        if old_toml != toml_text:
            bad.append("results/claims.toml")
        if new_readme != readme:
            bad.append("README.md's claims table")
        if bad:
            print("error: %s differ(s) from the committed tables: run python3 scripts/claims.py" % " and ".join(bad),
                  file=sys.stderr)
            return 1
        print("claims: %d claims, README and results/claims.toml match the tables" % len(claims))
        return 0
    open(toml_path, "w").write(toml_text)
    open(readme_path, "w").write(new_readme)
    for c in claims:
        print("%-60s %s" % (c["claim"][:60], c["verdict"]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
