"""The paper's example scenes and motion systems (Sections 4.1, 4.3, 5.1).

* :mod:`.paper` - the scenes of eqs. 37 and 42 and the rod of Fig. 7, in the raw scene form
* :mod:`.rod` - the rod on two moving supports (Figs. 7-8) as a finite-motion system, with its closed form
* :mod:`.pushing` - a polygon pushed across a floor by a point finger (contacts appearing)
"""
