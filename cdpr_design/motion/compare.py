"""Comparison of two logged runs of the same motion: delay, errors, segments.

Pure functions on arrays (no file access): the command line reads the CSV
files and passes their columns.  Used by ``cdpr-design compare`` (any two
logs with a time column, e.g. a simulation against a prototype's scope
export) and by ``cdpr-design simulate`` (set-points against the simulated
robot), to reproduce the seed paper's Table 1 (time delay per axis) and
Table 2 (mean target and mean actual position of each horizontal segment of
the square path, with the position error in %).

Conventions
-----------
- A *positive* delay means the actual signal lags the target:
  actual(t) ~ target(t - delay) + offset.
- Position error is the Euclidean distance between the target and actual
  positions (columns ``x``, ``y``, ``z`` present in both logs) at the same
  time, without removing the delay (as in the paper's Fig. 7).
- Segment error in % is |mean actual - mean target| / |mean target| x 100 of
  the coordinate that stays constant along the segment (the paper's Table 2,
  e.g. (947.613 - 946.016) / 947.613 = 0.168 %).

References
----------
Rivera, Garrido, Riveiro, Silva: "Environment for the Design and Automation
of New CDPR Architectures" (seed paper), section 4, Tables 1 and 2.
Parabolic peak interpolation: e.g. Jacobsen & Kootsookos, "Fast, accurate
frequency estimators", IEEE Signal Processing Magazine 24(3), 2007.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import minimize_scalar
from scipy.signal import correlate

POSITION_COORDS = ("x", "y", "z")


# ----------------------------------------------------------------------------
# Time bases
# ----------------------------------------------------------------------------


def uniform_grid(t: np.ndarray, t0: float | None = None, t1: float | None = None,
                 dt: float | None = None) -> np.ndarray:
    """A uniform time grid over [t0, t1] with the median step of ``t`` [s]."""
    t = np.asarray(t, float)
    if dt is None:
        steps = np.diff(t)
        steps = steps[steps > 0]
        if steps.size == 0:
            raise ValueError("the time column must increase")
        dt = float(np.median(steps))
    t0 = float(t[0]) if t0 is None else t0
    t1 = float(t[-1]) if t1 is None else t1
    n = int(np.floor((t1 - t0) / dt + 1e-9)) + 1
    return t0 + dt * np.arange(n)


def resample(t_src, values, t_new) -> np.ndarray:
    """Linear interpolation of a signal onto new times (NaN outside its range)."""
    t_src = np.asarray(t_src, float)
    v = np.asarray(values, float)
    ok = np.isfinite(v)
    if ok.sum() < 2:
        return np.full(np.shape(t_new), np.nan)
    return np.interp(t_new, t_src[ok], v[ok], left=np.nan, right=np.nan)


# ----------------------------------------------------------------------------
# Delay
# ----------------------------------------------------------------------------


def estimate_delay(dt: float, target, actual, max_delay: float | None = None,
                   refine: bool = True) -> float:
    """Time delay [s] of ``actual`` behind ``target``, both sampled every ``dt``.

    Cross-correlation of the first differences (so that a constant offset
    and the trend of a position signal do not bias the peak), peak found with
    sub-sample resolution by parabolic interpolation of the three samples
    around it (the plain sum over the overlap: its peak leans towards zero
    lag on a short record, but stays in the right basin), then (``refine``) polished
    by minimising the variance of actual(t) - target(t - d) (offset removed,
    target linearly interpolated): a downhill walk over whole samples from
    the peak, then a bounded scalar search within one sample of the best.
    Returns NaN when either signal does not move, and when the delay lies
    beyond the searched window (:func:`search_delay`): never a delay outside it.

    Parameters
    ----------
    dt : float
        Sample period [s] of both signals (same time grid).
    target, actual : (k,) arrays
    max_delay : float, optional
        Largest |delay| searched [s]; default: half the record.
    """
    d, beyond = search_delay(dt, target, actual, max_delay, refine)
    return float("nan") if beyond else d


def search_delay(dt: float, target, actual, max_delay: float | None = None,
                 refine: bool = True) -> tuple[float, bool]:
    """(delay [s], beyond) of ``actual`` behind ``target`` (:func:`estimate_delay`), the delay
    within the window [-max_delay, max_delay] (default: half the record); ``beyond``: the best
    fit sits at the window's edge and the fit improves past it, so the true delay lies outside
    the window and the delay returned is only its edge.  (NaN, False) when a signal does not move."""
    xy = _common_stretch(target, actual)
    if xy is None:
        return float("nan"), False
    x, y = xy
    dx, dy = np.diff(x), np.diff(y)
    n = dx.size
    if max_delay is None:
        maxlag = n // 2
        limit = maxlag * dt
    else:
        maxlag = min(int(np.floor(max_delay / dt + 1e-9)), n - 1)
        limit = float(max_delay)
    lag, rising = _correlation_peak(dx, dy, maxlag)
    if not refine:
        return float(np.clip(lag * dt, -limit, limit)), rising
    return _polish(dt, x, y, lag * dt, maxlag, limit)


def _common_stretch(target, actual):
    """(x, y): the stretch where both are finite, inner gaps interpolated; None when either
    does not move (or fewer than 8 common samples)."""
    x = np.asarray(target, float)
    y = np.asarray(actual, float)
    ok = np.isfinite(x) & np.isfinite(y)
    if ok.sum() < 8:
        return None
    idx = np.flatnonzero(ok)
    x, y = x[idx[0]: idx[-1] + 1], y[idx[0]: idx[-1] + 1]
    x = np.where(np.isfinite(x), x, np.interp(np.arange(x.size), np.flatnonzero(np.isfinite(x)), x[np.isfinite(x)]))
    y = np.where(np.isfinite(y), y, np.interp(np.arange(y.size), np.flatnonzero(np.isfinite(y)), y[np.isfinite(y)]))
    dx, dy = np.diff(x), np.diff(y)
    scale = max(np.abs(x).max(), np.abs(y).max(), 1e-300)
    if np.sqrt(np.mean(dx ** 2)) <= 1e-12 * scale or np.sqrt(np.mean(dy ** 2)) <= 1e-12 * scale:
        return None
    return x, y


def _correlation_peak(dx, dy, maxlag: int) -> tuple[float, bool]:
    """(lag [samples], sub-sample, of the correlation peak within |lag| <= maxlag; whether that
    peak is the window's edge with the correlation still rising past it)."""
    n = dx.size
    full = correlate(dy, dx, mode="full", method="auto")  # full[n-1+k] = sum dy[i+k] dx[i]
    lags = np.arange(-(n - 1), n)
    sel = np.abs(lags) <= maxlag
    c, lags = full[sel], lags[sel]
    i = int(np.argmax(c))
    frac = 0.0
    if 0 < i < c.size - 1:
        a, b, d = c[i - 1], c[i], c[i + 1]
        den = a - 2 * b + d
        if den < 0:
            frac = 0.5 * (a - d) / den
    outside = [k for k in (lags[i] - 1, lags[i] + 1) if maxlag < abs(k) < n]  # neighbours past the edge
    return float(lags[i] + frac), any(full[n - 1 + k] > c[i] for k in outside)


def _polish(dt: float, x, y, d0: float, maxlag: int, limit: float) -> tuple[float, bool]:
    """Least-squares polish of the delay ``d0`` [s] within [-limit, limit] (:func:`search_delay`)."""
    t = dt * np.arange(x.size)

    def cost(d):
        xs = np.interp(t - d, t, x, left=np.nan, right=np.nan)
        r = y - xs
        r = r[np.isfinite(r)]
        if r.size < 4:
            return np.inf
        return float(np.mean((r - r.mean()) ** 2))

    # the correlation peak of a finite record can sit off the true delay:
    # walk the least-squares cost downhill over whole samples from it
    kb = int(np.rint(d0 / dt))
    cb = cost(kb * dt)
    for step in (1, -1):
        while abs(kb + step) <= maxlag:
            cn = cost((kb + step) * dt)
            if not cn < cb:
                break
            kb, cb = kb + step, cn
    lo, hi = max((kb - 1) * dt, -limit), min((kb + 1) * dt, limit)
    best = float(np.clip(kb * dt, -limit, limit))
    if lo < hi:
        res = minimize_scalar(cost, bounds=(lo, hi), method="bounded", options={"xatol": 1e-6 * dt})
        if res.success and np.isfinite(res.fun) and res.fun <= cost(best):
            best = float(res.x)
    return best, _beyond(cost, best, dt, limit)


def _beyond(cost, best: float, dt: float, limit: float) -> bool:
    """Whether the fit is better half a sample past an edge of [-limit, limit] (within one sample
    of ``best``) than half a sample inside it: the cost falls across the edge, so the true delay
    lies outside the window.  (Equal offsets: the overlap of the two records, hence the cost's
    small steps, is alike at both points.)"""
    edges = [e for e in (-limit, limit) if abs(e - best) < dt]
    return any(cost(e + np.copysign(dt / 2, e)) < cost(e - np.copysign(dt / 2, e)) for e in edges)


# ----------------------------------------------------------------------------
# Errors
# ----------------------------------------------------------------------------


def column_stats(target, actual) -> dict:
    """Error statistics of actual - target: ``mean``, ``rms``, ``max`` (abs), NaN-safe."""
    e = np.asarray(actual, float) - np.asarray(target, float)
    e = e[np.isfinite(e)]
    if e.size == 0:
        return {"mean": None, "rms": None, "max": None}
    return {"mean": float(e.mean()), "rms": float(np.sqrt(np.mean(e * e))),
            "max": float(np.abs(e).max())}


# ----------------------------------------------------------------------------
# Segments (the paper's Table 2)
# ----------------------------------------------------------------------------


def detect_segments(position: np.ndarray, rel_tol: float = 1e-3, min_samples: int = 10,
                    angle_tol: float = np.deg2rad(2.0), rest_step: float | None = None) -> np.ndarray:
    """Straight segments of a target path, as a segment id per sample.

    The path is cut where the target stops (a step shorter than
    ``rest_step``) or turns (consecutive steps differ in direction by more
    than ``angle_tol``); a piece is a segment when it has at least
    ``min_samples`` samples and stays on the chord between its ends within
    ``rel_tol`` of the chord's length (so a sampled circle gives none).
    Samples in no segment get -1; a corner sample goes with the piece it ends.

    Parameters
    ----------
    position : (k, d) array
        Target positions [m].
    """
    p = np.asarray(position, float)
    k = p.shape[0]
    seg = np.full(k, -1, dtype=np.int64)
    if k < 3:
        return seg
    steps = np.diff(p, axis=0)
    size = np.linalg.norm(steps, axis=1)
    if rest_step is None:
        rest_step = 1e-12 * max(float(np.nanmax(np.abs(p))), 1.0)
    moving = size > rest_step
    unit = np.zeros_like(steps)
    unit[moving] = steps[moving] / size[moving, None]
    cos_tol = np.cos(angle_tol)
    # piece boundaries: step j starts a new piece when j-1 is not moving or turns
    new_piece = np.ones(k - 1, dtype=bool)
    same_dir = np.einsum("ij,ij->i", unit[1:], unit[:-1]) >= cos_tol
    new_piece[1:] = ~(moving[1:] & moving[:-1] & same_dir)
    nid = 0
    j = 0
    while j < k - 1:
        if not moving[j]:
            j += 1
            continue
        s0 = j
        j += 1
        while j < k - 1 and moving[j] and not new_piece[j]:
            j += 1
        e = j  # steps s0..j-1 join samples s0..j
        a, b = p[s0], p[e]
        chord = np.linalg.norm(b - a)
        if e - s0 + 1 >= min_samples and chord > 0:
            u = (b - a) / chord
            rel = p[s0: e + 1] - a
            off = rel - np.outer(rel @ u, u)
            if np.nanmax(np.linalg.norm(off, axis=1)) <= rel_tol * chord:
                seg[s0 + 1: e + 1] = nid
                if seg[s0] < 0:
                    seg[s0] = nid
                nid += 1
    return seg


@dataclass(frozen=True)
class SegmentRow:
    """One row of the per-segment table (the paper's Table 2)."""

    segment: int
    axis: str
    samples: int
    mean_target: float
    mean_actual: float
    error: float
    error_pct: float
    start: tuple[float, ...]
    end: tuple[float, ...]

    def to_dict(self) -> dict:
        return {"segment": self.segment, "axis": self.axis, "samples": self.samples,
                "mean_target": self.mean_target, "mean_actual": self.mean_actual,
                "error": self.error, "error_pct": self.error_pct,
                "start": list(self.start), "end": list(self.end)}


def segment_table(target_pos: np.ndarray, actual_pos: np.ndarray, segment_ids: np.ndarray,
                  coords: tuple[str, ...]) -> list[SegmentRow]:
    """Mean target and mean actual position of each straight segment.

    For each segment id >= 0 the reported coordinate (``axis``) is the one
    that varies least along the segment (for the square: y on the horizontal
    segments, x on the vertical ones).  ``error = mean_actual - mean_target``
    [m]; ``error_pct = |error| / |mean_target| x 100``.
    """
    tp = np.asarray(target_pos, float)
    ap = np.asarray(actual_pos, float)
    ids = np.asarray(segment_ids)
    rows = []
    for sid in np.unique(ids[ids >= 0]):
        sel = ids == sid
        sel &= np.all(np.isfinite(ap), axis=1) & np.all(np.isfinite(tp), axis=1)
        if not np.any(sel):
            continue
        t_seg = tp[sel]
        j = int(np.argmin(np.ptp(t_seg, axis=0)))
        mt = float(t_seg[:, j].mean())
        ma = float(ap[sel, j].mean())
        err = ma - mt
        pct = abs(err) / abs(mt) * 100 if mt != 0 else float("nan")
        rows.append(SegmentRow(int(sid), coords[j], int(sel.sum()), mt, ma, err, pct,
                               tuple(map(float, t_seg[0])), tuple(map(float, t_seg[-1]))))
    return rows


# ----------------------------------------------------------------------------
# Whole comparison
# ----------------------------------------------------------------------------


@dataclass(frozen=True)
class Comparison:
    """Result of :func:`compare` (JSON keys of the CLI contract via :meth:`to_json`).

    Attributes
    ----------
    delay : dict
        Column -> delay [s] of the actual behind the target (NaN: no motion, or a delay beyond
        the searched window).
    rms_error, max_error : float
        Position error [m] (Euclidean over x, y, z) or, without position
        columns, the largest per-column RMS and max error.
    columns : dict
        Column -> {mean, rms, max} of actual - target.
    segments : list of SegmentRow
    time : (k,) array
        The common uniform time grid [s] both logs were resampled to.
    beyond : tuple of str
        Columns whose delay lies beyond the searched window (``max_delay``, default half the
        record): the best fit is at its edge and improves past it; their delay is NaN.
    """

    delay: dict
    rms_error: float
    max_error: float
    columns: dict
    segments: list
    position_columns: tuple[str, ...] = ()
    time: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    error: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    beyond: tuple[str, ...] = ()

    def to_json(self) -> dict:
        def num(v):
            return None if v is None or not np.isfinite(v) else float(v)

        return {
            "delay": {k: num(v) for k, v in self.delay.items()},
            "delay_beyond_window": list(self.beyond),
            "rms_error": num(self.rms_error),
            "max_error": num(self.max_error),
            "columns": self.columns,
            "segments": [r.to_dict() for r in self.segments],
        }


def compare(t_target, target: dict, t_actual, actual: dict, *, columns=None,
            segment_ids=None, max_delay: float | None = None) -> Comparison:
    """Compare two logs of the same motion.

    Parameters
    ----------
    t_target, t_actual : (k,), (q,) arrays
        Time columns [s] (need not match; the actual log is resampled onto a
        uniform grid with the target's median step over the common range).
    target, actual : dict of name -> array
        Value columns.
    columns : list of str, optional
        Columns to compare (default: every column present in both).
    segment_ids : (k,) int array, optional
        Segment id per *target* sample (-1: none); default: detected from the
        target's position columns (:func:`detect_segments`).
    max_delay : float, optional
        Largest |delay| searched [s] (default: half the record); a column whose delay lies
        beyond it has a NaN delay and is listed in ``beyond``.
    """
    tt = np.asarray(t_target, float)
    ta = np.asarray(t_actual, float)
    if columns is None:
        columns = [c for c in target if c in actual]
    if not columns:
        raise ValueError("the two logs have no value column in common")
    t0, t1 = max(tt[0], ta[0]), min(tt[-1], ta[-1])
    if not t1 > t0:
        raise ValueError("the two logs do not overlap in time")
    grid = uniform_grid(tt, t0, t1)
    dt = float(grid[1] - grid[0]) if grid.size > 1 else 1.0
    X = {c: resample(tt, target[c], grid) for c in columns}
    Y = {c: resample(ta, actual[c], grid) for c in columns}
    found = {c: search_delay(dt, X[c], Y[c], max_delay) for c in columns}
    delay = {c: float("nan") if out else d for c, (d, out) in found.items()}
    beyond = tuple(c for c, (_, out) in found.items() if out)
    stats = {c: column_stats(X[c], Y[c]) for c in columns}
    pos = tuple(c for c in POSITION_COORDS if c in columns)
    err = np.zeros(0)
    if pos:
        tp = np.stack([X[c] for c in pos], axis=1)
        ap = np.stack([Y[c] for c in pos], axis=1)
        err = np.linalg.norm(ap - tp, axis=1)
        fin = err[np.isfinite(err)]
        rms = float(np.sqrt(np.mean(fin ** 2))) if fin.size else float("nan")
        mx = float(fin.max()) if fin.size else float("nan")
        if segment_ids is None:
            ids = detect_segments(tp)
        else:
            src = np.asarray(segment_ids)
            near = np.rint(np.interp(grid, tt, np.arange(tt.size))).astype(np.int64)
            ids = src[np.clip(near, 0, src.size - 1)]
        segs = segment_table(tp, ap, ids, pos)
    else:
        rmss = [s["rms"] for s in stats.values() if s["rms"] is not None]
        maxs = [s["max"] for s in stats.values() if s["max"] is not None]
        rms = max(rmss) if rmss else float("nan")
        mx = max(maxs) if maxs else float("nan")
        segs = []
    return Comparison(delay, rms, mx, stats, segs, pos, grid, err, beyond)


__all__ = ["Comparison", "SegmentRow", "column_stats", "compare", "detect_segments",
           "estimate_delay", "resample", "search_delay", "segment_table", "uniform_grid"]
