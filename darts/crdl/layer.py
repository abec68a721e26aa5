"""The Constrained Rigid Deformation Layer (paper, Sec. 3): deform a template so that its feature
lines reach target lines while it stays as rigid as possible and outside the body.

Objective over the vertices p [V,3] (canonical frame, metres), the same for both solvers:

    E(p) = E_arap(p) + w_h sum_k m_k |p_{h_k} - t_k|^2 + w_f sum_i max(0, m - s_i(p))^2 [+ w_s L_sil(p)]

with E_arap of Eq. 2, t_k the target matched to handle vertex h_k (arc length), m_k its multiplier
(1 unless given: registration weighs feature lines above the surface pull), s_i the signed
distance to the fit surface (Eq. 3, body or lower-body hull) and m a margin.

- ``solve_adam``: the paper's way, p a learnable parameter, Adam on E.
- ``solve_local_global``: block descent on E(p, R, z) = E_arap(p, R) + handles + w_f (n.(p - z))^2
  with z_i the point of the feasible half-space nearest p_i: local steps set R (Horn's method) and
  z (projection), the global step solves (K^T W K + w_h S^T S + w_f n n^T) p = b, one matrix
  factored per contact round, accelerated by L-BFGS with that matrix as initial inverse Hessian;
  the better of two starts (rest, handles snapped onto their targets) goes on. It is
  differentiable: gradients reach the targets.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
import torch
from scipy.sparse.linalg import splu

from darts.crdl.arap import arap_energy, arap_system, best_rotations, rotated_rest_spokes
from darts.crdl.fit import FitSurface, fit_deficit, row_dot
from darts.crdl.local_step import LocalStep

#: Metres beyond the margin within which a vertex joins the contact set before the first round:
#: trousers' sitting allowance holds their legs 3 cm off the body (with 1 cm, shortening the shipped
#: long pants' legs 10 cm dove into the body, E 0.39 against 0.019).
CONTACT_BAND = 0.035
#: Steps over which the relative decrease is averaged for the stopping test (accelerated steps are
#: uneven: one small step among large ones stopped a run at 8 % above its converged energy).
STALL_WINDOW = 5
#: Relative decrease per step, averaged over STALL_WINDOW steps, below which a descent stops.
TOLERANCE = 2e-5
#: Steps each of the two starts descends before the one with the lower objective goes on.
RACE_STEPS = 5
#: Relative tolerance of the contact rounds before the contact set is complete.
ROUND_TOLERANCE = 1e-3
#: 1/tau of the silhouette's proximal-gradient step (per vertex, in the units of the ARAP weights).
SILHOUETTE_PROXIMAL = 10.0


@dataclass
class CrdlWeights:
    """Weights of the objective's terms (the ARAP term has weight 1)."""

    handle: float = 1000.0
    fit: float = 10.0
    silhouette: float = 0.0
    margin: float = 0.003  # metres outside the fit surface a vertex is pushed to


@dataclass
class CrdlResult:
    """Deformed vertices [V,3] and what the run measured."""

    vertices: np.ndarray
    arap_energy: float
    handle_rmse: float
    objective: float
    iterations: int
    wall_seconds: float
    history: list[float] = field(default_factory=list)

    def report(self, penetration: float, solver: str) -> dict:
        """The ``--report`` document."""
        return {"solver": solver, "arap_energy": self.arap_energy, "handle_rmse": self.handle_rmse,
                "penetration": penetration, "objective": self.objective, "iterations": self.iterations,
                "wall_seconds": self.wall_seconds, "objective_history": self.history}


class _Interleaved:
    """LU factors of a 3V x 3V matrix whose unknowns are ordered vertex by vertex (x, y, z of each)
    in the order ``order`` (order[k]: the vertex at place k; position: its inverse), solving
    right-hand sides given as [V,3] in the template's vertex order (float64 in and out, whatever
    the factors' precision)."""

    def __init__(self, factor, order: np.ndarray, position: np.ndarray):
        self.factor, self.order, self.position = factor, order, position

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        ordered = np.ascontiguousarray(rhs[self.order], dtype=self.factor.L.dtype).reshape(-1)
        return self.factor.solve(ordered).reshape(-1, 3)[self.position].astype(np.float64)


