"""mu-space (Section 4): multilinear forms, exact regions (Appendices A and B), maps and slices, the graphical test (Corollary 1)."""
