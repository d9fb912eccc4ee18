"""The architecture of qsplan, asserted: one package, layered modules, public names between modules.

An AST walk over the source (no import of the code under test):

* the import graph between the project's modules, *including imports inside functions*, has no cycle
  (a cycle hidden by a function-level import is still a cycle);
* the subpackages form layers (:data:`LAYERS`, lowest first): a module imports only modules of its own
  layer or lower ones, imports inside functions counted; ``qsplan``'s and ``qsplan.planner``'s own
  ``__init__`` (lazy public names, which may point anywhere) are the only modules outside the layers;
* exactly one package imports ``ompl`` (:data:`OMPL_PACKAGE`);
* no name starting with ``_`` is imported from another module;
* no module is longer than :data:`MAX_MODULE_LINES` (a hint to look for a second concept, not a target);
* code, tests, examples and benchmarks import the project only as ``qsplan.*``, and examples and
  benchmarks import no private name;
* every folder with an ``__init__.py`` is a package that ``pyproject.toml`` installs.
"""

from __future__ import annotations

import ast
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
#: The user's top-level folders and the subpackage of ``qsplan`` each installs as.
FOLDERS = {"mechanics": "qsplan.mechanics", "hands": "qsplan.hands", "planner": "qsplan.planner"}
#: A module this long almost surely holds more than one concept.  Not a target to cut to: modules are split by
#: concept, whatever their length (a 400-line cap left ten modules at 388-400 lines, cut to the count); this
#: bound only flags the module nobody looked at.
MAX_MODULE_LINES = 800
#: The layers of the package, lowest first (issue 22's design): the paper's mechanics, hands, then the
#: planner from the task up to the command line.  A module may import its own layer and lower ones only.
LAYERS = (
    "qsplan.mechanics",
    "qsplan.hands",
    "qsplan.planner.task",
    "qsplan.planner.torque",
    "qsplan.planner.states",
    "qsplan.planner.search",
    "qsplan.planner.plan",
    "qsplan.planner.export",
    "qsplan.planner.certify",
    "qsplan.planner.replay",
    "qsplan.planner.plotting",
    "qsplan.planner.reports",
    "qsplan.planner.pipeline",
    "qsplan.planner.cli",
)
#: The two package ``__init__``s outside the layers.  ``qsplan`` holds ``__version__`` and the lazy-import
#: helper every package ``__init__`` uses: below every layer, it imports nothing of the project.
#: ``qsplan.planner`` is the public facade whose lazy names reach every layer: above them all, no module
#: of the package imports it.
ROOT_MODULE, FACADE = "qsplan", "qsplan.planner"
#: The one package that talks to OMPL (the adapter and the OMPL search planners).
OMPL_PACKAGE = "qsplan.planner.search"


def _modules() -> dict[str, Path]:
    """``{qualified module name: path}`` for every module of the package."""
    mods = {"qsplan": ROOT / "src" / "qsplan" / "__init__.py"}
    for folder, package in FOLDERS.items():
        for path in sorted((ROOT / folder).rglob("*.py")):
            parts = list(path.relative_to(ROOT / folder).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            mods[".".join([package, *parts])] = path
    return mods


MODULES = _modules()


def _imports(name: str, path: Path):
    """``(target module, imported names)`` for every import of a project module in one file."""
    tree = ast.parse(path.read_text(), filename=str(path))
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.split(".")[0] != "qsplan":
                continue
            for alias in node.names:
                sub = f"{target}.{alias.name}"
                yield (sub, None) if sub in MODULES else (target, alias.name)
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] == "qsplan":
                    yield alias.name, None
        elif isinstance(node, ast.Call) and getattr(node.func, "attr", getattr(node.func, "id", "")) == "import_module":
            if node.args and isinstance(node.args[0], ast.Constant) and str(node.args[0].value).startswith("qsplan"):
                yield node.args[0].value, None


def _graph() -> dict[str, set[str]]:
    """Module -> the project modules it imports (a package import counts as its ``__init__``)."""
    graph = {}
    for name, path in MODULES.items():
        edges = set()
        for target, _ in _imports(name, path):
            while target not in MODULES and "." in target:
                target = target.rpartition(".")[0]
            if target != name and target in MODULES:
                edges.add(target)
        graph[name] = edges
    return graph


