"""The feature-line regressor (paper, Fig. 2): from a picture, its camera and the category's initial
feature lines F_g to the garment's 3D feature lines, in the body's canonical frame (Y up, metres).

Every line is a loop of K points (``darts.geometry.loops.resample_loop``); a sample has up to
``MAX_LINES`` lines (padding is masked). One forward pass:

1. **Encoder** (``ResNetEncoder``): feature maps X_f of the picture at strides 4, 8, 16, 32.
2. **Image-space projection and feature pooling** (as Pixel2Mesh): each point is projected with the
   picture's camera and every map is sampled there bilinearly; the q = 240 pooled values and the
   point's 3 coordinates make Z [n_i, q + 3] per line.
3. **Image-Guided Spatial Transformer** (``image_stm``): one translation per line, t_i =
   MLP([mean-pooled X_f of the whole picture, mean of the line's pooled features, the line's crease
   embedding]); the line moves by t_i.
4. **Crease Regressor Blocks** (``blocks``): graph convolutions over each line's loop (every point
   has exactly two neighbours), h' = relu(W_s h + W_n (h_prev + h_next) / 2), with a residual every
   two layers (Pixel2Mesh's G-ResNet), fed with features pooled again at the current points. Each
   block ends in a **GCN-Guided Spatial Transformer** (``gcn_stm``): a per-point translation
   Linear(h), added to the points.

Translation heads start at zero, so an untrained network returns F_g (the identity). The two
ablations of Table 1 come from the same code: **P2M-GCN** (no spatial transformers: each block's
last graph convolution outputs the points' new coordinates, as Pixel2Mesh's blocks do) and
**Im-Guided STM** (the image-guided transformer, then P2M blocks).
"""
from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import nn
from torch.nn import functional

from darts.regress.encoder import ResNetEncoder

#: Crease labels of the paper's Fig. 4 and the line names that carry them.
CREASES = ("W", "LL", "RL", "LA", "RA", "N", "H")
CREASE_OF_LINE = {"waist": "W", "left_hem": "LL", "right_hem": "RL", "left_cuff": "LA", "right_cuff": "RA",
                  "neckline": "N", "hem": "H"}
MAX_LINES = 4
VARIANTS = {"p2m-gcn": (False, False), "im-stm": (True, False), "ours": (True, True)}


@dataclass
class CameraBatch:
    """Pinhole cameras of a batch (``darts.camera.Camera``): R [B,3,3], t [B,3], focal [B,2] (fx,
    fy), centre [B,2] (cx, cy), and the image size in pixels."""

    rotation: torch.Tensor
    translation: torch.Tensor
    focal: torch.Tensor
    centre: torch.Tensor
    width: int
    height: int

    def project(self, points: torch.Tensor) -> torch.Tensor:
        """Pixels [B,N,2] (u, v) of canonical points [B,N,3]."""
        camera = torch.einsum("bij,bnj->bni", self.rotation, points) + self.translation[:, None]
        depth = camera[..., 2:].clamp_min(1e-3)
        return camera[..., :2] / depth * self.focal[:, None] + self.centre[:, None]

    def index(self, rows) -> CameraBatch:
        return CameraBatch(self.rotation[rows], self.translation[rows], self.focal[rows], self.centre[rows],
                           self.width, self.height)


def pool_features(maps: list[torch.Tensor], pixels: torch.Tensor, width: int, height: int) -> torch.Tensor:
    """Bilinear samples [B,N,sum C_i] of every map at image points ``pixels`` [B,N,2] (pixel centres
    at +0.5, so ``align_corners=False``); points off the image read zero padding."""
    grid = torch.stack([pixels[..., 0] / width * 2 - 1, pixels[..., 1] / height * 2 - 1], -1)[:, :, None]
    return torch.cat([functional.grid_sample(m, grid, mode="bilinear", padding_mode="zeros", align_corners=False)[..., 0]
                      for m in maps], 1).transpose(1, 2)


class LoopConv(nn.Module):
    """Graph convolution on closed loops of K points: h' = W_s h + W_n (h_{k-1} + h_{k+1}) / 2 for
    h [B,L,K,C] (every point's neighbours are the previous and the next on its loop)."""

    def __init__(self, inputs: int, outputs: int):
        super().__init__()
        self.own = nn.Linear(inputs, outputs)
        self.neighbours = nn.Linear(inputs, outputs, bias=False)

    def forward(self, h: torch.Tensor) -> torch.Tensor:
        return self.own(h) + self.neighbours((torch.roll(h, 1, 2) + torch.roll(h, -1, 2)) / 2)


