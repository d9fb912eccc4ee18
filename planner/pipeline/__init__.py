"""The planning pipeline in one call (:func:`~.run.run_plan`): plan, export, certify, re-simulate, plot, publish."""
