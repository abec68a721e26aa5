"""Test data builders."""
from __future__ import annotations

import pickle
import sys
import types
from pathlib import Path

import numpy as np

from darts.dart.model import Dart


def random_motion_arrays(frames: int, seed: int = 0, scale: float = 0.4) -> dict:
    """A classic SMPL-H AMASS dict with random poses (radians) and translations."""
    rng = np.random.default_rng(seed)
    return {
        "poses": rng.normal(0, scale, (frames, 156)),
        "trans": rng.normal(0, 0.3, (frames, 3)) + [0, 0, 1.0],
        "betas": np.zeros(16),
        "gender": np.array("neutral"),
        "mocap_framerate": np.array(30.0),
    }


def write_classic_amass_120fps(source_path, path) -> None:
    """A classic AMASS SMPL-H file at 120.00004577 fps (dmpls, bytes gender) made from a motion."""
    from darts.fileio import save_npz
    from darts.motion.amass import load_motion
    from darts.motion.resampling import resample

    fine = resample(load_motion(source_path), 120.00004577)
    save_npz(path, poses=np.concatenate([fine.body_pose, fine.hand_pose], 1).reshape(fine.num_frames, -1),
             trans=fine.trans, betas=np.zeros(16), gender=np.array(b"male"), dmpls=np.zeros((fine.num_frames, 8)),
             mocap_framerate=np.array(120.00004577))


def grid_sheet(n: int, spacing: float, origin, height) -> tuple[np.ndarray, np.ndarray]:
    """An n x n grid of Z-up vertices at ``origin`` + (i, j) ``spacing`` (vertex i n + j), z =
    height(x, y), and its faces: each square split along its (i, j)-(i + 1, j + 1) diagonal, normals up."""
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    xy = np.asarray(origin, float) + spacing * np.stack([i.ravel(), j.ravel()], axis=1)
    vertices = np.column_stack([xy, height(xy[:, 0], xy[:, 1])])
    a = (i[:-1, :-1] * n + j[:-1, :-1]).ravel()
    faces = np.concatenate([np.stack([a, a + n, a + n + 1], 1), np.stack([a, a + n + 1, a + 1], 1)])
    return vertices, faces


def sheet_dart(vertices: np.ndarray, faces: np.ndarray) -> Dart:
    """A one-panel DART of a bare mesh (no lines, no seams), for solver tests."""
    empty = np.zeros((0, 2), np.int32)
    return Dart(category="test-sheet", vertices=vertices.astype(np.float32), faces=faces.astype(np.int32),
                panel=np.zeros(len(faces), np.int32), panel_names=["sheet"], lines={}, seams=[], pairs=empty,
                pair_seam=np.zeros(0, np.int32), pair_position=np.zeros(0, np.float32))


class ChumpyArray:
    """Pickles as ``chumpy.ch.Ch`` does in legacy SMPL files: the state holds the value under 'x'."""

    def __init__(self, x):
        self.x = x


ChumpyArray.__module__, ChumpyArray.__qualname__ = "chumpy.ch", "Ch"


def chumpy_holding_itself() -> ChumpyArray:
    """A chumpy array whose value is itself (a pickle can hold such a loop)."""
    array = ChumpyArray(None)
    array.x = array
    return array


def nested_chumpy(value, depth: int):
    """``value`` wrapped in ``depth`` chumpy arrays."""
    for _ in range(depth):
        value = ChumpyArray(value)
    return value


def npz_arrays(path) -> dict[str, np.ndarray]:
    """Every array of an ``.npz`` file, by key."""
    with np.load(path) as archive:
        return {key: archive[key] for key in archive.files}


def legacy_pickle(values: dict) -> bytes:
    """``values`` as the bytes of a legacy SMPL ``.pkl`` (protocol 2), ChumpyArray values pickled
    as chumpy arrays; chumpy is faked only while pickling, so loading runs without it."""
    chumpy, ch = types.ModuleType("chumpy"), types.ModuleType("chumpy.ch")
    ch.Ch = ChumpyArray
    saved = {name: sys.modules.get(name) for name in ("chumpy", "chumpy.ch")}
    limit = sys.getrecursionlimit()
    sys.modules.update({"chumpy": chumpy, "chumpy.ch": ch})
    sys.setrecursionlimit(max(limit, 30000))  # deeply nested values
    try:
        return pickle.dumps(values, protocol=2)
    finally:
        sys.setrecursionlimit(limit)
        for name, module in saved.items():
            sys.modules.pop(name) if module is None else sys.modules.__setitem__(name, module)


