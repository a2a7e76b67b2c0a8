"""The files shipped with posegen: the robots' configs (``configs/``) and the example pool (``plans/talos/``).

The top-level folders of the source tree are the source; a wheel carries a copy of them
in ``posegen/_data/`` (``setup.py`` copies them at build time). A relative path into one
of them (``configs/talos_table.yaml``, the commands' default) is read where it is when it
exists there, else from posegen's copy, so the commands and scripts work outside the
checkout too.
"""

from __future__ import annotations

from pathlib import Path

SHIPPED = ("configs", "plans/talos")  # folders copied into the wheel, relative to the source tree
DATA = Path(__file__).resolve().parent / "_data"  # the wheel's copy
CHECKOUT = Path(__file__).resolve().parents[1]  # the source tree, when posegen runs from one
EXAMPLE_POOL = "plans/talos/pool.yaml"  # 200 feasible postures of TALOS at its table
DEFAULT_CONFIG = "configs/talos_table.yaml"  # TALOS at its table


def shipped_path(path: str | Path) -> Path:
    """Where to read ``path``: itself when it exists, else posegen's copy of a shipped file.

    Args:
        path: A file path; relative ones into :data:`SHIPPED` folders may be read from
            posegen's copy (the wheel's, or the source tree's when run elsewhere).

    Returns:
        ``path`` itself when it exists, is absolute or is outside the shipped folders, or
        no copy has it; else the copy.

    Example:
        >>> shipped_path("configs/talos_table.yaml").is_file()
        True

    """
    given = Path(path)
    if given.is_absolute() or given.exists():
        return given
    if not any(given.as_posix().startswith(f"{folder}/") for folder in SHIPPED):
        return given
    for base in (DATA, CHECKOUT):
        if (base / given).is_file():
            return base / given
    return given


def shipped_files() -> list[str]:
    """Every shipped file, as its path relative to the source tree (``configs/talos_table.yaml``)."""
    base = DATA if DATA.is_dir() else CHECKOUT
    return sorted(
        p.relative_to(base).as_posix() for folder in SHIPPED for p in (base / folder).rglob("*") if p.is_file()
    )
