"""Loading SMPL-format body files (official SMPL / SMPL-H / SMPL-X ``.pkl`` and ``.npz``, and the
bundled default body) and exporting a body in the official SMPL ``.npz`` layout.

Legacy ``.pkl`` files hold chumpy arrays and scipy sparse matrices; they are read with a restricted
unpickler that needs no chumpy and refuses any class outside numpy, scipy.sparse and chumpy.

``read_body`` gives the validated arrays (numpy, no torch: ``darts body info`` starts in a fraction
of a second); ``load_body`` makes them a ``BodyModel`` (torch) for posing and fitting.
"""
from __future__ import annotations

import json
import os
import pickle
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from darts import arguments as check
from darts.body.joints import BodySizes
from darts.body.segmentation import PART_NAMES
from darts.errors import DartsInputError
from darts.fileio import check_input_file, check_output, read_npz, require_indices, require_keys, require_real, save_npz

DEFAULT_BODY_PATH = Path(__file__).parent / "data" / "darts_default_body.npz"
DEFAULT_BODY_NAME = "darts-default-v1"
REQUIRED_KEYS = ("v_template", "shapedirs", "J_regressor", "weights", "kintree_table", "f")


class _ChumpyStub:
    """Stands in for any chumpy class while unpickling; keeps the pickled state."""

    def __new__(cls, *args, **kwargs):
        return object.__new__(cls)

    def __setstate__(self, state):
        self.state = state


@dataclass
class BodyArrays(BodySizes):
    """A validated SMPL-format body as numpy arrays (float64; canonical frame, Y up, metres):
    v_template [V,3], faces [F,3], shapedirs [V,3,K], posedirs [V,3,9(J-1)] or None (all zero),
    J_regressor [J,V], weights [V,J], parents [J] (-1 at the root)."""

    name: str
    v_template: np.ndarray
    faces: np.ndarray
    shapedirs: np.ndarray
    posedirs: np.ndarray | None
    J_regressor: np.ndarray
    weights: np.ndarray
    parents: np.ndarray
    gender: str = "neutral"
    metadata: dict = field(default_factory=dict)

    def shaped(self, betas=None) -> tuple[np.ndarray, np.ndarray]:
        """Rest shape T + S beta [V,3] and its joints J_regressor (T + S beta) [J,3] (canonical frame)."""
        vertices = self.v_template
        if betas is not None and len(betas := check.betas(betas, self.num_betas)):
            vertices = vertices + self.shapedirs[:, :, : len(betas)] @ betas
        return vertices, self.J_regressor @ vertices


class _SMPLUnpickler(pickle.Unpickler):
    """Unpickler for legacy SMPL pickles: numpy, scipy.sparse and chumpy stubs only."""

    _ALLOWED = {
        ("copy_reg", "_reconstructor"), ("copyreg", "_reconstructor"), ("__builtin__", "object"),
        ("builtins", "object"), ("copyreg", "__newobj__"), ("builtins", "set"), ("__builtin__", "set"),
        ("_codecs", "encode"),  # how protocol-2 pickles carry raw array bytes
    }

    def find_class(self, module, name):
        if module.split(".")[0] == "chumpy":
            return type(name, (_ChumpyStub,), {})
        if module.startswith("scipy.sparse") and name.endswith(("_matrix", "_array")):
            import scipy.sparse

            return getattr(scipy.sparse, name)
        if module.startswith("numpy"):
            module = module.replace("numpy.core", "numpy._core")
            if name in ("_reconstruct", "ndarray", "dtype", "scalar", "_frombuffer"):
                return super().find_class(module, name)
        if (module, name) in self._ALLOWED:
            return super().find_class(module, name)
        raise pickle.UnpicklingError(f"refusing to load {module}.{name}")


#: Chumpy arrays wrap their value (``state["x"]``), sometimes a few times over; deeper is refused.
_CHUMPY_DEPTH = 8


