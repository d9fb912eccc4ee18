"""Re-simulation of an exported plan (Section 5.1): its commands replayed by the finite-motion simulator.

:mod:`.replay` (:func:`~.replay.replay_plan`) drives the hand with the exported commands at friction
vectors of the task's set (:mod:`qsplan.hands.chains.reclose` closes the fingers again between segments).
:mod:`.mujoco_scene` writes the task's scene for MuJoCo (``scene.xml`` beside each plan) and
:mod:`.mujoco_replay` (:func:`~.mujoco_replay.replay_mujoco`) executes the exported commands in MuJoCo
(``qsplan replay PLAN_DIR --engine mujoco``; ``pip install '.[sim]'``).
"""
