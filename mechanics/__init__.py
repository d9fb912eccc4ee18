"""qsplan.mechanics: the quasistatic contact model of Trinkle & Zeng (1995), Sections 3-4."""
