"""What a parsed photograph says of the garments — where the cloth gives way to skin along the
limbs, the fill between the legs, how a hem hangs, the colour test of one piece or two — and the
garments and categories that follow, with probabilities.

Each limb is a polyline of BlazePose landmarks (arm: shoulder, elbow, wrist; leg: hip, knee, ankle)
in the parsing's crop pixels. Every person pixel of the limb's body parts (the parsing's nearest
parts: upper arm, forearm and hand; thigh, calf and foot) is projected on to the polyline, giving
s in [0, 1] (0 at the shoulder or hip, 0.5 at the elbow or knee, 1 at the wrist or ankle, linear
along each bone). In ``BINS`` bins of s, the *coverage* is the share of the bin's cloth and skin
pixels that are cloth (the garment's label). The garment's **end** along the limb is where
coverage first falls under one half for two bins running, k, refined by the coverages on either
side: s = (k - 1 + c_{k-1} + c_k) / BINS (1 when it never falls; the last bin in the picture
when the limb leaves it covered: ``beyond_picture``).

A limb bare where it first comes into view (past s = 0.2) has its end hidden and is left out; of
two limbs the shorter end counts (``_garment_end``).

- **Sleeves**: the arms' end (``sleeve_end``; an arm out of sight left out).
- **Lower garment's length**: the legs' end (``hem_end``).
- **A top's length**: its end down the body's middle line (``torso_line``: shoulders, hips,
  knees), measured the same way (``top_hem_end``).
- **The gap between the legs** down to the hem — inside the polygon of the two legs' polylines,
  off the fitted body's silhouette (below its crotch) — and the share of it that is the garment's
  cloth against background (``between_legs_fill``: a skirt fills the gap, trousers leave it open;
  skin there is a leg the fit put elsewhere), read for hems past ``MIN_GAP_HEM`` with both knees
  seen.
- **How the hem hangs**: the share of the garment's leg pixels from ``HEM_BAND`` of its hem's s
  down that lie off the fitted body's silhouette (``off_the_legs``).

The cloth is measured both ways (``measure``): the parsing's upper and lower cloth as a top and a
lower garment, and the two as one dress. Four decisions — one piece or two, the sleeves (none,
short, long), the lower garment long or short, skirt or trousers — are taken by two experts,
the hand-set rules on the measurements (``darts.photo.rules``) and a small network over the
parsing and both measurements (``darts.photo.outfit_net``), combined per decision by a weighted
geometric mean (``combine``, ``RULE_WEIGHTS``), then bounded by what the picture shows
(``rules.within_picture_bounds``). The categories' probabilities follow: a top's or a dress's are
the sleeves', a lower garment's P(long or short) x P(skirt or trousers). A one-colour cloth
decided to be two garments (a suit) is split at the hips (``Parsing.split_one_piece``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from darts.body.segmentation import PART_INDEX
from darts.photo.parsing import BACKGROUND, DRESS, LOWER, SKIN, UPPER, Parsing

BINS = 10
#: a limb counts as seen when this many of its bins hold at least ``MIN_BIN`` pixels
MIN_SEEN_BINS, MIN_BIN = 3, 3
#: a garment is present when its pixels are at least this share of the person's
MIN_GARMENT_SHARE = 0.02
#: a limb's pixels lie within this share of its length from its polyline (a torso pixel beside a
#: hanging arm is not the arm's)
REACH = 0.12
#: the same for the body's middle line (the torso is wider than a limb)
TORSO_REACH = 0.15
#: the least gap between the legs (crop pixels, of 256) that says anything of what fills it
MIN_GAP_PIXELS = 25
#: per decision, the weight of the hand-set rules' log-probabilities against the network's
#: (``combine``). On the validation renders (1,808 pictures of garments never trained on:
#: ``python scripts/train_outfit_net.py --data ~/.cache/darts/posed-s100x6 ~/.cache/darts/posed-s102x4
#: ~/.cache/darts/posed-s103x4 ~/.cache/darts/posed-s105x4r2 --weights``) the network alone is within
#: 0.1 point of the best at every decision (one piece 98.4 %, sleeves 94.7 %, length 96.9 %, skirt or trousers
#: 87.2 %; the rules alone 96.5, 84.6, 90.1, 65.6 %); the rules keep a say where the renders and
#: the pictures of people have disagreed: one piece 0.2 (98.4 % there; on the held-out renders s101
#: and s104 it reads 98.7 and 97.5 % against 98.3 and 97.1 % alone), or the sample render's
#: thigh-length top with bare legs under it (``scenes/reconstruct``) has read as a dress; skirt or
#: trousers 0.2 (85.0 % there, 87.4 and 84.4 % on s101 and s104 against 88.6 and 85.6 % alone, but
#: the picture's garment right 90.8 and 86.3 % against 90.4 and 85.4 %), or the navy blazer over
#: navy shorts — no gap shown between the legs — has read as a skirt, which the rules' hem
#: following the legs gets right
RULE_WEIGHTS = {"one_piece": 0.2, "sleeves": 0.0, "long": 0.0, "skirt": 0.2}
#: the least probability an expert gives a class in ``combine``
FLOOR = 1e-3
#: the hem (s) above which there is a gap between the legs to read
MIN_GAP_HEM = 0.45
#: the lower part of a garment, from this share of its hem's s down, says how it hangs
HEM_BAND = 0.6
ARM = ("shoulder", "elbow", "wrist")
LEG = ("hip", "knee", "ankle")


def _project(points: np.ndarray, polyline: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(s [N] in [0, 1], distance [N]) of ``points`` [N,2] projected on the two-bone ``polyline`` [3,2]."""
    best_s, best_d = np.zeros(len(points)), np.full(len(points), np.inf)
    for bone in range(2):
        a, b = polyline[bone], polyline[bone + 1]
        ab = b - a
        t = np.clip(((points - a) @ ab) / max(ab @ ab, 1e-9), 0.0, 1.0)
        d = np.linalg.norm(points - (a + t[:, None] * ab), axis=1)
        closer = d < best_d
        best_s[closer], best_d[closer] = (bone + t[closer]) / 2, d[closer]
    return best_s, best_d


