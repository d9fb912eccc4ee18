"""Independent second methods: the exact rational test, the LP check of the force side, and the LCP solved by Lemke's method."""
