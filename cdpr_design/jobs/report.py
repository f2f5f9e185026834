"""Files: atomic CSV / JSON / PNG writers and the pictures (matplotlib, Agg).

Every file is written to a temporary name in the destination folder and
renamed into place when complete, so an interrupted run never leaves a
truncated file under the final name.  An output folder remembers what
cdpr-design wrote into it (``.cdpr-design-outputs``): a file of the same name
that cdpr-design did not write is never overwritten unless the user asks
(``--overwrite``).
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
import re
import tempfile
from pathlib import Path
from typing import Iterable, Sequence

import numpy as np

from cdpr_design.plots.worker import PictureWorker
from cdpr_design.errors import InputError

MANIFEST = ".cdpr-design-outputs"
#: Resolution of every PNG [dots per inch].
DPI = 120


# ----------------------------------------------------------------------------
# Output folders and atomic files
# ----------------------------------------------------------------------------


class OutputDir:
    """An output folder; refuses to replace files cdpr-design did not write.

    Parameters
    ----------
    path : folder, created if missing.
    overwrite : replace foreign files of the same name too.
    """

    def __init__(self, path: str | Path, overwrite: bool = False):
        self.path = Path(path)
        self.overwrite = overwrite
        if self.path.exists() and not self.path.is_dir():
            raise InputError(f"--out: {self.path} exists and is not a folder")
        try:
            self.path.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise InputError(f"--out: cannot create {self.path}: {exc}") from None
        self._manifest = self.path / MANIFEST
        try:
            self._ours = set(self._manifest.read_text().split("\n")) - {""}
        except FileNotFoundError:
            self._ours = set()

    def target(self, name: str) -> Path:
        """The path for output ``name``, after checking it may be (over)written."""
        p = self.path / name
        if p.exists() and name not in self._ours and not self.overwrite:
            raise InputError(
                f"{p} exists and was not written by cdpr-design; move it away or pass --overwrite")
        return p

    def wrote(self, name: str) -> None:
        if name not in self._ours:
            self._ours.add(name)
            write_text_atomic(self._manifest, "\n".join(sorted(self._ours)) + "\n")

    def write_text(self, name: str, text: str) -> Path:
        p = self.target(name)
        write_text_atomic(p, text)
        self.wrote(name)
        return p

    def write_json(self, name: str, data) -> Path:
        return self.write_text(name, json.dumps(data, indent=2, default=_json_default) + "\n")

    def write_csv(self, name: str, header: Sequence[str], rows: Iterable[Sequence]) -> Path:
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        w.writerow(header)
        for r in rows:
            w.writerow([fmt(v) for v in r])
        return self.write_text(name, buf.getvalue())

    def stream(self, name: str) -> "AtomicFile":
        """An :class:`AtomicFile` for writing ``name`` piece by piece."""
        p = self.target(name)
        return AtomicFile(p, on_commit=lambda: self.wrote(name))

    def write_bytes(self, name: str, data: bytes) -> Path:
        p = self.target(name)
        with AtomicFile(p, binary=True) as fh:
            fh.write(data)
        self.wrote(name)
        return p

    def save_figure(self, name: str, fig, dpi: int = DPI) -> Path:
        p = self.target(name)
        with AtomicFile(p, binary=True) as fh:
            fig.savefig(fh, format="png", dpi=dpi)
        self.wrote(name)
        return p


class AtomicFile:
    """A file written under a temporary name and renamed into place on success.

    Use as a context manager; on an exception (or :meth:`abort`) the
    temporary file is removed and the final name is untouched.
    ``keep_partial=True`` renames what was written to ``<name>.partial``
    instead, so a long interrupted log is not lost.
    """

    def __init__(self, path: str | Path, binary: bool = False, on_commit=None, keep_partial: bool = False):
        self.path = Path(path)
        self.on_commit = on_commit
        self.keep_partial = keep_partial
        fd, tmp = tempfile.mkstemp(prefix=f".{self.path.name}.", suffix=".tmp", dir=self.path.parent)
        self.tmp = Path(tmp)
        os.chmod(self.tmp, 0o666 & ~_umask())
        self.fh = os.fdopen(fd, "wb" if binary else "w", **({} if binary else {"newline": "", "encoding": "utf-8"}))
        self.closed = False

    def write(self, data):
        return self.fh.write(data)

    def flush(self):
        self.fh.flush()

    def commit(self) -> Path:
        if self.closed:
            return self.path
        self.fh.flush()
        os.fsync(self.fh.fileno())
        self.fh.close()
        os.replace(self.tmp, self.path)
        self.closed = True
        if self.on_commit:
            self.on_commit()
        return self.path

    def abort(self) -> None:
        if self.closed:
            return
        self.fh.close()
        self.closed = True
        if self.keep_partial and self.tmp.stat().st_size:
            os.replace(self.tmp, self.path.with_name(self.path.name + ".partial"))
        else:
            self.tmp.unlink(missing_ok=True)

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        if exc_type is None:
            self.commit()
        else:
            self.abort()
        return False


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def write_text_atomic(path: str | Path, text: str) -> None:
    with AtomicFile(path) as fh:
        fh.write(text)


def _json_default(o):
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")


def fmt(v) -> str:
    """A CSV cell: numbers with 10 significant digits, NaN/None as empty."""
    if v is None:
        return ""
    if isinstance(v, (bool, np.bool_)):
        return "1" if v else "0"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        return "" if not math.isfinite(v) else format(float(v), ".10g")
    return str(v)


_NONFINITE = re.compile(r"(?<![^,\n])-?(?:nan|inf)(?![^,\n])")


def format_block(columns: list[np.ndarray], int_cols: Sequence[int] = ()) -> str:
    """Rows of a numeric block as CSV text: NaN cells empty, floats with 10 digits.

    ``columns`` are 1-D arrays of equal length; those listed in ``int_cols``
    are written as integers.  Non-finite cells (NaN, inf) are written empty.
    """
    if not columns or not len(columns[0]):
        return ""
    ints = set(int_cols)
    fmt = ",".join("%d" if j in ints else "%.10g" for j in range(len(columns)))
    block = np.column_stack([np.asarray(c, dtype=float) for c in columns])
    for j in ints:
        if not np.isfinite(block[:, j]).all():
            raise ValueError(f"integer column {j} holds a non-finite value")
    text = "\n".join([fmt % row for row in map(tuple, block.tolist())]) + "\n"
    return _NONFINITE.sub("", text) if "n" in text else text


# ----------------------------------------------------------------------------
# Workspace CSV (streamed)
# ----------------------------------------------------------------------------


def workspace_header(design) -> list[str]:
    """``workspace.csv`` columns (cli.md): pose coords, feasible, margin, tensions, lengths."""
    names = design.cable_names
    return (list(design.motion.coords) + ["feasible", "margin"]
            + [f"tension_{c}" for c in names] + [f"length_{c}" for c in names])


def workspace_rows(chunk, extra: dict[str, np.ndarray] | None = None) -> str:
    """CSV text of one :class:`~cdpr_design.workspaces.grid.Chunk` (no header)."""
    cols = [chunk.poses[:, j] for j in range(chunk.poses.shape[1])]
    cols.append(chunk.feasible)
    cols.append(chunk.margin)
    cols += [chunk.tensions[:, i] for i in range(chunk.tensions.shape[1])]
    cols += [chunk.lengths[:, i] for i in range(chunk.lengths.shape[1])]
    ints = [chunk.poses.shape[1]]
    for v in (extra or {}).values():
        if v.dtype.kind in "biu":
            ints.append(len(cols))
        cols.append(v)
    return format_block(cols, int_cols=ints)


# ----------------------------------------------------------------------------
# Pictures
# ----------------------------------------------------------------------------


def _plt():
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    return plt


def _frame_rect(ax, design, **kw):
    from matplotlib.patches import Rectangle

    lo, hi = design.frame_lower, design.frame_upper
    ax.add_patch(Rectangle((lo[0], lo[1]), hi[0] - lo[0], hi[1] - lo[1], fill=False,
                           lw=2.0, ec=kw.get("ec", "0.15"), zorder=3))


def _draw_robot(ax, design, pose, proj=(0, 1)):
    """Outlets, cables and the effector box at ``pose`` (motion coords), projected."""
    from matplotlib.patches import Polygon

    from cdpr_design.statics import kinematics as kin

    a, b = proj
    A = design.outlets
    ax.plot(A[:, a], A[:, b], "v", ms=9, mfc="tab:red", mec="k", zorder=6, label="outlets")
    for i, c in enumerate(design.cables):
        ax.annotate(c.name, (A[i, a], A[i, b]), textcoords="offset points", xytext=(4, 6),
                    fontsize=8, zorder=7)
    if pose is None:
        return
    geo = kin.cable_geometry(design, pose)
    for i in range(design.m):
        ax.plot([A[i, a], geo.anchors[i, a]], [A[i, b], geo.anchors[i, b]], "-", color="k",
                lw=1.2, zorder=5)
    R = kin.pose_rotation(design, pose)
    full = design.full_pose(pose)
    hx, hy = design.effector.size[a] / 2, design.effector.size[b] / 2
    corners = np.array([[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]])
    pts3 = np.zeros((4, 3))
    pts3[:, a], pts3[:, b] = corners[:, 0], corners[:, 1]
    world = full[:3] + pts3 @ R.T
    ax.add_patch(Polygon(world[:, [a, b]], closed=True, fc="tab:orange", ec="k", lw=1.0,
                         alpha=0.9, zorder=6, label="effector"))


def _extent(axes2):
    x, y = axes2
    dx = (x[1] - x[0]) if x.size > 1 else 1.0
    dy = (y[1] - y[0]) if y.size > 1 else 1.0
    return [x[0] - dx / 2, x[-1] + dx / 2, y[0] - dy / 2, y[-1] + dy / 2]


def _slices(result, nmax: int = 6) -> list[int]:
    """z-slice indices to show for a spatial result: evenly spread, up to nmax."""
    nz = result.feasible_map.shape[2]
    if nz <= nmax:
        return list(range(nz))
    return sorted({int(round(v)) for v in np.linspace(0, nz - 1, nmax)})


def workspace_figure(result, title_extra: str = ""):
    """Feasible region shaded by capacity margin, with frame, outlets, cables and effector.

    Planar motions: one panel.  Spatial motions: a stack of z-slices (x-y
    panels), each with the frame's footprint and the outlets.
    """
    from cdpr_design import workspaces as wsmod

    plt = _plt()
    d = result.design
    feas = result.feasible_map.astype(bool)
    marg = np.where(feas, result.margin_map, np.nan)
    finite = marg[np.isfinite(marg)]
    vmax = float(finite.max()) if finite.size else 1.0
    vmax = vmax if vmax > 0 else 1.0
    kind_txt = {"static": "static-equilibrium", "wrench-feasible": "wrench-feasible",
                "wrench-closure": "wrench-closure"}[result.kind]
    unit = "m²" if d.motion.planar else "m³"
    title = (f"{d.name}: {kind_txt} workspace — {100 * result.fraction:.1f} % of "
             f"{result.poses:,} poses feasible ({result.measure:.3g} {unit})")
    ori = result.orientation_coords()
    if ori:
        title += "\norientation " + ", ".join(
            f"{n} = {np.degrees(v):.3g}°" for n, v in zip(d.motion.rotation_coords, ori))
    if title_extra:
        title += "\n" + title_extra
    cmap = plt.get_cmap("viridis").with_extremes(bad=(0.85, 0.85, 0.85, 1.0))
    rep = wsmod.representative_pose(result)
    if d.motion.planar:
        fig, ax = plt.subplots(figsize=(7.5, 6.6))
        fig.subplots_adjust(left=0.09, right=0.97, bottom=0.08, top=0.90)
        im = ax.imshow(marg.T, origin="lower", extent=_extent(result.map_axes), cmap=cmap,
                       vmin=0.0, vmax=vmax, interpolation="nearest", aspect="equal", zorder=1)
        ax.contour(result.map_axes[0], result.map_axes[1], feas.T.astype(float), levels=[0.5],
                   colors="k", linewidths=0.8, zorder=2)
        _frame_rect(ax, d)
        _draw_robot(ax, d, rep)
        if d.requirements.task_box is not None:
            from matplotlib.patches import Rectangle

            lo, hi = d.requirements.task_box
            ax.add_patch(Rectangle((lo[0], lo[1]), hi[0] - lo[0], hi[1] - lo[1], fill=False,
                                   ls="--", lw=1.5, ec="tab:blue", zorder=4, label="task box"))
        _pad_limits(ax, d)
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        fig.colorbar(im, ax=ax, shrink=0.85, label="capacity margin [N] (grey: infeasible)")
        ax.legend(loc="lower right", fontsize=8, framealpha=0.9)
        ax.set_title(title, fontsize=10)
        if rep is not None:
            ax.text(0.01, 0.01, "drawn at the pose of largest margin " + _pose_txt(d, rep),
                    transform=ax.transAxes, fontsize=7, va="bottom", zorder=8,
                    bbox=dict(fc="white", ec="none", alpha=0.7))
        return fig
    zs = _slices(result)
    ncol = min(3, len(zs))
    nrow = math.ceil(len(zs) / ncol)
    aspect = _frame_aspect(d)
    height = (3.9 * aspect + 0.9) * nrow + 0.9
    fig, axs = plt.subplots(nrow, ncol, figsize=(4.6 * ncol, height), squeeze=False)
    fig.subplots_adjust(left=0.07, right=0.88, bottom=0.7 / height, top=1 - 0.8 / height,
                        wspace=0.3, hspace=0.9 / (3.9 * aspect))
    ext = _extent(result.map_axes[:2])
    z_axis = result.map_axes[2]
    im = None
    for k, ax in enumerate(axs.flat):
        if k >= len(zs):
            ax.axis("off")
            continue
        iz = zs[k]
        im = ax.imshow(marg[:, :, iz].T, origin="lower", extent=ext, cmap=cmap, vmin=0.0, vmax=vmax,
                       interpolation="nearest", aspect="equal")
        frac = feas[:, :, iz].mean() if feas[:, :, iz].size else 0.0
        _frame_rect(ax, d)
        A = d.outlets
        ax.plot(A[:, 0], A[:, 1], "v", ms=6, mfc="tab:red", mec="k")
        _pad_limits(ax, d)
        ax.set_title(f"z = {z_axis[iz]:.3g} m  ({100 * frac:.0f} % feasible)", fontsize=9)
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
    fig.colorbar(im, ax=axs.ravel().tolist(), shrink=0.8, label="capacity margin [N] (grey: infeasible)")
    fig.suptitle(title, fontsize=10)
    return fig


def _pose_txt(d, pose) -> str:
    return "(" + ", ".join(f"{n} = {v:.3g}" for n, v in zip(d.motion.coords, pose)) + ")"


def _frame_aspect(d) -> float:
    """Height / width of the frame's x-y footprint (panel shape of the pictures)."""
    lo, hi = np.array(d.frame_lower), np.array(d.frame_upper)
    return float(np.clip((hi[1] - lo[1]) / (hi[0] - lo[0]), 0.3, 3.0))