@dataclass
class LimbCoverage:
    """The cloth along one limb: ``coverage`` [BINS] (NaN where unseen), the ``end`` s, whether the
    cloth runs out of the picture (``beyond_picture``) and how many bins were seen."""

    coverage: np.ndarray
    end: float | None
    beyond_picture: bool
    seen_bins: int

    def as_dict(self) -> dict:
        return {"coverage": [None if np.isnan(c) else round(float(c), 3) for c in self.coverage],
                "end": None if self.end is None else round(self.end, 3), "beyond_picture": self.beyond_picture,
                "seen_bins": self.seen_bins}


def limb_coverage(parsing: Parsing, polyline: np.ndarray, parts: list[str], cloth: tuple[int, ...],
                  reach: float | None = None, bare: tuple[int, ...] = (SKIN,), last: bool = False) -> LimbCoverage:
    """The ``cloth`` labels' coverage along ``polyline`` [3,2] (crop pixels) over the pixels of body
    ``parts`` within ``reach`` (default ``REACH``) of the polyline's length, against the ``bare``
    labels (module docstring). With ``last`` the end is after the last covered bin instead of at
    the first bare one (a top open over a shirt is bare in the middle, not at its end)."""
    reach = REACH if reach is None else reach
    wanted = [PART_INDEX[p] for p in parts]
    rows, cols = np.nonzero(np.isin(parsing.parts, wanted))
    s, distance = _project(np.stack([cols + 0.5, rows + 0.5], 1), polyline)
    near = distance <= reach * (np.linalg.norm(polyline[1] - polyline[0]) + np.linalg.norm(polyline[2] - polyline[1]))
    rows, cols, s = rows[near], cols[near], s[near]
    labels = parsing.labels[rows, cols]
    covered = np.isin(labels, cloth)
    counted = covered | np.isin(labels, bare)
    index = np.minimum((s * BINS).astype(int), BINS - 1)
    totals = np.bincount(index[counted], minlength=BINS)
    coverage = np.where(totals >= MIN_BIN, np.bincount(index[counted & covered], minlength=BINS) / np.maximum(totals, 1),
                        np.nan)
    seen = np.flatnonzero(~np.isnan(coverage))
    if len(seen) < MIN_SEEN_BINS:
        return LimbCoverage(coverage, None, False, len(seen))
    if seen[0] > 2 and coverage[seen[0]] < 0.5:  # bare where it comes into view: its end is hidden
        return LimbCoverage(coverage, None, False, len(seen))
    end = None
    if last:
        covered_bins = [k for k in seen if coverage[k] >= 0.5]
        if not covered_bins:
            end = 0.0
        elif covered_bins[-1] < seen[-1]:  # the bin after the last covered one is in view
            k = covered_bins[-1] + 1
            end = (k - 1 + coverage[k - 1] + (0.0 if np.isnan(coverage[k]) else coverage[k])) / BINS
    for k in [] if last else seen:
        if coverage[k] < 0.5 and (k + 1 >= BINS or np.isnan(coverage[k + 1]) or coverage[k + 1] < 0.5):
            # between bins: the last covered bin's bare share back, the first bare bin's cloth on
            before = coverage[k - 1] if k > 0 and not np.isnan(coverage[k - 1]) else 1.0
            end = (k - 1 + before + coverage[k]) / BINS if k > 0 else coverage[k] / BINS
            break
    beyond = False
    if end is None:
        end = (seen[-1] + 1) / BINS
        beyond = bool(seen[-1] < BINS - 1 and parsing.at_picture_bottom(np.isin(parsing.labels, cloth)))
    return LimbCoverage(coverage, float(end), beyond, len(seen))


