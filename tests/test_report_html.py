"""report.html (self-contained, the design named, interactive figures with their JSON valid) and
the commands' --format parquet tables against their CSV."""

from __future__ import annotations

import json
from html.parser import HTMLParser

import numpy as np
import pytest

from cdpr_design.io.columns import read_table, table_metadata
from cdpr_design.io.tables import fmt

from .helpers import DESIGNS, PLANAR2, invoke

_VOID = {"meta", "br", "img", "input", "link", "hr", "col", "area", "base", "embed", "source", "track", "wbr"}


class _Page(HTMLParser):
    """Checks that tags nest and close; collects the figure JSON blocks and script sources."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.stack, self.errors, self.figures, self.sources, self.text = [], [], {}, [], []
        self._figure = None

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "script":
            if "src" in a:
                self.sources.append(a["src"])
            self._figure = a.get("data-figure") if a.get("type") == "application/json" else None
        if tag not in _VOID:
            self.stack.append(tag)

    def handle_endtag(self, tag):
        if not self.stack or self.stack[-1] != tag:
            self.errors.append(f"</{tag}> closes {self.stack[-1:] or 'nothing'}")
            return
        self.stack.pop()
        self._figure = None

    def handle_data(self, data):
        if self._figure is not None:
            self.figures[self._figure] = json.loads(data)
        elif self.stack and self.stack[-1] != "script":
            self.text.append(data)


def parse_page(path):
    text = path.read_text(encoding="utf-8")
    page = _Page()
    page.feed(text)
    page.close()
    assert not page.errors, page.errors[:5]
    assert page.stack == [], page.stack
    assert text.startswith("<!DOCTYPE html>")
    return text, page


def _check_self_contained(text: str, page: _Page) -> None:
    assert not page.sources  # every script inline: the page opens offline
    assert '<script src="http' not in text and "<script src='http" not in text
    assert "Plotly.newPlot" in text and len(text) > 3_000_000  # plotly.js itself is inlined


def test_planar_workspace_html(tmp_path):
    r = invoke("workspace", PLANAR2, "--step", "0.02", "--out", tmp_path, "--html", "--quiet")
    assert r.exit_code == 0, r.output
    text, page = parse_page(tmp_path / "report.html")
    _check_self_contained(text, page)
    assert "<title>planar2" in text and "<h1>planar2</h1>" in text
    assert set(page.figures) == {"workspace", "tensions"}
    ws = page.figures["workspace"]
    heat = [t for t in ws["data"] if t["type"] == "heatmap"]
    assert len(heat) == 2  # infeasible (grey) and feasible (margin) cells
    summary = json.loads((tmp_path / "summary.json").read_text())
    nx, ny = summary["grid"]["shape"]
    feasible_cells = 0
    for t in heat:
        z = np.array(t["z"], dtype=float)
        assert z.shape == (ny, nx) and len(t["x"]) == nx and len(t["y"]) == ny
        assert np.array(t["customdata"], dtype=float).shape == (ny, nx, 2)  # both cables' tensions
        assert "margin" in t["hovertemplate"] and "T c1" in t["hovertemplate"] and "x = " in t["hovertemplate"]
        feasible_cells += int(np.isfinite(z).sum()) if t["name"] == "feasible" else 0
    assert feasible_cells == summary["feasible"]
    assert ws["layout"]["xaxis"]["title"]["text"] == "x [m]"
    ten = page.figures["tensions"]
    assert [t["name"] for t in ten["data"]] == ["c1", "c2"]
    assert "Summary" in "".join(page.text)


def test_spatial_workspace_html_holds_3d_points(tmp_path):
    r = invoke("workspace", DESIGNS / "ipanema3.yaml", "--step", "0.6", "--out", tmp_path, "--html", "--quiet")
    assert r.exit_code == 0, r.output
    text, page = parse_page(tmp_path / "report.html")
    _check_self_contained(text, page)
    assert "<h1>ipanema3</h1>" in text
    pts = [t for t in page.figures["workspace"]["data"] if t["name"] == "feasible poses"][0]
    assert pts["type"] == "scatter3d"
    n = len(pts["x"])
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert n == len(pts["y"]) == len(pts["z"]) == len(pts["marker"]["color"]) == summary["feasible"] > 0
    hover = np.array(pts["customdata"], dtype=float)
    assert hover.shape == (n, 9)  # the margin, then the 8 tensions
    np.testing.assert_allclose(hover[:, 0], pts["marker"]["color"])
    assert min(pts["marker"]["color"]) >= 0  # feasible: margin >= 0
    assert "z = " in pts["hovertemplate"] and "T c8" in pts["hovertemplate"]
    assert page.figures["workspace"]["layout"]["scene"]["zaxis"]["title"]["text"] == "z [m]"
    assert len(page.figures["tensions"]["data"]) == 8


def test_report_command_writes_the_page_with_sizing_and_checks(tmp_path):
    r = invoke("report", PLANAR2, "--step", "0.05", "--out", tmp_path, "--json")
    assert r.exit_code == 0, r.output
    out = json.loads(r.stdout)
    assert set(out["timings"]) == {"load_s", "sweep_s", "write_s", "pictures_s", "total_s"}
    text, page = parse_page(tmp_path / "report.html")
    _check_self_contained(text, page)
    body = " ".join(page.text)
    assert "Motor sizing" in body and "AM8112-0F21-EL7211" in body
    assert "Requirement checks" in body and "min_margin" in body
    assert ("FAIL" in body) == (not all(c["passed"] for c in out["checks"]))
    assert json.loads((tmp_path / "report.json").read_text())["timings"]["total_s"] > 0


#: Chromium as a headless test browser: no sandbox (CI runs as root), nothing fetched on its own.
BROWSER_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                "--disable-component-update", "--disable-sync", "--no-first-run"]
#: Where a system's package manager puts Chromium (Debian: ``apt-get install chromium``).
SYSTEM_BROWSERS = ["/usr/bin/chromium", "/usr/bin/chromium-browser", "/usr/bin/google-chrome"]


def _browser(sync_api_module, p):
    """A launched Chromium: playwright's own, else a system one.  None found: under ``CI=true`` the
    test fails (CI installs one: .ci/run), elsewhere it is skipped with the reason."""
    import os
    import shutil

    tried = []
    for path in [None] + [b for b in SYSTEM_BROWSERS + [shutil.which("chromium")] if b and os.path.exists(b)]:
        try:
            return p.chromium.launch(args=BROWSER_ARGS, **({"executable_path": path} if path else {}))
        except Exception as exc:  # noqa: BLE001 - not installed, or not startable here
            tried.append(f"{path or 'playwright’s own'}: {str(exc).splitlines()[0] if str(exc) else exc!r}")
    reason = "no browser can be started here: " + "; ".join(tried)
    if os.environ.get("CI", "").lower() == "true":
        pytest.fail(reason)
    pytest.skip(reason)


def _playwright():
    import os

    try:
        from playwright import sync_api
    except ImportError as exc:  # the test extra installs it
        if os.environ.get("CI", "").lower() == "true":
            pytest.fail(f"playwright is not installed: {exc}")
        pytest.skip(f"playwright is not installed: {exc}")
    return sync_api


def _overlap(a, b, slack: float = 0.5) -> bool:
    return (a["x"] + slack < b["x"] + b["width"] and b["x"] + slack < a["x"] + a["width"]
            and a["y"] + slack < b["y"] + b["height"] and b["y"] + slack < a["y"] + a["height"])


def _inside(a, box, slack: float = 0.5) -> bool:
    return (a["x"] >= box["x"] - slack and a["y"] >= box["y"] - slack
            and a["x"] + a["width"] <= box["x"] + box["width"] + slack
            and a["y"] + a["height"] <= box["y"] + box["height"] + slack)


#: The page's layout as the browser lays it out: the boxes of the body's blocks, and of each figure
#: its box, its drawing's and those of its texts (titles, axis titles, tick labels, panel titles).
_LAYOUT_JS = """() => {
  const box = el => { const r = el.getBoundingClientRect();
                      return {x: r.x, y: r.y + window.scrollY, width: r.width, height: r.height}; };
  const named = (el, kind) => Object.assign(box(el), {kind: kind, text: el.textContent.trim().slice(0, 40)});
  const blocks = [...document.body.children]  // the page's flow (not plotly's off-page measuring helpers)
                 .filter(el => el.tagName !== 'SCRIPT' && getComputedStyle(el).position === 'static')
                 .map(el => Object.assign(box(el), {tag: el.tagName, id: el.id}));
  const figures = [...document.querySelectorAll('div.figure')].map(div => {
    const svg = div.querySelector('.main-svg');
    const texts = [];
    for (const [sel, kind] of [['.gtitle', 'title'], ['.annotation-text', 'panel title'],
                               ['.g-xtitle text', 'x title'], ['.g-ytitle text', 'y title'],
                               ['.xtick text', 'tick'], ['.ytick text', 'tick'], ['.legendtext', 'legend'],
                               ['.cbtitle text', 'colour bar title']]) {
      for (const el of div.querySelectorAll(sel)) { if (el.textContent.trim()) texts.push(named(el, kind)); }
    }
    const scene = div.querySelector('.gl-container > div');
    return {id: div.id, box: box(div), svg: svg ? box(svg) : null, texts: texts, scene: scene ? box(scene) : null};
  });
  return {blocks: blocks, figures: figures};
}"""


def _layout_problems(layout) -> list[str]:
    """What a reader would see wrong: blocks of the page drawn over each other, a figure cut off by
    its box or leaving a blank band in it, texts of a figure over each other or outside it."""
    out = []
    blocks = layout["blocks"]
    for a, b in zip(blocks, blocks[1:]):
        if b["y"] < a["y"] + a["height"] - 1:
            out.append(f"{b['tag']}#{b['id']} starts {a['y'] + a['height'] - b['y']:.0f} px inside the "
                       f"{a['tag']}#{a['id']} above it")
    for f in layout["figures"]:
        if f["svg"] is None:
            out.append(f"#{f['id']} has no drawing")
            continue
        if abs(f["svg"]["height"] - f["box"]["height"]) > 2:
            out.append(f"#{f['id']}: its drawing is {f['svg']['height']:.0f} px tall in a box of "
                       f"{f['box']['height']:.0f} px (cut off, or a blank band)")
        texts = f["texts"]
        for t in texts:
            if not _inside(t, f["box"]):
                out.append(f"#{f['id']}: {t['kind']} '{t['text']}' reaches outside the figure")
        for i, a in enumerate(texts):
            for b in texts[i + 1:]:
                if "tick" in (a["kind"], b["kind"]) and a["kind"] == b["kind"]:
                    continue  # tick labels of two axes may meet at a corner
                if _overlap(a, b):
                    out.append(f"#{f['id']}: {a['kind']} '{a['text']}' overlaps {b['kind']} '{b['text']}'")
    return out


def _scene_cut_off(page, figure) -> str | None:
    """A 3-D view drawn past the edge of its scene (WebGL: no element boxes inside it): the scene's
    outermost pixel rows and columns must all be background."""
    import io

    from PIL import Image

    s = figure["scene"]
    if s is None:
        return None
    png = page.screenshot(full_page=True, clip={"x": s["x"], "y": s["y"], "width": s["width"], "height": s["height"]})
    img = np.asarray(Image.open(io.BytesIO(png)).convert("L"), dtype=float)
    edges = {"top": img[:3], "bottom": img[-3:], "left": img[:, :3], "right": img[:, -3:]}
    cut = [side for side, px in edges.items() if (px < 200).mean() > 0.002]
    return f"#{figure['id']}: the 3-D view is cut off at its {', '.join(cut)} edge" if cut else None


@pytest.mark.slow
@pytest.mark.parametrize("command, design, args", [
    ("workspace", "planar2", ["--step", "0.01", "--html"]),
    ("report", "ipanema3", []),
])
def test_report_renders_in_a_real_browser_offline_and_nothing_overlaps(tmp_path, command, design, args):
    """In a real Chromium, offline: the page draws its figures with every network request refused and no
    script error, and as laid out nothing is drawn over anything else or cut off (the element boxes
    of the page's blocks and of every text of the figures; the 3-D view's edge pixels).  Was: the
    tension grid's panel titles over the axis titles of the row above, the tension grid spilling over
    the motor-sizing heading, the 3-D view cut off at the bottom, a blank band under planar2's maps."""
    sync_api = _playwright()
    r = invoke(command, DESIGNS / f"{design}.yaml", *args, "--out", tmp_path, "--quiet")
    assert r.exit_code == 0, r.output
    with sync_api.sync_playwright() as p:
        browser = _browser(sync_api, p)
        try:
            page = browser.new_page(viewport={"width": 1200, "height": 900})
            errors, requests = [], []
            page.on("pageerror", lambda exc: errors.append(exc))
            page.route("**/*", lambda route: route.continue_() if route.request.url.startswith("file:")
                       else (requests.append(route.request.url), route.abort()))
            page.goto((tmp_path / "report.html").as_uri())
            page.wait_for_selector("#workspace .main-svg", timeout=60_000)
            page.wait_for_selector("#tensions .main-svg", timeout=60_000)
            page.wait_for_timeout(1000)  # the WebGL scene's first frame
            page.screenshot(path=str(tmp_path / "page.png"), full_page=True)
            layout = page.evaluate(_LAYOUT_JS)
            problems = _layout_problems(layout)
            problems += [p for p in (_scene_cut_off(page, f) for f in layout["figures"]) if p]
            text = page.inner_text("body")
        finally:
            browser.close()
    assert not errors and not requests, (errors, requests)
    assert {f["id"] for f in layout["figures"]} == {"workspace", "tensions"}
    assert not problems, problems
    assert "m^2" not in text and "m^3" not in text  # the page writes m² and m³, as its figures do
    if design == "ipanema3":  # the tension maps say which slice they show
        assert "minimum-norm cable tensions [N] in the slice z =" in text


