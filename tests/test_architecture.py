"""The package layout: imports run only downward, and packages meet only at their public names.

Layers, bottom first (docs/architecture.md)::

    posegen (version), errors, progress, numeric
    extras
    io | parallel | arguments
    robot
    model
    draft | pool | select | route | calibrate   (stages: never each other; draft is stage 0, robot init)
    session | view | physics               (chains the stages | reads every stage's artefacts | rehearses a route)
    cli

A module may import its own package freely (its siblings by module path), and from
another package only a lower layer, and only the names that package's ``__init__``
lists in ``__all__``. Every import is read with ``ast``, including those inside
functions.
"""

from __future__ import annotations

import ast
import re
from dataclasses import dataclass
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "posegen"
MAX_LINES = 400

LAYERS = {
    "posegen": 0,  # the root package: __version__ only
    "posegen.resources": 0,
    "posegen.extras": 0.5,  # optional packages: raises errors.ExtraError for io, parallel and view
    "posegen.errors": 0,
    "posegen.numeric": 0,  # array types (FloatArray)
    "posegen.progress": 0,
    "posegen.io": 1,
    "posegen.parallel": 1,
    "posegen.arguments": 1,
    "posegen.robot": 2,
    "posegen.model": 3,
    "posegen.draft": 4,  # stage 0: a robot's config drafted from its description (robot init)
    "posegen.pool": 4,
    "posegen.select": 4,
    "posegen.route": 4,
    "posegen.calibrate": 4,
    "posegen.session": 5,  # an experiment: chains the stages (beside view)
    "posegen.view": 5,  # reads every stage's artefacts
    "posegen.physics": 5,  # a route rehearsed in MuJoCo: reads routes, draws the perturbed robot (calibrate)
    "posegen.api": 5.5,  # the public API: a function per command (re-exported lazily by the root package)
    "posegen.cli": 6,
}


@dataclass(frozen=True)
class Source:
    """One module of the tree: its dotted name, whether it is a package's ``__init__``, its text."""

    name: str
    is_package: bool
    text: str


def read_tree(root: Path) -> dict[str, Source]:
    """Every module below ``root`` (the ``posegen`` folder), by dotted name."""
    modules = {}
    for path in sorted(root.rglob("*.py")):
        parts = path.relative_to(root.parent).with_suffix("").parts
        is_package = parts[-1] == "__init__"
        name = ".".join(parts[:-1] if is_package else parts)
        modules[name] = Source(name, is_package, path.read_text())
    return modules


def component(name: str) -> str:
    """The unit layers are given to: a top-level subpackage or module, or the root package."""
    parts = name.split(".")
    return ".".join(parts[:2])


def declared_all(source: Source) -> list[str] | None:
    """The string names of a module's ``__all__``, or None when it has none."""
    for node in ast.parse(source.text).body:
        if isinstance(node, ast.Assign) and any(isinstance(t, ast.Name) and t.id == "__all__" for t in node.targets):
            value = ast.literal_eval(node.value)
            return [str(v) for v in value]
    return None


def bound_names(source: Source) -> set[str]:
    """Names a module binds at its top level (imports, definitions, assignments; in try and if too)."""
    names = set()
    statements = list(ast.parse(source.text).body)
    while statements:
        node = statements.pop()
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            names.update(a.asname or a.name.split(".")[0] for a in node.names)
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, ast.Assign):
            names.update(t.id for t in node.targets if isinstance(t, ast.Name))
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            names.add(node.target.id)
        elif isinstance(node, (ast.If, ast.Try)):
            statements.extend([*node.body, *node.orelse])
            if isinstance(node, ast.Try):
                statements.extend([*node.finalbody, *(s for h in node.handlers for s in h.body)])
    return names