def chain(landmarks: np.ndarray, side: str, joints: tuple[str, ...]) -> np.ndarray:
    """[len(joints),D] the ``side`` landmarks of ``joints`` (``ARM``, ``LEG``) of ``landmarks`` [33,D]."""
    from darts.photo.person import LANDMARKS

    return np.array([landmarks[LANDMARKS.index(f"{side}_{j}")] for j in joints])


def _garment_end(limbs: list[LimbCoverage]) -> tuple[float | None, bool]:
    """(the garment's end: the shorter of the limbs' measured ends, whether it runs out of the
    picture). The shorter: a limb seen over other cloth of the same garment (an arm across the
    torso, a leg behind a skirt) reads too long, never too short."""
    seen = [limb for limb in limbs if limb.end is not None]
    if not seen:
        return None, False
    shortest = min(seen, key=lambda limb: limb.end)
    return float(shortest.end), shortest.beyond_picture


def point_at(polyline: np.ndarray, s: float) -> np.ndarray:
    """The point at ``s`` in [0, 1] along a two-bone ``polyline`` [3,D] (0.5 at its middle point)."""
    bone = min(int(s * 2), 1)
    return polyline[bone] + (s * 2 - bone) * (polyline[bone + 1] - polyline[bone])


def between_legs_fill(parsing: Parsing, legs: list[np.ndarray], cloth: tuple[int, ...], hem: float) -> float | None:
    """The share of the ``cloth`` labels in the gap between the legs down to ``hem`` (module
    docstring), or None when under ``MIN_GAP_PIXELS`` of gap show (legs together, crossed or seen
    from the side). The gap: the pixels inside the polygon of the two legs' polylines from the hips
    to ``hem`` that the fitted body does not cover (its silhouette grown by 2 pixels: below the
    crotch, between the thighs). Skin there is left out (a leg the fit put elsewhere), so the share
    is of cloth against background."""
    from matplotlib.path import Path as Polygon
    from scipy import ndimage

    if hem < MIN_GAP_HEM:  # a short garment ends about where the legs part: no gap to read
        return None
    steps = np.linspace(0.0, hem, 12)
    outline = [point_at(legs[0], t) for t in steps] + [point_at(legs[1], t) for t in steps[::-1]]
    size = len(parsing.labels)
    rows, cols = np.mgrid[:size, :size]
    inside = Polygon(np.array(outline)).contains_points(np.stack([cols.ravel() + 0.5, rows.ravel() + 0.5], 1))
    body = ndimage.binary_dilation(parsing.body_parts >= 0, iterations=2)
    gap = inside.reshape(size, size) & ~body & parsing.in_picture()
    covered = gap & np.isin(parsing.labels, cloth)
    seen = covered | (gap & (parsing.labels == BACKGROUND))
    if seen.sum() < MIN_GAP_PIXELS:
        return None
    return float(covered.sum() / seen.sum())


