"""The package layout: imports run only downward, and packages meet only at their public names.

Layers, bottom first (docs/architecture.md)::

    posegen (version), errors, progress
    extras
    io | parallel | arguments
    robot
    model
    pool | select | route | calibrate      (stages: never each other)
    session | view                         (chains the stages | reads every stage's artefacts)
    cli

A module may import its own package freely (its siblings by module path), and from
another package only a lower layer, and only the names that package's ``__init__``
lists in ``__all__``. Every import is read with ``ast``, including those inside
functions.
"""

from __future__ import annotations

import ast
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
    "posegen.progress": 0,
    "posegen.io": 1,
    "posegen.parallel": 1,
    "posegen.arguments": 1,
    "posegen.robot": 2,
    "posegen.model": 3,
    "posegen.pool": 4,
    "posegen.select": 4,
    "posegen.route": 4,
    "posegen.calibrate": 4,
    "posegen.session": 5,  # an experiment: chains the stages (beside view)
    "posegen.view": 5,  # reads every stage's artefacts
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


def test_every_package_states_its_public_names():
    for source in read_tree(PACKAGE).values():
        if source.is_package:
            public = declared_all(source)
            assert public is not None, f"{source.name}: no __all__"
            missing = set(public) - bound_names(source)
            assert not missing, f"{source.name}: __all__ names {sorted(missing)} it does not bind"


def test_no_module_is_long():
    for source in read_tree(PACKAGE).values():
        lines = source.text.count("\n")
        assert lines <= MAX_LINES, f"{source.name}: {lines} lines (split it by concept)"


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
