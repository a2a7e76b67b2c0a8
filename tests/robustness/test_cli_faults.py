"""Every subcommand on bad input: exit 2, one stderr line ``posegen: error: ...``, no traceback, no new file.

One table, a row per (subcommand, fault). The command runs in this process through
``posegen.cli.main`` (exit code and stderr are what a shell would see; an exception
escaping ``main`` is a traceback and fails the row). Around each row, every file under
the row's folder is hashed: a failing command may neither create a file nor change one
(an existing output keeps its bytes).

A subcommand of another open issue gets its rows here when it lands: one ``Fault(...)``
line per bad input, in the block named after it at the end of the table.
"""

from __future__ import annotations

import hashlib
import os
import shutil
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
import yaml

from posegen.cli import main
from posegen.io import (
    ROUTE_ARRAYS,
    JointStates,
    OutputLock,
    Wrenches,
    load_pool,
    read_arrays,
    write_recording,
    write_with_arrays,
    write_yaml,
)
from posegen.model import Contacts, measurements_to_dict
from posegen.robot import Scene, load_config
from tests.conftest import CONFIG, EXAMPLE_POOL

UNWRITABLE = "/sys/posegen-test"  # no file can be created there, not even by root


@dataclass(frozen=True)
class Fault:
    """One bad input to one subcommand.

    ``argv`` may name the prepared inputs as ``{name}`` (see :func:`inputs`) and the
    row's own folder as ``{out}``; ``locked`` is an output this test holds the lock of
    while the command runs.
    """

    command: str
    what: str
    argv: tuple[str, ...]
    locked: str = ""
    expect: str = ""  # the error line says this too

    @property
    def id(self) -> str:
        return f"{self.command}: {self.what}"


def F(command: str, what: str, *argv: str, locked: str = "", expect: str = "") -> Fault:  # noqa: N802  (a table row)
    return Fault(command, what, (command, *argv) if command else argv, locked, expect)


C = ("--config", "{config}")  # the default TALOS scene, by absolute path
Q = "-q"

PLAN_FILES = {  # bad pool or selection files, by what is wrong with them: input name
    "binary file": "binary",
    "empty file": "empty",
    "truncated pool": "truncated_pool",
    "wrong format field": "wrong_format",
    "NaN in a pool": "nan_pool",
    "future format_version": "future_pool",
    "pool of another robot model": "other_robot_pool",
    "a selection's rank NaN": "nan_rank_selection",  # read by the stages' reader, not by posegen.load's: as load's now
    "a selection's method unknown": "magic_selection",
}
MEASUREMENT_FILES = {  # bad measurement files (posegen YAML or recorded CSV): input name
    "binary YAML": "binary",
    "binary CSV": "binary_csv",
    "empty YAML": "empty",
    "empty CSV": "empty_csv",
    "truncated measurements": "truncated_measurements",
    "NaN joint angle": "nan_measurements",
    "no contact": "no_contact_measurements",
    "unknown joint in a CSV": "unknown_joint_csv",
}
BAD_ROUTES = {  # routes no reader accepts (posegen check too, through the same reader): input name
    "a NaN time": "route_nan_time",
    "a last time of 1e39 s": "route_huge_time",
    "a NaN last time": "route_nan_last_time",
    "a repeated time": "route_repeated_time",
    "a time going back": "route_reversed_time",
    "a NaN position": "route_nan_position",
    "an infinite velocity": "route_inf_velocity",
    "more points than declared": "route_count",
    "no segment": "route_no_segment",
    "format_version 3": "route_version_3",
    "a NaN segment time": "route_nan_segment_time",
}
CALIBRATION_FILES = {  # bad calibration.yaml files: input name
    "binary": "binary",
    "a pool": "pool",
    "version 1 (no model section)": "calibration_v1",
    "unknown candidate part": "calibration_bad_fit",
    "NaN prior scale": "calibration_nan_scale",
    "weakest chain not in the pool": "calibration_other_chain",
    "another robot model's": "calibration_other_robot",
}
STAGE_PLANS = {**PLAN_FILES, "empty pool": "empty_pool", "posture outside the joint limits": "out_of_limits_pool"}


def bad_inputs(command: str, files: dict[str, str], *rest: str) -> list[Fault]:
    """A row per bad input file: ``posegen COMMAND FILE REST...``."""
    return [F(command, what, f"{{{name}}}", *rest) for what, name in files.items()]


def bad_outputs(command: str, *before: str, flag: str = "-o") -> list[Fault]:
    """A row per output that cannot be written: a folder, inside a file, unwritable, being written."""
    return [
        F(command, "output is a folder", *before, flag, "{out}"),
        F(command, "output inside a file", *before, flag, "{existing}/out.yaml"),
        F(command, "unwritable output", *before, flag, f"{UNWRITABLE}/out.yaml"),
        F(command, "output being written", *before, flag, "{existing}", locked="{existing}"),
        F(command, "output named empty", *before, flag, ""),  # a pool crashed on its checkpoint's name
        F(command, "output named /", *before, flag, "/"),
    ]


