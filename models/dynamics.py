"""The paper's Model Matching network as a torch module.

x̂(k+1) = x̂(k) + Δ · f(c(k), x̂(k), h(k)),  h(k+1) = GRU(h(k), [c(k), x̂(k)])

- inputs: actuator commands c(k) and the *model's own* state x̂(k) (feedback RC_1): after the
  initial state no sensor value enters, so a failed sensor cannot corrupt the prediction;
- outputs: the change of each sensed quantity over Δt (scaled by ``delta_scale``);
- a GRU hidden state h carries the past (recurrent context RC_2: thruster lag, coupling);
- multiple inputs and outputs, so coupling between surge and yaw is learned;
- optionally on top of a fixed linear model (``linear``, fitted by least squares, see
  `models.baselines.fit_linear`): x̂(k+1) = x̂(k) + [x̂(k), c(k), 1] · W + Δ · f(…), so the
  network learns only what the linear model misses.
Everything is in normalised units; `Normaliser` converts.
"""

import numpy as np
import torch
from torch import nn

from models.normaliser import Normaliser


class RecurrentDynamics(nn.Module):
    """Free-running recurrent model of the vehicle (see module docstring)."""

    def __init__(self, n_commands: int, n_states: int, hidden: int = 32,
                 delta_ratio: float = 0.1, linear: np.ndarray | None = None) -> None:
        super().__init__()
        # Fixed, not learnt, and kept out of the state dict: the model file stores it apart.
        self.linear: torch.Tensor | None = None if linear is None else torch.as_tensor(
            linear, dtype=torch.float32)
        self.n_commands, self.n_states, self.hidden = n_commands, n_states, hidden
        self.delta_ratio = delta_ratio
        self.cell = nn.GRUCell(n_commands + n_states, hidden)
        self.head = nn.Sequential(
            nn.Linear(hidden + n_commands + n_states, hidden), nn.Tanh(),
            nn.Linear(hidden, n_states))

    def forward(self, commands: torch.Tensor, initial_state: torch.Tensor) -> torch.Tensor:
        """Roll out from ``initial_state`` (batch, n_states) under ``commands``
        (batch, steps, n_commands); return x̂(0 … steps−1), shape (batch, steps, n_states)."""
        batch, steps, _ = commands.shape
        hidden = commands.new_zeros(batch, self.hidden)
        state = initial_state
        outputs = [state]
        for k in range(steps - 1):
            features = torch.cat((commands[:, k], state), dim=1)
            hidden = self.cell(features, hidden)
            step = self.delta_ratio * self.head(torch.cat((hidden, features), dim=1))
            if self.linear is not None:
                n_s = self.n_states
                step = (step + state @ self.linear[:n_s]
                        + commands[:, k] @ self.linear[n_s:-1] + self.linear[-1])
            state = state + step
            outputs.append(state)
        return torch.stack(outputs, dim=1)


def replay(model: RecurrentDynamics, normaliser: Normaliser, commands: np.ndarray,
           initial_state: np.ndarray) -> np.ndarray:
    """Run the model free over a whole log: SM(t) in physical units, shape (steps, n_states)."""
    with torch.inference_mode():
        predicted = model(normaliser.commands(commands)[None],
                          normaliser.states(initial_state)[None])
    return normaliser.to_units(predicted[0])
