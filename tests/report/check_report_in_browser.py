"""Opens a subject's HTML report (or a dataset's or a benchmark's page) in headless Chromium (Debian's chromium) and checks what a reader
sees: the page loads with no console error, no exception and no request outside the file; every
image is loaded and not blank (more than one colour, or not fully transparent); the warnings
section comes first, and its warning box shows when the run warned; a <script> from the scene
file shows as text and does not run. Talks to Chromium over its DevTools pipe (file descriptors
3 and 4, messages ended by a NUL byte), so it needs no network and no Python package.

A dataset's page (--kind dataset) and a benchmark's page (--kind benchmark) have no script and
no warnings-first rule; their links may point at files inside --root (the dataset folder) that
exist, nothing else. Every plot (SVG) of any page must have a size and data (points, or lines
through points); --min-plots counts them.

usage: check_report_in_browser.py REPORT.html [--kind subject|dataset|benchmark] [--root DIR]
       [--min-plots N] [--expect-warnings] [--expect-text TEXT] [--screenshot PNG [--screenshot-at ID]]
exit 0 when every check holds; otherwise 1, with one line per failed check."""
import argparse
import base64
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time


class DevTools:
    """One Chromium over --remote-debugging-pipe, one page attached (flat sessions)."""

    def __init__(self, profile):
        to_browser_r, self.to_browser = os.pipe()
        self.from_browser, from_browser_w = os.pipe()
        # The browser reads commands on its fd 3 and writes answers and events on its fd 4.
        def child_fds():
            # Through descriptors above 4 first, so that neither end overwrites the other.
            read_end, write_end = os.dup(to_browser_r), os.dup(from_browser_w)
            os.dup2(read_end, 3, inheritable=True)
            os.dup2(write_end, 4, inheritable=True)
        self.process = subprocess.Popen(
            ["chromium", "--headless", "--disable-gpu", "--no-sandbox", "--remote-debugging-pipe",
             "--no-first-run", "--user-data-dir=" + profile, "--window-size=1200,900", "about:blank"],
            preexec_fn=child_fds, close_fds=False,
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        os.close(to_browser_r)
        os.close(from_browser_w)
        self.buffer = b""
        self.next_id = 0
        self.events = []
        self.session = None

    def send(self, method, params=None, session=True):
        self.next_id += 1
        message = {"id": self.next_id, "method": method, "params": params or {}}
        if session and self.session:
            message["sessionId"] = self.session
        os.write(self.to_browser, json.dumps(message).encode() + b"\0")
        while True:
            reply = self.receive()
            if reply.get("id") == self.next_id:
                if "error" in reply:
                    raise RuntimeError(method + ": " + json.dumps(reply["error"]))
                return reply.get("result", {})
            self.events.append(reply)

    def receive(self):
        while b"\0" not in self.buffer:
            chunk = os.read(self.from_browser, 1 << 20)
            if not chunk:
                raise RuntimeError("chromium closed its DevTools pipe")
            self.buffer += chunk
        message, self.buffer = self.buffer.split(b"\0", 1)
        return json.loads(message)

    def wait_for(self, method, seconds=60):
        deadline = time.time() + seconds
        while time.time() < deadline:
            for event in self.events:
                if event.get("method") == method:
                    return event
            self.events.append(self.receive())
        raise RuntimeError("no " + method + " within " + str(seconds) + " s")

    def close(self):
        try:
            self.send("Browser.close", session=False)
        except Exception:
            pass
        try:
            self.process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.process.kill()


# Runs in the page after its load: what each image shows and where the sections are.
PAGE_FACTS = r"""
(() => {
  const images = Array.from(document.images).map((img) => {
    const fact = {alt: img.alt, complete: img.complete, width: img.naturalWidth, height: img.naturalHeight,
                  source: img.src.slice(0, 22), colours: 0, opaque: 0};
    if (!img.complete || img.naturalWidth === 0) return fact;
    const canvas = document.createElement('canvas');
    canvas.width = img.naturalWidth; canvas.height = img.naturalHeight;
    const context = canvas.getContext('2d');
    context.drawImage(img, 0, 0);
    const data = context.getImageData(0, 0, canvas.width, canvas.height).data;
    const seen = new Set();
    for (let i = 0; i < data.length; i += 4) {
      if (seen.size < 3) seen.add(data[i] + ',' + data[i + 1] + ',' + data[i + 2] + ',' + data[i + 3]);
      if (data[i + 3] > 0) fact.opaque++;
    }
    fact.colours = seen.size;
    return fact;
  });
  const headings = Array.from(document.querySelectorAll('h2')).map((h) => ({id: h.id, text: h.textContent,
                                                                            top: h.getBoundingClientRect().top}));
  const plots = Array.from(document.querySelectorAll('svg')).map((svg) => {
    const box = svg.getBoundingClientRect();
    return {label: svg.getAttribute('aria-label') || '', width: box.width, height: box.height,
            points: svg.querySelectorAll('circle').length +
                    Array.from(svg.querySelectorAll('polyline')).filter((l) => l.points.numberOfItems > 0).length};
  });
  const warningBox = document.querySelector('#warnings + .warn, #warnings + .bad');
  return JSON.stringify({
    images, headings, plots,
    warningBoxTop: warningBox ? warningBox.getBoundingClientRect().top : null,
    scripts: document.scripts.length,
    injected: window.phantasmInjected === true,
    text: document.body.textContent,
    external: Array.from(document.querySelectorAll('[src],[href]')).map((e) => e.getAttribute('src') || e.getAttribute('href'))
                   .filter((u) => !u.startsWith('data:') && !u.startsWith('#')),
  });
})()
"""


def outside_root(reference, report, root):
    """Why a link of a dataset or benchmark page is not allowed ("" when it is): it must be a
    relative path to a file inside root that exists."""
    if ":" in reference.split("/")[0] or reference.startswith("/"):
        return "reference outside the dataset: "
    target = os.path.realpath(os.path.join(os.path.dirname(os.path.abspath(report)), reference.split("#")[0]))
    if not target.startswith(os.path.realpath(root) + os.sep):
        return "reference outside the dataset: "
    if not os.path.isfile(target):
        return "link to a file that does not exist: "
    return ""


def check(report, expect_warnings, screenshot, kind="subject", root=None, screenshot_at=None):
    failures = []
    profile = tempfile.mkdtemp(prefix="phantasm-chromium-")
    browser = DevTools(profile)
    try:
        target = browser.send("Target.createTarget", {"url": "about:blank"}, session=False)["targetId"]
        browser.session = browser.send("Target.attachToTarget", {"targetId": target, "flatten": True},
                                       session=False)["sessionId"]
        for domain in ("Page", "Runtime", "Log", "Network"):
            browser.send(domain + ".enable")
        url = "file://" + os.path.abspath(report)
        browser.send("Page.navigate", {"url": url})
        browser.wait_for("Page.loadEventFired")
        facts = json.loads(browser.send("Runtime.evaluate", {"expression": PAGE_FACTS, "returnByValue": True})
                           ["result"]["value"])
        if screenshot:
            if screenshot_at:
                browser.send("Runtime.evaluate", {"expression": "document.getElementById(%s).scrollIntoView()"
                                                                % json.dumps(screenshot_at)})
            shot = browser.send("Page.captureScreenshot", {"format": "png"})["data"]
            with open(screenshot, "wb") as out:
                out.write(base64.b64decode(shot))
        events = list(browser.events)
    finally:
        browser.close()
        shutil.rmtree(profile, ignore_errors=True)

    for event in events:
        method, params = event.get("method"), event.get("params", {})
        if method == "Runtime.consoleAPICalled" and params.get("type") in ("error", "assert"):
            failures.append("console error: " + json.dumps(params.get("args"))[:200])
        if method == "Runtime.exceptionThrown":
            failures.append("exception: " + json.dumps(params.get("exceptionDetails"))[:200])
        if method == "Log.entryAdded" and params.get("entry", {}).get("level") == "error":
            failures.append("log error: " + params["entry"].get("text", "")[:200])
        if method == "Network.requestWillBeSent":
            requested = params.get("request", {}).get("url", "")
            if requested != url and not requested.startswith("data:"):
                failures.append("request outside the file: " + requested[:200])
    for outside in facts["external"]:
        if kind == "subject":
            failures.append("reference outside the file: " + outside[:200])
        elif outside_root(outside, report, root):
            failures.append(outside_root(outside, report, root) + outside[:200])
    if not facts["images"] and kind != "benchmark":
        failures.append("no image in the page")
    for plot in facts["plots"]:
        if plot["width"] == 0 or plot["height"] == 0:
            failures.append("plot not shown: " + plot["label"])
        elif plot["points"] == 0:
            failures.append("blank plot (no data point): " + plot["label"])
    for image in facts["images"]:
        if not image["complete"] or image["width"] == 0:
            failures.append("image not loaded: " + image["alt"])
        elif image["colours"] < 2 or image["opaque"] == 0:
            failures.append("blank image: " + image["alt"] + " (" + str(image["colours"]) + " colours, " +
                            str(image["opaque"]) + " opaque pixels)")
    if kind != "subject":
        if facts["injected"]:
            failures.append("a <script> from a file of the dataset ran")
        if facts["scripts"] != 0:
            failures.append("expected no script, found " + str(facts["scripts"]))
        return failures, facts
    headings = facts["headings"]
    if not headings or headings[0]["id"] != "warnings":
        failures.append("the first section is not the warnings: " + (headings[0]["text"] if headings else "none"))
    elif any(h["top"] < headings[0]["top"] for h in headings[1:]):
        failures.append("a section is shown above the warnings")
    if expect_warnings:
        if facts["warningBoxTop"] is None:
            failures.append("the run warned but the report shows no warning box")
        elif facts["warningBoxTop"] > 900:
            failures.append("the warning box is below the first screen (at " + str(facts["warningBoxTop"]) + " px)")
    if facts["injected"]:
        failures.append("a <script> from the scene ran")
    if facts["scripts"] != 1:
        failures.append("expected the report's own script only, found " + str(facts["scripts"]) + " scripts")
    return failures, facts


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("report")
    parser.add_argument("--expect-warnings", action="store_true")
    parser.add_argument("--expect-text", action="append", default=[],
                        help="text the page must show (e.g. a <script> tag of the scene, as text)")
    parser.add_argument("--screenshot", help="write what the window shows as this PNG")
    parser.add_argument("--screenshot-at", help="scroll the element of this id to the top first")
    parser.add_argument("--kind", choices=["subject", "dataset", "benchmark"], default="subject")
    parser.add_argument("--root", help="the folder a dataset or benchmark page may link into (default: its own)")
    parser.add_argument("--min-plots", type=int, default=0, help="plots (SVG) the page must hold at least")
    args = parser.parse_args()
    if shutil.which("chromium") is None:
        print("chromium is not installed (scripts/install-deps.sh installs it)")
        return 1
    if not os.path.isfile(args.report):
        print("no such page: " + args.report)
        return 1
    failures, facts = check(args.report, args.expect_warnings, args.screenshot, args.kind,
                            args.root or os.path.dirname(os.path.abspath(args.report)), args.screenshot_at)
    if len(facts["plots"]) < args.min_plots:
        failures.append("expected " + str(args.min_plots) + " plots at least, found " + str(len(facts["plots"])))
    for text in args.expect_text:
        if text not in facts["text"]:
            failures.append("the page does not show the text " + text)
    for failure in failures:
        print(failure)
    print(str(len(facts["images"])) + " images, " + str(len(facts["plots"])) + " plots, " +
          str(len(facts["headings"])) + " sections, " +
          str(len(failures)) + " failed checks")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