def imports(source: Source) -> list[tuple[int, str, list[str]]]:
    """Every import of a module: (line, absolute module imported from, names; empty for ``import x``)."""
    found = []
    package = source.name if source.is_package else source.name.rpartition(".")[0]
    for node in ast.walk(ast.parse(source.text)):
        if isinstance(node, ast.Import):
            found.extend((node.lineno, alias.name, []) for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                base = ".".join([*anchor, base] if base else anchor)
            found.append((node.lineno, base, [a.name for a in node.names]))
    return found


def violations(modules: dict[str, Source]) -> list[str]:
    """Every import against the layout's rules, as ``module:line: reason``."""
    out = []
    for source in modules.values():
        here = component(source.name)
        if here not in LAYERS:
            out.append(f"{source.name}: not in a known layer; give {here} one in LAYERS")
            continue
        for line, target, names in imports(source):
            if target != "posegen" and not target.startswith("posegen."):
                continue  # a third-party or standard module
            where = f"{source.name}:{line}"
            there = component(target)
            if there == here:
                through_init = target == here and source.name != here and modules[here].is_package
                not_modules = [n for n in names if f"{target}.{n}" not in modules]
                if through_init and not_modules:
                    out.append(f"{where}: imports {not_modules} through its own package's __init__")
                continue
            if there not in LAYERS:
                out.append(f"{where}: imports {target}, which is in no known layer")
                continue
            if LAYERS[there] >= LAYERS[here]:
                kind = "a sibling" if LAYERS[there] == LAYERS[here] else "a higher layer"
                out.append(f"{where}: imports {target}, {kind} ({there}) of {here}")
                continue
            if target != there:
                out.append(f"{where}: imports {target}, inside package {there}: use its public names")
                continue
            if target not in modules:
                out.append(f"{where}: imports {target}, which does not exist")
                continue
            if modules[target].is_package:
                public = declared_all(modules[target]) or []
            else:
                public = [n for n in bound_names(modules[target]) if not n.startswith("_")]
            hidden = [n for n in names if n not in public]
            if hidden:
                out.append(f"{where}: imports {hidden} from {target}, not in its public names")
    return out


def tree(**sources: str) -> dict[str, Source]:
    """A synthetic tree: ``pkg__mod="..."`` is module pkg.mod; ``pkg__init__`` a package's __init__."""
    out = {}
    for key, text in sources.items():
        is_package = key.endswith("__init__")
        name = key.removesuffix("__init__").rstrip("_").replace("__", ".")
        out[name] = Source(name, is_package, text)
    return out


BASE = {
    "posegen__init__": '__version__ = "0"\n__all__ = ["__version__"]\n',
    "posegen__errors": "class PosegenError(Exception): ...\n",
    "posegen__robot__init__": 'from posegen.robot.scene import Scene\n__all__ = ["Scene"]\n',
    "posegen__robot__scene": "class Scene: ...\nclass Hidden: ...\n",
    "posegen__select__init__": 'from posegen.select.design import Design\n__all__ = ["Design"]\n',
    "posegen__select__design": "class Design: ...\n",
    "posegen__io__init__": '__all__ = ["write"]\ndef write(): ...\n',
}


def check(module: str, text: str) -> list[str]:
    return violations(tree(**BASE, **{module: text}))


def test_the_synthetic_base_is_clean():
    assert check("posegen__route__init__", "__all__ = []\n") == []
    good = "from posegen.robot import Scene\nfrom posegen.errors import PosegenError\nfrom posegen import __version__\n"
    assert check("posegen__route__plan", good) == []
    inside = "from posegen.robot.scene import Hidden\nfrom posegen.robot import scene\n"  # its own package
    assert check("posegen__robot__extra", inside) == []


@pytest.mark.parametrize(
    ("module", "text", "reason"),
    [
        ("posegen__route__plan", "from posegen.select import Design\n", "a sibling (posegen.select)"),
        ("posegen__robot__extra", "from posegen.select import Design\n", "a higher layer"),
        ("posegen__io__extra", "from posegen.robot import Scene\n", "a higher layer (posegen.robot)"),
        ("posegen__route__plan", "from posegen.robot.scene import Scene\n", "use its public names"),
        ("posegen__route__plan", "import posegen.robot.scene\n", "use its public names"),
        ("posegen__route__plan", "from posegen.robot import Hidden\n", "not in its public names"),
        ("posegen__route__plan", "def f():\n    from posegen.select import Design\n", "a sibling"),
        ("posegen__route__plan", "from ..select import Design\n", "a sibling"),
        ("posegen__robot__extra", "from posegen.robot import Scene\n", "through its own package's __init__"),
        ("posegen__viewer__show", "from posegen.robot import Scene\n", "not in a known layer"),
    ],
)
def test_the_checker_catches_bad_imports(module, text, reason):
    found = check(module, text)
    assert len(found) == 1 and reason in found[0], found


def test_imports_run_downward_through_public_names():
    modules = read_tree(PACKAGE)
    assert "posegen.route.route" in modules and "posegen.cli.main" in modules  # the tree was read
    assert violations(modules) == []


def lazy_names(source: Source) -> set[str]:
    """Names a package binds at first use: the keys of its ``_HOMES`` when it defines ``__getattr__`` (PEP 562)."""
    tree = ast.parse(source.text)
    if not any(isinstance(n, ast.FunctionDef) and n.name == "__getattr__" for n in tree.body):
        return set()
    homes = [
        n.value
        for n in tree.body
        if isinstance(n, ast.Assign) and any(isinstance(t, ast.Name) and t.id == "_HOMES" for t in n.targets)
    ]
    return {k.value for d in homes if isinstance(d, ast.Dict) for k in d.keys if isinstance(k, ast.Constant)}


def test_every_package_states_its_public_names():
    for source in read_tree(PACKAGE).values():
        if source.is_package:
            public = declared_all(source)
            assert public is not None, f"{source.name}: no __all__"
            missing = set(public) - bound_names(source) - lazy_names(source)
            assert not missing, f"{source.name}: __all__ names {sorted(missing)} it does not bind"


def test_no_module_is_long():
    for source in read_tree(PACKAGE).values():
        lines = source.text.count("\n")
        assert lines <= MAX_LINES, f"{source.name}: {lines} lines (split it by concept)"


# --- no cycles inside a package ----------------------------------------------------------------


def type_only_lines(source: Source) -> set[int]:
    """Lines of the imports under ``if TYPE_CHECKING:`` (annotations only: never run, so never a cycle)."""
    lines: set[int] = set()
    for node in ast.walk(ast.parse(source.text)):
        if isinstance(node, ast.If) and isinstance(node.test, ast.Name) and node.test.id == "TYPE_CHECKING":
            lines |= {n.lineno for n in node.body if isinstance(n, ast.Import | ast.ImportFrom)}
    return lines


def package_graph(modules: dict[str, Source]) -> dict[str, set[str]]:
    """Imports between the modules of one package (any run import, in a function too): module -> modules it imports.

    Imports under ``if TYPE_CHECKING:`` are left out: a protocol may name the types that use it.
    """
    graph: dict[str, set[str]] = {name: set() for name in modules}
    for source in modules.values():
        type_only = type_only_lines(source)
        for line, target, names in imports(source):
            if not target.startswith("posegen") or component(target) != component(source.name) or line in type_only:
                continue
            submodules = {f"{target}.{n}" for n in names if f"{target}.{n}" in modules}
            graph[source.name] |= submodules
            if target in modules and len(submodules) < max(1, len(names)):
                graph[source.name].add(target)  # a name of the module itself (or ``import target``)
        graph[source.name].discard(source.name)
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The modules that import each other, directly or round a circle: each group sorted (Tarjan's SCC)."""
    order: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    found = []

    def visit(node: str) -> None:
        order[node] = low[node] = len(order)
        stack.append(node)
        for nxt in sorted(graph[node]):
            if nxt not in order:
                visit(nxt)
                low[node] = min(low[node], low[nxt])
            elif nxt in stack:
                low[node] = min(low[node], order[nxt])
        if low[node] == order[node]:
            group = []
            while True:
                member = stack.pop()
                group.append(member)
                if member == node:
                    break
            if len(group) > 1:
                found.append(sorted(group))

    for node in sorted(graph):
        if node not in order:
            visit(node)
    return found


def test_the_cycle_finder_finds_a_circle_and_only_it():
    modules = tree(
        posegen__parallel__init__="from posegen.parallel.backend import Backend\n__all__ = ['Backend']\n",
        posegen__parallel__backend="class Backend: ...\ndef f():\n    from posegen.parallel.cluster import D\n",
        posegen__parallel__cluster="from posegen.parallel.backend import Backend\nclass D(Backend): ...\n",
        posegen__parallel__free="from posegen.parallel import backend\n",
    )
    assert cycles(package_graph(modules)) == [["posegen.parallel.backend", "posegen.parallel.cluster"]]
    del modules["posegen.parallel.cluster"]
    assert cycles(package_graph(modules)) == []
    typed = "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from posegen.parallel.cluster import D\n"
    modules.update(
        tree(
            posegen__parallel__backend=typed,
            posegen__parallel__cluster="from posegen.parallel.backend import Backend\nclass D(Backend): ...\n",
        )
    )
    assert cycles(package_graph(modules)) == []  # an annotation-only import runs nothing


def test_no_modules_of_a_package_import_each_other():
    assert cycles(package_graph(read_tree(PACKAGE))) == []


# --- long functions: each listed, with its reason --------------------------------------------------

MAX_FUNCTION_LINES = 60
LONG_FUNCTIONS: dict[str, str] = {}  # module:qualified name -> why it is still one piece (the list stays true)


def body_lines(function: ast.FunctionDef | ast.AsyncFunctionDef) -> int:
    """Lines of a function's body, its docstring left out (nested functions count in)."""
    body = function.body
    if len(body) > 1 and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
        body = body[1:]
    assert function.end_lineno is not None
    return function.end_lineno - body[0].lineno + 1


def function_lengths(source: Source) -> dict[str, int]:
    """Every function and method of a module, as ``module:Class.name``, with its body's lines."""
    found = {}

    def visit(node: ast.AST, prefix: str) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                found[f"{source.name}:{prefix}{child.name}"] = body_lines(child)
                visit(child, f"{prefix}{child.name}.")
            elif isinstance(child, ast.ClassDef):
                visit(child, f"{prefix}{child.name}.")
            else:
                visit(child, prefix)

    visit(ast.parse(source.text), "")
    return found


def test_function_lengths_are_measured_on_the_body():
    text = (
        "class A:\n    def f(self):\n        '''Doc.\n\n        More.\n        '''\n        x = 1\n        return x\n"
    )
    assert function_lengths(Source("posegen.m", False, text)) == {"posegen.m:A.f": 2}


def test_every_long_function_is_listed_with_its_reason_and_every_listed_one_is_long():
    lengths = {k: v for s in read_tree(PACKAGE).values() for k, v in function_lengths(s).items()}
    long = {name: n for name, n in lengths.items() if n > MAX_FUNCTION_LINES}
    unlisted = {name: n for name, n in long.items() if name not in LONG_FUNCTIONS}
    assert not unlisted, f"over {MAX_FUNCTION_LINES} lines (split them, or list them with a reason): {unlisted}"
    stale = sorted(name for name in LONG_FUNCTIONS if name not in long)
    assert not stale, f"listed as long but gone or short now: remove them from LONG_FUNCTIONS: {stale}"
    assert all(reason.strip() for reason in LONG_FUNCTIONS.values())


# --- a loaded artefact is indexed as a dict only by its reader --------------------------------------

LOADERS = {"read_yaml", "load_yaml_file", "read_route", "safe_load"}  # functions that return a file's YAML tree
TREE_ATTRIBUTES = {"report"}  # a loaded calibration's calibration.yaml, as a dict (CalibrationRecord.report, ...)
PASS_THROUGH = {"enumerate", "zip", "reversed", "sorted", "list", "tuple", "dict", "iter"}
DICT_METHODS = {"get", "items", "values", "copy", "setdefault", "pop"}
TREE_PARAMETERS = ("dict[str, Any]", "Mapping[str, Any]")  # a parameter that is a YAML tree handed on

# Modules that index a YAML tree with string keys. Readers own their format; the others
# read someone else's tree (main today): each branch that turns an artefact into an object
# removes its entries, and the test then fails here until they are gone from this list.
DICT_READERS = {
    "posegen.io.artefact": "reader: read_yaml checks every artefact's format and version",
    "posegen.io.bag_metadata": "reader: a rosbag2 folder's metadata.yaml",
    "posegen.pool.checkpoint": "reader: the pool checkpoint's lines",
    "posegen.io.pool_file": "reader: the pool format (Pool)",
    "posegen.io.route_file": "reader: the route format (Route)",
    "posegen.api": "load(): dispatches on an artefact's format field to its reader",
    "posegen.model.measurements": "reader: the measurement format",
    "posegen.calibrate.record": "reader: the calibration folder (CalibrationRecord)",
    "posegen.calibrate.compliance": "reader: compliance.yaml",
    "posegen.calibrate.summary": "reader: calibration.yaml (CalibrationSummary)",
    "posegen.io.selection_file": "reader: the selection format (Selection), and a pool's or selection's postures",
    "posegen.calibrate.offsets": "reader: offsets.yaml",
    "posegen.session.index_reader": "reader: session.yaml (SessionIndex)",
    "posegen.physics.physics_file": "reader: physics.yaml (PhysicsReport)",
    "posegen.parallel.cluster": "not an artefact: a worker plugin's pickled state (__setstate__)",
    "posegen.robot.config": "reader: the scene config (Config); an artefact given for one is named by its format",
    "posegen.robot.scene": "Provenance: an artefact's provenance as a dict (scene_for, check_made_for)",
    "posegen.route.workflow": "Route and Selection: segments, entries and provenance as dicts",
    "posegen.view.artefact": "Route and Selection: segments and provenance as dicts",
    "posegen.calibrate.plots": "Calibration: the report's cross-validation rows",
    "posegen.select.followup": "Calibration: calibration.yaml read for the follow-up's model",
    "posegen.view.calibration_view": "Calibration: the report's noise and parameters",
    "posegen.view.report_page": "Calibration: every section of the report",
}


def _is_tree(node: ast.AST, names: set[str]) -> bool:
    """Whether an expression is (part of) a YAML tree: a loader's result, a name bound to one, an item of one."""
    if isinstance(node, ast.Name):
        return node.id in names
    if isinstance(node, ast.Attribute):
        return node.attr in TREE_ATTRIBUTES
    if isinstance(node, ast.Subscript):
        return _is_tree(node.value, names)
    if isinstance(node, ast.BoolOp):
        return any(_is_tree(v, names) for v in node.values)
    if isinstance(node, ast.IfExp):
        return _is_tree(node.body, names) or _is_tree(node.orelse, names)
    if not isinstance(node, ast.Call):
        return False
    func = node.func
    if isinstance(func, ast.Name):
        return func.id in LOADERS or (func.id in PASS_THROUGH and any(_is_tree(a, names) for a in node.args))
    if isinstance(func, ast.Attribute):
        json_load = func.attr in ("load", "loads") and isinstance(func.value, ast.Name) and func.value.id == "json"
        return func.attr in LOADERS or json_load or (func.attr in DICT_METHODS and _is_tree(func.value, names))
    return False


def _bound(target: ast.AST) -> list[str]:
    if isinstance(target, ast.Name):
        return [target.id]
    if isinstance(target, (ast.Tuple, ast.List)):
        return [n for t in target.elts for n in _bound(t)]
    return _bound(target.value) if isinstance(target, ast.Starred) else []


def _own_nodes(scope: ast.AST) -> list[ast.AST]:
    """A scope's nodes, those of the functions and classes defined in it left out."""
    found, stack = [], list(ast.iter_child_nodes(scope))
    while stack:
        node = stack.pop()
        found.append(node)
        if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef, ast.Lambda)):
            stack.extend(ast.iter_child_nodes(node))
    return found


