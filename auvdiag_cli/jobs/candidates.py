"""The predictors `train` fits, and keeps per signal by held-out skill: the least-squares
linear model, the same linear model refined against the replay's error, the recurrent
network, and the network on top of the least-squares model (it learns only what the linear
model misses)."""

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from models.baselines import fit_linear
from models.fast import LINEAR_REPLAY, NETWORK, PREDICTOR_KINDS, FastDynamics, linear_only
from models.linear_replay import WINDOW_STEPS_MAX, fit_linear_to_replay
from models.normaliser import Normaliser
from models.skill import HorizonScore, ScoringLog, assess, choose_predictors
from models.store import LINEAR_KEY, LINEAR_REPLAY_KEY, ON_LINEAR_PREFIX

if TYPE_CHECKING:
    from models.dynamics import RecurrentDynamics

# Trains the network on the training logs, on top of a linear model (normalised units) or
# alone (None).
NetworkFit = Callable[[np.ndarray | None], tuple["RecurrentDynamics", Normaliser]]


@dataclass(frozen=True)
class Candidates:
    network: "RecurrentDynamics"          # the network alone: the model file's main weights
    normaliser: Normaliser
    extra: dict[str, np.ndarray]          # the other predictors' arrays, for the model file
    scores: list[HorizonScore]            # per horizon, each signal by its best predictor
    by_kind: dict[str, list[HorizonScore]]
    notes: tuple[str, ...]                # predictors left out, and why


def _fast(network: "RecurrentDynamics", normaliser: Normaliser,
          linear: np.ndarray | None = None) -> FastDynamics:
    return FastDynamics.from_state({k: v.detach().numpy() for k, v in
                                    network.state_dict().items()},
                                   network.n_commands, normaliser.delta_ratio, linear)


def fit_candidates(training: Sequence[ScoringLog], heldout: Sequence[ScoringLog],
                   sensor_names: Sequence[str], dt_s: float,
                   horizons: Sequence[float | None], kinds: Sequence[str],
                   fit_network: NetworkFit, progress: Callable[[str], None]) -> Candidates:
    """Fit every predictor of ``kinds`` and score each on ``heldout`` at every horizon. The
    model file is built around the network: ``fit_network`` gives it even where ``kinds``
    leave it out (untrained, `train.network_asked`)."""
    network, normaliser = fit_network(None)
    command_scale = np.asarray(normaliser.command_scale)
    state_scale = np.asarray(normaliser.state_scale)
    linear = fit_linear([t.commands / command_scale for t in training],
                        [t.sensors / state_scale for t in training]).weights.astype(np.float32)
    members = {NETWORK: _fast(network, normaliser), "linear": linear_only(
        linear, network.n_commands)}
    extra = {LINEAR_KEY: linear}
    notes = []
    if LINEAR_REPLAY in kinds:
        progress("refining the linear model against the replay's error")
        replayed = _linear_to_replay(training, linear, command_scale, state_scale,
                                     _window_steps(horizons, dt_s))
        if isinstance(replayed, str):
            notes.append(replayed)
        else:
            members[LINEAR_REPLAY] = linear_only(replayed, network.n_commands)
            extra[LINEAR_REPLAY_KEY] = replayed
    if "network-on-linear" in kinds:
        progress("training the network on top of the linear model")
        try:
            on_linear, _ = fit_network(linear)
        except ValueError as problem:
            notes.append(f"the network on top of the linear model is not kept: {problem}")
        else:
            members["network-on-linear"] = _fast(on_linear, normaliser, linear)
            extra |= {ON_LINEAR_PREFIX + k: v.detach().numpy().copy()
                      for k, v in on_linear.state_dict().items()}
    progress("scoring each predictor against the naive ones on the held-out data")
    by_kind = {kind: assess(members[kind], command_scale, state_scale, training, heldout,
                            sensor_names, dt_s, horizons)
               for kind in PREDICTOR_KINDS if kind in kinds and kind in members}
    return Candidates(network, normaliser, extra, choose_predictors(by_kind), by_kind,
                      tuple(notes))


def _window_steps(horizons: Sequence[float | None], dt_s: float) -> int:
    """Replay windows as long as the longest horizon scored (a free run: as long as the
    fit allows)."""
    finite = [h for h in horizons if h is not None]
    if len(finite) < len(horizons) or not finite:
        return WINDOW_STEPS_MAX
    return max(2, round(max(finite) / dt_s))


def _linear_to_replay(training: Sequence[ScoringLog], linear: np.ndarray,
                      command_scale: np.ndarray, state_scale: np.ndarray,
                      window_steps: int) -> np.ndarray | str:
    """The refined weights, or why there are none."""
    why = "the linear model refined against the replay is not kept: "
    try:
        refined = fit_linear_to_replay([t.commands / command_scale for t in training],
                                       [t.sensors / state_scale for t in training],
                                       [t.cuts for t in training], linear, window_steps)
    except ValueError as problem:
        return why + str(problem)
    return why + "it replays the training logs no better" if refined is None else refined