def _lazy_targets(name: str, path: Path) -> set[str]:
    """Modules a package ``__init__`` loads on first attribute access (a ``_LAZY`` name -> module table)."""
    tree = ast.parse(path.read_text())
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Assign) and any(getattr(t, "id", "") == "_LAZY" for t in node.targets):
            if isinstance(node.value, ast.Dict):
                out |= {v.value for v in node.value.values if isinstance(v, ast.Constant)}
    return out


def _find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    colour, stack = {}, []

    def visit(u):
        colour[u] = 1
        stack.append(u)
        for v in sorted(graph.get(u, ())):
            if colour.get(v) == 1:
                return stack[stack.index(v):] + [v]
            if v not in colour and (c := visit(v)):
                return c
        colour[u] = 2
        stack.pop()
        return None

    for u in sorted(graph):
        if u not in colour and (c := visit(u)):
            return c
    return None


def _layer_of(name: str) -> int | None:
    """Index in :data:`LAYERS` of the layer holding module ``name``, or None outside every layer."""
    for i, layer in enumerate(LAYERS):
        if name == layer or name.startswith(layer + "."):
            return i
    return None


def _layer_violations(graph: dict[str, set[str]]) -> list[str]:
    """Every edge of ``graph`` that leaves the layering: upward, out of a layer, or into the facade."""
    out = []
    for name in sorted(graph):
        for target in sorted(graph[name]):
            if target == FACADE:
                out.append(f"{name} imports the facade {FACADE} (import the defining module)")
            elif name == ROOT_MODULE:
                out.append(f"{ROOT_MODULE} imports {target}")
            elif target == ROOT_MODULE or name == FACADE:
                continue
            elif _layer_of(name) is None or _layer_of(target) is None:
                out.append(f"{name} -> {target}: a module outside {LAYERS}")
            elif (low := _layer_of(name)) < (high := _layer_of(target)):
                out.append(f"{name} ({LAYERS[low]}) imports {target} ({LAYERS[high]}), a higher layer")
    return out


def _ompl_importers(modules: dict[str, Path] = MODULES) -> dict[str, list[str]]:
    """Package -> its modules with an ``import ompl`` / ``from ompl ...`` (inside functions too)."""
    out = {}
    for name, path in modules.items():
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                hit = any(a.name.split(".")[0] == "ompl" for a in node.names)
            elif isinstance(node, ast.ImportFrom):
                hit = not node.level and (node.module or "").split(".")[0] == "ompl"
            else:
                continue
            if hit:
                package = name if path.name == "__init__.py" else name.rpartition(".")[0]
                out.setdefault(package, []).append(name)
                break
    return out


def test_every_module_found():
    assert len(MODULES) > 60
    assert "qsplan.mechanics.solver" in MODULES and "qsplan.planner.cli" in MODULES


def test_import_graph_has_no_cycle():
    graph = _graph()
    for name, path in MODULES.items():
        if path.name == "__init__.py":
            graph[name] |= {t for t in _lazy_targets(name, path) if t in MODULES}
    # A package's __init__ re-exports its submodules; a submodule importing its own package's
    # __init__ would close a cycle through it, which this check reports too.
    cycle = _find_cycle(graph)
    assert cycle is None, "import cycle: " + " -> ".join(cycle)


def test_the_cycle_check_finds_cycles():
    assert _find_cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert _find_cycle({"a": {"b"}, "b": set()}) is None


def test_every_module_is_in_a_layer():
    assert [name for name in MODULES if _layer_of(name) is None] == [ROOT_MODULE, FACADE]
    assert all(layer in MODULES for layer in LAYERS)  # each layer is a package of the tree


def test_imports_go_down_the_layers():
    # imports inside functions count, and so do the lazy maps of package __init__s, but those of
    # qsplan's and qsplan.planner's (the public names, which may point anywhere)
    graph = _graph()
    for name, path in MODULES.items():
        if path.name == "__init__.py" and name not in (ROOT_MODULE, FACADE):
            graph[name] |= {t for t in _lazy_targets(name, path) if t in MODULES}
    assert _layer_violations(graph) == []


def test_the_layer_check_finds_violations():
    graph = {
        "qsplan.planner.task.task": {"qsplan.planner.torque.command", "qsplan.mechanics.errors", ROOT_MODULE},
        "qsplan.planner.cli.verify": {FACADE, "qsplan.planner.task.task"},
        "qsplan.planner.plan.scripted": {"qsplan.planner.states.contact", "qsplan.planner.plan.results"},
        "qsplan.planner.extra": {"qsplan.mechanics.errors"},
        ROOT_MODULE: {"qsplan.mechanics"},
    }
    assert _layer_violations(graph) == [
        f"{ROOT_MODULE} imports qsplan.mechanics",
        "qsplan.planner.cli.verify imports the facade qsplan.planner (import the defining module)",
        f"qsplan.planner.extra -> qsplan.mechanics.errors: a module outside {LAYERS}",
        "qsplan.planner.task.task (qsplan.planner.task) imports qsplan.planner.torque.command "
        "(qsplan.planner.torque), a higher layer",
    ]