def _pad_limits(ax, d):
    lo, hi = np.array(d.frame_lower), np.array(d.frame_upper)
    pad = 0.06 * (hi - lo)
    ax.set_xlim(lo[0] - pad[0], hi[0] + pad[0])
    ax.set_ylim(lo[1] - pad[1], hi[1] + pad[1])


def tension_figure(result):
    """Tension of each cable over the grid: one panel per cable, shared colour scale.

    Infeasible poses are masked (grey).  Spatial motions show, for every
    cable, the z-slice with the most feasible poses.
    """
    plt = _plt()
    d = result.design
    feas = result.feasible_map.astype(bool)
    T = np.where(feas[None], result.tension_maps, np.nan)
    finite = T[np.isfinite(T)]
    vmin = 0.0
    vmax = float(finite.max()) if finite.size else 1.0
    if vmax <= vmin:
        vmax = vmin + 1.0
    cmap = plt.get_cmap("magma").with_extremes(bad=(0.85, 0.85, 0.85, 1.0))
    m = d.m
    ncol = min(4, m) if m > 2 else m
    nrow = math.ceil(m / ncol)
    aspect = _frame_aspect(d)
    height = (3.7 * aspect + 0.9) * nrow + 0.7
    fig, axs = plt.subplots(nrow, ncol, figsize=(4.0 * ncol + 1.4, height), squeeze=False)
    fig.subplots_adjust(left=0.08, right=0.9, bottom=0.6 / height, top=1 - 0.6 / height,
                        wspace=0.3, hspace=0.9 / (3.7 * aspect))
    if d.motion.planar:
        img = T
        sub = ""
    else:
        iz = int(np.argmax(feas.sum(axis=(0, 1))))
        img = T[:, :, :, iz]
        sub = f" at z = {result.map_axes[2][iz]:.3g} m (slice with the most feasible poses)"
    ext = _extent(result.map_axes[:2])
    im = None
    for i, ax in enumerate(axs.flat):
        if i >= m:
            ax.axis("off")
            continue
        im = ax.imshow(img[i].T, origin="lower", extent=ext, cmap=cmap, vmin=vmin, vmax=vmax,
                       interpolation="nearest", aspect="equal")
        _frame_rect(ax, d)
        A = d.outlets
        ax.plot(A[i, 0], A[i, 1], "v", ms=9, mfc="tab:cyan", mec="k", zorder=6)
        _pad_limits(ax, d)
        c = d.cables[i]
        ax.set_title(f"{c.name}: {c.tension_min:g}–{c.tension_max:g} N", fontsize=9)
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
    fig.colorbar(im, ax=axs.ravel().tolist(), shrink=0.85, label="cable tension [N] (grey: infeasible)")
    fig.suptitle(f"{d.name}: minimum-norm cable tensions, {result.kind} workspace{sub}", fontsize=10)
    return fig


