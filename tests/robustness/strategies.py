"""Hypothesis strategies for bad input: any YAML value; documents, arrays, CSVs, sessions mutated; damaged files."""

from __future__ import annotations

import copy
import math
from typing import Any

import numpy as np
from hypothesis import strategies as st

SCALARS = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(min_value=-(2**70), max_value=2**70),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=12),
    st.sampled_from(["", "left", "right", "posegen-pool", "free", "nan", "1e999", "-0", "joint_names"]),
)
VALUES = st.recursive(
    SCALARS,
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=8), inner, max_size=4),
    max_leaves=10,
)


@st.composite
def mutated(draw: st.DrawFn, document: Any, edits: int = 3) -> Any:
    """``document`` with one to ``edits`` nodes replaced by any value, deleted, or lists cut short."""
    doc = copy.deepcopy(document)
    for _ in range(draw(st.integers(1, edits))):
        parent: Any = None
        key: Any = None
        node = doc
        while isinstance(node, (dict, list)) and node and draw(st.integers(0, 4)) > 0:  # mostly go deeper
            key = draw(st.sampled_from(list(node) if isinstance(node, dict) else range(len(node))))
            parent, node = node, node[key]
        action = draw(st.sampled_from(["replace", "delete", "truncate"]))
        if action == "truncate" and isinstance(node, list):
            del node[draw(st.integers(0, len(node))) :]
        elif parent is None:
            doc = draw(VALUES)
        elif action == "delete":
            del parent[key]
        else:
            parent[key] = draw(VALUES)
    return doc


@st.composite
def damaged(draw: st.DrawFn, content: str | bytes) -> bytes:
    """The bytes of ``content`` damaged as files get damaged: cut short, bytes overwritten, or noise."""
    data = content.encode() if isinstance(content, str) else content
    kind = draw(st.sampled_from(["truncate", "overwrite", "noise", "empty", "bom-crlf"]))
    if kind == "truncate":
        return data[: draw(st.integers(0, max(len(data) - 1, 0)))]
    if kind == "overwrite":
        start = draw(st.integers(0, max(len(data) - 1, 0)))
        patch = draw(st.binary(min_size=1, max_size=16))
        return data[:start] + patch + data[start + len(patch) :]
    if kind == "noise":
        return draw(st.binary(max_size=256))
    if kind == "empty":
        return b""
    return b"\xef\xbb\xbf" + data.replace(b"\n", b"\r\n")


# --- artefacts as the commands read them: arrays, CSV text, recorded sessions -----------------------

NUMBERS = st.sampled_from([math.nan, math.inf, -math.inf, 1e39, -1e39, 1e300, 0.0, -1.0, 4.0])
NAMES = st.one_of(st.text(max_size=12), st.sampled_from(["", "left", "right", "arm_left_1_joint", "x" * 300]))


def array_mutations(names: tuple[str, ...]) -> st.SearchStrategy[tuple[Any, ...]]:
    """A mutation of named arrays (a sidecar's): a value, a row or column gone, all cut to k rows, a kind changed."""
    return st.one_of(
        st.tuples(st.just("cell"), st.sampled_from(names), st.integers(0, 10**6), st.integers(0, 64), NUMBERS),
        st.tuples(st.just("drop_row"), st.sampled_from(names), st.integers(0, 10**6)),
        st.tuples(st.just("drop_column"), st.sampled_from(names), st.integers(0, 64)),
        st.tuples(st.just("rows"), st.integers(0, 3)),
        st.tuples(st.just("integer"), st.sampled_from(names), st.integers(-(2**40), 2**40)),
        st.tuples(st.just("kind"), st.sampled_from(names), st.sampled_from(["float32", "int8", "bool", "complex128"])),
    )


def mutate_arrays(spec: tuple[Any, ...], arrays: dict[str, np.ndarray]) -> None:
    """Apply an :func:`array_mutations` spec to ``arrays``, in place."""
    kind, *args = spec
    if kind == "rows":
        for name in arrays:
            arrays[name] = arrays[name][: args[0]]
        return
    name = args[0]
    values = arrays[name]
    if kind == "cell" and values.size:
        row, column, value = args[1:]
        where = (row % len(values),) if values.ndim == 1 else (row % len(values), column % values.shape[1])
        with np.errstate(over="ignore", invalid="ignore"):  # NaN into an integer array: a mutation like any other
            values = values.astype(float) if not np.issubdtype(values.dtype, np.floating) else values
            values[where] = value
    elif kind == "drop_row" and len(values):
        values = np.delete(values, args[1] % len(values), axis=0)
    elif kind == "drop_column":
        values = np.delete(values, args[1] % values.shape[1], axis=1) if values.ndim == 2 else values[:, None]
    elif kind == "integer" and values.size:
        values = values.astype(np.int64) if np.issubdtype(values.dtype, np.integer) else values.copy()
        values.flat[0] = args[1]
    elif kind == "kind":
        with np.errstate(over="ignore", invalid="ignore"):
            values = values.astype(args[1])
    arrays[name] = values


@st.composite
def edited_csv(draw: st.DrawFn, text: str) -> str:
    """CSV text edited as recordings get edited: cells, rows dropped or repeated, a column gone, a name changed."""
    rows = [line.split(",") for line in text.splitlines()]
    for _ in range(draw(st.integers(1, 3))):
        kind = draw(st.sampled_from(["cell", "drop_row", "repeat_row", "drop_column", "name", "short_row"]))
        k = draw(st.integers(0, len(rows) - 1)) if rows else 0
        if not rows:
            break
        if kind == "cell" or kind == "name":
            row = 0 if kind == "name" else k
            column = draw(st.integers(0, len(rows[row]) - 1))
            value = draw(NAMES) if kind == "name" else draw(st.one_of(NAMES, NUMBERS.map(repr), st.floats().map(repr)))
            rows[row][column] = value.replace(",", ";").replace("\n", " ").replace("\r", " ")
        elif kind == "drop_row":
            del rows[k]
        elif kind == "repeat_row":
            rows.insert(k, list(rows[k]))
        elif kind == "drop_column":
            column = draw(st.integers(0, max(len(r) for r in rows) - 1))
            rows = [[c for i, c in enumerate(r) if i != column] for r in rows]
        else:
            del rows[k][draw(st.integers(0, len(rows[k]))) :]
    return "\n".join(",".join(r) for r in rows) + "\n"


SESSION_MUTATIONS = st.one_of(
    st.tuples(st.just("joint"), st.integers(0, 10**6), st.integers(0, 64), NUMBERS),
    st.tuples(st.just("force"), st.integers(0, 8), st.integers(0, 10**6), st.integers(0, 5), NUMBERS),
    st.tuples(st.just("time"), st.sampled_from(["repeat", "back", "jump", "shuffle"]), st.integers(0, 10**6), NUMBERS),
    st.tuples(st.just("name"), st.integers(0, 64), st.one_of(NAMES, st.just("<duplicate>"))),
    st.tuples(st.just("drop_joint"), st.integers(0, 64)),
    st.tuples(st.just("cut"), st.floats(0.0, 1.0)),
    st.tuples(st.just("drop_topic"), st.integers(0, 8)),
)
