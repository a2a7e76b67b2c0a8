"""Argument types and defaults shared by the subcommands.

The types run the checks of :mod:`posegen.arguments`, so a bad value is refused by the
parser, before any file is read, with the message a library caller would get.
"""

from __future__ import annotations

import argparse
import re
from collections.abc import Callable
from typing import TypeVar

from posegen.arguments import check_count, check_seed, check_size
from posegen.errors import PosegenError
from posegen.parallel import usable_cores

DEFAULT_CONFIG = "configs/talos_table.yaml"
EXIT_VIOLATIONS = 1  # a check found violations
JOINT_STATES_TOPIC = "/joint_states"  # ROS 2 convention (joint_state_broadcaster)

T = TypeVar("T")

FLAGS = {  # the library's words for a parameter (PosegenError.parameter) -> the flag that sets it
    "output": "-o",
    "seed": "--seed",
    "n": "--n",
    "workers": "--workers",
    "k": "--k",
    "runs": "--runs",
    "given": "--given",
    "min_dt": "--min-dt",
    "rate_hz": "--rate",
    "session": "--session",
    "route_path": "--route",
    "use_wrench=False": "--no-wrench",
    "config_path": "--config",
    "held_out": "--validate",
    "prior_scale": "--prior-scale",
    "fold_seeds": "--fold-seeds",
    "error_mm": "--error-mm",
    "error_deg": "--error-deg",
    "noise_deg": "--noise-deg",
    "compliance_rad_per_knm": "--compliance",
    "contact_noise_mm": "--contact-noise-mm",
    "contact_noise_deg": "--contact-noise-deg",
    "target_mm": "--target-mm",
    "margin": "--margin",
    "batch_postures": "--batch",
    "candidates": "--candidates",
    "max_batches": "--max-batches",
    "patience": "--patience",
    "package_dirs": "--package-dir",
    "topic": "--topic",
    "segments_topic": "--segments-topic",
    "joint_topic": "--joint-topic",
    "host": "--host",
}


def in_flags(error: PosegenError) -> str:
    """An error's message as the command line says it: the flag in place of the parameter it names.

    The parameter is the message's subject when the message starts with it, followed by
    ``=``, ``:`` or `` must `` (``k=80: ...`` reads ``--k 80: ...``); else its last mention
    is (advice: ``..., give config_path``), as a path given earlier may hold the same
    word. A message about no parameter, or one no flag sets, is left as is.
    """
    words = error.parameter
    text = str(error)
    if words is None or words not in FLAGS:
        return text
    mentions = list(re.finditer(rf"(?<![\w./-]){re.escape(words)}(?![\w./-])(=?)", text))  # words, not in a path
    if not mentions:
        return text
    subject = re.match(rf"{re.escape(words)}(=|:| must )", text) is not None
    found = mentions[0] if subject else mentions[-1]
    flag = FLAGS[words] + (" " if found.group(1) else "")
    return text[: found.start()] + flag + text[found.end() :]


def _checked(parse: Callable[[str], object], check: Callable[[object], T]) -> Callable[[str], T]:
    def convert(text: str) -> T:
        try:
            value = parse(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
        try:
            return check(value)
        except PosegenError as exc:
            raise argparse.ArgumentTypeError(str(exc).replace("value ", "", 1)) from None

    return convert


positive = _checked(int, lambda v: check_count(v, "value"))
non_negative = _checked(int, lambda v: check_count(v, "value", minimum=0))
seed = _checked(int, lambda v: check_seed(v, "value"))
size = _checked(float, lambda v: check_size(v, "value"))
port = _checked(int, lambda v: check_count(v, "value", minimum=0, maximum=65535))
positive_size = _checked(float, lambda v: check_size(v, "value", positive=True))


def fraction(text: str) -> float:
    """A fraction in (0, 1]."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not 0.0 < value <= 1.0:
        raise argparse.ArgumentTypeError(f"must be in (0, 1], got {value}")
    return value


def add_backend_arguments(parser: argparse.ArgumentParser) -> None:
    """``--workers`` and ``--scheduler``: where a command's independent jobs run."""
    parser.add_argument(
        "--workers", type=positive, default=usable_cores(), help="local worker processes (default: cores)"
    )
    parser.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        default=None,
        help="run on the Dask cluster of this scheduler (tcp://host:8786) instead of local processes",
    )


def session_name(text: str) -> str:
    """A table session's name: printable, not blank (a label, as ``FILE@SESSION`` gives one: '/' allowed)."""
    if not text.strip() or not text.isprintable():
        raise argparse.ArgumentTypeError(f"not a usable session name: {text!r}")
    return text
