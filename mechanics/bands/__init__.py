"""Effort bands (eq. 28, Section 5.2): one joint's efforts that keep a mode feasible, guaranteed over friction, competitors precluded."""
