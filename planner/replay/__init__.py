"""Re-simulation of an exported plan (Section 5.1): its commands replayed by the finite-motion simulator.

:mod:`.replay` (:func:`~.replay.replay_plan`) drives the hand with the exported commands at friction
vectors of the task's set; :mod:`.grasp` closes the fingers again between segments.
"""