def _bindings(node: ast.AST) -> list[tuple[list[ast.expr], ast.expr | None]]:
    """What a node binds: (targets, the value they are bound to, or iterate over)."""
    if isinstance(node, ast.Assign):
        return [(node.targets, node.value)]
    if isinstance(node, (ast.AnnAssign, ast.NamedExpr)):
        return [([node.target], node.value)]
    if isinstance(node, (ast.For, ast.comprehension)):
        return [([node.target], node.iter)]
    return []


def _string_key(node: ast.AST) -> bool:
    return isinstance(node, ast.Constant) and isinstance(node.value, str)


def tree_indexing(source: Source) -> list[int]:
    """Lines where a module indexes a YAML tree by a string key (``tree["key"]``, ``tree.get("key")``).

    Per function: names bound to a loader's result, to an item of one, or a parameter
    typed as a string-keyed dict, are followed through assignments and loops.
    """
    module = ast.parse(source.text)
    scopes = [module, *(n for n in ast.walk(module) if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef)))]
    lines = []
    for scope in scopes:
        names: set[str] = set()
        if isinstance(scope, (ast.FunctionDef, ast.AsyncFunctionDef)):
            every = [*scope.args.posonlyargs, *scope.args.args, *scope.args.kwonlyargs]
            annotated = [a for a in every if a.annotation is not None]
            names |= {a.arg for a in annotated if any(t in ast.unparse(a.annotation) for t in TREE_PARAMETERS)}
        nodes = _own_nodes(scope)
        while True:  # follow the tree through bindings until nothing new is bound
            known = len(names)
            for node in nodes:
                for targets, value in _bindings(node):
                    if value is not None and _is_tree(value, names):
                        names.update(n for t in targets for n in _bound(t))
            if len(names) == known:
                break
        for node in nodes:
            if (isinstance(node, ast.Subscript) and _string_key(node.slice) and _is_tree(node.value, names)) or (
                isinstance(node, ast.Call)
                and isinstance(node.func, ast.Attribute)
                and node.func.attr == "get"
                and node.args
                and _string_key(node.args[0])
                and _is_tree(node.func.value, names)
            ):
                lines.append(node.lineno)
    return sorted(lines)


