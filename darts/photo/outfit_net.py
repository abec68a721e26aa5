"""What a parsed photograph's garments are, from what is seen: a small network over the parsing.

The parsing (``darts.photo.parsing``: a label per person pixel) and the measurements along the
limbs (``darts.photo.attributes``: where the cloth gives way to skin on each arm and leg, the fill
between the legs, how the hem hangs off the legs, the colour test of one piece or two) are the
evidence; ``OutfitNet`` turns them into the probabilities of four decisions:

- **one piece** or two (a dress against a top and a bottom),
- **sleeves**: none, short or long (of the top or the dress),
- the lower garment **long** or short,
- the lower garment a **skirt** or trousers.

Input, all side-agnostic (a picture and its mirror image are the same outfit):
- ``maps`` [``CHANNELS``, ``MAP_SIZE``, ``MAP_SIZE``]: the parsing's square crop around the person
  (256 pixels) averaged down to ``MAP_SIZE``: the share of each block's pixels that are upper
  cloth, lower cloth, skin, face and hair, other; the fitted body's silhouette by zone (head and
  neck, upper torso, lower torso and hips, upper arms, forearms and hands, thighs, calves and
  feet); and the crop's part outside the picture;
- ``thighs`` [``CHANNELS``, ``THIGH_SIZE``, ``THIGH_SIZE``]: the same channels sampled (bilinear)
  over a square ``THIGH_SPAN`` x the hips-to-knees distance a side, centred between them (where
  a skirt and shorts differ);
- ``scalars`` [``SCALARS``]: the measurements of both readings — the cloth read as a top and a
  lower garment, and read as one dress — the colour test's two log-likelihood ratios
  (sign(x) log(1 + |x|)) and BlazePose's visibility of the elbows, wrists, knees, ankles, hips
  (the lesser of left and right) and the nose. A measurement not made is -1 with a flag.

``OutfitNet``: four stride-2 3 x 3 convolutions (w, 2w, 4w, 4w channels, ReLU) over each map
(two towers), flattened, joined with the scalars, one hidden layer of 64 (ReLU, dropout), and a
linear head per decision. ``OutfitEnsemble``: several such networks, trained alike from different
seeds, whose probabilities are averaged (what ships: ``scripts/train_outfit_net.py``, its record in
the weights). ``darts.photo.attributes`` combines its answers with the hand-set rules'.
"""
from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np
import torch
from torch import nn

from darts.body.segmentation import PART_NAMES
from darts.photo.parsing import FACE_HAIR, LOWER, OTHER, SIZE, SKIN, UPPER

WEIGHTS = Path(__file__).parent / "weights" / "outfit_net.pt"
MAP_SIZE = 64
#: the thighs' map: THIGH_SIZE pixels a side, over a square THIGH_SPAN x the hips-to-knees distance
#: a side, centred between them
THIGH_SIZE, THIGH_SPAN = 48, 2.4
LABELS = (UPPER, LOWER, SKIN, FACE_HAIR, OTHER)
ZONES = (("head", "neck"), ("upper_torso",), ("lower_torso", "hips"), ("upper_arm",), ("forearm", "hand"), ("thigh",),
         ("calf", "foot"))
CHANNELS = len(LABELS) + len(ZONES) + 1
#: the decisions and their classes
HEADS = {"one_piece": ("two", "one"), "sleeves": ("none", "short", "long"), "long": ("short", "long"),
         "skirt": ("pants", "skirt")}
#: the visibility of these landmarks (the lesser of left and right; the nose alone)
VISIBLE = ("elbow", "wrist", "knee", "ankle", "hip")
SCALAR_NAMES = (
    *(f"{reading}_{name}" for reading in ("top", "dress")
      for name in ("sleeve_end", "sleeve_unread", "sleeve_beyond_picture", "shorter_arm_end", "longer_arm_end")),
    "top_hem_end",
    *(f"{reading}_{name}" for reading in ("lower", "dress")
      for name in ("hem_end", "hem_unread", "hem_beyond_picture", "between_legs_fill", "off_the_legs")),
    "lower_by_upper_nats", "upper_by_lower_nats", *(f"{joint}_visibility" for joint in VISIBLE), "nose_visibility")
SCALARS = len(SCALAR_NAMES)

