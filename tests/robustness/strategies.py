"""Hypothesis strategies for bad input: any YAML-like value, valid documents mutated, files damaged."""

from __future__ import annotations

import copy
from typing import Any

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
