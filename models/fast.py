"""The replay hot path without torch: the same network as `RecurrentDynamics`, stepped in
NumPy with everything that does not depend on the model's own state computed for the whole
command history at once (the command half of the GRU's input gates and of the head's first
layer). Several rollouts (logs, or the independent stretches between restarts of one log)
advance together as one batch, so the per-step cost of Python is paid once for all of them.

Matches the torch module to float32 rounding (see tests/test_fast_replay.py)."""

from dataclasses import dataclass

import numpy as np

from models.dynamics import Normaliser, RecurrentDynamics


@dataclass(frozen=True)
class FastDynamics:
    """The network's weights, split by what they multiply (float32, as torch stores them)."""

    input_commands: np.ndarray   # (n_commands, 3H): GRU input weights for c(k)
    input_states: np.ndarray     # (n_states, 3H):   GRU input weights for x̂(k)
    input_bias: np.ndarray       # (3H,)
    hidden_weights: np.ndarray   # (H, 3H)
    hidden_bias: np.ndarray      # (3H,)
    head_hidden: np.ndarray      # (H, H): first head layer, the hidden-state part
    head_commands: np.ndarray    # (n_commands, H)
    head_states: np.ndarray      # (n_states, H)
    head_bias: np.ndarray        # (H,)
    out_weights: np.ndarray      # (H, n_states)
    out_bias: np.ndarray         # (n_states,)
    delta_ratio: float

    @classmethod
    def from_module(cls, network: RecurrentDynamics) -> "FastDynamics":
        def weight(tensor: object) -> np.ndarray:
            return np.ascontiguousarray(tensor.detach().numpy(), dtype=np.float32)  # type: ignore[attr-defined]

        nc, hidden = network.n_commands, network.hidden
        w_ih, w_hh = weight(network.cell.weight_ih), weight(network.cell.weight_hh)
        first, last = network.head[0], network.head[2]
        w1 = weight(first.weight)            # (H, H + nc + ns): [hidden, commands, states]
        return cls(
            input_commands=w_ih[:, :nc].T.copy(), input_states=w_ih[:, nc:].T.copy(),
            input_bias=weight(network.cell.bias_ih), hidden_weights=w_hh.T.copy(),
            hidden_bias=weight(network.cell.bias_hh), head_hidden=w1[:, :hidden].T.copy(),
            head_commands=w1[:, hidden:hidden + nc].T.copy(),
            head_states=w1[:, hidden + nc:].T.copy(), head_bias=weight(first.bias),
            out_weights=weight(last.weight).T.copy(), out_bias=weight(last.bias),
            delta_ratio=float(network.delta_ratio))

    @property
    def hidden(self) -> int:
        return self.hidden_weights.shape[0]

    def rollout(self, commands: np.ndarray, initial_states: np.ndarray) -> np.ndarray:
        """Free-run ``batch`` rollouts in normalised units: commands (batch, steps, n_c),
        initial states (batch, n_s) → states x̂(0 … steps−1), (batch, steps, n_s)."""
        commands = commands.astype(np.float32, copy=False)
        batch, steps, _ = commands.shape
        h = self.hidden
        # Everything the commands contribute, for every step at once.
        gates_from_commands = commands @ self.input_commands + self.input_bias
        head_from_commands = commands @ self.head_commands + self.head_bias
        states = np.empty((batch, steps, self.out_bias.size), np.float32)
        state = initial_states.astype(np.float32)
        hidden = np.zeros((batch, h), np.float32)
        states[:, 0] = state
        for k in range(steps - 1):
            x_gates = gates_from_commands[:, k] + state @ self.input_states
            h_gates = hidden @ self.hidden_weights + self.hidden_bias
            reset_update = 1.0 / (1.0 + np.exp(-(x_gates[:, :2 * h] + h_gates[:, :2 * h])))
            reset, update = reset_update[:, :h], reset_update[:, h:]
            candidate = np.tanh(x_gates[:, 2 * h:] + reset * h_gates[:, 2 * h:])
            hidden = candidate + update * (hidden - candidate)
            layer = np.tanh(hidden @ self.head_hidden + head_from_commands[:, k]
                            + state @ self.head_states)
            state = state + self.delta_ratio * (layer @ self.out_weights + self.out_bias)
            states[:, k + 1] = state
        return states


def fast_replay(dynamics: FastDynamics, normaliser: Normaliser, commands: np.ndarray,
                initial_state: np.ndarray) -> np.ndarray:
    """`models.dynamics.replay` on the NumPy path: SM(t) in physical units, (steps, n_s)."""
    return fast_replay_batch(dynamics, normaliser, [commands], [initial_state])[0]


def fast_replay_batch(dynamics: FastDynamics, normaliser: Normaliser,
                      commands: list[np.ndarray], initial_states: list[np.ndarray]
                      ) -> list[np.ndarray]:
    """Several independent replays advanced together; each keeps its own length (shorter
    ones are padded with their last command and the padding is dropped)."""
    if not commands:
        return []
    longest = max(len(c) for c in commands)
    command_scale = np.asarray(normaliser.command_scale)
    state_scale = np.asarray(normaliser.state_scale)
    padded = np.stack([np.pad(c, ((0, longest - len(c)), (0, 0)), mode="edge") if len(c)
                       else np.zeros((longest, command_scale.size)) for c in commands])
    starts = np.stack([np.asarray(s, float) for s in initial_states])
    states = dynamics.rollout(padded / command_scale, starts / state_scale)
    return [states[i, :len(c)].astype(np.float64) * state_scale
            for i, c in enumerate(commands)]
