"""Reading and writing files safely: whole-file atomic writes and validated ``.npz`` reading."""
from __future__ import annotations

import contextlib
import errno
import glob
import math
import os
import shutil
import socket
import stat
import tempfile
import zipfile
from pathlib import Path

import numpy as np

from darts.errors import DartsInputError
from darts.interrupts import raise_if_interrupted

#: The most bytes an input file's contents may take in memory (the arrays of an ``.npz`` together,
#: a text file): larger is refused before it is allocated. The largest real input, an SMPL-X model,
#: is about 0.3 GiB.
MAX_INPUT_BYTES = 4 << 30


def temporary_prefix(path: Path) -> str:
    """The name prefix of the temporary files and folders written beside ``path`` by this process:
    ``.NAME.HOST-PID-``, so that ``remove_stale_temporaries`` can tell a killed writer's leftovers."""
    return f".{path.name}.{socket.gethostname()}-{os.getpid()}-"


def remove_stale_temporaries(path: Path) -> list[Path]:
    """Delete what writers of ``path`` on this host left beside it when they were killed (their
    process is gone), and return it. Another process still writing keeps its temporaries."""
    host = socket.gethostname()
    removed = []
    for stale in path.parent.glob(f".{glob.escape(path.name)}.{glob.escape(host)}-*-*"):
        pid = stale.name[len(f".{path.name}.{host}-"):].split("-")[0]
        if not pid.isdigit() or _alive(int(pid)):
            continue
        shutil.rmtree(stale, ignore_errors=True) if stale.is_dir() else stale.unlink(missing_ok=True)
        removed.append(stale)
    return removed


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # someone else's process: alive
        pass
    return True


#: What a ``Janitor`` runs: wait until the pipe from its writer closes (the writer finished, or died,
#: SIGKILL included: the kernel closes a dead process's files), then remove the path if it is still there.
_JANITOR = ("import os, shutil, sys\nsys.stdin.buffer.read()\npath = sys.argv[1]\n"
            "shutil.rmtree(path, ignore_errors=True) if os.path.isdir(path) else os.path.exists(path) and os.unlink(path)")


