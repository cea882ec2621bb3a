"""``notebooks/explore.ipynb`` as a person uses it: JupyterLab on 127.0.0.1 with its file browser
open (the widget gets an 848 px column at 1280 px), Chromium driven by Playwright, Run All, then
every advertised path: hover, clicks, each model control, each layer (a click on the
verdict over every model where it depends names both witness models; a reversed or NaN model
box typed in is the one-line refusal naming ``model_box``, then a good box gives a verdict), 129^2 and 513^2 (the status
line's texts recorded while the 513^2 map is computed), each overlay, clicks next to each kind of
certified curve and on a codimension-2 point, exact settlements, "settle undecided"; the
inspector's text, the status line, the hover text, the canvas's pixels, the widget's output area
and the kernel's log console are read back from the page (any traceback fails the test).

The same checks fail once a last cell, run in the same kernel, has disconnected the widget's click
handler and made its "settle undecided" raise.  Needs the ``e2e`` extra (jupyterlab, playwright) and Debian's
``chromium-headless-shell`` or ``chromium`` (``$ATLAS_CHROMIUM``; Playwright's own browser download is not used); skipped
without them, except in CI (``CI`` set), where it fails.  ``python
tests/explore/test_notebook_browser.py --n 129`` prints the latencies of a run at ``n x n``
cells.  About 2 minutes with a warm compilation cache (2 shared cores).
"""

from __future__ import annotations

import base64
import contextlib
import io
import json
import math
import os
import re
import secrets
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
if __name__ == "__main__":
    sys.path.insert(0, str(ROOT / "tests"))
from notebook_run import prepare_notebook  # noqa: E402

#: the browser: ``$ATLAS_CHROMIUM``, else Debian's ``chromium-headless-shell`` (Chromium's
#: headless shell, without the full browser's processes: about 6 s less CPU a run), else its
#: ``chromium`` (the full browser in headless mode)
CHROMIUM = os.environ.get("ATLAS_CHROMIUM") or next(
    (
        p
        for p in ("/usr/lib/chromium/chromium-headless-shell", "/usr/bin/chromium")
        if Path(p).is_file()
    ),
    "/usr/bin/chromium",
)
PI = math.pi
#: JupyterLab's settings for the run: every cell in the page (no windowing), no news pop-up
_SETTINGS = {
    "@jupyterlab/notebook-extension/tracker.jupyterlab-settings": {
        "windowingMode": "none",
        "autoStartDefaultKernel": True,
    },
    "@jupyterlab/apputils-extension/notification.jupyterlab-settings": {
        "fetchNews": "false",
        "checkForUpdates": False,
    },
}
_CANVAS = ".atlas-explorer .jupyter-matplotlib-canvas-div canvas"


def _need_browser(need_module):
    """Chromium, Playwright and JupyterLab, or a skip (a failure in CI)."""
    if not Path(CHROMIUM).is_file():
        msg = f"no Chromium at {CHROMIUM} (apt-get install chromium-headless-shell, or set ATLAS_CHROMIUM)"
        if os.environ.get("CI"):
            pytest.fail(msg)
        pytest.skip(msg)
    need_module("playwright")
    need_module("jupyterlab")
    need_module("ipympl")