def _plain(value, key: str, source) -> np.ndarray:
    """A chumpy stub (unwrapped at most ``_CHUMPY_DEPTH`` times) or a sparse matrix as a dense numpy
    array; a value that is neither, nor an array of numbers, is refused naming ``key``."""
    for _ in range(_CHUMPY_DEPTH):
        if not isinstance(value, _ChumpyStub):
            break
        state = getattr(value, "state", None)
        if not isinstance(state, dict) or "x" not in state:
            raise DartsInputError(source, f"'{key}' is a chumpy expression, not a plain chumpy array")
        value = state["x"]
    else:
        raise DartsInputError(source, f"'{key}' is a chumpy array nested more than {_CHUMPY_DEPTH} deep")
    if hasattr(value, "toarray"):  # a scipy.sparse matrix (the only class the unpickler lets through with it)
        value = _sparse_to_dense(value, key, source)
    if not isinstance(value, np.ndarray | np.generic | int | float | list | tuple):
        raise DartsInputError(source, f"'{key}' must be an array of numbers, found a {type(value).__name__}")
    try:
        array = np.asarray(value)
    except (ValueError, TypeError, RecursionError) as exc:  # ragged or self-containing lists
        raise DartsInputError(source, f"'{key}' is not an array of numbers ({type(exc).__name__})") from None
    return require_real(key, array, source)


def _sparse_to_dense(matrix, key: str, source) -> np.ndarray:
    """A scipy sparse matrix (CSC, CSR or COO, as SMPL pickles hold) as a dense array, its structure
    checked in numpy first: scipy's own conversion trusts the index arrays, and indices outside the
    shape make it write outside its memory (the process dies with no message)."""
    def refuse(problem: str):
        raise DartsInputError(source, f"'{key}' is a sparse matrix {problem}")

    try:
        rows, cols = (int(n) for n in matrix.shape)
        form = matrix.format
    except (AttributeError, TypeError, ValueError):
        refuse("without a readable shape")
    if rows < 0 or cols < 0 or rows * cols > 10**9:
        refuse(f"of shape {rows}x{cols}")
    if form in ("csc", "csr"):
        indptr, indices, data = (np.asarray(getattr(matrix, name)) for name in ("indptr", "indices", "data"))
        major, minor = (cols, rows) if form == "csc" else (rows, cols)
        if (indptr.ndim != 1 or len(indptr) != major + 1 or indptr[0] != 0 or np.any(np.diff(indptr) < 0)
                or indptr[-1] != len(indices) or len(indices) != len(data)):
            refuse(f"whose {form.upper()} pointers do not fit its {rows}x{cols} shape")
        outer = np.repeat(np.arange(major), np.diff(indptr))
        r, c = (indices, outer) if form == "csc" else (outer, indices)
    elif form == "coo":
        r, c, data = (np.asarray(getattr(matrix, name)) for name in ("row", "col", "data"))
        if not (len(r) == len(c) == len(data)):
            refuse("whose row, column and value arrays differ in length")
    else:
        refuse(f"in the {form!r} format (CSC, CSR or COO expected)")
    if len(data) and (r.min() < 0 or r.max() >= rows or c.min() < 0 or c.max() >= cols):
        refuse(f"whose indices fall outside its {rows}x{cols} shape")
    dense = np.zeros((rows, cols), np.float64)
    np.add.at(dense, (r.astype(np.int64), c.astype(np.int64)), require_real(key, np.asarray(data), source))
    return dense


def _read_pkl(path: Path) -> dict:
    with open(path, "rb") as handle:
        if handle.read(4) == b"PK\x03\x04":
            raise DartsInputError(path, "is a zip archive (an .npz?), not a pickle: name it .npz")
    try:
        with open(path, "rb") as handle:
            data = _SMPLUnpickler(handle, encoding="latin1").load()
    # What damaged pickle data raises: LookupError covers a bad memo key, index or codec name.
    except (pickle.UnpicklingError, EOFError, AttributeError, ImportError, LookupError, TypeError, ValueError,
            RecursionError, MemoryError, OverflowError) as exc:
        raise DartsInputError(path, f"not a readable SMPL pickle ({exc})") from None
    if not isinstance(data, dict):
        raise DartsInputError(path, f"expected a dict of arrays, found {type(data).__name__}")
    return {key: _plain(value, key, path) for key, value in data.items() if key in REQUIRED_KEYS + ("posedirs",)}


