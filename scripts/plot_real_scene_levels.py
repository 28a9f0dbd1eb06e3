#!/usr/bin/env python3
"""Rays per sphere-cache level in the BART kitchen, with and without its garden backdrop, against the
uniform-line law (experiment real-scene-levels; the paper's Figures 6–7). Same figure as cornell-levels:
measured rays per level, the raw law and the §4.1 calibrated law, and both errors relative to the
measurement.
"""
import raycost_plot as rp
from plot_cornell_levels import extra, plot

if __name__ == "__main__":
    rp.script(plot, __doc__, "real-scene-levels", extra=extra)
