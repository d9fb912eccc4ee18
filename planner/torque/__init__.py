"""Torque commands along a segment (Section 5.2, Figs. 10-13): band sweeps and the command rule."""
