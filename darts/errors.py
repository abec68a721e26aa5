"""Errors raised for bad user input; the CLIs turn them into one clear line and exit code 2."""
from __future__ import annotations

import os


class DartsInputError(ValueError):
    """A file or argument is not what it claims to be. ``str()`` names the file and the problem on
    one line: line breaks inside ``problem`` (a quoted value, a library's message) become spaces."""

    def __init__(self, source: str | os.PathLike | None, problem: str):
        self.source = None if source is None else os.fspath(source)
        self.problem = " ".join(problem.split())
        super().__init__(f"{self.source}: {self.problem}" if self.source else self.problem)
