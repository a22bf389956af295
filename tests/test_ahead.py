"""The change test's predictor a moment ahead: fitted by least squares on normal logs, it
recovers a known linear closed loop, its error stays at the noise on a normal log and moves
when the loop changes, it never predicts across a cut, and it travels through model.json."""

import json

import numpy as np
import pytest

from models.ahead import AheadLog, AheadPredictor, fit_ahead

DT_S = 0.1
NAMES = ["attitude", "rate"]


def _closed_loop(seconds: float, seed: int, gain: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """A second-order loop following a set point; ``gain`` scales what its actuator
    achieves (1: healthy)."""
    rng = np.random.default_rng(seed)
    steps = round(seconds / DT_S)
    set_point = np.repeat(rng.uniform(-1, 1, steps // 50 + 1), 50)[:steps, None]
    state = np.zeros((steps, 2))
    for k in range(steps - 1):
        attitude, rate = state[k]
        push = gain * (4.0 * (set_point[k, 0] - attitude) - 2.5 * rate)
        state[k + 1] = attitude + DT_S * rate, rate + DT_S * push + rng.normal(0, 0.01)
    return set_point, state + rng.normal(0, 0.002, state.shape)


def _fitted() -> AheadPredictor:
    logs = [_closed_loop(120.0, seed) for seed in range(3)]
    held = _closed_loop(60.0, 9)
    ahead = fit_ahead([AheadLog(c, x) for c, x in logs], NAMES, DT_S, [AheadLog(*held)])
    assert ahead is not None
    return ahead


def test_a_known_loop_is_predicted_a_moment_ahead_to_its_noise():
    ahead = _fitted()
    assert ahead.steps == 5 and ahead.lag == 2
    assert ahead.skill["attitude"] > 0.9 and ahead.skill["rate"] > 0.7
    commands, sensors = _closed_loop(60.0, 11)
    error = ahead.residual(commands, sensors)
    assert np.isnan(error[:ahead.steps + ahead.lag]).all()     # nothing to predict from yet
    assert np.nanstd(error[:, 0]) < 0.02      # half a second of the rate's noise


def test_its_error_moves_when_the_loop_weakens():
    ahead = _fitted()
    healthy = ahead.residual(*_closed_loop(60.0, 12))
    weak = ahead.residual(*_closed_loop(60.0, 12, gain=0.4))
    assert np.nanstd(weak[:, 0]) > 3 * np.nanstd(healthy[:, 0])


def test_no_prediction_reaches_across_a_cut_or_a_missing_sample():
    ahead = _fitted()
    commands, sensors = _closed_loop(30.0, 13)
    sensors[100, 1] = np.nan
    error = ahead.residual(commands, sensors, cuts=[200])
    # Predicted from k to k + 5 with the change over k - 2 .. k: the sample missing at 100
    # leaves out the predictions made from it (k = 100 and 102: targets 105 and 107) and
    # its own signal's target at 100 (k = 95), but not the other signal's there; a cut at
    # 200, every prediction whose span holds it (targets 200 .. 206).
    assert np.isnan(error[[105, 107]]).all() and np.isnan(error[100, 1])
    assert np.isfinite(error[100, 0])
    assert np.isfinite(error[[99, 101, 104, 106, 108]]).all()
    assert np.isnan(error[200:207, 0]).all() and np.isfinite(error[207, 0])


def test_too_little_data_fits_no_predictor():
    commands, sensors = _closed_loop(2.0, 1)
    assert fit_ahead([AheadLog(commands, sensors)], NAMES, DT_S) is None


def test_the_predictor_travels_through_model_json_as_numbers():
    ahead = _fitted()
    entry = json.loads(json.dumps(ahead.to_json()))
    again = AheadPredictor.from_json(entry, n_commands=1, n_sensors=2, n_inputs=0)
    commands, sensors = _closed_loop(20.0, 14)
    np.testing.assert_allclose(again.residual(commands, sensors),
                               ahead.residual(commands, sensors), atol=1e-6)
    with pytest.raises(ValueError, match="do not fit 2 commands"):
        AheadPredictor.from_json(entry, n_commands=2, n_sensors=2, n_inputs=0)


def _loop_pushed_by_a_measured_input(seconds: float, seed: int
                                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The loop of `_closed_loop`, its rate also pushed by a slowly wandering quantity
    that is measured but not among the sensors (an aircraft's airspeed error, which its
    autopilot answers): set point, sensors, the measured input."""
    rng = np.random.default_rng(seed)
    steps = round(seconds / DT_S)
    set_point = np.repeat(rng.uniform(-1, 1, steps // 50 + 1), 50)[:steps, None]
    wander = np.convolve(rng.normal(0, 1, steps + 29), np.ones(30) / 30, "valid")[:, None]
    state = np.zeros((steps, 2))
    for k in range(steps - 1):
        attitude, rate = state[k]
        push = 4.0 * (set_point[k, 0] - attitude) - 2.5 * rate + 3.0 * wander[k, 0]
        state[k + 1] = attitude + DT_S * rate, rate + DT_S * push + rng.normal(0, 0.01)
    return set_point, state + rng.normal(0, 0.002, state.shape), wander


def test_a_measured_input_joins_the_state_it_is_predicted_from():
    logs = [_loop_pushed_by_a_measured_input(120.0, seed) for seed in range(3)]
    held = _loop_pushed_by_a_measured_input(60.0, 9)
    blind = fit_ahead([AheadLog(c, x) for c, x, _ in logs], NAMES, DT_S,
                      [AheadLog(*held[:2])])
    seeing = fit_ahead([AheadLog(c, x, i) for c, x, i in logs], NAMES, DT_S,
                       [AheadLog(*held)])
    assert blind is not None and seeing is not None and seeing.inputs == 1
    # The push it adds is 3 x a wander of spread ~0.13: unseen, it is what the blind fit
    # misses of the rate's change over half a second (skill 0.63 against 0.75).
    assert seeing.skill["rate"] > blind.skill["rate"] + 0.08
    commands, sensors, measured = _loop_pushed_by_a_measured_input(60.0, 11)
    entry = json.loads(json.dumps(seeing.to_json()))
    again = AheadPredictor.from_json(entry, n_commands=1, n_sensors=2, n_inputs=1)
    np.testing.assert_allclose(again.residual(commands, sensors, measured),
                               seeing.residual(commands, sensors, measured), atol=1e-6)
    assert np.nanstd(seeing.residual(commands, sensors, measured)[:, 1]) < 0.85 * np.nanstd(
        blind.residual(commands, sensors)[:, 1])
    with pytest.raises(ValueError, match="1 inputs do not fit"):
        AheadPredictor.from_json(entry, n_commands=1, n_sensors=2, n_inputs=2)



def test_each_log_its_own_constant_and_a_channel_one_log_never_fed_bend_no_weight():
    # Three normal logs of a loop with a third signal (a rate sensor fitted only on some
    # days); each log pushed by its own constant disturbance (the day's trim), and on the
    # third log the sensor not fitted: it reads 0 throughout.
    logs = []
    for seed, trim in ((0, 0.3), (1, -0.2), (2, 0.1)):
        commands, sensors = _closed_loop(120.0, seed)
        sensors = sensors + np.array([trim, 0.0])
        rate = np.append(0.0, np.diff(sensors[:, 0])) / DT_S
        logs.append((commands, np.column_stack([sensors, rate if seed < 2 else 0 * rate])))
    held_commands, held = _closed_loop(60.0, 9)
    held = np.column_stack([held, np.append(0.0, np.diff(held[:, 0])) / DT_S])
    names = [*NAMES, "measured_rate"]
    ahead = fit_ahead([AheadLog(c, x) for c, x in logs], names, DT_S,
                      [AheadLog(held_commands, held)])
    assert ahead is not None
    # One constant for all logs and the unfed log's zeros taken for motion: skill 0.58 for
    # the sensor and an attitude error of 0.027 on this held-out log.
    assert ahead.skill["measured_rate"] > 0.7
    assert np.nanstd(ahead.residual(held_commands, held)[:, 0]) < 0.015


def test_without_held_out_logs_its_skill_is_each_logs_from_a_fit_to_the_others():
    logs = [AheadLog(*_closed_loop(120.0, seed)) for seed in range(4)]
    crossed = fit_ahead(logs, NAMES, DT_S)
    held = fit_ahead(logs[:3], NAMES, DT_S, [logs[3]])
    assert crossed is not None and held is not None
    # Every log enters the weights; the skill is measured on errors the fit never saw,
    # so it comes out like a held-out log's, not above it.
    assert abs(crossed.skill["rate"] - held.skill["rate"]) < 0.05
    assert crossed.skill["attitude"] > 0.9 and crossed.skill["rate"] > 0.7
    # A loop that no log showed: the fit to the others cannot know it.
    strange = [*logs[:3], AheadLog(*_closed_loop(120.0, 5, gain=0.3))]
    odd = fit_ahead(strange, NAMES, DT_S)
    assert odd is not None and odd.skill["rate"] < crossed.skill["rate"] - 0.05


def test_a_feature_beyond_anything_fitted_is_held_at_the_edge_of_what_was():
    # Four logs of the loop pushed by a measured input; in one, the input's first sample is
    # far off (an autopilot's altitude target before it takes over).
    logs = [_loop_pushed_by_a_measured_input(120.0, seed) for seed in range(4)]
    clean = fit_ahead([AheadLog(*log) for log in logs], NAMES, DT_S)
    commands, sensors, measured = logs[0]
    jumped = measured.copy()
    jumped[0] = 1000 * measured.std()
    odd = fit_ahead([AheadLog(commands, sensors, jumped), *(AheadLog(*log) for log in logs[1:])],
                    NAMES, DT_S)
    assert clean is not None and odd is not None and odd.ranges is not None
    # Predicted by a fit to the other logs, that one step would have set the rate's error
    # over the whole log left out (skill 0.75 -> 0.42); held within range, it does not.
    assert odd.skill["rate"] > clean.skill["rate"] - 0.05
    # The predictor keeps the range through model.json; a model fitted before has none and
    # extrapolates as it always did.
    entry = json.loads(json.dumps(clean.to_json()))
    assert np.shape(entry["feature_range"]) == (2, len(clean.weights) - 1)
    held = AheadPredictor.from_json(entry, n_commands=1, n_sensors=2, n_inputs=1)
    before = AheadPredictor.from_json({k: v for k, v in entry.items() if k != "feature_range"},
                                      n_commands=1, n_sensors=2, n_inputs=1)
    error, unheld = (p.residual(commands, sensors, jumped)[:, 1] for p in (held, before))
    # The first prediction reads the jump (from step 2 to 7): held, it errs as any other.
    spread = np.nanstd(error)
    assert abs(error[7]) < 2 * spread and abs(unheld[7]) > 5 * spread
    np.testing.assert_allclose(error[20:], unheld[20:], atol=1e-9)   # within range: alike
    entry["feature_range"] = entry["feature_range"][::-1]
    with pytest.raises(ValueError, match="feature ranges"):
        AheadPredictor.from_json(entry, n_commands=1, n_sensors=2, n_inputs=1)


def test_a_handful_of_short_logs_shrinks_what_they_cannot_pin_down(monkeypatch):
    """Three 20 s logs of the loop beside six channels that wander on their own: plain least
    squares follows what those logs happened to hold and predicts the logs left out worse
    than "no change"; shrunk as far as predicts them best, each channel's weights stay near
    "no change" and the loop keeps its skill."""
    import models.ahead as ahead_module

    names = [*NAMES, *(f"wander_{i}" for i in range(6))]
    logs = []
    for seed in range(3):
        commands, state = _closed_loop(20.0, seed)
        wander = np.cumsum(np.random.default_rng(100 + seed).normal(0, 0.05, (len(state), 6)),
                           axis=0)
        logs.append(AheadLog(commands, np.hstack([state, wander])))
    shrunk = fit_ahead(logs, names, DT_S)
    monkeypatch.setattr(ahead_module, "SHRINKAGE", (0.0,))
    plain = fit_ahead(logs, names, DT_S)
    assert shrunk is not None and plain is not None
    assert min(plain.skill[n] for n in names[2:]) < -0.2
    assert min(shrunk.skill[n] for n in names[2:]) > -0.05
    assert all(shrunk.skill[n] >= plain.skill[n] for n in names)
    assert shrunk.skill["attitude"] > 0.9 and shrunk.skill["rate"] > 0.7
