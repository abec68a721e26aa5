"""Where BlazePose's 33 landmarks sit on the SMPL-format body: each one a joint plus an offset in that
joint's frame, fitted to what the landmark model finds in renders of the default body.

    python scripts/calibrate_landmarks.py [--count 200] [--seed 0] [--out darts/photo/landmarks.json]
    python scripts/calibrate_landmarks.py --check 12 --seed 5     # the shipped table, on fresh renders

Renders (256 x 256, ``darts.photo.synthetic``): the default body with 8 random betas (N(0, 1)
truncated to +-2) in a pose from a random frame of a random shipped motion, turned by a random yaw
(+-60 degrees) about the vertical, seen by a camera 2.5-4 m away from 0.5 m below to 0.5 m above
the body's middle, focal length 0.8-1.2 x 256 pixels. In each the person is found
(``find_person``); landmark k of a render n is modelled as the pixel of J_j(n) + R_j(n) o_k, with j
the landmark's joint (``JOINTS``), J_j and R_j that joint's posed position and rotation, and o_k
the offset (metres, the joint's rest frame) fitted over all renders: minimise
sum_n v_nk rho(|pi_n(J_j + R_j o_k) - l_nk|) (v: the landmark's visibility, rho: Charbonnier at 1 px)
by Adam. The shipped table records the command, the renders' count and the median residual
of each landmark before (offset 0) and after. ``--check N`` instead fits the body
(``darts.photo.fit``, the shipped table) to N fresh renders and prints how far its 22 body joints
project from the true ones (median pixels) and how far its 8 betas are from the truth.
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

#: each BlazePose landmark's joint (SMPL names)
JOINTS = {
    "nose": "head", "left_eye_inner": "head", "left_eye": "head", "left_eye_outer": "head", "right_eye_inner": "head",
    "right_eye": "head", "right_eye_outer": "head", "left_ear": "head", "right_ear": "head", "mouth_left": "head",
    "mouth_right": "head", "left_shoulder": "left_shoulder", "right_shoulder": "right_shoulder",
    "left_elbow": "left_elbow", "right_elbow": "right_elbow", "left_wrist": "left_wrist", "right_wrist": "right_wrist",
    "left_pinky": "left_wrist", "right_pinky": "right_wrist", "left_index": "left_wrist", "right_index": "right_wrist",
    "left_thumb": "left_wrist", "right_thumb": "right_wrist", "left_hip": "left_hip", "right_hip": "right_hip",
    "left_knee": "left_knee", "right_knee": "right_knee", "left_ankle": "left_ankle", "right_ankle": "right_ankle",
    "left_heel": "left_ankle", "right_heel": "right_ankle", "left_foot_index": "left_foot", "right_foot_index": "right_foot",
}
MOTIONS = ("walk", "run", "squat", "twist", "wave", "jumping_jacks")


def renders(count: int, seed: int):
    """(person, joints [J,3], rotations [J,3,3], camera) of each render where a person is found."""
    from scipy.spatial.transform import Rotation

    from darts.body.io import load_body
    from darts.camera import Camera
    from darts.motion.amass import load_motion
    from darts.photo.person import find_person
    from darts.photo.synthetic import posed_body, render_person
    from darts.shipped import resolve_motion

    body = load_body(None)
    poses = [load_motion(resolve_motion(m)).model_pose(body.num_joints) for m in MOTIONS]
    rng = np.random.default_rng(seed)
    found = []
    for _ in range(count):
        frames = poses[int(rng.integers(len(poses)))]
        pose = frames[int(rng.integers(len(frames)))].copy()
        pose[0] = (Rotation.from_euler("y", rng.uniform(-60, 60), degrees=True)).as_rotvec()
        betas = np.zeros(body.num_betas)
        betas[:8] = np.clip(rng.normal(0, 1, 8), -2, 2)
        vertices, joints, rotations = posed_body(body, pose, betas)
        middle = (vertices.min(0) + vertices.max(0)) / 2
        distance = rng.uniform(2.5, 4.0)
        eye = middle + [0.0, rng.uniform(-0.5, 0.5), distance]
        camera = Camera.look_at(eye, middle, 256, 256, 256 * rng.uniform(0.8, 1.2))
        person = find_person(render_person(camera, vertices, body.faces))
        if person is not None:
            found.append((person, joints, rotations, camera, betas))
    return body, found


def check(count: int, seed: int) -> None:
    """The fit with the shipped table on ``count`` fresh renders (module docstring)."""
    import torch

    from darts.photo.fit import fit_body

    body, found = renders(count, seed)
    model = body.to(torch.float64)
    joints_px, betas_off = [], []
    for person, joints, _, camera, betas in found:
        fit = fit_body(person, body, camera.width, camera.height)
        fitted = model(torch.tensor(fit.pose)[None], torch.tensor(fit.betas)[None]).joints[0].numpy()[:22]
        error = np.linalg.norm(fit.posed_camera.project(fitted)[0] - camera.project(joints[:22])[0], axis=1)
        joints_px.append(float(np.median(error)))
        betas_off.append(float(np.abs(fit.betas[:8] - betas[:8]).mean()))
    print(json.dumps({"renders": count, "people_found": len(found), "joint_error_px_median": float(np.median(joints_px)),
                      "joint_error_px_mean": float(np.mean(joints_px)), "betas_abs_error_mean": float(np.mean(betas_off))}))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=200)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=Path("darts/photo/landmarks.json"))
    parser.add_argument("--check", type=int, metavar="N", help="check the shipped table on N fresh renders instead")
    args = parser.parse_args()
    if args.check:
        check(args.check, args.seed)
        return
    import torch

    from darts.photo.person import LANDMARKS

    body, found = renders(args.count, args.seed)
    names = body.joint_names
    index = torch.tensor([names.index(JOINTS[name]) for name in LANDMARKS])
    joints = torch.tensor(np.stack([f[1] for f in found]))[:, index]  # [N,33,3]
    rotations = torch.tensor(np.stack([f[2] for f in found]))[:, index]  # [N,33,3,3]
    target = torch.tensor(np.stack([f[0].landmarks for f in found]))
    weight = torch.tensor(np.stack([f[0].visibility for f in found]))
    cameras = [f[3] for f in found]

    def pixels(offsets):
        points = joints + torch.einsum("nkxy,ky->nkx", rotations, offsets)
        return torch.stack([cameras[n].project(points[n])[0] for n in range(len(cameras))])

    def residual(offsets):
        return (pixels(offsets) - target).norm(dim=2)

    offsets = torch.zeros(len(LANDMARKS), 3, dtype=torch.float64, requires_grad=True)
    before = residual(offsets.detach())
    optimiser = torch.optim.Adam([offsets], lr=0.003)
    for _ in range(600):
        optimiser.zero_grad()
        loss = (weight * (torch.sqrt(residual(offsets) ** 2 + 1) - 1)).sum() / weight.sum()
        loss.backward()
        optimiser.step()
    after = residual(offsets.detach())
    seen = weight > 0.5
    median = lambda r, k: float(r[:, k][seen[:, k]].median()) if seen[:, k].any() else None  # noqa: E731
    table = {name: {"joint": JOINTS[name], "offset_m": offsets[k].detach().numpy().round(4).tolist(),
                    "residual_px_before": median(before, k), "residual_px_after": median(after, k)}
             for k, name in enumerate(LANDMARKS)}
    record = {"command": f"python scripts/calibrate_landmarks.py --count {args.count} --seed {args.seed}",
              "renders": args.count, "people_found": len(found),
              "median_residual_px_before": float(before[seen].median()), "median_residual_px_after": float(after[seen].median()),
              "landmarks": table}
    args.out.write_text(json.dumps(record, indent=1))
    print(json.dumps({k: v for k, v in record.items() if k != "landmarks"}, indent=1))


if __name__ == "__main__":
    main()