def test_unknown_format_is_refused():
    r = invoke("workspace", PLANAR2, "--format", "xlsx")
    assert r.exit_code == 2 and "--format" in r.output


# ----------------------------------------------------------------------------
# --format parquet against the CSV of the same command
# ----------------------------------------------------------------------------


def _same_table(csv_path, pq_path):
    a, b = read_table(csv_path), read_table(pq_path)
    assert list(a) == list(b)
    n = len(next(iter(a.values())))
    for k in a:
        assert len(b[k]) == n, k
        if a[k].dtype.kind == "f" and b[k].dtype.kind in "biuf":
            np.testing.assert_allclose(a[k], b[k].astype(float), rtol=1e-9, atol=1e-300, err_msg=k)
        else:  # text in Parquet (cells of mixed kinds, joined values): the CSV's cells
            want = [fmt(v) for v in a[k]]
            got = [fmt(v) for v in b[k]]
            assert got == want, k
    return a, b


@pytest.mark.slow
@pytest.mark.parametrize("design,extra", [("planar2", ["--step", "0.05"]),
                                          ("ipanema3", ["--step", "0.8", "--collisions"]),
                                          ("planar4", ["--step", "0.2", "--orientations", "range"])])
def test_workspace_parquet_round_trip(tmp_path, design, extra):
    spec_path = DESIGNS / f"{design}.yaml"
    for fmt_ in ("csv", "parquet"):
        r = invoke("workspace", spec_path, *extra, "--out", tmp_path / fmt_, "--format", fmt_, "--quiet")
        assert r.exit_code == 0, r.output
    assert not (tmp_path / "parquet" / "workspace.csv").exists()
    a, b = _same_table(tmp_path / "csv" / "workspace.csv", tmp_path / "parquet" / "workspace.parquet")
    summary = json.loads((tmp_path / "parquet" / "summary.json").read_text())
    assert b["feasible"].dtype == bool and int(b["feasible"].sum()) == int(np.nansum(a["feasible"])) == \
        summary["feasible"]
    assert len(b["feasible"]) == summary["poses"]
    assert b["margin"].dtype == np.float64
    if "collision_free" in b:
        assert b["collision_free"].dtype == bool
    meta = table_metadata(tmp_path / "parquet" / "workspace.parquet")
    assert meta["name"] == design and meta["table"] == "workspace" and meta["kind"] == "static"
    assert meta["grid"] == summary["grid"] and meta["spec"].endswith(f"{design}.yaml")
    assert meta["units"]["margin"] == "N" and meta["units"]["tension_c1"] == "N"
    assert meta["units"]["length_c1"] == "m" and meta["units"]["x"] == "m"