class Janitor:
    """A helper process that removes a temporary file or folder if this process dies before
    ``release`` (after the temporary was renamed into place, or removed, it finds nothing to do).
    For the outputs of long runs, so that a SIGKILL leaves nothing beside them."""

    def __init__(self, path: str | os.PathLike):
        import subprocess
        import sys

        self._helper = subprocess.Popen([sys.executable, "-I", "-S", "-c", _JANITOR, os.fspath(path)],
                                        stdin=subprocess.PIPE, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                        start_new_session=True)  # Ctrl-C to this process group spares it

    def release(self) -> None:
        if self._helper.stdin and not self._helper.stdin.closed:
            self._helper.stdin.close()
            self._helper.wait()


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike, keep_suffix: bool = False, janitor: bool = False):
    """Yield a temporary path beside ``path``; rename it onto ``path`` only if the block succeeds
    (and no Ctrl-C arrived meanwhile, see ``darts.interrupts``).
    With ``keep_suffix`` the temporary name ends like ``path`` (for writers that go by extension);
    with ``janitor`` a ``Janitor`` removes it if this process is killed meanwhile. Temporaries of
    earlier writers that were killed are removed first."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    remove_stale_temporaries(path)
    suffix = f".tmp{path.suffix}" if keep_suffix else ".tmp"
    fd, tmp = tempfile.mkstemp(prefix=temporary_prefix(path), suffix=suffix, dir=path.parent)
    os.close(fd)
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes 0600; give the file the usual permissions
    helper = None
    try:
        helper = Janitor(tmp) if janitor else None  # inside: a failed start still removes the temporary
        yield Path(tmp)
        raise_if_interrupted()  # a Ctrl-C a finaliser swallowed still leaves nothing written
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
        if helper is not None:
            helper.release()


def check_input_file(path: str | os.PathLike, kind: str) -> Path:
    """``path`` as a Path if it is a regular file this process may read, else a DartsInputError
    saying what it is instead: missing, a broken or looping link, a directory, a device, unreadable."""
    path = Path(path)
    try:
        mode = path.stat().st_mode
    except FileNotFoundError:
        raise DartsInputError(path, "is a broken symbolic link" if path.is_symlink() else "no such file") from None
    except OSError as exc:
        problem = "is a symbolic link loop" if exc.errno == errno.ELOOP else f"cannot be read ({exc.strerror or exc})"
        raise DartsInputError(path, problem) from None
    if stat.S_ISDIR(mode):
        raise DartsInputError(path, f"is a directory, not a {kind}")
    if not stat.S_ISREG(mode):
        what = {stat.S_IFCHR: "a character device", stat.S_IFBLK: "a block device", stat.S_IFIFO: "a pipe",
                stat.S_IFSOCK: "a socket"}.get(stat.S_IFMT(mode), "not a regular file")
        raise DartsInputError(path, f"is {what}, not a {kind}")
    if not os.access(path, os.R_OK):
        raise DartsInputError(path, "cannot be read (permission denied)")
    return path


def read_input(path: str | os.PathLike, kind: str) -> bytes:
    """The bytes of the input file ``path`` (a ``kind``: "camera file", "batch SPEC", ...), or a
    DartsInputError saying what it is instead (``check_input_file``)."""
    path = check_input_file(path, kind)
    size = path.stat().st_size
    if size > MAX_INPUT_BYTES:
        raise DartsInputError(path, f"is {size / 2**30:.1f} GiB, more than a {kind} can be "
                                    f"({MAX_INPUT_BYTES / 2**30:.0f} GiB)")
    try:
        return path.read_bytes()
    except OSError as exc:
        raise DartsInputError(path, f"cannot be read ({exc.strerror or exc})") from None


#: pixels an input image may have: a 64-megapixel picture decodes to 192 MB of RGB; beyond that
#: the reconstruction learns nothing more (it works at 224 px) and a decompression bomb would not fit
MAX_IMAGE_PIXELS = 64_000_000


def _as_8_bit(image):
    """``image`` (PIL) with 8 bits a channel: a 16-bit or 32-bit integer or a float grey image is
    scaled from its type's range (16-bit: / 257; 32-bit integer: its own maximum, or 16-bit's when
    under it; float: 0..1, or its maximum when above 1) instead of clipped at 255 as PIL's convert does."""
    from PIL import Image

    if image.mode not in ("I", "I;16", "I;16B", "I;16L", "I;16N", "F"):
        return image
    values = np.asarray(image, np.float64)
    if image.mode == "F":
        top = max(1.0, float(values.max(initial=0.0)))
    elif image.mode == "I":
        top = max(65535.0, float(values.max(initial=0.0)))
    else:
        top = 65535.0
    return Image.fromarray(np.clip(np.rint(values / top * 255.0), 0, 255).astype(np.uint8), mode="L")


def read_image(path: str | os.PathLike, mode: str = "RGB") -> np.ndarray:
    """An image file as an array ([H,W,3] uint8 for mode RGB, [H,W] for L) as a viewer shows it (its
    EXIF orientation applied; 16-bit and float grey scaled to 8 bits, ``_as_8_bit``), or a
    DartsInputError: not an image, damaged, or more than MAX_IMAGE_PIXELS pixels (checked from the
    header, before anything is decoded)."""
    from PIL import Image, ImageOps, UnidentifiedImageError

    path = check_input_file(path, "image")
    limit, Image.MAX_IMAGE_PIXELS = Image.MAX_IMAGE_PIXELS, None  # our own limit, with the size in its message
    try:
        with Image.open(path) as image:
            width, height = image.size
            if width * height > MAX_IMAGE_PIXELS:
                raise DartsInputError(path, f"the image is {width}x{height} pixels ({width * height / 1e6:.0f} "
                                            f"megapixels); at most {MAX_IMAGE_PIXELS / 1e6:.0f} megapixels are read")
            return np.asarray(_as_8_bit(ImageOps.exif_transpose(image)).convert(mode))
    except (UnidentifiedImageError, OSError, ValueError, SyntaxError) as exc:  # PIL's errors for damaged files
        raise DartsInputError(path, f"not an image ({exc})") from None
    finally:
        Image.MAX_IMAGE_PIXELS = limit


