"""``posegen pool``'s start: the workers' imports begin before the command's own."""

from tests.cli.backend_probe import at_backend_opening


def test_the_workers_imports_start_before_the_commands_own(tmp_path):
    """The forkserver imports placo, pinocchio and coal for the workers while this process imports its own.

    Opened after them, the first chunk waited for it: 1500 postures on 2 workers took 9.64 s against 9.33 s
    (3 whole-process runs each, in alternation; the same bytes).
    """
    argv = ["pool", "--n", "5", "-q", "-o", "out.yaml"]
    imported, preload = at_backend_opening(tmp_path, argv, ["posegen.pool", "posegen.robot"])
    assert imported == [False, False]
    assert "posegen.pool.generation" in preload
