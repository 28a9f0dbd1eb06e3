#!/usr/bin/env python3
"""E[N_I] and E[N_S] against the cell width for the quickstart experiment, measured vs theory.

The same figure as plot_grid_cell_width.py (Result 3.1's band, the sharper predictors, measured means
± 95 % CI, and E[N_S] with its deviation in standard errors), read from results/quickstart/quickstart.csv
by default.
"""

import sys

import plot_grid_cell_width
import raycost_plot as rp

if __name__ == "__main__":
    rp.run(lambda: plot_grid_cell_width.main(sys.argv[1:], name="quickstart", doc=__doc__))