@pytest.mark.slow
def test_sizing_trajectory_and_sweep_parquet(tmp_path):
    runs = {"motor_sizing": ["size-motors", PLANAR2, "--step", "0.05"],
            "trajectory": ["trajectory", PLANAR2, "square_fast", "--cycle-time", "0.02"],
            "sweep": ["sweep", PLANAR2, "--vary", "effector.mass=0.5,1", "--step", "0.1", "--workers", "1",
                      "--no-picture"]}
    for stem, args in runs.items():
        for fmt_ in ("csv", "parquet"):
            r = invoke(*args, "--out", tmp_path / fmt_, "--format", fmt_, "--json")
            assert r.exit_code == 0, r.output
            assert "timings" in json.loads(r.stdout)
        _same_table(tmp_path / "csv" / f"{stem}.csv", tmp_path / "parquet" / f"{stem}.parquet")
        assert table_metadata(tmp_path / "parquet" / f"{stem}.parquet")["name"] == "planar2"
    units = table_metadata(tmp_path / "parquet" / "trajectory.parquet")["units"]
    assert units["time"] == "s" and units["x_vel"] == "m/s" and units["cable_speed_c1"] == "m/s"
    assert read_table(tmp_path / "parquet" / "motor_sizing.parquet")["motor"].dtype == object


