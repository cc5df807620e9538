"""A real browser for the tests: Debian's Chromium, headless, driven over the Chrome DevTools Protocol.

Chromium is a test dependency (``apt-get install chromium``; .ci/run installs it): without it the
browser tests fail, naming the package, as a missing corpus does. :class:`Browser` starts one
headless Chromium with a fresh profile (``--user-data-dir``), no sandbox (CI runs as root), no GPU
(WebGL on the CPU: SwiftShader) and no background networking, and talks to it on its DevTools web
socket (the ``websockets`` package). A :class:`Page` opens a URL and records what a person would see
in the console: uncaught exceptions, ``console.error`` and the browser's own error log entries (a
failed load, a blocked request). Clicks and drags are real input events at screen coordinates, not
synthetic DOM events; screenshots are PNG pixels.
"""

from __future__ import annotations

import base64
import io
import itertools
import json
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np
import pytest

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
MISSING = ("Chromium is not installed: the browser tests need Debian's chromium package (apt-get install chromium; "
           ".ci/run installs it)")
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking", "--enable-unsafe-swiftshader",
         "--use-angle=swiftshader", "--no-first-run", "--no-default-browser-check", "--hide-scrollbars",
         "--window-size=1280,1000", "--remote-debugging-port=0", "--remote-allow-origins=*"]


class BrowserError(RuntimeError):
    pass