_ZONE_OF_PART = np.array([next(i for i, zone in enumerate(ZONES) if name.removeprefix("left_").removeprefix("right_") in zone)
                          for name in PART_NAMES] + [-1])


def _channels(labels: np.ndarray, body_parts: np.ndarray, in_picture: np.ndarray) -> np.ndarray:
    """[CHANNELS,S,S] float32: one channel per label, per body zone and the crop outside the picture."""
    zone = _ZONE_OF_PART[np.where(body_parts >= 0, body_parts, len(PART_NAMES))]
    return np.concatenate([np.stack([labels == label for label in LABELS]),
                           np.stack([zone == k for k in range(len(ZONES))]), ~in_picture[None]]).astype(np.float32)


def maps(labels: np.ndarray, body_parts: np.ndarray, in_picture: np.ndarray, points: np.ndarray
         ) -> tuple[np.ndarray, np.ndarray]:
    """(the whole person [CHANNELS,MAP_SIZE,MAP_SIZE], the thighs [CHANNELS,THIGH_SIZE,THIGH_SIZE])
    float32 (module docstring) of a parsing's ``labels`` [S,S], the fitted body's ``body_parts``
    [S,S] (-1 off the body), ``in_picture`` [S,S] bool and the landmarks ``points`` [33,2] (crop
    pixels, u v)."""
    from scipy import ndimage

    from darts.photo.person import LANDMARKS

    full = _channels(labels, body_parts, in_picture)
    block = SIZE // MAP_SIZE
    whole = full.reshape(CHANNELS, MAP_SIZE, block, MAP_SIZE, block).mean((2, 4))

    def middle(joint: str) -> np.ndarray:
        return 0.5 * (points[LANDMARKS.index(f"left_{joint}")] + points[LANDMARKS.index(f"right_{joint}")])

    hips, knees = middle("hip"), middle("knee")
    side = THIGH_SPAN * max(float(np.linalg.norm(knees - hips)), 8.0)
    steps = (np.arange(THIGH_SIZE) + 0.5) / THIGH_SIZE - 0.5
    centre = 0.5 * (hips + knees)
    u, v = np.meshgrid(centre[0] + side * steps - 0.5, centre[1] + side * steps - 0.5)
    thigh = np.stack([ndimage.map_coordinates(channel, [v, u], order=1, cval=0.0) for channel in full])
    return whole, thigh.astype(np.float32)


def _value(x) -> float:
    return -1.0 if x is None else float(x)


def _signed_log(x) -> float:
    return 0.0 if x is None else float(np.sign(x) * np.log1p(abs(x)))


def scalars(top: dict | None, lower: dict | None, dress: dict | None, colour: dict, visibility: np.ndarray) -> np.ndarray:
    """[SCALARS] float32 (``SCALAR_NAMES``): the measurements of the cloth read as a ``top`` and a
    ``lower`` garment and as one ``dress`` (``darts.photo.attributes`` evidence dicts, None when
    that garment is not in the picture), the ``colour`` test's evidence and BlazePose's
    ``visibility`` [33]."""
    from darts.photo.person import LANDMARKS

    values = []
    for garment in (top, dress):
        evidence = garment or {}
        ends = sorted(arm["end"] for arm in evidence.get("arms", {}).values() if arm["end"] is not None)
        values += [_value(evidence.get("sleeve_end")), float(evidence.get("sleeve_end") is None),
                   float(bool(evidence.get("sleeve_beyond_picture"))), ends[0] if ends else -1.0, ends[-1] if ends else -1.0]
    values.append(_value((top or {}).get("top_hem_end")))
    for garment in (lower, dress):
        evidence = garment or {}
        values += [_value(evidence.get("hem_end")), float(evidence.get("hem_end") is None),
                   float(bool(evidence.get("hem_beyond_picture"))), _value(evidence.get("between_legs_fill")),
                   _value(evidence.get("off_the_legs"))]
    values += [_signed_log(colour.get("lower_by_upper_nats")), _signed_log(colour.get("upper_by_lower_nats"))]
    seen = np.asarray(visibility, np.float64)
    values += [min(seen[LANDMARKS.index(f"left_{joint}")], seen[LANDMARKS.index(f"right_{joint}")]) for joint in VISIBLE]
    values.append(seen[LANDMARKS.index("nose")])
    return np.array(values, np.float32)