TABLE = [
    # pool
    F("pool", "--n 0", "--n", "0", *C, "-o", "{out}/pool.yaml"),
    F("pool", "negative --n", "--n", "-5", *C, "-o", "{out}/pool.yaml"),
    F("pool", "--n not a number", "--n", "1e3", *C, "-o", "{out}/pool.yaml"),
    F("pool", "negative --seed", "--n", "3", "--seed", "-1", *C, "-o", "{out}/pool.yaml"),
    F("pool", "huge --seed", "--n", "3", "--seed", str(2**64), *C, "-o", "{out}/pool.yaml"),
    F("pool", "--workers 0", "--n", "3", "--workers", "0", *C, "-o", "{out}/pool.yaml"),
    F("pool", "binary config", "--n", "3", "--config", "{binary}", "-o", "{out}/pool.yaml"),
    F("pool", "empty config", "--n", "3", "--config", "{empty}", "-o", "{out}/pool.yaml"),
    F("pool", "truncated config", "--n", "3", "--config", "{truncated_config}", "-o", "{out}/pool.yaml"),
    F(
        "pool",
        "a pool given as config",
        *("--n", "3", "--config", "{pool}", "-o", "{out}/pool.yaml"),
        expect="a posegen-pool file, not a scene config",
    ),
    F("pool", "NaN in config", "--n", "3", "--config", "{nan_config}", "-o", "{out}/pool.yaml"),
    F("pool", "huge chunk_size", "--n", "3", "--config", "{huge_chunk_config}", "-o", "{out}/pool.yaml"),
    F("pool", "unknown frame", "--n", "3", "--config", "{unknown_frame_config}", "-o", "{out}/pool.yaml"),
    F("pool", "robot name not a name", "--n", "3", "--config", "{robot_number_config}", "-o", "{out}/pool.yaml"),
    F("pool", "missing config", "--n", "3", "--config", "{out}/nothing.yaml", "-o", "{out}/pool.yaml"),
    F("pool", "unknown option", "--n", "3", "--sede", "1", "-o", "{out}/pool.yaml"),
    F("pool", "malformed --scheduler", "--n", "3", "--scheduler", "nonsense", *C, "-o", "{out}/pool.yaml"),
    *bad_outputs("pool", "--n", "3", *C),
    # check
    *bad_inputs("check", PLAN_FILES),
    F("check", "missing file", "{out}/nothing.yaml"),
    F("check", "a folder", "{out}"),
    F("check", "malformed route", "{malformed_route}"),
    F("check", "an empty pool", "{empty_pool}", expect="holds no posture"),
    F("check", "a route of format_version 3", "{route_version_3}", expect="reads versions 1 and 2"),
    F("check", "a route with a NaN segment time", "{route_nan_segment_time}", expect="segment times must be finite"),
    F("check", "a route with more points than declared", "{route_count}", expect="the header declares"),
    F("check", "binary config", "{pool}", "--config", "{binary}"),
    F("check", "--workers 0", "{pool}", "--workers", "0"),
    F("check", "malformed --scheduler", "{pool}", "--scheduler", "::::"),
    F("check", "--scheduler for a route", "{route}", "--scheduler", "tcp://127.0.0.1:9"),
    F("check", "--workers 0 for a route", "{route}", "--workers", "0"),
    F("check", "--min-dt 0", "{route}", "--min-dt", "0"),
    F("check", "--min-dt NaN", "{route}", "--min-dt", "nan"),
    F("check", "negative --min-dt", "{route}", "--min-dt", "-0.01"),
    # select
    *bad_inputs("select", STAGE_PLANS, "-o", "{out}/sel.yaml"),
    F("select", "--k 0", "{pool}", "--k", "0", "-o", "{out}/sel.yaml"),
    F("select", "--k larger than the pool", "{pool}", "--k", "100000", "-o", "{out}/sel.yaml"),
    F("select", "negative --runs", "{pool}", "--runs", "-1", "-o", "{out}/sel.yaml"),
    F("select", "--runs 1e9", "{pool}", "--runs", "1000000000", "-o", "{out}/sel.yaml", expect="from 0 to 10000"),
    F("select", "negative --seed", "{pool}", "--seed", "-3", "-o", "{out}/sel.yaml"),
    F("select", "--fraction NaN", "{pool}", "--fraction", "nan", "-o", "{out}/sel.yaml"),
    F("select", "--fraction 0", "{pool}", "--fraction", "0", "-o", "{out}/sel.yaml"),
    *bad_outputs("select", "{pool}"),
    # select --given (issue 16): follow-up postures for measured contacts (and their calibration)
    *bad_inputs(
        "select", {**PLAN_FILES, "empty pool": "empty_pool"}, "--given", "{measurements}", "-o", "{out}/f.yaml"
    ),
    *[
        F("select", f"--given {what}", "{pool}", "--given", f"{{{name}}}", "-o", "{out}/f.yaml")
        for what, name in MEASUREMENT_FILES.items()
    ],
    F("select", "--given missing file", "{pool}", "--given", "{out}/nothing.yaml", "-o", "{out}/f.yaml"),
    F("select", "--given no file", "{pool}", "--given", "-o", "{out}/f.yaml"),
    F("select", "--given a pool", "{pool}", "--given", "{pool}", "-o", "{out}/f.yaml"),
    F("select", "--given --k 0", "{pool}", "--given", "{measurements}", "--k", "0", "-o", "{out}/f.yaml"),
    F("select", "--given --k past the pool", "{pool}", "--given", "{measurements}", "--k", "999", "-o", "{out}/f.yaml"),
    F("select", "--calibration without --given", "{pool}", "--calibration", "{calibration}", "-o", "{out}/f.yaml"),
    *[
        F(
            "select",
            f"--calibration {what}",
            "{pool}",
            "--given",
            "{measurements}",
            "--calibration",
            f"{{{name}}}",
            "-o",
            "{out}/f.yaml",
        )
        for what, name in CALIBRATION_FILES.items()
    ],
    *bad_outputs("select", "{pool}", "--given", "{measurements}"),
    # route
    *bad_inputs("route", STAGE_PLANS, "-o", "{out}/route.yaml"),
    F("route", "negative --seed", "{pool}", "--seed", "-1", "-o", "{out}/route.yaml"),
    F("route", "huge --seed", "{pool}", "--seed", str(2**40), "-o", "{out}/route.yaml"),
    F("route", "binary config", "{pool}", "--config", "{binary}", "-o", "{out}/route.yaml"),
    F("route", "output named .csv", "{pool}", "-o", "{out}/route.csv"),
    F("route", "--workers 0", "{pool}", "--workers", "0", "-o", "{out}/route.yaml"),
    F("route", "malformed --scheduler", "{pool}", "--scheduler", "nonsense", "-o", "{out}/route.yaml"),
    F("route", "binary --pool", "{selection}", "--pool", "{binary}", "-o", "{out}/route.yaml"),
    F("route", "--pool not the selection's", "{selection}", "--pool", "{other_pool}", "-o", "{out}/route.yaml"),
    *(  # each was a traceback (int() of None or of 'x', Path() of 5)
        F("route", what, f"{{{name}}}", "-o", "{out}/route.yaml", expect=expect)
        for what, name, expect in (
            (
                "a selection's pool_id null",
                "null_pool_id_selection",
                "'pool_id' must be an integer, got None",
            ),
            (
                "a selection's pool_id text",
                "text_pool_id_selection",
                "'pool_id' must be an integer, got 'x'",
            ),
            ("a selection's provenance.pool a number", "number_pool_selection", "provenance.pool 5 is not a path"),
        )
    ),
    *bad_outputs("route", "{pool}"),
    # simulate
    *bad_inputs("simulate", STAGE_PLANS, *C, "-o", "{out}/m.yaml"),
    F("simulate", "negative --seed", "{pool}", "--seed", "-1", *C, "-o", "{out}/m.yaml"),
    F("simulate", "negative --error-mm", "{pool}", "--error-mm", "-1", *C, "-o", "{out}/m.yaml"),
    F("simulate", "NaN --error-mm", "{pool}", "--error-mm", "nan", *C, "-o", "{out}/m.yaml"),
    F("simulate", "infinite --noise-deg", "{pool}", "--noise-deg", "inf", *C, "-o", "{out}/m.yaml"),
    F("simulate", "huge --error-deg", "{pool}", "--error-deg", "1e400", *C, "-o", "{out}/m.yaml"),
    F("simulate", "empty --session", "{pool}", "--session", "", *C, "-o", "{out}/m.yaml"),
    F("simulate", "binary config", "{pool}", "--config", "{binary}", "-o", "{out}/m.yaml"),
    F("simulate", "negative --compliance", "{pool}", "--compliance", "-0.1", *C, "-o", "{out}/m.yaml"),
    F("simulate", "NaN --compliance", "{pool}", "--compliance", "nan", *C, "-o", "{out}/m.yaml"),
    F(
        "simulate",
        "--compliance, config without groups",
        "{pool}",
        "--compliance",
        "0.1",
        "--config",
        "{rigid_config}",
        "-o",
        "{out}/m.yaml",
    ),
    *bad_outputs("simulate", "{pool}", *C),
    # calibrate
    F("calibrate", "binary YAML", "{binary}", *C, "-o", "{out}/cal"),
    F("calibrate", "binary CSV", "{binary_csv}", *C, "-o", "{out}/cal"),
    F("calibrate", "empty YAML", "{empty}", *C, "-o", "{out}/cal"),
    F("calibrate", "empty CSV", "{empty_csv}", *C, "-o", "{out}/cal"),
    F("calibrate", "truncated measurements", "{truncated_measurements}", *C, "-o", "{out}/cal"),
    F("calibrate", "wrong format field", "{pool}", *C, "-o", "{out}/cal"),
    F("calibrate", "NaN joint angle", "{nan_measurements}", *C, "-o", "{out}/cal"),
    F("calibrate", "no contact", "{no_contact_measurements}", *C, "-o", "{out}/cal"),
    F("calibrate", "too few contacts", "{few_measurements}", *C, "-o", "{out}/cal"),
    F("calibrate", "unknown joint in a CSV", "{unknown_joint_csv}", *C, "-o", "{out}/cal"),
    F(
        "calibrate",
        "a free joint without a column",
        "{missing_joint_csv}",
        *C,
        "-o",
        "{out}/cal",
        expect="no column for",
    ),
    F("calibrate", "a joint column twice", "{twice_joint_csv}", *C, "-o", "{out}/cal", expect="given twice"),
    F("calibrate", "a row left out, then too few (-q: one line)", "{one_good_row_csv}", *C, "-o", "{out}/cal"),
    F(
        "calibrate",
        "a file trained on and held out",
        *("{measurements}", "--validate", "{measurements}", *C, "-o", "{out}/cal"),
        expect="a training file and a held-out one",
    ),
    F("calibrate", "an '@' with no session", "{measurements}@", *C, "-o", "{out}/cal", expect="no session name"),
    F("calibrate", "missing file", "{out}/nothing.csv", *C, "-o", "{out}/cal"),
    F("calibrate", "binary held-out file", "{measurements}", "--validate", "{binary}", *C, "-o", "{out}/cal"),
    F("calibrate", "--prior-scale 0", "{measurements}", "--prior-scale", "0", *C, "-o", "{out}/cal"),
    F("calibrate", "negative --prior-scale", "{measurements}", "--prior-scale", "-1", *C, "-o", "{out}/cal"),
    F("calibrate", "NaN --prior-scale", "{measurements}", "--prior-scale", "nan", *C, "-o", "{out}/cal"),
    *(
        F(
            "calibrate",
            f"--prior-scale {scale}",
            "{measurements}",
            "--prior-scale",
            scale,
            *C,
            "-o",
            "{out}/cal",
            expect="--prior-scale must be a number from 0.001 to 10000",
        )
        for scale in ("1e300", "1e-300")
    ),
    F("calibrate", "negative --seed", "{measurements}", "--seed", "-1", *C, "-o", "{out}/cal"),
    F("calibrate", "--candidates unknown", "{measurements}", "--candidates", "nonsense", *C, "-o", "{out}/cal"),
    F("calibrate", "--fold-seeds 0", "{measurements}", "--fold-seeds", "0", *C, "-o", "{out}/cal"),
    F("calibrate", "--fold-seeds 1e9", "{measurements}", "--fold-seeds", "1000000000", *C, "-o", "{out}/cal"),
    F(
        "calibrate",
        "a prior sigma of 1e-300 in the config",
        *("{measurements}", "--config", "{tiny_prior_config}", "-o", "{out}/cal"),
        expect="calibration.prior.joint_offset_deg: expected a number >= 1e-06",
    ),
    F("calibrate", "negative --fold-seeds", "{measurements}", "--fold-seeds", "-2", *C, "-o", "{out}/cal"),
    F("calibrate", "huge --seed", "{measurements}", "--seed", str(2**40), *C, "-o", "{out}/cal"),
    F("calibrate", "no training file", "--validate", "{measurements}", *C, "-o", "{out}/cal"),
    F(
        "calibrate",
        "every row alone in its session",
        "{lonely_measurements}",
        *C,
        "-o",
        "{out}/cal",
        expect="12 row(s) left out: lonely_measurements.yaml:0 (alone in its session)",
    ),
    F(
        "calibrate",
        "rows with their feet off the floor",
        "{kneeling_measurements}",
        *C,
        "-o",
        "{out}/cal",
        expect="3 row(s) left out: kneeling_measurements.yaml:9 (feet off the floor",
    ),
    F(
        "calibrate",
        "one spot per chain",
        "{one_spot_measurements}",
        *C,
        "-o",
        "{out}/cal",
        expect="(one_spot_measurements.yaml:0, one_spot_measurements.yaml:2, one_spot_measurements.yaml:4 and 3 more)",
    ),
    F(
        "calibrate",
        "every row of a chain at one posture",
        *("{one_posture_measurements}", *C, "-o", "{out}/cal"),
        expect="its 6 usable rows (one_posture_measurements.yaml:0, one_posture_measurements.yaml:2, "
        "one_posture_measurements.yaml:4 and 3 more) hold one posture",
    ),
    F("calibrate", "output is a file", "{measurements}", *C, "-o", "{existing}"),
    F("calibrate", "output folder holds other files", "{measurements}", *C, "-o", "{out}", expect="not replacing it"),
    F("calibrate", "unwritable output", "{measurements}", *C, "-o", f"{UNWRITABLE}/cal"),
    F("calibrate", "output being written", "{measurements}", *C, "-o", "{out}/cal", locked="{out}/cal"),
    # view
    *bad_inputs("view", PLAN_FILES, "--html", "{out}/v.html"),
    F("view", "binary file, live", "{binary}", "--port", "0"),
    F("view", "malformed route", "{malformed_route}", "--html", "{out}/v.html"),
    F("view", "a posture of an unknown chain", "{tail_chain_pool}", "--html", "{out}/v.html", expect="chain 'tail'"),
    *(F("view", f"a route with {what}", f"{{{name}}}", "--html", "{out}/v.html") for what, name in BAD_ROUTES.items()),
    *(
        F("check", f"a route with {what}", f"{{{name}}}")
        for what, name in BAD_ROUTES.items()
        if name not in ("route_version_3", "route_nan_segment_time", "route_count")  # with their message above
    ),
    F("view", "a route with a contact of an unknown chain", "{route_tail_chain}", "--html", "{out}/v.html"),
    F("check", "a route with a contact of an unknown chain", "{route_tail_chain}", expect="names chain 'tail'"),
    F("check", "a pool whose sidecar holds a scalar", "{scalar_sample_pool}", expect="'sample' is of shape ()"),
    F("check", "a route approaching with an unknown chain", "{route_tail_approach}", expect="(approach) names chain"),
    F("view", "a route approaching with an unknown chain", "{route_tail_approach}", "--html", "{out}/v.html"),
    *(F("export", f"a route with {what}", f"{{{name}}}", "--bag", "{out}/b") for what, name in BAD_ROUTES.items()),
    *(
        F("simulate", f"--bag: a route with {what}", f"{{{name}}}", "--bag", "{out}/b")
        for what, name in BAD_ROUTES.items()
    ),
    F("view", "a folder that is no calibration", "{out}", "--html", "{out}/v.html"),
    F("view", "missing file", "{out}/nothing.yaml", "--html", "{out}/v.html"),
    F("view", "binary config", "{pool}", "--config", "{binary}", "--html", "{out}/v.html"),
    F("view", "negative --port", "{pool}", "--port", "-1"),
    F("view", "--port past 65535", "{pool}", "--port", "70000"),
    F("view", "--host not of this machine", "{pool}", "--host", "10.9.9.9", expect="--host: cannot listen on"),
    F(
        "view",
        "a calibration folder with a damaged calibration.yaml",
        "{damaged_calibration_folder}",
        "--html",
        "{out}/v.html",
    ),
    *bad_outputs("view", "{pool}", flag="--html"),
    # the command line itself
    F("", "no subcommand"),
    F("nonsense", "unknown subcommand"),
    # export
    *bad_inputs("export", {**PLAN_FILES, "malformed route": "malformed_route"}, "--bag", "{out}/bag"),
    F("export", "--bag a folder that is no bag", "{route}", "--bag", "{out}"),
    F("export", "--bag a file", "{route}", "--bag", "{existing}"),
    F("export", "--bag unwritable", "{route}", "--bag", f"{UNWRITABLE}/bag"),
    F("export", "--bag being written", "{route}", "--bag", "{out}/bag", locked="{out}/bag"),
    F(
        "export",
        "--segments-topic equal to --topic",
        *("{route}", "--topic", "/x", "--segments-topic", "/x", "--bag", "{out}/bag"),
        expect="--segments-topic: '/x' is already in use (by topic)",
    ),
    F("export", "--topic no ROS 2 name", "{route}", "--topic", "x y", "--bag", "{out}/bag", expect="starts with '/'"),
    F("export", "empty --segments-topic", "{route}", "--segments-topic", "", "--bag", "{out}/bag"),
    # simulate --bag
    F("simulate", "--bag of a pool", "{pool}", "--bag", "{out}/bag"),
    F("simulate", "--bag of a binary file", "{binary}", "--bag", "{out}/bag"),
    F("simulate", "--bag --rate 0", "{route}", "--rate", "0", "--bag", "{out}/bag"),
    F("simulate", "--bag --rate NaN", "{route}", "--rate", "nan", "--bag", "{out}/bag"),
    F("simulate", "--bag --rate 1e9", "{route}", "--rate", "1e9", "--bag", "{out}/bag", expect="from 50 to 2000"),
    F("simulate", "--bag --rate 0.001", "{route}", "--rate", "0.001", "--bag", "{out}/bag", expect="from 50 to 2000"),
    F(
        "simulate",
        "--bag --joint-topic a wrist's topic",
        *("{route}", "--joint-topic", "/left_wrist_ft", "--bag", "{out}/bag"),
        expect="--joint-topic: '/left_wrist_ft' is already in use (by chains.left.wrench_topic)",
    ),
    *(
        F("simulate", f"--bag --joint-topic {topic!r}", "{route}", "--joint-topic", topic, "--bag", "{out}/bag")
        for topic in ("", "joint_states", "/a//b", "/2d")
    ),
    F("simulate", "--noise-deg 1e300", "{pool}", "--noise-deg", "1e300", *C, "-o", "{out}/m.yaml", expect="to 180"),
    F("simulate", "--bag negative --seed", "{route}", "--seed", "-2", "--bag", "{out}/bag"),
    F("simulate", "--bag a folder that is no bag", "{route}", "--bag", "{out}"),
    F("simulate", "--bag unwritable", "{route}", "--bag", f"{UNWRITABLE}/bag"),
    F("simulate", "--bag being written", "{route}", "--bag", "{out}/bag", locked="{out}/bag"),
    F("simulate", "--bag with -o", "{route}", "--bag", "{out}/bag", "-o", "{out}/m.yaml", expect="drop -o"),
    F("simulate", "--rate without --bag", "{pool}", "--rate", "100", *C, "-o", "{out}/m.yaml", expect="give --bag"),
    F("simulate", "--joint-topic without --bag", "{pool}", "--joint-topic", "/j", *C, "-o", "{out}/m.yaml"),
    # measure
    F("measure", "a binary file", "{binary}", "-o", "{out}/m.yaml"),
    F("measure", "a folder that is no bag", "{out}", "-o", "{out}/m.yaml"),
    F("measure", "missing bag", "{out}/nothing", "-o", "{out}/m.yaml"),
    F("measure", "truncated storage file", "{truncated_bag}", "-o", "{out}/m.yaml"),
    F("measure", "unknown storage plugin", "{unknown_storage_bag}", "-o", "{out}/m.yaml"),
    F("measure", "missing topic", "{bag}", "--joint-topic", "/nothing", "-o", "{out}/m.yaml"),
    F("measure", "joints the robot lacks", "{bag}", "--no-wrench", "--route", "{route}", "-o", "{out}/m.yaml"),
    F("measure", "--no-wrench without --route", "{bag}", "--no-wrench", "-o", "{out}/m.yaml"),
    F("measure", "binary --route", "{bag}", "--route", "{binary}", "-o", "{out}/m.yaml"),
    F("measure", "binary config", "{bag}", "--config", "{binary}", "-o", "{out}/m.yaml"),
    F(
        "measure",
        "--route not the one the simulated bag ran",
        *("{other_route_bag}", "--route", "{route}", "-o", "{out}/m.yaml"),
        expect="a recording of another route than",
    ),
    F("measure", "empty --session", "{bag}", "--session", " ", "-o", "{out}/m.yaml"),
    *bad_outputs("measure", "{bag}"),
    # robot init and robot pairs (issue 12), and configs whose additions to the description are wrong
    F("robot", "init: unknown robot", "init", "nonsense", "-o", "{out}/c.yaml", expect="valid example-robot-data"),
    F("robot", "init: missing --srdf", "init", "talos", "--srdf", "{out}/nothing.srdf", "-o", "{out}/c.yaml"),
    F("robot", "init: --samples 0", "init", "talos", "--samples", "0", "-o", "{out}/c.yaml"),
    F("robot", "init: truncated --srdf", "init", "talos", "--srdf", "{truncated_srdf}", "-o", "{out}/c.yaml"),
    F("robot", "init: --srdf no SRDF", "init", "talos", "--srdf", "{not_srdf_txt}", "-o", "{out}/c.yaml"),
    F(
        "robot",
        "init: another robot's SRDF",
        *("init", "talos", "--srdf", "{other_robot_srdf}", "-o", "{out}/c.yaml"),
        expect="names none of this robot's joints (such as 'wing_joint')",
    ),
    F("pool", "another robot's SRDF", "--n", "3", "--config", "{other_srdf_config}", "-o", "{out}/p.yaml"),
    F("pool", "two chains, one contact frame", "--n", "3", "--config", "{shared_frame_config}", "-o", "{out}/p.yaml"),
    F(
        "route",
        "route.waypoint_step_rad 0 in the config",
        *("{pool}", "--config", "{zero_step_config}", "-o", "{out}/route.yaml"),
        expect="route.waypoint_step_rad: must be > 0",
    ),
    F(
        "route",
        "route.hold_s 1e9 in the config",
        *("{pool}", "--config", "{huge_hold_config}", "-o", "{out}/route.yaml"),
        expect="route.hold_s: must be <= 600",
    ),
    F(
        "route",
        "route.waypoint_step_rad 100 in the config",
        *("{pool}", "--config", "{huge_step_config}", "-o", "{out}/route.yaml"),
        expect="route.waypoint_step_rad: must be <= 0.2, got 100",
    ),
    F("robot", "init: negative --seed", "init", "talos", "--seed", "-1", "-o", "{out}/c.yaml"),
    F("robot", "init: no name", "init", "-o", "{out}/c.yaml"),
    F("robot", "init: a quadruped", "init", "a1", "-o", "{out}/c.yaml", expect="a1: 4 limbs alike in mass reach the"),
    *bad_outputs("robot", "init", "talos"),
    F("robot", "pairs: missing config", "pairs", "{out}/nothing.yaml"),
    F("robot", "pairs: binary config", "pairs", "{binary}"),
    F("robot", "pairs: --samples 0", "pairs", "{config}", "--samples", "0"),
    F("robot", "pairs: a frame on a link the robot lacks", "pairs", "{bad_frame_config}", expect="no_such_link"),
    F("robot", "pairs: a link paired with itself", "pairs", "{self_pair_config}", expect="paired with itself"),
    F("robot", "pairs: a reference outside the limits", "pairs", "{outside_config}", expect="reference_joints"),
    F("robot", "unknown action", "nonsense"),
    F("pool", "a frame on a link the robot lacks", "--n", "3", "--config", "{bad_frame_config}", "-o", "{out}/p.yaml"),
    F("pool", "a malformed frame", "--n", "3", "--config", "{malformed_frame_config}", "-o", "{out}/p.yaml"),
    F("pool", "a disabled pair of an unknown link", "--n", "3", "--config", "{bad_pair_config}", "-o", "{out}/p.yaml"),
    F("pool", "a point frame the robot lacks", "--n", "3", "--config", "{bad_point_config}", "-o", "{out}/p.yaml"),
    F("calibrate", "a contact kind the chain does not make", "{point_measurements}", *C, "-o", "{out}/cal"),
    # session (issue 25): start, add, status, rehearse
    *[F("session", f"start: {what}", "start", f"{{{name}}}", "-o", "{out}/s") for what, name in STAGE_PLANS.items()],
    F("session", "start: --target-mm 0", "start", "{pool}", "--target-mm", "0", "-o", "{out}/s"),
    F("session", "start: negative --margin", "start", "{pool}", "--margin", "-1", "-o", "{out}/s"),
    F("session", "start: --margin 1e9", "start", "{pool}", "--margin", "1e9", "-o", "{out}/s", expect="from 0 to 10"),
    F("session", "start: --fold-seeds 1e9", "start", "{pool}", "--fold-seeds", "1000000000", "-o", "{out}/s"),
    F("session", "start: --batch 0", "start", "{pool}", "--batch", "0", "-o", "{out}/s"),
    F("session", "start: negative --patience", "start", "{pool}", "--patience", "-1", "-o", "{out}/s"),
    F("session", "start: unknown candidate", "start", "{pool}", "--candidates", "nonsense", "-o", "{out}/s"),
    F("session", "start: -o a file", "start", "{pool}", "-o", "{existing}"),
    F("session", "start: -o unwritable", "start", "{pool}", "-o", f"{UNWRITABLE}/s"),
    F("session", "start: -o a session", "start", "{pool}", "-o", "{malformed_session}", expect="already holds"),
    F("session", "start: no -o", "start", "{pool}"),
    F("session", "add: not a session", "add", "{out}", "{bag}", expect="not a posegen session"),
    F("session", "add: malformed index", "add", "{malformed_session}", "{bag}", expect="not a valid session"),
    F("session", "status: not a session", "status", "{out}", expect="not a posegen session"),
    F("session", "status: malformed index", "status", "{malformed_session}", expect="not a valid session"),
    F("session", "rehearse: not a session", "rehearse", "{out}", "--seed", "1"),
    F("session", "rehearse: no --seed", "rehearse", "{out}"),
    F("session", "rehearse: --max-batches 0", "rehearse", "{out}", "--seed", "1", "--max-batches", "0"),
    F("session", "unknown step", "nonsense"),
]