def save_workspace_pictures(out: OutputDir, result, worker: PictureWorker | None = None) -> list[Path]:
    """``workspace.png`` and ``tension_map.png`` of a workspace result (drawn by ``worker`` if given)."""
    names = ("workspace.png", "tension_map.png")
    for name in names:  # refuse a foreign file before drawing anything
        out.target(name)
    jobs = [(names[0], workspace_figure, (result,)), (names[1], tension_figure, (result,))]
    pngs = (worker or PictureWorker(enabled=False)).render(jobs)
    return [out.write_bytes(name, data) for name, data in pngs]


# ----------------------------------------------------------------------------
# Motor sizing and the design report (size-motors, report, check)
# ----------------------------------------------------------------------------


def write_motor_sizing(out: OutputDir, sizing) -> Path:
    """``motor_sizing.csv``: one row per cable, the contract columns first (cli.md)."""
    rows = sizing.rows()
    header = list(rows[0].keys()) if rows else list(getattr(sizing, "CONTRACT", ()))
    return out.write_csv("motor_sizing.csv", header, ([r[k] for k in header] for r in rows))


def write_design_report(out: OutputDir, row: dict, name: str = "design_report.csv") -> Path:
    """``design_report.csv``: one row of the design's headline figures (booleans as 1/0)."""
    header = list(row.keys())
    return out.write_csv(name, header, [[row[k] for k in header]])


