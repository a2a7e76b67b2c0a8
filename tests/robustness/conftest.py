"""Hypothesis settings of the fuzz suite: derandomized, so that CI and a laptop see the same cases.

``HYPOTHESIS_PROFILE=explore`` draws new cases each run, ten times as many (for a
search, not for CI); ``fuzz`` (``make fuzz``) is the long run of the fuzz suites (``test_fuzz.py``,
``test_fuzz_surfaces.py``, ``test_readers.py``; ``tests/session/test_journal.py``'s kills).
"""

from __future__ import annotations

import os

from hypothesis import HealthCheck, settings

settings.register_profile(
    "posegen",
    max_examples=40,
    deadline=None,
    derandomize=True,
    database=None,  # no .hypothesis folder in the checkout
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
settings.register_profile("explore", parent=settings.get_profile("posegen"), max_examples=400, derandomize=False)
# make fuzz: about 10 min
settings.register_profile("fuzz", parent=settings.get_profile("posegen"), max_examples=800, derandomize=False)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "posegen"))
