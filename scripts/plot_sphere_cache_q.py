#!/usr/bin/env python3
"""Sphere-cache cost against Q (experiment sphere-cache-q; Proposition 1: optimum Q = 2/3).
Left: counted tests per replica (mean ± 95 % CI across replicas) for the paper's cache (inherited
lists) and raycost's exact lists, with Theorem 1's count T_R + T_I (t = u = 1); the optimum Q of each
is the registered statistic of claims/preregistered.toml (rule proposition-1): the minimum of a
weighted polynomial fit of log(cost) over the whole Q range, degree chosen by the fit rule in every
bootstrap draw, the interval widened by the fit's misfit; printed and marked. Right: seconds per
replica, same layout. A CSV without detp.list_mode (one list mode) is drawn as one series.
"""
import os
import tomllib

import raycost_plot as rp
from raycost_stats import Parametric, dof, optimum, t95

PREREG = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "claims", "preregistered.toml")


def registered_fit():
    """(degrees, alpha, draws, seed, level) of the optimum's registered rule."""
    with open(PREREG, "rb") as f:
        pre = tomllib.load(f)
    d = pre["defaults"]
    rule = next(c for c in pre["claim"] if c["statistic"] == "optimum")
    return rule.get("fit_degrees", d["fit_degrees"]), d["fit_alpha"], d["draws"], d["seed"], d["level"]

NAME = "sphere-cache-q"
REQUIRED = ["detp.q", "tests_sphere_cache_per_replica_mean", "tests_sphere_cache_per_replica_se",
            "tests_sphere_cache_per_replica_n", "cost_sphere_cache_per_replica_s_mean",
            "cost_sphere_cache_per_replica_s_se", "tests_sphere_cache_theory"]


def plot(args):
    rows = rp.read_csv(args.input, REQUIRED)
    key = "detp.list_mode" if rp.has(rows, "detp.list_mode") else None
    groups = rp.group_by(rows, key)[1] if key else {("as run",): rows}
    fig, axes = rp.subplots(1, 2, panel_w=6.0, panel_h=4.2)
    ax, ax_t = axes[0]
    lines = []
    for j, (value, grp) in enumerate(groups.items()):
        grp = rp.sort_by(grp, "detp.q")
        q = rp.col(grp, "detp.q")
        reps = grp[0]["tests_sphere_cache_per_replica_n"]
        z = t95(reps - 1)
        for a, stem in ((ax, "tests_sphere_cache_per_replica"), (ax_t, "cost_sphere_cache_per_replica_s")):
            m, s = rp.col(grp, stem + "_mean"), rp.col(grp, stem + "_se")
            a.errorbar(q, m, yerr=[z * x for x in s], fmt="o-", ms=4, lw=1, capsize=2, color="C%d" % j,
                       label="%s lists" % value[0])
            degrees, alpha, draws, seed, level = registered_fit()
            c = optimum(q, Parametric(m, s, [dof(r, stem) for r in grp]), degrees, alpha, draws, seed, level)
            best = c.interval.value
            a.axvline(best, color="C%d" % j, ls=":", lw=0.9)
            lines.append("%s lists, %s: optimum Q = %.3f [%.3f, %.3f] (95 %% CI; fit degree %d, misfit ×%.1f; "
                         "%.1f %% of draws with the minimum at an end; %d replicas)"
                         % (value[0], "tests" if a is ax else "seconds", best, c.lo, c.hi, c.fit.degree, c.misfit,
                            100 * c.interval.categories.get("edge", 0.0), reps))
        # Theorem 1's count is per replica times the replicas in the CSV: divide back.
        ax.plot(q, [r["tests_sphere_cache_theory"] / reps for r in grp], "-", color="black", lw=0.8,
                label="Theorem 1 (t = u = 1)" if j == 0 else None)
    for a in (ax, ax_t):
        a.axvline(2.0 / 3.0, color="0.4", ls="--", lw=0.9)
        a.set_xlabel("Q")
        a.legend(fontsize=7)
    rp.log_scale(ax, y=True)
    ax.set_ylabel("counted tests per replica")
    ax_t.set_ylabel("sphere-cache seconds per replica")
    rp.text_box(ax, "\n".join(l.split(" (95")[0] for l in lines if ", tests:" in l), fontsize=6)
    for l in lines:
        print(l)
    rp.finish(fig, args)


if __name__ == "__main__":
    rp.script(plot, __doc__, NAME)