@dataclass
class GarmentGuess:
    """One visible garment: its ``kind`` (upper, lower, dress), the parsing label of its pixels,
    its categories with probabilities (most likely first) and the evidence."""

    kind: str
    label: int
    ranked: list[tuple[str, float]]
    attributes: dict

    @property
    def category(self) -> str:
        return self.ranked[0][0]

    @property
    def probability(self) -> float:
        return self.ranked[0][1]

    def as_dict(self) -> dict:
        return {"kind": self.kind, "category": self.category, "probability": round(self.probability, 4),
                "probabilities": {c: round(p, 4) for c, p in self.ranked}, "attributes": self.attributes}


def _ranked(probabilities: dict[str, float]) -> list[tuple[str, float]]:
    return sorted(probabilities.items(), key=lambda item: -item[1])


def _sleeves(parsing: Parsing, landmarks: np.ndarray, cloth: tuple[int, ...]) -> dict:
    """The evidence of the sleeves of the garment labelled ``cloth``: the arms' coverage, their
    ends and the garment's (the shorter), and whether it runs out of the picture."""
    arms = {side: limb_coverage(parsing, chain(landmarks, side, ARM), [f"{side}_upper_arm", f"{side}_forearm",
                                                                       f"{side}_hand"], cloth)
            for side in ("left", "right")}
    end, beyond = _garment_end(list(arms.values()))
    return {"sleeve_end": None if end is None else round(end, 3), "sleeve_beyond_picture": beyond,
            "arms": {k: v.as_dict() for k, v in arms.items()}}


def torso_line(landmarks: np.ndarray) -> np.ndarray:
    """[3,D] the body's middle line: between the shoulders, the hips and the knees (``landmarks`` [33,D])."""
    from darts.photo.person import LANDMARKS

    def middle(joint: str) -> np.ndarray:
        return 0.5 * (landmarks[LANDMARKS.index(f"left_{joint}")] + landmarks[LANDMARKS.index(f"right_{joint}")])

    return np.array([middle("shoulder"), middle("hip"), middle("knee")])


def _top_hem(parsing: Parsing, landmarks: np.ndarray, cloth: tuple[int, ...]) -> dict:
    """Where a top ends down the body's middle line (``torso_line``: 0 between the shoulders, 0.5
    between the hips, 1 between the knees), over the torso's, hips' and thighs' pixels within
    ``TORSO_REACH`` of the line's length, against skin and the lower garment: after its last
    covered bin (an open jacket shows a shirt in the middle)."""
    torso = limb_coverage(parsing, torso_line(landmarks), ["upper_torso", "lower_torso", "hips", "left_thigh",
                                                           "right_thigh"], cloth, TORSO_REACH, (SKIN, LOWER), last=True)
    return {"top_hem_end": None if torso.end is None else round(torso.end, 3), "torso": torso.as_dict()}


def _lower(parsing: Parsing, landmarks: np.ndarray, cloth: tuple[int, ...], read_gap: bool = True) -> dict:
    """The evidence of the garment below the waist labelled ``cloth``: the legs' coverage, the hem's
    end (the shorter leg's) and whether it runs out of the picture, the fill between the legs
    (``read_gap``: both knees seen) and how the hem hangs off the legs."""
    polylines = {side: chain(landmarks, side, LEG) for side in ("left", "right")}
    legs = {side: limb_coverage(parsing, polylines[side], [f"{side}_thigh", f"{side}_calf", f"{side}_foot"], cloth)
            for side in ("left", "right")}
    end, beyond = _garment_end(list(legs.values()))
    fill = between_legs_fill(parsing, list(polylines.values()), cloth, end if end is not None else 0.5) if read_gap else None
    off_body = None if end is None or beyond else off_the_legs(parsing, polylines, cloth, end)
    return {"hem_end": None if end is None else round(end, 3), "hem_beyond_picture": beyond,
            "between_legs_fill": None if fill is None else round(fill, 3),
            "off_the_legs": None if off_body is None else round(off_body, 3),
            "legs": {k: v.as_dict() for k, v in legs.items()}}