@pytest.mark.parametrize(
    ("text", "found"),
    [
        ("data = read_yaml(p, 'k')\nx = data['segments']\n", [2]),
        ("def f(p):\n    for seg in read_route(p)['segments']:\n        y = seg['first_point']\n", [2, 3]),
        ("def f(header: dict[str, Any]):\n    return header.get('provenance') or {}\n", [2]),
        ("def f(calibrated):\n    return calibrated.report['deliverables']\n", [2]),
        ("def f(route):\n    return route.segments[0].first_point, {'a': 1}['a']\n", []),  # an object; a literal
        ("def f(p):\n    rows = read_yaml(p, 'k')['rows']\n    return rows[0], len(rows)\n", [2]),  # by position
    ],
)
def test_the_tree_indexing_finder(text, found):
    assert tree_indexing(Source("posegen.m", False, text)) == found


def test_only_readers_index_a_loaded_artefact_as_a_dict():
    found = {s.name: tree_indexing(s) for s in read_tree(PACKAGE).values()}
    readers = {name for name, lines in found.items() if lines}
    unlisted = {name: found[name] for name in sorted(readers - set(DICT_READERS))}
    assert not unlisted, f"indexes a loaded artefact as a dict (use its object, or list a reader): {unlisted}"
    stale = sorted(set(DICT_READERS) - readers)
    assert not stale, f"listed in DICT_READERS but index no YAML tree now: remove them: {stale}"
    assert all(reason.strip() for reason in DICT_READERS.values())


