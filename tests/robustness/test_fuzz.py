"""Fuzzing the commands through what they read: routes, pools, selections, measurements, recorded sessions.

Routes go through ``check``, ``export`` and ``simulate --bag``; version-2 pools through
``simulate``, ``check`` and ``select --given``; selections through ``simulate`` and
``check``; measurements (YAML and recorded CSV) through ``select --given``; recorded
sessions (rosbag2) through ``measure``. ``view --html``, ``route`` and ``calibrate`` take
seconds on a valid input: they run on the inputs the readers refuse, which they must
refuse before any work.

Each example is a valid artefact with one mutation (for a route: a value made NaN,
infinite or huge, a time repeated, sent back or pushed to 1e39, a point dropped from the
arrays, the declared count changed, a header node replaced, the sidecar's bytes damaged;
the others below). Every command must: raise nothing (a traceback fails the example),
exit 0, 1 or 2 with one ``posegen: error:`` line on 2, leave its inputs' bytes as they
were, and agree with the readers' rules: what the reader (:func:`posegen.io.read_route`,
``load_postures``, ``read_measurements``, ``RecordedBag.read``) refuses, no command runs
with (exit 0).

``make test`` runs a few examples (the ``posegen`` profile); ``make fuzz`` runs many, with
new random draws (the ``fuzz`` profile). Every failure found is kept below as an
``@example`` (the corpus), so that it is run every time.
"""

from __future__ import annotations

import hashlib
import math
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, event, example, given, settings
from hypothesis import strategies as st

from posegen.calibrate.bag_workflow import wrench_topics
from posegen.cli import main
from posegen.errors import PosegenError
from posegen.io import (
    ROUTE_ARRAYS,
    JointStates,
    RecordedBag,
    Wrenches,
    load_postures,
    pool_from_dict,
    read_arrays,
    read_route,
    sidecars_of,
    write_pool,
    write_recording,
    write_with_arrays,
)
from posegen.io.pool_file import ARRAY_NAMES
from posegen.model import read_measurements
from posegen.robot import Scene, load_config
from tests.conftest import CONFIG, EXAMPLE_POOL
from tests.robustness.strategies import (
    NAMES,
    NUMBERS,
    SCALARS,
    SESSION_MUTATIONS,
    array_mutations,
    damaged,
    edited_csv,
    mutate_arrays,
    mutated,
)
from tests.robustness.test_readers import POOL_DATA, csv_text, dump, selection_data

DELETE = "<delete>"  # a header mutation that removes the node
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
@example(spec=("header", 95, None))  # corpus: the route's saved config made malformed (export now refuses, as check)
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
            damage(sidecars_of(route)[0], spec[1], spec[2])
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
            # export reads a route as check does: the reader's rules, the robot's names, the config it was made with
            assert codes["export"] == 0 or codes["check"] == 2, codes


# --- pools, selections, measurements and recorded sessions through the commands that read them ----

