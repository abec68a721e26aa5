"""A batch SPEC (TOML or JSON, ``docs/batch.md``): garments x motions x body shapes x materials x seam
settings, each combination one simulation (a ``sim.api.SimJob``, what one ``darts-sim`` run does),
plus explicit jobs.

    [sim]      simulation settings for every job (frames, settle, fps, solver, format, ...)
    [sweep]    garments, motions, bodies (name, betas and/or file), materials, seams: the cross product
    [[jobs]]   explicit jobs (garment, motion, body, material, seams, and sim settings of their own)

Relative paths are relative to the SPEC's folder; names of shipped garments and motions stay names.
Everything is checked here, once, before any job runs: the keys, their types, that every garment
and motion names a file or a shipped one, and each job's settings (range-checked by ``SimJob.check``,
as for darts-sim). Whether a garment or motion file can be read is each
job's own business: a broken file fails that job only.
"""
from __future__ import annotations

import hashlib
import itertools
import json
import os
from dataclasses import dataclass
from pathlib import Path

from darts.errors import DartsInputError
from darts.fileio import read_input
from darts.jobs import Job, safe_id
from sim.engine.settings import user_settings

#: SPEC sim keys -> (what they set: "settings" a SimSettings field, "job" a SimJob field, None the
#: outputs; the field's name; the kind of value). A SPEC's bools set the field as they are.
#: a spec's ``[sim]`` keys -> (where the value goes: the job's settings, the job, or neither (the
#: outputs), the field it sets, its kind): every setting darts-sim has (``sim.engine.settings.user_settings``),
#: then the job's own
SIM_KEYS = {setting.key: ("settings", setting.name, {"float": float, "int": int, "str": str, "bool": bool,
                                                    "vector": "vector"}[setting.kind]) for setting in user_settings()} | {
    "frames": ("job", "frames", int), "start": ("job", "start", int), "end": ("job", "end", int),
    "settle": ("job", "settle", float), "seam_curves": ("job", "seam_curves", bool), "format": (None, "format", str),
    "preview": (None, "preview", str),
}
FORMATS = ("usd", "usda", "usdc", "obj", "ply")
PREVIEWS = ("gif", "png", "mp4")
BODY_KEYS = ("name", "betas", "file")
JOB_KEYS = ("garment", "motion", "body", "material", "seams", "sim")
SWEEP_KEYS = ("garments", "motions", "bodies", "materials", "seams")
#: In a job's command line, the job's own (temporary, then final) folder.
JOB_FOLDER = "{job}"


@dataclass(frozen=True)
class Body:
    name: str
    betas: tuple[float, ...] | None = None
    file: str | None = None


@dataclass(frozen=True)
class SeamSet:
    name: str
    settings: tuple[str, ...] = ()


def read_spec(path: str | os.PathLike) -> dict:
    """The SPEC document: TOML (``.toml``) or JSON (anything else)."""
    path = Path(path)
    text = read_input(path, "batch SPEC")
    try:
        if path.suffix.lower() == ".toml":
            import tomllib

            document = tomllib.loads(text.decode("utf-8"))
        else:
            document = json.loads(text.decode("utf-8"))
    except UnicodeDecodeError:
        raise DartsInputError(path, "is not text (a batch SPEC is TOML or JSON)") from None
    except ValueError as exc:  # tomllib.TOMLDecodeError and json.JSONDecodeError are ValueErrors
        raise DartsInputError(path, f"is not valid {'TOML' if path.suffix.lower() == '.toml' else 'JSON'} ({exc})") from None
    if not isinstance(document, dict):
        raise DartsInputError(path, "must be a table (TOML) or an object (JSON) at the top")
    return document


