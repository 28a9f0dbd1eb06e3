#!/usr/bin/env python3
"""Opens a `raycost report` page in a real headless Chromium and checks it as a reader would see it.

Asserts that the page loads, that nothing is logged as an error (console errors, uncaught
exceptions, resources that failed to load), that every <img> was decoded (naturalWidth > 0), that
every claim's verdict cell is coloured by its outcome (class outcome-OUTCOME and the computed
background of that class: holds green, holds-in-part yellow, differs and refuted one red,
inconclusive grey), and that every measured cell lies inside the viewport's width (readable without
scrolling at 1280 px); then writes a PNG screenshot of the top of the page.

Drives the system Chromium over the DevTools protocol through --remote-debugging-pipe (JSON
messages separated by NUL on file descriptors 3 and 4), so it needs only the Python standard
library and a Chromium binary: nothing is downloaded.

Usage: report_browser_test.py PAGE.html --screenshot OUT.png [--chrome PATH] [--width 1280]
       [--height 2000] [--timeout 60] [--expect-claims]
Exit 0 when every check passes, 1 with the failures listed otherwise, 2 for a usage problem.
"""

import argparse
import base64
import fcntl
import json
import os
import pathlib
import shutil
import subprocess
import sys
import tempfile
import time


def find_chrome(given):
    """The Chromium binary: --chrome, $CHROME, or the usual names on PATH."""
    for c in [given, os.environ.get("CHROME"), "chromium", "chromium-browser",
              "google-chrome", "google-chrome-stable"]:
        if c and shutil.which(c):
            return shutil.which(c)
    return None


class DevTools:
    """One Chromium process and its DevTools pipe."""

    def __init__(self, chrome, width, height):
        self.profile = tempfile.mkdtemp(prefix="raycost-chrome-")
        # Chromium reads commands on its fd 3 and writes replies and events on its fd 4. The pipe
        # ends are moved to fds >= 10 (so they cannot collide with 3 and 4), kept open across exec
        # (pass_fds), and bash (dash takes one-digit fds only) puts them on 3 and 4 before it becomes Chromium.
        r, w = os.pipe()
        self.from_chrome, w4 = os.pipe()
        r3 = fcntl.fcntl(r, fcntl.F_DUPFD, 10)
        w4_high = fcntl.fcntl(w4, fcntl.F_DUPFD, 10)
        os.close(r)
        os.close(w4)
        self.to_chrome = w
        args = [
            chrome, "--headless=new", "--remote-debugging-pipe", "--no-first-run",
            "--no-default-browser-check", "--disable-gpu", "--disable-extensions",
            "--disable-background-networking", "--disable-sync", "--mute-audio",
            f"--user-data-dir={self.profile}", f"--window-size={width},{height}",
            "--hide-scrollbars", "about:blank",
        ]
        if os.geteuid() == 0:
            args.insert(1, "--no-sandbox")  # Chromium refuses to run as root with its sandbox
        shell = f'exec "$@" 3<&{r3} 4>&{w4_high} {r3}<&- {w4_high}>&-'
        self.stderr = tempfile.TemporaryFile()
        self.proc = subprocess.Popen(["bash", "-c", shell, "bash", *args], stdin=subprocess.DEVNULL,
                                     stdout=subprocess.DEVNULL, stderr=self.stderr,
                                     pass_fds=(r3, w4_high))
        os.close(r3)
        os.close(w4_high)
        self.buf = b""
        self.next_id = 0
        self.events = []

    def close(self):
        try:
            self.send("Browser.close")
        except Exception:
            pass
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        for fd in (self.to_chrome, self.from_chrome):
            try:
                os.close(fd)
            except OSError:
                pass
        shutil.rmtree(self.profile, ignore_errors=True)

    def _read_message(self, deadline):
        while b"\0" not in self.buf:
            if time.monotonic() > deadline:
                raise TimeoutError("no reply from Chromium")
            chunk = os.read(self.from_chrome, 1 << 20)
            if not chunk:
                self.stderr.seek(0)
                err = self.stderr.read().decode(errors="replace")
                raise RuntimeError(f"Chromium closed the DevTools pipe:\n{err[-2000:]}")
            self.buf += chunk
        msg, self.buf = self.buf.split(b"\0", 1)
        return json.loads(msg)

    def send(self, method, params=None, session=None, timeout=60):
        """Sends a command and returns its result, keeping every event that arrives meanwhile."""
        self.next_id += 1
        cmd = {"id": self.next_id, "method": method, "params": params or {}}
        if session:
            cmd["sessionId"] = session
        os.write(self.to_chrome, json.dumps(cmd).encode() + b"\0")
        deadline = time.monotonic() + timeout
        while True:
            msg = self._read_message(deadline)
            if msg.get("id") == self.next_id:
                if "error" in msg:
                    raise RuntimeError(f"{method}: {msg['error']}")
                return msg.get("result", {})
            self.events.append(msg)

    def wait_event(self, method, session, timeout):
        """Waits for an event (it may have arrived already)."""
        deadline = time.monotonic() + timeout
        while True:
            for e in self.events:
                if e.get("method") == method and e.get("sessionId") == session:
                    return e
            self.events.append(self._read_message(deadline))


