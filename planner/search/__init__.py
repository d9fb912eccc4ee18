"""The search of a plan's sequence (issue 14): band tables over grasps and x, the widest route, OMPL.

:mod:`.tables` evaluates every candidate grasp along the palm (configurations, overlaps, joint
limits, guaranteed 4S bands with competitors precluded, batched); :mod:`.widest` finds the route
of slides and regrasps whose narrowest band is widest (exact at the tables' resolution);
:mod:`.ompl_search` runs it as an OMPL planner beside OMPL's sampling planners; :mod:`.ompl_bridge`
plans over a box of real variables (the regrasps, the slides of described hands). This is the only
package that imports ``ompl``.
"""
