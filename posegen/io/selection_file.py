"""The selection file (``format: posegen-selection``) as an object: :class:`Selection`, its reader and writer.

The file reads like a pool (the same posture fields, so ``simulate`` and ``route`` take
either) plus, per posture, ``pool_id``, ``rank`` (IROC rank; 0 for a posture planned
again) and ``weight`` (IROC weight, or the follow-up's gain), and the figures of the
selection, whose fields depend on its method::

    format: posegen-selection
    format_version: 1
    provenance: {posegen_version, robot_model_sha256, seed, config, pool, pool_sha256, ...}
    method: iroc | k | followup | session
    joint_names: [...]
    figures: {...}              # DesignFigures (iroc, k), FollowUpFigures, SessionFigures
    postures: [{pool_id, rank, weight, id, sample, chain, spot, joints, ...}, ...]

:func:`read_selection` reads the whole file; the stages read a pool's or a selection's postures
with :func:`load_postures`, which checks a selection whole (a file ``route`` takes is one ``posegen.load`` takes).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Generic, TypeVar

from posegen.errors import InputError, reason
from posegen.io.artefact import read_yaml, write_yaml
from posegen.io.pool_file import (
    POOL_FORMAT,
    POOL_VERSION,
    SELECTION_FORMAT,
    Pool,
    Posture,
    pool_from_dict,
    posture_from_dict,
)
from posegen.numeric import is_finite_number


class SelectionMethod(str, enum.Enum):
    """How a selection's postures were chosen."""

    IROC = "iroc"  # the IROC top k, where O1 stops rising
    K = "k"  # an exact design of k postures
    FOLLOWUP = "followup"  # select --given: for the weakest chain of a calibration
    SESSION = "session"  # a session's batch: the missing postures, then a follow-up


@dataclass(frozen=True)
class ChosenPosture:
    """A pool posture in a selection."""

    pool_id: int  # its row in the pool
    rank: int  # IROC rank (1 first), the follow-up's order, 0 for a posture planned again
    weight: float  # IROC weight, the follow-up's gain, 0.0 for a posture planned again
    posture: Posture

    def to_dict(self) -> dict[str, Any]:
        """The posture's entry in the file."""
        return {"pool_id": self.pool_id, "rank": self.rank, "weight": self.weight, **self.posture.to_dict(self.pool_id)}


def chosen_from_pool(pool: Pool, row: int, rank: int, weight: float) -> ChosenPosture:
    """Row ``row`` of a pool, chosen."""
    return ChosenPosture(pool_id=int(row), rank=rank, weight=weight, posture=pool.postures[row])


@dataclass(frozen=True)
class Certificate:
    """How close the continuous weights are to D-optimal."""

    kiefer_wolfowitz_gap: float
    d_efficiency_at_least: float
    o1_ratio_at_least: float
    iterations: int


@dataclass(frozen=True)
class IrocFigures:
    """IROC's ranking, where it stops, and the k reaching fractions of O1*."""

    selected_k: int
    selected_o1: float
    k_reaching_fraction_of_o1_star: dict[str, int | None]  # fraction (as written) -> smallest k; None: never
    support: int  # postures with a non-negligible weight
    weight_drop_after_rank: int
    o1_curve: tuple[tuple[int, float], ...]  # (k, O1 of the top k)


@dataclass(frozen=True)
class DetmaxFigures:
    """The DETMAX runs from seeded random starts."""

    o1: tuple[float, ...]
    rank: tuple[int, ...]

    @property
    def runs(self) -> int:
        """Number of runs."""
        return len(self.o1)

    @property
    def best_o1(self) -> float | None:
        """The best run's O1; None without runs."""
        return max(self.o1, default=None)


