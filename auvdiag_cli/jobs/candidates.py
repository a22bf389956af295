"""The predictors `train` fits, and keeps per signal by held-out skill: the least-squares
linear model, the recurrent network, and the network on top of the linear model (it learns
only what the linear model misses)."""

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from models.baselines import fit_linear
from models.fast import NETWORK, PREDICTOR_KINDS, FastDynamics, linear_only
from models.normaliser import Normaliser
from models.skill import HorizonScore, ScoringLog, assess, choose_predictors
from models.store import LINEAR_KEY, ON_LINEAR_PREFIX

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
    """Fit every predictor of ``kinds`` (the network is always trained: the model file is
    built around it) and score each on ``heldout`` at every horizon."""
    network, normaliser = fit_network(None)
    command_scale = np.asarray(normaliser.command_scale)
    state_scale = np.asarray(normaliser.state_scale)
    linear = fit_linear([t.commands / command_scale for t in training],
                        [t.sensors / state_scale for t in training]).weights.astype(np.float32)
    members = {NETWORK: _fast(network, normaliser), "linear": linear_only(
        linear, network.n_commands)}
    extra = {LINEAR_KEY: linear}
    notes = []
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
