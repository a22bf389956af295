"""One step of the dynamics model in NumPy, its weights rearranged so that a step is as
few array operations as the arithmetic allows.

The NumPy loop pays Python's overhead per array operation, per step, for every rollout
advancing together, so fewer operations are what make it fast: the three products with
the state (the GRU's input gates, the head, the linear part) are one matrix product; the
bias, the step ratio and the identity of ``x̂ + Δx̂`` are folded into the weights; and
the logistic function's ``0.5 *`` inside ``tanh`` is folded into the reset and update
gates' weights. Equal to the torch module and to the compiled loop (`models.compiled`) to
float32 rounding (tests/test_fast_replay.py).
"""

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class FusedStep:
    """Columns of the per-step inputs: ``[gates (3H) | head (H) | next state (n_s)]``;
    the reset and update gates' columns (the first 2H) are halved."""

    from_commands: np.ndarray    # (n_c, 4H + n_s)
    command_bias: np.ndarray     # (4H + n_s,)
    from_state: np.ndarray       # (n_s, 4H + n_s)
    from_hidden: np.ndarray      # (H, 3H)
    hidden_bias: np.ndarray      # (3H,)
    head_hidden: np.ndarray      # (H, H)
    out_weights: np.ndarray      # (H, n_s), times the step ratio

    @classmethod
    def of(cls, input_commands: np.ndarray, input_states: np.ndarray,
           input_bias: np.ndarray, hidden_weights: np.ndarray, hidden_bias: np.ndarray,
           head_hidden: np.ndarray, head_commands: np.ndarray, head_states: np.ndarray,
           head_bias: np.ndarray, out_weights: np.ndarray, out_bias: np.ndarray,
           delta_ratio: float, linear: np.ndarray) -> "FusedStep":
        """From `FastDynamics`' weights (the same names and shapes)."""
        hidden = hidden_weights.shape[0]
        n_s = out_bias.size
        halved = np.ones(3 * hidden, np.float32)
        halved[:2 * hidden] = 0.5
        state_linear = linear[:n_s] + np.eye(n_s, dtype=np.float32)

        def joined(*parts: np.ndarray) -> np.ndarray:
            return np.ascontiguousarray(np.concatenate(parts, axis=-1), np.float32)

        return cls(
            from_commands=joined(input_commands * halved, head_commands, linear[n_s:-1]),
            command_bias=joined(input_bias * halved, head_bias,
                                linear[-1] + np.float32(delta_ratio) * out_bias),
            from_state=joined(input_states * halved, head_states, state_linear),
            from_hidden=joined(hidden_weights * halved), hidden_bias=joined(
                hidden_bias * halved), head_hidden=np.ascontiguousarray(head_hidden),
            out_weights=joined(out_weights * np.float32(delta_ratio)))

    @property
    def hidden(self) -> int:
        return self.head_hidden.shape[0]

    def inputs(self, commands: np.ndarray) -> np.ndarray:
        """What the commands (…, n_c) and the biases give each step, (…, 4H + n_s)."""
        result: np.ndarray = commands @ self.from_commands + self.command_bias
        return result

    def advance(self, inputs: np.ndarray, state: np.ndarray, hidden: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray]:
        """One step of ``batch`` rollouts: the step's `inputs` (batch, 4H + n_s), the state
        (batch, n_s) and the GRU's hidden state (batch, H) → the next state and hidden."""
        h = self.hidden
        mixed = inputs + state @ self.from_state
        from_hidden = hidden @ self.from_hidden + self.hidden_bias
        # logistic(x) = 0.5 + 0.5·tanh(x / 2); it cannot overflow on extreme inputs.
        reset_update = 0.5 + 0.5 * np.tanh(mixed[:, :2 * h] + from_hidden[:, :2 * h])
        candidate = np.tanh(mixed[:, 2 * h:3 * h] + reset_update[:, :h] * from_hidden[:, 2 * h:])
        hidden = candidate + reset_update[:, h:] * (hidden - candidate)
        layer = np.tanh(hidden @ self.head_hidden + mixed[:, 3 * h:4 * h])
        return mixed[:, 4 * h:] + layer @ self.out_weights, hidden