def check_output(path: str | os.PathLike, suffixes: tuple[str, ...] | None = None, directory: bool = False) -> Path:
    """``path`` as a Path, or a DartsInputError if the output cannot be written there: a suffix not
    in ``suffixes``, an existing directory (a file when ``directory``: the output is a folder, and
    then not the working directory or one above it, which it would replace), a parent that is a
    file, or a folder where a file cannot be created (tried: permissions, read-only or virtual file
    systems such as /proc). Called for every output before a long run starts."""
    path = Path(path)
    if suffixes is not None and path.suffix.lower() not in suffixes:
        raise DartsInputError(path, f"must end in {', '.join(suffixes)}")
    if path.is_dir() and not directory:
        raise DartsInputError(path, "is a directory")
    if directory and path.exists() and not path.is_dir():
        raise DartsInputError(path, "exists and is not a directory (this output is a folder)")
    if directory and path.resolve() in (Path.cwd(), *Path.cwd().parents):
        raise DartsInputError(path, "is the working directory or one above it, which this folder output would "
                                    "replace; name a folder of its own")
    parent = path.absolute().parent
    existing = next(p for p in [parent, *parent.parents] if p.exists() or p.is_symlink())
    if not existing.is_dir():
        raise DartsInputError(path, f"cannot be written: {existing} is {'a file' if existing.exists() else 'a broken link'}")
    try:
        fd, probe = tempfile.mkstemp(prefix=".darts-write-test-", dir=existing)
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        raise DartsInputError(path, f"cannot be written: no file can be created in {existing} "
                                    f"({exc.strerror or exc})") from None
    return path


def save_npz(path: str | os.PathLike, compressed: bool = True, **arrays) -> None:
    """Write arrays to ``path`` exactly (no ``.npz`` appended), atomically."""
    with atomic_path(path) as tmp, open(tmp, "wb") as handle:
        (np.savez_compressed if compressed else np.savez)(handle, **arrays)


class NpzArrays(dict):
    """The arrays of an ``.npz`` archive by key; ``refused`` names the members left out and why."""

    def __init__(self):
        super().__init__()
        self.refused: dict[str, str] = {}


#: Compression methods of the members an ``.npz`` may hold (numpy writes the first two).
_COMPRESSIONS = {zipfile.ZIP_STORED: "stored", zipfile.ZIP_DEFLATED: "deflate", zipfile.ZIP_BZIP2: "bzip2",
                 zipfile.ZIP_LZMA: "lzma"}


def _npy_header(handle) -> tuple[tuple[int, ...], bool, np.dtype]:
    """(shape, Fortran order, dtype) from the header of a ``.npy`` stream (format versions 1 and 2)."""
    version = np.lib.format.read_magic(handle)
    if version == (1, 0):
        return np.lib.format.read_array_header_1_0(handle)
    if version == (2, 0):
        return np.lib.format.read_array_header_2_0(handle)
    raise ValueError(f".npy format version {version[0]}.{version[1]} is not supported")


def _read_member(archive: zipfile.ZipFile, info: zipfile.ZipInfo, budget: int, path: Path) -> np.ndarray | None:
    """One member of an ``.npz`` as an array, None if it is an object array (it would need pickle),
    or a DartsInputError naming the member: not ``.npy``, encrypted, an unknown compression, a header
    declaring more than ``budget`` bytes, data that is damaged or not as long as its header says."""
    where = f"member '{info.filename}'"
    if not info.filename.endswith(".npy"):
        raise DartsInputError(path, f"{where} is not a .npy array")
    if info.flag_bits & 0x1:
        raise DartsInputError(path, f"{where} is encrypted")
    if info.compress_type not in _COMPRESSIONS:
        raise DartsInputError(path, f"{where} uses compression method {info.compress_type} "
                                    f"(readable: {', '.join(_COMPRESSIONS.values())})")
    try:
        with archive.open(info) as handle:
            shape, fortran, dtype = _npy_header(handle)
            if dtype.hasobject:
                return None
            count = math.prod(shape)
            size = count * dtype.itemsize
            if size > budget:
                raise DartsInputError(path, f"{where} declares a {shape} {dtype} array of {size / 2**30:.3g} GiB, "
                                            f"more than an input may hold ({MAX_INPUT_BYTES / 2**30:.0f} GiB)")
            data = handle.read(size + 1)  # one byte more: reaching the end checks the member's CRC
            if len(data) != size:
                raise DartsInputError(path, f"{where} holds {len(data)}{'+' if len(data) > size else ''} bytes of "
                                            f"data where its header declares {size}")
            return np.frombuffer(data, dtype=dtype, count=count).reshape(shape, order="F" if fortran else "C").copy()
    except DartsInputError:
        raise
    except Exception as exc:  # noqa: BLE001 -- damaged bytes fail in zlib, lzma, bz2, zipfile or numpy's parser
        raise DartsInputError(path, f"{where} is damaged ({type(exc).__name__}: {exc})") from None


