"""Per-signal scales between physical and network units (no torch needed to hold them)."""

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    import torch


@dataclass(frozen=True)
class Normaliser:
    """Per-signal scales: states are divided by ``state_scale``; a model step moves the
    normalised state by ``delta_ratio`` times the network output."""

    command_scale: tuple[float, ...]
    state_scale: tuple[float, ...]
    delta_ratio: float = 0.1

    def commands(self, values: np.ndarray) -> "torch.Tensor":
        import torch

        return torch.as_tensor(values / np.asarray(self.command_scale), dtype=torch.float32)

    def states(self, values: np.ndarray) -> "torch.Tensor":
        import torch

        return torch.as_tensor(values / np.asarray(self.state_scale), dtype=torch.float32)

    def to_units(self, states: "torch.Tensor") -> np.ndarray:
        result: np.ndarray = states.detach().numpy().astype(np.float64) * np.asarray(
            self.state_scale)
        return result
