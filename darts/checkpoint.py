"""Network checkpoints: one file holding the kind of network, its constructor's arguments
(``config``), its weights (``state_dict``) and its ``record`` (the command, data, seed and numbers
that made it). Written atomically; read with ``weights_only`` (no code runs on load)."""
from __future__ import annotations

import os
from pathlib import Path

import torch

from darts.errors import DartsInputError


def save_checkpoint(path: str | os.PathLike, kind: str, model: torch.nn.Module, config: dict, record: dict) -> None:
    """Write ``model`` (built by ``config``) as a checkpoint of ``kind`` with its ``record``."""
    from darts.fileio import atomic_path

    with atomic_path(path) as tmp:
        torch.save({"kind": kind, "config": config, "state_dict": model.state_dict(), "record": record}, tmp)


def load_model(path: str | os.PathLike, kind: str, network) -> tuple[torch.nn.Module, dict]:
    """(``network(**config)`` with the weights, in eval mode; the record) of a checkpoint of ``kind``;
    a missing or foreign file is a ``DartsInputError``."""
    try:
        data = torch.load(Path(path), map_location="cpu", weights_only=True)
    except FileNotFoundError:
        raise DartsInputError(path, "no such file") from None
    except Exception as exc:  # noqa: BLE001 - any unreadable checkpoint is bad input
        raise DartsInputError(path, f"not a DARTs checkpoint ({type(exc).__name__})") from None
    if not isinstance(data, dict) or data.get("kind") != kind:
        raise DartsInputError(path, f"is not a {kind} checkpoint")
    model = network(**data["config"])
    model.load_state_dict(data["state_dict"])
    return model.eval(), data["record"]
