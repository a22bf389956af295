"""The replay hot path without torch: the same network as `RecurrentDynamics`, stepped in
NumPy with everything that does not depend on the model's own state computed for the whole
command history at once (the command half of the GRU's input gates and of the head's first
layer). Several rollouts (logs, or the independent stretches between restarts of one log)
advance together as one batch, so the per-step cost of Python is paid once for all of them.
Long rollouts go to the numba-compiled loop in `models.compiled` when numba is installed.

Matches the torch module to float32 rounding (see tests/test_fast_replay.py)."""

import importlib.util
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass, fields
from functools import cache, cached_property
from typing import Literal

import numpy as np

from models.normaliser import Normaliser
from models.numpy_step import FusedStep

Engine = Literal["auto", "numpy", "compiled"]
# Loading the compiled kernel costs about 0.4 s a process; the NumPy loop 8-20 µs a step,
# paid once for every rollout advancing together in a batch. Below this many sequential
# steps (each batch's length, summed) the NumPy loop is done before numba would have loaded.
COMPILED_PAYS_FROM_STEPS = 20_000
# The commands' contributions to the gates are held for this many values at once (4 MB of
# float32), however many rollouts and steps a replay has; at least CHUNK_STEPS_MIN steps.
CHUNK_VALUES = 1 << 20
CHUNK_STEPS_MIN = 16


@cache
def compiled_available() -> bool:
    return importlib.util.find_spec("numba") is not None


@dataclass
class _ReplayBudget:
    """Which loop replays, for the work under way in this thread (or task)."""

    expected_steps: int = 0     # sequential steps announced since `new_replay_budget`
    many_logs: bool = False     # within `replaying_many_logs`: every replay is compiled


# Per thread and per asyncio task, never shared: one thread's audit of many logs must not
# change how a diagnosis running beside it replays.
_budget: ContextVar[_ReplayBudget | None] = ContextVar("replay_budget", default=None)


def _current() -> _ReplayBudget:
    budget = _budget.get()
    if budget is None:
        budget = _ReplayBudget()
        _budget.set(budget)
    return budget


def new_replay_budget() -> None:
    """A new piece of work (one log's diagnosis) begins: which loop replays follows the
    steps it announces, never what this thread ran before. The two loops agree to float32
    rounding only, and a log's figures must not depend on the logs diagnosed before it."""
    _budget.set(_ReplayBudget(many_logs=_current().many_logs))


@contextmanager
def replaying_many_logs() -> Iterator[None]:
    """Within: one of many logs replayed in a row (an audit's task): the compiled loop,
    loaded once a process, replays every log, so that each log of the audit is replayed
    the same way whatever came before it (the NumPy loop would take short logs otherwise)."""
    token = _budget.set(_ReplayBudget(_current().expected_steps, many_logs=True))
    try:
        yield
    finally:
        _budget.reset(token)


def expect_steps(steps: int) -> None:
    """Say that about ``steps`` sequential steps are coming in several calls (batches of
    rollouts, each as long as its longest): the compiled loop is loaded now, and used from
    now on, once the steps announced (a diagnosis replays once per hypothesis) pay for it."""
    budget = _current()
    budget.expected_steps += steps
    if compiled_available() and budget.expected_steps >= COMPILED_PAYS_FROM_STEPS:
        importlib.import_module("models.compiled")


