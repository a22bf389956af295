"""The change test's statistics (`engine.change_check`) on a log's residuals: each signal's
window means in units of the spread of the earlier windows that do not overlap them (z), and
the two-sided CUSUM of those z beyond an allowance (the sum), each way apart; and the words
that name a signal's way ("roll above", "roll below")."""

from collections.abc import Collection, Mapping, Sequence

import numpy as np

from auvdiag_cli.engine.change_signatures import Signature, with_signatures

# k: a window mean within one spread of its reference adds nothing; a shift of two spreads
# adds one a window.
DRIFT_ALLOWANCE = 1.0
# A window is judged every this many steps, each against the windows before it that do
# not overlap it: a change is seen once a window's worth of it is in, not at the next of a
# fixed row of windows (models calibrated before record none: windows side by side).
STRIDE_STEPS = 1
WINDOW, SUM = "window", "sum"
STATISTICS = (WINDOW, SUM)
# statistic -> signal -> (above, below): how far normal logs typically go each way
# (`jobs.change_calibration.way_scales`); a signal without one is judged either way alike.
WayScales = Mapping[str, Mapping[str, tuple[float, float]]]
ABOVE, BELOW = " above", " below"


def each_way(names: Sequence[str]) -> list[str]:
    """The names of ``names`` each way apart: every one above, then every one below."""
    return [*(n + ABOVE for n in names), *(n + BELOW for n in names)]


def larger_way(above: np.ndarray | float, below: np.ndarray | float,
               scale: tuple[np.ndarray | float, np.ndarray | float] = (1.0, 1.0)
               ) -> np.ndarray:
    """A signal's statistic: the larger of its two ways, each divided by its scale."""
    return np.asarray(np.fmax(np.asarray(above) / scale[0], np.asarray(below) / scale[1]))


def signal_of(name: str) -> str:
    """The signal a name of one way is of ("accel_x below" -> "accel_x")."""
    for way in (ABOVE, BELOW):
        if name.endswith(way):
            return name[:-len(way)]
    return name


def _running(values: np.ndarray) -> np.ndarray:
    """Running sums down the columns, with a zero row in front (row i: the first i rows)."""
    return np.vstack([np.zeros((1, values.shape[1])), np.cumsum(values, axis=0)])


def _windowed_means(values: np.ndarray, window: int) -> np.ndarray:
    """Each step's mean over the last ``window`` steps (NaN where fewer than half are
    finite), per column."""
    finite = np.isfinite(values)
    sums = _running(np.where(finite, values, 0.0))
    counts = _running(finite.astype(float))
    means = np.full(values.shape, np.nan)
    if values.shape[0] >= window:
        total = sums[window:] - sums[:-window]
        n = counts[window:] - counts[:-window]
        with np.errstate(invalid="ignore", divide="ignore"):
            means[window - 1:] = np.where(n * 2 >= window, total / np.maximum(n, 1), np.nan)
    return means


def _standardised(residual: np.ndarray, window: int, reference_min: int, stride: int
                  ) -> tuple[np.ndarray, np.ndarray]:
    """z of each whole window, one ending every ``stride`` steps (each window's last step's
    index, and z per signal: NaN until the earlier windows hold ``reference_min`` steps,
    and where a window has no mean). A window's reference is every window judged before it
    that does not overlap it: those ending a whole window or more earlier. Pooling the
    phases keeps the spread as steady as the log allows early on, where each phase's own
    handful of windows let one phase's spread come out small and its z large."""
    ends = np.arange(window - 1, residual.shape[0], stride)
    means = _windowed_means(residual, window)[ends]
    finite = np.isfinite(means)
    values = np.where(finite, means, 0.0)
    lag = window // stride        # windows ending within one window's span
    # The reference of window b: windows 0 .. b - lag.
    first, second = (_running(v)[:-lag] for v in (values, values ** 2))
    counts = _running(finite.astype(float))[:-lag]
    z = np.full(means.shape, np.nan)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = first / counts
        spread = np.sqrt(np.maximum(second / counts - mean * mean, 0.0))
        z[lag - 1:] = (means[lag - 1:] - mean) / spread
    covered = np.full(means.shape, -np.inf)
    covered[lag - 1:] = counts * stride + window - stride     # the reference's steps
    z[(covered < reference_min) | ~finite] = np.nan
    z[lag - 1:][~(spread > 0)] = np.nan
    return ends, z


