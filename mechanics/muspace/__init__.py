"""mu-space (Section 4): which modes are feasible for which friction coefficients.

* :mod:`.multilinear` - multilinear polynomials in mu, ``det Q_AI`` and its adjugate by column expansion (eqs. 46-47)
* :mod:`.regions` - a mode's exact region ``{D > 0, P_i >= 0}`` or ``{D < 0, P_i <= 0}`` (eqs. 26, 28, 46-47)
* :mod:`.appendices` - Appendix A (3S, eqs. 34-36, 50-57) and Appendix B (RS, eqs. 39-41, 58-60)
* :mod:`.zero_sets` - exact zero sets of bilinear polynomials (the boundaries on a 2-D slice)
* :mod:`.maps` - feasible modes over many mu points (the solver's eqs. 26-28, or the multilinear forms)
* :mod:`.slices` - 2-D slices with their exact region boundaries (Figs. 3, 6, 8)
* :mod:`.graphical` - the graphical test of Corollary 1 (Section 4.1, Fig. 4)
"""