@contextlib.contextmanager
def jupyterlab(root: Path):
    """A JupyterLab server on 127.0.0.1 serving ``root``; yields its base URL with the token."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    token = secrets.token_hex(16)
    settings = root / ".lab" / "settings"
    for name, value in _SETTINGS.items():
        f = settings / name
        f.parent.mkdir(parents=True, exist_ok=True)
        f.write_text(json.dumps(value))
    env = dict(os.environ)
    env.pop("MPLBACKEND", None)  # the notebook chooses ipympl
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), env.get("PYTHONPATH", "")) if p)
    cmd = [sys.executable, "-m", "jupyterlab", "--no-browser", "--allow-root"]
    cmd += ["--ServerApp.ip=127.0.0.1", f"--ServerApp.port={port}", f"--ServerApp.root_dir={root}"]
    cmd += [f"--IdentityProvider.token={token}", f"--LabApp.user_settings_dir={settings}"]
    cmd += [f"--LabApp.workspaces_dir={root / '.lab' / 'workspaces'}"]
    log = open(root / ".lab" / "server.log", "w")
    proc = subprocess.Popen(cmd, cwd=root, env=env, stdout=log, stderr=subprocess.STDOUT)
    base = f"http://127.0.0.1:{port}"
    try:
        # until the server answers or dies, however loaded the machine (pytest-timeout bounds a
        # hang): a fixed number of tries went on to the browser before the server listened
        while True:
            try:
                urllib.request.urlopen(f"{base}/api/status?token={token}", timeout=1).close()
                break
            except OSError:
                assert proc.poll() is None, (root / ".lab" / "server.log").read_text()[-3000:]
                time.sleep(0.1)
        yield base, token
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
        log.close()


def _rgba(data_url: str) -> np.ndarray:
    from PIL import Image

    png = base64.b64decode(data_url.split(",", 1)[1])
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGBA"), dtype=np.int16)


#: the rendered text (``innerText``) of each cell output, the widget's output area and each
#: entry of the log console whose text holds "Traceback" or "Error" (the others, most of the page,
#: are not laid out to be read: their rendered text cannot hold what their text does not)
_ERROR_TEXTS = """() => {
    const out = [];
    for (const css of ['.jp-OutputArea-output', '.atlas-explorer .atlas-log',
                       '.jp-LogConsolePanel .jp-OutputArea-output'])
        for (const el of document.querySelectorAll(css))
            if (/Traceback|Error/.test(el.textContent)) out.push(el.innerText);
    return out;
}"""


class Notebook:
    """One notebook open in a JupyterLab tab: Run All, then the explorer widget's DOM and
    canvas."""

    def __init__(self, browser, base: str, token: str, name: str):
        from playwright.sync_api import TimeoutError as PlaywrightTimeout

        self.page = browser.new_page(viewport={"width": 1280, "height": 1000})
        # a workspace of its own: a second tab does not restore the first one's notebook
        ws = Path(name).stem
        self.page.goto(f"{base}/lab/workspaces/{ws}/tree/{name}?reset&token={token}")
        self.page.wait_for_selector(".jp-NotebookPanel .jp-Cell", timeout=120_000)
        with contextlib.suppress(PlaywrightTimeout):  # older JupyterLab: it asks for the kernel
            self.page.get_by_role("button", name="Select", exact=True).click(timeout=2000)
        # JupyterLab's default file browser stays open: the notebook gets an ~850 px column
        self.page.wait_for_selector(".jp-FileBrowser", timeout=60_000)

    def open_log_console(self):
        """View > Show Log Console: the kernel's log (a widget callback's error lands there)."""
        self.page.get_by_role("menuitem", name="View", exact=True).click()
        self.page.get_by_text("Show Log Console", exact=True).click()
        self.page.wait_for_selector(".jp-LogConsolePanel", timeout=30_000)
        self.page.locator(".jp-NotebookPanel").first.click(position={"x": 5, "y": 5})

    def start_run_all(self):
        """Run > Run All Cells, once the kernel is connected (a Run All before runs nothing)."""
        page = self.page
        page.wait_for_function(
            "() => /\\| Idle/.test((document.querySelector('#jp-main-statusbar') ?? document.body).textContent)",
            timeout=120_000,
            polling=100,
        )
        self._started = time.perf_counter()
        page.get_by_role("menuitem", name="Run", exact=True).click()
        page.get_by_text("Run All Cells", exact=True).click()

    def wait_run_all(self, timeout: float = 300) -> float:
        """Wait until every code cell has run, or a cell's traceback is shown (the cells after it
        never run); returns the seconds since :meth:`start_run_all`."""
        self.page.wait_for_function(
            """() => {
                const p = [...document.querySelectorAll('.jp-CodeCell .jp-InputPrompt')];
                const out = [...document.querySelectorAll('.jp-OutputArea-output')];
                return (p.length > 0 && p.every(e => /^\\[\\d+\\]:$/.test(e.textContent.trim())))
                    || out.some(e => e.textContent.includes('Traceback'));
            }""",
            timeout=timeout * 1e3,
            polling=200,
        )
        return time.perf_counter() - self._started

    def tracebacks(self) -> list[str]:
        """The text of every error in the page: cell outputs, the widget's output area (its
        callbacks' tracebacks), the status line and the kernel's log console."""
        texts = self.page.evaluate(_ERROR_TEXTS) + [self.status()]
        return [t for t in texts if "Traceback" in t or "Error" in t.split("\n", 1)[0]]

    def record_status(self):
        """Record every text the status line takes from now on (a MutationObserver)."""
        self.page.locator(".atlas-explorer .atlas-status").evaluate(
            """el => { window.__atlasStatus = [];
                new MutationObserver(() => window.__atlasStatus.push(el.textContent))
                    .observe(el, {subtree: true, childList: true, characterData: true}); }"""
        )

    def recorded_status(self) -> list[str]:
        return self.page.evaluate("() => window.__atlasStatus")

    # --- the widget ----------------------------------------------------------------------
    def widget(self, css: str):
        return self.page.locator(f".atlas-explorer .atlas-{css}")

    def inspector(self) -> str:
        return self.page.locator(".atlas-explorer .atlas-inspector").inner_text()

    def status(self) -> str:
        loc = self.page.locator(".atlas-explorer .atlas-status")
        return loc.inner_text() if loc.count() else ""

    def canvas_box(self) -> dict:
        return self.page.locator(_CANVAS).first.bounding_box()

    def pixels(self) -> np.ndarray:
        """The map canvas as an RGBA array (CSS pixels at device scale 1), once it has a size (a
        canvas not yet laid out gives the empty ``data:,``; pytest-timeout ends a hang)."""
        canvas = self.page.locator(_CANVAS).first
        url = canvas.evaluate("c => c.toDataURL('image/png')")
        while url == "data:,":
            self.page.wait_for_timeout(50)
            url = canvas.evaluate("c => c.toDataURL('image/png')")
        return _rgba(url)

    def fingerprint(self) -> tuple[int, int, str]:
        """The map canvas's width, height [px] and the SHA-256 of its RGBA pixels, computed in
        the page (equal for equal pixels; no PNG encoded, sent and decoded), once it has a
        size."""
        canvas = self.page.locator(_CANVAS).first
        js = """async c => {
            if (!c.width || !c.height) return null;
            const px = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
            const h = new Uint8Array(await crypto.subtle.digest('SHA-256', px));
            return [c.width, c.height, Array.from(h, b => b.toString(16).padStart(2, '0')).join('')];
        }"""
        got = canvas.evaluate(js)
        while got is None:
            self.page.wait_for_timeout(50)
            got = canvas.evaluate(js)
        return tuple(got)

    def to_page(self, beta1: float, beta2: float) -> tuple[float, float]:
        """Page coordinates of the map point ``(beta1, beta2)`` [rad]."""
        from atlas.explore.map_view import AXES_RECT

        b = self.canvas_box()
        x0, y0, w, h = AXES_RECT
        fx = x0 + w * beta1 / (2 * PI)
        fy = y0 + h * beta2 / (2 * PI)
        return b["x"] + fx * b["width"], b["y"] + (1 - fy) * b["height"]

    def wait_change(self, before: tuple | None, status: str | None, timeout: float):
        """Wait until the canvas differs from ``before`` (a :meth:`fingerprint`, if given) and the
        status line from ``status`` (if given); returns the seconds, or raises
        ``AssertionError``.  Polled at 20 ms growing to 0.2 s: each look at the canvas reads its
        pixels back in the browser, which must not take the CPU from the kernel it waits for."""
        t, pause = time.perf_counter(), 0.02
        while True:
            done = True
            if before is not None:
                done &= self.fingerprint() != before
            if status is not None:
                now = self.status()
                done &= now != status and not _busy(now)
            if done:
                return time.perf_counter() - t
            if time.perf_counter() - t > timeout:
                raise AssertionError(
                    f"no repaint within {timeout} s (status: {self.status()!r}, "
                    f"tracebacks: {self.tracebacks()})"
                )
            time.sleep(pause)
            pause = min(2 * pause, 0.2)

    def click_map(self, beta1: float, beta2: float, timeout: float = 10) -> float:
        """Click the map at ``(beta1, beta2)``; the inspector must move there (within 0.01 pi)
        and the marker appear (canvas pixels change).  Returns the click-to-inspector seconds."""
        from playwright.sync_api import TimeoutError as PlaywrightTimeout

        self.page.locator(_CANVAS).first.scroll_into_view_if_needed()  # the whole map in view
        old, before = self.inspector(), self.fingerprint()
        x, y = self.to_page(beta1, beta2)
        inspector = self.page.locator(".atlas-explorer .atlas-inspector").element_handle()
        t = time.perf_counter()
        self.page.mouse.click(x, y)
        try:  # watched in the page (every 10 ms), not by a round trip from here each time
            self.page.wait_for_function(
                "([el, old]) => el.innerText !== old",
                arg=[inspector, old],
                timeout=timeout * 1e3,
                polling=10,
            )
        except PlaywrightTimeout:
            raise AssertionError(
                f"a click at ({beta1 / PI:.3f} pi, {beta2 / PI:.3f} pi) did not move the "
                f"inspector in {timeout} s"
            ) from None
        latency = time.perf_counter() - t
        m = re.search(r"\(([\d.]+) pi\), beta2 = [-\d.e+]+ \(([\d.]+) pi\)", self.inspector())
        assert m, self.inspector()
        got = float(m.group(1)), float(m.group(2))
        np.testing.assert_allclose(got, (beta1 / PI, beta2 / PI), atol=0.01)
        self.wait_change(before, None, timeout)
        return latency

    def set_text(self, css: str, value: str):
        """Type into a text box (or a slider's readout) and press Enter."""
        box = self.widget(css).locator("input, .widget-readout").first
        box.click()
        self.page.keyboard.press("Control+a")
        self.page.keyboard.type(value)
        self.page.keyboard.press("Enter")

    def readout(self, css: str) -> str:
        return self.widget(css).locator(".widget-readout").first.inner_text().strip()


def _busy(status: str) -> bool:
    """The status line says the session is still working or drawing."""
    return status.startswith("working --") or "drawing in the browser" in status


def _fits(nb: Notebook) -> list[str]:
    """Every figure and the widget within the notebook's column; labels not cut."""
    return nb.page.evaluate(
        """() => {
            const bad = [];
            for (const out of document.querySelectorAll('.jp-OutputArea-output')) {
                const r = out.getBoundingClientRect();
                for (const el of out.querySelectorAll('canvas, img, .atlas-explorer')) {
                    const e = el.getBoundingClientRect();
                    if (e.width > 0 && e.right > r.right + 1)
                        bad.push(`${el.tagName}.${el.className} ${e.width}px wide ends at ${e.right}, column ends at ${r.right}`);
                }
            }
            for (const el of document.querySelectorAll('.jp-NotebookPanel .jp-OutputArea-output, .jp-NotebookPanel .jp-WindowedPanel-outer, .atlas-explorer, .atlas-explorer .widget-hbox')) {
                if (el.scrollWidth > el.clientWidth + 1)
                    bad.push(`${el.className} scrolls sideways (${el.scrollWidth} > ${el.clientWidth} px)`);
            }
            for (const l of document.querySelectorAll('.atlas-explorer .widget-label, .atlas-explorer .widget-label-basic')) {
                if (l.scrollWidth > l.clientWidth + 1)
                    bad.push(`label '${l.textContent}' cut (${l.scrollWidth} > ${l.clientWidth} px)`);
            }
            return bad;
        }"""
    )


def _legend_pixels(img: np.ndarray) -> int:
    """Coloured (not grey) pixels right of the map: the colour key."""
    from atlas.explore.map_view import AXES_RECT

    x = int((AXES_RECT[0] + AXES_RECT[2]) * img.shape[1]) + 6
    rgb = img[:, x:, :3]
    return int(np.sum(rgb.max(axis=-1) - rgb.min(axis=-1) > 40))


#: the slice whose certified boundaries the browser test clicks: ``(kappa, q)``
SLICE = (0.5, 0.3)
#: the kinds of certified curves a click must name
KINDS = ("SS_stability", "II_consistency", "II_stability")


def _on_torus(xy: np.ndarray) -> np.ndarray:
    """Angles [rad] taken to [0, 2 pi) (a periodic k-d tree's box)."""
    xy = np.mod(xy, 2 * PI)
    return np.where(xy >= 2 * PI, 0.0, xy)


def slice_targets():
    """Click targets on the certified boundaries of :data:`SLICE` (computed here, independently
    of the kernel): per curve kind a vertex ``(beta1, beta2, curve)`` far (> 0.15 rad) from
    every curve of another kind and from the codimension-2 points, and the codimension-2 point
    off ``det B = 0`` farthest from the others."""
    from scipy.spatial import cKDTree

    from atlas.data.boundaries import slice_boundaries
    from atlas.explore.maps import beta_grid

    g = beta_grid(64)
    b = slice_boundaries(g, g, SLICE[0], SLICE[1], SLICE[1])
    pts = np.array([(p.beta1, p.beta2) for p in b.points]).reshape(-1, 2)

    def far(xy, others):  # the distance to the nearest of ``others`` on the torus
        if not len(others):
            return np.full(len(xy), 9.0)
        return cKDTree(_on_torus(others), boxsize=2 * PI).query(_on_torus(xy))[0]

    out = {}
    for kind in KINDS:
        mine = [c for c in b.curves if c.kind == kind]
        others = np.concatenate([c.vertices for c in b.curves if c.kind != kind] + [pts])
        best = None
        for c in mine:
            v = c.vertices
            inside = np.all((v > 0.15) & (v < 2 * PI - 0.15), axis=1)
            score = np.where(inside, far(v, others), -1.0)
            i = int(np.argmax(score))
            if best is None or score[i] > best[0]:
                best = (score[i], v[i, 0], v[i, 1], c)
        assert best is not None and best[0] > 0.15, (kind, best)
        out[kind] = best[1:]
    spread = far(pts, pts + 10 * np.eye(len(pts), 2)) if len(pts) > 1 else np.ones(len(pts))
    inside = np.all((pts > 0.15) & (pts < 2 * PI - 0.15), axis=1)
    inside &= np.abs(np.sin(pts[:, 1] - pts[:, 0])) > 0.15  # off det B = 0 (slow exact reference)
    out["point"] = b.points[int(np.argmax(np.where(inside, spread, -1)))]
    return out


def _first_state(nb: Notebook) -> dict:
    """After Run All: the widget's first state as its cell says, no error, and every figure and
    the widget within the notebook's column (no sideways scroll).  Returns the widths [px].

    The first canvas draw is done when the browser asks for it, a comm message queued behind
    Run All's later cells: it may still be pending when they have run, so the status line is
    given a minute to leave "drawing in the browser" (a draw that never comes still fails)."""
    assert not nb.tracebacks(), nb.tracebacks()
    with contextlib.suppress(Exception):  # the assertions below say what the status was
        nb.page.wait_for_function(
            "el => !el.textContent.includes('drawing in the browser')",
            arg=nb.page.locator(".atlas-explorer .atlas-status").element_handle(),
            timeout=60_000,
            polling=100,
        )
    assert nb.status().startswith("stable_SS at kappa = 0.5, q = 0,"), nb.status()
    assert nb.status().endswith(", drawn"), nb.status()  # not a first draw's wait as a repaint
    assert "click the map" in nb.inspector()
    assert not _fits(nb), _fits(nb)
    col = nb.page.locator(".jp-OutputArea-output:has(.atlas-explorer)").first.bounding_box()
    box = nb.page.locator(".atlas-explorer").bounding_box()
    assert 800 <= col["width"] <= 900, col  # the column a person with the file browser open has
    assert box["x"] + box["width"] <= col["x"] + col["width"], (box, col)
    return {"column_px": col["width"], "widget_px": box["width"]}


def _footer(nb: Notebook) -> str:
    return nb.page.locator(".atlas-explorer .jupyter-matplotlib-footer").inner_text()


def _hover(nb: Notebook):
    """Hovering shows (beta1, beta2) in units of pi; the toolbar stays above the map."""
    page = nb.page
    page.locator(".atlas-explorer").scroll_into_view_if_needed()
    page.locator(_CANVAS).first.scroll_into_view_if_needed()
    x, y = nb.to_page(0.25 * PI, 1.5 * PI)
    page.mouse.move(x, y)
    footer = page.locator(".atlas-explorer .jupyter-matplotlib-footer")
    page.wait_for_function(
        "el => el.textContent.includes('beta1 =')",
        arg=footer.element_handle(),
        timeout=20_000,
        polling=100,
    )
    m = re.search(r"beta1 = ([\d.]+) pi, beta2 = ([\d.]+) pi", footer.inner_text())
    np.testing.assert_allclose([float(m.group(1)), float(m.group(2))], [0.25, 1.5], atol=0.01)
    tb = page.locator(".atlas-explorer .jupyter-matplotlib-toolbar").bounding_box()
    _, axes_top = nb.to_page(0, 2 * PI)
    assert tb["y"] + tb["height"] <= axes_top, (tb, axes_top)


def _act(nb: Notebook, action, repaint=True, timeout=60) -> float:
    """Run ``action``; wait for the canvas to change (``repaint``) or the status line to change
    and settle; no error anywhere.  Returns the seconds."""
    before, status = nb.fingerprint(), nb.status()
    t = time.perf_counter()
    action()
    nb.wait_change(before if repaint else None, None if repaint else status, timeout)
    if repaint:  # and the status line done too
        nb.wait_change(None, "", timeout)
    assert not nb.tracebacks(), nb.tracebacks()
    return time.perf_counter() - t


def _model_controls(nb: Notebook, times: dict):
    """kappa (text box, slider), q, q1/q2 separately, alpha."""
    page = nb.page
    times["kappa_text_s"] = _act(nb, lambda: nb.set_text("kappa", "2"))
    assert float(nb.readout("log10-kappa")) == 0.30
    slider = nb.widget("log10-kappa").locator(".noUi-handle").first
    times["kappa_slider_s"] = _act(
        nb, lambda: (slider.focus(), page.keyboard.press("ArrowLeft")), False
    )
    assert "kappa = 1.95," in nb.status(), nb.status()  # one step: x 10^-0.01
    times["q_s"] = _act(nb, lambda: nb.set_text("q", "0.3"))
    _act(nb, lambda: nb.widget("separate").locator("input").click(), False)
    assert float(nb.readout("q1")) == float(nb.readout("q2")) == 0.3  # the model did not jump
    assert "q = 0.3," in nb.status(), nb.status()
    times["q2_s"] = _act(nb, lambda: nb.set_text("q2", "1.5"))
    assert "q1 = 0.3, q2 = 1.5" in nb.status()
    times["q1_s"] = _act(nb, lambda: nb.set_text("q1", "0.4"))
    assert "q1 = 0.4, q2 = 1.5" in nb.status()
    select = nb.widget("layer").locator("select")
    _act(nb, lambda: select.select_option("subclass_code"))
    times["alpha_s"] = _act(nb, lambda: nb.set_text("alpha", "0.6"))
    assert "alpha = 0.600 pi" in nb.status(), nb.status()


def _layers(nb: Notebook, times: dict):
    """Every layer: the status names it, the hover readout (pointer kept on the map) follows it
    without a mouse move, the categorical ones have a colour key."""
    from atlas.explore import maps

    select = nb.widget("layer").locator("select")
    # the controls and the map in view together: selecting a layer scrolls nothing (a scroll
    # under a resting pointer moves it off the map)
    nb.page.locator(".atlas-explorer").evaluate("e => e.scrollIntoView({block: 'start'})")
    x, y = nb.to_page(0.4 * PI, 1.3 * PI)
    nb.page.mouse.move(x, y)
    t = time.perf_counter()
    for layer in select.evaluate("s => [...s.options].map(o => o.value)"):
        if layer == select.input_value():
            continue
        _act(nb, lambda layer=layer: select.select_option(layer), False, timeout=120)
        where = "over the model box" if maps.is_box_layer(layer) else "at kappa"
        assert nb.status().startswith(f"{layer} {where}"), nb.status()
        nb.page.wait_for_function(
            "([el, k]) => el.textContent.includes('| ' + k + ':')",
            arg=[
                nb.page.locator(".atlas-explorer .jupyter-matplotlib-footer").element_handle(),
                layer,
            ],
            timeout=20_000,
            polling=100,
        )
        if layer in ("class_code", "subclass_code"):
            assert _legend_pixels(nb.pixels()) > 200, layer  # a colour key
    times["all_layers_s"] = time.perf_counter() - t
    _act(nb, lambda: select.select_option("stable_SS"), False)


def _box_layer(nb: Notebook, times: dict):
    """The ``ss_over_models`` layer: a click where SS depends on the model (class 13 over the
    whole model space) shows both witness models in the inspector, each on its side by the
    exact reference; a new "model box" text recomputes the map over it."""
    from atlas.core import exact
    from atlas.core.verdicts import Verdict
    from atlas.explore import maps

    select = nb.widget("layer").locator("select")
    _act(nb, lambda: select.select_option("ss_over_models"), False, timeout=120)
    b1, b2 = 0.25 * PI, 0.6 * PI
    times["click_depends_s"] = nb.click_map(b1, b2)
    text = nb.inspector()
    assert f"ss_over_models over the model box {maps.WHOLE_BOX}: depends" in text, text
    d = (math.cos(b1), math.sin(b1), math.cos(b2), math.sin(b2))
    for side in ("stable", "unstable"):
        m = re.search(rf"{side} witness: kappa = (\S+), q1 = (\S+), q2 = (\S+) \(", text)
        assert m, text
        v = exact.point_spectral(*d, *(float(x) for x in m.groups()))["stable_SS"]
        assert (v in (Verdict.STABLE, Verdict.NEUTRAL)) == (side == "stable"), (side, m, v)
    times["model_box_s"] = _act(nb, lambda: nb.set_text("model-box", "kappa=0.5:2,q=0:1"), False)
    assert "over the model box kappa=0.5:2,q=0:1" in nb.status(), nb.status()
    _bad_box(nb, times)
    _act(nb, lambda: select.select_option("stable_SS"), False)


#: boxes typed into the explorer's "model box" and the one line that must refuse each
BAD_BOXES = {
    "kappa=2:1": "model_box: kappa: reversed range 2:1",
    "kappa=nan:2": "model_box: kappa: NaN bound in (nan, 2.0)",
    "q1=0:nan": "model_box: q1: NaN bound in (0.0, nan)",
}


def _bad_box(nb: Notebook, times: dict):
    """A reversed and a NaN box typed in (the ``ss_over_models`` layer shown): the status line is
    the one-line refusal naming ``model_box`` and the map is not redrawn; then the whole model
    space typed again gives a verdict at a click: "depends" at a class-13 point, where the
    closed form over the whole model space (stable for every model iff ``det B >= 0``, ``c1 >
    0``, ``s2 > 0``, ``s1 c2 >= 0``; unstable for every model iff ``det B < 0`` or ``c1, s2 <=
    0``) gives neither."""
    from atlas.explore import maps

    status = nb.page.locator(".atlas-explorer .atlas-status").element_handle()
    for text, refusal in BAD_BOXES.items():
        before = nb.fingerprint()
        nb.set_text("model-box", text)
        with contextlib.suppress(Exception):  # the assertion below says what the status was
            nb.page.wait_for_function(
                "([el, t]) => el.textContent.trim() === t",
                arg=[status, refusal],
                timeout=60_000,
                polling=100,
            )
        assert nb.status() == refusal, (text, nb.status())
        assert not nb.tracebacks(), nb.tracebacks()
        assert nb.fingerprint() == before, text  # the map over the last good box stays
    b1, b2 = 0.25 * PI, 0.6 * PI
    c1, s1, c2, s2 = math.cos(b1), math.sin(b1), math.cos(b2), math.sin(b2)
    det = c1 * s2 - c2 * s1
    assert not (det >= 0 and c1 > 0 and s2 > 0 and s1 * c2 >= 0)  # not stable for every model
    assert not (det < 0 or (c1 <= 0 and s2 <= 0))  # nor unstable for every model: depends
    times["good_box_after_bad_s"] = _act(
        nb, lambda: nb.set_text("model-box", maps.WHOLE_BOX), False
    )
    assert f"over the model box {maps.WHOLE_BOX}" in nb.status(), nb.status()
    nb.click_map(0.3 * PI, 1.2 * PI)  # away first: the click below must move the inspector
    nb.click_map(b1, b2)
    assert f"ss_over_models over the model box {maps.WHOLE_BOX}: depends" in nb.inspector()


def _resolution(nb: Notebook, times: dict, small: str):
    """129^2 and 513^2: the status says what is being done before the 513^2 map arrives (every
    status text recorded), and a kappa move's repaint at each size."""
    n = nb.widget("n").locator("select")
    if n.input_value() != "129":  # (a run at 129^2 starts there)
        times["n129_s"] = _act(nb, lambda: n.select_option("129"), timeout=300)
    times["repaint_129_s"] = _act(nb, lambda: nb.set_text("kappa", "0.6"))
    nb.record_status()
    times["n513_s"] = _act(nb, lambda: n.select_option("513"), timeout=600)
    seen = nb.recorded_status()
    done = next(i for i, s in enumerate(seen) if "513^2 cells: compute" in s)
    working = [s for s in seen[:done] if s.startswith("working --")]
    assert any("computing stable_SS on 513^2" in s or "compiling" in s for s in working), seen
    times["repaint_513_s"] = _act(nb, lambda: nb.set_text("kappa", "0.5"), timeout=300)
    _act(nb, lambda: n.select_option(small))


def _certified(nb: Notebook, targets, times: dict):
    """The certified boundaries of :data:`SLICE`: drawn once computed; a click next to a curve
    of each kind names the kind, the bracket and the codes on its two sides; a click on a
    codimension-2 point names it."""
    from atlas.core.brackets import FIELD_LABELS

    if nb.widget("separate").locator("input").is_checked():
        _act(nb, lambda: nb.widget("separate").locator("input").click(), False)
    for name, value in (("q", SLICE[1]), ("kappa", SLICE[0])):
        if f"{name} = {value:g}," not in nb.status():
            _act(nb, lambda name=name, value=value: nb.set_text(name, f"{value}"), False)
    assert nb.status().startswith(f"stable_SS at kappa = {SLICE[0]:g}, q = {SLICE[1]:g},")
    over = nb.widget("overlays").locator("select")
    t = time.perf_counter()
    over.select_option(["certified boundaries"])
    nb.page.wait_for_function(
        "() => /certified boundaries \\d+ ms/.test(document.querySelector('.atlas-explorer .atlas-status').textContent)",
        timeout=600_000,
        polling=200,
    )
    times["first_overlay_s"] = time.perf_counter() - t
    assert not nb.tracebacks(), nb.tracebacks()
    tg = targets()
    for kind in KINDS:
        b1, b2, c = tg[kind]
        times[f"click_{kind}_s"] = nb.click_map(b1, b2)
        text, lab = nb.inspector(), FIELD_LABELS[c.field]
        assert f"near the certified {kind} boundary" in text, text
        assert "bracketed within" in text and f"{lab[c.side_left]} | {lab[c.side_right]}" in text
        assert not nb.tracebacks(), nb.tracebacks()
    p = tg["point"]
    times["click_point_s"] = nb.click_map(p.beta1, p.beta2)
    assert f"on the codimension-2 point '{p.kind}'" in nb.inspector(), nb.inspector()
    assert not nb.tracebacks(), nb.tracebacks()
    for chosen in (["class boundaries", "SS boundary"], ["class boundaries"]):
        times["overlays_s"] = _act(nb, lambda chosen=chosen: over.select_option(chosen))


def check_explorer(nb: Notebook, targets=None) -> dict:
    """The explorer after Run All, as a person meets it, then every advertised path: hover,
    clicks, each model control, each layer, 129^2 and 513^2 (the status during the long
    computation), each overlay with clicks near each kind of certified curve and on a
    codimension-2 point (``targets``: a callable giving :func:`slice_targets`; skipped if
    None), exact settlements, 'settle undecided', 'inspect point'; no error anywhere (cell
    outputs, the widget's output area, the status line, the kernel's log console).  Returns the
    measured seconds."""
    times = _first_state(nb)
    _hover(nb)
    times["click_s"] = [
        nb.click_map(b1 * PI, b2 * PI) for b1, b2 in ((0.15, 1.07), (1.6, 0.3), (0.8, 1.8))
    ]
    small = nb.widget("n").locator("select").input_value()
    _model_controls(nb, times)
    _layers(nb, times)
    _box_layer(nb, times)
    _resolution(nb, times, small)
    if targets is not None:
        _certified(nb, targets, times)
    _act(nb, lambda: nb.set_text("max-resolve", "0"), False)
    assert "at most 0 a redraw" in nb.status()
    _act(nb, lambda: nb.widget("settle").click(), False)
    assert "settled in" in nb.status()
    nb.set_text("beta1", "1.5")
    nb.set_text("beta2", "0.5")
    old = nb.inspector()
    _act(nb, lambda: nb.widget("inspect").click())
    assert nb.inspector() != old and "(1.5000 pi)" in nb.inspector()
    times["click_after_s"] = nb.click_map(0.4 * PI, 0.9 * PI)
    assert not nb.tracebacks(), nb.tracebacks()
    return times


def _launch(p):
    """Chromium headless, drawing in software: no GPU process emulating one (SwiftShader)."""
    args = ["--no-sandbox", "--disable-gpu", "--disable-software-rasterizer"]
    return p.chromium.launch(executable_path=CHROMIUM, args=args)


#: a last cell: the widget's click handler disconnected and its "settle undecided" raising (an
#: error in a widget callback)
BREAK = "box.figure.canvas.mpl_disconnect(box.click_cid)\nbox.explorer.settle = lambda: 1 / 0"


def _break(nb: Notebook):
    """Add :data:`BREAK` as the notebook's last cell and run it (the kernel of the checks)."""
    page, cells = nb.page, nb.page.locator(".jp-NotebookPanel .jp-CodeCell")
    n = cells.count()
    cells.last.locator(".jp-InputPrompt").click()
    page.keyboard.press("Escape")
    page.keyboard.press("b")  # a new cell below
    page.wait_for_function(
        "n => document.querySelectorAll('.jp-NotebookPanel .jp-CodeCell').length > n",
        arg=n,
        polling=100,
    )
    page.keyboard.press("Enter")
    page.keyboard.insert_text(BREAK)
    page.keyboard.press("Shift+Enter")
    page.wait_for_function(
        """n => {
            const p = document.querySelectorAll('.jp-NotebookPanel .jp-CodeCell .jp-InputPrompt')[n];
            return p !== undefined && /^\\[\\d+\\]:$/.test(p.textContent.trim());
        }""",
        arg=n,
        timeout=60_000,
        polling=100,
    )


def _check_broken(broken: Notebook):
    """The checks fail once :func:`_break` has run: a click does not move the inspector, and the
    error of "settle undecided" is seen in the widget's output area and in the kernel's log
    console."""
    assert not broken.tracebacks(), broken.tracebacks()
    with pytest.raises(AssertionError, match="did not move the inspector"):
        broken.click_map(0.15 * PI, 1.07 * PI, timeout=3)
    broken.widget("settle").click()
    broken.page.wait_for_function(
        "() => /ZeroDivisionError/.test(document.querySelector('.jp-LogConsolePanel')?.textContent ?? '')",
        timeout=30_000,
        polling=100,
    )
    assert "ZeroDivisionError" in broken.page.locator(".atlas-explorer .atlas-log").inner_text()
    assert any("ZeroDivisionError" in t for t in broken.tracebacks())


@pytest.mark.e2e
def test_explorer_in_a_browser(tmp_path, need):
    """Run All in JupyterLab (the file browser open: an ~850 px column), then every check of
    :func:`check_explorer`; then the click and error checks fail once a last cell has
    disconnected the widget's click handler and made "settle undecided" raise (:func:`_break`)."""
    _need_browser(need)
    from concurrent.futures import ThreadPoolExecutor

    from playwright.sync_api import sync_playwright

    prepare_notebook(ROOT / "notebooks" / "explore.ipynb", tmp_path / "explore.ipynb")
    t0 = time.perf_counter()
    with (
        ThreadPoolExecutor(1) as pool,
        jupyterlab(tmp_path) as (base, token),
        sync_playwright() as p,
    ):
        targets = pool.submit(slice_targets)  # the click targets, computed here meanwhile
        browser = _launch(p)
        try:
            nb = Notebook(browser, base, token, "explore.ipynb")
            nb.start_run_all()
            seconds = nb.wait_run_all()
            assert not nb.tracebacks(), nb.tracebacks()
            assert (tmp_path / "tiny_atlas.nc").is_file()  # its last cells ran
            nb.open_log_console()
            times = check_explorer(nb, targets.result)
            nb.page.screenshot(path=str(tmp_path / "explorer.png"), full_page=True)
            _break(nb)
            _check_broken(nb)
        finally:
            browser.close()
    print(f"Run All {seconds:.1f} s, test {time.perf_counter() - t0:.1f} s, {times}")


def _measure(n: int):
    """One run at ``n x n`` cells (no broken cell): prints Run All and the latencies."""
    import tempfile

    from playwright.sync_api import sync_playwright

    tmp = Path(tempfile.mkdtemp())
    prepare_notebook(ROOT / "notebooks" / "explore.ipynb", tmp / "explore.ipynb", n=n)
    with jupyterlab(tmp) as (base, token), sync_playwright() as p:
        browser = _launch(p)
        try:
            nb = Notebook(browser, base, token, "explore.ipynb")
            nb.start_run_all()
            seconds = nb.wait_run_all(timeout=1800)
            nb.open_log_console()
            times = check_explorer(nb, slice_targets)
            nb.page.screenshot(path=str(tmp / "explorer.png"), full_page=True)
        finally:
            browser.close()
    print(json.dumps({"n": n, "run_all_s": seconds, **times}, indent=1), tmp)


if __name__ == "__main__":
    _measure(int(sys.argv[sys.argv.index("--n") + 1]) if "--n" in sys.argv else 129)
