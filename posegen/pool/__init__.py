"""Stage 1: the pool of feasible contact postures.

Uniform joint samples projected onto balanced flush contact (placo), checked for
collisions (coal); generated in chunks over processes and resumable after a kill; and
re-verified from scratch on the original meshes (``posegen check``).

Internal: scripts use the public API at ``posegen.`` (stable, documented with examples); the
names here are its plumbing and may change between versions.
"""

from posegen.pool.check import verify_postures
from posegen.pool.generation import generate_pool
from posegen.pool.sampler import Draw, PostureSampler, Rejection, draw, rejection_counts
from posegen.pool.workflow import check_pool_file, generate_pool_file

__all__ = [
    "Draw",
    "PostureSampler",
    "Rejection",
    "check_pool_file",
    "draw",
    "generate_pool",
    "generate_pool_file",
    "rejection_counts",
    "verify_postures",
]
