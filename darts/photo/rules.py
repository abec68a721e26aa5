"""The hand-set rules' probabilities of a photograph's garment decisions, from the measurements along
the limbs (``darts.photo.attributes.Measured``), per decision of ``darts.photo.outfit_net.HEADS``:

- **one piece**: the colour test (``darts.photo.parsing``: the upper and lower cloth one colour)
  unless the gap between the legs is clearly open (fill under ``SUIT_FILL``: a suit, a top and
  trousers); the vote is worth ``ONE_PIECE_RULE``, the colour test's accuracy on the validation
  renders;
- **sleeves** (of the top, or of the dress when the colour test says one piece): P(none) =
  sigma((0.12 - s) / 0.03), P(long) = sigma((s - 0.49) / 0.04) (past the elbow: rolled and 3/4
  sleeves are long), P(short) the rest; no arm read: ``SLEEVE_PRIOR``;
- **long**: P(long) = sigma((s - 0.55) / 0.05) of the hem's s along the legs (the knee is 0.5); not
  read: one half;
- **skirt**: P(skirt) = sigma((fill - 0.65) / 0.06) of the fill between the legs; where no gap is
  read, sigma((off - 0.2) / 0.04) of the share of the hem's band off the fitted legs (a skirt
  stands away from the thighs at its hem); neither: ``SKIRT_PRIOR``.

``within_picture_bounds`` applies to any decision what the picture itself says: cloth running out
of the picture is at least as long as it was seen.
"""
from __future__ import annotations

from scipy.special import expit

#: the sleeve end (s) at which short and long sleeves are as likely: past the elbow (0.5 less a
#: little: the elbow's landmark sits inside the joint)
LONG_SLEEVE = 0.49
#: P(none / short / long) of sleeves no arm shows
SLEEVE_PRIOR = {"none": 0.15, "short": 0.4, "long": 0.45}
#: the share of cloth in the gap between the legs at which a skirt and trousers are as likely
SKIRT_FILL = 0.65
#: one cloth from the shoulders down is taken for a suit (a top and trousers) only under this fill
SUIT_FILL = 0.35
#: with no gap to read, the share of the hem's band off the fitted legs at which a skirt and
#: trousers are as likely
SKIRT_OFF_BODY = 0.2
#: P(skirt) when neither the gap nor the hem's hang is read
SKIRT_PRIOR = 0.35
#: P(one piece) when the rule says one piece (and 1 - it when it says two)
ONE_PIECE_RULE = 0.95


def sleeve_probabilities(evidence: dict | None) -> dict[str, float]:
    """P(none / short / long) of the sleeves measured in ``evidence`` (module docstring)."""
    end = None if evidence is None else evidence["sleeve_end"]
    if end is None:
        return dict(SLEEVE_PRIOR)
    none = float(expit((0.12 - end) / 0.03))
    long = float(expit((end - LONG_SLEEVE) / 0.04))
    short = max(0.0, 1.0 - none - long)
    total = none + short + long
    return {"none": none / total, "short": short / total, "long": long / total}


def lower_probabilities(evidence: dict | None) -> tuple[dict[str, float], dict[str, float]]:
    """(P(short / long), P(pants / skirt)) of the lower garment measured in ``evidence``."""
    end = None if evidence is None else evidence["hem_end"]
    p_long = 0.5 if end is None else float(expit((end - 0.55) / 0.05))
    fill, off = (None, None) if evidence is None else (evidence["between_legs_fill"], evidence["off_the_legs"])
    if fill is not None:
        p_skirt = float(expit((fill - SKIRT_FILL) / 0.06))
    elif off is not None:
        p_skirt = float(expit((off - SKIRT_OFF_BODY) / 0.04))
    else:
        p_skirt = SKIRT_PRIOR
    return {"short": 1 - p_long, "long": p_long}, {"pants": 1 - p_skirt, "skirt": p_skirt}


def rule_probabilities(measured) -> dict[str, dict[str, float]]:
    """The rules' probabilities per decision (module docstring) of a ``Measured`` person."""
    dress = measured.dress
    one = measured.parsing.one_piece and dress is not None and not (
        dress["between_legs_fill"] is not None and dress["between_legs_fill"] < SUIT_FILL)
    p_one = ONE_PIECE_RULE if one else 1 - ONE_PIECE_RULE
    length, kind = lower_probabilities(measured.lower)
    return {"one_piece": {"two": 1 - p_one, "one": p_one},
            "sleeves": sleeve_probabilities(dress if one else measured.top), "long": length, "skirt": kind}


def within_picture_bounds(decided: dict[str, dict[str, float]], measured) -> dict[str, dict[str, float]]:
    """``decided`` (probabilities per decision) with what the picture says of a ``Measured``
    person's cloth that runs out of it: a sleeve covered out of the picture from at least s = 0.3
    is long at 0.6 or more (and not none); a hem out of the picture makes the lower garment long at
    0.6 or more (at least that long, more likely long than short)."""
    out = dict(decided)
    sleeved = measured.dress if decided["one_piece"]["one"] > 0.5 else measured.top
    if sleeved is not None and sleeved["sleeve_beyond_picture"] and sleeved["sleeve_end"] >= 0.3 \
            and decided["sleeves"]["long"] < 0.6:
        out["sleeves"] = {"none": 0.0, "short": 0.4, "long": 0.6}
    if measured.lower is not None and measured.lower["hem_beyond_picture"] and decided["long"]["long"] < 0.6:
        out["long"] = {"short": 0.4, "long": 0.6}
    return out
