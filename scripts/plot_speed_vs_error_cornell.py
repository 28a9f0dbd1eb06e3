#!/usr/bin/env python3
"""Speed against error on the Cornell box against the path-traced reference (experiment
speed-vs-error-cornell): the same figure as plot_speed_vs_error.py, which documents it."""

import raycost_plot as rp
import plot_speed_vs_error

NAME = "speed-vs-error-cornell"

if __name__ == "__main__":
    rp.script(plot_speed_vs_error.plot, __doc__, NAME)
