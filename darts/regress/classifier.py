"""The garment classifier: the ResNet encoder, global average pooling of its last map, and a linear
layer over the ten categories (``darts.regress.data.CATEGORY_IDS``)."""
from __future__ import annotations

import torch
from torch import nn

from darts.regress.encoder import ResNetEncoder


class GarmentClassifier(nn.Module):
    """Images [B,3,H,W] in [0,1] -> category logits [B, classes]."""

    def __init__(self, classes: int = 10, encoder: ResNetEncoder | None = None):
        super().__init__()
        self.encoder = encoder or ResNetEncoder()
        self.head = nn.Linear(self.encoder.widths[-1], classes)

    def forward(self, images: torch.Tensor) -> torch.Tensor:
        return self.head(self.encoder(images)[-1].mean((2, 3)))
