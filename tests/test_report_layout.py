"""The report in a real browser: headless Chromium at 1280 px, driven over the DevTools protocol.

Renders the comparison report of a short run and a page of deliberately wide
tables, and checks that the page logs no console error, that no table or
image is wider than the content column, that every image has alternative
text, and saves a screenshot of the first screen into the test's folder.
Skipped, saying why, when no Chromium is installed (CI installs Debian's).
"""

from __future__ import annotations

import base64
import json
import os
import re
import shutil
import subprocess
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest

from sensorless.comparison import compare, write_comparison_report
from sensorless.report import CONTENT_WIDTH_PX, Table, write_report
from sensorless.simulation.scenario import load_scenario

websocket = pytest.importorskip(
    "websocket", reason="websocket-client (a dev dependency) drives Chromium"
)

VIEWPORT = (1280, 900)
BROWSERS = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")


def find_chromium() -> str | None:
    given = os.environ.get("SENSORLESS_CHROMIUM")
    if given:
        return given
    return next((path for name in BROWSERS if (path := shutil.which(name))), None)


CHROMIUM = find_chromium()
pytestmark = pytest.mark.skipif(
    CHROMIUM is None,
    reason=f"no Chromium found (looked for {', '.join(BROWSERS)} and $SENSORLESS_CHROMIUM); "
    "install Debian's: apt-get install -y chromium",
)


class DevTools:
    """A headless Chromium and one page, spoken to over the DevTools protocol."""

    def __init__(self, executable: str, profile: Path) -> None:
        self.process = subprocess.Popen(
            [executable, "--headless=new", "--no-sandbox", "--disable-gpu",
             "--remote-debugging-port=0", f"--user-data-dir={profile}", "--no-first-run",
             f"--window-size={VIEWPORT[0]},{VIEWPORT[1]}", "about:blank"],
            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
        )  # fmt: skip
        assert self.process.stderr is not None
        url = None
        for line in self.process.stderr:
            found = re.search(r"DevTools listening on (ws://\S+)", line)
            if found:
                url = found.group(1)
                break
        if url is None:
            raise RuntimeError("Chromium did not announce its DevTools address")
        self.socket = websocket.create_connection(url, timeout=60)
        self.next_id = 0
        self.events: list[dict[str, Any]] = []
        target = self.call("Target.createTarget", url="about:blank")["targetId"]
        self.session = self.call("Target.attachToTarget", targetId=target, flatten=True)[
            "sessionId"
        ]

    def call(self, method: str, session: bool = False, **params: Any) -> dict[str, Any]:
        self.next_id += 1
        message: dict[str, Any] = {"id": self.next_id, "method": method, "params": params}
        if session:
            message["sessionId"] = self.session
        self.socket.send(json.dumps(message))
        while True:
            reply = json.loads(self.socket.recv())
            if reply.get("id") == self.next_id:
                if "error" in reply:
                    raise RuntimeError(f"{method}: {reply['error']}")
                return reply.get("result", {})
            self.events.append(reply)

    def wait_for(self, method: str) -> None:
        while not any(event.get("method") == method for event in self.events):
            self.events.append(json.loads(self.socket.recv()))

    def close(self) -> None:
        self.socket.close()
        self.process.terminate()
        self.process.wait(timeout=30)


@pytest.fixture(scope="module")
def browser(tmp_path_factory):
    assert CHROMIUM is not None
    tools = DevTools(CHROMIUM, tmp_path_factory.mktemp("chromium-profile"))
    yield tools
    tools.close()


# Everything the page needs to know about its layout, measured in the browser.
MEASURE = """(() => {
  const column = document.querySelector('main').getBoundingClientRect();
  const wide = [];
  for (const el of document.querySelectorAll('table, img')) {
    const box = el.getBoundingClientRect();
    if (box.right > column.right + 0.5 || box.left < column.left - 0.5) {
      wide.push(el.tagName + ' ' + Math.round(box.width) + ' px: ' +
                (el.caption ? el.caption.textContent : (el.alt || '')).slice(0, 80));
    }
  }
  const noAlt = [...document.querySelectorAll('img')].filter(i => !(i.alt || '').trim()).length;
  return JSON.stringify({column: column.width, wide: wide, noAlt: noAlt,
                         images: document.images.length,
                         tables: document.querySelectorAll('table').length,
                         brokenImages: [...document.images].filter(i => !i.naturalWidth).length,
                         pageWidth: document.documentElement.scrollWidth});
})()"""