def read_npz(path: str | os.PathLike) -> NpzArrays:
    """The arrays of an ``.npz`` archive, or a DartsInputError naming the file, the member and what
    is wrong with it; nothing larger than ``MAX_INPUT_BYTES`` in all is allocated.

    Object arrays (they need pickle: metadata dicts in official SMPL-X files, marker lists in some
    AMASS releases) are never unpickled: they are left out and named in ``refused``."""
    path = check_input_file(path, ".npz archive")
    try:
        archive = zipfile.ZipFile(path)
    # NotImplementedError: zipfile's answer to a header asking for a zip version it lacks (a damaged byte)
    except (zipfile.BadZipFile, zipfile.LargeZipFile, EOFError, OSError, ValueError, NotImplementedError) as exc:
        raise DartsInputError(path, f"not a valid .npz archive ({exc})") from None
    arrays, budget = NpzArrays(), MAX_INPUT_BYTES
    with archive:
        for info in archive.infolist():
            key = info.filename[:-4] if info.filename.endswith(".npy") else info.filename
            if key in arrays or key in arrays.refused:
                raise DartsInputError(path, f"member '{info.filename}' appears twice")
            array = _read_member(archive, info, budget, path)
            if array is None:
                arrays.refused[key] = "an object array (it would need pickle, which is never used)"
                continue
            arrays[key] = array
            budget -= array.nbytes
    return arrays


def require_keys(arrays: dict, keys, source, what: str | None = None) -> None:
    """Raise a DartsInputError listing every key of ``keys`` missing from ``arrays``, saying why
    where ``read_npz`` refused it, and that the file is not ``what`` (e.g. "an AMASS motion")."""
    missing = [key for key in keys if key not in arrays]
    if missing:
        refused = getattr(arrays, "refused", {})
        listed = ", ".join(f"'{key}' (stored as {refused[key]})" if key in refused else f"'{key}'" for key in missing)
        raise DartsInputError(source, f"missing key{'s' if len(missing) > 1 else ''} {listed}"
                                      + (f": not {what}" if what else ""))


def require_real(name: str, array: np.ndarray, source) -> np.ndarray:
    """``array`` if it holds real numbers (booleans, integers or floats), all finite; else a
    DartsInputError naming the array and what it holds instead (text, complex, records, objects)."""
    array = np.asarray(array)
    if array.dtype.kind not in "biuf":
        raise DartsInputError(source, f"'{name}' must be numbers, found {array.dtype.name} values")
    if array.dtype.kind == "f" and not np.isfinite(array).all():
        raise DartsInputError(source, f"'{name}' contains NaN or infinite values")
    return array


def require_indices(name: str, array: np.ndarray, source) -> np.ndarray:
    """``array`` as int64 if it holds whole numbers: integers, or floats without a fraction and
    below 2^53 (as some converted SMPL files store faces); else a DartsInputError naming it."""
    array = require_real(name, array, source)
    if array.dtype.kind == "f" and ((np.abs(array) > 2.0**53).any() or (array != np.round(array)).any()):
        raise DartsInputError(source, f"'{name}' must be whole numbers (indices)")
    return array.astype(np.int64)