# ----------------------------------------------------------------------------
# Pictures a designer keeps: filled figures, units on every axis, submit()
# ----------------------------------------------------------------------------


def _map_axes(fig):
    """The axes holding a picture (not hidden, not the colour bar)."""
    return [ax for ax in fig.axes if ax.get_visible() and ax.axison and ax.images and ax.get_label() != "<colorbar>"]


def _assert_outer_labels(ax, maps):
    """``ax``'s column has x tick labels and ``x [m]`` on its lowest panel, its row y tick labels
    and ``y [m]`` on its leftmost one, both over the same limits as ``ax``."""
    pos = ax.get_position()
    col = [o for o in maps if abs(o.get_position().x0 - pos.x0) < 1e-6]
    row = [o for o in maps if abs(o.get_position().y0 - pos.y0) < 1e-6]
    low = min(col, key=lambda o: o.get_position().y0)
    left = min(row, key=lambda o: o.get_position().x0)
    assert low.get_xlabel().endswith("[m]") and left.get_ylabel().endswith("[m]")
    assert [t.get_text() for t in low.get_xticklabels() if t.get_visible() and t.get_text()]
    assert [t.get_text() for t in left.get_yticklabels() if t.get_visible() and t.get_text()]
    assert low.get_xlim() == ax.get_xlim() and left.get_ylim() == ax.get_ylim()


