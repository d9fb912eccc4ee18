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


def lazy_attributes(package: str, table: dict, namespace: dict):
    """A module-level ``__getattr__`` (PEP 562) that imports ``table[name]`` on first access.

    Used by the subpackages' ``__init__`` so that ``import qsplan.mechanics`` stays light: heavy
    modules (shapely, scipy, matplotlib, OMPL) load only when one of their public names is used.

    Parameters
    ----------
    package : str
        The package's ``__name__`` (for the error message).
    table : dict[str, str]
        Public name -> fully qualified module that defines it.
    namespace : dict
        The package's ``globals()``: a loaded name is stored there, so it is imported once.
    """

    def __getattr__(name):
        if name in table:
            import importlib

            value = getattr(importlib.import_module(table[name]), name)
            namespace[name] = value
            return value
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    return __getattr__
