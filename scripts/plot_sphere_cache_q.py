#!/usr/bin/env python3
"""Sphere-cache cost against Q (experiment sphere-cache-q; Proposition 1: optimum Q = 2/3).
Left: counted tests per replica (mean ± 95 % CI across replicas) for the paper's cache (inherited
lists) and raycost's exact lists, with Theorem 1's count T_R + T_I (t = u = 1); the optimum Q of each
with its bootstrap CI is printed and marked. Right: seconds per replica, same layout. A CSV without
detp.list_mode (one list mode) is drawn as one series.
"""
import raycost_plot as rp
from raycost_stats import bootstrap, dof, optimum_q, t95

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
            best, lo, hi = bootstrap(optimum_q(grp), m, s, dofs=[dof(r, stem) for r in grp])
            a.axvline(best, color="C%d" % j, ls=":", lw=0.9)
            lines.append("%s lists, %s: optimum Q = %.3f [%.3f, %.3f] (95 %% bootstrap CI, %d replicas)"
                         % (value[0], "tests" if a is ax else "seconds", best, lo, hi, reps))
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
