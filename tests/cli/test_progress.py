"""Progress on stderr: a bar on a terminal, a few lines in a log, nothing with -q."""

import io

from posegen.cli.progress import ProgressBar
from posegen.progress import Progress


class Clock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_a_log_gets_a_line_every_interval_and_the_last_report():
    stream, clock = io.StringIO(), Clock()
    with ProgressBar(False, stream, interval_s=10.0, clock=clock) as bar:
        for done in range(10_001):  # 10 000 reports over 100 s
            clock.now = done * 0.01
            bar(Progress(done, 10_000, "posture", attempts=3 * done))
    lines = stream.getvalue().splitlines()
    assert 10 <= len(lines) <= 12, lines
    assert lines[0] == "posegen: 0/10000 postures (0%), 0 attempted"
    assert lines[-1] == "posegen: 10000/10000 postures (100%), 30000 attempted"


def test_a_log_ends_with_where_the_work_ended():
    stream, clock = io.StringIO(), Clock()
    with ProgressBar(False, stream, clock=clock) as bar:
        bar(Progress(1, 4, "step", "information matrices"))
        bar(Progress(2, 4, "step", "IROC weights"))
    assert stream.getvalue().splitlines() == [
        "posegen: 1/4 steps (25%): information matrices",
        "posegen: 2/4 steps (50%): IROC weights",
    ]


def test_quiet_shows_nothing_anywhere():
    for stream in (io.StringIO(), Terminal()):
        with ProgressBar(True, stream) as bar:
            for done in range(100):
                bar(Progress(done, 99, "point"))
        assert stream.getvalue() == ""


def test_a_terminal_gets_a_bar():
    stream = Terminal()
    with ProgressBar(False, stream) as bar:
        for done in range(51):
            bar(Progress(done, 50, "posture"))
    assert "50/50" in stream.getvalue() and "posegen:" not in stream.getvalue()