@dataclass(frozen=True)
class DesignFigures:
    """What a design from a pool (method ``iroc`` or ``k``) achieves."""

    base_parameters: int
    pool_postures: int
    selected: int
    rank: int  # base parameters the selection identifies
    o1: float
    o1_star: float  # O1 of the optimal continuous design
    o1_over_o1_star: float
    certificate: Certificate
    iroc: IrocFigures
    detmax: DetmaxFigures


@dataclass(frozen=True)
class FollowUpFigures:
    """What a follow-up (method ``followup``) is for and what it predicts."""

    selected: int
    pool_postures: int
    given_contacts: int
    excluded_postures: int | None  # pool postures never chosen (a session's); None: none given
    candidate: str  # the calibration model designed with
    prior_scale: float
    weakest_chain: str
    weakest_from: str  # where the weakest chain came from
    predicted_height_sigma_mm: dict[str, tuple[float, float]]  # chain -> (before, after), mm


@dataclass(frozen=True)
class SessionFigures:
    """A session's batch (method ``session``): the postures planned again, and the follow-up's figures."""

    missing_postures: tuple[int, ...]  # pool rows planned again, first
    follow_up: FollowUpFigures | None  # None: only the missing postures


Figures = DesignFigures | FollowUpFigures | SessionFigures
F = TypeVar("F", bound=Figures)


@dataclass(frozen=True)
class Selection(Generic[F]):
    """A selection file: the chosen postures, their provenance and the figures of their choice.

    Example:
        >>> chosen = posegen.select_postures("plans/pool.yaml", "plans/selected.yaml")
        >>> [p.pool_id for p in chosen.postures][:5], chosen.method

    """

    provenance: dict[str, Any]  # the pool's, with the seed, the pool's path and SHA-256 (and a follow-up's inputs)
    method: SelectionMethod
    joint_names: tuple[str, ...]
    figures: F
    postures: tuple[ChosenPosture, ...]

    def to_dict(self) -> dict[str, Any]:
        """The file's content."""
        head = {
            "format": SELECTION_FORMAT,
            "format_version": POOL_VERSION,
            "provenance": self.provenance,
            "method": self.method.value,
            "joint_names": list(self.joint_names),
        }
        return {**head, "figures": figures_to_dict(self.figures), "postures": [p.to_dict() for p in self.postures]}


def figures_to_dict(figures: Figures) -> dict[str, Any]:
    """The ``figures`` section of a selection file."""
    if isinstance(figures, SessionFigures):
        out: dict[str, Any] = {"missing_postures": list(figures.missing_postures)}
        if figures.follow_up is not None:
            out["follow_up"] = figures_to_dict(figures.follow_up)
        return out
    if isinstance(figures, FollowUpFigures):
        return {
            "selected": figures.selected,
            "pool_postures": figures.pool_postures,
            "given_contacts": figures.given_contacts,
            **({} if figures.excluded_postures is None else {"excluded_postures": figures.excluded_postures}),
            "model": {"candidate": figures.candidate, "prior_scale": figures.prior_scale},
            "weakest_chain": figures.weakest_chain,
            "weakest_from": figures.weakest_from,
            "predicted_height_sigma_mm": {
                c: {"before": b, "after": a} for c, (b, a) in figures.predicted_height_sigma_mm.items()
            },
        }
    c, i, d = figures.certificate, figures.iroc, figures.detmax
    return {
        "base_parameters": figures.base_parameters,
        "pool_postures": figures.pool_postures,
        "selected": figures.selected,
        "rank": figures.rank,
        "o1": figures.o1,
        "o1_star": figures.o1_star,
        "o1_over_o1_star": figures.o1_over_o1_star,
        "certificate": {
            "kiefer_wolfowitz_gap": c.kiefer_wolfowitz_gap,
            "d_efficiency_at_least": c.d_efficiency_at_least,
            "o1_ratio_at_least": c.o1_ratio_at_least,
            "iterations": c.iterations,
        },
        "iroc": {
            "selected_k": i.selected_k,
            "selected_o1": i.selected_o1,
            "k_reaching_fraction_of_o1_star": dict(i.k_reaching_fraction_of_o1_star),
            "support": i.support,
            "weight_drop_after_rank": i.weight_drop_after_rank,
            "o1_curve": [[k, v] for k, v in i.o1_curve],
        },
        "detmax": {"runs": d.runs, "o1": list(d.o1), "rank": list(d.rank), "best_o1": d.best_o1},
    }