def problems_in(events):
    """Console errors, uncaught exceptions and failed loads among the page's events."""
    out = []
    for e in events:
        m, p = e.get("method"), e.get("params", {})
        if m == "Runtime.exceptionThrown":
            d = p.get("exceptionDetails", {})
            out.append(f"exception: {d.get('text')} {d.get('exception', {}).get('description', '')}")
        elif m == "Runtime.consoleAPICalled" and p.get("type") in ("error", "assert"):
            out.append("console.error: " + " ".join(str(a.get("value", a.get("description")))
                                                 for a in p.get("args", [])))
        elif m == "Log.entryAdded" and p.get("entry", {}).get("level") == "error":
            ent = p["entry"]
            out.append(f"log error ({ent.get('source')}): {ent.get('text')} {ent.get('url', '')}")
        elif m == "Network.loadingFailed" and not p.get("canceled"):
            out.append(f"failed load: {p.get('errorText')} ({p.get('type')})")
    return out


# The background a verdict cell must have for each outcome (page.rs's style sheet): differs and
# refuted share one tone, as they share a meaning for a reader (the paper is not borne out).
OUTCOME_COLOURS = {
    "holds": "rgb(220, 241, 216)",
    "holds-in-part": "rgb(246, 239, 200)",
    "differs": "rgb(249, 220, 215)",
    "refuted": "rgb(249, 220, 215)",
    "inconclusive": "rgb(236, 236, 236)",
}

# The claims table's cells, found by its header (so a page that lacks the classes is still read):
# each verdict cell with its outcome, class and computed background, each measured cell's box.
CLAIMS_JS = """(() => {
  const t = document.querySelector('#claims table');
  if (!t) return JSON.stringify(null);
  const heads = Array.from(t.rows[0].cells).map(c => c.textContent.trim());
  const vi = heads.findIndex(h => h.startsWith('verdict'));
  const mi = heads.findIndex(h => h.startsWith('measured'));
  const rows = Array.from(t.rows).slice(1);
  const box = td => { const r = td.getBoundingClientRect();
    return {left: r.left, right: r.right, width: r.width, text: td.textContent.trim().slice(0, 60)}; };
  return JSON.stringify({
    verdicts: vi < 0 ? [] : rows.map(r => r.cells[vi]).map(td => ({
      outcome: td.dataset.outcome || null, cls: td.className,
      bg: getComputedStyle(td).backgroundColor,
      text: (td.querySelector('strong') || td).textContent.trim()})),
    measured: mi < 0 ? [] : rows.map(r => box(r.cells[mi])),
    columns: heads});
})()"""

# The measured cells of the experiments' tables (class "measured", page.rs).
MEASURED_JS = """JSON.stringify(Array.from(document.querySelectorAll('section:not(#claims) td.measured')).map(td => {
  const r = td.getBoundingClientRect();
  return {left: r.left, right: r.right, width: r.width, text: td.textContent.slice(0, 60)}; }))"""


def verdict_failures(cells):
    """Every verdict cell of the claims table must carry its outcome, the matching class and the
    outcome's computed colour; the bold word shown must be the outcome."""
    out = []
    for i, c in enumerate(cells):
        o = c["outcome"]
        if o not in OUTCOME_COLOURS:
            out.append(f"claim {i}: verdict cell without a known outcome ({o!r}, class {c['cls']!r})")
            continue
        if f"outcome-{o}" not in c["cls"].split():
            out.append(f"claim {i}: outcome {o} but class {c['cls']!r}")
        if c["bg"] != OUTCOME_COLOURS[o]:
            out.append(f"claim {i}: outcome {o} coloured {c['bg']}, expected {OUTCOME_COLOURS[o]}")
        if c["text"] != o:
            out.append(f"claim {i}: outcome {o} shown as {c['text']!r}")
    return out


def measured_failures(cells, width):
    """Every measured cell must lie within [0, width] horizontally (no scrolling to read it)."""
    return [f"measured cell {i} at x = {c['left']:.0f}–{c['right']:.0f} px, outside the {width} px "
            f"viewport ({c['text']!r})" for i, c in enumerate(cells)
            if c["left"] < 0 or c["right"] > width + 0.5 or c["width"] <= 0]