class OutfitNet(nn.Module):
    """Logits per decision (``HEADS``) of ``maps`` [B,CHANNELS,M,M], ``thighs`` [B,CHANNELS,T,T]
    and ``scalars`` [B,SCALARS] (module docstring)."""

    def __init__(self, width: int = 16, dropout: float = 0.3):
        super().__init__()
        channels = [CHANNELS, width, 2 * width, 4 * width, 4 * width]
        self.convolutions = nn.ModuleList([nn.Conv2d(a, b, 3, 2, 1) for a, b in zip(channels, channels[1:])])
        self.thigh_convolutions = nn.ModuleList([nn.Conv2d(a, b, 3, 2, 1) for a, b in zip(channels, channels[1:])])
        features = channels[-1] * ((MAP_SIZE // 16) ** 2 + (THIGH_SIZE // 16) ** 2)
        self.hidden = nn.Linear(features + SCALARS, 64)
        self.dropout = nn.Dropout(dropout)
        self.heads = nn.ModuleDict({name: nn.Linear(64, len(classes)) for name, classes in HEADS.items()})

    def forward(self, maps: torch.Tensor, thighs: torch.Tensor, scalars: torch.Tensor) -> dict[str, torch.Tensor]:
        x, t = maps, thighs
        for convolution, thigh_convolution in zip(self.convolutions, self.thigh_convolutions):
            x, t = torch.relu(convolution(x)), torch.relu(thigh_convolution(t))
        h = self.dropout(torch.relu(self.hidden(torch.cat([x.flatten(1), t.flatten(1), scalars], 1))))
        return {name: head(h) for name, head in self.heads.items()}


class OutfitEnsemble(nn.Module):
    """Per decision, log((1/K) sum_k softmax(member_k logits)) over its K ``members``: logits whose
    softmax is the members' mean probability."""

    def __init__(self, members: list[OutfitNet]):
        super().__init__()
        self.members = nn.ModuleList(members)

    def forward(self, maps: torch.Tensor, thighs: torch.Tensor, scalars: torch.Tensor) -> dict[str, torch.Tensor]:
        outputs = [member(maps, thighs, scalars) for member in self.members]
        count = torch.log(torch.tensor(float(len(outputs))))
        return {name: torch.logsumexp(torch.stack([torch.log_softmax(out[name], 1) for out in outputs]), 0) - count
                for name in HEADS}


def probabilities_of(network, maps_batch: np.ndarray, thighs_batch: np.ndarray, scalars_batch: np.ndarray
                     ) -> dict[str, np.ndarray]:
    """Per decision [B,classes]: the mean of the softmax of ``network`` on the inputs and on their
    mirror image (the outfit is the same)."""
    network.eval()
    m, t, s = torch.as_tensor(maps_batch), torch.as_tensor(thighs_batch), torch.as_tensor(scalars_batch)
    with torch.no_grad():
        straight, mirrored = network(m, t, s), network(m.flip(3), t.flip(3), s)
    return {name: ((torch.softmax(straight[name], 1) + torch.softmax(mirrored[name], 1)) / 2).numpy() for name in HEADS}


def ensemble_of(checkpoint: dict) -> OutfitEnsemble:
    """The ``OutfitEnsemble`` saved in ``checkpoint`` ({"width", "members": [state dicts], ...}),
    in evaluation mode."""
    members = []
    for state in checkpoint["members"]:
        member = OutfitNet(int(checkpoint["width"]))
        member.load_state_dict(state)
        members.append(member)
    return OutfitEnsemble(members).eval()


@lru_cache(maxsize=1)
def shipped_network() -> OutfitEnsemble:
    """The shipped ``OutfitEnsemble`` (``WEIGHTS``), in evaluation mode."""
    return ensemble_of(torch.load(WEIGHTS, map_location="cpu", weights_only=True))


def decide(maps_one: np.ndarray, thighs_one: np.ndarray, scalars_one: np.ndarray) -> dict[str, dict[str, float]]:
    """The shipped network's probabilities per decision, class by name (``HEADS``), of one picture."""
    from darts.threads import one_torch_thread

    with one_torch_thread():
        result = probabilities_of(shipped_network(), maps_one[None], thighs_one[None], scalars_one[None])
    return {name: {c: float(p) for c, p in zip(HEADS[name], result[name][0])} for name in HEADS}