# ----------------------------------------------------------------------------
# Trajectories, simulations and logs (trajectory, simulate, compare)
# ----------------------------------------------------------------------------


def write_columns(out: OutputDir, name: str, columns: dict) -> Path:
    """A CSV of named 1-D columns (``trajectory.csv``, ``simulation.csv``), written atomically.

    Integer columns are written as integers, NaN cells empty, floats with 10
    significant digits.
    """
    names = list(columns)
    cols = [np.asarray(columns[c]) for c in names]
    ints = [j for j, c in enumerate(cols) if c.dtype.kind in "biu"]
    text = ",".join(names) + "\n" + format_block(cols, int_cols=ints)
    return out.write_text(name, text)


def read_csv_columns(path: str | Path, what: str = "CSV") -> dict[str, np.ndarray]:
    """Numeric columns of a CSV log with a header row: name -> float array.

    Empty or non-numeric cells become NaN; columns with no number at all are
    dropped.  Bad files raise :class:`InputError` naming the file.
    """
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{what} {p}: cannot read: {exc}") from None
    rows = list(csv.reader(io.StringIO(text)))
    rows = [r for r in rows if r and any(c.strip() for c in r)]
    if len(rows) < 2:
        raise InputError(f"{what} {p}: expected a header row and at least one data row")
    header = [h.strip() for h in rows[0]]
    if len(set(header)) != len(header):
        raise InputError(f"{what} {p}: duplicate column names in the header")
    data = np.full((len(rows) - 1, len(header)), np.nan)
    for i, r in enumerate(rows[1:]):
        for j, cell in enumerate(r[: len(header)]):
            try:
                data[i, j] = float(cell)
            except ValueError:
                pass
    out = {}
    for j, h in enumerate(header):
        if np.any(np.isfinite(data[:, j])):
            out[h] = data[:, j]
    return out


def read_log(path: str | Path, what: str = "log") -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """A logged run: its time column (``time`` or ``t``, increasing) and the other columns."""
    cols = read_csv_columns(path, what)
    tname = "time" if "time" in cols else ("t" if "t" in cols else None)
    if tname is None:
        raise InputError(f"{what} {path}: no time column (expected 'time' or 't'; found {', '.join(cols) or 'none'})")
    t = cols.pop(tname)
    ok = np.isfinite(t)
    t = t[ok]
    cols = {k: v[ok] for k, v in cols.items()}
    if t.size < 4:
        raise InputError(f"{what} {path}: expected at least 4 timed rows, got {t.size}")
    if np.any(np.diff(t) <= 0):
        raise InputError(f"{what} {path}: the time column must strictly increase")
    return t, cols


def read_poses(path: str | Path, design, what: str) -> np.ndarray:
    """Poses of a ``csv`` trajectory: columns named after the motion's coordinates
    (``x,y[,z][,phi|rx,ry,rz]``; orientation optional), or a header-less table
    in that order."""
    p = Path(path)
    coords = list(design.motion.coords)
    pos = coords[: design.motion.dim]
    try:
        first = p.read_text(encoding="utf-8-sig").splitlines()[0] if p.exists() else None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{what}: cannot read {p}: {exc}") from None
    if first is None:
        raise InputError(f"{what}: no such file {p}")
    try:
        [float(c) for c in first.split(",") if c.strip()]
        has_header = False
    except ValueError:
        has_header = True
    if has_header:
        cols = read_csv_columns(p, what)
        missing = [c for c in pos if c not in cols]
        if missing:
            raise InputError(f"{what}: {p} lacks column(s) {', '.join(missing)} (expected {','.join(coords)})")
        use = coords if all(c in cols for c in coords) else pos
        arr = np.stack([cols[c] for c in use], axis=1)
    else:
        try:
            arr = np.loadtxt(p, delimiter=",", ndmin=2)
        except ValueError as exc:
            raise InputError(f"{what}: {p}: {exc}") from None
        if arr.shape[1] not in (len(pos), len(coords)):
            raise InputError(f"{what}: {p} has {arr.shape[1]} columns; expected {len(pos)} or {len(coords)} "
                             f"({','.join(coords)})")
    if not np.all(np.isfinite(arr)):
        raise InputError(f"{what}: {p} has empty or non-numeric cells")
    if arr.shape[0] < 2:
        raise InputError(f"{what}: {p} needs at least 2 poses, got {arr.shape[0]}")
    return arr


