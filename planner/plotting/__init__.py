"""Plots for people: one style module and one module per kind of figure. Compute lives elsewhere; these only draw."""
