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