def test_one_package_imports_ompl():
    importers = _ompl_importers()
    assert list(importers) == [OMPL_PACKAGE], importers


def test_the_ompl_check_finds_importers(tmp_path):
    sources = {"qsplan.planner.plan.a": "def f():\n    from ompl import base\n",
               "qsplan.planner.search.b": "import ompl.geometric as og\n",
               "qsplan.planner.search.c": "import numpy\n"}  # fmt: skip
    modules = {}
    for name, text in sources.items():
        modules[name] = tmp_path / f"{name}.py"
        modules[name].write_text(text)
    assert _ompl_importers(modules) == {"qsplan.planner.plan": ["qsplan.planner.plan.a"],
                                        "qsplan.planner.search": ["qsplan.planner.search.b"]}  # fmt: skip


#: The hands' and grasps' classes: outside ``qsplan.hands`` nothing asks which of them a value is (the planner asks the
#: :class:`qsplan.hands.protocol.Hand` protocol; the paper's closed forms are the hand's accelerator, its own business).
HAND_CLASSES = frozenset({"TwoFingerHand", "ChainHand", "DescribedHand", "Hand", "Grasp", "ChainGrasp", "OnVertex",
                          "TipOnEdge", "FingerContact"})
#: Calls and attributes that branch on a hand's type or reach into its accelerator.
HAND_TYPE_CALLS = frozenset({"is_chain_hand"})
HAND_INTERNALS = frozenset({"accelerated", "paper", "chain", "paper_form", "record"})


def _hand_type_branches(modules=None) -> list:
    """Every place outside ``qsplan.hands`` that branches on a hand's or grasp's type (``isinstance``/``issubclass`` with
    a hand class, :data:`HAND_TYPE_CALLS`) or reads a hand's accelerator (:data:`HAND_INTERNALS`), as ``module:line``."""
    out = []
    for name, path in (MODULES if modules is None else modules).items():
        if name.startswith("qsplan.hands"):
            continue
        for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
            if isinstance(node, ast.Call):
                f = node.func
                fname = getattr(f, "id", getattr(f, "attr", ""))
                if fname in ("isinstance", "issubclass") and len(node.args) == 2:
                    kinds = node.args[1].elts if isinstance(node.args[1], ast.Tuple) else [node.args[1]]
                    if any(getattr(k, "id", getattr(k, "attr", "")) in HAND_CLASSES for k in kinds):
                        out.append(f"{name}:{node.lineno} {fname}(..., {ast.unparse(node.args[1])})")
                elif fname in HAND_TYPE_CALLS:
                    out.append(f"{name}:{node.lineno} {fname}()")
            elif isinstance(node, ast.Attribute) and node.attr in HAND_INTERNALS and isinstance(node.ctx, ast.Load):
                out.append(f"{name}:{node.lineno} .{node.attr}")
    return out


def test_no_hand_type_branch_outside_hands():
    assert _hand_type_branches() == []


def test_the_hand_type_check_finds_branches(tmp_path):
    sources = {"qsplan.planner.plan.a": "def f(h):\n    return isinstance(h, (int, ChainHand))\n",
               "qsplan.planner.plan.b": "def f(h):\n    return h.paper.finger_length\n",
               "qsplan.planner.plan.c": "def f(h):\n    return is_chain_hand(h)\n",
               "qsplan.hands.d": "def f(h):\n    return isinstance(h, TwoFingerHand)\n",
               "qsplan.planner.plan.e": "def f(h):\n    return isinstance(h, dict) and h.joint_names\n"}  # fmt: skip
    modules = {}
    for name, text in sources.items():
        modules[name] = tmp_path / f"{name}.py"
        modules[name].write_text(text)
    assert [b.split(":")[0] for b in _hand_type_branches(modules)] == ["qsplan.planner.plan.a", "qsplan.planner.plan.b",
                                                                       "qsplan.planner.plan.c"]  # fmt: skip