def _sums(z: np.ndarray, one_sided: np.ndarray, per_window: int) -> np.ndarray:
    """The CUSUM of each phase's windows (every ``per_window``-th row of ``z``): a window
    adds to the sum of the window a whole window before it. The phases run side by side,
    a block of ``per_window`` rows at a time."""
    rows, signals = z.shape
    blocks = -(-rows // per_window)
    padded = np.full((blocks * per_window, signals), np.nan)
    padded[:rows] = z
    padded = padded.reshape(blocks, per_window, signals)
    sums = np.full(padded.shape, np.nan)
    high = np.zeros((per_window, signals))
    low = np.zeros((per_window, signals))
    for block, values in enumerate(padded):
        known = np.isfinite(values)
        high = np.where(known, np.maximum(0.0, high + values - DRIFT_ALLOWANCE), high)
        low = np.where(known, np.maximum(0.0, low - values - DRIFT_ALLOWANCE), low)
        low[:, one_sided] = 0.0
        sums[block] = np.where(known | (high + low > 0), np.maximum(high, low), np.nan)
    return sums.reshape(-1, signals)[:rows]


def way_statistics(residual: np.ndarray, window: int, reference_min: int,
                   found: Sequence[Signature] = (), stride: int | None = STRIDE_STEPS,
                   below_only: Sequence[int] = ()) -> dict[str, np.ndarray]:
    """Each statistic per step, as of the last whole window (NaN until the reference is
    long enough), each way apart: every signal above the prediction (z), then every signal
    below it (−z), then one column per signature in ``found`` (`change_signatures`); each
    column one-sided, a move against it adds nothing. The columns ``below_only`` are never
    judged above (a loop's gain: a part that fails makes it smaller, `models.tracking`).
    A window ends every ``stride`` steps (a divisor of ``window``; None: ``window``,
    windows side by side)."""
    stride = stride_of(window, stride)
    ends, z = _standardised(residual, window, reference_min, stride)
    z, one_sided = with_signatures(np.hstack([z, -z]), found)
    z[:, list(below_only)] = np.nan
    sums = _sums(z, np.ones_like(one_sided), window // stride)

    def on_steps(per_window: np.ndarray) -> np.ndarray:
        """Each window's value held from its last step until the next window's."""
        out = np.full((residual.shape[0], z.shape[1]), np.nan)
        if ends.size:
            held = np.repeat(per_window, stride, axis=0)
            out[ends[0]:] = held[:residual.shape[0] - ends[0]]
        return out

    return {WINDOW: on_steps(np.maximum(z, 0.0)), SUM: on_steps(sums)}


def change_statistics(residual: np.ndarray, window: int, reference_min: int,
                      found: Sequence[Signature] = (), stride: int | None = STRIDE_STEPS,
                      scales: WayScales | None = None, names: Sequence[str] = (),
                      below_only: Collection[str] = ()) -> dict[str, np.ndarray]:
    """Each statistic per step and signal (`way_statistics`): per signal the larger of its
    two ways, each divided by its scale (``scales``: statistic -> signal of ``names`` ->
    (above, below), `way_scales`; a signal without one: |z| and the two-sided CUSUM,
    max(S_above, S_below); one of ``below_only``: below alone); after the signals'
    columns, the signatures'."""
    values = way_statistics(residual, window, reference_min, found, stride,
                            below_only_columns(names, below_only))
    n = residual.shape[1]
    out = {}
    for statistic, ways in values.items():
        scaled = (scales or {}).get(statistic, {})
        pairs = np.array([scaled.get(name, (1.0, 1.0)) for name in names]).reshape(-1, 2) \
            if scaled else np.ones((n, 2))
        out[statistic] = np.hstack([larger_way(ways[:, :n], ways[:, n:2 * n],
                                               (pairs[:, 0], pairs[:, 1])),
                                    ways[:, 2 * n:]])
    return out


def below_only_columns(names: Sequence[str], below_only: Collection[str]) -> list[int]:
    """The columns of ``names`` judged below their usual value only (a loop's gain)."""
    return [i for i, name in enumerate(names) if name in below_only]


def stride_of(window: int, stride: int | None) -> int:
    if stride is None:
        return window
    if stride < 1 or window % stride:
        raise ValueError(f"a stride of {stride} steps does not divide a window of {window}")
    return stride
