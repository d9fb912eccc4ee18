"""Independent second methods, each re-deriving the model on purpose so that tests compare two implementations.

* :mod:`.exact` - the one-mode test of eqs. (13)-(28) in rational arithmetic (ground truth)
* :mod:`.lp_check` - the force side of one mode (eqs. 26-28) as a linear programme
* :mod:`.lcp` - one feasible mode from a linear complementarity problem (eqs. 2-11 as an LCP)
* :mod:`.lemke` - Lemke's complementary pivoting for that LCP
"""
