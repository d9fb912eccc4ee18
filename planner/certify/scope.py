"""What a certificate proves and what it does not cover, in words for the help texts and the plan card.

Strings only (the command line imports this to build its help: nothing heavy).
"""

__all__ = ["SCOPE", "SCOPE_SHORT"]

#: What a certificate proves, and what it does not cover (``qsplan verify --help``, ``qsplan replay --help``, the plan
#: card): the model's limits, which a MuJoCo replay samples (:data:`qsplan.planner.cli.replay.MUJOCO_ADDS`).
SCOPE = ("The certificate (qsplan verify) proves the exported rows in the quasistatic rigid-body model from the task "
         "alone: each row's contact mode the only one for every friction in the set, every torque inside its "
         "guaranteed band, the holds, geometry and timing. It does not cover compliance, servo stiffness, torque "
         "limits or dynamics between rows.")

#: The plan card's short form of :data:`SCOPE`.
SCOPE_SHORT = ("modes and torque bands proved in the rigid quasistatic model for every friction in the set; compliance, "
               "servo stiffness and dynamics not covered (qsplan replay --engine mujoco samples them)")
