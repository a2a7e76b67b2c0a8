"""``posegen robot``: set up a new robot (``init``), re-find its collision pairs (``pairs``)."""

from __future__ import annotations

import argparse

from posegen.cli.options import positive, seed

NAME = "robot"
HELP = "set up a robot: draft its config (init), re-find its collision pairs (pairs)"
PROGRESS = False  # draws a progress bar (and takes -q)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the command's arguments."""
    actions = parser.add_subparsers(dest="action", required=True)
    init = actions.add_parser(
        "init",
        help="draft a config for a humanoid: example-robot-data name, URDF or MJCF file (soles, posture, contacts)",
        description="Study a humanoid (an example-robot-data name, a URDF file, or an MJCF file converted to a URDF "
        "written beside the config; no SRDF needed) and write a "
        "starting config to edit: up axis, legs and soles, a standing posture, arms, joints to lock, a contact "
        "per hand, collision geometry for links that have none, a table from the arms' reach, velocity limits "
        "the URDF lacks, collision pairs to disable (sampled, as MoveIt's setup assistant). Every guess is "
        "marked '# CHECK:' in the draft.",
    )
    init.add_argument(
        "name",
        metavar="SOURCE",
        help="example-robot-data name, a URDF file, or an MJCF file (converted to OUTPUT.urdf)",
    )
    init.add_argument("-o", "--output", required=True, help="config file to write (e.g. configs/NAME_table.yaml)")
    init.add_argument("--srdf", default=None, help="an SRDF (path or package:// URI): its first state, disabled pairs")
    init.add_argument(
        "--package-dir",
        action="append",
        default=[],
        help="where package://NAME/ mesh paths are found (repeatable; folders above the URDF named NAME are tried too)",
    )
    init.add_argument("--samples", type=positive, default=400, help="random postures for collision pairs (400)")
    init.add_argument("--seed", type=seed, default=0, help="seed of those postures (default 0)")
    pairs = actions.add_parser(
        "pairs",
        help="re-find the collision pairs to disable for a config and print the block to paste",
    )
    pairs.add_argument("config", help="scene config")
    pairs.add_argument("--samples", type=positive, default=400, help="random postures (default 400)")
    pairs.add_argument("--seed", type=seed, default=0, help="seed of those postures (default 0)")
    for action in (init, pairs):
        action.add_argument("-q", "--quiet", action="store_true", help="no progress output")


def run(args: argparse.Namespace) -> int:
    """Draft a config, or survey a config's collision pairs, and say what was found."""
    if args.action == "init":
        from posegen.draft import write_draft

        command = " ".join(
            ["posegen robot init", args.name, *(f"--srdf {args.srdf}" for _ in [0] if args.srdf)]
            + [f"--package-dir {d}" for d in args.package_dir]
            + [f"-o {args.output}"]
        )
        draft = write_draft(
            args.name, args.output, args.srdf, args.samples, args.seed, tuple(args.package_dir), command
        )
        left, right = draft.chains
        contact = "flush" if left.contact.flush else "point"
        print(f"robot init: {args.name} -> {args.output}")
        print(f"  up axis {draft.up_axis}; soles {draft.soles[0].frame}, {draft.soles[1].frame}")
        print(f"  hands {left.hand}, {right.hand} ({contact} contact); arms of {len(left.joints)} joints")
        print(f"  {len(draft.locked)} joints locked; {len(draft.covered)} links given collision geometry")
        print(f"  table top {list(draft.table_center_m)} m (arm reach {draft.reach_m:.2f} m)")
        print(
            f"  {len(draft.survey.disabled)} collision pairs disabled of {draft.survey.pairs_surveyed} "
            f"({draft.survey.samples} postures)"
        )
        for note in draft.notes:
            print(f"  note: {note}")
        print(f"still to decide ({len(draft.checks)} '# CHECK:' lines in the draft):")
        for check in draft.checks:
            print(f"  - {check}")
        return 0
    from posegen.draft import survey_config_pairs

    survey, block = survey_config_pairs(args.config, args.samples, args.seed)
    found = f"{len(survey.disabled)} of {survey.pairs_surveyed} link pairs, {survey.samples} postures"
    print(f"# {found}; paste under robot.collision:")
    print(block)
    return 0
