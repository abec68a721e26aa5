"""Reading and writing files safely: whole-file atomic writes and validated ``.npz`` reading."""
from __future__ import annotations

import contextlib
import os
import tempfile
import zipfile
from pathlib import Path

import numpy as np

from darts.errors import DartsInputError


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike, keep_suffix: bool = False):
    """Yield a temporary path beside ``path``; rename it onto ``path`` only if the block succeeds.
    With ``keep_suffix`` the temporary name ends like ``path`` (for writers that go by extension)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    suffix = f".tmp{path.suffix}" if keep_suffix else ".tmp"
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=suffix, dir=path.parent)
    os.close(fd)
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes 0600; give the file the usual permissions
    try:
        yield Path(tmp)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def read_input(path: str | os.PathLike, kind: str) -> bytes:
    """The bytes of the input file ``path`` (a ``kind``: "camera file", "batch SPEC", ...), or a
    DartsInputError saying what it is instead: missing, a directory, unreadable."""
    path = Path(path)
    try:
        return path.read_bytes()
    except FileNotFoundError:
        raise DartsInputError(path, "no such file") from None
    except IsADirectoryError:
        raise DartsInputError(path, f"is a directory, not a {kind}") from None
    except OSError as exc:
        raise DartsInputError(path, f"cannot be read ({exc.strerror or exc})") from None


def check_output(path: str | os.PathLike, suffixes: tuple[str, ...] | None = None) -> Path:
    """``path`` as a Path, or a DartsInputError if a file cannot be written there: a suffix not in
    ``suffixes``, an existing directory, a parent that is a file or cannot be created or written.
    Called for every output before a long run starts."""
    path = Path(path)
    if suffixes is not None and path.suffix.lower() not in suffixes:
        raise DartsInputError(path, f"must end in {', '.join(suffixes)}")
    if path.is_dir():
        raise DartsInputError(path, "is a directory")
    parent = path.parent
    existing = next((p for p in [parent, *parent.parents] if p.exists()), None)
    if existing is not None and not existing.is_dir():
        raise DartsInputError(path, f"cannot be written: {existing} is a file")
    if existing is not None and not os.access(existing, os.W_OK | os.X_OK):
        raise DartsInputError(path, f"cannot be written: no permission in {existing}")
    return path


def save_npz(path: str | os.PathLike, compressed: bool = True, **arrays) -> None:
    """Write arrays to ``path`` exactly (no ``.npz`` appended), atomically."""
    with atomic_path(path) as tmp, open(tmp, "wb") as handle:
        (np.savez_compressed if compressed else np.savez)(handle, **arrays)


def check_npz_file(path: Path) -> None:
    """Raise a DartsInputError unless ``path`` is an existing zip archive (what .npz files are)."""
    if not path.is_file():
        raise DartsInputError(path, "no such file")
    if not zipfile.is_zipfile(path):
        raise DartsInputError(path, "not a valid .npz archive (not a zip file)")


def read_npz(path: str | os.PathLike) -> dict[str, np.ndarray]:
    """The arrays of an ``.npz`` archive, or a DartsInputError naming the file and what is wrong.

    Entries that would need pickle (metadata dicts in official SMPL-X files, marker lists in some
    AMASS releases) are skipped, never unpickled."""
    path = Path(path)
    check_npz_file(path)
    try:
        with np.load(path, allow_pickle=False) as archive:
            out = {}
            for key in archive.files:
                try:
                    out[key] = archive[key]
                except ValueError:
                    continue
            return out
    except (zipfile.BadZipFile, EOFError, OSError, ValueError) as exc:
        raise DartsInputError(path, f"not a valid .npz archive ({exc})") from None


def require_keys(arrays: dict, keys, source) -> None:
    """Raise a DartsInputError listing every key of ``keys`` missing from ``arrays``."""
    missing = [key for key in keys if key not in arrays]
    if missing:
        raise DartsInputError(source, f"missing key(s) {', '.join(missing)}")


def require_finite(name: str, array: np.ndarray, source) -> None:
    """Raise a DartsInputError if a numeric array holds NaN or infinity."""
    if array.dtype.kind in "fc" and not np.isfinite(array).all():
        raise DartsInputError(source, f"'{name}' contains NaN or infinite values")