def _use_compiled(engine: Engine, rollout_steps: int) -> bool:
    if engine == "numpy":
        return False
    if engine == "compiled":
        if not compiled_available():
            raise RuntimeError("the compiled replay needs numba (pip install numba)")
        return True
    budget = _current()
    return compiled_available() and (
        budget.many_logs
        or max(rollout_steps, budget.expected_steps) >= COMPILED_PAYS_FROM_STEPS)


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
    # The fixed linear model the network sits on, [x̂, c, 1] · W: (n_s + n_c + 1, n_s);
    # zero for a network alone.
    linear: np.ndarray

    @classmethod
    def from_state(cls, state: Mapping[str, np.ndarray], n_commands: int,
                   delta_ratio: float, linear: np.ndarray | None = None) -> "FastDynamics":
        """From the network's state dict (names as `RecurrentDynamics` has them) and the
        linear model under it, if any."""
        def weight(name: str) -> np.ndarray:
            return np.asarray(state[name], dtype=np.float32)

        nc = n_commands
        w_ih, w_hh, w1 = weight("cell.weight_ih"), weight("cell.weight_hh"), weight(
            "head.0.weight")                     # w1: (H, H + nc + ns): [hidden, c, x]
        hidden = w_hh.shape[1]
        n_s = w_ih.shape[1] - nc
        return cls(
            input_commands=w_ih[:, :nc].T.copy(), input_states=w_ih[:, nc:].T.copy(),
            input_bias=weight("cell.bias_ih"), hidden_weights=w_hh.T.copy(),
            hidden_bias=weight("cell.bias_hh"), head_hidden=w1[:, :hidden].T.copy(),
            head_commands=w1[:, hidden:hidden + nc].T.copy(),
            head_states=w1[:, hidden + nc:].T.copy(), head_bias=weight("head.0.bias"),
            out_weights=weight("head.2.weight").T.copy(), out_bias=weight("head.2.bias"),
            delta_ratio=float(delta_ratio),
            linear=np.zeros((n_s + nc + 1, n_s), np.float32) if linear is None
            else np.asarray(linear, np.float32))

    def linear_from(self, commands: np.ndarray) -> np.ndarray:
        """What the commands (…, n_c) and the bias give the linear part's step."""
        n_s = self.out_bias.size
        result: np.ndarray = commands @ self.linear[n_s:-1] + self.linear[-1]
        return result

    @property
    def hidden(self) -> int:
        return self.hidden_weights.shape[0]

    @cached_property
    def fused(self) -> FusedStep:
        """The weights as the NumPy loop steps them (`models.numpy_step`)."""
        return FusedStep.of(**{f.name: getattr(self, f.name) for f in fields(self)})

    def rollout(self, commands: np.ndarray, initial_states: np.ndarray,
                engine: Engine = "auto") -> np.ndarray:
        """Free-run ``batch`` rollouts in normalised units: commands (batch, steps, n_c),
        initial states (batch, n_s) → states x̂(0 … steps−1), (batch, steps, n_s).

        What the commands contribute to the gates is worked out a chunk of steps at a time
        (the hidden state carried across), so memory stays bounded however long the log."""
        commands = commands.astype(np.float32, copy=False)
        batch, steps, _ = commands.shape
        states = np.empty((batch, steps, self.out_bias.size), np.float32)
        states[:, 0] = initial_states.astype(np.float32)
        hidden = np.zeros((batch, self.hidden), np.float32)
        compiled = _use_compiled(engine, steps)
        chunk_steps = max(CHUNK_STEPS_MIN, CHUNK_VALUES // (batch * self.input_bias.size))
        for first in range(0, steps - 1, chunk_steps):
            last = min(first + chunk_steps, steps - 1)      # steps first … last − 1 advance
            chunk = commands[:, first:last]
            if compiled:
                self._compiled_rollout(chunk @ self.input_commands + self.input_bias,
                                       chunk @ self.head_commands + self.head_bias,
                                       self.linear_from(chunk), states[:, first], hidden,
                                       states[:, first + 1:last + 1])
                continue
            # Step-major, so that each step's inputs and states are contiguous.
            inputs = self.fused.inputs(chunk.transpose(1, 0, 2))
            advanced = np.empty((last - first, batch, states.shape[2]), np.float32)
            state = states[:, first]
            for k in range(last - first):
                state, hidden = self.fused.advance(inputs[k], state, hidden)
                advanced[k] = state
            states[:, first + 1:last + 1] = advanced.transpose(1, 0, 2)
        return states

    def _compiled_rollout(self, gates_from_commands: np.ndarray,
                          head_from_commands: np.ndarray, linear_from_commands: np.ndarray,
                          initial_states: np.ndarray, hidden: np.ndarray, states: np.ndarray
                          ) -> None:
        from models.compiled import rollout_kernel

        def outputs_by_inputs(weights: np.ndarray) -> np.ndarray:
            return np.ascontiguousarray(weights.T)

        out = np.empty(states.shape, np.float32)
        rollout_kernel(np.ascontiguousarray(gates_from_commands),
                       np.ascontiguousarray(head_from_commands),
                       np.ascontiguousarray(initial_states), hidden,
                       outputs_by_inputs(self.input_states),
                       outputs_by_inputs(self.hidden_weights), self.hidden_bias,
                       outputs_by_inputs(self.head_hidden), outputs_by_inputs(self.head_states),
                       outputs_by_inputs(self.out_weights), self.out_bias,
                       np.float32(self.delta_ratio),
                       np.ascontiguousarray(linear_from_commands, np.float32),
                       outputs_by_inputs(self.linear[:self.out_bias.size]), out)
        states[:] = out


# The predictors a model can keep per signal, simplest first (kept on a tie).
PREDICTOR_KINDS = ("linear", "linear-replay", "network", "network-on-linear")
NETWORK, LINEAR_REPLAY = "network", "linear-replay"


def linear_only(linear: np.ndarray, n_commands: int) -> FastDynamics:
    """The least-squares linear model alone, as a `FastDynamics` whose network part is one
    hidden unit with every weight zero (it adds nothing)."""
    n_s = linear.shape[1]

    def zeros(*shape: int) -> np.ndarray:
        return np.zeros(shape, np.float32)

    return FastDynamics(zeros(n_commands, 3), zeros(n_s, 3), zeros(3), zeros(1, 3), zeros(3),
                        zeros(1, 1), zeros(n_commands, 1), zeros(n_s, 1), zeros(1),
                        zeros(1, n_s), zeros(n_s), 0.0, np.asarray(linear, np.float32))


@dataclass(frozen=True)
class ChosenDynamics:
    """Each signal predicted by the predictor that won it on held-out data: every member
    runs its own rollout (its state feeds only itself, as in scoring), and each signal is
    read from its own member's."""

    members: tuple[FastDynamics, ...]
    source: tuple[int, ...]          # per signal, the index of its member

    @classmethod
    def single(cls, dynamics: FastDynamics) -> "ChosenDynamics":
        return cls((dynamics,), (0,) * dynamics.out_bias.size)

    def rollout(self, commands: np.ndarray, initial_states: np.ndarray,
                engine: Engine = "auto") -> np.ndarray:
        runs = {m: self.members[m].rollout(commands, initial_states, engine)
                for m in dict.fromkeys(self.source)}
        if len(runs) == 1:
            return next(iter(runs.values()))
        return np.stack([runs[m][..., i] for i, m in enumerate(self.source)], axis=-1)


class FastStepper:
    """The model one step at a time, for closed-loop use: a controller reads its state and
    chooses the next command. ``warm_up`` replays a command history first, exactly as a
    free run does, so the context matches the replay up to that point."""

    def __init__(self, dynamics: ChosenDynamics, normaliser: Normaliser) -> None:
        self.dynamics, self.normaliser = dynamics, normaliser
        self.command_scale = np.asarray(normaliser.command_scale)
        self.state_scale = np.asarray(normaliser.state_scale)
        self.hidden = [np.zeros((1, m.hidden), np.float32) for m in dynamics.members]
        self.states = [np.zeros((1, m.out_bias.size), np.float32) for m in dynamics.members]

    def warm_up(self, commands: np.ndarray, initial_state: np.ndarray) -> np.ndarray:
        """Run over ``commands`` from ``initial_state``; return the state after the last."""
        start = (np.asarray(initial_state) / self.state_scale).astype(np.float32)[None]
        self.states = [start.copy() for _ in self.dynamics.members]
        for command in commands:
            self.step(command)
        return self.current

    @property
    def current(self) -> np.ndarray:
        chosen = [self.states[m][0, i] for i, m in enumerate(self.dynamics.source)]
        return np.asarray(chosen, np.float64) * self.state_scale

    def step(self, command: np.ndarray) -> np.ndarray:
        scaled = (np.asarray(command) / self.command_scale).astype(np.float32)[None]
        for m, d in enumerate(self.dynamics.members):
            self.states[m], self.hidden[m] = d.fused.advance(
                d.fused.inputs(scaled), self.states[m], self.hidden[m])
        return self.current


def fast_replay(dynamics: FastDynamics | ChosenDynamics, normaliser: Normaliser,
                commands: np.ndarray,
                initial_state: np.ndarray, engine: Engine = "auto") -> np.ndarray:
    """`models.dynamics.replay` on the NumPy path: SM(t) in physical units, (steps, n_s)."""
    return fast_replay_batch(dynamics, normaliser, [commands], [initial_state], engine)[0]


def fast_replay_batch(dynamics: FastDynamics | ChosenDynamics, normaliser: Normaliser,
                      commands: list[np.ndarray], initial_states: list[np.ndarray],
                      engine: Engine = "auto") -> list[np.ndarray]:
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
    states = dynamics.rollout(padded / command_scale, starts / state_scale, engine)
    return [states[i, :len(c)].astype(np.float64) * state_scale
            for i, c in enumerate(commands)]