def _read_arrays(path: Path) -> dict:
    check_input_file(path, "body model file")
    if path.suffix.lower() == ".pkl":
        return _read_pkl(path)
    if path.suffix.lower() == ".npz":
        return read_npz(path)
    raise DartsInputError(path, "unknown body file type (expected .npz or .pkl)")


def _parents_from_kintree(kintree: np.ndarray, num_joints: int, source) -> np.ndarray:
    if kintree.ndim != 2 or kintree.shape != (2, num_joints):
        raise DartsInputError(source, f"'kintree_table' has shape {kintree.shape}, expected (2, {num_joints})")
    parents = kintree[0].astype(np.int64)
    parents[0] = -1
    if (parents[1:] < 0).any() or (parents[1:] >= np.arange(1, num_joints)).any():
        raise DartsInputError(source, "'kintree_table' must list every parent before its children")
    return parents


#: metres: how tall (along Y, at rest) a body can be: an infant's SMIL body to a giant's.
HEIGHT_RANGE = (0.3, 3.0)


def body_arrays(arrays: dict, source, name: str | None = None) -> BodyArrays:
    """Validate SMPL-layout arrays (a file's keys: v_template, f, shapedirs, ...); every problem names ``source``."""
    require_keys(arrays, REQUIRED_KEYS, source)
    for key in REQUIRED_KEYS + ("posedirs",):
        if key in arrays:
            require_real(key, arrays[key], source)
    v_template = np.asarray(arrays["v_template"], np.float64)
    if v_template.ndim != 2 or v_template.shape[1] != 3 or len(v_template) < 4:
        raise DartsInputError(source, f"'v_template' has shape {v_template.shape}, expected [V, 3]")
    height = np.ptp(v_template[:, 1])  # the rest pose stands along Y (canonical frame)
    if not HEIGHT_RANGE[0] <= height <= HEIGHT_RANGE[1]:
        raise DartsInputError(source, f"the rest body is {height:.4g} m tall (Y); a body in metres stands "
                                      f"{HEIGHT_RANGE[0]:g} to {HEIGHT_RANGE[1]:g} m (is it in centimetres or millimetres?)")
    nv = len(v_template)
    faces = require_indices("f", arrays["f"], source)
    if faces.ndim != 2 or faces.shape[1] != 3 or faces.min(initial=0) < 0 or faces.max(initial=0) >= nv:
        raise DartsInputError(source, f"'f' must be [F, 3] indices into {nv} vertices")
    proper = (faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 0] != faces[:, 2])
    if proper.sum() < 4:  # the least closed surface; Warp's mesh and the distance queries need a surface
        raise DartsInputError(source, f"'f' holds {int(proper.sum())} proper triangles: a body is a surface of many")
    shapedirs = np.asarray(arrays["shapedirs"], np.float64)
    if shapedirs.ndim != 3 or shapedirs.shape[:2] != (nv, 3):
        raise DartsInputError(source, f"'shapedirs' has shape {shapedirs.shape}, expected [{nv}, 3, K]")
    weights = np.asarray(arrays["weights"], np.float64)
    if weights.ndim != 2 or weights.shape[0] != nv:
        raise DartsInputError(source, f"'weights' has shape {weights.shape}, expected [{nv}, J]")
    nj = weights.shape[1]
    regressor = np.asarray(arrays["J_regressor"], np.float64)
    if regressor.shape != (nj, nv):
        raise DartsInputError(source, f"'J_regressor' has shape {regressor.shape}, expected [{nj}, {nv}]")
    parents = _parents_from_kintree(require_indices("kintree_table", arrays["kintree_table"], source), nj, source)
    refused = getattr(arrays, "refused", {})
    if "posedirs" in refused:  # optional, but given: taking it as absent would pose without correctives unsaid
        raise DartsInputError(source, f"'posedirs' is {refused['posedirs']}: give it as an array of numbers, or leave it out")
    posedirs = arrays.get("posedirs")
    if posedirs is not None:
        posedirs = np.asarray(posedirs, np.float64)
        if posedirs.shape != (nv, 3, 9 * (nj - 1)):
            raise DartsInputError(source, f"'posedirs' has shape {posedirs.shape}, expected [{nv}, 3, {9 * (nj - 1)}]")
        if not posedirs.any():
            posedirs = None
    metadata = {}
    if "metadata_json" in arrays:
        try:
            metadata = json.loads(str(arrays["metadata_json"]))
        except ValueError as exc:
            raise DartsInputError(source, f"'metadata_json' is not JSON ({exc})") from None
        if not isinstance(metadata, dict):
            raise DartsInputError(source, "'metadata_json' must be a JSON object")
    body = BodyArrays(
        name=name or metadata.get("name") or Path(source).stem, v_template=v_template, faces=faces,
        shapedirs=shapedirs, posedirs=posedirs, J_regressor=regressor, weights=weights, parents=parents,
        gender=str(metadata.get("gender", "neutral")), metadata=metadata,
    )
    if "part_labels" in arrays:
        body.metadata["part_labels"] = _part_labels(arrays["part_labels"], nv, source)
    return body