IMAGES_JS = """JSON.stringify(Array.from(document.images).map(i => ({
  src: i.getAttribute('src'), complete: i.complete, w: i.naturalWidth, h: i.naturalHeight})))"""


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("page", type=pathlib.Path)
    ap.add_argument("--screenshot", type=pathlib.Path, required=True)
    ap.add_argument("--chrome")
    ap.add_argument("--width", type=int, default=1280)
    ap.add_argument("--height", type=int, default=2000)
    ap.add_argument("--timeout", type=float, default=60)
    ap.add_argument("--expect-claims", action="store_true",
                    help="fail when the page has no claims table (a results folder with claims.toml)")
    a = ap.parse_args()
    if not a.page.is_file():
        print(f"error: {a.page}: no such page", file=sys.stderr)
        return 2
    chrome = find_chrome(a.chrome)
    if not chrome:
        print("error: no Chromium found (install it, e.g. apt-get install chromium, or set CHROME)",
              file=sys.stderr)
        return 2
    url = a.page.resolve().as_uri()
    dt = DevTools(chrome, a.width, a.height)
    failures = []
    try:
        version = dt.send("Browser.getVersion")
        print(f"browser: {version.get('product')}")
        target = dt.send("Target.createTarget", {"url": "about:blank"})["targetId"]
        session = dt.send("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
        for domain in ("Page", "Runtime", "Log", "Network"):
            dt.send(f"{domain}.enable", session=session)
        dt.send("Emulation.setDeviceMetricsOverride", {"width": a.width, "height": a.height,
                "deviceScaleFactor": 1, "mobile": False}, session=session)
        nav = dt.send("Page.navigate", {"url": url}, session=session)
        if nav.get("errorText"):
            failures.append(f"navigation failed: {nav['errorText']}")
        dt.wait_event("Page.loadEventFired", session, a.timeout)
        print(f"loaded: {url}")
        title = dt.send("Runtime.evaluate", {"expression": "document.title", "returnByValue": True},
                        session=session)["result"].get("value")
        sections = dt.send("Runtime.evaluate", {"expression": "document.querySelectorAll('section').length",
                           "returnByValue": True}, session=session)["result"].get("value")
        print(f"title: {title!r}, sections: {sections}")
        if not sections:
            failures.append("the page has no sections")
        imgs = json.loads(dt.send("Runtime.evaluate", {"expression": IMAGES_JS, "returnByValue": True},
                                  session=session)["result"]["value"])
        bad = [i for i in imgs if not (i["complete"] and i["w"] > 0)]
        print(f"images: {len(imgs)}, decoded (naturalWidth > 0): {len(imgs) - len(bad)}")
        failures += [f"image not loaded: {i['src']} (complete={i['complete']}, naturalWidth={i['w']})"
                     for i in bad]
        claims = json.loads(dt.send("Runtime.evaluate", {"expression": CLAIMS_JS, "returnByValue": True},
                                    session=session)["result"]["value"])
        if claims is None:
            if a.expect_claims:
                failures.append("the page has no claims table")
        else:
            bad = verdict_failures(claims["verdicts"])
            if not claims["verdicts"]:
                bad.append("the claims table has no verdict column (columns %s)" % claims["columns"])
            print(f"claims: {len(claims['verdicts'])} verdict cells, coloured by their outcome: "
                  f"{len(claims['verdicts']) - len(bad)}")
            failures += bad
            bad = measured_failures(claims["measured"], a.width)
            if not claims["measured"]:
                bad.append("the claims table has no measured column (columns %s)" % claims["columns"])
            print(f"claims: {len(claims['measured'])} measured cells, inside the {a.width} px viewport: "
                  f"{len(claims['measured']) - len(bad)}")
            failures += bad
        cells = json.loads(dt.send("Runtime.evaluate", {"expression": MEASURED_JS, "returnByValue": True},
                                   session=session)["result"]["value"])
        bad_cells = measured_failures(cells, a.width)
        print(f"experiments: {len(cells)} measured cells, inside the {a.width} px viewport: "
              f"{len(cells) - len(bad_cells)}")
        failures += bad_cells
        shot = dt.send("Page.captureScreenshot", {"format": "png"}, session=session)["data"]
        png = base64.b64decode(shot)
        a.screenshot.parent.mkdir(parents=True, exist_ok=True)
        a.screenshot.write_bytes(png)
        if not png.startswith(b"\x89PNG\r\n\x1a\n"):
            failures.append("the screenshot is not a PNG")
        print(f"screenshot: {a.screenshot} ({len(png)} bytes, {a.width}x{a.height})")
        problems = problems_in(dt.events)
        print(f"console errors, exceptions and failed loads: {len(problems)}")
        failures += problems
    finally:
        dt.close()
    for f in failures:
        print(f"FAIL: {f}")
    print("browser test: " + ("FAILED" if failures else "passed"))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