@dataclass
class Contacts:
    """Vertices ``index`` [k] with their closest fit-surface points and outward normals [k,3], held fixed."""

    index: torch.Tensor
    closest: torch.Tensor
    normal: torch.Tensor

    def deficit(self, vertices: torch.Tensor, margin: float) -> torch.Tensor:
        """How far each of these vertices is short of ``margin`` outside [k] (see ``fit_deficit``)."""
        return fit_deficit(vertices[self.index], self.closest, self.normal, margin)


class _SymmetricMap(torch.autograd.Function):
    """y = M x for a fixed symmetric linear map M given as a function of numpy arrays (a scipy
    sparse product, or a factored solve for M = A^-1); dL/dx = M dL/dy. (torch's own sparse product
    took 2 ms for the 10k-vertex dress where scipy's takes 0.13 ms.)"""

    @staticmethod
    def forward(ctx, x: torch.Tensor, linear_map) -> torch.Tensor:
        ctx.linear_map = linear_map
        return torch.from_numpy(linear_map(x.detach().numpy()))

    @staticmethod
    def backward(ctx, grad: torch.Tensor):
        return torch.from_numpy(ctx.linear_map(grad.contiguous().numpy())), None


class Crdl:
    """The layer for one template: rest ``vertices`` [V,3], ``faces`` [F,3], handle vertex indices
    [H] (the feature lines' vertices, in the order of the targets), an optional fit surface, and
    optional per-handle multipliers [H] of the handle weight (1 for all by default; a vertex may be
    a handle more than once, its terms add up)."""

    def __init__(self, vertices: np.ndarray, faces: np.ndarray, handles: np.ndarray,
                 surface: FitSurface | None = None, weights: CrdlWeights | None = None, silhouette=None,
                 handle_weights: np.ndarray | None = None):
        self.weights = weights or CrdlWeights()
        self._bar = None  # the progress bar of a solve_local_global in progress
        self.system = arap_system(vertices, faces)
        self.faces = np.asarray(faces, np.int64)
        self.handles = torch.as_tensor(np.asarray(handles, np.int64))
        multipliers = np.ones(len(handles)) if handle_weights is None else np.asarray(handle_weights, np.float64)
        self._handle_multipliers = torch.as_tensor(multipliers)[:, None]
        self.surface = surface
        self.silhouette = None if silhouette is None else silhouette.bind(vertices, faces)
        count = self.system.vertex_count
        selector = sp.csr_matrix((np.ones(len(handles)), (np.arange(len(handles)), np.asarray(handles))),
                                 shape=(len(handles), count))
        self._incidence_t = torch.sparse_coo_tensor(*_coo(self.system.incidence().T.tocoo()), check_invariants=True)
        # The silhouette term enters as a proximal-gradient step: its gradient at p_k plus
        # (1/tau) |p - p_k|^2, which keeps the matrix constant.
        self._proximal = SILHOUETTE_PROXIMAL if self._uses_silhouette() else 0.0
        self._matrix = (self.system.laplacian() + self.weights.handle * (selector.T @ sp.diags(multipliers) @ selector)
                        + self._proximal * sp.identity(count)).tocsc()
        # Symmetric positive definite: no pivoting, minimum-degree ordering on A + A^T. The 3V x 3V
        # matrices of the contact rounds have the graph of A with every vertex tripled, so A's
        # ordering, vertex by vertex, serves them too (computed once: 30 % faster factorisations
        # than ordering each, 13 % less fill).
        self._factor = splu(self._matrix, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                            options={"SymmetricMode": True})
        self._position = self._factor.perm_c  # where each vertex goes in the ordering
        self._order = np.argsort(self._position)
        tripled = (3 * self._order[:, None] + np.arange(3)).reshape(-1)
        self._ordered_matrix3 = sp.kron(self._matrix, sp.identity(3)).tocsr()[tripled][:, tripled].tocsc()
        self._fast_local_step = LocalStep(self.system)

    def _uses_silhouette(self) -> bool:
        return self.silhouette is not None and self.weights.silhouette > 0

    # -- the objective ------------------------------------------------------------------------------
    def _contacts(self, vertices: torch.Tensor, among: torch.Tensor | None = None) -> Contacts | None:
        """Closest fit-surface points and normals of the vertices ``among`` (all by default) at ``vertices``."""
        if self.surface is None:
            return None
        index = torch.arange(self.system.vertex_count) if among is None else among
        _, closest, normal = self.surface.query(vertices.detach()[index].numpy(), winding=False)
        return Contacts(index, torch.as_tensor(closest), torch.as_tensor(normal))

    def objective(self, vertices: torch.Tensor, targets: torch.Tensor, contacts: Contacts | None = None,
                  rotations=None, silhouette: bool = True) -> torch.Tensor:
        """E(p); best rotations (detached) unless given; the fit term over ``contacts``; the
        silhouette term unless ``silhouette`` is False."""
        return arap_energy(self.system, vertices, rotations) + self._penalties(vertices, targets, contacts, silhouette)

    def _penalties(self, vertices: torch.Tensor, targets: torch.Tensor, contacts: Contacts | None,
                   silhouette: bool) -> torch.Tensor:
        """E(p) without its ARAP term: handles, fit over ``contacts``, silhouette if asked."""
        w = self.weights
        total = w.handle * (self._handle_multipliers * (vertices[self.handles] - targets).square()).sum()
        if contacts is not None:
            total = total + w.fit * contacts.deficit(vertices, w.margin).square().sum()
        if silhouette and self._uses_silhouette():
            total = total + w.silhouette * self.silhouette.loss(vertices)
        return total

    def _result(self, vertices: torch.Tensor, targets: torch.Tensor, iterations: int, start: float,
                history: list[float]) -> CrdlResult:
        with torch.no_grad():
            p = vertices.detach()
            objective = float(self.objective(p, targets.detach(), self._contacts(p)))
            rmse = float((p[self.handles] - targets.detach()).square().sum(1).mean().sqrt())
            energy = float(arap_energy(self.system, p))
        return CrdlResult(p.numpy().copy(), energy, rmse, objective, iterations, time.perf_counter() - start, history)

    # -- the local-global solver ----------------------------------------------------------------------
    def _factor_for(self, contacts: Contacts | None):
        """Factors of the global step's matrix: A (ARAP and handles, factored once, the same for x,
        y and z), plus w_f n_i n_i^T on the diagonal block of every vertex in the contact set (then
        the 3V x 3V matrix is factored, once per contact round). Without a gradient K^-1 is only
        L-BFGS's initial inverse Hessian (the gradient and E stay float64), and float32 factors
        solve 25 % faster (half the memory traffic), 3e-6 off."""
        if contacts is None or len(contacts.index) == 0:
            return self._factor
        places = 3 * self._position[contacts.index.numpy()]
        rows = places[:, None, None] + np.arange(3)[None, :, None]
        cols = places[:, None, None] + np.arange(3)[None, None, :]
        blocks = self.weights.fit * contacts.normal.numpy()[:, :, None] * contacts.normal.numpy()[:, None, :]
        contact = sp.csc_matrix((blocks.reshape(-1), (np.broadcast_to(rows, blocks.shape).reshape(-1),
                                                       np.broadcast_to(cols, blocks.shape).reshape(-1))),
                                shape=self._ordered_matrix3.shape)
        matrix = (self._ordered_matrix3 + contact).astype(np.float64 if torch.is_grad_enabled() else np.float32)
        return _Interleaved(splu(matrix, permc_spec="NATURAL", diag_pivot_thresh=0.0,
                                 options={"SymmetricMode": True}), self._order, self._position)

    def _value_and_rhs(self, p: torch.Tensor, targets: torch.Tensor, handle_rhs: torch.Tensor,
                       contacts: Contacts | None):
        """At p: E(p) (best R) and the right-hand side b(p) of the global step K x = b(p) (K: A plus the
        contact blocks): ARAP at fixed R, handles, and w_f (n_i . (x_i - z_i))^2 over the contact
        set, z_i = p_i + (m - s_i)^+ n_i the nearest point of vertex i's feasible half-space. That term
        is at least the squared distance to the half-space, so x = K^-1 b(p) majorises E and never
        increases it; it holds the vertex along n_i only, leaving it free to slide along the body."""
        w = self.weights
        if torch.is_grad_enabled():
            rotations = best_rotations(self.system, p)
            value = self.objective(p, targets, contacts, rotations, silhouette=False).detach()
            rhs = torch.sparse.mm(self._incidence_t, self.system.weights[:, None] * rotated_rest_spokes(self.system, rotations))
        else:  # the same in two Warp kernels, several times faster
            arap, rhs = self._fast_local_step(p)
            value = arap + self._penalties(p, targets, contacts, silhouette=False)
        rhs = rhs + handle_rhs
        if contacts is not None and len(contacts.index):
            n = contacts.normal
            height = row_dot(p[contacts.index], n) + contacts.deficit(p, w.margin)
            rhs = rhs.index_add(0, contacts.index, w.fit * height[:, None] * n)
        if self._uses_silhouette():
            loss, gradient = self.silhouette.value_and_gradient(p)
            value = value + w.silhouette * loss
            rhs = rhs + self._proximal * p - w.silhouette * gradient / 2
        return value, rhs

    def _global_matrix_times(self, p: torch.Tensor, contacts: Contacts | None) -> torch.Tensor:
        """K p [V,3]: A p plus w_f n_i (n_i . p_i) for the vertices in the contact set."""
        product = _SymmetricMap.apply(p, self._matrix.__matmul__)
        if contacts is not None and len(contacts.index):
            n = contacts.normal
            product = product.index_add(0, contacts.index, self.weights.fit * row_dot(p[contacts.index], n)[:, None] * n)
        return product

    def _descend(self, p, targets, handle_rhs, contacts, iterations: int, tolerance: float, memory: int = 5,
                 factor=None):
        """L-BFGS on E at a fixed contact set with K as the initial inverse Hessian (Liu et al. 2017):
        g = K p - b(p) is half of E's gradient (E is minimal in R and z), so with no history the step
        -K^-1 g is the local-global step, which never increases E. A quasi-Newton step is kept if it
        meets Armijo's condition E(p + d) <= E(p) + 2e-4 g.d, else the local-global step is taken and
        the history restarts. Stops when E fell by less than ``tolerance`` (relative) per step over the
        last STALL_WINDOW steps (``factor``: K's, if already made). Differentiable (every step is
        torch operations and factored solves)."""
        factor = self._factor_for(contacts) if factor is None else factor
        value, rhs = self._value_and_rhs(p, targets, handle_rhs, contacts)
        g = self._global_matrix_times(p, contacts) - rhs
        history, pairs = [float(value)], []
        for _ in range(iterations):
            step = -_two_loop(pairs, g, factor)
            new_p = p + step
            new_value, new_rhs = self._value_and_rhs(new_p, targets, handle_rhs, contacts)
            if pairs and float(new_value) > float(value) + 2e-4 * float(_dot(g, step).detach()):
                pairs, step = [], -_SymmetricMap.apply(g, factor.solve)
                new_p = p + step
                new_value, new_rhs = self._value_and_rhs(new_p, targets, handle_rhs, contacts)
            new_g = self._global_matrix_times(new_p, contacts) - new_rhs
            change = new_g - g
            curvature = _dot(step, change)
            # E is not convex where the curvature is not positive: skip the pair
            if float(curvature.detach()) > 1e-12 * float((step.norm() * change.norm()).detach()):
                pairs = (pairs + [(step, change, 1.0 / curvature)])[-memory:]
            p, value, g = new_p, new_value, new_g
            history.append(float(value))
            if self._bar is not None:
                self._bar.update(1)
                self._bar.set_postfix(E=f"{float(value):.4g}", refresh=False)
            if len(history) > STALL_WINDOW and (history[-1 - STALL_WINDOW] - history[-1]
                                                < STALL_WINDOW * tolerance * abs(history[-1])):
                break
        return p, history

    def deform(self, targets: torch.Tensor, iterations: int = 300, tolerance: float = TOLERANCE,
               start: torch.Tensor | None = None) -> torch.Tensor:
        """The local-global solution from ``start`` (by default the better of two, see ``_race``);
        differentiable in ``targets`` [H,3]."""
        return self._local_global(targets, iterations, tolerance, start)[0]

    def _local_global(self, targets: torch.Tensor, iterations: int, tolerance: float, start=None,
                      rounds: int = 6):
        """Contact rounds: descend with the contact set fixed (and its half-spaces), then add every
        vertex short of the margin and re-query the set's closest points; stop when a round adds
        none (or after ``rounds``). A vertex once in contact stays in the set (its term is zero
        while it is clear), so the set only grows and E of every round majorises the next.
        Without ``start`` the first round races two starts (``_race``)."""
        handle_rhs = torch.zeros_like(self.system.rest).index_add(0, self.handles,
                                                                  self.weights.handle * self._handle_multipliers * targets)
        round_tolerance = max(tolerance, ROUND_TOLERANCE) if self.surface is not None else tolerance
        if start is None:
            p, history, in_contact, spent = self._race(targets, handle_rhs, iterations, round_tolerance)
        else:
            in_contact, contacts = self._first_contacts(start)
            p, history = self._descend(start.clone(), targets, handle_rhs, contacts, iterations, round_tolerance)
            spent = 0
        for _ in range(rounds - 1):
            if self.surface is None or len(history) >= iterations:
                break
            short = self._contacts(p).deficit(p.detach(), self.weights.margin) > 0
            if not (short & ~in_contact).any():
                if round_tolerance <= tolerance:
                    break
                round_tolerance = tolerance  # the set is complete: one last round to full tolerance
            in_contact |= short
            contacts = self._contacts(p, torch.nonzero(in_contact).flatten())
            p, steps = self._descend(p, targets, handle_rhs, contacts, iterations - len(history), round_tolerance)
            history += steps
        return p, len(history) + spent, history

    def _first_contacts(self, start: torch.Tensor):
        """The contact set of the first round (a mask [V] and its Contacts): every vertex within
        margin + CONTACT_BAND of the surface, half-spaces taken at ``start``. Without them the
        first descent can dive so deep that the nearest surface point is on the far side of a leg."""
        if self.surface is None:
            return torch.zeros(self.system.vertex_count, dtype=torch.bool), None
        near = self._contacts(start).deficit(start.detach(), self.weights.margin + CONTACT_BAND) > 0
        return near, self._contacts(start, torch.nonzero(near).flatten())

    def _race(self, targets: torch.Tensor, handle_rhs: torch.Tensor, iterations: int, tolerance: float):
        """The first round from two starts, the rest shape and the rest shape with the handle
        vertices moved onto their targets, each for RACE_STEPS steps; the one with the lower E goes
        on. They lead to different local minima where a line moves far: shortening a pants leg, the
        snapped hem buckles into a turned-up cuff (Adam's answer, 39 % less energy than compressing
        the leg), while snapped cuffs of a shortened sleeve fold badly (35 % above). E after
        RACE_STEPS steps tells them apart on every shipped garment. Returns (p, history, contact
        mask, steps spent on the start that lost)."""
        snapped = self.system.rest.clone().index_put((self.handles,), targets)
        in_contact, contacts = self._first_contacts(self.system.rest)
        factor = self._factor_for(contacts)  # half-spaces taken at rest for both: one factorisation
        runs = []
        for start in (self.system.rest, snapped):
            p, history = self._descend(start.clone(), targets, handle_rhs, contacts, min(RACE_STEPS, iterations),
                                       tolerance, factor=factor)
            runs.append((history[-1], p, history))
        (_, p, history), (_, _, lost) = sorted(runs, key=lambda run: run[0])
        if len(history) < iterations:
            p, steps = self._descend(p, targets, handle_rhs, contacts, iterations - len(history), tolerance,
                                     factor=factor)
            history = history + steps
        return p, history, in_contact, len(lost)

    def solve_local_global(self, targets: np.ndarray, iterations: int = 300, tolerance: float = TOLERANCE,
                           progress: bool = False) -> CrdlResult:
        """The fast default (see ``_local_global``); ``progress`` shows a bar of the steps taken
        (at most ``iterations``) and the energy E."""
        from tqdm import tqdm

        start = time.perf_counter()
        target = torch.as_tensor(np.asarray(targets, np.float64))
        self._bar = tqdm(total=iterations, desc="crdl", unit="step", disable=not progress, leave=False)
        try:
            with torch.no_grad():
                p, done, history = self._local_global(target, iterations, tolerance)
        finally:
            self._bar.close()
            self._bar = None
        return self._result(p, target, done, start, history)

    def solve_adam(self, targets: np.ndarray, iterations: int = 2000, learning_rate: float = 1e-3,
                   requery: int = 10, progress: bool = False) -> CrdlResult:
        """The paper's solver: the vertices are a parameter, Adam minimises E (fit contacts
        re-queried every ``requery`` steps, the learning rate decayed tenfold over the run)."""
        from tqdm import tqdm

        start = time.perf_counter()
        target = torch.as_tensor(np.asarray(targets, np.float64))
        p = torch.nn.Parameter(self.system.rest.clone())
        optimiser = torch.optim.Adam([p], lr=learning_rate)
        schedule = torch.optim.lr_scheduler.ExponentialLR(optimiser, gamma=0.1 ** (1.0 / iterations))
        contacts, history = None, []
        for step in tqdm(range(iterations), desc="adam", unit="step", disable=not progress, leave=False):
            if step % requery == 0:
                contacts = self._contacts(p)
            optimiser.zero_grad()
            loss = self.objective(p, target, contacts)
            loss.backward()
            optimiser.step()
            schedule.step()
            history.append(float(loss.detach()))
        return self._result(p, target, iterations, start, history)


def _two_loop(pairs: list, gradient: torch.Tensor, factor) -> torch.Tensor:
    """H g by L-BFGS's two-loop recursion over the (s, y, 1 / s.y) ``pairs``, oldest first, with
    H_0 = K^-1 applied by ``factor``."""
    q, alphas = gradient, []
    for s, y, rho in reversed(pairs):
        alpha = rho * _dot(s, q)
        q = q - alpha * y
        alphas.append(alpha)
    r = _SymmetricMap.apply(q, factor.solve)
    for (s, y, rho), alpha in zip(pairs, reversed(alphas)):
        r = r + (alpha - rho * _dot(y, r)) * s
    return r


def _dot(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """sum(a * b) over every entry, without the [V,3] temporary."""
    return torch.dot(a.reshape(-1), b.reshape(-1))


def _coo(matrix: sp.coo_matrix):
    indices = torch.as_tensor(np.stack([matrix.row, matrix.col]).astype(np.int64))
    return indices, torch.as_tensor(matrix.data, dtype=torch.float64), matrix.shape
