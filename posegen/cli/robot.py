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
        help="draft a config for an example-robot-data robot (frames, limits, table, collision pairs)",
        description="Study an example-robot-data humanoid and write a starting config to edit: legs and "
        "soles, arms, joints to lock, contact frames, a table from the arms' reach, velocity limits the "
        "URDF lacks, collision pairs to disable (sampled, as MoveIt's setup assistant).",
    )
    init.add_argument("name", help="example-robot-data name (as example_robot_data.load takes it)")
    init.add_argument("-o", "--output", required=True, help="config file to write (e.g. configs/NAME_table.yaml)")
    init.add_argument("--srdf", default=None, help="SRDF to use instead of the loader's (path or package:// URI)")
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
        from posegen.robot import write_draft

        draft = write_draft(args.name, args.output, args.srdf, args.samples, args.seed)
        left, right = draft.chains
        print(f"robot init: {args.name} -> {args.output}")
        print(f"  soles {draft.soles[0]}, {draft.soles[1]}; hands {left.hand}, {right.hand}")
        print(f"  arms of {len(left.joints)} joints; {len(draft.locked)} joints locked")
        print(f"  table top {list(draft.table_center_m)} m (arm reach {draft.reach_m:.2f} m)")
        print(
            f"  {len(draft.survey.disabled)} collision pairs disabled of {draft.survey.pairs_surveyed} "
            f"({draft.survey.samples} postures)"
        )
        for note in draft.notes:
            print(f"  note: {note}")
        return 0
    from posegen.robot import survey_config_pairs

    survey, block = survey_config_pairs(args.config, args.samples, args.seed)
    found = f"{len(survey.disabled)} of {survey.pairs_surveyed} link pairs, {survey.samples} postures"
    print(f"# {found}; paste under robot.collision:")
    print(block)
    return 0
