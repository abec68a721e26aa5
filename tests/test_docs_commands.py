"""The commands in the README and ``docs/`` are runnable as written: every ``darts``/``darts-sim`` line
of a ``bash`` block parses (its flags, choices and numbers) and names input files that exist, and
every ``python scripts/...``/``benchmarks/...`` line names a script that has the flags it is given."""
from __future__ import annotations

import json
import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).parents[1]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def _bash_lines() -> list[tuple[str, str]]:
    found = []
    for doc in DOCS:
        for block in re.findall(r"```bash\n(.*?)```", doc.read_text(), re.S):
            for line in block.replace("\\\n", " ").splitlines():
                command = line.split(" #")[0].strip()
                for part in command.split("&&"):
                    part = part.strip().removeprefix(".venv/bin/")
                    if re.match(r"^(darts|darts-sim|python3? (scripts|benchmarks)/)", part):
                        found.append((f"{doc.name}: {part[:60]}", part))
    return found


def _expanded(command: str) -> list[str]:
    """The words of ``command`` as bash gives them (``$(...)`` substituted), the program dropped."""
    env = dict(os.environ, PATH=f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}")
    probe = f'{shlex.quote(sys.executable)} -c "import json, sys; print(json.dumps(sys.argv[1:]))" '
    done = subprocess.run(["bash", "-c", probe + command.split(" ", 1)[1]], capture_output=True, text=True,
                          cwd=ROOT, env=env, check=True)
    return json.loads(done.stdout)


COMMANDS = _bash_lines()


def test_the_docs_have_commands_to_check():
    assert len(COMMANDS) >= 8


@pytest.mark.parametrize("where, command", COMMANDS, ids=[w for w, _ in COMMANDS])
def test_a_documented_command_parses_and_its_inputs_exist(where, command):
    from darts.cli.main import build_parser
    from sim.cli import parser as sim_parser

    words = _expanded(command)
    program = command.split()[0]
    if program.startswith("python"):
        script = ROOT / words[0]
        assert script.is_file(), f"{where}: no {words[0]}"
        source = script.read_text()
        for flag in (w for w in words[1:] if w.startswith("--")):
            assert f'"{flag.split("=")[0]}"' in source, f"{where}: {words[0]} has no {flag}"
        return
    args = (sim_parser() if program == "darts-sim" else build_parser()).parse_args(words)
    for value in vars(args).values():
        if isinstance(value, str) and value.startswith("scenes/"):
            assert (ROOT / value).exists(), f"{where}: {value} does not exist"


def test_the_readmes_darts_sim_synopsis_names_every_option():
    """The README's darts-sim line lists every flag darts-sim has (settings come from one declaration
    and drift in; this catches a synopsis that does not follow)."""
    from sim.cli import parser

    synopsis = next(line for line in (ROOT / "README.md").read_text().splitlines() if line.startswith("| `darts-sim GARMENT"))
    flags = {option for action in parser()._actions for option in action.option_strings
             if option.startswith("--") and option not in ("--help", "--version", "--output")}
    missing = sorted(flag for flag in flags if not re.search(rf"(?<![\w-]){re.escape(flag)}(?![\w-])", synopsis))
    assert not missing, f"README's darts-sim synopsis leaves out {missing}"