def render(browser: DevTools, page: Path, screenshot: Path) -> tuple[dict[str, Any], list[str]]:
    """Open ``page`` at 1280 px; its measurements and the console errors."""
    browser.events.clear()
    for domain in ("Page.enable", "Runtime.enable", "Log.enable"):
        browser.call(domain, session=True)
    browser.call(
        "Emulation.setDeviceMetricsOverride", session=True, width=VIEWPORT[0],
        height=VIEWPORT[1], deviceScaleFactor=1, mobile=False,
    )  # fmt: skip
    browser.call("Page.navigate", session=True, url=page.resolve().as_uri())
    browser.wait_for("Page.loadEventFired")
    result = browser.call("Runtime.evaluate", session=True, expression=MEASURE)
    measured = json.loads(result["result"]["value"])
    shot = browser.call("Page.captureScreenshot", session=True, format="png")
    screenshot.write_bytes(base64.b64decode(shot["data"]))
    errors = []
    for event in browser.events:
        method, params = event.get("method"), event.get("params", {})
        if method == "Runtime.exceptionThrown":
            errors.append(str(params.get("exceptionDetails", {}).get("text")))
        elif method == "Runtime.consoleAPICalled" and params.get("type") == "error":
            errors.append(str(params.get("args")))
        elif method == "Log.entryAdded" and params.get("entry", {}).get("level") == "error":
            errors.append(str(params["entry"].get("text")))
    return measured, errors


def check_layout(measured: dict[str, Any], errors: list[str]) -> None:
    assert errors == []
    assert measured["column"] <= CONTENT_WIDTH_PX
    assert measured["wide"] == [], "wider than the content column"
    assert measured["noAlt"] == 0
    assert measured["brokenImages"] == 0
    assert measured["pageWidth"] <= VIEWPORT[0]


def test_comparison_report_fits_1280_px_in_chromium(browser, tmp_path) -> None:
    scenario = load_scenario("panda-gaz").with_duration(8.0)
    comparison = compare(
        scenario, methods=("constant", "time-variant", "velocity"), n_tuning=1, master_seed=3
    )
    page = write_comparison_report([comparison], tmp_path / "report.html", command="test")
    measured, errors = render(browser, page, tmp_path / "first-screen.png")
    check_layout(measured, errors)
    assert measured["images"] >= 3 and measured["tables"] >= 2
    assert (tmp_path / "first-screen.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_wide_tables_are_transposed_to_fit(browser, tmp_path) -> None:
    rng = np.random.default_rng(0)
    columns = [f"velocity-combined (joint) {k} [N m]" for k in range(12)]
    wide = pd.DataFrame(rng.normal(size=(3, 12)) * 1e3, columns=columns)
    square = pd.DataFrame(
        rng.normal(size=(20, 20)) * 1e3, columns=[f"{c} #2" for c in columns * 2][:20]
    )
    page = write_report(
        tmp_path / "wide.html",
        title="Wide tables",
        sections=[("Tables", [Table(wide, "Twelve columns, three rows"), wide, square])],
    )
    measured, errors = render(browser, page, tmp_path / "first-screen.png")
    check_layout(measured, errors)
    assert measured["tables"] == 2 + 3  # the 20 × 20 table in three parts


def test_the_measure_sees_what_overflows(browser, tmp_path) -> None:
    """The check itself: a page with a too-wide table, an image without alt and an error."""
    page = tmp_path / "bad.html"
    page.write_text(
        "<!DOCTYPE html><html><head><style>main { max-width: 600px; }</style></head><body>"
        "<main><table><tr><td><div style='width: 900px'>wide</div></td></tr></table>"
        "<img src='data:image/gif;base64,R0lGODlhAQABAAAAACw=' width='10'>"
        "<script>console.error('boom')</script></main></body></html>",
        encoding="utf-8",
    )
    measured, errors = render(browser, page, tmp_path / "first-screen.png")
    assert len(measured["wide"]) == 1 and measured["wide"][0].startswith("TABLE"), measured
    assert measured["noAlt"] == 1
    assert any("boom" in error for error in errors)
