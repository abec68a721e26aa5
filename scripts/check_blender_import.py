"""Check that a darts-sim USD file imports into Blender with its animation (headless, `pip install bpy`).

    python scripts/check_blender_import.py OUT.usd [OUT2.usda ...]

For each file: import it, then compare the garment's evaluated vertices in Blender with the USD
points at the first, middle and last time codes (which must differ: the animation plays) (Blender
and the file are both Z up, metres).
Exits non-zero on any mismatch.
"""
from __future__ import annotations

import sys

import numpy as np


def check(path: str) -> float:
    import bpy
    from pxr import Usd, UsdGeom

    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.wm.usd_import(filepath=path, set_frame_range=True)
    stage = Usd.Stage.Open(path)
    start, end = int(stage.GetStartTimeCode()), int(stage.GetEndTimeCode())
    scene = bpy.context.scene
    assert (scene.frame_start, scene.frame_end) == (start, end), (scene.frame_start, scene.frame_end, start, end)
    points = UsdGeom.Mesh(stage.GetPrimAtPath("/World/garment")).GetPointsAttr()
    objects = {o.name: o for o in scene.objects if o.type == "MESH"}
    garment = objects["garment"]
    assert "body" in objects, sorted(objects)
    worst, seen = 0.0, []
    for frame in (start, (start + end) // 2, end):
        scene.frame_set(frame)
        evaluated = garment.evaluated_get(bpy.context.evaluated_depsgraph_get())
        mesh = evaluated.to_mesh()
        blender = np.array([evaluated.matrix_world @ v.co for v in mesh.vertices])
        evaluated.to_mesh_clear()
        usd = np.array(points.Get(frame))
        assert blender.shape == usd.shape, (blender.shape, usd.shape)
        worst = max(worst, float(np.abs(blender - usd).max()))
        seen.append(blender)
    assert np.abs(seen[-1] - seen[0]).max() > 1e-3, "the garment does not move in Blender"
    assert worst < 1e-5, f"Blender's garment differs from the USD points by {worst} m"
    return worst


if __name__ == "__main__":
    for arg in sys.argv[1:]:
        print(f"{arg}: imported; garment matches the USD points to {check(arg):.2e} m at three frames")
