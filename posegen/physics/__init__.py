"""A route rehearsed in MuJoCo by a free-standing perturbed robot with real controllers (``simulate --physics``).

Above the stages (like :mod:`posegen.session`): it reads routes, draws the robot
``posegen simulate`` draws, and writes the recording ``measure`` and ``calibrate`` read.
Needs the ``physics`` extra (``mujoco``).

Internal: scripts use the public API at ``posegen.`` (stable, documented with examples); the
names here are its plumbing and may change between versions.
"""

from posegen.extras import Extra, require

require(Extra.PHYSICS, "the physics rehearsal (simulate --physics)")

from posegen.physics.physics_file import (
    PHYSICS_FILE,
    PHYSICS_FORMAT,
    PhysicsReport,
    PhysicsSummary,
    SegmentFigures,
    UnwantedContact,
    read_physics,
    write_physics,
)
from posegen.physics.workflow import PHYSICS_RATE_HZ, PhysicsBag, PhysicsOptions, simulate_physics_bag

__all__ = [
    "PHYSICS_FILE",
    "PHYSICS_FORMAT",
    "PHYSICS_RATE_HZ",
    "PhysicsBag",
    "PhysicsOptions",
    "PhysicsReport",
    "PhysicsSummary",
    "SegmentFigures",
    "UnwantedContact",
    "read_physics",
    "simulate_physics_bag",
    "write_physics",
]
