#!/usr/bin/env python3
"""Theorem 1's re-building excess decomposed (experiment theorem1-decomposition).

Left: spheres rebuilt per level, m_i (misses_level, all replicas), over the paper's model Q^(−3i)
(misses_level_theory), for each of the 8 combinations of list mode × pop rule × point layout.
Right: total ray–sphere tests (T_R's work) over Theorem 1's T_R for each combination.
Printed: the factor of each switch along the path raycost's former set-up (exact, chain, ball) →
the paper's pop rule → inherited lists → eq. 4's grid layout, whose product is the total ratio
between the two ends (it telescopes), per level and for T_R. Each sweep point draws its own lines
and points (keyed by the point index), so a factor near 1 is within the replicas' noise.
"""

import raycost_plot as rp

NAME = "theorem1-decomposition"
KEYS = ("detp.list_mode", "detp.pop_rule", "detp.point_source")
REQUIRED = ["level", "misses_level", "misses_level_theory", "rays_copied_level"]
MAIN = ["ray_sphere_tests", "ray_sphere_tests_theory", "spheres_built", "rays_copied", "pop_repairs"]
PATH = [("exact", "chain", "ball"), ("exact", "paper", "ball"),
        ("inherited", "paper", "ball"), ("inherited", "paper", "grid")]


def key(r):
    return tuple(r[k] for k in KEYS)


def plot(args):
    main, levels = rp.with_params(args.input, "levels", REQUIRED)
    rp.require_columns(args.input, main[0].keys(), MAIN + list(KEYS))
    by_cfg = {key(r): r for r in main}
    lv = {}
    for r in levels:
        lv.setdefault(key(r), {})[int(r["level"])] = r
    fig, axes = rp.subplots(1, 2, panel_w=6.2, panel_h=4.4)
    ax, ax_t = axes[0]
    cfgs = sorted(by_cfg)
    for n, c in enumerate(cfgs):
        rows = [lv[c][i] for i in sorted(lv[c]) if i > 0 and lv[c][i]["misses_level"] > 0]
        ax.plot([r["level"] for r in rows],
                [r["misses_level"] / r["misses_level_theory"] for r in rows],
                "o-", ms=3, lw=0.9, color="C%d" % n, label="/".join(c))
    rp.log_scale(ax, y=True)
    ax.set_xlabel("level i")
    ax.set_ylabel("m_i / Q^(−3i)")
    ax.legend(fontsize=6)
    ratio = [by_cfg[c]["ray_sphere_tests"] / by_cfg[c]["ray_sphere_tests_theory"] for c in cfgs]
    ax_t.bar(range(len(cfgs)), ratio, color=["C%d" % n for n in range(len(cfgs))])
    ax_t.set_xticks(range(len(cfgs)))
    ax_t.set_xticklabels(["/".join(c) for c in cfgs], rotation=60, ha="right", fontsize=6)
    ax_t.set_ylabel("ray–sphere tests / Theorem 1's T_R")
    lines = []
    if all(p in by_cfg for p in PATH):
        tr = [by_cfg[p]["ray_sphere_tests"] for p in PATH]
        factors = [b / a for a, b in zip(tr, tr[1:])]
        lines.append("T_R path: " + " × ".join("%.3f" % f for f in factors)
                     + " = %.3f (end/start %.3f)" % (_prod(factors), tr[-1] / tr[0]))
        print(lines[-1])
        common = set.intersection(*(set(lv[p]) for p in PATH))
        for i in sorted(common):
            m = [lv[p][i]["misses_level"] for p in PATH]
            if i == 0 or min(m) == 0:
                continue
            f = [b / a for a, b in zip(m, m[1:])]
            print("level %2d: m_i %s, factors %s, product %.3f, model Q^(-3i) %.1f, start/model %.2f, end/model %.2f"
                  % (i, m, " × ".join("%.3f" % x for x in f), _prod(f),
                     lv[PATH[0]][i]["misses_level_theory"],
                     m[0] / lv[PATH[0]][i]["misses_level_theory"],
                     m[-1] / lv[PATH[-1]][i]["misses_level_theory"]))
    rp.text_box(ax_t, "\n".join(lines) or "path incomplete", fontsize=6)
    rp.finish(fig, args)


def _prod(xs):
    p = 1.0
    for x in xs:
        p *= x
    return p


if __name__ == "__main__":
    rp.script(plot, __doc__, NAME)