@pytest.mark.slow
@pytest.mark.parametrize("design,step,orient", [("planar2", 0.02, None), ("ipanema3", 0.6, None),
                                                ("planar4", 0.1, "range"), ("crane4", 0.25, None)])
def test_map_pictures_fill_their_figure_and_label_units(design, step, orient):
    """Every map picture of a workspace (the tilt map of a hanging design too, planar or spatial)."""
    from cdpr_design import workspaces as ws
    from cdpr_design.model import spec
    from cdpr_design.plots import workspace as wsplots
    import matplotlib.pyplot as plt
    from cdpr_design.plots.hanging import tilt_figure

    d = spec.load(DESIGNS / f"{design}.yaml")
    r = ws.run(d, ws.Analysis(orientations=orient), step=step)
    figures = [wsplots.workspace_figure(r), wsplots.tension_figure(r)]
    if orient:
        figures.append(wsplots.orientation_figure(r))
    if getattr(r, "hanging", None) is not None:
        figures.append(tilt_figure(r))
    for fig in figures:
        fig.canvas.draw()
        maps = _map_axes(fig)
        assert maps
        for ax in maps:  # panels share their axes: the outer ones carry the labels, with units
            _assert_outer_labels(ax, maps)
        bars = [ax for ax in fig.axes if ax not in maps and ax.get_visible() and ax.axison and ax.get_ylabel()]
        assert bars and all("[" in ax.get_ylabel() or "scale" in ax.get_ylabel() for ax in bars)
        # the drawn maps fill the figure: rows of panels leave no white band (the old tension map of
        # IPAnema 3 had 55 % of its height blank)
        rows = sorted({(round(ax.get_position().y0, 3), round(ax.get_position().y1, 3)) for ax in maps})
        filled = sum(y1 - y0 for y0, y1 in rows)
        assert filled > 0.6, (fig.get_suptitle(), filled)
        _assert_inside(fig)
        plt.close(fig)


