"""Reading and writing DARTs (``garment.npz``, format "dart/1"; see docs/dart-format.md).

Every load validates the whole file; any problem raises DartsInputError naming the file.
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from darts.dart.model import FORMAT, MATERIAL_RANGES, REGIMES, Dart, Seam
from darts.errors import DartsInputError
from darts.fileio import read_npz, require_keys, require_real, save_npz
from darts.templates.categories import CATEGORIES

MATERIAL_KEYS = ("density", "stretch_stiffness", "bend_stiffness", "friction", "thickness")
REQUIRED = (
    "format", "category", "vertices", "faces", "panel", "panel_names", "line_names", "line_offsets",
    "line_vertices", "seam_names", "seam_regimes", "seam_stiffness", "seam_rest_length", "seam_partial_range",
    "pairs", "pair_seam", "pair_position", "pair_active", "body_model", "body_betas", "material_name",
    "accessories", *(f"material_{k}" for k in MATERIAL_KEYS),
)


def dart_arrays(dart: Dart) -> dict[str, np.ndarray]:
    """The arrays of ``garment.npz`` for ``dart``."""
    names = list(dart.lines)
    loops = [np.asarray(dart.lines[n], np.int32) for n in names]
    arrays = {
        "format": np.array(FORMAT), "category": np.array(dart.category),
        "vertices": np.asarray(dart.vertices, np.float32), "faces": np.asarray(dart.faces, np.int32),
        "panel": np.asarray(dart.panel, np.int32), "panel_names": np.array(dart.panel_names, dtype=str),
        "line_names": np.array(names, dtype=str),
        "line_offsets": np.cumsum([0] + [len(loop) for loop in loops]).astype(np.int32),
        "line_vertices": np.concatenate(loops).astype(np.int32) if loops else np.zeros(0, np.int32),
        "seam_names": np.array([s.name for s in dart.seams], dtype=str),
        "seam_regimes": np.array([s.regime for s in dart.seams], dtype=str),
        "seam_stiffness": np.array([s.stiffness for s in dart.seams], np.float32),
        "seam_rest_length": np.array([s.rest_length for s in dart.seams], np.float32),
        "seam_partial_range": np.array([s.partial_range for s in dart.seams], np.float32).reshape(-1, 2),
        "pairs": np.asarray(dart.pairs, np.int32).reshape(-1, 2), "pair_seam": np.asarray(dart.pair_seam, np.int32),
        "pair_position": np.asarray(dart.pair_position, np.float32), "pair_active": dart.pair_active,
        "body_model": np.array(dart.body_model), "body_betas": np.asarray(dart.body_betas, np.float32),
        "material_name": np.array(dart.material_name), "accessories": np.array(dart.accessories, dtype=str),
    }
    for key in MATERIAL_KEYS:
        arrays[f"material_{key}"] = np.array(dart.material[key], np.float32)
    if dart.hull_vertices is not None:
        arrays["hull_vertices"] = np.asarray(dart.hull_vertices, np.float32)
        arrays["hull_faces"] = np.asarray(dart.hull_faces, np.int32)
    return arrays


def save_dart(dart: Dart, path: str | os.PathLike) -> None:
    """Validate and write ``dart`` to ``path`` atomically."""
    arrays = dart_arrays(dart)
    dart_from_arrays(arrays, path)  # never write a file we would refuse to read
    save_npz(path, **arrays)


def _shape(arrays, key, shape, kind, source):
    value = arrays[key]
    if value.dtype.kind not in kind:
        expected = {"iu": "integers", "f": "floats", "U": "text", "b": "booleans"}[kind]
        raise DartsInputError(source, f"'{key}' has dtype {value.dtype}, expected {expected}")
    if len(shape) != value.ndim or any(s is not None and s != v for s, v in zip(shape, value.shape)):
        raise DartsInputError(source,
                              f"'{key}' has shape {value.shape}, expected {tuple('N' if s is None else s for s in shape)}")
    return value if kind == "U" else require_real(key, value, source)


def _indices(arrays, key, bound, source):
    value = arrays[key]
    if value.size and (value.min() < 0 or value.max() >= bound):
        raise DartsInputError(source, f"'{key}' has indices outside [0, {bound})")
    return value.astype(np.int64)


def _text(arrays, key, source) -> str:
    value = arrays[key]
    if value.dtype.kind != "U" or value.ndim != 0:
        raise DartsInputError(source, f"'{key}' must be a text value")
    return str(value)


def dart_from_arrays(arrays: dict, source) -> Dart:
    """Validate the arrays of a ``garment.npz`` and build the Dart."""
    require_keys(arrays, REQUIRED, source)
    if _text(arrays, "format", source) != FORMAT:
        raise DartsInputError(source, f"format '{arrays['format']}' is not supported (expected '{FORMAT}')")
    category = _text(arrays, "category", source)
    if category not in CATEGORIES:
        raise DartsInputError(source, f"unknown category '{category}'")
    vertices = _shape(arrays, "vertices", (None, 3), "f", source)
    faces = _indices(arrays | {"faces": _shape(arrays, "faces", (None, 3), "iu", source)}, "faces", len(vertices), source)
    _check_surface(vertices, faces, source)
    panel_names = [str(n) for n in _shape(arrays, "panel_names", (None,), "U", source)]
    panel = _indices(arrays | {"panel": _shape(arrays, "panel", (len(faces),), "iu", source)}, "panel", len(panel_names), source)
    line_names = [str(n) for n in _shape(arrays, "line_names", (None,), "U", source)]
    offsets = _shape(arrays, "line_offsets", (len(line_names) + 1,), "iu", source).astype(np.int64)
    line_vertices = _indices(arrays | {"line_vertices": _shape(arrays, "line_vertices", (None,), "iu", source)},
                             "line_vertices", len(vertices), source)
    if offsets[0] != 0 or offsets[-1] != len(line_vertices) or (np.diff(offsets) < 3).any():
        raise DartsInputError(source, "'line_offsets' do not split 'line_vertices' into loops of 3 or more")
    seam_names = [str(n) for n in _shape(arrays, "seam_names", (None,), "U", source)]
    count = len(seam_names)
    regimes = [str(r) for r in _shape(arrays, "seam_regimes", (count,), "U", source)]
    stiffness = _shape(arrays, "seam_stiffness", (count,), "f", source)
    rest = _shape(arrays, "seam_rest_length", (count,), "f", source)
    ranges = _shape(arrays, "seam_partial_range", (count, 2), "f", source)
    seams = [Seam(n, r, float(k), float(l), (float(a), float(b)))
             for n, r, k, l, (a, b) in zip(seam_names, regimes, stiffness, rest, ranges)]
    for seam in seams:
        if seam.regime not in REGIMES:
            raise DartsInputError(source, f"seam '{seam.name}': unknown regime '{seam.regime}'")
        seam.check(source)
    pairs = _indices(arrays | {"pairs": _shape(arrays, "pairs", (None, 2), "iu", source)}, "pairs", len(vertices), source)
    if len(pairs) and (pairs[:, 0] == pairs[:, 1]).any():
        raise DartsInputError(source, "a seam pair joins a vertex to itself")
    pair_seam = _indices(arrays | {"pair_seam": _shape(arrays, "pair_seam", (len(pairs),), "iu", source)},
                         "pair_seam", count, source)
    position = _shape(arrays, "pair_position", (len(pairs),), "f", source)
    if len(position) and (position.min() < 0 or position.max() > 1):
        raise DartsInputError(source, "'pair_position' must lie in [0, 1]")
    material = {k: float(_shape(arrays, f"material_{k}", (), "f", source)) for k in MATERIAL_KEYS}
    for key, value in material.items():
        low, high = MATERIAL_RANGES[key]
        if not low <= value <= high:
            raise DartsInputError(source, f"'material_{key}' is {value:g}, outside the range of cloth [{low:g}, {high:g}]")
    hull_vertices = hull_faces = None
    if ("hull_vertices" in arrays) != ("hull_faces" in arrays):
        raise DartsInputError(source, "'hull_vertices' and 'hull_faces' come together (one of them is missing)")
    if "hull_vertices" in arrays:
        hull_vertices = _shape(arrays, "hull_vertices", (None, 3), "f", source)
        hull_faces = _indices(arrays | {"hull_faces": _shape(arrays, "hull_faces", (None, 3), "iu", source)},
                              "hull_faces", len(hull_vertices), source).astype(np.int32)
    dart = Dart(
        category=category, vertices=vertices.astype(np.float32), faces=faces.astype(np.int32), panel=panel.astype(np.int32),
        panel_names=panel_names,
        lines={n: line_vertices[offsets[i]:offsets[i + 1]].astype(np.int32) for i, n in enumerate(line_names)},
        seams=seams, pairs=pairs.astype(np.int32), pair_seam=pair_seam.astype(np.int32),
        pair_position=position.astype(np.float32),
        body_model=_text(arrays, "body_model", source),
        body_betas=_shape(arrays, "body_betas", (None,), "f", source).astype(np.float32),
        material_name=_text(arrays, "material_name", source), material=material,
        hull_vertices=None if hull_vertices is None else hull_vertices.astype(np.float32), hull_faces=hull_faces,
        accessories=[str(a) for a in _shape(arrays, "accessories", (None,), "U", source)],
    )
    if not np.array_equal(_shape(arrays, "pair_active", (len(pairs),), "b", source), dart.pair_active):
        raise DartsInputError(source, "'pair_active' does not match the seams' partial ranges")
    _check_lines(dart, source)
    return dart


#: The sides of a garment's bounding box, metres: the largest side at least a glove's, at most a
#: gown's train (a file in millimetres or a point cloud collapsed to a point is refused).
GARMENT_SIZE = (0.05, 5.0)


def _check_surface(vertices: np.ndarray, faces: np.ndarray, source) -> None:
    """A garment is a surface of a garment's size: at least one triangle, every triangle with three
    different corners, its bounding box's largest side within ``GARMENT_SIZE``."""
    if len(faces) == 0:
        raise DartsInputError(source, "the garment has no triangles")
    if ((faces[:, 0] == faces[:, 1]) | (faces[:, 1] == faces[:, 2]) | (faces[:, 2] == faces[:, 0])).any():
        raise DartsInputError(source, "a triangle of 'faces' repeats a corner")
    size = float(np.ptp(vertices[np.unique(faces)], axis=0).max())
    if not GARMENT_SIZE[0] <= size <= GARMENT_SIZE[1]:
        raise DartsInputError(source, f"the garment is {size:.3g} m across; a garment in metres is "
                                      f"{GARMENT_SIZE[0]:g} to {GARMENT_SIZE[1]:g} m")


def _check_lines(dart: Dart, source) -> None:
    """Each feature line is closed: consecutive vertices share a mesh edge or are a seam pair, and
    each vertex has exactly two neighbours on the loop."""
    size = len(dart.vertices)
    edges = np.concatenate([dart.faces[:, [0, 1]], dart.faces[:, [1, 2]], dart.faces[:, [2, 0]], dart.pairs]).astype(np.int64)
    known = set((np.minimum(edges[:, 0], edges[:, 1]) * size + np.maximum(edges[:, 0], edges[:, 1])).tolist())
    for name, loop in dart.lines.items():
        loop = loop.astype(np.int64)
        nxt = np.roll(loop, -1)
        steps = np.minimum(loop, nxt) * size + np.maximum(loop, nxt)
        if len(np.unique(loop)) != len(loop) or not all(int(s) in known for s in steps):
            raise DartsInputError(source, f"feature line '{name}' is not a closed edge loop")


def load_dart(path: str | os.PathLike) -> Dart:
    """Read and validate a ``garment.npz``."""
    path = Path(path)
    return dart_from_arrays(read_npz(path), path)
