"""Many independent jobs on Ray (local by default, a cluster by address), resumable, with a manifest.

A job writes into a temporary folder beside its final one, ``OUT_DIR/.<id>.tmp-*``, that is renamed
to ``OUT_DIR/<id>/`` only when the job has finished, with its manifest row as ``result.json``. So:

- a finished job is a folder with ``result.json``; re-running skips it;
- a job killed mid-way (SIGKILL of the driver kills its workers) leaves at most a temporary folder,
  which the next run deletes before it starts;
- ``OUT_DIR/manifest.jsonl`` has one JSON row per job (its inputs, ``status`` ok / unstable /
  failed, ``wall_seconds``, ``error`` and what the job measured). The driver appends a row as each
  job ends (a line cut by a kill is ignored when read back) and rewrites the file, one row per
  job in job order, at the start and the end of every run.

A failing job (bad input, an exception) is recorded with its message and the others go on; failed
jobs are tried again on the next run. ``retry`` re-runs a job whose worker process died (Ray's
task retries); a job that raised is not retried. Workers run one job at a time with torch and the
BLAS/OpenMP pools at one thread: Warp's CPU backend is single-threaded, and two processes with
default threading on two cores ran a CRDL solve 16 times slower.
"""
from __future__ import annotations

import contextlib
import json
import os
import re
import shutil
import socket
import time
import traceback
import uuid
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path

from darts.errors import DartsInputError
from darts.fileio import atomic_path, check_output

#: Environment of every worker process: one thread in each pool.
SINGLE_THREAD_ENV = {name: "1" for name in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS",
                                            "NUMEXPR_NUM_THREADS", "VECLIB_MAXIMUM_THREADS")}
MANIFEST = "manifest.jsonl"
RESULT = "result.json"
FINISHED = ("ok", "unstable")  # statuses a re-run keeps; "failed" jobs are tried again


@dataclass(frozen=True)
class Job:
    """One unit of work: ``id`` (letters, digits, ``._-``) is unique; ``inputs`` (JSON) go into its
    manifest row and tell ``function`` what to do; ``folder`` is where under OUT_DIR its output is
    published (default: ``id``)."""

    id: str
    inputs: dict = field(hash=False)
    folder: str | None = None

    @property
    def path(self) -> str:
        return self.folder or self.id


#: ``function(job, folder)`` does the job, writing its files into ``folder`` (which exists), and
#: returns the manifest fields it measured (``status`` defaults to "ok").
JobFunction = Callable[[Job, Path], dict]
#: ``function(jobs, folders)`` does several jobs at once (one solver stepping them all), each
#: writing into its folder, and returns each job's manifest fields, in order.
GroupFunction = Callable[[list[Job], list[Path]], list[dict]]


def safe_id(text: str) -> str:
    """``text`` made usable as a folder name."""
    return re.sub(r"[^A-Za-z0-9._-]+", "-", text).strip("-.") or "job"


def _single_threaded() -> None:
    os.environ.update(SINGLE_THREAD_ENV)
    import torch

    torch.set_num_threads(1)


class _Attempt:
    """One job's temporary folder beside its final one, its manifest row and its clock."""

    def __init__(self, job: Job, out_dir: Path):
        self.final = Path(out_dir) / job.path
        self.work = self.final.parent / f".{job.id}.tmp-{uuid.uuid4().hex[:8]}"
        self.work.mkdir(parents=True)
        self.started = time.perf_counter()
        self.row = {"id": job.id, **job.inputs}

    def publish(self, measured: dict) -> dict:
        """The job succeeded: its row with what it ``measured``, its folder moved into place."""
        self.row.update({"status": "ok", "error": ""}, **measured)
        self.row["wall_seconds"] = round(time.perf_counter() - self.started, 3)
        (self.work / RESULT).write_text(json.dumps(self.row, indent=1))
        if self.final.exists():
            shutil.rmtree(self.final)
        os.replace(self.work, self.final)
        return self.row

    def fail(self, exc: Exception) -> dict:
        """The job failed with ``exc``: its row with the message (a DartsInputError's one line)."""
        message = str(exc) if isinstance(exc, DartsInputError) else f"{type(exc).__name__}: {exc}"
        self.row.update(status="failed", error=message.splitlines()[0] if message else type(exc).__name__,
                        wall_seconds=round(time.perf_counter() - self.started, 3))
        if not isinstance(exc, DartsInputError):
            self.row["traceback"] = traceback.format_exc(limit=-3)
        return self.row

    def clean(self) -> None:
        if self.work.exists():
            shutil.rmtree(self.work, ignore_errors=True)


