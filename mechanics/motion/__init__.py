"""Finite quasistatic motions (Section 5.1): a mode held along a motion, events, mode switches.

* :mod:`.system` - the :class:`MotionSystem` protocol, per-contact :class:`Friction`, rigid-body rates
* :mod:`.conditions` - one mode's feasibility conditions as numbers (eqs. 15-16, 24-28, 32)
* :mod:`.events` - integrating in one mode and locating the first event (a condition's zero, a contact, a limit)
* :mod:`.trajectory` - the result: segments, events, why the motion stopped
* :mod:`.simulator` - :func:`simulate`: the mode selection rule at every event
"""