class CreaseBlock(nn.Module):
    """A Crease Regressor Block: ``layers`` loop convolutions with ReLU and a residual every two,
    then new points: p + Linear(h) (GCN-guided STM, zero at the start) or, without it, a last loop
    convolution's output taken as the points' coordinates (Pixel2Mesh)."""

    def __init__(self, inputs: int, hidden: int, layers: int, gcn_stm: bool):
        super().__init__()
        self.first = LoopConv(inputs, hidden)
        self.convs = nn.ModuleList(LoopConv(hidden, hidden) for _ in range(layers - 1))
        self.gcn_stm = gcn_stm
        self.head = nn.Linear(hidden, 3) if gcn_stm else LoopConv(hidden, 3)
        if gcn_stm:
            nn.init.zeros_(self.head.weight)
            nn.init.zeros_(self.head.bias)

    def forward(self, z: torch.Tensor, points: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        h = torch.relu(self.first(z))
        for k in range(0, len(self.convs) - 1, 2):
            h = (h + torch.relu(self.convs[k + 1](torch.relu(self.convs[k](h))))) / 2
        if len(self.convs) % 2:
            h = torch.relu(self.convs[-1](h))
        return (points + self.head(h) if self.gcn_stm else self.head(h)), h


class FeatureLineRegressor(nn.Module):
    """Picture + camera + initial lines -> the lines after the image-guided STM (if any) and after
    every Crease Regressor Block (module docstring)."""

    def __init__(self, variant: str = "ours", blocks: int = 3, hidden: int = 128, layers: int = 4,
                 encoder: ResNetEncoder | None = None):
        super().__init__()
        if variant not in VARIANTS:
            raise ValueError(f"unknown variant '{variant}' (one of {', '.join(VARIANTS)})")
        self.variant = variant
        self.image_stm, gcn_stm = VARIANTS[variant]
        self.encoder = encoder or ResNetEncoder()
        pooled = sum(self.encoder.widths)
        self.crease = nn.Embedding(len(CREASES), 16)
        if self.image_stm:
            self.global_mlp = nn.Sequential(nn.Linear(2 * pooled + 16, hidden), nn.ReLU(), nn.Linear(hidden, hidden), nn.ReLU())
            self.global_head = nn.Linear(hidden, 3)
            nn.init.zeros_(self.global_head.weight)
            nn.init.zeros_(self.global_head.bias)
        self.blocks = nn.ModuleList(
            CreaseBlock(pooled + 3 + 16 + (hidden if k else 0), hidden, layers, gcn_stm) for k in range(blocks))

    def forward(self, images: torch.Tensor | None, cameras: CameraBatch, lines: torch.Tensor,
                creases: torch.Tensor, maps: list[torch.Tensor] | None = None) -> list[torch.Tensor]:
        """images [B,3,H,W] in [0,1] (or their encoder ``maps``, computed beforehand); lines
        [B,L,K,3] (canonical, metres); creases [B,L] indices of CREASES (padding lines: any).
        Returns the lines [B,L,K,3] after each stage."""
        maps = self.encoder(images) if maps is None else maps
        b, n_lines, k, _ = lines.shape
        crease = self.crease(creases)[:, :, None].expand(b, n_lines, k, -1)

        def pooled(points):
            pixels = cameras.project(points.reshape(b, n_lines * k, 3))
            return pool_features(maps, pixels, cameras.width, cameras.height).reshape(b, n_lines, k, -1)

        points, outputs, hidden = lines, [], None
        if self.image_stm:
            whole = torch.cat([m.mean((2, 3)) for m in maps], 1)[:, None].expand(b, n_lines, -1)
            shift = self.global_head(self.global_mlp(torch.cat([whole, pooled(points).mean(2), self.crease(creases)], -1)))
            points = points + shift[:, :, None]
            outputs.append(points)
        for block in self.blocks:
            parts = [pooled(points), points, crease] + ([hidden] if hidden is not None else [])
            points, hidden = block(torch.cat(parts, -1), points)
            outputs.append(points)
        return outputs
