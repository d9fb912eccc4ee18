"""Effort bands (eq. 28, Section 5.2): one joint's efforts that keep a mode feasible.

* :mod:`.effort` - the band at one friction: Coulomb slacks affine in the effort (eqs. 26, 28)
* :mod:`.guaranteed` - over uncertain friction: guaranteed (box vertices, shared-mu roots), possible, sampled
* :mod:`.preclusion` - competing modes precluded over uncertain friction (Figs. 12-13)
* :mod:`.cells` - a competitor's control values on cells of the friction set (times the wrench box), for the search
* :mod:`.certificates` - a competitor proved infeasible on a whole friction cell by one combination of its rows
* :mod:`.robust` - the guaranteed band of one scene with every competitor precluded (Fig. 13)
* :mod:`.disturbance` - a box of disturbance wrenches on the workpiece every band above may be asked to withstand
  (``disturbance=``; the paper's ref. [39]): why the vertex argument extends, and where a projection needs the search
* :mod:`.hold` - certified holds: nothing moves while the hand holds still and ramps a torque, for every friction
* :mod:`.batched`, :mod:`.batched_modes`, :mod:`.batched_preclusion`, :mod:`.batched_robust` - the same for a
  batch of states (and many modes) at once, bit-identical and fast; :func:`.batched_robust.robust_band_arrays`
  gives the numbers alone (the band tables)
"""
