"""What a command had imported when it opened its backend, and what it asked the workers to preload."""

import json
import subprocess
import sys

# open_backend replaced by a probe: it reports which of the watched modules this process had imported when
# the backend was asked for, and the preload the workers were to import, then ends the run
PROBE = """
import json, os, sys
import posegen.parallel as parallel

def probe(workers=1, scheduler=None, preload=()):
    print(json.dumps([[m in sys.modules for m in {watched!r}], sorted(preload)]), flush=True)
    os._exit(0)

parallel.open_backend = probe
from posegen.cli import main
main({argv!r})
"""


def at_backend_opening(tmp_path, argv: list[str], watched: list[str]) -> tuple[list[bool], list[str]]:
    """Run ``posegen ARGV`` in ``tmp_path`` until it opens its backend: whether each watched module was imported
    by then, and the modules the workers were to preload."""
    result = subprocess.run(
        [sys.executable, "-c", PROBE.format(watched=watched, argv=argv)],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    imported, preload = json.loads(result.stdout)
    return imported, preload
