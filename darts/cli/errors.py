"""Turning bad input into one clear line on stderr and exit code 2."""
from __future__ import annotations

import argparse
import sys
from collections.abc import Callable

from darts.errors import DartsInputError
from darts.interrupts import catching_interrupts, raise_if_interrupted


def run_guarded(prog: str, main: Callable[[list[str] | None], int], argv: list[str] | None = None) -> int:
    """Run ``main``; a DartsInputError prints ``prog: error: FILE: problem`` and returns 2 instead
    of a traceback (anything else is a bug and keeps its traceback). Ctrl-C prints ``prog:
    interrupted`` and returns 130, also when the KeyboardInterrupt was swallowed on the way."""
    try:
        with catching_interrupts():
            code = main(argv) or 0
            raise_if_interrupted()
            return code
    except DartsInputError as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        _close_progress_bars()
        print(f"{prog}: interrupted", file=sys.stderr)
        return 130


def _close_progress_bars() -> None:
    """Close the progress bars still open, so that the next message starts a line of its own."""
    tqdm = sys.modules.get("tqdm")
    for bar in list(getattr(getattr(tqdm, "tqdm", None), "_instances", ())):
        bar.close()


class OneLineParser(argparse.ArgumentParser):
    """An ArgumentParser whose errors are DartsInputErrors: one line ``prog: error: problem`` and
    exit code 2 from ``run_guarded``, not the usage block (``--help`` still shows it)."""

    def error(self, message: str):
        raise DartsInputError(None, f"{message} (see {self.prog} --help)")