def trajectory_path_figure(design, samples, workspace_result=None):
    """The sampled path over the static workspace map (planar) or the frame (x-y projection).

    Feasible samples in blue, infeasible ones in red; corners marked; the
    robot drawn at the first pose.
    """
    plt = _plt()
    fig, ax = plt.subplots(figsize=(7.2, 6.4))
    fig.subplots_adjust(left=0.1, right=0.97, bottom=0.08, top=0.9)
    if workspace_result is not None and design.motion.planar:
        feas = workspace_result.feasible_map.astype(float)
        from matplotlib.colors import ListedColormap

        ax.imshow(feas.T, origin="lower", extent=_extent(workspace_result.map_axes),
                  cmap=ListedColormap([(0.88, 0.88, 0.88), (0.80, 0.93, 0.80)]), vmin=0, vmax=1,
                  interpolation="nearest", aspect="equal", zorder=1)
        ax.plot([], [], "s", color=(0.80, 0.93, 0.80), label="static workspace")
    _frame_rect(ax, design)
    _draw_robot(ax, design, samples.pose[0])
    p = samples.pose
    ax.plot(p[:, 0], p[:, 1], "-", color="tab:blue", lw=1.6, zorder=7, label="path")
    bad = ~samples.feasible
    if bad.any():
        ax.plot(p[bad, 0], p[bad, 1], ".", color="tab:red", ms=3, zorder=8, label="infeasible tensions")
    ends = [s.last for s in samples.segments if s.kind != "arc"]
    if ends:
        ax.plot(p[ends, 0], p[ends, 1], "o", mfc="white", mec="tab:blue", ms=5, zorder=9, label="waypoints")
    _pad_limits(ax, design)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    s = samples.summary()
    ax.set_title(f"{design.name}: trajectory {samples.name} — {s['duration']:.3g} s, peak "
                 f"{s['max_speed']:.3g} m/s, {s['max_acceleration']:.3g} m/s²"
                 + ("" if samples.all_feasible else f"\n{s['infeasible_samples']} infeasible samples"),
                 fontsize=10)
    ax.legend(loc="lower right", fontsize=8, framealpha=0.9)
    return fig


def trajectory_axes_figure(samples):
    """Axis set-points over time: pose, cable lengths, cable speeds, motor angles, tensions."""
    plt = _plt()
    fig, axs = plt.subplots(5, 1, figsize=(8, 10.5), sharex=True)
    fig.subplots_adjust(left=0.11, right=0.97, bottom=0.05, top=0.95, hspace=0.12)
    t = samples.time
    for j, c in enumerate(samples.coords):
        axs[0].plot(t, samples.pose[:, j], label=c)
    axs[0].set_ylabel("pose [m, rad]")
    for data, ax, lab in ((samples.lengths, axs[1], "length [m]"), (samples.cable_speed, axs[2], "cable speed [m/s]"),
                          (samples.motor_angle, axs[3], "motor angle [rad]"), (samples.tensions, axs[4], "tension [N]")):
        for i, c in enumerate(samples.cable_names):
            ax.plot(t, data[:, i], label=c)
        ax.set_ylabel(lab)
    for ax in axs:
        ax.grid(alpha=0.3)
        ax.legend(loc="upper right", fontsize=7, ncol=4)
    axs[-1].set_xlabel("time [s]")
    fig.suptitle(f"trajectory {samples.name}: set-points every {1000 * samples.cycle_time:g} ms", fontsize=10)
    return fig


def simulation_figure(result):
    """Target against simulated run: position, position error, cable tensions over time."""
    plt = _plt()
    fig, axs = plt.subplots(3, 1, figsize=(8, 8.5), sharex=True)
    fig.subplots_adjust(left=0.11, right=0.97, bottom=0.06, top=0.93, hspace=0.12)
    t = result.time
    npos = sum(1 for c in result.coords if c in ("x", "y", "z"))
    for j in range(npos):
        c = result.coords[j]
        line, = axs[0].plot(t, result.target_pose[:, j], "--", lw=1.0, label=f"{c} target")
        axs[0].plot(t, result.pose[:, j], "-", color=line.get_color(), lw=1.4, label=c)
    axs[0].set_ylabel("position [m]")
    err_ = np.linalg.norm(result.pose[:, :npos] - result.target_pose[:, :npos], axis=1)
    axs[1].plot(t, 1000 * err_, color="tab:red")
    axs[1].set_ylabel("position error [mm]")
    for i, c in enumerate(result.cable_names):
        axs[2].plot(t, result.tensions[:, i], label=c)
    axs[2].set_ylabel("tension [N]")
    axs[2].set_xlabel("time [s]")
    for ax in axs:
        ax.grid(alpha=0.3)
    axs[0].legend(loc="upper right", fontsize=7, ncol=3)
    axs[2].legend(loc="upper right", fontsize=7)
    st = result.settings
    fig.suptitle(f"simulation of {result.name}: delay {1000 * st.get('delay', 0):g} ms, servo bandwidth "
                 f"{st.get('servo_bandwidth', float('nan')):g} rad/s", fontsize=10)
    return fig


def save_figures(out: OutputDir, figures: dict) -> list[Path]:
    """Save {name: figure} as PNGs (atomic) and close them."""
    plt = _plt()
    paths = []
    for name, fig in figures.items():
        try:
            paths.append(out.save_figure(name, fig))
        finally:
            plt.close(fig)
    return paths