#: The hand records' types (issue 32): each record answers for itself (:class:`qsplan.hands.protocol.HandRecord`), so
#: nothing asks which of them a value is but the record modules themselves and the door that converts a bare record.
RECORD_TYPES = frozenset({"TwoFingerHand", "ChainHand"})
#: Where asking a record's type is allowed: ``{module: functions}`` (None: anywhere in the module).
RECORD_TYPE_DOORS = {"qsplan.hands.paper_hand.two_finger": None, "qsplan.hands.chains.hand": None,
                     "qsplan.hands.described.build": frozenset({"as_hand", "record_of"})}  # fmt: skip


def _record_type_branches(modules=None) -> list:
    """Every ``isinstance``/``issubclass`` with a hand record type (:data:`RECORD_TYPES`, by name or attribute, alone or
    in a tuple) outside :data:`RECORD_TYPE_DOORS`, in any module of the package, as ``module:line function``."""
    out = []
    for name, path in (MODULES if modules is None else modules).items():
        allowed = RECORD_TYPE_DOORS.get(name, frozenset())
        if allowed is None:
            continue

        def visit(node, function):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                function = node.name if function is None else function  # a nested function is its outer one's
            if isinstance(node, ast.Call) and getattr(node.func, "id", getattr(node.func, "attr", "")) in (
                    "isinstance", "issubclass") and len(node.args) == 2:  # fmt: skip
                kinds = node.args[1].elts if isinstance(node.args[1], ast.Tuple) else [node.args[1]]
                if any(getattr(k, "id", getattr(k, "attr", "")) in RECORD_TYPES for k in kinds) and \
                        function not in allowed:  # fmt: skip
                    out.append(f"{name}:{node.lineno} {function or '<module>'}")
            for child in ast.iter_child_nodes(node):
                visit(child, function)

        visit(ast.parse(path.read_text(), filename=str(path)), None)
    return out


def test_no_isinstance_on_hand_records_past_the_door():
    assert _record_type_branches() == []


def test_the_record_type_check_finds_branches(tmp_path):
    sources = {"qsplan.hands.described.records": "def f(h):\n    return isinstance(h, (int, ChainHand))\n",
               "qsplan.hands.contacts.a": "import qsplan\nX = issubclass(T, qsplan.hands.TwoFingerHand)\n",
               "qsplan.planner.plan.b": "def f(h):\n    def g():\n        return isinstance(h, TwoFingerHand)\n",
               "qsplan.hands.described.build": "def as_hand(h):\n    return isinstance(h, ChainHand)\n"
                                               "def other(h):\n    return isinstance(h, ChainHand)\n",
               "qsplan.hands.chains.hand": "X = isinstance(1, ChainHand)\n",
               "qsplan.hands.contacts.c": "def f(h):\n    return isinstance(h, DescribedHand) or h.closed_form\n"}  # fmt: skip
    modules = {}
    for name, text in sources.items():
        modules[name] = tmp_path / f"{name}.py"
        modules[name].write_text(text)
    assert _record_type_branches(modules) == ["qsplan.hands.described.records:2 f", "qsplan.hands.contacts.a:2 <module>",
                                              "qsplan.planner.plan.b:3 f", "qsplan.hands.described.build:4 other"]


#: The module the planner asked its questions about a hand through before issue 32 (it dispatches on the hand records'
#: types): the planner asks the :class:`qsplan.hands.protocol.Hand` protocol instead.
HAND_DISPATCH = "qsplan.hands.described.records"


def _interface_importers(modules=None) -> list:
    """Every ``qsplan.planner`` module importing :data:`HAND_DISPATCH` (or a name of it), imports inside functions
    counted, as ``module imports target``."""
    out = []
    for name, path in (MODULES if modules is None else modules).items():
        if name.startswith("qsplan.planner"):
            out += [f"{name} imports {t}" for t, n in _imports(name, path)
                    if HAND_DISPATCH in (t, f"{t}.{n}") or t.startswith(HAND_DISPATCH + ".")]  # fmt: skip
    return out


def test_the_planner_does_not_import_the_hand_dispatch():
    assert _interface_importers() == []