class _Checker:
    """Type checks that name the SPEC and the offending key."""

    def __init__(self, path: Path):
        self.path, self.folder = path, path.parent

    def fail(self, where: str, problem: str):
        raise DartsInputError(self.path, f"{where}: {problem}")

    def table(self, value, where: str, allowed) -> dict:
        if not isinstance(value, dict):
            self.fail(where, "must be a table")
        unknown = sorted(set(value) - set(allowed))
        if unknown:
            self.fail(where, f"unknown key(s) {', '.join(unknown)} (known: {', '.join(allowed)})")
        return value

    def items(self, value, where: str) -> list:
        if not isinstance(value, list) or not value:
            self.fail(where, "must be a non-empty list")
        return value

    def text(self, value, where: str) -> str:
        if not isinstance(value, str) or not value.strip():
            self.fail(where, "must be a non-empty string")
        return value

    def number(self, value, where: str) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            self.fail(where, f"must be a number, got {value!r}")
        return float(value)

    def input_path(self, value, where: str, kind: str | None = None) -> str:
        """A shipped name stays as it is; anything that looks like a path is made absolute. A
        ``kind`` ("garment", "motion") must name a file or a shipped one of that kind."""
        text = self.text(value, where)
        if "/" in text or text.endswith(".npz") or text.endswith(".pkl"):
            text = str((self.folder / text).resolve()) if not os.path.isabs(text) else text
        if kind is not None:
            from darts.shipped import resolve_garment, resolve_motion

            try:
                (resolve_garment if kind == "garment" else resolve_motion)(text)
            except DartsInputError as exc:
                self.fail(where, f"{text}: {exc.problem}")
        return text

    def garment(self, value, where: str):
        """A garment (a name or path) or an outfit (a list of them, inner layer first)."""
        if isinstance(value, list):
            if not value:
                self.fail(where, "an outfit must list at least one garment")
            nested = next((item for item in value if not isinstance(item, str)), None)
            if nested is not None:
                self.fail(where, f"an outfit lists garment names or files, inner layer first; found {nested!r} "
                                 "among them (an outfit is one list, not a list of lists)")
            return tuple(self.input_path(item, where, "garment") for item in value)
        return self.input_path(value, where, "garment")

    def body(self, value, where: str) -> Body:
        if isinstance(value, str):
            value = {"name": value}
        value = self.table(value, where, BODY_KEYS)
        betas = value.get("betas")
        if betas is not None:
            if not isinstance(betas, list):
                self.fail(f"{where}.betas", "must be a list of numbers")
            betas = tuple(self.number(b, f"{where}.betas") for b in betas)
        file = self.input_path(value["file"], f"{where}.file") if "file" in value else None
        name = value.get("name") or ("mean" if not betas and file is None else safe_id(
            "betas" + "_".join(f"{b:g}" for b in betas or ()) if file is None else Path(file).stem))
        return Body(self.text(name, f"{where}.name"), betas, file)

    def seams(self, value, where: str) -> SeamSet:
        if isinstance(value, list):
            value = {"name": "seams-" + safe_id("-".join(str(v) for v in value)) if value else "default", "set": value}
        value = self.table(value, where, ("name", "set"))
        settings = value.get("set", [])
        if not isinstance(settings, list):
            self.fail(f"{where}.set", "must be a list of NAME=REGIME[:STIFFNESS] strings")
        return SeamSet(self.text(value.get("name", "seams"), f"{where}.name"),
                       tuple(self.text(s, f"{where}.set") for s in settings))

    def sim(self, value, where: str) -> dict:
        value = self.table(value, where, SIM_KEYS)
        for key, item in value.items():
            kind = SIM_KEYS[key][2]
            if kind is bool:
                if not isinstance(item, bool):
                    self.fail(f"{where}.{key}", f"must be true or false, got {item!r}")
            elif kind == "vector":
                if not isinstance(item, list) or len(item) != 3:
                    self.fail(f"{where}.{key}", "must be three numbers [x, y, z]")
                for v in item:
                    self.number(v, f"{where}.{key}")
            elif kind is str:
                self.text(item, f"{where}.{key}")
            elif kind is int and (isinstance(item, bool) or not isinstance(item, int)):
                self.fail(f"{where}.{key}", f"must be an integer, got {item!r}")
            elif kind is float:
                self.number(item, f"{where}.{key}")
        if "format" in value and value["format"] not in FORMATS:
            self.fail(f"{where}.format", f"must be one of {', '.join(FORMATS)}, got {value['format']!r}")
        if "preview" in value and value["preview"] not in PREVIEWS:
            self.fail(f"{where}.preview", f"must be one of {', '.join(PREVIEWS)}, got {value['preview']!r}")
        return value


def sim_job(garment: str, motion: str, body: Body, material: str | None, seams: SeamSet, sim: dict):
    """The ``SimJob`` of one SPEC job, its outputs in JOB_FOLDER (``stats.json`` always; ``sim.usdc``
    or the format's; ``preview.<kind>`` when asked)."""
    from sim.api import SimJob
    from sim.engine.settings import SimSettings

    form = sim.get("format", "usdc")
    settings, options = {}, {}
    for key, value in sim.items():
        where, name, kind = SIM_KEYS[key]
        value = tuple(float(v) for v in value) if kind == "vector" else value
        if where == "settings":
            settings[name] = value
        elif where == "job":
            options[name] = value
    return SimJob(list(garment) if isinstance(garment, tuple) else garment, motion, SimSettings(**settings), body=body.file,
                  betas=list(body.betas) if body.betas else None,
                  material=material, seams=seams.settings,
                  output=f"{JOB_FOLDER}/sim.{form}" if form.startswith("usd") else f"{JOB_FOLDER}/frames",
                  format=form if form in ("obj", "ply") else "obj", stats=f"{JOB_FOLDER}/stats.json",
                  preview=f"{JOB_FOLDER}/preview.{sim['preview']}" if "preview" in sim else None, **options)


