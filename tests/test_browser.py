"""The pages in a real browser (issue 23): Debian's Chromium, headless, driven over the DevTools protocol
(tests/browser.py). It executes web/player.js, meshcat's three.js viewer and the corpus index's script
as a reader's browser does, from file:// with no network.

- The animation page loads offline (every request is to the page itself or inline data) with no error
  in its console; the robot is drawn differently at ``#t=0`` and at ``#t=1.25`` (while two drawings
  of one time are the same); a click on Play moves it and a click on the slider moves it to the time
  under the mouse, its time line and the side panels' cursor with it.
- A scene report (``write_report``) and a corpus index (``write_corpus``) load with no console error
  and every plot and thumbnail decoded; the index's script runs (its count line, sorting on a click).

Chromium is a test dependency: without it these tests fail (tests/browser.py names the package)."""

from __future__ import annotations

import re
import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest

from browser import Browser
from urdf2links.integration.simulate import simulate
from urdf2links.scenes.scene_read import load_scene
from urdf2links.view.animation import trajectory_page

ROOT = Path(__file__).resolve().parent.parent
ROBOTS = ROOT / "robots"
READY = "document.querySelector('.u2l-motion') && document.querySelector('.u2l-motion').dataset.ready === '1'"
TIME = "document.querySelector('.u2l-time').textContent"
LOCAL = ("file:", "data:", "blob:", "about:")
# A pixel "changed" when a channel moved by more than 0.1 (of 1): anti-aliasing noise stays below it.
# The double pendulum's two links cover about 1% of the view: the drawings at two different times
# differ in ~0.9% of the pixels (measured: 0.87% between t = 0 and 1.2 s), two drawings of one time in
# none (the software renderer is deterministic). Bounds: moved > 0.2%, same < 0.02%.
MOVED, SAME = 2e-3, 2e-4


def changed(a: np.ndarray, b: np.ndarray) -> float:
    """The share of pixels that differ between two screenshots of one element."""
    assert a.shape == b.shape
    return float((np.abs(a - b).max(axis=-1) > 0.1).mean())


def seconds(page) -> float:
    """The time the player shows, from its 't = 1.250 s / 2.000 s'."""
    return float(re.match(r"t = ([0-9.]+) s", page.js(TIME)).group(1))


def _shown(page) -> tuple[float, float]:
    """Both numbers of the player's 't = 1.250 s / 2.000 s', parsed (no test matches a printed float)."""
    found = re.fullmatch(r"t = ([0-9.]+) s / ([0-9.]+) s", page.js(TIME))
    assert found, page.js(TIME)
    return float(found.group(1)), float(found.group(2))


@pytest.fixture(scope="module")
def browser():
    with Browser() as b:
        yield b


@pytest.fixture(scope="module")
def pages(tmp_path_factory):
    """The pages the tests open: an animation (the double pendulum's chaotic scene, 2 s), a scene report
    (the UR5-like arm falling, 0.5 s) and a corpus index (the shipped double pendulum and UR5-like arm,
    with thumbnails, and a file urdf2links refuses)."""
    from urdf2links.compare.agreement.trajectory import compare_scene
    from urdf2links.compare.corpus.report import write_corpus
    from urdf2links.compare.corpus.rows import CorpusSettings, find_robots
    from urdf2links.compare.corpus.runner import run_corpus
    from urdf2links.compare.reports.report import write_report

    out = tmp_path_factory.mktemp("pages")
    scene = load_scene(ROBOTS / "double_pendulum_chaos.toml")
    model = scene.model()
    page, _ = trajectory_page(simulate(scene, model=model, t_end=2.0, progress=False), model)
    (out / "animation.html").write_text(page)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        c = compare_scene(ROBOTS / "ur5_falling.toml", t_end=0.5, states=2, progress=False)
    report = write_report(c, out / "report")["html"]
    fleet = out / "fleet"
    fleet.mkdir()
    for name in ("double_pendulum.urdf", "ur5_like.urdf"):
        shutil.copy(ROBOTS / name, fleet / name)
    (fleet / "empty.urdf").write_text("<robot name='empty'/>")
    settings = CorpusSettings(t_end=0.05, states=1)
    results = run_corpus(find_robots([fleet]), settings, jobs=1)
    index = write_corpus(results, out / "corpus", settings=settings.describe(), run={"how": "here", "wall_s": 0.0})["html"]
    return {"animation": out / "animation.html", "report": report, "index": index, "dir": out}


def test_animation_loads_offline_without_console_errors(browser, pages):
    with browser.open(f"file://{pages['animation']}#t=0") as page:
        page.wait_for(READY)
        assert _shown(page) == pytest.approx((0.0, 2.0), abs=1e-9)
        assert page.js("document.querySelector('.u2l-status').textContent") == ""      # no 'cannot show the 3D view'
        assert page.js("!!document.querySelector('.u2l-viewer canvas')")
        assert page.errors() == []
        requests = [e["params"]["request"]["url"] for e in browser.events
                    if e.get("method") == "Network.requestWillBeSent" and e.get("sessionId") == page.session]
        assert requests and all(u.startswith(LOCAL) for u in requests), requests


