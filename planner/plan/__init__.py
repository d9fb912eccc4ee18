"""Plans (Section 5.2, Figs. 9-13): typed results, the phases that realise a route, the planners, failure reports.

* :mod:`.results` - :class:`~.results.Plan`, its segments and regrasps, :class:`~.results.PlanFailure`
* :mod:`.scripted` - :func:`~.scripted.plan_task` (the entry for every task) and the scripted waypoints
* :mod:`.autoplan` - tasks with a ``[goal]``: the widest route of the band tables, realised
* :mod:`.phases` - in-contact slides judged sample by sample, regrasps through OMPL
* :mod:`.chain_plan`, :mod:`.chain_slide`, :mod:`.chain_states`, :mod:`.chain_regrasp` - described hands,
  planned on the contact manifold
* :mod:`.failure`, :mod:`.obstacles` - why a task has no plan: where the band closes, what blocks the route
"""
