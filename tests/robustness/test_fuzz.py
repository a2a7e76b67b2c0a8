"""Fuzzing the commands that read a route: mutated routes through ``check``, ``export`` and ``simulate --bag``.

Each example is a valid route with one mutation (a value made NaN, infinite or huge, a time
repeated, sent back or pushed to 1e39, a point dropped from the arrays, the declared count
changed, a header node replaced, the sidecar's bytes damaged). Every command must: raise
nothing (a traceback fails the example), exit 0, 1 or 2 with one ``posegen: error:`` line
on 2, leave its input's bytes as they were, and agree with the readers' rules: what the
route reader (:func:`posegen.io.read_route`, the one every command reads through) refuses, every
command refuses in one line (exit 2), check included.

``make test`` runs a few examples (the ``posegen`` profile); ``make fuzz`` runs many, with
new random draws (the ``fuzz`` profile). Every failure found is kept below as an
``@example`` (the corpus), so that it is run every time.
"""

from __future__ import annotations

import hashlib
import math
import tempfile
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from posegen.cli import main
from posegen.errors import PosegenError
from posegen.io import ROUTE_ARRAYS, read_arrays, read_route, sidecars_of, write_with_arrays
from tests.robustness.strategies import SCALARS

DELETE = "<delete>"  # a header mutation that removes the node
NUMBERS = st.sampled_from([math.nan, math.inf, -math.inf, 1e39, -1e39, 1e300, 0.0, -1.0, 4.0])
MUTATIONS = st.one_of(
    st.tuples(st.just("cell"), st.sampled_from(ROUTE_ARRAYS), st.integers(0, 10**6), st.integers(0, 64), NUMBERS),
    st.tuples(st.just("time"), st.sampled_from(["repeat", "back", "last", "first"]), st.integers(1, 10**6), NUMBERS),
    st.tuples(st.just("drop"), st.sampled_from([*ROUTE_ARRAYS, "all"]), st.integers(0, 10**6)),
    st.tuples(st.just("count"), st.integers(-3, 3).filter(bool)),
    st.tuples(st.just("header"), st.integers(0, 10**6), st.one_of(SCALARS, st.just(DELETE))),
    st.tuples(st.just("sidecar"), st.integers(0, 10**6), st.binary(max_size=16)),
    st.tuples(st.just("segment"), st.integers(0, 100), st.sampled_from(["start_s", "end_s", "first_point"]), SCALARS),
)


@pytest.fixture(scope="module")
def good_route(route_file) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    header = yaml.safe_load(route_file.read_text())
    arrays = read_arrays(route_file, header.pop("arrays"), ROUTE_ARRAYS)
    return header, arrays


def mutate(spec: tuple, header: dict[str, Any], arrays: dict[str, np.ndarray]) -> None:
    """Apply one mutation to the header and arrays, in place (a sidecar's damage is done once written)."""
    kind, *args = spec
    m = len(arrays["time_from_start"])
    if kind == "cell":
        name, row, column, value = args
        values = arrays[name]
        with np.errstate(over="ignore"):  # 1e39 in a float32 array is inf: a mutation like any other
            values[(row % m,) if values.ndim == 1 else (row % m, column % values.shape[1])] = value
    elif kind == "time":
        how, k, value = args
        times = arrays["time_from_start"]
        k = 1 + k % (m - 1)
        times[k] = {"repeat": times[k - 1], "back": times[max(k - 2, 0)], "last": times[k], "first": value}[how]
        if how == "last":
            times[-1] = value
    elif kind == "drop":
        name, row = args
        for key in ROUTE_ARRAYS if name == "all" else (name,):
            arrays[key] = np.delete(arrays[key], row % m, axis=0)
    elif kind == "count":
        header["trajectory"]["points"] += args[0]
    elif kind == "header":
        replace_node(header, *args)
    elif kind == "segment":
        k, key, value = args
        segments = header["segments"]
        segments[k % len(segments)][key] = value


def replace_node(document: dict[str, Any], index: int, value: Any) -> None:
    """Replace (or delete) the ``index``-th node of the document, in depth-first order."""
    nodes: list[tuple[Any, Any]] = []

    def visit(node: Any) -> None:
        keys = list(node) if isinstance(node, dict) else range(len(node)) if isinstance(node, list) else []
        for key in keys:
            nodes.append((node, key))
            visit(node[key])

    visit(document)
    parent, key = nodes[index % len(nodes)]
    if value == DELETE:
        del parent[key]
    else:
        parent[key] = value


def header_copy(header: dict[str, Any]) -> dict[str, Any]:
    return yaml.safe_load(yaml.safe_dump(header))


def hashes(folder: Path) -> dict[str, str]:
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(folder.iterdir()) if p.is_file()}


def readers_accept(path: Path) -> bool:
    try:
        read_route(path)
    except PosegenError:
        return False
    return True


def run(argv: list[str], capsys) -> int:
    code = main([*argv, "-q"])
    err = capsys.readouterr().err
    assert code in (0, 1, 2), (argv, code, err)
    if code == 2:
        lines = [line for line in err.splitlines() if line.strip()]
        assert len(lines) == 1 and lines[0].startswith("posegen: error: "), err
    return code


@settings(
    max_examples=max(settings().max_examples // 4, 5),  # ~1.5 s an example: 10 in make test
    # capsys is read after every command: one fixture for every example is right
    suppress_health_check=[
        *settings().suppress_health_check,
        HealthCheck.function_scoped_fixture,
    ],  # capsys: read per run
)
@given(spec=MUTATIONS)
@example(spec=("cell", "time_from_start", 5, 0, math.nan))  # corpus: the NaN time
@example(spec=("time", "last", 1, 1e39))  # corpus: a last time of 1e39 s (struct.error in export)
@example(spec=("time", "last", 1, math.nan))  # corpus: a NaN last time (All-NaN slice in check)
@example(spec=("time", "repeat", 5, 0.0))  # corpus: a repeated time
@example(spec=("count", -1))  # corpus: a header count that disagrees with the arrays
@example(spec=("segment", 1, "start_s", math.nan))  # corpus: a NaN segment time passed check
def test_route_commands_on_mutated_routes(good_route, spec, capsys):
    header, arrays = header_copy(good_route[0]), {k: v.copy() for k, v in good_route[1].items()}
    with tempfile.TemporaryDirectory() as folder:
        here = Path(folder)
        route = here / "route.yaml"
        mutate(spec, header, arrays)
        try:
            write_with_arrays(route, header, arrays, compress=True)
        except (TypeError, ValueError, AttributeError, yaml.YAMLError):
            return  # the mutation made a header that cannot be written: nothing to read
        if spec[0] == "sidecar":  # cut short at a point, or bytes overwritten there
            sidecar = sidecars_of(route)[0]
            content = sidecar.read_bytes()
            at = spec[1] % len(content)
            sidecar.write_bytes(content[:at] + spec[2] + (content[at + len(spec[2]) :] if spec[2] else b""))
        before = hashes(here)
        accepted = readers_accept(route)
        codes = {
            "export": run(["export", str(route), "--bag", str(here / "bag")], capsys),
            "simulate --bag": run(["simulate", str(route), "--rate", "20", "--bag", str(here / "session")], capsys),
            "check": run(["check", str(route), "--workers", "1"], capsys),
        }
        assert {p: h for p, h in hashes(here).items() if p in before} == before  # no input changed
        if not accepted:
            assert codes["export"] == codes["simulate --bag"] == 2, codes
            assert codes["check"] == 2, codes  # check reads through the same reader
        else:
            assert codes["export"] == 0, codes  # the reader's rules are the only reasons export refuses
