"""What the CRDL's silhouette terms share: L(p) and its gradient for the local-global solver."""
from __future__ import annotations

import torch


class SilhouetteTerm:
    """A silhouette term: ``loss(vertices)`` is L(p) (torch, differentiable in p [V,3]);
    ``bind(vertices, faces)`` gives the term for the CRDL's mesh (its rest ``vertices`` [V,3], where
    the solve starts, and ``faces``)."""

    def bind(self, vertices, faces) -> SilhouetteTerm:
        raise NotImplementedError

    def loss(self, vertices: torch.Tensor) -> torch.Tensor:
        raise NotImplementedError

    def value_and_gradient(self, vertices: torch.Tensor) -> tuple[float, torch.Tensor]:
        """L and dL/dp [V,3] at ``vertices`` (for the local-global solver's proximal step)."""
        with torch.enable_grad():
            p = vertices.detach().clone().requires_grad_(True)
            loss = self.loss(p)
            (grad,) = torch.autograd.grad(loss, p)
        return float(loss.detach()), grad
