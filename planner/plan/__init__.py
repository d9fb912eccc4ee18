"""Plans (Section 5.2, Figs. 9-13): typed results, the phases that realise a route, the planners, failure reports.

* :mod:`.results` - :class:`~.results.Plan`, its segments and regrasps, :class:`~.results.PlanFailure`
* :mod:`.scripted` - :func:`~.scripted.plan_task` (the entry for every task and hand) and the scripted waypoints
* :mod:`.autoplan` - tasks with a ``[goal]``: the rows (grasps, and a hand's free joints along x), the widest
  route of their band tables, realised
* :mod:`.phases` - in-contact slides judged sample by sample, regrasps through OMPL, for any hand
* :mod:`.failure`, :mod:`.obstacles` - why a task has no plan: where the band closes, what blocks the route
"""
