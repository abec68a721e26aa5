"""Every simulator setting users set is declared once (``sim.engine.settings.SimSettings``' field metadata)
and reachable the same way from the three places that set it: a darts-sim flag, a batch spec's
``[sim]`` key and the Python API; a job's command line gives the job back."""
from __future__ import annotations

import shlex
from dataclasses import fields

import pytest

from sim.batch.spec import SIM_KEYS, Body, SeamSet, sim_job
from sim.cli import command_line, job_from_args, parser
from sim.engine.settings import SimSettings, user_settings

SETTINGS = user_settings()


def _other_value(setting):
    """A value of ``setting`` that is not its default, as the API takes it."""
    return {"bool": lambda: not setting.default, "vector": lambda: (1.5, -2.0, 0.25),
            "int": lambda: (setting.default or 7) + 3, "float": lambda: setting.default / 2 if setting.default else 0.5,
            "str": lambda: {"solver": "mass-spring", "device": "cuda:1"}[setting.name]}[setting.kind]()


def _flag_words(setting, value) -> list[str]:
    if setting.kind == "bool":
        return [setting.flag]
    return [setting.flag, ",".join(f"{v:g}" for v in value) if setting.kind == "vector" else str(value)]


def test_the_declaration_is_the_dataclass():
    """Every declared setting is a SimSettings field with its default; names, flags and keys unique."""
    defaults = SimSettings()
    assert {s.name for s in SETTINGS} <= {f.name for f in fields(SimSettings)}
    assert all(getattr(defaults, s.name) == s.default for s in SETTINGS)
    for attribute in ("name", "flag", "key"):
        assert len({getattr(s, attribute) for s in SETTINGS}) == len(SETTINGS), attribute
    assert {"fps", "substeps", "solver", "device", "wind", "ground", "tethers", "seed"} <= {s.name for s in SETTINGS}


@pytest.mark.parametrize("setting", SETTINGS, ids=[s.name for s in SETTINGS])
def test_every_setting_is_set_alike_by_flag_batch_key_and_api(setting):
    value = _other_value(setting)
    api = SimSettings(**{setting.name: value})
    args = parser().parse_args(["short-skirt", "walk", "-o", "out.usdc", *_flag_words(setting, value)])
    from_cli = job_from_args(args).settings
    spec_value = list(value) if setting.kind == "vector" else value
    from_batch = sim_job("short-skirt", "walk", Body("mean"), None, SeamSet("default"), {setting.key: spec_value}).settings
    assert from_cli == api == from_batch
    assert SIM_KEYS[setting.key][:2] == ("settings", setting.name)


@pytest.mark.parametrize("setting", SETTINGS, ids=[s.name for s in SETTINGS])
def test_a_jobs_command_line_gives_the_job_back(setting):
    value = _other_value(setting)
    job = job_from_args(parser().parse_args(["short-skirt", "walk", "-o", "out.usdc", *_flag_words(setting, value)]))
    words = shlex.split(command_line(job))[1:]
    assert job_from_args(parser().parse_args(words)) == job
    assert setting.flag in words