def _pool_data() -> dict:
    data = yaml.safe_load(EXAMPLE_POOL.read_text())
    data["postures"] = data["postures"][:40]
    return data


def _config_data() -> dict:
    return yaml.safe_load(CONFIG.read_text())


@pytest.fixture(scope="module")
def inputs(tmp_path_factory, route_file, calibration_folder, selection_file) -> dict[str, str]:
    """The bad (and a few good) input files of the table, by name."""
    folder = tmp_path_factory.mktemp("inputs")
    rng = np.random.default_rng(0)
    made: dict[str, str] = {"config": str(CONFIG)}

    def put(name: str, content: str | bytes | dict) -> None:
        path = folder / name
        if isinstance(content, dict):
            write_yaml(path, content)
        else:
            path.write_bytes(content.encode() if isinstance(content, str) else content)
        made[name.replace(".", "_").removesuffix("_yaml")] = str(path)

    binary = rng.integers(0, 256, 4096, dtype=np.uint8).tobytes()
    put("binary", binary)
    put("binary.csv", binary)
    put("empty", "")
    put("empty.csv", "")
    pool = _pool_data()
    put("pool.yaml", pool)
    text = (folder / "pool.yaml").read_text()
    put("truncated_pool.yaml", text[: len(text) // 2])
    put("wrong_format.yaml", pool | {"format": "posegen-calibration"})
    put("future_pool.yaml", pool | {"format_version": 99})
    put("empty_pool.yaml", pool | {"postures": []})
    nan = yaml.safe_load(text)
    nan["postures"][1]["joints"][4] = float("nan")
    put("nan_pool.yaml", nan)
    other = yaml.safe_load(text)
    other["provenance"]["robot_model_sha256"] = "0" * 64
    put("other_robot_pool.yaml", other)
    outside = yaml.safe_load(text)
    outside["postures"][7]["joints"][0] = 50.0
    put("out_of_limits_pool.yaml", outside)
    bag = folder / "bag"
    times = np.arange(50) / 500.0
    wrench = Wrenches(times, np.ones((50, 3)), np.zeros((50, 3)))
    joints = JointStates(("j_a", "j_b"), times, np.outer(times, [1.0, -1.0]))
    write_recording(bag, joints, "/joint_states", {"/ft": wrench}, {"seed": 0})
    made["bag"] = str(bag)
    simulated = {"simulation": {"route_sha256": "0" * 64}}  # posegen simulated it from another route
    write_recording(folder / "other_route_bag", joints, "/joint_states", {"/ft": wrench}, simulated)
    made["other_route_bag"] = str(folder / "other_route_bag")
    for name, edit in (("truncated_bag", "truncate"), ("unknown_storage_bag", "storage")):
        copy = folder / name
        shutil.copytree(bag, copy)
        if edit == "truncate":
            storage = next(copy.glob("*.mcap"))
            storage.write_bytes(storage.read_bytes()[:300])
        else:
            meta = copy / "metadata.yaml"
            meta.write_text(meta.read_text().replace("storage_identifier: mcap", "storage_identifier: tape"))
        made[name] = str(copy)
    made["route"] = str(route_file)
    made.update(bad_routes(route_file, folder))
    put("tail_chain_pool.yaml", pool | {"postures": [pool["postures"][0] | {"chain": "tail"}]})
    header, arrays = load_pool(EXAMPLE_POOL).to_arrays()
    arrays["sample"] = np.array(3)  # a script rewriting the sidecar, one array left a scalar (0-d)
    write_with_arrays(folder / "scalar_sample_pool.yaml", header, arrays, compress=True)
    made["scalar_sample_pool"] = str(folder / "scalar_sample_pool.yaml")
    put("malformed_route.yaml", {"format": "posegen-route", "format_version": 1, "trajectory": {"points": 3}})

    config = _config_data()
    text = CONFIG.read_text()
    put("truncated_config.yaml", text[: len(text) // 3])
    put("nan_config.yaml", config | {"margins": config["margins"] | {"com_m": float("nan")}})
    put("huge_chunk_config.yaml", config | {"sampling": config["sampling"] | {"chunk_size": 10**9}})
    unknown = _config_data()
    unknown["chains"]["left"]["gripper_frame"] = "left_hand"
    put("unknown_frame_config.yaml", unknown)
    put("robot_number_config.yaml", config | {"robot": config["robot"] | {"source": {"example_robot_data": 5}}})

    scene = Scene(load_config(CONFIG))
    joints = np.tile(scene.reference, (12, 1)) + rng.normal(0.0, 0.01, (12, len(scene.joint_names)))
    joints = np.clip(joints, scene.lower, scene.upper)
    contacts = Contacts(joints, ("left", "right") * 6, ("s",) * 12, tuple(f"c{i}" for i in range(12)))
    measurements = measurements_to_dict(scene, contacts, scene.provenance(0))
    put("measurements.yaml", measurements)
    text = (folder / "measurements.yaml").read_text()
    put("truncated_measurements.yaml", text[: len(text) // 2])
    nan = yaml.safe_load(text)
    nan["contacts"][2]["joints"][3] = float("nan")
    put("nan_measurements.yaml", nan)
    put("no_contact_measurements.yaml", measurements | {"contacts": []})
    put("few_measurements.yaml", measurements | {"contacts": measurements["contacts"][:2]})
    clean = np.tile(scene.reference, (12, 1))  # both soles flat: rows usable but for what is made wrong below
    chains = ("left", "right") * 6
    lonely = Contacts(clean, chains, tuple(f"s{i}" for i in range(12)), tuple(f"c{i}" for i in range(12)))
    put("lonely_measurements.yaml", measurements_to_dict(scene, lonely, scene.provenance(0)))
    kneeling = clean.copy()
    kneeling[9:, scene.joint_index("leg_left_4_joint")] += 0.3  # the left knee bends: a sole leaves the floor
    bent = Contacts(kneeling, chains, ("s",) * 12, ("spot",) * 9 + ("c9", "c10", "c11"))  # one spot for the rest
    put("kneeling_measurements.yaml", measurements_to_dict(scene, bent, scene.provenance(0)))
    one_spot = Contacts(clean, chains, ("s",) * 12, ("spot",) * 12)
    put("one_spot_measurements.yaml", measurements_to_dict(scene, one_spot, scene.provenance(0)))
    one_posture = Contacts(clean, chains, ("s",) * 12, tuple(f"c{i}" for i in range(12)))
    put("one_posture_measurements.yaml", measurements_to_dict(scene, one_posture, scene.provenance(0)))
    frames = config["robot"] | {"frames": {"tip": {"parent": "no_such_link", "xyz_m": [0.0, 0.0, 0.0]}}}
    put("bad_frame_config.yaml", config | {"robot": frames})
    frames = config["robot"] | {"frames": {"tip": {"parent": "arm_left_7_link", "xyz_m": [0.0, 0.0]}}}
    put("malformed_frame_config.yaml", config | {"robot": frames})
    pairs = {"disabled_pairs": [["arm_left_7_link", "no_such_link", "user"]]}
    put("bad_pair_config.yaml", config | {"robot": config["robot"] | {"collision": pairs}})
    pairs = {"disabled_pairs": [["arm_left_7_link", "arm_left_7_link", "user"]]}
    put("self_pair_config.yaml", config | {"robot": config["robot"] | {"collision": pairs}})
    put("outside_config.yaml", config | {"stance": config["stance"] | {"reference_joints": {"arm_left_4_joint": 3.0}}})
    point = _config_data()
    point["chains"]["left"] |= {"contact_kind": "point", "point_frame": "no_such_tip"}
    put("bad_point_config.yaml", point)
    as_points = measurements | {"contacts": [c | {"kind": "point"} for c in measurements["contacts"]]}
    put("point_measurements.yaml", as_points)  # the default config declares no point contact
    rigid = _config_data()
    rigid["calibration"] = {"compliance": {}, "candidates": {"offsets": {"fit": ["*.joint_offset"]}}}
    put("rigid_config.yaml", rigid)
    shared = _config_data()
    shared["chains"]["right"]["contact_frame"] = shared["chains"]["left"]["contact_frame"]
    put("shared_frame_config.yaml", shared)
    put("zero_step_config.yaml", config | {"route": {"waypoint_step_rad": 0}})
    put("huge_hold_config.yaml", config | {"route": {"hold_s": 1e9}})
    put("huge_step_config.yaml", config | {"route": {"waypoint_step_rad": 100}})
    tiny = _config_data()
    tiny["calibration"]["prior"] = {"joint_offset_deg": 1e-300}
    put("tiny_prior_config.yaml", tiny)
    srdf = scene.files.srdf
    put("truncated.srdf", srdf.read_text()[:3000])
    put("not_srdf.txt", "hello\n")
    state = '<group_state name="s" group="g"><joint name="wing_joint" value="0"/></group_state>'
    put("other_robot.srdf", f'<?xml version="1.0"?>\n<robot name="bird">{state}</robot>\n')
    put("other_srdf_config.yaml", config | {"robot": config["robot"] | {"srdf": made["other_robot_srdf"]}})

    pool_path = folder / "pool.yaml"
    selection = yaml.safe_load(pool_path.read_text())
    figures = yaml.safe_load(selection_file.read_text())["figures"]  # a whole section, of another selection
    selection |= {"format": "posegen-selection", "method": "k", "figures": figures}
    selection["postures"] = [
        p | {"pool_id": p["id"], "rank": r, "weight": 0.1} for r, p in enumerate(pool["postures"][:3])
    ]
    selection["provenance"] |= {
        "pool": str(pool_path),
        "pool_sha256": hashlib.sha256(pool_path.read_bytes()).hexdigest(),
    }
    put("selection.yaml", selection)
    put("other_pool.yaml", pool | {"postures": pool["postures"][:5]})
    put("null_pool_id_selection.yaml", selection | {"postures": [selection["postures"][0] | {"pool_id": None}]})
    put("text_pool_id_selection.yaml", selection | {"postures": [selection["postures"][0] | {"pool_id": "x"}]})
    put("number_pool_selection.yaml", selection | {"provenance": selection["provenance"] | {"pool": 5}})
    put("nan_rank_selection.yaml", selection | {"postures": [selection["postures"][0] | {"rank": float("nan")}]})
    put("magic_selection.yaml", selection | {"method": "magic"})

    report = yaml.safe_load((calibration_folder.path / "calibration.yaml").read_text())
    put("calibration.yaml", report)
    put("calibration_v1.yaml", {k: v for k, v in report.items() if k != "model"} | {"format_version": 1})
    put("calibration_bad_fit.yaml", report | {"model": report["model"] | {"fit": ["wing.joint_offset"]}})
    put("calibration_nan_scale.yaml", report | {"model": report["model"] | {"prior_scale": float("nan")}})
    error = next(iter(report["model"]["predicted_error"].values()))
    put("calibration_other_chain.yaml", report | {"model": report["model"] | {"predicted_error": {"tail": error}}})
    other_robot = report | {"provenance": report["provenance"] | {"robot_model_sha256": "0" * 64}}
    put("calibration_other_robot.yaml", other_robot)
    damaged = folder / "damaged_calibration"
    shutil.copytree(calibration_folder.path, damaged)
    text = (damaged / "calibration.yaml").read_text()
    (damaged / "calibration.yaml").write_text(text[: len(text) // 2])
    made["damaged_calibration_folder"] = str(damaged)

    (folder / "malformed_session").mkdir()
    put("malformed_session/session.yaml", {"format": "posegen-session", "format_version": 1, "batches": "none"})
    made["malformed_session"] = str(folder / "malformed_session")
    names = ",".join(scene.joint_names).replace("torso_1_joint", "torso_one_joint")
    angles = ",".join(repr(float(v)) for v in scene.reference)
    put("unknown_joint.csv", f"joint_names,{names}\ngripper,talos/left_gripper,handle,x,joint_states,{angles}\n")
    row = "gripper,talos/left_gripper,handle,x,joint_states,"
    free = int(np.flatnonzero(~scene.locked)[-1])  # a joint the config does not lock
    names = ",".join(n for j, n in enumerate(scene.joint_names) if j != free)
    kept = ",".join(a for j, a in enumerate(angles.split(",")) if j != free)
    put("missing_joint.csv", f"joint_names,{names}\n{row}{kept}\n")
    names = ",".join([*scene.joint_names, scene.joint_names[0]])
    put("twice_joint.csv", f"joint_names,{names}\n{row}{angles},{angles.split(',')[0]}\n")
    names = ",".join(scene.joint_names)
    put("one_good_row.csv", f"joint_names,{names}\n{row}{angles}\n{row}text,{angles}\n")
    return made


def bad_routes(route_file: Path, folder: Path) -> dict[str, str]:
    """Copies of a good route, each with one defect no reader accepts (a consistent header and sidecar)."""
    header = yaml.safe_load(route_file.read_text())
    good = read_arrays(route_file, header.pop("arrays"), ROUTE_ARRAYS)
    edits = {
        "route_nan_time": lambda a, h: a["time_from_start"].__setitem__(5, np.nan),
        "route_huge_time": lambda a, h: a["time_from_start"].__setitem__(-1, 1e39),
        "route_nan_last_time": lambda a, h: a["time_from_start"].__setitem__(-1, np.nan),
        "route_repeated_time": lambda a, h: a["time_from_start"].__setitem__(5, a["time_from_start"][4]),
        "route_reversed_time": lambda a, h: a["time_from_start"].__setitem__(5, a["time_from_start"][3]),
        "route_nan_position": lambda a, h: a["positions"].__setitem__((3, 2), np.nan),
        "route_inf_velocity": lambda a, h: a["velocities"].__setitem__((3, 2), np.inf),
        "route_count": lambda a, h: h["trajectory"].update(points=h["trajectory"]["points"] - 1),
        "route_no_segment": lambda a, h: h.update(segments=[]),
        "route_version_3": lambda a, h: h.update(format_version=3),
        "route_nan_segment_time": lambda a, h: h["segments"][1].update(start_s=float("nan")),
        "route_tail_chain": lambda a, h: next(s for s in h["segments"] if s["type"] == "hold").update(chain="tail"),
        "route_tail_approach": lambda a, h: next(s for s in h["segments"] if s["type"] == "approach").update(
            chain="tail"
        ),
    }
    made = {}
    for name, edit in edits.items():
        arrays = {k: v.copy() for k, v in good.items()}
        edited = yaml.safe_load(yaml.safe_dump(header))
        edit(arrays, edited)
        write_with_arrays(folder / f"{name}.yaml", edited, arrays, compress=True)
        made[name] = str(folder / f"{name}.yaml")
    return made


def tree_state(folder: Path) -> dict[str, str]:
    """Every file and folder under ``folder``, with a hash of each file's bytes."""
    state = {}
    for path in sorted(folder.rglob("*")):
        key = str(path.relative_to(folder))
        state[key] = hashlib.sha256(path.read_bytes()).hexdigest() if path.is_file() else "folder"
    return state


def assert_one_line_error(code: int, err: str) -> None:
    lines = [line for line in err.splitlines() if line.strip()]
    assert code == 2, (code, err)
    assert "Traceback" not in err, err
    assert len(lines) == 1 and lines[0].startswith("posegen: error: "), err


@pytest.mark.parametrize("fault", TABLE, ids=lambda f: f.id)
def test_bad_input_fails_cleanly(fault, inputs, tmp_path, capsys):
    if any(a.startswith(UNWRITABLE) for a in fault.argv) and os.access("/sys", os.W_OK) and not os.path.ismount("/sys"):
        pytest.skip("/sys is writable here")
    out = tmp_path / "out"
    out.mkdir()
    existing = out / "existing.yaml"
    existing.write_text("an earlier output: must keep its bytes\n")
    names = {**inputs, "out": str(out), "existing": str(existing)}
    argv = [a.format(**names) for a in fault.argv]
    if fault.command:
        argv.append(Q)
    before = tree_state(tmp_path)
    lock = OutputLock(fault.locked.format(**names)) if fault.locked else None
    if lock:
        lock.acquire()
    try:
        code = main(argv)
    finally:
        if lock:
            lock.release()
    err = capsys.readouterr().err
    assert_one_line_error(code, err)
    assert fault.expect in err, err
    assert tree_state(tmp_path) == before


def test_every_subcommand_has_rows():
    from posegen.cli.main import COMMANDS

    covered = {fault.command for fault in TABLE}
    missing = {command.NAME for command in COMMANDS} - covered
    assert not missing, f"no bad-input row for: {sorted(missing)}"


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only folders (the /sys rows cover root)")
def test_read_only_output_folder(inputs, tmp_path, capsys):
    folder = tmp_path / "read-only"
    folder.mkdir()
    folder.chmod(0o555)
    try:
        code = main(["select", inputs["pool"], "-q", "-o", str(folder / "sel.yaml")])
        assert_one_line_error(code, capsys.readouterr().err)
        assert list(folder.iterdir()) == []
    finally:
        folder.chmod(0o755)
