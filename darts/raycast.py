"""Ray-cast pictures of triangle meshes through a pinhole camera (``darts.camera.Camera``), on Warp's
CPU backend (``wp.mesh_query_ray`` over each mesh's BVH).

``cast`` finds, for every ray, the nearest hit over all meshes: which mesh (-1 none), which face,
where (the hit point, canonical frame) and whether the ray met the face's front (the side its
counter-clockwise normal points to) or its back (the inside of an open garment). ``shade`` turns
hits into colours: Lambert shading with the interpolated vertex normal turned towards the viewer,
an ambient term and a small Blinn-Phong highlight. A picture of W x H pixels with S x S samples per
pixel costs W H S^2 ray queries per mesh.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from darts.camera import Camera
from darts.geometry.mesh import vertex_normals
from darts.geometry.warp_runtime import warp

wp = warp()


@wp.kernel
def _nearest_hits(meshes: wp.array(dtype=wp.uint64), count: int, origin: wp.vec3, directions: wp.array(dtype=wp.vec3),
                  which: wp.array(dtype=wp.int32), face: wp.array(dtype=wp.int32), distance: wp.array(dtype=float)):
    i = wp.tid()
    best = distance[i]  # in: the farthest hit wanted; out: the nearest hit's distance
    which[i] = -1
    for m in range(count):
        query = wp.mesh_query_ray(meshes[m], origin, directions[i], best)
        if query.result and query.t < best:
            best = query.t
            which[i] = m
            face[i] = query.face
    distance[i] = best


@dataclass
class Hits:
    """Per ray: mesh index (-1: background), face, hit point [N,3], front (True) or back side."""

    which: np.ndarray
    face: np.ndarray
    point: np.ndarray
    front: np.ndarray


def pixel_samples(camera: Camera, samples: int) -> np.ndarray:
    """Image points [H*W*S*S, 2] (u, v): an S x S grid inside every pixel, row-major by pixel."""
    offsets = (np.arange(samples) + 0.5) / samples
    sub_v, sub_u = np.meshgrid(offsets, offsets, indexing="ij")
    rows, cols = np.meshgrid(np.arange(camera.height), np.arange(camera.width), indexing="ij")
    u = cols[:, :, None] + sub_u.reshape(-1)[None, None]
    v = rows[:, :, None] + sub_v.reshape(-1)[None, None]
    return np.stack([u.reshape(-1), v.reshape(-1)], 1)


def cast_rays(meshes: list[tuple[np.ndarray, np.ndarray]], origin: np.ndarray, directions: np.ndarray,
              max_distance: np.ndarray | float = 1e10) -> Hits:
    """Nearest hits of the rays ``origin`` + t ``directions`` [N,3] (unit), 0 < t < ``max_distance``
    ([N] or one value), against ``meshes`` [(vertices [V,3], faces [F,3])]."""
    points = [wp.array(np.ascontiguousarray(v, np.float32), dtype=wp.vec3) for v, _ in meshes]
    indices = [wp.array(np.ascontiguousarray(f, np.int32).reshape(-1), dtype=wp.int32) for _, f in meshes]
    built = [wp.Mesh(points=p, indices=i) for p, i in zip(points, indices)]
    n = len(directions)
    which, face = wp.zeros(n, dtype=wp.int32), wp.zeros(n, dtype=wp.int32)
    distance = wp.array(np.broadcast_to(np.asarray(max_distance, np.float32), (n,)).copy(), dtype=float)
    wp.launch(_nearest_hits, dim=n, inputs=[wp.array([m.id for m in built], dtype=wp.uint64), len(built),
                                            wp.vec3(*np.asarray(origin, np.float32)),
                                            wp.array(np.ascontiguousarray(directions, np.float32), dtype=wp.vec3),
                                            which, face, distance])
    which_np, face_np = which.numpy(), face.numpy()
    front = np.zeros(n, bool)
    for m, (vertices, faces) in enumerate(meshes):
        mine = which_np == m
        tri = np.asarray(vertices, np.float64)[np.asarray(faces)[face_np[mine]]]
        normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        front[mine] = (normal * directions[mine]).sum(1) < 0  # the ray meets the side the normal points to
    return Hits(which_np, face_np, origin + directions * distance.numpy()[:, None].astype(np.float64), front)


def cast(camera: Camera, meshes: list[tuple[np.ndarray, np.ndarray]], samples: int = 1) -> Hits:
    """Nearest hits of the rays of ``pixel_samples(camera, samples)`` against ``meshes``
    [(vertices [V,3] canonical frame, faces [F,3])]."""
    origin, directions = camera.rays(pixel_samples(camera, samples))
    return cast_rays(meshes, origin, directions)


def surface_normals(vertices: np.ndarray, faces: np.ndarray, face: np.ndarray, point: np.ndarray) -> np.ndarray:
    """Unit normals [N,3] at hit ``point``s on ``face``s, interpolated barycentrically from the vertex normals."""
    tri = vertices[faces[face]]
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    n = np.cross(b - a, c - a)
    area = np.maximum((n * n).sum(1), 1e-30)
    wa = (np.cross(c - b, point - b) * n).sum(1) / area
    wb = (np.cross(a - c, point - c) * n).sum(1) / area
    wc = 1.0 - wa - wb
    normals = vertex_normals(vertices, faces)[faces[face]]
    blended = wa[:, None] * normals[:, 0] + wb[:, None] * normals[:, 1] + wc[:, None] * normals[:, 2]
    return blended / np.maximum(np.linalg.norm(blended, axis=1, keepdims=True), 1e-12)


def shade(normals: np.ndarray, view: np.ndarray, albedo: np.ndarray, light: np.ndarray, ambient: float = 0.35,
          specular: float = 0.08, shininess: float = 24.0) -> np.ndarray:
    """Colours [N,3] in [0,1]: albedo (ambient + (1 - ambient) max(n.l, 0)) + specular (n.h)^shininess,
    with n turned to face the viewer (``view``: unit vectors from the points to the camera) and
    ``light`` the unit direction towards the light."""
    n = np.where(((normals * view).sum(1) < 0)[:, None], -normals, normals)
    lambert = np.clip(n @ light, 0.0, 1.0)
    half = view + light
    half /= np.maximum(np.linalg.norm(half, axis=1, keepdims=True), 1e-12)
    highlight = specular * np.clip((n * half).sum(1), 0.0, 1.0) ** shininess
    return np.clip(albedo * (ambient + (1 - ambient) * lambert)[:, None] + highlight[:, None], 0.0, 1.0)