def body_from_arrays(arrays: dict, source, name: str | None = None, dtype=None):
    """``body_arrays`` as a BodyModel (torch tensors of ``dtype``, default float32)."""
    from darts.body.model import BodyModel

    return BodyModel.from_arrays(body_arrays(arrays, source, name), dtype)


def read_body(path: str | os.PathLike | None = None) -> BodyArrays:
    """The validated arrays of the body in ``path`` (official SMPL/SMPL-H/SMPL-X .pkl or .npz), or
    of the bundled default; no torch."""
    source = Path(check.path_or(path, "path", what="None or a path")) if path is not None else DEFAULT_BODY_PATH
    return body_arrays(_read_arrays(source), source)


def load_body(path: str | os.PathLike | None = None, dtype=None):
    """The body in ``path`` (official SMPL/SMPL-H/SMPL-X .pkl or .npz), or the bundled default, as a
    ``BodyModel`` (torch tensors of ``dtype``, default float32)."""
    from darts.body.model import BodyModel

    return BodyModel.from_arrays(read_body(path), dtype)


def _part_labels(labels, num_vertices: int, source) -> np.ndarray:
    """One body part per vertex: integers indexing ``PART_NAMES``."""
    labels = require_indices("part_labels", labels, source)
    if labels.shape != (num_vertices,):
        raise DartsInputError(source, f"'part_labels' must be {num_vertices} integers (one per vertex), "
                                      f"found shape {labels.shape}")
    if labels.size and not (0 <= labels.min() and labels.max() < len(PART_NAMES)):
        raise DartsInputError(source, f"'part_labels' must lie in 0..{len(PART_NAMES) - 1} (the body parts)")
    return labels


def export_smpl_npz(body: BodyArrays, path: str | os.PathLike, betas=None) -> None:
    """Write ``body`` in the official SMPL ``.npz`` layout. With ``betas`` the shape is baked into
    ``v_template`` (shapedirs are kept, so further betas are relative to that shape)."""
    if not isinstance(body, BodyArrays):
        raise check.refuse("body", "a BodyArrays (darts.body.read_body)", body)
    path = check_output(check.path_or(path, "path"), (".npz",))
    v_shaped, _ = body.shaped(betas)
    num_joints = body.num_joints
    posedirs = body.posedirs
    if posedirs is None:
        posedirs = np.zeros((body.num_vertices, 3, 9 * (num_joints - 1)))
    kintree = np.stack([body.parents, np.arange(num_joints)]).astype(np.int64)
    kintree[0, 0] = -1
    save_npz(
        path, v_template=v_shaped, shapedirs=body.shapedirs, posedirs=posedirs, J_regressor=body.J_regressor,
        weights=body.weights, kintree_table=kintree, f=body.faces.astype(np.uint32),
    )