def test_the_dispatch_import_check_finds_imports(tmp_path):
    sources = {"qsplan.planner.plan.a": "def f(h):\n    from qsplan.hands.described.records import joint_names\n",
               "qsplan.planner.plan.b": "import qsplan.hands.described.records as i\n",
               "qsplan.planner.plan.c": "from qsplan.hands.described import records\n",
               "qsplan.planner.plan.d": "# from qsplan.hands.described.records import scene_at\n"
                                        "X = 'qsplan.hands.described.records'\n",
               "qsplan.hands.e": "from qsplan.hands.described.records import scene_at\n"}  # fmt: skip
    modules = {}
    for name, text in sources.items():
        modules[name] = tmp_path / f"{name}.py"
        modules[name].write_text(text)
    assert [f.split(" ")[0] for f in _interface_importers(modules)] == ["qsplan.planner.plan.a", "qsplan.planner.plan.b", "qsplan.planner.plan.c"]


def _protocol_members() -> set:
    """The :class:`qsplan.hands.protocol.Hand` protocol's attributes and methods, read from its source."""
    tree = ast.parse(MODULES["qsplan.hands.protocol"].read_text())
    cls = next(n for n in tree.body if isinstance(n, ast.ClassDef) and n.name == "Hand")
    return {n.target.id for n in cls.body if isinstance(n, ast.AnnAssign)} | \
        {n.name for n in cls.body if isinstance(n, ast.FunctionDef)}


def _hand_questions(modules=None) -> dict:
    """``{attribute: [module:line, ...]}``: every attribute the planner reads on a hand (a name ``hand``, or any
    ``<...>.hand``: ``task.hand``, ``plan.task.hand``, ``self.hand``)."""
    out = {}
    for name, path in (MODULES if modules is None else modules).items():
        if not name.startswith("qsplan.planner"):
            continue
        for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
            if isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Load):
                v = node.value
                if (isinstance(v, ast.Name) and v.id == "hand") or (isinstance(v, ast.Attribute) and v.attr == "hand"):
                    out.setdefault(node.attr, []).append(f"{name}:{node.lineno}")
    return out


def test_the_planner_asks_a_hand_only_what_the_protocol_answers():
    questions = _hand_questions()
    assert {"joint_units", "body_polygons", "scene", "finger_joint_names", "metadata"} <= set(questions)  # it looks
    assert {q: w for q, w in questions.items() if q not in _protocol_members()} == {}


def test_the_question_check_finds_questions_outside_the_protocol(tmp_path):
    sources = {"qsplan.planner.plan.a": "def f(task):\n    return task.hand.chain_polygons(0), task.hand.joint_names\n",
               "qsplan.planner.plan.b": "def f(hand):\n    return hand.finger_length\n",
               "qsplan.hands.c": "def f(hand):\n    return hand.paper\n"}  # fmt: skip
    modules = {}
    for name, text in sources.items():
        modules[name] = tmp_path / f"{name}.py"
        modules[name].write_text(text)
    questions = _hand_questions(modules)
    assert set(questions) == {"chain_polygons", "joint_names", "finger_length"}
    assert {q for q in questions if q not in _protocol_members()} == {"chain_polygons", "finger_length"}


def test_no_private_name_crosses_a_module_boundary():
    crossings = [
        f"{name} imports {imported} from {target}"
        for name, path in MODULES.items()
        for target, imported in _imports(name, path)
        if imported is not None and imported.startswith("_") and not imported.startswith("__")
    ]
    assert crossings == []


def test_examples_and_benchmarks_use_public_names_only():
    crossings = []
    for folder in ("examples", "benchmarks"):
        for path in sorted((ROOT / folder).rglob("*.py")):
            for target, imported in _imports(path.stem, path):
                if imported is not None and imported.startswith("_") and not imported.startswith("__"):
                    crossings.append(f"{path.relative_to(ROOT)} imports {imported} from {target}")
    assert crossings == []


@pytest.mark.parametrize("name", sorted(MODULES))
def test_module_size(name):
    lines = MODULES[name].read_text().count("\n")
    assert lines <= MAX_MODULE_LINES, f"{name}: {lines} lines; split it by concept"


def test_only_qsplan_names_are_imported():
    bare = []
    for folder in ("mechanics", "hands", "planner", "tests", "examples", "benchmarks", "src"):
        for path in sorted((ROOT / folder).rglob("*.py")):
            tree = ast.parse(path.read_text())
            for node in ast.walk(tree):
                names = []
                if isinstance(node, ast.ImportFrom) and not node.level:
                    names = [node.module or ""]
                elif isinstance(node, ast.ImportFrom) and node.level and folder not in FOLDERS:
                    names = ["." * node.level + (node.module or "")]
                elif isinstance(node, ast.Import):
                    names = [a.name for a in node.names]
                for n in names:
                    if n.split(".")[0] in FOLDERS or (n.startswith(".") and folder not in FOLDERS):
                        bare.append(f"{path.relative_to(ROOT)}:{node.lineno} imports {n}")
    assert bare == []


