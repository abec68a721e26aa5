"""``darts-sim GARMENT MOTION``: placeholder until the Warp cloth solver lands (issue 4).

It validates its arguments as the real command will and then says what is missing, exiting 2.
"""
from __future__ import annotations

import argparse
import sys

from darts.cli.errors import run_guarded
from darts.errors import DartsInputError
from darts.motion.amass import load_motion
from scenes import resolve_motion


def _main(argv: list[str] | None) -> int:
    parser = argparse.ArgumentParser(
        prog="darts-sim",
        description="Simulate a DART garment on a body posed by an AMASS motion (not implemented yet).",
    )
    parser.add_argument("garment", metavar="GARMENT", help="garment.npz (a DART)")
    parser.add_argument("motion", metavar="MOTION", help="AMASS .npz or a shipped motion name")
    parser.add_argument("-o", "--output", metavar="OUT", help="output .usd/.usda/.usdc or a directory")
    args = parser.parse_args(argv)
    load_motion(resolve_motion(args.motion))
    raise DartsInputError(None, "the cloth solver is not implemented yet: DART templates (issue 3) and the "
                          "Warp solver (issue 4) are still to come; 'darts body pose' poses the body today")


def main(argv: list[str] | None = None) -> int:
    """Console entry point of ``darts-sim``."""
    return run_guarded("darts-sim", _main, argv)


if __name__ == "__main__":
    sys.exit(main())
