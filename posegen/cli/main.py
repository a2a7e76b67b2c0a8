"""The ``posegen`` command line. The only place errors become exit codes.

Each subcommand is a module of this package: its name and help, its arguments, and a
``run`` that calls one public function of its stage and prints the result. Every
subcommand takes ``-q`` (no progress output).

Exit codes: 0 success, 1 a check found violations, 2 bad input (arguments and files
included), an infeasible problem, or an output that cannot be written, 130 interrupted.
Every error is one line on stderr, ``posegen: error: ...``.
"""

from __future__ import annotations

import argparse
import logging
import logging.handlers
import os
import sys
from typing import NoReturn

from posegen import __version__
from posegen.cli import calibrate, check, export, measure, pool, robot, route, select, session, simulate, view
from posegen.cli.options import in_flags
from posegen.errors import PosegenError

# the robot's set-up, then pipeline order, as --help lists them
COMMANDS = (robot, pool, check, select, route, export, simulate, measure, calibrate, session, view)
EXIT_ERROR = 2
EXIT_INTERRUPTED = 130


class Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line, like every other posegen error."""

    def error(self, message: str) -> NoReturn:
        """Print ``posegen: error: ...`` on one line and exit 2."""
        command = self.prog.removeprefix("posegen").strip()
        where = f"{command}: " if command else ""
        print(f"posegen: error: {where}{message} (see: {self.prog} --help)", file=sys.stderr)
        sys.exit(EXIT_ERROR)


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of every subcommand."""
    parser = Parser(
        prog="posegen",
        description="Plan and run the whole-body geometric calibration of a humanoid touching a table.",
        epilog="pipeline: pool -> select -> route -> export -> (record a rosbag2 on the robot) -> measure "
        "-> calibrate; simulate rehearses it on a perturbed robot; view shows any of their files in 3D. "
        "Exit codes: 0 ok, 1 check found violations, 2 bad input or infeasible problem, 130 interrupted.",
    )
    parser.add_argument("--version", action="version", version=f"posegen {__version__}")
    parser.add_argument("-v", "--verbose", action="store_true", help="log progress details")
    commands = parser.add_subparsers(dest="command", required=True)
    for command in COMMANDS:
        sub = commands.add_parser(command.NAME, help=command.HELP)
        command.add_arguments(sub)
        if "-q" not in sub._option_string_actions:
            sub.add_argument("-q", "--quiet", action="store_true", help="no progress output")
        sub.set_defaults(run=command.run)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the command line; return the exit code."""
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        # Before numpy loads: small matrices run faster on one BLAS thread (we parallelise
        # over processes), and results are bit-identical however the command is launched.
        os.environ.setdefault(var, "1")
    try:
        args = build_parser().parse_args(argv)
    except SystemExit as exc:  # --help, --version, or a bad argument (already reported)
        return exc.code if isinstance(exc.code, int) else EXIT_ERROR
    stream = logging.StreamHandler(sys.stderr)  # the current stderr, also when main runs more than once
    stream.setFormatter(logging.Formatter("posegen: %(message)s"))
    held = _held_warnings(stream) if getattr(args, "quiet", False) else None
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING, handlers=[held or stream], force=True)
    try:
        code = int(args.run(args))
        if held is not None:
            held.flush()  # -q: the warnings of a run that succeeded, at its end
        return code
    except PosegenError as exc:
        if held is not None:
            held.buffer.clear()  # -q: a failed run says one line, its error
        print(f"posegen: error: {' '.join(in_flags(exc).split())}", file=sys.stderr)  # one line, always
        return EXIT_ERROR
    except KeyboardInterrupt:
        print("posegen: interrupted; rerun the same command to resume", file=sys.stderr)
        return EXIT_INTERRUPTED
    except BrokenPipeError:  # output piped into a reader that stopped early (e.g. head)
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except OSError as exc:  # the machine refused (disk full, permissions changed mid-run)
        where = f"{exc.filename}: " if exc.filename else ""
        print(f"posegen: error: {where}{exc.strerror or exc}", file=sys.stderr)
        return EXIT_ERROR
    finally:
        if held is not None:  # nothing stays held once main returns: later records go to stderr as usual
            held.buffer.clear()
            logging.getLogger().removeHandler(held)
            logging.getLogger().addHandler(stream)


def _held_warnings(target: logging.Handler) -> logging.handlers.MemoryHandler:
    """A handler that keeps the log records until the run ends (``-q``: said once it succeeded, else dropped)."""
    return logging.handlers.MemoryHandler(1 << 20, flushLevel=logging.CRITICAL + 1, target=target, flushOnClose=False)


if __name__ == "__main__":
    sys.exit(main())
