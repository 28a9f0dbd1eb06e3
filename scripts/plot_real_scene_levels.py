#!/usr/bin/env python3
"""Rays per sphere-cache level in the BART kitchen against the uniform-line law (experiment
real-scene-levels; the paper's Figures 6–7). Same figure as cornell-levels: rays held by a level-i
sphere with n_R·(r_i/r_0)², and the law's percentage error per level with the paper's ±5 %.
"""

import raycost_plot as rp
from plot_cornell_levels import plot

if __name__ == "__main__":
    rp.script(plot, __doc__, "real-scene-levels")