def run_one(function: JobFunction, job: Job, out_dir: Path) -> dict:
    """Do ``job`` in a temporary folder and publish it as ``out_dir/<id>/``; the manifest row. Any
    exception is the job's failure, recorded with its message (a DartsInputError's one line)."""
    attempt = _Attempt(job, out_dir)
    try:
        return attempt.publish(function(job, attempt.work))
    except Exception as exc:  # noqa: BLE001 - every failure of a job is recorded, the batch goes on
        return attempt.fail(exc)
    finally:
        attempt.clean()


def run_group(function: GroupFunction, alone: JobFunction, jobs: list[Job], out_dir: Path) -> list[dict]:
    """Do ``jobs`` together (``function``), each in its temporary folder, published as ``run_one``
    does; the manifest rows. Where the group fails as a whole (one bad job refuses the group), each
    job is done alone (``alone``), so that only a bad job fails."""
    if len(jobs) == 1:
        return [run_one(alone, jobs[0], out_dir)]
    attempts = [_Attempt(job, out_dir) for job in jobs]
    try:
        measured = function(jobs, [a.work for a in attempts])
        return [attempt.publish(fields) for attempt, fields in zip(attempts, measured)]
    except Exception:  # noqa: BLE001 - one by one, each job's own failure is recorded
        return [run_one(alone, job, out_dir) for job in jobs]
    finally:
        for attempt in attempts:
            attempt.clean()


def _remote_group(function: GroupFunction | None, alone: JobFunction, jobs: list[Job], out_dir: str) -> list[dict]:
    _single_threaded()
    if function is None:
        return [run_one(alone, job, Path(out_dir)) for job in jobs]
    return run_group(function, alone, jobs, Path(out_dir))


def finished_rows(out_dir: Path, jobs: list[Job]) -> dict[str, dict]:
    """Rows of the finished ``jobs``, read from their folders."""
    rows = {}
    for job in jobs:
        try:
            row = json.loads((Path(out_dir) / job.path / RESULT).read_text())
        except (OSError, json.JSONDecodeError):
            continue
        if row.get("status") in FINISHED:
            rows[job.id] = row
    return rows


def read_manifest(path: Path) -> dict[str, dict]:
    """The last row of every job in a manifest (a line cut short by a kill is skipped)."""
    rows = {}
    if not path.is_file():
        return rows
    for line in path.read_text().splitlines():
        try:
            row = json.loads(line)
        except json.JSONDecodeError:
            continue
        if isinstance(row, dict) and "id" in row:
            rows[row["id"]] = row
    return rows


def _write_manifest(path: Path, jobs: list[Job], rows: dict[str, dict]) -> None:
    with atomic_path(path) as tmp:
        tmp.write_text("".join(json.dumps(rows[job.id]) + "\n" for job in jobs if job.id in rows))


def _append(handle, row: dict) -> None:
    handle.write(json.dumps(row) + "\n")
    handle.flush()
    os.fsync(handle.fileno())


def check_out_dir(out_dir: Path) -> None:
    """Create ``out_dir`` or raise a DartsInputError saying why it cannot hold the jobs."""
    out_dir = check_output(out_dir, directory=True)
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise DartsInputError(out_dir, f"cannot be created ({exc.strerror or exc})") from None


def check_cluster_options(workers: int | None, address: str | None) -> None:
    """Raise a DartsInputError for ``--workers`` under 1 or an ``--address`` nothing listens at."""
    if workers is not None and workers < 1:
        raise DartsInputError(None, f"--workers must be >= 1, got {workers}")
    if address:
        check_address(address)


def check_address(address: str, timeout: float = 5.0) -> None:
    """Raise a DartsInputError unless something listens at the Ray address ``host:port`` (or
    ``ray://host:port``); Ray itself would retry for minutes."""
    if address == "auto":
        return
    target = address.removeprefix("ray://")
    host, sep, port = target.rpartition(":")
    if not sep or not port.isdigit():
        raise DartsInputError(None, f"--address must be host:port, ray://host:port or auto, got '{address}'")
    try:
        socket.create_connection((host, int(port)), timeout=timeout).close()
    except OSError as exc:
        raise DartsInputError(None, f"cannot reach a Ray cluster at {address} ({exc.strerror or exc})") from None