def _stem(name: str) -> str:
    return safe_id(Path(name).stem if name.endswith(".npz") else name)


def _job(garment: str, motion: str, body: Body, material: str | None, seams: SeamSet, sim: dict, checker: _Checker,
         where: str) -> Job:
    from dataclasses import replace

    from sim.cli import command_line

    try:  # the settings and values only: the outputs are the job folder's, checked when it runs
        job = sim_job(garment, motion, body, material, seams, sim)
        replace(job, output=None, stats=None, preview=None).check()
    except DartsInputError as exc:
        checker.fail(where, exc.problem)
    request = job.to_dict()
    digest = hashlib.sha1(json.dumps(request, sort_keys=True).encode()).hexdigest()[:6]
    parts = ["+".join(_stem(g) for g in garment) if isinstance(garment, tuple) else _stem(garment), _stem(motion),
             body.name] + ([material] if material else []) + (
        [seams.name] if seams.settings else [])
    inputs = {"garment": garment, "motion": motion, "body": body.name, "betas": list(body.betas or ()),
              "body_file": body.file, "material": material or "own", "seams": seams.name,
              "seam_settings": list(seams.settings), "sim": sim, "job": request, "command": command_line(job)}
    return Job(safe_id("_".join(parts + [digest])), inputs)


def load_jobs(path: str | os.PathLike) -> list[Job]:
    """Every job of the SPEC at ``path``, in order: the sweep's cross product, then explicit jobs."""
    path = Path(path)
    document = read_spec(path)
    check = _Checker(path)
    check.table(document, "the SPEC", ("sim", "sweep", "jobs"))
    base = check.sim(document.get("sim", {}), "sim")
    jobs: list[Job] = []
    if "sweep" in document:
        sweep = check.table(document["sweep"], "sweep", SWEEP_KEYS)
        for key in ("garments", "motions"):
            if key not in sweep:
                check.fail("sweep", f"needs '{key}'")
        garments = [check.garment(g, "sweep.garments") for g in check.items(sweep["garments"], "sweep.garments")]
        motions = [check.input_path(m, "sweep.motions", "motion") for m in check.items(sweep["motions"], "sweep.motions")]
        bodies = [check.body(b, "sweep.bodies") for b in check.items(sweep.get("bodies", ["mean"]), "sweep.bodies")]
        materials = [None if m == "own" else check.text(m, "sweep.materials")
                     for m in check.items(sweep.get("materials", ["own"]), "sweep.materials")]
        seams = [check.seams(s, "sweep.seams") for s in check.items(sweep.get("seams", [[]]), "sweep.seams")]
        for garment, motion, body, material, seam in itertools.product(garments, motions, bodies, materials, seams):
            jobs.append(_job(garment, motion, body, material, seam, base, check, "sweep"))
    explicit = document.get("jobs", [])
    if not isinstance(explicit, list):
        check.fail("jobs", "must be a list of tables ([[jobs]])")
    for k, entry in enumerate(explicit):
        where = f"jobs[{k}]"
        entry = check.table(entry, where, JOB_KEYS)
        for key in ("garment", "motion"):
            if key not in entry:
                check.fail(where, f"needs '{key}'")
        seams = check.seams(entry.get("seams", []), f"{where}.seams")
        jobs.append(_job(check.garment(entry["garment"], f"{where}.garment"),
                         check.input_path(entry["motion"], f"{where}.motion", "motion"),
                         check.body(entry.get("body", "mean"), f"{where}.body"),
                         None if entry.get("material", "own") == "own" else check.text(entry["material"], f"{where}.material"),
                         seams, {**base, **check.sim(entry.get("sim", {}), f"{where}.sim")}, check, where))
    if not jobs:
        check.fail("the SPEC", "has no jobs (give a [sweep] or [[jobs]])")
    ids = [job.id for job in jobs]
    duplicate = next((i for i in ids if ids.count(i) > 1), None)
    if duplicate:
        check.fail("the SPEC", f"lists the same job twice ({duplicate})")
    return jobs
