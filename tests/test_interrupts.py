"""A Ctrl-C swallowed by a finaliser still stops the command and leaves nothing written."""
import gc
import os
import signal

import pytest

from darts.cli.errors import run_guarded
from darts.fileio import atomic_path


class _InterruptedWhileFinalised:
    """Sends SIGINT to this process from ``__del__``: Python runs the handler there and prints
    "Exception ignored" for its KeyboardInterrupt, as it did inside a Warp array's finaliser."""

    def __del__(self):
        os.kill(os.getpid(), signal.SIGINT)
        for _ in range(1000):  # the handler runs between these bytecodes
            pass


swallowed = pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")


def _swallow_an_interrupt():
    _InterruptedWhileFinalised()
    gc.collect()


@swallowed
def test_swallowed_interrupt_still_exits_130_and_writes_nothing(tmp_path, capsys):
    out = tmp_path / "out.txt"

    def main(argv):
        with atomic_path(out) as tmp:
            tmp.write_text("half")
            _swallow_an_interrupt()  # nothing raised here: the finaliser swallowed it
            tmp.write_text("whole")
        return 0

    assert run_guarded("prog", main, []) == 130
    assert capsys.readouterr().err.strip().splitlines()[-1] == "prog: interrupted"
    assert not out.exists() and not list(tmp_path.iterdir())


@swallowed
def test_swallowed_interrupt_after_the_output_still_exits_130(tmp_path, capsys):
    def main(argv):
        _swallow_an_interrupt()
        return 0

    assert run_guarded("prog", main, []) == 130


def test_without_an_interrupt_the_output_lands_and_the_handler_is_restored(tmp_path):
    out = tmp_path / "out.txt"
    before = signal.getsignal(signal.SIGINT)

    def main(argv):
        with atomic_path(out) as tmp:
            tmp.write_text("whole")
        return 0

    assert run_guarded("prog", main, []) == 0
    assert out.read_text() == "whole" and signal.getsignal(signal.SIGINT) is before
