"""Finite quasistatic motions (Section 5.1): a mode's conditions along a motion, events, and the simulator."""
