"""The task (Section 5.2): what a plan must achieve, read from a file or built in code.

* :mod:`.task` - the frozen :class:`~qsplan.planner.task.task.Task`, :func:`~.task.load_task`,
  :func:`~.task.make_task`, the bundled tasks (:func:`~.task.task_paths`)
* :mod:`.fields` - the ``[hand]`` table, the plausible ranges of every task number, the plan's force margin
* :mod:`.goal` - where a task starts and ends: grasps named by workpiece features
* :mod:`.limits` - the joint ranges and speeds: the hand's own, narrowed by the task
"""