def write_selection(path: str | Path, selection: Selection[Any]) -> None:
    """Write a selection file, atomically."""
    write_yaml(path, selection.to_dict())


def read_selection(path: str | Path) -> Selection[Figures]:
    """Read a selection file: its postures, provenance and figures.

    Raises:
        InputError: The file is missing, not a selection, or malformed.

    """
    return selection_from_dict(read_yaml(path, SELECTION_FORMAT), str(path))


def selection_from_dict(data: dict[str, Any], where: str = "selection") -> Selection[Figures]:
    """Parse and validate plain data in the selection file format.

    Raises:
        InputError: The data is not a valid selection.

    """
    if data.get("format_version") != POOL_VERSION or isinstance(data.get("format_version"), bool):
        raise InputError(f"{where}: unsupported format_version {data.get('format_version')!r} (this posegen reads 1)")
    try:
        method = SelectionMethod(data["method"])
        names = tuple(data["joint_names"])
        if not all(isinstance(n, str) for n in names) or not isinstance(data["provenance"], dict):
            raise TypeError("joint_names must be names and provenance a mapping")
        figures = _figures(method, data["figures"])
        raw_postures = list(data["postures"])
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise InputError(f"{where}: not a posegen selection ({reason(exc)})") from exc
    postures = []
    for i, raw in enumerate(raw_postures):
        at = f"{where}: posture {i}"
        postures.append(_chosen(raw, posture_from_dict(raw, len(names), at), at))
    if isinstance(figures, DesignFigures | FollowUpFigures):
        _check_design(figures, postures, where)
    return Selection(dict(data["provenance"]), method, names, figures, tuple(postures))


def _check_design(figures: DesignFigures | FollowUpFigures, postures: list[ChosenPosture], where: str) -> None:
    """Each posture a row of the design's pool, weighed zero or more (InputError naming it).

    A selection trimmed by hand (fewer postures than ``figures.selected``) or holding a
    posture twice (``route`` routes it once, and says so) is read as it is.
    """
    for i, chosen in enumerate(postures):
        if not 0 <= chosen.pool_id < figures.pool_postures:
            raise InputError(
                f"{where}: posture {i}: pool_id {chosen.pool_id} is not a row of its pool "
                f"(figures.pool_postures {figures.pool_postures})"
            )
        if chosen.weight < 0.0:
            raise InputError(f"{where}: posture {i}: 'weight' {chosen.weight:g} is negative")


def _chosen(raw: dict[str, Any], posture: Posture, where: str) -> ChosenPosture:
    """A posture's place in the selection: ``pool_id`` and ``rank`` integers, ``weight`` a finite number.

    Raises:
        InputError: A field missing or of another kind, named.

    """
    for name in ("pool_id", "rank"):
        value = raw.get(name)
        if not isinstance(value, int) or isinstance(value, bool):
            raise InputError(f"{where}: '{name}' must be an integer, got {value!r}")
    weight = raw.get("weight")
    if not is_finite_number(weight):
        raise InputError(f"{where}: 'weight' must be a finite number, got {weight!r}")
    return ChosenPosture(raw["pool_id"], raw["rank"], float(weight), posture)


