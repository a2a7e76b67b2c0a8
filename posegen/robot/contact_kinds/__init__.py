"""Contact kinds: how a hand touches the table, one object per kind (:mod:`.kind`).

``KINDS`` registers them: configs, measurement files and residual tables name a kind
by its ``value`` and :func:`kind_named` finds it here. A new kind is one module beside
``flush`` and ``point`` (a :class:`ContactKind` subclass and its instance) plus its line
in ``KINDS``.
"""

from posegen.robot.contact_kinds.flush import FLUSH, contact_placement
from posegen.robot.contact_kinds.kind import ContactKind
from posegen.robot.contact_kinds.point import POINT

KINDS: tuple[ContactKind, ...] = (FLUSH, POINT)  # the registered kinds, in their name's order
DEFAULT_KIND: ContactKind = FLUSH  # what a chain plans, and a contact is, when none is named


def registered_kinds() -> tuple[ContactKind, ...]:
    """The registered kinds (read at call time: a test may register one)."""
    return KINDS


def kind_named(name: str) -> ContactKind:
    """The registered kind called ``name``.

    Raises:
        ValueError: No kind is called so (the message lists the valid ones).

    """
    for kind in registered_kinds():
        if kind.value == name:
            return kind
    valid = ", ".join(k.value for k in registered_kinds())
    raise ValueError(f"unknown kind '{name}'; valid kinds: {valid}")


__all__ = [
    "DEFAULT_KIND",
    "FLUSH",
    "KINDS",
    "POINT",
    "ContactKind",
    "contact_placement",
    "kind_named",
    "registered_kinds",
]
