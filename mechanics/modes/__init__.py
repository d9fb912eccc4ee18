"""Contact modes and the test of one mode (Sections 3.1-3.2).

* :mod:`.contact_mode` - :class:`ContactMode`, the letter codes (:class:`Letter`), enumeration and count (eqs. 12, 29, 49)
* :mod:`.counting` - the number of modes tested (eq. 49), numpy-free
* :mod:`.kinematics` - applicable rows (eq. 14), ``P_AI`` and its solve (eqs. 23-24), breaking and sliding tests (eqs. 15-16, 25), batched
* :mod:`.equilibrium` - ``Q_AI`` (eqs. 18-20, 26), efforts (eq. 27), sliding friction (eq. 17), Coulomb slacks (eq. 28), batched
* :mod:`.solution` - :class:`ModeSolution` and the residuals of the full model (eqs. 2-11)
* :mod:`.partition` - control-mode partitions (eqs. 30-32)
* :mod:`.reference` - the one-mode reference test (eqs. 12-28), an independent re-derivation
* :mod:`.planted` - seeded random scenes with a planted feasible mode
"""