def _figures(method: SelectionMethod, raw: dict[str, Any]) -> Figures:
    """The figures of a selection made by ``method`` (KeyError, TypeError, ValueError when malformed)."""
    if method == SelectionMethod.SESSION:
        follow = raw.get("follow_up")
        return SessionFigures(
            tuple(int(r) for r in raw["missing_postures"]), None if follow is None else _follow_up(follow)
        )
    if method == SelectionMethod.FOLLOWUP:
        return _follow_up(raw)
    c, i, d = raw["certificate"], raw["iroc"], raw["detmax"]
    return DesignFigures(
        base_parameters=int(raw["base_parameters"]),
        pool_postures=int(raw["pool_postures"]),
        selected=int(raw["selected"]),
        rank=int(raw["rank"]),
        o1=float(raw["o1"]),
        o1_star=float(raw["o1_star"]),
        o1_over_o1_star=float(raw["o1_over_o1_star"]),
        certificate=Certificate(
            float(c["kiefer_wolfowitz_gap"]),
            float(c["d_efficiency_at_least"]),
            float(c["o1_ratio_at_least"]),
            int(c["iterations"]),
        ),
        iroc=IrocFigures(
            selected_k=int(i["selected_k"]),
            selected_o1=float(i["selected_o1"]),
            k_reaching_fraction_of_o1_star={
                str(f): None if k is None else int(k) for f, k in dict(i["k_reaching_fraction_of_o1_star"]).items()
            },
            support=int(i["support"]),
            weight_drop_after_rank=int(i["weight_drop_after_rank"]),
            o1_curve=tuple((int(k), float(v)) for k, v in i["o1_curve"]),
        ),
        detmax=DetmaxFigures(tuple(float(v) for v in d["o1"]), tuple(int(r) for r in d["rank"])),
    )


def _follow_up(raw: dict[str, Any]) -> FollowUpFigures:
    excluded = raw.get("excluded_postures")
    return FollowUpFigures(
        selected=int(raw["selected"]),
        pool_postures=int(raw["pool_postures"]),
        given_contacts=int(raw["given_contacts"]),
        excluded_postures=None if excluded is None else int(excluded),
        candidate=str(raw["model"]["candidate"]),
        prior_scale=float(raw["model"]["prior_scale"]),
        weakest_chain=str(raw["weakest_chain"]),
        weakest_from=str(raw["weakest_from"]),
        predicted_height_sigma_mm={
            str(c): (float(s["before"]), float(s["after"])) for c, s in dict(raw["predicted_height_sigma_mm"]).items()
        },
    )


def load_postures(path: str | Path) -> tuple[Pool, list[dict[str, Any]]]:
    """Read a pool or a selection that has postures: the postures, and their entries as plain data.

    Example:
        >>> postures, entries = load_postures("plans/pool.yaml")  # doctest: +SKIP

    Raises:
        InputError: The file is missing, malformed (a selection: as :func:`read_selection`
            finds it), neither a pool nor a selection, or empty.

    """
    return postures_from_dict(read_yaml(path, (POOL_FORMAT, SELECTION_FORMAT)), str(path))


def postures_from_dict(data: dict[str, Any], where: str) -> tuple[Pool, list[dict[str, Any]]]:
    """The postures of a pool's or a selection's content, and their entries as plain data.

    Raises:
        InputError: The content is not a valid pool or selection, or has no postures.

    """
    chosen = postures_of(data, where)
    if not chosen.postures:
        raise InputError(f"{where}: no postures")
    return chosen, posture_entries(data, chosen)


def postures_of(data: dict[str, Any], where: str) -> Pool:
    """The postures of a pool's or a selection's content; a selection is checked whole, as :func:`read_selection` does.

    Raises:
        InputError: The content is not a valid pool or selection.

    """
    if data.get("format") == SELECTION_FORMAT:
        selection_from_dict(data, where)  # its method, figures and each posture's pool_id, rank and weight
    return pool_from_dict(data, where)


def posture_entries(data: dict[str, Any], chosen: Pool) -> list[dict[str, Any]]:
    """The posture entries of a pool or selection file as plain data (a version-2 pool has none inline)."""
    if "postures" in data:
        return list(data["postures"])
    return [chosen.entry(i) for i in range(len(chosen.postures))]
