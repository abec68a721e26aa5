"""Accessories stitched onto a DART's seams (paper, Fig. 7c): a collar on the neckline, a tie at
the centre front. Each is a new panel; its first row coincides with garment vertices and is joined
to them by its own seam (zero gap at rest). The rest lies on the garment, ``LIFT`` above it.
"""
from __future__ import annotations

import numpy as np

from darts.dart.model import Dart, Seam
from darts.errors import DartsInputError
from darts.templates.defaults import DEFAULT_EDGE_LENGTH

LIFT = 0.004  # metres between an accessory and the garment under it
ACCESSORIES = ("collar", "tie")


def _strip_faces(rows: int, columns: int, closed: bool) -> np.ndarray:
    """Triangles of a rows x columns grid of vertices (row-major), optionally closed around."""
    faces = []
    span = columns if closed else columns - 1
    for r in range(rows - 1):
        for c in range(span):
            a, b = r * columns + c, r * columns + (c + 1) % columns
            faces += [(a, b, b + columns), (a, b + columns, a + columns)]
    return np.array(faces, np.int64)


def _surface(dart: Dart):
    from darts.geometry.distance import SurfaceDistance  # starts Warp only when needed

    return SurfaceDistance(dart.vertices, dart.faces)


def _project(dart: Dart, surface, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The closest garment points to ``points`` and the outward normals there (away from the
    garment's centre)."""
    _, closest, normal = surface.query(points, winding=False)
    return closest, normal * np.sign(np.einsum("ij,ij->i", normal, closest - dart.vertices.mean(0)))[:, None]


def _on_garment(dart: Dart, points: np.ndarray) -> np.ndarray:
    """Project points onto the garment and lift them off it along its normal (outwards)."""
    closest, outward = _project(dart, _surface(dart), points)
    return closest + LIFT * outward


def _neckline_ring(dart: Dart) -> np.ndarray:
    """The neckline's vertices without the second copy where a seam crosses it."""
    loop = dart.lines["neckline"]
    twin = {(int(a), int(b)) for a, b in dart.pairs} | {(int(b), int(a)) for a, b in dart.pairs}
    return np.array([v for i, v in enumerate(loop) if (int(loop[i - 1]), int(v)) not in twin], np.int64)


def _attach(dart: Dart, name: str, vertices: np.ndarray, faces: np.ndarray, stitched: np.ndarray) -> None:
    """Append an accessory panel whose first len(stitched) vertices pair with garment ``stitched``."""
    offset = len(dart.vertices)
    dart.vertices = np.concatenate([dart.vertices, vertices.astype(np.float32)])
    dart.faces = np.concatenate([dart.faces, (faces + offset).astype(np.int32)])
    dart.panel = np.concatenate([dart.panel, np.full(len(faces), len(dart.panel_names), np.int32)])
    dart.panel_names = dart.panel_names + [name]
    pairs = np.stack([stitched, offset + np.arange(len(stitched))], 1)
    dart.pairs = np.concatenate([dart.pairs, pairs.astype(np.int32)])
    dart.pair_seam = np.concatenate([dart.pair_seam, np.full(len(pairs), len(dart.seams), np.int32)])
    dart.pair_position = np.concatenate([dart.pair_position, np.linspace(0, 1, len(pairs)).astype(np.float32)])
    dart.seams = dart.seams + [Seam(name)]
    dart.accessories = dart.accessories + [name]


def add_collar(dart: Dart, width: float = 0.055, edge_length: float = DEFAULT_EDGE_LENGTH) -> None:
    """A collar band lying on the shoulders around the neckline, stitched to it."""
    ring = _neckline_ring(dart)
    base = dart.vertices[ring].astype(np.float64)
    centre = base.mean(0)
    outward = base - centre
    outward[:, 1] = 0.0
    outward /= np.linalg.norm(outward, axis=1, keepdims=True)
    rows = max(int(np.ceil(width / edge_length)), 2) + 1
    reach = (np.arange(1, rows) / (rows - 1))[:, None, None] * width * (outward - [0.0, 0.35, 0.0])
    draped = _on_garment(dart, (base + reach).reshape(-1, 3))
    # The ring follows the garment's boundary half-edges, so the collar runs the other way round:
    # welded to the neckline it continues the garment's surface with a consistent orientation.
    faces = _strip_faces(rows, len(ring), closed=True)[:, ::-1]
    _attach(dart, "collar", np.concatenate([base, draped]), faces, ring)


def add_tie(dart: Dart, length: float = 0.42, width: float = 0.07, edge_length: float = DEFAULT_EDGE_LENGTH) -> None:
    """A tie hanging from the centre front of the neckline, stitched there, laid on the garment row
    by row: each row's centre is one step down the surface from the last (the step taken along
    -Y in the tangent plane, then projected), its columns spread along +X in that plane."""
    ring = _neckline_ring(dart)
    base = dart.vertices[ring].astype(np.float64)
    knot = ring[int(np.argmin(-base[:, 2] + 10.0 * np.abs(base[:, 0])))]
    columns = 5
    rows = max(int(np.ceil(length / edge_length)), 2) + 1
    step = length / (rows - 1)
    surface = _surface(dart)
    centre, normal = _project(dart, surface, dart.vertices[knot][None].astype(np.float64))
    grid = []
    for r in range(1, rows):
        down = np.array([0.0, -1.0, 0.0]) - normal[0] * -normal[0, 1]
        centre, normal = _project(dart, surface, centre + step * down / np.linalg.norm(down))
        side = np.array([1.0, 0.0, 0.0]) - normal[0] * normal[0, 0]
        half = 0.5 * width * min(1.0, 0.35 + r / (rows - 1))
        row = centre + np.linspace(-half, half, columns)[:, None] * side / np.linalg.norm(side)
        closest, outward = _project(dart, surface, row)
        grid.append(closest + LIFT * outward)
    vertices = np.concatenate([dart.vertices[knot][None].astype(np.float64), *grid])
    # Fan from the knot vertex to the first row, then a grid.
    fan = np.array([(0, 1 + c + 1, 1 + c) for c in range(columns - 1)], np.int64)
    body = _strip_faces(rows - 1, columns, closed=False) + 1
    _attach(dart, "tie", vertices, np.concatenate([fan, body]), np.array([knot]))


def add_accessory(dart: Dart, name: str, edge_length: float = DEFAULT_EDGE_LENGTH) -> None:
    """Add the accessory ``name`` (collar or tie) to a top or dress."""
    if name not in ACCESSORIES:
        raise DartsInputError(None, f"unknown accessory '{name}' (one of {', '.join(ACCESSORIES)})")
    if "neckline" not in dart.lines:
        raise DartsInputError(None, f"a {name} needs a neckline: '{dart.category}' has none")
    if name in dart.accessories:
        raise DartsInputError(None, f"the garment already has a {name}")
    (add_collar if name == "collar" else add_tie)(dart, edge_length=edge_length)