# --- library errors speak in parameter names -------------------------------------------------------

FLAG = re.compile(r"(?<![\w-])(--[a-z]|-o\b)")


def flags_in_errors(source: Source) -> list[int]:
    """Lines where a module raises an error whose text names a command-line flag (``--k``, ``-o``)."""
    lines = []
    for node in ast.walk(ast.parse(source.text)):
        if isinstance(node, ast.Raise) and node.exc is not None:
            texts = [c.value for c in ast.walk(node.exc) if isinstance(c, ast.Constant) and isinstance(c.value, str)]
            if any(FLAG.search(t) for t in texts):
                lines.append(node.lineno)
    return lines


def test_the_flag_finder():
    assert flags_in_errors(Source("posegen.m", False, 'raise ArgumentError(f"--k {k}: too many")\n')) == [1]
    assert flags_in_errors(Source("posegen.m", False, 'raise ArgumentError(f"-o {out}: no")\n')) == [1]
    assert flags_in_errors(Source("posegen.m", False, 'raise ArgumentError(f"k={k}: a well-known -- no")\n')) == []


def test_library_errors_name_parameters_not_flags():
    found = {s.name: flags_in_errors(s) for s in read_tree(PACKAGE).values() if component(s.name) != "posegen.cli"}
    assert not {k: v for k, v in found.items() if v}, "name the parameter; posegen.cli.options.FLAGS shows its flag"