def off_the_legs(parsing: Parsing, legs: dict[str, np.ndarray], cloth: tuple[int, ...], hem: float) -> float | None:
    """The share of the ``cloth`` pixels nearest the thighs and calves, in the lower part of the
    garment (s from ``HEM_BAND`` x ``hem`` to ``hem`` along their leg's polyline in ``legs``), that
    lie off the fitted body's silhouette (grown by 2 pixels): a skirt hangs away from the legs
    towards its hem, trousers and shorts follow them (at the waist both sit on the body). None with
    under ``MIN_GAP_PIXELS`` such pixels."""
    from scipy import ndimage

    body = ndimage.binary_dilation(parsing.body_parts >= 0, iterations=2)
    near_hem = np.zeros(parsing.labels.shape, bool)
    for side, polyline in legs.items():
        rows, cols = np.nonzero(np.isin(parsing.parts, [PART_INDEX[f"{side}_thigh"], PART_INDEX[f"{side}_calf"]])
                                & np.isin(parsing.labels, cloth))
        s, _ = _project(np.stack([cols + 0.5, rows + 0.5], 1), polyline)
        band = (s >= HEM_BAND * hem) & (s <= hem + 0.02)
        near_hem[rows[band], cols[band]] = True
    if near_hem.sum() < MIN_GAP_PIXELS:
        return None
    return float((near_hem & ~body).sum() / near_hem.sum())


def _share(parsing: Parsing, label: int) -> float:
    """The share of the person's pixels labelled ``label``."""
    return float((parsing.labels == label).sum() / max((parsing.labels != BACKGROUND).sum(), 1))


def _separates(parsing: Parsing, points: np.ndarray, knees: bool) -> tuple[dict | None, dict | None]:
    """(the top's evidence, the lower garment's) of ``parsing``'s upper and lower cloth; None for a
    garment under ``MIN_GARMENT_SHARE`` of the person."""
    top = _sleeves(parsing, points, (UPPER,)) | _top_hem(parsing, points, (UPPER,)) \
        if _share(parsing, UPPER) >= MIN_GARMENT_SHARE else None
    lower = _lower(parsing, points, (LOWER,), knees) if _share(parsing, LOWER) >= MIN_GARMENT_SHARE else None
    return top, lower


