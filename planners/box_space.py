"""The OMPL side of the planning spaces: a bounded real-vector space and states made from body poses."""

from __future__ import annotations

import abc

import numpy as np
from ompl import base as ob


class BoxSpace(abc.ABC):
    """An OMPL RealVectorStateSpace with per-axis bounds; subclasses convert poses (`to_vector`)."""

    def __init__(self, low, high):
        self.low, self.high = np.asarray(low, float), np.asarray(high, float)
        self.dim = len(self.low)
        self.space = ob.RealVectorStateSpace(self.dim)
        bounds = ob.RealVectorBounds(self.dim)
        for k in range(self.dim):
            bounds.setLow(k, float(self.low[k]))
            bounds.setHigh(k, float(self.high[k]))
        self.space.setBounds(bounds)

    @abc.abstractmethod
    def to_vector(self, pose) -> np.ndarray:
        """One body pose (6,) -> a state vector (dim,)."""

    def state(self, pose):
        """An OMPL state holding `pose`."""
        s = self.space.allocState()
        for k, v in enumerate(self.to_vector(pose)):
            s[k] = float(v)
        return s