def test_pyproject_installs_every_package():
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    listed = set(config["packages"])
    on_disk = {name for name, path in MODULES.items() if path.name == "__init__.py"}
    assert listed == on_disk
    assert config["package-dir"] == {"qsplan": "src/qsplan", **FOLDERS.__class__({v: k for k, v in FOLDERS.items()})}


#: The kinds of a plan's phases and of its sequence's steps (:mod:`qsplan.planner.plan.results`,
#: :mod:`qsplan.planner.plan.steps`) and of the route search's edges: strings the files write, never a question a
#: planner module asks (a phase says what it is by its type, its class attributes and its methods).
PHASE_KINDS = frozenset({"slide", "hold", "pivot", "regrasp", "search"})


def _reads_kind(node) -> bool:
    """Whether ``node`` reads a kind: ``X.kind`` or ``getattr(X, "kind", ...)``."""
    if isinstance(node, ast.Attribute):
        return node.attr == "kind"
    return (isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "getattr"
            and len(node.args) >= 2 and isinstance(node.args[1], ast.Constant) and node.args[1].value == "kind")


def _kind_strings(node) -> set:
    """The phase kinds among the string constants ``node`` is or holds (a tuple, list, set or dict's keys)."""
    items = (node.elts if isinstance(node, (ast.Tuple, ast.List, ast.Set)) else node.keys if isinstance(node, ast.Dict)
             else [node])  # fmt: skip
    return {i.value for i in items if isinstance(i, ast.Constant) and i.value in PHASE_KINDS}


def kind_questions(source: str) -> list:
    """``(line, code)`` of every place ``source`` asks a kind string what a phase or step is: a comparison of a kind
    read (:func:`_reads_kind`) with a phase kind, or a dict with phase kinds for keys looked up by a kind read.  The
    body of a class that owns a ``kind`` (its definition) may ask its own."""
    out = []

    def visit(node, owner):
        if isinstance(node, ast.ClassDef):
            owner = any(isinstance(b, (ast.AnnAssign, ast.Assign)) and "kind" in
                        {getattr(t, "id", None) for t in getattr(b, "targets", [getattr(b, "target", None)])}
                        for b in node.body)  # fmt: skip
        if not owner and isinstance(node, ast.Compare):
            sides = [node.left, *node.comparators]
            if any(_reads_kind(s) for s in sides) and any(_kind_strings(s) for s in sides):
                out.append((node.lineno, ast.unparse(node)))
        if not owner and isinstance(node, ast.Subscript) and _reads_kind(node.slice) and _kind_strings(node.value):
            out.append((node.lineno, ast.unparse(node)))
        if (not owner and isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "get"
                and node.args and _reads_kind(node.args[0]) and _kind_strings(node.func.value)):
            out.append((node.lineno, ast.unparse(node)))
        for child in ast.iter_child_nodes(node):
            visit(child, owner)

    visit(ast.parse(source), False)
    return out


def test_the_kind_question_is_found():
    asked = ['if ph.in_contact and ph.kind == "hold":\n    pass',
             'count = 2 if getattr(ph, "kind", None) == "hold" else 3',
             'x = ph.kind in ("pivot", "hold")',
             'w = {"hold": "hold: ", "pivot": "pivot: "}.get(getattr(ph, "kind", "slide"), "")',
             'w = {"hold": 1, "slide": 2}[ph.kind]',
             'n = sum(s.kind != "search" for s in seq)']
    assert [len(kind_questions(src)) for src in asked] == [1] * len(asked)
    fine = ['if mode.kind == "3S":\n    pass', 'colour = step_colour(base, ph.kind)', 'd = {"kind": ph.kind}',
            'class Step:\n    kind: str\n    def slides(self):\n        return self.kind == "slide"']
    assert [kind_questions(src) for src in fine] == [[]] * len(fine)


def test_no_planner_module_asks_a_phase_its_kind_string():
    """Typed phases and steps (issue 32): the planner asks a phase's type or method, never its ``kind`` string."""
    asked = [f"{name}:{line}: {code}" for name, path in MODULES.items() if name.startswith("qsplan.planner")
             for line, code in kind_questions(path.read_text())]  # fmt: skip
    assert asked == []
