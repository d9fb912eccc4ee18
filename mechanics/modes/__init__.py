"""Contact modes (eqs. 12, 29, 49), the one-mode reference test (Sections 3.1-3.2), solutions with residuals (eqs. 2-11), control-mode partitions (eq. 32)."""