class Browser:
    """One headless Chromium process and its DevTools connection; ``with Browser() as b: page = b.open(url)``."""

    def __init__(self, timeout: float = 60.0):
        from websockets.sync.client import connect

        if CHROMIUM is None:
            pytest.fail(MISSING)
        self.profile = tempfile.TemporaryDirectory(prefix="u2l-chromium-")
        self.proc = subprocess.Popen([CHROMIUM, *FLAGS, f"--user-data-dir={self.profile.name}", "about:blank"],
                                     stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        port_file = Path(self.profile.name) / "DevToolsActivePort"
        deadline = time.monotonic() + timeout
        while not (port_file.is_file() and len(port_file.read_text().split()) >= 2):
            if self.proc.poll() is not None:
                raise BrowserError(f"chromium exited: {self.proc.stderr.read().decode(errors='replace')[-2000:]}")
            if time.monotonic() > deadline:
                self.close()
                raise BrowserError("chromium did not open its DevTools port")
            time.sleep(0.05)
        port, path = port_file.read_text().split()[:2]
        self.ws = connect(f"ws://127.0.0.1:{port}{path}", max_size=None, open_timeout=timeout).__enter__()
        self.ids = itertools.count(1)
        self.events: list[dict] = []

    def send(self, method: str, params: dict | None = None, session: str | None = None, timeout: float = 60.0) -> dict:
        """One DevTools command; its result (events that arrive meanwhile are kept in ``events``)."""
        i = next(self.ids)
        msg = {"id": i, "method": method, "params": params or {}}
        if session:
            msg["sessionId"] = session
        self.ws.send(json.dumps(msg))
        deadline = time.monotonic() + timeout
        while True:
            reply = json.loads(self.ws.recv(timeout=max(0.01, deadline - time.monotonic())))
            if reply.get("id") == i:
                if "error" in reply:
                    raise BrowserError(f"{method}: {reply['error']}")
                return reply.get("result", {})
            self.events.append(reply)

    def pump(self, seconds: float) -> None:
        """Receive events for ``seconds``."""
        deadline = time.monotonic() + seconds
        while (left := deadline - time.monotonic()) > 0:
            try:
                self.events.append(json.loads(self.ws.recv(timeout=left)))
            except TimeoutError:
                return

    def open(self, url: str, timeout: float = 60.0) -> "Page":
        target = self.send("Target.createTarget", {"url": "about:blank"})["targetId"]
        session = self.send("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
        page = Page(self, session, target)
        for domain in ("Page", "Runtime", "Log", "Network"):
            page.send(f"{domain}.enable")
        page.send("Emulation.setDeviceMetricsOverride", {"width": 1280, "height": 1000, "deviceScaleFactor": 1,
                                                         "mobile": False})
        page.goto(url, timeout=timeout)
        return page

    def close(self) -> None:
        try:
            if getattr(self, "ws", None) is not None:
                self.ws.__exit__(None, None, None)
        finally:
            if self.proc.poll() is None:
                self.proc.terminate()
                try:
                    self.proc.wait(timeout=10)
                except subprocess.TimeoutExpired:
                    self.proc.kill()
                    self.proc.wait()
            self.profile.cleanup()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


class Page:
    """A tab: what it logged, JavaScript, real mouse input, screenshots."""

    def __init__(self, browser: Browser, session: str, target: str):
        self.browser, self.session, self.target = browser, session, target

    def close(self) -> None:
        self.browser.send("Target.closeTarget", {"targetId": self.target})

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def send(self, method: str, params: dict | None = None, timeout: float = 60.0) -> dict:
        return self.browser.send(method, params, session=self.session, timeout=timeout)

    def goto(self, url: str, timeout: float = 60.0) -> None:
        """Load ``url`` (a new document: a change of the #fragment alone is no load, open a new page)."""
        start = len(self.browser.events)
        self.send("Page.navigate", {"url": url})
        deadline = time.monotonic() + timeout
        while not any(e.get("method") == "Page.loadEventFired" and e.get("sessionId") == self.session
                      for e in self.browser.events[start:]):
            if time.monotonic() > deadline:
                raise BrowserError(f"{url} did not finish loading in {timeout:g} s")
            self.browser.pump(0.1)

    def errors(self) -> list[str]:
        """Everything this page reported as an error so far: uncaught exceptions, console.error / assert,
        and the browser's error log (failed loads, blocked requests)."""
        self.browser.pump(0.2)
        out = []
        for e in self.browser.events:
            if e.get("sessionId") != self.session:
                continue
            m, p = e.get("method"), e.get("params", {})
            if m == "Runtime.exceptionThrown":
                d = p["exceptionDetails"]
                out.append(f"exception: {d.get('exception', {}).get('description') or d.get('text')} "
                           f"({d.get('url', '')}:{d.get('lineNumber')})")
            elif m == "Runtime.consoleAPICalled" and p.get("type") in ("error", "assert"):
                out.append("console." + p["type"] + ": " + " ".join(str(a.get("value", a.get("description")))
                                                                    for a in p.get("args", [])))
            elif m == "Log.entryAdded" and p["entry"].get("level") == "error":
                out.append(f"log: {p['entry'].get('text')} {p['entry'].get('url', '')}")
        return out

    def js(self, expression: str, timeout: float = 60.0):
        """The value of a JavaScript expression (awaited if a promise)."""
        res = self.send("Runtime.evaluate", {"expression": expression, "returnByValue": True, "awaitPromise": True},
                        timeout=timeout)
        if "exceptionDetails" in res:
            raise BrowserError(f"{expression}: {res['exceptionDetails']}")
        return res["result"].get("value")

    def wait_for(self, expression: str, timeout: float = 30.0):
        """Poll a JavaScript expression until it is truthy; its value."""
        deadline = time.monotonic() + timeout
        while True:
            value = self.js(expression)
            if value:
                return value
            if time.monotonic() > deadline:
                raise BrowserError(f"still false after {timeout:g} s: {expression}; the page's errors: {self.errors()}")
            self.browser.pump(0.1)

    def rect(self, selector: str) -> dict:
        """The element's box in the page's CSS pixels, scrolled into view."""
        return self.js(f"(() => {{ const el = document.querySelector({json.dumps(selector)}); "
                       "el.scrollIntoView({block: 'center'}); const r = el.getBoundingClientRect(); "
                       "return {x: r.x, y: r.y, width: r.width, height: r.height}; })()")

    def click(self, x: float, y: float) -> None:
        """A left click at (x, y) in the viewport: press and release, as a mouse does."""
        for kind in ("mouseMoved", "mousePressed", "mouseReleased"):
            self.send("Input.dispatchMouseEvent", {"type": kind, "x": x, "y": y, "button": "left", "clickCount": 1})

    def click_on(self, selector: str, fraction: float = 0.5) -> None:
        """Click an element, at ``fraction`` of its width (a slider's position) and half its height."""
        r = self.rect(selector)
        self.click(r["x"] + fraction * r["width"], r["y"] + r["height"] / 2)

    def screenshot(self, selector: str | None = None) -> np.ndarray:
        """The viewport, or one element, as an (h, w, 3) float array in [0, 1]."""
        from matplotlib.image import imread

        params = {"format": "png"}
        if selector is not None:
            r = self.rect(selector)
            params["clip"] = {**r, "scale": 1}
        png = base64.b64decode(self.send("Page.captureScreenshot", params)["data"])
        return imread(io.BytesIO(png), format="png")[..., :3]

    def save_screenshot(self, path: Path) -> None:
        path.write_bytes(base64.b64decode(self.send("Page.captureScreenshot", {"format": "png"})["data"]))
