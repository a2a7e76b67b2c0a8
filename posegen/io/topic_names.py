"""ROS 2 topic names as a rosbag2 stores them: fully qualified, one per stream.

A bag keeps each topic's fully qualified name (``/ns/name``). ROS 2's rules for it
(``rmw_validate_full_topic_name``): it starts with ``/``, holds only letters, digits,
``_`` and ``/``, has no empty token (``//``) and no trailing ``/``, and no token starts
with a digit. A bag posegen writes also gives every stream its own topic: two streams on
one topic would interleave two message types, a bag no reader can play.
"""

from __future__ import annotations

import re
from collections.abc import Mapping

from posegen.errors import ArgumentError

_TOKEN = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def topic_name_problem(name: object) -> str | None:
    """What makes ``name`` no fully qualified ROS 2 topic name, or None when it is one.

    Example:
        >>> topic_name_problem("/joint_states") is None
        True
        >>> topic_name_problem("joint_states")
        "a ROS 2 topic name starts with '/', got 'joint_states'"

    """
    if not isinstance(name, str) or not name:
        return f"expected a ROS 2 topic name such as '/joint_states', got {name!r}"
    if not name.startswith("/"):
        return f"a ROS 2 topic name starts with '/', got {name!r}"
    tokens = name[1:].split("/")
    if not all(_TOKEN.fullmatch(token) for token in tokens):
        return (
            f"a ROS 2 topic name is '/'-separated tokens of letters, digits and '_', none empty or "
            f"starting with a digit, got {name!r}"
        )
    return None


def check_topics(topics: Mapping[str, str]) -> None:
    """Check the topics of a bag to write: each a valid name, no two the same.

    Args:
        topics: parameter (or config field) -> topic name, in the order they are reported.

    Example:
        >>> check_topics({"topic": "/trajectory", "segments_topic": "/segments"})

    Raises:
        ArgumentError: A name that is not a fully qualified topic name, or two parameters
            naming one topic (the error names the parameter).

    """
    seen: dict[str, str] = {}
    for parameter, name in topics.items():
        problem = topic_name_problem(name)
        if problem is not None:
            raise ArgumentError(f"{parameter}: {problem}", parameter=parameter)
        if name in seen:
            raise ArgumentError(
                f"{parameter}: '{name}' is already in use (by {seen[name]}); give each stream its own topic",
                parameter=parameter,
            )
        seen[name] = parameter