def cone_skirt_obj(path, rows: int = 28, around: int = 80, centre=(0.12, 0.95, -0.05)) -> None:
    """A skirt made as a truncated elliptic cone of quads (OBJ, metres, Y up), not by the template
    builder: waist 0.17 x 0.12 m (half-axes) at ``centre``, hem 0.30 x 0.26 m, 0.42 m below."""
    height, top, bottom = 0.42, np.array([0.17, 0.12]), np.array([0.30, 0.26])
    lines = []
    for row in range(rows + 1):
        t = row / rows
        radii = (1 - t) * top + t * bottom
        for k in range(around):
            angle = 2 * np.pi * k / around
            lines.append(f"v {centre[0] + radii[0] * np.cos(angle):.6f} {centre[1] - t * height:.6f} "
                         f"{centre[2] + radii[1] * np.sin(angle):.6f}")
    for row in range(rows):
        for k in range(around):
            a, b = row * around + k, row * around + (k + 1) % around
            lines.append(f"f {a + 1} {b + 1} {b + around + 1} {a + around + 1}")
    Path(path).write_text("\n".join(lines) + "\n")


def remeshed_shirt(dart: Dart) -> tuple[np.ndarray, np.ndarray]:
    """A shirt not from the template builder: ``dart``'s welded surface subdivided (4x the
    triangles), stretched 6 % wide and 3 % long, turned 20 degrees about the vertical and 4 about
    the side axis, moved away, in centimetres (Y up): (vertices [N,3] cm, faces [F,3])."""
    import trimesh
    from scipy.spatial.transform import Rotation

    from darts.dart.model import welded

    vertices, faces, _ = welded(dart)
    vertices, faces = trimesh.remesh.subdivide(np.asarray(vertices, np.float64), faces)
    vertices = vertices * [1.06, 1.03, 1.0]
    vertices = Rotation.from_euler("yx", [20, 4], degrees=True).apply(vertices) + [0.3, 1.1, -0.2]
    return 100.0 * vertices, faces


def write_usd_mesh(path, vertices: np.ndarray, faces: np.ndarray, meters_per_unit: float, up: str,
                   translate=(0.0, 0.0, 0.0)) -> None:
    """A USD stage holding one mesh at /World/Garment (its points as given, an Xform translate
    ``translate`` on it), with the stage's metersPerUnit and upAxis set."""
    from pxr import Gf, Usd, UsdGeom

    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.SetStageMetersPerUnit(stage, meters_per_unit)
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z if up == "z" else UsdGeom.Tokens.y)
    UsdGeom.Xform.Define(stage, "/World")
    mesh = UsdGeom.Mesh.Define(stage, "/World/Garment")
    mesh.CreatePointsAttr([Gf.Vec3f(*map(float, p)) for p in vertices])
    mesh.CreateFaceVertexCountsAttr([3] * len(faces))
    mesh.CreateFaceVertexIndicesAttr([int(i) for i in np.asarray(faces).reshape(-1)])
    UsdGeom.XformCommonAPI(mesh).SetTranslate(Gf.Vec3d(*translate))
    stage.GetRootLayer().Save()


#: Surface samples each way of ``round_trip_distances``.
ROUND_TRIP_SAMPLES = 20_000
#: Seam vertices within this of the original's seams are where the template put them (metres).
SEAM_TOLERANCE = 0.005
#: ``isotropic_remesh`` keeps the vertices of creases sharper than this (dihedral angle, degrees).
CREASE_DEGREES = 30.0


