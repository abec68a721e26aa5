"""Greedy colouring of constraints so that no two constraints of one colour share a particle.

Constraints of one colour can be projected in parallel without races; projected colour after
colour they give a Gauss-Seidel sweep, the same on every device.
"""
from __future__ import annotations

import numpy as np


def color_constraints(members: np.ndarray, particle_count: int) -> np.ndarray:
    """Colour of each constraint (row of particle indices ``members`` [C,k]): the smallest colour
    not used yet by any constraint sharing one of its particles, constraints taken in order."""
    used = [0] * particle_count  # bit c set: colour c is taken at this particle
    colors = np.empty(len(members), np.int64)
    for index, row in enumerate(np.asarray(members).tolist()):
        taken = 0
        for p in row:
            taken |= used[p]
        color = (~taken & (taken + 1)).bit_length() - 1  # lowest clear bit
        bit = 1 << color
        for p in row:
            used[p] |= bit
        colors[index] = color
    return colors


def color_order(members: np.ndarray, particle_count: int) -> tuple[np.ndarray, np.ndarray]:
    """(permutation sorting constraints by colour, start offsets of each colour plus the total)."""
    colors = color_constraints(members, particle_count)
    order = np.argsort(colors, kind="stable")
    counts = np.bincount(colors) if len(colors) else np.zeros(0, np.int64)
    return order, np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