FAST = max(settings().max_examples // 8, 10)  # 0.1-3 s an example: 10 in make test, 100 in make fuzz
CAPSYS = [*settings().suppress_health_check, HealthCheck.function_scoped_fixture]  # capsys: read per run
JOINT_TOPIC = "/joint_states"


@dataclass(frozen=True, repr=False)
class Inputs:
    """Valid artefacts to mutate: a version-2 pool, a selection, measurements (YAML, CSV), a recorded session."""

    folder: Path  # the valid files, copied beside each mutated one (a pool, its measurements, a route)
    pool: tuple[dict[str, Any], dict[str, np.ndarray]]  # header (no sidecar reference), arrays
    selection: dict[str, Any]
    measurements: dict[str, Any]
    csv: str
    joints: JointStates
    wrenches: dict[str, Wrenches]

    def _repr_pretty_(self, printer: Any, cycle: bool) -> None:
        printer.text("Inputs(...)")  # a failing example names its mutation, not these 50 kB


@pytest.fixture(scope="module")
def inputs(tmp_path_factory, route_file) -> Inputs:
    folder = tmp_path_factory.mktemp("valid")
    pool = pool_from_dict(POOL_DATA, str(EXAMPLE_POOL))
    write_pool(folder / "pool.yaml", pool)
    assert main(["simulate", str(folder / "pool.yaml"), "--seed", "1", "-o", str(folder / "m.yaml"), "-q"]) == 0
    shutil.copy(route_file, folder / "route.yaml")  # its header names its sidecar, copied beside it
    for sidecar in sidecars_of(route_file):
        shutil.copy(sidecar, folder / sidecar.name)
    bag = tmp_path_factory.mktemp("bag") / "session"
    assert main(["simulate", str(route_file), "--rate", "50", "--bag", str(bag), "-q"]) == 0
    scene = Scene(load_config(CONFIG))
    topics = wrench_topics(scene)
    joints, wrenches = RecordedBag(bag).read(JOINT_TOPIC, list(topics.values()))
    return Inputs(
        folder,
        pool.to_arrays(),
        selection_data(),
        yaml.safe_load((folder / "m.yaml").read_text()),
        csv_text(scene),
        joints,
        dict(zip(topics.values(), wrenches, strict=True)),
    )


def tree(folder: Path) -> dict[str, str]:
    """Every file under ``folder`` (sub-folders included) and its sha256."""
    return {
        str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest() if p.is_file() else "folder"
        for p in folder.rglob("*")
    }


def agree(given: Path, accepted: bool, fast: dict[str, list[str]], slow: dict[str, list[str]], capsys) -> None:
    """Run the commands on the inputs in ``given`` (outputs elsewhere) and check what each must do.

    No traceback, exit 0, 1 or 2 with one line on 2 (:func:`run`), no file under
    ``given`` changed, added or removed, and no exit 0 on what the readers refuse. The
    ``slow`` commands (seconds on a valid input: ``view``, ``route``, ``calibrate``) run
    only on a refused input, which they must refuse before any work.
    """
    event("the readers accept" if accepted else "the readers refuse")
    before = tree(given)
    codes = {name: run(argv, capsys) for name, argv in (fast if accepted else fast | slow).items()}
    assert tree(given) == before, codes  # no input changed
    if not accepted:
        assert 0 not in codes.values(), codes


def accepts(read: Any, *args: Any) -> bool:
    try:
        read(*args)
    except PosegenError:
        return False
    return True


@contextmanager
def folders(inputs: Inputs) -> Iterator[tuple[Path, Path]]:
    """A fresh folder of inputs (the valid ones copied in) and one for the outputs."""
    with tempfile.TemporaryDirectory() as folder:
        given, out = Path(folder) / "in", Path(folder) / "out"
        shutil.copytree(inputs.folder, given)
        out.mkdir()
        yield given, out


def plan_commands(plan: Path, given: Path, out: Path) -> tuple[dict[str, list[str]], dict[str, list[str]]]:
    """The commands that read a pool or a selection: fast ones, and slow ones (see :func:`agree`)."""
    fast = {
        "simulate": ["simulate", str(plan), "-o", str(out / "m.yaml")],
        "check": ["check", str(plan), "--workers", "1"],
    }
    if plan.name == "pool.yaml":
        fast["select --given"] = [
            "select",
            str(plan),
            "--k",
            "2",
            "--given",
            str(given / "m.yaml"),
            "-o",
            str(out / "f.yaml"),
        ]
    slow = {
        "view --html": ["view", str(plan), "--html", str(out / "page.html")],
        "route": ["route", str(plan), "--workers", "1", "-o", str(out / "route.yaml")],
    }
    return fast, slow


POOL_MUTATIONS = st.one_of(
    array_mutations(ARRAY_NAMES).map(lambda spec: ("arrays", spec)),
    st.tuples(st.just("names"), st.sampled_from(["joint_names", "chains", "spots"]), st.integers(0, 64), NAMES),
    st.tuples(st.just("header"), st.integers(0, 10**6), st.one_of(SCALARS, st.just(DELETE))),
    st.tuples(st.just("sidecar"), st.integers(0, 10**6), st.binary(max_size=16)),
)


@settings(max_examples=FAST, suppress_health_check=CAPSYS)
@given(spec=POOL_MUTATIONS)
@example(spec=("arrays", ("kind", "joints", "complex128")))  # corpus: complex joints (a traceback in simulate)
@example(spec=("arrays", ("kind", "contact_xy_m", "complex128")))  # corpus: complex (a traceback in select --given)
def test_plan_commands_on_mutated_pools(inputs, spec, capsys):
    header, arrays = header_copy(inputs.pool[0]), {k: v.copy() for k, v in inputs.pool[1].items()}
    if spec[0] == "arrays":
        mutate_arrays(spec[1], arrays)
    elif spec[0] == "names":
        names = header[spec[1]]
        names[spec[2] % len(names)] = spec[3]
    elif spec[0] == "header":
        replace_node(header, spec[1], spec[2])
    with folders(inputs) as (given, out):
        pool = given / "pool.yaml"
        for old in sidecars_of(pool):
            old.unlink()
        try:
            write_with_arrays(pool, header, arrays)
        except (TypeError, ValueError, AttributeError, yaml.YAMLError):
            event("not written")
            return  # the mutation made a header that cannot be written: nothing to read
        if spec[0] == "sidecar":
            damage(sidecars_of(pool)[0], spec[1], spec[2])
        agree(given, accepts(load_postures, pool), *plan_commands(pool, given, out), capsys)


@settings(max_examples=FAST, suppress_health_check=CAPSYS)
@given(data=st.data())
def test_plan_commands_on_mutated_selections(inputs, data, capsys):
    document = inputs.selection
    text = data.draw(st.one_of(mutated(document).map(dump), damaged(dump(document)), cells(document, "postures")))
    with folders(inputs) as (given, out):
        selection = given / "selected.yaml"
        selection.write_bytes(text if isinstance(text, bytes) else text.encode())
        agree(given, accepts(load_postures, selection), *plan_commands(selection, given, out), capsys)


def measurement_commands(path: Path, given: Path, out: Path) -> tuple[dict[str, list[str]], dict[str, list[str]]]:
    """The commands that read measurements: ``select --given`` (fast) and ``calibrate`` (slow, see :func:`agree`)."""
    fast = {
        "select --given": [
            "select",
            str(given / "pool.yaml"),
            "--k",
            "2",
            "--given",
            str(path),
            "-o",
            str(out / "f.yaml"),
        ]
    }
    calibrate = ["calibrate", str(path), "--config", str(CONFIG), "--candidates", "offsets", "--prior-scale", "5"]
    slow = {"calibrate": [*calibrate, "--fold-seeds", "1", "--workers", "1", "-o", str(out / "cal")]}
    return fast, slow


@settings(max_examples=FAST, suppress_health_check=CAPSYS)
@given(data=st.data())
def test_measurement_commands_on_mutated_files(inputs, scene, data, capsys):
    document = inputs.measurements
    yaml_text = st.one_of(mutated(document).map(dump), damaged(dump(document)), cells(document, "contacts"))
    name, text = data.draw(
        st.one_of(
            st.tuples(st.just("m.yaml"), yaml_text),
            st.tuples(st.just("recorded.csv"), st.one_of(edited_csv(inputs.csv), damaged(inputs.csv))),
        )
    )
    with folders(inputs) as (given, out):
        path = given / name
        path.write_bytes(text if isinstance(text, bytes) else text.encode())
        agree(given, accepts(read_measurements, path, scene), *measurement_commands(path, given, out), capsys)


@settings(max_examples=FAST, suppress_health_check=CAPSYS)
@given(data=st.data())
def test_measure_on_mutated_sessions(inputs, data, capsys):
    joints, wrenches = inputs.joints, dict(inputs.wrenches)
    spec = data.draw(st.one_of(SESSION_MUTATIONS, st.just(("file",))))
    joints, wrenches = mutate_session(spec, joints, wrenches)
    with folders(inputs) as (given, out):
        bag = given / "session"
        try:
            with np.errstate(all="ignore"):
                write_recording(bag, joints, JOINT_TOPIC, wrenches, {"seed": 0})
        except (ValueError, OverflowError, TypeError, IndexError, PosegenError):  # IndexError: no sample left
            event("not written")
            return  # a session the writer cannot encode: nothing to read
        if spec[0] == "file":
            target = bag / data.draw(st.sampled_from(sorted(p.name for p in bag.iterdir())))
            target.write_bytes(data.draw(damaged(target.read_bytes())))
        accepted = accepts(lambda: RecordedBag(bag).read(JOINT_TOPIC, list(inputs.wrenches)))
        measure = ["measure", str(bag), "--config", str(CONFIG)]
        fast = {
            "measure --route": [*measure, "--route", str(given / "route.yaml"), "-o", str(out / "a.yaml")],
            "measure": [*measure, "-o", str(out / "b.yaml")],
        }
        agree(given, accepted, fast, {}, capsys)


def mutate_session(
    spec: tuple[Any, ...], joints: JointStates, wrenches: dict[str, Wrenches]
) -> tuple[JointStates, dict[str, Wrenches]]:
    """A recorded session with one :data:`SESSION_MUTATIONS` applied (``file``: none, the bytes are damaged)."""
    kind, *args = spec
    names, times, positions = list(joints.names), joints.times_s.copy(), joints.positions.copy()
    n, nj = positions.shape
    if kind == "joint":
        positions[args[0] % n, args[1] % nj] = args[2]
    elif kind == "force":
        topic = sorted(wrenches)[args[0] % len(wrenches)]
        w = wrenches[topic]
        forces, torques = w.forces.copy(), w.torques.copy()
        (forces if args[2] < 3 else torques)[args[1] % len(forces), args[2] % 3] = args[3]
        wrenches[topic] = Wrenches(w.times_s, forces, torques)
    elif kind == "time":
        how, k, value = args
        k = 1 + k % (n - 2)
        if how == "repeat":
            times[k] = times[k - 1]
        elif how == "back":
            times[k:] -= 3.0  # the clock jumps back 3 s, as in the issue
        elif how == "jump":
            times[k] = value
        else:
            times[[k, k + 1]] = times[[k + 1, k]]
    elif kind == "name":
        names[args[0] % nj] = names[args[0] % nj - 1] if args[1] == "<duplicate>" else args[1]
    elif kind == "drop_joint":
        del names[args[0] % nj]
        positions = np.delete(positions, args[0] % nj, axis=1)
    elif kind == "cut":
        keep = int(args[0] * n)
        times, positions = times[:keep], positions[:keep]
        wrenches = {t: Wrenches(w.times_s[:keep], w.forces[:keep], w.torques[:keep]) for t, w in wrenches.items()}
    elif kind == "drop_topic":
        del wrenches[sorted(wrenches)[args[0] % len(wrenches)]]
    return JointStates(tuple(names), times, positions), wrenches


@st.composite
def cells(draw: st.DrawFn, document: dict[str, Any], key: str) -> str:
    """``document`` with one joint angle of one of its ``key`` entries made NaN, infinite, huge or another value."""
    doc = header_copy(document)
    entries = doc[key]
    entry = entries[draw(st.integers(0, len(entries) - 1))]
    entry["joints"][draw(st.integers(0, len(entry["joints"]) - 1))] = draw(NUMBERS)
    return dump(doc)


def damage(path: Path, at: int, patch: bytes) -> None:
    """Cut ``path`` short at ``at`` (no patch), or overwrite its bytes there."""
    content = path.read_bytes()
    at %= len(content)
    path.write_bytes(content[:at] + patch + (content[at + len(patch) :] if patch else b""))