@contextlib.contextmanager
def ray_session(address: str | None = None, workers: int | None = None):
    """Ray, started here (``ray.init()`` with ``workers`` CPUs, default one per core) or joined at
    ``address``, for one or more ``run_jobs``; shut down at the end."""
    import logging

    import ray

    options = dict(include_dashboard=False, logging_level=logging.ERROR, log_to_driver=False,
                   runtime_env={"env_vars": dict(SINGLE_THREAD_ENV)})
    if address is None:
        ray.init(num_cpus=workers or os.cpu_count() or 1, **options)
    else:
        check_address(address)
        ray.init(address=address, **options)
    try:
        yield ray
    finally:
        ray.shutdown()


def run_jobs(jobs: Iterable[Job], out_dir: str | os.PathLike, function: JobFunction, *, workers: int | None = None,
             address: str | None = None, retry: int = 0, progress: bool = True, session=None,
             description: str = "jobs", group: GroupFunction | None = None, group_size: int = 1) -> list[dict]:
    """Run every unfinished job of ``jobs`` on Ray (``session``, else a ``ray_session(address,
    workers)`` of its own); the manifest rows of all jobs, in job order. With ``group``, the
    unfinished jobs go to the workers ``group_size`` at a time, each such group done at once by
    ``group`` (``run_group``)."""
    from tqdm import tqdm

    jobs = list(jobs)
    if len({job.id for job in jobs}) != len(jobs):
        raise ValueError("job ids must be unique")
    out_dir = Path(out_dir)
    check_out_dir(out_dir)
    _remove_temporaries(out_dir, jobs)
    manifest = out_dir / MANIFEST
    known = {job.id for job in jobs}
    rows = {key: row for key, row in read_manifest(manifest).items() if key in known and row.get("status") not in FINISHED}
    rows.update(finished_rows(out_dir, jobs))
    _write_manifest(manifest, jobs, rows)
    pending = [job for job in jobs if rows.get(job.id, {}).get("status") not in FINISHED]
    size = max(1, group_size) if group is not None else 1
    bar = tqdm(total=len(jobs), initial=len(jobs) - len(pending), unit="job", desc=description, disable=not progress)
    if pending:
        with contextlib.ExitStack() as stack:
            ray = session or stack.enter_context(ray_session(address, workers))
            remote = ray.remote(num_cpus=1, max_retries=retry)(_remote_group)
            limit = workers or max(1, int(ray.cluster_resources().get("CPU", 1)))
            queue = [pending[i:i + size] for i in range(0, len(pending), size)][::-1]
            running = {}
            with open(manifest, "a") as handle:
                while queue or running:
                    while queue and len(running) < limit:
                        batch = queue.pop()
                        running[remote.remote(group, function, batch, str(out_dir.resolve()))] = batch
                    done, _ = ray.wait(list(running), num_returns=1)
                    batch = running.pop(done[0])
                    try:
                        done_rows = ray.get(done[0])
                    except Exception as exc:  # noqa: BLE001 - the worker died (after its retries)
                        first = str(exc).splitlines()[0] if str(exc) else ""
                        done_rows = [{"id": job.id, **job.inputs, "status": "failed", "wall_seconds": 0.0,
                                      "error": f"worker lost: {type(exc).__name__}: {first}"} for job in batch]
                    for row in done_rows:
                        rows[row["id"]] = row
                        _append(handle, row)
                    bar.update(len(done_rows))
                    bar.set_postfix_str(f"{sum(r['status'] == 'failed' for r in rows.values())} failed", refresh=False)
    bar.close()
    # Every job is done: a temporary folder left now is a killed run's, written after the sweep above
    # by a worker that outlived its driver (Ray reaps such workers only seconds later).
    _remove_temporaries(out_dir, jobs)
    _write_manifest(manifest, jobs, rows)
    return [rows[job.id] for job in jobs]


def _remove_temporaries(out_dir: Path, jobs: list[Job]) -> None:
    """Remove the temporary job folders (``.<id>.tmp-*``) beside the jobs' folders."""
    for parent in {(out_dir / job.path).parent for job in jobs}:
        for stale in parent.glob(".*.tmp-*"):
            shutil.rmtree(stale, ignore_errors=True)
