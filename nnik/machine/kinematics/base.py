"""The one interface every kinematics implements (compare Klipper's klippy/kinematics/)."""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from nnik.errors import NnikError
from nnik.machine.params import Param


@dataclass(frozen=True)
class Workspace:
    """Axis-aligned rectangle of target positions, in mm."""

    x_mm: tuple[float, float]
    y_mm: tuple[float, float]

    @property
    def lo(self) -> np.ndarray:
        return np.array([self.x_mm[0], self.y_mm[0]])

    @property
    def hi(self) -> np.ndarray:
        return np.array([self.x_mm[1], self.y_mm[1]])

    @property
    def center(self) -> np.ndarray:
        return (self.lo + self.hi) / 2

    @property
    def half(self) -> np.ndarray:
        return (self.hi - self.lo) / 2

    def boundary(self, n_per_edge: int = 64) -> np.ndarray:
        """Points along the rectangle's edges (corners included), for reach checks."""
        t = np.linspace(0.0, 1.0, n_per_edge)
        lo, hi = self.lo, self.hi
        edges = [
            np.stack([lo[0] + t * (hi[0] - lo[0]), np.full_like(t, lo[1])], 1),
            np.stack([lo[0] + t * (hi[0] - lo[0]), np.full_like(t, hi[1])], 1),
            np.stack([np.full_like(t, lo[0]), lo[1] + t * (hi[1] - lo[1])], 1),
            np.stack([np.full_like(t, hi[0]), lo[1] + t * (hi[1] - lo[1])], 1),
        ]
        return np.concatenate(edges)

    def grid(self, n: int) -> np.ndarray:
        xs = np.linspace(self.x_mm[0], self.x_mm[1], n)
        ys = np.linspace(self.y_mm[0], self.y_mm[1], n)
        gx, gy = np.meshgrid(xs, ys, indexing="xy")
        return np.stack([gx.ravel(), gy.ravel()], 1)


class Mechanism(ABC):
    """Exact kinematics of one machine family.

    Positions p are (N, 2) float64 arrays in mm on the work plane. Joints q are (N, 2) float64
    arrays in radians: mechanical mirror angles for galvos, motor shaft angles for belt machines.
    The actuator counts from `q_rest` (the joint vector that is its zero).
    """

    kind: ClassVar[str]
    PARAMS: ClassVar[dict[str, Param]]
    joint_names: ClassVar[tuple[str, str]] = ("q1", "q2")
    family: ClassVar[str]  # "galvo" | "belt" | "measured"
    analytic: ClassVar[bool] = True

    def __init__(self, params: dict, workspace: Workspace, source: str = "<scenario>"):
        self.params = params
        self.workspace = workspace
        self.source = source

    @property
    def q_rest(self) -> np.ndarray:
        return np.zeros(2)

    @abstractmethod
    def forward(self, q: np.ndarray) -> np.ndarray:
        """Joint angles (rad) -> position (mm)."""

    @abstractmethod
    def inverse(self, p: np.ndarray) -> np.ndarray:
        """Position (mm) -> joint angles (rad)."""

    def check_reach(self) -> None:
        """Raise NnikError if the workspace is outside the mechanism's reach. Default: no limit."""

    def check_swing(self, limit_deg: float, key: str = "max_mech_deg") -> None:
        """Raise NnikError if any joint swings more than limit_deg from rest over the workspace."""
        swing = np.degrees(np.abs(self.inverse(self.workspace.boundary()) - self.q_rest)).max(0)
        for name, s in zip(self.joint_names, swing):
            if s > limit_deg:
                raise NnikError(
                    f"workspace needs a {name} swing of {s:.2f} deg mechanical, beyond the "
                    f"+/-{limit_deg:g} deg reach ({key})",
                    self.source,
                    "[workspace]",
                )

    def describe(self) -> str:
        values = ", ".join(f"{k}={v}" for k, v in self.params.items() if v is not None and k != "distortion")
        return f"{self.kind}({values})"


def as_points(a) -> np.ndarray:
    a = np.asarray(a, dtype=np.float64)
    if a.ndim == 1:
        a = a[None, :]
    if a.ndim != 2 or a.shape[1] != 2:
        raise ValueError(f"expected an (N, 2) array, got shape {a.shape}")
    return a
