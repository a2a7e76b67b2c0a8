"""The command line's words: a library error names a parameter; the command line shows its flag."""

import argparse
import ast
from pathlib import Path

import pytest

from posegen.cli.main import main
from posegen.cli.options import FLAGS, in_flags, session_name
from posegen.errors import ArgumentError, InputError
from posegen.route import route_postures_file
from posegen.select import SelectionSettings, select_pool_file

PACKAGE = Path(__file__).resolve().parents[2] / "posegen"
CHECKS = {"check_seed", "check_count", "check_size", "check_within"}


@pytest.mark.parametrize(
    ("message", "parameter", "shown"),
    [
        ("k=80: the pool has only 50 postures", "k", "--k 80: the pool has only 50 postures"),
        ("seed must be an integer from 0 to 9, got -1", "seed", "--seed must be an integer from 0 to 9, got -1"),
        ("output=r.txt: a route file ends in .yaml", "output", "-o r.txt: a route file ends in .yaml"),
        ("no topic (or measure with use_wrench=False)", "use_wrench=False", "no topic (or measure with --no-wrench)"),
        (
            "/data/held_out.yaml is a training file and a held-out one (held_out): give it once",
            "held_out",
            "/data/held_out.yaml is a training file and a held-out one (--validate): give it once",
        ),
        (
            "output already holds a session: add bags, or choose another output",
            "output",
            "output already holds a session: add bags, or choose another -o",
        ),  # advice: the last mention
        ("session: give a session name", "session", "--session: give a session name"),  # the subject: the first
        ("k must be an integer", None, "k must be an integer"),  # about no parameter: as it is
        ("tilt must be small", "tilt", "tilt must be small"),  # a parameter no flag sets: as it is
    ],
)
def test_the_first_mention_of_the_parameter_becomes_its_flag(message, parameter, shown):
    assert in_flags(InputError(message, parameter=parameter)) == shown


def _named_parameters(tree: ast.AST) -> list[tuple[int, str]]:
    """Every parameter a library error may name: ``parameter="..."`` and the name given to a check."""
    found = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.Call):
            continue
        found.extend(
            (node.lineno, k.value.value)
            for k in node.keywords
            if k.arg == "parameter" and isinstance(k.value, ast.Constant) and isinstance(k.value.value, str)
        )
        callee = node.func.id if isinstance(node.func, ast.Name) else None
        if callee in CHECKS and len(node.args) >= 2 and isinstance(node.args[1], ast.Constant):
            found.append((node.lineno, node.args[1].value))
    return found


def test_every_parameter_a_library_error_names_has_its_flag():
    named = []
    for path in sorted(PACKAGE.rglob("*.py")):
        if "cli" not in path.relative_to(PACKAGE).parts:
            where = path.relative_to(PACKAGE)
            named.extend((f"{where}:{line}", p) for line, p in _named_parameters(ast.parse(path.read_text())))
    assert len(named) > 20  # the scan found them
    missing = [f"{where}: {p}" for where, p in named if p not in FLAGS]
    assert not missing, f"parameters no flag is mapped to (add them to cli.options.FLAGS): {missing}"


def test_a_script_reads_the_parameter_and_the_command_line_its_flag(tmp_path, capsys):
    with pytest.raises(ArgumentError, match=r"^k must be an integer from 1") as caught:
        select_pool_file(str(tmp_path / "pool.yaml"), str(tmp_path / "s.yaml"), SelectionSettings(k=0))
    assert caught.value.parameter == "k" and "--" not in str(caught.value)
    out = tmp_path / "route.txt"
    with pytest.raises(ArgumentError, match=r"^output=.*route\.txt: a route file ends in"):
        route_postures_file(str(tmp_path / "selected.yaml"), str(out))
    assert main(["route", str(tmp_path / "selected.yaml"), "-q", "-o", str(out)]) == 2
    assert f"posegen: error: -o {out}: a route file ends in" in capsys.readouterr().err


def test_a_session_name_is_a_printable_label_as_file_at_session_gives_one():
    assert session_name("day 2/table B") == "day 2/table B"  # calibrate's FILE@day 2/table B names it too
    for bad in ("", "   ", "a\nb", "tab\there"):
        with pytest.raises(argparse.ArgumentTypeError, match="not a usable session name"):
            session_name(bad)
