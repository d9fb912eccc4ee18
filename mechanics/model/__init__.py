"""The model of one instant (Section 3): contact frames and wrenches (eq. 1), the manipulator (eqs. 3, 5), scenes and their files."""