def test_robot_is_drawn_differently_at_two_times(browser, pages):
    with browser.open(f"file://{pages['animation']}#t=0") as page:
        page.wait_for(READY)
        browser.pump(0.3)
        at_0 = page.screenshot(".u2l-viewer")
        page.save_screenshot(pages["dir"] / "animation_t0.png")
        again = page.screenshot(".u2l-viewer")
        assert page.errors() == []
    with browser.open(f"file://{pages['animation']}#t=1.25") as page:
        page.wait_for(READY)
        assert _shown(page) == pytest.approx((1.25, 2.0), abs=1e-9)      # parsed: the time asked for, and t_end
        browser.pump(0.3)
        later = page.screenshot(".u2l-viewer")
        page.save_screenshot(pages["dir"] / "animation_t1.25.png")
        assert page.errors() == []
    assert changed(at_0, again) < SAME
    assert changed(at_0, later) > MOVED
    assert at_0.std() > 0.02                      # a drawing, not a blank pane


def test_play_and_the_slider_move_the_robot(browser, pages):
    with browser.open(f"file://{pages['animation']}#t=0") as page:
        page.wait_for(READY)
        browser.pump(0.3)
        start = page.screenshot(".u2l-viewer")
        cursor = "document.querySelector('svg.u2l-panel .u2l-cursor').getAttribute('x1')"
        x0 = float(page.js(cursor))
        page.click_on(".u2l-play")
        assert page.js("document.querySelector('.u2l-play').textContent") == "Pause"
        page.wait_for(f"parseFloat({TIME}.slice(4)) > 0.4", timeout=20)
        page.click_on(".u2l-play")                    # pause, to look at one frame
        played = seconds(page)
        assert page.js("document.querySelector('.u2l-play').textContent") == "Play" and 0.4 < played < 2.0
        browser.pump(0.3)
        assert seconds(page) == played                # paused
        after_play = page.screenshot(".u2l-viewer")
        assert changed(start, after_play) > MOVED
        assert float(page.js(cursor)) > x0            # the panels' cursor follows
        page.click_on(".u2l-slider", 0.75)            # the slider under the mouse at three quarters: t ~ 1.5 s
        browser.pump(0.3)
        slid = seconds(page)
        assert abs(slid - 1.5) < 0.1, slid            # the thumb's width shifts the value a little
        after_slider = page.screenshot(".u2l-viewer")
        assert changed(after_play, after_slider) > MOVED and changed(start, after_slider) > MOVED
        assert page.errors() == []


def _images(page) -> list[dict]:
    return page.js("Array.from(document.images).map(i => ({alt: i.alt, complete: i.complete, "
                   "width: i.naturalWidth, height: i.naturalHeight}))")


def test_report_page_loads_with_its_plots(browser, pages):
    with browser.open(f"file://{pages['report']}") as page:
        page.wait_for(READY)
        page.save_screenshot(pages["dir"] / "report.png")
        images = _images(page)
        assert len(images) >= 4, images               # terms, difference and energy, coordinates, error, energy
        assert all(i["complete"] and i["width"] > 100 and i["height"] > 100 for i in images), images
        assert page.js("document.querySelectorAll('svg.u2l-panel').length") >= 1
        assert page.errors() == []


def test_corpus_index_loads_with_its_plots(browser, pages):
    with browser.open(f"file://{pages['index']}") as page:
        page.wait_for("document.getElementById('shown').textContent")
        page.save_screenshot(pages["dir"] / "index.png")
        assert page.js("document.getElementById('shown').textContent") == "3 of 3 robots shown"
        images = _images(page)
        thumbs = [i for i in images if i["alt"] == ""]
        assert len(thumbs) == 2 and any(i["alt"].startswith("every robot") for i in images), images
        assert all(i["complete"] and i["width"] > 50 for i in images), images
        rows = "Array.from(document.querySelectorAll('#corpus tbody tr')).map(r => r.dataset.status + ':' + r.cells[3].textContent)"
        assert page.js(rows)[-1].startswith("refused")                 # worst first: the refused file last
        heads = page.js("Array.from(document.querySelectorAll('#corpus th')).map(h => h.textContent)")
        page.click_on(f"#corpus th:nth-child({heads.index('n') + 1})")   # largest first on the first click
        assert [r.split(":")[1] for r in page.js(rows)][:2] == ["6", "2"]
        assert "coveragemoved" in heads          # both robots moved every coordinate: none is weak evidence
        page.click_on("#only-weak")
        assert page.js("document.getElementById('shown').textContent") == "0 of 3 robots shown"
        page.click_on("#only-weak")
        assert page.js("document.getElementById('shown').textContent") == "3 of 3 robots shown"
        assert page.errors() == []
