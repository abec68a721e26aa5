"""The image encoder: a ResNet (He et al. 2016) written with torch.nn, returning its multi-scale
feature maps X_f.

ResNet-18's layout (a 7x7 stride-2 stem, a max-pool, four stages of two basic blocks, stride 2
between stages) at a quarter of its width: 16, 32, 64, 128 channels instead of 64 ... 512. The
paper uses ResNet-50 on DeepFashion3D; here two CPU cores train it, and a 224 x 224 picture of one
garment has far fewer classes and looks than ImageNet: 0.70 M parameters (ResNet-50: 25.6 M),
0.14 G multiply-adds a picture (ResNet-50: 4.1 G). For a 224 x 224 input the maps are 56, 28, 14 and 7 pixels
across (strides 4, 8, 16, 32).
"""
from __future__ import annotations

import torch
from torch import nn

WIDTHS = (16, 32, 64, 128)


class BasicBlock(nn.Module):
    """y = relu(x' + BN(conv3(relu(BN(conv3(x)))))), x' the input (or its 1x1 projection when the
    stride or width changes)."""

    def __init__(self, inputs: int, outputs: int, stride: int):
        super().__init__()
        self.conv1 = nn.Conv2d(inputs, outputs, 3, stride, 1, bias=False)
        self.bn1 = nn.BatchNorm2d(outputs)
        self.conv2 = nn.Conv2d(outputs, outputs, 3, 1, 1, bias=False)
        self.bn2 = nn.BatchNorm2d(outputs)
        self.shortcut = nn.Identity() if stride == 1 and inputs == outputs else nn.Sequential(
            nn.Conv2d(inputs, outputs, 1, stride, bias=False), nn.BatchNorm2d(outputs))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        y = torch.relu(self.bn1(self.conv1(x)))
        return torch.relu(self.shortcut(x) + self.bn2(self.conv2(y)))


class ResNetEncoder(nn.Module):
    """Images [B,3,H,W] (RGB in [0,1]) -> feature maps [(B,C_i,H/s_i,W/s_i)], s_i = 4, 8, 16, 32."""

    def __init__(self, widths=WIDTHS, blocks=(2, 2, 2, 2)):
        super().__init__()
        self.widths = tuple(widths)
        self.stem = nn.Sequential(nn.Conv2d(3, widths[0], 7, 2, 3, bias=False), nn.BatchNorm2d(widths[0]),
                                  nn.ReLU(inplace=True), nn.MaxPool2d(3, 2, 1))
        stages, inputs = [], widths[0]
        for k, (width, count) in enumerate(zip(widths, blocks)):
            layers = [BasicBlock(inputs, width, 1 if k == 0 else 2)]
            layers += [BasicBlock(width, width, 1) for _ in range(count - 1)]
            stages.append(nn.Sequential(*layers))
            inputs = width
        self.stages = nn.ModuleList(stages)
        for module in self.modules():
            if isinstance(module, nn.Conv2d):
                nn.init.kaiming_normal_(module.weight, mode="fan_out", nonlinearity="relu")
        self.register_buffer("mean", torch.tensor([0.5, 0.5, 0.5]).view(1, 3, 1, 1))
        self.register_buffer("std", torch.tensor([0.25, 0.25, 0.25]).view(1, 3, 1, 1))

    def forward(self, images: torch.Tensor) -> list[torch.Tensor]:
        x = self.stem((images - self.mean) / self.std)
        maps = []
        for stage in self.stages:
            x = stage(x)
            maps.append(x)
        return maps