def _assert_inside(fig) -> None:
    """Every tick label, label and title of ``fig``, drawn at the PNGs' resolution, lies inside it
    with at least 0.02 in (2 pixels) to spare: nothing cut at an edge."""
    from cdpr_design.plots._style import DPI

    fig.set_dpi(DPI)
    box = fig.get_tightbbox(fig.canvas.get_renderer())
    width, height = fig.get_size_inches()
    room = min(box.x0, box.y0, width - box.x1, height - box.y1)
    assert room >= 0.02, (box.bounds, width, height)


@pytest.mark.slow
@pytest.mark.parametrize("design,step", [("sagging40", 4.0), ("cogiro", 3.0)])
def test_the_cable_model_picture_lies_inside_its_figure(design, step):
    """Planar (a single panel) and spatial (z-slice panels, :func:`~cdpr_design.plots._frame.fit_width`)."""
    from cdpr_design import workspaces as ws
    from cdpr_design.jobs.workspace import cable_model_picture
    from cdpr_design.model import spec
    import matplotlib.pyplot as plt

    r = ws.run(spec.with_cable_model(spec.load(DESIGNS / f"{design}.yaml"), "sagging"), step=step)
    name, builder, args = cable_model_picture(r)
    fig = builder(*args)
    fig.canvas.draw()
    _assert_inside(fig)
    plt.close(fig)


@pytest.mark.slow
@pytest.mark.parametrize("design", ["cogiro", "crane4"])
def test_a_spatial_grid_of_one_z_level_keeps_its_titles_inside(design):
    """One z-slice makes a one-panel figure narrower than its title: the figure widens to the
    title, the legend (the cable-model picture) and the colour bar; the panel keeps its size."""
    from cdpr_design import workspaces as ws
    from cdpr_design.jobs.workspace import cable_model_picture
    from cdpr_design.model import spec
    from cdpr_design.plots import workspace as wsplots
    import matplotlib.pyplot as plt
    from cdpr_design.plots.hanging import tilt_figure
    from cdpr_design.model.design import Grid

    d = spec.load(DESIGNS / f"{design}.yaml")
    g = d.workspace.grid
    z = 0.5 * (g.lower[2] + g.upper[2])
    one = Grid((g.lower[0], g.lower[1], z), (g.upper[0], g.upper[1], z), (0.5, 0.5, 0.5))
    r = ws.run(d, grid=one)
    figures = [wsplots.workspace_figure(r), wsplots.tension_figure(r)]
    if getattr(r, "hanging", None) is not None:
        figures.append(tilt_figure(r))
    else:
        sag = ws.run(spec.with_cable_model(d, "sagging"), grid=one)
        name, builder, args = cable_model_picture(sag)
        figures.append(builder(*args))
    for fig in figures:
        fig.canvas.draw()
        _assert_inside(fig)
        assert fig.get_suptitle()
        plt.close(fig)