ROUTE_KEYS = ("segments", "first_point", "last_point", "point_arrays", "trajectory")  # a route header's own keys
ROUTE_FORMAT = ("posegen.io.route_file", "posegen.io.route_writer")  # the route's reader and writer


def header_keys(source: Source, keys: tuple[str, ...]) -> list[str]:
    """Where a module indexes a mapping by one of ``keys`` (``x["k"]`` or ``x.get("k")``), as ``module:line``."""
    found = []
    for node in ast.walk(ast.parse(source.text)):
        key = None
        if isinstance(node, ast.Subscript) and isinstance(node.slice, ast.Constant):
            key = node.slice.value
        elif isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "get":
            key = node.args[0].value if node.args and isinstance(node.args[0], ast.Constant) else None
        if key in keys:
            found.append(f"{source.name}:{node.lineno} [{key!r}]")
    return found


def test_a_route_is_read_as_its_typed_object_outside_its_reader():
    """Stages, the viewer and the CLI take ``posegen.io.Route``: none digs through a route header's keys."""
    digging = tree(posegen__x='def f(d):\n    return d["segments"][0].get("first_point")\n')["posegen.x"]
    assert sorted(header_keys(digging, ROUTE_KEYS)) == ["posegen.x:2 ['first_point']", "posegen.x:2 ['segments']"]
    found = [
        hit
        for source in read_tree(PACKAGE).values()
        if source.name not in ROUTE_FORMAT
        for hit in header_keys(source, ROUTE_KEYS)
    ]
    assert found == []