@dataclass
class Measured:
    """A parsed person's cloth measured both ways: as a ``top`` and a ``lower`` garment (the
    parsing's upper and lower labels) and as one ``dress`` (the two labels one: ``whole``); each
    evidence dict None when that garment is under ``MIN_GARMENT_SHARE``; ``points`` the
    landmarks in crop pixels with their ``visibility``."""

    parsing: Parsing
    whole: Parsing
    points: np.ndarray
    visibility: np.ndarray
    top: dict | None
    lower: dict | None
    dress: dict | None

    @property
    def knees(self) -> bool:
        """Whether both knees are seen (``_knees_seen``)."""
        return _knees_seen(self.visibility)

    def network_inputs(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(maps, thighs, scalars) of ``darts.photo.outfit_net`` for this person."""
        from darts.photo import outfit_net

        parsing = self.parsing
        return (*outfit_net.maps(parsing.labels, parsing.body_parts, parsing.in_picture(), self.points),
                outfit_net.scalars(self.top, self.lower, self.dress, parsing.evidence, self.visibility))


def measure(parsing: Parsing, landmarks: np.ndarray, visibility: np.ndarray | None = None) -> Measured:
    """``parsing``'s cloth measured both ways (``Measured``); BlazePose's ``landmarks`` [33,2] in
    picture pixels with their ``visibility`` [33] (all seen when None)."""
    points = parsing.to_crop(landmarks)
    visibility = np.ones(len(landmarks)) if visibility is None else np.asarray(visibility, np.float64)
    knees = _knees_seen(visibility)
    top, lower = _separates(parsing, points, knees)
    whole = parsing.merged()
    dress = _sleeves(whole, points, (DRESS,)) | _lower(whole, points, (DRESS,), knees) \
        if _share(whole, DRESS) >= MIN_GARMENT_SHARE else None
    return Measured(parsing, whole, points, visibility, top, lower, dress)


def geometric_mix(rules: np.ndarray, network: np.ndarray, weight: float) -> np.ndarray:
    """[..., classes]: the rules' probabilities ``rules`` raised to ``weight`` times the network's
    ``network`` raised to 1 - ``weight`` (a weighted geometric mean, each clipped at ``FLOOR``),
    normalised over the last axis."""
    logs = weight * np.log(np.maximum(rules, FLOOR)) + (1 - weight) * np.log(np.maximum(network, FLOOR))
    mixed = np.exp(logs - logs.max(-1, keepdims=True))
    return mixed / mixed.sum(-1, keepdims=True)


def combine(rules: dict[str, dict[str, float]], network: dict[str, dict[str, float]], weights: dict[str, float]
            ) -> dict[str, dict[str, float]]:
    """Per decision, the two experts' probabilities by class mixed by ``geometric_mix`` with that
    decision's weight in ``weights``."""
    out = {}
    for name, classes in network.items():
        mixed = geometric_mix(np.array([rules[name][c] for c in classes]), np.array(list(classes.values())), weights[name])
        out[name] = {c: float(p) for c, p in zip(classes, mixed)}
    return out


def garments_seen(parsing: Parsing, landmarks: np.ndarray, visibility: np.ndarray | None = None
                  ) -> tuple[list[GarmentGuess], list[str], Parsing]:
    """(every visible garment, outermost last: the lower garment, then the top or the dress;
    notes on what could not be seen; the parsing as read: its upper and lower cloth one dress, or
    a one-colour cloth split at the hips into a top and a lower garment) of a parsed person whose
    BlazePose ``landmarks`` [33,2] are in picture pixels, with their ``visibility`` [33]. The
    cloth is measured both ways (``measure``) and the rules and the network decide together
    (module docstring): one piece or two, the sleeves, the lower garment's length and kind; each
    garment's attributes are its measurements, the sleeves decided, P(one piece), the network's
    own answers and the colour test."""
    from darts.photo.outfit_net import decide
    from darts.photo.rules import rule_probabilities, within_picture_bounds

    measured = measure(parsing, landmarks, visibility)
    network = decide(*measured.network_inputs())
    decided = within_picture_bounds(combine(rule_probabilities(measured), network, RULE_WEIGHTS), measured)
    evidence = {"p_one_piece": round(decided["one_piece"]["one"], 4),
                "network": {name: {c: round(p, 4) for c, p in classes.items()} for name, classes in network.items()},
                "colour": parsing.evidence}
    sleeves = decided["sleeves"]
    sleeve = {"sleeve": max(sleeves, key=sleeves.get)}
    if measured.dress is not None and decided["one_piece"]["one"] > 0.5:
        names = {"long": "long-sleeve-dress", "short": "short-sleeve-dress", "none": "sleeveless-dress"}
        return [GarmentGuess("dress", DRESS, _ranked({names[k]: p for k, p in sleeves.items()}),
                             {**measured.dress, **sleeve, **evidence})], [], measured.whole
    top, lower, read, notes = measured.top, measured.lower, parsing, []
    if parsing.one_piece:  # one colour read as two garments: a suit, split at the hips
        notes.append("one cloth from the shoulders to the legs, read as a top and a lower garment")
        read = measured.whole.split_one_piece()
        top, lower = _separates(read, measured.points, measured.knees)
    garments = []
    if lower is not None:
        if lower["hem_end"] is None:
            notes.append("the lower garment is not seen along the legs: its kind and length are guessed")
        p_long, p_skirt = decided["long"]["long"], decided["skirt"]["skirt"]
        probabilities = {"long-pants": (1 - p_skirt) * p_long, "short-pants": (1 - p_skirt) * (1 - p_long),
                         "long-skirt": p_skirt * p_long, "short-skirt": p_skirt * (1 - p_long)}
        garments.append(GarmentGuess("lower", LOWER, _ranked(probabilities), {**lower, **evidence}))
    else:
        notes.append("no lower garment in the picture (the legs are out of frame or bare)")
    if top is not None:
        names = {"long": "long-sleeve-top", "short": "short-sleeve-top", "none": "sleeveless-top"}
        garments.append(GarmentGuess("upper", UPPER, _ranked({names[k]: p for k, p in sleeves.items()}),
                                     {**top, **sleeve, **evidence}))
    else:
        notes.append("no upper garment in the picture")
    return garments, notes, read


def _seen(visibility: np.ndarray | None, landmark: str) -> bool:
    """Whether BlazePose sees ``landmark`` (visibility at least one half; without visibilities, yes):
    else it is guessed (out of frame, hidden)."""
    from darts.photo.person import LANDMARKS

    return visibility is None or visibility[LANDMARKS.index(landmark)] >= 0.5


def _knees_seen(visibility: np.ndarray | None) -> bool:
    """Whether both knees are seen: else no gap between the legs is read."""
    return _seen(visibility, "left_knee") and _seen(visibility, "right_knee")