def isotropic_remesh(dart: Dart, factor: float) -> tuple[np.ndarray, np.ndarray]:
    """The welded surface of ``dart`` (its panels joined at the seams) remeshed isotropically to
    ``factor`` times its mean edge (``darts.geometry.remesh.remesh``: gpytoolbox's ``remesh_botsch``,
    Botsch & Kobbelt 2004, 10 rounds; the openings kept, and the vertices of creases sharper than
    ``CREASE_DEGREES`` fixed, as a remesher that keeps features does: without them a collar folded
    over the shirt collapsed onto it, p95 25 mm): (vertices [N,3], faces [F,3]), another
    triangulation of the surface."""
    import trimesh

    from darts.dart.model import welded
    from darts.geometry.remesh import remesh

    vertices, faces, _ = welded(dart)
    vertices = np.asarray(vertices, np.float64)
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    mean_edge = float(np.linalg.norm(vertices[edges[:, 0]] - vertices[edges[:, 1]], axis=1).mean())
    surface = trimesh.Trimesh(vertices, faces, process=False)
    creases = np.unique(surface.face_adjacency_edges[surface.face_adjacency_angles > np.radians(CREASE_DEGREES)])
    return remesh(vertices, faces, factor * mean_edge, fixed=creases)


def _surface_samples(vertices: np.ndarray, faces: np.ndarray, count: int, seed: int) -> np.ndarray:
    import trimesh

    points, _ = trimesh.sample.sample_surface(trimesh.Trimesh(vertices, faces, process=False), count, seed=seed)
    return np.asarray(points)


def seam_edges(dart) -> np.ndarray:
    """[E,2,3] the panel-boundary edges of ``dart`` both of whose ends are seam vertices."""
    from darts.geometry.mesh import boundary_edges

    boundary = boundary_edges(np.asarray(dart.faces))
    on_seam = np.zeros(len(dart.vertices), bool)
    on_seam[np.asarray(dart.pairs).reshape(-1)] = True
    kept = boundary[on_seam[boundary[:, 0]] & on_seam[boundary[:, 1]]]
    return np.asarray(dart.vertices, np.float64)[kept]


def seam_offsets(imported, original) -> np.ndarray:
    """[S] metres: each seam vertex of ``imported`` to the nearest seam edge of ``original``."""
    points = np.asarray(imported.vertices, np.float64)[np.unique(np.asarray(imported.pairs))]
    segments = seam_edges(original)
    a, ab = segments[:, 0], segments[:, 1] - segments[:, 0]
    best = np.full(len(points), np.inf)
    for start in range(0, len(points), 256):
        chunk = points[start:start + 256, None]
        t = np.clip(((chunk - a) * ab).sum(-1) / np.maximum((ab * ab).sum(-1), 1e-18), 0, 1)
        best[start:start + 256] = np.linalg.norm(chunk - (a + t[..., None] * ab), axis=-1).min(1)
    return best


def round_trip_distances(imported: Dart, original: Dart, seed: int = 0) -> dict:
    """``imported`` against ``original`` (both canonical frame): unsigned point-to-surface distances
    both ways from ``ROUND_TRIP_SAMPLES`` area-uniform samples of one welded surface to the other
    (mean, p95, max, mm), and the seam vertices' offsets (``seam_offsets``: mean, max, the share
    within ``SEAM_TOLERANCE``)."""
    from darts.dart.model import welded
    from darts.geometry.distance import SurfaceDistance
    from darts.meshimport.register import distance_stats

    result = {}
    surfaces = {name: welded(dart)[:2] for name, dart in (("imported", imported), ("original", original))}
    for name, source, target in (("imported_to_original", "imported", "original"),
                                 ("original_to_imported", "original", "imported")):
        samples = _surface_samples(np.asarray(surfaces[source][0], np.float64), surfaces[source][1], ROUND_TRIP_SAMPLES, seed)
        distance, _, _ = SurfaceDistance(*surfaces[target]).query(samples, winding=False)
        result[name] = distance_stats(distance)
    seams = seam_offsets(imported, original)
    result["seams"] = {"mean_mm": 1e3 * float(seams.mean()), "max_mm": 1e3 * float(seams.max()),
                       "within_5mm": float((seams <= SEAM_TOLERANCE).mean()), "vertices": len(seams)}
    return result
