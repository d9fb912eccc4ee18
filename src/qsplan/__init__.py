"""qsplan: quasistatic planar contact-mode prediction and torque-band planning.

After Trinkle & Zeng (1995), *Prediction of the Quasistatic Planar Motion of a Contacted Rigid Body*.

* :mod:`qsplan.mechanics` - the quasistatic model: contact modes, the solver, mu-space, effort bands,
  finite motions (Sections 3-5).
* :mod:`qsplan.hands` - concrete hands and scenes (the paper's examples, the rod, the two-finger hand).
* :mod:`qsplan.planner` - planning two-finger tasks through OMPL, torque commands, export, plots, the CLI.

The repository keeps these as the top-level folders ``mechanics/``, ``hands/`` and ``planner/``; they
install as subpackages of this one (``pyproject.toml``: ``[tool.setuptools.package-dir]``).
"""

__version__ = "0.1.0"
