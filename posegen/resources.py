"""The files shipped with posegen: the robots' configs (``configs/``) and the example pool (under ``plans/``).

The top-level folders of the source tree are the source; a wheel carries a copy of the
shipped ones in ``posegen/_data/`` (``setup.py`` names them and copies them at build
time). A relative path into one of them (``configs/talos_table.yaml``, the commands'
default) is read where it is when it exists there, else from posegen's copy, so the
commands and scripts work outside the checkout too.
"""

from __future__ import annotations

from pathlib import Path

ROOTS = ("configs", "plans")  # top-level folders the shipped files live in (setup.py: which of them ship)
DATA = Path(__file__).resolve().parent / "_data"  # the wheel's copy
CHECKOUT = Path(__file__).resolve().parents[1]  # the source tree, when posegen runs from one
DEFAULT_CONFIG = "configs/talos_table.yaml"  # the commands' default scene


def shipped_path(path: str | Path) -> Path:
    """Where to read ``path``: itself when it exists, else posegen's copy of a shipped file.

    Args:
        path: A file path; a relative one into :data:`ROOTS` folders that does not exist
            from here is read from posegen's copy (the wheel's, or the source tree's when
            posegen runs from a checkout and the working folder is elsewhere).

    Returns:
        ``path`` itself when it exists, is absolute or is outside those folders, or no copy
        has it; else the copy.

    Example:
        >>> shipped_path("configs/talos_table.yaml").is_file()
        True

    """
    given = Path(path)
    if given.is_absolute() or given.exists() or given.parts[:1] not in {(root,) for root in ROOTS}:
        return given
    for base in (DATA, CHECKOUT):
        if (base / given).is_file():
            return base / given
    return given
