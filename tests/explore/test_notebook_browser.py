"""``notebooks/explore.ipynb`` as a person uses it: JupyterLab on 127.0.0.1, Chromium driven by
Playwright, Run All, then the map is clicked and every control moved; the inspector's text, the
status line, the hover text and the canvas's pixels are read back from the page.

The same checks fail on a copy of the notebook whose click handler is disconnected.  Needs the
``e2e`` extra (jupyterlab, playwright) and Debian's ``chromium`` (``$ATLAS_CHROMIUM``; Playwright's
own browser download is not used); skipped without them, except in CI (``CI`` set), where it
fails.  ``python tests/explore/test_notebook_browser.py --n 129`` prints the latencies of a run
at ``n x n`` cells.
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

CHROMIUM = os.environ.get("ATLAS_CHROMIUM", "/usr/bin/chromium")
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
        msg = f"no Chromium at {CHROMIUM} (apt-get install chromium, or set ATLAS_CHROMIUM)"
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
        for _ in range(300):
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
        self.page.keyboard.press("Control+b")  # close the file browser: the column a person sees

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
        """Wait until every code cell has run; returns the seconds since :meth:`start_run_all`."""
        self.page.wait_for_function(
            """() => {
                const p = [...document.querySelectorAll('.jp-CodeCell .jp-InputPrompt')];
                return p.length > 0 && p.every(e => /^\\[\\d+\\]:$/.test(e.textContent.trim()));
            }""",
            timeout=timeout * 1e3,
            polling=200,
        )
        return time.perf_counter() - self._started

    def tracebacks(self) -> list[str]:
        """The text of every error output and of anything in the page that shows a traceback."""
        texts = self.page.locator(".jp-OutputArea-output").all_inner_texts()
        texts += [self.status()]
        return [t for t in texts if "Traceback" in t or "Error" in t.split("\n", 1)[0]]

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
        """The map canvas as an RGBA array (CSS pixels at device scale 1)."""
        url = self.page.locator(_CANVAS).first.evaluate("c => c.toDataURL('image/png')")
        return _rgba(url)

    def to_page(self, beta1: float, beta2: float) -> tuple[float, float]:
        """Page coordinates of the map point ``(beta1, beta2)`` [rad]."""
        from atlas.explore.map_view import AXES_RECT

        b = self.canvas_box()
        x0, y0, w, h = AXES_RECT
        fx = x0 + w * beta1 / (2 * PI)
        fy = y0 + h * beta2 / (2 * PI)
        return b["x"] + fx * b["width"], b["y"] + (1 - fy) * b["height"]

    def wait_change(self, before: np.ndarray | None, status: str | None, timeout: float):
        """Wait until the canvas differs from ``before`` (if given) and the status line from
        ``status`` (if given); returns the seconds, or raises ``AssertionError``."""
        t = time.perf_counter()
        while True:
            done = True
            if before is not None:
                now = self.pixels()
                done &= now.shape != before.shape or bool(np.any(now != before))
            if status is not None:
                done &= self.status() != status and "pending" not in self.status()
            if done:
                return time.perf_counter() - t
            if time.perf_counter() - t > timeout:
                raise AssertionError(
                    f"no repaint within {timeout} s (status: {self.status()!r}, "
                    f"tracebacks: {self.tracebacks()})"
                )
            time.sleep(0.02)

    def click_map(self, beta1: float, beta2: float, timeout: float = 10) -> float:
        """Click the map at ``(beta1, beta2)``; the inspector must move there (within 0.01 pi)
        and the marker appear (canvas pixels change).  Returns the click-to-inspector seconds."""
        old, before = self.inspector(), self.pixels()
        x, y = self.to_page(beta1, beta2)
        t = time.perf_counter()
        self.page.mouse.click(x, y)
        while self.inspector() == old:
            if time.perf_counter() - t > timeout:
                raise AssertionError(
                    f"a click at ({beta1 / PI:.3f} pi, {beta2 / PI:.3f} pi) did not move the "
                    f"inspector in {timeout} s"
                )
            time.sleep(0.01)
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


def check_explorer(nb: Notebook) -> dict:
    """The explorer after Run All, as a person meets it; returns the measured seconds."""
    page, times = nb.page, {}
    # the widget's first state is the one its cell states, nothing went wrong
    assert not nb.tracebacks(), nb.tracebacks()
    assert nb.status().startswith("stable_SS at kappa = 0.5, q = 0,"), nb.status()
    assert "click the map" in nb.inspector()
    assert not _fits(nb), _fits(nb)

    # hovering shows (beta1, beta2) in units of pi; the toolbar stays above the map
    page.locator(".atlas-explorer").scroll_into_view_if_needed()
    page.locator(_CANVAS).first.scroll_into_view_if_needed()
    x, y = nb.to_page(0.25 * PI, 1.5 * PI)
    page.mouse.move(x, y)
    footer = page.locator(".atlas-explorer .jupyter-matplotlib-footer")
    page.wait_for_function(
        "el => el.textContent.includes('beta1 =')", arg=footer.element_handle(), timeout=20_000
    )
    m = re.search(r"beta1 = ([\d.]+) pi, beta2 = ([\d.]+) pi", footer.inner_text())
    np.testing.assert_allclose([float(m.group(1)), float(m.group(2))], [0.25, 1.5], atol=0.01)
    tb = page.locator(".atlas-explorer .jupyter-matplotlib-toolbar").bounding_box()
    _, axes_top = nb.to_page(0, 2 * PI)
    assert tb["y"] + tb["height"] <= axes_top, (tb, axes_top)

    # clicks move the inspector to the clicked point
    clicks = [nb.click_map(b1 * PI, b2 * PI) for b1, b2 in ((0.15, 1.07), (1.6, 0.3), (0.8, 1.8))]
    times["click_s"] = clicks

    # every control repaints the map (or, where the map cannot change, rewrites the status)
    def act(action, repaint=True):
        before, status = nb.pixels(), nb.status()
        t = time.perf_counter()
        action()
        nb.wait_change(before if repaint else None, None if repaint else status, 30)
        assert not nb.tracebacks(), nb.tracebacks()
        return time.perf_counter() - t

    times["kappa_text_s"] = act(lambda: nb.set_text("kappa", "2"))
    assert float(nb.readout("log10-kappa")) == 0.30
    slider = nb.widget("log10-kappa").locator(".noUi-handle").first
    times["kappa_slider_s"] = act(lambda: (slider.focus(), page.keyboard.press("ArrowLeft")), False)
    assert "kappa = 1.95," in nb.status(), nb.status()  # one step: x 10^-0.01
    times["q_s"] = act(lambda: nb.set_text("q", "0.3"))
    act(lambda: nb.widget("separate").locator("input").click(), False)
    assert float(nb.readout("q1")) == float(nb.readout("q2")) == 0.3  # the model did not jump
    assert "q = 0.3," in nb.status(), nb.status()
    times["q2_s"] = act(lambda: nb.set_text("q2", "1.5"))
    assert "q1 = 0.3, q2 = 1.5" in nb.status()
    select = nb.widget("layer").locator("select")
    times["layer_s"] = act(lambda: select.select_option("class_code"))
    assert _legend_pixels(nb.pixels()) > 200  # a colour key
    act(lambda: select.select_option("subclass_code"))
    times["alpha_s"] = act(lambda: nb.set_text("alpha", "0.6"))
    over = nb.widget("overlays").locator("select")
    times["overlays_s"] = act(lambda: over.select_option(["SS boundary"]))
    n = nb.widget("n").locator("select")
    other = next(
        v for v in n.evaluate("s => [...s.options].map(o => o.value)") if v != n.input_value()
    )
    times["resolution_s"] = act(lambda: n.select_option(other))
    act(lambda: nb.set_text("max-resolve", "0"), False)
    assert "at most 0 a redraw" in nb.status()
    act(lambda: nb.widget("settle").click(), False)
    assert "settled in" in nb.status()
    nb.set_text("beta1", "1.5")
    nb.set_text("beta2", "0.5")
    old = nb.inspector()
    act(lambda: nb.widget("inspect").click())
    assert nb.inspector() != old and "(1.5000 pi)" in nb.inspector()
    times["click_after_s"] = nb.click_map(0.4 * PI, 0.9 * PI)
    assert not nb.tracebacks(), nb.tracebacks()
    return times


def _launch(p):
    return p.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])


def _broken_copy(path: Path):
    """The notebook up to the widget's cell, its click handler disconnected."""
    import nbformat

    nb = nbformat.read(path, as_version=4)
    i = next(i for i, c in enumerate(nb.cells) if "make_widget(" in c.source)
    nb.cells[i].source += "\nbox.figure.canvas.mpl_disconnect(box.click_cid)\nbox"
    nb.cells = nb.cells[: i + 1]
    nbformat.write(nb, path)


