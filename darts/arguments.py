"""Checks of the Python API's arguments at its edge (``darts.api``, ``darts.body``, ``darts.motion``,
``sim.api``, ``sim.SimSettings``): each returns the value (numbers as Python's own, sequences as
tuples) or raises ``DartsInputError`` naming the argument, what it must be and what it got — one
line, as the commands say it — so that a bad call never fails deep inside numpy, torch or Warp with
a bare ``TypeError``. The commands' parsers check their own text; these check Python values.
"""
from __future__ import annotations

import numbers
import os
from collections.abc import Mapping

import numpy as np

from darts.errors import DartsInputError


def described(value) -> str:
    """``value`` as an error shows it: its type and a short repr (``int 123``, ``str 'h'``)."""
    text = repr(value)
    if len(text) > 40:
        text = text[:37] + "..."
    return f"{type(value).__name__} {text}"


def refuse(argument: str, must: str, value) -> DartsInputError:
    """The error for ``argument`` holding ``value`` where it ``must`` be something else."""
    return DartsInputError(None, f"{argument} must be {must}, got {described(value)}")


def is_path(value) -> bool:
    """Whether ``value`` names a file or a shipped item: a non-empty str or an ``os.PathLike``."""
    return (isinstance(value, str) and value.strip() != "") or isinstance(value, os.PathLike)


def path_or(value, argument: str, kinds: tuple[type, ...] = (), what: str = "a path") -> object:
    """``value`` when it is a path (``is_path``) or an instance of ``kinds``; ``what`` says which."""
    if is_path(value) or (kinds and isinstance(value, kinds)):
        return value
    raise refuse(argument, what, value)


def is_number(value) -> bool:
    """A real number that is not a bool (Python's or numpy's)."""
    return isinstance(value, numbers.Real) and not isinstance(value, (bool, np.bool_))


def number(value, argument: str, low: float | None = None, high: float | None = None, *, above: bool = False,
           whole: bool = False) -> float | int:
    """``value`` as a finite float (an int when ``whole``), within [low, high] (above ``low`` when ``above``)."""
    kind = "a whole number" if whole else "a number"
    if low is not None and high is not None:
        kind += f" in {'(' if above else '['}{low:g}, {high:g}]"
    elif low is not None:
        kind += f" {'>' if above else '>='} {low:g}"
    if not is_number(value) or not np.isfinite(float(value)):
        raise refuse(argument, kind, value)
    if whole:
        if isinstance(value, numbers.Integral):
            result = int(value)
        elif float(value).is_integer():
            raise refuse(argument, kind + " (an int, not a float)", value)
        else:
            raise refuse(argument, kind, value)
    else:
        result = float(value)
    if (low is not None and (result <= low if above else result < low)) or (high is not None and result > high):
        raise refuse(argument, kind, value)
    return result


def optional_number(value, argument: str, low: float | None = None, high: float | None = None, **options):
    """``number`` unless ``value`` is None."""
    return None if value is None else number(value, argument, low, high, **options)


def number_list(value, argument: str, most: int | None = None) -> tuple[float, ...]:
    """A sequence (list, tuple, 1-D array) of at most ``most`` finite numbers, as floats."""
    kind = "a list of numbers" + (f" (at most {most})" if most is not None else "")
    if isinstance(value, np.ndarray):
        if value.ndim != 1 or value.dtype.kind not in "iuf":
            raise refuse(argument, kind, value)
        value = value.tolist()
    if not isinstance(value, (list, tuple)) or not all(is_number(v) and np.isfinite(float(v)) for v in value):
        raise refuse(argument, kind, value)
    if most is not None and len(value) > most:
        raise DartsInputError(None, f"{argument}: {len(value)} given, the body has {most}")
    return tuple(float(v) for v in value)


def betas(value, most: int, frames: int | None = None) -> np.ndarray:
    """Body shape coefficients: a list of at most ``most`` finite numbers, or (``frames`` given) one
    such row per frame, [frames, K]; as float64."""
    if frames is not None and isinstance(value, (list, tuple, np.ndarray)) and np.ndim(value) == 2:
        try:
            rows = np.asarray(value, np.float64)
        except (TypeError, ValueError):
            raise refuse("betas", f"[{frames}, K] numbers (one shape per frame)", value) from None
        if rows.shape[0] != frames or rows.shape[1] > most or not np.isfinite(rows).all():
            raise DartsInputError(None, f"betas per frame must be [{frames}, K <= {most}] finite numbers, got {rows.shape}")
        return rows
    return np.array(number_list(value, "betas", most), np.float64)


def text(value, argument: str, options=None) -> str:
    """A str, one of ``options`` when given."""
    if not isinstance(value, str):
        raise refuse(argument, "a str" if options is None else f"one of {', '.join(options)}", value)
    if options is not None and value not in options:
        raise DartsInputError(None, f"unknown {argument} '{value}' (one of {', '.join(options)})")
    return value


def text_list(value, argument: str, example: str) -> tuple[str, ...]:
    """A list or tuple of str — not one str, whose letters would be taken one by one."""
    if isinstance(value, str):
        raise refuse(argument, f"a list of strings, e.g. ['{example}'], not one string", value)
    if not isinstance(value, (list, tuple)) or not all(isinstance(v, str) for v in value):
        raise refuse(argument, f"a list of strings, e.g. ['{example}']", value)
    return tuple(value)


def switch(value, argument: str) -> bool:
    """A bool (Python's or numpy's)."""
    if not isinstance(value, (bool, np.bool_)):
        raise refuse(argument, "True or False", value)
    return bool(value)


def vector(value, argument: str) -> tuple[float, float, float]:
    """Three finite numbers, as a tuple of floats."""
    values = number_list(value, argument) if isinstance(value, (list, tuple, np.ndarray)) else None
    if values is None or len(values) != 3:
        raise refuse(argument, "three numbers (x, y, z)", value)
    return values


def mapping(value, argument: str, keys, what: str) -> dict:
    """A dict whose keys are all among ``keys`` (``what`` names their owner in the error)."""
    if not isinstance(value, Mapping):
        raise refuse(argument, f"a dict of {what}", value)
    unknown = [k for k in value if k not in keys]
    if unknown:
        raise DartsInputError(None, f"{argument}: unknown key {unknown[0]!r} (the {what}: {', '.join(keys)})")
    return dict(value)
