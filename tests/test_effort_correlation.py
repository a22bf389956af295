"""The within-log correlation of a group's shares and the change test that sets it aside
(`models.effort_correlation`): with only the averaging's correlation it is the plain test;
a pair tied by the mixer is whitened; a slow wander larger than the windows' noise widens
the directions it moves in and no others."""

import numpy as np

from models.effort_correlation import (
    averaging_correlation,
    pooled_correlation,
    unit_rows,
    whitening,
    with_slow_wander,
)
from models.effort_directions import judged_directions, weakness_directions


def _toward(correlation: np.ndarray | None, members: int) -> np.ndarray:
    whiten = whitening(correlation, np.ones(members))
    return unit_rows(weakness_directions(members) @ whiten.T) @ whiten


def test_with_the_averaging_alone_the_test_is_the_plain_one():
    for members in (2, 4, 6):
        np.testing.assert_allclose(_toward(None, members), judged_directions(members),
                                   atol=1e-9)
        np.testing.assert_allclose(_toward(averaging_correlation(members), members),
                                   judged_directions(members), atol=1e-9)


def test_a_tied_pair_is_set_aside_and_the_change_test_has_unit_variance():
    rng = np.random.default_rng(4)
    # Shares of four thrusters whose first two and last two move against each other.
    tie = np.array([[1, -1, 0, 0], [0, 0, 1, -1]], float) / 2 ** 0.5
    noise = rng.normal(size=(20000, 2)) @ tie * 3 + rng.normal(size=(20000, 4)) * 0.5
    noise -= noise.mean(axis=1, keepdims=True)          # the shares average to one
    covariance = np.cov(noise.T)
    sigma = np.sqrt(np.diag(covariance))
    correlation = pooled_correlation([(covariance, 20000)])
    assert correlation is not None and correlation[0, 1] < -0.9
    whiten = whitening(correlation, sigma)
    toward = unit_rows(weakness_directions(4) @ whiten.T) @ whiten
    z = (noise / sigma) @ toward.T
    np.testing.assert_allclose(z.std(axis=0), 1.0, atol=0.03)
    # A weak motor 1 (its share up, the others' down alike) stands further out of that noise
    # than the plain projection, blind to the tie, sees it.
    shift = (np.eye(4)[0] - 0.25) / sigma
    assert toward[0] @ shift > 1.5 * judged_directions(4)[0] @ shift > 0
    assert pooled_correlation([(covariance, 100), (None, 100)]) is None


def test_a_slow_wander_widens_only_the_directions_it_moves_in():
    whiten = whitening(None, np.ones(4))
    assert with_slow_wander(whiten, None) is whiten
    # No more than the windows' own noise: nothing changes.
    np.testing.assert_allclose(with_slow_wander(whiten, 0.5 * averaging_correlation(4)),
                               whiten, atol=1e-9)
    # Four times the noise's variance along motor 1 against motor 2: that direction halved.
    along = np.array([1.0, -1.0, 0.0, 0.0]) / 2 ** 0.5
    slow = averaging_correlation(4) + 3 * np.outer(along, along) * (4 / 3)
    wider = with_slow_wander(whiten, slow)
    ratio = np.linalg.norm(wider @ along) / np.linalg.norm(whiten @ along)
    assert abs(ratio - 0.5) < 0.01
    other = np.array([0.0, 0.0, 1.0, -1.0]) / 2 ** 0.5
    np.testing.assert_allclose(wider @ other, whiten @ other, atol=1e-9)
