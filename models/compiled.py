"""The replay loop compiled with numba: the same model as the NumPy loop
(`models.numpy_step`), one sample at a time, with no per-step Python. A one-hour 10 Hz log
replays in about a tenth of a second instead of most of one.

Compiled once per machine (about 3 s, cached beside this file or in the user's cache);
loading the cached kernel costs about 0.4 s per process, mostly importing numba. Only
``reassoc`` and ``contract`` are relaxed: NaN and infinity keep their meaning. NumPy's error
model drops the zero-division checks (the rational tanh's denominator is never zero).

The gates' logistic functions and tanh go through `fast_tanh`, plain arithmetic that the
compiler vectorises, not the C library's scalar exp and tanh: those were two thirds of a
step (2.7x faster in all; benchmarks/speed.py measures the replay)."""

import numpy as np
from numba import njit

# tanh(x) ≈ x·P(s)/Q(s), s = (x/10)², on [−10, 10]; beyond, tanh rounds to ±1 in float32.
# A rational minimax fit (linearised least squares, reweighted until the error levels out),
# within 2e-8 of tanh: the float32 result is within an ulp (tests/test_compiled_tanh.py).
TANH_CLAMP = 10.0
TANH_NUMERATOR = (1.0, 13.038678697781013, 30.535594113263514, 10.63560786457199,
                  -1.8184266955387858, 0.4336975719935605, -0.061965312440959874)
TANH_DENOMINATOR = (1.0, 46.37199648877385, 242.9379590082429, 247.3219195976389)
_P0, _P1, _P2, _P3, _P4, _P5, _P6 = TANH_NUMERATOR
_Q0, _Q1, _Q2, _Q3 = TANH_DENOMINATOR
_SCALE = 1.0 / TANH_CLAMP**2
_HALF = np.float32(0.5)


@njit(inline="always", fastmath={"reassoc", "contract"}, error_model="numpy")
def fast_tanh(x: np.float32) -> np.float32:
    """tanh of a float32 without a library call; NaN stays NaN. Worked in float64: in
    float32 the rounding of the sums, not the fit, would set the error (6 ulp)."""
    clamped = min(max(np.float64(x), -TANH_CLAMP), TANH_CLAMP)
    s = clamped * clamped * _SCALE
    numerator = (((((_P6 * s + _P5) * s + _P4) * s + _P3) * s + _P2) * s + _P1) * s + _P0
    denominator = ((_Q3 * s + _Q2) * s + _Q1) * s + _Q0
    return np.float32(clamped * numerator / denominator)


@njit(inline="always", fastmath={"reassoc", "contract"}, error_model="numpy")
def fast_logistic(x: np.float32) -> np.float32:
    """1 / (1 + exp(−x)), as tanh: equal, and it cannot overflow."""
    return _HALF + _HALF * fast_tanh(_HALF * x)


@njit(cache=True, fastmath={"reassoc", "contract"}, error_model="numpy")
def rollout_kernel(gates_from_commands: np.ndarray, head_from_commands: np.ndarray,
                   initial_states: np.ndarray, hidden_states: np.ndarray,
                   states_to_gates: np.ndarray, hidden_to_gates: np.ndarray,
                   hidden_bias: np.ndarray, hidden_to_head: np.ndarray,
                   states_to_head: np.ndarray, head_to_out: np.ndarray, out_bias: np.ndarray,
                   delta_ratio: np.float32, linear_from_commands: np.ndarray,
                   states_to_linear: np.ndarray, states: np.ndarray) -> None:
    """Advance ``batch`` rollouts over ``steps`` commands: ``states`` (batch, steps, n_s)
    gets the state after each step; ``hidden_states`` (batch, h) comes in as the hidden
    state before the first step and leaves as the one after the last, so a long replay runs
    in chunks. The linear part (zero for a network alone) adds ``linear_from_commands``
    and ``states_to_linear`` times the state. Weights are transposed (outputs × inputs)
    so every dot product reads contiguous memory."""
    batch, steps, three_h = gates_from_commands.shape
    h = three_h // 3
    n_s = initial_states.shape[1]
    hidden = np.empty(h, np.float32)
    x_gates = np.empty(three_h, np.float32)
    h_gates = np.empty(three_h, np.float32)
    layer = np.empty(h, np.float32)
    state = np.empty(n_s, np.float32)
    following = np.empty(n_s, np.float32)
    for b in range(batch):
        hidden[:] = hidden_states[b]
        state[:] = initial_states[b]
        for k in range(steps):
            for j in range(three_h):
                acc = gates_from_commands[b, k, j]
                for i in range(n_s):
                    acc += states_to_gates[j, i] * state[i]
                x_gates[j] = acc
                acc = hidden_bias[j]
                for i in range(h):
                    acc += hidden_to_gates[j, i] * hidden[i]
                h_gates[j] = acc
            for j in range(h):
                reset = fast_logistic(x_gates[j] + h_gates[j])
                update = fast_logistic(x_gates[h + j] + h_gates[h + j])
                candidate = fast_tanh(x_gates[2 * h + j] + reset * h_gates[2 * h + j])
                hidden[j] = candidate + update * (hidden[j] - candidate)
            for j in range(h):
                acc = head_from_commands[b, k, j]
                for i in range(h):
                    acc += hidden_to_head[j, i] * hidden[i]
                for i in range(n_s):
                    acc += states_to_head[j, i] * state[i]
                layer[j] = acc
            for j in range(h):      # apart, so that it vectorises
                layer[j] = fast_tanh(layer[j])
            for j in range(n_s):
                acc = out_bias[j]
                for i in range(h):
                    acc += head_to_out[j, i] * layer[i]
                linear = linear_from_commands[b, k, j]
                for i in range(n_s):
                    linear += states_to_linear[j, i] * state[i]
                following[j] = state[j] + delta_ratio * acc + linear
            state[:] = following
            states[b, k] = state
        hidden_states[b] = hidden
