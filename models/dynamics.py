"""The paper's Model Matching network as a torch module.

x̂(k+1) = x̂(k) + Δ · f(c(k), x̂(k), h(k)),  h(k+1) = GRU(h(k), [c(k), x̂(k)])

- inputs: actuator commands c(k) and the *model's own* state x̂(k) (feedback RC_1): after the
  initial state no sensor value enters, so a failed sensor cannot corrupt the prediction;
- outputs: the change of each sensed quantity over Δt (scaled by ``delta_scale``);
- a GRU hidden state h carries the past (recurrent context RC_2: thruster lag, coupling);
- multiple inputs and outputs, so coupling between surge and yaw is learned.
Everything is in normalised units; `Normaliser` converts.
"""

from dataclasses import dataclass

import numpy as np
import torch
from torch import nn


@dataclass(frozen=True)
class Normaliser:
    """Per-signal scales: states are divided by ``state_scale``; a model step moves the
    normalised state by ``delta_ratio`` times the network output."""

    command_scale: tuple[float, ...]
    state_scale: tuple[float, ...]
    delta_ratio: float = 0.1

    def commands(self, values: np.ndarray) -> torch.Tensor:
        return torch.as_tensor(values / np.asarray(self.command_scale), dtype=torch.float32)

    def states(self, values: np.ndarray) -> torch.Tensor:
        return torch.as_tensor(values / np.asarray(self.state_scale), dtype=torch.float32)

    def to_units(self, states: torch.Tensor) -> np.ndarray:
        result: np.ndarray = states.detach().numpy().astype(np.float64) * np.asarray(
            self.state_scale)
        return result


class RecurrentDynamics(nn.Module):
    """Free-running recurrent model of the vehicle (see module docstring)."""

    def __init__(self, n_commands: int, n_states: int, hidden: int = 32,
                 delta_ratio: float = 0.1) -> None:
        super().__init__()
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
            state = state + self.delta_ratio * self.head(torch.cat((hidden, features), dim=1))
            outputs.append(state)
        return torch.stack(outputs, dim=1)


def replay(model: RecurrentDynamics, normaliser: Normaliser, commands: np.ndarray,
           initial_state: np.ndarray) -> np.ndarray:
    """Run the model free over a whole log: SM(t) in physical units, shape (steps, n_states)."""
    with torch.inference_mode():
        predicted = model(normaliser.commands(commands)[None],
                          normaliser.states(initial_state)[None])
    return normaliser.to_units(predicted[0])


class Stepper:
    """The model one step at a time, for closed-loop use: a controller reads its state and
    chooses the next command. ``warm_up`` replays a command history first, exactly as
    `replay` does, so the context matches the free run up to that point."""

    def __init__(self, model: RecurrentDynamics, normaliser: Normaliser) -> None:
        self.model, self.normaliser = model, normaliser
        self.hidden = torch.zeros(1, model.hidden)
        self.state = torch.zeros(1, model.n_states)

    def warm_up(self, commands: np.ndarray, initial_state: np.ndarray) -> np.ndarray:
        """Run over ``commands`` from ``initial_state``; return the state after the last."""
        self.state = self.normaliser.states(initial_state)[None]
        for command in commands:
            self.step(command)
        return self.current

    @property
    def current(self) -> np.ndarray:
        return self.normaliser.to_units(self.state[0])

    def step(self, command: np.ndarray) -> np.ndarray:
        with torch.inference_mode():
            features = torch.cat((self.normaliser.commands(np.asarray(command))[None],
                                  self.state), dim=1)
            self.hidden = self.model.cell(features, self.hidden)
            delta = self.model.head(torch.cat((self.hidden, features), dim=1))
            self.state = self.state + self.model.delta_ratio * delta
        return self.current
