"""Lengths read from a photograph as the CRDL's targets: where a sleeve, a hem or a trouser leg ends
(``darts.photo.attributes``: s along a limb or the body's middle line) placed on the fitted body at
rest, and the feature line moved there.

A measured end s is a point on the rest-posed body (canonical frame, Y up, metres): along the
polyline of the calibrated landmark points (``darts.photo.fit``: each landmark a joint plus an
offset; at rest the joints' frames are the canonical one) — shoulder, elbow, wrist for a cuff; hip,
knee, ankle for a trouser leg; the two legs' points averaged for a skirt's or a dress's hem; the
middle of the shoulders, the hips and the knees for a top's hem — at s of its length (two bones,
0.5 at the middle joint). The line (its loop's centre c and axis a, pointing away from the
garment: ``darts.crdl.targets.loop_frame``) moves along a by d = (T - c) . a, so that its centre
reaches the point's level; the loop keeps its shape and width. An end that runs out of the picture
is a lower bound: it may lengthen the line, never shorten it. ``reached`` measures the same d on
the deformed garment: how far its line still is from the length read.
"""
from __future__ import annotations

import numpy as np

from darts.crdl.targets import MAX_EDIT, loop_frame
from darts.photo.attributes import ARM, LEG, chain, point_at, torso_line
from darts.templates.categories import CATEGORIES


def rest_landmarks(body, betas) -> np.ndarray:
    """[33,3] the calibrated landmark points (``darts.photo.fit.landmark_table``) of ``body`` (a
    ``BodyModel``) with shape ``betas`` in its rest pose, canonical frame."""
    import torch

    from darts.photo.fit import landmark_table

    names, offsets = landmark_table()
    shape = None if betas is None or len(betas) == 0 else torch.as_tensor(np.asarray(betas), dtype=body.dtype)[None]
    _, joints = body.shaped(shape)
    joints = joints[0].double().numpy()
    return np.array([joints[body.joint_names.index(j)] for j in names]) + offsets


def length_targets(category: str, attributes: dict, body, betas) -> dict[str, dict]:
    """{line name: {"point": T [3], "s": s, "beyond_picture": bool}} for every line of ``category``
    whose end the photograph's ``attributes`` (a garment's, ``darts.photo.attributes``) measure."""
    points = rest_landmarks(body, betas)
    names = CATEGORIES[category].line_names
    targets = {}
    sleeve = attributes.get("sleeve_end")
    if sleeve is not None and CATEGORIES[category].sleeved:
        for side in ("left", "right"):
            targets[f"{side}_cuff"] = {"point": point_at(chain(points, side, ARM), sleeve), "s": sleeve,
                                       "beyond_picture": bool(attributes.get("sleeve_beyond_picture"))}
    hem, beyond = attributes.get("hem_end"), bool(attributes.get("hem_beyond_picture"))
    if hem is not None:
        legs = {side: point_at(chain(points, side, LEG), hem) for side in ("left", "right")}
        for side in ("left", "right"):
            if f"{side}_hem" in names:
                targets[f"{side}_hem"] = {"point": legs[side], "s": hem, "beyond_picture": beyond}
        if "hem" in names and category not in ("long-sleeve-top", "short-sleeve-top", "sleeveless-top"):
            targets["hem"] = {"point": 0.5 * (legs["left"] + legs["right"]), "s": hem, "beyond_picture": beyond}
    top = attributes.get("top_hem_end")
    if top is not None and "hem" in names and "hem" not in targets:
        targets["hem"] = {"point": point_at(torso_line(points), top), "s": top,
                          "beyond_picture": bool(attributes.get("torso", {}).get("beyond_picture"))}
    return targets


def place_lines(lines: dict[str, np.ndarray], targets: dict[str, dict],
                garment_centre: np.ndarray) -> tuple[dict[str, np.ndarray], dict[str, dict]]:
    """(``lines`` [K,3] each, the targeted ones moved along their axes to their targets' levels;
    per targeted line its s, the move in cm and whether the end ran out of the picture) — module
    docstring; moves are clipped to ``MAX_EDIT``."""
    placed, report = dict(lines), {}
    for name, target in targets.items():
        if name not in lines:
            continue
        centre, axis = loop_frame(lines[name], garment_centre)
        move = float(np.clip((target["point"] - centre) @ axis, -MAX_EDIT, MAX_EDIT))
        if target["beyond_picture"] and move < 0:
            move = 0.0  # the end is further than what is seen: never shorter
        placed[name] = lines[name] + move * axis
        report[name] = {"s": target["s"], "beyond_picture": target["beyond_picture"], "moved_cm": round(100 * move, 2)}
    return placed, report


def reached(lines: dict[str, np.ndarray], targets: dict[str, dict], report: dict[str, dict],
            garment_centre: np.ndarray) -> dict[str, dict]:
    """``report`` with each targeted line's remaining distance (cm, along its axis) from its target on
    the deformed garment's ``lines`` [K,3] (positive: still short of it)."""
    out = {}
    for name, entry in report.items():
        centre, axis = loop_frame(lines[name], garment_centre)
        out[name] = {**entry, "remaining_cm": round(100 * float((targets[name]["point"] - centre) @ axis), 2)}
    return out