def test_fit_width_measures_what_reaches_furthest():
    """:func:`~cdpr_design.plots._frame.fit_width` measures the first labelled panel of the left
    column (all of them carry the same y ticks and label at the same x) and the colour bar's y
    axis and frame: on a figure of two rows of panels, that is where every panel's y axis and
    the whole colour bar (all its artists) end."""
    from cdpr_design import workspaces as ws
    from cdpr_design.model import spec
    from cdpr_design.plots import workspace as wsplots
    import matplotlib.pyplot as plt

    r = ws.run(spec.load(DESIGNS / "ipanema3.yaml"), step=0.5)
    for fig in (wsplots.tension_figure(r), wsplots.workspace_figure(r)):
        renderer = fig.canvas.get_renderer()
        cax = fig.axes[-1]
        labelled = [ax for ax in fig.axes[:-1] if ax.get_visible() and ax.get_ylabel()]
        assert len(labelled) >= 2
        x0 = [ax.yaxis.get_tightbbox(renderer).x0 for ax in labelled]
        assert x0 == pytest.approx([x0[0]] * len(x0), abs=1e-9)
        assert min(ax.get_tightbbox(renderer).x0 for ax in fig.axes[:-1] if ax.get_visible()) >= x0[0] - 1e-9
        whole = cax.get_tightbbox(renderer).x1
        assert whole == pytest.approx(max(cax.yaxis.get_tightbbox(renderer).x1,
                                          cax.get_window_extent(renderer).x1), abs=1e-9)
        plt.close(fig)


def test_a_colour_bar_with_long_tick_labels_widens_its_figure():
    """The colour bar's room is fixed; 7-digit tensions need more, and the figure grows by that."""
    from cdpr_design import workspaces as ws
    from cdpr_design.model import spec
    from cdpr_design.plots import workspace as wsplots
    import matplotlib.pyplot as plt

    r = ws.run(spec.load(DESIGNS / "planar2.yaml"), step=0.05)
    fig = wsplots.tension_figure(r)
    fig.canvas.draw()
    width = fig.get_figwidth()
    _assert_inside(fig)
    panels = [ax.get_position().width * width for ax in fig.axes[:-1]]
    r.tension_maps = r.tension_maps * 1e4
    big = wsplots.tension_figure(r)
    big.canvas.draw()
    _assert_inside(big)
    assert big.get_figwidth() > width + 0.2
    # the panels keep their size in inches
    assert [ax.get_position().width * big.get_figwidth() for ax in big.axes[:-1]] == pytest.approx(panels)
    plt.close(fig)
    plt.close(big)


def test_submitted_pictures_are_drawn_while_the_caller_works():
    from cdpr_design.plots import worker as pw
    from cdpr_design.plots.report import report_html

    with pw.PictureWorker(force=True) as worker:
        pending = worker.submit([("a.html", report_html, (None, None, [], {"name": "x"}))])
        assert worker.proc is not None
        out = pending.result()
    assert out[0][0] == "a.html" and b"<h1>x</h1>" in out[0][1]
    local = pw.PictureWorker(enabled=False).submit([("a.html", report_html, (None, None, [], {"name": "x"}))])
    assert local.result() == out


def test_a_foreign_picture_or_page_is_refused_before_the_sweep(tmp_path):
    for name in ("report.html", "tension_map.png"):
        folder = tmp_path / name
        folder.mkdir()
        (folder / name).write_text("mine")
        r = invoke("workspace", PLANAR2, "--step", "0.1", "--out", folder, "--html", "--format", "parquet")
        assert r.exit_code == 2 and "--overwrite" in r.output
        assert (folder / name).read_text() == "mine"
        assert not (folder / "workspace.parquet").exists()  # refused before any work
