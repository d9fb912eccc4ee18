"""Every feasible contact mode of a scene (Sections 3.1-3.2, 4.7), layered bottom to top.

* :mod:`.result` - :class:`SolveResult` (counts per status sum to eq. 49) and the merge of partial results
* :mod:`.batch` - one batch of modes through the kinematic and equilibrium stages (eqs. 23-28), and the in-process stream
* :mod:`.chunks` - the stream split into chunks of batches on local processes or a Dask cluster
* :mod:`.breaking_sets` - breaking sets that admit equilibrium (eqs. 17, 26, 28 relaxed), one LP each
* :mod:`.search` - the exact pruned search over those breaking sets
* :mod:`.all_modes` - the public :func:`solve`, choosing among the three
* :mod:`.many` - every mode's status at many friction vectors of one scene (the kinematic stage once):
  :func:`~.many.solve_many` and its per-vector reference; mu-space maps use it; and of many scenes at once
  (:func:`~.many.solve_many_scenes`, each scene's vectors with their own loads): the plan certifier
* :mod:`.lp` - one small linear programme on HiGHS directly (the certified holds), without ``scipy.optimize``
"""
