#!/usr/bin/env python3
"""Result 3.2 (radius classes), measured vs theory (experiment grid-radius-classes).

Top row: E[N_I] against the cell width a (log-log), without mailboxing (n_i) and with it (n_i_mb), as
mean ± 95 % CI; the band of Result 3.2 (per-class bounds integrated over the radius densities,
n_i_lower..n_i_upper) shaded; the sharper predictors n_i_theory and n_i_mb_theory as lines and
n_i_plain_theory dashed. Middle and bottom rows: E[N_S] against n_s_theory and the deviation in
standard errors. One column per scene.radius_draw value (radii drawn per sphere, or once per class per
scene; the latter has a much larger spread between scenes, hence wider error bars).
"""

import sys

import plot_grid_cell_width
import raycost_plot as rp

NAME = "grid-radius-classes"

if __name__ == "__main__":
    args = rp.parse_args(__doc__, NAME, argv=sys.argv[1:])
    rp.run(lambda: plot_grid_cell_width.plot(
        args, title=NAME, x="a", group_keys=("scene.radius_draw", "scene.intensity", "grid.eye"),
        band_name="Result 3.2"))