# ----------------------------------------------------------------------------
# Parameter sweeps (sweep): journal, sweep.csv, pictures
# ----------------------------------------------------------------------------


class SweepJournal:
    """The append-only journal of a sweep (``sweep.journal.jsonl`` in the output folder).

    Line 1 is a JSON object naming the sweep (``fingerprint``); every further
    line is one finished variant (:func:`cdpr_design.batch.sweep.record`), appended
    and flushed as it finishes, so an interrupted sweep loses at most the
    variants in flight.  A torn last line (the process was killed while
    writing it) is dropped when the journal is read back.
    """

    NAME = "sweep.journal.jsonl"

    def __init__(self, out: OutputDir, name: str | None = None):
        self.out = out
        self.name = name or self.NAME
        self.path = out.path / self.name
        self.fh = None

    def read(self) -> tuple[dict | None, list[dict]]:
        """(meta, records) of the journal on disk; (None, []) when there is none."""
        try:
            text = self.path.read_text(encoding="utf-8")
        except FileNotFoundError:
            return None, []
        except (OSError, UnicodeDecodeError) as exc:
            raise InputError(f"--resume: cannot read {self.path}: {exc}") from None
        lines = text.split("\n")
        meta, records = None, []
        for k, line in enumerate(lines):
            if not line.strip():
                continue
            try:
                obj = json.loads(line)
            except json.JSONDecodeError:
                if k >= len(lines) - 2:  # the last line, torn by a kill
                    break
                raise InputError(f"--resume: {self.path} line {k + 1} is not a journal line") from None
            if meta is None:
                if not isinstance(obj, dict) or obj.get("journal") != "cdpr-design sweep":
                    raise InputError(f"--resume: {self.path} is not a sweep journal")
                meta = obj
            elif isinstance(obj, dict) and "variant" in obj:
                records.append(obj)
        return meta, records

    def start(self, meta: dict, records: Sequence[dict] = ()) -> None:
        """Write the journal afresh (meta and the records kept), then keep it open for appending."""
        self.out.target(self.name)
        body = json.dumps(meta, sort_keys=True) + "\n" + "".join(
            json.dumps(r) + "\n" for r in records)
        write_text_atomic(self.path, body)
        self.out.wrote(self.name)
        self.fh = open(self.path, "a", encoding="utf-8", newline="")

    def append(self, rec: dict) -> None:
        self.fh.write(json.dumps(rec) + "\n")
        self.fh.flush()

    def close(self) -> None:
        if self.fh is not None:
            self.fh.flush()
            try:
                os.fsync(self.fh.fileno())
            except OSError:
                pass
            self.fh.close()
            self.fh = None


