"""The ``posegen`` command line. The only place errors become exit codes.

Exit codes: 0 success, 1 a check found violations, 2 bad input or infeasible problem,
130 interrupted.
"""

from __future__ import annotations

import argparse
import logging
import os
import sys
from pathlib import Path

from posegen import __version__
from posegen.errors import PosegenError

DEFAULT_CONFIG = "configs/talos_table.yaml"
EXIT_VIOLATIONS = 1
EXIT_ERROR = 2
EXIT_INTERRUPTED = 130


def _progress_bar(total: int, unit: str, quiet: bool):  # type: ignore[no-untyped-def]
    from tqdm import tqdm

    return tqdm(total=total, unit=unit, disable=quiet, file=sys.stderr, dynamic_ncols=True)


def _cmd_pool(args: argparse.Namespace) -> int:
    from posegen.artefact import write_yaml
    from posegen.config import load_config
    from posegen.generation import generate_pool

    config = load_config(args.config)
    output = Path(args.output)
    checkpoint = output.with_name(output.name + ".partial.jsonl")
    with _progress_bar(args.n, "posture", args.quiet) as bar:

        def progress(accepted: int, attempted: int) -> None:
            bar.update(accepted - bar.n)
            bar.set_postfix(attempted=attempted, refresh=False)

        pool = generate_pool(config, args.n, args.seed, args.workers, checkpoint, progress)
    write_yaml(output, pool.to_dict())
    checkpoint.unlink(missing_ok=True)
    rate = 100.0 * len(pool.postures) / max(pool.attempted, 1)
    print(f"pool: {len(pool.postures)} postures accepted of {pool.attempted} samples ({rate:.1f}%) -> {output}")
    print("rejected: " + (", ".join(f"{k} {v}" for k, v in pool.rejected.items()) or "none"))
    for spot, counts in pool.per_spot().items():
        print(f"  {spot}: " + ", ".join(f"{chain} {n}" for chain, n in counts.items()))
    return 0


def _cmd_check(args: argparse.Namespace) -> int:
    from posegen.artefact import read_yaml
    from posegen.config import load_config, parse_config
    from posegen.errors import InputError
    from posegen.pool import POOL_FORMAT, pool_from_dict
    from posegen.scene import Scene
    from posegen.verification import verify_postures

    data = read_yaml(args.file, POOL_FORMAT)
    pool = pool_from_dict(data, args.file)
    config = load_config(args.config) if args.config else parse_config(pool.provenance.get("config"), "")
    scene = Scene(config)
    recorded = pool.provenance.get("robot_model_sha256")
    if recorded and recorded != scene.files.sha256():
        raise InputError(f"{args.file} was made for another robot model (sha256 {recorded[:12]}...)")
    if tuple(pool.joint_names) != scene.joint_names:
        raise InputError(f"{args.file}: joint names differ from the robot model's")
    with _progress_bar(len(pool.postures), "posture", args.quiet) as bar:
        result = verify_postures(scene, pool.postures, lambda k: bar.update(k - bar.n))
    print(f"checked {result.checked} postures of {args.file} (meshes, pinocchio; not the solver's word)")
    for worst in result.worst:
        status = "OK  " if worst.violations == 0 else "FAIL"
        print(
            f"  {status} {worst.invariant.value:<13} violations {worst.violations:>4}  "
            f"worst: posture {worst.posture} ({worst.detail})"
        )
    return 0 if result.ok else EXIT_VIOLATIONS


def _positive(text: str) -> int:
    value = int(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"must be a positive integer, got {value}")
    return value


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of every subcommand."""
    parser = argparse.ArgumentParser(prog="posegen", description=__doc__.splitlines()[0])
    parser.add_argument("--version", action="version", version=f"posegen {__version__}")
    parser.add_argument("-v", "--verbose", action="store_true", help="log progress details")
    sub = parser.add_subparsers(dest="command", required=True)

    pool = sub.add_parser("pool", help="generate feasible contact postures")
    pool.add_argument("--n", type=int, default=1500, help="number of postures (default 1500)")
    pool.add_argument("--config", default=DEFAULT_CONFIG, help=f"scene config (default {DEFAULT_CONFIG})")
    pool.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    pool.add_argument("--workers", type=_positive, default=os.cpu_count() or 1, help="processes (default: cores)")
    pool.add_argument("-o", "--output", default="plans/pool.yaml", help="pool file (default plans/pool.yaml)")
    pool.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    pool.set_defaults(run=_cmd_pool)

    check = sub.add_parser("check", help="re-verify a pool from scratch (exit 1 on any violation)")
    check.add_argument("file", help="pool file")
    check.add_argument("--config", default=None, help="scene config (default: the one saved in the file)")
    check.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    check.set_defaults(run=_cmd_check)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the command line; return the exit code."""
    args = build_parser().parse_args(argv)
    logging.basicConfig(
        level=logging.INFO if args.verbose else logging.WARNING, format="posegen: %(message)s", stream=sys.stderr
    )
    try:
        return int(args.run(args))
    except PosegenError as exc:
        print(f"posegen: error: {exc}", file=sys.stderr)
        return EXIT_ERROR
    except KeyboardInterrupt:
        print("posegen: interrupted; rerun the same command to resume", file=sys.stderr)
        return EXIT_INTERRUPTED


if __name__ == "__main__":
    sys.exit(main())
