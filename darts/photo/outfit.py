"""Every garment a photographed person wears: the parsing (``darts.photo.parsing``) of the person on
the fitted body, and the garments it shows with their categories (``darts.photo.attributes``).

``KIND_OF`` says which garment of the picture (upper, lower, dress) a category is; a reconstruction
of one category takes that garment's mask.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from darts.photo.attributes import GarmentGuess, garments_seen
from darts.photo.parsing import DRESS, LOWER, UPPER, Parsing, parse_person

KINDS = {"upper": UPPER, "lower": LOWER, "dress": DRESS}
#: each kind with its article, for messages
A_KIND = {"upper": "an upper garment", "lower": "a lower garment", "dress": "a dress"}
KIND_OF = {"long-sleeve-top": "upper", "short-sleeve-top": "upper", "sleeveless-top": "upper",
           "long-pants": "lower", "short-pants": "lower", "long-skirt": "lower", "short-skirt": "lower",
           "long-sleeve-dress": "dress", "short-sleeve-dress": "dress", "sleeveless-dress": "dress"}


@dataclass
class PhotoOutfit:
    """The person's ``parsing``, the ``garments`` seen (inner layer first: the lower garment, then the
    top; or one dress) and ``notes`` on what could not be seen."""

    parsing: Parsing
    garments: list[GarmentGuess]
    notes: list[str]

    def garment(self, kind: str) -> GarmentGuess | None:
        """The garment of ``kind`` (upper, lower, dress) seen, or None."""
        return next((g for g in self.garments if g.kind == kind), None)

    def mask(self, kind: str) -> np.ndarray:
        """[H,W] bool: the pixels of the garment of ``kind`` in the picture (after a suit's split, the
        parsing's labels as the garments were read)."""
        garment = self.garment(kind)
        label = garment.label if garment is not None else KINDS[kind]
        width, height = self.parsing.picture_size
        return self.parsing.mask(label, width, height)

    def as_dict(self) -> dict:
        return {"garments": [g.as_dict() for g in self.garments], "notes": self.notes,
                "one_colour": self.parsing.one_piece, "colour_evidence": self.parsing.evidence}


def read_outfit(image: np.ndarray, person, fit, body) -> PhotoOutfit | None:
    """The outfit of ``person`` (``darts.photo.person.Person``) in ``image`` [H,W,3] uint8, with the
    body ``body`` (a ``BodyModel``) fitted to it (``darts.photo.fit.BodyFit``); None when the
    person's mask is empty."""
    from darts.body.segmentation import body_segmentation

    parsing = parse_person(image, person.mask, person.landmarks, person.visibility, fit.vertices,
                           np.asarray(body.faces), body_segmentation(body), fit.posed_camera)
    if parsing is None:
        return None
    garments, notes, read = garments_seen(parsing, person.landmarks, person.visibility)
    return PhotoOutfit(read, garments, notes)