def read_csv_table(path: str | Path, what: str = "--check-against") -> tuple[list[str], list[list[str]]]:
    """(header, rows) of a CSV file, cells as text; bad files raise :class:`InputError`."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{what}: cannot read {p}: {exc}") from None
    rows = [r for r in csv.reader(io.StringIO(text)) if r]
    if not rows:
        raise InputError(f"{what}: {p} is empty (expected a header row)")
    return rows[0], rows[1:]


def _cells(rows):
    return [[fmt(v) for v in r] for r in rows]


def sweep_text_rows(header, rows) -> list[list[str]]:
    """The CSV cells of a sweep table (the text ``sweep.csv`` holds)."""
    return _cells(rows)


_FIG_LABELS = {
    "fraction": "feasible fraction", "min_margin_figure": "capacity margin [N]\n(task box)",
    "peak_tension": "peak tension [N]", "peak_motor_torque": "peak motor torque [N m]",
    "torque_margin": "torque margin (≥ 1 passes)", "speed_margin": "speed margin (≥ 1 passes)",
    "measure": "feasible measure", "task_min_margin": "task min margin [N]",
}


def _axis_values(header, rows, key):
    j = header.index(key)
    vals = [r[j] for r in rows]
    try:
        num = [float(v) for v in vals]
        return num, None
    except (TypeError, ValueError):
        labels = []
        for v in vals:
            s = str(v)
            if s not in labels:
                labels.append(s)
        return [labels.index(str(v)) for v in vals], labels


def _figure_column(header, rows, name):
    if name not in header:
        return None
    j = header.index(name)
    out = []
    for r in rows:
        v = r[j]
        try:
            x = float(v) if v not in (None, "") else math.nan
        except (TypeError, ValueError):
            x = math.nan
        out.append(x)
    return np.array(out, dtype=float)


def _passing(header, rows):
    ip = header.index("checks_passed") if "checks_passed" in header else None
    ie = header.index("error")
    return np.array([(not r[ie]) and ip is not None and r[ip] in (True, 1, "1") for r in rows], dtype=bool)


def sweep_figure(header: list[str], rows: list[list], keys: Sequence[str], title: str = "",
                 figures: Sequence[str] | None = None, rank_by: str | None = None):
    """Headline figures against the varied keys.

    One key: each figure against it (line plots, passing variants green,
    failing red crosses, failed evaluations as gaps).  Two keys: a heat map
    per figure (failing cells marked ×).  More: a parallel-coordinates view of
    the varied keys and the figures, lines coloured by ``rank_by``, variants
    failing a requirement in grey.
    """
    from cdpr_design.batch import sweep as sw

    plt = _plt()
    figs = [f for f in (figures or sw.HEADLINE) if f in header]
    if not figs:
        figs = [h for h in header if h not in keys and h not in ("variant", "error")][:1]
    ok = _passing(header, rows)
    n = len(figs)
    if len(keys) == 1:
        x, labels = _axis_values(header, rows, keys[0])
        x = np.array(x, dtype=float)
        order = np.argsort(x, kind="stable")
        ncol = min(3, n)
        nrow = math.ceil(n / ncol)
        fig, axs = plt.subplots(nrow, ncol, figsize=(4.3 * ncol, 3.4 * nrow + 0.7), squeeze=False)
        fig.subplots_adjust(left=0.08, right=0.98, bottom=0.12, top=0.86, wspace=0.35, hspace=0.5)
        for k, ax in enumerate(axs.flat):
            if k >= n:
                ax.axis("off")
                continue
            y = _figure_column(header, rows, figs[k])
            ax.plot(x[order], y[order], "-", color="0.5", lw=1.0, zorder=1)
            ax.plot(x[ok], y[ok], "o", ms=4, color="tab:green", label="passes", zorder=2)
            ax.plot(x[~ok], y[~ok], "x", ms=5, color="tab:red", label="fails a requirement", zorder=2)
            ax.set_ylabel(_FIG_LABELS.get(figs[k], figs[k]), fontsize=8)
            ax.set_xlabel(keys[0], fontsize=8)
            ax.tick_params(labelsize=7)
            if labels is not None:
                ax.set_xticks(range(len(labels)), labels, rotation=30, fontsize=7)
            ax.grid(alpha=0.3)
            if k == 0:
                ax.legend(fontsize=7)
    elif len(keys) == 2:
        x, xl = _axis_values(header, rows, keys[1])
        y, yl = _axis_values(header, rows, keys[0])
        xs, ys = sorted(set(x)), sorted(set(y))
        xi = {v: i for i, v in enumerate(xs)}
        yi = {v: i for i, v in enumerate(ys)}
        ncol = min(3, n)
        nrow = math.ceil(n / ncol)
        fig, axs = plt.subplots(nrow, ncol, figsize=(4.6 * ncol, 3.9 * nrow + 0.7), squeeze=False)
        fig.subplots_adjust(left=0.08, right=0.97, bottom=0.1, top=0.86, wspace=0.45, hspace=0.5)
        for k, ax in enumerate(axs.flat):
            if k >= n:
                ax.axis("off")
                continue
            col = _figure_column(header, rows, figs[k])
            img = np.full((len(ys), len(xs)), np.nan)
            fail = np.zeros_like(img, dtype=bool)
            for r in range(len(rows)):
                img[yi[y[r]], xi[x[r]]] = col[r]
                fail[yi[y[r]], xi[x[r]]] = not ok[r]
            cmap = plt.get_cmap("viridis").with_extremes(bad=(0.85, 0.85, 0.85, 1.0))
            im = ax.imshow(np.ma.masked_invalid(img), origin="lower", aspect="auto", cmap=cmap,
                           interpolation="nearest")
            fy, fx = np.nonzero(fail)
            ax.plot(fx, fy, "x", color="tab:red", ms=5, mew=1.2, label="fails a requirement")
            for axis, vals, lab in ((ax.set_xticks, xs, xl), (ax.set_yticks, ys, yl)):
                step = max(1, math.ceil(len(vals) / 8))
                pos = list(range(0, len(vals), step))
                axis(pos, [(lab[int(vals[p])] if lab is not None else f"{vals[p]:.4g}") for p in pos], fontsize=7)
            ax.set_xlabel(keys[1], fontsize=8)
            ax.set_ylabel(keys[0], fontsize=8)
            ax.set_title(_FIG_LABELS.get(figs[k], figs[k]).replace("\n", " "), fontsize=9)
            fig.colorbar(im, ax=ax, shrink=0.85)
            ax.set_xlim(-0.5, len(xs) - 0.5)
            ax.set_ylim(-0.5, len(ys) - 0.5)
    else:
        cols = list(keys) + figs
        data = []
        ticks = []
        for c in cols:
            if c in keys:
                v, lab = _axis_values(header, rows, c)
                v = np.array(v, dtype=float)
            else:
                v, lab = _figure_column(header, rows, c), None
            lo, hi = np.nanmin(v) if np.isfinite(v).any() else 0.0, np.nanmax(v) if np.isfinite(v).any() else 1.0
            span = hi - lo if hi > lo else 1.0
            data.append((v - lo) / span)
            ticks.append((lo, hi, lab))
        data = np.array(data)
        fig, ax = plt.subplots(figsize=(max(8.0, 1.4 * len(cols)), 5.2))
        fig.subplots_adjust(left=0.06, right=0.9, bottom=0.2, top=0.86)
        rank = _figure_column(header, rows, rank_by) if rank_by else None
        cmap = plt.get_cmap("viridis")
        xs = np.arange(len(cols))
        good = rank[ok] if rank is not None else np.array([])
        rlo = np.nanmin(good) if np.isfinite(good).any() else 0.0
        rhi = np.nanmax(good) if np.isfinite(good).any() else 1.0
        for r in np.argsort(ok, kind="stable"):  # failing first, passing on top
            yv = data[:, r]
            if ok[r] and rank is not None and np.isfinite(rank[r]):
                colr = cmap((rank[r] - rlo) / (rhi - rlo) if rhi > rlo else 0.5)
                ax.plot(xs, yv, "-", color=colr, lw=1.2, alpha=0.9, zorder=3)
            else:
                ax.plot(xs, yv, "-", color="0.75" if not ok[r] else "tab:green", lw=0.8, alpha=0.6, zorder=2)
        for k, (lo, hi, lab) in enumerate(ticks):
            ax.axvline(k, color="k", lw=0.8, zorder=1)
            top = lab[-1] if lab is not None else f"{hi:.4g}"
            bottom = lab[0] if lab is not None else f"{lo:.4g}"
            ax.text(k, 1.03, top, ha="center", fontsize=7)
            ax.text(k, -0.06, bottom, ha="center", va="top", fontsize=7)
        ax.set_xticks(xs, [c if c in keys else _FIG_LABELS.get(c, c).replace("\n", " ") for c in cols],
                      rotation=25, ha="right", fontsize=8)
        ax.set_yticks([])
        ax.set_ylim(-0.1, 1.1)
        ax.set_xlim(-0.3, len(cols) - 0.7)
        for s in ("top", "right", "left"):
            ax.spines[s].set_visible(False)
        if rank is not None and rank_by:
            from matplotlib.cm import ScalarMappable
            from matplotlib.colors import Normalize

            sm = ScalarMappable(norm=Normalize(rlo, rhi if rhi > rlo else rlo + 1), cmap=cmap)
            fig.colorbar(sm, ax=ax, shrink=0.8, label=f"{rank_by} (variants passing every requirement; grey: failing)")
    npass = int(ok.sum())
    fig.suptitle((title + "\n" if title else "") +
                 f"{len(rows)} variants, {npass} pass every requirement", fontsize=10)
    return fig


def write_sweep(out: OutputDir, header: list[str], rows: list[list], best_header: list[str],
                best_rows: list[list], keys: Sequence[str], title: str = "",
                rank_by: str | None = None, picture: bool = True) -> list[Path]:
    """``sweep.csv``, ``sweep_best.csv`` and ``sweep.png`` (atomically)."""
    paths = [out.write_csv("sweep.csv", header, rows), out.write_csv("sweep_best.csv", best_header, best_rows)]
    if picture and rows:
        plt = _plt()
        fig = sweep_figure(header, rows, keys, title=title, rank_by=rank_by)
        try:
            paths.append(out.save_figure("sweep.png", fig))
        finally:
            plt.close(fig)
    return paths


# ----------------------------------------------------------------------------
# Orientation workspaces (workspace --orientations total|range)
# ----------------------------------------------------------------------------


def orientation_figure(result):
    """Orientation workspace picture: the fraction of the orientation set that is
    feasible (``total``; the total orientation workspace outlined) or the
    orientation range scale s (``range``: the largest feasible box is
    nominal +- s * max) over the grid; a z-slice stack for spatial motions."""
    plt = _plt()
    d = result.design
    om = result.orientation_maps
    val = np.asarray(om.value, float)
    feas = result.feasible_map.astype(bool)
    rot = d.motion.rotation_coords
    if om.mode == "total":
        lo, hi = om.orientations.min(axis=0), om.orientations.max(axis=0)
        idx = [i - 3 for i in d.motion.pose_index[d.motion.dim:]]
        box = ", ".join(f"{c} ∈ [{np.degrees(lo[i]):.3g}°, {np.degrees(hi[i]):.3g}°]" for c, i in zip(rot, idx))
        title = (f"{d.name}: total orientation workspace ({result.kind}) — {100 * result.fraction:.1f} % "
                 f"of {result.poses:,} positions feasible for all {len(om.orientations)} orientations\n{box}")
        label = "fraction of the orientation set feasible"
        vmax = 1.0
    else:
        mx = ", ".join(f"{c} ± {np.degrees(s):.3g}°" for c, s in zip(rot, om.scale))
        title = (f"{d.name}: orientation range per position ({result.kind}) — largest feasible box "
                 f"s × ({mx})")
        label = "range scale s (grey: nominal orientation infeasible)"
        vmax = 1.0
    cmap = plt.get_cmap("cividis").with_extremes(bad=(0.85, 0.85, 0.85, 1.0))
    if d.motion.planar:
        fig, ax = plt.subplots(figsize=(7.5, 6.6))
        fig.subplots_adjust(left=0.09, right=0.97, bottom=0.08, top=0.88)
        im = ax.imshow(val.T, origin="lower", extent=_extent(result.map_axes), cmap=cmap, vmin=0.0,
                       vmax=vmax, interpolation="nearest", aspect="equal", zorder=1)
        if om.mode == "total" and feas.any():
            ax.contour(result.map_axes[0], result.map_axes[1], feas.T.astype(float), levels=[0.5],
                       colors="k", linewidths=0.8, zorder=2)
        _frame_rect(ax, d)
        ax.plot(d.outlets[:, 0], d.outlets[:, 1], "v", ms=7, mfc="tab:red", mec="k", zorder=5)
        _pad_limits(ax, d)
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        fig.colorbar(im, ax=ax, shrink=0.85, label=label)
        ax.set_title(title, fontsize=9)
        return fig
    zs = _slices(result)
    ncol = min(3, len(zs))
    nrow = math.ceil(len(zs) / ncol)
    fig, axs = plt.subplots(nrow, ncol, figsize=(4.6 * ncol, 4.2 * nrow + 0.9), squeeze=False)
    fig.subplots_adjust(left=0.07, right=0.88, bottom=0.08, top=0.86, wspace=0.3, hspace=0.35)
    ext = _extent(result.map_axes[:2])
    im = None
    for k, ax in enumerate(axs.flat):
        if k >= len(zs):
            ax.axis("off")
            continue
        iz = zs[k]
        im = ax.imshow(val[:, :, iz].T, origin="lower", extent=ext, cmap=cmap, vmin=0.0, vmax=vmax,
                       interpolation="nearest", aspect="equal")
        _frame_rect(ax, d)
        ax.plot(d.outlets[:, 0], d.outlets[:, 1], "v", ms=6, mfc="tab:red", mec="k")
        _pad_limits(ax, d)
        ax.set_title(f"z = {result.map_axes[2][iz]:.3g} m  ({100 * feas[:, :, iz].mean():.0f} % feasible)",
                     fontsize=9)
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
    fig.colorbar(im, ax=axs.ravel().tolist(), shrink=0.8, label=label)
    fig.suptitle(title, fontsize=9)
    return fig


def save_orientation_picture(out: OutputDir, result) -> Path:
    """``orientation_workspace.png`` of an orientation sweep (:func:`orientation_figure`)."""
    plt = _plt()
    fig = orientation_figure(result)
    try:
        return out.save_figure("orientation_workspace.png", fig)
    finally:
        plt.close(fig)