@pytest.mark.e2e
def test_explorer_in_a_browser(tmp_path, need):
    """Run All in JupyterLab, then every check of :func:`check_explorer`; the click check fails
    on a copy whose click handler is disconnected (run alongside, in a second tab)."""
    _need_browser(need)
    from playwright.sync_api import sync_playwright

    prepare_notebook(ROOT / "notebooks" / "explore.ipynb", tmp_path / "explore.ipynb")
    prepare_notebook(ROOT / "notebooks" / "explore.ipynb", tmp_path / "broken.ipynb")
    _broken_copy(tmp_path / "broken.ipynb")
    t0 = time.perf_counter()
    with jupyterlab(tmp_path) as (base, token), sync_playwright() as p:
        browser = _launch(p)
        try:
            nb, broken = (
                Notebook(browser, base, token, f) for f in ("explore.ipynb", "broken.ipynb")
            )
            nb.start_run_all()
            broken.start_run_all()  # the two kernels run side by side
            seconds = nb.wait_run_all()
            broken.wait_run_all()
            assert not broken.tracebacks(), broken.tracebacks()
            with pytest.raises(AssertionError, match="did not move the inspector"):
                broken.click_map(0.15 * PI, 1.07 * PI, timeout=3)
            times = check_explorer(nb)
            nb.page.screenshot(path=str(tmp_path / "explorer.png"), full_page=True)
        finally:
            browser.close()
    print(f"Run All {seconds:.1f} s, test {time.perf_counter() - t0:.1f} s, {times}")


def _measure(n: int):
    """One run at ``n x n`` cells (no broken copy): prints Run All and the latencies."""
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
            times = check_explorer(nb)
            nb.page.screenshot(path=str(tmp / "explorer.png"), full_page=True)
        finally:
            browser.close()
    print(json.dumps({"n": n, "run_all_s": seconds, **times}, indent=1), tmp)


if __name__ == "__main__":
    _measure(int(sys.argv[sys.argv.index("--n") + 1]) if "--n" in sys.argv else 129)
